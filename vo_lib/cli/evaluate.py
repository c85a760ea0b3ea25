"""``python -m vo_lib evaluate``: an estimated trajectory against ground truth in any common format."""

from __future__ import annotations

import contextlib
import io
import os
from functools import partial
from pathlib import Path

import numpy as np

from vo_lib.arguments import UsageError
from vo_lib.cli.run import ORDERS, calibration_digest, turns_differ
from vo_lib.evaluation import MAX_TIME_DIFF_S, associate, path_length
from vo_lib.formats.groundtruth import paired_apart, read_groundtruth, read_trajectory
from vo_lib.formats.poses import MAX_FILE_BYTES, TrajectoryError
from vo_lib.outputs import MARKER, file_sha256, read_marker


def read_whole(option: str, path: str, read):
    """``read(path)`` and the sha256 of the file it read, refused if it changed meanwhile."""

    def sha256() -> str | None:  # of a regular file that read() would read; else None (it says why)
        with contextlib.suppress(OSError):
            if Path(path).is_file() and 0 < Path(path).stat().st_size <= MAX_FILE_BYTES:
                return file_sha256(path)
        return None

    before = sha256()
    try:
        value = read(path)
    except TrajectoryError as exc:
        raise UsageError(f"{option} {exc}") from None
    if sha256() != before:
        raise UsageError(
            f"{option} {path}: changed while it was read; evaluate it again when nothing writes it"
        )
    return value, before


def run_marker(est: str, est_sha256: str) -> dict:
    """The marker of the ``run`` output holding ``est`` if ``est`` is as that run wrote it; else {}."""
    marker = read_marker(Path(est).parent) or {}
    files = marker.get("files") if marker.get("written_by") == "vo_lib run" else None
    return marker if isinstance(files, dict) and files.get(Path(est).name) == est_sha256 else {}


def check_against_its_run(gt: str, gt_sha256: str, est: str, marker: dict) -> None:
    """Refuse a ``--gt`` or a calibration changed since the run of ``marker`` used them; say when
    ``--gt`` is another file than that run's truth."""
    truth = marker.get("truth")
    if not isinstance(truth, dict):
        return
    now = calibration_digest(Path(str(marker.get("sequence"))), Path(str(truth.get("path"))))
    if now and truth.get("calibration") and now != truth.get("calibration"):
        raise UsageError(
            f"--est {est}: the calibration of {marker.get('sequence')!r} (its sensor.yaml files) changed "
            "since that run; run it again"
        )
    if gt_sha256 == truth.get("sha256"):
        return
    if Path(gt).resolve() == Path(str(truth.get("path"))).resolve():
        raise UsageError(
            f"--gt {gt}: changed since --est {est} was run against it (the run's marker records "
            "another checksum: was the sequence written again?); expected the truth of that run, "
            "or run it again"
        )
    print(
        f"--est {est} is a run of {marker.get('sequence')!r}, whose truth is {truth.get('path')!r}; "
        f"--gt {gt} is another file: the errors below are against it"
    )


def _check_one_to_one(truth, gt: str, est: str, count: int, marker: dict) -> None:
    """Poses without timestamps: equal counts, or ``--est`` a run of the first frames of ``--gt``'s."""
    record = marker.get("truth") if isinstance(marker.get("truth"), dict) else {}
    its_truth = Path(str(record.get("path", Path(str(marker.get("sequence"))) / "poses.txt")))
    first = marker.get("frames") == count and Path(gt).resolve() == its_truth.resolve()  # its first frames?
    if len(truth.positions) > count and first:
        print(f"--est {est} is a run of the first {count} frames of --gt's sequence: compared with those")
    elif len(truth.positions) != count:
        stamped = Path(est).parent / "trajectory.tum"  # what a run writes beside its poses.txt
        hint = f": --est {stamped} has them" if truth.times is not None and stamped.is_file() else ""
        raise UsageError(
            f"--gt {gt} has {len(truth.positions)} {'poses' if truth.poses is not None else 'positions'} "
            f"but --est {est} has {count} poses; expected equal counts (or timestamps in both{hint})"
        )


def _associated(
    truth, gt: str, est: str, times, E: np.ndarray, marker: dict, max_diff: float
) -> tuple[np.ndarray, np.ndarray]:
    """Indices ``(i_est, i_gt)`` of the poses compared: by timestamp where both files carry them, at
    most ``max_diff`` seconds apart (as evo does), else one to one."""
    if truth.times is None or times is None:
        _check_one_to_one(truth, gt, est, len(E), marker)
        if truth.times is not None:  # a run's trajectory.tum beside it has the times
            print(f"--est {est} has no timestamps: its poses are paired with --gt's one to one, in order")
        return np.arange(len(E)), np.arange(len(E))
    i_est, i_gt = associate(times, truth.times, max_diff)
    if len(i_est) < 3:  # an alignment needs three points
        inside = int(np.sum((truth.times >= times[0]) & (truth.times <= times[-1])))
        cause = (
            f"--gt has {inside} row{'s' * (inside != 1)} within --est's span: too sparse, or off its clock"
            if inside
            else "both must use one clock"
        )
        raise UsageError(
            f"--gt {gt}: {len(i_est) or 'no'} timestamp{'s' * (len(i_est) != 1)} within {max_diff:g} s of "
            f"--est {est}'s, expected at least 3 (--gt spans {truth.times[0]:.3f} to "
            f"{truth.times[-1]:.3f} s, --est {times[0]:.3f} to {times[-1]:.3f} s; a CSV's times are read "
            f"as nanoseconds, a text file's as seconds); {cause}"
        )
    print(f"associated {len(i_est)} of {len(E)} poses by timestamp (within {max_diff:g} s)")
    if said := paired_apart(truth, times[i_est] - truth.times[i_gt]):
        print(f"note: {said}")
    return i_est, i_gt


def recording_of(
    gt: str, extrinsic_of: str | None, kitti: bool, into: str = "its rectified left camera"
) -> str | None:
    """The ASL recording whose calibration moves ``--gt`` ``into`` a frame of it (its rectified left
    camera, or its body): ``extrinsic_of``, else the ``mav0`` folder holding ``--gt`` among its
    sensors' (links not followed), else None. KITTI poses and files this package wrote are never moved."""
    from vo_lib.formats.euroc import mav0_of

    path = Path(os.path.abspath(gt))  # symbolic links not followed
    if extrinsic_of is not None and (kitti or (path.parent / MARKER).is_file()):
        held = (
            "holds KITTI poses, which are a camera's"
            if kitti
            else "was written by this package, as a camera's poses"
        )
        raise UsageError(
            f"--extrinsic-of {extrinsic_of}: --gt {gt} {held} already; expected a "
            "body-frame truth (TUM, EuRoC CSV or positions)"
        )
    if extrinsic_of is not None or kitti:
        return extrinsic_of
    holders = (m for m in map(mav0_of, path.parents[:3]) if m in path.parents)
    found = next((m for m in holders if (m / "cam0" / "sensor.yaml").is_file()), None)
    written = [f for f in path.parents[:3] if found in f.parents and (f / MARKER).is_file()]
    if found is None or written:
        return None
    print(f"--gt lies in the ASL recording {found}: moved into {into}")
    return str(found)


def _to_camera(truth, gt: str, extrinsic_of: str | None, est_frame: str = "camera") -> np.ndarray:
    """The frame ``--est`` tracks (``est_frame``: the rectified left camera, or the body) in the frame
    ``--gt`` tracks (:func:`recording_of`), or the identity."""
    from vo_lib.formats.euroc import body_to_rectified_camera, tracked_to_camera

    into = "its body frame (--est-frame body)" if est_frame == "body" else "its rectified left camera"
    recording = recording_of(gt, extrinsic_of, kitti=truth.times is None, into=into)
    if recording is not None:
        tracker = recording if truth.poses is None else None  # a prism's lever arm
        body_to_est = np.eye(4) if est_frame == "body" else body_to_rectified_camera(recording)
        return tracked_to_camera(gt, body_to_est, tracker)
    if truth.times is not None and read_marker(Path(gt).parent) is None:
        held = "poses are of the body" if truth.poses is not None else "positions are of a tracked point"
        what = f"an EuRoC CSV, whose {held}" if truth.csv else "not in a recording"
        print(
            f"--gt {gt} is {what}: compared as they are, as the camera's (a body's or a tracker's: "
            "--extrinsic-of RECORDING moves them into its rectified left camera)"
        )
    return np.eye(4)


def _print_pose_errors(G: np.ndarray, E: np.ndarray, lengths, timed: bool = False) -> None:
    """The standard errors of ``E`` against ``G`` and KITTI's of each segment length, after a note where
    their turns differ (quaternions of another order in one file?)."""
    from vo_lib.evaluation import kitti_segment_errors, standard_errors

    if found := turns_differ(G, E):
        print(
            f"note: the estimate's rotations from pose to pose differ from the ground truth's by "
            f"{found[0]:.2g} deg (RMS), where the truth turns {found[1]:.2g} deg: are they of one "
            "recording and of one frame (a body's truth is the camera's only through --extrinsic-of; an "
            "estimate of the body needs --est-frame body), "
            f"each file's quaternions in the order of its format {ORDERS}"
            + (", and paired at the right times (--time-offset: the lag of one clock)?" if timed else "?")
        )
    for label, value in standard_errors(G, E, lengths).rows():
        print(f"{label:<62s}{value:>16s}")
    segments = kitti_segment_errors(G, E, lengths) if lengths and len(lengths) > 1 else {}
    for length, (t_pct, r_deg, count) in segments.items():  # each length on its own, too
        print(
            f"segment {length:g} m: translation {t_pct:.2f} %, rotation {100 * r_deg:.3f} deg/100 m "
            f"({count} segment{'s' * (count != 1)})"
        )


def _say_if_units_differ(truth_xyz: np.ndarray, est_xyz: np.ndarray) -> None:
    """A note where the two paths' lengths differ a hundredfold or more (one in millimetres?)."""
    truth_m, est_m = path_length(truth_xyz), path_length(est_xyz)
    if min(truth_m, est_m) > 0 and max(truth_m, est_m) >= 100 * min(truth_m, est_m):
        print(
            f"note: the ground truth's path is {truth_m:.4g} m long and the estimate's {est_m:.4g} m: "
            "is one of them in millimetres? Both files are read as metres"
        )


def _print_position_errors(positions: np.ndarray, E: np.ndarray, lever: np.ndarray) -> None:
    """ATE of the point ``lever`` (in the camera) carried along ``E`` against ``positions``."""
    from vo_lib.evaluation import Alignment, ate_positions, carried_point, shown, umeyama

    tracked = carried_point(E, lever)
    for alignment in (Alignment.SE3, Alignment.SIM3):
        a, _ = ate_positions(positions, E, lever, alignment)
        rmse, worst = shown(a.rmse, ".4f"), shown(a.max, ".4f")  # undefined: a scale of nothing moving
        scale = umeyama(tracked, positions, with_scale=True)[2] if alignment is Alignment.SIM3 else None
        named = "" if scale is None else f", scale {shown(scale, '.4f')}"
        print(f"ATE ({alignment} alignment{named}, positions only): rmse {rmse} m, max {worst}")


def _say_if_steps_skip(i_est: np.ndarray) -> None:
    """A note when the RPE's "1 frame" steps join poses the truth left unpaired between them."""
    longer = int(np.count_nonzero(np.diff(i_est) > 1))
    if longer:
        print(
            f"(RPE's steps join consecutive paired poses: {longer} of {len(i_est) - 1} span more than one "
            "estimated pose, where the truth has no pose between them)"
        )


def evaluate_command(
    gt: str,
    est: str,
    segments=None,
    extrinsic_of: str | None = None,
    time_offset: float = 0.0,
    max_time_diff: float = MAX_TIME_DIFF_S,
    est_frame: str = "camera",
) -> None:
    """Print the 3-D errors of an estimate (KITTI, TUM or EuRoC CSV) against ground truth in any format of
    :mod:`vo_lib.formats.groundtruth`: final error, ATE (SE(3), Sim(3)), RPE and KITTI's errors.

    ``segments``: lengths in metres (default: those the sequence allows). A truth of an ASL recording's
    body (:func:`recording_of`) is moved into its rectified left camera; positions only, as a lever arm.
    ``time_offset``: seconds added to the estimate's timestamps before they are paired with the truth's,
    at most ``max_time_diff`` apart. ``est_frame``: ``"body"`` for an estimate of the recording's body
    (a visual-inertial system's IMU), into which its truth is moved instead.
    """
    limits = (("--time-offset", time_offset, -60.0), ("--max-time-diff", max_time_diff, 0.0))
    for option, seconds, low in limits:
        if not low <= seconds <= 60.0:  # NaN too
            raise UsageError(f"{option} {seconds:g}: expected seconds from {low:g} to 60")
    truth, gt_sha256 = read_whole("--gt", gt, read_groundtruth)
    (times, E), est_sha256 = read_whole("--est", est, partial(read_trajectory, min_poses=3))  # 3 to align
    if (time_offset or max_time_diff != MAX_TIME_DIFF_S) and (times is None or truth.times is None):
        option = f"--time-offset {time_offset:g}" if time_offset else f"--max-time-diff {max_time_diff:g}"
        raise UsageError(f"{option}: expected timestamps in both --gt and --est")
    times = None if times is None else times + time_offset
    notes = io.StringIO()  # what the checks say, printed once every check has passed
    with contextlib.redirect_stdout(notes):
        marker = run_marker(est, est_sha256)  # of the run that wrote --est, if one did
        check_against_its_run(gt, gt_sha256, est, marker)
        i_est, i_gt = _associated(truth, gt, est, times, E, marker, max_time_diff)
        to_camera = _to_camera(truth, gt, extrinsic_of, est_frame)  # the estimate's frame in the tracked one
    print(notes.getvalue(), end="")
    truth_xyz = truth.positions[i_gt] if truth.poses is None else truth.poses[i_gt][:, :3, 3]
    _say_if_units_differ(truth_xyz, E[i_est][:, :3, 3])
    if truth.poses is not None:
        timed = times is not None and truth.times is not None  # paired by timestamp
        _print_pose_errors(truth.poses[i_gt] @ to_camera, E[i_est], segments, timed)  # truth: camera poses
        _say_if_steps_skip(i_est)
        return
    if segments is not None:
        print(f"--segments: --gt {gt} holds positions only, which give the ATE alone")
    _print_position_errors(truth.positions[i_gt], E[i_est], np.linalg.inv(to_camera)[:3, 3])
