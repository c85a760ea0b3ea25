"""``python -m vo_lib run``, ``convert`` and ``generate``: the pipeline as a command, and the
sequences it reads written (a recording rectified, a sample rendered).

The pipeline, the data folder and Matplotlib are imported where they are used, so that a run says
what it is about to do within a second or two.
"""

from __future__ import annotations

import contextlib
import csv
import hashlib
import os
import sys
import threading
import warnings
from collections import Counter
from dataclasses import asdict, fields
from pathlib import Path

import numpy as np

from vo_lib.arguments import UsageError
from vo_lib.evaluation import path_length, rotation_angle, rpe
from vo_lib.formats.poses import write_kitti_poses, write_tum
from vo_lib.geometry import as_homogeneous, camera_poses_from_planar, planar_from_camera_poses, rigid_inverse
from vo_lib.outputs import OutputError, OutputFolder, check_target, file_sha256, notice, read_marker, reading
from vo_lib.sim.samples import SAMPLES, generate, get_sample, is_sample
from vo_lib.stereo_vo.run_report import (
    error_report,
    errors_3d,
    odometry_name,
    position_only_errors,
    print_error_table,
    print_timing_table,
    tracked_offsets,
    tracked_truth,
    truth_and_odometry,
)

DEFAULT_SEQUENCE = "indoor_linear"


def input_path(name_or_path: str, frames: int | None) -> tuple[Path, int | None]:
    """The folder a run reads and the frame count to ask for (all of a sample shorter than ``--frames``)."""
    from vo_lib.data import sample_path

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
    if not Path(name_or_path).is_dir():  # said before --out is looked at
        raise UsageError(f"--sequence {name_or_path}: a file, not a sequence folder")
    return Path(name_or_path), frames


def _recording(path: Path) -> Path:
    """An ASL recording, given as ``mav0`` or the folder holding it; any other folder as it is."""
    return path.parent if path.name == "mav0" else path


def default_name(name_or_path: str, frames: int | None = None) -> str:
    """The NAME of a run's default ``runs/NAME``: the sample's, or the sequence folder's, with ``_Nf``
    for the first ``frames`` N (a short run does not replace the whole one's output)."""
    path = Path(name_or_path) if is_sample(name_or_path) else Path(name_or_path).resolve()
    return _recording(path).name + (f"_{frames}f" if frames else "")


#: A step that takes longer than this (seconds) says what it is doing.
SLOW_S = 2.0
#: Seconds to render and write one frame pair of a crawler sample (2 cores, quiet to a load of 9).
RENDER_S_PER_FRAME = (0.015, 0.1)


def announce_run(name: str, source: Path, frames: int | None, out_dir: Path) -> None:
    """The first line of a run, on stdout: what it reads, what comes first, where it writes."""
    from vo_lib.data import is_rendered

    if not is_sample(name):
        print(f"run: {source} -> {out_dir}/", flush=True)
        return
    n = frames or get_sample(name).frames
    if is_rendered(name, source):
        print(f"run: sample {name}, {n} frames (rendered in {source}) -> {out_dir}/", flush=True)
    else:
        fast, slow = (round(max(1.0, n * s)) for s in RENDER_S_PER_FRAME)
        how_long = f"{fast} to {slow} s" if slow > fast else f"{slow} s"
        print(
            f"run: sample {name}, {n} frames -> {out_dir}/. First use: its frames are rendered into "
            f"{source} first (about {how_long}; later runs reuse them)",
            flush=True,
        )


def _write_csv(path: Path, rows, cls) -> None:
    """One row per dataclass in ``rows`` under a header of ``cls``'s fields."""
    with path.open("w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=[f.name for f in fields(cls)])
        writer.writeheader()
        writer.writerows(map(asdict, rows))


def calibration_digest(sequence: Path, truth_file: Path) -> str | None:
    """sha256 of the numbers of an ASL recording's ``sensor.yaml`` files that move its truth into its
    rectified left camera (a comment changes none); None for another layout."""
    from vo_lib.formats.asl_calibration import read_camera_yaml, truth_extrinsic
    from vo_lib.formats.euroc import mav0_of

    mav0 = mav0_of(sequence)
    if mav0 is None:
        return None
    digest = hashlib.sha256()
    for camera in (read_camera_yaml(mav0 / side / "sensor.yaml") for side in ("cam0", "cam1")):
        digest.update(np.concatenate([camera.T_BS.ravel(), camera.K.ravel(), camera.distortion]).tobytes())
        digest.update(np.asarray(camera.resolution, float).tobytes())
    has_extrinsic = (truth_file.parent / "sensor.yaml").is_file()  # else the body's: no notice here
    digest.update(truth_extrinsic(truth_file).tobytes() if has_extrinsic else b"-")
    return digest.hexdigest()


def _truth_record(seq) -> dict | None:
    """The truth file of a run's errors and the sha256 of it and of its calibration, for ``evaluate``."""
    truth_file = seq.truth_file or (seq.path / "poses.txt" if seq.poses is not None else None)
    if truth_file is None or not Path(truth_file).is_file():  # none, or a folder of packets (raw KITTI)
        return None
    return {
        "path": os.path.abspath(truth_file),  # where the run read it: links not followed
        "sha256": file_sha256(truth_file),
        "calibration": calibration_digest(seq.path, Path(truth_file)),
    }


def _draw(path: Path, seq, name: str, n: int, planar, poses, truth, odo, vehicle) -> None:
    """The run's figure: its path (``planar`` poses, or the camera ``poses`` in the truth's plan)
    beside the truth, or beside position-only truth moved onto it."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from vo_lib.stereo_vo.vehicle import VehicleKind
    from vo_lib.viz.run_figure import plot_run

    mount = vehicle.mount
    # a name holding bytes that are not UTF-8 (read as surrogates) is drawn with U+FFFD in their place
    title = f"{os.fsencode(Path(name).name).decode('utf-8', 'replace')}: {n} frames"
    drone = vehicle.kind is VehicleKind.DRONE and truth is not None  # no ground plane: 3-D errors
    cameras = (poses, seq.poses[:n]) if drone else None
    offsets = tracked_offsets(seq, poses, n) if truth is None else None  # a prism's positions
    plan = planar_from_camera_poses(poses, mount) if drone or offsets is not None else planar
    tracked = None  # where position-only truth puts the body: the estimate moved by the truth's offset
    if offsets is not None:
        tracked = plan[offsets[0], :2] + (offsets[1] @ mount[:3, :3].T)[:, :2]
    fig = plt.figure(figsize=(11, 5), constrained_layout=True)
    with warnings.catch_warnings():  # a letter the font lacks (a name in Chinese) is drawn as a box
        warnings.filterwarnings("ignore", "Glyph .* missing from font", UserWarning)
        plot_run(fig, seq.times[:n], plan, truth, odo, title, odometry_name(vehicle), cameras, tracked)
        fig.savefig(path, dpi=110)
    plt.close(fig)


def run_command(
    sequence: str | None,
    out: str | None,
    frames: int | None,
    no_odometry: bool,
    seed: int = 0,
    force: bool = False,
    motion: str = "auto",
    no_truth: bool = False,
) -> dict:
    """Run the pipeline and write its outputs; returns the error report (empty without truth).
    ``motion``: the model (``auto``: planar for the crawler, 6-DoF for a car)."""
    from vo_lib.data import is_rendered, kept_data_folder, load_sequence

    name = sequence or DEFAULT_SEQUENCE
    source, load_frames = input_path(name, frames)
    out_dir = Path(out) if out else Path("runs") / default_name(name, frames)
    # a default runs/NAME holding the run of another sequence of that name (KITTI's 00 to 21): --force
    marker = {} if out or force else read_marker(out_dir) or {}
    earlier = marker.get("sequence") if marker.get("written_by") == "vo_lib run" else None
    if isinstance(earlier, str) and _recording(Path(earlier)) != _recording(source.resolve()):
        raise OutputError(
            f"{out_dir}: holds the run of {earlier}, another sequence of this name; give --out, "
            "or add --force to replace it"
        )
    keep = kept_data_folder()  # the samples' folder, not runs': nothing inside it
    with (
        OutputFolder(
            out_dir, "vo_lib run", force=force, inputs=[source], keep=keep, keep_inside=True, option="--out"
        ) as output,
        contextlib.ExitStack() as locks,
    ):
        announce_run(name, source, frames, out_dir)  # once --out is known to be writable
        progress = True if sys.stderr.isatty() else "lines"
        if not is_sample(name) or is_rendered(name, source):  # a sample rendered now: once it is
            locks.enter_context(reading(source))  # no command replaces the sequence while it is read
        seq = load_sequence(
            name, frames=load_frames, odometry=not no_odometry, progress=progress, truth=not no_truth
        )
        locks.enter_context(reading(seq.path))
        report = _run_into(output, seq, name, frames, no_odometry, seed, motion)
    print(f"\nwrote {out_dir}/: poses.txt trajectory.tum timings.csv diagnostics.csv trajectory.png")
    return report


#: Notices: a path this many times the truth's or this fraction of it (a baseline: more than drift),
#: a hundredfold (a truth in millimetres), no path judged under ``MIN_PATH_M`` metres.
PATH_RATIO, UNIT_RATIO, MIN_PATH_M = 1.5, 100.0, 0.1
#: ... this share of the frames flagged (the rendered samples flag a fifth at most).
FLAGGED_SHARE = 0.25
#: ... rotations from frame to frame that differ from the truth's by this share of its own turns (RMS,
#: and by ``TURNS_DIFFER_DEG``): runs differ by 2-13 %, quaternions written w first by 160 %.
TURNS_DIFFER, TURNS_DIFFER_DEG = 0.5, 0.2
ORDERS = "(TUM: qx qy qz qw; EuRoC CSV: qw qx qy qz)"  # of the quaternions in a trajectory's rows


def _say_if_suspect(seq, n: int, diagnostics, poses, motion: str = "auto") -> None:
    """A notice where a run looks like that of a calibration not of these images, or of a motion
    model not of this body: ``FLAGGED_SHARE`` of the frames flagged, turns or a path unlike the truth's."""
    from vo_lib.stereo_vo.pipeline import Reason

    reasons = Counter(d.reason for d in diagnostics if d.fallback)
    why = ", ".join(f"{count} {reason}" for reason, count in reasons.most_common())
    # a frame without a reference follows frames without features
    featureless = reasons[Reason.FEW_FEATURES] + reasons[Reason.NO_REFERENCE]
    if featureless >= FLAGGED_SHARE * (n - 1):  # the motion of these frames is only the prediction's
        others = f" ({reasons.total()} flagged in all: {why})" if reasons.total() > featureless else ""
        notice(
            f"{seq.path}: {featureless} of {n - 1} frames had too few stereo features to be matched"
            f"{others}; is each camera's calibration that of these images? (rows the rectification "
            "does not line up give no stereo matches)"
        )
    elif reasons.total() >= FLAGGED_SHARE * (n - 1):
        model = "" if motion == "auto" else f" is --motion {motion} the model of this body's motion, and"
        notice(
            f"{seq.path}: {reasons.total()} of {n - 1} frames were flagged, their vision not used "
            f"({why});{model} is each camera's calibration, distortion included, that of these images?"
        )
    else:
        _say_if_turns_differ(seq, n, poses)
        _say_if_path_differs(seq, n, poses)


def _say_if_path_differs(seq, n: int, poses) -> None:
    """A notice where the estimate's path is the truth's (poses, or a tracker's positions) times
    ``PATH_RATIO`` or more, or a hundredth of it; not on a path under ``MIN_PATH_M``."""
    tracked = None if seq.poses is not None else tracked_truth(seq, n)
    truth = seq.poses[:n, :3, 3] if seq.poses is not None else None if tracked is None else tracked[2]
    if truth is None:
        return
    truth_m, est_m = path_length(truth), path_length(poses[:n, :3, 3])
    if truth_m < MIN_PATH_M or est_m == 0 or max(truth_m, est_m) < PATH_RATIO * min(truth_m, est_m):
        return
    baseline = "is the stereo baseline that of the rig? (cam1's T_BS in its sensor.yaml, or P1 in calib.txt)"
    unit = f"is the ground truth in millimetres? ({seq.truth_file or 'it'} is read as metres)"
    ask = unit if truth_m >= UNIT_RATIO * est_m else baseline
    notice(f"{seq.path}: the estimate's path is {est_m:.4g} m long and the truth's {truth_m:.4g} m; {ask}")


def turns_differ(truth, poses) -> tuple[float, float] | None:
    """``(differ, turns)``, degrees (RMS): how far the estimate's rotations from pose to pose are from
    the truth's, and how far the truth turns, where the first is ``TURNS_DIFFER`` of it or more; else None."""
    truth = as_homogeneous(truth)
    turned = np.degrees(rotation_angle(np.swapaxes(truth[:-1, :3, :3], 1, 2) @ truth[1:, :3, :3]))
    differ, turns = rpe(truth, poses, rotation=True)[0].rmse, float(np.sqrt(np.mean(turned**2)))
    return (differ, turns) if differ >= max(TURNS_DIFFER * turns, TURNS_DIFFER_DEG) else None


def _say_if_turns_differ(seq, n: int, poses) -> None:
    """A notice where the estimate's turns have little in common with the truth's (:func:`turns_differ`)."""
    if seq.poses is None or not (found := turns_differ(seq.poses[:n], poses)):
        return
    truth = seq.truth_file or seq.path / "poses.txt"
    quaternions = truth.is_file() and seq.rectify is not None  # an ASL recording's: not KITTI's, nor OXTS
    order = f", its quaternions in the order of its format {ORDERS}" if quaternions else ""
    notice(
        f"{truth}: the estimate's rotations from frame to frame differ from the truth's by "
        f"{found[0]:.2g} deg (RMS), where the truth turns {found[1]:.2g} deg: is it the truth of "
        f"these images{order}, and is each camera's calibration that of these images (a rotation "
        "between the cameras that is not the rig's turns every estimate)?"
    )


def _say_if_odometry_unread(seq, motion: str, no_odometry: bool) -> None:
    """A notice where ``--motion hover`` leaves a sequence's odometry unread (a body without it)."""
    from vo_lib.stereo_vo.vehicle import vehicle_of

    if motion == "hover" and not no_odometry and vehicle_of(seq, motion="auto").odometry is not None:
        notice(f"{seq.path}: its odometry is not read: --motion hover models a body without odometry")


def _warm_up_saying_so(seq, **options) -> None:
    """The untimed :func:`~vo_lib.stereo_vo.pipeline.warm_up`; once it has taken ``SLOW_S``, a line
    says that the kernels are compiling, and another when they are done."""
    from vo_lib.stereo_vo.pipeline import WARM_UP_FRAMES, warm_up

    compiling = (
        f"compiling the Numba kernels on the first {WARM_UP_FRAMES} frames (once per environment and "
        "motion model: they are cached; up to a minute on 2 cores) ..."
    )
    said = []
    slow = threading.Timer(SLOW_S, lambda: said.append(print(compiling, flush=True)))
    slow.start()
    try:
        seconds = warm_up(seq, **options)
    finally:
        slow.cancel()
        slow.join()
    if said or seconds >= SLOW_S:
        print(f"compiled in {seconds:.0f} s, before the timed run (not in timings.csv)", flush=True)


#: Why ``--motion auto`` chose its model, by what carries the camera.
_AUTO_BECAUSE = {
    "crawler": "the crawler of a rendered sample",
    "car": "a folder in the KITTI layout is a car's unless its manifest.json names a body"
    " (--motion hover: a drone or a hand-held rig)",
    "drone": "a recording's own calibration: a drone or a hand-held rig",
}


def _run_into(
    output: OutputFolder, seq, name: str, frames, no_odometry: bool, seed: int, motion: str
) -> dict:
    """The pipeline on ``seq`` with its outputs written into ``output`` (committed at the end)."""
    from vo_lib.stereo_vo.pipeline import FrameDiagnostics, FrameTimings, run_sequence
    from vo_lib.stereo_vo.vehicle import VehicleKind, vehicle_of

    tmp = output.path
    if frames is not None and frames > len(seq) and not is_sample(name):  # samples: said above
        notice(f"--frames {frames}: {seq.path} has {len(seq)} frames; running all {len(seq)}")
    n = len(seq) if frames is None else min(frames, len(seq))
    if n < 2:
        raise UsageError(f"{seq.path}: has {n} frame; a run needs at least 2 frames")
    vehicle = vehicle_of(seq, use_odometry=not no_odometry, motion=motion)
    mount = vehicle.mount
    why = f"--motion {motion}" if motion != "auto" else _AUTO_BECAUSE[str(vehicle.kind)]
    print(f"motion model: {vehicle.motion if motion == 'auto' else motion} ({why})", flush=True)
    _say_if_odometry_unread(seq, motion, no_odometry)
    options = {"use_odometry": not no_odometry, "seed": seed, "motion": motion, "vehicle": vehicle}
    _warm_up_saying_so(seq, **options)
    print(f"visual odometry on {n} frames ...", flush=True)
    result = run_sequence(seq, frames=n, progress=sys.stderr.isatty(), **options)
    poses = result.camera_poses
    poses = camera_poses_from_planar(result.poses, mount) if poses is None else poses
    _say_if_suspect(seq, n, result.diagnostics, poses, motion)
    write_kitti_poses(tmp / "poses.txt", poses)
    origin = float(seq.manifest.get("time_origin_s", 0.0)) if isinstance(seq.manifest, dict) else 0.0
    write_tum(tmp / "trajectory.tum", seq.times[:n] + origin, poses)  # on the recording's clock
    _write_csv(tmp / "timings.csv", result.timings, FrameTimings)
    _write_csv(tmp / "diagnostics.csv", result.diagnostics, FrameDiagnostics)
    truth, odo = truth_and_odometry(seq, vehicle, n)
    if truth is not None and n < 3:  # as evaluate: errors of two poses mean nothing
        notice(f"{seq.path}: no errors for {n} frames; an evaluation needs at least 3 (--frames 3 or more)")
        truth = None
    _draw(tmp / "trajectory.png", seq, name, n, result.poses, poses, truth, odo, vehicle)
    decoding = [seq.decoding_ms[k] for k in range(1, n) if k in seq.decoding_ms]
    print_timing_table(result, seq.camera, n, decoding)
    report = position_only_errors(seq, poses, n) if truth is None else {}
    if truth is None:  # the error table, which counts them, is not printed
        print(f"\nframes flagged (VO not used): {len(result.flagged)} of {n}")
    else:
        report = error_report(result, truth, odo)
        report["errors_3d"] = errors_3d(seq.poses[:n], {"vo": poses, "odometry": odo}, mount)
        print_error_table(  # a drone has no ground plane: its planar figures mean nothing
            report,
            len(result.flagged),
            report["errors_3d"],
            odometry_name(vehicle),
            seq.truth_file or (None if is_sample(name) else seq.path / "poses.txt"),  # a KITTI layout's
            planar=vehicle.kind is not VehicleKind.DRONE,
            fused=vehicle.odometry is not None,
        )
    fused = vehicle.odometry is not None
    output.commit(
        sequence=str(seq.path.resolve()), frames=n, seed=seed, odometry=fused, truth=_truth_record(seq)
    )
    return report


def convert_command(sequence: str, to: str, out: str, force: bool = False, no_truth: bool = False) -> None:
    """Write a rectified copy of a sequence in the KITTI layout, with the source's manifest and its
    odometry files (:data:`~vo_lib.formats.sequence_writer.CARRIED`)."""
    from vo_lib.data import kept_data_folder, load_sequence
    from vo_lib.formats.sequence_writer import SequenceWriter
    from vo_lib.stereo_vo.vehicle import vehicle_of

    with contextlib.ExitStack() as locks:  # no command replaces the sequence while it is read
        locks.enter_context(reading(sequence))
        # read before --out is touched: a bad input changes nothing
        seq = load_sequence(Path(sequence), odometry=True, progress=False, truth=not no_truth)
        vehicle_of(seq)  # its mount and odometry as run reads them: no copy that run would refuse
        locks.enter_context(reading(seq.path))
        manifest = {k: v for k, v in seq.manifest.items() if k != "layout"}
        with SequenceWriter(
            out,
            seq.camera,
            force=force,
            option="--out",
            written_by="vo_lib convert",
            inputs=[seq.path],
            keep=kept_data_folder(),
            keep_inside=True,
        ) as writer:
            for left, right in seq:
                writer.add(left, right)
            writer.carry(seq.path, seq.oxts, seq.raw_calib)  # a raw KITTI drive's packets and calibration
            body = manifest.get("T_body_camera")  # an ASL rig's; KITTI's Tr is the body's into the camera
            from_body = None if body is None else rigid_inverse(body)
            path = writer.close(seq.times, seq.poses, manifest=manifest or None, camera_from_body=from_body)
    truth = "ground truth in poses.txt" if seq.poses is not None else "no ground truth"
    truth = "position-only ground truth in manifest.json" if "positions" in manifest else truth
    print(f"wrote {path}: {len(seq)} rectified pairs in the KITTI layout, {truth}")


def generate_command(name: str, out: str | None, frames: int | None, resolution, force: bool = False) -> None:
    """Render sample ``name`` into ``out`` (default: its folder in the data folder) in the KITTI layout."""
    from vo_lib.data import kept_data_folder, sample_path

    most = get_sample(name).frames
    if frames is not None and frames > most:
        raise UsageError(f"--frames {frames}: {name} has {most} frames; expected 2 to {most}")
    target = out or sample_path(name, frames, resolution)
    check_target(target, written_by="vo_lib generate", force=force, option="--out", keep=kept_data_folder())
    if out and not force and (Path(target) / "image_0").is_dir():  # ours, but a sequence
        raise OutputError(
            f"--out {out}: holds a sequence generated earlier, which something may still read; "
            "add --force to generate it again"
        )
    try:
        path = generate(name, target, frames, resolution, progress=sys.stderr.isatty(), force=force)
    except OutputError as exc:  # named by the folder; the user gave it as --out
        text = str(exc)
        raise OutputError(f"--out {text}" if out and not text.startswith("--out ") else text) from None
    print(f"wrote {path}")
