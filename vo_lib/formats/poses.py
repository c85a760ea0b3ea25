"""Pose files: KITTI (12 numbers a line, the top three rows of each pose) and TUM
(``timestamp tx ty tz qx qy qz qw``, as evo reads it). Poses are ``(N, 4, 4)`` or ``(N, 3, 4)``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from vo_lib.geometry import as_homogeneous


def _rigid(poses) -> tuple[np.ndarray, Rotation]:
    """``(N, 4, 4)`` poses and their rotations, each made exactly orthonormal (the nearest rotation,
    scipy's ``Rotation.from_matrix``): a product of many estimated motions drifts off SO(3) by
    ``1e-5``, which a file would otherwise keep and every reader would read differently."""
    T = as_homogeneous(poses)
    if T.ndim != 3 or T.shape[1:] != (4, 4):
        raise ValueError(f"poses must have shape (N, 3, 4) or (N, 4, 4); got {T.shape}")
    return T, Rotation.from_matrix(T[:, :3, :3])


def write_kitti_poses(path, poses) -> None:
    """12 numbers per line: the top three rows of each pose, its rotation made orthonormal."""
    T, rotations = _rigid(poses)
    rows = np.concatenate([rotations.as_matrix(), T[:, :3, 3:]], axis=2).reshape(-1, 12)
    Path(path).write_text("".join(" ".join(f"{v:.9e}" for v in row) + "\n" for row in rows))


def write_tum(path, times, poses) -> None:
    """TUM trajectory format, as evo reads it: ``timestamp tx ty tz qx qy qz qw`` per line."""
    T, rotations = _rigid(poses)
    q = rotations.as_quat()  # x, y, z, w
    rows = np.column_stack([np.asarray(times, float), T[:, :3, 3], q])
    Path(path).write_text("".join(" ".join(f"{v:.9f}" for v in row) + "\n" for row in rows))


class TrajectoryError(ValueError):
    """A trajectory file that cannot be read: missing, not text, or a malformed line (named)."""


#: Largest entry of ``R^T R - I`` accepted for the rotation part of a pose (files round numbers).
ROTATION_TOLERANCE = 1e-2
#: Largest coordinate accepted (m): beyond it, squared distances overflow in the alignment.
MAX_POSITION = 1e9


def rotation_problem(R: np.ndarray) -> str | None:
    """None if the 3x3 ``R`` is a rotation within :data:`ROTATION_TOLERANCE`, else what is wrong."""
    with np.errstate(all="ignore"):  # huge entries overflow: not a rotation either
        off = float(np.max(np.abs(R.T @ R - np.eye(3))))
    if not off <= ROTATION_TOLERANCE:
        return f"the first three columns are not a rotation matrix (R^T R differs from I by {off:.3g})"
    if np.linalg.det(R) < 0:
        return "the first three columns are a reflection, not a rotation (determinant -1)"
    return None


def _row(path: Path, n: int, line: str, first: tuple[int, int] | None) -> list[float]:
    """The numbers of line ``n``, checked: as many as the ``first`` row's (its count and line),
    finite, a rotation or a non-zero quaternion, a position within :data:`MAX_POSITION`."""
    try:
        values = [float(v) for v in line.split()]
    except ValueError:
        raise TrajectoryError(f"{path}, line {n}: not a row of numbers") from None
    if len(values) not in (8, 12) or (first and len(values) != first[0]):
        expected = f"{first[0]} numbers like line {first[1]}" if first else "12 numbers (KITTI) or 8 (TUM)"
        raise TrajectoryError(f"{path}, line {n}: expected {expected}, got {len(values)}")
    if not np.all(np.isfinite(values)):
        raise TrajectoryError(f"{path}, line {n}: holds a NaN or infinite value")
    position = values[3::4] if len(values) == 12 else values[1:4]
    if len(values) == 12:
        problem = rotation_problem(np.reshape(values, (3, 4))[:, :3])
    else:
        problem = None if np.max(np.abs(values[4:8])) > 1e-6 else "the quaternion qx qy qz qw is zero"
    if not problem and np.max(np.abs(position)) > MAX_POSITION:
        problem = f"a position beyond {MAX_POSITION:g} m"
    if problem:
        raise TrajectoryError(f"{path}, line {n}: {problem}")
    return values


def _check_increasing(path: Path, times: np.ndarray, lines: list[int]) -> None:
    """TUM timestamps must increase strictly (as ``times.txt``'s do): a repeated or earlier one
    pairs two poses with one time."""
    bad = np.flatnonzero(np.diff(times) <= 0)
    if len(bad):
        k = int(bad[0]) + 1
        what = "repeats" if times[k] == times[k - 1] else "comes before"
        raise TrajectoryError(
            f"{path}, line {lines[k]}: timestamp {times[k]:.9g} {what} the one on line {lines[k - 1]}; "
            "timestamps must increase"
        )


def read_trajectory(path, min_poses: int = 1) -> tuple[np.ndarray | None, np.ndarray]:
    """Read a KITTI pose file (12 numbers a line) or a TUM file (8); returns ``(times, poses)``.

    Empty lines and lines starting with ``#`` are skipped. Every other line must hold finite
    numbers, a rotation (KITTI) or a non-zero quaternion (TUM), and a position within
    :data:`MAX_POSITION`; any problem, and a file of fewer
    than ``min_poses`` poses, raises one :class:`TrajectoryError` naming the file and line.
    """
    path = Path(path)
    rows, lines = [], []
    for n, line in enumerate(read_text(path).split("\n"), start=1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        rows.append(_row(path, n, line, (len(rows[0]), lines[0]) if rows else None))
        lines.append(n)
    if len(rows) < max(min_poses, 1):
        if not rows:
            raise TrajectoryError(f"{path}: no poses")
        raise TrajectoryError(
            f"{path}: {len(rows)} pose{'s' * (len(rows) != 1)} (last on line {lines[-1]}); "
            f"need at least {min_poses}"
        )
    a = np.array(rows)
    if a.shape[1] == 12:
        return None, as_homogeneous(a.reshape(-1, 3, 4))
    _check_increasing(path, a[:, 0], lines)
    return a[:, 0], _tum_poses(a)


def read_text(path: Path) -> str:
    """The text of a trajectory file; a folder, a missing file, an unreadable or non-UTF-8 one
    raises :class:`TrajectoryError`."""
    if not path.is_file():
        what = "a folder, not a trajectory file" if path.is_dir() else "no such trajectory file"
        raise TrajectoryError(f"{path}: {what}")
    try:
        return path.read_bytes().decode("utf-8-sig")
    except OSError as exc:
        raise TrajectoryError(f"{path}: cannot read ({exc.strerror or exc})") from None
    except UnicodeDecodeError as exc:
        raise TrajectoryError(f"{path}: not a text file (byte {exc.start} is not UTF-8)") from None


def _tum_poses(a: np.ndarray) -> np.ndarray:
    """``(N, 4, 4)`` poses of TUM rows ``t x y z qx qy qz qw``."""
    T = np.tile(np.eye(4), (len(a), 1, 1))
    q = a[:, 4:8] / np.max(np.abs(a[:, 4:8]), axis=1, keepdims=True)  # no overflow in the norm
    T[:, :3, :3] = Rotation.from_quat(q).as_matrix()
    T[:, :3, 3] = a[:, 1:4]
    return T
