"""Grey-level textures, deterministic by seed: procedural corner-rich ones, photographs, paint.

The corner texture is blocky noise at several scales (grids upsampled nearest-neighbour, shifted at
random so that block corners do not line up across scales: FAST corners at every distance) plus
filled polygons and discs. Real surfaces are poorer in corners: :func:`surface_texture` draws each
style of :data:`_DRAW` (photographs are scikit-image's, tiled mirrored at a physical scale).
Mipmaps (Gaussian pyramids) let the renderer sample far surfaces without aliasing.
"""

from __future__ import annotations

import functools

import cv2
import numpy as np
import skimage.data

#: Block sizes (texels) and weights of the blocky noise layers.
BLOCK_LAYERS = ((96, 0.25), (24, 0.30), (6, 0.30), (2, 0.15))
#: Polygons per million texels.
SHAPES_PER_MEGATEXEL = 400
#: Grey levels the texture is stretched to, leaving room for shading and exposure.
GREY_RANGE = (25.0, 230.0)
#: Coarsest mipmap side in texels.
MIN_MIP_SIDE = 8


def corner_texture(height: int, width: int, seed: int) -> np.ndarray:
    """A ``(height, width)`` uint8 texture; the same arguments always give the same texels."""
    if height <= 0 or width <= 0:
        raise ValueError(f"texture size must be positive; got {height}x{width}")
    rng = np.random.default_rng(seed)
    img = np.zeros((height, width), np.float32)
    for block, weight in BLOCK_LAYERS:
        oy, ox = rng.integers(0, block, 2)
        gh, gw = (height + oy) // block + 1, (width + ox) // block + 1
        grid = rng.uniform(-1.0, 1.0, (gh, gw)).astype(np.float32)
        up = cv2.resize(grid, (gw * block, gh * block), interpolation=cv2.INTER_NEAREST)
        img += weight * up[oy : oy + height, ox : ox + width]
    n_shapes = int(SHAPES_PER_MEGATEXEL * height * width / 1e6) + 4
    sizes = rng.uniform(4, 40, n_shapes)
    centres = rng.uniform((0, 0), (width, height), (n_shapes, 2))
    levels = rng.uniform(-0.8, 0.8, n_shapes)
    kinds = rng.integers(0, 3, n_shapes)
    angles = rng.uniform(0, 2 * np.pi, (n_shapes, 5))
    for c, s, level, kind, ang in zip(centres, sizes, levels, kinds, angles, strict=True):
        if kind == 2:
            cv2.circle(img, (int(c[0]), int(c[1])), int(s / 2), float(level), -1)
        else:
            a = np.sort(ang[: 3 if kind == 0 else 5])  # a triangle or a pentagon
            pts = c + 0.5 * s * np.column_stack([np.cos(a), np.sin(a)])
            cv2.fillPoly(img, [pts.astype(np.int32)], float(level))
    lo, hi = np.percentile(img, (1, 99))
    scale = (GREY_RANGE[1] - GREY_RANGE[0]) / max(hi - lo, 1e-6)
    img = 0.5 * sum(GREY_RANGE) + (img - 0.5 * (lo + hi)) * scale
    return np.clip(img, 0, 255).astype(np.uint8)


#: Changed whenever a texture's texels change for the same arguments (it enters the samples'
#: fingerprints).
TEXTURE_VERSION = 4
#: Metres covered by the 512 pixels of each photograph (asphalt is the gravel, finer and flatter).
PHOTO_METRES = {"grass": 1.0, "gravel": 2.0, "asphalt": 0.5}
#: Grey level and contrast (times the photograph's deviation from its mean) of each style.
PHOTO_TONE = {"grass": (95.0, 1.2), "gravel": (130.0, 1.5), "asphalt": (105.0, 0.4)}
#: A brick's face and the mortar joint, metres (a common metric brick, 215 x 65 mm, 10 mm joints).
BRICK_SIZE, MORTAR = (0.215, 0.065), 0.010
#: Grey of the bricks (mean, spread from brick to brick) and of the mortar.
BRICK_GREY, MORTAR_GREY = (115.0, 8.0), 140.0
#: Height of a storey, metres: brick walls taller than a window get a row of windows per storey.
STOREY = 3.0


@functools.lru_cache(maxsize=4)
def photograph(name: str) -> np.ndarray:
    """A grey scikit-image photograph (``"grass"``, ``"gravel"``), float32."""
    return getattr(skimage.data, name)().astype(np.float32)


def mirrored_tiling(tile: np.ndarray, height: int, width: int, rng: np.random.Generator) -> np.ndarray:
    """``tile`` repeated over ``(height, width)``, every other copy mirrored (no seams), from a
    random offset."""
    h, w = tile.shape
    oy, ox = rng.integers(0, 2 * h), rng.integers(0, 2 * w)  # within the period, 2h x 2w
    tiled = np.pad(tile, ((0, oy + height), (0, ox + width)), mode="symmetric")
    return tiled[oy : oy + height, ox : ox + width]


def photo_texture(style: str, height: int, width: int, texel: float, seed: int) -> np.ndarray:
    """A photograph of ``style`` tiled over ``(height, width)`` texels of ``texel`` metres, float32."""
    photo = photograph("gravel" if style == "asphalt" else style)
    side = max(4, int(round(PHOTO_METRES[style] / texel)))
    tile = cv2.resize(photo, (side, side), interpolation=cv2.INTER_AREA)
    grey, contrast = PHOTO_TONE[style]
    tile = grey + contrast * (tile - tile.mean())
    return mirrored_tiling(tile, height, width, np.random.default_rng(seed))


def smooth_wash(
    height: int, width: int, texel: float, rng: np.random.Generator, amplitude: float
) -> np.ndarray:
    """Slow shading of ``amplitude`` grey levels over metres: light falling unevenly on paint."""
    step = max(1, int(round(1.0 / texel)))  # one random value per metre
    grid = rng.normal(0.0, amplitude, (height // step + 2, width // step + 2)).astype(np.float32)
    up = cv2.resize(grid, (grid.shape[1] * step, grid.shape[0] * step), interpolation=cv2.INTER_CUBIC)
    return up[:height, :width]


def _rect(img, x0, y0, x1, y1, texel, value):
    corners = [(int(x / texel), int(y / texel)) for x, y in ((x0, y0), (x1, y1))]
    cv2.rectangle(img, *corners, float(value), -1)


def _joint_share(centre: np.ndarray, texel: float, period: float) -> np.ndarray:
    """Share of each texel (``centre`` +- texel/2) that joints of width :data:`MORTAR`, one at the
    start of every ``period``, cover: the difference of the joints' running length at its edges."""

    def covered(p):  # length of joint in [0, p]
        return np.floor(p / period) * MORTAR + np.minimum(np.mod(p, period), MORTAR)

    return ((covered(centre + texel / 2) - covered(centre - texel / 2)) / texel).astype(np.float32)


def brick_wall(height: int, width: int, texel: float, seed: int) -> np.ndarray:
    """Bricks in running bond (each its own grey) in light mortar, with fine grain and framed windows
    on every storey. Joints are thinner than a texel: each texel gets the share of its area joints
    cover (an exact box filter) and the grey of the brick at its centre. Row 0 is the floor line."""
    rng = np.random.default_rng(seed)
    pitch, course = BRICK_SIZE[0] + MORTAR, BRICK_SIZE[1] + MORTAR  # brick plus one joint
    y = (np.arange(height) + 0.5) * texel
    x = (np.arange(width) + 0.5) * texel
    row = (y // course).astype(int)
    shifted = np.stack([x, x + 0.5 * pitch])  # running bond: odd courses shifted by half a brick
    col = (shifted // pitch).astype(int)[row % 2]  # (height, width)
    greys = rng.normal(*BRICK_GREY, (row.max() + 1, col.max() + 1)).astype(np.float32)
    bed = _joint_share(y, texel, course)[:, None]  # horizontal joints
    head = _joint_share(shifted, texel, pitch)[row % 2]  # vertical joints
    joint = 1.0 - (1.0 - bed) * (1.0 - head)
    img = greys[row[:, None], col] * (1.0 - joint) + MORTAR_GREY * joint
    grain = photo_texture("asphalt", height, width, texel, seed + 1) - PHOTO_TONE["asphalt"][0]
    img = img + 2.0 * grain + smooth_wash(height, width, texel, rng, 4.0)
    for floor in range(int((height * texel - 0.9) // STOREY)):  # windows on every storey
        sill = 0.9 + floor * STOREY
        side = rng.uniform(0.5, 2.0)  # a window's left side, metres along the wall
        while side < width * texel - 1.5:
            if rng.random() < 0.75:
                _rect(img, side - 0.08, sill - 0.08, side + 1.28, sill + 1.58, texel, 200.0)  # frame
                _rect(img, side, sill, side + 1.2, sill + 1.5, texel, rng.uniform(45, 85))  # glass
                _rect(img, side + 0.57, sill, side + 0.63, sill + 1.5, texel, 200.0)  # mullion
            side += rng.uniform(2.6, 4.0)
    return img


def painted_wall(height: int, width: int, texel: float, seed: int) -> np.ndarray:
    """Plain paint with doors (standing on row 0, the floor line) and posters of corner texture
    hanging 1.2-1.9 m high."""
    rng = np.random.default_rng(seed)
    grey = rng.uniform(150, 200)
    img = grey + smooth_wash(height, width, texel, rng, 3.0)
    x = rng.uniform(0.3, 2.0)
    while x < width * texel - 1.0:
        if rng.random() < 0.35:  # a door with its frame
            _rect(img, x - 0.06, 0.0, x + 0.96, 2.06, texel, grey - 60)
            _rect(img, x, 0.0, x + 0.9, 2.0, texel, rng.uniform(70, 120))
            _rect(img, x + 0.75, 0.95, x + 0.85, 1.0, texel, 40)  # handle
            x += rng.uniform(2.5, 5.0)
        else:  # a poster
            w, h = rng.uniform(0.4, 0.8), rng.uniform(0.5, 0.9)
            c0, r0 = int(x / texel), int(1.15 / texel)
            pw, ph = min(int(w / texel), width - c0), min(int(h / texel), height - r0)
            if pw > 4 and ph > 4:
                img[r0 : r0 + ph, c0 : c0 + pw] = corner_texture(ph, pw, int(rng.integers(1 << 30)))
            x += w + rng.uniform(2.0, 5.0)
    return img


def floor_tiles(height: int, width: int, texel: float, seed: int) -> np.ndarray:
    """Square tiles of 0.4 m, each its own grey, with dark grout lines and a fine speckle."""
    rng = np.random.default_rng(seed)
    n = max(1, int(round(0.4 / texel)))
    greys = rng.uniform(140, 160, (height // n + 2, width // n + 2)).astype(np.float32)
    img = cv2.resize(greys, (greys.shape[1] * n, greys.shape[0] * n), interpolation=cv2.INTER_NEAREST)
    img = img[:height, :width].copy()
    grout = max(1, int(round(0.006 / texel)))
    img[np.arange(height) % n < grout] = 95
    img[:, np.arange(width) % n < grout] = 95
    speckle = photo_texture("asphalt", height, width, texel, seed + 1) - PHOTO_TONE["asphalt"][0]
    return img + 3.0 * speckle


def ceiling_panels(height: int, width: int, texel: float, seed: int) -> np.ndarray:
    """Plain 0.6 m panels in a thin grid, with a bright light every few panels."""
    rng = np.random.default_rng(seed)
    n = max(1, int(round(0.6 / texel)))
    img = np.full((height, width), 175.0, np.float32) + smooth_wash(height, width, texel, rng, 2.0)
    img[np.arange(height) % n < 2] = 150
    img[:, np.arange(width) % n < 2] = 150
    for r in range(n, height - n, 4 * n):
        for c in range(n, width - n, 3 * n):
            img[r + 4 : r + n - 4, c + 4 : c + 2 * n - 4] = 245
    return img


def fence(height: int, width: int, texel: float, seed: int) -> np.ndarray:
    """A fence: dark posts every 0.25 m and two rails, before a plain pale background."""
    rng = np.random.default_rng(seed)
    img = np.full((height, width), 170.0, np.float32) + smooth_wash(height, width, texel, rng, 4.0)
    pitch, post = int(round(0.25 / texel)), max(1, int(round(0.05 / texel)))
    img[:, np.arange(width) % pitch < post] = 70
    for y in (0.3, 1.1):
        img[int(y / texel) : int((y + 0.06) / texel) + 1] = 80
    return img


def far_structure(height: int, width: int, texel: float, seed: int) -> np.ndarray:
    """Distant buildings and trees seen through haze: blurred blocks of low contrast."""
    rng = np.random.default_rng(seed)
    img = np.full((height, width), 165.0, np.float32)
    x = 0
    while x < width:
        w = int(rng.uniform(3.0, 15.0) / texel)
        top = int(rng.uniform(0.3, 1.0) * height)
        img[:top, x : x + w] = rng.uniform(145, 175)
        x += w
    return cv2.GaussianBlur(img, (0, 0), max(1.0, 0.3 / texel))


#: Cross-section of the ``"road"`` texture from its left edge, metres: verge, kerb, edge line,
#: lane, centre line, and the same mirrored (10 m in all).
_HALF_ROAD = (("gravel", 0.8), ("kerb", 0.2), ("line", 0.15), ("asphalt", 3.7))
ROAD_BANDS = (*_HALF_ROAD, ("dashes", 0.3), *_HALF_ROAD[::-1])
ROAD_WIDTH = sum(w for _, w in ROAD_BANDS)
#: Centre-line dashes: painted length and period along the road, metres.
DASH = (3.0, 9.0)
#: Contrast of a road's asphalt against the ``"asphalt"`` style (worn, patched road surface).
ROAD_GRAIN = 5.0
#: Grey levels of paint and kerb stone.
LINE_GREY, KERB_GREY = 200.0, 165.0


def road_surface(height: int, width: int, texel: float, seed: int) -> np.ndarray:
    """A two-lane road: rows across it (row 0 at the left verge), columns along it."""
    asphalt = photo_texture("asphalt", height, width, texel, seed)
    grey = PHOTO_TONE["asphalt"][0]
    img = grey + ROAD_GRAIN * (asphalt - grey)
    gravel = photo_texture("gravel", height, width, texel, seed + 1)
    wash = smooth_wash(height, width, texel, np.random.default_rng(seed + 2), 4.0)
    painted = np.mod(np.arange(width) * texel, DASH[1]) < DASH[0]  # the centre line's dashes
    edges = np.cumsum([0.0, *(w for _, w in ROAD_BANDS)])
    for (band, _), start, end in zip(ROAD_BANDS, edges, edges[1:], strict=False):
        r0, r1 = int(round(start / texel)), int(round(end / texel))  # the band's rows (asphalt: img's)
        if band == "dashes":  # asphalt, the line painted over the band's middle third
            third = (r1 - r0) // 3
            img[r0 + third : r1 - third, painted] = LINE_GREY
        elif band == "gravel":
            img[r0:r1] = gravel[r0:r1]
        elif band == "kerb":
            img[r0:r1] = KERB_GREY + 0.3 * (gravel[r0:r1] - PHOTO_TONE["gravel"][0])
        elif band == "line":
            img[r0:r1] = LINE_GREY
    return img + wash


def vehicle_side(height: int, width: int, texel: float, seed: int) -> np.ndarray:
    """A car body seen from one side: paint, a dark window band above the waist, two wheels."""
    rng = np.random.default_rng(seed)
    paint = rng.uniform(60, 200)
    img = paint + smooth_wash(height, width, texel, rng, 6.0)
    waist, roof = int(0.9 / texel), int(1.35 / texel)
    img[waist:roof, int(0.15 * width) : int(0.85 * width)] = rng.uniform(30, 55)
    img[roof:] = paint * 0.85
    radius = max(1, int(0.33 / texel))
    for x in (0.18, 0.82):
        cv2.circle(img, (int(x * width), radius), radius, 25.0, -1)
        cv2.circle(img, (int(x * width), radius), radius // 2, 120.0, -1)
    return img


def plain_paint(height: int, width: int, texel: float, seed: int) -> np.ndarray:
    """A uniform grey with a faint wash."""
    rng = np.random.default_rng(seed)
    return rng.uniform(150, 200) + smooth_wash(height, width, texel, rng, 3.0)


#: Every style, drawn by a function of ``(height, width, texel, seed)``.
_DRAW = {
    "corners": lambda height, width, texel, seed: corner_texture(height, width, seed),
    **{style: functools.partial(photo_texture, style) for style in PHOTO_METRES},
    "plain": plain_paint,
    "brick": brick_wall,
    "wall": painted_wall,
    "tiles": floor_tiles,
    "panels": ceiling_panels,
    "fence": fence,
    "far": far_structure,
    "road": road_surface,
    "vehicle": vehicle_side,
}


def surface_texture(style: str, height: int, width: int, texel: float, seed: int) -> np.ndarray:
    """A ``(height, width)`` uint8 texture of ``style`` with texels of ``texel`` metres; row 0 is the
    floor line of a wall (z = 0) and the ``xmin, ymin`` corner of a floor."""
    if height <= 0 or width <= 0:
        raise ValueError(f"texture size must be positive; got {height}x{width}")
    if style not in _DRAW:
        raise ValueError(f"unknown texture style {style!r}; known: {', '.join(STYLES)}")
    return np.clip(_DRAW[style](height, width, texel, seed) + 0.5, 0, 255).astype(np.uint8)


STYLES = tuple(_DRAW)


@functools.lru_cache(maxsize=256)
def cached_surface(style: str, height: int, width: int, texel: float, seed: int) -> tuple[np.ndarray, ...]:
    """Mipmaps of :func:`surface_texture` (level L has ``2**L`` texels of level 0 per texel), computed
    once per process for each argument set."""
    levels = [surface_texture(style, height, width, texel, seed)]
    while min(levels[-1].shape) >= 2 * MIN_MIP_SIDE:
        levels.append(cv2.pyrDown(levels[-1]))
    return tuple(levels)
