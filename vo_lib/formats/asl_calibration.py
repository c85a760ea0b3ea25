"""A camera's calibration in the ASL layout of EuRoC (and Kalibr), and the checked stereo
rectification of two (:func:`vo_lib.camera.rectify_stereo`).

``sensor.yaml`` holds ``T_BS`` (camera to body, 4x4), ``intrinsics`` ``[fu, fv, cu, cv]``,
``distortion_model`` (radial-tangential, or a fisheye's equidistant), ``distortion_coefficients``
(Kalibr's ``distortion_coeffs``) and ``resolution``. A problem raises one :class:`AslError`.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml
from scipy.spatial.transform import Rotation

from vo_lib.atomic import notice
from vo_lib.camera import Rectification, rectify_stereo, undistorted_share
from vo_lib.formats.frame_files import (
    MAX_MOUNT_M,
    MIN_BASELINE_M,
    SequenceError,
    check_metres,
    focal_problem,
    numbers_at,
    read_text,
)
from vo_lib.formats.images import MAX_IMAGE_SIDE
from vo_lib.formats.poses import rigid_problem

#: Largest angle between the baseline and cam0's image rows: rectifying a steeper rig turns the
#: images so far that little of them is left.
MAX_BASELINE_TILT_DEG = 20.0
#: Largest angle between the two cameras' axes: a stereo rig's cameras look the same way.
MAX_CAMERA_TURN_DEG = 30.0
#: Least share of a raw image in view once rectified: a calibration of other images, or a principal
#: point by a corner, leaves a sliver.
MIN_VALID_SHARE = 0.25
#: Largest distortion coefficient taken as a lens's (real ones stay below 1 or so).
MAX_DISTORTION = 100.0
#: Bound of each number of a transform (a rotation's are at most 1): a camera a kilometre from its body
#: is no rig's (the bound of a rectified copy's manifest.json; far beyond, products overflow).
MAX_TRANSFORM_ENTRY = MAX_MOUNT_M


AslError = SequenceError


@dataclass(frozen=True)
class CameraCalibration:
    """One camera's ``sensor.yaml``: ``T_BS`` (camera to body), ``K``, ``distortion``
    (radial-tangential ``[k1, k2, p1, p2]``, or equidistant ``[k1, k2, k3, k4]`` where
    ``fisheye``) and ``resolution`` ``(width, height)``."""

    T_BS: np.ndarray
    K: np.ndarray
    distortion: np.ndarray
    resolution: tuple[int, int]
    fisheye: bool = False


ALIAS = "an alias (*name, or a merge <<: *name): valid YAML, but not read here; write the values out"


class _UniqueKeys(yaml.SafeLoader):
    """YAML as ``safe_load`` reads it, but a key given twice in one mapping is an error, and a
    number written without a point (``1e-05``) is a number, as in YAML 1.2, not a text."""

    def compose_node(self, parent, index):
        if self.check_event(yaml.AliasEvent):  # *name repeats a value: a few lines can expand to gigabytes
            raise yaml.composer.ComposerError(None, None, ALIAS, self.peek_event().start_mark)
        return super().compose_node(parent, index)

    def construct_mapping(self, node, deep=False):
        seen = []
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=deep)
            if key in seen:
                raise yaml.constructor.ConstructorError(
                    problem=f"key {key!r} given twice", problem_mark=key_node.start_mark
                )
            seen.append(key)
        return super().construct_mapping(node, deep)


# Numbers as YAML 1.2 writes them, and no others: 1e-05, 1.5e2 and -.5 are floats (YAML 1.1 wants
# 1.0e+2), 0480 is 480 (not base 8), and 7:38 or 4_58 are texts (458 to YAML 1.1)
INT, FLOAT = "tag:yaml.org,2002:int", "tag:yaml.org,2002:float"
_UniqueKeys.yaml_implicit_resolvers = {
    first: [(tag, regexp) for tag, regexp in resolvers if tag not in (INT, FLOAT)]
    for first, resolvers in yaml.SafeLoader.yaml_implicit_resolvers.items()
}
_UniqueKeys.add_implicit_resolver(INT, re.compile(r"^[-+]?[0-9]+$"), list("-+0123456789"))
_UniqueKeys.add_implicit_resolver(
    FLOAT, re.compile(r"^[-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?$"), list("-+.0123456789")
)
_UniqueKeys.add_constructor(INT, lambda loader, node: int(loader.construct_scalar(node)))


def _yaml(path: Path) -> dict:
    text = read_text(path, "the sensor's calibration (T_BS, intrinsics, distortion)")
    try:
        data = yaml.load(text, Loader=_UniqueKeys)  # noqa: S506 (a SafeLoader)
    except (yaml.YAMLError, RecursionError, ValueError) as exc:  # nested too deep, a number too long
        mark = getattr(exc, "problem_mark", None)
        where = f", line {mark.line + 1}" if mark is not None else ""
        problem = getattr(exc, "problem", None) or exc
        context, begun = getattr(exc, "context", None), getattr(exc, "context_mark", None)
        if context and begun is not None and mark is not None and begun.line != mark.line:
            problem = f"{problem}, {context} begun on line {begun.line + 1}"  # an unclosed [ or "
        raise AslError(
            f"{path}{where}: {problem}" if problem == ALIAS else f"{path}{where}: not valid YAML ({problem})"
        ) from None
    if not isinstance(data, dict):
        got = "an empty file" if data is None else f"a {type(data).__name__}"
        raise AslError(f"{path}: expected YAML keys (T_BS, intrinsics, ...), got {got}")
    return data


def _numbers(path: Path, data: dict, key: str, count: int, what: str, bound=np.inf) -> np.ndarray:
    """``count`` finite numbers at ``key`` (of a ``{rows, cols, data}`` matrix too), each within ``bound``."""
    value = data.get(key)
    if isinstance(value, dict) and "data" in value:  # T_BS: {rows, cols, data}
        shape = (value.get("rows", 4), value.get("cols", 4))
        if shape != (4, 4):
            raise AslError(
                f"{path}: key {key}: rows: {shape[0]!r}, cols: {shape[1]!r}; expected the numbers 4 and 4"
            )
        value = value.get("data")
    rows = value if isinstance(value, list) else []
    if count == 16 and [len(r) if isinstance(r, list) else 0 for r in rows] == [4] * 4:
        value = [x for row in value for x in row]  # four rows of four, as Kalibr writes a transform
    within = "" if np.isinf(bound) else f", each within ±{bound:g}"
    return numbers_at(path, key, value, (count,), f"{what} ({count} finite numbers{within})", (-bound, bound))


def _transform(path: Path, data: dict, what: str) -> np.ndarray:
    """Key ``T_BS``: a rigid transform (a rotation, the last row 0 0 0 1)."""
    if "T_BS" not in data and "T_cam_imu" in data:
        raise AslError(
            f"{path}: key T_BS missing; the file has Kalibr's T_cam_imu, which maps the body into the "
            "camera: expected T_BS, the camera into the body (the inverse of T_cam_imu)"
        )
    T = _numbers(path, data, "T_BS", 16, what, MAX_TRANSFORM_ENTRY).reshape(4, 4)
    if problem := rigid_problem(T):
        raise AslError(f"{path}: key T_BS: {problem}")
    T[:3, :3] = Rotation.from_matrix(T[:3, :3]).as_matrix()  # the nearest rotation: rounding scales none
    return T


def _distortion(path: Path, data: dict) -> tuple[np.ndarray, bool]:
    """``[k1, k2, p1, p2]`` of a radial-tangential model (zeros for ``distortion_model: none``) or
    ``[k1, k2, k3, k4]`` of an equidistant one, at the ASL key or at Kalibr's (``camchain.yaml``)
    when only that one is there; and whether the model is equidistant."""
    model = data.get("distortion_model", "radial-tangential")
    if model not in ("equidistant", "equi", "radial-tangential", "radtan", "none"):
        raise AslError(
            f"{path}: key distortion_model: {model!r} is not supported; "
            "expected radial-tangential (radtan), equidistant or none"
        )
    if "distortion_coeffs" in data and "distortion_coefficients" in data:
        raise AslError(f"{path}: keys distortion_coefficients and distortion_coeffs both given; expected one")
    key = "distortion_coeffs" if "distortion_coeffs" in data else "distortion_coefficients"
    if model in ("equidistant", "equi"):
        return _numbers(path, data, key, 4, "[k1, k2, k3, k4]", MAX_DISTORTION), True
    return _radial_tangential(path, data, key, model), False


def _radial_tangential(path: Path, data: dict, key: str, model: str) -> np.ndarray:
    """``[k1, k2, p1, p2]`` at ``key``; zeros for ``model`` none (none given, or an empty list)."""
    if model == "none" and data.get(key) in (None, []):
        return np.zeros(4)
    if isinstance(data.get(key), list) and len(data[key]) == 5:
        raise AslError(
            f"{path}: key {key}: expected [k1, k2, p1, p2], got 5 numbers (OpenCV's order, with k3 last?): "
            "the radial-tangential model of the ASL layout has no k3"
        )
    dist = _numbers(path, data, key, 4, "[k1, k2, p1, p2]", MAX_DISTORTION)
    if model == "none" and dist.any():
        raise AslError(
            f"{path}: key distortion_model: none, but key {key} is not zero; "
            "expected radial-tangential for these coefficients, or zeros"
        )
    return dist


def _image_size(path: Path, data: dict) -> tuple[int, int]:
    """Key ``resolution``: ``(width, height)``, two positive whole numbers."""
    width, height = _numbers(path, data, "resolution", 2, "[width, height]")
    if not (1 <= width <= MAX_IMAGE_SIDE and 1 <= height <= MAX_IMAGE_SIDE) or width % 1 or height % 1:
        raise AslError(
            f"{path}: key resolution: expected two whole numbers from 1 to {MAX_IMAGE_SIDE}, "
            f"got [{width:g}, {height:g}]"
        )
    return int(width), int(height)


def read_camera_yaml(path) -> CameraCalibration:
    """One camera's calibration from its ``sensor.yaml``; raises :class:`AslError` naming the key."""
    path = Path(path)
    data = _yaml(path)
    T = _transform(path, data, "a 4x4 camera-to-body transform as data")
    if data.get("camera_model", "pinhole") != "pinhole":
        raise AslError(
            f"{path}: key camera_model: {data['camera_model']!r} is not supported; expected pinhole"
        )
    fu, fv, cu, cv = _numbers(path, data, "intrinsics", 4, "[fu, fv, cu, cv]")
    if fu <= 0 or fv <= 0:
        raise AslError(f"{path}: key intrinsics: focal lengths must be > 0, got fu={fu:g}, fv={fv:g}")
    dist, fisheye = _distortion(path, data)
    width, height = _image_size(path, data)
    if problem := focal_problem(fu, fv, width):
        raise AslError(f"{path}: key intrinsics: {problem} (key resolution)")
    if not (0 <= cu <= width and 0 <= cv <= height):
        raise AslError(
            f"{path}: key intrinsics: principal point ({cu:g}, {cv:g}) outside the "
            f"{width:g}x{height:g} image (key resolution)"
        )
    K = np.array([[fu, 0.0, cu], [0.0, fv, cv], [0.0, 0.0, 1.0]])
    return CameraCalibration(T, K, dist, (width, height), fisheye)


def rectify(left: CameraCalibration, right: CameraCalibration, where: Path) -> Rectification:
    """:func:`~vo_lib.camera.rectify_stereo` of a pair, checked: one image size, two cameras that
    look the same way, a baseline in metres, cam1 to the right of cam0, most of each image in view
    once rectified, and the rectified principal point inside the images."""
    if left.resolution != right.resolution:
        raise AslError(
            f"{where}: cam0 is {left.resolution[0]}x{left.resolution[1]} but cam1 is "
            f"{right.resolution[0]}x{right.resolution[1]} (key resolution); expected one size"
        )
    if left.fisheye != right.fisheye:
        fisheye, other = ("cam0", "cam1") if left.fisheye else ("cam1", "cam0")
        raise AslError(
            f"{where / 'cam1' / 'sensor.yaml'}: key distortion_model: {fisheye}'s is equidistant but "
            f"{other}'s is not; expected one model for both cameras"
        )
    T_right_left = np.linalg.inv(right.T_BS) @ left.T_BS  # left camera -> right camera
    _check_turn(T_right_left, where / "cam1" / "sensor.yaml")
    cam1_in_cam0 = _check_baseline(T_right_left, where / "cam1" / "sensor.yaml")
    lenses = (left.K, left.distortion), (right.K, right.distortion)
    rect = rectify_stereo(*lenses, left.resolution, T_right_left, left.T_BS, fisheye=left.fisheye)
    if min(rect.valid_shares) < MIN_VALID_SHARE:
        raise AslError(_share_problem(left, right, min(rect.valid_shares), where))
    _check_rectified(rect, cam1_in_cam0, where)
    return rect


def _share_problem(left: CameraCalibration, right: CameraCalibration, share: float, where: Path) -> str:
    """The line for a pair that rectifies to a sliver of its images: it names the camera whose own
    calibration leaves little of its image once undistorted alone (a bad cam1 shrinks both views, as
    the two are rectified to one camera), or both where each alone is fine."""
    cameras = {"cam0": left, "cam1": right}
    alone = {s: undistorted_share(c.K, c.distortion, c.resolution, c.fisheye) for s, c in cameras.items()}
    bad = [s for s in cameras if alone[s] < MIN_VALID_SHARE]
    if bad:
        return (
            f"{where / min(bad, key=alone.get) / 'sensor.yaml'}: keys intrinsics and distortion_coefficients "
            f"leave {share:.0%} of the image in view once rectified; expected a calibration of these images"
        )
    return (
        f"{where / 'cam0' / 'sensor.yaml'} and {where / 'cam1' / 'sensor.yaml'}: keys intrinsics leave "
        f"{share:.0%} of the images in view once rectified together, though each camera alone keeps "
        f"{min(alone.values()):.0%}; expected one rig's intrinsics (focal lengths and principal points alike)"
    )


def _check_rectified(rect: Rectification, cam1_in_cam0: np.ndarray, where: Path) -> None:
    """One line when the rectified rig has cam1 on the left of cam0, or its principal point outside
    the images (as a rectified copy's ``calib.txt`` would be refused when read back)."""
    try:
        (cx, cy), (w, h) = (rect.camera.cx, rect.camera.cy), rect.size  # cam1 on the left of cam0 raises
    except ValueError:
        x, y, _ = cam1_in_cam0  # x right, y down
        raise AslError(
            f"{where}: the T_BS of cam0 and cam1 put cam1 {x:+.3g} m to the right of cam0 and {y:+.3g} m "
            "below it; expected cam1 to the right (are the folders swapped, or is T_BS inverted? it "
            "takes the camera's coordinates into the body's)"
        ) from None
    if not (0 <= cx <= w and 0 <= cy <= h):
        raise AslError(
            f"{where}: the intrinsics of cam0 and cam1 put the rectified principal point at ({cx:.0f}, "
            f"{cy:.0f}), outside the {w}x{h} images; expected principal points nearer their centres"
        )


def _check_baseline(T_right_left: np.ndarray, sensor: Path) -> np.ndarray:
    """cam1's position in cam0's frame (x right, y down, z ahead), checked: in metres, apart from
    cam0 and beside it along the image rows."""
    baseline = float(np.linalg.norm(T_right_left[:3, 3]))
    if baseline < MIN_BASELINE_M:
        raise AslError(
            f"{sensor}: key T_BS puts cam1 where cam0 is (baseline {baseline:.3g} m); "
            "expected two cameras apart"
        )
    check_metres(sensor, "key T_BS puts cam1 {} m from cam0", baseline)
    cam1_in_cam0 = np.linalg.inv(T_right_left)[:3, 3]
    x, y, z = np.round(cam1_in_cam0, 3) + 0.0
    if np.degrees(np.arctan2(np.hypot(y, z), abs(x))) > MAX_BASELINE_TILT_DEG:
        raise AslError(
            f"{sensor}: key T_BS puts cam1 {x:+.3f} m to the right of cam0, {y:+.3f} m below and "
            f"{z:+.3f} m ahead; expected cam1 beside cam0 along its image rows "
            f"(within {MAX_BASELINE_TILT_DEG:g}°; is T_BS inverted? it takes the camera's coordinates "
            "into the body's)"
        )
    return cam1_in_cam0


def _check_turn(T_right_left: np.ndarray, sensor: Path) -> None:
    """One line when the two cameras do not look the same way (within :data:`MAX_CAMERA_TURN_DEG`)."""
    turn = float(np.degrees(Rotation.from_matrix(T_right_left[:3, :3]).magnitude()))
    if turn > MAX_CAMERA_TURN_DEG:
        raise AslError(
            f"{sensor}: key T_BS turns cam1 {turn:.0f}° from cam0; expected two cameras that look the "
            f"same way (within {MAX_CAMERA_TURN_DEG:g}°; is its rotation inverted?)"
        )


def truth_extrinsic(truth_path: Path) -> np.ndarray:
    """``T_BS`` of the ``sensor.yaml`` beside a ground-truth file (the tracked frame in the body), or
    the identity (with a notice) where there is none."""
    sensor = truth_path.parent / "sensor.yaml"
    if not sensor.is_file():
        notice(f"{truth_path}: no sensor.yaml beside it; its poses or positions are taken as the body's")
        return np.eye(4)
    T = _transform(sensor, _yaml(sensor), "a 4x4 transform, data: [16 numbers]")
    lever = np.linalg.norm(T[:3, 3])
    check_metres(sensor, "key T_BS puts the tracked point {} from the body", lever)
    return T
