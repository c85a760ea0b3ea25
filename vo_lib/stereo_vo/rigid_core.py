"""The compiled core of :mod:`vo_lib.stereo_vo.rigid_motion` (Numba): its normal equations.

One Gauss-Newton iteration needs ``J^T W J`` and ``J^T W r`` over a few hundred matches; in NumPy
that is a dozen temporary arrays per iteration, here one loop. The residual, Jacobian and Huber
weights are those written out in ``rigid_motion._normal_equations_numpy``, which the tests hold
this to.
"""

from __future__ import annotations

import numpy as np

from vo_lib.compiled import jit as _jit


@_jit(twin="vo_lib.stereo_vo.rigid_plain.normal_equations")
def normal_equations(P, w, R, t, fx, fy, cx, cy, fb, huber):
    A = np.zeros((6, 6))
    g = np.zeros(6)
    cost = 0.0
    ju = np.empty(6)
    jv = np.empty(6)
    jd = np.empty(6)
    for k in range(P.shape[0]):
        X = R[0, 0] * P[k, 0] + R[0, 1] * P[k, 1] + R[0, 2] * P[k, 2] + t[0]
        Y = R[1, 0] * P[k, 0] + R[1, 1] * P[k, 1] + R[1, 2] * P[k, 2] + t[1]
        Z = R[2, 0] * P[k, 0] + R[2, 1] * P[k, 1] + R[2, 2] * P[k, 2] + t[2]
        iz = 1.0 / Z
        ru = fx * X * iz + cx - w[k, 0]
        rv = fy * Y * iz + cy - w[k, 1]
        rd = fb * iz - w[k, 2]
        e = np.sqrt(ru * ru + rv * rv + rd * rd)
        wgt = 1.0 if e <= huber else huber / max(e, 1e-12)
        iz2 = iz * iz
        ju[0], ju[1], ju[2] = -fx * X * Y * iz2, fx * (1 + X * X * iz2), -fx * Y * iz
        ju[3], ju[4], ju[5] = fx * iz, 0.0, -fx * X * iz2
        jv[0], jv[1], jv[2] = -fy * (1 + Y * Y * iz2), fy * X * Y * iz2, fy * X * iz
        jv[3], jv[4], jv[5] = 0.0, fy * iz, -fy * Y * iz2
        jd[0], jd[1], jd[2] = -fb * Y * iz2, fb * X * iz2, 0.0
        jd[3], jd[4], jd[5] = 0.0, 0.0, -fb * iz2
        for i in range(6):
            g[i] += wgt * (ju[i] * ru + jv[i] * rv + jd[i] * rd)
            for j in range(i, 6):
                A[i, j] += wgt * (ju[i] * ju[j] + jv[i] * jv[j] + jd[i] * jd[j])
        cost += wgt * e * e
    for i in range(6):
        for j in range(i):
            A[i, j] = A[j, i]
    return A, g, cost
