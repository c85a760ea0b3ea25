"""[Yuan]'s visual odometer (section II): ORB landmarks, motion-model matching, PnP with
RANSAC, and a local map of key frames.

* Landmarks: ORB features placed in 3-D by our stereo pair (the paper's Kinect), compared by
  Hamming distance (eq. 1).
* Matching: brute force at the start and after a loss; else the velocity (eq. 2) predicts the
  pose (eq. 3) and each projected map landmark (eq. 4-5) is matched within ``SEARCH_RADIUS``.
* The local map drops a key frame when fewer than ``MIN_SEEN_RATIO`` of its landmarks project
  into the image (eq. 6) within ``VIEW_LIMIT`` of its viewing ray (eq. 7, which as printed
  compares a world-frame vector with a camera-frame one).

Poses are camera-to-world 4x4 matrices in the first camera's frame (KITTI convention).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import cv2
import numpy as np

from vo_lib.geometry import rigid_matrix
from vo_lib.stereo_vo.baselines import cross_checked_matches
from vo_lib.stereo_vo.features import StereoFrontEnd, best_matches, hamming

SEARCH_RADIUS = 15.0  # pixels around the predicted position (eq. 5)
MAX_KEYFRAMES = 5
MIN_SEEN_RATIO = 0.3
VIEW_LIMIT = math.radians(45.0)
MIN_INLIERS = 20
REPROJECTION_THRESHOLD = 2.0  # pixels
NEW_KEYFRAME_TRACKED = 0.6  # add a key frame when fewer than this share of features is tracked
NEW_KEYFRAME_DISTANCE = 0.5  # ... or when the camera moved this far from the newest key frame, metres
#: [Yuan], Table I: the paper's visual odometer's deviation per axis, metres (mean, median, std,
#: max), and its time per frame, ms (mean, median, std).
PAPER_TABLE1 = {"X": (0.050, 0.041, 0.042, 0.149), "Y": (0.045, 0.035, 0.036, 0.130), "ms": (40.3, 41, 6.2)}


@dataclass
class KeyFrame:
    """A key frame: its camera-to-world pose, landmarks (world) and their descriptors."""

    pose: np.ndarray
    points: np.ndarray
    descriptors: np.ndarray

    @property
    def centre(self) -> np.ndarray:
        return self.pose[:3, 3]


@dataclass
class PnpStep:
    """One frame: matches used, PnP inliers, whether the frame was matched by brute force."""

    matches: int
    inliers: int
    brute_force: bool
    lost: bool
    keyframes: int


class PnpVisualOdometry:
    """Frame-by-frame 6-DoF visual odometry of [Yuan] on a rectified stereo pair."""

    def __init__(self, camera):
        self.camera = camera
        self.front_end = StereoFrontEnd(camera)
        self.pose = np.eye(4)
        self.velocity = np.eye(4)
        self.keyframes: list[KeyFrame] = []
        self.lost = True
        self.steps: list[PnpStep] = []

    # ------------------------------------------------------------------ the local map
    def _project(self, points_w: np.ndarray, pose: np.ndarray):
        """Pixels of world points seen from camera pose ``pose`` (eq. 4-6), and their depth."""
        T_cw = np.linalg.inv(pose)
        pc = points_w @ T_cw[:3, :3].T + T_cw[:3, 3]
        z = pc[:, 2]
        safe = np.where(z > 1e-6, z, 1e-6)
        u = self.camera.fx * pc[:, 0] / safe + self.camera.cx
        v = self.camera.fy * pc[:, 1] / safe + self.camera.cy
        return u, v, z

    def properly_observed(self, keyframe: KeyFrame, pose: np.ndarray) -> np.ndarray:
        """Eq. 6-7: landmarks of ``keyframe`` inside the current image and seen within
        ``VIEW_LIMIT`` of the key frame's viewing direction."""
        u, v, z = self._project(keyframe.points, pose)
        inside = (z > 0) & (u >= 0) & (u < self.camera.width) & (v >= 0) & (v < self.camera.height)
        ray_now = keyframe.points - pose[:3, 3]
        ray_then = keyframe.points - keyframe.centre
        cos = np.einsum("ij,ij->i", ray_now, ray_then) / (
            np.linalg.norm(ray_now, axis=1) * np.linalg.norm(ray_then, axis=1) + 1e-12
        )
        return inside & (cos >= math.cos(VIEW_LIMIT))

    def _cull(self) -> None:
        keep = [
            k
            for i, k in enumerate(self.keyframes)
            if i == len(self.keyframes) - 1 or self.properly_observed(k, self.pose).mean() >= MIN_SEEN_RATIO
        ]
        self.keyframes = keep[-MAX_KEYFRAMES:]

    # ------------------------------------------------------------------ matching
    def _match_guided(self, points_w, desc_w, feats, prediction):
        """Motion-model matching (eq. 4-5): each landmark projected with the prediction, to the
        nearest feature by Hamming distance within ``SEARCH_RADIUS`` pixels (ratio, mutual tests)."""
        u, v, z = self._project(points_w, prediction)
        r = SEARCH_RADIUS
        du = feats.w[None, :, 0] - u[:, None]
        dv = feats.w[None, :, 1] - v[:, None]
        ia, ib = np.nonzero((np.abs(du) <= r) & (np.abs(dv) <= r) & (z[:, None] > 0))
        dist = hamming(desc_w[ia], feats.descriptors[ib])
        a, b, _ = best_matches(ia, ib, dist, len(points_w), len(feats))
        return a, b

    # ------------------------------------------------------------------ one frame
    def predicted_pose(self) -> np.ndarray:
        """Eq. 2-3: the last motion repeated (the paper's ``T_curr T_prev^-1`` on the left is our
        ``T_prev^-1 T_curr`` on the right)."""
        return self.pose @ self.velocity

    def process(self, left: np.ndarray, right: np.ndarray) -> np.ndarray:
        """Track one stereo pair; returns the camera-to-world pose of this frame."""
        feats = self.front_end.process(left, right)
        points_c = self.camera.backproject(feats.w) if len(feats) else np.zeros((0, 3))
        if not self.keyframes:
            self.keyframes.append(KeyFrame(self.pose.copy(), points_c.copy(), feats.descriptors.copy()))
            self.lost = False
            self.steps.append(PnpStep(0, 0, False, False, 1))
            return self.pose.copy()
        prediction = self.predicted_pose()  # eq. 2-3
        points_w = np.vstack([k.points for k in self.keyframes])
        desc_w = np.vstack([k.descriptors for k in self.keyframes])
        brute = self.lost
        a, b = (  # every landmark against every feature, or motion-model matching
            cross_checked_matches(desc_w, feats.descriptors)
            if brute
            else self._match_guided(points_w, desc_w, feats, prediction)
        )
        inliers = 0
        new_pose = prediction
        if len(a) >= MIN_INLIERS:
            T_cw = np.linalg.inv(prediction)
            rvec, _ = cv2.Rodrigues(T_cw[:3, :3])
            tvec = T_cw[:3, 3].reshape(3, 1).copy()
            world, pixels = points_w[a].astype(np.float64), feats.w[b, :2].astype(np.float64)
            cv2.setRNGSeed(0)  # RANSAC's draws: the same poses on every run
            ok, rvec, tvec, idx = cv2.solvePnPRansac(
                world,
                pixels,
                self.camera.K,
                None,
                rvec,
                tvec,
                useExtrinsicGuess=not brute,
                reprojectionError=REPROJECTION_THRESHOLD,
            )
            if ok and idx is not None and len(idx) >= MIN_INLIERS:
                inliers = len(idx)
                sel = idx.ravel()
                rvec, tvec = cv2.solvePnPRefineLM(world[sel], pixels[sel], self.camera.K, None, rvec, tvec)
                new_pose = np.linalg.inv(rigid_matrix(cv2.Rodrigues(rvec)[0], tvec.ravel()))
        self.lost = inliers == 0
        self.velocity = np.linalg.inv(self.pose) @ new_pose if not self.lost else self.velocity
        self.pose = new_pose
        moved = np.linalg.norm(self.pose[:3, 3] - self.keyframes[-1].centre)
        if not self.lost and (inliers < NEW_KEYFRAME_TRACKED * len(feats) or moved > NEW_KEYFRAME_DISTANCE):
            pw = points_c @ self.pose[:3, :3].T + self.pose[:3, 3]
            self.keyframes.append(KeyFrame(self.pose.copy(), pw, feats.descriptors.copy()))
        self._cull()
        self.steps.append(PnpStep(len(a), inliers, brute, self.lost, len(self.keyframes)))
        return self.pose.copy()


def run_pnp_odometry(camera, frames):
    """Run over ``(left, right, ...)`` frames: ``(camera poses (N, 4, 4), seconds of each
    :meth:`PnpVisualOdometry.process`, odometer)``."""
    vo = PnpVisualOdometry(camera)
    poses, seconds = [], []
    for f in frames:
        t0 = time.perf_counter()
        poses.append(vo.process(f[0], f[1]))
        seconds.append(time.perf_counter() - t0)
    return np.stack(poses), np.array(seconds), vo
