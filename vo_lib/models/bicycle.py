"""The bicycle (front-wheel-steered) vehicle of [Yan 2020] (eq. 4-7) and its steering controller.

With speed ``V``, steering angle ``a`` of the front wheel, wheelbase ``L`` and period ``T``, the
pose ``(x, y, phi)`` advances as

    x'   = x + T V cos(phi + a)                                   eq. 5
    y'   = y + T V sin(phi + a)
    phi' = phi + T V sin(a) / L

The printed Jacobians carry two sign errors, both corrected here and shown in notebook 09:
``df/dx`` (eq. 6) has ``+T V cos(phi + a)`` in row 2, column 3 (printed with a minus), and
``df/du`` (eq. 7) has ``+T sin(phi + a)`` in row 2, column 1 (printed with a minus).
"""

from __future__ import annotations

import math

import numpy as np

from vo_lib.geometry import wrap_angle

#: [Yan 2020]'s vehicle: 3 m/s, steering at most 30 degrees, turned at most pi/9 rad/s.
PAPER_SPEED = 3.0
PAPER_MAX_STEER = math.radians(30.0)
PAPER_MAX_STEER_RATE = math.pi / 9
#: Not printed in [Yan 2020]: that of the EKF-SLAM simulator whose other settings the paper repeats.
DEFAULT_WHEELBASE = 4.0


def bicycle_step(pose, speed: float, steer: float, period: float, wheelbase: float = DEFAULT_WHEELBASE):
    """One step of eq. 5 (noise-free): the pose ``(x, y, phi)`` after ``period`` seconds."""
    x, y, phi = pose
    heading = phi + steer
    return np.array(
        [
            x + period * speed * math.cos(heading),
            y + period * speed * math.sin(heading),
            wrap_angle(phi + period * speed * math.sin(steer) / wheelbase),
        ]
    )


def bicycle_jacobians(pose, speed: float, steer: float, period: float, wheelbase: float = DEFAULT_WHEELBASE):
    """``(F_x, F_u)``: the Jacobians of eq. 5 by the pose and by ``u = (V, a)`` (eq. 6-7, corrected)."""
    phi = pose[2]
    c, s = math.cos(phi + steer), math.sin(phi + steer)
    tv = period * speed
    f_x = np.array([[1.0, 0.0, -tv * s], [0.0, 1.0, tv * c], [0.0, 0.0, 1.0]])
    f_u = np.array(
        [
            [period * c, -tv * s],
            [period * s, tv * c],
            [period * math.sin(steer) / wheelbase, tv * math.cos(steer) / wheelbase],
        ]
    )
    return f_x, f_u


def steer_towards(
    pose,
    steer: float,
    target,
    period: float,
    max_steer: float = PAPER_MAX_STEER,
    max_rate: float = PAPER_MAX_STEER_RATE,
) -> float:
    """The next steering angle: turn the wheel towards ``target`` at most ``max_rate`` rad/s,
    never beyond ``max_steer``."""
    wanted = wrap_angle(math.atan2(target[1] - pose[1], target[0] - pose[0]) - pose[2] - steer)
    change = min(max(wanted, -max_rate * period), max_rate * period)
    return min(max(steer + change, -max_steer), max_steer)
