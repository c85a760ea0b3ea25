"""The small interfaces between the pipeline's parts, and what passes through them.

A frame goes through a **front end** (stereo features ``w = (u, v, d)``), a **motion model**
(prediction, matching, the motion of the matches) and the **filter** ([Zhao], Fig. 3), strung
together by ``pipeline.StereoOdometry``; any object with the same methods replaces a part.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from vo_lib.stereo_vo.features import StereoFeatures
from vo_lib.stereo_vo.kalman import VoKalmanFilter
from vo_lib.stereo_vo.temporal import MotionPrior, TemporalMatches


@dataclass
class Prediction:
    """The filter's predicted motion since the reference frame: ``(theta, rho)`` with its
    covariance (``prior``), False while nothing predicts the motion (``informative``), and a 6-DoF
    model's 4x4 ``T_curr_from_prev`` (``motion``, else None)."""

    prior: MotionPrior
    informative: bool
    motion: np.ndarray | None = None


@dataclass
class Estimate:
    """A measured motion since the reference frame, ready for the filter: ``z`` is ``(theta,
    rho)``, or ``(theta, rho, sideways)`` where the model measures the deviation from the chord;
    ``timings`` are milliseconds of ``estimation`` and ``refinement``."""

    success: bool
    z: np.ndarray
    covariance: np.ndarray
    inliers: int
    inlier_ratio: float
    ransac_inliers: int = 0
    motion: np.ndarray | None = None
    timings: dict = field(default_factory=dict)


class FrontEnd(Protocol):
    """Stereo processing: features with disparity from a rectified pair."""

    def process(self, left: np.ndarray, right: np.ndarray) -> StereoFeatures: ...


class MotionModel(Protocol):
    """Prediction, temporal matching and motion estimation for one model of the motion."""

    #: 4x4 camera pose of the last frame in frame 0's camera, or None for a planar-only model.
    camera_pose: np.ndarray | None

    def predict(self, kf: VoKalmanFilter, steps: int = 1) -> Prediction:
        """The motion since the reference frame, as the filter (just moved on ``steps`` frame
        intervals) predicts it."""

    def match(
        self, reference: StereoFeatures, features: StereoFeatures, prediction: Prediction, recent: list
    ) -> TemporalMatches:
        """Temporal matches, guided by the prediction; ``recent`` are match counts of good frames."""

    def estimate(self, matches: TemporalMatches, prediction: Prediction, rng) -> Estimate:
        """The motion of the matches (1-point RANSAC and whatever refines it)."""

    def place(self, kf: VoKalmanFilter, estimate: Estimate | None, prediction: Prediction) -> None:
        """Pose this frame after the filter's update (``estimate``) or without one."""

    def commit(self, kf: VoKalmanFilter, estimate: Estimate | None, gap: int) -> None:
        """This frame becomes the reference; ``estimate`` is its measured motion, if any."""
