"""Likelihood field of a world's mapped segments, and the scores of candidate poses against one
laser scan ([Yuan], section III.A).

Each cell holds ``exp(-d^2 / (2 sigma^2))``, ``d`` its distance to the nearest occupied cell; a
pose's score is the sum of the field at the scan's end points: between 0 and the number of beams.
Reading the field is compiled (:func:`field_at`, one pass where NumPy's :func:`field_at_plain`
makes several, with the same arithmetic and so the same scores): it is most of a tracker's time.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import cv2
import numpy as np

from vo_lib.compiled import jit

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
        x, y, heading = (np.ascontiguousarray(poses[:, i]) for i in range(3))
        px, py = (np.ascontiguousarray(scan_points[:, i], dtype=float) for i in range(2))
        grid = (self._padded, *self.field.shape, *self.origin, self.resolution)
        return field_at(*grid, x, y, np.cos(heading), np.sin(heading), px, py).sum(axis=1)


@jit
def field_at(padded, rows, cols, origin_x, origin_y, resolution, x, y, c, s, px, py):
    """As :func:`field_at_plain`, one pose and one point at a time."""
    out = np.empty((x.shape[0], px.shape[0]))
    for i in range(x.shape[0]):
        for k in range(px.shape[0]):
            col = min(max(np.rint((x[i] + c[i] * px[k] - s[i] * py[k] - origin_x) / resolution), -1.0), cols)
            row = min(max(np.rint((y[i] + s[i] * px[k] + c[i] * py[k] - origin_y) / resolution), -1.0), rows)
            out[i, k] = padded[int(row + 1) * (cols + 2) + int(col + 1)]
    return out


def field_at_plain(padded, rows, cols, origin_x, origin_y, resolution, x, y, c, s, px, py):
    """The field (flattened, with a border of zeros: ``padded``) at the nearest cell of each point
    ``(px, py)`` seen from each pose ``(x, y)`` with heading cosine ``c`` and sine ``s``: ``(n, K)``."""
    x, y, c, s = (v[:, None] for v in (x, y, c, s))
    col = np.clip(np.rint((x + c * px - s * py - origin_x) / resolution), -1, cols).astype(np.intp)
    row = np.clip(np.rint((y + s * px + c * py - origin_y) / resolution), -1, rows).astype(np.intp)
    return padded.take((row + 1) * (cols + 2) + (col + 1)).astype(np.float64)
