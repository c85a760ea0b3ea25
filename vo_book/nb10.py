"""Figures of notebook 10 (VO-assisted laser tracking), kept out of its story cells.

Nothing here tracks or scores anything: each function draws arrays the notebook computed. The
figures are left open, for Jupyter to show each one after its cell's printed lines. The
corridor's scaffolding (score profiles, box statistics, ROC area) is :mod:`vo_book.demo_corridor`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import matplotlib.pyplot as plt
import numpy as np

from vo_book.plotting import new_axes, plot_world


def plot_scans(world, scans: Mapping[float, np.ndarray]) -> None:
    """One panel per robot position ``x`` on the corridor's axis: the map, and the scan taken
    there ``{x: (N, 2) end points in the world frame}``, 6 m behind to 10.5 m ahead."""
    _, axes = new_axes(len(scans), width=5.5, height=2.6)
    for ax, (x, pts) in zip(axes, scans.items(), strict=True):
        plot_world(ax, world, f"robot at x = {x:g} m")
        ax.plot(pts[:, 0], pts[:, 1], ".", ms=2, color="C3")
        ax.plot(x, 0, "k>")
        ax.set_aspect("equal", adjustable="box")  # keep the limits below; the box takes the aspect
        ax.set_xlim(x - 6, x + 10.5)
        ax.set_ylim(-2, 2)
    axes[0].legend(fontsize="x-small", loc="lower right")


def plot_profiles(offsets: np.ndarray, profiles: Mapping[float, np.ndarray]) -> None:
    """Score of poses shifted by ``offsets`` along the corridor, below the best score, one line
    per position ``{x: scores}``."""
    _, ax = new_axes(width=7, height=3)
    for x, scores in profiles.items():
        ax.plot(offsets, scores - scores.max(), label=f"x = {x:g} m")
    ax.set_xlabel("pose offset along the corridor [m]")
    ax.set_ylabel("score - best score")
    ax.legend(fontsize="small")
    ax.set_title("Score of poses shifted along the corridor")


def plot_posterior_boxes(values: Mapping[str, np.ndarray], top: float) -> None:
    """One box plot per frame ``{title: posterior × n of its samples}``, whiskers at the minimum
    and maximum, every panel on the same scale up to ``top``."""
    _, axes = new_axes(len(values), width=5.5, height=3.4)
    for ax, (title, v) in zip(axes, values.items(), strict=True):
        ax.boxplot(v, whis=(0, 100))
        ax.set_title(title)
        ax.set_ylabel("posterior × n (box: quartiles, whiskers: min and max)")
        ax.set_xticks([])
    for ax in axes:
        ax.set_ylim(-0.03 * top, 1.05 * top)


def plot_corrections(x: np.ndarray, r_lo: np.ndarray, r_vo: np.ndarray, cal) -> None:
    """Lengths of the laser's and the visual odometer's corrections to the odometry along the
    corridor (``x``), against their upper control limits in the calibration ``cal``."""
    _, ax = new_axes(width=8, height=3)
    ax.plot(x, 100 * r_lo, lw=0.8, label="R_lo: laser's correction")
    ax.plot(x, 100 * r_vo, lw=0.8, label="R_vo: visual odometer's correction")
    ax.axhline(100 * cal.laser.upper, color="C0", ls="--", lw=0.8, label="UCL_lo")
    ax.axhline(100 * cal.vo.upper, color="C1", ls="--", lw=0.8, label="UCL_vo")
    ax.set_xlabel("true x along the corridor [m]")
    ax.set_ylabel("correction to the odometry [cm]")
    ax.set_title("Corrections in the normal run (Fig. 1(c), Fig. 5)")
    ax.legend(fontsize="x-small", ncol=2)


def plot_drive(lbpt, voapt, v_max_threshold: float, unoccluded: Sequence[tuple[float, float]]) -> None:
    """The paper's Fig. 7 for one drive, against the true position along the corridor: the X and
    Y errors of both trackers, LBPT's V_max against its threshold, and the indicator C_s with
    LBPT's credibility T_s; the ``unoccluded`` stretches shaded."""
    x = lbpt.truth[:, 0]
    _, axes = plt.subplots(4, 1, figsize=(9, 8.5), sharex=True, constrained_layout=True)
    axes[0].plot(x, lbpt.errors[:, 0], label="LBPT")
    axes[0].plot(x, voapt.errors[:, 0], label="VOAPT")
    axes[0].set_ylabel("X error [m]")
    axes[0].set_title("Errors along (X) and across (Y) the corridor (the paper's Fig. 7), one drive")
    axes[0].legend(fontsize="small")
    axes[1].plot(x, 100 * lbpt.errors[:, 1], label="LBPT")
    axes[1].plot(x, 100 * voapt.errors[:, 1], label="VOAPT")
    axes[1].set_ylabel("Y error [cm]")
    axes[2].semilogy(x, [s.stats.v_max for s in lbpt.steps], lw=0.8, label="V_max (LBPT's samples)")
    axes[2].axhline(v_max_threshold, color="k", lw=0.8, ls="--", label="threshold")
    axes[2].set_ylabel("V_max")
    axes[2].legend(fontsize="small")
    axes[3].plot(x, [s.c_s for s in lbpt.steps], lw=0.8, label="C_s")
    axes[3].plot(x, [0.5 * s.credible for s in lbpt.steps], lw=0.8, label="T_s / 2 (LBPT)")
    axes[3].set_ylabel("indicator")
    axes[3].set_xlabel("true x along the corridor [m]")
    axes[3].legend(fontsize="small")
    for ax in axes:
        for lo, hi in unoccluded:
            ax.axvspan(lo, hi, color="C2", alpha=0.08)


def plot_directions(world, run) -> None:
    """The corridor's map with an arrow, 0.6 m long, along the principal error direction at each
    estimated pose of ``run`` where it was compensated."""
    _, ax = new_axes(width=10, height=2.6)
    plot_world(ax, world, "principal error directions (arrows) where VOAPT compensated")
    for s, pose in zip(run.steps, run.estimate, strict=True):
        if s.direction is not None:
            ax.arrow(
                pose[0], pose[1], 0.6 * s.direction[0], 0.6 * s.direction[1], head_width=0.08, color="C1"
            )
    ax.set_aspect("equal", adjustable="box")
    ax.set_ylim(-1.8, 1.8)
