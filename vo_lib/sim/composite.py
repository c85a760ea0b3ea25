"""The z-buffer step of the renderer, compiled: one pass over the box where NumPy
(:mod:`vo_lib.sim.composite_plain`) makes five, with the same arithmetic and so the same images.
"""

from __future__ import annotations

import numpy as np

from vo_lib.compiled import jit


@jit
def draw_nearer(image, inv_depth, warped, mask, x0, y0, a, b, e, shade):
    """As :func:`vo_lib.sim.composite_plain.draw_nearer`."""
    h, w = warped.shape
    sf = np.float32(shade)
    for r in range(h):
        y = y0 + r
        row = b * y + e
        for c in range(w):
            if mask[r, c] == 0:
                continue
            x = x0 + c
            z = a * x + row
            if z > inv_depth[y, x]:
                inv_depth[y, x] = np.float32(z)
                if sf == 1.0:
                    image[y, x] = warped[r, c]
                else:
                    image[y, x] = min(np.rint(np.float32(warped[r, c]) * sf), 255.0)
