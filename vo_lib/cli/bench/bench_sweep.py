"""The sweep machinery: ``python -m vo_lib bench sweep``.

A 20-seed corridor sweep (seed 004, Table III) run serially in this process and on a 2-worker
Dask LocalCluster, in one run. The shared setup (the PnP visual odometer on the rendered corridor
and the calibration) is computed once beforehand and given to both, so both time the same 20
tasks. The cluster's time is given with and without starting it; the figures of both runs are
checked equal.
"""

from __future__ import annotations

import os
import tempfile
import time


def _load() -> str:
    try:
        one, _, _ = os.getloadavg()
    except OSError:
        return "unknown"
    return f"{one:.1f}"


def bench_sweep(seeds: int = 20, workers: int = 2) -> dict[str, float]:
    """Wall time of a ``seeds``-seed corridor sweep serially and on ``workers`` local workers."""
    from distributed import Client

    from vo_lib.cli.experiments import corridor_experiment, corridor_setup, corridor_tasks
    from vo_lib.cli.sweep import local_cluster, run_sweep

    experiment, tasks = corridor_experiment(), corridor_tasks(seeds)
    t0 = time.perf_counter()
    context = corridor_setup()
    setup = time.perf_counter() - t0
    print(
        f"corridor sweep, {seeds} seeds; shared setup (visual odometer, calibration) {setup:.1f} s, untimed"
    )
    print(f"machine: {os.cpu_count()} cores, load average before {_load()}")
    with tempfile.TemporaryDirectory(prefix="vo_lib-bench-sweep-") as tmp:
        t0 = time.perf_counter()
        serial = run_sweep(experiment, tasks, f"{tmp}/serial", workers=1, context=context, progress=False)
        t_serial = time.perf_counter() - t0
        load_serial = _load()
        t0 = time.perf_counter()
        cluster = local_cluster(workers)
        client = Client(cluster)
        t_start = time.perf_counter() - t0
        try:
            t1 = time.perf_counter()
            parallel = run_sweep(
                experiment, tasks, f"{tmp}/dask", context=context, progress=False, client=client
            )
            t_tasks = time.perf_counter() - t1
        finally:
            client.close()
            cluster.close()
        load_parallel = _load()
    same = [a["figures"] for a in serial.rows] == [b["figures"] for b in parallel.rows]
    failed = len(serial.failed) + len(parallel.failed)
    total = t_start + t_tasks
    print(f"  {'serial, in this process':<42s}{t_serial:9.1f} s   (load average after {load_serial})")
    print(
        f"  {f'Dask LocalCluster, {workers} workers':<42s}{total:9.1f} s   "
        f"({t_start:.1f} s to start the cluster, {t_tasks:.1f} s of tasks; "
        f"load average after {load_parallel})"
    )
    print(
        f"  speed-up {t_serial / total:.2f}x with the cluster's start, {t_serial / t_tasks:.2f}x without; "
        f"target >= 1.7x on 2 cores ({'met' if t_serial / total >= 1.7 else 'NOT met'} with the start)"
    )
    print(
        f"  figures identical serially and on the cluster: {'yes' if same else 'NO'}; failed rows: {failed}"
    )
    if max(float(x) if x != "unknown" else 0.0 for x in (load_serial, load_parallel)) > (os.cpu_count() or 1):
        print("  note: the load average exceeds the core count: other processes share the machine")
    return {"serial": t_serial, "cluster start": t_start, "cluster tasks": t_tasks}
