"""Demonstration drives of notebook 07 (Kalman fusion), kept out of its story cells.

A drive of the project's samples with synthetic matches, run through odometry alone, VO alone,
the fused filter and the slip-calibrated filter; the figures the notebook compares over seeds;
and the interactive ``fuse`` widget. The filters themselves are :mod:`vo_lib.stereo_vo.kalman`.

The seed study of section 4 (five conditions and the sideways study, :data:`STUDY_SEEDS` seeds
each: about 276,000 frames, about eight minutes on two cores) is run once and stored beside this module
(``demo_fusion.json``, package data). :func:`seed_figures` reads it when it holds the seeds asked
for and was made from the present samples, and runs the study otherwise. ``python -m vo_book.demo_fusion``
stores it again; ``pytest -m samples`` runs it again and must find the same figures.
"""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from vo_book.nb07 import plot_errors
from vo_book.plotting import new_axes
from vo_lib.atomic import write_atomic
from vo_lib.camera import StereoCamera
from vo_lib.comparison import Comparison
from vo_lib.geometry import compose_planar, relative_planar, wrap_angle
from vo_lib.models.track_odometry import TrackOdometry
from vo_lib.sim.samples import SAMPLES, fingerprint
from vo_lib.sim.trajectories import simulate_drive
from vo_lib.stereo_vo import circular_motion as cm
from vo_lib.stereo_vo.kalman import SIDEWAYS_SIGMA, SlipCalibratedFilter, VoKalmanFilter, nis
from vo_lib.stereo_vo.ransac import one_point_ransac
from vo_lib.stereo_vo.synthetic import synthetic_matches

#: The notebook's base seed: a drive's draws come from it unless another is given.
SEED = 7
#: The estimators every drive reports, in the order of the notebook's tables.
ESTIMATORS = ("odometry", "VO", "fused", "calibrated")
#: Section 4's conditions: a sample and the drive's settings (weak vision: 40 matches with 2 px
#: noise, as on a low-texture floor; an outage: no VO for 100 frames).
CONDITIONS = {
    "spot turn": ("spot_turn", {}),
    "spot turn, weak vision": ("spot_turn", {"vo_noise": 2.0, "matches": 40}),
    "spot turn, VO outage": ("spot_turn", {"outage": range(100, 200)}),
    "indoor": ("indoor_free", {}),
    "indoor, weak vision": ("indoor_free", {"vo_noise": 2.0, "matches": 40}),
}
#: Frames of each condition's drive.
STUDY_FRAMES = 300
#: Seeds of the study, from :data:`SEED` on. Ten and then forty left some verdicts to the draws
#: (the sideways study read otherwise at other base seeds); at 120 the verdicts on differences of
#: a few hundredths of a degree, and the plain filter's indoor NEES near 3, still move with the base.
STUDY_SEEDS = 120
#: The comparisons section 4 states from the one study: ten of the fused filter against each
#: sensor alone, six of the calibrated filter against the plain one, and one of the sideways row.
#: Each interval is one of this family's (:mod:`vo_lib.comparison`): judged each at 95 %, the
#: borderline ones among seventeen read one way at base seed 7 and the other way at 1007.
STUDY_COMPARISONS = 17
#: The verdicts the section draws from the same study: those comparisons and the four time-averaged
#: NEES against 3 (two filters, two conditions). Every interval is widened for all of them.
STUDY_FAMILY = STUDY_COMPARISONS + 4
#: The comparisons :func:`said` has stated, ``(id of the comparison, a, b)``: the notebook's
#: checks hold their number to :data:`STUDY_COMPARISONS`.
STATED: set[tuple[int, str, str]] = set()
#: The stored seed study (package data, so an installed wheel has it too).
STORED = Path(__file__).resolve().with_name("demo_fusion.json")
camera = StereoCamera.bumblebee2()
odometry = TrackOdometry()


def run_drive(
    name,
    frames,
    seed=SEED,
    outage=(),
    vo_noise=0.5,
    matches=300,
    slip_scale=1.0,
    use_odometry=True,
    sideways_sigma=SIDEWAYS_SIGMA,
):
    """One draw of a sample drive with synthetic matches: the trajectories of the truth, odometry
    alone, VO alone, the fused filter and the slip-calibrated fused filter, the fused filter's
    heading σ, its NEES per frame and NIS per update, and the frames without VO. The seed draws
    the drive's slip and encoder noise and the matches (the fused filters predict with constant
    velocity when ``use_odometry`` is false)."""
    sample = SAMPLES[name]
    slip = sample.slip
    if slip_scale != 1.0:
        slip = replace(
            slip,
            mean=slip.mean * slip_scale,
            spot_turn_mean=slip.spot_turn_mean * slip_scale,
            difference=slip.difference * slip_scale,
            spot_turn_difference=slip.spot_turn_difference * slip_scale,
        )
    drive_rng = np.random.default_rng(seed)
    drive = simulate_drive(sample.legs, sample.rate, sample.start, drive_rng, odometry, slip)
    truth = drive.poses[: frames + 1]
    r = np.random.default_rng(seed + 10_000)
    kf = VoKalmanFilter(odometry, pose=truth[0], sideways_sigma=sideways_sigma)
    cal = SlipCalibratedFilter(odometry, pose=truth[0], sideways_sigma=sideways_sigma)
    paths = {k: [truth[0]] for k in ("odometry", "VO", "fused", "calibrated")}
    yaw_sigma, nees_f, nees_c, nis_f, flagged, last = [0.0], [], [], [], [], np.zeros(3)
    for k in range(1, frames + 1):
        u = drive.odometry[k] if use_odometry else None
        kf.predict(u)
        cal.predict(u)
        paths["odometry"].append(odometry.predict(paths["odometry"][-1], drive.odometry[k]))
        theta, rho = cm.circular_motion_from_increment(relative_planar(truth[k - 1], truth[k]))
        if k in outage:
            flagged.append(k)  # nothing to see: the filters keep their predictions
        else:
            m = synthetic_matches(camera, matches, theta, rho, r, noise_px=vo_noise, outlier_ratio=0.3)
            est = one_point_ransac(
                m.w_prev, m.w_curr, camera, prior=kf.motion_prior(), rng=r, pixel_sigma=max(vo_noise, 0.1)
            )
            kf.update(est.theta, est.rho, est.covariance)
            nis_f.append(nis(kf.ekf.y[:2], kf.ekf.S[:2, :2]))
            cal.update(est.theta, est.rho, est.covariance)
            last = cm.robot_increment(est.theta, est.rho)
        paths["VO"].append(compose_planar(paths["VO"][-1], last))  # its last motion again in a gap
        for f_, key, log in ((kf, "fused", nees_f), (cal, "calibrated", nees_c)):
            f_.finish_frame()
            paths[key].append(f_.pose)
            log.append(f_.nees(truth[k]))
        yaw_sigma.append(math.sqrt(kf.covariance[2, 2]))
    return {
        "truth": truth,
        **{k: np.array(v) for k, v in paths.items()},
        "yaw_sigma": np.array(yaw_sigma),
        "nees": np.array(nees_f),
        "nees_calibrated": np.array(nees_c),
        "nis": np.array(nis_f),
        "flagged": flagged,
        "turn_scale": float(np.mean(cal.scales)),
        "scale_sigma": math.sqrt(np.ones(2) @ cal.scale_covariance @ np.ones(2)) / 2,
    }


def heading_error(est: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """Heading error of each pose of ``est`` against ``truth``, degrees in (-180, 180]."""
    return np.degrees(wrap_angle(est[:, 2] - truth[:, 2]))


def final_heading(d: dict) -> dict[str, float]:
    """|Final heading error| [deg] of each estimator of the drive ``d``."""
    return {k: abs(heading_error(d[k], d["truth"])[-1]) for k in ESTIMATORS}


def final_position(d: dict) -> dict[str, float]:
    """Final position error [cm] of each estimator of the drive ``d``."""
    return {k: 100 * float(np.linalg.norm(d[k][-1, :2] - d["truth"][-1, :2])) for k in ESTIMATORS}


def said(comparison: Comparison, a: str, b: str, unit: str) -> str:
    """The sentence of a comparison, with its unit (and counted in :data:`STATED`)."""
    STATED.add((id(comparison), a, b))
    return comparison.sentence(a, b, unit=unit, digits=3)


def nees_words(mean, low_, high_):
    """A seed interval of a time-averaged NEES against 3, in words."""
    if low_ > 3:
        return f"{mean:.2f} (interval {low_:.2f}–{high_:.2f}, above 3: over-confident)"
    if high_ < 3:
        return f"{mean:.2f} (interval {low_:.2f}–{high_:.2f}, below 3: more cautious than it need be)"
    return f"{mean:.2f} (interval {low_:.2f}–{high_:.2f}, consistent with 3)"


def sideways_ends(seed):
    """Final position error [cm] of the fused filter with and without the sideways measurement,
    predicting with odometry and with constant velocity, on one draw of 200 indoor frames."""
    ends = {}
    for label, sigma_side in (("with", SIDEWAYS_SIGMA), ("without", 1e3)):  # σ = 1 km: not observed
        for use_odo, pred in ((True, "odometry"), (False, "constant velocity")):
            d = run_drive("indoor_free", 200, seed=seed, use_odometry=use_odo, sideways_sigma=sigma_side)
            end_error = np.linalg.norm(d["fused"][-1, :2] - d["truth"][-1, :2])
            ends[f"{pred} {label} the sideways row"] = 100 * float(end_error)
    return ends


def fuse(slip_scale=1.0, vo_noise_px=0.5, outage_frames=0, seed=SEED):
    """Final heading errors of odometry, VO and the two fused filters on 300 spot-turn frames."""
    gap = set(range(100, 100 + int(outage_frames)))
    d = run_drive("spot_turn", 300, seed=int(seed), outage=gap, vo_noise=vo_noise_px, slip_scale=slip_scale)
    fig, ax = new_axes(width=6.5, height=3.2)
    frames_t = np.arange(len(d["truth"])) / SAMPLES["spot_turn"].rate
    plot_errors(ax, frames_t, {k: heading_error(d[k], d["truth"]) for k in ESTIMATORS}, "heading error [deg]")
    if gap:
        ax.axvspan(min(gap) / SAMPLES["spot_turn"].rate, max(gap) / SAMPLES["spot_turn"].rate, color="0.85")
    plt.show()
    return {k: abs(heading_error(d[k], d["truth"])[-1]) for k in ESTIMATORS}


def drive_figures(d: dict) -> dict:
    """What section 4 keeps of one drive: final heading [deg] and position [cm] errors of each
    estimator, the calibrated filter's learnt turn scale and its σ, and the two filters'
    time-averaged NEES."""
    return {
        "heading": final_heading(d),
        "position": final_position(d),
        "turn_scale": d["turn_scale"],
        "scale_sigma": d["scale_sigma"],
        "nees": float(d["nees"].mean()),
        "nees_calibrated": float(d["nees_calibrated"].mean()),
    }


def study_fingerprint() -> str:
    """The fingerprints of the samples the study draws from."""
    return " ".join(fingerprint(n) for n in sorted({n for n, _ in CONDITIONS.values()}))


def run_study(seeds) -> dict:
    """Section 4's seed study, run: ``{"seeds", "fingerprint", "conditions": {condition: {seed:
    drive_figures}}, "sideways": {seed: sideways_ends}}`` (seeds as text, as JSON keeps them)."""
    seeds = [int(s) for s in seeds]
    return {
        "seeds": seeds,
        "fingerprint": study_fingerprint(),
        "conditions": {
            c: {str(s): drive_figures(run_drive(n, STUDY_FRAMES, seed=s, **kw)) for s in seeds}
            for c, (n, kw) in CONDITIONS.items()
        },
        "sideways": {str(s): sideways_ends(s) for s in seeds},
    }


def seed_figures(seeds, fresh: bool = False) -> dict:
    """Section 4's seed study for ``seeds``: the stored one when it holds exactly these seeds and
    was made from the present samples (and ``fresh`` is false), else run now (about 2 s a seed)."""
    seeds = [int(s) for s in seeds]
    if not fresh and STORED.exists():
        stored = json.loads(STORED.read_text())
        if stored["seeds"] == seeds and stored["fingerprint"] == study_fingerprint():
            return stored
    return run_study(seeds)


def main(argv=None) -> int:
    """Run the study for the notebook's seeds and store it (an interrupted write keeps the old file)."""
    study = run_study(range(SEED, SEED + STUDY_SEEDS))
    print(f"written {write_atomic(STORED, json.dumps(study, indent=1) + chr(10))}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
