"""Least-squares refinement of a planar motion ``(theta, rho)`` on its inliers, the last step of
1-point RANSAC (:mod:`vo_lib.stereo_vo.ransac`, step 5).

The motion moves each back-projected point of the previous frame by eq. 15 (``R P + T``) and each
point of the current frame back (``R^T (Q - T)``); both are projected to ``(u, v, d)`` and compared
with the matched pixels. Pixel noise is the same in every direction there, while a back-projected
point is uncertain mostly along its ray, so the residuals are minimised (Gauss-Newton with the
analytic Jacobian) and gated (eq. 21 whitened) in disparity space rather than in metres.

The two problems sit side by side in arrays with a leading axis of 2 (0: forward, 1: backward):
``points`` of shape (2, 4, N), homogeneous ``(x, y, z, 1)`` as rows, and ``targets`` of shape
(2, 3, N), the pixels each problem's points must project to, as rows ``u - u0, v - v0, d``.
"""

from __future__ import annotations

import math

import numpy as np

from vo_lib.camera import StereoCamera

#: Gauss-Newton iterations of a first refinement (RANSAC's default, ``RansacParams.refine_iterations``).
ITERATIONS = 2


def motion_rows(theta: float, rho: float, camera: StereoCamera) -> np.ndarray:
    """What eq. 15 and its derivatives make of a homogeneous point, as one matrix per direction
    (shape (2, 6, 4)): applied to ``(x, y, z, 1)``, its rows give ``fx x'``, ``fy y'``, ``fx B``,
    ``z'``, ``fx dx'/dtheta`` and ``-dz'/dtheta`` of the moved point ``(x', y', z')``, forward
    ``R X + T`` and backward ``R^T (X - T)``, with ``T = -rho (sin(theta/2), 0, cos(theta/2))``.
    """
    c, s, sp, cp = math.cos(theta), math.sin(theta), math.sin(0.5 * theta), math.cos(0.5 * theta)
    fx, fy, fb = camera.fx, camera.fy, camera.fx * camera.baseline
    rows = []
    for g in (1.0, -1.0):  # forward, backward: R^T is R with theta -> -theta, and T changes sign
        rows.append(
            [
                [fx * c, 0.0, g * fx * s, -fx * rho * sp],
                [0.0, fy, 0.0, 0.0],
                [0.0, 0.0, 0.0, fb],
                [-g * s, 0.0, c, -g * rho * cp],
                [-fx * s, 0.0, g * fx * c, -0.5 * fx * rho * cp],
                [g * c, 0.0, s, -0.5 * g * rho * sp],
            ]
        )
    return np.array(rows)


def pixel_targets(wa: np.ndarray, wb: np.ndarray, camera: StereoCamera) -> np.ndarray:
    """The pixels the forward problem's points must project to (``wb``) and the backward one's
    (``wa``), relative to the principal point: rows ``u - u0, v - v0, d``, shape (2, 3, N)."""
    return np.array([wb.T, wa.T]) - np.array([[camera.cx], [camera.cy], [0.0]])


def both_directions(P, Q, wa, wb, camera: StereoCamera) -> tuple[np.ndarray, np.ndarray]:
    """The forward ``P -> wb`` and backward ``Q -> wa`` problems side by side (inputs of shape
    (N, 3)): ``points`` (2, 4, N) and ``targets`` (2, 3, N), as the module's docstring describes."""
    points = np.ones((2, 4, len(P)))
    points[0, :3], points[1, :3] = np.asarray(P).T, np.asarray(Q).T
    return points, pixel_targets(wa, wb, camera)


def reprojection(theta: float, rho: float, points: np.ndarray, targets: np.ndarray, camera: StereoCamera):
    """Residuals ``pi(R P + T) - w'`` and ``pi(R^T (Q - T)) - w`` in disparity space of the problems
    side by side (:func:`both_directions`), ``r`` of shape (2, 3, N), and their Jacobians in
    ``(theta, rho)``, ``(J_theta, J_rho)`` of the same shape, by the chain rule through ``pi``."""
    m = motion_rows(theta, rho, camera) @ points  # (2, 6, N): fx x', fy y', fx B, z', fx dx'/dt, -dz'/dt
    iz = 1.0 / m[:, 3]
    p = m[:, :3] * iz[:, None]  # pi(X') = (fx x', fy y', fx B) / z'
    # d pi / d theta = (d(fx x', fy y', fx B)/d theta - pi dz'/d theta) / z'; only fx x' turns with theta
    J_theta = p * (m[:, 5] * iz)[:, None]
    J_theta[:, 0] += m[:, 4] * iz
    # d z'/d rho = -cos(theta/2) forward, +cos(theta/2) backward; d x'/d rho = -sin(theta/2) both ways
    J_rho = p * (np.array([[1.0], [-1.0]]) * math.cos(0.5 * theta) * iz)[:, None]
    J_rho[:, 0] -= camera.fx * math.sin(0.5 * theta) * iz
    return p - targets, J_theta, J_rho


def gauss_newton(points, targets, theta: float, rho: float, camera: StereoCamera, iterations: int):
    """Gauss-Newton on ``(theta, rho)`` over :func:`reprojection` (the arguments as
    :func:`both_directions` gives them): ``(theta, rho, A, rss)`` with the normal matrix
    ``A = J^T J`` and the residual sum of squares of the last iterate before its step."""
    A, rss = np.zeros((2, 2)), 0.0
    for _ in range(max(iterations, 1)):
        r, jt, jr = reprojection(theta, rho, points, targets, camera)
        a00, a01, a11 = float(np.vdot(jt, jt)), float(np.vdot(jt, jr)), float(np.vdot(jr, jr))
        b0, b1, rss = float(np.vdot(jt, r)), float(np.vdot(jr, r)), float(np.vdot(r, r))
        A = np.array([[a00, a01], [a01, a11]])
        det = a00 * a11 - a01 * a01
        if not det > 0:
            break
        d_theta, d_rho = -(a11 * b0 - a01 * b1) / det, -(a00 * b1 - a01 * b0) / det
        theta, rho = theta + d_theta, rho + d_rho
        if abs(d_theta) < 1e-10 and abs(d_rho) < 1e-9:
            break
    return theta, rho, A, rss


def covariance(A: np.ndarray, rss: float, count: int) -> np.ndarray:
    """``2 sigma^2 A^-1``: forward and backward residuals carry the same noise, so their
    information counts once; infinite variances when ``A`` is singular."""
    det = A[0, 0] * A[1, 1] - A[0, 1] * A[0, 1]
    if not det > 0:
        return np.array([[np.inf, 0.0], [0.0, np.inf]])
    inverse = np.array([[A[1, 1], -A[0, 1]], [-A[0, 1], A[0, 0]]]) / det
    return 2.0 * (rss / max(count - 2, 1)) * inverse


def whitened_pass(
    points, targets, theta: float, rho: float, camera: StereoCamera, gate: float, pixel_sigma: float
) -> np.ndarray:
    """eq. 21 whitened on the forward problem (:func:`both_directions`): the moved point in front
    of the camera and its (u, v, d) residual within ``gate`` standard deviations (``pixel_sigma``
    sqrt 2 per coordinate)."""
    m = motion_rows(theta, rho, camera)[0, :4] @ points[0]  # fx x', fy y', fx B, z'
    r = m[:3] / m[3] - targets[0]  # a point at z' = 0 gives inf or NaN, and fails
    return (m[3] > 0) & ((r * r).sum(axis=0) <= gate**2 * 2.0 * pixel_sigma**2)


def refine_motion(
    w_prev, w_curr, theta: float, rho: float, camera: StereoCamera, iterations: int = ITERATIONS
) -> tuple[float, float, np.ndarray]:
    """Least-squares ``(theta, rho)`` on matches, minimising reprojection errors in disparity space
    in both directions (Gauss-Newton, analytic Jacobian, :func:`reprojection`).
    Returns ``(theta, rho, covariance)``."""
    wa, wb = np.asarray(w_prev, float), np.asarray(w_curr, float)
    points, targets = both_directions(camera.backproject(wa), camera.backproject(wb), wa, wb, camera)
    theta, rho, A, rss = gauss_newton(points, targets, float(theta), float(rho), camera, int(iterations))
    return float(theta), float(rho), covariance(A, rss, 6 * len(wa))
