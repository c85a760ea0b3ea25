"""Likelihood field of a world's mapped segments, and the scores of candidate poses against one
laser scan ([Yuan], section III.A).

Each cell holds ``exp(-d^2 / (2 sigma^2))``, ``d`` its distance to the nearest occupied cell; a
pose's score is the sum of the field at the scan's end points: between 0 and the number of beams.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import cv2
import numpy as np

#: Grid cell size, metres, and the field's spread, metres.
DEFAULT_RESOLUTION = 0.05
DEFAULT_SIGMA = 0.1
#: Free margin around the world's floor, metres.
MARGIN = 1.0


@dataclass(frozen=True)
class LikelihoodField:
    """A likelihood field on a grid: ``field[row, col]``, row = y, col = x."""

    field: np.ndarray
    origin: tuple[float, float]
    resolution: float
    sigma: float

    @classmethod
    def from_world(cls, world) -> LikelihoodField:
        """Rasterise the world's *mapped* segments (unmapped obstacles are not in the map)."""
        resolution, sigma = DEFAULT_RESOLUTION, DEFAULT_SIGMA
        xmin, xmax, ymin, ymax = world.floor_extent
        origin = (xmin - MARGIN, ymin - MARGIN)
        cols = int(np.ceil((xmax - xmin + 2 * MARGIN) / resolution)) + 1
        rows = int(np.ceil((ymax - ymin + 2 * MARGIN) / resolution)) + 1
        occupied = np.zeros((rows, cols), np.uint8)
        ends = world.segments_array(mapped_only=True).reshape(-1, 2, 2)  # (x, y) of both ends
        for p0, p1 in np.rint((ends - origin) / resolution).astype(int).tolist():  # nearest cells
            cv2.line(occupied, p0, p1, 1, 1)
        distance = cv2.distanceTransform(1 - occupied, cv2.DIST_L2, cv2.DIST_MASK_PRECISE) * resolution
        field = np.exp(-0.5 * (distance / sigma) ** 2).astype(np.float32)
        return cls(field, origin, resolution, sigma)

    @functools.cached_property
    def _padded(self) -> np.ndarray:
        """The field with a border of zero cells, flattened: every clipped index reads a value."""
        return np.pad(self.field, 1).ravel()

    def score(self, poses: np.ndarray, scan_points: np.ndarray) -> np.ndarray:
        """Score of each pose ``(n, 3)`` for sensor-frame end points ``(K, 2)``: the field summed
        at the nearest cells (0 off the grid)."""
        poses = np.atleast_2d(np.asarray(poses, dtype=float))
        c, s = np.cos(poses[:, 2:3]), np.sin(poses[:, 2:3])
        px, py = scan_points[:, 0], scan_points[:, 1]
        col = np.rint((poses[:, 0:1] + c * px - s * py - self.origin[0]) / self.resolution).astype(np.intp)
        row = np.rint((poses[:, 1:2] + s * px + c * py - self.origin[1]) / self.resolution).astype(np.intp)
        rows, cols = self.field.shape
        np.clip(col, -1, cols, out=col)
        np.clip(row, -1, rows, out=row)
        return self._padded.take((row + 1) * (cols + 2) + (col + 1)).sum(axis=1, dtype=np.float64)
