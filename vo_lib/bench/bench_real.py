"""``python -m vo_lib bench real``: our pipeline beside the OpenCV PnP baseline on every sequence
of ``$VO_LIB_REALDATA`` (KITTI or ASL layout), same frames, same process (``docs/benchmarks.md``).
"""

from __future__ import annotations

import os
from functools import partial
from pathlib import Path

import numpy as np

from vo_lib.bench.common import timed_ms

#: Where the development sequences sit when ``$VO_LIB_REALDATA`` is not set: beside the checkout.
DEFAULT_REALDATA = Path(__file__).resolve().parents[2].parent / "shared" / "realdata"
#: Runs of each method per sequence; the fastest is reported.
REPEATS = 3


def realdata_folders() -> list[Path]:
    """Sequence folders (``image_0/``, ``mav0/`` or a raw KITTI drive) in ``$VO_LIB_REALDATA`` (or that
    one sequence); a variable set to anything but a folder of them raises :class:`UsageError`."""
    from vo_lib.arguments import UsageError
    from vo_lib.formats.euroc import mav0_of
    from vo_lib.formats.kitti_raw import raw_drive_of

    def is_sequence(p: Path) -> bool:
        return (p / "image_0").is_dir() or mav0_of(p) is not None or raw_drive_of(p) is not None

    root = Path(os.environ.get("VO_LIB_REALDATA") or DEFAULT_REALDATA)
    if os.environ.get("VO_LIB_REALDATA") and not root.is_dir():
        raise UsageError(
            f"VO_LIB_REALDATA={root}: not a folder; expected a folder of sequences or one sequence"
        )
    if not root.is_dir():
        return []
    found = [root] if is_sequence(root) else sorted(p for p in root.iterdir() if is_sequence(p))
    if os.environ.get("VO_LIB_REALDATA") and not found:
        raise UsageError(f"VO_LIB_REALDATA={root}: no sequence in it (a folder holding image_0/ or mav0/)")
    return found


def decoded_sequence(folder) -> tuple[object, float]:
    """The sequence in ``folder`` (no odometry), every pair decoded (and rectified) beforehand and
    read from memory, and the median milliseconds a pair took; fewer than 3 frames raise
    :class:`UsageError` (as in evaluate)."""
    from vo_lib.arguments import UsageError
    from vo_lib.data import load_sequence

    seq = load_sequence(folder, odometry=False, progress=False)
    if len(seq) < 3:
        raise UsageError(f"{folder}: {len(seq)} frame(s); a benchmark needs at least 3")
    seq.read_ahead = 0
    timed = [timed_ms(seq.pair, k) for k in range(len(seq))]
    seq.pair = [pair for pair, _ in timed].__getitem__
    return seq, float(np.median([ms for _, ms in timed]))


def run_ours(seq, repeats: int = REPEATS) -> tuple[object, list[float]]:
    """Our pipeline on ``seq`` (no odometry, seed 0) after an untimed warm-up: :func:`fastest` of
    ``repeats`` runs by the median whole frame."""
    from vo_lib.stereo_vo.pipeline import run_sequence, warm_up

    warm_up(seq, use_odometry=False)  # compiled kernels ready before the timed run
    return fastest(
        partial(run_sequence, seq, use_odometry=False, seed=0), lambda r: r.timing_table()["total"], repeats
    )


def step_scale(truth, poses, stride: int = 1) -> float:
    """The least-squares factor ``s`` of ``t_est = s t_true`` over every step of ``stride`` frames,
    each translation in the camera of the step's start (no alignment needed); below 1, the steps are
    measured short (even on a path longer than the truth's, that moves sideways from frame to frame).
    The truth's own noise pulls it below 1; a longer stride weighs that less."""
    T, E = np.asarray(truth, float), np.asarray(poses, float)
    t_true = (np.linalg.inv(T[:-stride]) @ T[stride:])[:, :3, 3]
    t_est = (np.linalg.inv(E[:-stride]) @ E[stride:])[:, :3, 3]
    moved = np.sum(t_true * t_true)
    return float(np.sum(t_est * t_true) / moved) if moved > 0 else float("nan")  # a truth standing still


def error_rows(truth, poses) -> dict[str, float]:
    """ATE (SE(3)), final 3-D position (% of the path) and rotation errors, path lengths and
    :func:`step_scale`."""
    from vo_lib.evaluation import ate, final_error_3d

    final = final_error_3d(truth, poses)
    return {
        "ate_m": ate(truth, poses)[0].rmse,
        "final_pct": final.percent,
        "final_rotation_deg": final.rotation_deg,
        "path_m": final.estimate_distance_m,
        "truth_path_m": final.distance_m,
        "step_scale": step_scale(truth, poses),
    }


def fastest(run, median_ms, repeats: int = REPEATS) -> tuple[object, list[float]]:
    """The fastest of ``repeats`` calls of ``run()`` by ``median_ms(result)``, and every run's figure;
    the runs must give the same camera poses."""
    runs = [run() for _ in range(repeats)]
    for other in runs[1:]:
        if not np.array_equal(other.camera_poses, runs[0].camera_poses):
            raise RuntimeError("two runs on the same frames with the same seed gave different poses")
    times = [median_ms(r) for r in runs]
    return runs[int(np.argmin(times))], times


def bench_real(folders=None, repeats: int = REPEATS) -> dict[str, float]:
    """Time and score our pipeline and the PnP baseline on real sequences (fastest of ``repeats``)."""
    import cv2

    from vo_lib.stereo_vo.baselines import run_pnp_baseline

    folders = [Path(f) for f in folders] if folders else realdata_folders()
    if not folders:
        print(
            f"no real sequences found ({DEFAULT_REALDATA} is not a folder): "
            "set VO_LIB_REALDATA to a folder of KITTI-layout or ASL sequences"
        )
        return {}
    cv2.setRNGSeed(0)
    out = {}
    for folder in folders:
        seq, decode = decoded_sequence(folder)  # both methods read the same frames, decoded beforehand
        ours, ours_runs = run_ours(seq, repeats)
        base, base_runs = fastest(
            partial(run_pnp_baseline, seq, seed=0), lambda r: float(np.median(r.milliseconds[1:])), repeats
        )
        table = ours.timing_table()
        ours_ms, base_ms = table["total"], min(base_runs)
        print(f"\n{folder.name}: {len(seq)} frames at {seq.camera.width}x{seq.camera.height}, no odometry")
        print(
            f"  decoding{' and rectifying' if seq.rectify else ''} a pair: {decode:.1f} ms "
            "(not in the times below)"
        )
        print(f"  {'stage (median ms per frame, fastest run)':<42s}{'ours':>10s}")
        for key in ("stereo", "prediction", "matching", "estimation", "refinement", "kalman", "total"):
            print(f"  {key:<42s}{table[key]:10.2f}")
        ratio = base_ms / ours_ms
        print(f"  per frame: ours {ours_ms:.1f} ms, PnP baseline {base_ms:.1f} ms: {ratio:.1f}x faster")
        runs = ", ".join(f"{a:.1f}/{b:.1f}" for a, b in zip(ours_runs, base_runs, strict=True))
        print(f"  the {repeats} runs, ours/baseline ms: {runs}")
        print(f"  frames flagged: {len(ours.flagged)}")
        out[f"{folder.name}:ours_ms"], out[f"{folder.name}:baseline_ms"] = ours_ms, base_ms
        out[f"{folder.name}:decode_ms"] = decode
        truth = seq.poses_4x4()
        if truth is not None:
            out.update(_error_table(folder.name, truth, ours.camera_poses, base.camera_poses))
    return out


#: The error table's columns: figure, heading, width, digits.
COLUMNS = (
    ("ate_m", "ATE SE(3) [m]", 14, 4),
    ("final_pct", "final [%]", 11, 3),
    ("final_rotation_deg", "rotation [deg]", 16, 3),
    ("path_m", "path [m]", 10, 3),
    ("step_scale", "step scale", 12, 4),
)


def _figure(value: float, width: int, digits: int) -> str:
    """``value`` in a column, or "undefined" (a percentage of no path, the scale of no motion)."""
    return f"{value:{width}.{digits}f}" if np.isfinite(value) else f"{'undefined':>{width}}"


def _error_table(name: str, truth, ours, baseline) -> dict[str, float]:
    """Print :func:`error_rows` of both methods and the truth's path; returns them keyed
    ``NAME:METHOD:KEY``."""
    print(f"  {'':<14s}" + "".join(f"{heading:>{width}s}" for _, heading, width, _ in COLUMNS))
    out = {}
    for method, poses in (("ours", ours), ("PnP baseline", baseline)):
        rows = error_rows(truth, poses)
        print(
            f"  {method:<14s}" + "".join(_figure(rows[k], width, digits) for k, _, width, digits in COLUMNS)
        )
        out.update({f"{name}:{method}:{key}": value for key, value in rows.items()})
    print(f"  {'truth':<14s}{'':>41s}{rows['truth_path_m']:10.3f}")
    return out
