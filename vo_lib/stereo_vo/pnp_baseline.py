"""The yardstick on real images: plain OpenCV stereo odometry, frame to frame.

ORB features in both images, stereo matches by brute-force Hamming matching with cross-check on
the same rows, their triangulated points matched to the next left image the same way, and the
motion from ``cv2.solvePnPRansac`` (iterative PnP on reprojection errors in the left image). This
is the usual first stereo odometry one writes with OpenCV; the benchmark and notebook 12 run it
on the same frames as our pipeline, in the same process.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import cv2
import numpy as np

from vo_lib.camera import StereoCamera

FEATURES = 3000
ROW_TOLERANCE = 1.5  # pixels
REPROJECTION_PIXELS = 1.0
ITERATIONS = 200
CONFIDENCE = 0.999


@dataclass
class PnpRun:
    """Camera poses ``(N, 4, 4)`` in frame 0's camera, milliseconds per frame, inliers per frame."""

    camera_poses: np.ndarray
    milliseconds: np.ndarray
    inliers: np.ndarray


class PnpStereoOdometry:
    """Frame-to-frame stereo odometry with ORB and ``solvePnPRansac``."""

    def __init__(self, camera: StereoCamera):
        self.camera = camera
        self.orb = cv2.ORB_create(FEATURES)
        self.matcher = cv2.BFMatcher(cv2.NORM_HAMMING, crossCheck=True)
        self.previous = None
        self.pose = np.eye(4)

    def _stereo(self, left, right):
        kl, dl = self.orb.detectAndCompute(left, None)
        kr, dr = self.orb.detectAndCompute(right, None)
        if dl is None or dr is None:
            return np.zeros((0, 2)), np.zeros((0, 32), np.uint8), np.zeros((0, 3))
        pl, pr = cv2.KeyPoint_convert(kl).reshape(-1, 2), cv2.KeyPoint_convert(kr).reshape(-1, 2)
        m = self.matcher.match(dl, dr)
        i = np.array([x.queryIdx for x in m], int)
        j = np.array([x.trainIdx for x in m], int)
        d = pl[i, 0] - pr[j, 0] if len(m) else np.zeros(0)
        ok = (np.abs(pl[i, 1] - pr[j, 1]) < ROW_TOLERANCE) & (d > 0.5) if len(m) else np.zeros(0, bool)
        i, d = i[ok], d[ok]
        points = self.camera.backproject(np.column_stack([pl[i], d]))
        return pl[i], dl[i], points

    def process(self, left: np.ndarray, right: np.ndarray) -> tuple[np.ndarray, int]:
        """Camera pose of this frame in frame 0's camera, and the PnP inlier count."""
        current = self._stereo(left, right)
        inliers = 0
        if self.previous is not None and len(self.previous[1]) and len(current[1]):
            m = self.matcher.match(self.previous[1], current[1])
            i = np.array([x.queryIdx for x in m], int)
            j = np.array([x.trainIdx for x in m], int)
            if len(m) >= 6:
                ok, rvec, tvec, idx = cv2.solvePnPRansac(
                    self.previous[2][i].astype(np.float64),
                    current[0][j].astype(np.float64),
                    self.camera.K,
                    None,
                    iterationsCount=ITERATIONS,
                    reprojectionError=REPROJECTION_PIXELS,
                    confidence=CONFIDENCE,
                )
                if ok and idx is not None:
                    T = np.eye(4)
                    T[:3, :3], T[:3, 3] = cv2.Rodrigues(rvec)[0], tvec.ravel()
                    self.pose = self.pose @ np.linalg.inv(T)
                    inliers = len(idx)
        self.previous = current
        return self.pose.copy(), inliers


def run_pnp_baseline(sequence, frames: int | None = None, seed: int = 0) -> PnpRun:
    """Run :class:`PnpStereoOdometry` over the first ``frames`` frames of a sequence."""
    cv2.setRNGSeed(seed)  # solvePnPRansac draws from OpenCV's generator
    n = len(sequence) if frames is None else min(int(frames), len(sequence))
    vo = PnpStereoOdometry(sequence.camera)
    poses, ms, inliers = [], [], []
    for k in range(n):
        left, right = sequence.pair(k)
        t0 = time.perf_counter()
        pose, count = vo.process(left, right)
        ms.append((time.perf_counter() - t0) * 1e3)
        poses.append(pose)
        inliers.append(count)
    return PnpRun(np.array(poses), np.array(ms), np.array(inliers))
