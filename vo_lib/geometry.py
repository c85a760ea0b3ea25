"""Frames, planar poses and angles: the conventions every other module relies on.

Conventions
-----------
* Units are metres and radians.
* Camera frame (OpenCV): x right, y down, z forward.
* Robot and world frames: x forward, y left, z up; yaw is counter-clockwise positive
  seen from above.
* A planar pose is ``(x, y, yaw)``; a full pose is a 4x4 homogeneous matrix.
* Angles are wrapped into ``[-pi, pi)`` by :func:`wrap_angle`, and only there.
"""

from __future__ import annotations

import math

import numpy as np

#: Rotation taking camera-frame coordinates to robot-frame coordinates for a camera that
#: looks along the robot's x axis: camera z -> robot x, camera x -> robot -y, camera y -> robot -z.
R_ROBOT_FROM_CAMERA = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])


def wrap_angle(angle):
    """Angles in radians (a float or an array) shifted by whole turns into ``[-pi, pi)``."""
    if isinstance(angle, float):  # one angle (the filter's hot path): the same sum, without an array
        return (float(angle) + math.pi) % (2.0 * math.pi) - math.pi
    wrapped = np.mod(np.asarray(angle, dtype=float) + np.pi, 2.0 * np.pi) - np.pi
    return float(wrapped) if wrapped.ndim == 0 else wrapped


def yaw_matrix(yaw: float) -> np.ndarray:
    """3x3 rotation about the z axis (up) by ``yaw``, counter-clockwise positive."""
    c, s = math.cos(yaw), math.sin(yaw)  # closed form: on the hot path, no Rotation object
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rigid_matrix(R, t) -> np.ndarray:
    """The 4x4 matrix ``[[R, t], [0, 1]]``."""
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, t
    return T


def planar_to_matrix(pose, z: float = 0.0) -> np.ndarray:
    """4x4 homogeneous matrix of a planar pose ``(x, y, yaw)`` lifted to height ``z``."""
    x, y, yaw = np.asarray(pose, dtype=float)
    return rigid_matrix(yaw_matrix(yaw), (x, y, z))


def matrix_to_planar(T) -> np.ndarray:
    """Planar pose ``(x, y, yaw)`` of a 4x4 matrix whose rotation is about the z axis."""
    T = np.asarray(T, dtype=float)
    return np.array([T[0, 3], T[1, 3], np.arctan2(T[1, 0], T[0, 0])])


def compose_planar(pose, increment) -> np.ndarray:
    """Apply ``increment`` ``(dx, dy, dyaw)``, expressed in the frame of ``pose``, to ``pose``
    (both may carry leading batch dimensions)."""
    pose, inc = np.asarray(pose, dtype=float), np.asarray(increment, dtype=float)
    if pose.shape == inc.shape == (3,):  # one pose: the same sums on floats, several times faster
        (x, y, yaw), (dx, dy, dyaw) = pose.tolist(), inc.tolist()
        c, s = math.cos(yaw), math.sin(yaw)
        return np.array([x + c * dx - s * dy, y + s * dx + c * dy, wrap_angle(yaw + dyaw)])
    c, s = np.cos(pose[..., 2]), np.sin(pose[..., 2])
    x = pose[..., 0] + c * inc[..., 0] - s * inc[..., 1]
    y = pose[..., 1] + s * inc[..., 0] + c * inc[..., 1]
    return np.stack([x, y, wrap_angle(pose[..., 2] + inc[..., 2])], axis=-1)


def relative_planar(pose_from, pose_to) -> np.ndarray:
    """Increment ``(dx, dy, dyaw)`` in the frame of ``pose_from`` that leads to ``pose_to``: the
    inverse of :func:`compose_planar`, ``compose_planar(a, relative_planar(a, b)) == b``."""
    a, b = np.asarray(pose_from, dtype=float), np.asarray(pose_to, dtype=float)
    if a.shape == b.shape == (3,):  # one pose: the same sums on floats, several times faster
        (ax, ay, ayaw), (bx, by, byaw) = a.tolist(), b.tolist()
        c, s = math.cos(ayaw), math.sin(ayaw)
        dx, dy = bx - ax, by - ay
        return np.array([c * dx + s * dy, -s * dx + c * dy, wrap_angle(byaw - ayaw)])
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    dx, dy = b[..., 0] - a[..., 0], b[..., 1] - a[..., 1]
    return np.stack([c * dx + s * dy, -s * dx + c * dy, wrap_angle(b[..., 2] - a[..., 2])], axis=-1)


def as_match_array(name: str, w) -> np.ndarray:
    """``w`` as a float array of shape ``(N, 3)``, all finite; else ValueError naming ``name``."""
    arr = np.asarray(w, dtype=float)
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ValueError(f"{name} must have shape (N, 3) with columns u, v, d; got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        bad = int(np.argwhere(~np.isfinite(arr))[0, 0])
        raise ValueError(f"{name} must be finite; row {bad} holds {arr[bad].tolist()}")
    return arr


def camera_mount(forward: float = 0.0, height: float = 0.5, left: float = 0.0) -> np.ndarray:
    """4x4 pose ``T_robot_camera`` of a forward-looking camera whose optical centre is at
    ``forward``, ``left``, ``height``; at ``forward = left = 0`` it sits above the turning axis,
    where the circular-motion model of [Zhao] is exact."""
    return rigid_matrix(R_ROBOT_FROM_CAMERA, (forward, left, height))


def camera_motion(pose_prev, pose_curr, T_robot_camera) -> np.ndarray:
    """4x4 ``T_curr_from_prev`` mapping points of the previous camera frame into the current one,
    for a camera mounted at ``T_robot_camera`` on a robot moving between two planar poses."""
    W0, W1 = (planar_to_matrix(pose) @ T_robot_camera for pose in (pose_prev, pose_curr))
    return np.linalg.solve(W1, W0)


def as_homogeneous(poses) -> np.ndarray:
    """``(..., 4, 4)`` matrices from ``(..., 3, 4)`` or ``(..., 4, 4)`` poses."""
    T = np.asarray(poses, dtype=float)
    if T.shape[-2:] == (3, 4):
        T = np.concatenate([T, np.broadcast_to([0.0, 0.0, 0.0, 1.0], T.shape[:-2] + (1, 4))], axis=-2)
    return T


def rigid_inverse(T) -> np.ndarray:
    """Inverses of rigid transforms ``(..., 4, 4)`` in closed form: ``[R t]^-1 = [R^T  -R^T t]``."""
    T = np.asarray(T, dtype=float)
    R_t = np.swapaxes(T[..., :3, :3], -1, -2)
    inverse = np.zeros_like(T)
    inverse[..., :3, :3] = R_t
    inverse[..., :3, 3] = -np.einsum("...ij,...j->...i", R_t, T[..., :3, 3])
    inverse[..., 3, 3] = 1.0
    return inverse


def camera_poses_from_planar(planar_poses, T_robot_camera) -> np.ndarray:
    """KITTI-style camera poses ``(N, 4, 4)``, each in the first camera's frame, of planar robot poses."""
    poses = np.asarray(planar_poses, dtype=float)
    first = np.linalg.inv(planar_to_matrix(poses[0]) @ T_robot_camera)
    return np.stack([first @ planar_to_matrix(p) @ T_robot_camera for p in poses])


def planar_from_camera_poses(camera_poses, T_robot_camera) -> np.ndarray:
    """Planar robot poses ``(N, 3)``, starting at the origin, of KITTI-style camera poses: the
    inverse of :func:`camera_poses_from_planar`; of a camera that also pitches and rolls (a car on
    a real road) it keeps the yaw and the ground-plane position."""
    robot = T_robot_camera @ as_homogeneous(camera_poses) @ np.linalg.inv(T_robot_camera)
    return np.stack([matrix_to_planar(M) for M in robot])
