"""The stereo visual odometry pipeline of [Zhao], frame by frame (Fig. 3 of the paper).

Per frame, :meth:`StereoOdometry.process` runs four parts (``parts`` gives their interfaces):

1. **stereo front end**: features with disparity, ``w = (u, v, d)`` (``features`` or
   ``pyramid_features``);
2. **prediction and temporal matching**: the Kalman filter moves the pose with the odometry, or
   with constant velocity when the sequence has none (``kalman``; a 6-DoF model's own, from the
   last frame, where it has one); the motion model matches the reference frame's features
   inside the predicted windows (``temporal``); where a 6-DoF motion was predicted and its
   windows' matches leave too few inliers or too low a ratio of them, every pair is matched
   again, without windows;
3. **motion estimation**: 1-point RANSAC with the prediction as a prior (``ransac``), and for a car
   a 6-DoF refinement (``planar_motion`` or ``six_dof``);
4. **Kalman update** with the VO motion.

A frame whose VO motion cannot be trusted (no features, too few matches or inliers, a low inlier
ratio as when a large object moves through the view, or a motion that contradicts the prediction)
never stops the run: the filter keeps its prediction, and the frame is flagged. The last good
frame stays the reference, so the next good frame is matched against it and its measurement spans
the gap. Exactly one pose is produced per input frame. A frame that comes two or more frame
intervals after the last (a dropped frame, from the sequence's timestamps) is predicted that many
steps ahead (of constant velocity, or of the odometry, which spans them). A pair whose images are the
previous pair's, sent again within half a frame interval (as a stalled camera driver may), is no
new view: it keeps the last pose and is flagged, and changes nothing else (odometry counted
meanwhile goes to the next frame). Every setting is a field of one
:class:`~vo_lib.stereo_vo.config.PipelineConfig`; ``CRAWLER`` and ``CAR`` are the two presets.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Iterable

import numpy as np

from vo_lib.camera import StereoCamera
from vo_lib.geometry import wrap_angle
from vo_lib.models.track_odometry import TrackOdometry
from vo_lib.stereo_vo.config import CRAWLER, PRESETS, PipelineConfig
from vo_lib.stereo_vo.features import StereoFeatures, StereoFrontEnd
from vo_lib.stereo_vo.frames import FrameDiagnostics, FrameTimings, PipelineResult, Reason, Stopwatch
from vo_lib.stereo_vo.kalman import VoKalmanFilter
from vo_lib.stereo_vo.parts import Estimate, FrontEnd, MotionModel, Prediction
from vo_lib.stereo_vo.planar_motion import PlanarMotion
from vo_lib.stereo_vo.pyramid_features import PyramidFrontEnd
from vo_lib.stereo_vo.six_dof import SixDofMotion

#: Reference-frame matching needs the recent medians of at least this many good frames.
MIN_HISTORY = 5
#: A frame more frame intervals than this after the last one (seconds of frames dropped, a paused
#: recording) is matched with its motion unknown, as the second frame is: constant velocity is no
#: guess over so long a gap. Up to it, the prediction's uncertainty grows with the gap.
MAX_PREDICTED_INTERVALS = 100
#: Outcomes after which a frame matched inside predicted windows is matched again without them.
UNGUIDED_RETRY = (Reason.FEW_INLIERS, Reason.LOW_INLIER_RATIO)


class StereoOdometry:
    """[Zhao]'s pipeline: stereo front end, prediction and matching, motion estimation, filter.

    ``config`` is :data:`~vo_lib.stereo_vo.config.CRAWLER` (default) or ``CAR``, or a variant of
    either; ``odometry`` the gauge and noise of the odometry, when frames come with track or wheel
    distances; ``mount`` is ``T_vehicle_camera``, which the 6-DoF motion model needs; ``seed``
    seeds the RANSAC draws; ``front_end`` and ``motion`` are parts to use instead of those the
    config names (see ``parts``).
    """

    def __init__(
        self,
        camera: StereoCamera,
        config: PipelineConfig = CRAWLER,
        odometry: TrackOdometry | None = None,
        mount: np.ndarray | None = None,
        seed: int = 0,
        front_end: FrontEnd | None = None,
        motion: MotionModel | None = None,
    ):
        self.camera = camera
        self.config = config
        if front_end is None:
            front_end = PyramidFrontEnd(camera) if config.front_end == "pyramid" else StereoFrontEnd(camera)
        if motion is None:
            if config.motion == "full":
                if mount is None:
                    raise ValueError("the 6-DoF motion model needs the camera's mount")
                motion = SixDofMotion(camera, mount, config)
            else:
                motion = PlanarMotion(camera, config)
        self.front, self.motion = front_end, motion
        self.kf = VoKalmanFilter(odometry or TrackOdometry(), lateral_sigma=config.lateral_sigma)
        self.rng = np.random.default_rng(seed)
        self.reference: StereoFeatures | None = None
        self.gap = 0  # frame intervals since the reference frame
        self.frame = 0
        self.recent_inliers: deque[int] = deque(maxlen=config.recent_frames)
        self.recent_matches: deque[int] = deque(maxlen=config.recent_frames)
        self.lost_view_frames = 0
        self.contradicted = 0  # consecutive frames whose vision contradicted the prediction
        self.last_reason = Reason.NONE
        self.reference_inliers = 0  # inliers of the first good frame against this reference
        self.last_pair: tuple[np.ndarray, np.ndarray] | None = None  # the last frame's images
        self.last_output: tuple[np.ndarray, np.ndarray] | None = None  # its pose and covariance
        self.owed_odometry = None  # odometry counted at repeats, added to the next frame's

    @property
    def camera_pose(self) -> np.ndarray | None:
        """6-DoF camera pose of the last frame in frame 0's camera (None for the planar model)."""
        return self.motion.camera_pose

    def process(self, left: np.ndarray, right: np.ndarray, odometry=None, steps: int = 1):
        """Process one stereo pair (and the odometry distances since the previous frame, if any)
        that comes ``steps`` frame intervals after the previous one (more than 1 after a dropped frame;
        the odometry, where given, must span them all, as distances counted between the two frames do;
        0 for a frame at the previous one's time, which is a repeat if its images are the same).

        Returns ``(planar pose, its covariance, FrameDiagnostics, FrameTimings)``.
        """
        watch = Stopwatch()
        if steps < 1 and self.last_pair is not None and repeated(self.last_pair, (left, right)):
            return self._repeated(odometry, watch)
        self.last_pair = (left, right)
        if self.owed_odometry is not None and odometry is not None:
            odometry = np.add(odometry, self.owed_odometry)
        self.owed_odometry = None
        with watch("stereo"):
            features = self.front.process(left, right)  # 1. stereo front end
        diag = FrameDiagnostics(self.frame, features=len(features), odometry=odometry is not None)
        if self.frame == 0:
            self._new_reference(features)
            self.frame += 1
            self.last_output = self.kf.pose, self.kf.covariance  # copies, as the filter gives them
            return self.kf.pose, self.kf.covariance, diag, self._timings(watch)
        with watch("prediction"):
            prediction = self._predict(odometry, diag, max(int(steps), 1))  # 2. prediction ...
        estimate, reason = None, self._unmatchable(features)
        if reason is Reason.NONE:
            estimate, reason = self._measure(features, prediction, diag, watch)
            if reason in UNGUIDED_RETRY and prediction.motion is not None:
                # the predicted motion may have sent the matching windows astray (a body that
                # reverses its turn): match every pair and estimate again, unguided
                unguided = Prediction(prediction.prior, prediction.informative)
                estimate, reason = self._measure(features, unguided, diag, watch)
        with watch("kalman"):
            pose, covariance = self._update(features, estimate, prediction, reason, diag)  # 4. Kalman update
        self.last_reason = reason
        self.frame += 1
        self.last_output = pose.copy(), covariance.copy()
        return pose, covariance, diag, self._timings(watch)

    def _repeated(self, odometry, watch: Stopwatch):
        """A frame whose images are the last frame's, sent again at its time: no new view. It keeps
        the last pose and is flagged; nothing else changes, but that odometry counted meanwhile
        is added to the next frame's."""
        counted = odometry is not None and bool(np.all(np.isfinite(odometry)))
        diag = FrameDiagnostics(self.frame, odometry=counted, fallback=True)
        diag.reason = Reason.REPEATED
        if odometry is not None:  # a non-finite count leaves the next frame's unknown too
            self.owed_odometry = np.add(0.0 if self.owed_odometry is None else self.owed_odometry, odometry)
        self.frame += 1
        pose, covariance = self.last_output
        return pose.copy(), covariance.copy(), diag, self._timings(watch)

    @staticmethod
    def _timings(watch: Stopwatch) -> FrameTimings:
        """The stages as the paper's Table 1 counts them: the refinement (6-DoF) apart from the
        estimation, and the filter's prediction with its update."""
        ms = dict(watch.ms)
        ms["estimation"] = ms.get("estimation", 0.0) - ms.get("refinement", 0.0)
        ms["kalman"] = ms.get("kalman", 0.0) + ms.get("prediction", 0.0)
        return FrameTimings(**ms, total=watch.total())

    # ------------------------------------------------------------------ the steps
    def _predict(self, odometry, diag: FrameDiagnostics, steps: int) -> Prediction:
        u = None if odometry is None else np.asarray(odometry, float)
        if u is not None and not np.all(np.isfinite(u)):
            u, diag.odometry = None, False
        # odometry spans the gap itself; constant velocity is stepped across it, up to where it means nothing
        self.kf.predict(u, keep_reference=self.gap > 1, steps=min(steps, MAX_PREDICTED_INTERVALS + 1))
        self.gap += steps - 1  # counted in frame intervals: the velocity is per interval
        if steps > MAX_PREDICTED_INTERVALS:  # too long a gap to guess the motion across
            prediction = Prediction(self.kf.motion_prior(), False)
        else:
            prediction = self.motion.predict(self.kf, steps)
        if not prediction.informative and self.config.unknown_motion_sigma:
            self.kf.widen(self.config.unknown_motion_sigma)  # nothing predicts the motion yet
            prediction.prior = self.kf.motion_prior()
        return prediction

    def _measure(self, features, prediction: Prediction, diag: FrameDiagnostics, watch: Stopwatch):
        """Temporal matching (2.) and motion estimation (3.): ``(estimate or None, reason)``."""
        diag.inliers, diag.inlier_ratio, diag.ransac_inliers = 0, 0.0, 0  # not an earlier attempt's
        diag.theta = diag.rho = float("nan")
        with watch("matching"):
            matches = self.motion.match(self.reference, features, prediction, self.recent_matches)
        diag.temporal_matches = len(matches)
        if len(matches) < self.config.min_inliers:
            return None, Reason.FEW_MATCHES
        with watch("estimation"):
            estimate = self.motion.estimate(matches, prediction, self.rng)
        watch.ms["refinement"] = watch.ms.get("refinement", 0.0) + estimate.timings.get("refinement", 0.0)
        return estimate, self._judge(estimate, prediction, diag)

    def _unmatchable(self, features: StereoFeatures) -> Reason:
        if self.reference is None:
            return Reason.NO_REFERENCE
        if len(features) < self.config.min_features:
            return Reason.FEW_FEATURES
        return Reason.NONE

    def _judge(self, estimate: Estimate, prediction: Prediction, diag: FrameDiagnostics) -> Reason:
        """Why the estimate is not to be trusted, or :attr:`Reason.NONE`."""
        cfg = self.config
        diag.inliers, diag.inlier_ratio = estimate.inliers, estimate.inlier_ratio
        diag.ransac_inliers = estimate.ransac_inliers
        diag.theta, diag.rho = float(estimate.z[0]), float(estimate.z[1])
        if not estimate.success or estimate.inliers < cfg.min_inliers:
            return Reason.FEW_INLIERS
        last = prediction.motion is None and cfg.last_attempt_ratio is not None  # matched without windows
        if estimate.inlier_ratio < (cfg.last_attempt_ratio if last else cfg.min_inlier_ratio):
            return Reason.LOW_INLIER_RATIO
        prior = prediction.prior
        innovation = np.array([wrap_angle(estimate.z[0] - prior.theta), estimate.z[1] - prior.rho])
        gate = prior.covariance + estimate.covariance[:2, :2]
        # a vision that keeps contradicting the prediction frame after frame, with enough inliers
        # to be sure, means the prediction is wrong: it is believed, not rejected for ever
        contradicts = innovation @ np.linalg.solve(gate, innovation) > cfg.prior_gate
        if prediction.informative and contradicts and self.contradicted < cfg.max_contradictions:
            self.contradicted += 1
            return Reason.CONTRADICTS_PREDICTION
        if cfg.lost_view_fraction and self._view_lost(estimate.inliers):
            return Reason.VIEW_LOST
        self.contradicted = 0
        return Reason.NONE

    def _update(self, features, estimate, prediction, reason, diag):
        """The filter's update with a trusted estimate, the keyframe decision, or the fallback."""
        cfg = self.config
        if reason is not Reason.NONE:
            diag.fallback, diag.reason = True, reason
            self.motion.place(self.kf, None, prediction)
            pose, covariance = self.kf.pose, self.kf.covariance
            stale = self.gap >= cfg.restart_gap and (not cfg.restart_reasons or reason in cfg.restart_reasons)
            if (self.reference is None or stale) and len(features) >= cfg.min_features:
                # start again from this frame, placed where the prediction puts it: a reference
                # the view has left behind would never match again
                self._commit(features, None)
            else:
                self.gap += 1
            return pose, covariance
        # the update goes to a copy: until the keyframe changes, the filter keeps only its
        # prediction, so the reference frame's errors are never counted twice
        saved = self.kf.snapshot()
        z = estimate.z
        sideways = float(z[2]) if len(z) > 2 else 0.0  # measured by a 6-DoF model, else constrained to 0
        self.kf.update(float(z[0]), float(z[1]), estimate.covariance, sideways=sideways)
        self.motion.place(self.kf, estimate, prediction)
        pose, covariance = self.kf.pose, self.kf.covariance
        if self.reference_inliers == 0:
            self.reference_inliers = estimate.inliers
        if not cfg.typical_counts_only or self._after_vision():
            self.recent_inliers.append(estimate.inliers)
            self.recent_matches.append(diag.temporal_matches)
        new_key = (
            abs(z[1]) >= cfg.key_distance
            or abs(z[0]) >= cfg.key_angle
            or estimate.inliers < cfg.key_inlier_fraction * self.reference_inliers
            or self.gap >= cfg.key_max_gap
        )
        if new_key:
            self._commit(features, estimate)
        else:
            self.kf.restore(saved)
            self.gap += 1
        return pose, covariance

    # ------------------------------------------------------------------ bookkeeping
    def _after_vision(self) -> bool:
        """The previous frame was measured (its motion used, or flagged only for a lost part of the
        view): counts right after frames without vision are not typical of the next ones."""
        return self.last_reason in (Reason.NONE, Reason.VIEW_LOST)

    def _commit(self, features: StereoFeatures, estimate: Estimate | None) -> None:
        """Make this frame the reference (keyframe): its filter state becomes the prior's base."""
        self.motion.commit(self.kf, estimate, max(self.gap, 1))
        self.kf.finish_frame(max(self.gap, 1))
        self._new_reference(features)
        self.reference_inliers = 0

    def _view_lost(self, inliers: int) -> bool:
        """A sudden drop of the inliers below the recent median; a lasting one becomes the norm.

        Judged only against the previous frame, or while a loss is going on: after frames without
        vision the reference is older and fewer matches are expected.
        """
        if (
            not self._after_vision()
            or len(self.recent_inliers) < MIN_HISTORY
            or inliers >= self.config.lost_view_fraction * np.median(self.recent_inliers)
        ):
            self.lost_view_frames = 0
            return False
        self.lost_view_frames += 1
        if self.lost_view_frames > self.config.lost_view_patience:
            self.recent_inliers.clear()
            self.recent_matches.clear()
            self.lost_view_frames = 0
            return False
        return True

    def _new_reference(self, features: StereoFeatures) -> None:
        self.reference = features if len(features) >= self.config.min_features else None
        self.gap = 1 if self.reference is not None else self.gap + 1


def run_frames(
    frames: Iterable,
    camera: StereoCamera,
    seed: int = 0,
    progress=None,
    odometer: StereoOdometry | None = None,
    times=None,
) -> PipelineResult:
    """Run the pipeline over ``(left, right, odometry_or_None)`` triples.

    ``odometer`` is the :class:`StereoOdometry` to run (default: the crawler's, with track odometry
    and ``seed``); with the 6-DoF model the result carries each frame's camera pose too. ``times``
    (seconds, one per frame) tell a dropped frame: :func:`frame_steps`.
    """
    vo = odometer or StereoOdometry(camera, CRAWLER, seed=seed)
    poses, covs, diags, timings, cameras = [], [], [], [], []
    steps = iter(frame_steps(times)) if times is not None else None
    for left, right, odo in frames:
        pose, cov, diag, timing = vo.process(left, right, odo, 1 if steps is None else next(steps, 1))
        poses.append(pose)
        covs.append(cov)
        diags.append(diag)
        timings.append(timing)
        if vo.camera_pose is not None:
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


def frame_steps(times) -> np.ndarray:
    """Frame intervals from the previous frame to each frame (1 for the first): the gap between
    their times in frame intervals, rounded half up. It is 1 but after dropped frames, as long as
    fewer than half the gaps hold a drop, and 0 for a frame within half an interval of the one
    before (a repeated pair; a new one counts as one interval), whose successor then counts from
    that one. The frame interval is the median gap, leaving out those under a quarter of the upper
    half's median (repeats)."""
    times = np.asarray(times, float)
    if not np.all(np.isfinite(times)):
        raise ValueError("times must be finite seconds, one per frame")
    gaps = np.diff(times)
    typical = np.median(gaps) if len(gaps) else 0.0
    if not typical > 0:
        return np.ones(len(times), int)
    # a frame interval, not a repeat's short gap, even where every frame is repeated (and
    # not the gap of a drop, where a third of the frames or more are dropped)
    typical = np.median(gaps[gaps > 0.25 * np.median(gaps[gaps >= typical])])
    steps, anchor = np.ones(len(times), int), times[0]
    for k in range(1, len(times)):
        steps[k] = max(int(np.floor((times[k] - anchor) / typical + 0.5)), 0)
        anchor = times[k] if steps[k] > 0 else anchor  # a repeat's successor counts from the frame before it
    return steps


def repeated(previous, pair) -> bool:
    """Is ``pair`` (left and right images) the ``previous`` pair again, pixel for pixel? A front end
    that needs no images may be given None: that is never a repeat."""
    return all(
        a is not None and b is not None and np.array_equal(a, b) for a, b in zip(previous, pair, strict=True)
    )


MOTION_MODELS = ("auto", "planar", "full", "hover")
#: Frames of the untimed warm-up before a timed run: the second and third exercise matching, the
#: 1-point RANSAC (without and with a prior) and the filter, so every compiled kernel is ready
#: and every lazy import done.
WARM_UP_FRAMES = 3


def run_sequence(
    sequence,
    frames: int | None = None,
    use_odometry: bool = True,
    seed: int = 0,
    progress: bool = False,
    motion: str = "auto",
    vehicle=None,
) -> PipelineResult:
    """Run the pipeline on a :class:`~vo_lib.formats.sequence.Sequence` (its first ``frames`` frames).

    ``motion`` is ``"planar"`` (the circular-motion model, for a camera above the turning axis on
    a flat floor: the crawler of the samples, preset ``CRAWLER``), ``"full"`` (6-DoF, :mod:`.six_dof`:
    a car on a real road, preset ``CAR``), ``"hover"`` (6-DoF for a body free in all six, a drone
    or a hand-held rig, preset ``HOVER``; a sequence that names no body turns about its camera), or
    ``"auto"``: the one that fits the sequence's vehicle (:mod:`.vehicle`). ``vehicle``: that
    vehicle, where the caller has read it already (``vehicle_of(sequence, use_odometry, motion)``).
    """
    from vo_lib.stereo_vo.vehicle import vehicle_of

    if motion not in MOTION_MODELS:
        raise ValueError(f"motion must be one of {', '.join(MOTION_MODELS)}; got {motion!r}")
    vehicle = vehicle or vehicle_of(sequence, use_odometry, motion)
    model = vehicle.motion if motion == "auto" else motion
    n = len(sequence) if frames is None else min(int(frames), len(sequence))
    odo = vehicle.odometry
    times = sequence.times[:n]

    def frame_iter():
        for k in range(n):
            yield *sequence.pair(k), (None if odo is None or k == 0 else odo[k])

    odometer = StereoOdometry(sequence.camera, PRESETS[model], vehicle.odometry_model, vehicle.mount, seed)
    if not progress:
        return run_frames(frame_iter(), sequence.camera, odometer=odometer, times=times)
    from tqdm.auto import tqdm

    with tqdm(total=n, desc=f"VO {sequence.path.name}", unit="frame") as bar:
        return run_frames(frame_iter(), sequence.camera, progress=bar, odometer=odometer, times=times)


def warm_up(sequence, use_odometry: bool = True, seed: int = 0, motion: str = "auto", vehicle=None) -> float:
    """Run the pipeline once, untimed and discarded, on the first frames of ``sequence``.

    Every Numba kernel the run will call is then compiled, or loaded from its cache, before the
    timed run starts, so compile time (seconds in a fresh environment) stays out of the per-frame
    timings (``vehicle`` as in :func:`run_sequence`). Returns the seconds the warm-up took.
    """
    t0 = time.perf_counter()
    frames = min(WARM_UP_FRAMES, len(sequence))
    run_sequence(
        sequence, frames=frames, use_odometry=use_odometry, seed=seed, motion=motion, vehicle=vehicle
    )
    return time.perf_counter() - t0
