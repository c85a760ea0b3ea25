"""Seed 000's pipeline for a camera that moves in six degrees of freedom (a car on a real road).

The steps are those of :mod:`vo_lib.stereo_vo.pipeline` (Fig. 3 of the paper); what changes is
the model of the motion between two frames:

1. **stereo processing** at two scales (:mod:`~vo_lib.stereo_vo.pyramid_features`);
2. **prediction**: the last measured 6-DoF motion, repeated (constant velocity), with its planar
   part (yaw and ground-plane translation of the vehicle) taken from the Kalman filter, which
   moves it with the odometry when the sequence has some;
3. **temporal matching** inside windows around each feature's predicted position; a window grows
   when the prediction proves poor (braking, the start of a turn) and the matcher falls back to
   comparing every pair, so that no frame is left unmatched while the images overlap;
4. **1-point RANSAC** (theta from eq. 14, rho from eq. 17): the outlier filter. The circular-motion
   model holds for a camera above the axis the vehicle turns about; a car's camera is a metre
   ahead of it, and in a turn it also slides sideways by that metre times the turned angle
   (7 cm in a 4 deg frame: several pixels at 10 m, so that the model's gates reject true
   matches). The matches are therefore seen from a *virtual camera on the turning axis*: each
   stereo match is triangulated, moved into that camera's frame through the mount and projected
   again (:func:`turning_axis_view`); the model is exact there, whatever the turn. Where it
   keeps too few matches, the vehicle pitched or rolled between the frames (a bump, the start of
   a slope), and a general 3-point RANSAC (OpenCV's P3P) gives the hypothesis instead;
5. **6-DoF refinement** of the inliers on reprojection errors in both images
   (:mod:`~vo_lib.stereo_vo.rigid_motion`), which also chooses the inliers again;
6. **Kalman update**: the filter keeps the vehicle's *planar* pose, ``(x, y, yaw)`` of the axis it
   turns about; the refined camera motion is carried into the vehicle frame through the camera's
   mount (so a camera a metre ahead of the axis does not read a turn as a sideways step) and its
   ``(theta, rho)`` corrects the filter, as in the planar pipeline, together with the sideways
   deviation from the chord, which the 6-DoF motion measures: the crawler's constraint that it is
   zero is not imposed, because where a car's axis lies and how its frame is aligned are known
   only to a few tenths of a degree, and 0.4 deg of misalignment is 0.7 m of drift per 100 m.
   The rest of the motion (height, pitch, roll), which odometry cannot observe, comes from the
   vision alone.

Why the filter stays planar: the odometry it fuses (tracks, wheels, or speed and yaw rate) measures
only the planar motion, and the paper's filter (eq. 1-11) is planar; a 6-DoF state would carry
three components that nothing but the vision measures, and gain nothing from the filter.

Each frame's 6-DoF camera pose is its reference frame's pose composed with the motion since then,
whose planar part is the filter's and whose other part is the vision's.
"""

from __future__ import annotations

import math
import time
from collections import deque

import numpy as np
from scipy.stats import chi2

from vo_lib.camera import StereoCamera
from vo_lib.geometry import camera_mount, wrap_angle
from vo_lib.models.track_odometry import TrackOdometry
from vo_lib.stereo_vo.circular_motion import motion_matrices
from vo_lib.stereo_vo.kalman import VoKalmanFilter, chord_measurement
from vo_lib.stereo_vo.pipeline import FrameDiagnostics, FrameTimings
from vo_lib.stereo_vo.pyramid_features import PyramidFrontEnd
from vo_lib.stereo_vo.ransac import one_point_ransac
from vo_lib.stereo_vo.rigid_motion import (
    general_ransac,
    predict_features,
    refine_rigid_motion,
    rotation_matrix,
    scaled_motion,
)
from vo_lib.stereo_vo.temporal import match_to_prediction

MIN_FEATURES = 20
MIN_INLIERS = 15
MIN_RANSAC_RATIO = 0.5  # of the temporal matches that 1-point RANSAC keeps
PRIOR_GATE = float(chi2.ppf(0.9999, 2))
#: Consecutive frames the prior gate may reject before the vision is believed over the prediction.
MAX_CONTRADICTIONS = 2
#: Window half-width around a predicted position: a floor, plus a share of the predicted image
#: motion (a near point moving 100 px between frames is predicted less well than a far one).
WINDOW_PIXELS = 12.0
WINDOW_FLOW_FRACTION = 0.15
WIDER = 3.0  # the window grows by this factor when it finds too few matches
RETRY_FRACTION = 0.6  # ...fewer than this fraction of the recent median
RECENT_FRAMES = 10
#: A motion is measured against the reference until it is this large (metres, radians): a
#: standing car keeps its reference, so that it does not drift while it waits.
KEY_DISTANCE = 0.05
KEY_ANGLE = math.radians(1.0)
KEY_MAX_GAP = 10
#: Scale of the least-squares covariance before it enters the filter (the residuals of real
#: matches are neither independent nor Gaussian).
VO_COVARIANCE_SCALE = 2.0**2
#: Sideways motion per metre travelled that wheel odometry cannot see, as process noise: a car's
#: odometry frame is aligned with its direction of travel only to a fraction of a degree, and a
#: tight value lets the odometry's zero sideways motion overrule the vision's heading through
#: their correlation. At 5 % the sideways motion is the vision's.
LATERAL_SIGMA = 0.05
#: Uncertainty (x, y metres; yaw radians) added to the prediction while nothing predicts the motion.
UNKNOWN_MOTION_SIGMA = (10.0, 10.0, 1.0)


def _rz(yaw: float) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rigid_inverse(T: np.ndarray) -> np.ndarray:
    """Inverse of a 4x4 rigid transform: ``(R^T, -R^T t)``."""
    out = np.eye(4)
    out[:3, :3] = T[:3, :3].T
    out[:3, 3] = -T[:3, :3].T @ T[:3, 3]
    return out


def vehicle_increment(T_cam: np.ndarray, mount: np.ndarray) -> np.ndarray:
    """``(dx, dy, dyaw)`` of the vehicle, in its previous frame, for a camera motion ``T_cam``
    (``T_curr_from_prev`` of the camera mounted at ``mount`` = ``T_vehicle_camera``)."""
    V = mount @ rigid_inverse(T_cam) @ rigid_inverse(mount)
    return np.array([V[0, 3], V[1, 3], math.atan2(V[1, 0], V[0, 0])])


def with_planar_increment(T_cam: np.ndarray, mount: np.ndarray, increment) -> np.ndarray:
    """``T_cam`` with the vehicle's yaw and ground-plane translation replaced by ``increment``;
    height, pitch and roll are kept."""
    V = mount @ rigid_inverse(T_cam) @ rigid_inverse(mount)
    yaw = math.atan2(V[1, 0], V[0, 0])
    dx, dy, dyaw = (float(v) for v in increment)
    V[:3, :3] = _rz(dyaw) @ _rz(-yaw) @ V[:3, :3]
    V[0, 3], V[1, 3] = dx, dy
    return rigid_inverse(rigid_inverse(mount) @ V @ mount)


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


def chord_covariance(T_cam: np.ndarray, covariance6: np.ndarray, mount: np.ndarray) -> np.ndarray:
    """3x3 covariance of ``(theta, rho, sideways)`` of the vehicle, propagated from the 6x6
    covariance of the camera motion (rotation vector on the left, translation) by central
    differences."""
    J = np.zeros((3, 6))
    h = 1e-6
    for k in range(6):
        delta = np.zeros(6)
        delta[k] = h
        out = []
        for sign in (1.0, -1.0):
            dR = rotation_matrix(sign * delta[:3])
            T = np.eye(4)
            T[:3, :3] = dR @ T_cam[:3, :3]
            T[:3, 3] = dR @ T_cam[:3, 3] + sign * delta[3:]
            out.append(chord_measurement(vehicle_increment(T, mount)))
        J[:, k] = (out[0] - out[1]) / (2 * h)
    return J @ covariance6 @ J.T


class RigidStereoOdometry:
    """Stereo visual odometry with 1-point RANSAC and a 6-DoF refinement, frame by frame.

    Parameters
    ----------
    camera : StereoCamera
    mount : ndarray, 4x4
        ``T_vehicle_camera``; the filter's planar pose is the vehicle's.
    odometry : TrackOdometry, optional
        Gauge and noise of the odometry, when frames come with wheel or track distances.
    seed : int
        Seed of the RANSAC draws.
    front_end : optional
        Defaults to :class:`~vo_lib.stereo_vo.pyramid_features.PyramidFrontEnd`.
    """

    def __init__(
        self,
        camera: StereoCamera,
        mount: np.ndarray,
        odometry: TrackOdometry | None = None,
        seed: int = 0,
        front_end=None,
    ):
        self.camera = camera
        self.mount = np.asarray(mount, float)
        self.to_axis = turning_axis_transform(self.mount)
        self.front = front_end or PyramidFrontEnd(camera)
        self.kf = VoKalmanFilter(odometry or TrackOdometry(), lateral_sigma=LATERAL_SIGMA)
        self.rng = np.random.default_rng(seed)
        self.reference = None
        self.reference_pose = np.eye(4)  # camera pose of the reference frame, in frame 0's
        self.camera_pose = np.eye(4)
        self.velocity: np.ndarray | None = None  # camera motion per frame, T_curr_from_prev
        self.gap = 0
        self.frame = 0
        self.contradicted = 0  # consecutive frames whose vision contradicted the prediction
        self.recent_matches: deque[int] = deque(maxlen=RECENT_FRAMES)

    # ------------------------------------------------------------------ prediction
    def _predicted_motion(self) -> np.ndarray | None:
        """Camera motion from the reference to this frame: constant velocity, planar part from
        the filter (which used the odometry, if any)."""
        if self.velocity is None and not self.kf.flags.odometry:
            return None
        T = np.eye(4) if self.velocity is None else scaled_motion(self.velocity, self.gap)
        return with_planar_increment(T, self.mount, self.kf.increment)

    def _match(self, features, T_pred):
        if T_pred is None:
            return match_to_prediction(self.reference, features, None)
        pred, _ = predict_features(self.reference.w, self.camera, T_pred)
        flow = np.linalg.norm(pred[:, :2] - self.reference.w[:, :2], axis=1)
        radius = WINDOW_PIXELS + WINDOW_FLOW_FRACTION * np.nan_to_num(flow, nan=0.0)
        matches = match_to_prediction(self.reference, features, pred, radius)
        expected = np.median(self.recent_matches) if len(self.recent_matches) >= 3 else 4 * MIN_INLIERS
        if len(matches) < RETRY_FRACTION * expected:
            wider = match_to_prediction(self.reference, features, pred, WIDER * radius)
            matches = wider if len(wider) > len(matches) else matches
        if len(matches) < MIN_INLIERS:  # the prediction is lost: compare every pair
            brute = match_to_prediction(self.reference, features, None)
            matches = brute if len(brute) > len(matches) else matches
        return matches

    def hypothesis(self, w_prev, w_curr, T_pred):
        """The outlier filter: ``(motion guess, inlier mask or None, inlier ratio)`` of matches.

        1-point RANSAC on the matches seen from the turning axis (eq. 14-17); when it keeps fewer
        than :data:`MIN_RANSAC_RATIO` of them (the vehicle pitched or rolled, or most matches
        are wrong) a general 3-point RANSAC is tried and the better of the two is kept.
        """
        est = one_point_ransac(
            turning_axis_view(w_prev, self.camera, self.to_axis),
            turning_axis_view(w_curr, self.camera, self.to_axis),
            self.camera,
            rng=self.rng,
            pixel_sigma=1.0,
        )
        ratio = float(est.inliers.mean()) if est.success else 0.0
        if est.success:
            on_axis = np.eye(4)
            on_axis[:3, :3], on_axis[:3, 3] = motion_matrices(est.theta, est.rho)
            # the virtual camera's motion, seen from the real camera
            guess, start = rigid_inverse(self.to_axis) @ on_axis @ self.to_axis, est.inliers
        else:
            guess, start = (np.eye(4) if T_pred is None else T_pred), None
        if ratio < MIN_RANSAC_RATIO:
            general = general_ransac(w_prev, w_curr, self.camera, int(self.rng.integers(2**31)))
            if general is not None and general[1].mean() > ratio:
                guess, start = general
                ratio = float(start.mean())
        return guess, start, ratio

    # ------------------------------------------------------------------ one frame
    def process(self, left: np.ndarray, right: np.ndarray, odometry=None):
        """Process one stereo pair (and the odometry distances since the previous frame, if any).

        Returns ``(planar vehicle pose, its covariance, FrameDiagnostics, FrameTimings)``; the 6-DoF
        camera pose is :attr:`camera_pose`.
        """
        t0 = time.perf_counter()
        features = self.front.process(left, right)
        t1 = time.perf_counter()
        diag = FrameDiagnostics(self.frame, features=len(features), odometry=odometry is not None)
        timing = FrameTimings(stereo=(t1 - t0) * 1e3)
        if self.frame == 0:
            self.reference = features if len(features) >= MIN_FEATURES else None
            self.gap = 1
            self.frame += 1
            timing.total = timing.stereo
            return self.kf.pose, self.kf.covariance, diag, timing
        u = None if odometry is None else np.asarray(odometry, float)
        if u is not None and not np.all(np.isfinite(u)):
            u, diag.odometry = None, False
        self.kf.predict(u, keep_reference=self.gap > 1)
        T_pred = self._predicted_motion()
        informative = T_pred is not None
        if not informative:  # no odometry and no motion measured yet: the prediction knows nothing
            self.kf.ekf.P[:3, :3] += np.diag(UNKNOWN_MOTION_SIGMA) ** 2
        t2 = time.perf_counter()
        timing.prediction = (t2 - t1) * 1e3
        reason, t3, t4, t5, accepted = "", t2, t2, t2, None
        if self.reference is None:
            reason = "no reference frame with features"
        elif len(features) < MIN_FEATURES:
            reason = "too few stereo features"
        else:
            matches = self._match(features, T_pred)
            t3 = t4 = t5 = time.perf_counter()  # stages that do not run take no time
            diag.temporal_matches = len(matches)
            if len(matches) < MIN_INLIERS:
                reason = "too few temporal matches"
            else:
                guess, start, ratio = self.hypothesis(matches.w_prev, matches.w_curr, T_pred)
                t4 = t5 = time.perf_counter()
                motion = refine_rigid_motion(matches.w_prev, matches.w_curr, self.camera, guess, start)
                t5 = time.perf_counter()
                diag.inliers = int(motion.inliers.sum())
                diag.inlier_ratio = ratio
                diag.ransac_inliers = int(round(ratio * len(matches)))
                increment = vehicle_increment(motion.matrix, self.mount)
                z = chord_measurement(increment)
                diag.theta, diag.rho = float(z[0]), float(z[1])
                if not motion.success or diag.inliers < MIN_INLIERS:
                    reason = "too few inliers"
                elif diag.inlier_ratio < MIN_RANSAC_RATIO:
                    reason = "low inlier ratio"
                else:
                    r_vo = VO_COVARIANCE_SCALE * chord_covariance(
                        motion.matrix, motion.covariance, self.mount
                    )
                    prior = self.kf.motion_prior()
                    innovation = np.array([wrap_angle(z[0] - prior.theta), z[1] - prior.rho])
                    gate = prior.covariance + r_vo[:2, :2]
                    contradicts = innovation @ np.linalg.solve(gate, innovation) > PRIOR_GATE
                    # a vision that keeps contradicting the prediction frame after frame, with
                    # enough inliers to be sure, means the prediction is wrong (wheels slipping,
                    # a speed that lags when braking): it is believed, not rejected for ever
                    if informative and contradicts and self.contradicted < MAX_CONTRADICTIONS:
                        reason = "motion contradicts the prediction"
                        self.contradicted += 1
                    else:
                        accepted = (motion, z, r_vo, len(matches))
                        self.contradicted = 0
        timing.matching = (t3 - t2) * 1e3
        timing.estimation = (t4 - t3) * 1e3
        timing.refinement = (t5 - t4) * 1e3
        t6 = time.perf_counter()
        if reason:
            diag.fallback, diag.reason = True, reason
            motion_since_reference = T_pred if T_pred is not None else np.eye(4)
            self.camera_pose = self.reference_pose @ np.linalg.inv(
                with_planar_increment(motion_since_reference, self.mount, self.kf.increment)
            )
            pose, covariance = self.kf.pose, self.kf.covariance
            self.gap += 1
            if self.reference is None and len(features) >= MIN_FEATURES:
                self._commit(features)
        else:
            motion, z, r_vo, n_matches = accepted
            saved_x, saved_P = self.kf.ekf.x.copy(), self.kf.ekf.P.copy()
            self.kf.update(float(z[0]), float(z[1]), r_vo, sideways=float(z[2]))
            fused = with_planar_increment(motion.matrix, self.mount, self.kf.increment)
            self.camera_pose = self.reference_pose @ np.linalg.inv(fused)
            pose, covariance = self.kf.pose, self.kf.covariance
            self.recent_matches.append(n_matches)
            if abs(z[1]) >= KEY_DISTANCE or abs(z[0]) >= KEY_ANGLE or self.gap >= KEY_MAX_GAP:
                self._commit(features, fused)
            else:
                self.kf.ekf.x, self.kf.ekf.P = saved_x, saved_P
                self.gap += 1
        t7 = time.perf_counter()
        timing.kalman = (t7 - t6) * 1e3 + timing.prediction
        timing.total = (t7 - t0) * 1e3
        self.frame += 1
        return pose, covariance, diag, timing

    def _commit(self, features, measured: np.ndarray | None = None) -> None:
        """This frame becomes the reference; a measured motion since the old reference is
        remembered per frame (constant velocity)."""
        if measured is not None:
            self.velocity = scaled_motion(measured, 1.0 / max(self.gap, 1))
        self.kf.finish_frame(max(self.gap, 1))
        self.reference = features if len(features) >= MIN_FEATURES else None
        self.reference_pose = self.camera_pose.copy()
        self.gap = 1
