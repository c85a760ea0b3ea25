"""Pose files: KITTI (12 numbers a line, the top three rows of each pose) and TUM
(``timestamp tx ty tz qx qy qz qw``, as evo reads it). Poses are ``(N, 4, 4)`` or ``(N, 3, 4)``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from vo_lib.evaluation import as_4x4


def write_kitti_poses(path, poses) -> None:
    """12 numbers per line: the top three rows of each pose."""
    T = as_4x4(poses)[:, :3, :].reshape(-1, 12)
    Path(path).write_text("".join(" ".join(f"{v:.9e}" for v in row) + "\n" for row in T))


def write_tum(path, times, poses) -> None:
    """TUM trajectory format, as evo reads it: ``timestamp tx ty tz qx qy qz qw`` per line."""
    T = as_4x4(poses)
    q = Rotation.from_matrix(T[:, :3, :3]).as_quat()  # x, y, z, w
    rows = np.column_stack([np.asarray(times, float), T[:, :3, 3], q])
    Path(path).write_text("".join(" ".join(f"{v:.9f}" for v in row) + "\n" for row in rows))


def read_trajectory(path) -> tuple[np.ndarray | None, np.ndarray]:
    """Read a KITTI pose file (12 numbers a line) or a TUM file (8); returns ``(times, poses)``."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such trajectory file")
    rows = []
    for n, line in enumerate(path.read_text().splitlines(), start=1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        try:
            values = [float(v) for v in line.split()]
        except ValueError:
            raise ValueError(f"{path}, line {n}: not a row of numbers") from None
        if len(values) not in (8, 12) or (rows and len(values) != len(rows[0])):
            raise ValueError(f"{path}, line {n}: expected 12 numbers (KITTI) or 8 (TUM), got {len(values)}")
        rows.append(values)
    if not rows:
        raise ValueError(f"{path}: no poses")
    a = np.array(rows)
    if a.shape[1] == 12:
        return None, as_4x4(a.reshape(-1, 3, 4))
    T = np.tile(np.eye(4), (len(a), 1, 1))
    T[:, :3, :3] = Rotation.from_quat(a[:, 4:8]).as_matrix()
    T[:, :3, 3] = a[:, 1:4]
    return a[:, 0], T
