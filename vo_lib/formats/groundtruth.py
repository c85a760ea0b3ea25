"""Ground truth in the common formats, associated with the images by timestamp.

Formats, told apart by their rows:

========================  ===========================================================  =========
format                    one row                                                       holds
========================  ===========================================================  =========
KITTI poses               12 numbers: the top three rows of a 4x4 pose, one per image   poses
TUM trajectory            ``t tx ty tz qx qy qz qw`` (seconds; quaternion x y z w)      poses
EuRoC ground-truth CSV    ``t[ns], px, py, pz, qw, qx, qy, qz[, velocities, biases]``   poses
positions (CSV or text)   ``t, x, y, z`` (a laser tracker's prism, a GPS antenna)       positions
========================  ===========================================================  =========

A CSV is a file whose first data row holds commas; its timestamps are nanoseconds (EuRoC's
``leica0/data.csv`` and ``state_groundtruth_estimate0/data.csv``), a text file's are seconds.
Poses are of the frame the file states (a body frame, or a camera); :func:`to_camera` moves them
into a camera with the extrinsic ``T_body_camera``. Association follows evo
(``evo.core.sync.associate_trajectories``): every query time takes the nearest ground-truth
time within ``max_diff`` seconds.

Every problem raises one :class:`GroundTruthError` naming the file and line.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from vo_lib.formats.poses import MAX_POSITION, TrajectoryError, read_text, read_trajectory

#: Largest time difference (s) at which a ground-truth sample is associated with an image: evo's
#: default ``max_diff``.
MAX_TIME_DIFF_S = 0.01
#: Largest ground-truth file read (bytes): a 200 Hz EuRoC CSV of an hour is about 70 MB.
MAX_FILE_BYTES = 200_000_000
NANOSECONDS = 1e-9


class GroundTruthError(ValueError):
    """A ground-truth file that cannot be read or does not cover the images (file and line named)."""


class TruthKind(str, Enum):
    """What a ground-truth file holds."""

    POSES = "poses"  #: full 6-DoF poses
    POSITIONS = "positions"  #: positions only (a tracked prism, an antenna)

    def __str__(self) -> str:
        return self.value


@dataclass(frozen=True)
class GroundTruth:
    """A ground truth as read: ``times`` in seconds (None for KITTI poses, one per image),
    ``poses`` ``(N, 4, 4)`` of the file's frame in its world (None for positions only) and
    ``positions`` ``(N, 3)``."""

    path: Path
    kind: TruthKind
    times: np.ndarray | None
    positions: np.ndarray
    poses: np.ndarray | None = None


def _check_size(path: Path) -> None:
    if not path.is_file():
        what = "a folder, not a trajectory file" if path.is_dir() else "no such trajectory file"
        raise GroundTruthError(f"{path}: {what}")
    size = path.stat().st_size
    if size > MAX_FILE_BYTES:
        raise GroundTruthError(
            f"{path}: {size / 1e6:.0f} MB; a ground-truth file is expected below "
            f"{MAX_FILE_BYTES / 1e6:.0f} MB"
        )


def _text_rows(path: Path) -> list[tuple[int, str]]:
    """The numbered rows of the file, comments (``#``, ``%``) and blank lines left out."""
    try:
        text = read_text(path)
    except TrajectoryError as exc:
        raise GroundTruthError(str(exc)) from None
    return [
        (n, line.strip())
        for n, line in enumerate(text.split("\n"), start=1)
        if line.strip() and not line.lstrip().startswith(("#", "%"))
    ]


def _parse(path: Path, rows: list[tuple[int, str]], comma: bool) -> np.ndarray:
    """The rows as one float array; a row of another width, a non-number or a non-finite value
    raises naming its line."""
    out, width = [], None
    for n, line in rows:
        parts = [p for p in (line.split(",") if comma else line.split())]
        try:
            values = [float(p) for p in parts]
        except ValueError:
            raise GroundTruthError(f"{path}, line {n}: not a row of numbers") from None
        if width is None:
            width = len(values)
        if len(values) != width:
            raise GroundTruthError(f"{path}, line {n}: {len(values)} numbers; the first row has {width}")
        if not np.all(np.isfinite(values)):
            raise GroundTruthError(f"{path}, line {n}: holds a NaN or infinite value")
        out.append(values)
    return np.array(out)


def _check_times(path: Path, times: np.ndarray, rows: list[tuple[int, str]]) -> None:
    bad = np.flatnonzero(np.diff(times) <= 0)
    if len(bad):
        k = int(bad[0]) + 1
        raise GroundTruthError(
            f"{path}, line {rows[k][0]}: timestamp does not come after the one on line {rows[k - 1][0]}; "
            "timestamps must increase"
        )


def _check_positions(path: Path, positions: np.ndarray, rows: list[tuple[int, str]]) -> None:
    far = np.flatnonzero(np.max(np.abs(positions), axis=1) > MAX_POSITION)
    if len(far):
        raise GroundTruthError(f"{path}, line {rows[int(far[0])][0]}: a position beyond {MAX_POSITION:g} m")


def _quaternion_poses(path: Path, positions, quat_xyzw, rows) -> np.ndarray:
    norm = np.linalg.norm(quat_xyzw, axis=1)
    zero = np.flatnonzero(norm < 1e-6)
    if len(zero):
        raise GroundTruthError(f"{path}, line {rows[int(zero[0])][0]}: the quaternion is zero")
    T = np.tile(np.eye(4), (len(positions), 1, 1))
    T[:, :3, :3] = Rotation.from_quat(quat_xyzw / norm[:, None]).as_matrix()
    T[:, :3, 3] = positions
    return T


def read_groundtruth(path, min_poses: int = 2) -> GroundTruth:
    """Read a KITTI, TUM, EuRoC CSV or position-only ground truth (see the module's table) of at
    least ``min_poses`` rows."""
    path = Path(path)
    _check_size(path)
    rows = _text_rows(path)
    if not rows:
        raise GroundTruthError(f"{path}: no rows")
    comma = "," in rows[0][1]
    if not comma and len(rows[0][1].split()) in (8, 12):
        try:
            times, poses = read_trajectory(path, min_poses=min_poses)
        except TrajectoryError as exc:
            raise GroundTruthError(str(exc)) from None
        return GroundTruth(path, TruthKind.POSES, times, poses[:, :3, 3].copy(), poses)
    if len(rows) < min_poses:
        raise GroundTruthError(
            f"{path}: {len(rows)} row{'s' * (len(rows) != 1)} (last on line {rows[-1][0]}); "
            f"need at least {min_poses}"
        )
    a = _parse(path, rows, comma)
    width = a.shape[1]
    if width < 4 or (not comma and width != 4):
        expected = (
            "t[ns], x, y, z (positions) or t[ns], x, y, z, qw, qx, qy, qz (EuRoC)"
            if comma
            else "12 numbers (KITTI), 8 (TUM: t x y z qx qy qz qw) or 4 (t x y z)"
        )
        raise GroundTruthError(f"{path}, line {rows[0][0]}: {width} numbers; expected {expected}")
    times = a[:, 0] * (NANOSECONDS if comma else 1.0)
    _check_times(path, a[:, 0], rows)
    positions = a[:, 1:4]
    _check_positions(path, positions, rows)
    if width < 8:
        return GroundTruth(path, TruthKind.POSITIONS, times, positions)
    poses = _quaternion_poses(path, positions, a[:, [5, 6, 7, 4]], rows)  # EuRoC: qw qx qy qz
    return GroundTruth(path, TruthKind.POSES, times, positions, poses)


def associate(query_times, truth_times, max_diff: float = MAX_TIME_DIFF_S) -> tuple[np.ndarray, np.ndarray]:
    """Indices ``(i_query, i_truth)`` of the pairs whose times differ by less than ``max_diff``
    seconds, each query time taking its nearest truth time, as evo's ``associate_trajectories``."""
    q, t = np.asarray(query_times, float), np.asarray(truth_times, float)
    right = np.clip(np.searchsorted(t, q), 1, len(t) - 1) if len(t) > 1 else np.zeros(len(q), int)
    left = np.maximum(right - 1, 0)
    nearest = np.where(np.abs(t[left] - q) <= np.abs(t[right] - q), left, right)
    keep = np.abs(t[nearest] - q) < max_diff
    return np.flatnonzero(keep), nearest[keep]


def covering(truth: GroundTruth, times, max_diff: float = MAX_TIME_DIFF_S) -> tuple[np.ndarray, np.ndarray]:
    """:func:`associate` the images at ``times`` (seconds, the file's clock) with ``truth``,
    checked: the truth must span the images, and a 6-DoF truth must match every image."""
    times = np.asarray(times, float)
    if truth.times is None:
        if len(truth.positions) != len(times):
            raise GroundTruthError(
                f"{truth.path}: {len(truth.positions)} poses but there are {len(times)} images; "
                "a file without timestamps needs one pose per image"
            )
        return np.arange(len(times)), np.arange(len(times))
    t0, t1 = truth.times[0], truth.times[-1]
    if times[0] < t0 - max_diff or times[-1] > t1 + max_diff:
        raise GroundTruthError(
            f"{truth.path}: covers {t0:.3f} to {t1:.3f} s but the images span {times[0]:.3f} to "
            f"{times[-1]:.3f} s; the ground truth must cover every image"
        )
    i_img, i_gt = associate(times, truth.times, max_diff)
    if truth.kind is TruthKind.POSES and len(i_img) < len(times):
        missing = int(np.setdiff1d(np.arange(len(times)), i_img)[0])
        raise GroundTruthError(
            f"{truth.path}: no pose within {max_diff} s of image {missing} (t = {times[missing]:.3f} s); "
            "the ground truth must cover every image"
        )
    if len(i_img) < 3:
        raise GroundTruthError(
            f"{truth.path}: only {len(i_img)} positions within {max_diff} s of an image; need at least 3"
        )
    return i_img, i_gt


def to_camera(poses, T_body_camera) -> np.ndarray:
    """Poses of a body frame in the world ``(N, 4, 4)`` made poses of a camera fixed on it,
    relative to the camera's first pose: ``C_k = (W_0 X)^-1 W_k X`` with ``X = T_body_camera``."""
    X = np.asarray(T_body_camera, float)
    C = np.asarray(poses, float) @ X
    return np.linalg.inv(C[0]) @ C
