"""A grid of experiments (seeds x parameters x sequences), run in this process or on Dask.

One *task* is one point of the grid: a dict of JSON-able parameters (``seed`` among them where
the experiment draws random numbers) given to the experiment's ``run(params, context)``, which
returns a dict of figures. Each task draws its random numbers from its own parameters, never from
the worker it lands on, so a sweep gives the same figures serially and on any cluster.

Where tasks run
    ``workers=1`` and no scheduler: one after the other in this process. ``workers=N > 1``: a
    ``dask.distributed`` LocalCluster of N worker processes with one thread each. ``scheduler``
    (``tcp://host:8786``), or the ``DASK_SCHEDULER_ADDRESS`` environment variable when none is
    given: an existing Dask cluster, whose workers must have ``vo_lib`` installed.

What is written
    The output folder (rules of :mod:`vo_lib.outputs`: new, empty or written by this
    program; marker ``.vo_lib_output.json``) holds ``rows.jsonl``, one finished task per line,
    appended as each task finishes and keyed by a hash of the experiment's name and the task's
    parameters, and ``results.csv``, the table of the whole grid (one row per task: parameters,
    figures, wall seconds, error text), replaced atomically when the sweep ends or stops. Running
    the same sweep into the same folder again skips the rows already finished, so an interrupted
    sweep finishes only the missing ones; rows that failed are run again.

A task that raises becomes a row with its error; the sweep goes on.
"""

from __future__ import annotations

import csv
import hashlib
import io
import itertools
import json
import math
import os
import sys
import time
import traceback
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from vo_lib.arguments import one_line
from vo_lib.outputs import (
    OutputFolder,
    check_target,
    read_marker,
    remove_stale_temporaries,
    write_atomic,
)

ROWS = "rows.jsonl"
TABLE = "results.csv"
#: Columns every row has after its parameters and figures.
SECONDS, ERROR = "seconds", "error"
#: Fewest tasks kept in flight on a cluster (four per worker when there are more workers).
SUBMIT_WINDOW = 64
#: Seconds allowed to reach an existing scheduler.
CONNECT_TIMEOUT = 10.0


class SweepError(ValueError):
    """A bad argument or folder for a sweep: reported in one line, exit status 2."""


@dataclass(frozen=True)
class Experiment:
    """What a sweep runs: ``run(params, context) -> {figure: number}`` once per task.

    ``setup()`` (optional) computes what every task shares (e.g. one visual-odometry run); it
    runs once per sweep, only when some task is still missing, on a worker when there is a
    cluster. ``written_by`` names the experiment in the folder's marker.
    """

    name: str
    run: Callable[[dict, object], dict]
    setup: Callable[[], object] | None = None
    describe: str = ""


@dataclass
class SweepResult:
    """The rows of the grid in grid order, and which keys ran now (the others came from disk)."""

    experiment: str
    rows: list[dict]
    ran: list[str] = field(default_factory=list)
    reused: list[str] = field(default_factory=list)
    path: Path | None = None
    workers: str = ""

    @property
    def failed(self) -> list[dict]:
        return [r for r in self.rows if r.get(ERROR)]


def task_key(experiment: str, params: dict) -> str:
    """The key of a task on disk: a hash of the experiment's name and its parameters."""
    text = json.dumps({"experiment": experiment, "params": params}, sort_keys=True, separators=(",", ":"))
    return hashlib.sha1(text.encode()).hexdigest()[:16]


def grid(**axes) -> list[dict]:
    """Every combination of the given axes, in order (the first axis varies slowest)::

    grid(resolution=["640x480", "320x240"], seed=range(3))  # 6 tasks
    """
    tasks: list[dict] = [{}]
    for name, values in axes.items():
        tasks = [{**t, name: _plain(v)} for t in tasks for v in values]
    return tasks


def _plain(value):
    """A parameter as JSON sees it (NumPy numbers and tuples become Python numbers and lists)."""
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, tuple):
        return [_plain(v) for v in value]
    return value


def execute(run: Callable[[dict, object], dict], params: dict, context=None) -> dict:
    """Run one task: ``{"figures": ..., "seconds": wall time, "error": "" or one line}``."""
    t0 = time.perf_counter()
    try:
        figures = {str(k): _plain(v) for k, v in dict(run(params, context)).items()}
        error = ""
    except Exception as exc:  # a failed run is a row, not a lost sweep
        figures = {}
        where = traceback.extract_tb(exc.__traceback__)[-1]
        error = one_line(f"{type(exc).__name__}: {exc} ({Path(where.filename).name}:{where.lineno})")
    return {"figures": figures, SECONDS: time.perf_counter() - t0, ERROR: error}


# --------------------------------------------------------------------------- the folder on disk


class SweepFolder:
    """The folder of one experiment's sweep: opened (created, or resumed when it holds a sweep of
    the same experiment), appended to row by row, its table replaced at the end."""

    def __init__(self, target, experiment: str, *, force: bool = False, inputs=(), option="--out"):
        self.target = Path(target)
        self.experiment = experiment
        self.written_by = f"vo_lib sweep {experiment}"
        marker = read_marker(self.target) if self.target.is_dir() else None
        if marker is not None and marker.get("written_by") == self.written_by:  # resume it
            remove_stale_temporaries(self.target)
            check_target(self.target, written_by=self.written_by, inputs=inputs, option=option)
        else:  # anything else is replaced only as the output rules allow
            with OutputFolder(self.target, self.written_by, force=force, inputs=inputs, option=option) as out:
                (out.path / ROWS).touch()
                (out.path / TABLE).touch()
                out.commit(experiment=experiment)
        self.path = self.target
        self._lock()

    def _lock(self) -> None:
        """Hold an exclusive lock on the rows file: two sweeps never write one folder at once."""
        self._fh = open(self.path / ROWS, "a+b")  # noqa: SIM115 (held for the sweep's life)
        try:
            import fcntl
        except ImportError:  # Windows: no advisory lock
            return
        try:
            fcntl.flock(self._fh.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            self._fh.close()
            raise SweepError(f"{self.target}: another sweep is writing to this folder") from None

    def close(self) -> None:
        self._fh.close()

    def finished(self) -> dict[str, dict]:
        """The rows on disk by key, the last one of a key winning; a line cut short by a kill is
        ignored."""
        rows = {}
        self._fh.seek(0)
        for line in self._fh.read().decode("utf-8", "replace").splitlines():
            try:
                row = json.loads(line)
                rows[row["key"]] = row
            except (ValueError, KeyError, TypeError):
                continue
        return rows

    def append(self, row: dict) -> None:
        """Add one finished row: one write of one line, flushed to disk."""
        self._fh.seek(0, os.SEEK_END)
        size = self._fh.tell()
        prefix = b""
        if size:
            self._fh.seek(size - 1)
            if self._fh.read(1) != b"\n":  # the cut-short line of a killed sweep stays apart
                prefix = b"\n"
        self._fh.write(prefix + (json.dumps(row) + "\n").encode())
        self._fh.flush()
        os.fsync(self._fh.fileno())

    def write_table(self, rows: list[dict]) -> Path:
        write_atomic(self.path / TABLE, table_csv(rows))
        return self.path / TABLE


def flatten(row: dict) -> dict:
    """A stored row as one table row: parameters, figures, seconds, error."""
    return {**row["params"], **row["figures"], SECONDS: row[SECONDS], ERROR: row[ERROR]}


def table_csv(rows: list[dict]) -> str:
    """The CSV text of ``rows`` (stored rows): parameters first, then figures, seconds, error."""
    params, figures = [], []
    for row in rows:
        params += [k for k in row["params"] if k not in params]
        figures += [k for k in row["figures"] if k not in figures and k not in params]
    columns = params + figures + [SECONDS, ERROR]
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=columns, lineterminator="\n")
    writer.writeheader()
    for row in rows:
        flat = flatten(row)
        writer.writerow({k: _cell(flat.get(k, "")) for k in columns})
    return buffer.getvalue()


def _cell(value):
    if isinstance(value, float):
        return repr(value)  # all digits: the table reads back to the same numbers
    if isinstance(value, list | dict):
        return json.dumps(value)
    return value


# --------------------------------------------------------------------------- where tasks run


def scheduler_address(given: str | None) -> str | None:
    """The scheduler to use: ``given``, else ``DASK_SCHEDULER_ADDRESS``, else None (local).

    Read by Dask's own address parser (``distributed.comm.addressing``): a scheme Dask knows
    (``tcp://`` when none is given), a host and a port in 1..65535; anything else is one line."""
    from distributed.comm.addressing import parse_address, parse_host_port, unparse_address
    from distributed.comm.registry import backends

    address = given if given is not None else os.environ.get("DASK_SCHEDULER_ADDRESS") or None
    if address is None:
        return None
    option = "--scheduler" if given is not None else "DASK_SCHEDULER_ADDRESS"
    try:
        scheme, location = parse_address(address.strip())
        _, port = parse_host_port(location)
        if scheme not in backends or not 0 < port < 65536 or any(c.isspace() for c in location):
            raise ValueError(address)
    except (ValueError, TypeError):
        raise SweepError(f"{option} {address!r}: expected a scheduler address like tcp://host:8786") from None
    return unparse_address(scheme, location)


def default_workers() -> int:
    """One worker per core this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:
        return max(1, os.cpu_count() or 1)


#: Local worker processes allowed per core: more only share the cores and multiply the memory.
WORKERS_PER_CORE = 4


def _check_workers(workers: int | None, local: bool) -> int:
    """``workers`` (default: one per core), refused in one line if below 1 or, for a local
    cluster, above :data:`WORKERS_PER_CORE` per core."""
    cores = default_workers()
    workers = cores if workers is None else int(workers)
    if workers < 1:
        raise SweepError(f"--workers {workers}: expected at least 1")
    if local and workers > WORKERS_PER_CORE * cores:
        raise SweepError(
            f"--workers {workers}: this machine gives this process {cores} core(s); at most "
            f"{WORKERS_PER_CORE * cores} local workers (--scheduler ADDRESS runs on a cluster)"
        )
    return workers


class _Serial:
    """Tasks one after the other in this process."""

    label = "serial, in this process"

    def run(self, experiment: Experiment, tasks: list[dict], context, need_setup: bool):
        if need_setup:
            context = experiment.setup()
        for params in tasks:
            yield params, execute(experiment.run, params, context)

    def close(self):
        pass


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


def local_cluster(workers: int):
    """A LocalCluster of ``workers`` processes, one thread each, quiet, dashboard on a free port."""
    import logging

    import dask
    from distributed import LocalCluster

    with dask.config.set(LOCAL_CLUSTER_CONFIG):
        return LocalCluster(
            n_workers=workers,
            threads_per_worker=1,
            processes=True,
            dashboard_address=":0",
            silence_logs=logging.ERROR,
        )


class _Dask:
    """Tasks on a dask.distributed cluster: a new LocalCluster, or an existing scheduler."""

    def __init__(self, workers: int, address: str | None, client=None):
        from distributed import Client

        self.cluster = None
        self.owned = client is None
        if client is not None:
            self.client = client
            self.label = (
                f"Dask client {client.scheduler.address}, {len(client.scheduler_info()['workers'])} workers"
            )
        elif address is None:
            self.cluster = local_cluster(workers)
            self.client = Client(self.cluster)
            self.label = f"Dask LocalCluster, {workers} worker processes"
        else:
            try:
                self.client = Client(address, timeout=CONNECT_TIMEOUT)
            except (OSError, TimeoutError) as exc:
                raise SweepError(
                    f"--scheduler {address}: cannot reach the scheduler ({one_line(exc)})"
                ) from None
            n = len(self.client.scheduler_info().get("workers", {}))
            self.label = f"Dask scheduler {address}, {n} workers"

    def run(self, experiment: Experiment, tasks: list[dict], context, need_setup: bool):
        from distributed import as_completed

        if need_setup:
            context = self.client.submit(experiment.setup, pure=False)
        elif context is not None:
            [context] = self.client.scatter([context], broadcast=True)
        futures: dict = {}

        def submit(params: dict):
            future = self.client.submit(execute, experiment.run, params, context, pure=False)
            futures[future] = params
            return future

        # a window of tasks in flight, topped up as they finish: the scheduler never holds the
        # whole grid (a million futures is gigabytes), and the first rows arrive at once
        pending = iter(tasks)
        window = max(SUBMIT_WINDOW, 4 * len(self.client.scheduler_info().get("workers", {})))
        running = as_completed([submit(params) for params in itertools.islice(pending, window)])
        for future in running:
            params = futures.pop(future)
            following = next(pending, None)
            if following is not None:
                running.add(submit(following))
            try:
                outcome = future.result()
            except Exception as exc:  # the setup failed, or a worker died
                outcome = {
                    "figures": {},
                    SECONDS: float("nan"),
                    ERROR: one_line(f"{type(exc).__name__}: {exc}"),
                }
            future.release()
            yield params, outcome

    def close(self):
        if self.owned:
            self.client.close()
        if self.cluster is not None:
            self.cluster.close()


def _run_missing(runner, experiment, todo, context, need_setup, folder, done, result, progress) -> None:
    """Run the tasks ``todo`` on ``runner``, each finished row appended to ``folder`` at once and
    recorded in ``done`` and ``result.ran``; a bar on stderr counts them against the whole grid."""
    from tqdm import tqdm

    total = len(result.reused) + len(todo)
    bar = tqdm(
        total=total,
        initial=len(result.reused),
        desc=f"sweep {experiment.name}",
        unit="run",
        disable=(not sys.stderr.isatty()) if progress is None else not progress,
        file=sys.stderr,
    )
    try:
        for params, outcome in runner.run(experiment, todo, context, need_setup):
            key = task_key(experiment.name, params)
            row = {"key": key, "params": params, **outcome}
            folder.append(row)
            done[key] = row
            result.ran.append(key)
            bar.update()
            if outcome[ERROR]:
                bar.write(f"failed: {params}: {outcome[ERROR]}", file=sys.stderr)
    finally:
        bar.close()


def run_sweep(
    experiment: Experiment,
    tasks: Sequence[dict],
    out,
    workers: int | None = None,
    scheduler: str | None = None,
    *,
    force: bool = False,
    inputs: Iterable = (),
    context=None,
    progress: bool | None = None,
    client=None,
) -> SweepResult:
    """Run every task of ``tasks`` not already finished in ``out``; returns all rows of the grid.

    ``context`` given: passed to every task instead of running ``experiment.setup``.
    ``progress``: a tqdm bar on stderr (default: when stderr is a terminal).
    ``client``: a ``distributed.Client`` to use (left open) instead of ``workers``/``scheduler``.
    """
    tasks = [{k: _plain(v) for k, v in t.items()} for t in tasks]
    keys = [task_key(experiment.name, t) for t in tasks]
    if len(set(keys)) != len(keys):
        raise SweepError("the sweep repeats a task (two identical parameter sets)")
    address = scheduler_address(scheduler)
    workers = _check_workers(workers, local=client is None and address is None)
    runner = None
    if client is None and address is not None:  # reach it before anything is written
        runner = _Dask(workers, address)
    try:
        folder = SweepFolder(out, experiment.name, force=force, inputs=inputs)
    except BaseException:
        if runner is not None:
            runner.close()
        raise
    result = SweepResult(experiment.name, [], path=folder.path / TABLE)
    done: dict[str, dict] = {}
    try:
        done = {k: r for k, r in folder.finished().items() if not r.get(ERROR)}
        todo = [t for t, k in zip(tasks, keys, strict=True) if k not in done]
        result.reused = [k for k in keys if k in done]
        if todo:
            if client is not None:
                runner = _Dask(workers, None, client)
            elif runner is None:
                runner = _Serial() if workers == 1 else _Dask(workers, None)
            result.workers = runner.label
            need_setup = context is None and experiment.setup is not None
            _run_missing(runner, experiment, todo, context, need_setup, folder, done, result, progress)
    finally:
        if runner is not None:
            runner.close()
        result.rows = [done[k] for k in keys if k in done]
        try:
            folder.write_table(result.rows)
        finally:
            folder.close()
    return result


# --------------------------------------------------------------------------- the aggregate table


def numeric_figures(rows: list[dict]) -> list[str]:
    names: list[str] = []
    for row in rows:
        for k, v in row["figures"].items():
            if k not in names and isinstance(v, int | float) and not isinstance(v, bool):
                names.append(k)
    return names


def aggregate(rows: list[dict], over: str = "seed") -> dict[tuple, dict[str, tuple[float, float, int]]]:
    """Mean, standard deviation and count of every numeric figure over ``over`` (successful rows),
    per combination of the other parameters: ``{group: {figure: (mean, std, n)}}``."""
    groups: dict[tuple, list[dict]] = {}
    for row in rows:
        if row.get(ERROR):
            continue
        group = tuple((k, json.dumps(v)) for k, v in row["params"].items() if k != over)
        groups.setdefault(group, []).append(row)
    out = {}
    for group, members in groups.items():
        stats = {}
        for name in numeric_figures(members):
            v = np.array([m["figures"].get(name, math.nan) for m in members], float)
            v = v[np.isfinite(v)]
            stats[name] = (float(v.mean()), float(v.std()), len(v)) if len(v) else (math.nan, math.nan, 0)
        out[group] = stats
    return out


def print_aggregate(result: SweepResult, over: str = "seed", digits: int = 4) -> None:
    """Print mean +- std over ``over`` of every figure, one column per other parameter set."""
    table = aggregate(result.rows, over)
    failed = len(result.failed)
    print(
        f"\n{result.experiment}: {len(result.rows)} rows ({len(result.ran)} run now, "
        f"{len(result.reused)} from earlier runs{f', {failed} failed' if failed else ''}); "
        f"mean ± std over {over}s"
    )
    if not table:
        print("  no successful row")
        return
    groups = list(table)
    width = 26
    if any(groups):
        header = "".join(
            f"{', '.join(f'{k}={json.loads(v)}' for k, v in g) or '-':>{width}s}" for g in groups
        )
        print(f"  {'figure':<24s}{header}")
    names = []
    for g in groups:
        names += [n for n in table[g] if n not in names]
    for name in names:
        cells = ""
        for g in groups:
            m, s, n = table[g].get(name, (math.nan, math.nan, 0))
            cells += f"{f'{m:.{digits}g} ± {s:.{digits}g} (n={n})':>{width}s}"
        print(f"  {name:<24s}{cells}")
    for row in result.failed[:5]:
        print(f"  failed {row['params']}: {row[ERROR]}")
    if failed > 5:
        print(f"  ... and {failed - 5} more failed rows (see {result.path})")
