"""The tables ``python -m vo_lib run`` prints: time per stage (like [Zhao]'s Table 1) and the
errors against ground truth, position errors and distances in 3-D, heading errors planar."""

from __future__ import annotations

from dataclasses import fields
from typing import TYPE_CHECKING

import numpy as np

from vo_lib.geometry import camera_poses_from_planar, planar_from_camera_poses, wrap_angle
from vo_lib.stereo_vo.frames import FrameTimings, PipelineResult
from vo_lib.stereo_vo.paper_tables import PAPER_LONG_RUN, PAPER_TABLE1

if TYPE_CHECKING:
    from vo_lib.evaluation import StandardErrors

#: Width of a row's label and of each column in the error table.
LABEL, COLUMN = 46, 18
#: The timing table's stages (the refinement's only where it ran).
STAGES = (
    ("stereo", "binocular stereo vision processing"),
    ("matching", "guided temporal matching"),
    ("estimation", "parameter estimation (RANSAC)"),
    ("refinement", "6-DoF refinement"),
    ("kalman", "Kalman filtering (prediction + update)"),
)


def timing_rows(result: PipelineResult) -> list[tuple[str, str, np.ndarray]]:
    """Per-frame milliseconds of each stage: ``(key, label, values)``; with "between the stages"
    they add up to the whole frame, frame by frame."""
    rows = result.timings[1:] or result.timings  # the first frame only detects: no motion yet
    column = {f.name: np.array([getattr(r, f.name) for r in rows]) for f in fields(FrameTimings)}
    stages = [(k, label, column[k]) for k, label in STAGES if k != "refinement" or column[k].any()]
    between = column["total"] - sum(values for _, _, values in stages)
    return [*stages, ("between", "between the stages (keyframes, bookkeeping)", between)]


def print_timing_table(result: PipelineResult, camera, frames: int, decoding_ms=None) -> None:
    """The timing table like the paper's Table 1: median and mean milliseconds per stage beside the
    paper's mean at this resolution; ``decoding_ms``: each frame's decoding on the reader thread."""
    rows = timing_rows(result)
    whole = sum(values for _, _, values in rows)
    paper = PAPER_TABLE1.get((camera.width, camera.height), {})
    timed = len(rows[0][2])  # the frames the figures are of
    first = f" (the first of the {frames} only detects: left out)" if timed < frames else ""
    print(f"\nTime per frame at {camera.width}x{camera.height} over {timed} frames{first}, in ms")
    title = f"   paper's mean (Table 1, {camera.width}x{camera.height})" if paper else ""
    print(f"  {'stage':<46s}{'median':>8s}{'mean':>9s}{title}")
    rows += [("whole", "whole frame", whole)]
    if decoding_ms is not None and len(decoding_ms):
        rows += [("decoding", "image decoding (on the reader thread)", decoding_ms)]  # no paper's figure
    for key, label, values in rows:
        figure = f"   {paper[key]:.3f}" if key in paper else ""
        print(f"  {label:<46s}{np.median(values):8.3f}{np.mean(values):9.3f}{figure}")
    print("  The means of the stages add up to the whole frame; the medians (each stage's typical")
    print("  frame) need not. Images are decoded ahead on a reader thread, outside the whole frame.")
    if paper:
        print(
            f"  The paper's {PAPER_LONG_RUN[0]:,}-frame run: mean {PAPER_LONG_RUN[1]} ms per frame, s.d. "
            f"{PAPER_LONG_RUN[2]} ms (IV.A.1; resolution not stated)."
        )
    print(f"  frames per second: {1000.0 / np.mean(whole):.0f} (from the mean whole frame)")


def truth_and_odometry(seq, vehicle, frames: int):
    """Planar vehicle poses of the truth and of odometry alone over the first ``frames`` frames
    (each None where the sequence has none)."""
    truth = None if seq.poses is None else planar_from_camera_poses(seq.poses[:frames], vehicle.mount)
    odometry = None
    if vehicle.odometry is not None:
        odometry = vehicle.odometry_model.integrate(vehicle.odometry[1:frames])
    return truth, odometry


def error_report(result: PipelineResult, truth_planar: np.ndarray, odometry_planar=None) -> dict:
    """Planar errors of the estimate (and of odometry alone) against the truth: final position
    error (m, % of the distance), planar ATE, heading errors."""
    from vo_lib.evaluation import ate_planar, final_error, is_spot_turn, turned_degrees

    trajectories = {"vo": result.poses, "odometry": odometry_planar}
    finals = {label: final_error(truth_planar, t) for label, t in trajectories.items() if t is not None}
    dist = finals["vo"].distance_m
    report = {
        "distance_m": dist,
        "turned_deg": turned_degrees(truth_planar),
        "spot_turn": is_spot_turn(truth_planar),
    }
    for label, final in finals.items():
        traj = trajectories[label]
        # a spot turn has no distance to divide by (None: no row); a standstill's is undefined (NaN)
        percent = None if report["spot_turn"] else final.percent if dist > 0 else np.nan
        heading = np.degrees(np.abs(wrap_angle(traj[:, 2] - truth_planar[:, 2])))
        report[label] = {
            "final_position_error_m": final.position_m,
            "final_position_error_pct": percent,
            "ate_rmse_m": ate_planar(truth_planar, traj)[0].rmse,
            "heading_error_mean_deg": float(heading.mean()),
            "heading_error_max_deg": float(heading.max()),
            "final_heading_error_deg": final.heading_deg,
        }
    return report


#: The 3-D rows: label, the figure of a column's :class:`~vo_lib.evaluation.StandardErrors`, format.
ROWS_3D = (
    ("final position error, 3-D [m]", lambda e: e.final.position_m, "{:.4f}"),
    ("  of distance travelled, 3-D [%]", lambda e: e.final.percent, "{:.2f}"),
    ("final rotation error, 3-D [deg]", lambda e: e.final.rotation_deg, "{:.3f}"),
    ("distance travelled by the estimate, 3-D [m]", lambda e: e.final.estimate_distance_m, "{:.3f}"),
    ("ATE RMSE, SE(3) alignment [m]", lambda e: e.ate_se3.rmse, "{:.4f}"),
    ("ATE RMSE, Sim(3) alignment [m]", lambda e: e.ate_sim3.rmse, "{:.4f}"),
    ("  scale of the Sim(3) alignment", lambda e: e.sim3_scale, "{:.4f}"),
    ("RPE RMSE, 1 frame: translation [m]", lambda e: e.rpe_m.rmse, "{:.5f}"),
    ("RPE RMSE, 1 frame: rotation [deg]", lambda e: e.rpe_deg.rmse, "{:.4f}"),
    ("KITTI translation error [%]", lambda e: e.kitti and e.kitti.translation_pct, "{:.3f}"),
    ("KITTI rotation error [deg/100 m]", lambda e: e.kitti and e.kitti.rotation_deg_per_100m, "{:.3f}"),
)
#: The planar rows: label, key of :func:`error_report`'s column, format.
ROWS_PLANAR = (
    ("final position error, planar [m]", "final_position_error_m", "{:.4f}"),
    ("  of distance travelled, planar [%]", "final_position_error_pct", "{:.2f}"),
    ("ATE RMSE, planar alignment [m]", "ate_rmse_m", "{:.4f}"),
    ("planar heading error, mean [deg]", "heading_error_mean_deg", "{:.3f}"),
    ("planar heading error, max [deg]", "heading_error_max_deg", "{:.3f}"),
    ("planar heading error, final [deg]", "final_heading_error_deg", "{:.3f}"),
)


def _row(label: str, values, fmt: str) -> str:
    # None: no figure for this column; not finite: no value (the scale of a standing trajectory)
    cells = ["" if v is None else fmt.format(v) if np.isfinite(v) else "undefined" for v in values]
    return f"  {label:<{LABEL}s}" + "".join(f"{c:>{COLUMN}s}" for c in cells)


def _how_far(report: dict, vo_3d) -> str:
    """The table's title: the turn of a spot turn, else the distance (3-D where known)."""
    if report["spot_turn"]:
        return f"{report['turned_deg']:.0f}° turned on the spot"
    if vo_3d is not None:
        return f"{vo_3d.final.distance_m:.2f} m travelled in 3-D"
    return f"{report['distance_m']:.2f} m travelled, planar"


def _print_rows_3d(errors: dict, cols: list[str], spot_turn: bool) -> None:
    """The 3-D rows of :func:`print_error_table`, and the segment lengths of the KITTI errors."""
    kitti = errors["vo"].kitti
    for label, figure, fmt in ROWS_3D:
        if not (spot_turn and "of distance" in label or kitti is None and label.startswith("KITTI")):
            print(_row(label, [None if errors.get(c) is None else figure(errors[c]) for c in cols], fmt))
    if kitti is None:  # a truth standing still, or moving less than any segment
        print("  KITTI errors: no segment fits the truth's path")
    else:
        print(f"  (KITTI errors over {kitti.label()}, {kitti.count} segment{'s' * (kitti.count != 1)})")


def print_error_table(
    report: dict,
    flagged: int,
    errors: dict[str, StandardErrors | None] | None = None,
    odometry_label: str = "track odometry",
    truth_file: str | None = None,
    planar: bool = True,
    fused: bool = False,
) -> None:
    """Errors against ground truth, a column for visual odometry (``fused`` with the odometry) and
    one for odometry alone: the 3-D rows of ``errors`` (:func:`vo_lib.evaluation.standard_errors`)
    and, with ``planar``, the planar rows of ``report`` (:func:`error_report`)."""
    errors = errors or {}
    vo_3d = errors.get("vo")
    source = f"{truth_file}, " if truth_file else ""  # a recording's, of the several it may hold
    print(f"\nErrors against ground truth ({source}{_how_far(report, vo_3d)})")
    cols = [k for k in ("vo", "odometry") if k in report]
    names = {"vo": "VO + odometry" if fused else "visual odometry", "odometry": odometry_label}
    print(f"  {'':<{LABEL}s}" + "".join(f"{names[c]:>{COLUMN}s}" for c in cols))
    if vo_3d is not None:
        _print_rows_3d(errors, cols, report["spot_turn"])
    if planar or vo_3d is None:  # without 3-D rows, the planar ones are all there is
        for label, key, fmt in ROWS_PLANAR:
            if not (report["spot_turn"] and "of distance" in label):
                print(_row(label, [report[c][key] for c in cols], fmt))
    print(_row("frames flagged (VO not used)", [flagged], "{:d}"))


def tracked_truth(seq, n: int):
    """Position-only truth (a laser tracker's prism) in the first ``n`` frames: ``(the manifest's
    entry, frames, positions)``; None with fewer than 3."""
    positions = seq.manifest.get("positions") if isinstance(seq.manifest, dict) else None
    frames = np.asarray(positions["frames"], int) if positions else np.zeros(0, int)
    keep = frames < n
    return None if keep.sum() < 3 else (positions, frames[keep], np.asarray(positions["xyz"])[keep])


def tracked_offsets(seq, poses: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray] | None:
    """The frames of position-only truth and, at each, its tracked point minus the estimate's
    after SE(3) alignment, in the first camera's frame ``(K, 3)``; None without such truth."""
    from vo_lib.evaluation import carried_point, umeyama

    found = tracked_truth(seq, n)
    if found is None:
        return None
    positions, frames, xyz = found
    tracked = carried_point(poses[frames], positions["lever_arm_camera"])
    R, t, _ = umeyama(tracked, xyz)  # xyz ~ R tracked + t
    return frames, (xyz - t) @ R - tracked


def position_only_errors(seq, poses: np.ndarray, n: int) -> dict:
    """Print and return the tracked point's ATE against position-only truth (empty without)."""
    from vo_lib.evaluation import Alignment, ate_positions

    found = tracked_truth(seq, n)
    if found is None:
        return {}
    positions, frames, xyz = found
    ate, _ = ate_positions(xyz, poses[frames], positions["lever_arm_camera"], Alignment.SE3)
    source = positions.get("file", "the manifest's positions")  # the file they were read from, if named
    print(f"\nErrors against position-only ground truth ({source}, {len(frames)} positions)")
    print(f"  {'ATE RMSE of the tracked point, SE(3) alignment [m]':<62s}{ate.rmse:>16.4f}")
    print(
        "  paired at the images' times: a tracker's clock not synchronised with the cameras adds its\n"
        "  offset to this figure; evaluate --time-offset SECONDS takes it out (seconds added to the\n"
        "  estimate's times: the tracker's lag behind the images)"
    )
    return {"ate_positions_m": ate.rmse}


def odometry_name(vehicle) -> str:
    """What the vehicle's odometry is, as the tables and the figure name it."""
    if vehicle.kind == "crawler":
        return "track odometry"
    return "OXTS odometry" if vehicle.odometry_source.startswith("oxts") else "wheel odometry"


def errors_3d(truth: np.ndarray, estimates: dict, mount: np.ndarray) -> dict:
    """:func:`vo_lib.evaluation.standard_errors` of each estimate (camera poses, or planar ones
    carried through ``mount``) against the 6-DoF truth; None for a missing estimate."""
    from vo_lib.evaluation import standard_errors

    errors = {}
    for label, poses in estimates.items():
        if poses is not None and np.ndim(poses) == 2:
            poses = camera_poses_from_planar(poses, mount)
        errors[label] = None if poses is None else standard_errors(truth, poses)
    return errors
