"""The front-end widget of notebook 05 (stereo front end), kept out of its story cells."""

from __future__ import annotations

from collections.abc import Callable

import matplotlib.pyplot as plt
import numpy as np

from vo_book.plotting import new_axes
from vo_lib.camera import StereoCamera
from vo_lib.stereo_vo.features import StereoFrontEnd


def front_end_on(
    camera: StereoCamera, left: np.ndarray, right: np.ndarray, true_disparity: np.ndarray
) -> Callable[..., int]:
    """The widget's function on one rendered pair: ``front_end(threshold, max_features)`` runs the
    front end, draws its matches coloured by disparity, titles the figure with their count, median
    disparity error against ``true_disparity`` and time, and returns the count."""

    def front_end(threshold: int = 40, max_features: int = 600) -> int:
        """Stereo matches of the rendered pair for a FAST threshold and a feature cap."""
        fe = StereoFrontEnd(camera, max_features=int(max_features), fast_threshold=int(threshold))
        f = fe.process(left, right)
        if len(f) == 0:
            print("no stereo matches")
            return 0
        ui, vi = np.rint(f.w[:, 0]).astype(int), np.rint(f.w[:, 1]).astype(int)
        err = np.abs(f.w[:, 2] - true_disparity[vi, ui])
        fig, ax = new_axes(width=6, height=4.4)
        ax.imshow(left, cmap="gray")
        sc = ax.scatter(f.w[:, 0], f.w[:, 1], c=f.w[:, 2], s=8, cmap="plasma")
        fig.colorbar(sc, ax=ax, shrink=0.7, label="disparity [px]")
        ax.set_title(
            f"{len(f)} matches, median |error| {np.median(err):.2f} px, {sum(f.timings.values()):.1f} ms"
        )
        ax.axis("off")
        plt.show()
        return len(f)

    return front_end
