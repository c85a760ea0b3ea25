"""The normal equations of :mod:`vo_lib.stereo_vo.rigid_core` in plain NumPy, for reading.

Registered as the twin of the compiled kernel; ``VO_LIB_PLAIN=1`` runs it instead
(:mod:`vo_lib.compiled`). Same arguments, same results to rounding (the sums run in another order).
"""

from __future__ import annotations

import numpy as np


def normal_equations(P, w, R, t, fx, fy, cx, cy, fb, huber):
    """``(J^T W J, J^T W r, sum of weighted squares)`` of the Huber-weighted residuals
    ``pi(R P + t) - w`` in ``(u, v, d)``, for a left-multiplied update ``(dw, dt)`` of the pose.

    ``pi(X, Y, Z) = (fx X / Z + cx, fy Y / Z + cy, fb / Z)``; a residual of length ``e`` weighs
    1 within ``huber`` and ``huber / e`` beyond.
    """
    Q = P @ R.T + t
    X, Y, Z = Q[:, 0], Q[:, 1], Q[:, 2]
    iz = 1.0 / Z
    r = np.column_stack([fx * X * iz + cx, fy * Y * iz + cy, fb * iz]) - w
    e = np.sqrt(np.sum(r * r, axis=1))
    wgt = np.where(e <= huber, 1.0, huber / np.maximum(e, 1e-12))
    zero = 0 * iz
    # rows of d pi / dQ @ [-[Q]x | I]: d(u, v, d) / d(dw_x, dw_y, dw_z, dt_x, dt_y, dt_z)
    ju = np.column_stack(
        [-fx * X * Y * iz**2, fx * (1 + X * X * iz**2), -fx * Y * iz, fx * iz, zero, -fx * X * iz**2]
    )
    jv = np.column_stack(
        [-fy * (1 + Y * Y * iz**2), fy * X * Y * iz**2, fy * X * iz, zero, fy * iz, -fy * Y * iz**2]
    )
    jd = np.column_stack([-fb * Y * iz**2, fb * X * iz**2, zero, zero, zero, -fb * iz**2])
    A, g = np.zeros((6, 6)), np.zeros(6)
    for J, res in ((ju, r[:, 0]), (jv, r[:, 1]), (jd, r[:, 2])):
        A += (J * wgt[:, None]).T @ J
        g += (J * wgt[:, None]).T @ res
    return A, g, float(np.sum(wgt * e * e))
