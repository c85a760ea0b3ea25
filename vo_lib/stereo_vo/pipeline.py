"""The stereo visual odometry pipeline of seed 000, frame by frame (Fig. 3 of the paper).

Per frame:

1. **stereo processing**: features with disparity, ``w = (u, v, d)`` (``vo_lib.stereo_vo.features``);
2. **prediction**: the Kalman filter moves the pose with the track odometry, or with constant
   velocity when the sequence has none (``vo_lib.stereo_vo.kalman``);
3. **guided temporal matching** against the reference frame inside the predicted windows
   (``vo_lib.stereo_vo.temporal``);
4. **1-point RANSAC** for ``(theta, rho)``, with the prediction as a prior (``vo_lib.stereo_vo.ransac``);
5. **Kalman update** with the VO motion.

A frame whose VO motion cannot be trusted (no features, too few matches or inliers, a low inlier
ratio as when a large object moves through the view, or a motion that contradicts the prediction)
never stops the run: the filter keeps its prediction, and the frame is flagged. The last good
frame stays the reference, so the next good frame is matched against it and its measurement spans
the gap. Exactly one pose is produced per input frame.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Iterable
from dataclasses import asdict, dataclass, field, replace

import numpy as np
from scipy.stats import chi2

from vo_lib.camera import StereoCamera
from vo_lib.models.track_odometry import TrackOdometry
from vo_lib.stereo_vo.features import StereoFeatures, StereoFrontEnd
from vo_lib.stereo_vo.kalman import VoKalmanFilter
from vo_lib.stereo_vo.ransac import one_point_ransac
from vo_lib.stereo_vo.temporal import match_temporal

MIN_FEATURES = 20  # stereo features a frame needs to be matched
MIN_INLIERS = 15
MIN_INLIER_RATIO = 0.7  # of the temporal matches; a large moving object drags it down
PRIOR_GATE = float(chi2.ppf(0.9999, 2))  # VO motion against the prediction (Mahalanobis^2)
MAX_GAP = 90  # frames; after this long without a good frame, start again from the current one
#: A frame whose inliers fall below this fraction of the recent median has lost part of its view
#: to something that does not move with the world (an occluder, a large moving object)...
LOST_VIEW_FRACTION = 0.6
#: ...unless the drop lasts this many frames: then it is the new normal (a changed scene).
LOST_VIEW_PATIENCE = 15
RECENT_FRAMES = 15  # good frames whose inlier counts make the recent median
LOST_VIEW = "part of the view lost (occluder or moving object)"
#: Guided matching that finds fewer than this fraction of the recent median is retried with a
#: window four times wider (a prediction more than three sigma off, e.g. as a turn begins).
RETRY_FRACTION = 0.8
#: Keyframes: frames are measured against a reference frame until the motion since it is large
#: enough, so that the sub-pixel errors of feature positions are small against the motion.
KEY_DISTANCE = 0.04  # metres of chord
KEY_ANGLE = np.radians(1.5)
KEY_INLIER_FRACTION = 0.75  # of the inliers of the first frame measured against this reference
KEY_MAX_GAP = 12  # frames
#: Scale of the least-squares covariance of (theta, rho) before it enters the filter. The
#: least-squares covariance assumes independent pixel noise, but corners sit on whole pixels and
#: motion between frames is often below a pixel, so the errors are correlated with the motion;
#: measured on the rendered indoor samples, theta's spread is about 1.2x and rho's about 2.7x the
#: least-squares figure (notebook 08).
VO_COVARIANCE_SCALE = np.diag([1.5, 3.0]) ** 2


@dataclass
class FrameDiagnostics:
    """What happened to one frame."""

    frame: int
    features: int = 0
    temporal_matches: int = 0
    inliers: int = 0
    inlier_ratio: float = 0.0
    ransac_inliers: int = 0  # rigid pipeline: 1-point RANSAC's, before the 6-DoF refinement
    theta: float = float("nan")
    rho: float = float("nan")
    odometry: bool = False
    fallback: bool = False
    reason: str = ""


@dataclass
class FrameTimings:
    """Milliseconds per stage (the columns of the paper's Table 1, plus matching)."""

    stereo: float = 0.0
    prediction: float = 0.0
    matching: float = 0.0
    estimation: float = 0.0
    refinement: float = 0.0  # 6-DoF refinement (rigid pipeline only)
    kalman: float = 0.0
    total: float = 0.0


@dataclass
class PipelineResult:
    """One planar pose (and covariance) per frame, with diagnostics and timings; the rigid
    pipeline also gives each frame's 6-DoF camera pose (``camera_poses``, in frame 0's camera)."""

    poses: np.ndarray
    covariances: np.ndarray
    diagnostics: list[FrameDiagnostics] = field(default_factory=list)
    timings: list[FrameTimings] = field(default_factory=list)
    camera_poses: np.ndarray | None = None

    @property
    def flagged(self) -> np.ndarray:
        """Indices of frames whose VO motion was not used."""
        return np.array([d.frame for d in self.diagnostics if d.fallback], dtype=int)

    def timing_table(self) -> dict[str, float]:
        """Median milliseconds of each stage over the frames after the first."""
        rows = self.timings[1:] or self.timings
        return {k: float(np.median([asdict(t)[k] for t in rows])) for k in asdict(rows[0])}


class StereoVisualOdometry:
    """Seed 000's pipeline: stereo front end, Kalman prediction, guided matching, 1-point RANSAC.

    Parameters
    ----------
    camera : StereoCamera
    odometry : TrackOdometry, optional
        The crawler's odometry model; used when frames come with track distances.
    seed : int
        Seed of the RANSAC draws.
    front_end : StereoFrontEnd, optional
        Defaults to ``StereoFrontEnd(camera)``.
    """

    def __init__(
        self,
        camera: StereoCamera,
        odometry: TrackOdometry | None = None,
        seed: int = 0,
        front_end: StereoFrontEnd | None = None,
    ):
        self.camera = camera
        self.front = front_end or StereoFrontEnd(camera)
        self.kf = VoKalmanFilter(odometry or TrackOdometry())
        self.rng = np.random.default_rng(seed)
        self.reference: StereoFeatures | None = None
        self.gap = 0  # frames since the reference frame
        self.frame = 0
        self.recent_inliers: deque[int] = deque(maxlen=RECENT_FRAMES)
        self.recent_matches: deque[int] = deque(maxlen=RECENT_FRAMES)
        self.lost_view_frames = 0
        self.last_reason = ""
        self.reference_inliers = 0  # inliers of the first good frame against this reference
        self.velocity_known = False

    def process(self, left: np.ndarray, right: np.ndarray, odometry=None):
        """Process one stereo pair (and the track distances since the previous frame, if any).

        Returns ``(pose, covariance, FrameDiagnostics, FrameTimings)``.
        """
        t0 = time.perf_counter()
        features = self.front.process(left, right)
        t1 = time.perf_counter()
        diag = FrameDiagnostics(self.frame, features=len(features), odometry=odometry is not None)
        timing = FrameTimings(stereo=(t1 - t0) * 1e3)
        if self.frame == 0:
            self._new_reference(features)
            self.frame += 1
            timing.total = timing.stereo
            return self.kf.pose, self.kf.covariance, diag, timing
        u = None if odometry is None else np.asarray(odometry, float)
        if u is not None and not np.all(np.isfinite(u)):
            u, diag.odometry = None, False
        self.kf.predict(u, keep_reference=self.gap > 1)
        prior = self.kf.motion_prior()
        # without odometry, the prediction means something only once a motion has been measured
        informative = u is not None or self.velocity_known
        t2 = time.perf_counter()
        timing.prediction = (t2 - t1) * 1e3
        reason, t3, t4, accepted = "", t2, t2, None
        if self.reference is None or len(self.reference) < MIN_FEATURES:
            reason = "no reference frame with features"
        elif len(features) < MIN_FEATURES:
            reason = "too few stereo features"
        else:
            matches = match_temporal(self.reference, features, self.camera, prior if informative else None)
            if len(self.recent_matches) >= 5 and len(matches) < RETRY_FRACTION * np.median(
                self.recent_matches
            ):
                wider = match_temporal(
                    self.reference,
                    features,
                    self.camera,
                    replace(prior, covariance=16.0 * np.asarray(prior.covariance)),
                )
                matches = wider if len(wider) > len(matches) else matches
            t3 = t4 = time.perf_counter()  # no estimation time unless it runs
            diag.temporal_matches = len(matches)
            if len(matches) < MIN_INLIERS:
                reason = "too few temporal matches"
            else:
                est = one_point_ransac(
                    matches.w_prev,
                    matches.w_curr,
                    self.camera,
                    prior=prior if informative else None,
                    rng=self.rng,
                )
                t4 = time.perf_counter()
                diag.inliers = int(est.inliers.sum())
                diag.inlier_ratio = diag.inliers / len(matches)
                diag.theta, diag.rho = est.theta, est.rho
                innovation = np.array([est.theta - prior.theta, est.rho - prior.rho])
                r_vo = VO_COVARIANCE_SCALE * est.covariance
                if not est.success or diag.inliers < MIN_INLIERS:
                    reason = "too few inliers"
                elif diag.inlier_ratio < MIN_INLIER_RATIO:
                    reason = "low inlier ratio"
                elif (
                    informative
                    and innovation @ np.linalg.solve(prior.covariance + r_vo, innovation) > PRIOR_GATE
                ):
                    reason = "motion contradicts the prediction"
                elif self._view_lost(diag.inliers):
                    reason = LOST_VIEW
                else:
                    accepted = (est.theta, est.rho, r_vo, diag.inliers, len(matches))
        timing.matching = (t3 - t2) * 1e3
        timing.estimation = (t4 - t3) * 1e3
        t5 = time.perf_counter()
        pose, covariance = self.kf.pose, self.kf.covariance
        if reason:
            diag.fallback, diag.reason = True, reason
            self.gap += 1
            if (self.reference is None or self.gap > MAX_GAP) and len(features) >= MIN_FEATURES:
                self._commit(features)
        else:
            theta, rho, r_vo, inliers, n_matches = accepted
            # the update goes to a copy: until the keyframe changes, the filter keeps only its
            # prediction, so the reference frame's errors are never counted twice
            saved_x, saved_P = self.kf.ekf.x.copy(), self.kf.ekf.P.copy()
            self.kf.update(theta, rho, r_vo)
            pose, covariance = self.kf.pose, self.kf.covariance
            if self.reference_inliers == 0:
                self.reference_inliers = inliers
            if self._counts_are_typical():
                self.recent_inliers.append(inliers)
                self.recent_matches.append(n_matches)
            new_key = (
                abs(rho) >= KEY_DISTANCE
                or abs(theta) >= KEY_ANGLE
                or inliers < KEY_INLIER_FRACTION * self.reference_inliers
                or self.gap >= KEY_MAX_GAP
            )
            if new_key:
                self._commit(features)
            else:
                self.kf.ekf.x, self.kf.ekf.P = saved_x, saved_P
                self.gap += 1
        self.last_reason = reason
        t6 = time.perf_counter()
        timing.kalman = (t6 - t5) * 1e3 + timing.prediction
        timing.total = (t6 - t0) * 1e3
        self.frame += 1
        return pose, covariance, diag, timing

    def _counts_are_typical(self) -> bool:
        """Counts measured right after frames without vision are not typical of the next ones."""
        return self.last_reason in ("", LOST_VIEW)  # still the previous frame's

    def _commit(self, features: StereoFeatures) -> None:
        """Make this frame the reference (keyframe): its filter state becomes the prior's base."""
        self.velocity_known = self.velocity_known or self.kf.flags.vo_update
        self.kf.finish_frame(max(self.gap, 1))
        self._new_reference(features)
        self.reference_inliers = 0

    def _view_lost(self, inliers: int) -> bool:
        """A sudden drop of the inliers below the recent median; a lasting one becomes the norm.

        Judged only against the previous frame, or while a loss is going on: after frames without
        vision the reference is older and fewer matches are expected.
        """
        judged = self.last_reason in ("", LOST_VIEW)
        if (
            not judged
            or len(self.recent_inliers) < 5
            or inliers >= LOST_VIEW_FRACTION * np.median(self.recent_inliers)
        ):
            self.lost_view_frames = 0
            return False
        self.lost_view_frames += 1
        if self.lost_view_frames > LOST_VIEW_PATIENCE:
            self.recent_inliers.clear()
            self.recent_matches.clear()
            self.lost_view_frames = 0
            return False
        return True

    def _new_reference(self, features: StereoFeatures) -> None:
        self.reference = features if len(features) >= MIN_FEATURES else None
        self.gap = 1 if self.reference is not None else self.gap + 1


def run_frames(
    frames: Iterable,
    camera: StereoCamera,
    odometry_model: TrackOdometry | None = None,
    seed: int = 0,
    progress=None,
    front_end: StereoFrontEnd | None = None,
    odometer=None,
) -> PipelineResult:
    """Run the pipeline over ``(left, right, odometry_or_None)`` triples.

    ``odometer`` is any object with this module's ``process`` method (default: the planar
    :class:`StereoVisualOdometry`); one that has a ``camera_pose`` gives 6-DoF poses too.
    """
    vo = odometer or StereoVisualOdometry(camera, odometry_model, seed, front_end)
    poses, covs, diags, timings, cameras = [], [], [], [], []
    for left, right, odo in frames:
        pose, cov, diag, timing = vo.process(left, right, odo)
        poses.append(pose)
        covs.append(cov)
        diags.append(diag)
        timings.append(timing)
        if hasattr(vo, "camera_pose"):
            cameras.append(vo.camera_pose.copy())
        if progress is not None:
            progress.update(1)
    return PipelineResult(
        np.array(poses).reshape(-1, 3),
        np.array(covs).reshape(-1, 3, 3),
        diags,
        timings,
        np.array(cameras) if cameras else None,
    )


MOTION_MODELS = ("auto", "planar", "full")
#: Frames of the untimed warm-up before a timed run: the second and third exercise matching, the
#: 1-point RANSAC (without and with a prior) and the filter, so every compiled kernel is ready.
WARM_UP_FRAMES = 3


def run_sequence(
    sequence,
    frames: int | None = None,
    use_odometry: bool = True,
    seed: int = 0,
    progress: bool = False,
    motion: str = "auto",
) -> PipelineResult:
    """Run the pipeline on a :class:`~vo_lib.formats.sequence.Sequence` (its first ``frames`` frames).

    ``motion`` is ``"planar"`` (the circular-motion model, for a camera above the turning axis on
    a flat floor: the crawler of the samples), ``"full"`` (6-DoF, :mod:`.rigid_pipeline`: a car on
    a real road), or ``"auto"``: the one that fits the sequence's vehicle (:mod:`.vehicle`).
    """
    from vo_lib.stereo_vo.rigid_pipeline import RigidStereoOdometry
    from vo_lib.stereo_vo.vehicle import vehicle_of

    if motion not in MOTION_MODELS:
        raise ValueError(f"motion must be one of {', '.join(MOTION_MODELS)}; got {motion!r}")
    vehicle = vehicle_of(sequence, use_odometry)
    model = vehicle.motion if motion == "auto" else motion
    n = len(sequence) if frames is None else min(int(frames), len(sequence))
    odo = vehicle.odometry

    def frame_iter():
        for k in range(n):
            left, right = sequence.pair(k)
            yield left, right, (None if odo is None or k == 0 else odo[k])

    odometer = None
    if model == "full":
        odometer = RigidStereoOdometry(sequence.camera, vehicle.mount, vehicle.odometry_model, seed)
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=n, desc=f"VO {sequence.path.name}", unit="frame")
    try:
        return run_frames(
            frame_iter(), sequence.camera, vehicle.odometry_model, seed=seed, progress=bar, odometer=odometer
        )
    finally:
        if bar is not None:
            bar.close()


def warm_up(sequence, use_odometry: bool = True, seed: int = 0, motion: str = "auto") -> float:
    """Run the pipeline once, untimed and discarded, on the first frames of ``sequence``.

    Every Numba kernel the run will call is then compiled, or loaded from its cache, before the
    timed run starts, so compile time (seconds in a fresh environment) stays out of the per-frame
    timings. Returns the seconds the warm-up took.
    """
    t0 = time.perf_counter()
    run_sequence(
        sequence,
        frames=min(WARM_UP_FRAMES, len(sequence)),
        use_odometry=use_odometry,
        seed=seed,
        motion=motion,
    )
    return time.perf_counter() - t0
