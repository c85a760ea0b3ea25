"""Checks, timings and figures of notebook 09 (line-feature EKF-SLAM), kept out of its story cells.

The helpers compare matrices and time functions the notebook passes in; they know nothing of SLAM.
The figures draw what the notebook computed: walls, visible parts, echoes, the association case,
the observers' timings and the filter's consistency over seeds.
"""

from __future__ import annotations

import timeit
from collections.abc import Callable, Sequence

import matplotlib.pyplot as plt
import numpy as np
import sympy as sp

from vo_book.plotting import covariance_ellipse, new_axes


def differing_entries(derived: sp.Matrix, printed: sp.Matrix) -> list[tuple]:
    """Entries (row, column, derived, printed) where a derived and a printed matrix are not identical."""
    return [
        (i, j, derived[i, j], printed[i, j])
        for i in range(derived.rows)
        for j in range(derived.cols)
        if sp.simplify(derived[i, j] - printed[i, j]) != 0
    ]


def finite_difference(fn: Callable[[np.ndarray], np.ndarray], at, eps: float = 1e-6) -> np.ndarray:
    """Central finite-difference Jacobian of ``fn`` at ``at``, one column per input."""
    at = np.asarray(at, dtype=float)
    return np.column_stack([(fn(at + eps * e) - fn(at - eps * e)) / (2 * eps) for e in np.eye(at.size)])


def judge(
    name: str, numeric: np.ndarray, derived: sp.Matrix, printed: sp.Matrix, values: dict
) -> tuple[float, float]:
    """Print and return the largest gap of the finite differences ``numeric`` to the derived and
    to the printed Jacobian, both evaluated at ``values``."""
    d = np.array(derived.subs(values), dtype=float)
    p = np.array(printed.subs(values), dtype=float)
    to_derived, to_printed = float(abs(numeric - d).max()), float(abs(numeric - p).max())
    print(f"{name}: |finite diff - derived| = {to_derived:.1e}, |finite diff - printed| = {to_printed:.1e}")
    return to_derived, to_printed


def seconds_per_call(fn: Callable, tol: float, calls: Sequence[tuple]) -> float:
    """Best of three timings of ``fn(start, end, position, 30 m range, tol)`` over ``calls``, per call."""

    def run_all():
        return [fn(a_, b_, g_, 30.0, tol) for a_, b_, g_ in calls]

    return min(timeit.repeat(run_all, number=1, repeat=3)) / len(calls)


def plot_scan_against_observer(world, parts: Sequence, hits: np.ndarray, pose, max_range: float) -> None:
    """The walls of ``world``, the part of each that the observer finds visible from ``pose``
    (``parts``: ``(t_start, t_end)`` along the wall, or ``None``), and the laser's echoes ``hits``
    in the world frame, inside the range circle."""
    _, ax = new_axes(width=6, height=5)
    for i, (seg, part) in enumerate(zip(world.segments, parts, strict=True)):
        a_, b_ = np.array(seg.start), np.array(seg.end)
        ax.plot(*np.transpose([a_, b_]), color="0.4", lw=1)
        if part is not None:
            seen = a_ + np.outer(part, b_ - a_)
            ax.plot(
                seen[:, 0],
                seen[:, 1],
                color="C1",
                lw=4,
                alpha=0.6,
                label="visible (closed form)" if i == 0 else None,
            )
    ax.plot(hits[:, 0], hits[:, 1], ".", ms=2, color="C0", label="laser echoes")
    ax.add_patch(plt.Circle(pose[:2], max_range, fill=False, color="0.7"))
    ax.plot(*pose[:2], "k^")
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.legend(fontsize="small")
    ax.set_title("The shared laser scanner agrees with the observer")
    plt.show()


def plot_association(ekf, placed: np.ndarray, cov: np.ndarray, sigma_across: float) -> None:
    """The observation placed with the estimated pose, its 2σ ellipse ``cov``, and the feature
    points of the filter's two walls, A and B, in a window 2.6σ across the line of sight."""
    _, ax = new_axes(width=6, height=4.5)
    covariance_ellipse(ax, placed, cov, 2.0, color="C0", label="observation, 2σ")
    for j, name in enumerate("AB"):
        ax.plot(*ekf.landmark(j), "s", label=f"wall {name}'s feature point")
    ax.plot(*placed, "x", color="C0", ms=9, label="observation placed with the estimated pose")
    ax.set_xlim(17, 23)
    ax.set_ylim(placed[1] - 2.6 * sigma_across, placed[1] + 2.6 * sigma_across)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m] (along the line of sight)")
    ax.set_ylabel("y [m]")
    ax.legend(fontsize="small", loc="lower left")
    ax.set_title("Nearest in metres is B; nearest in σ is A")
    plt.show()


def plot_timings(tolerances: Sequence[float], table: dict[str, Sequence[float]]) -> None:
    """Seconds per call ``{observer: one per tolerance}`` against the tolerance, log-log, finest
    tolerance on the right."""
    _, ax = new_axes(width=5.5, height=3.4)
    for name, times in table.items():
        ax.loglog(tolerances, np.array(times) * 1e6, "o-", label=name)
    ax.set_xlabel("tolerance [m]")
    ax.set_ylabel("time per call [µs]")
    ax.invert_xaxis()
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize="small")
    plt.show()


def plot_line_triple(
    wall: tuple[np.ndarray, np.ndarray],
    label: str,
    ends: np.ndarray,
    pose: np.ndarray,
    foot: np.ndarray,
    feature: np.ndarray,
    max_range: float,
) -> None:
    """One wall seen from ``pose``: its visible part (world ``ends``), the rays to the ends, the
    distance ``d`` to the line (to its ``foot``), the wall's ``feature`` point and the world origin."""
    a_, b_ = wall
    _, ax = new_axes(width=6.5, height=5)
    ax.plot(*np.transpose([a_, b_]), color="0.4", lw=1, label=label)
    ax.plot(*ends.T, color="C1", lw=4, alpha=0.6, label="visible part")
    for q in ends:
        ax.plot(*np.transpose([pose[:2], q]), color="C0", lw=0.8)
    ax.plot(*np.transpose([pose[:2], foot]), "k:", lw=1, label="d: distance to the line")
    ax.plot(*feature, "s", color="C3", label="feature point (what eq. 10 observes)")
    ax.plot(0, 0, "k+", ms=10, label="world origin")
    ax.add_patch(plt.Circle(pose[:2], max_range, fill=False, color="0.7"))
    ax.plot(*pose[:2], "k^")
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.legend(fontsize="x-small", loc="best")
    ax.set_title("The paper's triple: d, and the angles of the rays to the visible part's ends")
    plt.show()


def plot_consistency(
    t_obs: np.ndarray,
    mean_nees: np.ndarray,
    band: tuple[float, float],
    t_ctrl: np.ndarray,
    z_heading: np.ndarray,
    seed: int,
) -> None:
    """Left, the pose NEES averaged over the seeds at each observation step against its per-step
    95 % ``band`` and the dof, 3; right, each seed's heading error in units of its own σ (the
    first seed, ``seed``, in red) against ±2."""
    n_seeds = len(z_heading)
    _, axes = new_axes(2, width=6.5, height=3.2)
    axes[0].plot(t_obs, mean_nees, lw=1, label=f"mean NEES over {n_seeds} seeds")
    axes[0].axhspan(*band, color="C2", alpha=0.2, label="95 % band, per step")
    axes[0].axhline(3, color="k", lw=0.5)
    axes[0].set_xlabel("time [s]")
    axes[0].set_ylabel("pose NEES")
    axes[0].set_title(f"Pose NEES, {n_seeds} seeds")
    axes[0].legend(fontsize="small")
    for i, zz in enumerate(z_heading):
        axes[1].plot(t_ctrl, zz, lw=0.6, color="C0" if i else "C3", alpha=0.5 if i else 1.0)
    axes[1].axhline(2, color="k", lw=0.6, ls="--")
    axes[1].axhline(-2, color="k", lw=0.6, ls="--")
    axes[1].set_xlabel("time [s]")
    axes[1].set_ylabel("heading error / σ")
    axes[1].set_title(f"Heading error in σ, each seed (seed {seed} red)")
    plt.show()
