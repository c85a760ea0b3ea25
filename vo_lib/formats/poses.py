"""Pose files: KITTI (12 numbers a line, the top three rows of each pose) and TUM
(``timestamp tx ty tz qx qy qz qw``, as evo reads it). Poses are ``(N, 4, 4)`` or ``(N, 3, 4)``.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from vo_lib.geometry import as_homogeneous


def _rigid(poses) -> tuple[np.ndarray, Rotation]:
    """``(N, 4, 4)`` poses and their rotations made orthonormal (a product of many motions drifts off
    SO(3) by ``1e-5``, which readers of a file would each read differently)."""
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
    rows = np.column_stack([np.asarray(times, float), T[:, :3, 3], rotations.as_quat()])  # q: x y z w
    Path(path).write_text("".join(" ".join(f"{v:.9f}" for v in row) + "\n" for row in rows))


class TrajectoryError(ValueError):
    """A file of any format here that cannot be read (file and line or key named)."""


#: Largest entry of ``R^T R - I`` accepted, and largest difference of a quaternion's norm from 1
#: (files round numbers; beyond, a file holds something else).
ROTATION_TOLERANCE = 1e-2
QUATERNION_TOLERANCE = 1e-2
#: Largest coordinate accepted (m): beyond it, squared distances overflow in the alignment.
MAX_POSITION = 1e9
#: Largest file read (bytes): a 200 Hz EuRoC CSV of an hour is about 70 MB (12 times that in memory).
MAX_FILE_BYTES = 100_000_000
#: Widths of a row of a text file: KITTI pose, TUM (``t x y z qx qy qz qw``), position (``t x y z``).
TEXT_WIDTHS = {12: "12 numbers (KITTI)", 8: "8 (TUM: t x y z qx qy qz qw)", 4: "4 (t x y z)"}


def rotation_problem(R: np.ndarray) -> str | None:
    """None if the 3x3 ``R`` is a rotation within :data:`ROTATION_TOLERANCE`, else what is wrong."""
    with np.errstate(all="ignore"):  # huge entries overflow: not a rotation either
        off = float(np.max(np.abs(R.T @ R - np.eye(3))))
    if not off <= ROTATION_TOLERANCE:
        return f"the first three columns are not a rotation matrix (R^T R differs from I by {off:.3g})"
    if np.linalg.det(R) < 0:
        return "the first three columns are a reflection, not a rotation (determinant -1)"
    return None


def rigid_problem(T: np.ndarray) -> str | None:
    """None if the 4x4 ``T`` is a rigid transform (:func:`rotation_problem`), else what is wrong."""
    return rotation_problem(T[:3, :3]) or (
        None if np.allclose(T[3], [0, 0, 0, 1]) else "the last row is not 0 0 0 1"
    )


def check_file(path: Path, what: str = "the file", optional: bool = False) -> bool:
    """Raise :class:`TrajectoryError` unless ``path`` is a regular file: missing, or what is there;
    ``optional``: whether it is there (False where nothing is, a file or not)."""
    if optional and not os.path.lexists(path):
        return False
    if not Path(path).is_file():
        kind = "a folder" if Path(path).is_dir() else "not a regular file" if os.path.lexists(path) else None
        raise TrajectoryError(
            f"{path}: {kind}, where {what} should be a file" if kind else f"{path}: missing ({what})"
        )
    return True


def read_text(path, what: str = "the file") -> str:
    """The UTF-8 text of a file (without a byte-order mark); else :class:`TrajectoryError`."""
    path = Path(path)
    check_file(path, what)
    if (size := path.stat().st_size) > MAX_FILE_BYTES:
        raise TrajectoryError(f"{path}: {size / 1e6:.0f} MB; expected below {MAX_FILE_BYTES / 1e6:.0f} MB")
    if size == 0:  # nothing to read (and a kernel file such as /proc/kmsg, which says 0, would block)
        return ""
    try:
        return path.read_bytes().decode("utf-8-sig")
    except OSError as exc:
        raise TrajectoryError(f"{path}: cannot read ({exc.strerror or exc})") from None
    except UnicodeDecodeError as exc:
        raise TrajectoryError(f"{path}: not a text file (byte {exc.start} is not UTF-8)") from None


def data_lines(path: Path, what: str = "the file") -> list[tuple[int, str]]:
    """``(line number, text)`` of the lines neither blank nor comments (``#``, ``%``)."""
    text = read_text(path, what).replace("\r\n", "\n").replace("\r", "\n").split("\n")
    return [(n, s) for n, line in enumerate(text, 1) if (s := line.strip()) and not s.startswith(("#", "%"))]


def _row(path: Path, n: int, line: str, comma: bool, first: tuple[int, int] | None) -> list[float]:
    """The numbers of line ``n``: as many as the ``first`` row's (count, line), else a known width."""
    try:
        values = [float(v) for v in (line.split(",") if comma else line.split())]
    except ValueError:
        raise TrajectoryError(f"{path}, line {n}: not a row of numbers") from None
    if first and len(values) != first[0]:
        raise TrajectoryError(
            f"{path}, line {n}: expected {first[0]} numbers like line {first[1]}, got {len(values)}"
        )
    if not first and (len(values) < 4 if comma else len(values) not in TEXT_WIDTHS):
        *some, last = TEXT_WIDTHS.values()
        expected = "t[ns], x, y, z[, ...]" if comma else f"{', '.join(some)} or {last}"
        raise TrajectoryError(f"{path}, line {n}: expected {expected}, got {len(values)}")
    return values


def _refuse(path: Path, lines: list[int], bad: np.ndarray, what) -> None:
    """One line naming the first ``bad`` row: ``what``, or ``what(k)`` of that row ``k``."""
    if bad.any():
        k = int(np.argmax(bad))
        raise TrajectoryError(f"{path}, line {lines[k]}: {what(k) if callable(what) else what}")


def _check(path: Path, a: np.ndarray, rows: list[tuple[int, str]], comma: bool) -> None:
    """Every row finite, a rotation (KITTI) or a unit quaternion, a position within
    :data:`MAX_POSITION`, timestamps increasing; else the first bad row is named."""
    lines = [n for n, _ in rows]
    _refuse(path, lines, ~np.isfinite(a).all(axis=1), "holds a NaN or infinite value")
    if a.shape[1] == 12 and not comma:
        R = a.reshape(-1, 3, 4)[:, :, :3]
        with np.errstate(all="ignore"):  # huge entries overflow: not a rotation either
            off = np.abs(np.swapaxes(R, 1, 2) @ R - np.eye(3)).max(axis=(1, 2))
            bad = ~(off <= ROTATION_TOLERANCE) | (np.linalg.det(R) < 0)
            _refuse(path, lines, bad, lambda k: rotation_problem(R[k]))
    else:
        _check_stamped(path, a, rows, comma)
    positions = a[:, 3::4] if a.shape[1] == 12 and not comma else a[:, 1:4]
    _refuse(
        path, lines, np.abs(positions).max(axis=1) > MAX_POSITION, f"a position beyond {MAX_POSITION:g} m"
    )


def _check_stamped(path: Path, a: np.ndarray, rows: list[tuple[int, str]], comma: bool) -> None:
    """Rows with a timestamp first (TUM, EuRoC, positions): increasing times, unit quaternions; the
    first row with either problem is named (its time first: a KITTI file with commas is told so)."""
    t, lines = a[:, 0], [n for n, _ in rows]
    late = np.concatenate([[False], np.diff(t) <= 0])
    with np.errstate(all="ignore"):  # huge entries overflow: no unit quaternion either
        norm = np.linalg.norm(a[:, 4:8], axis=1) if a.shape[1] >= 8 else np.ones(len(a))
    kitti = "; 12 numbers a row, as KITTI poses? they are separated by spaces, not commas"

    def problem(k: int) -> str:
        if not late[k]:
            tolerance = f"norm 1 within {QUATERNION_TOLERANCE:g}"
            return f"the quaternion's norm is {norm[k]:.4g}; expected a unit quaternion ({tolerance})"
        now, before = (re.split(r"[\s,]+", rows[j][1])[0] for j in (k, k - 1))  # as written, not rounded
        order = "comes before" if t[k] < t[k - 1] else "repeats" if now == before else "rounds to the time of"
        return (
            f"timestamp {now} {order} the one on line {lines[k - 1]} ({before}); timestamps must increase"
            + (kitti if comma and a.shape[1] == 12 else "")
        )

    _refuse(path, lines, late | ~(np.abs(norm - 1.0) <= QUATERNION_TOLERANCE), problem)


def read_rows(path, min_rows: int = 1) -> tuple[np.ndarray, list[int], bool]:
    """The rows of a trajectory file, checked (:func:`_check`), their line numbers, and whether the
    file is a CSV (commas in its first row). Comments and a first line of names are skipped. Any
    problem, and fewer than ``min_rows`` rows, raises one :class:`TrajectoryError`."""
    path = Path(path)
    rows = data_lines(path, "the trajectory")
    header = None
    if rows and re.match(r"[A-Za-z_]", rows[0][1]) and not re.match(r"(?i)(nan|inf)\b", rows[0][1]):
        header, rows = rows[0], rows[1:]  # a first line of names without '#' (timestamp,px,...): a header
    if not rows:
        names = f" (line {header[0]}, {header[1][:40]!r}, reads as a header of names)" if header else ""
        raise TrajectoryError(f"{path}: no poses{names}")
    lines, comma = [n for n, _ in rows], "," in rows[0][1]
    width = len(_row(path, *rows[0], comma, None))  # a width the formats know
    try:  # every row at once; where that fails, row by row, to name the first bad line
        a = np.loadtxt([line for _, line in rows], delimiter="," if comma else None, comments=None, ndmin=2)
    except ValueError:
        a = np.array([_row(path, n, line, comma, (width, lines[0])) for n, line in rows])
    if len(rows) < min_rows:
        plural = "s" * (len(rows) != 1)
        raise TrajectoryError(
            f"{path}: {len(rows)} pose{plural} (last on line {lines[-1]}); need at least {min_rows}"
        )
    _check(path, a, rows, comma)
    return a, lines, comma
