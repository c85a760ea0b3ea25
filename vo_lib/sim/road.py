"""The road drive: a car at KITTI's rig, two sharp turns, a climb, a banked bend and traffic.

The road is laid along the car's planned drive (no lateral slip: the true path is the plan), the
car :data:`LANE_OFFSET` right of its centre line. Along the arc length ``s`` the surface has an
elevation (a climb of :data:`CLIMB_GRADE`) and a crossfall (a bank, left side up, through the second
bend); the car's height is the surface's plus :data:`VEHICLE_ORIGIN_HEIGHT`, its pitch the grade,
its roll the crossfall. The car's frame is x forward, y left, z up, origin above the rear axle
(KITTI's IMU); the camera sits as in KITTI's calibration (:data:`CAMERA_IN_VEHICLE`), 1.65 m up.
"""

from __future__ import annotations

import numpy as np

from vo_lib.geometry import camera_mount
from vo_lib.models.track_odometry import TrackOdometry
from vo_lib.sim.trajectories import Leg, command_profile

#: Frame rate of the drive, Hz (KITTI's).
RATE = 10.0
#: The drive: straight at 12 m/s, brake, a left bend (90 deg at 5.5 m/s, radius 10.5 m), away at
#: 11 m/s up the climb, brake, a right bend (90 deg, banked), away at 12 m/s.
TURN_RATE = np.radians(90.0) / 3.0
LEGS = (
    *(Leg(50, 12.0), Leg(10, 9.0), Leg(10, 6.0), Leg(30, 5.5, TURN_RATE), Leg(10, 8.0), Leg(40, 11.0)),
    *(Leg(10, 7.0), Leg(30, 5.5, -TURN_RATE), Leg(10, 8.0), Leg(40, 12.0)),
)
START = (0.0, 0.0, 0.0)
#: The car's path lies this far to the right of the road's centre line, metres.
LANE_OFFSET = 1.9
#: Road before the start and beyond the end of the drive, metres.
RUN_IN, RUN_OUT = 30.0, 100.0
#: The road surface sits this high above the verge ground (z = 0) where it is flat, metres.
ROAD_RAISE = 0.1
#: Climb: grade, and the arc lengths where it starts and ends; the grade changes over
#: :data:`VERTICAL_CURVE` metres at either end.
CLIMB_GRADE = 0.04
CLIMB = (95.0, 150.0)
VERTICAL_CURVE = 15.0
#: Bank: crossfall (rise per metre to the left) through the second bend.
BANK_CROSSFALL = 0.05
BANK = (140.0, 180.0)
#: Height of the car's origin (rear axle, IMU) above the road, metres: puts the camera 1.65 m up.
VEHICLE_ORIGIN_HEIGHT = 0.92
#: Left camera in the car's frame (forward, left, up, metres): KITTI's calibration to the centimetre,
#: as the car pipeline assumes for a sequence without ``raw_calib/``.
CAMERA_IN_VEHICLE = (1.08, -0.31, 0.73)
#: Wheel odometry: two wheels 1.6 m apart, 0.02 of noise per square-root metre (the car gauge).
CAR_ODOMETRY = TrackOdometry(track_distance=1.6, track_width=0.0, encoder_sigma=0.02)
#: KITTI's left camera: fx = fy, principal point, baseline (metres), width, height.
KITTI_RIG = (718.856, 607.1928, 185.2157, 0.5371657, 1242, 375)


def planned_path() -> np.ndarray:
    """The car's planar poses ``(N, 3)`` at :data:`RATE`, as
    :func:`vo_lib.sim.trajectories.simulate_drive` integrates them."""
    speed, turn = command_profile(LEGS, RATE)
    ground = CAR_ODOMETRY.controls_for(speed / RATE, turn / RATE)
    return CAR_ODOMETRY.integrate(ground, start=START, exact=True)


def arc_length(poses: np.ndarray) -> np.ndarray:
    """Cumulative distance along planar poses, metres (0 at the first)."""
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(poses[:, :2], axis=0), axis=1))])


def _ramp(s, start: float, end: float, value: float) -> np.ndarray:
    """0 before ``start``, ``value`` between, back to 0 after ``end``, linear over VERTICAL_CURVE."""
    knots = [start, start + VERTICAL_CURVE, end - VERTICAL_CURVE, end]
    return np.interp(s, knots, [0.0, value, value, 0.0])


def grade(s) -> np.ndarray:
    """Rise of the road per metre along it at arc length ``s``."""
    return _ramp(s, *CLIMB, CLIMB_GRADE)


def crossfall(s) -> np.ndarray:
    """Rise of the road per metre to the left at arc length ``s``."""
    return _ramp(s, *BANK, BANK_CROSSFALL)


def elevation(s) -> np.ndarray:
    """Height of the road's centre line at arc length ``s``: ROAD_RAISE plus the integrated grade."""
    fine = np.linspace(-RUN_IN, arc_length(planned_path())[-1] + RUN_OUT, 4001)
    g = grade(fine)
    height = np.concatenate([[0.0], np.cumsum(0.5 * (g[1:] + g[:-1]) * np.diff(fine))])
    return ROAD_RAISE + np.interp(s, fine, height)


def centre_line(step: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Arc lengths ``(M,)`` and planar poses ``(M, 3)`` of the car's lane every ``step`` metres, from
    RUN_IN before the start to RUN_OUT beyond the end."""
    path = planned_path()
    s = arc_length(path)
    keep = np.concatenate([[True], np.diff(s) > 1e-9])  # drop standing frames
    path, s = path[keep], s[keep]
    at = np.arange(-RUN_IN, s[-1] + RUN_OUT + step / 2, step)
    inside = np.clip(at, 0.0, s[-1])
    x, y, h = (np.interp(inside, s, v) for v in (path[:, 0], path[:, 1], np.unwrap(path[:, 2])))
    beyond = at - inside  # metres before the start (< 0) or beyond the end (> 0)
    return at, np.column_stack([x + beyond * np.cos(h), y + beyond * np.sin(h), h])


def vehicle_poses(poses: np.ndarray) -> np.ndarray:
    """``(N, 4, 4)`` world poses of the car at planar ``poses`` of its planned path, on the road."""
    s = arc_length(poses)
    g, c = grade(s), crossfall(s)
    pitch, roll = -np.arctan(g), np.arctan(c)
    z = elevation(s) - LANE_OFFSET * c + VEHICLE_ORIGIN_HEIGHT
    (cy, sy), (cp, sp), (cr, sr) = ((np.cos(a), np.sin(a)) for a in (poses[:, 2], pitch, roll))
    o, i = np.zeros(len(poses)), np.ones(len(poses))
    Rz = np.stack([cy, -sy, o, sy, cy, o, o, o, i], axis=1).reshape(-1, 3, 3)
    Ry = np.stack([cp, o, sp, o, i, o, -sp, o, cp], axis=1).reshape(-1, 3, 3)
    Rx = np.stack([i, o, o, o, cr, -sr, o, sr, cr], axis=1).reshape(-1, 3, 3)
    out = np.tile(np.eye(4), (len(poses), 1, 1))
    out[:, :3, :3] = Rz @ Ry @ Rx
    out[:, :3, 3] = np.column_stack([poses[:, :2], z])
    return out


def camera_in_vehicle() -> np.ndarray:
    """``T_vehicle_camera`` of the road drive's left camera."""
    forward, left, up = CAMERA_IN_VEHICLE
    return camera_mount(forward=forward, height=up, left=left)
