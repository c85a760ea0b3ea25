"""Which part of a line segment lies within a laser's range: three observers ([Yan 2020], section 2).

Each returns the part of the segment ``A -> B`` within range ``D`` of the robot at ``G`` as
``(t_start, t_end)`` of ``P(t) = A + t (B - A)``, or ``None``: one interval (the distance is
convex in ``t``); the approximate observers return points inside it within ``tolerance`` metres
of its ends.

* :func:`visible_segment_point_by_point`: samples every ``tolerance`` metres (the paper's baseline).
* :func:`visible_segment_bisection`: the paper's observer, by where the foot ``O`` of the
  perpendicular from ``G`` falls: outside the segment (Fig. 3) it bisects between the near and the
  far end; inside (Fig. 4) it bisects on the longer half and mirrors the crossing about ``O``.
* :func:`visible_segment`: exact, the circle about ``G`` cut with the line (a quadratic in ``t``).
"""

from __future__ import annotations

import math

import numpy as np

#: Default accuracy of the approximate observers, metres (a tenth of [Yan 2020]'s 0.1 m range noise).
DEFAULT_TOLERANCE = 0.01


def visible_segment(a, b, centre, max_range: float, tolerance: float | None = None):
    """Exact visible part: solve ``|A + t (B - A) - G|^2 = D^2`` for ``t``, clipped to [0, 1]
    (``tolerance``, ignored, gives the three observers one signature)."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    fx, fy = a[0] - centre[0], a[1] - centre[1]
    qa = dx * dx + dy * dy
    half_b = fx * dx + fy * dy
    qc = fx * fx + fy * fy - max_range * max_range
    disc = half_b * half_b - qa * qc
    if disc < 0.0:
        return None
    root = math.sqrt(disc)
    t0, t1 = (-half_b - root) / qa, (-half_b + root) / qa
    if t0 > 1.0 or t1 < 0.0:
        return None
    return max(t0, 0.0), min(t1, 1.0)


def visible_segment_point_by_point(a, b, centre, max_range: float, tolerance: float = DEFAULT_TOLERANCE):
    """Baseline: test points every ``tolerance`` metres along the segment; first and last inside."""
    length = math.hypot(b[0] - a[0], b[1] - a[1])
    t = np.linspace(0.0, 1.0, int(math.ceil(length / tolerance)) + 1)
    px = a[0] + t * (b[0] - a[0]) - centre[0]
    py = a[1] + t * (b[1] - a[1]) - centre[1]
    inside = np.flatnonzero(px * px + py * py <= max_range * max_range)
    if inside.size == 0:
        return None
    return float(t[inside[0]]), float(t[inside[-1]])


def _bisect(a, d, centre, r2: float, t_in: float, t_out: float, t_tol: float) -> float:
    """Bisection on ``F(t) = |A + t d - G|^2 - D^2`` between an inside and an outside parameter;
    returns the inside end of the final bracket (``F <= 0``), within ``t_tol`` of the crossing."""
    ax, ay = a[0] - centre[0], a[1] - centre[1]
    while abs(t_out - t_in) > t_tol:
        t = 0.5 * (t_in + t_out)
        px, py = ax + t * d[0], ay + t * d[1]
        if px * px + py * py <= r2:
            t_in = t
        else:
            t_out = t
    return t_in


def visible_segment_bisection(a, b, centre, max_range: float, tolerance: float = DEFAULT_TOLERANCE):
    """[Yan 2020]'s observer: choose the order of computation by where the foot of the perpendicular
    from ``G`` falls (Fig. 3 and 4), decide the easy cases from end-point distances, and bisect the
    crossing of ``F = d - D_max`` otherwise."""
    d = (b[0] - a[0], b[1] - a[1])
    length2 = d[0] * d[0] + d[1] * d[1]
    t_tol = tolerance / math.sqrt(length2)
    r2 = max_range * max_range
    t_foot = ((centre[0] - a[0]) * d[0] + (centre[1] - a[1]) * d[1]) / length2

    def dist2(t):
        px, py = a[0] + t * d[0] - centre[0], a[1] + t * d[1] - centre[1]
        return px * px + py * py

    if t_foot <= 0.0 or t_foot >= 1.0:
        # Fig. 3: the distance grows monotonically from the end nearer the foot to the other.
        near, far = (0.0, 1.0) if t_foot <= 0.0 else (1.0, 0.0)
        if dist2(near) > r2:
            return None
        if dist2(far) <= r2:
            return 0.0, 1.0
        cross = _bisect(a, d, centre, r2, near, far, t_tol)
        return (near, cross) if near < cross else (cross, near)
    # Fig. 4: the foot O lies inside; bisect on the longer half O -> far end, mirror about O.
    if dist2(t_foot) > r2:
        return None
    far = 1.0 if t_foot < 0.5 else 0.0
    if dist2(far) <= r2:
        return 0.0, 1.0
    cross = _bisect(a, d, centre, r2, t_foot, far, t_tol)
    mirror = 2.0 * t_foot - cross
    if far == 1.0:
        return max(mirror, 0.0), cross
    return cross, min(mirror, 1.0)


OBSERVERS = {
    "point_by_point": visible_segment_point_by_point,
    "bisection": visible_segment_bisection,
    "closed_form": visible_segment,
}
