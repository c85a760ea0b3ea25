"""Sweeps (vo_lib.cli.sweep): the same figures serially and on a 2-worker Dask LocalCluster, a
re-run finishes only the missing rows, a failing task is a row, the folder follows the output
rules, command-line errors are one line; evaluate-all on the real sequence."""

from __future__ import annotations

import csv
import json
import os
import sys
from pathlib import Path

import cloudpickle
import numpy as np
import pytest

from vo_lib.cli import sweep
from vo_lib.cli import tasks as task_engine
from vo_lib.cli.evaluate_all import find_sequences
from vo_lib.cli.experiments import LAP, NEES, lap_tasks, nees_tasks
from vo_lib.cli.main import main
from vo_lib.cli.sweep import (
    ROWS,
    TABLE,
    Experiment,
    SweepError,
    aggregate,
    local_cluster,
    run_sweep,
    task_key,
)

REAL = Path(os.environ.get("VO_LIB_REALDATA") or Path(__file__).resolve().parents[2] / "shared" / "realdata")

# the toy tasks below travel to the workers by value (the test module is not importable there)
cloudpickle.register_pickle_by_value(sys.modules[__name__])


@pytest.fixture(scope="module")
def client():
    """One 2-worker LocalCluster for the module (starting one costs seconds)."""
    from distributed import Client

    cluster = local_cluster(2)
    c = Client(cluster)
    yield c
    c.close()
    cluster.close()


def square(params, context=None):
    if params["seed"] == 2 and params.get("fail"):
        raise RuntimeError("seed 2 refuses")
    return {"square": params["seed"] ** 2, "offset": params["seed"] + (context or 0)}


TOY = Experiment("toy", square)


def figures(result):
    return [(r["params"], r["figures"]) for r in result.rows]


def test_same_figures_serially_and_on_the_cluster(tmp_path, client):
    for experiment, tasks in ((NEES, nees_tasks(4, steps=60)), (LAP, lap_tasks(2))):
        serial = run_sweep(experiment, tasks, tmp_path / f"{experiment.name}-serial", workers=1)
        dask = run_sweep(experiment, tasks, tmp_path / f"{experiment.name}-dask", client=client)
        assert dask.workers.startswith("Dask") and serial.workers.startswith("serial")
        assert not serial.failed and not dask.failed
        assert figures(serial) == figures(dask)  # exactly, not approximately
        assert [r["params"]["seed"] for r in dask.rows] == [t["seed"] for t in tasks]  # grid order


def test_rerun_finishes_only_the_missing_rows(tmp_path, client, monkeypatch):
    tasks = [{"seed": s} for s in range(5)]
    out = tmp_path / "toy"
    first = run_sweep(TOY, tasks[:2], out, workers=1)  # the sweep "interrupted" after two rows
    assert len(first.ran) == 2
    with open(out / ROWS, "a") as fh:  # and a row cut short by a kill
        fh.write('{"key": "abc", "params": {"se')
    monkeypatch.setattr(task_engine, "CHUNK", 2)  # the three missing tasks go to the cluster as 2 + 1
    again = run_sweep(TOY, tasks, out, client=client)
    keys = [task_key("toy", t) for t in tasks]
    assert sorted(again.ran) == sorted(keys[2:]) and again.reused == keys[:2]
    assert [r["figures"]["square"] for r in again.rows] == [0, 1, 4, 9, 16]
    with open(out / TABLE, newline="") as fh:
        table = list(csv.DictReader(fh))
    assert [int(r["seed"]) for r in table] == list(range(5))
    assert [float(r["square"]) for r in table] == [0, 1, 4, 9, 16]
    assert all(float(r["seconds"]) >= 0 and r["error"] == "" for r in table)
    nothing = run_sweep(TOY, tasks, out, workers=2)  # all done: no cluster is even started
    assert nothing.ran == [] and len(nothing.reused) == 5 and nothing.workers == ""
    marker = json.loads((out / ".vo_lib_output.json").read_text())
    assert marker["written_by"] == "vo_lib sweep toy" and set(marker["contents"]) == {ROWS, TABLE}
    assert sorted(p.name for p in out.iterdir()) == sorted([".vo_lib_output.json", ROWS, TABLE])


def test_a_failing_task_is_a_row_and_runs_again(tmp_path, client):
    tasks = [{"seed": s, "fail": True} for s in range(4)]
    for where, kw in (("serial", {"workers": 1}), ("dask", {"client": client})):
        result = run_sweep(TOY, tasks, tmp_path / where, context=10, **kw)
        assert len(result.rows) == 4 and len(result.failed) == 1
        bad = result.failed[0]
        assert bad["params"]["seed"] == 2 and bad["error"].startswith("RuntimeError: seed 2 refuses")
        assert [r["figures"].get("offset") for r in result.rows] == [10, 11, None, 13]
        with open(tmp_path / where / TABLE, newline="") as fh:  # whole numbers stay whole beside a blank
            assert [r["offset"] for r in csv.DictReader(fh)] == ["10", "11", "", "13"]
        again = run_sweep(TOY, tasks, tmp_path / where, workers=1, context=10)
        assert again.ran == [task_key("toy", tasks[2])] and len(again.failed) == 1


def test_folder_rules(tmp_path):
    foreign = tmp_path / "mine"
    foreign.mkdir()
    (foreign / "notes.txt").write_text("keep me")
    with pytest.raises(ValueError, match="not written by this program"):
        run_sweep(TOY, [{"seed": 0}], foreign, workers=1)
    assert sorted(p.name for p in foreign.iterdir()) == ["notes.txt"]
    run_sweep(TOY, [{"seed": 0}], tmp_path / "toy", workers=1)
    other = Experiment("other", square)
    with pytest.raises(ValueError, match="holds the output of `vo_lib sweep toy`"):
        run_sweep(other, [{"seed": 0}], tmp_path / "toy", workers=1)
    with pytest.raises(SweepError, match="repeats a task"):
        run_sweep(TOY, [{"seed": 0}, {"seed": 0}], tmp_path / "twice", workers=1)
    from vo_lib.outputs import writing

    with writing(tmp_path / "toy"), pytest.raises(ValueError, match="a running command is writing to"):
        run_sweep(TOY, [{"seed": 1}], tmp_path / "toy", workers=1)  # another sweep holds the folder
    assert not (tmp_path / "twice").exists()


@pytest.mark.parametrize("bad", ["nonsense", "tcp://host", "http://host:80/x", "tcp://host:99999", "a b:5"])
def test_a_malformed_scheduler_address_is_one_line_and_writes_nothing(bad, tmp_path, monkeypatch):
    """Dask reads the address (--scheduler, or DASK_SCHEDULER_ADDRESS when none is given)."""
    monkeypatch.delenv("DASK_SCHEDULER_ADDRESS", raising=False)
    with pytest.raises(SweepError, match=f"--scheduler '{bad}': expected a scheduler address like tcp"):
        run_sweep(TOY, [{"seed": 0}], tmp_path / "out", scheduler=bad)
    monkeypatch.setenv("DASK_SCHEDULER_ADDRESS", bad)
    with pytest.raises(SweepError, match=f"DASK_SCHEDULER_ADDRESS '{bad}': expected a scheduler address"):
        run_sweep(TOY, [{"seed": 0}], tmp_path / "out", workers=1)
    assert list(tmp_path.iterdir()) == []


def test_the_aggregate_groups_the_other_parameters_and_skips_failed_rows(tmp_path):
    tasks = [{"size": size, "seed": s, "fail": True} for size in (10, 20) for s in range(4)]
    result = run_sweep(TOY, tasks, tmp_path / "toy", workers=1, context=0)
    stats = aggregate(result.rows)
    assert list(stats.index) == ["size=10, fail=True", "size=20, fail=True"]
    # seeds 0, 1, 3 (seed 2 fails): squares 0, 1, 9
    assert stats["mean"]["square"].tolist() == pytest.approx([10 / 3] * 2)
    assert stats["std"]["square"].tolist() == pytest.approx([np.std([0, 1, 9])] * 2)
    assert stats["n"]["square"].tolist() == [3, 3]


@pytest.mark.parametrize(
    "argv, message",
    [
        (["sweep", "lap", "--seeds", "0"], "--seeds: expected a whole number from 1 to 100000 (seeds)"),
        (["sweep", "lap", "--seeds", "x"], "--seeds: expected a whole number (seeds)"),
        (["sweep", "nees", "--seeds", "1000000000000", "--workers", "1"], "from 1 to 100000 (seeds)"),
        (["sweep", "lap", "--workers", "0"], "--workers: expected a whole number from 1 to 1024"),
        (["sweep", "nees", "--workers", "99999"], "--workers: expected a whole number from 1 to 1024"),
        (["sweep", "nees", "--workers", "1000", "--seeds", "2"], "--workers 1000: this machine gives"),
        (["sweep", "lap", "--scheduler", "not an address"], "expected a scheduler address"),
        (["sweep", "nothing"], "invalid choice"),
        (["evaluate-all", "no/such/folder"], "folder not found"),
        (
            ["sweep", "nees", "--seeds", "2", "--scheduler", "tcp://127.0.0.1:1", "--out", "X"],
            "--scheduler tcp://127.0.0.1:1: cannot reach the scheduler",
        ),
    ],
)
def test_command_line_errors(argv, message, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("DASK_SCHEDULER_ADDRESS", raising=False)
    try:
        status = main(argv)
    except SystemExit as exc:  # argparse's own errors
        status = exc.code
    assert status == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1
    assert list(tmp_path.iterdir()) == []  # nothing written


def test_sweep_command_prints_the_aggregate(tmp_path, capsys):
    assert main(["sweep", "nees", "--seeds", "3", "--workers", "1", "--out", str(tmp_path / "n")]) == 0
    out = capsys.readouterr().out
    assert "nees_mean" in out and "±" in out and "NEES averaged over 3 runs" in out
    assert len(list(csv.DictReader(open(tmp_path / "n" / TABLE)))) == 3


def test_find_sequences(tmp_path):
    for name in ("sequences/00", "sequences/10", "sequences/02", ".hidden/x", "other/deep/seq"):
        (tmp_path / name / "image_0").mkdir(parents=True)
    (tmp_path / "sequences/00/image_0/inner/image_0").mkdir(parents=True)  # inside a sequence: not one
    found = [p.relative_to(tmp_path).as_posix() for p in find_sequences(tmp_path)]
    assert found == ["other/deep/seq", "sequences/00", "sequences/02", "sequences/10"]
    assert find_sequences(tmp_path / "sequences/02") == [tmp_path / "sequences/02"]


@pytest.mark.skipif(not REAL.is_dir(), reason=f"real data not found at {REAL} (see DESIGN.md, Real data)")
def test_evaluate_all_on_the_real_sequence(tmp_path, capsys):
    out = tmp_path / "ev"
    assert main(["evaluate-all", str(REAL), "--frames", "30", "--workers", "1", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    rows = list(csv.DictReader(open(out / TABLE)))
    assert [r["sequence"] for r in rows] == ["kitti_raw_2011_09_26_drive_0001"]
    row = rows[0]
    assert row["error"] == "" and row["lengths"] == "short" and int(row["segments"]) > 0
    assert 0 < float(row["t_pct"]) < 3 and 0 <= float(row["r_deg_100m"]) < 3
    assert "overall" in text and "short 25/50/100 m" in text


def test_evaluate_all_fails_when_a_sequence_fails(tmp_path, capsys, monkeypatch):
    """Every sequence failing (here: no images) is an exit status 2 and one line saying how many."""
    monkeypatch.chdir(tmp_path)
    for name in ("a", "b"):
        (tmp_path / "root" / name / "image_0").mkdir(parents=True)
    assert main(["evaluate-all", "root", "--workers", "1", "--out", "ev"]) == 2
    captured = capsys.readouterr()
    assert "failed" in captured.out
    *each, last = captured.err.strip().splitlines()  # each failure as it happens, then the count
    assert len(each) == 2 and all(line.startswith("failed: ") for line in each)
    assert last.startswith("python -m vo_lib evaluate-all: error: 2 of 2 sequence(s) failed")


def test_evaluate_all_refuses_figures_of_a_sequence_changed_while_read(tmp_path, capsys, monkeypatch):
    """A frame rewritten while the pipeline reads the sequence: no figure, exit 2; a sequence
    replaced by `generate` meanwhile is refused by the reader's lock; the next sweep runs it anew."""
    from vo_lib.cli import evaluate_all
    from vo_lib.outputs import OutputError, OutputFolder

    monkeypatch.chdir(tmp_path)
    assert main(["generate", "corridor", "--frames", "3", "--resolution", "64x48", "--out", "root/s"]) == 0
    score, refusals = evaluate_all._score, []

    def rewrite_while_reading(params):
        figures = score(params)
        try:
            OutputFolder(params["path"], "vo_lib generate", force=True).discard()
        except OutputError as exc:
            refusals.append(str(exc))
        frame = Path(params["path"]) / "image_0" / "000001.png"
        frame.write_bytes((Path(params["path"]) / "image_0" / "000000.png").read_bytes())
        return figures

    monkeypatch.setattr(evaluate_all, "_score", rewrite_while_reading)
    assert main(["evaluate-all", "root", "--workers", "1", "--out", "ev"]) == 2
    captured = capsys.readouterr()
    assert "its files changed while it was read" in captured.out
    (row,) = csv.DictReader(open(tmp_path / "ev" / TABLE))
    assert "t_pct" not in row and "SequenceChanged" in row["error"]  # no figure of the mixed data
    assert refusals and "a running command is reading this folder" in refusals[0]
    monkeypatch.setattr(evaluate_all, "_score", score)
    assert main(["evaluate-all", "root", "--workers", "1", "--out", "ev"]) == 0
    rows = list(csv.DictReader(open(tmp_path / "ev" / TABLE)))
    assert (
        len(rows) == 1 and rows[0]["error"] == "" and rows[0]["snapshot"] == evaluate_all.snapshot("root/s")
    )


def test_a_full_disk_says_which_rows_are_kept(tmp_path, capsys, monkeypatch):
    """No space left after two rows: one line saying two rows are kept, and the next run
    resumes from them."""
    import errno

    real_dumps, written = json.dumps, []

    def full_after_two(obj, *args, **kwargs):
        if isinstance(obj, dict) and "key" in obj:  # a row of the store
            if len(written) == 2:
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
            written.append(obj)
        return real_dumps(obj, *args, **kwargs)

    monkeypatch.setattr(sweep.json, "dumps", full_after_two)
    argv = ["sweep", "nees", "--seeds", "4", "--workers", "1", "--out", str(tmp_path / "n")]
    assert main(argv) == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert "no space left on device; 2 finished row(s) are kept in rows.jsonl" in line
    monkeypatch.setattr(sweep.json, "dumps", real_dumps)
    assert main(argv) == 0
    assert "(2 run now, 2 from earlier runs)" in capsys.readouterr().out


def test_ctrl_c_to_the_process_group_of_a_dask_sweep_prints_one_line(tmp_path):
    """Ctrl-C in a terminal reaches every process of the group: the workers ignore it, the
    sweep closes them and prints one line; the rows it finished are kept."""
    import signal
    import subprocess
    import time

    proc = subprocess.Popen(
        [sys.executable, "-m", "vo_lib", "sweep", "nees", "--seeds", "2000", "--workers", "2", "--out", "X"],
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    rows, end = tmp_path / "X" / ROWS, time.monotonic() + 120
    while time.monotonic() < end and proc.poll() is None and not (rows.exists() and rows.stat().st_size):
        time.sleep(0.2)
    os.killpg(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130 and err.strip().splitlines() == [
        "python -m vo_lib sweep: interrupted (Ctrl-C); nothing half-written is left"
    ], err
    assert len(sweep.read_rows(rows)) >= 1
