"""[Yan 2020]'s simulation: a car-like robot laps four line landmarks, seen by a simulated laser
through one of the three segment observers, mapped and localised by EKF-SLAM.

Parameters are the paper's (section 3); what it does not print is stated in
:class:`LineSlamScenario`. ``python -m vo_lib sweep lap`` prints the README's figures
(:func:`lap_figures` per seed, :func:`lap_report` over them).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from vo_lib.comparison import Comparison, chi2_band, interval_text
from vo_lib.geometry import wrap_angle
from vo_lib.line_slam.ekf_slam import DROPPED, EkfSlam, diagonal_cov
from vo_lib.line_slam.line_landmarks import (
    PAPER_EXTENDED_RIGHT_END,
    along_line,
    feature_point,
    line_points,
    paper_world,
)
from vo_lib.line_slam.line_observation import LINE, measure_line
from vo_lib.line_slam.range_bearing import POINT, observe_point, point_from_observation
from vo_lib.line_slam.segment_observers import DEFAULT_TOLERANCE, OBSERVERS, visible_segment
from vo_lib.models.bicycle import (
    DEFAULT_WHEELBASE,
    PAPER_MAX_STEER,
    PAPER_MAX_STEER_RATE,
    PAPER_SPEED,
    bicycle_step,
    steer_towards,
)

#: The lap: start at (0, 35), then these waypoints in turn, back to the start.
PAPER_START = (0.0, 35.0)
PAPER_WAYPOINTS = ((25.0, 0.0), (0.0, -20.0), (-35.0, 0.0), (-35.0, 10.0), (0.0, 35.0))
#: Upper end of one lap's per-step 95 % band of the pose NEES (χ² with 3 degrees of freedom).
NEES_HIGH = chi2_band(3, 1)[1]


@dataclass(frozen=True)
class LineSlamScenario:
    """[Yan 2020]'s simulation settings.

    Not printed in the paper, so ours: the wheelbase, an observation every 8 control periods, a
    waypoint reached within 1 m, the start heading towards the first waypoint, an all-round laser.
    ``observation``: ``"feature_point"`` (the paper's, range and bearing of the wall's feature
    point, eq. 10) or ``"line"`` (``line_observation.LINE`` through the visible part's measured
    end points; unused when its direction's sigma exceeds ``max_line_direction_sigma``).
    """

    speed: float = PAPER_SPEED
    speed_sigma: float = 0.3
    max_steer: float = PAPER_MAX_STEER
    max_steer_rate: float = PAPER_MAX_STEER_RATE
    steer_sigma: float = math.radians(3.0)
    period: float = 0.025
    max_range: float = 30.0
    range_sigma: float = 0.1
    bearing_sigma: float = math.radians(1.0)
    wheelbase: float = DEFAULT_WHEELBASE
    observe_every: int = 8
    waypoint_radius: float = 1.0
    start: tuple[float, float] = PAPER_START
    waypoints: tuple[tuple[float, float], ...] = PAPER_WAYPOINTS
    extended: bool = False
    max_steps: int = 10_000
    observation: str = "feature_point"
    max_line_direction_sigma: float = math.radians(2.0)

    def filter(self, pose, **options) -> EkfSlam:
        """EKF-SLAM from ``pose`` with this scenario's noise, period and wheelbase (``options``:
        :class:`EkfSlam`'s ``pose_cov`` and ``model``)."""
        Q = diagonal_cov(self.speed_sigma, self.steer_sigma)  # speed and steering angle
        R = diagonal_cov(self.range_sigma, self.bearing_sigma)  # range and bearing
        return EkfSlam(pose, Q, R, self.period, self.wheelbase, **options)


@dataclass
class LineSlamRun:
    """One simulated lap. Pose arrays have one row per control step (``(K, 3)``)."""

    scenario: LineSlamScenario
    observer: str
    truth: np.ndarray
    estimate: np.ndarray
    pose_cov: np.ndarray
    dead_reckoning: np.ndarray
    observed_at: np.ndarray
    nees: np.ndarray
    landmarks: np.ndarray
    landmark_cov: np.ndarray
    true_landmarks: np.ndarray
    landmark_of_segment: dict
    endpoints: dict = field(default_factory=dict)
    dropped: int = 0
    observer_seconds: float = 0.0
    seconds: float = 0.0

    def final_error(self) -> float:
        """Distance between the final estimated and true positions, metres."""
        return float(np.hypot(*(self.estimate[-1, :2] - self.truth[-1, :2])))

    def final_dead_reckoning_error(self) -> float:
        return float(np.hypot(*(self.dead_reckoning[-1, :2] - self.truth[-1, :2])))

    def estimated_segment(self, segment: int) -> np.ndarray:
        """End points (2 x 2) of a segment as mapped: the observed end points, placed with the
        estimated pose at the time, projected on the final estimated line; extremes kept."""
        j = self.landmark_of_segment[segment]
        point = self.landmarks[j]
        s = along_line(point, self.endpoints[segment])
        return line_points(point, [s.min(), s.max()])


def true_visible_extent(world, poses) -> dict:
    """For each segment, the extreme x of its visible part from any of ``poses`` (exact observer)."""
    out = {}
    for i, seg in enumerate(world.segments):
        xs = []
        for p in poses:
            part = visible_segment(seg.start, seg.end, p, LineSlamScenario.max_range)
            if part is not None:
                xs += [seg.start[0] + t * (seg.end[0] - seg.start[0]) for t in part]
        out[i] = (min(xs), max(xs)) if xs else None
    return out


def _observe(segs, features, pose, sc, observe_part, rng):
    """Noisy observations of the segments visible from ``pose``: ``(measurements, covariances
    (line form), segment indices, end-point observations, observer seconds)``."""
    obs_sigma = np.array([sc.range_sigma, sc.bearing_sigma])
    zs, obs_covs, which, ends = [], [], [], []
    seconds = 0.0
    for i, (a, b) in enumerate(segs):
        t0 = time.perf_counter()
        part = observe_part(a, b, pose[:2], sc.max_range, DEFAULT_TOLERANCE)
        seconds += time.perf_counter() - t0
        if part is None:
            continue
        if sc.observation == "feature_point":
            z = observe_point(pose, features[i]) + obs_sigma * rng.standard_normal(2)
        e = [observe_point(pose, a + t * (b - a)) + obs_sigma * rng.standard_normal(2) for t in part]
        if sc.observation == "line":
            z, cov = measure_line(e, sc.range_sigma, sc.bearing_sigma)
            if cov[1, 1] > sc.max_line_direction_sigma**2:
                continue
            obs_covs.append(cov)
        zs.append(z)
        which.append(i)
        ends.append(e)
    return zs, obs_covs, which, ends, seconds


def simulate_lap(
    seed: int = 0,
    observer: str = "closed_form",
    scenario: LineSlamScenario | None = None,
) -> LineSlamRun:
    """Drive one lap of the waypoints and run EKF-SLAM on it.

    The filter and dead reckoning get the commanded controls with Gaussian noise (eq. 4's ``w``).
    Every ``observe_every`` periods ``observer`` finds each segment's visible part, whose end
    points are observed in range and bearing (and, in the feature-point form, its feature point).
    """
    if observer not in OBSERVERS:
        raise ValueError(f"observer must be one of {sorted(OBSERVERS)}; got {observer!r}")
    sc = scenario or LineSlamScenario()
    models = {"feature_point": POINT, "line": LINE}
    if sc.observation not in models:
        raise ValueError(f"observation must be one of {sorted(models)}; got {sc.observation!r}")
    rng = np.random.default_rng(seed)
    world = paper_world(sc.extended)
    segs = [(np.array(s.start), np.array(s.end)) for s in world.segments]
    features = np.array([feature_point(a, b) for a, b in segs])
    observe_part = OBSERVERS[observer]

    first = sc.waypoints[0]
    pose = np.array([*sc.start, math.atan2(first[1] - sc.start[1], first[0] - sc.start[0])])
    ekf = sc.filter(pose, model=models[sc.observation])
    dr = pose.copy()
    steer, target = 0.0, 0
    # per step: truth, estimate, pose covariance, dead reckoning
    rows = [(pose.copy(), pose.copy(), ekf.P.copy(), dr.copy())]
    observed_at, nees = [], []
    landmark_of_segment: dict[int, int] = {}
    endpoints: dict[int, list] = {i: [] for i in range(len(segs))}
    dropped, observer_seconds = 0, 0.0
    noise_sigma = np.array([sc.speed_sigma, sc.steer_sigma])
    started = time.perf_counter()
    for k in range(1, sc.max_steps + 1):
        if math.hypot(*(np.asarray(sc.waypoints[target]) - pose[:2])) < sc.waypoint_radius:
            target += 1
            if target == len(sc.waypoints):
                break
        steer = steer_towards(pose, steer, sc.waypoints[target], sc.period, sc.max_steer, sc.max_steer_rate)
        pose = bicycle_step(pose, sc.speed, steer, sc.period, sc.wheelbase)
        speed_m, steer_m = np.array([sc.speed, steer]) + noise_sigma * rng.standard_normal(2)
        ekf.predict(speed_m, steer_m)
        dr = bicycle_step(dr, speed_m, steer_m, sc.period, sc.wheelbase)
        if k % sc.observe_every == 0:
            zs, obs_covs, which, ends, seconds = _observe(segs, features, pose, sc, observe_part, rng)
            observer_seconds += seconds
            indices = ekf.observe(zs, covariances=obs_covs if sc.observation == "line" else None)
            for i, j, e in zip(which, indices, ends, strict=True):
                if j == DROPPED:
                    dropped += 1
                    continue
                landmark_of_segment.setdefault(i, j)
                endpoints[i] += [point_from_observation(ekf.pose, z)[0] for z in e]
            observed_at.append(k)
            if k >= 4 * sc.observe_every:  # the pose covariance is rank-deficient for the first steps
                nees.append(ekf.pose_nees(pose))
        rows.append((pose.copy(), ekf.pose.copy(), ekf.pose_cov.copy(), dr.copy()))
    truth, est, covs, dead = (np.array(column) for column in zip(*rows, strict=True))
    n = ekf.n_landmarks
    return LineSlamRun(
        scenario=sc,
        observer=observer,
        truth=truth,
        estimate=est,
        pose_cov=covs,
        dead_reckoning=dead,
        observed_at=np.array(observed_at),
        nees=np.array(nees),
        landmarks=ekf.x[3:].reshape(n, 2).copy(),
        landmark_cov=np.array([ekf.landmark_cov(j) for j in range(n)]),
        true_landmarks=features,
        landmark_of_segment=landmark_of_segment,
        endpoints={i: np.array(v).reshape(-1, 2) for i, v in endpoints.items()},
        dropped=dropped,
        observer_seconds=observer_seconds,
        seconds=time.perf_counter() - started,
    )


def heading_errors(run: LineSlamRun) -> np.ndarray:
    """Estimated minus true heading per control step, wrapped."""
    return wrap_angle(run.estimate[:, 2] - run.truth[:, 2])


def lap_row(run: LineSlamRun, extended: LineSlamRun, line: LineSlamRun) -> dict[str, float]:
    """One seed's figures from its lap, its lap with landmark 3 ``extended`` and its ``line`` lap:
    final errors (m), pose NEES, landmarks, dropped observations, and how far the extended landmark
    3 is mapped (NaN if never) and visible."""
    nees = np.asarray(run.nees, float)
    mapped = 2 in extended.landmark_of_segment
    return {
        "final_error": run.final_error(),
        "dead_reckoning_error": run.final_dead_reckoning_error(),
        "line_form_error": line.final_error(),
        "slam_closer": float(run.final_error() < run.final_dead_reckoning_error()),
        "nees_mean": float(np.nanmean(nees)),
        "nees_final": float(nees[-1]),
        "nees_above": float(np.mean(nees > NEES_HIGH)),
        "landmarks": len(run.landmarks),
        "dropped": int(run.dropped),
        "extended_mapped_to": float(extended.estimated_segment(2)[:, 0].max()) if mapped else math.nan,
        "extended_visible_to": true_visible_extent(paper_world(True), extended.truth)[2][1],
    }


def lap_figures(seed: int, observer: str = "closed_form") -> dict:
    """One seed's :func:`lap_row` (a task of ``sweep lap``), its three laps drawn with ``seed``."""
    scenarios = (LineSlamScenario(), LineSlamScenario(extended=True), LineSlamScenario(observation="line"))
    return lap_row(*(simulate_lap(int(seed), observer, sc) for sc in scenarios))


def lap_report(table, stats) -> None:
    """What ``sweep lap`` prints below its summary (``table``: a row per seed; ``stats``: a row per
    figure): EKF-SLAM against dead reckoning, the NEES, the extended landmark 3 beside the paper's."""
    closer, laps = int(table["slam_closer"].sum()), len(table)
    ratio = stats.loc["dead_reckoning_error", "mean"] / stats.loc["final_error", "mean"]
    mapped, visible = stats.loc["extended_mapped_to"], stats.loc["extended_visible_to"]
    print(
        f"EKF-SLAM ends closer to the truth than dead reckoning on {closer} of {laps} laps; dead "
        f"reckoning's mean final error is {ratio:.0f}x EKF-SLAM's"
    )
    point, line = "the feature-point form", "the line form"
    forms = Comparison(tuple(table["seed"]), {point: table["final_error"], line: table["line_form_error"]})
    print(f"final error: {forms.sentence(point, line, unit='m', digits=3)}")
    print(
        "a consistent filter: nees_mean 3, nees_above 2.5 % "
        f"(one lap's per-step 95 % band ends at {NEES_HIGH:.2f})"
    )
    print(
        f"extended landmark 3 mapped up to x = {mapped['mean']:.2f} "
        f"(95 % interval {interval_text(mapped['low'], mapped['high'], 2)}), "
        f"visible from the true path up to {visible['mean']:.2f}; "
        f"paper {PAPER_EXTENDED_RIGHT_END}"
    )


def association_example():
    """A case where the nearest landmark in metres is the wrong one: ``(ekf, z, true_index)``.

    The robot believes it faces +x at the origin (5 degrees of heading doubt); A is 20 m away 4
    degrees left, B 20.9 m ahead. A seen at 20 m, bearing 0, is 1.4 m from A and 0.9 m from B:
    Euclidean distance picks B, the Mahalanobis distance (eq. 13) A, as the error lies along the
    uncertain bearing.
    """
    ekf = LineSlamScenario().filter(np.zeros(3), pose_cov=np.diag([0.05**2, 0.05**2, math.radians(5.0) ** 2]))
    a = 20.0 * np.array([math.cos(math.radians(4.0)), math.sin(math.radians(4.0))])
    for point in (a, np.array([20.9, 0.0])):
        ekf.augment(observe_point(ekf.pose, point))
    # The landmarks were mapped long ago: only their own small uncertainty remains.
    ekf.P[3:, :3] = ekf.P[:3, 3:] = 0.0
    ekf.P[3:, 3:] = np.eye(4) * 0.05**2
    return ekf, np.array([20.0, 0.0]), 0
