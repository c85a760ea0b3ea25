"""The general motion of a stereo camera: six degrees of freedom, refined on reprojection errors.

A car breaks the assumptions of the circular-motion model (eq. 12-17): the camera sits ahead of
the rear axle, the road climbs and banks, the body pitches as the car brakes. The inliers of
1-point RANSAC, the outlier filter (:mod:`.six_dof`), are refined here with all six degrees of
freedom.

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
from scipy.spatial.transform import Rotation

from vo_lib.camera import StereoCamera
from vo_lib.geometry import rigid_matrix

#: Huber threshold of the refinement, pixels (of the 3-vector residual's norm).
HUBER_PIXELS = 1.0
#: A match is an inlier of the refined motion when its reprojection error is below this (pixels).
INLIER_PIXELS = 1.0
ITERATIONS = 4
ROUNDS = 2  # refine, choose the inliers again, refine again while they change
NEAR = 0.1  # metres: points closer than this to the camera after the motion are not used
CONVERGED = 1e-8  # radians and metres: an update smaller than this ends the iterations
MIN_INLIERS = 6  # a refinement or a 3-point RANSAC that keeps fewer has failed
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
        return rigid_matrix(self.R, self.t)


def reprojection_errors(P: np.ndarray, w_curr: np.ndarray, R, t, camera: StereoCamera) -> np.ndarray:
    """Norm of the disparity-space residual of every match (inf behind the camera)."""
    Q = P @ np.asarray(R).T + np.asarray(t)
    err = np.full(len(P), np.inf)
    ok = Q[:, 2] > NEAR
    err[ok] = np.linalg.norm(camera.project(Q[ok]) - w_curr[ok], axis=1)
    return err


def normal_equations(P, w, R, t, camera: StereoCamera, huber: float) -> tuple[np.ndarray, np.ndarray, float]:
    """``(J^T W J, J^T W r, sum of weighted squares)`` of the Huber-weighted residuals
    ``pi(R P + t) - w`` in ``(u, v, d)``, for a left-multiplied update ``(dw, dt)`` of the pose.

    ``pi(X, Y, Z) = (fx X / Z + cx, fy Y / Z + cy, fb / Z)``; a residual of length ``e`` weighs
    1 within ``huber`` and ``huber / e`` beyond. The Jacobian rows are ``dpi/dQ [-[Q]x | I]``.
    """
    fx, fy, fb = camera.fx, camera.fy, camera.fx * camera.baseline
    Q = np.asarray(P, float) @ np.asarray(R, float).T + np.asarray(t, float)
    iz = 1.0 / Q[:, 2]
    x, y = Q[:, 0] * iz, Q[:, 1] * iz  # normalised image coordinates
    r = np.empty((len(Q), 3))
    r[:, 0] = fx * x + camera.cx - w[:, 0]
    r[:, 1] = fy * y + camera.cy - w[:, 1]
    r[:, 2] = fb * iz - w[:, 2]
    e = np.sqrt(np.einsum("ij,ij->i", r, r))
    weight = np.where(e <= huber, 1.0, huber / np.maximum(e, 1e-12))
    J = np.zeros((len(Q), 3, 6))  # d(u, v, d) / d(dw_x, dw_y, dw_z, dt_x, dt_y, dt_z)
    J[:, 0, 0], J[:, 0, 1], J[:, 0, 2] = -fx * x * y, fx * (1 + x * x), -fx * y
    J[:, 0, 3], J[:, 0, 5] = fx * iz, -fx * x * iz
    J[:, 1, 0], J[:, 1, 1], J[:, 1, 2] = -fy * (1 + y * y), fy * x * y, fy * x
    J[:, 1, 4], J[:, 1, 5] = fy * iz, -fy * y * iz
    J[:, 2, 0], J[:, 2, 1], J[:, 2, 5] = -fb * y * iz, fb * x * iz, -fb * iz * iz
    # the sums over matches as one matrix product of the stacked rows (3 per match)
    WJ = (J * weight[:, None, None]).reshape(-1, 6)
    return WJ.T @ J.reshape(-1, 6), WJ.T @ r.ravel(), float(np.sum(weight * e * e))


def _gauss_newton(P, w, R, t, camera, iterations, huber):
    A = np.eye(6)
    for _ in range(iterations):
        A, g, _ = normal_equations(P, w, R, t, camera, huber)
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
    huber: float = HUBER_PIXELS,
    rounds: int = ROUNDS,
    gate: float = INLIER_PIXELS,
) -> RigidMotion:
    """Refine a motion on matches ``w_prev -> w_curr`` (disparity space) from the guess ``T0``
    (``T_curr_from_prev``: the 1-point RANSAC motion, or the prediction), starting from the
    ``inliers`` (default: all with positive disparity); ``huber`` is the refinement's Huber
    threshold, ``gate`` the largest reprojection error of an inlier (pixels). ``success`` is False
    (and the guess returned) when fewer than ``MIN_INLIERS`` remain.
    """
    wa, wb = np.asarray(w_prev, float), np.asarray(w_curr, float)
    T0 = np.asarray(T0, float)
    R, t = T0[:3, :3].copy(), T0[:3, 3].copy()
    usable = (wa[:, 2] > 0) & (wb[:, 2] > 0)
    P = np.zeros_like(wa)
    P[usable] = camera.backproject(wa[usable])
    inl = usable.copy() if inliers is None else (np.asarray(inliers, bool) & usable)
    for _ in range(max(rounds, 1)):
        if np.count_nonzero(inl) < MIN_INLIERS:
            break
        R, t = _gauss_newton(P[inl], wb[inl], R, t, camera, ITERATIONS, huber)
        err = reprojection_errors(P, wb, R, t, camera)  # of the motion the inliers below end with
        new = usable & (err < gate)
        if np.array_equal(new, inl):
            break
        inl = new
    count = np.count_nonzero(inl)
    if count < MIN_INLIERS:
        return RigidMotion(T0[:3, :3], T0[:3, 3], np.full((6, 6), np.inf), inl, np.inf, False)
    A, _, _ = normal_equations(P[inl], wb[inl], R, t, camera, np.inf)
    res = err[inl]
    dof = max(3 * int(count) - 6, 1)
    sigma2 = float(np.sum(res**2)) / dof
    try:
        cov = sigma2 * np.linalg.inv(A)
    except np.linalg.LinAlgError:
        cov = np.full((6, 6), np.inf)
    return RigidMotion(R, t, cov, inl, float(np.sqrt(np.mean(res**2))), True)


def _left_jacobian(rotvec: np.ndarray) -> np.ndarray:
    """``V(w)`` of SE(3): ``t = V(w) v`` for the twist ``(w, v)``, in closed form,
    ``V = I + (1 - cos a) / a^2 [w]x + (a - sin a) / a^3 [w]x^2`` with ``a = |w|`` (series below 1e-4)."""
    a = float(np.linalg.norm(rotvec))
    W = np.array([[0.0, -rotvec[2], rotvec[1]], [rotvec[2], 0.0, -rotvec[0]], [-rotvec[1], rotvec[0], 0.0]])
    if a < 1e-4:
        b, c = 0.5 - a * a / 24.0, 1.0 / 6.0 - a * a / 120.0
    else:
        b, c = (1.0 - np.cos(a)) / (a * a), (a - np.sin(a)) / (a * a * a)
    return np.eye(3) + b * W + c * (W @ W)


def se3_log(T) -> tuple[np.ndarray, np.ndarray]:
    """The twist ``(w, v)`` of a rigid motion ``T``: ``w`` its rotation vector, ``v = V(w)^-1 t``."""
    T = np.asarray(T, float)
    w = Rotation.from_matrix(T[:3, :3]).as_rotvec()
    return w, np.linalg.solve(_left_jacobian(w), T[:3, 3])


def se3_exp(w, v) -> np.ndarray:
    """The 4x4 rigid motion of the twist ``(w, v)``: ``R = exp([w]x)``, ``t = V(w) v``."""
    w = np.asarray(w, float)
    return rigid_matrix(rotation_matrix(w), _left_jacobian(w) @ np.asarray(v, float))  # R: exp of so(3)


def scaled_motion(T, factor: float) -> np.ndarray:
    """The motion ``T`` repeated ``factor`` times: ``exp(factor log T)`` in SE(3), the same screw
    motion run for ``factor`` times as long (``factor = 2`` gives ``T @ T``). Closed-form log and
    exp (:func:`se3_log`, :func:`se3_exp`)."""
    T = np.asarray(T, float)
    if factor == 1.0:
        return T.copy()
    w, v = se3_log(T)
    return se3_exp(factor * w, factor * v)


def general_ransac(
    w_prev: np.ndarray, w_curr: np.ndarray, camera: StereoCamera, seed: int
) -> tuple[np.ndarray, np.ndarray] | None:
    """A 6-DoF motion ``T_curr_from_prev`` and its inlier mask from 3-point RANSAC, or ``None``.

    The previous frame's triangulated points and the current left-image pixels go to OpenCV's
    ``solvePnPRansac`` (AP3P hypotheses, seeded with ``cv2.setRNGSeed``): the hypothesis generator
    for frames where the vehicle pitches or rolls (a bump, a kerb, the start of a slope), which
    the 1-point model of eq. 14-17 cannot describe.
    """
    if len(w_prev) < MIN_INLIERS:
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
    if not ok or idx is None or len(idx) < MIN_INLIERS:
        return None
    inliers = np.zeros(len(w_prev), bool)
    inliers[idx.ravel()] = True
    return rigid_matrix(cv2.Rodrigues(rvec)[0], tvec.ravel()), inliers
