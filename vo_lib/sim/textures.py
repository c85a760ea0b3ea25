"""Procedural grey-level textures, rich in corners, deterministic by seed.

A texture is a sum of blocky noise at several scales (nearest-neighbour upsampled random grids,
each offset by a random shift, so block corners do not line up across scales) plus random
filled polygons and discs. Blocks give FAST its corners at every viewing distance; the polygons
add corners at arbitrary angles. Mipmaps (Gaussian pyramids) let the renderer sample far surfaces
without aliasing.
"""

from __future__ import annotations

from functools import lru_cache

import cv2
import numpy as np

#: Block sizes (texels) and weights of the blocky noise layers.
BLOCK_LAYERS = ((96, 0.25), (24, 0.30), (6, 0.30), (2, 0.15))
#: Polygons per million texels.
SHAPES_PER_MEGATEXEL = 400
#: Grey levels the texture is stretched to, leaving room for shading and exposure.
GREY_RANGE = (25.0, 230.0)
#: Coarsest mipmap side in texels.
MIN_MIP_SIDE = 8


def corner_texture(height: int, width: int, seed: int, contrast: float = 1.0) -> np.ndarray:
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
            k = 3 if kind == 0 else 5
            a = np.sort(ang[:k])
            pts = c + 0.5 * s * np.column_stack([np.cos(a), np.sin(a)])
            cv2.fillPoly(img, [pts.astype(np.int32)], float(level))
    lo, hi = np.percentile(img, (1, 99))
    mid, half = 0.5 * sum(GREY_RANGE), 0.5 * (GREY_RANGE[1] - GREY_RANGE[0]) * contrast
    img = mid + (img - 0.5 * (lo + hi)) * (2 * half / max(hi - lo, 1e-6))
    return np.clip(img, 0, 255).astype(np.uint8)


def mipmaps(texture: np.ndarray) -> list[np.ndarray]:
    """Gaussian pyramid of a texture: level L has ``2**L`` texels of level 0 per texel."""
    levels = [texture]
    while min(levels[-1].shape) >= 2 * MIN_MIP_SIDE:
        levels.append(cv2.pyrDown(levels[-1]))
    return levels


@lru_cache(maxsize=256)
def cached_mipmaps(height: int, width: int, seed: int, contrast: float = 1.0) -> tuple[np.ndarray, ...]:
    """Mipmaps of :func:`corner_texture`, computed once per process for each argument set."""
    return tuple(mipmaps(corner_texture(height, width, seed, contrast)))
