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
from vo_lib.compiled import choose
from vo_lib.geometry import as_match_array
from vo_lib.stereo_vo import ransac_core as core
from vo_lib.stereo_vo.circular_motion import motion_matrices, rho_from_pixels, theta_from_pixels
from vo_lib.stereo_vo.ransac_core import CameraTerms, RansacParams
from vo_lib.stereo_vo.ransac_core import hypotheses_needed as hypotheses_needed  # one formula for all

#: The default settings; every field is documented in :class:`RansacParams`.
DEFAULT_PARAMS = RansacParams()
GATE_SIGMAS = DEFAULT_PARAMS.gate_sigmas
WHITENED_GATE = DEFAULT_PARAMS.whitened_gate
PIXEL_SIGMA = DEFAULT_PARAMS.pixel_sigma
CONFIDENCE = DEFAULT_PARAMS.confidence
MAX_HYPOTHESES = DEFAULT_PARAMS.max_hypotheses
POOL_FRACTION = DEFAULT_PARAMS.pool_fraction
MIN_POOL = DEFAULT_PARAMS.min_pool
REFINE_ITERATIONS = DEFAULT_PARAMS.refine_iterations
REFINE_ROUNDS = DEFAULT_PARAMS.refine_rounds
INITIAL_INLIER_RATIO = DEFAULT_PARAMS.initial_inlier_ratio


@dataclass
class RansacResult:
    """Outcome of :func:`one_point_ransac`."""

    theta: float
    rho: float
    inliers: np.ndarray
    covariance: np.ndarray
    success: bool
    diagnostics: dict = field(default_factory=dict)


def hypothesis_draws(rng=None, max_hypotheses: int = MAX_HYPOTHESES) -> np.ndarray:
    """The random numbers :func:`one_point_ransac` draws: one uniform number in [0, 1) per hypothesis.

    Row 0 serves the theta search, row 1 the rho search; hypothesis ``k`` of a phase is match
    ``pool[min(int(u_k * len(pool)), len(pool) - 1)]`` of that phase's pool (its best-conditioned
    matches, ordered by variance). ``one_point_ransac(..., rng=r)`` and
    ``one_point_ransac(..., draws=hypothesis_draws(r))`` make the same draws, so another
    implementation given these numbers can be compared with it hypothesis by hypothesis.

    Parameters
    ----------
    rng : numpy.random.Generator or int, optional
        Source of the draws (seeded, for repeatable results).
    max_hypotheses : int
        Hypotheses per phase at most.

    Returns
    -------
    numpy.ndarray, shape (2, max_hypotheses)
    """
    return np.random.default_rng(rng).random(2 * int(max_hypotheses)).reshape(2, -1)


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
def camera_terms(camera: StereoCamera) -> CameraTerms:
    """The camera as the kernels take it."""
    return CameraTerms(
        float(camera.fx), float(camera.fy), float(camera.cx), float(camera.cy), float(camera.baseline)
    )


def refine_motion(
    w_prev,
    w_curr,
    theta: float,
    rho: float,
    camera: StereoCamera,
    iterations: int = REFINE_ITERATIONS,
    plain: bool | None = None,
) -> tuple[float, float, np.ndarray]:
    """Least-squares ``(theta, rho)`` on matches, minimising reprojection errors in disparity space
    in both directions (Gauss-Newton, analytic Jacobian; ``ransac_plain.reprojection`` writes the
    model out). Returns ``(theta, rho, covariance)``; ``plain`` runs the plain NumPy twin."""
    wa, wb = np.asarray(w_prev, float), np.asarray(w_curr, float)
    P, Q = camera.backproject(wa), camera.backproject(wb)
    cam = camera_terms(camera)
    theta, rho, a00, a01, a11, rss = choose(core.gauss_newton, plain)(
        P, Q, wa, wb, float(theta), float(rho), cam, int(iterations)
    )
    return float(theta), float(rho), choose(core.covariance, plain)(a00, a01, a11, rss, 6 * len(P))


# ---------------------------------------------------------------------- the estimator
def one_point_ransac(
    w_prev,
    w_curr,
    camera: StereoCamera,
    prior=None,
    rng=None,
    *,
    params: RansacParams = DEFAULT_PARAMS,
    draws=None,
    plain: bool | None = None,
    **settings,
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
    params : RansacParams
        The settings (gate widths, pixel noise, stopping rule, pool, refinement).
    draws : array_like, shape (2, params.max_hypotheses), optional
        The hypotheses' random numbers (:func:`hypothesis_draws`); when given, ``rng`` is not used.
    plain : bool, optional
        Run the plain NumPy twin (``ransac_plain``) instead of the compiled kernel; by default
        the environment variable ``VO_LIB_PLAIN`` decides (:mod:`vo_lib.compiled`).
    **settings
        Fields of :class:`RansacParams` to change from ``params`` (e.g. ``gate_sigmas=2.5``).

    Returns
    -------
    RansacResult
        ``theta``, ``rho``, an ``inliers`` mask, a 2x2 ``covariance`` and ``diagnostics``;
        ``success`` is False when fewer than 3 usable matches exist (the prior, or zeros, are
        returned then, with an empty inlier set).
    """
    t_start = time.perf_counter()
    params = params._replace(**settings) if settings else params
    a, b = as_match_array("w_prev", w_prev), as_match_array("w_curr", w_curr)
    if a.shape != b.shape:
        raise ValueError(f"w_prev and w_curr must have the same shape; got {a.shape} and {b.shape}")
    draws = np.ascontiguousarray(
        hypothesis_draws(rng, params.max_hypotheses) if draws is None else draws, float
    )
    if draws.shape != (2, int(params.max_hypotheses)):
        raise ValueError(
            f"draws must have shape (2, max_hypotheses) = (2, {params.max_hypotheses}); got {draws.shape}"
        )
    no_prior = np.array([np.nan, np.nan])
    prior_theta = np.array([prior.theta, prior.covariance[0][0]], float) if prior is not None else no_prior
    prior_rho = np.array([prior.rho, prior.covariance[1][1]], float) if prior is not None else no_prior
    status, theta, rho, covariance, inliers, tried_theta, tried_rho, theta_in, rounds = choose(
        core.one_point_core, plain
    )(
        np.ascontiguousarray(a),
        np.ascontiguousarray(b),
        camera_terms(camera),
        prior_theta,
        prior_rho,
        draws,
        params,
    )
    diagnostics = {"matches": len(a)}
    if status != core.FEW_USABLE:
        diagnostics.update(hypotheses_theta=int(tried_theta), theta_inliers=int(theta_in))
    if status in (core.OK, core.FEW_INLIERS):
        count = int(inliers.sum())
        diagnostics.update(
            hypotheses_rho=int(tried_rho),
            inliers=count,
            inlier_ratio=float(count / len(a)),
            refined=bool(params.refine),
            refine_rounds=int(rounds),
        )
    diagnostics["time_ms"] = (time.perf_counter() - t_start) * 1e3
    if status == core.OK:
        return RansacResult(float(theta), float(rho), inliers, covariance, True, diagnostics)
    diagnostics["reason"] = _FAILURES[status]
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


_FAILURES = {
    core.FEW_USABLE: "fewer than 3 matches with positive disparities off the camera's height",
    core.FEW_THETA_INLIERS: "fewer than 3 theta inliers",
    core.FEW_INLIERS: "fewer than 3 inliers after refinement",
}


def histogram_voting(w_prev, w_curr, camera: StereoCamera, bin_width: float = math.radians(0.05)):
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
