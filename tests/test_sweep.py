"""Sweeps (vo_lib.cli.sweep): the same figures serially and on a 2-worker Dask LocalCluster, the
summary's statistics, the folder written whole, command-line errors in one line."""

from __future__ import annotations

import contextlib

import numpy as np
import pandas as pd
import pytest
from scipy.stats import t

from vo_lib.cli import sweep
from vo_lib.cli.main import main


@pytest.mark.parametrize("name", ["nees", "lap"])
def test_same_figures_serially_and_on_the_cluster(name):
    function, tasks = sweep.function_of(name), sweep.SWEEPS[name][1](3)
    serial = sweep.run_tasks(function, tasks, workers=1)
    assert serial == sweep.run_tasks(function, tasks, workers=2)
    assert [row["seed"] for row in serial] == [task["seed"] for task in tasks]
    assert len({tuple(row.values()) for row in serial}) == len(tasks)  # each seed draws its own


def test_every_sweep_names_a_function_that_takes_its_tasks():
    import inspect

    for name, (_, make_tasks, _) in sweep.SWEEPS.items():
        parameters = inspect.signature(sweep.function_of(name)).parameters
        assert all(set(task) <= set(parameters) for task in make_tasks(2)), name


def test_the_summary_groups_the_other_arguments():
    table = pd.DataFrame(
        [{"size": size, "seed": s, "square": s**2 * size} for size in (10, 20) for s in range(4)]
    )
    stats = sweep.summary(table, ["size", "seed"])
    ten = stats.loc[(10, "square")]
    assert ten["mean"] == pytest.approx(35.0) and ten["count"] == 4
    assert ten["std"] == pytest.approx(np.std([0, 10, 40, 90], ddof=1))
    half = t.ppf(0.975, 3) * ten["std"] / 2
    assert (ten["low"], ten["high"]) == pytest.approx((max(0, 35 - half), 35 + half))  # squares: >= 0
    assert stats.loc[(20, "square")]["mean"] == pytest.approx(70.0)
    # a figure never negative (an error, a NEES): its interval stops at 0; one that can be, does not
    skewed = pd.DataFrame({"seed": range(3), "nees": [0.1, 0.2, 30.0], "bias": [-0.1, 0.2, -30.0]})
    lows = sweep.summary(skewed, ["seed"])["low"]
    assert lows[("all", "nees")] == 0.0 and lows[("all", "bias")] < -30


def test_sweep_command_writes_its_table_and_prints_the_summary(tmp_path, capsys):
    assert main(["sweep", "nees", "--seeds", "3", "--workers", "1", "--out", str(tmp_path / "n")]) == 0
    out = capsys.readouterr().out
    assert "nees_mean" in out and "NEES averaged over 3 runs" in out
    table = pd.read_csv(tmp_path / "n" / "results.csv")
    assert table["seed"].tolist() == [1000, 1001, 1002] and {"nees_mean", "inside_95"} <= set(table)
    assert sorted(p.name for p in (tmp_path / "n").iterdir()) == [".vo_lib_output.json", "results.csv"]
    # one seed has no spread: its standard deviation and interval are undefined, not NaN
    assert main(["sweep", "nees", "--seeds", "1", "--workers", "1", "--out", str(tmp_path / "one")]) == 0
    out = capsys.readouterr().out
    assert "undefined" in out and "nan" not in out.lower().replace("nees_mean", ""), out


@pytest.mark.parametrize(
    "argv, message",
    [
        (["sweep", "lap", "--seeds", "0"], "--seeds: expected a whole number from 1 to 100000 (seeds)"),
        (["sweep", "lap", "--seeds", "x"], "--seeds: expected a whole number (seeds)"),
        (["sweep", "lap", "--workers", "0"], "--workers: expected a whole number from 1 to 1024"),
        (["sweep", "nees", "--workers", "1000", "--seeds", "2"], "--workers 1000: at most"),
        (["sweep", "nothing"], "invalid choice"),
        (["sweep", "lap", "--scheduler", "not an address", "--out", "X"], "cannot reach a scheduler"),
        (
            ["sweep", "nees", "--seeds", "2", "--scheduler", "tcp://127.0.0.1:1", "--out", "X"],
            "--scheduler tcp://127.0.0.1:1: cannot reach a scheduler",
        ),
    ],
)
def test_command_line_errors(argv, message, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    try:
        status = main(argv)
    except SystemExit as exc:  # argparse's own errors
        status = exc.code
    assert status == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1
    assert list(tmp_path.iterdir()) == []  # nothing written


@pytest.mark.parametrize(
    ("greeting", "message"),
    [
        (None, "no answer as a Dask scheduler within 1 s"),
        (b"SSH-2.0-OpenSSH_9.6\r\n", "not as a Dask scheduler"),
    ],
)
def test_a_scheduler_address_of_another_service_gets_one_line(
    greeting, message, capsys, tmp_path, monkeypatch
):
    """A server that accepts and stays silent (a dashboard's port) or talks first (SSH): one line."""
    import socket
    import threading

    monkeypatch.setattr(sweep, "SCHEDULER_SECONDS", 1)
    monkeypatch.chdir(tmp_path)
    server = socket.create_server(("127.0.0.1", 0))
    held = []

    def serve():
        with contextlib.suppress(OSError):
            while True:
                conn, _ = server.accept()
                held.append(conn)
                if greeting:
                    conn.sendall(greeting)

    threading.Thread(target=serve, daemon=True).start()
    address = f"tcp://127.0.0.1:{server.getsockname()[1]}"
    try:
        assert main(["sweep", "nees", "--seeds", "2", "--scheduler", address, "--out", "X"]) == 2
    finally:
        server.close()
    err = capsys.readouterr().err
    assert f"--scheduler {address}: cannot reach a scheduler" in err and message in err
    assert len(err.strip().splitlines()) == 1 and list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("seeds", ["2", "1"])
def test_lap_sweep_prints_the_papers_figures_beside_ours(seeds, tmp_path, capsys):
    assert main(["sweep", "lap", "--seeds", seeds, "--workers", "1", "--out", str(tmp_path / "l")]) == 0
    out = capsys.readouterr().out
    assert ("(95 % interval undefined)" in out) == (seeds == "1") and "nan" not in out.lower(), out
    assert "dead reckoning on" in out and f"of {seeds} lap" in out and "paper 54.4412" in out
    assert "final error: the feature-point form " in out and " the line form: " in out
    table = pd.read_csv(tmp_path / "l" / "results.csv")
    assert {"nees_above", "slam_closer", "extended_mapped_to", "line_form_error"} <= set(table)


def test_corridor_report_puts_table3_beside_ours(capsys):
    """The corridor's report on a made-up table: every Table III value of the paper, beside ours,
    and the T_s shares pooled over the seeds (not averaged per seed)."""
    from vo_lib.lidar_tracking.corridor_experiment import PAPER_TABLE3, STATISTICS, corridor_report

    row = {f"{m}_{a}_{k}": 0.5 for m in ("lbpt", "voapt") for a in "xy" for k in STATISTICS}
    table = pd.DataFrame(
        [
            {"seed": 0, **row, "lbpt_lost": 10, "lbpt_lost_flagged": 10, "voapt_unoccluded": 100},
            {"seed": 1, **row, "lbpt_lost": 0, "lbpt_lost_flagged": 0, "voapt_unoccluded": 100},
        ]
    ).assign(voapt_false_alarms=[0, 4])
    corridor_report(table, sweep.summary(table, ["seed"]).droplevel(0))
    out = capsys.readouterr().out
    for methods in PAPER_TABLE3.values():
        for paper in methods.values():
            assert all(f"0.500 m (0.500-0.500) [{v:.3f}]" in out for v in paper.values())
    assert "100.0 % of LBPT's updates" in out and "(10 of 10)" in out and "2.0 % of VOAPT's" in out
    # one seed: no interval, said in words
    corridor_report(table[:1], sweep.summary(table[:1], ["seed"]).droplevel(0))
    out = capsys.readouterr().out
    assert "0.500 m (undefined)" in out and "nan" not in out, out
