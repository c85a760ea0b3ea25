"""One world for every sensor: a 2-D floor plan of line segments extruded to textured planes.

The same :class:`World` feeds the stereo renderer (``vo_lib.sim.render``), the laser scanner
(``vo_lib.sim.laser``), the line landmarks of the EKF-SLAM notebook and the corridor of the
pose-tracking notebook. A segment is a vertical rectangle standing on the floor (z = 0) between
two plan points, with a height and a texture seed; ``mapped=False`` marks an obstacle the robot's
map does not know (the umbrella of seed 004).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

#: World-space size of one texel, metres.
TEXEL_SIZE = 0.01


@dataclass(frozen=True)
class Segment:
    """A vertical textured wall from ``start`` to ``end`` (plan coordinates, metres)."""

    start: tuple[float, float]
    end: tuple[float, float]
    height: float = 2.5
    kind: str = "wall"
    mapped: bool = True
    texture_seed: int = 0
    style: str = "corners"  # texture style, see vo_lib.sim.textures.surface_texture

    def __post_init__(self):
        if self.length <= 0:
            raise ValueError(f"segment from {self.start} to {self.end} has zero length")
        if not self.height > 0:
            raise ValueError(f"segment height must be > 0 metres; got {self.height!r}")

    @property
    def length(self) -> float:
        return float(np.hypot(self.end[0] - self.start[0], self.end[1] - self.start[1]))


@dataclass(frozen=True)
class World:
    """Segments, a textured floor over ``floor_extent`` and an optional ceiling.

    Parameters
    ----------
    name : str
    segments : tuple of Segment
    floor_extent : (xmin, xmax, ymin, ymax)
        Rectangle of textured floor, metres; beyond it the renderer shows nothing (background).
    seed : int
        Seed of the floor's and ceiling's textures.
    ceiling_height : float, optional
        Height of a textured ceiling, metres; ``None`` for open sky.
    floor_texel : float
        Texel size of floor and ceiling (outdoor floors use coarser texels).
    floor_style, ceiling_style : str
        Texture styles of floor and ceiling (:func:`vo_lib.sim.textures.surface_texture`).
    """

    name: str
    segments: tuple[Segment, ...]
    floor_extent: tuple[float, float, float, float]
    seed: int = 0
    ceiling_height: float | None = None
    floor_texel: float = TEXEL_SIZE
    notes: dict = field(default_factory=dict, compare=False)
    floor_style: str = "corners"
    ceiling_style: str = "corners"

    def segments_array(self, mapped_only: bool = False) -> np.ndarray:
        """``(M, 4)`` array of ``x0, y0, x1, y1`` rows, for vectorised ray casting."""
        rows = [(*s.start, *s.end) for s in self.segments if s.mapped or not mapped_only]
        return np.array(rows, dtype=float).reshape(-1, 4)

    def with_segments(self, extra) -> World:
        """A copy of this world with more segments."""
        return World(
            self.name,
            self.segments + tuple(extra),
            self.floor_extent,
            self.seed,
            self.ceiling_height,
            self.floor_texel,
            dict(self.notes),
            self.floor_style,
            self.ceiling_style,
        )


# ---------------------------------------------------------------------- building blocks
def polyline(
    points,
    height: float,
    seed: int,
    kind: str = "wall",
    closed: bool = False,
    mapped: bool = True,
    style: str = "corners",
) -> list[Segment]:
    """Segments joining consecutive plan points; texture seeds count up from ``seed``."""
    pts = [tuple(map(float, p)) for p in points]
    if closed:
        pts.append(pts[0])
    pairs = zip(pts[:-1], pts[1:], strict=True)
    return [Segment(a, b, height, kind, mapped, seed + i, style) for i, (a, b) in enumerate(pairs)]


def box(
    centre,
    size,
    yaw: float,
    height: float,
    seed: int,
    kind: str = "box",
    mapped: bool = True,
    style: str = "corners",
) -> list[Segment]:
    """Four outward-facing sides of a rectangular block centred at ``centre`` with plan ``size``."""
    c, s = np.cos(yaw), np.sin(yaw)
    hx, hy = size[0] / 2, size[1] / 2
    corners = [(-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy)]
    pts = [(centre[0] + c * x - s * y, centre[1] + s * x + c * y) for x, y in corners]
    return polyline(pts, height, seed, kind, closed=True, mapped=mapped, style=style)


# ---------------------------------------------------------------------- ready-made worlds
def indoor_lab(seed: int = 10) -> World:
    """A 14 m x 9 m lab: painted walls 2.6 m high with doors and posters, two plain pillars,
    boxes (corner-rich clutter) and a plain cabinet, a tiled floor and a ceiling of panels."""
    segs = polyline([(-7, -4.5), (7, -4.5), (7, 4.5), (-7, 4.5)], 2.6, seed, closed=True, style="wall")
    segs += box((2.5, 2.0), (0.5, 0.5), 0.0, 2.6, seed + 10, "pillar", style="plain")
    segs += box((-2.0, -2.2), (0.5, 0.5), 0.0, 2.6, seed + 20, "pillar", style="plain")
    segs += box((4.8, -1.8), (1.2, 0.8), 0.3, 0.9, seed + 30)
    segs += box((-4.5, 2.6), (1.0, 1.4), -0.2, 1.2, seed + 40)
    segs += box((0.5, -3.6), (2.0, 0.6), 0.0, 1.8, seed + 50, "cabinet", style="plain")
    # shelves of equipment and clutter along the walls: the lab's corner-rich parts
    for i, (x, y, yaw, w) in enumerate(
        [
            (-5.5, -4.2, 0.0, 2.0),
            (4.0, 4.2, 0.0, 2.5),
            (6.7, 1.5, 1.5708, 2.0),
            (-6.7, -1.0, 1.5708, 2.5),
            (-1.5, 4.2, 0.0, 1.8),
            (3.5, -4.2, 0.0, 1.6),
        ]
    ):
        segs += box((x, y), (w, 0.5), yaw, 1.9, seed + 60 + 4 * i, "shelf")
    return World(
        "indoor_lab",
        tuple(segs),
        (-7.0, 7.0, -4.5, 4.5),
        seed,
        ceiling_height=2.6,
        floor_style="tiles",
        ceiling_style="panels",
    )


def outdoor_yard(seed: int = 20) -> World:
    """An open 80 m x 80 m yard: far building fronts 8 m high, a few crates; no ceiling.

    Most structure is 15-40 m away: low parallax for a 12 cm baseline, as in the paper's
    outdoor experiments.
    """
    square = [(-40, -40), (40, -40), (40, 40), (-40, 40)]
    segs = polyline(square, 8.0, seed, "building", closed=True, style="brick")
    segs += polyline([(18, -12), (18, 12)], 6.0, seed + 10, "building", style="brick")
    segs += polyline([(-20, 25), (5, 25)], 1.4, seed + 12, "fence", style="fence")
    segs += polyline([(-25, -16), (15, -16)], 1.4, seed + 14, "fence", style="fence")
    segs += box((8.0, 12.0), (4.0, 3.0), 0.1, 2.6, seed + 16, "shed", style="brick")
    for i, (x, y) in enumerate([(9, 5), (12, -7), (-8, 9), (-10, -6), (4, -13)]):
        segs += box((x, y), (1.2, 1.2), 0.4 * i, 1.2, seed + 20 + 4 * i, "crate")
    return World(
        "outdoor_yard",
        tuple(segs),
        (-40.0, 40.0, -40.0, 40.0),
        seed,
        None,
        floor_texel=0.02,
        floor_style="gravel",
    )


def corridor(seed: int = 30, length: float = 30.0, width: float = 3.0) -> World:
    """The corridor of seed 004: two long walls, two pillars, two cross walls, a fire hydrant,
    and an unmapped umbrella that hides the second pillar from the stretch before it.

    The corridor runs along +x from x = 0; its axis is y = 0. Pillars, hydrant and cross walls
    are the "radial" features that fix the robot's position along the axis. With a 10 m laser
    that sees 135 degrees to either side, a robot on the axis sees the first pillar and the
    hydrant up to x = 6.4 and the cross walls from x = 12; in between only the second pillar
    (x = 15) could fix it, and the umbrella (x = 13.7, open, 1 m wide, standing against the
    wall) hides that pillar up to x = 12.8.
    """
    h, half = 2.8, width / 2
    segs = polyline([(0, -half), (length, -half)], h, seed, "wall")
    segs += polyline([(0, half), (length, half)], h, seed + 1, "wall")
    segs += polyline([(0, -half), (0, half)], h, seed + 2, "end wall")
    segs += polyline([(length, -half), (length, half)], h, seed + 3, "end wall")
    segs += box((3.5, half - 0.2), (0.5, 0.4), 0.0, h, seed + 10, "pillar")
    segs += box((5.0, -half + 0.15), (0.4, 0.3), 0.0, 0.9, seed + 20, "fire hydrant")
    segs += box((15.0, half - 0.2), (0.5, 0.4), 0.0, h, seed + 40, "pillar")
    segs += polyline([(22.0, half), (22.0, half - 0.6)], h, seed + 30, "cross wall")
    segs += polyline([(24.5, -half), (24.5, -half + 0.6)], h, seed + 31, "cross wall")
    # An open umbrella standing against the wall: at the laser's height its canopy is a half
    # circle of radius 0.55 m facing the robot's side of the corridor.
    angles = np.radians(np.linspace(90.0, 270.0, 7))
    canopy = [(13.9 + 0.55 * np.cos(a), half - 0.55 + 0.55 * np.sin(a)) for a in angles]
    segs += polyline(canopy, 1.6, seed + 50, "umbrella", mapped=False)
    return World(
        "corridor",
        tuple(segs),
        (0.0, length, -half, half),
        seed,
        ceiling_height=h,
        notes={"length": length, "width": width},
    )


WORLDS = {"indoor_lab": indoor_lab, "outdoor_yard": outdoor_yard, "corridor": corridor}
