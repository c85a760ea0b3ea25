"""The general motion of a stereo camera: six degrees of freedom, refined on reprojection errors.

The circular-motion model (eq. 12-17) holds for a camera above the turning axis of a robot on a
flat floor. A car breaks all three assumptions: the camera sits ahead of the rear axle, the road
climbs and banks, and the body pitches as the car brakes. The pipeline therefore keeps 1-point
RANSAC (theta from eq. 14 alone, then rho) as the *outlier filter*, which is why it is fast, and
refines the motion of its inliers here with all six degrees of freedom.

A motion ``T = (R, t)`` maps a point of the previous camera frame into the current one,
``Q = R P + t``. Its residual for one match is the reprojection error in disparity space,

    r = pi(R P + t) - w',    pi(X, Y, Z) = (fx X / Z + cx,  fy Y / Z + cy,  fx b / Z),

that is the error in the left image (u, v) and, through the disparity, in the right one. The
refinement is Gauss-Newton with a rotation update on the left, ``R <- exp([dw]x) R``,
``t <- exp([dw]x) t + dt``, and the analytic Jacobian ``dr/d(dw, dt) = dpi/dQ [-[Q]x | I]``.
Large residuals are down-weighted (Huber), and the inliers are chosen again with the refined
motion, so matches that the approximate planar model rejected or admitted are judged by the
general one.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from scipy.linalg import expm, logm

from vo_lib.camera import StereoCamera
from vo_lib.compiled import choose

#: Huber threshold of the refinement, pixels (of the 3-vector residual's norm).
HUBER_PIXELS = 1.0
#: A match is an inlier of the refined motion when its reprojection error is below this (pixels).
INLIER_PIXELS = 1.0
ITERATIONS = 4
ROUNDS = 2  # refine, choose the inliers again, refine again while they change
NEAR = 0.1  # metres: points closer than this to the camera after the motion are not used
CONVERGED = 1e-8  # radians and metres: an update smaller than this ends the iterations
#: The general (3-point) RANSAC that stands in when the planar model does not hold between two
#: frames: hypotheses drawn, and the reprojection error (left image) of an inlier, pixels.
GENERAL_ITERATIONS = 200
GENERAL_PIXELS = 2.0


def rotation_matrix(rotvec) -> np.ndarray:
    """``exp([w]x)`` of a rotation vector (Rodrigues' formula, OpenCV's: far cheaper per call
    than SciPy's for the single small rotations of an iteration)."""
    return cv2.Rodrigues(np.asarray(rotvec, dtype=np.float64).reshape(3, 1))[0]


@dataclass
class RigidMotion:
    """A refined 6-DoF motion ``Q = R P + t`` with its 6x6 covariance (rotation vector, t)."""

    R: np.ndarray
    t: np.ndarray
    covariance: np.ndarray
    inliers: np.ndarray
    rms_pixels: float
    success: bool = True

    @property
    def matrix(self) -> np.ndarray:
        """4x4 ``T_curr_from_prev``."""
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = self.R, self.t
        return T


def reprojection_errors(P: np.ndarray, w_curr: np.ndarray, R, t, camera: StereoCamera) -> np.ndarray:
    """Norm of the disparity-space residual of every match (inf behind the camera)."""
    Q = P @ np.asarray(R).T + np.asarray(t)
    err = np.full(len(P), np.inf)
    ok = Q[:, 2] > NEAR
    err[ok] = np.linalg.norm(camera.project(Q[ok]) - w_curr[ok], axis=1)
    return err


def _normal_equations(P, w, R, t, camera, huber):
    """``(J^T W J, J^T W r, sum of weighted squares)`` of the Huber-weighted residuals, compiled
    (:mod:`.rigid_core`); ``rigid_plain.normal_equations`` is the same written out in NumPy."""
    from vo_lib.stereo_vo.rigid_core import normal_equations

    A, g, cost = choose(normal_equations)(
        np.ascontiguousarray(P, dtype=float),
        np.ascontiguousarray(w, dtype=float),
        np.ascontiguousarray(R, dtype=float),
        np.ascontiguousarray(t, dtype=float),
        camera.fx,
        camera.fy,
        camera.cx,
        camera.cy,
        camera.fx * camera.baseline,
        float(huber),
    )
    return A, g, float(cost)


def _gauss_newton(P, w, R, t, camera, iterations, huber):
    A = np.eye(6)
    for _ in range(iterations):
        A, g, _ = _normal_equations(P, w, R, t, camera, huber)
        try:
            dx = -np.linalg.solve(A, g)
        except np.linalg.LinAlgError:
            break
        dR = rotation_matrix(dx[:3])
        R, t = dR @ R, dR @ t + dx[3:]
        if np.abs(dx).max() < CONVERGED:
            break
    return R, t


def refine_rigid_motion(
    w_prev,
    w_curr,
    camera: StereoCamera,
    T0,
    inliers=None,
    *,
    inlier_pixels: float = INLIER_PIXELS,
    huber: float = HUBER_PIXELS,
    iterations: int = ITERATIONS,
    rounds: int = ROUNDS,
    min_inliers: int = 6,
) -> RigidMotion:
    """Refine a motion on matches ``w_prev -> w_curr`` (disparity space) from the guess ``T0``.

    Parameters
    ----------
    w_prev, w_curr : array_like, shape (N, 3)
        Matches ``(u, v, d)``; ``w_prev`` is back-projected with its disparity.
    camera : StereoCamera
    T0 : array_like, 4x4
        Initial ``T_curr_from_prev`` (e.g. the 1-point RANSAC motion, or the prediction).
    inliers : array_like of bool, optional
        The matches to start from (default: all with positive disparity).
    inlier_pixels, huber : float
        Reprojection error that makes an inlier; Huber threshold of the refinement.

    Returns
    -------
    RigidMotion
        ``success`` is False (and the guess returned) when fewer than ``min_inliers`` remain.
    """
    wa, wb = np.asarray(w_prev, float), np.asarray(w_curr, float)
    T0 = np.asarray(T0, float)
    R, t = T0[:3, :3].copy(), T0[:3, 3].copy()
    usable = (wa[:, 2] > 0) & (wb[:, 2] > 0)
    P = np.zeros_like(wa)
    P[usable] = camera.backproject(wa[usable])
    inl = usable.copy() if inliers is None else (np.asarray(inliers, bool) & usable)
    for _ in range(max(rounds, 1)):
        if np.count_nonzero(inl) < min_inliers:
            return RigidMotion(T0[:3, :3], T0[:3, 3], np.full((6, 6), np.inf), inl, np.inf, False)
        R, t = _gauss_newton(P[inl], wb[inl], R, t, camera, iterations, huber)
        err = reprojection_errors(P, wb, R, t, camera)  # of the motion the inliers below end with
        new = usable & (err < inlier_pixels)
        if np.array_equal(new, inl):
            break
        inl = new
    count = np.count_nonzero(inl)
    if count < min_inliers:
        return RigidMotion(T0[:3, :3], T0[:3, 3], np.full((6, 6), np.inf), inl, np.inf, False)
    A, _, _ = _normal_equations(P[inl], wb[inl], R, t, camera, np.inf)
    res = err[inl]
    dof = max(3 * int(count) - 6, 1)
    sigma2 = float(np.sum(res**2)) / dof
    try:
        cov = sigma2 * np.linalg.inv(A)
    except np.linalg.LinAlgError:
        cov = np.full((6, 6), np.inf)
    return RigidMotion(R, t, cov, inl, float(np.sqrt(np.mean(res**2))), True)


def scaled_motion(T, factor: float) -> np.ndarray:
    """The motion ``T`` repeated ``factor`` times: ``exp(factor log T)`` in SE(3), the same screw
    motion run for ``factor`` times as long (``factor = 2`` gives ``T @ T``)."""
    T = np.asarray(T, float)
    if factor == 1.0:
        return T.copy()
    return np.real(expm(factor * np.real(logm(T))))


def general_ransac(
    w_prev: np.ndarray, w_curr: np.ndarray, camera: StereoCamera, seed: int
) -> tuple[np.ndarray, np.ndarray] | None:
    """A 6-DoF motion ``T_curr_from_prev`` and its inlier mask from 3-point RANSAC, or ``None``.

    The previous frame's triangulated points and the current left-image pixels go to OpenCV's
    ``solvePnPRansac`` (AP3P hypotheses, seeded with ``cv2.setRNGSeed``): the hypothesis generator
    for frames where the vehicle pitches or rolls (a bump, a kerb, the start of a slope), which
    the 1-point model of eq. 14-17 cannot describe.
    """
    if len(w_prev) < 6:
        return None
    cv2.setRNGSeed(int(seed))
    ok, rvec, tvec, idx = cv2.solvePnPRansac(
        camera.backproject(w_prev),
        np.ascontiguousarray(w_curr[:, :2], dtype=np.float64),
        camera.K,
        None,
        iterationsCount=GENERAL_ITERATIONS,
        reprojectionError=GENERAL_PIXELS,
        confidence=0.999,
        flags=cv2.SOLVEPNP_AP3P,
    )
    if not ok or idx is None or len(idx) < 6:
        return None
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = cv2.Rodrigues(rvec)[0], tvec.ravel()
    inliers = np.zeros(len(w_prev), bool)
    inliers[idx.ravel()] = True
    return T, inliers
