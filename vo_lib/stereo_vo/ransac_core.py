"""The compiled core of :func:`vo_lib.stereo_vo.ransac.one_point_ransac` (Numba), and its parameters.

The estimator is a few hundred small steps over a few hundred matches: two hypothesis searches,
their gates, Gauss-Newton and re-selection. As NumPy calls each step costs microseconds of
overhead whatever its size; compiled, the loops below run the same arithmetic in one pass per
step. The algorithm, its equations and its constants are documented in ``vo_lib.stereo_vo.ransac``;
the same steps in plain NumPy, for reading, are in ``vo_lib.stereo_vo.ransac_plain``
(``VO_LIB_PLAIN=1`` runs those instead, see :mod:`vo_lib.compiled`).

Both searches share one support test. In each phase the residual of match ``j`` under hypothesis
``h`` is linear in ``h``: ``r_j(h) = offset_j + h * direction``. Phase 1 (theta, first-order eq. 20):
``offset_j = (theta_j, 0, 0)``, ``direction = (-1, 0, 0)``. Phase 2 (rho, eq. 21):
``offset_j = Q_j - R P_j`` and ``direction = (sin phi, 0, cos phi)``, since ``T = -rho (sin phi, 0,
cos phi)``. Match ``j`` supports ``h`` (of variance ``var_h``) when
``|r_j(h)|^2 <= k^2 (var_j + var_h)``.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from vo_lib.compiled import jit as _jit
from vo_lib.stereo_vo.circular_motion import theta_variance

OK, FEW_USABLE, FEW_THETA_INLIERS, FEW_INLIERS = 0, 1, 2, 3
_CORE = f"{__name__}.one_point_core"  # the kernel the steps below run inside


class RansacParams(NamedTuple):
    """The settings of 1-point RANSAC, as one immutable structure (Numba takes it as it is)."""

    pixel_sigma: float = 0.5  #: pixel noise of u, v and d assumed by the gates
    gate_sigmas: float = 3.0  #: a match is an inlier within this many standard deviations of each gate
    confidence: float = 0.999  #: probability of drawing at least one all-inlier hypothesis
    max_hypotheses: int = 200  #: hypotheses per phase at most
    refine: bool = True  #: refine on all inliers by least squares
    min_pool: int = 8  #: hypotheses come from at least this many matches ...
    pool_fraction: float = 0.5  #: ... the best-conditioned fraction of the matches
    refine_iterations: int = 2  #: Gauss-Newton iterations of the first refinement round
    refine_rounds: int = 3  #: refine, re-select inliers, and refine again while the set changes
    whitened_gate: float = 3.76  #: final gate on the whitened eq. 21 residual: sqrt chi-square(3) at 99.7 %
    initial_inlier_ratio: float = 0.5  #: first guess of the inlier ratio, before any hypothesis is scored


class CameraTerms(NamedTuple):
    """The stereo camera as the kernel needs it (pixels, metres)."""

    fx: float
    fy: float
    cx: float
    cy: float
    baseline: float


def hypotheses_needed(inlier_ratio, confidence=0.999, sample_size=1):
    """Hypotheses so that at least one is all-inlier with probability ``confidence``:
    ``ceil(log(1 - p) / log(1 - w**s))`` ([Zhao], III.A.3)."""
    w = min(max(float(inlier_ratio), 1e-9), 1.0)
    good = w**sample_size
    if good >= 1.0:
        return 1
    return max(1, math.ceil(math.log(1.0 - confidence) / math.log(1.0 - good)))


_theta_variance = _jit(theta_variance, step_of=_CORE)
_hypotheses_needed = _jit(hypotheses_needed, step_of=_CORE)


@_jit(twin="vo_lib.stereo_vo.ransac_plain.gauss_newton")
def gauss_newton(P, Q, wa, wb, theta, rho, cam, iterations):
    """Gauss-Newton on forward and backward reprojection errors in disparity space (the model
    and Jacobian are written out in ``ransac_plain.reprojection``). Returns
    ``(theta, rho, A00, A01, A11, rss)`` with the normal matrix and residuals of the last
    iterate before its update."""
    n = P.shape[0]
    fx, fy, fb = cam.fx, cam.fy, cam.fx * cam.baseline
    a00 = a01 = a11 = rss = 0.0
    for _ in range(max(iterations, 1)):
        c, s = math.cos(theta), math.sin(theta)
        sp, cp = math.sin(0.5 * theta), math.cos(0.5 * theta)
        a00 = a01 = a11 = b0 = b1 = rss = 0.0
        for k in range(2 * n):
            if k < n:  # forward: pi(R P + T) against the current match
                g, x, y, z = 1.0, P[k, 0], P[k, 1], P[k, 2]
                ou, ov, od = wb[k, 0] - cam.cx, wb[k, 1] - cam.cy, wb[k, 2]
            else:  # backward: pi(R^T (Q - T)) against the previous match
                j = k - n
                g, x, y, z = -1.0, Q[j, 0], Q[j, 1], Q[j, 2]
                ou, ov, od = wa[j, 0] - cam.cx, wa[j, 1] - cam.cy, wa[j, 2]
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


@_jit(twin="vo_lib.stereo_vo.ransac_plain.covariance")
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


@_jit(step_of=_CORE)
def supporters(offsets, direction, variances, h, var_h, k2):
    """Which matches support hypothesis ``h``: ``|offset_j + h direction|^2 <= k2 (var_j + var_h)``
    (first-order eq. 20 in phase 1, eq. 21 in phase 2; see the module text)."""
    n = offsets.shape[0]
    out = np.empty(n, np.bool_)
    for j in range(n):
        r2 = 0.0
        for i in range(3):
            r = offsets[j, i] + h * direction[i]
            r2 += r * r
        out[j] = r2 <= k2 * (variances[j] + var_h)
    return out


@_jit(step_of=_CORE)
def reestimate(values, variances, support):
    """Inverse-variance weighted mean of ``values[support]``, and its variance."""
    sw = swv = 0.0
    for j in range(values.shape[0]):
        if support[j]:
            sw += 1.0 / variances[j]
            swv += values[j] / variances[j]
    return swv / sw, 1.0 / sw


@_jit(step_of=_CORE)
def search(values, variances, offsets, direction, uniforms, extra, k2, params):
    """Adaptive single-match RANSAC (the rules are in ``vo_lib.stereo_vo.ransac``'s module text):
    batches of hypotheses, the most-supported (then most precise) wins, the batch size follows
    the best inlier ratio. ``extra = (value, variance)`` is scored first when finite.
    Hypotheses come from the ``pool_fraction`` best-conditioned matches (at least ``min_pool``).
    Returns ``(value, variance, count, tried)``."""
    pool = np.argsort(variances)[: max(params.min_pool, int(params.pool_fraction * values.shape[0]))]
    # a hypothesis is tested as if no less certain than a typical one of the pool
    cap = np.median(variances[pool])
    best_v, best_var, best_c = np.nan, np.nan, -1
    if np.isfinite(extra[0]):
        best_v, best_var = extra[0], min(extra[1], cap)
        best_c = supporters(offsets, direction, variances, best_v, best_var, k2).sum()
    n_total = max(values.shape[0], 1)
    tried = 0
    limit = min(_hypotheses_needed(params.initial_inlier_ratio, params.confidence), params.max_hypotheses)
    m_pool = pool.shape[0]
    while tried < limit:
        m = limit - tried
        vals, vars_, counts = np.empty(m), np.empty(m), np.empty(m, np.int64)
        for k in range(m):
            i = pool[min(int(uniforms[tried + k] * m_pool), m_pool - 1)]
            vals[k], vars_[k] = values[i], min(variances[i], cap)
            counts[k] = supporters(offsets, direction, variances, vals[k], vars_[k], k2).sum()
        top = np.argmax(counts - 0.5 * vars_ / (vars_.max() + 1e-300))  # ties: the more precise wins
        if counts[top] > best_c:
            best_v, best_var, best_c = vals[top], vars_[top], counts[top]
        tried += m
        ratio = best_c / n_total if best_c > 0 else 1e-9
        limit = min(_hypotheses_needed(min(ratio, 1.0), params.confidence), params.max_hypotheses)
    return best_v, best_var, best_c, tried


@_jit(step_of=_CORE)
def _gate(ta, ba, tb, bb, phi):
    """Signed eq. 20 for one match."""
    return tb / ta - math.sin(bb - phi) / math.sin(ba + phi)


@_jit(step_of=_CORE)
def theta_gate_pass(ta, ba, tb, bb, theta_j, var_theta, theta, var_ref, k2):
    """The eq. 20 gate of every match at ``theta`` against ``k`` first-order standard deviations
    (the slope by a forward difference), and the match's own theta consistent with it."""
    h = 1e-4
    out = np.empty(ta.shape[0], np.bool_)
    for j in range(ta.shape[0]):
        e = _gate(ta[j], ba[j], tb[j], bb[j], 0.5 * theta)
        slope = (_gate(ta[j], ba[j], tb[j], bb[j], 0.5 * (theta + h)) - e) / h
        var = var_theta[j] + var_ref
        out[j] = (e * e <= k2 * slope * slope * var) and ((theta_j[j] - theta) ** 2 <= k2 * var)
    return out


@_jit(step_of=_CORE)
def usable_matches(a, b, cam):
    """Indices of the matches with both disparities > 0 and off the camera's height (eq. 14 is 0/0 there)."""
    keep = (
        (a[:, 2] > 0)
        & (b[:, 2] > 0)
        & (np.abs(cam.fx * ((a[:, 1] - cam.cy) + (b[:, 1] - cam.cy))) > 1e-9 * cam.fx)
    )
    return np.flatnonzero(keep)


@_jit(step_of=_CORE)
def theta_per_match(a, b, cam, pixel_sigma):
    """theta of every match (eq. 14) and its first-order variance."""
    du, dv, du2, dv2 = a[:, 0] - cam.cx, a[:, 1] - cam.cy, b[:, 0] - cam.cx, b[:, 1] - cam.cy
    num, den = du2 * dv - du * dv2, cam.fx * (dv + dv2)  # eq. 14: tan(theta / 2) = num / den
    theta_j = 2.0 * np.arctan(num / den)
    return theta_j, _theta_variance(du, dv, du2, dv2, num, den, cam.fx, pixel_sigma)


@_jit(step_of=_CORE)
def points_per_match(a, b, cam, pixel_sigma):
    """Back-projected points P, Q (eq. 13) and the first-order variance of each pair."""
    m = a.shape[0]
    P, Q, var_point = np.empty((m, 3)), np.empty((m, 3)), np.empty(m)
    ps2, aspect = pixel_sigma * pixel_sigma, cam.fx / cam.fy
    for i in range(m):
        du, dv, du2, dv2 = a[i, 0] - cam.cx, a[i, 1] - cam.cy, b[i, 0] - cam.cx, b[i, 1] - cam.cy
        sa, sb = cam.baseline / a[i, 2], cam.baseline / b[i, 2]
        P[i, 0], P[i, 1], P[i, 2] = sa * du, sa * dv * aspect, sa * cam.fx
        Q[i, 0], Q[i, 1], Q[i, 2] = sb * du2, sb * dv2 * aspect, sb * cam.fx
        ray_a = math.sqrt(du**2 + (dv * aspect) ** 2 + cam.fx**2) / a[i, 2]
        ray_b = math.sqrt(du2**2 + (dv2 * aspect) ** 2 + cam.fx**2) / b[i, 2]
        var_point[i] = ps2 * (sa * sa * (ray_a * ray_a + 2.0) + sb * sb * (ray_b * ray_b + 2.0))
    return P, Q, var_point


@_jit(step_of=_CORE)
def rho_terms(P, Q, theta):
    """The chord of every match (eq. 16, sign corrected) and the offsets ``Q - R P`` of eq. 21."""
    sphi, cphi = math.sin(0.5 * theta), math.cos(0.5 * theta)
    c, s = math.cos(theta), math.sin(theta)
    m = P.shape[0]
    rho_j, offsets = np.empty(m), np.empty((m, 3))
    for i in range(m):
        rho_j[i] = (-sphi * P[i, 0] + cphi * P[i, 2]) - (sphi * Q[i, 0] + cphi * Q[i, 2])
        offsets[i, 0] = Q[i, 0] - (c * P[i, 0] + s * P[i, 2])
        offsets[i, 1] = Q[i, 1] - P[i, 1]
        offsets[i, 2] = Q[i, 2] - (-s * P[i, 0] + c * P[i, 2])
    return rho_j, offsets, np.array([sphi, 0.0, cphi])


@_jit(step_of=_CORE)
def whitened_pass(P, b, theta, rho, cam, params):
    """eq. 21 whitened: the moved point in front of the camera and its (u, v, d) residual within
    ``whitened_gate`` standard deviations (sigma sqrt 2 per coordinate)."""
    c, s = math.cos(theta), math.sin(theta)
    tx, tz = -rho * math.sin(0.5 * theta), -rho * math.cos(0.5 * theta)
    limit = params.whitened_gate * params.whitened_gate * 2.0 * params.pixel_sigma * params.pixel_sigma
    fb = cam.fx * cam.baseline
    out = np.empty(P.shape[0], np.bool_)
    for i in range(P.shape[0]):
        mx = c * P[i, 0] + s * P[i, 2] + tx
        mz = -s * P[i, 0] + c * P[i, 2] + tz
        iz = 1.0 / mz
        r2 = (
            (cam.fx * mx * iz - (b[i, 0] - cam.cx)) ** 2
            + (cam.fy * P[i, 1] * iz - (b[i, 1] - cam.cy)) ** 2
            + (fb * iz - b[i, 2]) ** 2
        )
        out[i] = mz > 0 and r2 <= limit
    return out


@_jit(twin="vo_lib.stereo_vo.ransac_plain.one_point")
def one_point_core(a, b, cam, prior_theta, prior_rho, draws, params):
    """Everything numeric of ``one_point_ransac``. ``cam`` is a :class:`CameraTerms`, ``params`` a
    :class:`RansacParams`, ``prior_theta`` / ``prior_rho`` are ``(value, variance)`` pairs, NaN
    when there is no prior, ``draws`` the ``(2, max_hypotheses)`` uniform numbers. Returns
    ``(status, theta, rho, covariance, inlier mask over all matches, hypotheses tried in each
    phase, theta inliers, refinement rounds)``."""
    n = a.shape[0]
    k2 = params.gate_sigmas * params.gate_sigmas
    inliers = np.zeros(n, np.bool_)
    cov = np.full((2, 2), np.inf)
    iu = usable_matches(a, b, cam)
    if iu.shape[0] < 3:
        return FEW_USABLE, np.nan, np.nan, cov, inliers, 0, 0, 0, 0
    wa, wb = a[iu], b[iu]
    # ------------------------------------------------------------ phase 1: theta (eq. 14, 18-20)
    theta_j, var_theta = theta_per_match(wa, wb, cam, params.pixel_sigma)
    offsets = np.zeros((iu.shape[0], 3))
    offsets[:, 0] = theta_j
    minus_x = np.array([-1.0, 0.0, 0.0])
    theta_h, var_h, _, tried_theta = search(
        theta_j, var_theta, offsets, minus_x, draws[0], prior_theta, k2, params
    )
    support = supporters(offsets, minus_x, var_theta, theta_h, var_h, k2)
    theta_hat, var_theta_hat = reestimate(theta_j, var_theta, support)
    beta_a, beta_b = np.arctan((wa[:, 0] - cam.cx) / cam.fx), np.arctan((wb[:, 0] - cam.cx) / cam.fx)
    ta, tb = (wa[:, 1] - cam.cy) * np.cos(beta_a) / cam.fy, (wb[:, 1] - cam.cy) * np.cos(beta_b) / cam.fy
    theta_in = theta_gate_pass(ta, beta_a, tb, beta_b, theta_j, var_theta, theta_hat, var_theta_hat, k2)
    it = np.flatnonzero(theta_in)
    if it.shape[0] < 3:
        return FEW_THETA_INLIERS, np.nan, np.nan, cov, inliers, tried_theta, 0, it.shape[0], 0
    # ------------------------------------------------------------ phase 2: rho (eq. 13, 16-17, 21)
    P, Q, var_point = points_per_match(wa, wb, cam, params.pixel_sigma)
    rho_j, offsets, direction = rho_terms(P[it], Q[it], theta_hat)
    var_pt = var_point[it]
    rho_h, var_h, _, tried_rho = search(rho_j, var_pt, offsets, direction, draws[1], prior_rho, k2, params)
    rho_hat, var_rho = reestimate(rho_j, var_pt, supporters(offsets, direction, var_pt, rho_h, var_h, k2))
    keep = np.zeros(iu.shape[0], np.bool_)
    keep[it] = supporters(offsets, direction, var_pt, rho_hat, var_rho, k2)
    theta, rho = theta_hat, rho_hat
    cov = np.zeros((2, 2))
    cov[0, 0], cov[1, 1] = var_theta_hat, var_rho
    # ------------------------------------------------------------ refinement on all inliers
    rounds = 0
    while params.refine and keep.sum() >= 3 and rounds < params.refine_rounds:
        rounds += 1
        sel = np.flatnonzero(keep)
        iterations = params.refine_iterations if rounds == 1 else 1
        theta, rho, a00, a01, a11, rss = gauss_newton(
            P[sel], Q[sel], wa[sel], wb[sel], theta, rho, cam, iterations
        )
        cov = covariance(a00, a01, a11, rss, 6 * sel.shape[0])
        # the refined motion decides the inliers again: the theta gate, and eq. 21 whitened in (u, v, d)
        new = theta_gate_pass(ta, beta_a, tb, beta_b, theta_j, var_theta, theta, cov[0, 0], k2)
        new &= whitened_pass(P, wb, theta, rho, cam, params)
        changed = np.any(new != keep)
        keep = new
        if not changed:
            break
    inliers[iu] = keep
    status = OK if keep.sum() >= 3 else FEW_INLIERS
    return status, theta, rho, cov, inliers, tried_theta, tried_rho, it.shape[0], rounds
