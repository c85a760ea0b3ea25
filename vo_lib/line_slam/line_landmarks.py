"""Line-segment landmarks of [Yan 2020] and their "landmark feature point".

A landmark is a wall segment of the shared :class:`~vo_lib.sim.world.World`; the filter carries
the foot of the perpendicular from the world origin to its line ([Yan 2020], section 1.3).
"""

from __future__ import annotations

import math

import numpy as np

from vo_lib.sim.world import Segment, World

#: [Yan 2020]'s four landmarks: (left x, right x, slope, intercept). Section 3 lists landmark 3 as
#: (0, 60, 7/9, -35), but its out-of-range case moves the right end "from 45 to 60": we read the
#: list as the extended landmark and take x = 45 for the normal case.
PAPER_LANDMARKS = (
    (-30.0, 0.0, 2.0 / 3.0, 30.0),
    (0.0, 20.0, -1.0, 20.0),
    (0.0, 45.0, 7.0 / 9.0, -35.0),
    (-60.0, 0.0, -0.7, -35.0),
)
#: The out-of-range case: landmark 3's right end moved from x = 45 to x = 60.
EXTENDED_RIGHT_X = 60.0
#: The paper's observed right end of the extended landmark 3.
PAPER_EXTENDED_RIGHT_END = 54.4412


def segment_from_slope(
    left_x: float, right_x: float, slope: float, intercept: float, seed: int = 0
) -> Segment:
    """The segment of ``y = slope x + intercept`` between ``left_x`` and ``right_x``."""
    if not right_x > left_x:
        raise ValueError(f"right_x must exceed left_x; got left_x={left_x!r}, right_x={right_x!r}")
    start = (left_x, slope * left_x + intercept)
    end = (right_x, slope * right_x + intercept)
    return Segment(start, end, height=2.0, kind="line landmark", texture_seed=seed)


def paper_world(extended: bool = False) -> World:
    """[Yan 2020]'s landmarks as a world; ``extended`` moves landmark 3's right end to x = 60."""
    rows = [list(r) for r in PAPER_LANDMARKS]
    if extended:
        rows[2][1] = EXTENDED_RIGHT_X
    segs = tuple(segment_from_slope(*r, seed=i) for i, r in enumerate(rows))
    return World("yan2020_landmarks", segs, (-65.0, 65.0, -45.0, 45.0), seed=2)


def feature_point(a, b) -> np.ndarray:
    """Foot of the perpendicular from the world origin to the line through ``a`` and ``b``."""
    a = np.asarray(a, dtype=float)
    d = np.asarray(b, dtype=float) - a
    return a - d * (a @ d) / (d @ d)


def line_direction(point) -> np.ndarray:
    """Unit direction of the line of feature point ``point`` (``point`` turned counter-clockwise)."""
    return np.array([-point[1], point[0]]) / math.hypot(point[0], point[1])


def along_line(point, positions) -> np.ndarray:
    """Coordinates of ``positions`` (N x 2) along the line of feature point ``point``."""
    return np.asarray(positions, dtype=float).reshape(-1, 2) @ line_direction(point)


def line_points(point, along) -> np.ndarray:
    """Points of the line of feature point ``point`` at coordinates ``along``."""
    return np.asarray(point, dtype=float) + np.outer(np.atleast_1d(along), line_direction(point))
