"""[Yuan]'s corridor experiment: LBPT alone against VOAPT along the occluded corridor.

The robot drives the ``corridor`` sample's path (1 m to 28 m at 0.5 m/s); each seed draws its own
odometry noise and slip, laser noise and pose samples; the visual odometer's increments come from
a VO run on the rendered corridor. ``python -m vo_lib sweep corridor`` prints Table III
(:func:`corridor_figures` per seed, :func:`corridor_report` over them).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, replace

import numpy as np

from vo_lib.comparison import interval_text
from vo_lib.evaluation import ErrorStats
from vo_lib.geometry import compose_planar, planar_from_camera_poses, relative_planar
from vo_lib.lidar_tracking.likelihood_field import LikelihoodField
from vo_lib.lidar_tracking.pnp_odometry import run_pnp_odometry
from vo_lib.lidar_tracking.pose_tracking import Calibration, ControlLimits, PoseTracker, Thresholds
from vo_lib.models.track_odometry import TrackOdometry
from vo_lib.sim.laser import LaserScanner
from vo_lib.sim.samples import get_sample, render_sample
from vo_lib.sim.trajectories import simulate_drive
from vo_lib.sim.world import World, corridor

#: The SICK TIM551 of the paper: 270 degrees at 1 degree (271 beams), 10 m, 1 cm noise.
TIM551 = LaserScanner(fov=np.radians(270.0), angular_step=np.radians(1.0), max_range=10.0, range_sigma=0.01)
#: LBPT's error above which a frame counts as lost, metres (the acceptance criterion's 0.2 m).
LOST_ERROR = 0.2
#: Stretches where radial features are in view of the 10 m laser (x along the corridor, metres).
UNOCCLUDED = ((1.0, 6.0), (18.0, 28.5))
#: The laser tracker updates every this many frames; Table III calibrates on this seed's normal run.
EVERY = 2
CALIBRATION_SEED = 1000
#: Table III's statistics of the absolute errors.
STATISTICS = ("max", "mean", "median", "std")


def corridor_drive(seed: int):
    """``(truth, odometry)`` planar poses per frame of the corridor sample, encoders drawn with ``seed``."""
    sample = get_sample("corridor")
    odo = TrackOdometry()
    drive = simulate_drive(
        sample.legs, sample.rate, sample.start, np.random.default_rng(seed), odo, sample.slip
    )
    return drive.poses, odo.integrate(drive.odometry[1:], start=drive.poses[0])


@functools.lru_cache(maxsize=1)
def corridor_visual_odometry() -> tuple[np.ndarray, np.ndarray]:
    """[Yuan]'s PnP visual odometer on the corridor rendered at 640x480: ``(planar robot poses in
    the world frame (K, 3), seconds per frame)``."""
    rendered, frame_iter = render_sample("corridor", None, (640, 480))
    poses, seconds, _ = run_pnp_odometry(rendered.camera, frame_iter)
    planar = planar_from_camera_poses(poses, rendered.mount)
    return compose_planar(rendered.truth()[0], planar), seconds


def without_umbrella(world: World) -> World:
    """The same corridor with its unmapped obstacle removed: the "normal run" of calibration."""
    return replace(world, segments=tuple(s for s in world.segments if s.mapped))


@dataclass
class TrackingRun:
    """One drive: frame indices of the updates, true and estimated poses there, each update's record."""

    frames: np.ndarray
    truth: np.ndarray
    estimate: np.ndarray
    steps: list

    @property
    def errors(self) -> np.ndarray:
        """``(N, 2)`` x (along the corridor) and y errors, metres."""
        return self.estimate[:, :2] - self.truth[:, :2]


def run_tracking(
    world: World,
    truth: np.ndarray,
    odometry: np.ndarray,
    vo: np.ndarray | None,
    seed: int,
    calibration: Calibration | None = None,
    compensate: bool = True,
    field: LikelihoodField | None = None,
) -> TrackingRun:
    """Track ``truth`` from the increments of the odometry's and the visual odometer's poses
    (``(K, 3)`` each): VOAPT with a calibration, LBPT with ``compensate=False`` (the calibration
    only judges) or without one."""
    field = field or LikelihoodField.from_world(world)
    segments = world.segments_array()
    tracker = PoseTracker(field, truth[0], calibration, compensate, rng=np.random.default_rng(seed))
    scan_rng = np.random.default_rng(seed + 1_000_003)
    frames = np.arange(EVERY, len(truth), EVERY)
    estimate, steps = [], []
    for k in frames:
        odo_inc = relative_planar(odometry[k - EVERY], odometry[k])
        vo_inc = None if vo is None else relative_planar(vo[k - EVERY], vo[k])
        scan = TIM551.scan(segments, truth[k], scan_rng)
        steps.append(tracker.update(odo_inc, scan.points(), vo_inc))
        estimate.append(tracker.pose.copy())
    return TrackingRun(frames, truth[frames], np.array(estimate), steps)


def calibrate(world: World, truth, odometry, vo, seed: int) -> Calibration:
    """Thresholds and control limits from a normal run (no obstacle): each threshold of eq. 13 is
    its indicator's 1 per cent point, the limits (eq. 14-15) come from the frames where ``C_s`` holds."""
    run = run_tracking(without_umbrella(world), truth, odometry, vo, seed)
    stats = [s.stats for s in run.steps]
    thresholds = Thresholds(
        *(float(np.percentile([getattr(s, k) for s in stats], 1.0)) for k in ("v_max", "d_s", "r_s"))
    )
    normal = [st for st in run.steps if thresholds.composite(st.stats)]
    laser, vo_limits = (
        ControlLimits.from_corrections([getattr(st, k) for st in normal])
        for k in ("laser_correction", "vo_correction")
    )
    return Calibration(thresholds, laser, vo_limits)


def statistics_table(errors: np.ndarray) -> dict[str, float]:
    """Table III's statistics (:data:`STATISTICS`) of absolute errors."""
    stats = ErrorStats.of(np.abs(errors))
    return {k: getattr(stats, k) for k in STATISTICS}


def unoccluded(x: np.ndarray) -> np.ndarray:
    """Mask of positions along the corridor where radial features are in the laser's view."""
    return np.any([(x >= lo) & (x <= hi) for lo, hi in UNOCCLUDED], axis=0)


def _flags(run: TrackingRun, where) -> list[bool]:
    """Whether T_s flags each update of ``run`` selected by the mask ``where``."""
    return [not s.credible for s, w in zip(run.steps, where, strict=True) if w]


@dataclass
class CorridorExperiment:
    """LBPT and VOAPT over many seeds, both judged by the same calibration."""

    seeds: list
    calibration: Calibration
    lbpt: list
    voapt: list

    def spread(self, statistic: str, axis: int = 0) -> dict[str, tuple[float, float]]:
        """Mean and standard deviation over seeds of one statistic."""
        out = {}
        for name, runs in (("LBPT", self.lbpt), ("VOAPT", self.voapt)):
            v = [statistics_table(r.errors[:, axis])[statistic] for r in runs]
            out[name] = (float(np.mean(v)), float(np.std(v)))
        return out

    def table(self, axis: int = 0) -> dict[str, dict[str, float]]:
        """Table III for one axis (0: x, along the corridor; 1: y), each statistic averaged over seeds."""
        means = {k: self.spread(k, axis) for k in STATISTICS}
        return {name: {k: means[k][name][0] for k in STATISTICS} for name in ("LBPT", "VOAPT")}

    @staticmethod
    def _flagged(runs, where) -> float:
        """Share of the updates of ``runs`` selected by ``where(run)`` (a mask) that T_s flags."""
        flags = [f for r in runs for f in _flags(r, where(r))]
        return float(np.mean(flags)) if flags else float("nan")

    def flagged_when_lost(self) -> float:
        """Share of LBPT's updates with an along-corridor error above 0.2 m that T_s flags."""
        return self._flagged(self.lbpt, lambda r: np.abs(r.errors[:, 0]) > LOST_ERROR)

    def false_alarms(self) -> float:
        """Share of VOAPT's updates in the unoccluded stretches that T_s flags."""
        return self._flagged(self.voapt, lambda r: unoccluded(r.truth[:, 0]))

    def false_alarms_lbpt(self) -> float:
        """The same on LBPT's updates in the unoccluded stretches where LBPT is within 0.1 m."""
        return self._flagged(self.lbpt, lambda r: unoccluded(r.truth[:, 0]) & (np.abs(r.errors[:, 0]) < 0.1))


def _table3(vo: np.ndarray) -> tuple[World, LikelihoodField, Calibration]:
    """The corridor, its likelihood field and the calibration on :data:`CALIBRATION_SEED`'s run."""
    world = corridor()
    truth, odometry = corridor_drive(CALIBRATION_SEED)
    return world, LikelihoodField.from_world(world), calibrate(world, truth, odometry, vo, CALIBRATION_SEED)


def track_seed(seed: int, vo: np.ndarray, calibration: Calibration, world, field) -> tuple[TrackingRun, ...]:
    """LBPT and VOAPT along the drive of ``seed``, both judged by ``calibration``."""
    truth, odometry = corridor_drive(seed)
    return tuple(run_tracking(world, truth, odometry, vo, seed, calibration, c, field) for c in (False, True))


def seed_figures(lbpt: TrackingRun, voapt: TrackingRun) -> dict[str, float]:
    """One seed's row of Table III: each method's statistics of the x and y errors (m), LBPT's
    lost updates (above :data:`LOST_ERROR`) and VOAPT's unoccluded ones, each with T_s's flags."""
    out = {
        f"{method}_{axis}_{stat}": value
        for method, run in (("lbpt", lbpt), ("voapt", voapt))
        for i, axis in enumerate("xy")
        for stat, value in statistics_table(run.errors[:, i]).items()
    }
    lost = np.abs(lbpt.errors[:, 0]) > LOST_ERROR
    clear = unoccluded(voapt.truth[:, 0])
    out["lbpt_lost"], out["lbpt_lost_flagged"] = int(lost.sum()), sum(_flags(lbpt, lost))
    out["voapt_unoccluded"], out["voapt_false_alarms"] = int(clear.sum()), sum(_flags(voapt, clear))
    return out


@functools.lru_cache(maxsize=1)
def corridor_setup():
    """The visual odometer's poses and :func:`_table3`, shared by every seed of a process."""
    vo, _ = corridor_visual_odometry()
    return vo, *_table3(vo)


def corridor_figures(seed: int) -> dict[str, float]:
    """Table III's row of ``seed`` (a task of ``sweep corridor``): :func:`seed_figures`."""
    vo, world, field, calibration = corridor_setup()
    return seed_figures(*track_seed(seed, vo, calibration, world, field))


def run_experiment(seeds, vo: np.ndarray) -> CorridorExperiment:
    """Calibrate on a normal run (:data:`CALIBRATION_SEED`), then track every seed with LBPT and VOAPT."""
    world, field, cal = _table3(vo)
    runs = [track_seed(seed, vo, cal, world, field) for seed in seeds]
    return CorridorExperiment(list(seeds), cal, [r[0] for r in runs], [r[1] for r in runs])


#: [Yuan], Table III: statistics of the absolute error (m) per axis (X along the corridor) and method.
PAPER_TABLE3 = {
    "X": {
        "LBPT": {"max": 1.060, "mean": 0.332, "median": 0.153, "std": 0.357},
        "VOAPT": {"max": 0.148, "mean": 0.045, "median": 0.047, "std": 0.029},
    },
    "Y": {
        "LBPT": {"max": 0.302, "mean": 0.114, "median": 0.067, "std": 0.099},
        "VOAPT": {"max": 0.133, "mean": 0.045, "median": 0.036, "std": 0.036},
    },
}


def corridor_report(table, stats) -> None:
    """What ``sweep corridor`` prints below its summary (``table``: a row per seed; ``stats``: a
    row per figure): Table III's means over the seeds with 95 % intervals beside the paper's, and
    the shares of LBPT's lost and VOAPT's unoccluded updates that T_s flags."""
    print(f"Table III over {len(table)} seeds: mean over seeds (95 % interval) [paper]")
    for axis, methods in PAPER_TABLE3.items():
        for method, paper in methods.items():
            rows = {k: stats.loc[f"{method.lower()}_{axis.lower()}_{k}"] for k in STATISTICS}
            cells = [
                f"{k} {r['mean']:.3f} m ({interval_text(r['low'], r['high'], 3)}) [{paper[k]:.3f}]"
                for k, r in rows.items()
            ]
            print(f"{method:>6s} {axis}: " + ", ".join(cells))
    lost, flagged = (int(table[c].sum()) for c in ("lbpt_lost", "lbpt_lost_flagged"))
    clear, alarms = (int(table[c].sum()) for c in ("voapt_unoccluded", "voapt_false_alarms"))
    print(
        f"T_s flags {100 * flagged / max(lost, 1):.1f} % of LBPT's updates whose error exceeds "
        f"{LOST_ERROR} m ({flagged} of {lost}) and {100 * alarms / max(clear, 1):.1f} % of VOAPT's "
        f"updates in the unoccluded stretches ({alarms} of {clear}), pooled over the {len(table)} seeds"
    )
