"""Stereo sequences on disk in the KITTI odometry layout, plus our ``odometry.txt``.

::

    SEQ/image_0/000000.png ...  left, rectified, 8-bit grey
    SEQ/image_1/000000.png ...  right
    SEQ/calib.txt               "P0: 12 numbers" and "P1: 12 numbers" (other lines are ignored)
    SEQ/times.txt               one timestamp in seconds per frame
    SEQ/poses.txt               optional: 12 numbers per frame, 3x4 pose of camera 0 in frame 0
    SEQ/odometry.txt            optional: "delta_u_left delta_u_right" per frame, metres
    SEQ/manifest.json           optional: how a sample was made (rate, speeds, rig, world)

A real KITTI odometry sequence loads unchanged. The rules of reading:

* **Frames are paired by file name, in numeric order.** ``image_0`` and ``image_1`` must hold the
  same names; a name on one side only is an error that names it. Names sort by the numbers in
  them, whatever their padding (``2.png`` before ``10.png``); two names of one number on one side
  (``1.png`` and ``01.png``) are an error. Hidden files (``._000001.png`` and the like) are ignored.
* **Every image header is checked when the sequence is opened**, cheaply (PNG headers and end
  markers are read without decoding; other formats through Pillow's lazy open): size equal to
  the first image's, 8 bits per channel, one to four channels, PNG and JPEG files complete (their
  end marker present). What can only
  be found by decoding (damaged compressed data) raises when the frame is read.
* Every problem raises one :class:`SequenceError` naming the file (and line or frame) and what
  was expected; the number of timestamps, poses and odometry rows must equal the frame count.

Writing (:class:`SequenceWriter`) goes to a temporary folder renamed when complete, under the
rules of :mod:`vo_lib.outputs`: nothing is written over a folder this package did not
write, and a failed write leaves nothing behind.
"""

from __future__ import annotations

import errno
import json
import os
import re
import struct
import threading
import zlib
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

from vo_lib.camera import StereoCamera
from vo_lib.formats.poses import TrajectoryError, read_trajectory
from vo_lib.geometry import as_homogeneous
from vo_lib.outputs import OutputError, OutputFolder

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".pgm", ".bmp", ".tif", ".tiff")
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
PNG_END = b"\x00\x00\x00\x00IEND\xaeB`\x82"
JPEG_START, JPEG_END = b"\xff\xd8", b"\xff\xd9"
#: Channels of each PNG colour type as OpenCV decodes it (palette images become BGR).
PNG_CHANNELS = {0: 1, 2: 3, 3: 3, 4: 4, 6: 4}
#: Pillow modes of 8 bits per channel (or fewer, widened to 8 when decoded).
EIGHT_BIT_MODES = {"1", "L", "P", "LA", "La", "PA", "RGB", "RGBA", "RGBa", "RGBX", "CMYK", "YCbCr"}


class SequenceError(ValueError):
    """A sequence on disk is missing something or holds something malformed."""


#: Largest image side accepted from a header (pixels): larger claims are refused before decoding.
MAX_IMAGE_SIDE = 16384
#: Bytes a line of a per-frame file may take on average (a KITTI pose line is about 200, an OXTS
#: packet about 300): a file larger than this per frame is refused before it is read.
MAX_LINE_BYTES = 1024


def present(path: Path, what: str) -> bool:
    """Whether the optional file ``path`` is there; a folder (or anything but a file) in its
    place raises :class:`SequenceError`, so that it is not silently ignored."""
    if not os.path.lexists(path):
        return False
    if not Path(path).is_file():
        kind = "a folder" if Path(path).is_dir() else "not a regular file"
        raise SequenceError(f"{path}: {kind}, where {what} should be a file")
    return True


def required(path: Path, what: str) -> None:
    """Raise :class:`SequenceError` unless ``path`` is a file: "missing", or what is there instead."""
    if not present(path, what):
        raise SequenceError(f"{path}: missing ({what})")


def check_size(path: Path, frames: int, what: str) -> None:
    """Refuse a per-frame file far larger than ``frames`` lines could be, before reading it."""
    size = Path(path).stat().st_size
    limit = MAX_LINE_BYTES * frames + 65536
    if size > limit:
        raise SequenceError(
            f"{path}: {size:,} bytes, far more than {frames} lines of {what} take (at most {limit:,}); "
            "expected one line per frame"
        )


def _numbers(path: Path, line_no: int, text: str, count: int, what: str) -> np.ndarray:
    parts = text.split()
    if len(parts) != count:
        plural = "s" if count != 1 else ""
        raise SequenceError(f"{path}, line {line_no}: {what} needs {count} number{plural}, got {len(parts)}")
    try:
        values = np.array([float(p) for p in parts])
    except ValueError as exc:
        raise SequenceError(f"{path}, line {line_no}: {what} holds a non-number ({exc})") from None
    if not np.all(np.isfinite(values)):
        raise SequenceError(f"{path}, line {line_no}: {what} holds a NaN or infinite value")
    return values


def read_text(path: Path) -> str:
    """The text of a small file (UTF-8, an initial byte-order mark dropped); any problem is a
    :class:`SequenceError` naming the file."""
    try:
        data = Path(path).read_bytes()
    except OSError as exc:
        raise SequenceError(f"{path}: cannot read ({exc.strerror or exc})") from None
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise SequenceError(f"{path}: not a text file (byte {exc.start} is not UTF-8)") from None


def _lines(path: Path) -> list[tuple[int, str]]:
    """Non-empty lines with their 1-based numbers (lines end at newlines only)."""
    return [(i, s.strip()) for i, s in enumerate(read_text(path).split("\n"), start=1) if s.strip()]


def read_calib(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """``(P0, P1)`` 3x4 matrices from a KITTI ``calib.txt``; raises :class:`SequenceError`."""
    found, where = {}, {}
    for line_no, text in _lines(path):
        key, sep, rest = text.partition(":")
        if not sep:
            raise SequenceError(f"{path}, line {line_no}: expected 'NAME: numbers', got {text[:40]!r}")
        key = key.strip()
        if key in ("P0", "P1", "P2", "P3"):
            if key in found:
                raise SequenceError(
                    f"{path}, line {line_no}: a second {key} line (the first is line {where[key]})"
                )
            found[key] = _numbers(path, line_no, rest, 12, key).reshape(3, 4)
            where[key] = line_no
    for key in ("P0", "P1"):
        if key not in found:
            side = "left" if key == "P0" else "right"
            raise SequenceError(f"{path}: no {key} line ({side} camera projection, 12 numbers)")
    return found["P0"], found["P1"]


def read_times(path: Path) -> np.ndarray:
    """Timestamps in seconds, one a line, strictly increasing; raises :class:`SequenceError`."""
    times, previous = [], None
    for line_no, text in _lines(path):
        t = _numbers(path, line_no, text, 1, "a timestamp")[0]
        if previous is not None and not t > previous:
            raise SequenceError(
                f"{path}, line {line_no}: time {t} is not after {previous} on the line before"
            )
        times.append(t)
        previous = t
    return np.array(times)


def read_rows(path: Path, count: int, what: str) -> np.ndarray:
    """``(N, count)`` finite numbers, one row a line; raises :class:`SequenceError`."""
    return np.array([_numbers(path, n, text, count, what) for n, text in _lines(path)]).reshape(-1, count)


def read_poses(path: Path) -> np.ndarray:
    """``(N, 3, 4)`` poses of a KITTI ``poses.txt`` (12 numbers a line, a rotation then a
    translation), read by :func:`vo_lib.formats.poses.read_trajectory`; raises
    :class:`SequenceError`."""
    try:
        times, poses = read_trajectory(path)
    except TrajectoryError as exc:
        raise SequenceError(str(exc)) from None
    if times is not None:
        raise SequenceError(f"{path}: TUM rows (8 numbers); a sequence's poses.txt holds KITTI rows of 12")
    return poses[:, :3, :]


_DEVNULL: int | None = None  # a descriptor of os.devnull, opened on first use
_STDERR_LOCK = threading.Lock()


def _decode(path: Path) -> np.ndarray | None:
    """OpenCV's decoder on the file's bytes, or None: ``cv2.imread`` takes its path as UTF-8 and
    crashes the process on a path holding any other byte. A damaged PNG is refused before
    libpng sees it."""
    try:
        data = np.fromfile(path, np.uint8)
    except OSError:
        return None
    if data.size == 0 or (data[:8].tobytes() == _PNG_SIGNATURE and not _png_intact(data.tobytes())):
        return None
    try:
        return cv2.imdecode(data, cv2.IMREAD_UNCHANGED)
    except cv2.error:
        return None


_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _png_intact(data: bytes) -> bool:
    """Every chunk of a PNG whole and matching its CRC, up to IEND: a damaged file is refused here,
    quietly, rather than by libpng, which prints its own message on stderr (from any thread)."""
    at = len(_PNG_SIGNATURE)
    while at + 12 <= len(data):
        (length,) = struct.unpack_from(">I", data, at)
        end = at + 8 + length
        if end + 4 > len(data) or zlib.crc32(data[at + 4 : end]) != struct.unpack_from(">I", data, end)[0]:
            return False
        if data[at + 4 : at + 8] == b"IEND":
            return True
        at = end + 4
    return False


def _imread_quietly(path: Path) -> np.ndarray | None:
    """The image, decoded with the process's stderr muted meanwhile (libpng prints its own
    message for a damaged file there, and ours, one line naming the file and frame, says it
    better), or None where OpenCV cannot decode it. Only the main thread mutes, one call at a
    time: muting from the reader thread could swallow what the main thread writes meanwhile."""
    global _DEVNULL
    if threading.current_thread() is not threading.main_thread():
        return _decode(path)
    with _STDERR_LOCK:
        try:
            if _DEVNULL is None:
                _DEVNULL = os.open(os.devnull, os.O_WRONLY)
            saved = os.dup(2)
        except OSError:
            return _decode(path)
        try:
            os.dup2(_DEVNULL, 2)
            return _decode(path)
        finally:
            os.dup2(saved, 2)
            os.close(saved)


def load_image(path: Path, frame: int | None = None) -> np.ndarray:
    """An 8-bit grey image; colour is converted to grey, 16-bit images are refused. A file that
    cannot be decoded raises one :class:`SequenceError` naming it (and ``frame``)."""
    where = f"{path}, frame {frame}" if frame is not None else f"{path}"
    img = _imread_quietly(path)
    if img is None or img.size == 0:
        raise SequenceError(f"{where}: cannot read the image (empty, truncated, damaged or not an image)")
    if img.dtype != np.uint8:
        raise SequenceError(
            f"{where}: {img.dtype} image; expected 8-bit grey (convert it, e.g. scale 16-bit values to 0-255)"
        )
    if img.ndim == 3:
        code = cv2.COLOR_BGRA2GRAY if img.shape[2] == 4 else cv2.COLOR_BGR2GRAY
        img = cv2.cvtColor(img, code)
    return img


def image_header(path: Path, frame: int | None = None) -> tuple[int, int, int]:
    """``(width, height, bits per channel)`` of an image file, read without decoding the pixels
    where possible; raises :class:`SequenceError` naming the file (and ``frame``)."""
    where = f"{path}, frame {frame}" if frame is not None else f"{path}"
    try:
        with open(path, "rb") as fh:
            head = fh.read(33)
            size = fh.seek(0, 2)
            if size == 0:
                raise SequenceError(f"{where}: empty file; expected an image")
            if head.startswith(PNG_SIGNATURE):
                if len(head) < 33 or head[12:16] != b"IHDR":
                    raise SequenceError(f"{where}: damaged PNG header (no IHDR chunk)")
                width, height = struct.unpack(">II", head[16:24])
                if not (0 < width <= MAX_IMAGE_SIDE and 0 < height <= MAX_IMAGE_SIDE):
                    raise SequenceError(
                        f"{where}: the PNG header claims {width}x{height} pixels; "
                        f"expected each side 1..{MAX_IMAGE_SIDE}"
                    )
                depth, colour = head[24], head[25]
                if colour not in PNG_CHANNELS:
                    raise SequenceError(f"{where}: damaged PNG header (colour type {colour})")
                fh.seek(max(0, size - 12))
                if fh.read(12) != PNG_END:
                    fh.seek(max(0, size - 65536))
                    if PNG_END not in fh.read():
                        raise SequenceError(
                            f"{where}: truncated PNG (no end chunk); expected a complete image"
                        )
                return width, height, depth
            if head.startswith(JPEG_START):
                fh.seek(max(0, size - 65536))
                if JPEG_END not in fh.read():
                    raise SequenceError(f"{where}: truncated JPEG (no end marker); expected a complete image")
    except OSError as exc:
        raise SequenceError(f"{where}: cannot open the image ({exc.strerror or exc})") from None
    return _header_other(path, where)


def _header_other(path: Path, where: str) -> tuple[int, int, int]:
    """Header of a non-PNG image through Pillow's lazy open, else by decoding it with OpenCV."""
    try:
        from PIL import Image

        with Image.open(path) as im:
            width, height = im.size
            return width, height, 8 if im.mode in EIGHT_BIT_MODES else 16
    except Exception:  # Pillow missing, or a file it cannot read: let OpenCV try
        img = _imread_quietly(path)
        if img is None or img.size == 0:
            raise SequenceError(f"{where}: cannot read the image (damaged or not an image)") from None
        return img.shape[1], img.shape[0], 8 * img.dtype.itemsize


@dataclass
class Sequence:
    """A stereo sequence read from disk; images are loaded when asked for."""

    path: Path
    camera: StereoCamera
    times: np.ndarray
    left_files: list[Path]
    right_files: list[Path]
    poses: np.ndarray | None = None  # (N, 3, 4): camera 0 at frame k in the frame of frame 0
    odometry: np.ndarray | None = None  # (N, 2)
    manifest: dict = field(default_factory=dict)
    #: Undistorts and rectifies a raw pair (a rig read as it records), or None: already rectified.
    rectify: Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]] | None = None

    #: Frames decoded ahead, on a reader thread, of the one asked for (0: none).
    read_ahead: int = 2
    _ahead: dict = field(default_factory=dict, init=False, repr=False, compare=False)
    _reader: ThreadPoolExecutor | None = field(default=None, init=False, repr=False, compare=False)

    def __len__(self) -> int:
        return len(self.left_files)

    def __getstate__(self) -> dict:
        state = dict(self.__dict__)
        state["_ahead"], state["_reader"] = {}, None  # a thread does not travel to another process
        return state

    def pair(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """Left and right images of frame ``k`` (rectified, where the sequence needs it); a file
        that cannot be decoded raises one :class:`SequenceError` naming it and the frame.

        Reading frame ``k`` starts decoding frames ``k + 1 ... k + read_ahead`` on a reader
        thread (OpenCV decodes without holding the interpreter), so that a caller going through
        the frames in order finds the next ones ready while it processes this one."""
        if self.read_ahead > 0:
            if self._reader is None:
                self._reader = ThreadPoolExecutor(max_workers=1, thread_name_prefix="vo_lib-reader")
            for j in range(k + 1, min(k + 1 + self.read_ahead, len(self))):
                if j not in self._ahead:
                    self._ahead[j] = self._reader.submit(self._decoded_ahead, j)
            for j in [j for j in self._ahead if j < k]:  # the caller went back: drop stale frames
                self._ahead.pop(j).cancel()
        ahead = self._ahead.pop(k, None)
        decoded = ahead.result() if ahead is not None else None
        return decoded if decoded is not None else self._decoded(k)

    def _decoded_ahead(self, k: int) -> tuple[np.ndarray, np.ndarray] | None:
        """Frame ``k`` decoded on the reader thread, or None: a bad frame is decoded again, and
        reported, by the caller's thread."""
        try:
            return self._decoded(k)
        except SequenceError:
            return None

    def _decoded(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        left, right = load_image(self.left_files[k], k), load_image(self.right_files[k], k)
        for path, img in ((self.left_files[k], left), (self.right_files[k], right)):
            if img.shape != (self.camera.height, self.camera.width):
                raise SequenceError(
                    f"{path}, frame {k}: {img.shape[1]}x{img.shape[0]} image; the sequence's images are "
                    f"{self.camera.width}x{self.camera.height}"
                )
        return (left, right) if self.rectify is None else self.rectify(left, right)

    def __iter__(self):
        for k in range(len(self)):
            yield self.pair(k)

    def poses_4x4(self) -> np.ndarray | None:
        """Ground-truth camera poses as ``(N, 4, 4)`` matrices, or None."""
        return None if self.poses is None else as_homogeneous(self.poses)


def frame_order(name: str) -> tuple:
    """Sort key of an image name: the numbers in it compared as numbers (``2.png`` < ``10.png``)."""
    parts = re.split(r"([0-9]+)", name)  # text, number, text, number, ..., text
    return tuple(int(part) if k % 2 else part for k, part in enumerate(parts))


def _image_files(folder: Path) -> list[Path]:
    """The images of ``folder`` in frame order; a name without a frame number, a dangling link
    and two names of one frame number raise :class:`SequenceError` naming the file."""
    if not folder.is_dir():
        raise SequenceError(f"{folder}: missing image folder")
    try:
        with os.scandir(folder) as entries:
            listed = [
                e
                for e in entries
                if os.path.splitext(e.name)[1].lower() in IMAGE_SUFFIXES and not e.name.startswith(".")
            ]
            names = []
            for e in listed:
                if e.is_file():
                    names.append(e.name)
                elif e.is_symlink():
                    target = os.readlink(e.path)
                    raise SequenceError(f"{e.path}: a symbolic link to {target}, which does not exist")
    except OSError as exc:
        raise SequenceError(f"{folder}: cannot list the images ({exc.strerror or exc})") from None
    for name in names:
        if not re.search(r"[0-9]", name):
            raise SequenceError(
                f"{folder / name}: no frame number in the name; name each image by its frame "
                "(000000.png, 000001.png, ...) or move it out of the folder"
            )
    keyed = sorted((frame_order(name), name) for name in names)
    for (key_a, a), (key_b, b) in zip(keyed, keyed[1:], strict=False):
        if key_a == key_b:
            raise SequenceError(f"{folder}: {a} and {b} carry the same frame number; keep one file per frame")
    return [folder / name for _, name in keyed]


def _one_side_only(root: Path, left: list[Path], right: list[Path]) -> str:
    names_l, names_r = {p.name for p in left}, {p.name for p in right}
    lonely = [f"image_0/{n}" for n in names_l - names_r] + [f"image_1/{n}" for n in names_r - names_l]
    lonely.sort(key=lambda s: frame_order(s.split("/")[1]))
    listed = ", ".join(lonely[:4]) + (f" and {len(lonely) - 4} more" if len(lonely) > 4 else "")
    return f"{len(lonely)} image(s) without a partner of the same name on the other side: {listed}"


def _check_headers(left: list[Path], right: list[Path]) -> tuple[int, int]:
    """Width and height shared by every image, checked from the headers; raises on the first
    file that is unreadable, not 8-bit or of another size."""
    size = None
    for k, (lpath, rpath) in enumerate(zip(left, right, strict=True)):
        for path in (lpath, rpath):
            width, height, depth = image_header(path, k)
            if depth > 8:
                raise SequenceError(
                    f"{path}, frame {k}: {depth}-bit image; expected 8-bit grey "
                    "(convert it, e.g. scale 16-bit values to 0-255)"
                )
            if size is None:
                size = (width, height)
            elif (width, height) != size:
                raise SequenceError(
                    f"{path}, frame {k}: {width}x{height} image, but {left[0]} is {size[0]}x{size[1]}; "
                    "every image of a sequence must have one size"
                )
    return size


def read_manifest(path: Path) -> dict:
    """The JSON object of a ``manifest.json``; raises :class:`SequenceError`."""
    try:
        manifest = json.loads(read_text(path))
    except json.JSONDecodeError as exc:
        raise SequenceError(
            f"{path}: not valid JSON ({exc.msg} at line {exc.lineno}, column {exc.colno})"
        ) from None
    if not isinstance(manifest, dict):
        raise SequenceError(f"{path}: expected a JSON object {{...}}, got a {type(manifest).__name__}")
    return manifest


def read_sequence(path, odometry: bool = True) -> Sequence:
    """Read and check a sequence folder (KITTI layout plus ``odometry.txt``).

    ``odometry=False`` ignores ``odometry.txt`` entirely (it is not even read).
    """
    root = Path(path)
    if not root.is_dir():
        what = "a file, not a sequence folder" if root.exists() else "sequence folder not found"
        raise SequenceError(f"{root}: {what}")
    left, right = _image_files(root / "image_0"), _image_files(root / "image_1")
    if not left:
        raise SequenceError(f"{root / 'image_0'}: no images")
    if [p.name for p in left] != [p.name for p in right]:
        counts = (
            f"image_0 has {len(left)} images but image_1 has {len(right)}; "
            if len(left) != len(right)
            else ""
        )
        raise SequenceError(f"{root}: {counts}{_one_side_only(root, left, right)}")
    calib = root / "calib.txt"
    required(calib, "needs P0 and P1 lines")
    w, h = _check_headers(left, right)
    P0, P1 = read_calib(calib)
    try:
        camera = StereoCamera.from_projection_matrices(P0, P1, w, h)
    except ValueError as exc:
        raise SequenceError(f"{calib}: {exc}") from None
    times_path = root / "times.txt"
    required(times_path, "one timestamp per frame")
    n = len(left)
    check_size(times_path, n, "timestamps")
    times = read_times(times_path)
    if len(times) != n:
        raise SequenceError(f"{times_path} has {len(times)} timestamps but there are {n} images")
    poses = odo = None
    poses_path, odo_path = root / "poses.txt", root / "odometry.txt"
    if present(poses_path, "the ground-truth poses"):
        check_size(poses_path, n, "poses")
        poses = read_poses(poses_path)
        if len(poses) != n:
            raise SequenceError(f"{poses_path} has {len(poses)} poses but there are {n} images")
    if odometry and present(odo_path, "the odometry"):
        check_size(odo_path, n, "odometry")
        odo = read_rows(odo_path, 2, "delta_u_left delta_u_right")
        if len(odo) != n:
            raise SequenceError(f"{odo_path} has {len(odo)} lines but there are {n} images")
    manifest_path = root / "manifest.json"
    manifest = read_manifest(manifest_path) if present(manifest_path, "the manifest") else {}
    return Sequence(root, camera, times, left, right, poses, odo, manifest)


def _format_row(values) -> str:
    return " ".join(repr(float(v)) for v in values)


class SequenceWriter:
    """Write a sequence frame by frame into a temporary folder, renamed on :meth:`close`.

    Use as a context manager; if the block raises, the temporary folder is removed and any
    existing sequence at ``path`` is left untouched. ``path`` must be new, empty or a sequence this
    package wrote; ``force`` replaces any other folder (see :mod:`vo_lib.outputs`, whose
    :class:`~vo_lib.outputs.OutputError` is raised otherwise, before anything is written).
    """

    def __init__(self, path, camera: StereoCamera, force: bool = False, option: str | None = None):
        self.path = Path(path)
        self.camera = camera
        self.label = f"{option} {path}" if option else str(path)
        self._out = OutputFolder(self.path, "vo_lib generate", force=force, option=option)
        self._tmp = self._out.path
        (self._tmp / "image_0").mkdir()
        (self._tmp / "image_1").mkdir()
        self.count = 0

    def add(self, left: np.ndarray, right: np.ndarray) -> None:
        for folder, img in (("image_0", left), ("image_1", right)):
            if img.dtype != np.uint8 or img.ndim != 2:
                raise ValueError(f"{folder} images must be 2-D uint8 grey; got {img.dtype} {img.shape}")
            ok, encoded = cv2.imencode(".png", img)
            if not ok:
                raise ValueError(f"{folder}: frame {self.count} cannot be encoded as PNG")
            self._write(self._tmp / folder / f"{self.count:06d}.png", encoded.tobytes())
        self.count += 1

    def _write(self, path: Path, data: bytes) -> None:
        """Write one file of the temporary folder; a full disk (or any write failure) raises
        :class:`~vo_lib.outputs.OutputError` naming the output folder, not the temporary."""
        try:
            path.write_bytes(data)
        except OSError as exc:
            why = "no space left on device" if exc.errno == errno.ENOSPC else (exc.strerror or str(exc))
            raise OutputError(
                f"{self.label}: cannot write the sequence ({why}); nothing was written"
            ) from None

    def close(self, times, poses=None, odometry=None, manifest: dict | None = None) -> Path:
        times = np.asarray(times, dtype=float)
        if len(times) != self.count:
            raise ValueError(f"times has {len(times)} entries for {self.count} frames")
        P0, P1 = self.camera.projection_matrices()
        self._write(
            self._tmp / "calib.txt",
            f"P0: {_format_row(P0.ravel())}\nP1: {_format_row(P1.ravel())}\n".encode(),
        )
        self._write(self._tmp / "times.txt", "".join(f"{t!r}\n" for t in times.tolist()).encode())
        if poses is not None:
            poses = np.asarray(poses, dtype=float)[:, :3, :].reshape(-1, 12)
            self._write(self._tmp / "poses.txt", "".join(_format_row(p) + "\n" for p in poses).encode())
        if odometry is not None:
            odometry = np.asarray(odometry, dtype=float).reshape(-1, 2)
            self._write(self._tmp / "odometry.txt", "".join(_format_row(o) + "\n" for o in odometry).encode())
        if manifest is not None:
            self._write(
                self._tmp / "manifest.json", (json.dumps(manifest, indent=2, sort_keys=True) + "\n").encode()
            )
        return self._out.commit(frames=self.count)

    def abort(self) -> None:
        self._out.discard()

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        self.abort()
        return False


def write_sequence(
    path, camera, left_images, right_images, times, poses=None, odometry=None, manifest=None, force=False
):
    """Write a whole sequence at once (see :class:`SequenceWriter`)."""
    if len(left_images) != len(right_images):
        raise ValueError(f"{len(left_images)} left images but {len(right_images)} right images")
    with SequenceWriter(path, camera, force=force) as writer:
        for left, right in zip(left_images, right_images, strict=True):
            writer.add(left, right)
        return writer.close(times, poses, odometry, manifest)
