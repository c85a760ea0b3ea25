"""Synthetic stereo matches under a known circular motion, for checks that need exact truth.

The points lie in a possible room (:class:`Scene`): on the floor below the (possibly pitched)
rig, or on upright surfaces up to ``top``, uniform in inverse range, so the image rows fill as in
a room. The camera moves by eq. 15 of [Zhao] (or any rigid motion); a point is kept only when
both views see it; pixel noise and gross outliers are optional.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from vo_lib.camera import StereoCamera
from vo_lib.geometry import rigid_matrix
from vo_lib.stereo_vo.circular_motion import circular_motion_from_transform, motion_matrices

#: Nearest depth a point may have in either view, metres.
MIN_DEPTH = 0.3
#: Height of the crawler's stereo rig above the floor, metres (the rendered samples' rig).
RIG_HEIGHT = 0.5


@dataclass(frozen=True)
class Scene:
    """Where the points of a synthetic match set may lie."""

    camera_height: float = RIG_HEIGHT  #: of the left camera's centre above the floor, metres
    pitch: float = 0.0  #: downward pitch of the optical axis from the horizontal, radians (0: level)
    top: float = 2.5  #: height above the floor of the highest point on an upright surface, metres
    floor_share: float = 0.3  #: share of the points drawn on the floor itself (the rest upright)

    def __post_init__(self) -> None:
        if not self.camera_height > 0:
            raise ValueError(f"Scene.camera_height must be > 0 m; got {self.camera_height}")
        if not self.top > 0:
            raise ValueError(f"Scene.top must be > 0 m; got {self.top}")
        if not 0.0 <= self.floor_share <= 1.0:
            raise ValueError(f"Scene.floor_share must lie in [0, 1]; got {self.floor_share}")
        if not abs(self.pitch) < np.pi / 2:
            raise ValueError(f"Scene.pitch must lie within ±90°; got {self.pitch} rad")

    def level_from_camera(self) -> np.ndarray:
        """Rotation from the (pitched) camera frame to the level frame (x right, y down, z ahead)."""
        c, s = np.cos(self.pitch), np.sin(self.pitch)
        return np.array([[1.0, 0.0, 0.0], [0.0, c, s], [0.0, -s, c]])

    def height_above_floor(self, points: np.ndarray) -> np.ndarray:
        """Height above the floor of camera-frame points ``(N, 3)``, metres."""
        level = np.asarray(points, float) @ self.level_from_camera().T
        return self.camera_height - level[:, 1]


@dataclass(frozen=True)
class SyntheticMatches:
    """Matches ``w_prev -> w_curr`` (``(N, 3)``: u, v, d), the truth behind them, and the inliers."""

    w_prev: np.ndarray
    w_curr: np.ndarray
    inliers: np.ndarray
    theta: float
    rho: float
    points: np.ndarray


def synthetic_matches(
    camera: StereoCamera,
    n: int,
    theta: float,
    rho: float,
    rng: np.random.Generator,
    depth_range: tuple[float, float] = (1.5, 15.0),
    noise_px: float = 0.0,
    outlier_ratio: float = 0.0,
    scene: Scene | None = None,
) -> SyntheticMatches:
    """Draw ``n`` matches of points seen before and after the robot's circular motion ``(theta,
    rho)`` (eq. 15), which a pitched camera sees as a motion off the planar model; the other
    parameters are :func:`matches_under_transform`'s.
    """
    scene = Scene() if scene is None else scene
    R, T = motion_matrices(theta, rho)
    L = scene.level_from_camera()
    M = rigid_matrix(L.T @ R @ L, L.T @ T)
    m = matches_under_transform(camera, n, M, rng, depth_range, noise_px, outlier_ratio, scene)
    return replace(m, theta=float(theta), rho=float(rho))


def matches_under_transform(
    camera: StereoCamera,
    n: int,
    T_curr_from_prev: np.ndarray,
    rng: np.random.Generator,
    depth_range: tuple[float, float] = (1.5, 15.0),
    noise_px: float = 0.0,
    outlier_ratio: float = 0.0,
    scene: Scene | None = None,
) -> SyntheticMatches:
    """Draw ``n`` matches of points seen before and after any rigid camera motion.

    ``T_curr_from_prev`` maps the previous camera frame (where ``scene`` is fixed) into the current
    one; the result's ``theta`` and ``rho`` are :func:`circular_motion_from_transform`'s.
    ``depth_range``: horizontal ranges from the previous camera, metres; ``noise_px``: Gaussian
    noise on u, v and d of both views; ``outlier_ratio``: the share of second views replaced by an
    unrelated pixel and disparity.
    """
    scene = Scene() if scene is None else scene
    if camera.width is None or camera.height is None:
        raise ValueError("camera must have width and height to draw matches inside the image")
    if n < 0:
        raise ValueError(f"n must be >= 0; got {n}")
    if not 0.0 <= outlier_ratio <= 1.0:
        raise ValueError(f"outlier_ratio must lie in [0, 1]; got {outlier_ratio}")
    M = np.asarray(T_curr_from_prev, dtype=float)
    if M.shape != (4, 4):
        raise ValueError(f"T_curr_from_prev must be a 4x4 matrix; got shape {M.shape}")
    theta, rho = circular_motion_from_transform(M)
    near, far = depth_range
    if not 0 < near < far:
        raise ValueError(f"depth_range must satisfy 0 < near < far; got {depth_range}")
    w_prev, w_curr, points = _visible_pairs(camera, M, n, rng, (near, far), (theta, rho), scene)
    inliers = np.ones(n, dtype=bool)
    n_out = int(round(outlier_ratio * n))
    if n_out:
        idx = rng.choice(n, n_out, replace=False)
        inliers[idx] = False
        w_curr[idx, 0] = rng.uniform(0, camera.width - 1, n_out)
        w_curr[idx, 1] = rng.uniform(0, camera.height - 1, n_out)
        w_curr[idx, 2] = rng.choice(w_prev[:, 2], n_out)
    if noise_px > 0:
        w_prev = w_prev + rng.normal(0.0, noise_px, w_prev.shape)
        w_curr = w_curr + rng.normal(0.0, noise_px, w_curr.shape)
        # a disparity pushed to or below zero by the noise is floored, as a matcher reports it
        w_prev[:, 2] = np.maximum(w_prev[:, 2], 0.05)
        w_curr[:, 2] = np.maximum(w_curr[:, 2], 0.05)
    return SyntheticMatches(w_prev, w_curr, inliers, float(theta), float(rho), points)


def _scene_points(
    camera: StereoCamera, m: int, rng: np.random.Generator, depth_range: tuple[float, float], scene: Scene
) -> np.ndarray:
    """``m`` points of the scene in the previous camera frame, ``(m, 3)``: image column uniform,
    range uniform in inverse range, height 0 or uniform up to ``scene.top``. Floor texture starts
    at the rig's height ahead (nearer than ``depth_range``), where a pitched camera sees it."""
    near, far = depth_range
    on_floor = rng.uniform(0, 1, m) < scene.floor_share
    nearest = np.where(on_floor, min(near, scene.camera_height), near)
    ahead = 1.0 / rng.uniform(1.0 / far, 1.0 / nearest, m)
    across = (rng.uniform(0, camera.width - 1, m) - camera.cx) / camera.fx * ahead
    height = np.where(on_floor, 0.0, rng.uniform(0, scene.top, m))
    level = np.column_stack([across, scene.camera_height - height, ahead])
    return level @ scene.level_from_camera()  # level -> camera: the transpose, row by row


def _visible_pairs(camera, M, n, rng, depth_range, motion, scene):
    """``n`` points of the scene seen by the previous view that stay in front of the camera and in
    the image after ``M``: ``(w_prev, w_curr, points)``."""
    kept = [(np.zeros((0, 3)),) * 3]  # (w_prev, w_curr, points) of each draw
    count = drawn = 0
    while count < n:
        if drawn > 1000 * (n + 16) and count < 0.001 * drawn:
            raise ValueError(
                f"the motion theta={motion[0]!r}, rho={motion[1]!r} leaves (almost) no point visible "
                f"in both views within depth_range={depth_range}"
            )
        m = 2 * (n - count) + 16
        drawn += m
        P = _scene_points(camera, m, rng, depth_range, scene)
        P2 = P @ M[:3, :3].T + M[:3, 3]
        ok = (P[:, 2] > MIN_DEPTH) & (P2[:, 2] > MIN_DEPTH)
        w1, w2 = np.full_like(P, np.nan), np.full_like(P2, np.nan)
        w1[ok], w2[ok] = camera.project(P[ok]), camera.project(P2[ok])
        ok &= camera.in_image(np.nan_to_num(w1, nan=-1.0)) & camera.in_image(np.nan_to_num(w2, nan=-1.0))
        kept.append((w1[ok], w2[ok], P[ok]))
        count += int(ok.sum())
    return tuple(np.concatenate(draws)[:n] for draws in zip(*kept, strict=True))
