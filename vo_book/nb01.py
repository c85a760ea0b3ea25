"""Notebook 01's seed study and figures, kept out of its story: section 5's Monte Carlo drawn
again, and its clouds, ellipses and lateral σ drawn from what the notebook computed. The figures
are left open, for Jupyter to show them after the cell's printed lines."""

from __future__ import annotations

from collections.abc import Iterable, Mapping

import numpy as np

from vo_book.plotting import covariance_ellipse, new_axes
from vo_lib.models.track_odometry import TrackOdometry

#: Section 5's figures draw this many of the Monte Carlo runs, enough to show each cloud's shape.
SHOWN_RUNS = 400


def dead_reckoning_seeds(
    odo: TrackOdometry,
    u: np.ndarray,
    runs: int,
    steps: int,
    models: tuple[np.ndarray, np.ndarray],
    seeds: Iterable[int],
) -> dict[str, np.ndarray]:
    """Section 5's Monte Carlo (``runs`` noisy drives of ``steps`` equal controls ``u``) once per
    seed, against the section's two covariances after the last step, ``models`` = (full
    Jacobians, eq. 9's F = I): ``relative``, the Frobenius distance of the full one from the
    cloud's over the cloud's size; ``sampling``, the same distance for ``runs`` draws of a Gaussian
    whose covariance is the full one (what the cloud's finite size alone gives); ``spread``, the
    cloud's lateral σ over the one F = I gives."""
    P_full, P_eq9 = models
    sd = odo.encoder_sigma * np.sqrt(np.abs(u))
    relative, sampling, spread = [], [], []
    for seed in seeds:
        rng = np.random.default_rng(seed)
        samples = np.zeros((runs, 3))
        for _ in range(steps):
            samples = odo.predict(samples, u + rng.normal(size=(runs, 2)) * sd)
        cloud = np.cov(samples.T)
        relative.append(np.linalg.norm(P_full - cloud) / np.linalg.norm(cloud))
        gaussian = np.cov(rng.multivariate_normal(np.zeros(3), P_full, runs).T)
        sampling.append(np.linalg.norm(P_full - gaussian) / np.linalg.norm(gaussian))
        spread.append(np.sqrt(cloud[1, 1] / P_eq9[1, 1]))
    return {"relative": np.array(relative), "sampling": np.array(sampling), "spread": np.array(spread)}


def plot_dead_reckoning(samples: np.ndarray, history: Mapping[int, tuple]) -> None:
    """Section 5's Monte Carlo clouds (the first ``SHOWN_RUNS`` runs of the final ``samples`` and
    of each checkpoint's) with the 2σ ellipses of both models at each checkpoint,
    ``history = {step: (mean, P_full, P_eq9, samples)}``."""
    _, ax = new_axes(width=7, height=4.5)
    label = f"Monte Carlo ({SHOWN_RUNS} of {len(samples)})"
    ax.plot(*samples[:SHOWN_RUNS, :2].T, ".", ms=2, alpha=0.3, color="0.5", label=label)
    for i, (m_k, Pf, P9, s_k) in enumerate(history.values()):
        ax.plot(*s_k[:SHOWN_RUNS, :2].T, ".", ms=2, alpha=0.3, color="0.5")
        covariance_ellipse(ax, m_k, Pf, color="C0", label="full Jacobians, 2σ" if i == 0 else None)
        covariance_ellipse(ax, m_k, P9, color="C3", ls="--", label="F = I (eq. 9), 2σ" if i == 0 else None)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.legend(fontsize="small")
    ax.set_title("Dead-reckoning uncertainty after 1, 2 and 3 m")


def plot_lateral(distance: np.ndarray, lateral: np.ndarray) -> None:
    """Section 5's σ across the path in centimetres against the ``distance`` travelled: the columns
    of ``lateral`` are the Monte Carlo's, the full Jacobians' and eq. 9's F = I, in metres."""
    _, ax = new_axes(width=6, height=3.5)
    for col, label, style in (
        (0, "Monte Carlo", "k-"),
        (1, "full Jacobians", "C0-"),
        (2, "F = I (eq. 9)", "C3--"),
    ):
        ax.plot(distance, lateral[:, col] * 100, style, label=label)
    ax.set_xlabel("distance travelled [m]")
    ax.set_ylabel("σ of y [cm]")
    ax.set_title("Lateral uncertainty: the F = I ellipses are too thin to see above")
    ax.legend(fontsize="small")
