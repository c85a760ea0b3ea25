"""Figures and small measurements of notebooks 11 and 12 (real stereo data), out of their story cells.

Nothing here estimates motion: the functions draw, locate or measure what the notebook computed.
The ``plot_*`` functions draw one figure each from the notebook's arrays and show it.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import cv2
import matplotlib.pyplot as plt
import numpy as np

from vo_book.plotting import new_axes, plot_paths
from vo_lib.geometry import wrap_angle
from vo_lib.sim.realism import gradient_magnitude

#: Where a reprojection error is clipped in the histogram of RANSAC's inliers [px].
REPROJECTION_CLIP = 4.0
#: Where a disparity error is clipped in the colours of the Motorcycle's features [px].
DISPARITY_CLIP = 1.0
#: The bins of the disparity-error histogram [px].
DISPARITY_BINS = np.linspace(0, 1.5, 31)


def find_repo(start: Path) -> Path:
    """The folder holding ``vo_lib`` (the notebook runs in notebooks/, a script may run anywhere)."""
    for folder in (start, *start.parents):
        if (folder / "vo_lib").is_dir():
            return folder
    return Path(__file__).resolve().parents[1]


def errors_against(truth: np.ndarray) -> Callable[[np.ndarray], tuple[float, float, float]]:
    """The function of planar poses that gives their final errors against ``truth``.

    Parameters
    ----------
    truth : (N, 3) array
        Planar ground truth (x, y, yaw), frame 0 first.

    Returns
    -------
    callable
        ``final_errors(poses)``: final position error (m, and % of the distance travelled so far)
        and heading error (deg) of the first ``len(poses)`` frames.
    """

    def final_errors(poses: np.ndarray) -> tuple[float, float, float]:
        n = len(poses)
        metres = float(np.linalg.norm(poses[-1, :2] - truth[n - 1, :2]))
        heading = math.degrees(wrap_angle(poses[-1, 2] - truth[n - 1, 2]))
        distance = float(np.sum(np.linalg.norm(np.diff(truth[:n, :2], axis=0), axis=1)))
        return metres, 100 * metres / distance, heading

    return final_errors


def show_corners(ax, image: np.ndarray, title: str, stats: dict, cell: int) -> None:
    """An image with its FAST corners and, shaded, the cells of ``cell`` pixels that have none;
    ``stats`` holds the image's ``occupied`` cells, ``corners`` and ``empty`` share."""
    ny, nx = stats["occupied"].shape
    ax.imshow(image, cmap="gray")
    extent = (0, nx * cell, ny * cell, 0)
    ax.imshow(~stats["occupied"], cmap="Reds", alpha=0.35, vmin=0, vmax=1.5, extent=extent)
    ax.plot(stats["corners"][:, 0], stats["corners"][:, 1], ".", ms=1, color="yellow")
    ax.set_xlim(0, image.shape[1])
    ax.set_ylim(image.shape[0], 0)
    ax.set_xlabel("u [px]")
    ax.set_ylabel("v [px]")
    ax.set_title(f"{title}: {stats['empty']:.0%} of cells without a corner")


def disparity_errors(front_end, left: np.ndarray, right: np.ndarray, truth: np.ndarray, sgbm: np.ndarray):
    """Our |disparity error| and SGBM's at the same pixels, where both the truth and SGBM have one.

    Returns the number of points the front end found, our errors, SGBM's errors and our points
    (u, v, d) where both are defined.
    """
    fw = front_end.process(left, right).w
    ui, vi = np.rint(fw[:, 0]).astype(int), np.rint(fw[:, 1]).astype(int)
    gt, sg = truth[vi, ui], sgbm[vi, ui]
    both = np.isfinite(gt) & (sg > 0)
    return len(fw), np.abs(fw[both, 2] - gt[both]), np.abs(sg[both] - gt[both]), fw[both]


def pixel_gap(Ta: np.ndarray, Tb: np.ndarray, camera, points: np.ndarray) -> float:
    """Median distance in (u, v, d) between ``points`` moved by two camera motions and projected."""
    a, b = (camera.project(points @ T[:3, :3].T + T[:3, 3]) for T in (Ta, Tb))
    return float(np.median(np.linalg.norm(a - b, axis=1)))


#: The side of the square cells whose share without a corner measures how a frame is covered [px].
CELL = 16


def image_statistics(image: np.ndarray, threshold: int = 20, low_gradient: float = 8.0) -> dict:
    """Empty-cell share, corners per 640x480, low-gradient share and the occupancy grid of an image.

    FAST corners at ``threshold`` (with non-maximum suppression) fill :data:`CELL`-pixel cells; a
    pixel is of low gradient below ``low_gradient`` grey levels per pixel (Sobel / 8).
    """
    h, w = image.shape
    keypoints = cv2.FastFeatureDetector_create(threshold, True).detect(image)
    corners = np.array([k.pt for k in keypoints]).reshape(-1, 2)
    occupied = np.zeros((h // CELL, w // CELL), bool)
    col, row = (corners // CELL).astype(int).T
    inside = (row < occupied.shape[0]) & (col < occupied.shape[1])
    occupied[row[inside], col[inside]] = True
    gradient = gradient_magnitude(image) / 8
    return {
        "empty": 1 - occupied.mean(),
        "per_vga": len(corners) * 640 * 480 / (h * w),
        "flat": float(np.mean(gradient < low_gradient)),
        "corners": corners,
        "occupied": occupied,
    }


def flat_shares(images, thresholds) -> np.ndarray:
    """The mean share of pixels below each of ``thresholds`` grey levels per pixel (Sobel / 8, as in
    :func:`image_statistics`), each image's gradient computed once."""
    gradients = [gradient_magnitude(img) / 8 for img in images]
    return np.array([np.mean([np.mean(g < t) for g in gradients]) for t in thresholds])


def plot_coverage(images: dict[str, np.ndarray]) -> None:
    """Images ``{title: image}`` side by side, each at its own aspect ratio, with its FAST corners
    and, shaded, the :data:`CELL`-pixel cells that have none (as :func:`image_statistics` finds
    them)."""
    ratios = [img.shape[1] / img.shape[0] for img in images.values()]
    _, axes = plt.subplots(
        1, len(images), figsize=(3.2 * sum(ratios), 3.8), width_ratios=ratios, constrained_layout=True
    )
    for ax, (title, image) in zip(axes, images.items(), strict=True):
        show_corners(ax, image, title, image_statistics(image), CELL)
    plt.show()


def plot_disparity_errors(image: np.ndarray, where: np.ndarray, ours: np.ndarray, theirs: np.ndarray) -> None:
    """Our matched features on ``image`` coloured by |disparity error| (``where`` holds their u, v),
    beside the histograms of our errors and SGBM's at the same pixels, with their medians."""
    fig, axes = new_axes(2, width=6, height=4)
    axes[0].imshow(image, cmap="gray")
    sc = axes[0].scatter(where[:, 0], where[:, 1], c=np.minimum(ours, DISPARITY_CLIP), s=8, cmap="viridis")
    fig.colorbar(sc, ax=axes[0], label=f"|disparity error| [px] (clipped at {DISPARITY_CLIP:g})")
    axes[0].set_xlabel("u [px]")
    axes[0].set_ylabel("v [px]")
    axes[0].set_title("Motorcycle: our matched features")
    axes[1].hist(ours, DISPARITY_BINS, alpha=0.6, label=f"ours, median {np.median(ours):.2f} px")
    axes[1].hist(
        theirs, DISPARITY_BINS, alpha=0.6, label=f"SGBM at the same pixels, median {np.median(theirs):.2f} px"
    )
    axes[1].set_xlabel("|disparity error| [px]")
    axes[1].set_ylabel("features")
    axes[1].set_title("Disparity error against ground truth")
    axes[1].legend(fontsize="small")
    plt.show()


def plot_attitude(yaw_pitch_roll: np.ndarray, height: np.ndarray, braking: tuple | None = None) -> None:
    """The vehicle's pitch and roll and its height per frame; with ``braking`` =
    ``(forward_accel, body_nose_up, gain, offset)``, a third panel of the body's pitch against the
    forward acceleration and the fitted line."""
    _, axes = new_axes(2 if braking is None else 3, width=4.6, height=3.4)
    axes[0].plot(yaw_pitch_roll[:, 1], label="pitch (nose down +)")
    axes[0].plot(yaw_pitch_roll[:, 2], label="roll")
    axes[0].set_xlabel("frame")
    axes[0].set_ylabel("angle from frame 0 [deg]")
    axes[0].set_title("Vehicle attitude (ground truth)")
    axes[0].legend(fontsize="small")
    axes[1].plot(height)
    axes[1].set_xlabel("frame")
    axes[1].set_ylabel("height above frame 0 [m]")
    axes[1].set_title("The road climbs")
    if braking is not None:
        forward_accel, body_nose_up, gain, offset = braking
        axes[2].plot(forward_accel, body_nose_up, ".", label="frames")
        aa = np.linspace(forward_accel.min(), forward_accel.max(), 2)
        axes[2].plot(aa, offset + gain * aa, label=f"fit: {gain:.2f} deg per m/s^2")
        axes[2].set_xlabel("forward acceleration [m/s^2]")
        axes[2].set_ylabel("nose up minus road slope [deg]")
        axes[2].set_title("The body dips as the car brakes")
        axes[2].legend(fontsize="small")
    plt.show()


def plot_inlier_errors(circular: np.ndarray, refined: np.ndarray, threshold: float, frames: tuple) -> None:
    """Histograms of the reprojection errors of RANSAC's inliers under the circular and the refined
    motion (clipped at :data:`REPROJECTION_CLIP`), with the inlier ``threshold``, for the pair
    ``frames``."""
    _, ax = new_axes(width=7, height=3.4)
    bins = np.linspace(0, REPROJECTION_CLIP, 41)
    ax.hist(np.minimum(circular, REPROJECTION_CLIP), bins, alpha=0.6, label="under RANSAC's circular motion")
    ax.hist(np.minimum(refined, REPROJECTION_CLIP), bins, alpha=0.6, label="under the refined 6-DoF motion")
    ax.axvline(threshold, color="k", ls="--", label="inlier threshold")
    ax.set_xlabel(f"reprojection error in (u, v, d) [px] (clipped at {REPROJECTION_CLIP:g})")
    ax.set_ylabel("RANSAC inliers")
    ax.set_title(f"Frames {frames[0]}->{frames[1]}: RANSAC's inliers judged by each model")
    ax.legend(fontsize="small")
    plt.show()


def plot_heading_errors(heading_error: dict[str, np.ndarray]) -> None:
    """Heading error per frame of the 6-DoF pipeline, one line per front end ``{name: error}``."""
    _, ax = new_axes(width=7, height=3.4)
    for name, err in heading_error.items():
        ax.plot(err, label=f"{name} front end")
    ax.set_xlabel("frame")
    ax.set_ylabel("heading error [deg]")
    ax.set_title("The same 6-DoF pipeline, two front ends, no odometry")
    ax.legend(fontsize="small")
    plt.show()


def plot_chained_errors(chained: dict[str, np.ndarray], truth: np.ndarray) -> None:
    """Position and heading error against ``truth`` per frame of chained planar poses
    ``{reading: poses}``, one line per reading."""
    _, axes = new_axes(2, width=5.5, height=3.4)
    for name, poses in chained.items():
        axes[0].plot(np.linalg.norm(poses[:, :2] - truth[:, :2], axis=1), label=name)
        axes[1].plot(np.degrees(wrap_angle(poses[:, 2] - truth[:, 2])), label=name)
    axes[0].set_xlabel("frame")
    axes[0].set_ylabel("position error [m]")
    axes[0].set_title("Frame-to-frame motions chained: position")
    axes[1].set_xlabel("frame")
    axes[1].set_ylabel("heading error [deg]")
    axes[1].set_title("... and heading")
    axes[0].legend(fontsize="small")
    plt.show()


def plot_inlier_counts(
    frames: np.ndarray, ransac_in: np.ndarray, refined_in: np.ndarray, share: np.ndarray
) -> None:
    """RANSAC's inliers and those the 6-DoF refinement keeps per frame, beside the share kept."""
    _, axes = new_axes(2, width=5.5, height=3.4)
    axes[0].plot(frames, ransac_in, label="1-point RANSAC inliers")
    axes[0].plot(frames, refined_in, label="after the 6-DoF refinement")
    axes[0].set_xlabel("frame")
    axes[0].set_ylabel("matches")
    axes[0].set_title("Inliers per frame")
    axes[0].legend(fontsize="small")
    axes[1].plot(frames, share, ".-")
    axes[1].set_ylim(0, 1.05)
    axes[1].set_xlabel("frame")
    axes[1].set_ylabel("refined / RANSAC inliers")
    axes[1].set_title("Share of RANSAC's inliers the refinement keeps")
    plt.show()


def plot_paths_and_errors(truth: np.ndarray, paths: dict[str, np.ndarray]) -> None:
    """Plan view of ``truth`` and the estimated ``paths`` ``{name: poses}``, beside each path's
    position error per frame in the colour the plan view gives it."""
    _, axes = new_axes(2, width=6, height=3.8)
    plot_paths(axes[0], {"truth": truth, **paths}, "Plan view (vehicle frame at frame 0)")
    for k, (name, poses) in enumerate(paths.items(), start=1):  # C0 is the truth's
        axes[1].plot(np.linalg.norm(poses[:, :2] - truth[:, :2], axis=1), f"C{k}", label=name)
    axes[1].set_xlabel("frame")
    axes[1].set_ylabel("position error [m]")
    axes[1].set_title("Error over time")
    axes[1].legend(fontsize="small")
    plt.show()
