"""Stereo front end: FAST corners, binary descriptors, matching along rows by Hamming distance.

Per stereo pair ([Zhao], III.A.1):

1. FAST corners in the left image, spread by grid bucketing (the strongest few per cell) and
   capped in number; FAST corners in the right image near the rows of the kept left ones.
2. Binary descriptors (ORB's rBRIEF) at those corners.
3. Left-right matching on the same row (within a row tolerance) and a disparity range, by
   Hamming distance, with a distance ceiling, a ratio test and mutual (left-right) consistency.
4. Sub-pixel disparity from an equiangular (V) fit to the block-matching cost at d-1, d, d+1.

Output per frame: ``w = (u, v, d)`` per feature and its descriptor (:class:`StereoFeatures`).
Hamming distances are computed only for candidate pairs, 64 bits at a time with
``numpy.bitwise_count``; the same :func:`best_matches` serves the temporal matcher.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np

from vo_lib.camera import StereoCamera
from vo_lib.stereo_vo.frames import Stopwatch

FAST_THRESHOLD = 40
GRID = (8, 6)  # cells across, down
MAX_FEATURES = 600
RIGHT_FACTOR = 2.0  # right-image corners kept per left feature (the candidates for stereo matching)
MAX_DISPARITY = 64.0  # pixels at 640 px width: about 0.9 m for the default rig
ROW_TOLERANCE = 1.0  # pixels between left and right rows
MAX_HAMMING = 60  # of 256 bits
RATIO = 0.85  # best / second-best distance
PATCH_HALF = 3  # 7x7 patches for sub-pixel refinement
ORB_BORDER = 16  # ORB cannot describe corners closer than this to the border


@dataclass
class StereoFeatures:
    """Stereo-matched features of one frame: ``w`` ``(N, 3)`` as u, v, d and ``descriptors`` ``(N, 32)``."""

    w: np.ndarray
    descriptors: np.ndarray
    timings: dict = field(default_factory=dict)
    image: np.ndarray | None = None  # the left image, for sub-pixel refinement of temporal matches

    def __len__(self) -> int:
        return len(self.w)


def hamming(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamming distances between paired rows of 32-byte descriptors (the last axis; the others
    broadcast, so ``hamming(a[:, None], b[None])`` is every row of ``a`` against every row of ``b``)."""
    x = np.bitwise_xor(a.view(np.uint64), b.view(np.uint64))
    return np.bitwise_count(x).sum(axis=-1, dtype=np.int32)


def best_matches(
    ia, ib, dist, n_a: int, n_b: int, max_distance: int = MAX_HAMMING, ratio: float = RATIO
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pick matches from candidate pairs ``(ia[k], ib[k])`` with Hamming distance ``dist[k]``.

    For each ``a`` the nearest ``b`` is kept if it is within ``max_distance``, if the second
    nearest is farther by the ``ratio`` test, and if no other ``a`` is nearer to that ``b``
    (mutual check). Returns ``(index_a, index_b, distance)``, ordered by ``b``. Runs compiled
    (:mod:`.matching_core`); ``matching_plain.best_matches`` is the same rule in NumPy.
    """
    from vo_lib.stereo_vo.matching_core import best_matches_core

    ia, ib, dist = np.asarray(ia, np.int64), np.asarray(ib, np.int64), np.asarray(dist)
    return best_matches_core(ia, ib, dist, int(n_a), int(n_b), float(max_distance), float(ratio))


def window_pairs(keys_a: np.ndarray, keys_b: np.ndarray, half_width) -> tuple[np.ndarray, np.ndarray]:
    """All pairs ``(i, j)`` with ``|keys_b[j] - keys_a[i]| <= half_width[i]``, by ``i`` then by
    ``keys_b[j]`` (a negative half-width finds none). Costs a sort and two binary searches instead of
    comparing every pair."""
    order = np.argsort(keys_b, kind="stable")
    sorted_b = keys_b[order]
    half = np.broadcast_to(np.asarray(half_width, dtype=float), keys_a.shape)
    lo = np.searchsorted(sorted_b, keys_a - half, side="left")
    hi = np.searchsorted(sorted_b, keys_a + half, side="right")
    counts = np.maximum(hi - lo, 0)
    ia = np.repeat(np.arange(len(keys_a)), counts)
    offsets = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
    return ia, order[np.repeat(lo, counts) + offsets]


def bucket(
    points: np.ndarray,
    response: np.ndarray,
    width: int,
    height: int,
    grid=GRID,
    max_features: int = MAX_FEATURES,
) -> np.ndarray:
    """Indices of at most ``max_features`` points, the strongest ones of each grid cell first."""
    if len(points) == 0:
        return np.zeros(0, int)
    cx = np.minimum((points[:, 0] * grid[0] / width).astype(int), grid[0] - 1)
    cy = np.minimum((points[:, 1] * grid[1] / height).astype(int), grid[1] - 1)
    cell = cy * grid[0] + cx
    order = np.lexsort((-response, cell))
    cell_sorted = cell[order]
    starts = np.searchsorted(cell_sorted, cell_sorted, side="left")
    rank = np.arange(len(order)) - starts  # rank within the cell by response
    per_cell = int(np.ceil(max_features / (grid[0] * grid[1])))
    chosen = order[rank < per_cell]
    if len(chosen) > max_features:
        chosen = chosen[np.argsort(-response[chosen])[:max_features]]
    return np.sort(chosen)


def equiangular_offset(c_minus: np.ndarray, c_zero: np.ndarray, c_plus: np.ndarray) -> np.ndarray:
    """Sub-pixel position of the minimum of a SAD cost sampled at -1, 0, +1 (0 where 0 is no minimum).

    A sum of absolute differences is V-shaped around its minimum, so the fit is equiangular: two
    lines of equal and opposite slope through the samples. A parabola would pull the minimum
    towards whole pixels ("pixel locking") and under-measure sub-pixel motion.
    """
    c_minus, c_zero, c_plus = (np.asarray(c, float) for c in (c_minus, c_zero, c_plus))
    rise = np.maximum(c_minus, c_plus) - c_zero
    ok = (rise > 0) & (c_zero <= c_minus) & (c_zero <= c_plus)
    return np.where(ok, np.clip(0.5 * (c_minus - c_plus) / np.where(ok, rise, 1.0), -0.5, 0.5), 0.0)


def subpixel_disparity(
    left: np.ndarray, right: np.ndarray, u: np.ndarray, v: np.ndarray, d: np.ndarray, search: int = 1
) -> np.ndarray:
    """Refine disparities by the equiangular fit of the SAD cost (7x7 patches) around its minimum.

    The costs are taken at ``d - search ... d + search`` (whole pixels about the rounded ``d``);
    the fit uses the lowest inner one and its two neighbours. ``search = 1`` refines within half a
    pixel; a larger search also corrects a coarse disparity (from corners found on an upper pyramid
    level, whose positions sit on a coarser grid).
    """
    h, w = left.shape
    r = PATCH_HALF
    ui, vi, di = np.rint(u).astype(np.int64), np.rint(v).astype(np.int64), np.rint(d).astype(np.int64)
    ok = (
        (vi - r >= 0)
        & (vi + r < h)
        & (ui - r >= 0)
        & (ui + r < w)
        & (ui - di - r - search >= 0)
        & (ui - di + r + search < w)
    )
    out = d.astype(float).copy()
    if not ok.any():
        return out
    from vo_lib.stereo_vo.matching_core import sad_costs

    # costs[k + search] belongs to disparity d + k (one compiled pass over the patches)
    costs = sad_costs(left, right, ui[ok], vi[ok], di[ok], r, search)
    best = 1 + np.argmin(costs[1:-1], axis=0)  # the lowest inner cost
    pick = np.arange(costs.shape[1])
    offset = equiangular_offset(costs[best - 1, pick], costs[best, pick], costs[best + 1, pick])
    out[ok] = di[ok] + (best - search) + offset
    return out


class StereoFrontEnd:
    """Detect, describe and stereo-match features of rectified pairs: at most ``max_features``
    left corners after bucketing, FAST's intensity threshold, and the largest disparity searched
    (default: :data:`MAX_DISPARITY` scaled to the image width)."""

    def __init__(
        self,
        camera: StereoCamera,
        max_features: int = MAX_FEATURES,
        fast_threshold: int = FAST_THRESHOLD,
        max_disparity: float | None = None,
    ):
        if camera.width is None or camera.height is None:
            raise ValueError("the front end needs a camera with width and height")
        if max_features <= 0:
            raise ValueError(f"max_features must be > 0; got {max_features}")
        self.camera = camera
        self.max_features = max_features
        self.max_disparity = (
            MAX_DISPARITY * camera.width / 640 if max_disparity is None else float(max_disparity)
        )
        self.fast = cv2.FastFeatureDetector_create(fast_threshold, True)
        self.orb = cv2.ORB_create(
            nfeatures=int(RIGHT_FACTOR * max_features) + 1, nlevels=1, edgeThreshold=ORB_BORDER, patchSize=31
        )

    def _detect(self, image: np.ndarray):
        kps = self.fast.detect(image)
        if not kps:
            return np.zeros((0, 2), np.float32), np.zeros(0, np.float32)
        pts = cv2.KeyPoint_convert(kps).reshape(-1, 2)
        resp = np.fromiter((k.response for k in kps), np.float32, len(kps))
        size = np.array(image.shape[::-1])  # (width, height)
        inside = np.all((pts >= ORB_BORDER) & (pts < size - ORB_BORDER), axis=1)
        return pts[inside], resp[inside]

    def _describe(self, image: np.ndarray, pts: np.ndarray):
        if len(pts) == 0:
            return np.zeros((0, 2), np.float32), np.zeros((0, 32), np.uint8)
        kps, des = self.orb.compute(image, cv2.KeyPoint_convert(np.ascontiguousarray(pts, np.float32), 31.0))
        if des is None or not kps:
            return np.zeros((0, 2), np.float32), np.zeros((0, 32), np.uint8)
        return cv2.KeyPoint_convert(kps).reshape(-1, 2), des

    def process(self, left: np.ndarray, right: np.ndarray) -> StereoFeatures:
        """Stereo features of one rectified pair, with per-stage timings in milliseconds."""
        if left.shape != right.shape or left.ndim != 2:
            raise ValueError(
                f"left and right must be 2-D grey images of one size; got {left.shape}, {right.shape}"
            )
        h, w = left.shape
        watch = Stopwatch()
        with watch("detect"):
            pl, rl = self._detect(left)
            keep = bucket(pl, rl, w, h, GRID, self.max_features)
            pl = pl[keep]
            pr, rr = self._detect(right)
            if len(pl) and len(pr):
                # right corners only near the rows of the kept left corners
                row_has_left = np.zeros(h + 2, bool)
                rows = np.rint(pl[:, 1]).astype(int)
                for k in range(-int(ROW_TOLERANCE), int(ROW_TOLERANCE) + 1):
                    row_has_left[np.clip(rows + k, 0, h - 1)] = True
                near = row_has_left[np.rint(pr[:, 1]).astype(int)]
                pr, rr = pr[near], rr[near]
                pr = pr[bucket(pr, rr, w, h, GRID, int(RIGHT_FACTOR * len(pl)))]
        with watch("describe"):
            pl, dl = self._describe(left, pl)
            pr, dr = self._describe(right, pr)
        with watch("stereo_match"):
            w_lr, descriptors = self._stereo_match(left, right, pl, dl, pr, dr)
        return StereoFeatures(w_lr, descriptors, watch.ms, left)

    def _stereo_match(self, left, right, pl, dl, pr, dr) -> tuple[np.ndarray, np.ndarray]:
        """``w = (u, v, d)`` and descriptors of the left features matched along rows, sub-pixel."""
        if len(pl) == 0 or len(pr) == 0:
            return np.zeros((0, 3)), np.zeros((0, 32), np.uint8)
        ia, ib = self._row_candidates(pl, pr)
        a, b, _ = best_matches(ia, ib, hamming(dl[ia], dr[ib]), len(pl), len(pr))
        u, v = pl[a, 0].astype(float), pl[a, 1].astype(float)
        d = subpixel_disparity(left, right, u, v, (pl[a, 0] - pr[b, 0]).astype(float))
        ok = d > 0
        return np.column_stack([u, v, d])[ok], dl[a][ok]

    def _row_candidates(self, pl: np.ndarray, pr: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """All (left, right) pairs on rows within the tolerance and disparities within the range."""
        ia, ib = window_pairs(pl[:, 1], pr[:, 1], ROW_TOLERANCE)
        disp = pl[ia, 0] - pr[ib, 0]
        ok = (disp >= 0.5) & (disp <= self.max_disparity)
        return ia[ok], ib[ok]
