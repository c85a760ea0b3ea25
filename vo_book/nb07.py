"""Figures of notebook 07 (Kalman fusion), kept out of its story cells: one colour per estimator
in every panel.

The estimators keep their colour from figure to figure, so that a reader who has learnt that
the fused filter is green finds it green in the next panel too. The figures draw what the
notebook computed; nothing they draw is computed here.
"""

from __future__ import annotations

from collections.abc import Mapping

import matplotlib.pyplot as plt
import numpy as np

from vo_book.plotting import new_axes

#: One colour per estimator, for every panel of the notebook.
COLOURS: dict[str, str] = {
    "truth": "k",
    "odometry": "C0",
    "VO": "C1",
    "fused": "C2",
    "calibrated": "C3",
}


def plot_errors(ax, t: np.ndarray, errors: Mapping[str, np.ndarray], ylabel: str, title: str = "") -> None:
    """One line per estimator ``{name: error per time}``, each in its :data:`COLOURS` colour."""
    for name, err in errors.items():
        ax.plot(t, err, label=name, color=COLOURS.get(name))
    ax.set_xlabel("time [s]")
    ax.set_ylabel(ylabel)
    if title:
        ax.set_title(title)
    ax.legend(fontsize="small")


def plot_heading_errors(t: np.ndarray, errors: Mapping[str, np.ndarray], title: str) -> None:
    """Heading error [deg] of each estimator ``{name: error per time}`` of one drive, against time
    ``t``: all but the last estimator in the left panel (``title``), all but the first in the
    right, where the odometry's larger error no longer sets the scale."""
    names = list(errors)
    _, axes = new_axes(2, width=5.5, height=3.6)
    for ax, shown, panel in (
        (axes[0], names[:-1], title),
        (axes[1], names[1:], "the same, without odometry alone"),
    ):
        plot_errors(ax, t, {k: errors[k] for k in shown}, "heading error [deg]", panel)
    plt.show()


def plot_outage(yaw_sigma: np.ndarray, gap: tuple[int, int]) -> None:
    """The filter's heading σ (radians, drawn in degrees) frame by frame, the frames ``gap`` (first,
    last) without VO shaded."""
    _, ax = new_axes(width=7, height=3.2)
    ax.plot(np.degrees(yaw_sigma))
    ax.axvspan(*gap, color="0.85", label="no VO (flagged)")
    ax.set_xlabel("frame")
    ax.set_ylabel("heading σ [deg]")
    ax.set_title("Heading uncertainty through a VO outage")
    ax.legend(fontsize="small")
    plt.show()


def plot_nees(average: np.ndarray, band: tuple[float, float], runs: int) -> None:
    """The pose NEES of each step averaged over ``runs`` Monte Carlo runs, against the 95 % ``band``
    (low, high) of that average and its expectation 3."""
    _, ax = new_axes(width=7, height=3.2)
    ax.plot(average, label=f"NEES averaged over {runs} runs")
    ax.axhspan(*band, color="C2", alpha=0.2, label="95 % band")
    ax.axhline(3, color="k", lw=0.8)
    ax.set_xlabel("step")
    ax.set_ylabel("pose NEES")
    ax.set_title(f"Consistency of the fused filter ({runs} Monte Carlo runs)")
    ax.legend(fontsize="small")
    plt.show()
