"""A 2-D laser scanner ray-cast against the world's segments, vectorised over beams x segments.

Beam ``i`` leaves the sensor at bearing ``b_i`` (radians, counter-clockwise from the sensor's x
axis). With the beam ``o + r (cos, sin)`` and a segment ``p + t s``, ``t in [0, 1]``, the crossing
solves a 2x2 system by cross products: ``r = (p - o) x s / (d x s)``, ``t = (p - o) x d / (d x s)``.
The nearest positive ``r`` over all segments is the range, so nearer segments occlude farther ones.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vo_lib.geometry import compose_planar


@dataclass(frozen=True)
class LaserScan:
    """Bearings (radians, sensor frame), ranges (metres) and which beams returned an echo."""

    bearings: np.ndarray
    ranges: np.ndarray
    valid: np.ndarray

    def points(self) -> np.ndarray:
        """``(K, 2)`` end points of the valid beams in the sensor frame."""
        b, r = self.bearings[self.valid], self.ranges[self.valid]
        return np.column_stack([r * np.cos(b), r * np.sin(b)])


@dataclass(frozen=True)
class LaserScanner:
    """A planar scanner: by default 270 degrees in 1/3 degree steps, 10 m (the SICK TIM551 of [Yuan]
    steps 1 degree: ``corridor_experiment.TIM551``)."""

    fov: float = np.radians(270.0)  #: field of view, radians, centred on the sensor's x axis
    angular_step: float = np.radians(1.0 / 3.0)  #: between beams, radians
    max_range: float = 10.0  #: metres; beams that hit nothing nearer are invalid
    range_sigma: float = 0.01  #: standard deviation of a range, metres
    mount: tuple[float, float, float] = (0.0, 0.0, 0.0)  #: x, y, yaw of the sensor in the robot frame

    def __post_init__(self):
        for name in ("fov", "angular_step", "max_range"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be > 0; got {getattr(self, name)!r}")
        if self.range_sigma < 0:
            raise ValueError("range_sigma must be >= 0")

    @property
    def bearings(self) -> np.ndarray:
        n = int(round(self.fov / self.angular_step)) + 1
        return (np.arange(n) - (n - 1) / 2) * self.angular_step

    def scan(self, segments, robot_pose, rng: np.random.Generator | None = None) -> LaserScan:
        """Scan ``segments`` (``(M, 4)``: x0, y0, x1, y1, world frame) from ``robot_pose``, with
        range noise only when an ``rng`` is given."""
        segs = np.asarray(segments, dtype=float).reshape(-1, 4)
        sensor = compose_planar(np.asarray(robot_pose, dtype=float), np.asarray(self.mount, dtype=float))
        bearings = self.bearings
        ranges = cast_rays(segs, sensor[:2], sensor[2] + bearings)
        if rng is not None and self.range_sigma > 0:
            ranges = ranges + rng.normal(0.0, self.range_sigma, ranges.shape)
        valid = np.isfinite(ranges) & (ranges <= self.max_range) & (ranges > 0)
        return LaserScan(bearings, np.where(valid, ranges, np.inf), valid)


def cast_rays(segments: np.ndarray, origin, angles) -> np.ndarray:
    """Range to the nearest segment along each ray from ``origin`` (``inf`` where none is hit)."""
    d = np.stack([np.cos(angles), np.sin(angles)], axis=-1)[:, None, :]  # (B, 1, 2)
    p = segments[None, :, :2]
    s = segments[None, :, 2:] - segments[None, :, :2]  # (1, M, 2)
    q = p - np.asarray(origin, dtype=float)
    denom = d[..., 0] * s[..., 1] - d[..., 1] * s[..., 0]  # d x s, (B, M)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = (q[..., 0] * s[..., 1] - q[..., 1] * s[..., 0]) / denom
        t = (q[..., 0] * d[..., 1] - q[..., 1] * d[..., 0]) / denom
    hit = (np.abs(denom) > 1e-12) & (r > 0) & (t >= 0) & (t <= 1)
    return np.where(hit, r, np.inf).min(axis=1)
