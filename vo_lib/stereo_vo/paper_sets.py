"""[Zhao]'s experiments at the paper's length (:data:`PAPER`), run through the full pipeline and
reported as the paper does: the average (AVG) and standard deviation (S.D.) of the errors at key
positions.

The about 12,700 frames are more than a notebook can afford: ``python -m
vo_lib.stereo_vo.paper_sets [SET ...]`` (default: all; ``contradictions``:
:func:`contradiction_study`; ``fusion``: :func:`fusion_study`) stores the figures in :data:`RESULTS`,
each set with the code version and sample fingerprint that made it; notebook 08 reads them (:func:`load`).
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

from vo_lib.atomic import write_atomic
from vo_lib.evaluation import key_position_errors, planar_path_length, turned_degrees
from vo_lib.geometry import relative_planar, wrap_angle
from vo_lib.models.track_odometry import TrackOdometry
from vo_lib.sim.samples import SAMPLES, fingerprint, render_sample
from vo_lib.stereo_vo.config import CRAWLER
from vo_lib.stereo_vo.pipeline import StereoOdometry, run_frames

#: The stored results, beside this module (package data).
RESULTS = Path(__file__).resolve().with_name("paper_sets.json")
#: Key positions every this many frames (the paper, Fig. 11, does not state their spacing).
KEY_EVERY = 50
#: The pipeline's seed for these runs (notebook 08's).
SEED = 8

#: [Zhao]'s AVG and S.D. of each set's errors at key positions, by quantity (x, y in mm, heading in
#: degrees), the paper's frame count beside each: the spot turns (IV.B.2, heading only), Table 2's three
#: free-motion sets (IV.B.3), outdoor linear motion (IV.B.1, x and y) and indoor free motion (IV.A.3).
PAPER = {
    "spot_turn": {"theta_deg": (6.38, 6.38)},  # 1800
    "spot_turn_2": {"theta_deg": (4.09, 8.17)},  # 2400
    "outdoor_free": {"x_mm": (47.1, 36.4), "y_mm": (268.4, 287.7), "theta_deg": (2.32, 2.57)},  # 1403
    "outdoor_free_2": {"x_mm": (-326.2, 818.1), "y_mm": (-1057.3, 950.6), "theta_deg": (16.68, 5.32)},  # 2419
    "outdoor_free_3": {"x_mm": (-25.4, 135.8), "y_mm": (-131.9, 115.1), "theta_deg": (2.43, 3.68)},  # 2670
    "outdoor_linear": {"x_mm": (15.8, 53.0), "y_mm": (124.5, 40.3)},  # 1200
    "indoor_free": {"x_mm": (-1.5, 47.4), "y_mm": (7.4, 8.5), "theta_deg": (0.05, 0.56)},  # not stated
}
SETS = tuple(PAPER)


def code_version() -> str:
    """The repository's commit, with ``+changes`` when the package's code (not the stored results)
    differs from it."""
    root = Path(__file__).resolve().parents[2]

    def git(*args) -> str:
        done = subprocess.run(["git", *args], cwd=root, capture_output=True, text=True, check=True)
        return done.stdout.strip()

    try:
        commit = git("rev-parse", "HEAD")
        dirty = git(
            "status", "--porcelain", "--untracked-files=no", "--", "vo_lib", f":!{RESULTS.relative_to(root)}"
        )
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    return commit + ("+changes" if dirty else "")


def run_set(name: str) -> dict:
    """Run one set, whole, and return its statistics: the errors (estimate minus truth in the
    start's frame) at every ``KEY_EVERY`` frames of the fused pipeline and of odometry alone
    (:func:`vo_lib.evaluation.key_position_errors`), and the heading errors over every frame."""
    rendered, frame_iter = render_sample(name)
    n = rendered.frames
    result = run_frames(frame_iter, rendered.camera, seed=SEED)
    truth = relative_planar(rendered.truth()[0], rendered.truth())
    odometry = TrackOdometry().integrate(rendered.drive.odometry[1:n])
    keys = np.arange(KEY_EVERY, n, KEY_EVERY)
    heading = np.degrees(wrap_angle(result.poses[:, 2] - truth[:, 2]))
    return {
        "frames": int(n),
        "code_version": code_version(),
        "fingerprint": fingerprint(name),
        "distance_m": planar_path_length(truth),
        "turned_deg": turned_degrees(truth),
        "keys": int(len(keys)),
        "fused": key_position_errors(truth, result.poses, keys),
        "odometry": key_position_errors(truth, odometry, keys),
        "mean_abs_heading_deg": float(np.abs(heading).mean()),
        "max_abs_heading_deg": float(np.abs(heading).max()),
        "flagged": int(len(result.flagged)),
    }


#: The study of vision rejected after a lost track contact: the sample, its first frames, the drives
#: (the sample's seed and the next ones). It sets the preset, which believes the vision after
#: ``CRAWLER.max_contradictions`` consecutive contradicting frames, beside a pipeline that never does.
CONTRADICTION_SET = "outdoor_free_3"
CONTRADICTION_FRAMES = 600
CONTRADICTION_DRIVES = 10
#: The crawler's pipeline that never believes the vision over the prediction, set beside the preset.
NEVER_BELIEVES = replace(CRAWLER, max_contradictions=math.inf)


def drive(name: str, seed: int, frames: int):
    """A draw of sample ``name``'s drive plan with ``seed`` (slip, losses of contact and image noise
    drawn anew), its first ``frames`` frames: ``(rendered, [(left, right, odometry), ...], truth)``
    with the planar truth in the start's frame."""
    variant = f"{name}@{seed}"
    SAMPLES[variant] = replace(SAMPLES[name], name=variant, seed=seed)
    try:
        rendered, frame_iter = render_sample(variant, frames)
        images = list(frame_iter)
    finally:
        del SAMPLES[variant]
    return rendered, images, relative_planar(rendered.truth()[0], rendered.truth())


def contradiction_study(drives=range(CONTRADICTION_DRIVES)) -> dict:
    """The crawler's pipeline as preset and with the vision never believed over the prediction
    (``max_contradictions = inf``) on the study's drives (``drives``: their numbers, all by
    default): per drive, each setting's flagged frames and RMS heading error (degrees)."""
    seeds = [SAMPLES[CONTRADICTION_SET].seed + k for k in drives]
    settings = {"never": NEVER_BELIEVES, "believed": CRAWLER}
    rows = {label: {"flagged": [], "heading_rms_deg": []} for label in settings}
    for seed in seeds:
        rendered, images, truth = drive(CONTRADICTION_SET, seed, CONTRADICTION_FRAMES)
        for label, config in settings.items():
            odometer = StereoOdometry(rendered.camera, config, TrackOdometry(), seed=SEED)
            result = run_frames(iter(images), rendered.camera, odometer=odometer)
            heading = np.degrees(wrap_angle(result.poses[:, 2] - truth[:, 2]))
            rows[label]["flagged"].append(int(len(result.flagged)))
            rows[label]["heading_rms_deg"].append(float(np.sqrt(np.mean(heading**2))))
    return {
        "set": CONTRADICTION_SET,
        "frames": CONTRADICTION_FRAMES,
        "seeds": seeds,
        "limit": CRAWLER.max_contradictions,
        "fingerprint": fingerprint(CONTRADICTION_SET),
        "code_version": code_version(),
        **rows,
    }


#: The study of fusion on rendered drives: the samples (a flat floor without skid, one with skid in
#: tight turns, rough ground with losses of contact, driven freely, straight, and turning on the
#: spot), their first frames and the drives of each.
FUSION_SETS = ("indoor_linear", "indoor_free", "outdoor_free", "outdoor_linear", "spot_turn")
FUSION_FRAMES = 400
FUSION_DRIVES = 40
#: The estimates of each drive: the pipeline fused with track odometry, the same pipeline without
#: odometry (constant-velocity prediction), track odometry alone (eq. 1-4), and the fused pipeline
#: that never believes the vision over the prediction (the setting the contradiction study rejected).
FUSION_ESTIMATES = ("fused", "vision", "odometry", "never")


def fusion_study(drives=range(FUSION_DRIVES)) -> dict:
    """Per set of :data:`FUSION_SETS` and per drive (the sample's seed and the next ones; ``drives``:
    their numbers, all by default): the final position error (m) and the RMS heading error
    (degrees) of each of :data:`FUSION_ESTIMATES`, and the frames each pipeline run flagged."""
    sets = {}
    for name in FUSION_SETS:
        seeds = [SAMPLES[name].seed + k for k in drives]
        rows = {label: {"final_m": [], "heading_rms_deg": [], "flagged": []} for label in FUSION_ESTIMATES}
        for seed in seeds:
            rendered, images, truth = drive(name, seed, FUSION_FRAMES)
            estimates = {"odometry": (TrackOdometry().integrate([u for *_, u in images[1:]]), 0)}
            for label, frames, config in (
                ("fused", images, CRAWLER),
                ("vision", [(a, b, None) for a, b, _ in images], CRAWLER),
                ("never", images, NEVER_BELIEVES),
            ):
                odometer = StereoOdometry(rendered.camera, config, TrackOdometry(), seed=SEED)
                result = run_frames(iter(frames), rendered.camera, odometer=odometer)
                estimates[label] = result.poses, len(result.flagged)
            for label, (poses, flagged) in estimates.items():
                heading = np.degrees(wrap_angle(poses[:, 2] - truth[:, 2]))
                rows[label]["final_m"].append(float(np.hypot(*(poses[-1, :2] - truth[-1, :2]))))
                rows[label]["heading_rms_deg"].append(float(np.sqrt(np.mean(heading**2))))
                rows[label]["flagged"].append(int(flagged))
        sets[name] = {"seeds": seeds, "fingerprint": fingerprint(name), **rows}
    return {"frames": FUSION_FRAMES, "code_version": code_version(), "sets": sets}


def load(path=RESULTS) -> dict:
    """The stored results; ``ValueError`` when a set's sample has changed since they were made."""
    results = json.loads(Path(path).read_text())
    stale = [n for n, r in results["sets"].items() if r["fingerprint"] != fingerprint(n)]
    if stale:
        raise ValueError(
            f"stored results of {', '.join(stale)} were made from other sample definitions; "
            "run python -m vo_lib.stereo_vo.paper_sets again"
        )
    return results


def main(argv=None) -> int:
    names = (sys.argv[1:] if argv is None else list(argv)) or list(SETS)
    studies = {"contradictions": contradiction_study, "fusion": fusion_study}
    study = names[0] if len(names) == 1 and names[0] in studies else None
    unknown = [n for n in names if n not in SETS]
    if unknown and not study:
        print(
            f"error: unknown set {unknown[0]!r}; the sets are {', '.join(SETS)} "
            "(or 'contradictions' or 'fusion' alone)",
            file=sys.stderr,
        )
        return 2
    empty = {"key_every": KEY_EVERY, "seed": SEED, "sets": {}}
    stored = json.loads(RESULTS.read_text()) if RESULTS.exists() else empty
    stored.update({study: studies[study]()} if study else {})
    for name in [] if study else names:  # the sets, printed as each is done
        stored["sets"][name] = run_set(name)
        print(f"{name}: {stored['sets'][name]}", flush=True)
    text = json.dumps(stored, indent=1) + "\n"
    print(f"written {write_atomic(RESULTS, text)}")  # an interrupted write keeps the old file
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
