"""Figures and small measurements of notebooks 11 and 12 (real stereo data), out of their story cells.

Nothing here estimates motion: the functions draw, locate or measure what the notebook computed.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import cv2
import numpy as np

from vo_lib.geometry import wrap_angle


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
    gradient = np.hypot(cv2.Sobel(image, cv2.CV_32F, 1, 0), cv2.Sobel(image, cv2.CV_32F, 0, 1)) / 8
    return {
        "empty": 1 - occupied.mean(),
        "per_vga": len(corners) * 640 * 480 / (h * w),
        "flat": float(np.mean(gradient < low_gradient)),
        "corners": corners,
        "occupied": occupied,
    }
