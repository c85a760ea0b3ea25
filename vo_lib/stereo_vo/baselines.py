"""General-purpose motion estimators, run on the same matches as the 1-point method, and the
plain OpenCV stereo odometry that is the yardstick on real images.

* :func:`rigid_ransac`: 3-point RANSAC on 3-D to 3-D matches (Kabsch/Umeyama fit, 6 DoF).
* :func:`pnp_ransac`: OpenCV ``solvePnPRansac``, previous 3-D points to current pixels (6 DoF).
* :func:`essential_ransac`: OpenCV's 5-point essential-matrix RANSAC (no scale).

Each returns a :class:`MotionEstimate` with the ``theta`` and ``rho`` of the closest planar
circular motion. :class:`PnpStereoOdometry` is the usual first OpenCV stereo odometry: ORB in both
images, cross-checked Hamming matches (on the same rows for stereo, to the next left image in
time) and ``cv2.solvePnPRansac``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import cv2
import numpy as np

from vo_lib.camera import StereoCamera
from vo_lib.geometry import rigid_matrix
from vo_lib.stereo_vo.circular_motion import circular_motion_from_transform
from vo_lib.stereo_vo.ransac import DEFAULT_PARAMS, hypotheses_needed

#: Pixels, in (u, v, d) for the rigid fit and (u, v) for PnP: ~99 % of two noisy views.
REPROJECTION_THRESHOLD = 3.0
MAX_ITERATIONS = 1000
#: The PnP stereo odometry: ORB features per image, stereo row tolerance (pixels), and
#: ``solvePnPRansac``'s inlier threshold (pixels) and hypotheses.
PNP_FEATURES = 3000
PNP_ROW_TOLERANCE = 1.5
PNP_REPROJECTION_PIXELS = 1.0
PNP_ITERATIONS = 200


@dataclass
class MotionEstimate:
    """A rigid motion ``P' = R P + t`` with its planar ``(theta, rho)`` and inlier mask."""

    R: np.ndarray
    t: np.ndarray
    inliers: np.ndarray
    success: bool

    @property
    def transform(self) -> np.ndarray:
        return rigid_matrix(self.R, self.t)

    @property
    def theta(self) -> float:
        return circular_motion_from_transform(self.transform)[0]

    @property
    def rho(self) -> float:
        return circular_motion_from_transform(self.transform)[1]


def kabsch(P: np.ndarray, Q: np.ndarray, weights=None) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares rotation and translation with ``Q ~ R P + t``, batched over leading axes;
    ``weights`` (one per point) weigh the squared residuals."""
    wts = np.ones(P.shape[:-1]) if weights is None else np.broadcast_to(weights, P.shape[:-1])
    wn = (wts / wts.sum(axis=-1, keepdims=True))[..., None]
    mp, mq = (wn * P).sum(axis=-2, keepdims=True), (wn * Q).sum(axis=-2, keepdims=True)
    H = np.swapaxes(wn * (P - mp), -1, -2) @ (Q - mq)
    U, _, Vt = np.linalg.svd(H)
    D = np.ones(H.shape[:-1])
    D[..., -1] = np.sign(np.linalg.det(np.swapaxes(Vt, -1, -2) @ np.swapaxes(U, -1, -2)))
    R = np.swapaxes(Vt, -1, -2) @ (D[..., :, None] * np.swapaxes(U, -1, -2))
    t = mq[..., 0, :] - (R @ mp[..., 0, :, None])[..., 0]
    return R, t


def _reprojection_error(P, w_curr, R, t, camera):
    """Distance in (u, v, d) between ``w_curr`` and the projection of ``R P + t``; batched over R, t."""
    Q = P @ np.swapaxes(R, -1, -2) + t[..., None, :]
    z = np.where(Q[..., 2] > 1e-6, Q[..., 2], np.nan)
    du = camera.cx + camera.fx * Q[..., 0] / z - w_curr[:, 0]
    dv = camera.cy + camera.fy * Q[..., 1] / z - w_curr[:, 1]
    dd = camera.fx * camera.baseline / z - w_curr[:, 2]
    return np.nan_to_num(np.sqrt(du * du + dv * dv + dd * dd), nan=np.inf)


def rigid_ransac(w_prev, w_curr, camera: StereoCamera, rng=None) -> MotionEstimate:
    """3-point RANSAC on back-projected points; hypotheses scored in batches, refit on all inliers."""
    rng = np.random.default_rng(rng)
    a, b = np.asarray(w_prev, float), np.asarray(w_curr, float)
    P, Q = camera.backproject(a), camera.backproject(b)
    n = len(P)
    best_count, best = -1, None
    threshold, confidence = REPROJECTION_THRESHOLD, DEFAULT_PARAMS.confidence
    tried, limit = 0, min(hypotheses_needed(0.5, confidence, 3), MAX_ITERATIONS)
    while tried < limit:
        k = limit - tried
        idx = np.stack([rng.choice(n, 3, replace=False) for _ in range(k)])
        R, t = kabsch(P[idx], Q[idx])
        counts = (_reprojection_error(P, b, R, t, camera) <= threshold).sum(axis=1)
        j = int(np.argmax(counts))
        if counts[j] > best_count:
            best_count, best = int(counts[j]), (R[j], t[j])
        tried += k
        limit = min(hypotheses_needed(max(best_count, 1) / n, confidence, 3), MAX_ITERATIONS)
    inliers = _reprojection_error(P, b, best[0], best[1], camera) <= threshold
    if inliers.sum() >= 3:
        # refit on all inliers, each weighted by its inverse depth variance (z^2 grows as 1/d^4)
        weights = 1.0 / (1.0 / a[inliers, 2] ** 4 + 1.0 / b[inliers, 2] ** 4)
        R, t = kabsch(P[inliers], Q[inliers], weights)
        inliers = _reprojection_error(P, b, R, t, camera) <= threshold
        best = (R, t)
    return MotionEstimate(best[0], best[1], inliers, bool(inliers.sum() >= 3))


def pnp_ransac(w_prev, w_curr, camera: StereoCamera, seed: int = 0) -> MotionEstimate:
    """OpenCV ``solvePnPRansac`` (EPnP), previous 3-D points to current pixels, refined on the inliers."""
    a, b = np.asarray(w_prev, float), np.asarray(w_curr, float)
    P = camera.backproject(a)
    cv2.setRNGSeed(seed)
    ok, rvec, tvec, idx = cv2.solvePnPRansac(
        P.astype(np.float64),
        b[:, :2].astype(np.float64),
        camera.K,
        None,
        iterationsCount=100,
        reprojectionError=REPROJECTION_THRESHOLD,
        confidence=DEFAULT_PARAMS.confidence,
        flags=cv2.SOLVEPNP_EPNP,
    )
    inliers = np.zeros(len(a), bool)
    if not ok or idx is None:
        return MotionEstimate(np.eye(3), np.zeros(3), inliers, False)
    inliers[idx.ravel()] = True
    rvec, tvec = cv2.solvePnPRefineLM(P[inliers], b[inliers, :2], camera.K, None, rvec, tvec)
    return MotionEstimate(cv2.Rodrigues(rvec)[0], tvec.ravel(), inliers, True)


def essential_ransac(w_prev, w_curr, camera: StereoCamera, seed: int = 0) -> MotionEstimate:
    """OpenCV 5-point essential-matrix RANSAC (1 pixel) and ``recoverPose``: rotation and a unit
    translation."""
    a, b = np.asarray(w_prev, float), np.asarray(w_curr, float)
    cv2.setRNGSeed(seed)
    E, mask = cv2.findEssentialMat(a[:, :2], b[:, :2], camera.K, cv2.RANSAC, DEFAULT_PARAMS.confidence, 1.0)
    inliers = np.zeros(len(a), bool)
    if E is None or E.shape != (3, 3):
        return MotionEstimate(np.eye(3), np.zeros(3), inliers, False)
    _, R, t, mask = cv2.recoverPose(E, a[:, :2], b[:, :2], camera.K, mask=mask)
    inliers = mask.ravel() > 0
    return MotionEstimate(R, t.ravel(), inliers, True)


@dataclass
class PnpRun:
    """Camera poses ``(N, 4, 4)`` in frame 0's camera, milliseconds per frame, inliers per frame."""

    camera_poses: np.ndarray
    milliseconds: np.ndarray
    inliers: np.ndarray


def cross_checked_matches(des_a: np.ndarray, des_b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Index pairs ``(i, j)`` of OpenCV's cross-checked brute-force Hamming matcher."""
    matches = cv2.BFMatcher(cv2.NORM_HAMMING, crossCheck=True).match(des_a, des_b)
    return np.array([m.queryIdx for m in matches], int), np.array([m.trainIdx for m in matches], int)


class PnpStereoOdometry:
    """Frame-to-frame stereo odometry with ORB and ``solvePnPRansac``."""

    def __init__(self, camera: StereoCamera):
        self.camera = camera
        self.orb = cv2.ORB_create(PNP_FEATURES)
        self.previous = None
        self.pose = np.eye(4)

    def _stereo(self, left, right):
        kl, dl = self.orb.detectAndCompute(left, None)
        kr, dr = self.orb.detectAndCompute(right, None)
        if dl is None or dr is None:
            return np.zeros((0, 2)), np.zeros((0, 32), np.uint8), np.zeros((0, 3))
        pl, pr = cv2.KeyPoint_convert(kl).reshape(-1, 2), cv2.KeyPoint_convert(kr).reshape(-1, 2)
        i, j = cross_checked_matches(dl, dr)
        d = pl[i, 0] - pr[j, 0]
        ok = (np.abs(pl[i, 1] - pr[j, 1]) < PNP_ROW_TOLERANCE) & (d > 0.5)
        i, d = i[ok], d[ok]
        points = self.camera.backproject(np.column_stack([pl[i], d]))
        return pl[i], dl[i], points

    def process(self, left: np.ndarray, right: np.ndarray) -> tuple[np.ndarray, int]:
        """Camera pose of this frame in frame 0's camera, and the PnP inlier count."""
        current = self._stereo(left, right)
        inliers = 0
        if self.previous is not None and len(self.previous[1]) and len(current[1]):
            i, j = cross_checked_matches(self.previous[1], current[1])
            if len(i) >= 6:
                ok, rvec, tvec, idx = cv2.solvePnPRansac(
                    self.previous[2][i].astype(np.float64),
                    current[0][j].astype(np.float64),
                    self.camera.K,
                    None,
                    iterationsCount=PNP_ITERATIONS,
                    reprojectionError=PNP_REPROJECTION_PIXELS,
                    confidence=DEFAULT_PARAMS.confidence,
                )
                if ok and idx is not None:
                    T = rigid_matrix(cv2.Rodrigues(rvec)[0], tvec.ravel())
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
