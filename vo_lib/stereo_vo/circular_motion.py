"""The planar circular-motion model of a camera on a crawler ([Zhao], eq. 12-17).

Between two frames the camera turns by the deflection angle ``theta`` about its vertical (y)
axis and moves along a chord of length ``rho`` that makes the angle ``phi = theta / 2`` with its
previous optical axis. A point ``P`` seen before the motion is seen afterwards at (eq. 15)

    P' = R(theta) P + T,    R = [[cos t, 0, sin t], [0, 1, 0], [-sin t, 0, cos t]],
                            T = -rho [sin phi, 0, cos phi].

Matches are given in disparity space, ``w = (u, v, d)`` per row (shape ``(N, 3)``).

What we derived (``notebooks/02_circular_motion_derivation.py``) and use here:

* eq. 12 and 14 hold as printed; in eq. 14 ``f`` is ``fx``. The height ``v`` of a match must
  differ from the principal row: a point at the camera's height carries no information on theta.
* eq. 16 and 17 as printed add the second term; eliminating ``theta`` from eq. 15 subtracts it:
  ``rho = [-sin phi, 0, cos phi] P - [sin phi, 0, cos phi] P'``. For straight motion the printed
  form gives ``z + z'`` instead of the distance travelled ``z - z'``.

Frames: the robot's yaw increment equals ``theta`` (:func:`yaw_increment`); a camera on the
turning axis moves by ``(rho cos phi, rho sin phi)`` in the previous robot frame.
"""

from __future__ import annotations

import numpy as np

from vo_lib.camera import StereoCamera
from vo_lib.geometry import as_match_array, rigid_matrix

#: ``|v + v' - 2 v0|`` below this many pixels: a match at the camera's height, where eq. 14 is 0/0.
DEGENERATE_ROW_PIXELS = 1e-9


def match_pair(w_prev, w_curr) -> tuple[np.ndarray, np.ndarray]:
    """Matches ``(N, 3)`` of both frames as float arrays; ``ValueError`` unless of one shape."""
    a, b = as_match_array("w_prev", w_prev), as_match_array("w_curr", w_curr)
    if a.shape != b.shape:
        raise ValueError(f"w_prev and w_curr must have the same shape; got {a.shape} and {b.shape}")
    return a, b


def _eq14_terms(a: np.ndarray, b: np.ndarray, camera: StereoCamera):
    """Numerator and denominator of eq. 14, ``tan phi = num / den``, and the centred pixels
    ``(u - u0, v - v0, u' - u0, v' - v0)`` they are made of."""
    du, dv = a[:, 0] - camera.cx, a[:, 1] - camera.cy
    du2, dv2 = b[:, 0] - camera.cx, b[:, 1] - camera.cy
    return du2 * dv - du * dv2, camera.fx * (dv + dv2), (du, dv, du2, dv2)


def degenerate_theta_mask(w_prev, w_curr, camera: StereoCamera, min_pixels: float = 0.5) -> np.ndarray:
    """Matches too close to the camera's height for eq. 14: ``|v + v' - 2 v0| < min_pixels``."""
    a, b = match_pair(w_prev, w_curr)
    return np.abs(a[:, 1] + b[:, 1] - 2.0 * camera.cy) < min_pixels


def theta_from_pixels(w_prev, w_curr, camera: StereoCamera) -> np.ndarray:
    """Deflection angle ``theta`` of every match, from pixels alone ([Zhao], eq. 14).

    ``tan(theta / 2) = ((u'-u0)(v-v0) - (u-u0)(v'-v0)) / (fx (v + v' - 2 v0))``

    Radians in ``(-pi, pi)``; matches at infinity (``d = 0``) are fine; NaN at the camera's height
    (``v + v' = 2 v0``, :func:`degenerate_theta_mask`).
    """
    a, b = match_pair(w_prev, w_curr)
    num, den, _ = _eq14_terms(a, b, camera)
    degenerate = np.abs(den) < DEGENERATE_ROW_PIXELS * camera.fx
    with np.errstate(divide="ignore", invalid="ignore"):
        theta = 2.0 * np.arctan(num / den)
    theta[degenerate] = np.nan
    return theta


def theta_standard_deviation(w_prev, w_curr, camera: StereoCamera, sigma_px: float) -> np.ndarray:
    """First-order standard deviation of eq. 14's theta when u, v, u', v' carry noise ``sigma_px``
    (:func:`theta_and_variance`)."""
    return np.sqrt(theta_and_variance(*match_pair(w_prev, w_curr), camera, sigma_px)[1])


def theta_and_variance(
    a: np.ndarray, b: np.ndarray, camera: StereoCamera, sigma_px: float
) -> tuple[np.ndarray, np.ndarray]:
    """eq. 14's theta and its first-order variance for checked matches ``a -> b``.

    With ``tan phi = N / (fx D)``, ``N = (u'-u0)(v-v0) - (u-u0)(v'-v0)``, ``D = v + v' - 2 v0``:
    ``dphi = (fx D dN - fx N dD) / (fx^2 D^2 + N^2)`` with ``dN/d(u, u', v, v') = (-dv', dv, du', -du)``
    and ``dD/dv = dD/dv' = 1``; theta = 2 phi.
    """
    num, den, (du, dv, du2, dv2) = _eq14_terms(a, b, camera)
    q = den * den + num * num
    g_n, g_d = den / q, camera.fx * num / q
    return 2.0 * np.arctan(num / den), (4.0 * sigma_px**2) * (
        (dv2 * g_n) ** 2 + (dv * g_n) ** 2 + (du2 * g_n - g_d) ** 2 + (du * g_n + g_d) ** 2
    )


def rho_from_pixels(w_prev, w_curr, theta, camera: StereoCamera) -> np.ndarray:
    """Chord length ``rho`` of every match given ``theta`` ([Zhao], eq. 16-17, sign corrected).

    ``rho = B/d [-sin phi, 0, cos phi](u-u0, ., fx) - B/d' [sin phi, 0, cos phi](u'-u0, ., fx)``
    with ``phi = theta / 2`` (the paper prints ``+``). ``theta``: one, or one per match; both
    disparities must be > 0; ``rho`` is negative backwards.
    """
    a, b = match_pair(w_prev, w_curr)
    for name, arr in (("w_prev", a), ("w_curr", b)):
        if np.any(arr[:, 2] <= 0):
            bad = int(np.flatnonzero(arr[:, 2] <= 0)[0])
            raise ValueError(
                f"{name}[:, 2] (disparity) must be > 0 to give rho; row {bad} has d={float(arr[bad, 2])}"
            )
    phi = 0.5 * np.asarray(theta, dtype=float)
    s, c = np.sin(phi), np.cos(phi)
    B, f = camera.baseline, camera.fx
    return B / a[:, 2] * (-s * (a[:, 0] - camera.cx) + c * f) - B / b[:, 2] * (
        s * (b[:, 0] - camera.cx) + c * f
    )


def motion_matrices(theta, rho) -> tuple[np.ndarray, np.ndarray]:
    """Rotation ``R`` and translation ``T`` of eq. 15 such that ``P' = R P + T``.

    Scalars give ``(3, 3)`` and ``(3,)``; arrays of shape ``(N,)`` give ``(N, 3, 3)`` and ``(N, 3)``.
    """
    theta, rho = np.broadcast_arrays(np.asarray(theta, dtype=float), np.asarray(rho, dtype=float))
    c, s = np.cos(theta), np.sin(theta)
    R = np.zeros(theta.shape + (3, 3))
    R[..., 0, 0], R[..., 0, 2], R[..., 1, 1], R[..., 2, 0], R[..., 2, 2] = c, s, 1.0, -s, c
    phi = 0.5 * theta
    T = np.zeros(theta.shape + (3,))
    T[..., 0], T[..., 2] = -rho * np.sin(phi), -rho * np.cos(phi)
    return R, T


def motion_transform(theta: float, rho: float) -> np.ndarray:
    """4x4 ``T_curr_from_prev`` of a circular motion (eq. 15): ``[[R, T], [0, 1]]``."""
    return rigid_matrix(*motion_matrices(theta, rho))


def apply_motion(points, theta: float, rho: float) -> np.ndarray:
    """``P' = R P + T`` (eq. 15) for points ``(N, 3)`` in the previous camera frame."""
    R, T = motion_matrices(theta, rho)
    return np.asarray(points, dtype=float) @ R.T + T


# ---------------------------------------------------------------------- camera <-> robot
def yaw_increment(theta):
    """The robot's yaw increment (counter-clockwise positive, z up) for a deflection ``theta``:
    equal, as the camera's y axis points down (a positive ``theta`` turns the camera left)."""
    return np.asarray(theta, dtype=float) * 1.0


def robot_increment(theta, rho) -> np.ndarray:
    """``(dx, dy, dyaw)`` in the previous robot frame for a camera on the robot's turning axis."""
    theta, rho = np.broadcast_arrays(np.asarray(theta, dtype=float), np.asarray(rho, dtype=float))
    phi = 0.5 * theta
    return np.stack([rho * np.cos(phi), rho * np.sin(phi), yaw_increment(theta)], axis=-1)


def circular_motion_from_increment(increment) -> tuple[np.ndarray, np.ndarray]:
    """``(theta, rho)`` closest to a planar robot increment ``(dx, dy, dyaw)``: the yaw, and the
    projection on the chord direction ``phi = theta / 2`` (the signed chord of a circular motion)."""
    inc = np.asarray(increment, dtype=float)
    theta = inc[..., 2]
    phi = 0.5 * theta
    return theta, inc[..., 0] * np.cos(phi) + inc[..., 1] * np.sin(phi)


def circular_motion_from_transform(T_curr_from_prev) -> tuple[float, float]:
    """``(theta, rho)`` of a 4x4 camera transform ``P' = R P + T`` that is a planar motion."""
    M = np.asarray(T_curr_from_prev, dtype=float)
    theta = float(np.arctan2(M[0, 2], M[0, 0]))
    phi = 0.5 * theta
    rho = float(-(M[0, 3] * np.sin(phi) + M[2, 3] * np.cos(phi)))
    return theta, rho
