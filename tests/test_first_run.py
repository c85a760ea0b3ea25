"""A newcomer's first ``python -m vo_lib run``: it says at once what comes, shows progress when its
output goes to a file, and prints a timing table and a picture a student can read."""

from __future__ import annotations

import os
import re
import subprocess
import sys

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from vo_lib.stereo_vo.paper_tables import PAPER_TABLE1  # noqa: E402
from vo_lib.stereo_vo.pipeline import FrameTimings, PipelineResult  # noqa: E402
from vo_lib.stereo_vo.run_report import odometry_name, print_timing_table, timing_rows  # noqa: E402
from vo_lib.viz.run_figure import plot_run  # noqa: E402


def test_first_run_talks_at_once_and_shows_progress_when_piped(tmp_path):
    """A sample not rendered yet: the first line names the sample, its frames and the rendering to
    come; progress lines follow although stdout is a pipe, not a terminal."""
    env = dict(os.environ, VO_LIB_DATA=str(tmp_path / "data"), MPLBACKEND="Agg")
    command = [sys.executable, "-m", "vo_lib", "run", "--frames", "12", "--out", str(tmp_path / "out")]
    with open(tmp_path / "stderr", "w+", encoding="utf-8") as stderr:
        proc = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=stderr, text=True, env=env)
        first = proc.stdout.readline()
        # "at once", without a clock that a loaded machine would stretch: the line is out while the
        # run is still at work (its output folder appears only at the end), not flushed with the rest
        at_once = proc.poll() is None and not (tmp_path / "out").exists()
        # read on through the same buffer: communicate() would read the pipe beneath it and lose
        # lines that readline() had already buffered
        rest = proc.stdout.read()
        proc.wait(timeout=600)
        stderr.seek(0)
        assert proc.returncode == 0, stderr.read()
    assert at_once, "the first line came only when the run had finished"
    assert first.startswith("run: sample indoor_linear, 12 frames") and "rendered" in first
    assert re.search(r"about (\d+ to )?\d+ s", first), first  # how long the rendering will take
    lines = rest.splitlines()
    assert (
        lines[0]
        == "rendering indoor_linear: 12 frames (the first takes longest: the world's textures are built)"
    )
    assert any(line.startswith("rendering indoor_linear: 12/12 frames") for line in lines)
    assert "visual odometry on 12 frames ..." in lines
    assert not any(line.startswith("compiling") for line in lines) or any(
        line.startswith("compiled in") for line in lines
    ), "a compile notice comes with the time it took"


def _result(stages: dict[str, list[float]], extra: list[float]) -> PipelineResult:
    n = len(extra)
    timings = [FrameTimings()]  # the first frame: detection only, left out of the table
    for k in range(n):
        t = FrameTimings(**{name: values[k] for name, values in stages.items()})
        t.total = sum(values[k] for values in stages.values()) + extra[k]
        timings.append(t)
    return PipelineResult(np.zeros((n + 1, 3)), np.zeros((n + 1, 3, 3)), timings=timings)


class _Camera:
    def __init__(self, width, height):
        self.width, self.height = width, height


def test_timing_rows_add_up_to_the_whole_frame_and_name_mean_and_median(capsys):
    rng = np.random.default_rng(0)
    stages = {k: list(rng.uniform(0.1, 5.0, 50)) for k in ("stereo", "matching", "estimation", "kalman")}
    result = _result(stages, list(rng.uniform(0.0, 0.3, 50)))
    rows = timing_rows(result)
    whole = np.array([t.total for t in result.timings[1:]])
    np.testing.assert_allclose(sum(values for _, _, values in rows), whole)
    assert "refinement" not in [key for key, _, _ in rows]  # no 6-DoF stage on the crawler
    print_timing_table(result, _Camera(640, 480), 51)
    out = capsys.readouterr().out
    assert "median" in out and "mean" in out and "The means of the stages add up to the whole frame" in out
    assert f"{PAPER_TABLE1[(640, 480)]['stereo']:.3f}" in out and "paper's mean (Table 1, 640x480)" in out


def test_no_paper_column_where_the_paper_has_no_figure(capsys):
    rng = np.random.default_rng(1)
    stages = {k: list(rng.uniform(0.1, 5.0, 20)) for k in ("stereo", "matching", "estimation", "kalman")}
    print_timing_table(_result(stages, [0.1] * 20), _Camera(1242, 375), 21)
    out = capsys.readouterr().out
    assert "paper" not in out and "48.969" not in out


def test_odometry_is_named_for_what_it_is():
    class Vehicle:
        def __init__(self, kind, source):
            self.kind, self.odometry_source = kind, source

    assert odometry_name(Vehicle("crawler", "odometry.txt")) == "track odometry"
    assert odometry_name(Vehicle("car", "odometry.txt")) == "wheel odometry"
    assert odometry_name(Vehicle("car", "oxts.txt (speed and yaw rate)")) == "OXTS odometry"


def test_a_straight_drive_is_drawn_with_the_axis_across_it_scaled_to_the_drift():
    """Out and back along x with 6 cm of drift across: the y axis spans centimetres, not metres."""
    t = np.linspace(0.0, 10.0, 201)
    x = 2.0 * np.sin(np.pi * t / 10.0)
    truth = np.column_stack([x, np.zeros_like(t), np.zeros_like(t)])
    odometry = truth + np.column_stack([np.zeros_like(t), 0.06 * t / 10.0, np.zeros_like(t)])
    estimate = truth + np.column_stack([np.zeros_like(t), 0.004 * np.ones_like(t), np.zeros_like(t)])
    fig = plt.figure(figsize=(11, 5))
    try:
        main = plot_run(fig, t, estimate, truth, odometry, "straight", "track odometry")["main"]
        low, high = main.get_ylim()
        assert low <= 0.0 and high >= 0.06  # every path inside
        assert high - low < 0.1, (low, high)  # scaled to the 6 cm drift, not to the 2 m drive
        assert "not to scale" in main.get_ylabel()
    finally:
        plt.close(fig)


def test_help_gives_one_example_per_command_and_a_line_per_bench(capsys):
    """Plain text (no reST backticks), an example for each command, and each benchmark with what
    it times and how long it runs."""
    import pytest

    from vo_lib.bench import BENCH_HELP, BENCHES
    from vo_lib.cli.main import build_parser

    parser = build_parser()
    commands = ["run", "evaluate", "convert", "generate", "bench", "sweep"]
    texts = {}
    for argv in ([], *([c] for c in commands)):
        with pytest.raises(SystemExit):
            parser.parse_args([*argv, "--help"])
        texts[" ".join(argv)] = capsys.readouterr().out
    assert "``" not in "".join(texts.values())
    for command in commands:
        assert "example:" in texts[command], command
        assert f" {command} " in texts[command].split("example:")[1], command
        assert f"vo_lib {command} " in texts[""], f"the overview has no example of {command}"
    assert set(BENCH_HELP) == set(BENCHES)
    for name, (what, how_long) in BENCH_HELP.items():
        assert f"{name}" in texts["bench"] and f"{what} ({how_long})" in " ".join(texts["bench"].split())
