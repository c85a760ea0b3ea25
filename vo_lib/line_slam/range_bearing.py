"""Range-bearing observation of a point landmark ([Yan 2020], eq. 8-12) and its inverse.

From the robot pose ``(x_v, y_v, phi)`` a point ``(x_i, y_i)`` is seen at

    r = sqrt((x_i - x_v)^2 + (y_i - y_v)^2)                         eq. 10
    b = atan2(y_i - y_v, x_i - x_v) - phi

The printed Jacobian (eq. 11) is right in its range row and in the bearing row's pose columns,
but its bearing row's landmark columns read ``(-dx/D^2, -dy/D^2)``; the derivative is
``(dy/D^2, -dx/D^2)`` with the paper's ``dx = x_v - x_i``, ``dy = y_v - y_i`` (eq. 12).
Notebook 09 derives it with sympy and checks it by finite differences.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from vo_lib.geometry import wrap_angle


def observe_point(pose, point) -> np.ndarray:
    """``(r, b)`` of ``point`` seen from ``pose`` (eq. 10, noise-free); ``b`` wrapped."""
    dx, dy = point[0] - pose[0], point[1] - pose[1]
    return np.array([math.hypot(dx, dy), wrap_angle(math.atan2(dy, dx) - pose[2])])


def observation_jacobians(pose, point) -> tuple[np.ndarray, np.ndarray]:
    """``(H_pose, H_point)``: eq. 10 differentiated by the pose (2x3) and by the point (2x2), the
    non-zero blocks of the paper's ``H_k`` (eq. 11), corrected."""
    dx, dy = point[0] - pose[0], point[1] - pose[1]
    q = dx * dx + dy * dy
    r = math.sqrt(q)
    h_point = np.array([[dx / r, dy / r], [-dy / q, dx / q]])
    h_pose = np.column_stack([-h_point, [0.0, -1.0]])
    return h_pose, h_point


def point_from_observation(pose, z) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Invert eq. 10: the world point seen at ``z = (r, b)`` from ``pose``, with its Jacobians
    ``G_pose`` (2x3) and ``G_z`` (2x2), used to add a new landmark to the state."""
    r, b = z
    angle = pose[2] + b
    c, s = math.cos(angle), math.sin(angle)
    point = np.array([pose[0] + r * c, pose[1] + r * s])
    g_pose = np.array([[1.0, 0.0, -r * s], [0.0, 1.0, r * c]])
    g_z = np.array([[c, -r * s], [s, r * c]])
    return point, g_pose, g_z


class ObservationModel(NamedTuple):
    """How a wall's feature point is observed: the prediction ``h(pose, point)``, its Jacobians
    ``(H_pose, H_point)``, the inverse with ``(point, G_pose, G_z)``, and ``align(z, cov,
    predicted)``, the description of ``z`` nearest the prediction."""

    predict: Callable
    jacobians: Callable
    invert: Callable
    align: Callable


#: Range and bearing of a wall's feature point (eq. 10): the observation of the paper's filter. A
#: point has one description: ``align`` returns ``z`` and ``cov`` unchanged.
POINT = ObservationModel(
    observe_point,
    observation_jacobians,
    point_from_observation,
    lambda z, cov, predicted: (np.asarray(z, dtype=float), cov),
)
