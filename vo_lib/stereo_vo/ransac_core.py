"""The compiled core of :func:`vo_lib.stereo_vo.ransac.one_point_ransac` (Numba).

The estimator is a few hundred small steps over a few hundred matches: two hypothesis searches,
their gates, Gauss-Newton and re-selection. As NumPy calls each step costs microseconds of
overhead whatever its size; compiled, the loops below run the same arithmetic in one pass per
step. The algorithm, its equations and its constants are documented in ``vo_lib.stereo_vo.ransac``; this
module only computes (compiled and cached as :mod:`vo_lib.compiled` says).
"""

from __future__ import annotations

import math

import numpy as np

from vo_lib.compiled import jit as _jit
from vo_lib.stereo_vo.circular_motion import theta_variance

_theta_variance = _jit(theta_variance)

OK, FEW_USABLE, FEW_THETA_INLIERS, FEW_INLIERS = 0, 1, 2, 3


@_jit
def hypotheses_needed(inlier_ratio, confidence):
    """``ceil(log(1 - p) / log(1 - w))`` for one-point samples (see ``ransac.hypotheses_needed``)."""
    w = min(max(inlier_ratio, 1e-9), 1.0)
    if w >= 1.0:
        return 1
    return max(1, math.ceil(math.log(1.0 - confidence) / math.log(1.0 - w)))


@_jit
def gauss_newton(P, Q, wa, wb, theta, rho, fx, fy, cx, cy, fb, iterations):
    """Gauss-Newton on forward and backward reprojection errors in disparity space (the model
    and Jacobian are written out in ``ransac._gauss_newton``). Returns
    ``(theta, rho, A00, A01, A11, rss)`` with the normal matrix and residuals of the last
    iterate before its update."""
    n = P.shape[0]
    a00 = a01 = a11 = rss = 0.0
    for _ in range(max(iterations, 1)):
        c, s = math.cos(theta), math.sin(theta)
        sp, cp = math.sin(0.5 * theta), math.cos(0.5 * theta)
        a00 = a01 = a11 = b0 = b1 = rss = 0.0
        for k in range(2 * n):
            if k < n:  # forward: pi(R P + T) against the current match
                g, x, y, z = 1.0, P[k, 0], P[k, 1], P[k, 2]
                ou, ov, od = wb[k, 0] - cx, wb[k, 1] - cy, wb[k, 2]
            else:  # backward: pi(R^T (Q - T)) against the previous match
                j = k - n
                g, x, y, z = -1.0, Q[j, 0], Q[j, 1], Q[j, 2]
                ou, ov, od = wa[j, 0] - cx, wa[j, 1] - cy, wa[j, 2]
            gx, gz = g * x, g * z
            xm = c * x + s * gz - rho * sp
            zm = c * z - s * gx - rho * cp * g
            dx_t = c * gz - s * x - 0.5 * rho * cp
            dz_t = 0.5 * rho * sp * g - c * gx - s * z
            dz_r = -cp * g
            iz = 1.0 / zm
            iz2 = iz * iz
            ru, rv, rd = fx * xm * iz - ou, fy * y * iz - ov, fb * iz - od
            fz = fx * iz2
            ju_t, ju_r = fz * (dx_t * zm - xm * dz_t), fz * (-sp * zm - xm * dz_r)
            yz = -fy * y * iz2
            jv_t, jv_r = yz * dz_t, yz * dz_r
            jd_t, jd_r = -fb * iz2 * dz_t, -fb * iz2 * dz_r
            a00 += ju_t * ju_t + jv_t * jv_t + jd_t * jd_t
            a01 += ju_t * ju_r + jv_t * jv_r + jd_t * jd_r
            a11 += ju_r * ju_r + jv_r * jv_r + jd_r * jd_r
            b0 += ju_t * ru + jv_t * rv + jd_t * rd
            b1 += ju_r * ru + jv_r * rv + jd_r * rd
            rss += ru * ru + rv * rv + rd * rd
        det = a00 * a11 - a01 * a01
        if not det > 0:
            break
        d_theta = -(a11 * b0 - a01 * b1) / det
        d_rho = -(a00 * b1 - a01 * b0) / det
        theta, rho = theta + d_theta, rho + d_rho
        if abs(d_theta) < 1e-10 and abs(d_rho) < 1e-9:
            break
    return theta, rho, a00, a01, a11, rss


@_jit
def covariance(a00, a01, a11, rss, count):
    """Covariance of ``(theta, rho)`` from the normal matrix; forward and backward residuals
    carry the same noise, so their information counts once (the factor 2)."""
    sigma2 = rss / max(count - 2, 1)
    det = a00 * a11 - a01 * a01
    out = np.empty((2, 2))
    if not det > 0:
        out[:] = np.inf
        out[0, 1] = out[1, 0] = 0.0
        return out
    out[0, 0], out[0, 1], out[1, 0], out[1, 1] = a11 / det, -a01 / det, -a01 / det, a00 / det
    return 2.0 * sigma2 * out


@_jit
def _passes(phase, j, h, vh, values, variances, k2, bx, by, bz, sphi, cphi):
    """Does match ``j`` pass hypothesis ``h`` (variance ``vh``)? Phase 1: ``(theta_j - h)^2 <=
    k2 (var_j + vh)`` (first-order eq. 20); phase 2: eq. 21, ``|Q - R P - T(h)|^2 <= k2 (var_j + vh)``."""
    if phase == 1:
        r2 = (values[j] - h) ** 2
    else:
        rx, rz = bx[j] + h * sphi, bz[j] + h * cphi
        r2 = rx * rx + by[j] * by[j] + rz * rz
    return r2 <= k2 * (variances[j] + vh)


@_jit
def _count(phase, h, vh, values, variances, k2, bx, by, bz, sphi, cphi):
    """Matches passing a hypothesis."""
    count = 0
    for j in range(values.shape[0]):
        count += _passes(phase, j, h, vh, values, variances, k2, bx, by, bz, sphi, cphi)
    return count


@_jit
def reestimate(phase, h, vh, values, variances, k2, bx, by, bz, sphi, cphi):
    """Inverse-variance weighted mean of the per-match values of a hypothesis' inliers, and its variance."""
    sw = swv = 0.0
    for j in range(values.shape[0]):
        if _passes(phase, j, h, vh, values, variances, k2, bx, by, bz, sphi, cphi):
            sw += 1.0 / variances[j]
            swv += values[j] / variances[j]
    return swv / sw, 1.0 / sw


@_jit
def search(
    phase,
    values,
    variances,
    uniforms,
    confidence,
    max_hypotheses,
    extra,
    k2,
    bx,
    by,
    bz,
    sphi,
    cphi,
    min_pool,
    pool_fraction,
):
    """Adaptive single-match RANSAC (the rules are in ``vo_lib.stereo_vo.ransac``'s module text):
    batches of hypotheses, the most-supported (then most precise) wins, the batch size follows
    the best inlier ratio. ``extra = (value, variance)`` is scored first when finite.
    Hypotheses come from the ``pool_fraction`` best-conditioned matches (at least ``min_pool``).
    Returns ``(value, variance, count, tried)``."""
    pool = np.argsort(variances)[: max(min_pool, int(pool_fraction * values.shape[0]))]
    # a hypothesis is tested as if no less certain than a typical one of the pool
    cap = np.median(variances[pool])
    best_v, best_var, best_c = np.nan, np.nan, -1
    if np.isfinite(extra[0]):
        var_e = min(extra[1], cap)
        best_v, best_var = extra[0], var_e
        best_c = _count(phase, extra[0], var_e, values, variances, k2, bx, by, bz, sphi, cphi)
    n_total = max(values.shape[0], 1)
    tried, used = 0, 0
    limit = min(hypotheses_needed(0.5, confidence), max_hypotheses)
    m_pool = pool.shape[0]
    while tried < limit:
        m = limit - tried
        vals, vars_, counts = np.empty(m), np.empty(m), np.empty(m, np.int64)
        vmax = 0.0
        for k in range(m):
            i = pool[min(int(uniforms[used] * m_pool), m_pool - 1)]
            used += 1
            vals[k], vars_[k] = values[i], min(variances[i], cap)
            counts[k] = _count(phase, vals[k], vars_[k], values, variances, k2, bx, by, bz, sphi, cphi)
            vmax = max(vmax, vars_[k])
        top, top_score = 0, -np.inf
        for k in range(m):  # among equal counts the more precise hypothesis wins
            score = counts[k] - 0.5 * vars_[k] / (vmax + 1e-300)
            if score > top_score:
                top, top_score = k, score
        if counts[top] > best_c:
            best_v, best_var, best_c = vals[top], vars_[top], counts[top]
        tried += m
        ratio = best_c / n_total if best_c > 0 else 1e-9
        limit = min(hypotheses_needed(min(ratio, 1.0), confidence), max_hypotheses)
    return best_v, best_var, best_c, tried


@_jit
def _gate(ta, ba, tb, bb, phi):
    """Signed eq. 20 for one match."""
    return tb / ta - math.sin(bb - phi) / math.sin(ba + phi)


@_jit
def theta_gate_pass(ta, ba, tb, bb, theta_j, var_theta, theta, var_ref, k2, out):
    """The eq. 20 gate of every match at ``theta`` against ``k`` first-order standard deviations,
    and the match's own theta consistent with it."""
    h = 1e-4
    for j in range(ta.shape[0]):
        e = _gate(ta[j], ba[j], tb[j], bb[j], 0.5 * theta)
        slope = (_gate(ta[j], ba[j], tb[j], bb[j], 0.5 * (theta + h)) - e) / h
        var = var_theta[j] + var_ref
        out[j] = (e * e <= k2 * slope * slope * var) and ((theta_j[j] - theta) ** 2 <= k2 * var)


@_jit
def one_point_core(
    a,
    b,
    fx,
    fy,
    cx,
    cy,
    baseline,
    prior_theta,
    prior_rho,
    pixel_sigma,
    gate_sigmas,
    confidence,
    max_hypotheses,
    refine,
    uniforms_theta,
    uniforms_rho,
    min_pool,
    pool_fraction,
    refine_iterations,
    refine_rounds,
    whitened_gate,
):
    """Everything numeric of ``one_point_ransac``. ``prior_theta`` / ``prior_rho`` are
    ``(value, variance)`` pairs, NaN when there is no prior. Returns ``(status, theta, rho,
    covariance, inlier mask over all matches, hypotheses tried in each phase, theta inliers,
    refinement rounds)``."""
    n = a.shape[0]
    k2 = gate_sigmas * gate_sigmas
    inliers = np.zeros(n, np.bool_)
    cov = np.full((2, 2), np.inf)
    # ------------------------------------------------------------ per match, once
    iu_list = []
    for j in range(n):
        dv, dv2 = a[j, 1] - cy, b[j, 1] - cy
        den = fx * (dv + dv2)  # eq. 14: tan(phi) = num / den
        if a[j, 2] > 0 and b[j, 2] > 0 and abs(den) > 1e-9 * fx:
            iu_list.append(j)
    m = len(iu_list)
    if m < 3:
        return FEW_USABLE, np.nan, np.nan, cov, inliers, 0, 0, 0, 0
    iu = np.array(iu_list)
    du, dv, du2, dv2 = np.empty(m), np.empty(m), np.empty(m), np.empty(m)
    num, den, theta_j = np.empty(m), np.empty(m), np.empty(m)
    for i in range(m):
        j = iu[i]
        du[i], dv[i], du2[i], dv2[i] = a[j, 0] - cx, a[j, 1] - cy, b[j, 0] - cx, b[j, 1] - cy
        num[i], den[i] = du2[i] * dv[i] - du[i] * dv2[i], fx * (dv[i] + dv2[i])
        theta_j[i] = 2.0 * math.atan(num[i] / den[i])
    var_theta = _theta_variance(du, dv, du2, dv2, num, den, fx, pixel_sigma)
    # ------------------------------------------------------------ phase 1: theta (eq. 14, 18-20)
    e = np.empty(0)
    theta_h, var_h, _, tried_theta = search(
        1,
        theta_j,
        var_theta,
        uniforms_theta,
        confidence,
        max_hypotheses,
        prior_theta,
        k2,
        e,
        e,
        e,
        0.0,
        0.0,
        min_pool,
        pool_fraction,
    )
    # refine theta: inverse-variance weighted mean of the hypothesis' inliers
    theta_hat, var_theta_hat = reestimate(1, theta_h, var_h, theta_j, var_theta, k2, e, e, e, 0.0, 0.0)
    beta_a, beta_b = np.arctan(du / fx), np.arctan(du2 / fx)
    ta, tb = dv * np.cos(beta_a) / fy, dv2 * np.cos(beta_b) / fy
    theta_in = np.empty(m, np.bool_)
    theta_gate_pass(ta, beta_a, tb, beta_b, theta_j, var_theta, theta_hat, var_theta_hat, k2, theta_in)
    n_theta_in = int(theta_in.sum())
    if n_theta_in < 3:
        return FEW_THETA_INLIERS, np.nan, np.nan, cov, inliers, tried_theta, 0, n_theta_in, 0
    # ------------------------------------------------------------ phase 2: rho (eq. 13, 17, 21)
    P, Q = np.empty((m, 3)), np.empty((m, 3))
    au, bu = np.empty((m, 3)), np.empty((m, 3))
    var_point = np.empty(m)
    ps2 = pixel_sigma * pixel_sigma
    for i in range(m):
        au[i], bu[i] = a[iu[i]], b[iu[i]]
        sa, sb = baseline / au[i, 2], baseline / bu[i, 2]
        P[i, 0], P[i, 1], P[i, 2] = sa * du[i], sa * dv[i] * (fx / fy), sa * fx
        Q[i, 0], Q[i, 1], Q[i, 2] = sb * du2[i], sb * dv2[i] * (fx / fy), sb * fx
        ray_a = math.sqrt(du[i] ** 2 + (dv[i] * fx / fy) ** 2 + fx * fx) / au[i, 2]
        ray_b = math.sqrt(du2[i] ** 2 + (dv2[i] * fx / fy) ** 2 + fx * fx) / bu[i, 2]
        var_point[i] = ps2 * (sa * sa * (ray_a * ray_a + 2.0) + sb * sb * (ray_b * ray_b + 2.0))
    phi = 0.5 * theta_hat
    sphi, cphi = math.sin(phi), math.cos(phi)
    c, s = math.cos(theta_hat), math.sin(theta_hat)
    it = np.flatnonzero(theta_in)
    rho_j, var_pt = np.empty(n_theta_in), np.empty(n_theta_in)
    bx, by, bz = np.empty(n_theta_in), np.empty(n_theta_in), np.empty(n_theta_in)
    for k in range(n_theta_in):
        i = it[k]
        rho_j[k] = (-sphi * P[i, 0] + cphi * P[i, 2]) - (sphi * Q[i, 0] + cphi * Q[i, 2])  # eq. 16, corrected
        bx[k] = Q[i, 0] - (c * P[i, 0] + s * P[i, 2])  # Q - R P; the gate adds rho (sin phi, 0, cos phi)
        by[k] = Q[i, 1] - P[i, 1]
        bz[k] = Q[i, 2] - (-s * P[i, 0] + c * P[i, 2])
        var_pt[k] = var_point[i]
    rho_h, var_rho, _, tried_rho = search(
        2,
        rho_j,
        var_pt,
        uniforms_rho,
        confidence,
        max_hypotheses,
        prior_rho,
        k2,
        bx,
        by,
        bz,
        sphi,
        cphi,
        min_pool,
        pool_fraction,
    )
    rho_hat, var_rho = reestimate(2, rho_h, var_rho, rho_j, var_pt, k2, bx, by, bz, sphi, cphi)  # like theta
    keep = np.zeros(m, np.bool_)
    for k in range(n_theta_in):
        keep[it[k]] = _passes(2, k, rho_hat, var_rho, rho_j, var_pt, k2, bx, by, bz, sphi, cphi)
    theta, rho = theta_hat, rho_hat
    cov = np.zeros((2, 2))
    cov[0, 0], cov[1, 1] = var_theta_hat, var_rho
    # ------------------------------------------------------------ refinement on all inliers
    rounds = 0
    fb = fx * baseline
    new = np.empty(m, np.bool_)
    while refine and keep.sum() >= 3 and rounds < refine_rounds:
        rounds += 1
        sel = np.flatnonzero(keep)
        theta, rho, a00, a01, a11, rss = gauss_newton(
            P[sel],
            Q[sel],
            au[sel],
            bu[sel],
            theta,
            rho,
            fx,
            fy,
            cx,
            cy,
            fb,
            refine_iterations if rounds == 1 else 1,
        )
        cov = covariance(a00, a01, a11, rss, 6 * len(sel))
        # the refined motion decides the inliers again: the theta gate, and eq. 21 whitened in (u, v, d)
        theta_gate_pass(ta, beta_a, tb, beta_b, theta_j, var_theta, theta, cov[0, 0], k2, new)
        c, s = math.cos(theta), math.sin(theta)
        tx, tz = -rho * math.sin(0.5 * theta), -rho * math.cos(0.5 * theta)
        limit = whitened_gate * whitened_gate * 2.0 * ps2
        changed = False
        for i in range(m):
            mx = c * P[i, 0] + s * P[i, 2] + tx
            mz = -s * P[i, 0] + c * P[i, 2] + tz
            iz = 1.0 / mz
            r2 = (fx * mx * iz - du2[i]) ** 2 + (fy * P[i, 1] * iz - dv2[i]) ** 2 + (fb * iz - bu[i, 2]) ** 2
            new[i] = new[i] and mz > 0 and r2 <= limit
            changed = changed or new[i] != keep[i]
        keep[:] = new
        if not changed:
            break
    for i in range(m):
        inliers[iu[i]] = keep[i]
    status = OK if keep.sum() >= 3 else FEW_INLIERS
    return status, theta, rho, cov, inliers, tried_theta, tried_rho, n_theta_in, rounds
