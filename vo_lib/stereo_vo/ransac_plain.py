"""1-point RANSAC in plain NumPy: the twin of the compiled ``ransac_core``, for reading.

Each function is one step of the estimator of [Zhao], III.A.3 (the rules and their reasons are
in ``vo_lib.stereo_vo.ransac``'s module text), and is registered as the plain twin of the kernel
it mirrors: ``VO_LIB_PLAIN=1`` (or ``one_point_ransac(..., plain=True)``) runs these instead of
the compiled kernels, so a reader can step through them in a debugger. They take the same
:class:`~vo_lib.stereo_vo.ransac_core.RansacParams` and give the same results, to rounding (the
tests hold them to it on random inputs).
"""

from __future__ import annotations

import math

import numpy as np

from vo_lib.stereo_vo import ransac_core as core
from vo_lib.stereo_vo.circular_motion import theta_variance


def usable_matches(a, b, cam):
    """Indices of the matches with both disparities > 0, off the camera's height (eq. 14 is 0/0 there)."""
    off_height = np.abs(cam.fx * ((a[:, 1] - cam.cy) + (b[:, 1] - cam.cy))) > 1e-9 * cam.fx
    return np.flatnonzero((a[:, 2] > 0) & (b[:, 2] > 0) & off_height)


def theta_per_match(a, b, cam, pixel_sigma):
    """theta of every match, ``tan(theta / 2) = num / den`` (eq. 14), and its first-order variance."""
    du, dv, du2, dv2 = a[:, 0] - cam.cx, a[:, 1] - cam.cy, b[:, 0] - cam.cx, b[:, 1] - cam.cy
    num, den = du2 * dv - du * dv2, cam.fx * (dv + dv2)
    return 2.0 * np.arctan(num / den), theta_variance(du, dv, du2, dv2, num, den, cam.fx, pixel_sigma)


def supporters(offsets, direction, variances, h, var_h, k2):
    """Matches supporting hypothesis ``h``: ``|offset_j + h direction|^2 <= k2 (var_j + var_h)``.

    Phase 1 (eq. 20 to first order): offset ``(theta_j, 0, 0)``, direction ``(-1, 0, 0)``.
    Phase 2 (eq. 21): offset ``Q - R P``, direction ``(sin phi, 0, cos phi)``.
    """
    r = offsets + h * direction
    return np.sum(r * r, axis=1) <= k2 * (variances + var_h)


def reestimate(values, variances, support):
    """Inverse-variance weighted mean of ``values[support]``, and its variance."""
    w = 1.0 / variances[support]
    return np.sum(w * values[support]) / np.sum(w), 1.0 / np.sum(w)


def search(values, variances, offsets, direction, uniforms, extra, k2, params):
    """The hypothesis with most supporters (eq. 18-19): ``(value, variance, supporters, tried)``.

    Hypotheses are the values of matches drawn from the pool (the best-conditioned matches);
    a draw ``u`` picks ``pool[int(u * len(pool))]``. They are tried in batches until
    ``hypotheses_needed`` of them, for the best inlier ratio so far, have been tried. ``extra``
    (the filter's prediction) is scored first when finite.
    """
    pool = np.argsort(variances)[: max(params.min_pool, int(params.pool_fraction * len(values)))]
    cap = np.median(variances[pool])  # a hypothesis counts as no more certain than a typical one

    def count(h, var_h):
        return int(supporters(offsets, direction, variances, h, var_h, k2).sum())

    best = (np.nan, np.nan, -1)
    if np.isfinite(extra[0]):
        best = (extra[0], min(extra[1], cap), count(extra[0], min(extra[1], cap)))
    tried = 0
    limit = min(core.hypotheses_needed(params.initial_inlier_ratio, params.confidence), params.max_hypotheses)
    while tried < limit:
        picked = pool[np.minimum((uniforms[tried:limit] * len(pool)).astype(int), len(pool) - 1)]
        hyp, hyp_var = values[picked], np.minimum(variances[picked], cap)
        counts = np.array([count(h, v) for h, v in zip(hyp, hyp_var, strict=True)])
        top = int(np.argmax(counts - 0.5 * hyp_var / (hyp_var.max() + 1e-300)))  # ties: the more precise wins
        if counts[top] > best[2]:
            best = (hyp[top], hyp_var[top], counts[top])
        tried = limit
        ratio = best[2] / max(len(values), 1) if best[2] > 0 else 1e-9
        limit = min(core.hypotheses_needed(min(ratio, 1.0), params.confidence), params.max_hypotheses)
    return best[0], best[1], best[2], tried


def gate_angles(w, cam):
    """``(tan(alpha), beta)`` of Fig. 5 for matches ``w``: depression and bearing of each ray."""
    beta = np.arctan((w[:, 0] - cam.cx) / cam.fx)
    return (w[:, 1] - cam.cy) * np.cos(beta) / cam.fy, beta


def theta_gate_pass(wa, wb, theta_j, var_theta, theta, var_ref, k2, cam, step=1e-4):
    """eq. 20 at ``theta`` within ``k`` of each match's first-order sigma (slope by a forward
    difference), and the match's own theta within ``k`` sigma of ``theta``."""
    (ta, ba), (tb, bb) = gate_angles(wa, cam), gate_angles(wb, cam)

    def gate(t):  # signed eq. 20
        return tb / ta - np.sin(bb - 0.5 * t) / np.sin(ba + 0.5 * t)

    e = gate(theta)
    slope = (gate(theta + step) - e) / step
    var = var_theta + var_ref
    return (e * e <= k2 * slope * slope * var) & ((theta_j - theta) ** 2 <= k2 * var)


def points_per_match(a, b, cam, pixel_sigma):
    """Points ``P = B/d (u - u0, (v - v0) fx/fy, fx)`` (eq. 13) of both frames and the first-order
    variance of each pair: ``sigma^2 (B/d)^2 (|ray|^2 / d^2 + 2)`` per view."""

    def back_project(w):
        ray = np.stack([w[:, 0] - cam.cx, (w[:, 1] - cam.cy) * (cam.fx / cam.fy), np.full(len(w), cam.fx)], 1)
        scale = cam.baseline / w[:, 2]
        variance = scale**2 * (np.sum(ray * ray, axis=1) / w[:, 2] ** 2 + 2.0)
        return scale[:, None] * ray, variance

    (P, var_a), (Q, var_b) = back_project(a), back_project(b)
    return P, Q, pixel_sigma**2 * (var_a + var_b)


def rho_terms(P, Q, theta):
    """The chord of every match (eq. 16, sign corrected), the offsets ``Q - R P`` of eq. 21 and
    the direction in which ``rho`` moves them."""
    sphi, cphi, c, s = math.sin(0.5 * theta), math.cos(0.5 * theta), math.cos(theta), math.sin(theta)
    R = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
    rho_j = (-sphi * P[:, 0] + cphi * P[:, 2]) - (sphi * Q[:, 0] + cphi * Q[:, 2])
    return rho_j, Q - P @ R.T, np.array([sphi, 0.0, cphi])


def project(X, cam):
    """Centred ``(u, v, d)`` of points ``X`` and the Jacobian ``d pi / dX``, shape (N, 3, 3)."""
    x, y, z = X.T
    fb = cam.fx * cam.baseline
    J = np.zeros((len(X), 3, 3))
    J[:, 0, 0], J[:, 0, 2] = cam.fx / z, -cam.fx * x / z**2
    J[:, 1, 1], J[:, 1, 2] = cam.fy / z, -cam.fy * y / z**2
    J[:, 2, 2] = -fb / z**2
    return np.stack([cam.fx * x / z, cam.fy * y / z, fb / z], axis=1), J


def reprojection(theta, rho, P, Q, wa, wb, cam):
    """Forward ``pi(R P + T) - w'`` and backward ``pi(R^T (Q - T)) - w`` residuals (6N,) and their
    Jacobian in ``(theta, rho)``, (6N, 2), by the chain rule."""
    c, s, sp, cp = math.cos(theta), math.sin(theta), math.sin(theta / 2), math.cos(theta / 2)
    R, T = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]), -rho * np.array([sp, 0, cp])
    dR = np.array([[-s, 0, c], [0, 0, 0], [-c, 0, -s]])  # dR / dtheta
    dT_theta, dT_rho = -rho / 2 * np.array([cp, 0, -sp]), -np.array([sp, 0, cp])
    fwd, J_fwd = project(P @ R.T + T, cam)
    bwd, J_bwd = project((Q - T) @ R, cam)  # R^T (Q - T), row by row
    n = len(P)
    d_fwd = np.stack([P @ dR.T + dT_theta, np.tile(dT_rho, (n, 1))], axis=2)  # (N, 3, 2)
    d_bwd = np.stack([(Q - T) @ dR - dT_theta @ R, np.tile(-dT_rho @ R, (n, 1))], axis=2)
    centre = np.array([cam.cx, cam.cy, 0.0])
    r = np.concatenate([fwd - (wb - centre), bwd - (wa - centre)]).ravel()
    return r, np.concatenate([J_fwd @ d_fwd, J_bwd @ d_bwd]).reshape(-1, 2)


def gauss_newton(P, Q, wa, wb, theta, rho, cam, iterations):
    """Gauss-Newton on ``(theta, rho)``: ``(theta, rho, A00, A01, A11, rss)`` with the normal
    matrix ``J^T J`` and residuals of the last iterate before its step."""
    A, rss = np.zeros((2, 2)), 0.0
    for _ in range(max(iterations, 1)):
        r, J = reprojection(theta, rho, P, Q, wa, wb, cam)
        A, rss = J.T @ J, float(r @ r)
        if not np.linalg.det(A) > 0:
            break
        step = -np.linalg.solve(A, J.T @ r)
        theta, rho = theta + step[0], rho + step[1]
        if abs(step[0]) < 1e-10 and abs(step[1]) < 1e-9:
            break
    return theta, rho, A[0, 0], A[0, 1], A[1, 1], rss


def covariance(a00, a01, a11, rss, count):
    """``2 sigma^2 A^-1``: forward and backward residuals carry the same noise, so their
    information counts once; infinite variances when ``A`` is singular."""
    A = np.array([[a00, a01], [a01, a11]])
    if not np.linalg.det(A) > 0:
        return np.array([[np.inf, 0.0], [0.0, np.inf]])
    return 2.0 * rss / max(count - 2, 1) * np.linalg.inv(A)


def whitened_pass(P, b, theta, rho, cam, params):
    """eq. 21 whitened: the moved point in front of the camera, its (u, v, d) residual within
    ``whitened_gate`` standard deviations (sigma sqrt 2 per coordinate)."""
    c, s, sp, cp = math.cos(theta), math.sin(theta), math.sin(theta / 2), math.cos(theta / 2)
    moved = P @ np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]).T - rho * np.array([sp, 0, cp])
    with np.errstate(divide="ignore", invalid="ignore"):
        r = project(moved, cam)[0] - (b - np.array([cam.cx, cam.cy, 0.0]))
    limit = params.whitened_gate**2 * 2.0 * params.pixel_sigma**2
    return (moved[:, 2] > 0) & (np.sum(r * r, axis=1) <= limit)


def one_point(a, b, cam, prior_theta, prior_rho, draws, params):
    """The whole estimator, with the arguments and results of ``ransac_core.one_point_core``."""
    k2 = params.gate_sigmas**2
    inliers, cov = np.zeros(len(a), bool), np.full((2, 2), np.inf)
    iu = usable_matches(a, b, cam)
    if len(iu) < 3:
        return core.FEW_USABLE, np.nan, np.nan, cov, inliers, 0, 0, 0, 0
    wa, wb = a[iu], b[iu]
    # phase 1: theta of one match is a hypothesis (eq. 14); its gate eq. 20
    theta_j, var_theta = theta_per_match(wa, wb, cam, params.pixel_sigma)
    offsets, minus_x = np.stack([theta_j, 0 * theta_j, 0 * theta_j], 1), np.array([-1.0, 0.0, 0.0])
    h, var_h, _, tried_theta = search(theta_j, var_theta, offsets, minus_x, draws[0], prior_theta, k2, params)
    theta, var_t = reestimate(theta_j, var_theta, supporters(offsets, minus_x, var_theta, h, var_h, k2))
    theta_in = theta_gate_pass(wa, wb, theta_j, var_theta, theta, var_t, k2, cam)
    if theta_in.sum() < 3:
        return core.FEW_THETA_INLIERS, np.nan, np.nan, cov, inliers, tried_theta, 0, int(theta_in.sum()), 0
    # phase 2: rho of one theta inlier is a hypothesis (eq. 16-17); its gate eq. 21
    P, Q, var_point = points_per_match(wa, wb, cam, params.pixel_sigma)
    rho_j, offsets, direction = rho_terms(P[theta_in], Q[theta_in], theta)
    var_i = var_point[theta_in]
    h, var_h, _, tried_rho = search(rho_j, var_i, offsets, direction, draws[1], prior_rho, k2, params)
    rho, var_r = reestimate(rho_j, var_i, supporters(offsets, direction, var_i, h, var_h, k2))
    keep = np.zeros(len(wa), bool)
    keep[theta_in] = supporters(offsets, direction, var_i, rho, var_r, k2)
    cov = np.diag([var_t, var_r])
    # refinement on all inliers; the refined motion decides the inliers again
    rounds = 0
    while params.refine and keep.sum() >= 3 and rounds < params.refine_rounds:
        rounds += 1
        iterations = params.refine_iterations if rounds == 1 else 1
        theta, rho, *normal = gauss_newton(P[keep], Q[keep], wa[keep], wb[keep], theta, rho, cam, iterations)
        cov = covariance(*normal, 6 * int(keep.sum()))
        new = theta_gate_pass(wa, wb, theta_j, var_theta, theta, cov[0, 0], k2, cam)
        new &= whitened_pass(P, wb, theta, rho, cam, params)
        changed, keep = bool(np.any(new != keep)), new
        if not changed:
            break
    inliers[iu] = keep
    status = core.OK if keep.sum() >= 3 else core.FEW_INLIERS
    return status, theta, rho, cov, inliers, tried_theta, tried_rho, int(theta_in.sum()), rounds
