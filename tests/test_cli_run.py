"""python -m vo_lib run / evaluate: outputs, tables, and bad arguments."""

import os
import re
import subprocess
import sys

import numpy as np
import pytest

from vo_lib.formats.groundtruth import read_trajectory


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
    table = proc.stdout[proc.stdout.index("Errors against ground truth") :]
    assert "m travelled in 3-D" in table.splitlines()[0]
    for row in (
        "final position error, 3-D [m]",
        "distance travelled by the estimate, 3-D [m]",
        "planar heading error",
    ):
        assert row in table
    assert "final position error [m]" not in proc.stdout and "Errors in 3-D" not in proc.stdout  # one table
    assert "image decoding (on the reader thread)" in proc.stdout
    assert "median" in proc.stdout and "mean" in proc.stdout and "whole frame" in proc.stdout
    assert proc.stdout.startswith("run: sample indoor_linear, 25 frames")  # the first line: what comes
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
        (["run", "--sequence", "indoor_linear", "--frames", "1"], "expected a whole number >= 2 (frames)"),
        (["evaluate", "--gt", "missing.txt", "--est", "missing.txt"], "missing (the trajectory)"),
        # a negative value is judged as a value, not taken for an option
        (["evaluate", "--gt", "g.txt", "--est", "e.txt", "--segments", "-1,2"], "each 0.001"),
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


def test_warm_up_runs_before_the_first_timed_frame(workdir, monkeypatch):
    """Compiling happens in the untimed warm-up: the timed run starts only after it has finished."""
    from vo_lib.cli import run as run_module
    from vo_lib.stereo_vo import pipeline

    calls = []
    real_warm_up, real_run_frames = pipeline.warm_up, pipeline.run_frames

    def warm_up(*args, **kwargs):
        calls.append("warm-up starts")
        seconds = real_warm_up(*args, **kwargs)
        calls.append("warm-up ends")
        return seconds

    def run_frames(frames, *args, **kwargs):
        calls.append("frames")
        return real_run_frames(frames, *args, **kwargs)

    monkeypatch.setenv("VO_LIB_DATA", str(workdir / "data"))
    monkeypatch.setattr(pipeline, "warm_up", warm_up)  # run_command imports it when it runs
    monkeypatch.setattr(pipeline, "run_frames", run_frames)
    report = run_module.run_command("indoor_linear", str(workdir / "order"), 6, False)
    # the warm-up's own run of the pipeline, then the timed one
    assert calls == ["warm-up starts", "frames", "warm-up ends", "frames"]
    assert report["vo"]["final_position_error_m"] < 0.01 and not report["spot_turn"]


def test_error_table_of_a_spot_turn_reports_the_turn_not_a_percentage(capsys):
    from vo_lib.stereo_vo.pipeline import PipelineResult
    from vo_lib.stereo_vo.run_report import error_report, print_error_table

    yaw = np.radians(np.linspace(0.0, 400.0, 41))
    truth = np.column_stack([np.zeros(41), np.zeros(41), yaw])
    estimate = truth + [0.002, -0.001, np.radians(0.5)]
    result = PipelineResult(estimate, np.zeros((41, 3, 3)), [], [], None)
    report = error_report(result, truth, truth + [0.0, 0.0, np.radians(3.0)])
    assert report["spot_turn"] and report["turned_deg"] == pytest.approx(400.0)
    print_error_table(report, 0)
    out = capsys.readouterr().out
    assert "Errors against ground truth (400° turned on the spot)" in out
    assert "m travelled" not in out and "nan" not in out and "of distance travelled" not in out
    assert re.search(r"planar heading error, final \[deg\]\s+0\.500\s+3\.000", out)
    assert "visual odometry" in out and "VO + odometry" not in out
    print_error_table(report, 0, fused=True)  # the vision with the odometry fused: headed so
    assert "VO + odometry" in capsys.readouterr().out


def test_error_table_gives_each_column_its_3d_errors(capsys):
    from vo_lib.evaluation import standard_errors
    from vo_lib.geometry import camera_poses_from_planar
    from vo_lib.stereo_vo.pipeline import PipelineResult
    from vo_lib.stereo_vo.run_report import error_report, print_error_table

    x = np.linspace(0.0, 2.0, 21)
    truth = np.column_stack([x, np.zeros(21), np.zeros(21)])
    drifted = truth + np.column_stack([np.zeros(21), np.linspace(0.0, 0.03, 21), np.zeros(21)])
    mount = np.eye(4)
    errors = {
        c: standard_errors(camera_poses_from_planar(truth, mount), camera_poses_from_planar(p, mount))
        for c, p in (("vo", truth), ("odometry", drifted))
    }
    result = PipelineResult(truth, np.zeros((21, 3, 3)), [], [], None)
    print_error_table(error_report(result, truth, drifted), 1, errors)
    out = capsys.readouterr().out
    assert "(2.00 m travelled in 3-D)" in out
    assert re.search(r"final position error, 3-D \[m\]\s+0\.0000\s+0\.0300", out)
    assert re.search(r"frames flagged \(VO not used\)\s+1\n", out)


def test_convert_carries_the_odometry_files_of_a_kitti_folder(tmp_path):
    """A KITTI-layout copy keeps the source's per-frame odometry files and raw calibration, byte for
    byte (a copy without them runs without odometry, or with another camera mount)."""
    import shutil

    from vo_lib.cli.main import main

    source = tmp_path / "drive"
    shutil.copytree(os.path.join(os.path.dirname(__file__), "..", "data", "fixtures", "kitti_tiny"), source)
    (source / "oxts.txt").write_text("".join(" ".join(["0.5"] * 30) + "\n" for _ in range(3)))
    (source / "odometry.txt").write_text("0 0\n0.01 0.01\n0.02 0.02\n")
    (source / "raw_calib").mkdir()
    calibration = {  # what a run reads of them: the copy holds no calibration a run would refuse
        "calib_imu_to_velo.txt": "R: 1 0 0 0 1 0 0 0 1\nT: 0 0 0\n",
        "calib_velo_to_cam.txt": "R: 0 -1 0 0 0 -1 1 0 0\nT: 0 -0.08 -0.27\n",
        "calib_cam_to_cam.txt": "R_rect_00: 1 0 0 0 1 0 0 0 1\n",
    }
    for name, text in calibration.items():
        (source / "raw_calib" / name).write_text(text)
    (tmp_path / "manual").mkdir()
    (tmp_path / "manual" / "calib_cam_to_cam.txt").write_text("not read\n")
    (source / "raw_calib" / "docs").symlink_to(tmp_path / "manual")  # not read: not copied
    (source / "raw_calib" / "loop").symlink_to("loop")
    (source / "raw_calib" / "env").symlink_to("/proc/self/environ")  # a file, but not one that is read
    assert main(["convert", str(source), "--to", "kitti", "--out", str(tmp_path / "copy")]) == 0
    assert sorted(p.name for p in (tmp_path / "copy" / "raw_calib").iterdir()) == sorted(calibration)
    for name in ("oxts.txt", "odometry.txt", *(f"raw_calib/{name}" for name in calibration)):
        assert (tmp_path / "copy" / name).read_bytes() == (source / name).read_bytes(), name
    # a read-only source (a dataset kept safe) gives a copy that can be replaced: new files' modes
    for path in (*(source / "raw_calib" / name for name in calibration), source / "raw_calib"):
        path.chmod(0o555 if path.is_dir() else 0o444)
    try:
        for _ in range(2):
            assert main(["convert", str(source), "--to", "kitti", "--out", str(tmp_path / "copy2")]) == 0
    finally:
        (source / "raw_calib").chmod(0o755)
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # nothing left beside it
    for path in (
        tmp_path / "copy2" / "raw_calib",
        tmp_path / "copy2" / "raw_calib" / "calib_imu_to_velo.txt",
    ):
        assert path.stat().st_mode & 0o200, path  # writable by its owner (root may write regardless)


def test_evaluate_compares_a_run_of_the_first_frames_with_those_of_its_sequence(tmp_path, capsys):
    """`run --frames N` then `evaluate` against the sequence's whole poses.txt: the run's marker
    says which frames it ran, so the first N poses are compared (and agree with the run's table);
    an estimate that no such run wrote still needs equal counts."""
    import shutil

    from vo_lib.cli.main import main

    seq, out = tmp_path / "seq", tmp_path / "out"
    assert main(["generate", "corridor", "--frames", "8", "--resolution", "96x72", "--out", str(seq)]) == 0
    assert main(["run", "--sequence", str(seq), "--frames", "5", "--out", str(out)]) == 0
    table = capsys.readouterr().out
    ran = next(line.split()[-1] for line in table.splitlines() if "final position error, 3-D" in line)
    for est in ("poses.txt", "trajectory.tum"):
        assert main(["evaluate", "--gt", str(seq / "poses.txt"), "--est", str(out / est)]) == 0
        text = capsys.readouterr().out
        assert "is a run of the first 5 frames of --gt's sequence" in text
        assert next(line.split()[-1] for line in text.splitlines() if "final position error" in line) == ran
    shutil.copy(out / "poses.txt", tmp_path / "mine.txt")
    assert main(["evaluate", "--gt", str(seq / "poses.txt"), "--est", str(tmp_path / "mine.txt")]) == 2
    assert "has 8 poses but --est" in capsys.readouterr().err
    # another sequence's truth of equal length: compared, and said to be another file than the run's
    other = tmp_path / "other"
    assert (
        main(["generate", "indoor_free", "--frames", "5", "--resolution", "96x72", "--out", str(other)]) == 0
    )
    capsys.readouterr()
    assert main(["evaluate", "--gt", str(other / "poses.txt"), "--est", str(out / "poses.txt")]) == 0
    assert f"is a run of '{seq.resolve()}', whose truth is" in capsys.readouterr().out
    # the sequence written again over the one the run was made on: refused, not scored
    assert (
        main(
            [
                "generate",
                "indoor_free",
                "--frames",
                "8",
                "--resolution",
                "96x72",
                "--out",
                str(seq),
                "--force",
            ]
        )
        == 0
    )
    capsys.readouterr()
    assert main(["evaluate", "--gt", str(seq / "poses.txt"), "--est", str(out / "poses.txt")]) == 2
    assert "changed since --est" in capsys.readouterr().err
    # a run's poses.txt replaced by another's: no longer the run its marker describes
    assert main(["run", "--sequence", str(other), "--out", str(tmp_path / "out2")]) == 0
    shutil.copy(tmp_path / "out2" / "poses.txt", out / "poses.txt")
    capsys.readouterr()
    assert main(["evaluate", "--gt", str(seq / "poses.txt"), "--est", str(out / "poses.txt")]) == 2
    assert "has 8 poses but --est" in capsys.readouterr().err


def test_a_near_miss_of_the_asl_layout_is_named_as_such(tmp_path, capsys):
    """An empty mav0, one camera's folder, or the folder above a recording: the error speaks of
    the ASL layout, not of KITTI's image_0."""
    from vo_lib.cli.main import main

    (tmp_path / "empty" / "mav0").mkdir(parents=True)
    for rec in ("rec", "rec2", "rec3"):
        for side in ("cam0", "cam1"):
            (tmp_path / ("above" if rec == "rec" else "many") / rec / "mav0" / side / "data").mkdir(
                parents=True
            )
    (tmp_path / "many" / "rec").mkdir()
    (tmp_path / "many" / "rec" / "mav0").symlink_to(tmp_path / "above" / "rec" / "mav0")
    cases = {
        tmp_path / "empty": "mav0: no cam0 or cam1 folder; expected the ASL layout",
        tmp_path / "above" / "rec" / "mav0" / "cam0": "cam0: one camera of an ASL recording; give the folder",
        tmp_path / "above": "above: holds the ASL recording",
        tmp_path
        / "above"
        / "rec"
        / "mav0"
        / "cam0"
        / "data": f"inside the ASL recording {tmp_path / 'above' / 'rec'};",
        tmp_path / "many": "many: holds 3 ASL recordings (rec, rec2, rec3); give one of them",
    }
    for folder, expected in cases.items():
        assert main(["run", "--sequence", str(folder), "--out", str(tmp_path / "out")]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and expected in err[0], err


def test_a_trajectory_in_nanoseconds_is_read_so(tmp_path, capsys):
    """A TUM file whose times are EuRoC's nanoseconds is read as nanoseconds, with a notice naming
    it: against the same poses in seconds it agrees, against another clock it is refused in one line."""
    from vo_lib.cli.main import main

    rows = [f"{1403636579763555584 + k * 50_000_000} {0.1 * k} 0 0 0 0 0 1" for k in range(5)]
    (tmp_path / "ns.tum").write_text("\n".join(rows) + "\n")
    same = [f"{1403636579.763555584 + k * 0.05:.9f} {0.1 * k} 0 0 0 0 0 1" for k in range(5)]
    (tmp_path / "same.tum").write_text("\n".join(same) + "\n")
    (tmp_path / "s.tum").write_text("\n".join(f"{k * 0.05} {0.1 * k} 0 0 0 0 0 1" for k in range(5)) + "\n")
    assert main(["evaluate", "--gt", str(tmp_path / "ns.tum"), "--est", str(tmp_path / "same.tum")]) == 0
    captured = capsys.readouterr()
    assert "ns.tum: every time is beyond 1e+11 s (the year 5138): read as nanoseconds" in captured.err
    assert "associated 5 of 5 poses" in captured.out
    assert main(["evaluate", "--gt", str(tmp_path / "ns.tum"), "--est", str(tmp_path / "s.tum")]) == 2
    err = [line for line in capsys.readouterr().err.strip().splitlines() if not line.startswith("notice:")]
    assert len(err) == 1 and "both must use one clock" in err[0], err


def test_the_flagged_frames_notice_counts_every_flagged_frame(capsys):
    """The notice's count is the error table's: frames without stereo features are among them."""
    from types import SimpleNamespace

    from vo_lib.cli.run import _say_if_suspect
    from vo_lib.stereo_vo.frames import FrameDiagnostics, Reason

    reasons = [Reason.FEW_FEATURES] * 10 + [Reason.FEW_INLIERS] * 20 + [Reason.NONE] * 70
    diagnostics = [
        FrameDiagnostics(k, fallback=r is not Reason.NONE, reason=r) for k, r in enumerate(reasons)
    ]
    _say_if_suspect(SimpleNamespace(path="seq", poses=None), 101, diagnostics, None)
    err = capsys.readouterr().err
    assert "30 of 100 frames were flagged" in err and "20 too few inliers, 10 too few stereo features" in err
    # most frames without stereo features: the notice says so, and counts the others flagged too
    reasons = [Reason.FEW_FEATURES] * 5 + [Reason.FEW_MATCHES] * 14
    diagnostics = [FrameDiagnostics(k, fallback=True, reason=r) for k, r in enumerate(reasons)]
    _say_if_suspect(SimpleNamespace(path="seq", poses=None), 20, diagnostics, None)
    err = capsys.readouterr().err
    assert "5 of 19 frames had too few stereo features to be matched (19 flagged in all: 14 too few" in err


@pytest.mark.parametrize("where", ["missing", "afile", "empty"])
def test_bench_real_names_a_realdata_variable_that_holds_no_sequence(tmp_path, monkeypatch, where):
    (tmp_path / "afile").write_text("a file, not a folder")
    (tmp_path / "empty").mkdir()
    monkeypatch.setenv("VO_LIB_REALDATA", str(tmp_path / where))
    proc = cli("bench", "real", cwd=tmp_path, data=tmp_path / "data")
    assert (
        proc.returncode == 2
        and proc.stderr.count("\n") == 1
        and f"VO_LIB_REALDATA={tmp_path / where}" in proc.stderr
    )


def test_bench_real_refuses_a_sequence_too_short_for_its_errors(tmp_path, monkeypatch, capsys):
    """A real sequence of two frames: one line and exit 2, as evaluate, not a traceback."""
    from vo_lib.camera import StereoCamera
    from vo_lib.cli.main import main
    from vo_lib.formats.sequence_writer import write_sequence

    images = [np.random.default_rng(k).integers(0, 256, (48, 64), dtype=np.uint8) for k in range(2)]
    camera = StereoCamera(50.0, 50.0, 31.5, 23.5, 0.12, 64, 48)
    write_sequence(
        tmp_path / "real" / "short", camera, images, images, np.arange(2) / 10, np.tile(np.eye(4), (2, 1, 1))
    )
    monkeypatch.setenv("VO_LIB_REALDATA", str(tmp_path / "real"))
    assert main(["bench", "real"]) == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert line.endswith("short: 2 frame(s); a benchmark needs at least 3")


def test_a_two_frame_run_prints_no_errors_and_says_why(workdir):
    """As ``evaluate`` refuses two poses, ``run`` on two frames prints no errors (its segment
    errors over millimetres were thousands of degrees per 100 m) and says so in one notice."""
    proc = cli("run", "--frames", "2", "--out", str(workdir / "two"), cwd=workdir, data=workdir / "data")
    assert proc.returncode == 0 and "Errors" not in proc.stdout and "KITTI" not in proc.stdout
    assert "no errors for 2 frames; an evaluation needs at least 3" in proc.stderr


@pytest.mark.parametrize("frames", ["2", "3"])
def test_a_path_of_millimetres_is_not_judged_against_the_truths(workdir, frames):
    """The spot turn's first frames move the camera by millimetres: their lengths say nothing of the
    baseline, and no notice asks about it."""
    out = str(workdir / f"spot{frames}")
    proc = cli(
        "run", "--sequence", "spot_turn", "--frames", frames, "--out", out, cwd=workdir, data=workdir / "data"
    )
    assert proc.returncode == 0 and "stereo baseline" not in proc.stderr, proc.stderr
