"""The paper's motion model as a pipeline part: the filter's ``(theta, rho)`` prior (eq. 15),
matching in each feature's predicted window (``temporal``), and 1-point RANSAC with the prior as
one more hypothesis (``ransac``, eq. 14-21).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from vo_lib.camera import StereoCamera
from vo_lib.stereo_vo.config import PipelineConfig
from vo_lib.stereo_vo.kalman import VoKalmanFilter
from vo_lib.stereo_vo.parts import Estimate, Prediction
from vo_lib.stereo_vo.ransac import one_point_ransac
from vo_lib.stereo_vo.temporal import match_temporal

#: Good frames the recent median needs before a thin match is retried.
RETRY_HISTORY = 5


class PlanarMotion:
    """Circular motion of a camera above the turning axis on a flat floor [Zhao]."""

    camera_pose = None

    def __init__(self, camera: StereoCamera, config: PipelineConfig):
        self.camera = camera
        self.config = config
        self.velocity_known = False  # a motion has been measured (constant velocity means something)

    def predict(self, kf: VoKalmanFilter, steps: int = 1) -> Prediction:
        # without odometry, the prediction means something only once a motion has been measured
        return Prediction(kf.motion_prior(), kf.flags.odometry or self.velocity_known)

    def match(self, reference, features, prediction: Prediction, recent) -> object:
        prior = prediction.prior
        matches = match_temporal(reference, features, self.camera, prior if prediction.informative else None)
        if len(recent) >= RETRY_HISTORY and len(matches) < self.config.retry_fraction * np.median(recent):
            widened = replace(prior, covariance=self.config.retry_widening**2 * np.asarray(prior.covariance))
            wider = match_temporal(reference, features, self.camera, widened)
            matches = wider if len(wider) > len(matches) else matches
        return matches

    def estimate(self, matches, prediction: Prediction, rng) -> Estimate:
        prior = prediction.prior if prediction.informative else None
        est = one_point_ransac(
            matches.w_prev, matches.w_curr, self.camera, prior, rng, params=self.config.ransac
        )
        inliers, z = int(est.inliers.sum()), np.array([est.theta, est.rho])
        covariance = np.asarray(self.config.vo_covariance_scale) * est.covariance
        return Estimate(est.success, z, covariance, inliers, inliers / len(matches))

    def place(self, kf, estimate, prediction) -> None:
        """The planar pose is the filter's; nothing more to place."""

    def commit(self, kf: VoKalmanFilter, estimate, gap: int) -> None:
        self.velocity_known = self.velocity_known or kf.flags.vo_update
