"""A grid of experiments (seeds x parameters x sequences), run in this process or on Dask.

One *task* is one point of the grid: a dict of JSON-able parameters (``seed`` among them where
the experiment draws random numbers) given to the experiment's ``run(params, context)``, which
returns a dict of figures. Each task draws its random numbers from its own parameters, never from
the worker it lands on, so a sweep gives the same figures serially and on any cluster.

Where tasks run
    ``workers=1`` and no scheduler: one after the other in this process. ``workers=N > 1``: a
    ``dask.distributed`` LocalCluster of N worker processes with one thread each. ``scheduler``
    (``tcp://host:8786``), or the ``DASK_SCHEDULER_ADDRESS`` environment variable when none is
    given: an existing Dask cluster, whose workers must have ``vo_lib`` installed. The tasks go
    to Dask with ``Client.map`` and come back with ``as_completed``; Dask reads the address.

What is written
    The output folder (rules of :mod:`vo_lib.outputs`: new, empty or written by this
    program; marker ``.vo_lib_output.json``) holds ``rows.jsonl``, one finished task per line,
    appended as each task finishes and keyed by a hash of the experiment's name and the task's
    parameters, and ``results.csv``, the table of the whole grid (one row per task: parameters,
    figures, wall seconds, error text; written by pandas), replaced atomically when the sweep ends
    or stops. Running the same sweep into the same folder again skips the rows already finished,
    so an interrupted sweep finishes only the missing ones; rows that failed are run again. The
    folder is locked while a sweep writes it (:func:`vo_lib.outputs.writing`).

A task that raises becomes a row with its error; the sweep goes on (:mod:`vo_lib.cli.tasks`).
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import sys
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from vo_lib.atomic import recover
from vo_lib.cli.tasks import (
    ERROR,
    SECONDS,
    SweepError,
    check_workers,
    connect,
    local_cluster,
    outcomes,
    plain,
    start_client,
)
from vo_lib.outputs import (
    OutputFolder,
    check_target,
    read_marker,
    write_atomic,
    writing,
)

__all__ = ["SweepError", "local_cluster"]

ROWS = "rows.jsonl"
TABLE = "results.csv"


@dataclass(frozen=True)
class Experiment:
    """What a sweep runs: ``run(params, context) -> {figure: number}`` once per task.

    ``setup()`` (optional) computes what every task shares (e.g. one visual-odometry run); it
    runs once per sweep, only when some task is still missing, on a worker when there is a
    cluster. ``name`` names the experiment in the folder's marker.
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


# --------------------------------------------------------------------------- the folder on disk


def open_folder(target, experiment: str, *, force: bool = False, inputs=()) -> Path:
    """The folder of ``experiment``'s sweep: resumed when it holds a sweep of the same experiment,
    otherwise created (or replaced, as the output rules allow) with an empty store."""
    target = Path(target)
    written_by = f"vo_lib sweep {experiment}"
    marker = read_marker(target) if target.is_dir() else None
    if marker is not None and marker.get("written_by") == written_by:
        recover(target)
        check_target(target, written_by=written_by, inputs=inputs, option="--out")
        return target
    with OutputFolder(target, written_by, force=force, inputs=inputs, option="--out") as out:
        (out.path / ROWS).touch()
        (out.path / TABLE).touch()
        return out.commit(experiment=experiment)


def read_rows(path: Path) -> dict[str, dict]:
    """The stored rows by key, the last one of a key winning; a line cut short by a kill is
    skipped."""
    rows = {}
    for line in path.read_text(encoding="utf-8", errors="replace").splitlines():
        with contextlib.suppress(ValueError, KeyError, TypeError):
            row = json.loads(line)
            rows[row["key"]] = row
    return rows


def results_table(rows: list[dict]):
    """The table of stored ``rows`` (a pandas DataFrame): parameters first, then figures, seconds
    and error; lists and dicts as JSON text, Python numbers as they are (all digits in the CSV)."""
    import pandas as pd

    cells = [{**r["params"], **r["figures"]} for r in rows]
    frame = pd.DataFrame(
        [
            {k: json.dumps(v) if isinstance(v, list | dict) else v for k, v in c.items()}
            | {SECONDS: r[SECONDS], ERROR: r[ERROR]}
            for c, r in zip(cells, rows, strict=True)
        ],
        dtype=object,  # each number as it is: an int stays an int beside a failed row's blank
    )
    return frame.reindex(columns=[c for c in frame.columns if c not in (SECONDS, ERROR)] + [SECONDS, ERROR])


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
    tasks = [{k: plain(v) for k, v in t.items()} for t in tasks]
    keys = [task_key(experiment.name, t) for t in tasks]
    if len(set(keys)) != len(keys):
        raise SweepError("the sweep repeats a task (two identical parameter sets)")
    option = "--scheduler" if scheduler is not None else "DASK_SCHEDULER_ADDRESS"
    address = scheduler if scheduler is not None else os.environ.get("DASK_SCHEDULER_ADDRESS") or None
    workers = check_workers(workers, local=client is None and address is None)
    with contextlib.ExitStack() as stack:
        label = ""
        if client is None and address is not None:  # reach it before anything is written
            client = stack.enter_context(connect(address, option))
            label = f"Dask scheduler {address.strip()}"
        folder = open_folder(out, experiment.name, force=force, inputs=inputs)
        stack.enter_context(writing(folder, option="--out"))  # one sweep at a time writes it
        done = {k: r for k, r in read_rows(folder / ROWS).items() if not r.get(ERROR)}
        todo = [t for t, k in zip(tasks, keys, strict=True) if k not in done]
        result = SweepResult(experiment.name, [], reused=[k for k in keys if k in done], path=folder / TABLE)
        try:
            if todo:
                client, result.workers = start_client(stack, client, workers, label)
                need_setup = context is None and experiment.setup is not None
                found = outcomes(experiment, todo, context, need_setup, client)
                _store(found, experiment.name, folder / ROWS, done, result, progress, len(keys))
        except OSError as exc:  # a full disk: say what is kept, read back from the store
            raise _kept(folder, exc) from None
        finally:
            result.rows = [done[k] for k in keys if k in done]
            try:
                write_atomic(
                    folder / TABLE, results_table(result.rows).to_csv(index=False, lineterminator="\n")
                )
            except OSError as exc:
                raise _kept(folder, exc) from None
    return result


def _kept(folder: Path, exc: OSError) -> SweepError:
    """What a sweep stopped by ``exc`` (a full disk) keeps: the finished rows its store holds."""
    why = (exc.strerror or str(exc)).lower()  # "no space left on device"
    kept = sum(not r.get(ERROR) for r in read_rows(folder / ROWS).values())
    return SweepError(
        f"--out {folder}: {why}; {kept} finished row(s) are kept in {ROWS}, and a run of the same "
        f"sweep resumes from them"
    )


def _store(found, name: str, path: Path, done: dict, result: SweepResult, progress, total: int) -> None:
    """Append each finished row of ``found`` to the store ``path`` at once (one flushed line),
    recording it in ``done`` and ``result.ran``; a bar on stderr counts them against the grid."""
    from tqdm import tqdm

    show = sys.stderr.isatty() if progress is None else progress
    with (
        open(path, "a", encoding="utf-8") as store,
        tqdm(
            total=total, initial=len(result.reused), desc=f"sweep {name}", unit="run", disable=not show
        ) as bar,
    ):
        if store.tell() and not path.read_bytes().endswith(b"\n"):  # a line cut short by a kill
            store.write("\n")
        for params, outcome in found:
            key = task_key(name, params)
            row = {"key": key, "params": params, **outcome}
            store.write(json.dumps(row) + "\n")
            store.flush()
            os.fsync(store.fileno())
            done[key] = row
            result.ran.append(key)
            bar.update()
            if outcome[ERROR]:
                bar.write(f"failed: {params}: {outcome[ERROR]}", file=sys.stderr)


# --------------------------------------------------------------------------- the aggregate table


def aggregate(rows: list[dict], over: str = "seed"):
    """Mean, standard deviation and count of every numeric figure over ``over`` (successful rows,
    finite values) per combination of the other parameters: a pandas DataFrame with one row per
    combination (``name=value, ...``, in the order first met) and columns ``(statistic, figure)``
    for the statistics ``mean``, ``std`` and ``n``."""
    import pandas as pd

    ok = [r for r in rows if not r.get(ERROR)]
    if not ok:
        return pd.DataFrame()
    figures = pd.DataFrame([r["figures"] for r in ok]).select_dtypes("number")
    figures = figures.replace([np.inf, -np.inf], np.nan)
    group = pd.Series(
        [", ".join(f"{k}={v}" for k, v in r["params"].items() if k != over) for r in ok], name="group"
    )
    by = figures.groupby(group, sort=False)
    return pd.concat({"mean": by.mean(), "std": by.std(ddof=0), "n": by.count()}, axis=1)


def print_aggregate(result: SweepResult, over: str = "seed", digits: int = 4) -> None:
    """Print mean +- std over ``over`` of every figure, one column per other parameter set."""
    import pandas as pd

    failed = result.failed
    print(
        f"\n{result.experiment}: {len(result.rows)} rows ({len(result.ran)} run now, "
        f"{len(result.reused)} from earlier runs{f', {len(failed)} failed' if failed else ''}); "
        f"mean ± std over {over}s"
    )
    stats = aggregate(result.rows, over)
    if stats.empty:
        print("  no successful row")
    else:
        figures = stats["n"].columns
        cells = {
            group or "-": [
                f"{s['mean'][f]:.{digits}g} ± {s['std'][f]:.{digits}g} (n={s['n'][f]:.0f})" for f in figures
            ]
            for group, s in stats.iterrows()
        }
        table = pd.DataFrame(cells, index=figures)
        print("  " + table.to_string().replace("\n", "\n  "))
    for row in failed[:5]:
        print(f"  failed {row['params']}: {row[ERROR]}")
    if len(failed) > 5:
        print(f"  ... and {len(failed) - 5} more failed rows (see {result.path})")
