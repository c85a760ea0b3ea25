import re
import shutil
from pathlib import Path

import cv2
import numpy as np
import pytest

from vo_lib.camera import StereoCamera
from vo_lib.formats.sequence import SequenceError, read_sequence
from vo_lib.formats.sequence_writer import SequenceWriter, write_sequence

FIXTURE = Path(__file__).resolve().parents[1] / "data" / "fixtures" / "kitti_tiny"


@pytest.fixture
def seq_dir(tmp_path, rng):
    """A valid 4-frame sequence with every optional file."""
    cam = StereoCamera(100.0, 100.0, 31.5, 23.5, 0.12, 64, 48)
    left = [rng.integers(0, 256, (48, 64), dtype=np.uint8) for _ in range(4)]
    right = [rng.integers(0, 256, (48, 64), dtype=np.uint8) for _ in range(4)]
    poses = np.tile(np.eye(4), (4, 1, 1))
    poses[:, 2, 3] = rng.normal(size=4)
    odo = rng.normal(size=(4, 2)) * 0.01
    path = write_sequence(tmp_path / "seq", cam, left, right, np.arange(4) / 30.0, poses, odo, {"seed": 1})
    return path, cam, left, right, poses, odo


def test_round_trip_is_exact(seq_dir):
    path, cam, left, right, poses, odo = seq_dir
    seq = read_sequence(path)
    assert len(seq) == 4 and seq.camera == cam
    for k, (l_img, r_img) in enumerate(seq):
        np.testing.assert_array_equal(l_img, left[k])
        np.testing.assert_array_equal(r_img, right[k])
    np.testing.assert_array_equal(seq.times, np.arange(4) / 30.0)
    np.testing.assert_array_equal(seq.poses_4x4(), poses)
    np.testing.assert_array_equal(seq.odometry, odo)
    assert seq.manifest == {"seed": 1}
    assert [p.name for p in path.parent.iterdir()] == ["seq"]  # no temporary folder left


def test_real_kitti_layout_loads_unchanged():
    seq = read_sequence(FIXTURE)
    assert len(seq) == 3 and seq.odometry is None
    assert seq.camera.fx == pytest.approx(718.856) and seq.camera.cx == pytest.approx(607.1928)
    assert seq.camera.baseline == pytest.approx(386.1448 / 718.856)
    assert (seq.camera.width, seq.camera.height) == (1241, 376)  # KITTI 00 images, flat blocks
    np.testing.assert_allclose(seq.times, [0.0, 0.10364, 0.20728])
    assert seq.poses.shape == (3, 3, 4) and seq.poses[2, 2, 3] == pytest.approx(1.716275)
    assert seq.pair(1)[0].shape == (376, 1241)


def copy_fixture(tmp_path) -> Path:
    dst = tmp_path / "kitti"
    shutil.copytree(FIXTURE, dst)
    return dst


def edit_line(path: Path, line_no: int, text: str):
    lines = path.read_text().splitlines()
    lines[line_no - 1] = text
    path.write_text("\n".join(lines) + "\n")


def test_missing_folder(tmp_path):
    with pytest.raises(SequenceError, match=r"nowhere: sequence folder not found"):
        read_sequence(tmp_path / "nowhere")


def test_unequal_image_counts(tmp_path):
    d = copy_fixture(tmp_path)
    (d / "image_1" / "000002.png").unlink()
    with pytest.raises(SequenceError, match=r"image_0 has 3 images but image_1 has 2"):
        read_sequence(d)


def test_unreadable_and_empty_images(tmp_path):
    d = copy_fixture(tmp_path)
    (d / "image_0" / "000000.png").write_bytes(b"")
    with pytest.raises(SequenceError, match=r"image_0/000000.png, frame 0: empty file"):
        read_sequence(d)
    d2 = copy_fixture(tmp_path / "b")
    (d2 / "image_1" / "000002.png").write_bytes(b"not a png at all")
    # every header is checked when the sequence opens, not when the frame is reached
    with pytest.raises(SequenceError, match=r"image_1/000002.png, frame 2: cannot read the image"):
        read_sequence(d2)


def test_left_and_right_of_different_sizes(tmp_path):
    d = copy_fixture(tmp_path)
    cv2.imwrite(str(d / "image_1" / "000000.png"), np.zeros((376, 1240), np.uint8))
    with pytest.raises(
        SequenceError,
        match=r"image_1/000000.png, frame 0: 1240x376 image, but .*image_0/000000.png is 1241x376",
    ):
        read_sequence(d)


def test_colour_is_converted_and_16_bit_is_refused(tmp_path):
    d = copy_fixture(tmp_path)
    colour = np.zeros((376, 1241, 3), np.uint8)
    colour[..., 1] = 200  # green
    cv2.imwrite(str(d / "image_0" / "000001.png"), colour)
    left, _ = read_sequence(d).pair(1)
    assert left.shape == (376, 1241) and 100 < left.mean() < 150  # grey of pure green
    cv2.imwrite(str(d / "image_0" / "000000.png"), np.zeros((376, 1241), np.uint16))
    with pytest.raises(SequenceError, match=r"000000.png, frame 0: 16-bit image; expected 8-bit grey"):
        read_sequence(d)
    from PIL import Image  # a float TIFF is told its own depth, not 16 bits

    for side in ("image_0", "image_1"):  # every image a TIFF, as a sequence is named alike
        for png in sorted((d / side).glob("*.png")):
            png.unlink()
            Image.fromarray(np.zeros((376, 1241), np.float32)).save(png.with_suffix(".tif"))
    with pytest.raises(SequenceError, match=r"000000.tif, frame 0: 32-bit image; expected 8-bit grey"):
        read_sequence(d)


def test_calib_with_wrong_count_and_missing_p1(tmp_path):
    d = copy_fixture(tmp_path)
    edit_line(d / "calib.txt", 2, "P1: 1 2 3")
    with pytest.raises(SequenceError, match=r"calib.txt, line 2: P1 needs 12 numbers, got 3"):
        read_sequence(d)
    lines = (FIXTURE / "calib.txt").read_text().splitlines()
    (d / "calib.txt").write_text("\n".join(x for x in lines if not x.startswith("P1")) + "\n")
    with pytest.raises(SequenceError, match=r"calib.txt: no P1 line \(right camera projection"):
        read_sequence(d)


def test_non_monotonic_times(tmp_path):
    d = copy_fixture(tmp_path)
    edit_line(d / "times.txt", 3, "0.05")
    with pytest.raises(SequenceError, match=r"times.txt, line 3: time 0.05 is not after 0.10364"):
        read_sequence(d)


def test_pose_count_differs_from_images(tmp_path):
    d = copy_fixture(tmp_path)
    lines = (d / "poses.txt").read_text().splitlines()
    (d / "poses.txt").write_text("\n".join(lines[:2]) + "\n")
    with pytest.raises(SequenceError, match=r"poses.txt has 2 poses but there are 3 images"):
        read_sequence(d)


@pytest.mark.parametrize(
    "content, message",
    [
        ("0 0\n0.01 nan\n0.01 0.01\n", r"odometry.txt, line 2: delta_u_left delta_u_right holds a NaN"),
        (
            "0 0\n0.01\n0.01 0.01\n",
            r"odometry.txt, line 2: delta_u_left delta_u_right needs 2 numbers, got 1",
        ),
        ("0 0\n0.01 0.01\n", r"odometry.txt has 2 rows but there are 3 images"),
    ],
)
def test_bad_odometry(tmp_path, content, message):
    d = copy_fixture(tmp_path)
    (d / "odometry.txt").write_text(content)
    with pytest.raises(SequenceError, match=message):
        read_sequence(d)


def test_failed_write_leaves_nothing_and_keeps_the_old_sequence(seq_dir):
    path, cam, left, right, poses, odo = seq_dir
    before = sorted(p.name for p in path.iterdir())
    with pytest.raises(RuntimeError, match="interrupted"):
        with SequenceWriter(path, cam) as writer:
            writer.add(left[0], right[0])
            raise RuntimeError("interrupted")
    assert sorted(p.name for p in path.parent.iterdir()) == ["seq"]
    assert sorted(p.name for p in path.iterdir()) == before
    with pytest.raises(ValueError, match="images must be 2-D uint8 grey"):
        with SequenceWriter(path.parent / "other", cam) as writer:
            writer.add(np.zeros((4, 4), np.float32), np.zeros((4, 4), np.float32))
    assert not (path.parent / "other").exists()


@pytest.mark.parametrize("name", ["poses.txt", "odometry.txt", "manifest.json", "calib.txt", "times.txt"])
def test_a_folder_where_a_file_belongs_is_named(seq_dir, name):
    path = seq_dir[0]
    (path / name).unlink()
    (path / name).mkdir()
    with pytest.raises(SequenceError, match=f"{name}: a folder, where .* should be a file"):
        read_sequence(path)


def test_an_oversized_pose_file_is_refused_before_it_is_read(seq_dir):
    import time

    path = seq_dir[0]
    with open(path / "poses.txt", "w") as fh:
        fh.write("1 0 0 0 0 1 0 0 0 0 1 0\n" * 200_000)  # 4 frames
    t0 = time.perf_counter()
    with pytest.raises(SequenceError, match="poses.txt: .* bytes, far more than 4 lines"):
        read_sequence(path)
    assert time.perf_counter() - t0 < 1.0


def test_a_png_header_claiming_a_huge_image_is_one_error(seq_dir):
    import struct
    import zlib

    path = seq_dir[0]
    target = path / "image_1" / "000002.png"
    data = bytearray(target.read_bytes())
    data[16:24] = struct.pack(">II", 65535, 65535)
    data[29:33] = struct.pack(">I", zlib.crc32(bytes(data[12:29])))  # a valid header otherwise
    target.write_bytes(bytes(data))
    with pytest.raises(SequenceError, match=r"000002.png, frame 2: the PNG header claims 65535x65535"):
        read_sequence(path)


def test_a_singular_rotation_in_a_raw_calibration_is_one_error(tmp_path):
    from vo_lib.formats.kitti_raw import camera_in_imu_frame

    raw = tmp_path / "raw_calib"
    raw.mkdir()
    eye = "1 0 0 0 1 0 0 0 1"
    (raw / "calib_imu_to_velo.txt").write_text(f"R: {eye}\nT: 0 0 0\n")
    (raw / "calib_velo_to_cam.txt").write_text("R: 1 0 0 0 1 0 0 0 0\nT: 0 0 0\n")  # singular
    (raw / "calib_cam_to_cam.txt").write_text(f"R_rect_00: {eye}\n")
    with pytest.raises(SequenceError, match="calib_velo_to_cam.txt: R: it is not a rotation matrix"):
        camera_in_imu_frame(raw)
    # a translation in millimetres, and a second R line (which one would be meant?)
    (raw / "calib_velo_to_cam.txt").write_text(f"R: {eye}\nT: 0 -80 -270\n")
    with pytest.raises(
        SequenceError, match="calib_velo_to_cam.txt: T puts one sensor 281.6.* expected metres"
    ):
        camera_in_imu_frame(raw)
    (raw / "calib_velo_to_cam.txt").write_text(f"R: {eye}\nT: 0 0 0\nR: {eye}\n")
    with pytest.raises(
        SequenceError, match="calib_velo_to_cam.txt, line 3: a second R line .the first is line 1"
    ):
        camera_in_imu_frame(raw)


def test_frames_are_read_ahead_and_in_order(seq_dir):
    path, _, left, right, _, _ = seq_dir
    seq = read_sequence(path)
    assert seq.read_ahead > 0
    for k in (0, 1, 3, 2, 0):  # forwards, skipping, backwards
        np.testing.assert_array_equal(seq.pair(k)[0], left[k])
        np.testing.assert_array_equal(seq.pair(k)[1], right[k])
    seq.pair(1)  # frames 2 and 3 are now decoded ahead; a damaged one still raises, when asked for
    fresh = read_sequence(path)
    target = path / "image_0" / "000003.png"
    target.write_bytes(target.read_bytes()[:60] + bytes(200) + target.read_bytes()[260:])
    fresh.pair(2)
    with pytest.raises(SequenceError, match="000003.png, frame 3"):
        fresh.pair(3)


def test_a_long_value_in_an_error_says_how_many_values_it_holds():
    """Every value the file holds is counted, a NaN or a text among them, in nested lists and maps."""
    from vo_lib.formats.frame_files import shown

    assert shown([float("nan"), "x", *[1.0] * 14]).startswith("16 values, [NaN, ")
    assert shown({"fu": 458.654, "fv": 457.296, "cu": 367.215, "cv": 248.375}).startswith("4 values, {")
    assert shown([[1.5] * 4] * 4).startswith("16 values, [[1.5,")
    assert shown([1, 2]) == "[1, 2]" and shown("a" * 50) == '"' + "a" * 39 + "..."


def test_a_bad_entry_of_a_list_is_named_by_its_place_a_nested_one_too():
    """The first entry that is not a number within the bounds, a list in its place included."""
    from vo_lib.formats.frame_files import numbers_at

    for value, named in (([1, 2, 3, "x"], 'entry 4 of 4: "x"'), ([[1, 2], 3, 4, 5], "entry 1 of 4: [1, 2]")):
        with pytest.raises(SequenceError, match=re.escape(f"key intrinsics: expected four, got {named}")):
            numbers_at(Path("sensor.yaml"), "intrinsics", value, (4,), "four")


@pytest.mark.parametrize(
    "column, value, expected",
    [
        (8, 9e5, "packet 3: forward speed vf 900000 m/s; expected at most 50 m/s"),
        (19, -9e5, "packet 3: yaw rate wz -900000 rad/s; expected at most 10 rad/s"),
        (0, 270.0, "packet 3: latitude lat 270 deg; expected at most 85 deg"),  # the projection: NaN
        (1, -190.0, "packet 3: longitude lon -190 deg; expected at most 180 deg"),
    ],
)
def test_one_damaged_oxts_packet_is_named(tmp_path, column, value, expected):
    """A packet whose speed or yaw rate no car reaches, among good ones, is named, not driven."""
    from vo_lib.formats.kitti_raw import read_oxts

    packets = np.zeros((5, 30))
    packets[:, 8] = 10.0  # m/s
    packets[2, column] = value
    np.savetxt(tmp_path / "oxts.txt", packets)
    with pytest.raises(SequenceError, match=re.escape(expected)):
        read_oxts(tmp_path / "oxts.txt")


def _damage_compressed_data(path: Path) -> None:
    """Flip bytes of a PNG's compressed data and rewrite the chunk's CRC, as a tool that re-saves
    a broken stream would: only the decoder can tell."""
    import struct
    import zlib

    data = bytearray(path.read_bytes())
    at = data.index(b"IDAT") - 4
    length = struct.unpack(">I", data[at : at + 4])[0]
    for k in range(at + 10, at + 8 + min(length, 40)):
        data[k] ^= 0x5A
    end = at + 8 + length
    data[end : end + 4] = zlib.crc32(bytes(data[at + 4 : end])).to_bytes(4, "big")
    path.write_bytes(bytes(data))


def test_damaged_compressed_data_is_our_one_error_on_any_thread(seq_dir, capfd):
    """The decoder says nothing of its own on stderr (the descriptor, not just sys.stderr), whether
    the frame is decoded ahead on the reader thread or on the calling one."""
    path = seq_dir[0]
    _damage_compressed_data(path / "image_0" / "000003.png")
    for read_ahead in (True, False):
        seq = read_sequence(path)
        if not read_ahead:
            seq.read_ahead = 0
        seq.pair(2)
        with pytest.raises(SequenceError, match="000003.png, frame 3: cannot read the image"):
            seq.pair(3)
    assert capfd.readouterr().err == ""


def test_an_image_larger_than_the_decoder_takes_is_refused_from_its_header(seq_dir):
    """A header that claims more pixels than Pillow decodes without its bomb warning: one line, no
    decoding; each side within the bound alone is not enough."""
    import struct
    import zlib

    path = seq_dir[0]
    ihdr = b"IHDR" + struct.pack(">IIBBBBB", 10000, 9000, 8, 0, 0, 0, 0)
    iend = b"IEND"
    png = b"\x89PNG\r\n\x1a\n"
    for chunk in (ihdr, iend):
        png += struct.pack(">I", len(chunk) - 4) + chunk + zlib.crc32(chunk).to_bytes(4, "big")
    (path / "image_1" / "000001.png").write_bytes(png)
    with pytest.raises(SequenceError, match="000001.png, frame 1: the PNG header claims 10000x9000 pixels; "):
        read_sequence(path)


def test_a_value_just_beyond_a_bound_is_not_shown_as_the_bound(tmp_path):
    """A figure rounded for its message must not read as the bound it broke ("10 m; at most 10")."""
    from vo_lib.formats.frame_files import check_metres
    from vo_lib.formats.sequence import check_frame_spacing

    with pytest.raises(SequenceError, match=r"puts cam1 10\.000000000000002 m from cam0; expected metres"):
        check_metres(tmp_path, "puts cam1 {} m from cam0", 10 + 2e-15)
    with pytest.raises(SequenceError, match=r"frames 10\.000000000000002 s apart \(median\); expected 0.001"):
        check_frame_spacing(tmp_path, np.array([0.0, 10 + 2e-15]))
    with pytest.raises(SequenceError, match=r"frames 0\.000999 s apart \(median\)"):
        check_frame_spacing(tmp_path, np.array([0.0, 0.000999, 0.001998]))
    with pytest.raises(SequenceError, match=r"comes 10\.1 s after the one before; expected at most 10 s"):
        check_frame_spacing(tmp_path, np.array([0.0, 0.1, 10.2]))
