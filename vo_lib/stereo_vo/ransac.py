"""1-point RANSAC for the planar circular-motion model ([Zhao], III.A.3, eq. 18-21).

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

Both phases share one support test, which is what makes one loop serve them: under hypothesis
``h`` the residual of match ``j`` is linear in ``h``, ``r_j(h) = offset_j + h direction``. Phase 1
(eq. 20 to first order): ``offset_j = (theta_j, 0, 0)``, ``direction = (-1, 0, 0)``. Phase 2
(eq. 21): ``offset_j = Q_j - R P_j`` and ``direction = (sin phi, 0, cos phi)``, since
``T = -rho (sin phi, 0, cos phi)``. Match ``j`` supports ``h`` (of variance ``var_h``) when
``|r_j(h)|^2 <= k^2 (var_j + var_h)``; NumPy tests every hypothesis of a batch against every
match at once, an ``(H, N)`` array.

Hypotheses are drawn from the best-conditioned half of the matches, scored all at once, and
drawn until ``log(1 - p) / log(1 - w)`` of them have been tried for the best inlier ratio ``w``
found. The refinement and its final gate (eq. 21 *whitened*) work in disparity space: a
back-projected point is uncertain mostly along its ray (metres, far away) and little across it
(millimetres), so the residual is compared in (u, v, d), where its noise is the same in every
direction.
"""

from __future__ import annotations

import enum
import functools
import math
import numbers
import time
from dataclasses import dataclass, field
from typing import NamedTuple, Protocol

import numpy as np

from vo_lib.camera import StereoCamera
from vo_lib.stereo_vo.circular_motion import (
    DEGENERATE_ROW_PIXELS,
    match_pair,
    motion_matrices,
    rho_from_pixels,
    theta_and_variance,
    theta_from_pixels,
)
from vo_lib.stereo_vo.refinement import ITERATIONS, covariance, gauss_newton, pixel_targets, whitened_pass


class RansacInputError(ValueError):
    """Matches, draws or settings that :func:`one_point_ransac` cannot use."""


class RansacParams(NamedTuple):
    """The settings of 1-point RANSAC, as one immutable structure."""

    pixel_sigma: float = 0.5  #: pixel noise of u, v and d assumed by the gates
    gate_sigmas: float = 3.0  #: a match is an inlier within this many standard deviations of each gate
    confidence: float = 0.999  #: probability of drawing at least one all-inlier hypothesis
    max_hypotheses: int = 200  #: hypotheses per phase at most
    refine: bool = True  #: refine on all inliers by least squares
    min_pool: int = 8  #: hypotheses come from at least this many matches ...
    pool_fraction: float = 0.5  #: ... the best-conditioned fraction of the matches
    refine_iterations: int = ITERATIONS  #: Gauss-Newton iterations of the first refinement round
    refine_rounds: int = 3  #: refine, re-select inliers, and refine again while the set changes
    whitened_gate: float = 3.76  #: final gate on the whitened eq. 21 residual: sqrt chi-square(3) at 99.73 %
    initial_inlier_ratio: float = 0.5  #: first guess of the inlier ratio, before any hypothesis is scored


#: The default settings; every field is documented in :class:`RansacParams`.
DEFAULT_PARAMS = RansacParams()


class Outcome(enum.Enum):
    """How :func:`one_point_ransac` ended; the value is the sentence the diagnostics carry."""

    OK = "ok"
    FEW_USABLE = "fewer than 3 matches with positive disparities off the camera's height"
    FEW_THETA_INLIERS = "fewer than 3 theta inliers"
    FEW_INLIERS = "fewer than 3 inliers after refinement"


@dataclass
class RansacResult:
    """Outcome of :func:`one_point_ransac`."""

    theta: float
    rho: float
    inliers: np.ndarray
    covariance: np.ndarray
    success: bool
    diagnostics: dict = field(default_factory=dict)
    outcome: Outcome = Outcome.OK


def hypotheses_needed(inlier_ratio, confidence=0.999, sample_size=1) -> int:
    """Hypotheses so that at least one is all-inlier with probability ``confidence``:
    ``ceil(log(1 - p) / log(1 - w**s))`` ([Zhao], III.A.3)."""
    w = min(max(float(inlier_ratio), 1e-9), 1.0)
    good = w**sample_size
    if good >= 1.0:
        return 1
    return max(1, math.ceil(math.log(1.0 - confidence) / math.log(1.0 - good)))


def hypothesis_draws(rng=None, max_hypotheses: int = DEFAULT_PARAMS.max_hypotheses) -> np.ndarray:
    """The random numbers :func:`one_point_ransac` draws: one uniform number in [0, 1) per hypothesis.

    Row 0 serves the theta search, row 1 the rho search; hypothesis ``k`` of a phase is match
    ``pool[min(int(u_k * len(pool)), len(pool) - 1)]`` of that phase's pool (its best-conditioned
    matches, ordered by variance). ``one_point_ransac(..., rng=r)`` and
    ``one_point_ransac(..., draws=hypothesis_draws(r))`` make the same draws, so another
    implementation given these numbers can be compared with it hypothesis by hypothesis. Shape
    ``(2, max_hypotheses)``.
    """
    if isinstance(rng, numbers.Integral):  # a seed: the same numbers every time, drawn once
        return _seeded_draws(int(rng), int(max_hypotheses)).copy()
    return np.random.default_rng(rng).random(2 * int(max_hypotheses)).reshape(2, -1)


@functools.lru_cache(maxsize=64)
def _seeded_draws(seed: int, max_hypotheses: int) -> np.ndarray:
    return np.random.default_rng(seed).random(2 * max_hypotheses).reshape(2, -1)


# ---------------------------------------------------------------------- eq. 18-20
def gate_angles(w: np.ndarray, camera: StereoCamera) -> tuple[np.ndarray, np.ndarray]:
    """``(tan(alpha), beta)`` of Fig. 5 for matches ``w``: depression and bearing of each ray."""
    beta = np.arctan((w[:, 0] - camera.cx) / camera.fx)
    tan_alpha = (w[:, 1] - camera.cy) * np.cos(beta) / camera.fy
    return tan_alpha, beta


def match_angles(a: np.ndarray, b: np.ndarray, camera: StereoCamera) -> tuple[np.ndarray, ...]:
    """``(tan(alpha') / tan(alpha), beta, beta')`` of matches ``a -> b``: what eq. 20 reads of them."""
    (ta, ba), (tb, bb) = gate_angles(a, camera), gate_angles(b, camera)
    with np.errstate(divide="ignore", invalid="ignore"):
        return tb / ta, ba, bb


def theta_gate_and_slope(tan_ratio, beta_a, beta_b, theta) -> tuple[np.ndarray, np.ndarray]:
    """Signed eq. 20, ``tan(alpha')/tan(alpha) - sin(gamma')/sin(gamma)``, and its slope in theta:
    only ``sin(gamma') / sin(gamma)`` depends on theta, and d/d phi of ``-sin(beta' - phi) /
    sin(beta + phi)`` is ``sin(beta + beta') / sin^2(beta + phi)``. Broadcasts over ``theta``."""
    phi = 0.5 * np.asarray(theta, dtype=float)
    sin_a = np.sin(beta_a + phi)
    with np.errstate(divide="ignore", invalid="ignore"):
        return tan_ratio - np.sin(beta_b - phi) / sin_a, 0.5 * np.sin(beta_a + beta_b) / (sin_a * sin_a)


def theta_gate_error(w_prev, w_curr, theta, camera: StereoCamera) -> np.ndarray:
    """``error_theta`` of eq. 20 for every match under deflection ``theta`` (zero for a true match)."""
    a, b = match_pair(w_prev, w_curr)
    return np.abs(theta_gate_and_slope(*match_angles(a, b, camera), theta)[0])


# ---------------------------------------------------------------------- eq. 21
def rho_gate_error(P, Q, theta, rho) -> np.ndarray:
    """``error_rho = || P' - (R P + T) ||`` of eq. 21 for points ``P -> Q``; broadcasts over ``rho``."""
    R, T = motion_matrices(theta, rho)
    moved = np.asarray(P) @ R.T  # (N, 3)
    return np.linalg.norm(np.asarray(Q) - moved - T[..., None, :], axis=-1)


# ---------------------------------------------------------------------- the two one-point models
class OnePointModel(Protocol):
    """A motion parameter that one match determines, as the hypothesis search sees it."""

    def each_match(self) -> tuple[np.ndarray, np.ndarray]:
        """The parameter from every match alone, and its variance: two arrays of shape (N,)."""

    def squared_residuals(self, h: np.ndarray) -> np.ndarray:
        """``|r_j(h)|^2`` of every match ``j`` under every hypothesis ``h``: shape (H, N)."""


class ThetaModel:
    """Phase 1: theta of one match ([Zhao], eq. 14), its first-order variance, and the gate of
    eq. 18-20 to first order, ``r_j(theta) = theta_j - theta``."""

    def __init__(self, wa: np.ndarray, wb: np.ndarray, camera: StereoCamera, pixel_sigma: float):
        self.values, self.variances = theta_and_variance(wa, wb, camera, pixel_sigma)
        self.tan_ratio, self.beta_a, self.beta_b = match_angles(wa, wb, camera)
        # eq. 20's slope in theta is 0.5 sin(beta + beta') / sin^2(gamma) (theta_gate_and_slope)
        self.two_over_sin_sum = 2.0 / np.sin(self.beta_a + self.beta_b)

    def each_match(self) -> tuple[np.ndarray, np.ndarray]:
        return self.values, self.variances

    def squared_residuals(self, h: np.ndarray) -> np.ndarray:
        r = self.values[None, :] - h[:, None]
        return r * r

    def gate_pass(self, theta: float, var_ref: float, k2: float) -> np.ndarray:
        """eq. 20 at ``theta`` within ``k`` of each match's first-order sigma, and the match's own
        theta within ``k`` sigma of ``theta`` (``k2 = k^2``; ``var_ref``: the variance of ``theta``).

        eq. 20's error over its slope (:func:`theta_gate_and_slope`) is the angle it stands for,
        ``(tan_ratio sin(gamma) - sin(gamma')) sin(gamma) 2 / sin(beta + beta')``, and is held to
        the same bound as the match's own theta."""
        sin_a = np.sin(self.beta_a + 0.5 * theta)
        angle = (self.tan_ratio * sin_a - np.sin(self.beta_b - 0.5 * theta)) * sin_a * self.two_over_sin_sum
        bound = k2 * (self.variances + var_ref)
        return (angle * angle <= bound) & ((self.values - theta) ** 2 <= bound)


class RhoModel:
    """Phase 2, theta fixed: the chord of one match ([Zhao], eq. 16-17, sign corrected) and the
    gate of eq. 21, ``r_j(rho) = o_j + rho e`` with ``o_j = Q_j - R P_j`` and the unit vector
    ``e = (sin phi, 0, cos phi)``. ``P`` and ``Q`` are points as rows ``x, y, z`` (shape (3, N))."""

    def __init__(self, P: np.ndarray, Q: np.ndarray, variances: np.ndarray, theta: float):
        c, s, sp, cp = math.cos(theta), math.sin(theta), math.sin(0.5 * theta), math.cos(0.5 * theta)
        e = np.array([sp, 0.0, cp])
        self.values = np.array([-sp, 0.0, cp]) @ P - e @ Q  # eq. 17
        self.variances = variances
        offset = Q - np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]) @ P  # Q - R P (eq. 15)
        # |o + rho e|^2 = |o|^2 + 2 rho (o . e) + rho^2: a batch of hypotheses in three operations
        self.offset_squared = np.einsum("ij,ij->j", offset, offset)
        self.twice_along = 2.0 * (e @ offset)

    def each_match(self) -> tuple[np.ndarray, np.ndarray]:
        return self.values, self.variances

    def squared_residuals(self, h: np.ndarray) -> np.ndarray:
        hc = h[:, None]
        return self.offset_squared[None, :] + hc * (self.twice_along[None, :] + hc)


def search(
    model: OnePointModel, uniforms: np.ndarray, prior: tuple[float, float] | None, params: RansacParams
) -> tuple[float, float, int]:
    """The hypothesis with most supporters ([Zhao], eq. 18-19): ``(value, variance, tried)``.

    Hypotheses are the values of matches drawn from the pool (the ``pool_fraction``
    best-conditioned matches, at least ``min_pool``); draw ``u`` picks ``pool[int(u * len(pool))]``.
    Each batch is scored at once; batches follow until ``hypotheses_needed`` of them, for the best
    inlier ratio so far, have been tried. Among equal counts the more precise hypothesis wins.
    ``prior`` (the filter's prediction, ``(value, variance)``) is scored first.
    """
    values, variances = model.each_match()
    k2 = params.gate_sigmas**2
    bounds = k2 * variances

    def support(hyp: np.ndarray, hyp_var: np.ndarray) -> np.ndarray:  # supporters of each hypothesis
        return (model.squared_residuals(hyp) <= bounds + (k2 * hyp_var)[:, None]).sum(axis=1)

    pool = np.argsort(variances)[: max(params.min_pool, int(params.pool_fraction * len(values)))]
    # a hypothesis counts as no more certain than a typical one: the pool's median variance (the
    # pool is sorted, so the median is its middle value, or the mean of its middle two)
    in_order = variances[pool]
    cap = 0.5 * float(in_order[(len(pool) - 1) // 2] + in_order[len(pool) // 2])
    best_value, best_var, best_count = math.nan, math.nan, -1
    if prior is not None and math.isfinite(prior[0]):
        best_value, best_var = prior[0], min(prior[1], cap)
        best_count = int(support(np.array([best_value]), np.array([best_var]))[0])
    tried = 0
    limit = min(hypotheses_needed(params.initial_inlier_ratio, params.confidence), params.max_hypotheses)
    while tried < limit:
        picked = pool[np.minimum((uniforms[tried:limit] * len(pool)).astype(np.int64), len(pool) - 1)]
        hyp, hyp_var = values[picked], np.minimum(variances[picked], cap)
        counts = support(hyp, hyp_var)
        top = int(np.lexsort((hyp_var, -counts))[0])  # most supporters; among equals, least variance
        if counts[top] > best_count:
            best_value, best_var, best_count = float(hyp[top]), float(hyp_var[top]), int(counts[top])
        tried = limit
        ratio = best_count / max(len(values), 1) if best_count > 0 else 1e-9
        limit = min(hypotheses_needed(min(ratio, 1.0), params.confidence), params.max_hypotheses)
    return best_value, best_var, tried


def supporters(model: OnePointModel, h: float, var_h: float, params: RansacParams) -> np.ndarray:
    """Mask of the matches supporting hypothesis ``h`` of variance ``var_h``."""
    variances = model.each_match()[1]
    return model.squared_residuals(np.array([h]))[0] <= params.gate_sigmas**2 * (variances + var_h)


def reestimate(model: OnePointModel, support: np.ndarray) -> tuple[float, float]:
    """Inverse-variance weighted mean of the supporters' values, and its variance."""
    values, variances = model.each_match()
    w = 1.0 / variances[support]
    total = float(w.sum())
    if total == 0.0:  # no supporter: no estimate, and the caller finds too few inliers
        return math.nan, math.inf
    return float(w @ values[support]) / total, 1.0 / total


# ---------------------------------------------------------------------- inliers of a motion
def points_and_variances(
    a: np.ndarray, b: np.ndarray, camera: StereoCamera, pixel_sigma: float
) -> tuple[np.ndarray, np.ndarray]:
    """Points ``P = B/d (u - u0, (v - v0) fx/fy, fx)`` ([Zhao], eq. 13) of both frames, as
    homogeneous rows ``x, y, z, 1`` (shape (2, 4, N): ``P`` then ``Q``), and the first-order
    variance of each pair: ``sigma^2 (B/d)^2 (1 + (fx/fy)^2 + |ray|^2 / d^2)`` per view, the terms of
    u, v and d in turn."""
    w = np.array([a, b])  # (2, N, 3)
    du, dv, d = w[..., 0] - camera.cx, (w[..., 1] - camera.cy) * (camera.fx / camera.fy), w[..., 2]
    scale = camera.baseline / d
    points = np.ones((2, 4, len(a)))
    points[:, 0], points[:, 1], points[:, 2] = scale * du, scale * dv, scale * camera.fx
    ray2 = (du * du + dv * dv + camera.fx**2) / (d * d)
    across = 1.0 + (camera.fx / camera.fy) ** 2  # the u and v terms
    return points, pixel_sigma**2 * (scale * scale * (ray2 + across)).sum(axis=0)


# ---------------------------------------------------------------------- the estimator
@np.errstate(divide="ignore", invalid="ignore")  # 0/0 in a gate fails it, as NaN compares false
def one_point_ransac(  # noqa: PLR0915 (the algorithm's five steps read best in one function)
    w_prev,
    w_curr,
    camera: StereoCamera,
    prior=None,
    rng=None,
    *,
    params: RansacParams = DEFAULT_PARAMS,
    draws=None,
    **settings,
) -> RansacResult:
    """Estimate ``(theta, rho)`` from matches with 1-point RANSAC and the two gates of [Zhao].

    The algorithm:

    1. Keep the usable matches: both disparities > 0, off the camera's height (eq. 14 is 0/0 there).
    2. Phase 1, theta: every match gives a theta (eq. 14) with a first-order variance
       (:class:`ThetaModel`). :func:`search` draws hypotheses from the best-conditioned matches,
       counts each one's supporters (eq. 18-20 to first order, ``k`` sigma per match) and stops
       after ``log(1 - p) / log(1 - w)`` of them for the best inlier ratio ``w`` (eq. 19).
    3. Average the winner's supporters by inverse variance; the gate of eq. 20 at that theta
       picks the theta inliers.
    4. Phase 2, rho: every theta inlier gives a rho (eq. 16-17) with the variance of its points
       (eq. 13); :func:`search` again, with the gate of eq. 21 (:class:`RhoModel`), then the
       weighted average of the supporters.
    5. Refine ``(theta, rho)`` on all inliers by Gauss-Newton on the reprojection errors in
       disparity space (:func:`gauss_newton`); the refined motion picks the inliers again with
       eq. 20 and eq. 21 whitened. Repeat while the inliers change, ``refine_rounds`` at most.

    Parameters
    ----------
    w_prev, w_curr : array_like, shape (N, 3)
        Matches ``(u, v, d)`` in the previous and current frame.
    camera : StereoCamera
    prior : MotionPrior, optional
        The filter's predicted motion; it is scored as one more hypothesis in each phase.
    rng : numpy.random.Generator or int, optional
        Source of the random draws (seeded, for repeatable results).
    params : RansacParams
        The settings (gate widths, pixel noise, stopping rule, pool, refinement).
    draws : array_like, shape (2, params.max_hypotheses), optional
        The hypotheses' random numbers (:func:`hypothesis_draws`); when given, ``rng`` is not used.
    **settings
        Fields of :class:`RansacParams` to change from ``params`` (e.g. ``gate_sigmas=2.5``).

    Returns
    -------
    RansacResult
        ``theta``, ``rho``, an ``inliers`` mask, a 2x2 ``covariance``, the ``outcome`` and
        ``diagnostics``; ``success`` is False when fewer than 3 matches survive a step (the prior,
        or zeros, are returned then).

    Raises
    ------
    RansacInputError
        When the matches or the draws have the wrong shape or are not finite.
    """
    t_start = time.perf_counter()
    params = params._replace(**settings) if settings else params
    try:
        a, b = match_pair(w_prev, w_curr)
    except ValueError as exc:
        raise RansacInputError(str(exc)) from None
    draws = np.asarray(hypothesis_draws(rng, params.max_hypotheses) if draws is None else draws, float)
    if draws.shape != (2, int(params.max_hypotheses)):
        raise RansacInputError(
            f"draws must have shape (2, max_hypotheses) = (2, {params.max_hypotheses}); got {draws.shape}"
        )
    inliers = np.zeros(len(a), bool)
    diagnostics: dict = {"matches": len(a)}

    def failed(outcome: Outcome) -> RansacResult:
        diagnostics["reason"] = outcome.value
        diagnostics["time_ms"] = (time.perf_counter() - t_start) * 1e3
        if prior is None:
            return RansacResult(0.0, 0.0, inliers, np.diag([np.inf, np.inf]), False, diagnostics, outcome)
        cov = np.asarray(prior.covariance, float)
        return RansacResult(float(prior.theta), float(prior.rho), inliers, cov, False, diagnostics, outcome)

    # 1. usable matches
    off_height = np.abs((a[:, 1] - camera.cy) + (b[:, 1] - camera.cy)) > DEGENERATE_ROW_PIXELS
    usable = np.flatnonzero((a[:, 2] > 0) & (b[:, 2] > 0) & off_height)
    if len(usable) < 3:
        return failed(Outcome.FEW_USABLE)
    wa, wb = a[usable], b[usable]
    # 2-3. theta
    thetas = ThetaModel(wa, wb, camera, params.pixel_sigma)
    prior_theta = None if prior is None else (float(prior.theta), float(prior.covariance[0][0]))
    h, var_h, tried_theta = search(thetas, draws[0], prior_theta, params)
    theta, var_theta = reestimate(thetas, supporters(thetas, h, var_h, params))
    k2 = params.gate_sigmas**2
    theta_in = thetas.gate_pass(theta, var_theta, k2)
    n_theta = int(np.count_nonzero(theta_in))
    diagnostics.update(hypotheses_theta=tried_theta, theta_inliers=n_theta)
    if n_theta < 3:
        return failed(Outcome.FEW_THETA_INLIERS)
    # 4. rho
    points, var_points = points_and_variances(wa, wb, camera, params.pixel_sigma)
    P, Q = points[:, :3, theta_in]
    rhos = RhoModel(P, Q, var_points[theta_in], theta)
    prior_rho = None if prior is None else (float(prior.rho), float(prior.covariance[1][1]))
    h, var_h, tried_rho = search(rhos, draws[1], prior_rho, params)
    rho, var_rho = reestimate(rhos, supporters(rhos, h, var_h, params))
    keep = np.zeros(len(wa), bool)
    keep[theta_in] = supporters(rhos, rho, var_rho, params)
    cov = np.diag([var_theta, var_rho])
    # 5. refinement; the refined motion decides the inliers again
    rounds = 0
    targets = pixel_targets(wa, wb, camera)
    while params.refine and np.count_nonzero(keep) >= 3 and rounds < params.refine_rounds:
        rounds += 1
        iterations = params.refine_iterations if rounds == 1 else 1
        theta, rho, A, rss = gauss_newton(
            points[..., keep], targets[..., keep], theta, rho, camera, iterations
        )
        cov = covariance(A, rss, 6 * int(np.count_nonzero(keep)))
        new = thetas.gate_pass(theta, cov[0, 0], k2) & whitened_pass(
            points, targets, theta, rho, camera, params.whitened_gate, params.pixel_sigma
        )
        changed, keep = bool(np.any(new != keep)), new
        if not changed:
            break
    inliers[usable] = keep
    count = int(np.count_nonzero(keep))
    diagnostics.update(
        hypotheses_rho=tried_rho,
        inliers=count,
        inlier_ratio=count / len(a),
        refined=bool(params.refine),
        refine_rounds=rounds,
    )
    if count < 3:
        return failed(Outcome.FEW_INLIERS)
    diagnostics["time_ms"] = (time.perf_counter() - t_start) * 1e3
    return RansacResult(float(theta), float(rho), inliers, cov, True, diagnostics)


def histogram_voting(w_prev, w_curr, camera: StereoCamera, bin_width: float = math.radians(0.05)):
    """theta as the mode of the per-match thetas (a histogram vote), then rho as the median of
    the per-match rhos of the matches in the winning bin. Returns ``(theta, rho, votes_mask)``."""
    a, b = match_pair(w_prev, w_curr)
    with np.errstate(divide="ignore", invalid="ignore"):
        theta_j = theta_from_pixels(a, b, camera)
    ok = np.isfinite(theta_j) & (a[:, 2] > 0) & (b[:, 2] > 0)
    if ok.sum() < 3:
        raise RansacInputError("histogram voting needs at least 3 matches with a defined theta")
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
