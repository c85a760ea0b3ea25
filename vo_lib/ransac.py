"""1-point RANSAC for the planar circular-motion model (seed 000, III.A.3, eq. 18-21).

One match determines the motion: theta from its pixels alone (eq. 14), then rho from its pixels
and disparities (eq. 17, sign corrected). Following the paper, the search runs in two phases.

**Phase 1, theta.** Each hypothesis is the theta of one match; every match is checked with the
gate of eq. 18-20. Fig. 5, which defines its angles, is missing from the paper; our
reconstruction (notebook 06): in the horizontal plane, a point at horizontal range ``r`` is seen
at depression angle ``alpha`` (``tan alpha = height / r``) and at angle ``gamma`` between its ray
and the chord the camera travels. The height does not change, so ``r tan alpha = r' tan alpha'``;
and the perpendicular distance from the point to the chord line is the same from both ends (law
of sines), so ``r sin gamma = r' sin gamma'``. Both give ``r / r'``, and eq. 20 is their
difference:

    error_theta = | tan(alpha') / tan(alpha) - sin(gamma') / sin(gamma) |,
    tan(alpha) = (v - v0) cos(beta) / fy,  beta = atan((u - u0) / fx),
    gamma = beta + phi,  gamma' = beta' - phi,  phi = theta / 2,

zero for a true match. Pixel noise moves it by an amount that differs by orders of magnitude
between matches (it explodes near the camera's height and near the direction of travel), so one
fixed threshold cannot serve all; each match's threshold is ``k`` standard deviations of its own
gate, to first order: ``|d error / d theta| * sqrt(sigma_theta_match^2 + sigma_theta_hypothesis^2)``.

**Phase 2, rho.** With theta fixed, each hypothesis is the rho of one match (eq. 17); the gate is
eq. 21, ``|| P' - (R P + T) ||``, against ``k`` standard deviations of that residual (depth noise
grows as ``z^2``, so again per match, plus the hypothesis' own uncertainty).

Hypotheses are drawn from the best-conditioned half of the matches, scored all at once, and
drawn until ``log(1 - p) / log(1 - w)`` of them have been tried for the best inlier ratio ``w``
found. The winner is refined on all inliers by Gauss-Newton least squares on the reprojection
errors in disparity space, both ways, where pixel noise is uniform; the refined motion then
decides the final inliers with the theta gate and with eq. 21 *whitened*: a back-projected
point is uncertain mostly along its ray (metres, far away) and little across it (millimetres),
so the residual is compared in (u, v, d), where its noise is the same in every direction.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from vo_lib.camera import StereoCamera
from vo_lib.circular_motion import motion_matrices, rho_from_pixels, theta_from_pixels, theta_variance
from vo_lib.geometry import as_match_array

GATE_SIGMAS = 3.0  # a match is an inlier within this many standard deviations of each gate
#: Final gate on the whitened eq. 21 residual, a 3-vector: sqrt of chi-square(3) at 99.7 %.
WHITENED_GATE = 3.76
PIXEL_SIGMA = 0.5  # pixel noise of u, v and d assumed by the gates
CONFIDENCE = 0.999  # probability of drawing at least one all-inlier hypothesis
MAX_HYPOTHESES = 200
POOL_FRACTION = 0.5  # hypotheses come from this best-conditioned fraction of the matches
MIN_POOL = 8
REFINE_ITERATIONS = 2
REFINE_ROUNDS = 3  # refine, re-select inliers, and refine again while the set changes
INITIAL_INLIER_RATIO = 0.5  # first guess, before any hypothesis has been scored


@dataclass
class RansacResult:
    """Outcome of :func:`one_point_ransac`."""

    theta: float
    rho: float
    inliers: np.ndarray
    covariance: np.ndarray
    success: bool
    diagnostics: dict = field(default_factory=dict)


def hypotheses_needed(inlier_ratio: float, confidence: float = CONFIDENCE, sample_size: int = 1) -> int:
    """Hypotheses so that at least one is all-inlier with probability ``confidence``:
    ``ceil(log(1 - p) / log(1 - w**s))``."""
    w = min(max(float(inlier_ratio), 1e-9), 1.0)
    good = w**sample_size
    if good >= 1.0:
        return 1
    return max(1, math.ceil(math.log(1.0 - confidence) / math.log(1.0 - good)))


# ---------------------------------------------------------------------- eq. 18-20
def gate_angles(w: np.ndarray, camera: StereoCamera) -> tuple[np.ndarray, np.ndarray]:
    """``(tan(alpha), beta)`` of Fig. 5 for matches ``w``: depression and bearing of each ray."""
    beta = np.arctan((w[:, 0] - camera.cx) / camera.fx)
    tan_alpha = (w[:, 1] - camera.cy) * np.cos(beta) / camera.fy
    return tan_alpha, beta


def _theta_gate(ta, ba, tb, bb, phi):
    """Signed eq. 20: ``tan(alpha')/tan(alpha) - sin(gamma')/sin(gamma)``; broadcasts over ``phi``."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return tb / ta - np.sin(bb - phi) / np.sin(ba + phi)


def theta_gate_error(w_prev, w_curr, theta, camera: StereoCamera) -> np.ndarray:
    """``error_theta`` of eq. 20 for every match under deflection ``theta`` (zero for a true match)."""
    a, b = as_match_array("w_prev", w_prev), as_match_array("w_curr", w_curr)
    ta, ba = gate_angles(a, camera)
    tb, bb = gate_angles(b, camera)
    return np.abs(_theta_gate(ta, ba, tb, bb, 0.5 * np.asarray(theta, dtype=float)))


# ---------------------------------------------------------------------- eq. 21
def rho_gate_error(P, Q, theta, rho) -> np.ndarray:
    """``error_rho = || P' - (R P + T) ||`` of eq. 21 for points ``P -> Q``; broadcasts over ``rho``."""
    R, T = motion_matrices(theta, rho)
    moved = np.asarray(P) @ R.T  # (N, 3)
    return np.linalg.norm(np.asarray(Q) - moved - T[..., None, :], axis=-1)


# ---------------------------------------------------------------------- refinement
def _gauss_newton(P, Q, wa, wb, theta, rho, camera, iterations):
    """Gauss-Newton on forward and backward reprojection errors in disparity space.

    Forward: ``pi(R P + T) - w'``; backward: ``pi(R^T (Q - T)) - w``. With ``c, s`` of theta and
    ``sp, cp`` of phi = theta/2, ``R P + T = (c X + s Z - rho sp, Y, -s X + c Z - rho cp)`` and
    ``R^T (Q - T) = (c X' - s Z' - rho sp, Y', s X' + c Z' + rho cp)``: one formula with a sign
    ``g = +1`` forward and ``-1`` backward, so both run as one vector of length 2N. The Jacobian
    is analytic. Returns ``(theta, rho, normal_matrix, residual_sum_of_squares, count)``; the normal
    matrix and residuals are those of the last iterate before its update.
    """
    fx, fy, cx, cy, fb = camera.fx, camera.fy, camera.cx, camera.cy, camera.fx * camera.baseline
    x = np.concatenate([P[:, 0], Q[:, 0]])
    y = np.concatenate([P[:, 1], Q[:, 1]])
    z = np.concatenate([P[:, 2], Q[:, 2]])
    g = np.concatenate([np.ones(len(P)), -np.ones(len(Q))])
    obs = np.concatenate([wb, wa])
    ou, ov, od = obs[:, 0] - cx, obs[:, 1] - cy, obs[:, 2]
    gx, gz = g * x, g * z
    A = np.zeros((2, 2))
    rss = 0.0
    for _ in range(max(iterations, 1)):
        c, s = math.cos(theta), math.sin(theta)
        sp, cp = math.sin(0.5 * theta), math.cos(0.5 * theta)
        xm = c * x + s * gz - rho * sp
        zm = c * z - s * gx - (rho * cp) * g
        dx_t = c * gz - s * x - 0.5 * rho * cp
        dz_t = (0.5 * rho * sp) * g - c * gx - s * z
        dz_r = -cp * g
        iz = 1.0 / zm
        iz2 = iz * iz
        ru, rv, rd = fx * xm * iz - ou, fy * y * iz - ov, fb * iz - od
        fz = fx * iz2
        ju_t, ju_r = fz * (dx_t * zm - xm * dz_t), fz * (-sp * zm - xm * dz_r)
        yz = -fy * y * iz2
        jv_t, jv_r = yz * dz_t, yz * dz_r
        jd_t, jd_r = (-fb * iz2) * dz_t, (-fb * iz2) * dz_r
        A[0, 0] = ju_t @ ju_t + jv_t @ jv_t + jd_t @ jd_t
        A[0, 1] = A[1, 0] = ju_t @ ju_r + jv_t @ jv_r + jd_t @ jd_r
        A[1, 1] = ju_r @ ju_r + jv_r @ jv_r + jd_r @ jd_r
        b0 = ju_t @ ru + jv_t @ rv + jd_t @ rd
        b1 = ju_r @ ru + jv_r @ rv + jd_r @ rd
        rss = ru @ ru + rv @ rv + rd @ rd
        det = A[0, 0] * A[1, 1] - A[0, 1] ** 2
        if not det > 0:
            break
        d_theta = -(A[1, 1] * b0 - A[0, 1] * b1) / det
        d_rho = -(A[0, 0] * b1 - A[0, 1] * b0) / det
        theta, rho = theta + d_theta, rho + d_rho
        if abs(d_theta) < 1e-10 and abs(d_rho) < 1e-9:
            break
    return theta, rho, A.copy(), float(rss), 6 * len(P)


def _covariance(A, rss, count):
    sigma2 = rss / max(count - 2, 1)
    det = A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0]
    if not det > 0:
        return np.diag([np.inf, np.inf])
    inverse = np.array([[A[1, 1], -A[0, 1]], [-A[1, 0], A[0, 0]]]) / det
    # forward and backward residuals carry the same noise, so their information counts once
    return 2.0 * sigma2 * inverse


def refine_motion(
    w_prev, w_curr, theta: float, rho: float, camera: StereoCamera, iterations: int = REFINE_ITERATIONS
) -> tuple[float, float, np.ndarray]:
    """Least-squares ``(theta, rho)`` on matches, minimising reprojection errors in disparity space
    in both directions. Returns ``(theta, rho, covariance)``."""
    wa, wb = np.asarray(w_prev, float), np.asarray(w_curr, float)
    P, Q = camera.backproject(wa), camera.backproject(wb)
    theta, rho, A, rss, count = _gauss_newton(P, Q, wa, wb, float(theta), float(rho), camera, iterations)
    return float(theta), float(rho), _covariance(A, rss, count)


# ---------------------------------------------------------------------- the search
def _search(
    pool: np.ndarray,
    values: np.ndarray,
    variances: np.ndarray,
    passes,
    rng,
    confidence: float,
    max_hypotheses: int,
    extra=None,
):
    """Adaptive single-match RANSAC: draw batches of hypotheses from ``pool``, score each batch at
    once with ``passes(values, variances) -> (H, N) bool``, stop after ``hypotheses_needed``.

    Returns ``(value, variance, count, tried)`` of the best hypothesis; ``extra`` is one more
    ``(value, variance)`` scored first (the filter's prediction).
    """
    # a hypothesis is tested as if no less certain than a typical one of the pool: a very uncertain
    # hypothesis would otherwise open every gate and out-count the precise ones
    cap = float(np.median(variances[pool]))
    best = (None, None, -1)
    if extra is not None:
        var_extra = min(float(extra[1]), cap)
        count = int(passes(np.array([extra[0]]), np.array([var_extra]))[0].sum())
        best = (float(extra[0]), var_extra, count)
    tried, limit = 0, min(hypotheses_needed(INITIAL_INLIER_RATIO, confidence), max_hypotheses)
    n_total = max(len(pool), 1)
    while tried < limit:
        idx = pool[rng.integers(0, len(pool), limit - tried)]
        var = np.minimum(variances[idx], cap)
        counts = passes(values[idx], var).sum(axis=1)
        # among equal counts the more precise hypothesis wins
        k = int(np.argmax(counts - 0.5 * var / (var.max() + 1e-300)))
        if counts[k] > best[2]:
            best = (float(values[idx[k]]), float(var[k]), int(counts[k]))
        tried += len(idx)
        ratio = best[2] / n_total if best[2] > 0 else 1e-9
        limit = min(hypotheses_needed(min(ratio, 1.0), confidence), max_hypotheses)
    return best[0], best[1], best[2], tried


def one_point_ransac(
    w_prev,
    w_curr,
    camera: StereoCamera,
    prior=None,
    rng=None,
    *,
    pixel_sigma: float = PIXEL_SIGMA,
    gate_sigmas: float = GATE_SIGMAS,
    confidence: float = CONFIDENCE,
    max_hypotheses: int = MAX_HYPOTHESES,
    refine: bool = True,
) -> RansacResult:
    """Estimate ``(theta, rho)`` from matches with 1-point RANSAC and the two gates of the paper.

    Parameters
    ----------
    w_prev, w_curr : array_like, shape (N, 3)
        Matches ``(u, v, d)`` in the previous and current frame.
    camera : StereoCamera
    prior : MotionPrior, optional
        The filter's predicted motion; it is scored as one more hypothesis in each phase.
    rng : numpy.random.Generator or int, optional
        Source of the random draws (seeded, for repeatable results).
    pixel_sigma, gate_sigmas : float
        Pixel noise assumed by the gates, and their width in standard deviations.
    confidence, max_hypotheses : float, int
        Stopping rule of the adaptive hypothesis count.
    refine : bool
        Refine on all inliers by least squares.

    Returns
    -------
    RansacResult
        ``theta``, ``rho``, an ``inliers`` mask, a 2x2 ``covariance`` and ``diagnostics``;
        ``success`` is False when fewer than 3 usable matches exist (the prior, or zeros, are
        returned then, with an empty inlier set).
    """
    t_start = time.perf_counter()
    a, b = as_match_array("w_prev", w_prev), as_match_array("w_curr", w_curr)
    if a.shape != b.shape:
        raise ValueError(f"w_prev and w_curr must have the same shape; got {a.shape} and {b.shape}")
    rng = np.random.default_rng(rng)
    n = len(a)
    inliers = np.zeros(n, bool)
    diagnostics = {"matches": n}

    def failure(reason: str) -> RansacResult:
        diagnostics.update(reason=reason, time_ms=(time.perf_counter() - t_start) * 1e3)
        if prior is not None:
            return RansacResult(
                float(prior.theta),
                float(prior.rho),
                inliers,
                np.asarray(prior.covariance, float),
                False,
                diagnostics,
            )
        return RansacResult(0.0, 0.0, inliers, np.diag([np.inf, np.inf]), False, diagnostics)

    k2 = gate_sigmas**2
    fx, fy, cx, cy, B = camera.fx, camera.fy, camera.cx, camera.cy, camera.baseline
    # ------------------------------------------------------------ per match, once
    du, dv, du2, dv2 = a[:, 0] - cx, a[:, 1] - cy, b[:, 0] - cx, b[:, 1] - cy
    num, den = du2 * dv - du * dv2, fx * (dv + dv2)  # eq. 14: tan(phi) = num / den
    usable = (a[:, 2] > 0) & (b[:, 2] > 0) & (np.abs(den) > 1e-9 * fx)
    if usable.sum() < 3:
        return failure("fewer than 3 matches with positive disparities off the camera's height")
    iu = np.flatnonzero(usable)
    du, dv, du2, dv2, num, den = du[iu], dv[iu], du2[iu], dv2[iu], num[iu], den[iu]
    au, bu = a[iu], b[iu]
    theta_j = 2.0 * np.arctan(num / den)
    var_theta = theta_variance(du, dv, du2, dv2, num, den, fx, pixel_sigma)

    # ------------------------------------------------------------ phase 1: theta, eq. 14 and 18-20
    def theta_consistent(theta_h, var_h):
        # first-order form of the eq. 20 gate: the match's own theta agrees with the hypothesis
        return (theta_j - theta_h[:, None]) ** 2 <= k2 * (var_theta + var_h[:, None])

    pool = np.argsort(var_theta)[: max(MIN_POOL, int(POOL_FRACTION * len(iu)))]
    extra = (prior.theta, prior.covariance[0][0]) if prior is not None else None
    theta_h, var_h, _, tried_theta = _search(
        pool, theta_j, var_theta, theta_consistent, rng, confidence, max_hypotheses, extra
    )
    passes = theta_consistent(np.array([theta_h]), np.array([var_h]))[0]
    wts = 1.0 / var_theta[passes]  # refine theta: inverse-variance weighted mean of its inliers
    theta_hat = float(np.sum(wts * theta_j[passes]) / np.sum(wts))
    var_theta_hat = float(1.0 / np.sum(wts))
    # the paper's gate (eq. 18-20) decides the theta inliers of the refined theta
    beta_a, beta_b = np.arctan(du / fx), np.arctan(du2 / fx)
    ta, tb = dv * np.cos(beta_a) / fy, dv2 * np.cos(beta_b) / fy
    h = 1e-4
    e0 = _theta_gate(ta, beta_a, tb, beta_b, 0.5 * theta_hat)
    slope = (_theta_gate(ta, beta_a, tb, beta_b, 0.5 * (theta_hat + h)) - e0) / h

    def theta_gate_pass(e, slope_, theta_ref, var_ref):
        var = var_theta + var_ref
        with np.errstate(invalid="ignore"):
            return (e * e <= k2 * slope_ * slope_ * var) & ((theta_j - theta_ref) ** 2 <= k2 * var)

    theta_in = theta_gate_pass(e0, slope, theta_hat, var_theta_hat)
    if theta_in.sum() < 3:
        return failure("fewer than 3 theta inliers")

    # ------------------------------------------------------------ phase 2: rho, eq. 17 and 21
    sa, sb = B / au[:, 2], B / bu[:, 2]
    P = np.column_stack([sa * du, sa * dv * (fx / fy), sa * fx])  # eq. 13
    Q = np.column_stack([sb * du2, sb * dv2 * (fx / fy), sb * fx])
    ray_a = np.sqrt(du * du + (dv * fx / fy) ** 2 + fx * fx) / au[:, 2]
    ray_b = np.sqrt(du2 * du2 + (dv2 * fx / fy) ** 2 + fx * fx) / bu[:, 2]
    var_point = pixel_sigma**2 * (sa * sa * (ray_a * ray_a + 2.0) + sb * sb * (ray_b * ray_b + 2.0))
    phi = 0.5 * theta_hat
    sphi, cphi = math.sin(phi), math.cos(phi)
    it = np.flatnonzero(theta_in)
    rho_j = (-sphi * P[it, 0] + cphi * P[it, 2]) - (sphi * Q[it, 0] + cphi * Q[it, 2])  # eq. 16, corrected
    c, s = math.cos(theta_hat), math.sin(theta_hat)
    # residual of eq. 21 without T: Q - R P; then the gate subtracts rho * (-sin phi, 0, -cos phi)
    base_x = Q[it, 0] - (c * P[it, 0] + s * P[it, 2])
    base_y = Q[it, 1] - P[it, 1]
    base_z = Q[it, 2] - (-s * P[it, 0] + c * P[it, 2])
    var_pt = var_point[it]

    def rho_pass(rho_h, var_h):
        rx = base_x + (rho_h * sphi)[:, None]
        rz = base_z + (rho_h * cphi)[:, None]
        return rx * rx + base_y * base_y + rz * rz <= k2 * (var_pt + var_h[:, None])

    pool2 = np.argsort(var_pt)[: max(MIN_POOL, int(POOL_FRACTION * len(it)))]
    extra = (prior.rho, prior.covariance[1][1]) if prior is not None else None
    rho_hat, var_rho, _, tried_rho = _search(
        pool2, rho_j, var_pt, rho_pass, rng, confidence, max_hypotheses, extra
    )
    rho_in = rho_pass(np.array([rho_hat]), np.array([var_rho]))[0]
    # refine rho on its inliers, like theta: inverse-variance weighted mean of the per-match rhos
    w_rho = 1.0 / var_pt[rho_in]
    rho_hat, var_rho = float(np.sum(w_rho * rho_j[rho_in]) / np.sum(w_rho)), float(1.0 / np.sum(w_rho))
    keep = np.zeros(len(iu), bool)
    keep[it[rho_pass(np.array([rho_hat]), np.array([var_rho]))[0]]] = True
    theta, rho = theta_hat, rho_hat
    covariance = np.diag([var_theta_hat, var_rho])

    # ------------------------------------------------------------ refinement on all inliers
    rounds = 0
    while refine and keep.sum() >= 3 and rounds < REFINE_ROUNDS:
        rounds += 1
        theta, rho, A, rss, count = _gauss_newton(
            P[keep], Q[keep], au[keep], bu[keep], theta, rho, camera, REFINE_ITERATIONS if rounds == 1 else 1
        )
        covariance = _covariance(A, rss, count)
        # the refined motion decides the inliers again, through both gates, with its own small
        # uncertainty; a far outlier that slipped through the hypotheses' wide gates drops out
        e = _theta_gate(ta, beta_a, tb, beta_b, 0.5 * theta)
        slope = (_theta_gate(ta, beta_a, tb, beta_b, 0.5 * (theta + h)) - e) / h
        new = theta_gate_pass(e, slope, theta, covariance[0, 0])
        # eq. 21 whitened: a point's noise is long along its ray and short across it, so the residual
        # P' - (R P + T) is tested where its noise is uniform, projected into (u, v, d)
        R, T = motion_matrices(theta, rho)
        moved = P @ R.T + T
        with np.errstate(divide="ignore", invalid="ignore"):
            iz = 1.0 / moved[:, 2]
            r2 = (
                (fx * moved[:, 0] * iz - du2) ** 2
                + (fy * moved[:, 1] * iz - dv2) ** 2
                + (fx * B * iz - bu[:, 2]) ** 2
            )
        new &= (moved[:, 2] > 0) & (r2 <= WHITENED_GATE**2 * 2.0 * pixel_sigma**2)
        changed = not np.array_equal(new, keep)
        keep = new
        if not changed:
            break
    inliers[iu[keep]] = True
    diagnostics.update(
        hypotheses_theta=tried_theta,
        hypotheses_rho=tried_rho,
        theta_inliers=int(theta_in.sum()),
        inliers=int(keep.sum()),
        inlier_ratio=float(keep.sum() / n),
        refined=bool(refine),
        refine_rounds=rounds,
        time_ms=(time.perf_counter() - t_start) * 1e3,
    )
    if keep.sum() < 3:
        return failure("fewer than 3 inliers after refinement")
    return RansacResult(float(theta), float(rho), inliers, covariance, True, diagnostics)


def histogram_voting(
    w_prev,
    w_curr,
    camera: StereoCamera,
    bin_width: float = math.radians(0.05),
    pixel_sigma: float = PIXEL_SIGMA,
    gate_sigmas: float = GATE_SIGMAS,
):
    """theta as the mode of the per-match thetas (a histogram vote), then rho as the median of
    the per-match rhos of the matches in the winning bin. Returns ``(theta, rho, votes_mask)``."""
    a, b = as_match_array("w_prev", w_prev), as_match_array("w_curr", w_curr)
    with np.errstate(divide="ignore", invalid="ignore"):
        theta_j = theta_from_pixels(a, b, camera)
    ok = np.isfinite(theta_j) & (a[:, 2] > 0) & (b[:, 2] > 0)
    if ok.sum() < 3:
        raise ValueError("histogram voting needs at least 3 matches with a defined theta")
    t = theta_j[ok]
    edges = np.arange(t.min(), t.max() + 2 * bin_width, bin_width)
    counts, edges = np.histogram(t, edges)
    k = int(np.argmax(counts))
    in_bin = (t >= edges[k]) & (t < edges[k + 1])
    theta = float(np.median(t[in_bin]))
    votes = np.zeros(len(a), bool)
    votes[np.flatnonzero(ok)[in_bin]] = True
    rho = float(np.median(rho_from_pixels(a[votes], b[votes], theta, camera)))
    return theta, rho, votes
