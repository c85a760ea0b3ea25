"""Where a sweep's tasks run, and how one runs: in this process, or on Dask (a LocalCluster of
worker processes, or an existing scheduler). A task that raises becomes an outcome with its
error; a Ctrl-C to the process group stops only the process that started the cluster."""

from __future__ import annotations

import contextlib
import functools
import signal
import time
import traceback
from collections.abc import Callable
from pathlib import Path

import numpy as np

from vo_lib.arguments import one_line

#: Columns every row has after its parameters and figures.
SECONDS, ERROR = "seconds", "error"
#: Tasks given to the cluster at once: the scheduler never holds a whole grid of hundreds of
#: thousands of tasks (each costs it memory), and a chunk keeps every worker busy to its end.
CHUNK = 10_000
#: Seconds allowed to reach an existing scheduler.
CONNECT_TIMEOUT = 10.0
#: Local worker processes allowed per core: more only share the cores and multiply the memory.
WORKERS_PER_CORE = 4


class SweepError(ValueError):
    """A bad argument or folder for a sweep: reported in one line, exit status 2."""


def plain(value):
    """A parameter as JSON sees it (NumPy numbers and tuples become Python numbers and lists)."""
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, tuple):
        return [plain(v) for v in value]
    return value


def execute(run: Callable[[dict, object], dict], params: dict, context=None) -> dict:
    """Run one task: ``{"figures": ..., "seconds": wall time, "error": "" or one line}``."""
    t0 = time.perf_counter()
    try:
        figures = {str(k): plain(v) for k, v in dict(run(params, context)).items()}
        error = ""
    except Exception as exc:  # a failed run is a row, not a lost sweep
        figures = {}
        where = traceback.extract_tb(exc.__traceback__)[-1]
        error = one_line(f"{type(exc).__name__}: {exc} ({Path(where.filename).name}:{where.lineno})")
    return {"figures": figures, SECONDS: time.perf_counter() - t0, ERROR: error}


def check_workers(workers: int | None, local: bool) -> int:
    """``workers`` (default: one per core Dask finds for this process), refused in one line if
    below 1 or, for a local cluster, above :data:`WORKERS_PER_CORE` per core."""
    from dask.system import CPU_COUNT

    workers = CPU_COUNT if workers is None else int(workers)
    if workers < 1:
        raise SweepError(f"--workers {workers}: expected at least 1")
    if local and workers > WORKERS_PER_CORE * CPU_COUNT:
        raise SweepError(
            f"--workers {workers}: this machine gives this process {CPU_COUNT} core(s); at most "
            f"{WORKERS_PER_CORE * CPU_COUNT} local workers (--scheduler ADDRESS runs on a cluster)"
        )
    return workers


#: Dask settings of the local cluster. Dask sets ``MALLOC_TRIM_THRESHOLD_`` in its workers, which
#: also turns off glibc's adaptive mmap threshold: every large NumPy temporary (the tracker scores
#: a thousand poses at once) is then mapped and unmapped afresh. Unset, a task still runs in the
#: worker's executor thread, whose malloc arena gives its top back to the system after every large
#: free: a corridor task spent as long in page faults (system time) as in computing, twice its
#: time in this process. A 64 MiB top pad keeps the arena's memory for the next temporary, and the
#: task runs as fast as here. The statistical profiler is off too (10 ms samples).
LOCAL_CLUSTER_CONFIG = {
    "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None,
    "distributed.nanny.pre-spawn-environ.MALLOC_TOP_PAD_": str(64 * 2**20),
    "distributed.worker.profile.enabled": False,
}


@contextlib.contextmanager
def _without_ctrl_c():
    """SIGINT ignored meanwhile (call it from the main thread): processes started here inherit the
    ignored signal, so that a Ctrl-C to the process group stops only this process (which then
    closes the cluster), not every worker with a traceback of its own. A Ctrl-C in the seconds the
    workers take to start is not seen."""
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def local_cluster(workers: int):
    """A LocalCluster of ``workers`` processes, one thread each, quiet, dashboard on a free port;
    its processes ignore Ctrl-C (see :func:`_without_ctrl_c`)."""
    import logging

    import dask
    from distributed import LocalCluster

    with dask.config.set(LOCAL_CLUSTER_CONFIG), _without_ctrl_c():
        return LocalCluster(
            n_workers=workers,
            threads_per_worker=1,
            processes=True,
            dashboard_address=":0",
            silence_logs=logging.ERROR,
        )


def connect(address: str, option: str):
    """A ``distributed.Client`` of the scheduler at ``address`` (Dask parses it); one line if the
    address is malformed or the scheduler cannot be reached."""
    from distributed import Client
    from distributed.comm.addressing import get_address_host_port, parse_address
    from distributed.comm.registry import get_backend

    address = address.strip()
    try:
        # Dask's own parser first: a malformed address is refused at once, before a Client starts
        # its event loop (which, on a loaded machine, can take longer than Dask waits for it)
        scheme, _ = parse_address(address, strict=True)
        get_backend(scheme)  # an unknown scheme
        if scheme in ("tcp", "tls") and not 0 < get_address_host_port(address)[1] < 65536:
            raise ValueError("the port is not between 1 and 65535")
        return Client(address, timeout=CONNECT_TIMEOUT)
    except ValueError as exc:
        raise SweepError(
            f"{option} {address!r}: expected a scheduler address like tcp://host:8786 ({one_line(exc)})"
        ) from None
    except (OSError, TimeoutError) as exc:
        raise SweepError(f"{option} {address}: cannot reach the scheduler ({one_line(exc)})") from None


def _lost(exc: Exception) -> dict:
    """The outcome of a task the cluster lost (its setup failed, its worker died)."""
    return {"figures": {}, SECONDS: float("nan"), ERROR: one_line(f"{type(exc).__name__}: {exc}")}


def outcomes(experiment, tasks: list[dict], context, need_setup: bool, client=None):
    """``(params, outcome)`` of each task as it finishes: in this process without ``client``,
    else on its cluster (:func:`_on_cluster`)."""
    if client is not None:
        yield from _on_cluster(experiment, tasks, context, need_setup, client)
        return
    context = experiment.setup() if need_setup else context
    for params in tasks:
        yield params, execute(experiment.run, params, context)


def _on_cluster(experiment, tasks: list[dict], context, need_setup: bool, client):
    """The tasks on ``client``'s cluster, :data:`CHUNK` at a time (``Client.map``,
    ``as_completed``); a task the cluster lost is an outcome with its error."""
    from distributed import as_completed

    if need_setup:
        context = client.submit(experiment.setup, pure=False)
    elif context is not None:
        [context] = client.scatter([context], broadcast=True)
    for start in range(0, len(tasks), CHUNK):
        chunk = tasks[start : start + CHUNK]
        futures = client.map(functools.partial(execute, experiment.run), chunk, context=context, pure=False)
        params_of = dict(zip(futures, chunk, strict=True))
        for future in as_completed(futures):
            try:
                outcome = future.result()
            except Exception as exc:  # the setup failed, or a worker died
                outcome = _lost(exc)
            params = params_of.pop(future)
            future.release()  # the scheduler forgets a finished task at once
            yield params, outcome


def start_client(stack: contextlib.ExitStack, client, workers: int, label: str):
    """The client that runs the missing tasks (None: in this process) and how the table names
    where they ran; a local cluster of ``workers`` processes is started when asked for."""
    if client is not None:
        label = label or f"Dask client {client.scheduler.address}"
        return client, f"{label}, {len(client.scheduler_info()['workers'])} workers"
    if workers == 1:
        return None, "serial, in this process"
    from distributed import Client

    client = stack.enter_context(Client(stack.enter_context(local_cluster(workers))))
    return client, f"Dask LocalCluster, {workers} worker processes"
