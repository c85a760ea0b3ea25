"""One world for every sensor: a 2-D floor plan of line segments extruded to textured planes.

A :class:`World` feeds the stereo renderer, the laser scanner, the EKF-SLAM landmarks and the
pose-tracking corridor. A segment is a vertical textured rectangle standing on the floor (z = 0);
``mapped=False`` marks an obstacle the robot's map does not know (the umbrella of [Yuan]). Only the
camera sees *patches* (flat textured quads in any orientation: a road) and *movers* (textured boxes
driving along a path: traffic, a cart).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from vo_lib.sim import road
from vo_lib.sim.textures import ROAD_WIDTH

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
    texel: float | None = None  # texel size, metres; None: the world's floor_texel

    def __post_init__(self):
        if self.length <= 0:
            raise ValueError(f"segment from {self.start} to {self.end} has zero length")
        if not self.height > 0:
            raise ValueError(f"segment height must be > 0 metres; got {self.height!r}")

    @property
    def length(self) -> float:
        return float(np.hypot(self.end[0] - self.start[0], self.end[1] - self.start[1]))


@dataclass(frozen=True)
class Patch:
    """A flat textured quad: ``origin + a * along + b * across`` for ``a`` in ``[0, length]``, ``b``
    in ``[0, width]`` (metres; unit vectors). Texture columns run along ``along``, column 0 lying
    ``offset`` metres before ``origin``, so that the patches of one ribbon (a road) continue one
    texture of ``texture_length`` metres."""

    origin: tuple[float, float, float]
    along: tuple[float, float, float]
    across: tuple[float, float, float]
    length: float
    width: float
    style: str
    texture_seed: int
    offset: float = 0.0
    texture_length: float = 0.0
    outline: tuple = ()  # four 3-D corners drawn instead of the parallelogram, if given

    def __post_init__(self):
        if not (self.length > 0 and self.width > 0):
            raise ValueError(f"patch sides must be > 0 metres; got {self.length!r} x {self.width!r}")


@dataclass(frozen=True)
class Mover:
    """A textured box (four sides and a top) driving at ``speed`` along a 3-D ``path``: at time ``t``
    (seconds) its bottom centre is ``start + speed * t`` metres along it (held at its end), facing
    along it."""

    path: tuple[tuple[float, float, float], ...]
    speed: float
    size: tuple[float, float]  # length, width, metres
    height: float
    style: str
    texture_seed: int
    start: float = 0.0
    kind: str = "car"

    def pose(self, time: float) -> tuple[np.ndarray, float]:
        """Bottom centre ``(x, y, z)`` and yaw at ``time``."""
        pts = np.asarray(self.path, float)
        steps = np.linalg.norm(np.diff(pts, axis=0), axis=1)
        s = np.concatenate([[0.0], np.cumsum(steps)])
        at = float(np.clip(self.start + self.speed * time, 0.0, s[-1]))
        i = int(np.clip(np.searchsorted(s, at, side="right") - 1, 0, len(steps) - 1))
        f = (at - s[i]) / steps[i]
        d = pts[i + 1] - pts[i]
        return pts[i] + f * d, float(np.arctan2(d[1], d[0]))


@dataclass(frozen=True)
class World:
    """Segments, a textured floor over ``floor_extent`` and an optional ceiling (patches and movers:
    camera only)."""

    name: str
    segments: tuple[Segment, ...]
    floor_extent: tuple[float, float, float, float]  #: xmin, xmax, ymin, ymax (metres); beyond, background
    seed: int = 0  #: of the floor's and ceiling's textures
    ceiling_height: float | None = None  #: metres; None: open sky
    floor_texel: float = TEXEL_SIZE  #: texel size of floor and ceiling, metres
    notes: dict = field(default_factory=dict, compare=False)
    floor_style: str = "corners"  #: texture styles (:func:`vo_lib.sim.textures.surface_texture`)
    ceiling_style: str = "corners"
    patches: tuple[Patch, ...] = ()
    movers: tuple[Mover, ...] = ()

    def segments_array(self, mapped_only: bool = False) -> np.ndarray:
        """``(M, 4)`` array of ``x0, y0, x1, y1`` rows, for vectorised ray casting."""
        rows = [(*s.start, *s.end) for s in self.segments if s.mapped or not mapped_only]
        return np.array(rows, dtype=float).reshape(-1, 4)


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
    centre, size, yaw: float, height: float, seed: int, kind: str = "box", style: str = "corners"
) -> list[Segment]:
    """Four outward-facing sides of a rectangular block centred at ``centre`` with plan ``size``."""
    c, s = np.cos(yaw), np.sin(yaw)
    hx, hy = size[0] / 2, size[1] / 2
    corners = [(-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy)]
    pts = [(centre[0] + c * x - s * y, centre[1] + s * x + c * y) for x, y in corners]
    return polyline(pts, height, seed, kind, closed=True, style=style)


# ---------------------------------------------------------------------- ready-made worlds
#: The textures of an indoor world's floor and ceiling.
_INDOOR = {"floor_style": "tiles", "ceiling_style": "panels"}


def indoor_lab(seed: int = 10) -> World:
    """A 14 m x 9 m lab: painted walls 2.6 m high, two plain pillars, boxes, a cabinet, shelves of
    clutter, a tiled floor and a panelled ceiling."""
    segs = polyline([(-7, -4.5), (7, -4.5), (7, 4.5), (-7, 4.5)], 2.6, seed, closed=True, style="wall")
    segs += box((2.5, 2.0), (0.5, 0.5), 0.0, 2.6, seed + 10, "pillar", style="plain")
    segs += box((-2.0, -2.2), (0.5, 0.5), 0.0, 2.6, seed + 20, "pillar", style="plain")
    segs += box((4.8, -1.8), (1.2, 0.8), 0.3, 0.9, seed + 30)
    segs += box((-4.5, 2.6), (1.0, 1.4), -0.2, 1.2, seed + 40)
    segs += box((0.5, -3.6), (2.0, 0.6), 0.0, 1.8, seed + 50, "cabinet", style="plain")
    # shelves of equipment along the walls (x, y, yaw, width): the lab's corner-rich parts
    shelves = [(-5.5, -4.2, 0.0, 2.0), (4.0, 4.2, 0.0, 2.5), (6.7, 1.5, 1.5708, 2.0)]
    shelves += [(-6.7, -1.0, 1.5708, 2.5), (-1.5, 4.2, 0.0, 1.8), (3.5, -4.2, 0.0, 1.6)]
    for i, (x, y, yaw, w) in enumerate(shelves):
        segs += box((x, y), (w, 0.5), yaw, 1.9, seed + 60 + 4 * i, "shelf")
    return World("indoor_lab", tuple(segs), (-7.0, 7.0, -4.5, 4.5), seed, ceiling_height=2.6, **_INDOOR)


def outdoor_yard(seed: int = 20) -> World:
    """An open 80 m x 80 m yard: building fronts 8 m high, fences, a shed and crates; no ceiling.
    Most structure is 15-40 m away: low parallax for a 12 cm baseline, as outdoors in the paper."""
    square = [(-40, -40), (40, -40), (40, 40), (-40, 40)]
    segs = polyline(square, 8.0, seed, "building", closed=True, style="brick")
    segs += polyline([(18, -12), (18, 12)], 6.0, seed + 10, "building", style="brick")
    segs += polyline([(-20, 25), (5, 25)], 1.4, seed + 12, "fence", style="fence")
    segs += polyline([(-25, -16), (15, -16)], 1.4, seed + 14, "fence", style="fence")
    segs += box((8.0, 12.0), (4.0, 3.0), 0.1, 2.6, seed + 16, "shed", style="brick")
    for i, (x, y) in enumerate([(9, 5), (12, -7), (-8, 9), (-10, -6), (4, -13)]):
        segs += box((x, y), (1.2, 1.2), 0.4 * i, 1.2, seed + 20 + 4 * i, "crate")
    return World(
        "outdoor_yard", tuple(segs), (-40.0, 40.0, -40.0, 40.0), seed, floor_texel=0.02, floor_style="gravel"
    )


def corridor(seed: int = 30) -> World:
    """The corridor of [Yuan], 30 m long and 3 m wide along +x from x = 0 (axis y = 0): two long walls,
    two pillars, two cross walls, a fire hydrant and an unmapped umbrella; most of the view is plain.

    Pillars, hydrant and cross walls are the "radial" features that fix the position along the
    axis. A 10 m laser seeing 135 degrees to either side sees, from the axis, the first pillar and
    the hydrant up to x = 6.4 and the cross walls from x = 12; in between only the second pillar
    (x = 15) could, and the umbrella (x = 13.7, 1 m wide, against the wall) hides it up to x = 12.8.
    """
    h, half, length = 2.8, 1.5, 30.0
    segs = polyline([(0, -half), (length, -half)], h, seed, "wall", style="wall")
    segs += polyline([(0, half), (length, half)], h, seed + 1, "wall", style="wall")
    segs += polyline([(0, -half), (0, half)], h, seed + 2, "end wall", style="wall")
    segs += polyline([(length, -half), (length, half)], h, seed + 3, "end wall", style="wall")
    segs += box((3.5, half - 0.2), (0.5, 0.4), 0.0, h, seed + 10, "pillar", style="plain")
    segs += box((5.0, -half + 0.15), (0.4, 0.3), 0.0, 0.9, seed + 20, "fire hydrant")
    segs += box((15.0, half - 0.2), (0.5, 0.4), 0.0, h, seed + 40, "pillar", style="plain")
    segs += polyline([(22.0, half), (22.0, half - 0.6)], h, seed + 30, "cross wall", style="wall")
    segs += polyline([(24.5, -half), (24.5, -half + 0.6)], h, seed + 31, "cross wall", style="wall")
    # an open umbrella against the wall: at the laser's height, a half circle of radius 0.55 m
    angles = np.radians(np.linspace(90.0, 270.0, 7))
    canopy = [(13.9 + 0.55 * np.cos(a), half - 0.55 + 0.55 * np.sin(a)) for a in angles]
    segs += polyline(canopy, 1.6, seed + 50, "umbrella", mapped=False)
    notes = {"length": length, "width": 2 * half}
    return World(
        "corridor", tuple(segs), (0.0, length, -half, half), seed, ceiling_height=h, notes=notes, **_INDOOR
    )


#: Texel size of the objects beside the road (seen from a few metres), metres.
NEAR_TEXEL = 0.02
#: Far structure: how far beyond the road's extent it stands and how high, metres.
FAR_DISTANCE, FAR_HEIGHT = 80.0, 14.0


def _ribbon_breaks(s, poses) -> list[int]:
    """Indices cutting a centre line into pieces up to 6 m long, nearly flat, straight and even."""
    breaks, first = [0], 0
    g, c = road.grade(s), road.crossfall(s)
    for i in range(1, len(s)):
        bent = abs(poses[i, 2] - poses[first, 2]) > np.radians(1.0)
        changed = abs(g[i] - g[first]) > 0.004 or abs(c[i] - c[first]) > 0.004
        if bent or changed or s[i] - s[first] > 6.0 or i == len(s) - 1:
            breaks.append(i)
            first = i
    return breaks


def road_ribbon(seed: int) -> tuple[Patch, ...]:
    """The road surface along :func:`vo_lib.sim.road.centre_line`: one patch per piece, each a
    quad whose ends stand square to the road (so that pieces meet without gaps in the bends)."""
    s, poses = road.centre_line()
    c = road.crossfall(s)
    left = np.column_stack([-np.sin(poses[:, 2]), np.cos(poses[:, 2]), c])  # per metre to the left
    centre = np.column_stack([poses[:, :2] + road.LANE_OFFSET * left[:, :2], road.elevation(s)])
    half, total = ROAD_WIDTH / 2, float(s[-1] - s[0])
    patches = []
    breaks = _ribbon_breaks(s, poses)
    for i, j in zip(breaks[:-1], breaks[1:], strict=True):
        step = centre[j] - centre[i]
        length = float(np.linalg.norm(step))
        mid = left[i] + left[j]
        along, across = tuple(step / length), tuple(-mid / np.linalg.norm(mid))
        ends = ((i, 1), (j, 1), (j, -1), (i, -1))  # left edge at i and j, right edge at j and i
        outline = tuple(tuple(centre[k] + side * half * left[k]) for k, side in ends)
        offset = float(s[i] - s[0])
        patches.append(
            Patch(outline[0], along, across, length, ROAD_WIDTH, "road", seed, offset, total, outline)
        )
    return tuple(patches)


def _lane(offset: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Arc lengths and poses of the centre line every 2 m, unit vectors to its left and the 3-D
    points ``offset`` metres left of the car's lane."""
    s, poses = road.centre_line(2.0)
    left = np.column_stack([-np.sin(poses[:, 2]), np.cos(poses[:, 2])])
    z = road.elevation(s) + road.crossfall(s) * (offset - road.LANE_OFFSET)
    return s, poses, left, np.column_stack([poses[:, :2] + offset * left, z])


def road_traffic(seed: int) -> tuple[Mover, ...]:
    """Two oncoming cars that pass the driven car on the first and last straights, and one ahead."""
    ego_s = road.arc_length(road.planned_path())
    movers = []
    s, _, _, points = _lane(2 * road.LANE_OFFSET)
    oncoming_s, oncoming = s[::-1], points[::-1]  # driven the other way
    lane = tuple(map(tuple, oncoming))
    for i, (frame, speed) in enumerate(((35, 10.0), (185, 8.0))):
        # metres along its lane to where the driven car is at the frame they pass each other
        along = float(np.sum(np.linalg.norm(np.diff(oncoming[oncoming_s >= ego_s[frame]], axis=0), axis=1)))
        start = along - speed * frame / road.RATE
        movers.append(Mover(lane, speed, (4.3, 1.8), 1.5, "vehicle", seed + 10 * i, start))
    ahead_s, _, _, ahead = _lane(0.0)
    start = float(np.sum(np.linalg.norm(np.diff(ahead[ahead_s <= 40.0], axis=0), axis=1)))
    movers.append(Mover(tuple(map(tuple, ahead)), 11.0, (4.5, 1.8), 1.6, "vehicle", seed + 30, start))
    return tuple(movers)


def road_side(seed: int) -> list[Segment]:
    """Buildings, trees, fences and parked cars beside the road, and far low-contrast structure."""
    rng = np.random.default_rng(seed)
    s, poses, left, lane = _lane(road.LANE_OFFSET)
    road_xy = lane[:, :2]
    segs: list[Segment] = []
    kinds = ("building", "tree", "fence", "parked car", "building", "tree")
    for k in range(0, len(s), 4):
        for side in (1.0, -1.0):
            kind = kinds[int(rng.integers(len(kinds)))]
            size, height, style, gap = {
                "building": ((rng.uniform(8, 15), rng.uniform(6, 10)), rng.uniform(6, 14), "brick", 4.0),
                "tree": ((1.2, 1.2), rng.uniform(4, 7), "grass", 2.0),
                "fence": ((rng.uniform(8, 14), 0.1), 1.5, "fence", 2.5),
                "parked car": ((4.3, 1.8), 1.5, "vehicle", 0.6),
            }[kind]
            if kind == "building" and rng.random() < 0.3:
                style = "wall"
            centre = road_xy[k] + side * left[k] * (ROAD_WIDTH / 2 + gap + size[1] / 2 + rng.uniform(0, 4))
            reach = np.hypot(*size) / 2 + ROAD_WIDTH / 2 + 0.3
            if np.min(np.linalg.norm(road_xy - centre, axis=1)) < reach:
                continue  # would stand on the road (inside a bend)
            near = box(tuple(centre), size, poses[k, 2], height, seed + 100 + len(segs), kind, style=style)
            segs += [replace(seg, texel=NEAR_TEXEL) for seg in near]
    lo, hi = road_xy.min(axis=0) - FAR_DISTANCE, road_xy.max(axis=0) + FAR_DISTANCE
    ring = [(lo[0], lo[1]), (hi[0], lo[1]), (hi[0], hi[1]), (lo[0], hi[1])]
    segs += polyline(ring, FAR_HEIGHT, seed + 5000, "far structure", closed=True, style="far")
    return segs


def road_world(seed: int = 40) -> World:
    """A road drive's world (:mod:`vo_lib.sim.road`): the road along the car's path, what stands beside
    it (:func:`road_side`), rough ground up to the far structure, the sky and traffic."""
    segs = road_side(seed)
    _, poses = road.centre_line(5.0)
    # grass up to the far structure (whose ring is measured from the road's edge points)
    lo, hi = poses[:, :2].min(axis=0) - FAR_DISTANCE - 5.0, poses[:, :2].max(axis=0) + FAR_DISTANCE + 5.0
    return World(
        "road",
        tuple(segs),
        (float(lo[0]), float(hi[0]), float(lo[1]), float(hi[1])),
        seed,
        floor_texel=0.06,
        floor_style="gravel",
        patches=road_ribbon(seed + 1),
        movers=road_traffic(seed + 2),
    )


def indoor_lab_cart(seed: int = 10) -> World:
    """The lab with a trolley of boxes (1.0 m x 0.6 m, 1.1 m high) pushed back and forth along its
    north side at walking pace: an independently moving object."""
    path = ((-5.0, 3.0, 0.0), (5.0, 3.0, 0.0)) * 3
    cart = Mover(path, 0.7, (1.0, 0.6), 1.1, "corners", seed + 90, kind="cart")
    return replace(indoor_lab(seed), name="indoor_lab_cart", movers=(cart,))


WORLDS = {
    "indoor_lab_cart": indoor_lab_cart,
    "indoor_lab": indoor_lab,
    "outdoor_yard": outdoor_yard,
    "corridor": corridor,
    "road": road_world,
}
