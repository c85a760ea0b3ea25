"""KITTI raw files a sequence folder may carry (``docs/real_data.md``): ``oxts.txt`` (GPS/IMU packets,
whose speed and yaw rate stand in for wheel odometry) and ``raw_calib/`` (the camera's mount).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from vo_lib.formats.frame_files import SequenceError, check_metres, numbers, read_rows
from vo_lib.formats.poses import data_lines, rotation_problem

OXTS_FIELDS = 30
VF, WZ = 8, 19  # zero-based columns of forward speed (m/s) and yaw rate (rad/s)
#: Largest magnitude of any OXTS field: beyond, a packet is damaged (and would overflow the filter).
MAX_OXTS_VALUE = 1e6


def read_oxts(path) -> np.ndarray:
    """``(N, 30)`` OXTS packets, finite and within :data:`MAX_OXTS_VALUE`."""
    rows = read_rows(Path(path), OXTS_FIELDS, "an OXTS packet", MAX_OXTS_VALUE)
    if not len(rows):
        raise SequenceError(f"{path}: no OXTS packets")
    return rows


def wheel_distances_from_oxts(oxts: np.ndarray, times: np.ndarray, gauge: float) -> np.ndarray:
    """Distances ``(N, 2)`` (metres, row 0 zero) of wheels ``gauge`` apart, ``s -/+ gauge dpsi / 2``,
    with ``s`` and ``dpsi`` the trapezoidal integrals of ``vf`` and ``wz`` between frames: the
    track-odometry model ([Zhao], eq. 4) turns them back into ``s`` and ``dpsi``."""
    dt = np.diff(np.asarray(times, float))
    s = 0.5 * (oxts[1:, VF] + oxts[:-1, VF]) * dt
    dpsi = 0.5 * (oxts[1:, WZ] + oxts[:-1, WZ]) * dt
    out = np.zeros((len(oxts), 2))
    out[1:, 0] = s - 0.5 * gauge * dpsi
    out[1:, 1] = s + 0.5 * gauge * dpsi
    return out


def _calib_values(path: Path, key: str, count: int) -> np.ndarray:
    found = [(n, line) for n, line in data_lines(path, f"a line '{key}:'") if line.startswith(key + ":")]
    if not found:
        raise SequenceError(f"{path}: no line starting with '{key}:'")
    (line_no, line), *others = found
    if others:
        raise SequenceError(f"{path}, line {others[0][0]}: a second {key} line (the first is line {line_no})")
    return numbers(path, line_no, line.split(":", 1)[1], count, key)


def _rotation(path: Path, key: str) -> np.ndarray:
    """The 3x3 rotation of line ``key``; else :class:`SequenceError`."""
    R = _calib_values(path, key, 9).reshape(3, 3)
    problem = rotation_problem(R)
    if problem:
        raise SequenceError(f"{path}: {key}: {problem.replace('the first three columns are', 'it is')}")
    return R


def _rigid(path: Path) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = _rotation(path, "R")
    T[:3, 3] = _calib_values(path, "T", 3)
    distance = np.linalg.norm(T[:3, 3])
    check_metres(path, f"T puts one sensor {distance:g} from the other", distance)
    return T


def camera_in_imu_frame(raw_calib) -> np.ndarray:
    """4x4 pose of the left rectified camera in the IMU frame (x forward, y left, z up)."""
    folder = Path(raw_calib)
    if not folder.is_dir():
        raise SequenceError(
            f"{folder}: not a folder, where that of KITTI's raw calibration (calib_*.txt) should be"
        )
    imu_to_velo = _rigid(folder / "calib_imu_to_velo.txt")
    velo_to_cam = _rigid(folder / "calib_velo_to_cam.txt")
    rect = np.eye(4)
    rect[:3, :3] = _rotation(folder / "calib_cam_to_cam.txt", "R_rect_00")
    return np.linalg.inv(rect @ velo_to_cam @ imu_to_velo)
