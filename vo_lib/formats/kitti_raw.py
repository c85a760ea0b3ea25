"""KITTI's raw set (``docs/real_data.md``): the files a KITTI-layout folder may carry beside its
images, ``oxts.txt`` (GPS/IMU packets, whose speed and yaw rate stand in for wheel odometry) and
``raw_calib/`` (the camera's mount); and a drive as the raw set stores it, read as it is::

    DATE/calib_cam_to_cam.txt, calib_imu_to_velo.txt, calib_velo_to_cam.txt
    DATE/DATE_drive_NNNN_sync/image_00/data/0000000000.png ...   left, rectified, grey
                              image_01/data/ ...                  right
                              image_00/timestamps.txt             date and time of each image
                              oxts/data/0000000000.txt ...        one GPS/IMU packet per image

(the calibration files may also sit in the drive's folder). Its ground truth is the left camera's
pose from the packets, as KITTI's development kit computes it.
"""

from __future__ import annotations

import contextlib
import warnings
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from vo_lib.formats.frame_files import (
    SequenceError,
    calib_values,
    check_metres,
    read_per_frame,
    read_rows,
    shown,
)
from vo_lib.formats.images import check_headers
from vo_lib.formats.poses import data_lines, rotation_problem
from vo_lib.formats.sequence import (
    MAX_TRACK_SPEED_M_S,
    Sequence,
    check_frame_spacing,
    checked_camera,
    image_pairs,
)

OXTS_FIELDS = 30
VF, WZ = 8, 19  # zero-based columns of forward speed (m/s) and yaw rate (rad/s)
#: Largest magnitude of any OXTS field: beyond, a packet is damaged (and would overflow the filter).
MAX_OXTS_VALUE = 1e6
#: Fastest turn of a car in an OXTS packet, rad/s (a car turns at 1 rad/s or less): beyond, damaged.
MAX_YAW_RATE = 10.0
#: Latitude and longitude bounds (degrees): Mercator's projection grows without bound near the poles.
MAX_LATITUDE, MAX_LONGITUDE = 85.0, 180.0
RAW_CALIB_FILES = ("calib_cam_to_cam.txt", "calib_imu_to_velo.txt", "calib_velo_to_cam.txt")
#: The Earth's equatorial radius (WGS 84), metres, of the Mercator projection of the OXTS positions.
EARTH_RADIUS_M = 6378137.0


def read_oxts(path) -> np.ndarray:
    """``(N, 30)`` OXTS packets, finite and within :data:`MAX_OXTS_VALUE`; position, forward speed and
    yaw rate within their own bounds."""
    rows = read_rows(Path(path), OXTS_FIELDS, "an OXTS packet", MAX_OXTS_VALUE)
    if not len(rows):
        raise SequenceError(f"{path}: no OXTS packets")
    speed = float(np.median(np.abs(rows[:, VF])))
    claim = "the forward speed vf is {} per second (median)"
    check_metres(path, claim, speed, MAX_TRACK_SPEED_M_S, " m/s")
    for column, name, most, unit in (
        (0, "latitude lat", MAX_LATITUDE, "deg"),
        (1, "longitude lon", MAX_LONGITUDE, "deg"),
        (VF, "forward speed vf", MAX_TRACK_SPEED_M_S, "m/s"),
        (WZ, "yaw rate wz", MAX_YAW_RATE, "rad/s"),
    ):
        k = int(np.argmax(np.abs(rows[:, column])))  # one damaged packet among good ones
        if abs(rows[k, column]) > most:
            raise SequenceError(
                f"{path}: packet {k + 1}: {name} {rows[k, column]:g} {unit}; expected at most {most:g} {unit}"
            )
    return rows


def wheel_distances_from_oxts(oxts: np.ndarray, times: np.ndarray, gauge: float) -> np.ndarray:
    """Distances ``(N, 2)`` (metres, row 0 zero) of wheels ``gauge`` apart, ``s -/+ gauge dpsi / 2``,
    with ``s`` and ``dpsi`` the trapezoidal integrals of ``vf`` and ``wz`` between frames: the
    track-odometry model ([Zhao], eq. 4) turns them back into ``s`` and ``dpsi``."""
    dt = np.diff(np.asarray(times, float))
    s = 0.5 * (oxts[1:, VF] + oxts[:-1, VF]) * dt
    dpsi = 0.5 * (oxts[1:, WZ] + oxts[:-1, WZ]) * dt
    out = np.zeros((len(oxts), 2))
    out[1:] = np.column_stack([s - 0.5 * gauge * dpsi, s + 0.5 * gauge * dpsi])
    return out


def _rotation(path: Path, key: str) -> np.ndarray:
    """The 3x3 rotation of line ``key``; else :class:`SequenceError`."""
    R = calib_values(path, key, 9).reshape(3, 3)
    if problem := rotation_problem(R):
        raise SequenceError(f"{path}: {key}: {problem.replace('the first three columns are', 'it is')}")
    return R


def _rigid(path: Path) -> np.ndarray:
    """The rigid transform of lines ``R`` and ``T`` (metres)."""
    T = np.eye(4)
    T[:3, :3] = _rotation(path, "R")
    T[:3, 3] = calib_values(path, "T", 3)
    with np.errstate(over="ignore"):  # a distance beyond floats is inf, and refused below
        distance = np.linalg.norm(T[:3, 3])
    check_metres(path, "T puts one sensor {} from the other", distance)
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


def raw_drive_of(path) -> Path | None:
    """``path`` if it is a drive folder of KITTI's raw set (holding ``image_00/data``), else None."""
    path = Path(path)
    return path if (path / "image_00" / "data").is_dir() else None


def raw_near_miss(path) -> str | None:
    """What to pass instead where ``path`` holds drives of the raw set (a date folder), else None."""
    path, drives = Path(path), []
    with contextlib.suppress(OSError):  # a folder that cannot be listed holds no drive we can read
        drives = sorted(p.name for p in path.iterdir() if raw_drive_of(p))
    if not drives:
        return None
    count = f"{len(drives)} drive{'s' * (len(drives) > 1)}"
    return f"{path}: holds {count} of KITTI's raw set; pass one, e.g. {path / drives[0]}"


def read_raw_timestamps(path: Path) -> np.ndarray:
    """Nanoseconds since 1970 of each line ``YYYY-MM-DD HH:MM:SS.fffffffff`` (the raw set's clock)."""
    stamps = []
    for n, line in data_lines(path, "a date and time per image"):
        try:
            with warnings.catch_warnings():  # NumPy warns of what it will refuse: refused here
                warnings.simplefilter("error")
                stamps.append(np.datetime64(line.replace(" ", "T", 1), "ns"))
        except (ValueError, Warning):
            raise SequenceError(
                f"{path}, line {n}: {shown(line)}; expected a date and time, YYYY-MM-DD HH:MM:SS.fffffffff"
            ) from None
        if len(stamps) > 1 and not stamps[-1] > stamps[-2]:
            raise SequenceError(
                f"{path}, line {n}: {stamps[-1]} is not after {stamps[-2]} on the line before"
            )
    return np.array(stamps, "datetime64[ns]").astype(np.int64)


def poses_from_oxts(oxts: np.ndarray, camera_in_imu: np.ndarray) -> np.ndarray:
    """``(N, 4, 4)`` poses of the left rectified camera in its first frame, from OXTS packets: the
    IMU at the Mercator projection of latitude and longitude (scaled at the first latitude) and the
    altitude, turned by ``R = Rz(yaw) Ry(pitch) Rx(roll)``; ``camera_in_imu`` from
    :func:`camera_in_imu_frame` (KITTI's development kit, ``convertOxtsToPose``)."""
    lat, lon = np.radians(oxts[:, 0]), np.radians(oxts[:, 1])
    imu = np.tile(np.eye(4), (len(oxts), 1, 1))
    scale = EARTH_RADIUS_M * np.cos(lat[0])
    imu[:, :3, 3] = np.column_stack([scale * lon, scale * np.log(np.tan(np.pi / 4 + lat / 2)), oxts[:, 2]])
    imu[:, :3, :3] = Rotation.from_euler("ZYX", oxts[:, [5, 4, 3]]).as_matrix()
    camera = imu @ camera_in_imu
    return np.linalg.inv(camera[0]) @ camera


def read_kitti_raw(path, truth: bool = True, odometry: bool = True) -> Sequence:
    """A drive of KITTI's raw set as the set stores it (module docstring); ``truth=False``: no poses;
    neither truth nor ``odometry``: no OXTS packets read (they are both)."""
    drive = Path(path)
    left, right = image_pairs(drive, ("image_00/data", "image_01/data"))
    calib = next((f for f in (drive, drive.parent) if (f / RAW_CALIB_FILES[0]).is_file()), None)
    if calib is None:  # the raw calibration: in the drive's folder, else in the one holding it
        raise SequenceError(
            f"{drive}: no {RAW_CALIB_FILES[0]} in it or in {drive.parent}; expected KITTI's raw calibration "
            f"({', '.join(RAW_CALIB_FILES)}) beside the drive's folder, where the raw set keeps it"
        )
    cam_to_cam = calib / RAW_CALIB_FILES[0]
    P0, P1 = (calib_values(cam_to_cam, key, 12).reshape(3, 4) for key in ("P_rect_00", "P_rect_01"))
    size, rectified = check_headers(left, right), tuple(calib_values(cam_to_cam, "S_rect_00", 2))
    if size != rectified:  # the raw set's "extract" drives: distorted, not rectified
        raise SequenceError(
            f"{drive / 'image_00' / 'data'}: {size[0]}x{size[1]} images, where the rectified ones are "
            f"{rectified[0]:g}x{rectified[1]:g} (S_rect_00 of {cam_to_cam}); expected a drive's "
            "synced and rectified images (a _sync drive)"
        )
    camera = checked_camera(cam_to_cam, P0, P1, size, ("P_rect_00", "P_rect_01"))
    stamps_file = drive / "image_00" / "timestamps.txt"
    stamps = read_per_frame(stamps_file, len(left), "timestamps", read_raw_timestamps)
    seconds = (stamps - stamps[0]) * 1e-9  # from whole nanoseconds: exact to 1 ns
    check_frame_spacing(stamps_file, seconds)
    packets = None
    if truth or odometry:  # oxts/data/NAME.txt for image NAME.png
        files = [drive / "oxts" / "data" / f"{image.stem}.txt" for image in left]
        if missing := next((f for f in files if not f.is_file()), None):
            raise SequenceError(f"{missing}: missing; expected one OXTS packet per image, named as the image")
        packets = np.concatenate([read_per_frame(f, 1, "OXTS packets", read_oxts) for f in files])
    poses = poses_from_oxts(packets, camera_in_imu_frame(calib))[:, :3] if truth else None
    manifest = {"layout": "kitti_raw", "time_origin_s": float(stamps[0] * 1e-9)}
    found = {"truth_file": drive / "oxts" / "data" if truth else None, "oxts": packets, "raw_calib": calib}
    return Sequence(drive, camera, seconds, left, right, poses, None, manifest, **found)
