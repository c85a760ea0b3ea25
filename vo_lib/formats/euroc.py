"""A stereo rig as it records, in the ASL layout of the EuRoC datasets (and of Kalibr):

::

    ROOT/mav0/cam0/data/<timestamp ns>.png   left images, raw (distorted, not rectified)
    ROOT/mav0/cam0/data.csv                  "#timestamp [ns],filename" then one row per image
    ROOT/mav0/cam0/sensor.yaml               T_BS (camera -> body, 4x4), intrinsics [fu, fv, cu, cv],
                                             distortion_model: radial-tangential,
                                             distortion_coefficients [k1, k2, p1, p2], resolution
    ROOT/mav0/cam1/...                       the right camera, likewise
    ROOT/mav0/state_groundtruth_estimate0/   optional ground truth: groundtruth.tum or data.csv
    ROOT/mav0/leica0/data.csv                optional: a laser tracker's prism positions

``ROOT`` may also be the ``mav0`` folder itself. Reading it undistorts and rectifies both
cameras with OpenCV (``stereoRectify``, ``initUndistortRectifyMap``), pairs the images by
timestamp, and moves a 6-DoF ground truth from the body frame into the rectified left camera.
The result is a :class:`~vo_lib.formats.sequence.Sequence` like any other, whose images are
rectified as they are read. Every problem raises one :class:`AslError` naming the file and key.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import yaml

from vo_lib.camera import StereoCamera
from vo_lib.formats.groundtruth import (
    GroundTruthError,
    TruthKind,
    covering,
    read_groundtruth,
    to_camera,
)
from vo_lib.formats.poses import rotation_problem
from vo_lib.formats.sequence import Sequence, SequenceError, image_header

NANOSECONDS = 1e-9
#: Ground-truth files looked for under ``mav0``, in order: 6-DoF first, then positions only.
GROUND_TRUTH_FILES = (
    "state_groundtruth_estimate0/groundtruth.tum",
    "state_groundtruth_estimate0/data.csv",
    "vicon0/data.csv",
    "leica0/data.csv",
)


class AslError(SequenceError):
    """An ASL folder that cannot be read: the file (and key or line) named, and what was expected."""


@dataclass(frozen=True)
class CameraCalibration:
    """One camera's ``sensor.yaml``: ``T_BS`` (camera to body), ``K``, radial-tangential
    ``distortion`` ``[k1, k2, p1, p2]`` and ``resolution`` ``(width, height)``."""

    T_BS: np.ndarray
    K: np.ndarray
    distortion: np.ndarray
    resolution: tuple[int, int]


@dataclass(frozen=True)
class Rectification:
    """The undistort-and-rectify maps of a stereo pair and the rectified left camera's pose in
    the body frame (``T_body_rect``)."""

    left_maps: tuple[np.ndarray, np.ndarray]
    right_maps: tuple[np.ndarray, np.ndarray]
    camera: StereoCamera
    T_body_rect: np.ndarray

    def __call__(self, left: np.ndarray, right: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Both images undistorted and rectified (bilinear)."""
        return (
            cv2.remap(left, *self.left_maps, cv2.INTER_LINEAR),
            cv2.remap(right, *self.right_maps, cv2.INTER_LINEAR),
        )


def mav0_of(path) -> Path | None:
    """The ``mav0`` folder of an ASL recording at ``path`` (the folder itself or the one holding
    it), or None if ``path`` is not one."""
    path = Path(path)
    for candidate in (path / "mav0", path):
        if (candidate / "cam0").is_dir() or (candidate / "cam1").is_dir():
            return candidate
    return None


def _yaml(path: Path) -> dict:
    if not path.is_file():
        raise AslError(f"{path}: missing (the camera's calibration: T_BS, intrinsics, distortion)")
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as exc:
        raise AslError(f"{path}: cannot read ({exc})") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f", line {mark.line + 1}" if mark is not None else ""
        raise AslError(f"{path}{where}: not valid YAML ({getattr(exc, 'problem', None) or exc})") from None
    if not isinstance(data, dict):
        raise AslError(f"{path}: expected YAML keys (T_BS, intrinsics, ...), got {type(data).__name__}")
    return data


def _numbers(path: Path, data: dict, key: str, count: int, what: str) -> np.ndarray:
    value = data.get(key)
    if isinstance(value, dict):  # T_BS: {rows, cols, data}
        value = value.get("data")
    try:
        a = np.array(value, dtype=float).ravel()
    except (TypeError, ValueError):
        a = np.array([])
    if value is None:
        raise AslError(f"{path}: key {key} missing; expected {what}")
    if a.size != count or not np.all(np.isfinite(a)):
        raise AslError(f"{path}: key {key}: expected {what} ({count} finite numbers), got {value!r:.60}")
    return a


def read_camera_yaml(path) -> CameraCalibration:
    """One camera's calibration from its ``sensor.yaml``; raises :class:`AslError` naming the key."""
    path = Path(path)
    data = _yaml(path)
    T = _numbers(path, data, "T_BS", 16, "a 4x4 camera-to-body transform, data: [16 numbers]").reshape(4, 4)
    problem = rotation_problem(T[:3, :3])
    if problem or not np.allclose(T[3], [0, 0, 0, 1]):
        raise AslError(f"{path}: key T_BS: {problem or 'the last row is not 0 0 0 1'}")
    fu, fv, cu, cv = _numbers(path, data, "intrinsics", 4, "[fu, fv, cu, cv]")
    if fu <= 0 or fv <= 0:
        raise AslError(f"{path}: key intrinsics: focal lengths must be > 0, got fu={fu:g}, fv={fv:g}")
    model = data.get("distortion_model", "radial-tangential")
    if model not in ("radial-tangential", "radtan", "none"):
        raise AslError(
            f"{path}: key distortion_model: {model!r} is not supported; expected radial-tangential"
        )
    dist = (
        np.zeros(4)
        if model == "none"
        else _numbers(path, data, "distortion_coefficients", 4, "[k1, k2, p1, p2]")
    )
    width, height = _numbers(path, data, "resolution", 2, "[width, height]")
    if width < 1 or height < 1 or width != int(width) or height != int(height):
        raise AslError(f"{path}: key resolution: expected two positive whole numbers, got {[width, height]}")
    K = np.array([[fu, 0.0, cu], [0.0, fv, cv], [0.0, 0.0, 1.0]])
    return CameraCalibration(T, K, dist, (int(width), int(height)))


def rectify(left: CameraCalibration, right: CameraCalibration, where: Path) -> Rectification:
    """OpenCV's rectification of a calibrated pair (``stereoRectify`` with zero disparity at
    infinity, ``alpha = 0``: only valid pixels), its maps, and the rectified stereo camera."""
    if left.resolution != right.resolution:
        raise AslError(
            f"{where}: cam0 is {left.resolution[0]}x{left.resolution[1]} but cam1 is "
            f"{right.resolution[0]}x{right.resolution[1]} (key resolution); expected one size"
        )
    T_right_left = np.linalg.inv(right.T_BS) @ left.T_BS  # left camera -> right camera
    size = left.resolution
    R = np.ascontiguousarray(T_right_left[:3, :3])
    t = T_right_left[:3, 3:].copy()
    R1, R2, P1, P2, _, _, _ = cv2.stereoRectify(
        left.K,
        left.distortion,
        right.K,
        right.distortion,
        size,
        R,
        t,
        flags=cv2.CALIB_ZERO_DISPARITY,
        alpha=0.0,
    )
    try:
        camera = StereoCamera.from_projection_matrices(P1, P2, *size)
    except ValueError as exc:
        raise AslError(f"{where}: cam1 is not to the right of cam0 in T_BS ({exc})") from None
    maps = [
        cv2.initUndistortRectifyMap(c.K, c.distortion, R, P, size, cv2.CV_16SC2)
        for c, R, P in ((left, R1, P1), (right, R2, P2))
    ]
    T_left_rect = np.eye(4)
    T_left_rect[:3, :3] = R1.T  # rectified -> raw left camera
    return Rectification(tuple(maps[0]), tuple(maps[1]), camera, left.T_BS @ T_left_rect)


def read_image_list(camera_dir: Path) -> tuple[np.ndarray, list[Path]]:
    """``(timestamps in ns, image files)`` of one camera from its ``data.csv``."""
    csv_path = camera_dir / "data.csv"
    if not camera_dir.is_dir():
        raise AslError(f"{camera_dir}: missing camera folder (data/, data.csv, sensor.yaml)")
    if not csv_path.is_file():
        raise AslError(f"{csv_path}: missing (one line 'timestamp [ns],filename' per image)")
    stamps, files = [], []
    for n, line in enumerate(csv_path.read_text(encoding="utf-8-sig").split("\n"), start=1):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        stamp, sep, name = line.partition(",")
        if not sep or not stamp.strip().isdigit() or not name.strip():
            raise AslError(f"{csv_path}, line {n}: expected 'timestamp [ns],filename', got {line[:50]!r}")
        stamps.append(int(stamp))
        files.append(camera_dir / "data" / name.strip())
    if not stamps:
        raise AslError(f"{csv_path}: no images listed")
    order = np.diff(stamps)
    if np.any(order <= 0):
        n = int(np.flatnonzero(order <= 0)[0]) + 1
        raise AslError(f"{csv_path}: timestamp {stamps[n]} does not come after {stamps[n - 1]}")
    return np.array(stamps, dtype=np.int64), files


def pair_by_timestamp(mav0: Path) -> tuple[np.ndarray, list[Path], list[Path]]:
    """Left and right images of equal timestamps; a timestamp on one side only is an error."""
    t0, left = read_image_list(mav0 / "cam0")
    t1, right = read_image_list(mav0 / "cam1")
    only = np.setxor1d(t0, t1)
    if len(only):
        side = "cam0" if only[0] in set(t0.tolist()) else "cam1"
        raise AslError(
            f"{mav0 / side / 'data.csv'}: timestamp {int(only[0])} has no image of the same timestamp on "
            f"the other camera ({len(only)} unpaired); the two cameras must be triggered together"
        )
    for path in (left[0], right[0], left[-1], right[-1]):
        if not path.is_file():
            raise AslError(f"{path}: listed in data.csv but missing")
    return t0, left, right


def find_groundtruth(mav0: Path) -> Path | None:
    """The first ground-truth file of :data:`GROUND_TRUTH_FILES` present under ``mav0``."""
    return next((mav0 / name for name in GROUND_TRUTH_FILES if (mav0 / name).is_file()), None)


def truth_extrinsic(truth_path: Path) -> np.ndarray:
    """``T_BS`` of the ``sensor.yaml`` beside a ground-truth file (the tracked frame in the body),
    or the identity where there is none."""
    sensor = truth_path.parent / "sensor.yaml"
    if not sensor.is_file():
        return np.eye(4)
    T = _numbers(sensor, _yaml(sensor), "T_BS", 16, "a 4x4 transform, data: [16 numbers]").reshape(4, 4)
    problem = rotation_problem(T[:3, :3])
    if problem:
        raise AslError(f"{sensor}: key T_BS: {problem}")
    return T


def body_to_rectified_camera(path) -> np.ndarray:
    """``T_body_rect``: the rectified left camera of the ASL recording at ``path`` in its body frame."""
    mav0 = mav0_of(path)
    if mav0 is None:
        raise AslError(f"{path}: no mav0/cam0 or cam0 folder; expected the ASL layout")
    calib = [read_camera_yaml(mav0 / side / "sensor.yaml") for side in ("cam0", "cam1")]
    return rectify(*calib, mav0).T_body_rect


def read_asl(path, groundtruth=None) -> Sequence:
    """Read an ASL recording as a rectified :class:`~vo_lib.formats.sequence.Sequence`.

    The 6-DoF ground truth (``groundtruth`` or the first of :data:`GROUND_TRUTH_FILES`) becomes
    ``poses``: the rectified left camera at each image in its first pose. Position-only ground
    truth is kept in ``manifest["positions"]`` (for an alignment; see :mod:`vo_lib.evaluation`).
    """
    root = Path(path)
    mav0 = mav0_of(root)
    if mav0 is None:
        raise AslError(f"{root}: no mav0/cam0 or cam0 folder; expected the ASL layout")
    for side in ("cam0", "cam1"):
        if not (mav0 / side).is_dir():
            raise AslError(f"{mav0 / side}: missing camera folder (data/, data.csv, sensor.yaml)")
    calib = [read_camera_yaml(mav0 / side / "sensor.yaml") for side in ("cam0", "cam1")]
    rect = rectify(*calib, mav0)
    stamps, left, right = pair_by_timestamp(mav0)
    width, height, _ = image_header(left[0], 0)
    if (width, height) != calib[0].resolution:
        raise AslError(
            f"{left[0]}: {width}x{height} image but {mav0 / 'cam0' / 'sensor.yaml'} says resolution "
            f"{calib[0].resolution[0]}x{calib[0].resolution[1]}"
        )
    seconds = stamps * NANOSECONDS
    manifest = {
        "layout": "asl",
        "time_origin_s": float(seconds[0]),
        "T_body_camera": rect.T_body_rect.tolist(),
    }
    truth_path = Path(groundtruth) if groundtruth else find_groundtruth(mav0)
    poses = None
    if truth_path is not None:
        poses = _truth_into_camera(truth_path, seconds, rect.T_body_rect, manifest)
    return Sequence(root, rect.camera, seconds - seconds[0], left, right, poses, None, manifest, rect)


def _truth_into_camera(truth_path: Path, seconds, T_body_rect, manifest: dict):
    """The ground truth at the images, in the rectified left camera (6-DoF); or, for positions
    only, the positions and the lever arm put into ``manifest``."""
    try:
        truth = read_groundtruth(truth_path)
        i_img, i_gt = covering(truth, seconds)
    except GroundTruthError as exc:
        raise AslError(str(exc)) from None
    extrinsic = truth_extrinsic(truth_path)  # the tracked frame (prism, body) in the body
    if truth.kind is TruthKind.POSES:
        body = truth.poses[i_gt] @ np.linalg.inv(extrinsic)  # body in the world
        return to_camera(body, T_body_rect)
    lever = np.linalg.inv(T_body_rect) @ extrinsic[:, 3]  # the prism in the rectified camera
    manifest["positions"] = {
        "file": str(truth_path),
        "frames": i_img.tolist(),
        "xyz": truth.positions[i_gt].tolist(),
        "lever_arm_camera": lever[:3].tolist(),
    }
    return None
