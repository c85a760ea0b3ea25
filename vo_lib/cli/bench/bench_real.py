"""Benchmark on real stereo: our pipeline beside the OpenCV PnP baseline, same frames, same process.

``VO_LIB_REALDATA=FOLDER python -m vo_lib bench real`` runs on every sequence folder in FOLDER. Per
sequence it prints the per-stage median milliseconds and frames per second of our pipeline
(without odometry), the final and segment errors of both, and the speed ratio.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np

SEGMENTS = (25.0, 50.0, 100.0)  # metres: short sequences have no KITTI-length segments


def realdata_folders() -> list[Path]:
    """Sequence folders (holding ``image_0/``) in the folder named by ``$VO_LIB_REALDATA``."""
    root = Path(os.environ.get("VO_LIB_REALDATA", ""))
    if not os.environ.get("VO_LIB_REALDATA") or not root.is_dir():
        return []
    return sorted(p for p in root.iterdir() if (p / "image_0").is_dir())


def _errors(truth, poses, mount) -> tuple[float, str]:
    """The final error as ``run`` prints it (:func:`vo_lib.evaluation.final_error`, the car's
    planar pose through the camera ``mount``), in per cent, and the segment errors."""
    from vo_lib.evaluation import final_error, kitti_segment_errors
    from vo_lib.geometry import planar_from_camera_poses

    final = final_error(planar_from_camera_poses(truth, mount), planar_from_camera_poses(poses, mount))
    segments = kitti_segment_errors(truth, poses, SEGMENTS, step=1)
    text = ", ".join(f"{length:g} m: {t:.2f} %" for length, (t, _, _) in segments.items())
    return final.percent, text or "no segment fits"


def bench_real(folders=None) -> dict[str, float]:
    """Time and score our pipeline and the PnP baseline on real sequences."""
    import cv2

    from vo_lib.formats.sequence import read_sequence
    from vo_lib.stereo_vo.pipeline import run_sequence
    from vo_lib.stereo_vo.pnp_baseline import run_pnp_baseline
    from vo_lib.stereo_vo.vehicle import vehicle_of

    folders = [Path(f) for f in folders] if folders else realdata_folders()
    if not folders:
        print("no real sequences found: set VO_LIB_REALDATA to a folder of KITTI-layout sequences")
        return {}
    cv2.setRNGSeed(0)
    out = {}
    for folder in folders:
        seq = read_sequence(folder)
        for k in range(len(seq)):  # read every image once, so that both methods time the same work
            seq.pair(k)
        w, h = seq.camera.width, seq.camera.height
        t0 = time.perf_counter()
        ours = run_sequence(seq, use_odometry=False, seed=0)
        ours_wall = time.perf_counter() - t0
        base = run_pnp_baseline(seq, seed=0)
        table = ours.timing_table()
        ours_ms, base_ms = table["total"], float(np.median(base.milliseconds[1:]))
        print(f"\n{folder.name}: {len(seq)} frames at {w}x{h}")
        print(f"  {'stage (median ms per frame)':<40s}{'ours':>10s}")
        for key in ("stereo", "prediction", "matching", "estimation", "refinement", "kalman", "total"):
            print(f"  {key:<40s}{table[key]:10.2f}")
        print(f"  frames per second: ours {1000 / ours_ms:.0f}, PnP baseline {1000 / base_ms:.1f}")
        print(f"  whole run: ours {ours_wall:.1f} s (incl. first-call compilation)")
        truth = seq.poses_4x4()
        if truth is not None:
            for name, poses in (("ours", ours.camera_poses), ("PnP baseline", base.camera_poses)):
                final, segments = _errors(truth, poses, vehicle_of(seq, use_odometry=False).mount)
                print(f"  {name:<14s} final error {final:.3f} % of the distance; segments {segments}")
                out[f"{folder.name}:{name}:final_pct"] = final
        print(f"  frames flagged: {len(ours.flagged)}")
        ratio = base_ms / ours_ms
        print(f"  speed: ours {ours_ms:.1f} ms, baseline {base_ms:.1f} ms per frame: {ratio:.1f}x faster")
        out[f"{folder.name}:ours_ms"], out[f"{folder.name}:baseline_ms"] = ours_ms, base_ms
    return out
