"""The papers' statistics as sweep experiments (:mod:`vo_lib.cli.sweep`), one task per seed.

``corridor``  [Yuan], Table III: LBPT and VOAPT along the occluded corridor; the shared setup
              is one PnP visual-odometry run on the rendered corridor and the calibration on the
              normal run (``corridor_experiment.run_experiment`` split into its per-seed pieces)
``lap``       [Yan 2020]: one lap of the line-feature EKF-SLAM, final error and NEES
``nees``      [Zhao]: one Monte Carlo run of the fused Kalman filter (notebook 07, section 4)
``table1``    [Zhao], Table 1: time per stage on the rendered ``indoor_linear`` drive at one
              resolution (notebook 08, section 2)

Every task draws from its own parameters (``seed``); figures are plain numbers. Timings
(``table1``) measured with several workers on one machine compete for its cores.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from vo_lib.cli.sweep import Experiment

#: [Zhao]'s Table 1 resolutions, largest first.
TABLE1_RESOLUTIONS = ("640x480", "512x384", "400x300", "320x240", "256x192")


# --------------------------------------------------------------------------- [Yuan], Table III


def corridor_setup(calibration_seed: int = 1000, every: int = 2):
    """What every corridor task shares: the visual odometer's poses and the calibration."""
    from vo_lib.lidar_tracking.corridor_experiment import (
        calibrate,
        corridor_drive,
        corridor_visual_odometry,
    )
    from vo_lib.sim.world import corridor

    vo, _ = corridor_visual_odometry()
    truth, odometry = corridor_drive(calibration_seed)
    return {"vo": vo, "calibration": calibrate(corridor(), truth, odometry, vo, calibration_seed, every)}


@functools.lru_cache(maxsize=1)
def _corridor_world():
    from vo_lib.lidar_tracking.likelihood_field import LikelihoodField
    from vo_lib.sim.world import corridor

    world = corridor()
    return world, LikelihoodField.from_world(world)


def corridor_task(params: dict, context) -> dict:
    """Table III's statistics of one seed: LBPT and VOAPT, x and y, max/mean/median/std (m), and
    LBPT's lost updates (error above 0.2 m) with how many of them T_s flags."""
    from vo_lib.lidar_tracking.corridor_experiment import (
        LOST_ERROR,
        corridor_drive,
        run_tracking,
        statistics_table,
    )

    world, field = _corridor_world()
    seed, every = int(params["seed"]), int(params.get("every", 2))
    truth, odometry = corridor_drive(seed)
    vo, cal = context["vo"], context["calibration"]
    runs = {
        "lbpt": run_tracking(
            world, truth, odometry, vo, seed, cal, compensate=False, every=every, field=field
        ),
        "voapt": run_tracking(world, truth, odometry, vo, seed, cal, every=every, field=field),
    }
    out = {}
    for method, run in runs.items():
        for axis, name in ((0, "x"), (1, "y")):
            for stat, value in statistics_table(run.errors[:, axis]).items():
                out[f"{method}_{name}_{stat}"] = value
    lost = np.abs(runs["lbpt"].errors[:, 0]) > LOST_ERROR
    out["lbpt_lost"] = int(lost.sum())
    out["lbpt_lost_flagged"] = int(
        sum(not s.credible for s, x in zip(runs["lbpt"].steps, lost, strict=True) if x)
    )
    return out


def corridor_experiment(calibration_seed: int = 1000, every: int = 2) -> Experiment:
    return Experiment(
        "corridor",
        corridor_task,
        functools.partial(corridor_setup, calibration_seed, every),
        "[Yuan], Table III (LBPT and VOAPT along the occluded corridor)",
    )


def corridor_tasks(seeds: int, calibration_seed: int = 1000, every: int = 2) -> list[dict]:
    return [{"seed": s, "calibration_seed": calibration_seed, "every": every} for s in range(seeds)]


# --------------------------------------------------------------------------- [Yan 2020], laps


def lap_task(params: dict, context=None) -> dict:
    """One lap of [Yan 2020]'s EKF-SLAM: final errors (m), mean and final NEES, landmarks mapped."""
    from vo_lib.line_slam.lap import LineSlamScenario, simulate_lap

    scenario = LineSlamScenario(observation=params.get("observation", "feature_point"))
    run = simulate_lap(int(params["seed"]), params.get("observer", "closed_form"), scenario)
    nees = np.asarray(run.nees, float)
    return {
        "final_error": run.final_error(),
        "dead_reckoning_error": run.final_dead_reckoning_error(),
        "nees_mean": float(np.nanmean(nees)),
        "nees_final": float(nees[-1]),
        "landmarks": len(run.landmarks),
        "dropped": int(run.dropped),
    }


LAP = Experiment("lap", lap_task, None, "[Yan 2020], one lap of line-feature EKF-SLAM per seed")


def lap_tasks(seeds: int, observer: str = "closed_form", observation: str = "feature_point") -> list[dict]:
    return [{"seed": s, "observer": observer, "observation": observation} for s in range(seeds)]


# --------------------------------------------------------------------------- [Zhao], NEES

#: Notebook 07's Monte Carlo settings: VO noise, initial covariance.
NEES_R_VO = np.diag([math.radians(0.05) ** 2, 0.002**2])
NEES_P0 = np.diag([0.01**2, 0.01**2, math.radians(0.5) ** 2])


def nees_task(params: dict, context=None) -> dict:
    """One Monte Carlo run of the fused filter (notebook 07, section 4): the truth's start drawn
    from the initial covariance, odometry and VO drawn from exactly the noise the filter assumes.
    Figures: mean and final pose NEES, share of steps inside chi2(3)'s 95 % interval."""
    from scipy.stats import chi2

    from vo_lib.models.track_odometry import TrackOdometry
    from vo_lib.stereo_vo.kalman import VoKalmanFilter, measurement

    steps = int(params.get("steps", 150))
    r = np.random.default_rng(int(params["seed"]))
    odometry = TrackOdometry()
    f = VoKalmanFilter(odometry, covariance=NEES_P0)
    x_true = f.pose + r.multivariate_normal(np.zeros(3), NEES_P0)
    nees = np.zeros(steps)
    for k in range(steps):
        u_true = odometry.controls_for(0.02 + 0.01 * math.sin(k / 20), math.radians(1.0) * math.sin(k / 30))
        u_meas = u_true + r.multivariate_normal(np.zeros(2), f.control_covariance(u_true))
        x_prev, x_true = x_true, odometry.predict(x_true, u_true)
        f.predict(u_meas)
        z = measurement(np.concatenate([x_true, x_prev])) + r.multivariate_normal(np.zeros(2), NEES_R_VO)
        f.update(z[0], z[1], NEES_R_VO)
        f.finish_frame()
        nees[k] = f.nees(x_true)
    lo, hi = chi2.ppf([0.025, 0.975], 3)
    return {
        "nees_mean": float(nees.mean()),
        "nees_final": float(nees[-1]),
        "inside_95": float(np.mean((nees > lo) & (nees < hi))),
    }


NEES = Experiment("nees", nees_task, None, "[Zhao], consistency of the fused Kalman filter (pose NEES)")


def nees_tasks(seeds: int, steps: int = 150, first_seed: int = 1000) -> list[dict]:
    return [{"seed": first_seed + s, "steps": steps} for s in range(seeds)]


def nees_band(runs: int) -> tuple[float, float]:
    """The 95 % interval of the NEES averaged over ``runs`` consistent runs (3 degrees of freedom)."""
    from scipy.stats import chi2

    lo, hi = chi2.ppf([0.025, 0.975], 3 * runs) / runs
    return float(lo), float(hi)


# --------------------------------------------------------------------------- [Zhao], Table 1


def table1_task(params: dict, context=None) -> dict:
    """Median milliseconds per stage of the pipeline on ``frames`` rendered frames of the
    ``indoor_linear`` drive at one resolution, and the median stereo feature count."""
    from vo_lib.sim.samples import render_sample
    from vo_lib.stereo_vo.pipeline import run_frames

    w, h = (int(x) for x in str(params["resolution"]).split("x"))
    rendered, frames = render_sample("indoor_linear", int(params.get("frames", 40)), (w, h))
    result = run_frames(frames, rendered.camera, seed=int(params["seed"]))
    out = {f"{k}_ms": v for k, v in result.timing_table().items()}
    out["features"] = float(np.median([d.features for d in result.diagnostics]))
    return out


TABLE1 = Experiment("table1", table1_task, None, "[Zhao], Table 1: time per stage at five resolutions")


def table1_tasks(seeds: int, frames: int = 40) -> list[dict]:
    return [
        {"resolution": res, "seed": s, "frames": frames} for res in TABLE1_RESOLUTIONS for s in range(seeds)
    ]


# --------------------------------------------------------------------------- the command


def _experiment(name: str, seeds: int) -> tuple[Experiment, list[dict]]:
    if name == "corridor":
        return corridor_experiment(), corridor_tasks(seeds)
    if name == "lap":
        return LAP, lap_tasks(seeds)
    if name == "nees":
        return NEES, nees_tasks(seeds)
    if name == "table1":
        return TABLE1, table1_tasks(seeds)
    raise ValueError(f"unknown experiment {name!r}")


SWEEPS = ("corridor", "lap", "nees", "table1")


def sweep_command(
    name: str,
    seeds: int,
    workers: int | None = None,
    scheduler: str | None = None,
    out: str | None = None,
    force: bool = False,
) -> None:
    """``python -m vo_lib sweep NAME``: run the sweep, print where its table is and the aggregate."""
    from pathlib import Path

    from vo_lib.cli.sweep import print_aggregate, run_sweep

    experiment, tasks = _experiment(name, seeds)
    target = Path(out) if out else Path("sweeps") / name
    result = run_sweep(experiment, tasks, target, workers, scheduler, force=force)
    print(f"{experiment.describe}: {len(tasks)} tasks" + (f" ({result.workers})" if result.workers else ""))
    print(f"wrote {result.path}")
    print_aggregate(result)
    if name == "corridor":
        ok = [r for r in result.rows if not r.get("error")]
        lost = sum(r["figures"]["lbpt_lost"] for r in ok)
        flagged = sum(r["figures"]["lbpt_lost_flagged"] for r in ok)
        if lost:
            print(f"  T_s flags {flagged} of LBPT's {lost} lost updates ({100 * flagged / lost:.0f} %)")
    elif name == "nees":
        ok = [r["figures"]["nees_mean"] for r in result.rows if not r.get("error")]
        if ok:
            lo, hi = nees_band(len(ok))
            mean = float(np.mean(ok))
            verdict = "inside" if lo < mean < hi else "OUTSIDE"
            print(
                f"  NEES averaged over {len(ok)} runs: {mean:.3f}, {verdict} its 95 % band {lo:.3f}-{hi:.3f}"
            )
    elif name == "table1" and result.workers.startswith("Dask"):
        print("  timings measured on several workers at once share the machine; --workers 1 times alone")
