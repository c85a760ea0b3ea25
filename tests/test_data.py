import dataclasses
import os
import subprocess
import sys

import numpy as np
import pytest

from vo_lib.data import load_sequence, sample_path
from vo_lib.geometry import camera_mount, camera_poses_from_planar, planar_from_camera_poses
from vo_lib.sim import frame_store
from vo_lib.sim.samples import CAMERA_HEIGHT, SAMPLES, fingerprint, generate, render_sample


@pytest.fixture
def data_home(tmp_path, monkeypatch):
    monkeypatch.setenv("VO_LIB_DATA", str(tmp_path / "data"))
    return tmp_path / "data"


def test_named_sample_is_generated_once_then_reused(data_home):
    seq = load_sequence("indoor_linear", frames=3, resolution=(160, 120), progress=False)
    assert seq.path == data_home / "indoor_linear_3f_160x120"
    assert len(seq) == 3 and seq.camera.width == 160 and seq.odometry.shape == (3, 2)
    assert seq.manifest["rate_hz"] == 30.0 and seq.manifest["mirrors"].startswith("[Zhao]")
    stamp = (seq.path / "manifest.json").stat().st_mtime_ns
    again = load_sequence("indoor_linear", frames=3, resolution=(160, 120), progress=False)
    assert (again.path / "manifest.json").stat().st_mtime_ns == stamp
    np.testing.assert_array_equal(again.pair(2)[0], seq.pair(2)[0])


def test_out_of_date_sample_is_generated_again(data_home, monkeypatch):
    from vo_lib.sim import samples

    seq = load_sequence("corridor", frames=2, resolution=(80, 60), progress=False)
    assert seq.manifest["fingerprint"] in (seq.path / "manifest.json").read_text()
    monkeypatch.setattr(
        samples, "TEXTURE_VERSION", f"{samples.TEXTURE_VERSION}+1"
    )  # as if the code had changed
    again = load_sequence("corridor", frames=2, resolution=(80, 60), progress=False)
    assert again.path == seq.path and again.manifest["fingerprint"] == fingerprint("corridor")
    assert again.manifest["fingerprint"] != seq.manifest["fingerprint"]


def test_fingerprint_follows_what_shapes_the_images_not_the_prose(monkeypatch):
    """Rewording a sample's description keeps its cache; changing its random seed does not."""
    sample = SAMPLES["indoor_linear"]
    before = fingerprint("indoor_linear")
    monkeypatch.setitem(SAMPLES, "indoor_linear", dataclasses.replace(sample, purpose="p", mirrors="m"))
    assert fingerprint("indoor_linear") == before
    monkeypatch.setitem(SAMPLES, "indoor_linear", dataclasses.replace(sample, seed=sample.seed + 1))
    assert fingerprint("indoor_linear") != before


def test_generation_is_deterministic(tmp_path, monkeypatch):
    monkeypatch.setattr(frame_store, "FOLDER", None)  # both rendered, not the second read back
    a = generate("spot_turn", tmp_path / "a", frames=2, resolution=(96, 72), progress=False)
    b = generate("spot_turn", tmp_path / "b", frames=2, resolution=(96, 72), progress=False)
    for name in ("image_0/000001.png", "image_1/000001.png", "poses.txt", "odometry.txt", "times.txt"):
        assert (a / name).read_bytes() == (b / name).read_bytes()


def test_frame_store_gives_the_frames_one_render_gives(tmp_path, monkeypatch):
    """Frames read back from the store, and frames rendered after them from the stored noise
    state, are those of one uninterrupted render; a stored frame is read, not rendered again."""

    def frames(n, first=0):
        return [(left, right) for left, right, _ in render_sample("outdoor_free", n, (96, 72), first)[1]]

    monkeypatch.setattr(frame_store, "FOLDER", None)
    plain = frames(6)
    monkeypatch.setattr(frame_store, "FOLDER", tmp_path)
    assert all(np.array_equal(a, b) for a, b in zip(sum(frames(3), ()), sum(plain[:3], ()), strict=True))
    (folder,) = tmp_path.iterdir()
    assert sorted(p.name for p in folder.iterdir()) == ["000000.npz", "000001.npz", "000002.npz"]
    with np.load(folder / "000002.npz") as stored:
        marked = {name: stored[name] for name in stored.files}
    marked["left"] = np.zeros_like(marked["left"])
    np.savez(folder / "000002.npz", **marked)
    again = frames(6)  # frames 0-2 read (2 as marked), 3-5 rendered from the stored noise state
    assert not again[2][0].any()
    for k in (0, 1, 3, 4, 5):
        assert np.array_equal(again[k][0], plain[k][0]) and np.array_equal(again[k][1], plain[k][1]), k
    assert len(list(folder.iterdir())) == 6
    later = frames(2, first=3)  # another first frame, another noise stream: stored apart
    assert len(list(tmp_path.iterdir())) == 2 and not np.array_equal(later[0][0], plain[3][0])


def test_ground_truth_poses_match_the_robot_poses(tmp_path):
    seq = load_sequence(
        generate("indoor_free", tmp_path / "s", frames=5, resolution=(96, 72), progress=False)
    )
    robot = np.array(seq.manifest["robot_poses"])
    mount = camera_mount(height=CAMERA_HEIGHT)
    np.testing.assert_allclose(seq.poses_4x4(), camera_poses_from_planar(robot, mount), atol=1e-12)
    back = planar_from_camera_poses(seq.poses, mount)
    # relative to the start, the planar poses come back exactly
    from vo_lib.geometry import relative_planar

    np.testing.assert_allclose(back, relative_planar(robot[0], robot), atol=1e-12)
    # the camera looks along the robot's x axis: its z axis moves forward
    assert seq.poses[-1, 2, 3] > 0


def test_sample_path_names():
    assert sample_path("corridor").name == "corridor"
    assert sample_path("corridor", SAMPLES["corridor"].frames).name == "corridor"
    assert sample_path("corridor", 10, (320, 240)).name == "corridor_10f_320x240"


def run_cli(*args, cwd=None):
    env = dict(os.environ)
    return subprocess.run(
        [sys.executable, "-m", "vo_lib", *args], capture_output=True, text=True, cwd=cwd, env=env
    )


def test_generate_command(tmp_path):
    out = tmp_path / "gen"
    proc = run_cli("generate", "corridor", "--out", str(out), "--frames", "2", "--resolution", "80x60")
    assert proc.returncode == 0, proc.stderr
    assert f"wrote {out}" in proc.stdout
    assert sorted(p.name for p in out.iterdir()) == [
        ".vo_lib_output.json",
        "calib.txt",
        "image_0",
        "image_1",
        "manifest.json",
        "odometry.txt",
        "poses.txt",
        "times.txt",
    ]


@pytest.mark.parametrize(
    "args, message",
    [
        (["generate", "nope"], "invalid choice: 'nope'"),
        (["generate", "corridor", "--resolution", "big"], "expected WIDTHxHEIGHT"),
        (["generate", "corridor", "--frames", "100000"], "--frames 100000: corridor has 541 frames"),
    ],
)
def test_generate_bad_arguments_exit_2_and_leave_nothing(tmp_path, args, message):
    out = tmp_path / "gen"
    proc = run_cli(*args, "--out", str(out))
    assert proc.returncode == 2
    assert message in proc.stderr
    # one line; an unknown name's line lists every sample (eleven names), hence the 320 characters
    assert len(proc.stderr.strip().splitlines()[-1]) < 320
    assert not out.exists() and list(tmp_path.iterdir()) == []
