"""Least-squares refinement of a planar motion ``(theta, rho)`` on its inliers, the last step of
1-point RANSAC (:mod:`vo_lib.stereo_vo.ransac`, step 5).

The motion moves each back-projected point of the previous frame by eq. 15 (``R P + T``) and each
point of the current frame back (``R^T (Q - T)``); both are projected to ``(u, v, d)`` and compared
with the matched pixels. Pixel noise is the same in every direction there, while a back-projected
point is uncertain mostly along its ray, so the residuals are minimised (Gauss-Newton with the
analytic Jacobian) and gated (eq. 21 whitened) in disparity space rather than in metres.
"""

from __future__ import annotations

import math

import numpy as np

from vo_lib.camera import StereoCamera

#: Gauss-Newton iterations of a first refinement (RANSAC's default, ``RansacParams.refine_iterations``).
ITERATIONS = 2


def _moved(X: np.ndarray, theta: float, rho: float, sign):
    """``R X + T`` (sign 1) or ``R^T (X - T)`` (sign -1) of eq. 15 for points ``X`` given as rows
    ``x, y, z`` (shape (3, M)), with the derivatives in ``(theta, rho)``:
    ``(x, y, z, dx/dtheta, dz/dtheta, dz/drho)``; dx/drho is ``-sin(theta/2)``."""
    c, s, sp, cp = math.cos(theta), math.sin(theta), math.sin(0.5 * theta), math.cos(0.5 * theta)
    X0, X1, X2 = X
    gx, gz = sign * X0, sign * X2
    x = c * X0 + s * gz - rho * sp
    z = c * X2 - s * gx - rho * cp * sign
    dx_t = c * gz - s * X0 - 0.5 * rho * cp
    dz_t = 0.5 * rho * sp * sign - c * gx - s * X2
    return x, X1, z, dx_t, dz_t, -cp * sign


def both_directions(P, Q, wa, wb, camera: StereoCamera) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The forward ``P -> wb`` and backward ``Q -> wa`` problems side by side (all of shape (N, 3)):
    points as rows ``x, y, z`` (shape (3, 2N)), their ``sign`` (1 forward, -1 backward) and their
    target pixels relative to the principal point as rows ``u - u0, v - v0, d``."""
    sign = np.ones(len(P) + len(Q))
    sign[len(P) :] = -1.0
    target = np.concatenate([wb, wa]) - (camera.cx, camera.cy, 0.0)
    return np.concatenate([P, Q]).T.copy(), sign, target.T.copy()


def reprojection(theta: float, rho: float, X, sign, target, camera: StereoCamera):
    """Residuals ``pi(R P + T) - w'`` and ``pi(R^T (Q - T)) - w`` in disparity space of the problems
    side by side (:func:`both_directions`), ``r`` of shape (3, 2N), and their Jacobians in
    ``(theta, rho)``, ``(J_theta, J_rho)`` of shape (3, 2N), by the chain rule through ``pi``."""
    fx, fy, fb = camera.fx, camera.fy, camera.fx * camera.baseline
    x, y, z, dx_t, dz_t, dz_r = _moved(X, theta, rho, sign)
    iz = 1.0 / z
    iz2 = iz * iz
    u, v, d = target
    r = np.array([fx * x * iz - u, fy * y * iz - v, fb * iz - d])
    fz, yz, dz = fx * iz2, -fy * y * iz2, -fb * iz2
    sp = math.sin(0.5 * theta)
    J_theta = np.array([fz * (dx_t * z - x * dz_t), yz * dz_t, dz * dz_t])
    J_rho = np.array([fz * (-sp * z - x * dz_r), yz * dz_r, dz * dz_r])
    return r, J_theta, J_rho


def gauss_newton(X, sign, target, theta: float, rho: float, camera: StereoCamera, iterations: int):
    """Gauss-Newton on ``(theta, rho)`` over :func:`reprojection` (the arguments as
    :func:`both_directions` gives them): ``(theta, rho, A, rss)`` with the normal matrix
    ``A = J^T J`` and the residual sum of squares of the last iterate before its step."""
    A, rss = np.zeros((2, 2)), 0.0
    for _ in range(max(iterations, 1)):
        r, jt, jr = reprojection(theta, rho, X, sign, target, camera)
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
    X, target, theta: float, rho: float, camera: StereoCamera, gate: float, pixel_sigma: float
) -> np.ndarray:
    """eq. 21 whitened on the forward half of the problems side by side (:func:`both_directions`):
    the moved point in front of the camera and its (u, v, d) residual within ``gate`` standard
    deviations (``pixel_sigma`` sqrt 2 per coordinate)."""
    n = X.shape[1] // 2
    x, y, z, *_ = _moved(X[:, :n], theta, rho, 1.0)
    u, v, d = target[:, :n]
    with np.errstate(divide="ignore", invalid="ignore"):
        iz = 1.0 / z
        r2 = (
            (camera.fx * x * iz - u) ** 2
            + (camera.fy * y * iz - v) ** 2
            + (camera.fx * camera.baseline * iz - d) ** 2
        )
    return (z > 0) & (r2 <= gate**2 * 2.0 * pixel_sigma**2)


def refine_motion(
    w_prev, w_curr, theta: float, rho: float, camera: StereoCamera, iterations: int = ITERATIONS
) -> tuple[float, float, np.ndarray]:
    """Least-squares ``(theta, rho)`` on matches, minimising reprojection errors in disparity space
    in both directions (Gauss-Newton, analytic Jacobian, :func:`reprojection`).
    Returns ``(theta, rho, covariance)``."""
    wa, wb = np.asarray(w_prev, float), np.asarray(w_curr, float)
    X, sign, target = both_directions(camera.backproject(wa), camera.backproject(wb), wa, wb, camera)
    theta, rho, A, rss = gauss_newton(X, sign, target, float(theta), float(rho), camera, int(iterations))
    return float(theta), float(rho), covariance(A, rss, 6 * len(wa))
