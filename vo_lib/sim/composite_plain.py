"""The renderer's z-buffer step in plain NumPy: the reference of the compiled
:func:`vo_lib.sim.composite.draw_nearer`, which the renderer runs (``bench kernels``).
"""

from __future__ import annotations

import numpy as np


def draw_nearer(image, inv_depth, warped, mask, x0, y0, a, b, e, shade):
    """Write ``warped`` (the quad's texture over its box, top-left at ``(x0, y0)``) into ``image``
    and its inverse depth ``a u + b v + e`` (float64, stored as float32) into ``inv_depth`` where
    ``mask`` is set and the plane is nearer; ``shade`` scales the grey level, rounded half to even
    and saturated at 255."""
    h, w = warped.shape
    ys, xs = y0 + np.arange(h), x0 + np.arange(w)
    z = a * xs[None, :] + (b * ys[:, None] + e)  # inverse depth of the quad's plane over its box
    box = np.ix_(ys, xs)
    nearer = (mask != 0) & (z > inv_depth[box])
    rows, cols = ys[np.nonzero(nearer)[0]], xs[np.nonzero(nearer)[1]]
    inv_depth[rows, cols] = z[nearer].astype(np.float32)
    grey = warped[nearer]
    if np.float32(shade) != 1.0:
        grey = np.minimum(np.rint(grey.astype(np.float32) * np.float32(shade)), 255.0)
    image[rows, cols] = grey
