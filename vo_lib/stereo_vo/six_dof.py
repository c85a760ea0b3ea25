"""The car's motion model as a pipeline part: 1-point RANSAC as the outlier filter, then 6 DoF.

The steps are the paper's (Fig. 3, ``pipeline``); the model of the motion between frames differs:

1. **prediction**: the last frame's motion since the reference, one measured 6-DoF motion per frame
   further (constant velocity); with odometry, its planar part (yaw and ground-plane translation of
   the vehicle) is the Kalman filter's;
2. **temporal matching** in windows around each feature's predicted position; a window grows when
   the prediction proves poor (braking, the start of a turn), and the matcher falls back to every
   pair, so no frame goes unmatched while the images overlap;
3. **1-point RANSAC** (eq. 14, 17) as the outlier filter. The circular-motion model holds for a
   camera above the turning axis; a car's camera is a metre ahead of it and slides sideways in a
   turn (7 cm in a 4 deg frame: pixels at 10 m). So each stereo match is triangulated, moved into a
   *virtual camera on the turning axis* and projected again (:func:`turning_axis_view`), where the
   model is exact; where the vehicle pitched or rolled, a general 3-point RANSAC stands in
   (:meth:`SixDofMotion.hypothesis`);
4. **6-DoF refinement** of the inliers on reprojection errors in both images
   (:mod:`~vo_lib.stereo_vo.rigid_motion`), which chooses the inliers again: within a pixel, or,
   on a frame's last attempt that keeps too few, within ``LAST_RESORT_GATE``;
5. **Kalman update** of the vehicle's *planar* pose ``(x, y, yaw)``: the refined camera motion is
   carried into the vehicle frame through the mount (so a camera ahead of the axis does not read a
   turn as a sideways step), and its ``(theta, rho)`` and sideways deviation from the chord correct
   the filter. The crawler's zero-sideways constraint is not imposed: a car's axis and frame are
   known only to a few tenths of a degree, and 0.4 deg of misalignment is 0.7 m of drift per 100 m.

The filter stays planar because the odometry it fuses measures only the planar motion, as in the
paper's filter (eq. 1-11); height, pitch and roll come from the vision alone. Each frame's 6-DoF
camera pose is its reference frame's composed with the motion since then: planar part from the
filter, the rest from the vision (on a frame without vision, from the prediction).
"""

from __future__ import annotations

import math
import time

import numpy as np

from vo_lib.camera import StereoCamera
from vo_lib.geometry import camera_mount, rigid_inverse, yaw_matrix
from vo_lib.stereo_vo.circular_motion import motion_transform
from vo_lib.stereo_vo.config import PipelineConfig
from vo_lib.stereo_vo.frames import Stopwatch
from vo_lib.stereo_vo.kalman import VoKalmanFilter, chord_measurement
from vo_lib.stereo_vo.parts import Estimate, Prediction
from vo_lib.stereo_vo.ransac import one_point_ransac
from vo_lib.stereo_vo.rigid_motion import (
    INLIER_PIXELS,
    general_ransac,
    refine_rigid_motion,
    rotation_matrix,
    scaled_motion,
)
from vo_lib.stereo_vo.temporal import match_features, predict_features, track_subpixel

#: Window half-width around a predicted position: a floor, plus a share of the predicted image
#: motion (a near point moving 100 px between frames is predicted less well than a far one).
WINDOW_PIXELS = 12.0
WINDOW_FLOW_FRACTION = 0.15
#: The disparity window: a floor plus a share of the predicted disparity (pixels).
DISPARITY_FLOOR = 2.0
DISPARITY_WINDOW = 0.3
PREDICTED_RATIO = 0.9  # ratio test of the matching (pyramid features, larger motions)
#: Inlier gate of the refinement (pixels) when the usual one leaves too few inliers on a frame's
#: last attempt; a frame judged with it is flagged only if it still leaves too few.
LAST_RESORT_GATE = 2.0 * INLIER_PIXELS
#: Good frames the recent median needs; before, this many times ``min_inliers`` matches are expected.
RETRY_HISTORY = 3
EXPECTED_FACTOR = 4


def vehicle_increment(T_cam: np.ndarray, mount: np.ndarray) -> np.ndarray:
    """``(dx, dy, dyaw)`` of the vehicle, in its previous frame, for a camera motion ``T_cam``
    (``T_curr_from_prev`` of the camera mounted at ``mount`` = ``T_vehicle_camera``)."""
    V = mount @ rigid_inverse(T_cam) @ rigid_inverse(mount)
    return np.array([V[0, 3], V[1, 3], math.atan2(V[1, 0], V[0, 0])])


def with_planar_increment(T_cam: np.ndarray, mount: np.ndarray, increment) -> np.ndarray:
    """``T_cam`` with the vehicle's yaw and ground-plane translation replaced by ``increment``;
    height, pitch and roll are kept."""
    inverse = rigid_inverse(mount)
    V = mount @ rigid_inverse(T_cam) @ inverse
    yaw = math.atan2(V[1, 0], V[0, 0])
    dx, dy, dyaw = (float(v) for v in increment)
    V[:3, :3] = yaw_matrix(dyaw - yaw) @ V[:3, :3]
    V[0, 3], V[1, 3] = dx, dy
    return rigid_inverse(inverse @ V @ mount)


def turning_axis_transform(mount: np.ndarray) -> np.ndarray:
    """4x4 map from the camera's frame to a virtual camera's on the vehicle's turning axis.

    The virtual camera has the real one's height, looks along the vehicle's x axis with its y axis
    down the vehicle's z axis (``camera_mount(0, height, 0)``), so that a planar motion of the
    vehicle is exactly the circular motion of eq. 15 in its frame.
    """
    axis_camera = camera_mount(0.0, float(mount[2, 3]), 0.0)
    return rigid_inverse(axis_camera) @ np.asarray(mount, float)


def turning_axis_view(w: np.ndarray, camera: StereoCamera, to_axis: np.ndarray) -> np.ndarray:
    """Matches ``(u, v, d)`` as the virtual camera of :func:`turning_axis_transform` sees them
    (same intrinsics): triangulate, move, project."""
    X = camera.backproject(w)
    return camera.project(X @ to_axis[:3, :3].T + to_axis[:3, 3])


#: The central differences of :func:`chord_covariance`: each motion component moved by ``+h``
#: (rows 0-5), then by ``-h`` (rows 6-11); their rotations ``exp([step[:3]]x)``, the same for
#: every frame, are computed once, at import.
COVARIANCE_STEP = 1e-6
_STEPS = np.vstack([np.diag([COVARIANCE_STEP] * 6), np.diag([-COVARIANCE_STEP] * 6)])
_STEP_ROTATIONS = np.stack([rotation_matrix(step[:3]) for step in _STEPS])


def chord_covariance(T_cam: np.ndarray, covariance6: np.ndarray, mount: np.ndarray) -> np.ndarray:
    """3x3 covariance of the vehicle's ``(theta, rho, sideways)``, propagated from the 6x6
    covariance of the camera motion (rotation vector on the left, translation) by central
    differences: the twelve moved motions go through :func:`vehicle_increment`'s products as one
    stack of 4x4 matrices."""
    moved = np.zeros((12, 4, 4))  # R <- exp([dw]x) R, t <- exp([dw]x) t + dt
    moved[:, :3, :3] = _STEP_ROTATIONS @ T_cam[:3, :3]
    moved[:, :3, 3] = _STEP_ROTATIONS @ T_cam[:3, 3] + _STEPS[:, 3:]
    V = mount @ rigid_inverse(moved) @ rigid_inverse(mount)
    z = np.array([chord_measurement((M[0, 3], M[1, 3], math.atan2(M[1, 0], M[0, 0]))) for M in V])
    J = ((z[:6] - z[6:]) / (2 * COVARIANCE_STEP)).T
    return J @ covariance6 @ J.T


def windows(predicted: np.ndarray, square) -> np.ndarray:
    """Half-widths ``(N, 3)`` of the matching windows around predicted ``(u, v, d)``: ``square``
    pixels in u and v, and ``DISPARITY_FLOOR + DISPARITY_WINDOW * d`` in disparity."""
    square = np.broadcast_to(np.asarray(square, float), (len(predicted),))
    return np.column_stack([square, square, DISPARITY_FLOOR + DISPARITY_WINDOW * predicted[:, 2]])


class SixDofMotion:
    """A car's camera: 1-point RANSAC from the turning axis as the outlier filter, then 6 DoF.
    ``mount`` is ``T_vehicle_camera``; the filter's planar pose is the vehicle's."""

    def __init__(self, camera: StereoCamera, mount: np.ndarray, config: PipelineConfig):
        self.camera = camera
        self.config = config
        self.mount = np.asarray(mount, float)
        self.covariance_scale = np.asarray(config.vo_covariance_scale, float)
        self.to_axis = turning_axis_transform(self.mount)
        self.from_axis = rigid_inverse(self.to_axis)
        self.reference_pose = np.eye(4)  # camera pose of the reference frame, in frame 0's
        self.camera_pose = np.eye(4)
        self.velocity: np.ndarray | None = None  # camera motion per frame interval, T_curr_from_prev
        self.since_reference = np.eye(4)  # camera motion from the reference to the last frame

    # ------------------------------------------------------------------ prediction
    def predict(self, kf: VoKalmanFilter, steps: int = 1) -> Prediction:
        """Camera motion from the reference to this frame: the last frame's (measured or
        predicted, so frames measured against an older reference keep the motion they found),
        ``steps`` frame intervals of constant velocity further, with the planar part from the
        filter where odometry moved it (else the filter's predicted pose is moved to it); nothing
        while neither velocity nor odometry is known."""
        if self.velocity is None and not kf.flags.odometry:
            return Prediction(kf.motion_prior(), False)
        step = np.eye(4) if self.velocity is None else np.linalg.matrix_power(self.velocity, steps)
        motion = step @ self.since_reference
        if kf.flags.odometry:
            motion = with_planar_increment(motion, self.mount, kf.increment)
        else:  # the filter's planar prediction is this one's
            kf.predict_increment(vehicle_increment(motion, self.mount))
        return Prediction(kf.motion_prior(), True, motion)

    def match(self, reference, features, prediction: Prediction, recent):
        if prediction.motion is None:
            brute = match_features(reference, features, ratio=PREDICTED_RATIO)
            return self.tracked(reference, features, brute)
        pred, _ = predict_features(reference.w, self.camera, prediction.motion)
        flow = np.linalg.norm(pred[:, :2] - reference.w[:, :2], axis=1)
        square = WINDOW_PIXELS + WINDOW_FLOW_FRACTION * np.nan_to_num(flow, nan=0.0)
        matches = match_features(reference, features, pred, windows(pred, square), PREDICTED_RATIO)
        min_inliers = self.config.min_inliers
        expected = np.median(recent) if len(recent) >= RETRY_HISTORY else EXPECTED_FACTOR * min_inliers
        if len(matches) < self.config.retry_fraction * expected:
            radius = windows(pred, self.config.retry_widening * square)
            wider = match_features(reference, features, pred, radius, PREDICTED_RATIO)
            matches = wider if len(wider) > len(matches) else matches
        if len(matches) < min_inliers:  # the prediction is lost: compare every pair
            brute = match_features(reference, features, ratio=PREDICTED_RATIO)
            matches = brute if len(brute) > len(matches) else matches
        return self.tracked(reference, features, matches)

    def tracked(self, reference, features, matches):
        """``matches`` with the current positions tracked to sub-pixel (:func:`.track_subpixel`)
        where the preset asks for it and both images are known."""
        if not self.config.subpixel_tracking or reference.image is None or features.image is None:
            return matches
        t0 = time.perf_counter()
        matches.w_curr = track_subpixel(reference.image, features.image, matches.w_prev, matches.w_curr)
        ms = (time.perf_counter() - t0) * 1e3
        matches.timings["temporal_match"] = matches.timings.get("temporal_match", 0.0) + ms
        return matches

    # ------------------------------------------------------------------ estimation
    def hypothesis(self, w_prev, w_curr, T_pred, rng):
        """The outlier filter: ``(motion guess, inlier mask or None, inlier ratio)`` of matches.

        1-point RANSAC on the matches seen from the turning axis (eq. 14-17); where it keeps fewer
        than ``min_inlier_ratio`` (the vehicle pitched or rolled, or most matches are wrong), the
        better of it and a general 3-point RANSAC. Without ``planar_hypotheses`` (a body free in
        six degrees of freedom) the general one, and 1-point RANSAC only where it finds nothing.
        """
        if not self.config.planar_hypotheses:
            general = general_ransac(w_prev, w_curr, self.camera, int(rng.integers(2**31)))
            if general is not None:
                return general[0], general[1], float(general[1].mean())
        seen_from_axis = (turning_axis_view(w, self.camera, self.to_axis) for w in (w_prev, w_curr))
        est = one_point_ransac(*seen_from_axis, self.camera, rng=rng, params=self.config.ransac)
        ratio = float(est.inliers.mean()) if est.success else 0.0
        if est.success:
            # the virtual camera's motion, seen from the real camera
            guess, start = self.from_axis @ motion_transform(est.theta, est.rho) @ self.to_axis, est.inliers
        else:
            guess, start = (np.eye(4) if T_pred is None else T_pred), None
        if ratio < self.config.min_inlier_ratio:
            general = general_ransac(w_prev, w_curr, self.camera, int(rng.integers(2**31)))
            if general is not None and general[1].mean() > ratio:
                guess, start = general
                ratio = float(start.mean())
        return guess, start, ratio

    def estimate(self, matches, prediction: Prediction, rng) -> Estimate:
        """The hypothesis, refined in 6 DoF; ``z = (theta, rho, sideways)`` of the vehicle."""
        guess, start, ratio = self.hypothesis(matches.w_prev, matches.w_curr, prediction.motion, rng)
        watch = Stopwatch()
        with watch("refinement"):
            motion = refine_rigid_motion(matches.w_prev, matches.w_curr, self.camera, guess, start)
            if not motion.success and prediction.motion is None:
                # the frame's last attempt, matched without windows: in a fast turn, blur can
                # leave fewer than MIN_INLIERS matches within a pixel of any motion
                wide = refine_rigid_motion(
                    matches.w_prev, matches.w_curr, self.camera, guess, start, gate=LAST_RESORT_GATE
                )
                motion = wide if wide.success else motion
        T = motion.matrix
        z = chord_measurement(vehicle_increment(T, self.mount))
        covariance = np.full((3, 3), np.inf)  # a failed refinement measures nothing
        if motion.success:
            covariance = self.covariance_scale * chord_covariance(T, motion.covariance, self.mount)
        inliers, ransac_inliers = int(motion.inliers.sum()), int(round(ratio * len(matches)))
        return Estimate(motion.success, z, covariance, inliers, ratio, ransac_inliers, T, watch.ms)

    # ------------------------------------------------------------------ poses
    def place(self, kf: VoKalmanFilter, estimate: Estimate | None, prediction: Prediction) -> None:
        """The camera pose: the reference's, composed with the motion since it: the vision's with
        the filter's planar part, or, when the vision was not used, the prediction's (or none)."""
        if estimate is not None:
            fused = with_planar_increment(estimate.motion, self.mount, kf.increment)
        elif prediction.motion is not None:
            fused = prediction.motion
        else:
            fused = with_planar_increment(np.eye(4), self.mount, kf.increment)
        self.camera_pose = self.reference_pose @ np.linalg.inv(fused)
        self.since_reference = fused

    def commit(self, kf: VoKalmanFilter, estimate: Estimate | None, gap: int) -> None:
        """A measured motion since the old reference is remembered per frame (constant velocity)."""
        if estimate is not None:
            self.velocity = scaled_motion(self.since_reference, 1.0 / max(gap, 1))
        self.reference_pose = self.camera_pose.copy()
        self.since_reference = np.eye(4)
