"""Synthetic stereo matches under a known circular motion, for checks that need exact truth.

Points are drawn where a camera would see them (a uniform pixel and a depth), moved by eq. 15,
and kept only when the second view sees them too; pixel noise and gross outliers are optional.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vo_lib.camera import StereoCamera
from vo_lib.stereo_vo.circular_motion import circular_motion_from_transform, motion_matrices

#: Nearest depth a point may have in either view, metres.
MIN_DEPTH = 0.3


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
) -> SyntheticMatches:
    """Draw ``n`` matches of points seen before and after the circular motion ``(theta, rho)``.

    See :func:`matches_under_transform` for the parameters; the motion is eq. 15.
    """
    R, T = motion_matrices(theta, rho)
    M = np.eye(4)
    M[:3, :3], M[:3, 3] = R, T
    return matches_under_transform(camera, n, M, rng, depth_range, noise_px, outlier_ratio)


def matches_under_transform(
    camera: StereoCamera,
    n: int,
    T_curr_from_prev: np.ndarray,
    rng: np.random.Generator,
    depth_range: tuple[float, float] = (1.5, 15.0),
    noise_px: float = 0.0,
    outlier_ratio: float = 0.0,
) -> SyntheticMatches:
    """Draw ``n`` matches of points seen before and after any rigid camera motion.

    Parameters
    ----------
    camera : StereoCamera
        Must have ``width`` and ``height``.
    n : int
        Number of matches.
    T_curr_from_prev : array_like, shape (4, 4)
        Maps a point of the previous camera frame into the current one. ``theta`` and ``rho`` of
        the result are those of :func:`~vo_lib.stereo_vo.circular_motion.circular_motion_from_transform`.
    rng : numpy.random.Generator
        Source of every random draw.
    depth_range : (float, float)
        Depths of the points in the previous frame, metres, drawn uniformly in inverse depth
        so that near and far points are both present.
    noise_px : float
        Standard deviation of Gaussian noise added to u, v and d of both views, pixels.
    outlier_ratio : float
        Fraction of matches whose second view is replaced by an unrelated pixel and disparity.
    """
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
    w_prev, w_curr, points = _visible_pairs(camera, M, n, rng, (near, far), (theta, rho))
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


def _visible_pairs(camera, M, n, rng, depth_range, motion):
    """``n`` points drawn in the previous view (uniform in the image and in inverse depth) that stay
    in front of the camera and in the image after ``M``: ``(w_prev, w_curr, points)``."""
    near, far = depth_range
    kept_prev, kept_curr, kept_pts = [np.zeros((0, 3))], [np.zeros((0, 3))], [np.zeros((0, 3))]
    count = drawn = 0
    while count < n:
        if drawn > 1000 * (n + 16) and count < 0.001 * drawn:
            raise ValueError(
                f"the motion theta={motion[0]!r}, rho={motion[1]!r} leaves (almost) no point visible "
                f"in both views within depth_range={depth_range}"
            )
        m = 2 * (n - count) + 16
        drawn += m
        u = rng.uniform(0, camera.width - 1, m)
        v = rng.uniform(0, camera.height - 1, m)
        z = 1.0 / rng.uniform(1.0 / far, 1.0 / near, m)
        d = camera.fx * camera.baseline / z
        P = camera.backproject(np.column_stack([u, v, d]))
        P2 = P @ M[:3, :3].T + M[:3, 3]
        ok = P2[:, 2] > MIN_DEPTH
        w2 = np.full_like(P2, np.nan)
        w2[ok] = camera.project(P2[ok])
        ok &= camera.in_image(np.nan_to_num(w2, nan=-1.0))
        kept_prev.append(np.column_stack([u, v, d])[ok])
        kept_curr.append(w2[ok])
        kept_pts.append(P[ok])
        count += int(ok.sum())
    return tuple(np.concatenate(kept)[:n] for kept in (kept_prev, kept_curr, kept_pts))
