"""Figures of notebook 08 (full pipeline), kept out of its story cells.

Nothing here runs the pipeline: each function draws arrays the notebook computed and shows the
figure, so that it comes before the lines the cell prints after it. The runs of the samples and
the tables of the stored paper sets are :mod:`vo_book.demo_pipeline`.
"""

from __future__ import annotations

from collections.abc import Mapping

import matplotlib.pyplot as plt
import numpy as np

from vo_book.plotting import new_axes, plot_paths

#: The labels of section 4's heading errors, by the name the notebook keeps each under.
SPOT_LABELS = {"odometry": "track odometry only", "vision": "visual odometry only", "fused": "fused"}


def plot_features_by_resolution(features: dict) -> None:
    """The paper's Fig. 6 for our drive: median stereo features per frame against the pixels of
    each ``(width, height)`` in ``features``, each point labelled with its resolution."""
    counts = np.array(list(features.values()))
    pixels = np.array([w * h for w, h in features]) / 1e3
    _, ax = new_axes(width=5.5, height=3.4)
    ax.plot(pixels, counts, "o-")
    for (w, h), p, c in zip(features, pixels, counts, strict=True):
        ax.annotate(f"{w}×{h}", (p, c), fontsize="x-small", xytext=(3, 3), textcoords="offset points")
    ax.set_xlabel("pixels per image [thousands]")
    ax.set_ylabel("stereo features (median per frame)")
    ax.set_title("Fig. 6: stereo features against resolution")
    ax.set_ylim(0, 1.1 * counts.max())
    plt.show()


def plot_linear(truth: np.ndarray, poses: np.ndarray) -> None:
    """Section 3's linear motion, one panel each for x and y in millimetres against the frame:
    the truth and the visual odometry's ``poses``."""
    _, axes = new_axes(2, width=5.5, height=3.4)
    frames_axis = np.arange(len(truth))
    for ax, col, name in ((axes[0], 0, "x"), (axes[1], 1, "y")):
        ax.plot(frames_axis, truth[:, col] * 1000, label="truth")
        ax.plot(frames_axis, poses[:, col] * 1000, "--", label="visual odometry")
        ax.set_xlabel("frame")
        ax.set_ylabel(f"{name} [mm]")
    axes[0].legend(fontsize="small")
    plt.show()


def plot_outdoor_errors(error_mm: np.ndarray) -> None:
    """The paper's Fig. 9 for our outdoor linear drive: the x and y errors ``(K, 2)`` in
    millimetres against the frame."""
    _, ax = new_axes(width=7, height=3.2)
    for col, name in ((0, "x"), (1, "y")):
        ax.plot(np.arange(len(error_mm)), error_mm[:, col], label=f"{name} error")
    ax.set_xlabel("frame")
    ax.set_ylabel("error [mm]")
    ax.set_title(f"Fig. 9: outdoor linear motion, {len(error_mm)} frames")
    ax.legend(fontsize="small")
    plt.show()


def plot_spot_headings(t: np.ndarray, errors: Mapping[str, np.ndarray]) -> None:
    """Section 4's heading errors in degrees against the time ``t`` in seconds, one line per
    source ``{"odometry" | "vision" | "fused": errors}``."""
    _, ax = new_axes(width=7, height=3.4)
    for name, err in errors.items():
        ax.plot(t, err, label=SPOT_LABELS[name])
    ax.set_xlabel("time [s]")
    ax.set_ylabel("heading error [deg]")
    ax.legend(fontsize="small")
    plt.show()


def plot_free_paths(runs: Mapping[str, tuple[dict, np.ndarray]]) -> None:
    """Section 5's quick runs, one plan view per run ``{title: (paths, keys)}``: its ``paths``
    (truth, track odometry, visual odometry) and the key positions ``keys`` on the truth and on
    the visual odometry."""
    _, axes = new_axes(len(runs), width=4.2, height=4.0)
    for ax, (title, (paths, keys)) in zip(axes, runs.items(), strict=True):
        plot_paths(ax, paths, title)
        ax.plot(*paths["truth"][keys, :2].T, "ko", ms=4, mfc="none", label="key positions (truth)")
        ax.plot(*paths["visual odometry"][keys, :2].T, "k+", ms=6, label="key positions (VO)")
        ax.legend(fontsize="x-small")
    plt.show()


def plot_nees(frames: np.ndarray, per_frame: np.ndarray, band: tuple[float, float], runs: int) -> None:
    """The pose NEES averaged over ``runs`` runs at each of the ``frames``, on a log scale, in its
    95 % χ² ``band`` and against 3, its expectation."""
    _, ax = new_axes(width=7, height=3.2)
    ax.semilogy(frames, per_frame, color="C2", label=f"NEES averaged over {runs} runs")
    ax.axhspan(*band, color="C2", alpha=0.2, label="95 % band")
    ax.axhline(3, color="k", lw=0.8)
    ax.set_xlabel("frame")
    ax.set_ylabel("pose NEES")
    ax.legend(fontsize="small")
    plt.show()
