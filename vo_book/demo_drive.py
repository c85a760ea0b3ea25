"""The drive-it-yourself widget of notebook 01 (crawler odometry), kept out of its story cells."""

from __future__ import annotations

from collections.abc import Callable

import matplotlib.pyplot as plt
import numpy as np

from vo_book.plotting import covariance_ellipse, new_axes, plot_paths
from vo_lib.geometry import wrap_angle
from vo_lib.models.track_odometry import TrackOdometry, apply_slip


def drive_on(odo: TrackOdometry, rate: float) -> Callable[..., float]:
    """The widget's function for a crawler ``odo`` whose encoders are read ``rate`` times a second.

    ``drive(v_left, v_right, seconds, slip_left)`` dead-reckons constant track speeds (m/s), draws
    the believed path with its 2σ ellipses beside the slipping truth, prints the final errors and
    returns the final position error in metres.
    """

    def drive(
        v_left: float = 0.25, v_right: float = 0.30, seconds: float = 20.0, slip_left: float = 0.0
    ) -> float:
        """Dead-reckon constant track speeds (m/s) and compare with the slipping truth."""
        n = int(rate * seconds)
        controls = np.tile([v_left / rate, v_right / rate], (n, 1))
        believed = odo.integrate(controls)
        truth = odo.integrate(apply_slip(controls, slip_left=slip_left), exact=True)
        fig, ax = new_axes(width=6, height=4.5)
        plot_paths(ax, {"odometry": believed, "truth": truth}, f"{seconds:.0f} s of constant track speeds")
        state, P = np.zeros(3), np.zeros((3, 3))
        for k, u in enumerate(controls, start=1):
            state, P = odo.propagate(state, P, u)
            if k % max(1, n // 5) == 0:
                covariance_ellipse(ax, state, P, color="C0")
        err = float(np.hypot(*(believed[-1, :2] - truth[-1, :2])))
        print(
            f"final position error {err * 1e3:.3f} mm, heading error "
            f"{np.degrees(wrap_angle(believed[-1, 2] - truth[-1, 2])):.2f}°"
        )
        plt.show()
        return err

    return drive
