"""The z-buffer step of the renderer, compiled: one quad's warped texture into the image.

For every pixel of the quad's screen box that lies inside the quad (``mask``), the plane's
inverse depth ``a u + b v + e`` is compared with what is drawn; where the quad is nearer, its
inverse depth and its shaded grey level are written. In NumPy this is five passes over the box
with a temporary array each; here it is one pass with the same arithmetic (the plane in float64,
stored as float32), so the images are the same to the last grey level.
"""

from __future__ import annotations

import numpy as np

from vo_lib.compiled import jit


@jit
def draw_nearer(image, inv_depth, warped, mask, x0, y0, a, b, e, shade):
    """Write ``warped`` (the quad's texture over its box, top-left at ``(x0, y0)``) into ``image``
    and its plane into ``inv_depth`` where ``mask`` is set and the plane is nearer.

    ``shade`` scales the grey level, rounded half to even and saturated as ``cv2.convertScaleAbs``
    does; 1.0 copies it.
    """
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
