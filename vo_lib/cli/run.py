"""``python -m vo_lib run`` and ``python -m vo_lib evaluate``: the pipeline as a command.

``run`` writes, into ``--out`` (default ``runs/NAME``): ``poses.txt`` (KITTI), ``trajectory.tum``
(TUM, readable by evo), ``timings.csv``, ``diagnostics.csv``, ``trajectory.png`` and the marker
``.vo_lib_output.json`` (how the run was made), and prints a timing table like the paper's Table 1
and, where the sequence has ground truth, the errors.

Outputs follow :mod:`vo_lib.outputs`: ``--out`` must be new, empty or an earlier output
of this program (``--force`` replaces any other folder, but never the input sequence, a folder
above or inside it, the current or the home folder); every file goes to a temporary folder first,
renamed into place at the end, so a failed or interrupted run leaves nothing half-written and the
previous output untouched. An image that cannot be decoded mid-sequence stops the run the same
way: one line naming the file and frame, nothing written. Bad arguments and bad input print one
line and exit with status 2.
"""

from __future__ import annotations

import csv
import sys
from dataclasses import asdict, fields
from pathlib import Path

import numpy as np

from vo_lib.evaluation import (
    ate_planar,
    final_error,
    is_spot_turn,
    kitti_segment_errors,
    rpe,
    turned_degrees,
)
from vo_lib.formats.poses import read_trajectory, write_kitti_poses, write_tum
from vo_lib.geometry import camera_poses_from_planar, planar_from_camera_poses, wrap_angle
from vo_lib.outputs import OutputFolder, notice, reading
from vo_lib.sim.samples import SAMPLES
from vo_lib.stereo_vo.pipeline import (
    WARM_UP_FRAMES,
    FrameDiagnostics,
    FrameTimings,
    PipelineResult,
    run_sequence,
    warm_up,
)
from vo_lib.stereo_vo.vehicle import vehicle_of

DEFAULT_SEQUENCE = "indoor_linear"
#: Seed 000, Table 1, 640x480 row: stereo processing, parameter estimation, Kalman filtering (ms).
PAPER_TABLE1_640 = (48.969, 0.874, 0.161)


class UsageError(Exception):
    """A bad argument: reported in one line, exit status 2."""


def input_path(name_or_path: str, frames: int | None) -> tuple[Path, int | None]:
    """The folder a run reads (a sample's cache folder, or the given folder) and the frame count
    to ask for (``--frames`` beyond a sample's length asks for the whole sample, with a notice)."""
    from vo_lib.data import sample_path
    from vo_lib.sim.samples import get_sample

    if is_sample(name_or_path):
        full = get_sample(name_or_path).frames
        if frames is not None and frames > full:
            notice(f"--frames {frames}: sample {name_or_path} has {full} frames; running all {full}")
            frames = None
        return sample_path(name_or_path, frames), frames
    if not Path(name_or_path).exists():
        raise UsageError(
            f"--sequence {name_or_path!r}: neither a sample name ({', '.join(SAMPLES)}) "
            "nor an existing folder"
        )
    return Path(name_or_path), frames


def is_sample(name_or_path: str) -> bool:
    return name_or_path in SAMPLES and not Path(name_or_path).exists()


def resolve_sequence(name_or_path: str, frames: int | None, odometry: bool = True, checked: bool = False):
    """A loaded sequence for a sample name (generated on first use) or a KITTI-layout folder.

    ``checked``: ``frames`` already went through :func:`input_path`.
    """
    from vo_lib.data import load_sequence

    if not checked:
        _, frames = input_path(name_or_path, frames)
    return load_sequence(
        name_or_path,
        frames=frames if is_sample(name_or_path) else None,
        odometry=odometry,
        progress=sys.stderr.isatty(),
    )


def _write_csv(path: Path, rows, cls) -> None:
    names = [f.name for f in fields(cls)]
    with path.open("w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=names)
        writer.writeheader()
        for row in rows:
            writer.writerow(asdict(row))


def _plot(path: Path, times, estimate, truth, odometry, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from vo_lib.viz.run_figure import plot_run

    fig = plt.figure(figsize=(11, 5), constrained_layout=True)
    plot_run(fig, times, estimate, truth, odometry, title)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def print_timing_table(result: PipelineResult, camera, frames: int) -> None:
    t = result.timing_table()
    fps = 1000.0 / t["total"] if t["total"] > 0 else float("inf")
    print(f"\nAverage time per frame (median, ms) at {camera.width}x{camera.height}, {frames} frames")
    print(f"  {'stage':<44s}{'this run':>10s}  {'paper, 640x480':<s}")
    rows = [
        ("binocular stereo vision processing", t["stereo"], f"{PAPER_TABLE1_640[0]:.3f}"),
        ("prediction and guided temporal matching", t["prediction"] + t["matching"], "-"),
        ("parameter estimation (1-point RANSAC)", t["estimation"], f"{PAPER_TABLE1_640[1]:.3f}"),
        *([("6-DoF refinement", t["refinement"], "-")] if t["refinement"] > 0 else []),
        ("Kalman filtering", t["kalman"], f"{PAPER_TABLE1_640[2]:.3f}"),
        ("whole frame", t["total"], "26.551 (mean of 10,000)"),
    ]
    for name, value, paper in rows:
        print(f"  {name:<44s}{value:10.3f}  {paper}")
    print(f"  frames per second: {fps:.0f}")


def truth_and_odometry(seq, vehicle, frames: int):
    """Planar vehicle poses of the ground truth and of odometry alone over the first ``frames``
    frames (each None where the sequence has none): what :func:`error_report` compares."""
    truth = None if seq.poses is None else planar_from_camera_poses(seq.poses[:frames], vehicle.mount)
    odometry = None
    if vehicle.odometry is not None:
        odometry = vehicle.odometry_model.integrate(vehicle.odometry[1:frames])
    return truth, odometry


def error_report(result: PipelineResult, truth_planar: np.ndarray, odometry_planar=None) -> dict:
    """Errors of the estimate (and of odometry alone) against the ground truth."""
    est = result.poses
    dist = final_error(truth_planar, est).distance_m
    report = {
        "distance_m": dist,
        "turned_deg": turned_degrees(truth_planar),
        "spot_turn": is_spot_turn(truth_planar),
    }
    for label, traj in (("vo", est), ("odometry", odometry_planar)):
        if traj is None:
            continue
        final = final_error(truth_planar, traj)
        heading = np.degrees(np.abs(wrap_angle(traj[:, 2] - truth_planar[:, 2])))
        report[label] = {
            "final_position_error_m": final.position_m,
            "final_position_error_pct": final.percent if not report["spot_turn"] and dist > 0 else None,
            "ate_rmse_m": ate_planar(truth_planar, traj)[0].rmse,
            "heading_error_mean_deg": float(heading.mean()),
            "heading_error_max_deg": float(heading.max()),
            "final_heading_error_deg": final.heading_deg,
        }
    return report


def print_error_table(report: dict, flagged: int, rpe_m: float) -> None:
    if report["spot_turn"]:
        print(f"\nErrors against ground truth ({report['turned_deg']:.0f}° turned on the spot)")
    else:
        print(f"\nErrors against ground truth ({report['distance_m']:.2f} m travelled)")
    cols = [k for k in ("vo", "odometry") if k in report]
    names = {"vo": "visual odometry", "odometry": "track odometry"}
    print(f"  {'':<34s}" + "".join(f"{names[c]:>18s}" for c in cols))
    for key, label, fmt in (
        ("final_position_error_m", "final position error [m]", "{:.4f}"),
        ("final_position_error_pct", "  of distance travelled [%]", "{:.2f}"),
        ("ate_rmse_m", "ATE RMSE, planar alignment [m]", "{:.4f}"),
        ("heading_error_mean_deg", "mean heading error [deg]", "{:.3f}"),
        ("heading_error_max_deg", "max heading error [deg]", "{:.3f}"),
        ("final_heading_error_deg", "final heading error [deg]", "{:.3f}"),
    ):
        if report[cols[0]][key] is None:  # no distance to relate a position error to
            continue
        print(f"  {label:<34s}" + "".join(f"{fmt.format(report[c][key]):>18s}" for c in cols))
    print(f"  relative pose error, 1 frame [m]  {rpe_m:>16.5f}")
    print(f"  frames flagged (VO not used)      {flagged:>16d}")


def run_command(
    sequence: str | None,
    out: str | None,
    frames: int | None,
    no_odometry: bool,
    seed: int = 0,
    force: bool = False,
    motion: str = "auto",
) -> dict:
    """Run the pipeline and write its outputs; returns the error report (empty without truth).

    ``motion`` picks the model (``auto``: planar for the crawler samples, 6-DoF for a car); the
    written poses are the 6-DoF camera poses where the model has them, else the planar poses
    carried to the camera through its mount.
    """
    name = sequence or DEFAULT_SEQUENCE
    if frames is not None and frames < 2:
        raise UsageError(f"--frames {frames}: need at least 2 frames")
    if seed < 0:
        raise UsageError(f"--seed {seed}: expected a whole number >= 0")
    source, load_frames = input_path(name, frames)
    out_dir = Path(out) if out else Path("runs") / Path(name).name
    from vo_lib.data import data_dir

    keep = {data_dir(): "the sample data folder"}
    with OutputFolder(
        out_dir, "vo_lib run", force=force, inputs=[source], keep=keep, option="--out"
    ) as output:
        seq = resolve_sequence(name, load_frames, odometry=not no_odometry, checked=True)
        with reading(seq.path):  # no command replaces the sequence while it is read
            report = _run_into(output, seq, name, frames, no_odometry, seed, motion)
    print(f"\nwrote {out_dir}/: poses.txt trajectory.tum timings.csv diagnostics.csv trajectory.png")
    return report


def _run_into(
    output: OutputFolder, seq, name: str, frames, no_odometry: bool, seed: int, motion: str
) -> dict:
    """The pipeline on ``seq`` with its outputs written into ``output`` (committed at the end)."""
    tmp = output.path
    if frames is not None and frames > len(seq) and not is_sample(name):  # samples: said above
        notice(f"--frames {frames}: {seq.path} has {len(seq)} frames; running all {len(seq)}")
    n = len(seq) if frames is None else min(frames, len(seq))
    if n < 2:
        raise UsageError(f"{seq.path}: has {n} frame; a run needs at least 2 frames")
    vehicle = vehicle_of(seq, use_odometry=not no_odometry)
    mount = vehicle.mount
    seconds = warm_up(seq, use_odometry=not no_odometry, seed=seed, motion=motion)
    print(
        f"warm-up: {WARM_UP_FRAMES} frames run untimed first, {seconds:.1f} s (compiling the Numba "
        "kernels in a fresh environment, loading them from the cache after); not in timings.csv"
    )
    result = run_sequence(
        seq,
        frames=n,
        use_odometry=not no_odometry,
        seed=seed,
        progress=sys.stderr.isatty(),
        motion=motion,
    )
    if result.camera_poses is not None:
        poses = result.camera_poses
    else:
        poses = camera_poses_from_planar(result.poses, mount)
    write_kitti_poses(tmp / "poses.txt", poses)
    write_tum(tmp / "trajectory.tum", seq.times[:n], poses)
    _write_csv(tmp / "timings.csv", result.timings, FrameTimings)
    _write_csv(tmp / "diagnostics.csv", result.diagnostics, FrameDiagnostics)
    truth, odo = truth_and_odometry(seq, vehicle, n)
    title = f"{Path(name).name}: {n} frames"
    _plot(tmp / "trajectory.png", seq.times[:n], result.poses, truth, odo, title)
    print_timing_table(result, seq.camera, n)
    report = {}
    if truth is not None:
        report = error_report(result, truth, odo)
        rpe_m = rpe(seq.poses[:n], poses)[0].rmse
        print_error_table(report, len(result.flagged), rpe_m)
    output.commit(sequence=str(seq.path.resolve()), frames=n, seed=seed, odometry=not no_odometry)
    return report


def evaluate_command(gt: str, est: str, segments=None) -> None:
    """Print ATE, RPE and segment errors of two trajectory files (KITTI or TUM).

    ``segments`` are lengths in metres (a comma-separated string or numbers), each positive.
    """
    from vo_lib.evaluation import ate

    _, G = read_trajectory(gt, min_poses=2)
    _, E = read_trajectory(est, min_poses=2)
    if len(G) != len(E):
        raise UsageError(f"--gt {gt} has {len(G)} poses but --est {est} has {len(E)}; expected equal counts")
    if segments is None:
        lengths = (100, 200, 300, 400, 500, 600, 700, 800)
    else:
        try:
            lengths = tuple(
                float(x) for x in (segments.split(",") if isinstance(segments, str) else segments)
            )
        except ValueError:
            lengths = ()
        if not lengths or not all(np.isfinite(x) and x > 0 for x in lengths):
            raise UsageError(f"--segments {segments}: expected comma-separated positive lengths in metres")
    a, _ = ate(G, E)
    r, _ = rpe(G, E)
    ra, _ = rpe(G, E, rotation=True)
    print(
        f"ATE (SE(3) alignment): rmse {a.rmse:.4f} m, mean {a.mean:.4f}, "
        f"median {a.median:.4f}, max {a.max:.4f}"
    )
    print(f"RPE (1 frame): translation rmse {r.rmse:.5f} m, rotation rmse {ra.rmse:.4f} deg")
    seg = kitti_segment_errors(G, E, lengths)
    if not seg:
        print("no KITTI segments of the requested lengths fit this trajectory (try --segments 1,2,5)")
    for length, (t_pct, r_deg, count) in seg.items():
        print(
            f"segment {length:g} m: translation {t_pct:.2f} %, rotation {r_deg:.4f} deg/m ({count} segments)"
        )
