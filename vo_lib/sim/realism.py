"""How hard an image is for a corner-based front end: three statistics to compare rendered and real frames.

``empty_cells``: the share of 16 x 16-pixel cells (those cut by the right and bottom borders too)
holding no FAST corner (FAST-9/16 at threshold 20, non-maximum suppression). ``corners_per_vga``:
the number of those corners scaled to a 640 x 480 image. ``low_gradient``: the share of pixels
whose unnormalised 3 x 3 Sobel gradient magnitude is below 20 (a step of 5 grey levels gives 20).
On 20 frames spread evenly over KITTI raw drive 2011_09_26_0001 these give 0.40, 4,105 and 0.34.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import cv2
import numpy as np

#: Side of a grid cell, pixels.
CELL_PIXELS = 16
#: FAST intensity threshold of the corner statistics.
FAST_THRESHOLD = 20
#: Gradient magnitude (unnormalised 3x3 Sobel) below which a pixel counts as flat.
LOW_GRADIENT = 20.0
#: Image area the corner count is scaled to: 640 x 480 pixels.
VGA_PIXELS = 640 * 480


@dataclass(frozen=True)
class ImageStatistics:
    """The three statistics of one image (or their means over several)."""

    empty_cells: float
    corners_per_vga: float
    low_gradient: float

    @staticmethod
    def mean(rows) -> ImageStatistics:
        """The mean of each statistic over ``rows`` (a non-empty iterable of ImageStatistics)."""
        rows = list(rows)
        if not rows:
            raise ValueError("the mean of no statistics is undefined: give at least one image")
        return ImageStatistics(
            *(float(np.mean([getattr(r, f.name) for r in rows])) for f in fields(ImageStatistics))
        )


def occupied_cells(shape, corners: np.ndarray) -> np.ndarray:
    """Boolean grid, one entry per :data:`CELL_PIXELS`-square cell of an image of ``shape``: has a corner."""
    h, w, cell = *shape[:2], CELL_PIXELS
    grid = np.zeros((-(-h // cell), -(-w // cell)), bool)
    col, row = (np.asarray(corners, dtype=float).reshape(-1, 2) // cell).astype(int).T
    grid[row, col] = True
    return grid


def gradient_magnitude(image: np.ndarray) -> np.ndarray:
    """``sqrt(gx^2 + gy^2)`` of the unnormalised 3x3 Sobel derivatives, float32."""
    gx = cv2.Sobel(image, cv2.CV_32F, 1, 0, ksize=3)
    gy = cv2.Sobel(image, cv2.CV_32F, 0, 1, ksize=3)
    return cv2.magnitude(gx, gy)


def image_statistics(image: np.ndarray) -> ImageStatistics:
    """The empty-cell share, corners per 640x480 and low-gradient share of a grey uint8 image."""
    image = np.asarray(image)
    if image.ndim != 2 or image.dtype != np.uint8 or min(image.shape) < 3:
        raise ValueError(
            f"expected a grey uint8 image of at least 3x3 pixels; got {image.dtype} {image.shape}"
        )
    detector = cv2.FastFeatureDetector_create(FAST_THRESHOLD, True, cv2.FAST_FEATURE_DETECTOR_TYPE_9_16)
    corners = np.array([k.pt for k in detector.detect(image)], dtype=float).reshape(-1, 2)  # (u, v)
    return ImageStatistics(
        empty_cells=float(1.0 - occupied_cells(image.shape, corners).mean()),
        corners_per_vga=len(corners) * VGA_PIXELS / image.size,
        low_gradient=float(np.mean(gradient_magnitude(image) < LOW_GRADIENT)),
    )


def spread_frames(count: int, wanted: int = 20) -> np.ndarray:
    """Indices of ``wanted`` frames spread evenly over ``count`` (all of them if fewer)."""
    if count <= 0:
        raise ValueError(f"a sequence of {count} frames has none to measure")
    return np.unique(np.linspace(0, count - 1, min(wanted, count)).astype(int))
