"""[Yan 2020]'s observation of a line segment, and the line measurement a filter can use.

The paper's triple, distance to the line and the segment's start and end angles
(:func:`paper_line_triple`), does not fix the line (any tangent to the circle of radius ``d``
crossing both rays fits; notebook 09 builds two); the end points' measured ranges do. From them
this module builds the line in the robot's frame,

    z = (rho, psi):  the line is {q : (cos psi, sin psi) . q = rho} in robot coordinates,

and predicts it from the wall's feature point ``p`` (section 1.3) in the filter's state:

    c = |p|,  n = p / c,  rho = c - n . (x_v, y_v),  psi = atan2(p_y, p_x) - phi.

A line has two descriptions, ``(rho, psi)`` and ``(-rho, psi + pi)``: :func:`align_line` picks
the one nearest a prediction. :data:`LINE` is the observation model for ``EkfSlam``.
"""

from __future__ import annotations

import math

import numpy as np

from vo_lib.geometry import wrap_angle
from vo_lib.line_slam.range_bearing import ObservationModel


def paper_line_triple(end_points_robot) -> np.ndarray:
    """``(d, a_s, a_e)``: distance to the line through two robot-frame points (2 x 2, a point a
    row) and their bearings."""
    q = np.asarray(end_points_robot, dtype=float).reshape(2, 2)
    e = q[1] - q[0]
    d = abs(q[0, 0] * e[1] - q[0, 1] * e[0]) / math.hypot(*e)
    return np.array([d, math.atan2(q[0, 1], q[0, 0]), math.atan2(q[1, 1], q[1, 0])])


def line_from_points(end_points_robot) -> np.ndarray:
    """``(rho, psi)`` of the line through two points in the robot's frame, with ``rho >= 0``."""
    q = np.asarray(end_points_robot, dtype=float).reshape(2, 2)
    e = q[1] - q[0]
    m = np.array([-e[1], e[0]]) / math.hypot(*e)
    rho = float(m @ q[0])
    if rho < 0:
        m, rho = -m, -rho
    return np.array([rho, math.atan2(m[1], m[0])])


def line_from_range_bearing(z_ends) -> np.ndarray:
    """``(rho, psi)`` from the two end points measured as ``(r, b)`` rows (2 x 2)."""
    z = np.asarray(z_ends, dtype=float).reshape(2, 2)
    q = z[:, :1] * np.column_stack([np.cos(z[:, 1]), np.sin(z[:, 1])])
    return line_from_points(q)


def measure_line(z_ends, range_sigma: float, bearing_sigma: float, eps: float = 1e-6):
    """The line ``(rho, psi)`` from the visible part's two measured end points ``(r, b)``, and its
    covariance: the end points' independent noise propagated to first order."""
    z = np.asarray(z_ends, dtype=float).reshape(4)
    line = line_from_range_bearing(z)
    # central differences, one row per end-point component
    diff = np.array(
        [line_from_range_bearing(z + dz) - line_from_range_bearing(z - dz) for dz in eps * np.eye(4)]
    )
    diff[:, 1] = wrap_angle(diff[:, 1])
    J = diff.T / (2 * eps)
    noise = np.diag([range_sigma**2, bearing_sigma**2, range_sigma**2, bearing_sigma**2])
    return line, J @ noise @ J.T


def predict_line(pose, point) -> np.ndarray:
    """``(rho, psi)`` of the line of feature point ``point`` seen from ``pose``."""
    c = math.hypot(point[0], point[1])
    rho = c - (point[0] * pose[0] + point[1] * pose[1]) / c
    return np.array([rho, wrap_angle(math.atan2(point[1], point[0]) - pose[2])])


def line_jacobians(pose, point) -> tuple[np.ndarray, np.ndarray]:
    """``(H_pose, H_point)``: :func:`predict_line` differentiated by the pose (2x3) and the point (2x2)."""
    p = np.asarray(point, dtype=float)
    pos = np.asarray(pose[:2], dtype=float)
    c = math.hypot(*p)
    n = p / c
    h_pose = np.array([[-n[0], -n[1], 0.0], [0.0, 0.0, -1.0]])
    h_point = np.array([n - (pos - (n @ pos) * n) / c, np.array([-p[1], p[0]]) / (c * c)])
    return h_pose, h_point


def point_from_line(pose, z) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Invert :func:`predict_line`: the feature point of the line seen at ``z = (rho, psi)`` from
    ``pose``, with its Jacobians ``G_pose`` (2x3) and ``G_z`` (2x2)."""
    rho, psi = z
    beta = pose[2] + psi
    n = np.array([math.cos(beta), math.sin(beta)])
    n_perp = np.array([-n[1], n[0]])
    pos = np.asarray(pose[:2], dtype=float)
    c = rho + n @ pos
    d_angle = (n_perp @ pos) * n + c * n_perp
    g_pose = np.column_stack([n[0] * n, n[1] * n, d_angle])
    return c * n, g_pose, np.column_stack([n, d_angle])


def align_line(z, cov, predicted):
    """The description of the measured line, ``(rho, psi)`` or ``(-rho, psi + pi)``, whose
    normal lies within 90 degrees of the prediction's, and its covariance."""
    z = np.asarray(z, dtype=float)
    if abs(wrap_angle(z[1] - predicted[1])) <= math.pi / 2:
        return z, cov
    flip = np.diag([-1.0, 1.0])
    return np.array([-z[0], wrap_angle(z[1] + math.pi)]), flip @ cov @ flip


#: The line ``(rho, psi)`` as the observation of a wall's feature point.
LINE = ObservationModel(predict_line, line_jacobians, point_from_line, align_line)
