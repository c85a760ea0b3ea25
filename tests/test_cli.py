import signal
import subprocess
import sys

from vo_lib.cli.main import main


def test_bench_geometry_prints_table(capsys):
    assert main(["bench", "geometry"]) == 0
    out = capsys.readouterr().out
    assert "vo_lib theta_from_pixels + rho_from_pixels" in out and "python loop (baseline)" in out


def test_unknown_bench_exits_2():
    proc = subprocess.run([sys.executable, "-m", "vo_lib", "bench", "nope"], capture_output=True, text=True)
    assert proc.returncode == 2
    assert "invalid choice: 'nope'" in proc.stderr


def test_command_line_and_file_code_stay_small():
    """Every function of the command line, the file formats, the output folders and the
    evaluation stays within complexity 12 and 50 statements (ruff C901, PLR0915)."""
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    paths = ["vo_lib/cli", "vo_lib/formats", "vo_lib/outputs.py", "vo_lib/arguments.py"]
    paths += ["vo_lib/evaluation.py", "vo_lib/data.py"]
    proc = subprocess.run(
        [sys.executable, "-m", "ruff", "check", "--no-cache", "--select", "C901,PLR0915"]
        + ["--config", "lint.mccabe.max-complexity=12", "--config", "lint.pylint.max-statements=50"]
        + [str(root / p) for p in paths],
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr


def test_a_reader_closing_the_pipe_gets_one_line_not_a_traceback():
    """`python -m vo_lib ... | head`: the reader leaves early; the command says so and ends as by SIGPIPE."""
    script = (
        "import sys, vo_lib.cli.main as m\n"
        "m._dispatch = lambda args: [print('x' * 100) for _ in range(100000)]\n"
        "sys.exit(m.main(['run']))\n"
    )
    proc = subprocess.Popen(
        [sys.executable, "-c", script], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    proc.stdout.readline()
    proc.stdout.close()  # as `head -1` does
    err = proc.stderr.read()
    assert proc.wait(timeout=60) == 128 + signal.SIGPIPE
    expected = "python -m vo_lib run: stopped: whatever read its output closed the pipe"
    assert err.strip().splitlines() == [expected]
    # 2>&1: the line cannot be written either, and the exit status is still SIGPIPE's
    proc = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    proc.stdout.readline()
    proc.stdout.close()
    assert proc.wait(timeout=60) == 128 + signal.SIGPIPE


def test_bench_real_reports_the_fastest_run_and_refuses_runs_that_differ():
    from types import SimpleNamespace

    import numpy as np
    import pytest

    from vo_lib.bench.bench_real import REPEATS, fastest

    times = iter([5.0, 3.0, 4.0])
    run = lambda: SimpleNamespace(camera_poses=np.eye(4)[None], ms=next(times))  # noqa: E731
    best, all_times = fastest(run, lambda r: r.ms)
    assert REPEATS == 3 and best.ms == 3.0 and all_times == [5.0, 3.0, 4.0]
    poses = iter([np.eye(4)[None], np.eye(4)[None], 2 * np.eye(4)[None]])
    with pytest.raises(RuntimeError, match="different poses"):
        fastest(lambda: SimpleNamespace(camera_poses=next(poses)), lambda r: 1.0)


def test_step_scale_measures_the_steps_not_the_path():
    import numpy as np

    from vo_lib.bench.bench_real import step_scale

    truth = np.repeat(np.eye(4)[None], 50, axis=0)
    truth[:, 2, 3] = np.linspace(0.0, 4.9, 50)  # straight ahead, 0.1 m a frame
    short = truth.copy()
    short[:, :3, 3] *= 0.99
    assert np.isclose(step_scale(truth, short), 0.99, rtol=1e-12)
    jitter = truth.copy()
    jitter[::2, 0, 3] += 0.02  # sideways zigzag: a longer path, the same steps ahead
    path = lambda P: np.linalg.norm(np.diff(P[:, :3, 3], axis=0), axis=1).sum()  # noqa: E731
    assert path(jitter) > 1.01 * path(truth)
    assert np.isclose(step_scale(truth, jitter), 1.0, rtol=1e-12)
    # the truth's own noise pulls the factor down (errors in the regressor); a stride of 10 frames
    # leaves it a hundredth of the weight
    noisy = truth.copy()
    noisy[:, :3, 3] += np.random.default_rng(0).normal(0.0, 0.01, (50, 3))
    assert step_scale(noisy, truth) < 0.95 and abs(step_scale(noisy, truth, stride=10) - 1) < 0.01
    with np.errstate(all="raise"):  # a truth standing still has no scale: undefined, and no warning
        assert np.isnan(step_scale(np.repeat(np.eye(4)[None], 5, axis=0), truth[:5]))


def test_a_folder_that_refuses_to_be_searched_is_named(tmp_path, monkeypatch):
    """A file in a folder without search permission is reported by that folder, not as the file."""
    import os
    from pathlib import Path

    from vo_lib.cli.main import _os_error, closed_folder

    folder = tmp_path / "rig" / "cam1"
    folder.mkdir(parents=True)
    real_stat = os.stat

    def stat(path, *args, **kwargs):
        if Path(path).parent == folder:
            raise PermissionError(13, "Permission denied", str(path))
        return real_stat(path, *args, **kwargs)

    monkeypatch.setattr(os, "stat", stat)
    inside = folder / "sensor.yaml"
    assert closed_folder(inside) == folder
    assert closed_folder(tmp_path / "rig" / "other.yaml") is None
    assert _os_error(PermissionError(13, "Permission denied", str(inside)), None) == (
        f"{folder}: cannot read (Permission denied)"
    )
