"""The papers' statistics as sweep experiments (:mod:`vo_lib.cli.sweep`), one task per seed.

``corridor``  [Yuan], Table III: LBPT and VOAPT along the occluded corridor; the shared setup
              is one PnP visual-odometry run on the rendered corridor and the calibration on the
              normal run; each task is ``corridor_experiment.track_seed`` and ``seed_figures``
``lap``       [Yan 2020]: one lap of the line-feature EKF-SLAM, final error and NEES
``nees``      [Zhao]: one Monte Carlo run of the fused Kalman filter (notebook 07, section 6)
``table1``    [Zhao], Table 1: time per stage on the rendered ``indoor_linear`` drive at one
              resolution (notebook 08, section 2)

Every task draws from its own parameters (``seed``); figures are plain numbers. Timings
(``table1``) measured with several workers on one machine compete for its cores.
"""

from __future__ import annotations

import functools

import numpy as np

from vo_lib.cli.sweep import Experiment

#: [Zhao]'s Table 1 resolutions, largest first.
TABLE1_RESOLUTIONS = ("640x480", "512x384", "400x300", "320x240", "256x192")


# --------------------------------------------------------------------------- [Yuan], Table III


def corridor_setup(calibration_seed: int = 1000, every: int = 2):
    """What every corridor task shares: the visual odometer's poses and the calibration."""
    from vo_lib.lidar_tracking.corridor_experiment import corridor_calibration, corridor_visual_odometry

    vo, _ = corridor_visual_odometry()
    return {"vo": vo, "calibration": corridor_calibration(vo, calibration_seed, every)}


@functools.lru_cache(maxsize=1)
def _corridor_world():
    from vo_lib.lidar_tracking.likelihood_field import LikelihoodField
    from vo_lib.sim.world import corridor

    world = corridor()
    return world, LikelihoodField.from_world(world)


def corridor_task(params: dict, context) -> dict:
    """Table III's row of one seed (:func:`~vo_lib.lidar_tracking.corridor_experiment.seed_figures`)."""
    from vo_lib.lidar_tracking.corridor_experiment import seed_figures, track_seed

    world, field = _corridor_world()
    runs = track_seed(
        int(params["seed"]), context["vo"], context["calibration"], int(params.get("every", 2)), world, field
    )
    return seed_figures(*runs)


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
    """One lap of [Yan 2020]'s EKF-SLAM (:func:`vo_lib.line_slam.lap.lap_figures`)."""
    from vo_lib.line_slam.lap import lap_figures

    return lap_figures(**params)


LAP = Experiment("lap", lap_task, None, "[Yan 2020], one lap of line-feature EKF-SLAM per seed")


def lap_tasks(seeds: int, observer: str = "closed_form", observation: str = "feature_point") -> list[dict]:
    return [{"seed": s, "observer": observer, "observation": observation} for s in range(seeds)]


# --------------------------------------------------------------------------- [Zhao], NEES


def nees_task(params: dict, context=None) -> dict:
    """One Monte Carlo run of the fused filter (:func:`vo_lib.stereo_vo.consistency.monte_carlo_run`,
    notebook 07, section 6): mean and final pose NEES, share of steps inside chi2(3)'s 95 % interval."""
    from scipy.stats import chi2

    from vo_lib.stereo_vo.consistency import monte_carlo_run

    nees, _ = monte_carlo_run(int(params["seed"]), int(params.get("steps", 150)))
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


#: Each sweep: its experiment and its tasks for a number of seeds.
SWEEPS = {
    "corridor": (corridor_experiment, corridor_tasks),
    "lap": (lambda: LAP, lap_tasks),
    "nees": (lambda: NEES, nees_tasks),
    "table1": (lambda: TABLE1, table1_tasks),
}


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

    make_experiment, make_tasks = SWEEPS[name]
    experiment, tasks = make_experiment(), make_tasks(seeds)
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
