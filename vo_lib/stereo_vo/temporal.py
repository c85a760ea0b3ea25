"""Temporal matching between consecutive frames, guided by the filter's motion prediction.

The Kalman filter predicts the circular motion ``(theta, rho)`` with a covariance ``C``. Every
previous feature is moved by the predicted motion (eq. 15) and projected, giving a predicted
``(u, v, d)``; its uncertainty is ``J C J^T`` with ``J`` the derivative of the prediction with
respect to ``(theta, rho)``, plus the pixel noise. Current features are candidates only inside
that window, and the nearest descriptor wins (ratio test, mutual check). [Zhao] matches "in
the observation-prediction period" of the filter; this is that step. Without a prediction the
matcher falls back to comparing every pair (brute force).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import cv2
import numpy as np

from vo_lib.camera import StereoCamera
from vo_lib.stereo_vo.circular_motion import motion_transform
from vo_lib.stereo_vo.features import RATIO, StereoFeatures, best_matches, equiangular_offset, hamming
from vo_lib.stereo_vo.rigid_motion import NEAR

N_SIGMA = 3.0  # window half-width in standard deviations
PIXEL_SIGMA = 1.0  # pixel noise of a feature position, added to the prediction's uncertainty
MIN_RADIUS = 4.0  # pixels
MAX_RADIUS = 120.0  # pixels
PATCH_HALF = 3  # 7x7 patches for the sub-pixel refinement of matches
TRACK_HALF = 7  # 15x15 windows for the sub-pixel tracking of matches (Lucas-Kanade)
TRACK_MAX_SHIFT = 1.5  # pixels: a tracked position further than this from its corner is not kept


@dataclass(frozen=True)
class MotionPrior:
    """A predicted circular motion and its 2x2 covariance (theta, rho)."""

    theta: float
    rho: float
    covariance: np.ndarray


@dataclass
class TemporalMatches:
    """Index pairs into the previous and current features, their ``w``, and diagnostics."""

    idx_prev: np.ndarray
    idx_curr: np.ndarray
    w_prev: np.ndarray
    w_curr: np.ndarray
    candidates: int
    timings: dict = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.idx_prev)


def predict_features(w_prev: np.ndarray, camera: StereoCamera, T) -> tuple[np.ndarray, np.ndarray]:
    """Predicted ``(u, v, d)`` of previous features after the camera motion ``T`` (4x4
    ``T_curr_from_prev``; :func:`~vo_lib.stereo_vo.circular_motion.motion_transform` for a circular
    one), NaN where a point ends nearer than :data:`NEAR`, and which are in front."""
    T = np.asarray(T, float)
    Q = camera.backproject(w_prev) @ T[:3, :3].T + T[:3, 3]
    ok = Q[:, 2] > NEAR
    w = np.full_like(Q, np.nan)
    w[ok] = camera.project(Q[ok])
    return w, ok


def prediction_sigma(w_prev: np.ndarray, camera: StereoCamera, prior: MotionPrior, base=None) -> np.ndarray:
    """Standard deviation ``(N, 3)`` of each predicted ``(u, v, d)``: sqrt(diag(J C J^T)) + pixel noise.

    ``J`` is taken by finite differences in theta and rho; ``base`` is the prediction, if already known.
    """
    if base is None:
        base, _ = predict_features(w_prev, camera, motion_transform(prior.theta, prior.rho))
    h = 1e-5
    moved_theta = predict_features(w_prev, camera, motion_transform(prior.theta + h, prior.rho))[0]
    moved_rho = predict_features(w_prev, camera, motion_transform(prior.theta, prior.rho + h))[0]
    d_theta, d_rho = (moved_theta - base) / h, (moved_rho - base) / h
    C = np.asarray(prior.covariance, dtype=float)
    var = d_theta**2 * C[0, 0] + 2 * d_theta * d_rho * C[0, 1] + d_rho**2 * C[1, 1]
    return np.sqrt(np.nan_to_num(var, nan=np.inf) + PIXEL_SIGMA**2)


def refine_positions(
    prev_image: np.ndarray, curr_image: np.ndarray, w_prev: np.ndarray, w_curr: np.ndarray
) -> np.ndarray:
    """Sub-pixel position in the current image of each previous feature's patch.

    Corners sit on whole pixels, and motion between frames is often a fraction of one. Each
    previous feature's patch is compared (sum of absolute differences) with the current image at
    the matched pixel and one pixel around it; equiangular (V) fits along u and along v give the
    sub-pixel position. Returns ``w_curr`` with refined u, v (the disparity is kept).
    """
    out = np.array(w_curr, dtype=float, copy=True)
    if len(out) == 0:
        return out
    h, w = curr_image.shape
    half = PATCH_HALF
    offs = np.arange(-half, half + 1)
    up, vp = np.rint(w_prev[:, 0]).astype(int), np.rint(w_prev[:, 1]).astype(int)
    uc, vc = np.rint(w_curr[:, 0]).astype(int), np.rint(w_curr[:, 1]).astype(int)
    r = half + 1
    ok = (up >= half) & (up < w - half) & (vp >= half) & (vp < h - half)
    ok &= (uc >= r) & (uc < w - r) & (vc >= r) & (vc < h - r)
    if not ok.any():
        return out
    rows = vp[ok, None, None] + offs[None, :, None]
    cols = up[ok, None, None] + offs[None, None, :]
    patch = prev_image[rows, cols].astype(np.int32)
    rc, cc = vc[ok, None, None] + offs[None, :, None], uc[ok, None, None] + offs[None, None, :]

    def sad(du, dv):
        return np.abs(patch - curr_image[rc + dv, cc + du].astype(np.int32)).sum(axis=(1, 2))

    c0 = sad(0, 0)
    out[ok, 0] = uc[ok] + equiangular_offset(sad(-1, 0), c0, sad(1, 0))
    out[ok, 1] = vc[ok] + equiangular_offset(sad(0, -1), c0, sad(0, 1))
    return out


def track_subpixel(
    prev_image: np.ndarray, curr_image: np.ndarray, w_prev: np.ndarray, w_curr: np.ndarray
) -> np.ndarray:
    """Sub-pixel position in the current image of each matched previous feature, by tracking.

    Pyramid corners sit on whole pixels of their level (a grid of 1.2 px or coarser above the
    first). Each previous feature's window is tracked into the current image by OpenCV's iterative
    Lucas-Kanade (``calcOpticalFlowPyrLK``) from the matched corner; a track that fails or ends
    more than ``TRACK_MAX_SHIFT`` pixels from it (another corner, an occlusion) keeps the corner.
    Returns ``w_curr`` with refined u, v (the disparity is kept).
    """
    out = np.array(w_curr, dtype=float, copy=True)
    if len(out) == 0:
        return out
    p0 = np.ascontiguousarray(w_prev[:, :2], dtype=np.float32).reshape(-1, 1, 2)
    p1 = np.ascontiguousarray(w_curr[:, :2], dtype=np.float32).reshape(-1, 1, 2)
    tracked, status, _ = cv2.calcOpticalFlowPyrLK(
        prev_image,
        curr_image,
        p0,
        p1,
        winSize=(2 * TRACK_HALF + 1, 2 * TRACK_HALF + 1),
        maxLevel=0,
        criteria=(cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 20, 0.01),
        flags=cv2.OPTFLOW_USE_INITIAL_FLOW,
    )
    tracked = tracked.reshape(-1, 2).astype(float)
    keep = (status.ravel() == 1) & (np.linalg.norm(tracked - out[:, :2], axis=1) <= TRACK_MAX_SHIFT)
    out[keep, :2] = tracked[keep]
    return out


def match_features(
    prev: StereoFeatures,
    curr: StereoFeatures,
    predicted: np.ndarray | None = None,
    radius: np.ndarray | None = None,
    ratio: float = RATIO,
    refine: bool = False,
) -> TemporalMatches:
    """Match previous features to current ones: inside windows around their predictions, or all pairs.

    ``predicted`` is each previous feature's predicted ``(u, v, d)`` (NaN where not expected in
    view; without it, brute force) and ``radius`` its window's half-widths in ``u``, ``v`` and
    ``d``; one compiled pass finds the candidates inside and their Hamming distances
    (:func:`.matching_core.window_candidates`). ``refine``: current positions to sub-pixel
    (:func:`refine_positions`) where the images are known.
    """
    from vo_lib.stereo_vo.matching_core import window_candidates

    t0 = time.perf_counter()
    n_prev, n_curr = len(prev), len(curr)
    if n_prev == 0 or n_curr == 0:
        none = np.zeros(0, int)
        return TemporalMatches(none, none, np.zeros((0, 3)), np.zeros((0, 3)), 0, {"temporal_match": 0.0})
    if predicted is None:  # every (i, j) pair, ordered by i
        ia, ib = np.repeat(np.arange(n_prev), n_curr), np.tile(np.arange(n_curr), n_prev)
        dist = hamming(prev.descriptors[:, None], curr.descriptors[None]).ravel()
    else:
        order = np.argsort(curr.w[:, 1], kind="stable")
        half = np.broadcast_to(np.asarray(radius, float), (n_prev, 3))
        pred, half, w = (np.ascontiguousarray(x, dtype=float) for x in (predicted, half, curr.w))
        words_a, words_b = (np.ascontiguousarray(f.descriptors).view(np.uint64) for f in (prev, curr))
        ia, ib, dist = window_candidates(pred, half, w, order, w[order, 1], words_a, words_b)
    a, b, _ = best_matches(ia, ib, dist, n_prev, n_curr, ratio=ratio)
    w_curr = curr.w[b]
    if refine and prev.image is not None and curr.image is not None:
        w_curr = refine_positions(prev.image, curr.image, prev.w[a], w_curr)
    elapsed = (time.perf_counter() - t0) * 1e3
    return TemporalMatches(a, b, prev.w[a], w_curr, len(ia), {"temporal_match": elapsed})


def match_temporal(
    prev: StereoFeatures, curr: StereoFeatures, camera: StereoCamera, prior: MotionPrior | None = None
) -> TemporalMatches:
    """The paper's guided matching: inside each feature's window under the filter's ``prior``
    (``N_SIGMA`` standard deviations of its predicted ``(u, v, d)``, within ``[MIN_RADIUS,
    MAX_RADIUS]``), refined to sub-pixel; without a prior, every pair (brute force)."""
    if prior is None:
        return match_features(prev, curr, refine=True)
    pred, _ = predict_features(prev.w, camera, motion_transform(prior.theta, prior.rho))
    radius = np.clip(N_SIGMA * prediction_sigma(prev.w, camera, prior, pred), MIN_RADIUS, MAX_RADIUS)
    return match_features(prev, curr, pred, radius, refine=True)
