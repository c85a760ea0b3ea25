"""Stereo front end for real images: FAST corners in a scale pyramid, matched along rows.

The single-scale front end (:mod:`vo_lib.stereo_vo.features`) suits the crawler, whose camera
moves centimetres between frames. A car moves 0.5-1.5 m per frame, so a wall 15 m ahead grows by
7 % from one image to the next, and corners found at one scale drift with the growing texture (on
the real sequence that biased the heading frame after frame; notebook 11 sets single-scale and
pyramid corners side by side). Here corners are found at two scales and described at their own
(OpenCV's ORB: oriented FAST ranked by the Harris measure, rotated BRIEF), so a corner keeps its
place and its descriptor as the scene grows.

Per stereo pair:

1. **Detection and description** of both images at once (the right on a worker thread; OpenCV
   releases the interpreter lock), with a feature budget in proportion to the image area and a
   FAST threshold adapted frame by frame: lowered when an image gives fewer corners than the
   budget (sky, road, plain walls), raised again when it gives plenty.
2. **Matching along rows** by Hamming distance: candidates within ``ROW_TOLERANCE`` rows, a
   positive disparity below the largest searched, pyramid levels at most one apart; the nearest
   wins if it passes the ratio test (rails, fences, lane marks give several near-equal
   candidates, and such features are dropped) and the mutual check.
3. **Sub-pixel disparity** by the equiangular fit of the block-matching cost at ``d-1, d, d+1``
   (as in the single-scale front end).
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import cv2
import numpy as np

from vo_lib.camera import StereoCamera
from vo_lib.stereo_vo.features import StereoFeatures, best_matches, subpixel_disparity
from vo_lib.stereo_vo.frames import Stopwatch

#: Features per image pixel: 1,500 at KITTI's 1242x375, 950 at 640x480.
FEATURES_PER_PIXEL = 1500 / (1242 * 375)
MIN_FEATURES_BUDGET = 300
LEVELS = 2  # scales 1 and 1.2: enough for a car's 0.5-1.5 m per frame, and a fifth cheaper than 3
SCALE_FACTOR = 1.2
FAST_THRESHOLD = 20  # the starting threshold; it adapts within the bounds below
FAST_BOUNDS = (6, 40)
ROW_TOLERANCE = 1.5  # pixels: ORB keypoints of upper levels sit on a coarser grid
MAX_DISPARITY_FRACTION = 0.13  # of the image width: 160 px at 1242, about 2 m for KITTI's rig
MAX_HAMMING = 64
RATIO = 0.9
#: Whole pixels searched either side of a match's disparity before the sub-pixel fit: corners of
#: the upper pyramid levels sit on a grid 1.2-1.44 px wide.
DISPARITY_SEARCH = 2


def level_zero_positions(pts: np.ndarray, octave: np.ndarray, shape) -> np.ndarray:
    """ORB's corners in full-image pixels, with pixel centres where the image has them.

    ORB reports a corner of level ``L`` at its pixel on that level times ``s = SCALE_FACTOR ** L``
    (in single precision). But the level is the image resized to ``round(side / s)`` pixels a
    side, and OpenCV's resize puts pixel ``x`` of it at ``(x + 0.5) * side / size - 0.5`` of the
    full image. KITTI's 375 rows become 312, so a corner of the second level was reported 0.1 px
    too high at the top and 0.5 px too low at the bottom, and a corner that moved between levels
    from one frame to the next seemed to turn the camera.
    """
    out = np.array(pts, dtype=float)
    side = np.array(shape[1::-1], float)  # width, height
    for level in np.unique(octave[octave > 0]):
        scale = float(np.float32(SCALE_FACTOR**level))  # as ORB computes it
        on_level = octave == level
        out[on_level] = (out[on_level] / scale + 0.5) * (side / np.rint(side / scale)) - 0.5
    return out


class PyramidFrontEnd:
    """Detect, describe and stereo-match features of rectified pairs at two scales: features per
    image in proportion to its area, and disparities up to 13 % of its width by default."""

    def __init__(self, camera: StereoCamera, max_disparity: float | None = None):
        if camera.width is None or camera.height is None:
            raise ValueError("the front end needs a camera with width and height")
        self.camera = camera
        self.max_features = max(
            MIN_FEATURES_BUDGET, round(FEATURES_PER_PIXEL * (camera.width * camera.height))
        )
        self.max_disparity = float(max_disparity or MAX_DISPARITY_FRACTION * camera.width)
        self.threshold = [FAST_THRESHOLD, FAST_THRESHOLD]  # per image, adapted frame by frame
        self._orb = [
            cv2.ORB_create(
                self.max_features, scaleFactor=SCALE_FACTOR, nlevels=LEVELS, fastThreshold=FAST_THRESHOLD
            )
            for _ in range(2)
        ]
        self._worker = ThreadPoolExecutor(1)  # the right image's detection, beside the left's

    def _detect_and_describe(self, side: int, image: np.ndarray):
        kps, des = self._orb[side].detectAndCompute(image, None)
        # adapt the threshold: too few corners -> lower it next frame, plenty -> raise it
        if len(kps) < 0.9 * self.max_features:
            self.threshold[side] = max(FAST_BOUNDS[0], int(self.threshold[side] * 0.8))
        elif len(kps) >= self.max_features:
            self.threshold[side] = min(FAST_BOUNDS[1], self.threshold[side] + 1)
        self._orb[side].setFastThreshold(self.threshold[side])
        if des is None or not kps:
            return np.zeros((0, 2), np.float32), np.zeros(0, int), np.zeros((0, 32), np.uint8)
        pts = cv2.KeyPoint_convert(kps).reshape(-1, 2)
        octave = np.fromiter((k.octave for k in kps), int, len(kps))
        return level_zero_positions(pts, octave, image.shape), octave, des

    def _row_candidates(self, pl, ol, dl, pr, orr, dr):
        """Left-right pairs on rows within ``ROW_TOLERANCE``, a disparity from 0.5 px to the largest
        searched and levels at most one apart, with their Hamming distances (one compiled pass)."""
        from vo_lib.stereo_vo.matching_core import row_candidates

        pl, pr = np.ascontiguousarray(pl, dtype=float), np.ascontiguousarray(pr, dtype=float)
        order = np.argsort(pr[:, 1], kind="stable")
        rows = np.ascontiguousarray(pr[order, 1])
        words_l, words_r = (np.ascontiguousarray(d).view(np.uint64) for d in (dl, dr))
        return row_candidates(
            pl, ol, pr, orr, order, rows, ROW_TOLERANCE, 0.5, self.max_disparity, words_l, words_r
        )

    def process(self, left: np.ndarray, right: np.ndarray) -> StereoFeatures:
        """Stereo features ``w = (u, v, d)`` of one rectified pair, with timings in milliseconds."""
        if left.shape != right.shape or left.ndim != 2:
            raise ValueError(
                f"left and right must be 2-D grey images of one size; got {left.shape}, {right.shape}"
            )
        watch = Stopwatch()
        with watch("detect"):
            right_side = self._worker.submit(self._detect_and_describe, 1, right)
            pl, ol, dl = self._detect_and_describe(0, left)
            pr, orr, dr = right_side.result()
        watch.ms["describe"] = 0.0  # described with detection, in one OpenCV call per image
        with watch("stereo_match"):
            w, descriptors = self._stereo_match(left, right, (pl, ol, dl), (pr, orr, dr))
        return StereoFeatures(w, descriptors, watch.ms, left)

    def _stereo_match(self, left, right, left_features, right_features) -> tuple[np.ndarray, np.ndarray]:
        """``w = (u, v, d)`` and descriptors of the left features matched along rows, sub-pixel."""
        (pl, ol, dl), (pr, orr, dr) = left_features, right_features
        if len(pl) == 0 or len(pr) == 0:
            return np.zeros((0, 3)), np.zeros((0, 32), np.uint8)
        ia, ib, dist = self._row_candidates(pl, ol, dl, pr, orr, dr)
        a, b, _ = best_matches(ia, ib, dist, len(pl), len(pr), max_distance=MAX_HAMMING, ratio=RATIO)
        u, v = pl[a, 0].astype(float), pl[a, 1].astype(float)
        d = subpixel_disparity(left, right, u, v, (pl[a, 0] - pr[b, 0]).astype(float), DISPARITY_SEARCH)
        keep = d > 0.3
        return np.column_stack([u, v, d])[keep], dl[a][keep]
