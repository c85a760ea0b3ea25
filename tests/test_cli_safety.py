"""The command line against bad or awkward input: it exits 0 or 2 with one line, never a traceback,
and never changes a byte of a file it did not write.

Every case of the table runs ``python -m vo_lib ...`` in-process (``vo_lib.cli.main.main``) in a
fresh workspace holding a tiny user sequence ``seq/`` (4 frames of 64x48, no marker: not written
by us), a decoy ``important.txt``, a user folder ``thesis/``, an ``empty/`` folder and two
trajectory files. The checksums of every file the case does not mean to replace are compared
before and after. Signals and a read-only install run in a subprocess; the parsers of calib,
times, poses and TUM files meet random text (hypothesis).
"""

from __future__ import annotations

import hashlib
import os
import shlex
import shutil
import signal
import stat
import subprocess
import sys
import tempfile
import time
import zlib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from vo_lib.atomic import HOST
from vo_lib.camera import StereoCamera
from vo_lib.cli.main import main
from vo_lib.formats.frame_files import SequenceError, read_calib, read_poses, read_times
from vo_lib.formats.groundtruth import read_trajectory
from vo_lib.formats.poses import TrajectoryError
from vo_lib.formats.sequence import read_sequence
from vo_lib.formats.sequence_writer import write_sequence
from vo_lib.outputs import MARKER

ROOT = Path(__file__).resolve().parents[1]
W, H, FRAMES = 64, 48, 4
CAMERA = StereoCamera(50.0, 50.0, 31.5, 23.5, 0.12, W, H)


def make_sequence(path: Path, frames: int = FRAMES, size=(W, H), seed: int = 0) -> Path:
    """A user's sequence: textured images shifted a little each frame, poses and odometry; the
    marker is removed so that it counts as not written by this program."""
    rng = np.random.default_rng(seed)
    w, h = size
    base = cv2.GaussianBlur(rng.integers(0, 256, (h, w + 16), dtype=np.uint8), (3, 3), 0)
    left = [np.ascontiguousarray(base[:, k % 8 : k % 8 + w]) for k in range(frames)]
    right = [np.ascontiguousarray(base[:, k % 8 + 3 : k % 8 + 3 + w]) for k in range(frames)]
    poses = np.tile(np.eye(4), (frames, 1, 1))
    poses[:, 2, 3] = 0.01 * np.arange(frames)
    camera = CAMERA if size == (W, H) else StereoCamera(50.0, 50.0, (w - 1) / 2, (h - 1) / 2, 0.12, w, h)
    write_sequence(path, camera, left, right, np.arange(frames) / 30.0, poses, np.full((frames, 2), 0.01))
    (path / MARKER).unlink()
    return path


def kitti_rows(n: int, step: float = 0.1) -> str:
    return "".join(f"1 0 0 {step * k:.3f} 0 1 0 0 0 0 1 {0.5 * step * k:.3f}\n" for k in range(n))


@pytest.fixture(scope="module")
def template(tmp_path_factory) -> Path:
    ws = tmp_path_factory.mktemp("template")
    make_sequence(ws / "seq")
    (ws / "important.txt").write_text("years of work\n")
    (ws / "thesis").mkdir()
    (ws / "thesis" / "important.txt").write_text("chapter 1\n")
    (ws / "thesis" / "figures").mkdir()
    (ws / "thesis" / "figures" / "plot.png").write_bytes(b"\x89PNG not really")
    (ws / "empty").mkdir()
    (ws / "gt.txt").write_text(kitti_rows(5))
    (ws / "est.txt").write_text(kitti_rows(5, 0.11))
    (ws / "home").mkdir()
    (ws / "home" / "notes.txt").write_text("mine\n")
    (ws / "data").mkdir()
    (ws / "data" / "README.md").write_text("samples\n")
    return ws


def checksums(ws: Path, skip: tuple[str, ...]) -> dict[str, str]:
    """sha256 of every file of the workspace (symbolic links by their target's name), except
    under the paths a case may write (a path ending in "-" is a prefix)."""
    sums = {}
    for path in sorted(ws.rglob("*")):
        rel = path.relative_to(ws).as_posix()
        if any(rel == s or rel.startswith(s + "/") or (s.endswith("-") and rel.startswith(s)) for s in skip):
            continue
        if path.is_symlink():
            sums[rel] = "link:" + os.readlink(path)
        elif path.is_file():
            sums[rel] = hashlib.sha256(path.read_bytes()).hexdigest()
    return sums


def invoke(argv: list[str], capsys) -> tuple[int, str, str]:
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse
        code = exc.code
    out, err = capsys.readouterr()
    return code, out, err


def temporaries(ws: Path) -> list[Path]:
    """Temporaries left in ``ws`` (but a user's folder named like one, holding ``keep.txt``)."""
    found = [p for p in ws.rglob("*") if ".vo_lib-" in p.name and p.name.endswith((".tmp", ".old"))]
    return [p for p in found if not (p / "keep.txt").exists()]


# ---- setups: each shapes a fresh copy of the template ---------------------------------------------


def image(ws, side, k) -> Path:
    return ws / "seq" / f"image_{side}" / f"{k:06d}.png"


def unpadded(ws):
    """12 frames named 0.png .. 11.png: text order would run 0, 1, 10, 11, 2 ..."""
    shutil.rmtree(ws / "seq", ignore_errors=True)
    make_sequence(ws / "seq", frames=12)
    for side in (0, 1):
        for k in range(12):
            image(ws, side, k).rename(ws / "seq" / f"image_{side}" / f"{k}.png")


def write_png(path: Path, img: np.ndarray):
    assert cv2.imwrite(str(path), img)


def damaged_png_data(ws):
    """Header and end chunk intact, compressed data damaged: found only when decoded."""
    path = image(ws, 0, 2)
    data = bytearray(path.read_bytes())
    start = data.index(b"IDAT") + 8
    for k in range(start, start + 40):
        data[k] ^= 0x5A
    path.write_bytes(bytes(data))


def with_an_empty_apng_chunk(ws):
    """A valid PNG with an animation chunk that claims no frames: Pillow reads the image and warns."""
    path = image(ws, 0, 2)
    data = path.read_bytes()
    body = b"acTL" + bytes(8)
    path.write_bytes(
        data[:33] + (8).to_bytes(4, "big") + body + zlib.crc32(body).to_bytes(4, "big") + data[33:]
    )


def as_jpeg(ws):
    for path in (ws / "seq").glob("image_*/*.png"):
        assert cv2.imwrite(str(path.with_suffix(".jpg")), cv2.imread(str(path), cv2.IMREAD_UNCHANGED))
        path.unlink()


def truncated_jpeg(ws):
    as_jpeg(ws)
    path = ws / "seq" / "image_0" / "000001.jpg"
    path.write_bytes(path.read_bytes()[:-200])


def said(err: str) -> list[str]:
    """The lines of ``err`` but the notice that the workspace's images (64x48: no corners inside
    ORB's border) give every run: most frames had too few stereo features."""
    return [line for line in err.strip().splitlines() if "frames had too few stereo features" not in line]


def run_once(out: str):
    def setup(ws):
        assert main(["run", "--sequence", "seq", "--out", out]) == 0

    return setup


def dead_pid() -> int:
    """The number of a process that has ended."""
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    return dead.pid


def stale_temporary(ws):
    pid = dead_pid()
    stale = ws / f".out.vo_lib-{pid}-{HOST}-abcd1234.tmp"
    stale.mkdir()
    (stale / "poses.txt").write_text("half\n")
    foreign = ws / ".out.someone-else.tmp"  # not ours: must survive
    foreign.mkdir()
    (foreign / "keep.txt").write_text("keep\n")
    other = ws / f".notes.vo_lib-{pid}-{HOST}-mine.tmp"  # beside another name: not judged
    other.mkdir()
    (other / "keep.txt").write_text("keep\n")


def named_like_a_temporary(random: str, beside: str):
    """A user's folder named as a dead process's temporary beside ``beside`` would be."""

    def setup(ws):
        folder = ws / f".{beside}.vo_lib-{dead_pid()}-{HOST}-{random}.tmp"
        folder.mkdir()
        (folder / "keep.txt").write_text("keep\n")

    return setup


def kept_like_a_temporary(ws):
    return len(list(ws.glob(".*.vo_lib-*/keep.txt"))) == 1


def edit(rel: str, text: str | bytes):
    def setup(ws):
        path = ws / rel
        path.write_bytes(text if isinstance(text, bytes) else text.encode())

    return setup


def do(*steps):
    def setup(ws):
        for step in steps:
            step(ws)

    return setup


@dataclass
class Case:
    """One row: ``args`` is a command line (``RUN``, ``GEN`` and ``EVAL`` stand for the commands
    below) or a list; ``writes``, the paths the case may write or replace, space-separated;
    ``umask``, the process's umask while the command runs (left as it is if None)."""

    id: str
    args: str | list[str]
    code: int
    phrase: str
    setup: Callable | None = None
    writes: str = ""
    cwd: str = "."
    check: Callable | None = None
    umask: int | None = None

    @property
    def argv(self) -> list[str]:
        words = shlex.split(self.args) if isinstance(self.args, str) else self.args
        return [w for word in words for w in ALIASES.get(word, [word])]


def linked_into(ws: Path, name: str, folder: str) -> None:
    """Move the sequence's ``name`` into the user's ``folder`` and link it from where it was."""
    (ws / "seq" / name).rename(ws / folder / name)
    (ws / "seq" / name).symlink_to(Path("..") / folder / name)


def linked_twice(ws: Path) -> None:
    """seq/image_0 links to a folder of links, which lead to the user's files in ``thesis``."""
    (ws / "links").mkdir()
    for png in sorted((ws / "seq" / "image_0").iterdir()):
        png.rename(ws / "thesis" / png.name)
        (ws / "links" / png.name).symlink_to(Path("..") / "thesis" / png.name)
    (ws / "seq" / "image_0").rmdir()
    (ws / "seq" / "image_0").symlink_to(Path("..") / "links")


def link(name: str, to: str):
    return lambda ws: (ws / name).symlink_to(to)


def modes(expected: dict[str, int]):
    """The permission bits of each path, as ``{relative path: mode}``."""
    return lambda ws: {rel: stat.S_IMODE((ws / rel).stat().st_mode) for rel in expected} == expected


def reads(rel: str, text: str):
    return lambda ws: (ws / rel).read_text() == text


def gone(rel):
    return lambda ws: not (ws / rel).exists()


def has_marker(rel):
    return lambda ws: (ws / rel / MARKER).is_file() and (ws / rel / "poses.txt").is_file()


RUN = ["run", "--sequence", "seq"]
SAMPLE_MANIFEST = "data/corridor_2f/manifest.json"
#: A manifest's position-only truth without the name of the file it came from.
POSITIONS_ONLY = (
    '{"positions": {"frames": [0, 1, 2, 3], "xyz": [[0, 0, 0], [0, 0, 0.01], [0, 0, 0.02], [0, 0, 0.03]], '
    '"lever_arm_camera": [0, 0, 0]}}'
)
#: A crawler's manifest with the track odometry's settings ``%s``.
CRAWLER_TRACK = '{"camera": {"height_m": 0.5}, "track_odometry": {%s}}'
GEN = ["generate", "corridor", "--frames", "2", "--resolution", "64x48"]
EVAL = ["evaluate", "--gt", "gt.txt", "--est", "est.txt"]
ALIASES = {"RUN": RUN, "GEN": GEN, "EVAL": EVAL}

# fmt: off
CASES = [
    # --- outputs: never over what the program did not write ---------------------------------------
    Case("out-new", "RUN --out out", 0, "wrote out/", writes="out", check=has_marker("out")),
    Case("out-follows-the-umask", "RUN --out out", 0, "wrote out/", writes="out", umask=0o027,
        check=modes({"out": 0o750, "out/poses.txt": 0o640})),
    Case("out-nested-new", "RUN --out a/b/out", 0, "wrote", writes="a", check=has_marker("a/b/out")),
    Case("out-ours-again", "RUN --out out", 0, "wrote", run_once("out"), "out", check=has_marker("out")),
    Case("out-empty", "RUN --out empty", 0, "wrote", writes="empty", check=has_marker("empty")),
    Case("out-user-folder", "RUN --out thesis", 2, "this program replaces only what it wrote"),
    Case("out-user-folder-force", "RUN --out thesis --force", 2, "this program replaces only what it wrote"),
    Case("out-ours-file-edited", "RUN --out out", 2, "poses.txt was added, changed or removed",
        do(run_once("out"), edit("out/poses.txt", "mine")), "out", check=reads("out/poses.txt", "mine")),
    Case("out-ours-plus-user-file", "RUN --out out", 2, "notes.txt",
        do(run_once("out"), edit("out/notes.txt", "mine")), "out", check=reads("out/notes.txt", "mine")),
    Case("out-is-input", "RUN --out seq", 2, "is the input sequence"),
    Case("out-is-input-force", "RUN --out seq --force", 2, "is the input sequence"),
    Case("out-above-input-force", "RUN --out . --force", 2, "holds the input sequence"),
    Case("out-inside-input", "RUN --out seq/results", 2, "inside the input sequence"),
    Case("out-is-cwd-force", "run --sequence ../seq --out . --force", 2, "is the current folder",
        cwd="thesis"),
    Case("out-above-cwd-force", "run --sequence ../seq --out .. --force", 2, "holds the input sequence",
        cwd="thesis"),
    Case("out-home-force", "RUN --out home --force", 2, "your home folder"),
    # what the input reads through a symbolic link is input too: its truth, its images
    Case("out-holds-a-linked-input-file-force", "RUN --out thesis --force", 2,
        "holds what the input sequence links to", lambda ws: linked_into(ws, "poses.txt", "thesis")),
    Case("out-is-a-linked-input-folder-force", "RUN --out thesis/image_1 --force", 2,
        "is what the input sequence links to", lambda ws: linked_into(ws, "image_1", "thesis")),
    Case("out-holds-images-linked-through-a-linked-folder-force", "RUN --out thesis --force", 2,
        "holds what the input sequence links to", linked_twice),
    Case("convert-over-its-input-force", "convert seq --out seq/image_0 --force", 2,
        "inside the input sequence"),
    Case("convert-above-its-input-force", "convert seq --out . --force", 2, "holds the input sequence"),
    Case("out-empty-text", "RUN --out ''", 2, "--out: expected a folder; got an empty text"),
    Case("sequence-empty-text", "run --sequence ''", 2, "--sequence: expected a sample name"),
    Case("generate-out-empty-text", "GEN --out ''", 2, "--out: expected a folder"),
    Case("convert-out-empty-text", "convert seq --out ''", 2, "--out: expected a folder"),
    Case("generate-package-force", [*GEN, "--out", str(ROOT / "vo_lib" / "x"), "--force"], 2,
        "inside this package"),
    Case("generate-repo-data-force", [*GEN, "--out", str(ROOT / "data"), "--force"], 2, "sample data folder"),
    Case("out-data-folder-force", "RUN --out data --force", 2, "sample data folder"),
    Case("out-inside-data-folder-force", "RUN --out data/indoor_free --force", 2,
        "--out data/indoor_free: lies inside the sample data folder"),
    Case("convert-odometry-a-folder", "convert seq --out conv", 2, "odometry.txt: a folder, where",
        lambda ws: ((ws / "seq" / "odometry.txt").unlink(), (ws / "seq" / "odometry.txt").mkdir())),
    Case("convert-oxts-a-folder", "convert seq --out conv", 2, "oxts.txt: a folder, where a file should be",
        lambda ws: (ws / "seq" / "oxts.txt").mkdir()),
    Case("out-is-a-file", "RUN --out important.txt", 2, "is a file"),
    Case("out-is-a-file-force", "RUN --out important.txt --force", 2, "is a file"),
    Case("out-under-a-file", "RUN --out important.txt/sub", 2, "cannot write there"),
    Case("out-symlink-to-ours", "RUN --out link", 0, "wrote", do(run_once("real"), link("link", "real")),
        "real link", check=lambda ws: (ws / "link").is_symlink() and (ws / "real" / MARKER).is_file()),
    Case("out-symlink-to-user-folder", "RUN --out link", 2, "replaces only what", link("link", "thesis")),
    Case("out-in-a-link-loop", "RUN --out loop/out", 2, "cannot write there", link("loop", "loop")),
    Case("input-holds-a-link-loop", "RUN --out out", 0, "wrote",
        do(link("seq/a", "b"), link("seq/b", "a")), "out"),
    Case("out-marker-damaged-names", "RUN --out out", 2, "is damaged", do(run_once("out"),
        edit("out/.vo_lib_output.json", '{"written_by": "vo_lib run", "contents": [{"a": 1}]}')), "out"),
    Case("out-dangling-symlink", "RUN --out link", 2, "does not exist", link("link", "nowhere")),
    Case("stale-temporary-removed", "RUN --out out", 0, "removed 1 temporary folder", stale_temporary,
        "out .out.vo_lib-", check=lambda ws: (ws / ".out.someone-else.tmp" / "keep.txt").exists()
        and len(list(ws.glob(".notes.vo_lib-*/keep.txt"))) == 1),
    Case("temporary-name-huge-pid", "RUN --out out", 0, "wrote",
        lambda ws: (ws / f".out.vo_lib-{10**20}-{HOST}-abcdefgh.old/keep.txt").mkdir(parents=True), "out"),
    Case("marker-a-pipe", "RUN --out out", 2, "marker .vo_lib_output.json is damaged",
        lambda ws: ((ws / "out").mkdir(), os.mkfifo(ws / "out" / MARKER))),
    Case("temporary-name-kept-when-refused", "RUN --out thesis", 2, "replaces only what it wrote",
        named_like_a_temporary("abcd1234", "thesis"), check=kept_like_a_temporary),
    Case("temporary-name-not-ours-kept", "RUN --out out", 0, "wrote", named_like_a_temporary("x", "out"),
        "out", check=kept_like_a_temporary),
    # --- the sequence: paired by name, numeric order, headers checked ----------------------------
    Case("sequence-missing", "run --sequence nowhere", 2, "neither a sample name"),
    Case("sequence-is-a-file", "run --sequence important.txt", 2, "not a sequence folder"),
    Case("unpadded-names", "RUN --out out", 0, "wrote", unpadded, "out"),
    Case("right-image-missing", "RUN", 2, "image_0/000002.png", lambda ws: image(ws, 1, 2).unlink()),
    Case("names-differ", "RUN", 2, "image_1/000009.png", lambda ws: image(ws, 1, 3).rename(image(ws, 1, 9))),
    Case("same-number-twice", "RUN", 2, "same frame number",
        lambda ws: shutil.copy(image(ws, 0, 1), ws / "seq" / "image_0" / "1.png")),
    Case("hidden-files-ignored", "RUN --out out", 0, "wrote",
        edit("seq/image_0/._000001.png", b"\x00\x05\x16\x07 resource fork"), "out"),
    Case("image-a-pipe", "RUN", 2, "image_1/000001.png: a device, pipe or socket named like an image",
        lambda ws: (image(ws, 1, 1).unlink(), os.mkfifo(image(ws, 1, 1)))),
    Case("image-a-link-to-a-device", "RUN", 2, "000002.png: a device, pipe or socket named like an image",
        lambda ws: (image(ws, 0, 2).unlink(), image(ws, 0, 2).symlink_to("/dev/zero"))),
    Case("zero-byte-image", "RUN", 2, "000002.png, frame 2: empty file", edit("seq/image_0/000002.png", b"")),
    Case("truncated-image", "RUN", 2, "frame 2: truncated PNG",
        lambda ws: image(ws, 1, 2).write_bytes(image(ws, 1, 2).read_bytes()[:300])),
    Case("not-an-image", "RUN", 2, "frame 1: cannot read the image",
        edit("seq/image_0/000001.png", b"hello")),
    Case("jpeg-sequence", "RUN --out out", 0, "wrote", as_jpeg, "out"),
    Case("truncated-jpeg", "RUN", 2, "000001.jpg, frame 1: truncated JPEG", truncated_jpeg),
    Case("16-bit-image", "RUN", 2, "frame 3: 16-bit image",
        lambda ws: write_png(image(ws, 0, 3), np.zeros((H, W), np.uint16))),
    Case("size-changes", "RUN", 2, "frame 2: 60x48 image",
        lambda ws: write_png(image(ws, 1, 2), np.zeros((H, 60), np.uint8))),
    Case("colour-image-is-converted", "RUN --out out", 0, "wrote",
        lambda ws: write_png(image(ws, 0, 1), np.full((H, W, 3), 90, np.uint8)), "out"),
    Case("damaged-image-data", "RUN --out out", 2, "000002.png, frame 2: cannot read the image",
        damaged_png_data, check=gone("out")),
    # the run stops cleanly: the earlier output is left as it was, byte for byte
    Case("damaged-image-keeps-earlier-output", "RUN --out out", 2, "frame 2: cannot read the image",
        do(run_once("out"), damaged_png_data)),
    # --force replaces only when the run succeeds: the other command's output is untouched
    Case("force-but-bad-input", "RUN --out gen --force", 2, "frame 2: empty file",
        do(lambda ws: main([*GEN, "--out", "gen"]), edit("seq/image_1/000002.png", b"")), "gen",
        check=has_marker("gen")),
    Case("corrupt-manifest", "RUN", 2, "manifest.json: not valid JSON", edit("seq/manifest.json", "{oops")),
    Case("manifest-utf16", "RUN", 2, "manifest.json: not a text file (byte 0 is not UTF-8)",
        edit("seq/manifest.json", "{}".encode("utf-16"))),
    Case("manifest-height-true", "RUN", 2, "camera.height_m: expected a number from 0 to 10, got true",
        edit("seq/manifest.json", '{"camera": {"height_m": true}}')),
    Case("manifest-positions-without-file", "RUN --out out", 0, "(the manifest's positions, 4 positions)",
        do(lambda ws: (ws / "seq" / "poses.txt").unlink(), edit("seq/manifest.json", POSITIONS_ONLY)), "out"),
    Case("raw-calib-a-file", "RUN", 2, "raw_calib: not a folder, where that of KITTI's raw calibration",
        edit("seq/raw_calib", "R: 1 0 0")),
    Case("convert-raw-calib-a-file", "convert seq --out conv", 2, "raw_calib: not a folder, where that",
        edit("seq/raw_calib", "R: 1 0 0")),
    Case("raw-calib-a-broken-link", "RUN", 2, "raw_calib: not a folder", link("seq/raw_calib", "nowhere")),
    Case("convert-raw-calib-not-a-rotation", "convert seq --out conv", 2,
        "calib_imu_to_velo.txt: R: it is not a rotation matrix", do(lambda ws: (ws / "seq/raw_calib").mkdir(),
        edit("seq/raw_calib/calib_imu_to_velo.txt", "R: 0 0 0 0 0 0 0 0 0\nT: 0 0 0\n")), check=gone("conv")),
    Case("sequence-links-to-the-root", "RUN --out out", 2, "lies inside what the input sequence links to",
        link("seq/everything", "/")),
    Case("convert-inside-data-folder-force", "convert seq --out data/x --force", 2,
        "lies inside the sample data folder"),
    Case("sweep-inside-data-folder", "sweep nees --seeds 1 --workers 1 --out data/x", 2,
        "lies inside the sample data folder"),
    # VO_LIB_DATA points elsewhere (the workspace's): the checkout's own samples are kept too
    Case("run-inside-the-checkouts-data-folder", f"RUN --out {ROOT / 'data' / 'x'}", 2,
        "lies inside the checkout's sample data folder", check=lambda ws: not (ROOT / "data" / "x").exists()),
    Case("manifest-height-huge-integer", "RUN", 2, "camera.height_m: expected a number from 0 to 10",
        edit("seq/manifest.json", '{"camera": {"height_m": 1' + "0" * 400 + "}}")),
    Case("convert-empty-text", "convert '' --out conv", 2, "argument sequence: expected a recording folder"),
    Case("evaluate-gt-empty-text", "evaluate --gt '' --est seq/poses.txt", 2, "--gt: expected a ground"),
    Case("sample-manifest-damaged", "run --sequence corridor --frames 2 --out out", 2,
        "corridor_2f: the folder exists and manifest.json was added, changed or removed",
        do(lambda ws: main(["generate", "corridor", "--frames", "2"]), edit(SAMPLE_MANIFEST, "[1]")),
        "data"),
    Case("manifest-nested-deep", "RUN", 2, "manifest.json: not valid JSON",
        edit("seq/manifest.json", "[" * 100_000 + "]" * 100_000)),
    Case("manifest-number-too-long", "RUN", 2, "manifest.json: not valid JSON (a number too long)",
        edit("seq/manifest.json", '{"time_origin_s": 1' + "0" * 5000 + "}")),
    Case("manifest-time-origin-text", "RUN", 2,
        "time_origin_s: expected a number from -1e+10 to 1e+10, got \"abc\"",
        edit("seq/manifest.json", '{"time_origin_s": "abc"}')),
    Case("manifest-unknown-key", "RUN", 2, "key bogus is not a manifest's; expected some of",
        edit("seq/manifest.json", '{"bogus": 1}')),
    Case("manifest-misspelt-camera-key", "RUN", 2, "key camera.heigth_m is not a manifest's; expected",
        edit("seq/manifest.json", '{"camera": {"heigth_m": 0.5}}')),
    Case("manifest-unknown-positions-key", "RUN", 2, "key positions.lever_arm is not a manifest's",
        edit("seq/manifest.json", POSITIONS_ONLY.replace('"lever_arm_camera"', '"lever_arm"'))),
    Case("manifest-mount-a-word", "RUN", 2, "T_body_camera: expected 4 rows of 4 numbers within ±1000 m, got",
        edit("seq/manifest.json", '{"T_body_camera": "identity"}')),
    Case("manifest-mount-3x3", "RUN", 2, "key T_body_camera: expected 4 rows of 4 numbers within ±1000 m",
        edit("seq/manifest.json", '{"T_body_camera": [[1, 0, 0], [0, 1, 0], [0, 0, 1]]}')),
    Case("manifest-height-a-word", "RUN", 2, "camera.height_m: expected a number from 0 to 10, got \"tall\"",
        edit("seq/manifest.json", '{"camera": {"height_m": "tall"}}')),
    Case("manifest-time-origin-beyond", "RUN", 2, "key time_origin_s: expected a number from -1e+10 to 1e+10",
        edit("seq/manifest.json", '{"time_origin_s": 1e300}')),
    Case("manifest-height-negative", "RUN", 2, "camera.height_m: expected a number from 0 to 10, got -0.5",
        edit("seq/manifest.json", '{"camera": {"height_m": -0.5}}')),
    Case("manifest-mount-unknown", "RUN", 2, "key camera.mount: expected 'above turning axis' or",
        edit("seq/manifest.json", '{"camera": {"height_m": 0.5, "mount": "above the turning axis"}}')),
    Case("manifest-unknown-track-setting", "RUN", 2, "key track_odometry.gauge is not a manifest's",
        edit("seq/manifest.json", '{"camera": {"height_m": 0.5}, "track_odometry": {"gauge": 0.6}}')),
    Case("manifest-encoder-noise-beyond", "RUN", 2,
        "track_odometry.encoder_sigma: expected a number from 0 to 1, got 1e+160",
        edit("seq/manifest.json", CRAWLER_TRACK % '"encoder_sigma": 1e160')),
    Case("manifest-track-a-truth-value", "RUN", 2,
        "track_odometry.track_distance: expected a number from 0",
        edit("seq/manifest.json", CRAWLER_TRACK % '"track_distance": true')),
    Case("manifest-no-gauge", "RUN", 2,
        "track_distance + 2 track_width is 2e-300 m; expected at least 0.01 m",
        edit("seq/manifest.json", CRAWLER_TRACK % '"track_distance": 0, "track_width": 1e-300')),
    Case("manifest-mount-beyond", "RUN", 2, "T_body_camera: expected 4 rows of 4 numbers within ±1000 m",
        edit("seq/manifest.json", '{"T_body_camera": [[1, 0, 0, 1e100], [0, 1, 0, 0], [0, 0, 1, 0], '
             '[0, 0, 0, 1]]}')),
    Case("manifest-positions-beyond", "RUN", 2,
        "key positions.frames: expected 3 or more frame numbers 0 to 3",
        edit("seq/manifest.json", '{"positions": {"file": "x", "frames": [0, 9], '
             '"xyz": [[0, 0, 0], [1, 0, 0]], "lever_arm_camera": [0, 0, 0]}}')),
    Case("manifest-positions-repeated", "RUN", 2, "positions.frames: expected increasing frame numbers",
        edit("seq/manifest.json", POSITIONS_ONLY.replace("[0, 1, 2, 3]", "[3, 3, 3, 3]"))),
    Case("manifest-positions-far", "RUN", 2, "positions.xyz: expected 4 rows of x y z within ±1e+08 m",
        edit("seq/manifest.json", POSITIONS_ONLY.replace("[0, 0, 0.03]", "[0, 0, 1e300]"))),
    Case("manifest-lever-arm-far", "RUN", 2, "positions.lever_arm_camera: expected 3 numbers within ±1000 m",
        edit("seq/manifest.json", POSITIONS_ONLY.replace("[0, 0, 0]}", "[1e300, 0, 0]}"))),
    Case("manifest-positions-file-a-list", "RUN", 2, "positions.file: expected a text, got",
        edit("seq/manifest.json", POSITIONS_ONLY.replace('{"frames"', '{"file": ["x"], "frames"'))),
    Case("calib-focal-beyond", "RUN", 2, "calib.txt: P0's focal length 1e+300 px is over 100 image widths",
        edit("seq/calib.txt", "P0: 1e300 0 31.5 0 0 1e300 23.5 0 0 0 1 0\n"
             "P1: 1e300 0 31.5 -1e300 0 1e300 23.5 0 0 0 1 0")),
    Case("calib-no-p1", "RUN", 2, "no P1 line", edit("seq/calib.txt", "P0: " + "1 " * 12 + "\n")),
    Case("calib-short-line", "RUN", 2, "calib.txt, line 2: P1 needs 12 numbers",
        edit("seq/calib.txt", "P0: 50 0 31.5 0 0 50 23.5 0 0 0 1 0\nP1: 1 2 3\n")),
    Case("calib-binary", "RUN", 2, "calib.txt: not a text file", edit("seq/calib.txt", b"\xff\xfe\x00P0")),
    Case("times-short", "RUN", 2, "has 3 timestamps but there are 4 images",
        edit("seq/times.txt", "0\n1\n2\n")),
    Case("times-backwards", "RUN", 2, "times.txt, line 3", edit("seq/times.txt", "0\n1\n0.5\n2\n")),
    Case("times-with-an-underscore", "RUN", 2, "times.txt, line 4: a timestamp holds '0.3_0'; expected plain",
        edit("seq/times.txt", "0\n0.1\n0.2\n0.3_0\n")),
    Case("times-with-wide-digits", "RUN", 2, "times.txt, line 2: a timestamp holds '\uff11'; expected plain",
        edit("seq/times.txt", "0\n\uff11\n2\n3\n")),
    Case("times-with-a-comment", "RUN --out out", 0, "wrote",
        edit("seq/times.txt", "# t [s]\n0\n1\n2\n3\n"), "out"),
    Case("times-with-a-pause", "RUN", 2, "times.txt: the frame at 100000000 s comes 1e+08 s after the one",
        edit("seq/times.txt", "0\n0.1\n100000000\n100000000.1\n")),
    Case("times-in-milliseconds", "RUN", 2, "times.txt: frames 33.3 s apart (median); expected 0.001 to 10 s",
        edit("seq/times.txt", "0\n33.3\n66.6\n99.9\n")),
    Case("calib-baseline-in-millimetres", "RUN", 2, "calib.txt: P1 puts the right camera 120 from the left",
        edit("seq/calib.txt", "P0: 50 0 31.5 0 0 50 23.5 0 0 0 1 0\nP1: 50 0 31.5 -6e3 0 50 23.5 0 0 0 1 0")),
    Case("calib-focal-tiny", "RUN", 2, "calib.txt: P0's focal lengths fx=0.001, fy=0.001 px; expected pixels",
        edit("seq/calib.txt", "P0: 1e-3 0 31.5 0 0 1e-3 23.5 0 0 0 1 0\n"
             "P1: 1e-3 0 31.5 -1e-4 0 1e-3 23.5 0 0 0 1 0")),
    Case("calib-focal-ratio", "RUN", 2, "calib.txt: P0's focal lengths fx=50, fy=500 px; expected",
        edit("seq/calib.txt", "P0: 50 0 31.5 0 0 500 23.5 0 0 0 1 0\nP1: 50 0 31.5 -6 0 500 23.5 0 0 0 1 0")),
    Case("calib-not-rectified", "RUN", 2, "calib.txt: P0 and P1 are not a rectified pair",
        edit("seq/calib.txt", "P0: 50 0 31.5 0 0 50 23.5 0 0 0 1 0\nP1: 60 0 31.5 -6 0 50 23.5 0 0 0 1 0")),
    Case("calib-skewed", "RUN", 2, "calib.txt: P0 and P1 are not a rectified pair",
        edit("seq/calib.txt", "P0: 50 9 31.5 0 0 50 23.5 0 0 0 1 0\nP1: 50 9 31.5 -6 0 50 23.5 0 0 0 1 0\n")),
    Case("calib-baseline-nothing", "RUN", 2, "calib.txt: P1 puts the right camera 2e-08 from the left",
        edit("seq/calib.txt", "P0: 50 0 31.5 0 0 50 23.5 0 0 0 1 0\n"
             "P1: 50 0 31.5 -1e-6 0 50 23.5 0 0 0 1 0")),
    Case("calib-principal-point-outside", "RUN", 2, "P0's principal point (315, 23.5) lies outside the 64x48",
        edit("seq/calib.txt", "P0: 50 0 315 0 0 50 23.5 0 0 0 1 0\nP1: 50 0 315 -6 0 50 23.5 0 0 0 1 0\n")),
    Case("calib-right-camera-off-the-rows", "RUN", 2,
        "calib.txt: P1 puts the right camera at (63000.1, 45000, -100000) from the left; expected",
        edit("seq/calib.txt", "P0: 50 0 31.5 0 0 50 23.5 0 0 0 1 0\n"
             "P1: 50 0 31.5 -6 0 50 23.5 1e5 0 0 1 1e5")),
    Case("odometry-in-millimetres", "RUN", 2, "odometry.txt: the tracks move 300 per second",
        edit("seq/odometry.txt", "0 0\n10 10\n10 10\n10 10\n")),
    Case("odometry-one-row-damaged", "RUN", 2, "odometry.txt: frame 2: the tracks move 30000 m/s (with",
        edit("seq/odometry.txt", "0 0\n0.01 0.01\n1000 1000\n0.01 0.01\n")),
    Case("poses-nan", "RUN", 2, "poses.txt, line 2",
        edit("seq/poses.txt", kitti_rows(1) + "1 0 0 nan 0 1 0 0 0 0 1 0\n" + kitti_rows(2))),
    Case("poses-not-rotation", "RUN", 2, "not a rotation matrix",
        edit("seq/poses.txt", "0 " * 12 + "\n" * 1 + kitti_rows(3))),
    Case("odometry-malformed", "RUN", 2, "odometry.txt, line 2",
        edit("seq/odometry.txt", "0 0\n0.01\n0 0\n0 0\n")),
    Case("odometry-absurd", "RUN", 2, "odometry.txt, line 2: a number beyond",
        edit("seq/odometry.txt", "0 0\n1e300 -1e300\n0 0\n0 0\n")),
    Case("no-odometry-ignores-it", "RUN --no-odometry --out out", 0, "wrote",
        edit("seq/odometry.txt", b"\xff garbage"), "out"),
    Case("no-right-folder", "RUN", 2, "image_1: missing image folder",
        lambda ws: shutil.rmtree(ws / "seq" / "image_1")),
    Case("kitti-colour-pair-only", "RUN", 2, "colour pair image_2, image_3 is there: the grey pair",
        lambda ws: [(ws / "seq" / f"image_{k}").rename(ws / "seq" / f"image_{k + 2}") for k in (0, 1)]),
    Case("right-folder-a-file", "RUN", 2, "image_1: a file where the image folder should be",
        lambda ws: (shutil.rmtree(ws / "seq" / "image_1"), (ws / "seq" / "image_1").write_text(""))),
    Case("sequence-a-file-out-ours", "run --sequence important.txt --out out", 2,
        "--sequence important.txt: a file, not a sequence folder", run_once("out"), "out"),
    Case("sequence-is-its-image-folder", "run --sequence seq/image_0", 2,
        "missing image folder; give the folder holding image_0"),
    Case("sequence-holds-nothing", "run --sequence empty", 2,
        "empty holds no sequence: expected image_0/ and image_1/ (KITTI), mav0/"),
    Case("no-images", "RUN", 2, "image_0: no images",
        lambda ws: [p.unlink() for p in (ws / "seq").glob("image_*/*.png")]),
    # --- bounds ----------------------------------------------------------------------------------
    Case("seed-negative", "RUN --seed -5", 2, "--seed"),
    Case("seed-not-a-number", "RUN --seed abc", 2, "--seed"),
    Case("frames-one", "RUN --frames 1", 2, "expected a whole number >= 2 (frames)"),
    Case("generate-frames-one", "GEN --frames 1", 2, "expected a whole number >= 2 (frames)"),
    Case("frames-zero", "RUN --frames 0", 2, "expected a whole number >= 2 (frames)"),
    Case("frames-not-a-number", "RUN --frames many", 2, "expected a whole number"),
    Case("frames-beyond-sequence", "RUN --frames 99 --out out", 0, "has 4 frames; running all 4",
        writes="out"),
    Case("unknown-option", "RUN --fast", 2, "unrecognized arguments"),
    Case("option-name-cut-short", "RUN --frame 3", 2, "run: error: unrecognized arguments: --frame 3"),
    Case("default-out-of-a-short-run", "RUN --frames 3", 0, "wrote runs/seq_3f/", run_once("runs/seq"),
        "runs", check=lambda ws: (ws / "runs" / "seq" / MARKER).is_file()),
    # --- generate --------------------------------------------------------------------------------
    Case("generate-new", "GEN --out gen", 0, "wrote gen", writes="gen",
        check=lambda ws: read_sequence(ws / "gen").camera.width == 64),
    Case("generate-follows-the-umask", "GEN --out gen", 0, "wrote gen", writes="gen", umask=0o027,
        check=modes({"gen": 0o750, "gen/image_0": 0o750})),
    Case("generate-ours-again", "GEN --out gen", 2, "--out gen: holds a sequence generated earlier",
        lambda ws: main([*GEN, "--out", "gen"])),
    Case("generate-ours-again-force", "GEN --out gen --force", 0, "wrote gen",
        lambda ws: main([*GEN, "--out", "gen"]), "gen"),
    Case("generate-over-user-sequence", "GEN --out seq", 2, "replaces only what it wrote"),
    Case("generate-over-user-folder", "GEN --out thesis", 2, "replaces only what it wrote"),
    Case("generate-over-user-sequence-force", "GEN --out seq --force", 2, "replaces only what it wrote"),
    Case("generate-over-user-folder-force", "GEN --out thesis --force", 2, "replaces only what it wrote"),
    Case("generate-over-a-file", "GEN --out important.txt", 2, "is a file"),
    Case("generate-huge-resolution", "generate corridor --resolution 100000x100000", 2, "32..4096"),
    Case("generate-tiny-resolution", "generate corridor --resolution 10x10", 2, "32..4096"),
    Case("generate-bad-resolution", "generate corridor --resolution big", 2, "expected WIDTHxHEIGHT"),
    Case("generate-unknown-sample", "generate nope", 2, "invalid choice: 'nope'"),
    Case("generate-too-many-frames", "generate corridor --frames 100000 --out gen", 2,
        "--frames 100000: corridor has 541 frames; expected 2 to 541", check=gone("gen")),
    # --- evaluate --------------------------------------------------------------------------------
    Case("evaluate-ok", "EVAL --segments 0.1,0.2", 0, "ATE (SE(3) alignment)"),
    Case("evaluate-nan-row", "EVAL", 2, "est.txt, line 3: holds a NaN",
        edit("est.txt", kitti_rows(2) + "1 0 0 nan 0 1 0 0 0 0 1 0\n" + kitti_rows(2))),
    Case("evaluate-inf-row", "EVAL", 2, "gt.txt, line 1: holds a NaN or infinite",
        edit("gt.txt", "1 0 0 inf 0 1 0 0 0 0 1 0\n" + kitti_rows(4))),
    Case("evaluate-one-pose", "EVAL", 2, "gt.txt: 1 pose (last on line 2); need at least 2",
        edit("gt.txt", "# one pose\n" + kitti_rows(1))),
    Case("evaluate-empty", "EVAL", 2, "est.txt: no poses", edit("est.txt", "")),
    Case("evaluate-one-word", "EVAL", 2, "est.txt: no poses (line 1, 'garbage', reads as a header of names)",
        edit("est.txt", "garbage\n")),
    Case("evaluate-count-mismatch", "EVAL", 2, "has 5 poses but --est est.txt has 4",
        edit("est.txt", kitti_rows(4))),
    Case("evaluate-segments-text", "EVAL --segments abc", 2, "lengths in metres"),
    Case("evaluate-segments-negative", "EVAL --segments 0,-1", 2, "lengths in metres"),
    Case("evaluate-segments-nan", "EVAL --segments nan", 2, "each 0.001 to 1e+06"),
    Case("evaluate-segments-tiny", "EVAL --segments 1e-300", 2, "each 0.001 to 1e+06"),
    Case("evaluate-missing-file", "evaluate --gt missing.txt --est est.txt", 2,
        "missing.txt: missing (the trajectory)"),
    Case("evaluate-folder", "evaluate --gt thesis --est est.txt", 2,
        "thesis: a folder, where the trajectory"),
    Case("evaluate-zero-quaternion", "EVAL", 2, "line 2: the quaternion",
        edit("est.txt", "0 0 0 0 0 0 0 1\n0.1 0 0 0 0 0 0 0\n" + "0.2 0 0 0 0 0 0 1\n" * 3)),
    Case("evaluate-not-rotation", "EVAL", 2, "est.txt, line 1: the first three columns are not a rotation",
        edit("est.txt", "2 0 0 0 0 1 0 0 0 0 1 0\n" + kitti_rows(4))),
    Case("evaluate-binary", "EVAL", 2, "gt.txt: not a text file",
        edit("gt.txt", b"\x89PNG\r\n\x1a\n\xff\xff")),
    Case("evaluate-mixed-formats", "EVAL", 2, "line 2: expected 12 numbers like line 1, got 8",
        edit("est.txt", kitti_rows(1) + "0 0 0 0 0 0 0 1\n")),
    Case("evaluate-huge-position", "EVAL", 2, "beyond",
        edit("est.txt", "1 0 0 1e300 0 1 0 0 0 0 1 0\n" + kitti_rows(4))),
]
# fmt: on


def user_kitti_files(ws):
    """A folder of the user's own holding KITTI's file names (what a run writes, too)."""
    (ws / "u").mkdir()
    (ws / "u" / "poses.txt").write_text("my own poses\n")
    (ws / "u" / "timings.csv").write_text("t\n")
    (ws / "u" / "diagnostics.csv").write_text("d\n")


def finished_sweep(ws):
    assert main(["sweep", "nees", "--seeds", "2", "--workers", "1", "--out", "R"]) == 0


def generated(rel: str):
    def setup(ws):
        assert main([*GEN, "--out", rel]) == 0

    return setup


def one_frame(ws):
    shutil.rmtree(ws / "seq")
    make_sequence(ws / "seq", frames=1)


def dangling_link(ws):
    image(ws, 0, 2).unlink()
    image(ws, 0, 2).symlink_to("nowhere.png")


def tum_rows(times) -> str:
    return "".join(f"{t} {0.1 * k:.3f} 0 {0.05 * k:.3f} 0 0 0 1\n" for k, t in enumerate(times))


# A command replaces only what the same command wrote: each case's --out holds another's output.
# fmt: off
OWNERSHIP = [
    Case("run-over-user-kitti-files", "RUN --out u", 2, "not written by this program", user_kitti_files),
    Case("run-over-user-kitti-files-force", "RUN --out u --force", 2, "replaces only what it wrote",
        user_kitti_files, "u"),
    Case("run-over-a-sweep", "RUN --out R", 2, "holds the output of `vo_lib sweep nees`", finished_sweep),
    Case("generate-over-a-sweep", "GEN --out R", 2, "holds the output of `vo_lib sweep nees`",
        finished_sweep),
    Case("run-over-a-generated-sequence", "RUN --out gen", 2, "`vo_lib generate`", generated("gen")),
    Case("generate-over-a-run", "GEN --out out", 2, "`vo_lib run`", run_once("out")),
    Case("generate-over-its-own-plus-a-user-file-in-a-subfolder", "GEN --out gen", 2, "image_0/NOTES.txt",
        do(generated("gen"), edit("gen/image_0/NOTES.txt", "mine")), "gen",
        check=reads("gen/image_0/NOTES.txt", "mine")),
    # every command keeps off the samples' folder, and off an output of its own edited since
    Case("convert-data-folder-force", "convert seq --out data --force", 2, "is the sample data folder"),
    Case("sweep-data-folder-force", "sweep nees --seeds 1 --workers 1 --out data --force", 2,
        "is the sample data folder"),
    Case("convert-over-its-own-edited", "convert seq --out conv", 2, "poses.txt was added, changed or",
        do(lambda ws: main(["convert", "seq", "--out", "conv"]), edit("conv/poses.txt", "mine")), "conv",
        check=reads("conv/poses.txt", "mine")),
    Case("sweep-over-its-own-edited", "sweep nees --seeds 2 --workers 1 --out R", 2,
        "results.csv was added, changed or removed", do(finished_sweep, edit("R/results.csv", "mine")), "R",
        check=reads("R/results.csv", "mine")),
    Case("generate-over-its-own-edited-force", "GEN --out gen --force", 2, "poses.txt was added, changed",
        do(generated("gen"), edit("gen/poses.txt", "mine")), "gen", check=reads("gen/poses.txt", "mine")),
    Case("run-over-a-generated-sequence-force", "RUN --out gen --force", 0, "--force: replaced",
        generated("gen"), "gen", check=has_marker("gen")),
    Case("sweep-over-a-run", "sweep nees --seeds 2 --workers 1 --out out", 2,
        "holds the output of `vo_lib run`", run_once("out")),
    Case("sweep-over-another-sweep", "sweep lap --seeds 1 --workers 1 --out R", 2,
        "`vo_lib sweep nees`, which `vo_lib sweep lap` does not replace", finished_sweep),
    Case("run-over-a-sweep-force", "RUN --out R --force", 0, "--force: replaced", finished_sweep, "R",
        check=has_marker("R")),
    # what used to end in a traceback, a wrong name or a quiet acceptance
    Case("one-frame-sequence", "RUN --out out", 2, "has 1 frame; a run needs at least 2", one_frame),
    Case("name-without-frame-number", "RUN", 2, "image_0/left.png: no frame number in the name",
        lambda ws: shutil.copy(image(ws, 0, 1), ws / "seq" / "image_0" / "left.png")),
    Case("name-unlike-the-others", "RUN", 2, "image_0: 'x000001.png' is named unlike '000000.png'",
        lambda ws: image(ws, 0, 1).rename(ws / "seq" / "image_0" / "x000001.png")),
    Case("dangling-link-named", "RUN", 2,
        "seq/image_0/000002.png: a symbolic link to nowhere.png, which does not exist", dangling_link),
    Case("folder-named-like-an-image", "RUN", 2,
        "seq/image_1/000002.png: a folder named like an image; expected an image file",
        lambda ws: (image(ws, 1, 2).unlink(), image(ws, 1, 2).mkdir())),
    Case("evaluate-tum-repeated-time", "EVAL", 2, "est.txt, line 3: timestamp 0.1 repeats the one on line 2",
        edit("est.txt", tum_rows([0, 0.1, 0.1, 0.2, 0.3]))),
    Case("evaluate-tum-backwards-time", "EVAL", 2,
        "est.txt, line 4: timestamp 0.05 comes before the one on line 3",
        edit("est.txt", tum_rows([0, 0.1, 0.2, 0.05, 0.3]))),
    Case("calib-plain-numbers", "RUN", 2, "got P0[0,3]=0, P1[0,3]=6",
        edit("seq/calib.txt", "P0: 50 0 31.5 0 0 50 23.5 0 0 0 1 0\nP1: 50 0 31.5 6 0 50 23.5 0 0 0 1 0\n")),
]
# fmt: on
CASES += OWNERSHIP


def test_the_table_is_large_and_ids_are_unique():
    assert len(CASES) >= 40
    assert len({c.id for c in CASES}) == len(CASES)


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_case(case: Case, template, tmp_path, monkeypatch, capsys):
    monkeypatch.delenv("DASK_SCHEDULER_ADDRESS", raising=False)
    ws = tmp_path / "ws"
    shutil.copytree(template, ws, symlinks=True)
    monkeypatch.setenv("VO_LIB_DATA", str(ws / "data"))
    monkeypatch.setenv("HOME", str(ws / "home"))
    monkeypatch.setenv("MPLCONFIGDIR", str(tmp_path / "mpl"))  # matplotlib's cache: not in the workspace
    monkeypatch.chdir(ws)
    if case.setup:
        case.setup(ws)
    capsys.readouterr()
    before = checksums(ws, tuple(case.writes.split()))
    monkeypatch.chdir(ws / case.cwd)
    umask = os.umask(case.umask) if case.umask is not None else None
    try:
        code, out, err = invoke(case.argv, capsys)
    finally:
        if umask is not None:
            os.umask(umask)
    assert code == case.code, f"exit {code}\nstdout: {out}\nstderr: {err}"
    assert "Traceback" not in err
    lines = said(err)
    if case.code == 2:
        assert len(lines) == 1, err
        assert case.phrase in lines[0]
    else:
        assert len(lines) <= 1, err  # at most one notice
        assert case.phrase in out + err
    assert checksums(ws, tuple(case.writes.split())) == before  # not a byte of anything else changed
    assert temporaries(ws) == []  # nothing half-written left
    if case.check:
        assert case.check(ws)


# ---- a sequence being read is never replaced; a full disk is named ----------------------------------


def test_a_sequence_being_read_is_not_replaced(template, tmp_path, monkeypatch, capsys):
    """`generate --out S` while something reads S: refused in one line, S unchanged."""
    from vo_lib.outputs import reading

    ws = tmp_path / "ws"
    shutil.copytree(template, ws, symlinks=True)
    monkeypatch.chdir(ws)
    assert main([*GEN, "--out", "gen"]) == 0
    capsys.readouterr()
    before = checksums(ws, ())
    with reading(ws / "gen"):
        code, out, err = invoke([*GEN, "--out", "gen", "--force"], capsys)
    assert code == 2 and err.strip().splitlines() == [
        "python -m vo_lib generate: error: --out gen: a running command is reading this folder; "
        "try again when it has finished"
    ]
    assert checksums(ws, ()) == before and temporaries(ws) == []
    with reading(ws / "gen" / "image_0"):  # nor the folder that holds what is read
        code, out, err = invoke([*GEN, "--out", "gen", "--force"], capsys)
    assert code == 2 and "--out gen: a running command is reading this folder" in err
    assert checksums(ws, ()) == before and temporaries(ws) == []
    assert invoke([*GEN, "--out", "gen", "--force"], capsys)[0] == 0  # once it is read no more


def test_evaluate_refuses_files_written_while_it_read_them(tmp_path, monkeypatch, capsys):
    """--gt or --est written over while evaluate reads it (a `generate --force` or a run beside it):
    one line and exit 2, not the figures of one file checked against the other."""
    from vo_lib.cli import evaluate
    from vo_lib.formats.poses import write_kitti_poses

    T = np.tile(np.eye(4), (5, 1, 1))
    T[:, 0, 3] = np.arange(5.0)
    for option, name, reader in (
        ("--gt", "gt.txt", "read_groundtruth"),
        ("--est", "est.txt", "read_trajectory"),
    ):
        for path in ("gt.txt", "est.txt"):
            write_kitti_poses(tmp_path / path, T)
        real = getattr(evaluate, reader)

        def read_then_written_over(path, *args, real=real, name=name, **kwargs):
            value = real(path, *args, **kwargs)
            write_kitti_poses(tmp_path / name, 2 * T)  # another command writes it meanwhile
            return value

        monkeypatch.setattr(evaluate, reader, read_then_written_over)
        code, out, err = invoke(
            ["evaluate", "--gt", str(tmp_path / "gt.txt"), "--est", str(tmp_path / "est.txt")], capsys
        )
        monkeypatch.setattr(evaluate, reader, real)
        assert code == 2 and out == "", (option, out)
        assert err.strip().splitlines() == [
            f"python -m vo_lib evaluate: error: {option} {tmp_path / name}: changed while it was read; "
            "evaluate it again when nothing writes it"
        ]
    assert (
        invoke(["evaluate", "--gt", str(tmp_path / "gt.txt"), "--est", str(tmp_path / "est.txt")], capsys)[0]
        == 0
    )


def test_run_holds_its_input_while_it_reads(template, tmp_path, monkeypatch, capsys):
    """While the run loads its input sequence and while the pipeline reads its images, replacing
    the sequence fails (the run holds its lock from before it reads anything)."""
    import vo_lib.stereo_vo.pipeline as run_module  # run imports the pipeline where it runs it
    from vo_lib import data
    from vo_lib.outputs import OutputError, OutputFolder

    ws = tmp_path / "ws"
    shutil.copytree(template, ws, symlinks=True)
    monkeypatch.chdir(ws)
    assert main([*GEN, "--out", "gen"]) == 0
    attempts = []
    original_run, original_load = run_module.run_sequence, data.load_sequence

    def try_to_replace(path):
        try:
            OutputFolder(path, "vo_lib generate", force=True).discard()
            attempts.append("replaced")
        except OutputError as exc:
            attempts.append(str(exc))

    def load_sequence(name, **kwargs):  # while its files are read: the calibration, times, poses
        try_to_replace(ws / "gen")
        return original_load(name, **kwargs)

    def run_sequence(seq, **kwargs):  # while its images are read
        try_to_replace(seq.path)
        return original_run(seq, **kwargs)

    monkeypatch.setattr(data, "load_sequence", load_sequence)
    monkeypatch.setattr(run_module, "run_sequence", run_sequence)
    assert main(["run", "--sequence", "gen", "--out", "out"]) == 0
    assert len(attempts) >= 2 and all("a running command is reading this folder" in a for a in attempts)
    OutputFolder(ws / "gen", "vo_lib generate").discard()  # free again after the run


def test_a_full_disk_is_named_in_one_line(template, tmp_path, monkeypatch, capsys):
    """No space left while `generate` writes: one line naming --out, nothing left behind."""
    import errno

    ws = tmp_path / "ws"
    shutil.copytree(template, ws, symlinks=True)
    monkeypatch.chdir(ws)
    real_write = Path.write_bytes
    written = []

    def full(self, data):
        if ".vo_lib-" in str(self) and len(written) >= 2:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(self))
        written.append(self)
        return real_write(self, data)

    monkeypatch.setattr(Path, "write_bytes", full)
    before = checksums(ws, ())
    code, out, err = invoke([*GEN, "--out", "gen"], capsys)
    assert code == 2 and err.strip().splitlines() == [
        "python -m vo_lib generate: error: --out gen: cannot write the sequence (no space left on device);"
        " nothing was written"
    ]
    assert not (ws / "gen").exists() and temporaries(ws) == [] and checksums(ws, ()) == before


# ---- reading: numeric order and pairing, as a library -----------------------------------------------


def test_unpadded_names_are_read_in_numeric_order_and_paired_by_name(tmp_path):
    ws = tmp_path
    unpadded(ws)
    seq = read_sequence(ws / "seq")
    assert [p.name for p in seq.left_files] == [f"{k}.png" for k in range(12)]
    assert [p.name for p in seq.right_files] == [f"{k}.png" for k in range(12)]
    reference = read_sequence(make_sequence(tmp_path / "padded", frames=12))
    for k in (2, 10):
        np.testing.assert_array_equal(seq.pair(k)[0], reference.pair(k)[0])


def test_mixed_padding_sorts_numerically(tmp_path):
    seq = make_sequence(tmp_path / "seq", frames=3)
    for side in (0, 1):
        folder = seq / f"image_{side}"
        for old, new in (("000000.png", "8.png"), ("000001.png", "9.png"), ("000002.png", "0010.png")):
            (folder / old).rename(folder / new)
    assert [p.name for p in read_sequence(seq).left_files] == ["8.png", "9.png", "0010.png"]


def test_header_check_reads_no_pixels(tmp_path, monkeypatch):
    seq = make_sequence(tmp_path / "seq")
    calls = []
    monkeypatch.setattr(cv2, "imread", lambda *a: calls.append(a))
    monkeypatch.setattr(cv2, "imdecode", lambda *a: calls.append(a))
    read_sequence(seq)
    assert calls == []


# ---- signals, a read-only install, the real entry point --------------------------------------------


def cli_env(**extra) -> dict:
    env = dict(os.environ, PYTHONDONTWRITEBYTECODE="1", **extra)
    env.pop("NUMBA_CACHE_DIR", None)
    return env


def wait_for_temporary(folder: Path, proc: subprocess.Popen, timeout=60.0) -> None:
    end = time.monotonic() + timeout
    while time.monotonic() < end and proc.poll() is None:
        if temporaries(folder):
            time.sleep(0.3)  # well inside the work
            return
        time.sleep(0.02)
    raise AssertionError(f"no temporary folder appeared (exit {proc.poll()})")


@pytest.mark.parametrize(
    "args, signum, code, phrase",
    [
        (["generate", "corridor", "--resolution", "320x240", "--out", "gen"], signal.SIGTERM, 143, "SIGTERM"),
        (["generate", "corridor", "--resolution", "320x240", "--out", "gen"], signal.SIGINT, 130, "Ctrl-C"),
        (["run", "--sequence", "long", "--out", "out"], signal.SIGINT, 130, "Ctrl-C"),
    ],
    ids=["generate-sigterm", "generate-sigint", "run-sigint"],
)
def test_signals_leave_nothing_and_print_one_line(tmp_path, args, signum, code, phrase):
    if "long" in args:
        make_sequence(tmp_path / "long", frames=300, size=(320, 240))
    (tmp_path / "important.txt").write_text("keep\n")
    before = checksums(tmp_path, ())
    env = cli_env(VO_LIB_DATA=str(tmp_path / "data"))
    env.pop("VO_LIB_FRAME_STORE", None)  # frames the session stored would be written before the signal
    env["PYTHONUNBUFFERED"] = "1"  # the run's "visual odometry on" line arrives as it is printed
    proc = subprocess.Popen(
        [sys.executable, "-m", "vo_lib", *args],
        cwd=tmp_path,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    if args[0] == "run":  # the frames' work begins (a fixed wait ended after it on a fast machine)
        assert any(line.startswith("visual odometry on") for line in proc.stdout), proc.stderr.read()
    else:
        wait_for_temporary(tmp_path, proc)
    proc.send_signal(signum)
    _, err = proc.communicate(timeout=60)  # stderr whole; stdout's lines read above are not needed
    # 128 + N, or ended by the signal itself (a shell reports both as 128 + N): the latter when
    # the interrupt is raised again at interpreter exit, after the command has cleaned up
    assert proc.returncode in (code, -signum), err
    assert len(err.strip().splitlines()) == 1 and phrase in err, err
    assert temporaries(tmp_path) == [] and not (tmp_path / args[args.index("--out") + 1]).exists()
    assert checksums(tmp_path, ()) == before


def test_an_image_pillow_reads_with_a_warning_runs_without_it(tmp_path):
    """Pillow warns of an animation chunk it passes over (the tests' own warning capture would hide
    that in this process): the run prints no warning and writes its output."""
    make_sequence(tmp_path / "seq")
    with_an_empty_apng_chunk(tmp_path)
    env = cli_env(VO_LIB_DATA=str(tmp_path / "data"))
    argv = [sys.executable, "-m", "vo_lib", "run", "--sequence", "seq", "--out", "out"]
    proc = subprocess.run(argv, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0 and said(proc.stderr) == [], proc.stderr
    assert (tmp_path / "out" / "poses.txt").is_file()


def test_a_signal_while_exiting_after_the_command_says_so_in_one_line(tmp_path):
    """Ctrl-C or SIGTERM in the second the interpreter takes to shut down, after the command
    finished: one line and 128 + N, not a silent end by the signal."""
    script = (
        "import os, signal, sys, time\n"
        "import vo_lib.cli.main as m\n"
        "m.main = lambda argv=None: 0\n"
        "status = m.entry()\n"
        "os.kill(os.getpid(), signal.SIGTERM)\n"
        "time.sleep(30)\n"
        "sys.exit(status)\n"
    )
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 143 and proc.stderr.strip().splitlines() == [
        "vo_lib: SIGTERM while exiting; the command had finished"
    ]


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_in_the_interpreters_teardown_leaves_a_finished_commands_status(signum):
    """After the last exit function, Python runs no signal handler: a Ctrl-C then (a sweep's
    process group, a second after its table) ended a finished command as killed, silently. The
    signal is ignored there, and the command's own status stands."""
    script = (
        "import os, signal, sys, time\n"
        "import vo_lib.cli.main as m\n"
        "m.main = lambda argv=None: 0\n"
        "class Late:  # deleted in the teardown, after every exit function\n"
        "    def __del__(self):\n"
        f"        os.kill(os.getpid(), {int(signum)})\n"
        "        time.sleep(0.5)\n"
        "late = Late()\n"
        "sys.exit(m.entry())\n"
    )
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0 and proc.stderr == ""


@pytest.mark.parametrize("wrapper", [SystemError, ImportError])
@pytest.mark.parametrize(
    "signum, code, phrase", [(signal.SIGINT, 130, "Ctrl-C"), (signal.SIGTERM, 143, "SIGTERM")]
)
def test_a_signal_wrapped_by_compiled_code_still_exits_as_it(
    monkeypatch, capsys, signum, code, phrase, wrapper
):
    """A Ctrl-C that lands inside a callback from compiled code (Numba unpickling its cache) or
    while an extension module initialises surfaces as a SystemError or an ImportError caused by
    it: the run still stops as interrupted, in one line."""
    import vo_lib.cli.main as cli

    inner = KeyboardInterrupt() if signum == signal.SIGINT else cli._Stopped(signum)

    def dispatch(args):
        try:
            raise inner
        except BaseException as exc:
            raise wrapper("initialization failed") from exc

    monkeypatch.setattr(cli, "_dispatch", dispatch)
    assert main(["run", "--frames", "2"]) == code
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and phrase in err, err


@pytest.mark.parametrize(
    "signum, code, phrase", [(signal.SIGINT, 130, "Ctrl-C"), (signal.SIGTERM, 143, "SIGTERM")]
)
def test_a_signal_while_the_parser_imports_its_modules_exits_as_it(monkeypatch, capsys, signum, code, phrase):
    """A signal inside NumPy's compiled import comes out as an ImportError of NumPy's own, which
    keeps nothing of the signal: the one remembered says what it was."""
    import vo_lib.cli.main as cli

    def build_parser():
        try:
            cli._stop(signum, None)
        except BaseException:
            raise ImportError("Importing the numpy C-extensions failed.") from None

    monkeypatch.setattr(cli, "build_parser", build_parser)
    assert main(["run", "--frames", "2"]) == code
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and phrase in err, err


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_before_the_command_begins_says_so_in_one_line(signum):
    """Between the start and the command's own handler (its modules loading): one line, 128 + N."""
    script = (
        "import os, signal, sys, time\n"
        "import vo_lib.cli.main as m\n"
        f"m.main = lambda argv=None: os.kill(os.getpid(), {int(signum)}) or time.sleep(30)\n"
        "sys.exit(m.entry())\n"
    )
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60)
    name = signal.Signals(signum).name
    assert proc.returncode == 128 + signum
    assert proc.stderr.strip().splitlines() == [f"vo_lib: {name} while starting; nothing was done"]


def test_a_path_that_is_not_utf8_prints_under_a_strict_locale():
    """Under a UTF-8 locale other than C.UTF-8 standard output refuses the surrogates that stand for
    such bytes in a path; the command prints them as the bytes they are."""
    script = (
        "import sys\n"
        "import vo_lib.cli.main as m\n"
        "m.main = lambda argv=None: print('wrote out\\udcff/') or 0\n"
        "sys.exit(m.entry())\n"
    )
    env = {**os.environ, "PYTHONIOENCODING": "utf-8"}  # strict, as under en_US.UTF-8
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, env=env, timeout=60)
    assert proc.returncode == 0 and proc.stdout == b"wrote out\xff/\n", proc.stderr


@pytest.mark.parametrize(
    "signum, code, phrase", [(signal.SIGINT, 130, "Ctrl-C"), (signal.SIGTERM, 143, "SIGTERM")]
)
def test_a_signal_dropped_in_a_finalizer_still_stops_the_commit(
    monkeypatch, tmp_path, capsys, signum, code, phrase
):
    """A signal whose handler runs inside a finalizer raises where Python drops the exception: the
    command goes on, but the output is not put in place and it exits as stopped by the signal."""
    import vo_lib.cli.main as cli
    from vo_lib.outputs import OutputFolder

    class SignalsWhenFreed:
        def __del__(self):
            os.kill(os.getpid(), signum)
            time.sleep(0.05)  # the handler runs here, inside the finalizer

    def dispatch(args):
        SignalsWhenFreed()  # freed at once
        folder = OutputFolder(tmp_path / "out", "vo_lib test")
        folder.commit()
        return 0

    monkeypatch.setattr(cli, "_dispatch", dispatch)
    assert main(["run", "--frames", "2"]) == code
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and phrase in err, err
    assert not (tmp_path / "out").exists()


def test_a_system_error_of_our_own_is_not_taken_for_a_signal(monkeypatch):
    import vo_lib.cli.main as cli

    def dispatch(args):
        raise SystemError("a real bug")

    monkeypatch.setattr(cli, "_dispatch", dispatch)
    with pytest.raises(SystemError, match="a real bug"):
        main(["run", "--frames", "2"])


def test_runs_from_a_read_only_install(tmp_path):
    """The package copied to a read-only folder, with a home whose cache cannot be written
    either: Numba finds no cache folder, and the run compiles uncached instead of failing."""
    pkg = tmp_path / "site"
    shutil.copytree(ROOT / "vo_lib", pkg / "vo_lib", ignore=shutil.ignore_patterns("__pycache__"))
    home = tmp_path / "home"
    home.mkdir()
    (home / ".cache").write_text("a file where the cache folder would go\n")
    if os.geteuid() == 0:  # permissions do not bind root: a file where each __pycache__ would go
        for folder in [pkg / "vo_lib", *(pkg / "vo_lib").rglob("*")]:
            if folder.is_dir():
                (folder / "__pycache__").write_text("")
    for path in [pkg, *pkg.rglob("*")]:
        path.chmod(path.stat().st_mode & ~(stat.S_IWUSR | stat.S_IWGRP | stat.S_IWOTH))
    make_sequence(tmp_path / "seq")
    script = (
        "import sys, vo_lib; assert vo_lib.__file__.startswith(sys.argv[1]), vo_lib.__file__; "
        "from vo_lib.cli.main import main; sys.exit(main(sys.argv[2:]))"
    )
    env = cli_env(PYTHONPATH=str(pkg), HOME=str(home), MPLCONFIGDIR=str(tmp_path / "mpl"))
    env.pop("XDG_CACHE_HOME", None)
    try:
        proc = subprocess.run(
            [sys.executable, "-c", script, str(pkg), "run", "--sequence", "seq", "--out", "out"],
            cwd=tmp_path,
            env=env,
            capture_output=True,
            text=True,
            timeout=300,
        )
    finally:
        for path in [pkg, *pkg.rglob("*")]:
            path.chmod(path.stat().st_mode | stat.S_IWUSR)
    assert proc.returncode == 0, proc.stderr
    assert "wrote out/" in proc.stdout and "cannot cache" not in proc.stderr
    assert (tmp_path / "out" / "poses.txt").is_file()
    assert not [p for p in pkg.rglob("*") if p.suffix in (".nbi", ".nbc")]


def test_numba_without_any_cache_folder_compiles_uncached(monkeypatch):
    from numba.core import caching

    from vo_lib.compiled import jit

    impl = getattr(caching, "CacheImpl", None) or caching._CacheImpl
    monkeypatch.setattr(impl, "_locator_classes", [])

    def twice(x):
        return 2 * x

    compiled = jit(twice)
    assert compiled(21) == 42 and type(compiled._cache).__name__ == "NullCache"  # no cache behind it


def test_real_entry_point_prints_one_line(template, tmp_path):
    ws = tmp_path / "ws"
    shutil.copytree(template, ws)
    damaged_png_data(ws)
    env = cli_env(VO_LIB_DATA=str(ws / "data"))
    for args, phrase in (
        (["run", "--sequence", "seq", "--out", "out"], "frame 2: cannot read the image"),
        (["run", "--seed", "-5"], "--seed"),
    ):
        proc = subprocess.run(
            [sys.executable, "-m", "vo_lib", *args], cwd=ws, env=env, capture_output=True, text=True
        )
        assert proc.returncode == 2
        assert len(proc.stderr.strip().splitlines()) == 1 and phrase in proc.stderr, proc.stderr
    assert not (ws / "out").exists() and temporaries(ws) == []


@pytest.mark.skipif(not os.path.lexists("/proc/kmsg"), reason="no /proc/kmsg on this system")
def test_a_kernel_file_that_would_block_is_not_read(tmp_path):
    """``/proc/kmsg`` says it holds 0 bytes and blocks whoever reads it (where it may be read at
    all): given as either trajectory, it is taken as empty, in one line, without a wait."""
    (tmp_path / "poses.txt").write_text(kitti_rows(4))
    for args in (["--gt", "/proc/kmsg", "--est", "poses.txt"], ["--gt", "poses.txt", "--est", "/proc/kmsg"]):
        proc = subprocess.run(
            [sys.executable, "-m", "vo_lib", "evaluate", *args],
            cwd=tmp_path,
            env=cli_env(),
            capture_output=True,
            text=True,
            timeout=60,
        )
        assert proc.returncode == 2 and len(proc.stderr.strip().splitlines()) == 1, proc.stderr
        assert "/proc/kmsg: no poses" in proc.stderr or "/proc/kmsg: cannot read" in proc.stderr


# ---- the parsers against random text ------------------------------------------------------------------

TOKENS = [
    "P0:",
    "P1:",
    "P2:",
    "Tr:",
    "0",
    "1",
    "-1",
    "0.5",
    "1e-3",
    "nan",
    "inf",
    "-inf",
    "1e400",
    "abc",
    ":",
    "#",
    "",
    "0x1",
    "1_0",
    "\t",
    "\u00a0",
    "\r",
    "٣",
]
numbers = st.floats(allow_nan=True, allow_infinity=True).map(repr)
token = st.one_of(st.sampled_from(TOKENS), numbers, st.text(max_size=4))
line = st.lists(token, max_size=14).map(" ".join)
text_files = st.one_of(
    st.lists(line, max_size=8).map("\n".join),
    st.text(max_size=200),
    st.binary(max_size=100),
)
PROPERTY = settings(
    max_examples=100, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)


def write(folder: Path, content) -> Path:
    fd, name = tempfile.mkstemp(dir=folder, suffix=".txt")
    with os.fdopen(fd, "wb") as fh:
        fh.write(content if isinstance(content, bytes) else content.encode("utf-8", "surrogatepass"))
    return Path(name)


@pytest.fixture(scope="module")
def scratch(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("parsers")


def parses_or_raises(parser, path, error):
    try:
        return parser(path)
    except error:
        return None  # the documented error; anything else fails the test


@PROPERTY
@given(content=text_files)
def test_calib_parser_on_random_text(scratch, content):
    result = parses_or_raises(read_calib, write(scratch, content), SequenceError)
    if result is not None:
        assert all(P.shape == (3, 4) and np.all(np.isfinite(P)) for P in result)


@PROPERTY
@given(
    content=st.one_of(
        text_files,
        st.lists(st.sampled_from(["P0:", "P1:"]), min_size=1).flatmap(
            lambda keys: st.lists(
                st.lists(numbers, min_size=12, max_size=12), min_size=len(keys), max_size=len(keys)
            ).map(lambda rows: "\n".join(f"{k} {' '.join(r)}" for k, r in zip(keys, rows, strict=True)))
        ),
    )
)
def test_calib_parser_on_nearly_valid_text(scratch, content):
    parses_or_raises(read_calib, write(scratch, content), SequenceError)


@PROPERTY
@given(content=st.one_of(text_files, st.lists(numbers, max_size=10).map("\n".join)))
def test_times_parser_on_random_text(scratch, content):
    times = parses_or_raises(read_times, write(scratch, content), SequenceError)
    if times is not None:
        assert times.ndim == 1 and np.all(np.isfinite(times)) and np.all(np.diff(times) > 0)


pose_rows = st.lists(
    st.lists(st.one_of(numbers, st.sampled_from(["0", "1", "-1"])), min_size=12, max_size=12), max_size=4
).map(lambda rows: "\n".join(" ".join(r) for r in rows))


@PROPERTY
@given(content=st.one_of(text_files, pose_rows, st.integers(1, 5).map(kitti_rows)))
def test_poses_parsers_on_random_text(scratch, content):
    path = write(scratch, content)
    poses = parses_or_raises(read_poses, path, SequenceError)
    if poses is not None:
        assert poses.shape[1:] == (3, 4) and np.all(np.isfinite(poses))
    trajectory = parses_or_raises(read_trajectory, path, TrajectoryError)
    if trajectory is not None:
        assert trajectory[0] is None and trajectory[1].shape[1:] == (4, 4)


tum_rows = st.lists(
    st.lists(st.one_of(numbers, st.sampled_from(["0", "1", "0.5"])), min_size=8, max_size=8),
    min_size=1,
    max_size=4,
).map(lambda rows: "\n".join(" ".join(r) for r in rows))


@PROPERTY
@given(
    content=st.one_of(
        text_files, tum_rows, st.just("# t x y z qx qy qz qw\n0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1")
    )
)
def test_tum_parser_on_random_text(scratch, content):
    result = parses_or_raises(read_trajectory, write(scratch, content), TrajectoryError)
    if result is not None:
        times, T = result
        assert times is not None and len(times) == len(T) and np.all(np.isfinite(T))
        np.testing.assert_allclose(
            T[:, :3, :3] @ T[:, :3, :3].transpose(0, 2, 1), np.tile(np.eye(3), (len(T), 1, 1)), atol=1e-9
        )


def test_frames_beyond_a_sample_ask_for_the_whole_sample_with_a_notice(tmp_path, monkeypatch, capsys):
    from vo_lib.cli.run import input_path
    from vo_lib.data import sample_path

    monkeypatch.setenv("VO_LIB_DATA", str(tmp_path))
    assert input_path("corridor", 10) == (sample_path("corridor", 10), 10)
    assert input_path("corridor", 10_000) == (sample_path("corridor"), None)
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["notice: --frames 10000: sample corridor has 541 frames; running all 541"]


def test_a_sample_folder_that_is_a_file_is_named(tmp_path, monkeypatch, capsys):
    """``VO_LIB_DATA`` naming a file: the variable is named, not ``--out`` (an existing one)."""
    (tmp_path / "samples").write_text("not a folder")
    (tmp_path / "out").mkdir()
    monkeypatch.setenv("VO_LIB_DATA", str(tmp_path / "samples"))
    code, _, err = invoke(["run", "--sequence", "corridor", "--out", str(tmp_path / "out")], capsys)
    assert code == 2 and said(err) == [
        f"python -m vo_lib run: error: VO_LIB_DATA={tmp_path / 'samples'}: not a folder; expected the "
        "folder the samples are kept in"
    ]


def test_the_package_is_never_an_output_folder(tmp_path, monkeypatch):
    """Checked without writing: the package, a folder in it or holding it, and the repository's
    own data folder are refused, forced."""
    from vo_lib.outputs import OutputError, check_target

    monkeypatch.chdir(tmp_path)
    for target, phrase in (
        (ROOT / "vo_lib", "is this package"),
        (ROOT / "vo_lib" / "cli", "lies inside this package"),
        (ROOT / "vo_lib" / "new_folder", "lies inside this package"),
        (ROOT, "holds this package"),
        (ROOT / "data", "is the sample data folder"),
    ):
        with pytest.raises(OutputError, match=phrase):
            check_target(target, written_by="vo_lib run", force=True)


def test_claim_folder_for_a_folder_kept_over_many_runs(tmp_path, monkeypatch):
    """A build folder (kept, updated) is claimed when new, empty or claimed by the same command;
    a user's folder, another command's and a damaged marker are refused in one line, unchanged."""
    from vo_lib.outputs import OutputError, claim_folder, read_marker

    monkeypatch.chdir(tmp_path)
    site = claim_folder(tmp_path / "site", "docs build", option="--out")
    (site / "cache.db").write_text("kept\n")
    assert claim_folder(tmp_path / "site", "docs build") == site  # again: its own, whatever it holds
    assert read_marker(site)["written_by"] == "docs build" and (site / "cache.db").is_file()
    with pytest.raises(OutputError, match="holds the output of `docs build`"):
        claim_folder(tmp_path / "site", "coursework build")
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "notes.txt").write_text("mine\n")
    with pytest.raises(OutputError, match=r"program \(it holds notes.txt\); choose another folder"):
        claim_folder(tmp_path / "mine", "docs build", option="--out")
    (site / MARKER).write_text("{damaged")
    with pytest.raises(OutputError, match="marker .vo_lib_output.json is damaged"):
        claim_folder(site, "docs build")
    assert (tmp_path / "mine" / "notes.txt").read_text() == "mine\n" and (site / "cache.db").is_file()

    def denied(self, *args, **kwargs):  # a folder the user may not write (root may write anywhere)
        raise PermissionError(13, "Permission denied", str(self))

    monkeypatch.setattr(Path, "mkdir", denied)
    with pytest.raises(OutputError, match=r"--out new: cannot write there \(Permission denied\)"):
        claim_folder("new", "docs build", option="--out")


def test_a_full_disk_during_a_run_names_out_not_a_temporary(template, tmp_path, monkeypatch, capsys):
    """No space left while `run` writes its files: one line naming --out, nothing left behind."""
    import errno

    import vo_lib.cli.run as run_module

    ws = tmp_path / "ws"
    shutil.copytree(template, ws, symlinks=True)
    monkeypatch.chdir(ws)

    def full(path, *args):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))

    monkeypatch.setattr(run_module, "write_tum", full)
    before = checksums(ws, ())
    code, out, err = invoke([*RUN, "--out", "out"], capsys)
    assert code == 2 and said(err) == [
        "python -m vo_lib run: error: --out out: no space left on device; nothing was written"
    ]
    assert not (ws / "out").exists() and temporaries(ws) == [] and checksums(ws, ()) == before


def test_a_checksummed_folder_is_replaced_only_while_every_file_is_as_written(tmp_path):
    from vo_lib.outputs import OutputError, OutputFolder, check_target, read_marker

    def write(text: str) -> None:
        with OutputFolder(tmp_path / "book", "book build") as out:
            (out.path / "deep").mkdir()
            (out.path / "deep" / "page.txt").write_text(text)
            out.commit()

    write("one")
    assert read_marker(tmp_path / "book")["files"] == {"deep/page.txt": hashlib.sha256(b"one").hexdigest()}
    write("two")  # unchanged since written: replaced
    assert (tmp_path / "book" / "deep" / "page.txt").read_text() == "two"
    (tmp_path / "book" / "deep" / "answers.txt").write_text("a student's")
    with pytest.raises(OutputError, match="deep/answers.txt was added, changed or removed since"):
        write("three")
    (tmp_path / "book" / "deep" / "answers.txt").unlink()
    (tmp_path / "book" / "deep" / "page.txt").unlink()
    with pytest.raises(OutputError, match="deep/page.txt was added, changed or removed since"):
        check_target(tmp_path / "book", written_by="book build")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["book"]  # no temporary left


def test_a_folder_being_read_is_not_replaced(tmp_path):
    from vo_lib.outputs import OutputError, OutputFolder, claim_folder, reading, remove_replaced, swap_in

    folder = claim_folder(tmp_path / "rows", "vo_lib sweep toy")
    with reading(folder):
        with pytest.raises(OutputError, match="a running command is reading this folder"):
            OutputFolder(folder, "vo_lib sweep toy")
    done = tmp_path / "done"
    done.mkdir()
    (done / "a").write_text("new")
    remove_replaced(swap_in(done, folder), folder)  # released: a finished folder renamed over the old one
    assert [p.name for p in folder.iterdir()] == ["a"] and sorted(p.name for p in tmp_path.iterdir()) == [
        "rows"
    ]


def test_what_a_sequence_links_to_is_not_replaced_while_it_is_read(tmp_path):
    """A sequence whose image folder is a link into another folder: that folder is read too."""
    from vo_lib.outputs import OutputError, OutputFolder, claim_folder, reading

    converted = claim_folder(tmp_path / "converted", "vo_lib convert")
    (converted / "image_0").mkdir()
    (tmp_path / "seq").mkdir()
    (tmp_path / "seq" / "image_0").symlink_to(converted / "image_0")
    with reading(tmp_path / "seq"):
        with pytest.raises(OutputError, match="a running command is reading this folder"):
            OutputFolder(converted, "vo_lib convert")


def test_an_input_still_to_render_does_not_block_replacing_our_own_output(tmp_path):
    """A sample not rendered yet (its folder missing) links nowhere: a run replaces its own output."""
    from vo_lib.outputs import OutputFolder, check_target

    with OutputFolder(tmp_path / "run", "vo_lib run") as out:
        (out.path / "poses.txt").write_text("old\n")
        out.commit()
    assert check_target(tmp_path / "run", written_by="vo_lib run", inputs=[tmp_path / "not yet"]) is None


def test_force_replaces_nothing_it_did_not_write_inside_the_sample_data_folder(tmp_path, monkeypatch):
    """The repository's data/ holds tracked fixtures beside the rendered samples: --force replaces
    a folder there only if this program wrote it."""
    from vo_lib import outputs

    monkeypatch.setattr(outputs, "REPOSITORY_DATA", tmp_path / "data")
    (fixtures := tmp_path / "data" / "fixtures").mkdir(parents=True)
    (fixtures / "calib.txt").write_text("P0: 1 0 0 0\n")
    with pytest.raises(outputs.OutputError, match="lies inside the sample data folder"):
        outputs.check_target(fixtures, written_by="vo_lib run", force=True, option="--out")
    assert (fixtures / "calib.txt").is_file()
    with outputs.OutputFolder(tmp_path / "data" / "sample_5f", "vo_lib generate") as out:
        out.commit()
    assert outputs.check_target(tmp_path / "data" / "sample_5f", written_by="vo_lib generate") is None


# ---- a kill at any step of the swap leaves the previous output whole ------------------------------

KILLER = """
import os, shutil, signal, sys
import vo_lib.atomic as a
import vo_lib.outputs as o
target, mode, at, writer = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
steps = [0]

def counted(step):
    def call(*args, **kwargs):
        steps[0] += 1
        if steps[0] == at:
            os.kill(os.getpid(), signal.SIGKILL)
        return step(*args, **kwargs)
    return call

os.rename, shutil.rmtree = counted(os.rename), counted(shutil.rmtree)
a._exchange = counted(a._exchange) if mode == "exchange" else (lambda x, y: False)
if at == 0:  # killed when the new folder is written, before its commit
    o.OutputFolder.commit = lambda self, **details: os.kill(os.getpid(), signal.SIGKILL)
if writer == "run":
    with o.OutputFolder(target, "vo_lib run") as out:
        (out.path / "poses.txt").write_text("new\\n")
        out.commit()
else:
    from vo_lib.sim.samples import generate
    generate("corridor", target, 3, (64, 48), progress=False, force=True)
"""


def write_old(target: Path, writer: str) -> None:
    """The previous output: a run's folder, or a generated sequence of 2 frames (the new has 3)."""
    from vo_lib.outputs import OutputFolder
    from vo_lib.sim.samples import generate

    if writer == "generate":
        generate("corridor", target, 2, (64, 48), progress=False)
        return
    with OutputFolder(target, "vo_lib run") as out:
        (out.path / "poses.txt").write_text("old\n")
        out.commit()


def whole(folder: Path) -> str | None:
    """Which output ``folder`` holds ("old" or "new"), or None if it is missing or not whole."""
    from vo_lib.outputs import entries, read_marker

    marker = read_marker(folder)
    if marker is None or entries(folder) != marker["contents"]:
        return None
    if "frames" in marker:  # a generated sequence
        return (
            {2: "old", 3: "new"}[marker["frames"]] if len(read_sequence(folder)) == marker["frames"] else None
        )
    return (folder / "poses.txt").read_text().strip()


@pytest.mark.parametrize("writer", ["run", "generate"])
@pytest.mark.parametrize("mode", ["exchange", "renames"])
def test_a_kill_at_any_step_of_the_swap_leaves_the_previous_output(tmp_path, mode, writer):
    """Kill the writer (SIGKILL) before each step of the swap in turn (renames, the one-step
    exchange, the deletion of the replaced folder), for a run's output and a generated sequence.
    After each kill the folder is the old output or the new one, whole; the next command beside
    it (an ``OutputFolder`` that writes nothing) restores an old output set aside, even where an
    empty folder has been made in its place meanwhile, and removes every temporary. A run's output
    by renames has a name of 250 characters, whose temporaries' names would pass 255 bytes whole."""
    from vo_lib.outputs import OutputFolder

    seen, written_by = [], f"vo_lib {writer}"
    stem = "c" * 245 if (mode, writer) == ("renames", "run") else "out"
    for at in range(12):
        target = tmp_path / f"{stem}{at}"
        write_old(target, writer)
        proc = subprocess.run(
            [sys.executable, "-c", KILLER, str(target), mode, str(at), writer],
            env=cli_env(),
            capture_output=True,
        )
        if proc.returncode == 0:
            break
        assert proc.returncode == -signal.SIGKILL, proc.stderr
        after_kill = whole(target)
        assert after_kill in ("old", "new") or (mode == "renames" and not target.exists())
        if not target.exists():  # killed between the two renames; someone then makes the folder
            target.mkdir()  # empty: the old output set aside is still put back, not deleted
        with OutputFolder(target, written_by, force=True):
            pass
        seen.append(whole(target))
        assert seen[-1] == (after_kill or "old") and temporaries(tmp_path) == []
    assert proc.returncode == 0 and whole(target) == "new" and temporaries(tmp_path) == []
    # killed before the commit, at the failed first rename (the target is not empty), at the
    # exchange or each of the two renames, then while the replaced folder is deleted
    assert len(seen) == (4 if mode == "exchange" else 5) and seen[0] == seen[1] == "old"
    assert "new" in seen


def test_a_path_that_is_not_utf8_is_read(template, tmp_path):
    """A folder name holding the byte 0xff (read as a surrogate): OpenCV decodes the files' bytes,
    so nothing crashes (it was a segmentation fault, exit 139), and the output is written; letters
    the figure's font lacks (Chinese) are drawn without a warning."""
    name = os.fsdecode(b"seq\xff " + "数据".encode())
    root = tmp_path / "root"
    shutil.copytree(template / "seq", root / name)
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "vo_lib",
            "run",
            "--sequence",
            str(root / name),
            "--out",
            str(tmp_path / "out"),
        ],
        cwd=tmp_path,
        env=cli_env(MPLCONFIGDIR=str(tmp_path / "mpl")),
        capture_output=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr.decode(errors="replace")
    assert b"Traceback" not in proc.stderr and (tmp_path / "out" / MARKER).is_file()
    assert b"Warning" not in proc.stderr, proc.stderr.decode(errors="replace")


def test_a_closed_standard_output_is_one_line(tmp_path):
    """Started with standard output closed (``>&-``): one line and status 2, nothing written."""
    proc = subprocess.run(
        [sys.executable, "-m", "vo_lib", *GEN, "--out", str(tmp_path / "gen")],
        cwd=tmp_path,
        env=cli_env(MPLCONFIGDIR=str(tmp_path / "mpl")),
        stdin=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        timeout=300,
        preexec_fn=lambda: os.close(1),
    )
    assert proc.returncode == 2 and proc.stderr.splitlines() == [
        "python -m vo_lib: error: standard output is closed; expected it open (e.g. >/dev/null)"
    ], proc.stderr
    assert not (tmp_path / "gen").exists()


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="no /dev/full here to stand for a full disk")
def test_a_full_standard_output_is_named_not_the_output_folder(tmp_path):
    """Standard output on a full disk (``> /dev/full``): one line names it; the output folder, put
    in place before, stays whole."""
    with open("/dev/full", "w") as full:
        proc = subprocess.run(
            [sys.executable, "-m", "vo_lib", *GEN, "--out", str(tmp_path / "gen")],
            cwd=tmp_path,
            env=cli_env(MPLCONFIGDIR=str(tmp_path / "mpl")),
            stdout=full,
            stderr=subprocess.PIPE,
            text=True,
            timeout=300,
        )
    assert proc.returncode == 2 and proc.stderr.splitlines() == [
        "python -m vo_lib generate: error: standard output: no space left on device"
    ], proc.stderr
    assert (tmp_path / "gen" / MARKER).is_file()


def test_a_marker_names_a_file_added_in_a_subfolder(tmp_path):
    """Markers list every file and folder written, subfolders' too: a file added below them is
    not the command's to replace."""
    import json

    from vo_lib.outputs import foreign_content

    folder = tmp_path / "gen"
    (folder / "image_0").mkdir(parents=True)
    (folder / "image_0" / "000000.png").write_bytes(b"png")
    listed = {"written_by": "vo_lib generate", "contents": ["image_0", "image_0/000000.png"]}
    (folder / MARKER).write_text(json.dumps(listed))
    assert foreign_content(folder, "vo_lib generate") == (None, True)
    (folder / "image_0" / "NOTES.txt").write_text("mine")
    assert ("it holds image_0/NOTES.txt, which this program did not write", False) == foreign_content(
        folder, "vo_lib generate"
    )


def test_a_previous_output_that_cannot_be_deleted_is_a_notice_after_the_swap(tmp_path, monkeypatch, capsys):
    """The new folder is in place once swapped: failing to delete the old one only says where it is."""
    from vo_lib import atomic

    target, complete = tmp_path / "out", tmp_path / ".out.new.tmp"
    for folder, text in ((target, "old"), (complete, "new")):
        folder.mkdir()
        (folder / "poses.txt").write_text(text)

    def refuse(path, *args, **kwargs):
        raise PermissionError(13, "Permission denied", str(path))

    monkeypatch.setattr(atomic.shutil, "rmtree", refuse)
    atomic.remove_replaced(atomic.swap_in(complete, target), target)
    assert (target / "poses.txt").read_text() == "new"
    assert "its previous contents stay in" in capsys.readouterr().err


def test_a_signal_between_the_two_renames_waits_for_the_second(tmp_path, monkeypatch):
    """Where two folders cannot be swapped in one step, SIGTERM (or Ctrl-C) landing between the
    two renames is held back until the new folder has taken the name: the name is never missing."""
    from vo_lib import atomic
    from vo_lib.outputs import OutputFolder

    class Stopped(Exception):
        pass

    def stop(signum, frame):
        raise Stopped

    rename, calls = os.rename, []

    def rename_then_signal(src, dst):
        rename(src, dst)
        calls.append(dst)
        if len(calls) == 1:
            os.kill(os.getpid(), signal.SIGTERM)

    target = tmp_path / "out"
    previous = signal.signal(signal.SIGTERM, stop)
    try:
        for text in ("old\n", "new\n"):
            with OutputFolder(target, "vo_lib run") as out:
                (out.path / "poses.txt").write_text(text)
                if text == "new\n":
                    monkeypatch.setattr(atomic, "_exchange", lambda a, b: False)
                    monkeypatch.setattr(atomic.os, "rename", rename_then_signal)
                    with pytest.raises(Stopped):
                        out.commit()
                else:
                    out.commit()
    finally:
        signal.signal(signal.SIGTERM, previous)
    assert (target / "poses.txt").read_text() == "new\n" and len(calls) == 2


def test_a_signal_after_the_swap_leaves_the_new_folder_and_says_what_it_replaced(
    tmp_path, monkeypatch, capsys
):
    """Ctrl-C while the replaced folder is deleted: the new output stays in place (no second
    deletion by the failed command's clean-up), the --force notice is printed first, and what was
    not deleted keeps its temporary's name, for the next command beside it to clear."""
    from vo_lib import atomic
    from vo_lib.outputs import OutputFolder

    target = tmp_path / "notes"
    with OutputFolder(target, "vo_lib sweep nees") as earlier:  # another command's output
        (earlier.path / "results.csv").write_text("seed\n")
        earlier.commit()

    def interrupted(path, *args, **kwargs):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt), OutputFolder(target, "vo_lib run", force=True) as out:
        (out.path / "poses.txt").write_text("new\n")
        monkeypatch.setattr(atomic.shutil, "rmtree", interrupted)
        out.commit()
    assert (target / "poses.txt").read_text() == "new\n"
    assert "--force: replaced" in capsys.readouterr().err
    assert [p.name for p in tmp_path.glob(".notes.vo_lib-*/results.csv")] == ["results.csv"]


def test_a_folder_the_user_did_not_name_is_refused_without_advising_force(tmp_path):
    """A sample's folder (named by no option) that holds a user's file: --force would not apply."""
    from vo_lib.outputs import OutputError, check_target

    (tmp_path / "sample").mkdir()
    (tmp_path / "sample" / "notes.txt").write_text("mine")
    with pytest.raises(OutputError, match=r"program \(it holds notes.txt\); move it away$"):
        check_target(tmp_path / "sample", written_by="vo_lib generate")
    with pytest.raises(OutputError, match="choose another folder: this program replaces only what it wrote$"):
        check_target(tmp_path / "sample", written_by="vo_lib generate", option="--out", force=True)


def test_an_output_link_repointed_during_the_run_is_refused_at_commit(tmp_path, monkeypatch):
    """What was checked is where the output goes: a link --out repointed meanwhile is refused."""
    from vo_lib.outputs import OutputError, OutputFolder

    monkeypatch.chdir(tmp_path)
    for name in ("A", "B"):
        (tmp_path / name).mkdir()
    Path("X").symlink_to("A")
    with OutputFolder("X", "vo_lib run", option="--out") as out:
        (out.path / "poses.txt").write_text("new")
        (tmp_path / "A").rename(tmp_path / "A_saved")
        (tmp_path / "A").mkdir()
        (tmp_path / "A" / "thesis.tex").write_text("precious")
        Path("X").unlink()
        Path("X").symlink_to("B")
        with pytest.raises(OutputError, match="--out X: now leads to .*B; nothing was written"):
            out.commit()
    assert (tmp_path / "A" / "thesis.tex").read_text() == "precious" and not any((tmp_path / "B").iterdir())


def test_the_same_folder_under_another_name_is_guarded(tmp_path):
    """An output inside the input reached under a second name (a bind mount) is refused."""
    from vo_lib.outputs import OutputError, check_target

    (tmp_path / "seq" / "image_0").mkdir(parents=True)
    (tmp_path / "alias").mkdir()
    mount = subprocess.run(
        ["mount", "--bind", str(tmp_path / "seq"), str(tmp_path / "alias")], capture_output=True
    )
    if mount.returncode != 0:
        pytest.skip("mount --bind is not permitted here")
    try:
        with pytest.raises(OutputError, match="lies inside the input sequence"):
            check_target(
                tmp_path / "alias" / "image_0", written_by="vo_lib run", force=True, inputs=[tmp_path / "seq"]
            )
    finally:
        subprocess.run(["umount", str(tmp_path / "alias")], check=True)


def test_links_are_looked_through_within_a_budget(tmp_path, monkeypatch):
    """A link to a large folder (/, say) is not walked through to its end."""
    from vo_lib import outputs

    (tmp_path / "seq").mkdir()
    (tmp_path / "big").mkdir()
    for k in range(50):
        (tmp_path / "big" / f"{k}").mkdir()
        (tmp_path / "big" / f"{k}" / "link").symlink_to(tmp_path / "seq")
    (tmp_path / "seq" / "big").symlink_to(tmp_path / "big")
    assert outputs.linked_from(tmp_path / "seq") == ([tmp_path / "big", tmp_path / "seq"], None)
    monkeypatch.setattr(outputs, "MAX_WALKED", 2)
    assert outputs.linked_from(tmp_path / "seq") == (
        [tmp_path / "big"],
        "it holds or links to over 2 entries",
    )


def test_an_existing_folder_is_refused_where_the_inputs_links_were_not_all_followed(tmp_path, monkeypatch):
    """Where the budget ran out, or a folder of the input could not be listed (entered, as a reader
    opening files it names does, but not listed), a folder the input reads may lie beyond: an
    existing output folder is refused, --force or not; a new one is written."""
    from vo_lib import outputs

    (tmp_path / "seq" / "data").mkdir(parents=True)
    with outputs.OutputFolder(tmp_path / "notes", "vo_lib sweep nees") as earlier:  # another command's
        (earlier.path / "thesis.tex").write_text("mine\n")
        earlier.commit()
    for k in range(5):
        (tmp_path / "big" / f"{k}").mkdir(parents=True)
    (tmp_path / "seq" / "big").symlink_to(tmp_path / "big")
    check = dict(written_by="vo_lib run", force=True, inputs=[tmp_path / "seq"])
    assert "notes" in outputs.check_target(tmp_path / "notes", **check)  # every link followed
    monkeypatch.setattr(outputs, "MAX_WALKED", 3)
    with pytest.raises(
        outputs.OutputError, match="cannot be checked .the input: it holds or links to over 3"
    ):
        outputs.check_target(tmp_path / "notes", **check)
    assert outputs.check_target(tmp_path / "new", **check) is None  # a new folder is still written
    monkeypatch.setattr(outputs, "MAX_WALKED", 100_000)
    (tmp_path / "seq" / "data" / "000.png").symlink_to(tmp_path / "notes" / "thesis.tex")
    scandir, data = os.scandir, str(tmp_path / "seq" / "data")  # a folder of mode 0311, for root too

    def unlistable(path="."):
        if os.fspath(path) == data:
            raise PermissionError(13, "Permission denied", data)
        return scandir(path)

    monkeypatch.setattr(os, "scandir", unlistable)
    with pytest.raises(outputs.OutputError, match="data cannot be listed"):
        outputs.check_target(tmp_path / "notes", **check)
    assert outputs.check_target(tmp_path / "new", **check) is None  # a new folder is still written


def test_a_mount_point_as_out_is_refused_before_the_run(tmp_path, monkeypatch):
    """The finished output is renamed into the place of ``--out``; a mount point cannot be renamed
    over, so it is named as such at once, not after the run as "Device or resource busy"."""
    from vo_lib.outputs import OutputError, check_target

    mounted = tmp_path / "disk"
    mounted.mkdir()
    real_ismount = os.path.ismount
    monkeypatch.setattr(os.path, "ismount", lambda p: str(p) == str(mounted) or real_ismount(p))
    with pytest.raises(OutputError, match="--out .*disk: is a mount point.*give one inside it"):
        check_target(mounted, written_by="vo_lib run", option="--out")
    assert check_target(mounted / "run", written_by="vo_lib run", option="--out") is None


def test_a_default_output_of_another_sequence_of_that_name_is_not_replaced(tmp_path, monkeypatch, capsys):
    """runs/00 holds the run of one 00; a run of another 00 (KITTI's sequences share names) says so
    and writes nothing without --force; the same sequence, or --force, replaces it."""
    from vo_lib.cli.main import main

    monkeypatch.chdir(tmp_path)
    first, second = make_sequence(tmp_path / "a" / "00"), make_sequence(tmp_path / "b" / "00", seed=1)
    assert main(["run", "--sequence", str(first)]) == 0
    written = (tmp_path / "runs" / "00" / "poses.txt").read_bytes()
    capsys.readouterr()
    assert main(["run", "--sequence", str(second)]) == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert f"runs/00: holds the run of {first.resolve()}, another sequence of this name; give --out" in line
    assert (tmp_path / "runs" / "00" / "poses.txt").read_bytes() == written
    assert (
        main(["run", "--sequence", str(first)]) == 0
        and main(["run", "--sequence", str(second), "--force"]) == 0
    )


def test_a_temporary_that_cannot_be_removed_is_not_said_removed(tmp_path, monkeypatch, capsys):
    """The previous contents of an output left in a temporary (a read-only folder): the next run
    beside it says that it cannot remove it, not that it did, while it is there."""
    import vo_lib.atomic as atomic

    stale_temporary(tmp_path)
    (stale,) = tmp_path.glob(f".out.vo_lib-*-{HOST}-abcd1234.tmp")
    monkeypatch.setattr(atomic.shutil, "rmtree", lambda *a, **k: None)  # as a folder one may not empty
    atomic.clear_abandoned(tmp_path, "out")
    assert stale.is_dir() and capsys.readouterr().err == (
        f"notice: cannot remove 1 temporary folder(s) left by earlier runs: {stale.name}\n"
    )
    monkeypatch.undo()
    atomic.clear_abandoned(tmp_path, "out")
    assert not stale.exists() and "notice: removed 1 temporary folder(s)" in capsys.readouterr().err


def test_a_truth_standing_still_leaves_no_blank_figure(tmp_path, capsys):
    """poses.txt of a camera standing still: no KITTI segment fits, which the table says in words
    (its two rows were printed blank), and no notice asks about quaternions, which poses.txt has not."""
    from vo_lib.cli.main import main

    seq = make_sequence(tmp_path / "still", frames=6)
    (seq / "poses.txt").write_text("1 0 0 0 0 1 0 0 0 0 1 0\n" * 6)
    assert main(["run", "--sequence", str(seq), "--out", str(tmp_path / "out"), "--no-odometry"]) == 0
    out, err = capsys.readouterr()
    assert "KITTI errors: no segment fits the truth's path" in out and "KITTI translation" not in out
    table = out[out.index("Errors against ground truth") :].split("\n\n")[0].splitlines()[1:]
    assert all(len(line) > 62 and line[62:].strip() for line in table if not line.startswith("  KITTI")), (
        table
    )
    assert "quaternions" not in err
