"""Benchmarks, ``python -m vo_lib bench NAME``: each prints the median times of repeated runs beside a
baseline, on data drawn once with a fixed seed; each imports what it times when it runs.
"""

from __future__ import annotations

from vo_lib.bench import (
    bench_lidar_tracking,
    bench_line_slam,
    bench_real,
    bench_realism,
    bench_sim,
    bench_stereo_vo,
)

#: What each benchmark times and how long it runs on the shared 2-core machine (``bench --help``).
BENCH_HELP: dict[str, tuple[str, str]] = {
    "pipeline": ("[Zhao]'s pipeline, stage by stage, on 200 rendered frames", "about 15 s"),
    "long": ("the paper's 10,000-frame timing run (IV.A.1), rendered in memory", "about 6 min"),
    "ransac": ("1-point RANSAC against 3-point rigid RANSAC and OpenCV's solvePnPRansac", "about 30 s"),
    "kernels": ("whole frames with each compiled kernel and with its NumPy reference", "about 1 min"),
    "frontend": ("the stereo front end per stage, guided against brute-force matching", "about 10 s"),
    "geometry": ("theta and rho (eq. 12-17) for 10,000 matches against a Python loop", "about 5 s"),
    "sensors": ("the stereo renderer per world, and the laser scanner", "about 15 s"),
    "observers": ("[Yan 2020]'s segment observers: point by point, bisection, closed form", "about 10 s"),
    "tracking": ("[Yuan]'s likelihood-field scoring, vectorised against pose by pose", "about 5 s"),
    "odometers": ("[Yuan]'s PnP odometer beside [Zhao]'s on the rendered corridor", "about 50 s"),
    "real": (
        "our pipeline (car or drone) and OpenCV's PnP baseline on real sequences: those in "
        "$VO_LIB_REALDATA (a folder of them, or one; default ../shared/realdata)",
        "1-2 minutes",
    ),
    "realism": ("how real the samples' images look: empty cells, corners, noise", "about 10 s"),
}

#: Benchmark ``NAME`` is the function ``bench_NAME`` of one of these modules (one per wing).
_WINGS = (bench_stereo_vo, bench_sim, bench_line_slam, bench_lidar_tracking, bench_real, bench_realism)
BENCHES = {
    name: getattr(module, f"bench_{name}")
    for name in BENCH_HELP
    for module in _WINGS
    if hasattr(module, f"bench_{name}")
}
