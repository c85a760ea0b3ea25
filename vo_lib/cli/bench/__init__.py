"""Benchmarks, run as ``python -m vo_lib bench NAME``: each prints its times beside a baseline.

Times are medians of repeated runs on data drawn once with a fixed seed, so a run compares
like with like; they are measurements to read, never assertions. One module per wing
(``bench_stereo_vo``, ``bench_line_slam``, ``bench_lidar_tracking``), one for the simulated
sensors (``bench_sim``),
one for the real drive beside the PnP baseline (``bench_real``),
one for how real the samples' images look (``bench_realism``) and one for the sweep machinery
on Dask (``bench_sweep``); the timing
helpers are in ``common``. Each benchmark imports what it times when it runs, so listing them
stays fast.
"""

from __future__ import annotations

from collections.abc import Callable

from vo_lib.cli.bench.bench_lidar_tracking import bench_odometers, bench_tracking
from vo_lib.cli.bench.bench_line_slam import bench_observers
from vo_lib.cli.bench.bench_real import bench_real
from vo_lib.cli.bench.bench_realism import bench_realism
from vo_lib.cli.bench.bench_sim import bench_sensors
from vo_lib.cli.bench.bench_stereo_vo import (
    bench_frontend,
    bench_geometry,
    bench_long,
    bench_pipeline,
    bench_ransac,
)
from vo_lib.cli.bench.bench_sweep import bench_sweep

BENCHES: dict[str, Callable[[], dict[str, float]]] = {
    "pipeline": bench_pipeline,
    "long": bench_long,
    "ransac": bench_ransac,
    "frontend": bench_frontend,
    "geometry": bench_geometry,
    "sensors": bench_sensors,
    "observers": bench_observers,
    "tracking": bench_tracking,
    "odometers": bench_odometers,
    "real": bench_real,
    "realism": bench_realism,
    "sweep": bench_sweep,
}
