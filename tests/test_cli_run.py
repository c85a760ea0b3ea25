"""python -m vo_lib run / evaluate: outputs, tables, and bad arguments."""

import os
import subprocess
import sys

import numpy as np
import pytest

from vo_lib.formats.poses import read_trajectory


def cli(*args, cwd, data):
    env = dict(os.environ, VO_LIB_DATA=str(data))
    command = [sys.executable, "-m", "vo_lib", *args]
    return subprocess.run(command, capture_output=True, text=True, cwd=cwd, env=env)


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    return tmp_path_factory.mktemp("cli")


def test_run_writes_every_output(workdir):
    data = workdir / "data"
    proc = cli("run", "--sequence", "indoor_linear", "--frames", "25", "--out", "out", cwd=workdir, data=data)
    assert proc.returncode == 0, proc.stderr
    out = workdir / "out"
    assert sorted(p.name for p in out.iterdir()) == [
        ".vo_lib_output.json",
        "diagnostics.csv",
        "poses.txt",
        "timings.csv",
        "trajectory.png",
        "trajectory.tum",
    ]
    _, kitti = read_trajectory(out / "poses.txt")
    times, tum = read_trajectory(out / "trajectory.tum")
    assert len(kitti) == len(tum) == 25 and times[1] == pytest.approx(1 / 30)
    np.testing.assert_allclose(kitti, tum, atol=1e-6)
    assert len((out / "timings.csv").read_text().splitlines()) == 26
    assert "binocular stereo vision processing" in proc.stdout and "48.969" in proc.stdout
    assert "final position error [m]" in proc.stdout
    assert not [p for p in workdir.iterdir() if p.name.startswith(".out")]  # no temporary left


def test_evaluate_command(workdir):
    data = workdir / "data"
    gt = data / "indoor_linear_25f" / "poses.txt"
    if not gt.exists():
        cli("run", "--sequence", "indoor_linear", "--frames", "25", "--out", "out", cwd=workdir, data=data)
    args = ["evaluate", "--gt", str(gt), "--est", "out/poses.txt", "--segments", "0.1,0.2"]
    proc = cli(*args, cwd=workdir, data=data)
    assert proc.returncode == 0, proc.stderr
    assert "ATE (SE(3) alignment): rmse" in proc.stdout and "segment 0.1 m" in proc.stdout


@pytest.mark.parametrize(
    "args, message",
    [
        (["run", "--sequence", "no_such_sample_or_folder"], "neither a sample name"),
        (["run", "--sequence", "indoor_linear", "--out", "afile/sub"], "cannot write there"),
        (["run", "--sequence", "indoor_linear", "--frames", "1"], "need at least 2 frames"),
        (["evaluate", "--gt", "missing.txt", "--est", "missing.txt"], "missing.txt: no such trajectory file"),
    ],
)
def test_bad_arguments_exit_2_with_one_line_and_leave_nothing(tmp_path, args, message):
    (tmp_path / "afile").write_text("a file, not a folder")
    before = sorted(p.name for p in tmp_path.iterdir())
    proc = cli(*args, cwd=tmp_path, data=tmp_path / "data")
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == before
