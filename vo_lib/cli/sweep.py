"""``python -m vo_lib sweep NAME``: a paper's statistic over many seeds, on Dask or in this process.

Each task calls one function of its paper's package with keyword arguments (``seed`` its only source
of randomness: the figures are the same on any cluster) and gets a dict of numbers; ``results.csv``
holds one row per task, and each figure's mean, spread and 95 % interval over the seeds are printed.
"""

from __future__ import annotations

import contextlib
import os
import pkgutil
import signal
import sys
from pathlib import Path

import numpy as np

from vo_lib.arguments import UsageError, one_line
from vo_lib.outputs import OutputFolder
from vo_lib.stereo_vo.paper_tables import PAPER_TABLE1  # its resolutions, largest first

#: Each sweep: the function one task calls, the tasks for a number of seeds, and what it measures.
SWEEPS = {
    "corridor": (
        "vo_lib.lidar_tracking.corridor_experiment.corridor_figures",
        lambda n: [{"seed": s} for s in range(n)],
        "[Yuan], Table III: LBPT and VOAPT along the occluded corridor",
    ),
    "lap": (
        "vo_lib.line_slam.lap.lap_figures",
        lambda n: [{"seed": s} for s in range(n)],
        "[Yan 2020]: per seed, a lap of EKF-SLAM, one with landmark 3 extended and one observing lines",
    ),
    "nees": (
        "vo_lib.stereo_vo.consistency.nees_figures",
        lambda n: [{"seed": 1000 + s} for s in range(n)],
        "[Zhao]: consistency of the fused Kalman filter (pose NEES)",
    ),
    "table1": (
        "vo_lib.stereo_vo.paper_tables.stage_times",
        lambda n: [{"resolution": f"{w}x{h}", "seed": s} for w, h in PAPER_TABLE1 for s in range(n)],
        "[Zhao], Table 1: milliseconds per stage at five resolutions",
    ),
}
#: What prints, below a sweep's summary, what its paper's package says of the figures: called with
#: the table (one row per task) and the summary (one row per figure).
REPORTS = {
    "corridor": "vo_lib.lidar_tracking.corridor_experiment.corridor_report",
    "lap": "vo_lib.line_slam.lap.lap_report",
    "nees": "vo_lib.stereo_vo.consistency.nees_report",
}
#: Local worker processes allowed per core; seconds a --scheduler has to answer, handshake included.
WORKERS_PER_CORE, SCHEDULER_SECONDS = 4, 20
#: Dask settings of the local cluster: glibc keeps freed memory (Dask's trim threshold doubles a
#: corridor task's time in page faults); no statistical profiler.
LOCAL_CLUSTER_CONFIG = {
    "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None,
    "distributed.nanny.pre-spawn-environ.MALLOC_TOP_PAD_": str(64 * 2**20),
    "distributed.worker.profile.enabled": False,
}


def function_of(name: str):
    """The function a task of sweep ``name`` calls."""
    return pkgutil.resolve_name(SWEEPS[name][0])


def _call(function, kwargs: dict) -> dict:
    return {**kwargs, **{k: float(v) for k, v in function(**kwargs).items()}}


@contextlib.contextmanager
def _alarm():
    """A TimeoutError after ``SCHEDULER_SECONDS``."""

    def no_answer(signum, frame):
        raise TimeoutError(f"no answer as a Dask scheduler within {SCHEDULER_SECONDS} s")

    previous = signal.signal(signal.SIGALRM, no_answer)
    signal.alarm(SCHEDULER_SECONDS)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


#: The -W option that silences the semaphore tracker as it cleans up after a sweep stopped by Ctrl-C.
TRACKER_WARNING = "ignore:resource_tracker:UserWarning"


@contextlib.contextmanager
def dask_client(workers: int, scheduler: str | None):
    """A ``distributed.Client`` of ``scheduler``, else of a new LocalCluster of ``workers`` processes
    that ignore Ctrl-C (this process stops and closes the cluster)."""
    import logging

    import dask
    from distributed import Client, LocalCluster

    # a Ctrl-C leaves the client's pending tasks unretrieved; asyncio would log each one's traceback
    logging.getLogger("asyncio").setLevel(logging.CRITICAL)
    if scheduler is not None:
        try:
            with _alarm():  # bounds the handshake too, which a silent server never ends
                client = Client(scheduler.strip(), timeout=10)
        except (ValueError, TypeError, OSError, AssertionError, MemoryError) as exc:  # TimeoutError too
            why = "no event loop" if isinstance(exc, AssertionError) else one_line(exc)
            # a MemoryError (numpy's too): another service's greeting read as the length of a message
            why = "it answered, but not as a Dask scheduler" if isinstance(exc, MemoryError) else why
            raise UsageError(f"--scheduler {scheduler}: cannot reach a scheduler ({why})") from None
        with client:
            yield client
        return
    # the semaphore tracker that the cluster starts outlives a sweep stopped by Ctrl-C, cleans up after
    # it, then warns that it did, after the sweep's one line; it runs with this process's -W options
    if TRACKER_WARNING not in sys.warnoptions:
        sys.warnoptions.append(TRACKER_WARNING)
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)  # inherited by the workers
    try:
        with dask.config.set(LOCAL_CLUSTER_CONFIG):
            cluster = LocalCluster(
                n_workers=workers, threads_per_worker=1, dashboard_address=":0", silence_logs=logging.CRITICAL
            )  # a task's own error reaches gather; what the workers log as the cluster closes is noise
    finally:
        signal.signal(signal.SIGINT, previous)
    with cluster, Client(cluster) as client:
        yield client


def run_tasks(function, tasks: list[dict], workers: int = 1, scheduler: str | None = None) -> list[dict]:
    """Each task's arguments and figures, in the order of ``tasks``."""
    from tqdm import tqdm

    if workers == 1 and scheduler is None:
        return [_call(function, t) for t in tqdm(tasks, disable=not sys.stderr.isatty(), unit="task")]
    with dask_client(workers, scheduler) as client:
        futures = client.map(_call, [function] * len(tasks), tasks, pure=False)
        return client.gather(futures)


def summary(table, arguments: list[str]):
    """Mean, standard deviation, count and the 95 % interval of the mean (Student's t) of every
    figure over the seeds, per setting of the other ``arguments`` (a DataFrame). A figure never
    negative (an error, a NEES) has its interval cut at 0, which covers its mean as often."""
    from scipy.stats import t

    figures = [c for c in table.columns if c not in arguments]
    by = [a for a in arguments if a != "seed"] or (lambda _: "all")
    stats = table.groupby(by, sort=False)[figures].agg(["mean", "std", "count"]).stack(0, future_stack=True)
    half = t.ppf(0.975, np.maximum(stats["count"] - 1, 1)) * stats["std"] / np.sqrt(stats["count"])
    floor = [0.0 if (table[f] >= 0).all() else -np.inf for f in stats.index.get_level_values(-1)]
    return stats.assign(low=np.maximum(stats["mean"] - half, floor), high=stats["mean"] + half)


def sweep_command(name: str, seeds: int, workers=None, scheduler=None, out=None, force=False) -> None:
    """Run sweep ``name`` over ``seeds`` seeds, write its table and print its summary."""
    import pandas as pd

    from vo_lib.data import kept_data_folder

    cores = len(os.sched_getaffinity(0))
    workers = cores if workers is None else workers
    if scheduler is None and workers > WORKERS_PER_CORE * cores:
        raise UsageError(f"--workers {workers}: at most {WORKERS_PER_CORE * cores} on {cores} core(s)")
    _, make_tasks, describe = SWEEPS[name]
    tasks = make_tasks(seeds)
    target, keep = Path(out or f"sweeps/{name}"), kept_data_folder()
    with OutputFolder(
        target, f"vo_lib sweep {name}", force=force, option="--out", keep=keep, keep_inside=True
    ) as folder:
        table = pd.DataFrame(run_tasks(function_of(name), tasks, workers, scheduler))
        table.to_csv(folder.path / "results.csv", index=False, lineterminator="\n")
        path = folder.commit(seeds=seeds)
    where = scheduler or f"{workers} Dask workers"
    where = "in this process" if workers == 1 and scheduler is None else where
    print(f"{describe}: {len(tasks)} tasks ({where}); wrote {path / 'results.csv'}")
    stats = summary(table, list(tasks[0]))
    with pd.option_context("display.max_rows", None, "display.width", 120):
        print(stats.to_string(float_format=lambda v: f"{v:.4g}", na_rep="undefined"))  # one seed: no spread
    if name in REPORTS:
        pkgutil.resolve_name(REPORTS[name])(table, stats.droplevel(0))
