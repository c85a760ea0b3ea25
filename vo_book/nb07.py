"""Plotting helpers of notebook 07: one colour per estimator in every panel, and the
conditions-over-seeds table.

The estimators keep their colour from figure to figure, so that a reader who has learnt that
the fused filter is green finds it green in the next panel too.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

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
