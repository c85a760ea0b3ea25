"""Stereo sequences on disk in the KITTI odometry layout, plus our ``odometry.txt``.

::

    SEQ/image_0/000000.png ...  left, rectified, 8-bit grey
    SEQ/image_1/000000.png ...  right
    SEQ/calib.txt               "P0: 12 numbers" and "P1: 12 numbers" (other lines are ignored)
    SEQ/times.txt               one timestamp in seconds per frame
    SEQ/poses.txt               optional: 12 numbers per frame, 3x4 pose of camera 0 in frame 0
    SEQ/odometry.txt            optional: "delta_u_left delta_u_right" per frame, metres
    SEQ/manifest.json           optional: how a sample was made (rate, speeds, rig, world)

A real KITTI odometry sequence loads unchanged. Every problem raises one
:class:`SequenceError` naming the file (and line) and what was expected. Writing goes to a
temporary folder that is renamed when complete, so a failed write leaves nothing behind.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

from vo_lib.camera import StereoCamera
from vo_lib.geometry import as_homogeneous

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".pgm", ".bmp", ".tif", ".tiff")


class SequenceError(ValueError):
    """A sequence on disk is missing something or holds something malformed."""


def _numbers(path: Path, line_no: int, text: str, count: int, what: str) -> np.ndarray:
    parts = text.split()
    if len(parts) != count:
        raise SequenceError(f"{path}, line {line_no}: {what} needs {count} numbers, got {len(parts)}")
    try:
        values = np.array([float(p) for p in parts])
    except ValueError as exc:
        raise SequenceError(f"{path}, line {line_no}: {what} holds a non-number ({exc})") from None
    if not np.all(np.isfinite(values)):
        raise SequenceError(f"{path}, line {line_no}: {what} holds a NaN or infinite value")
    return values


def _lines(path: Path) -> list[tuple[int, str]]:
    """Non-empty lines with their 1-based numbers."""
    return [(i, s.strip()) for i, s in enumerate(path.read_text().splitlines(), start=1) if s.strip()]


def read_calib(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """``(P0, P1)`` 3x4 matrices from a KITTI ``calib.txt``."""
    found = {}
    for line_no, text in _lines(path):
        key, sep, rest = text.partition(":")
        if not sep:
            raise SequenceError(f"{path}, line {line_no}: expected 'NAME: numbers', got {text[:40]!r}")
        key = key.strip()
        if key in ("P0", "P1", "P2", "P3"):
            found[key] = _numbers(path, line_no, rest, 12, key).reshape(3, 4)
    for key in ("P0", "P1"):
        if key not in found:
            side = "left" if key == "P0" else "right"
            raise SequenceError(f"{path}: no {key} line ({side} camera projection, 12 numbers)")
    return found["P0"], found["P1"]


def read_times(path: Path) -> np.ndarray:
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
    return np.array([_numbers(path, n, text, count, what) for n, text in _lines(path)]).reshape(-1, count)


def load_image(path: Path) -> np.ndarray:
    """An 8-bit grey image; colour is converted to grey, 16-bit images are refused."""
    img = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if img is None or img.size == 0:
        raise SequenceError(f"{path}: cannot read the image (empty, truncated or not an image)")
    if img.dtype != np.uint8:
        raise SequenceError(
            f"{path}: {img.dtype} image; expected 8-bit grey (convert it, e.g. scale 16-bit values to 0-255)"
        )
    if img.ndim == 3:
        code = cv2.COLOR_BGRA2GRAY if img.shape[2] == 4 else cv2.COLOR_BGR2GRAY
        img = cv2.cvtColor(img, code)
    return img


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

    def __len__(self) -> int:
        return len(self.left_files)

    def pair(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """Left and right images of frame ``k``."""
        left, right = load_image(self.left_files[k]), load_image(self.right_files[k])
        if left.shape != right.shape:
            raise SequenceError(
                f"{self.right_files[k]} is {right.shape[1]}x{right.shape[0]} but "
                f"{self.left_files[k]} is {left.shape[1]}x{left.shape[0]}"
            )
        if left.shape != (self.camera.height, self.camera.width):
            raise SequenceError(
                f"{self.left_files[k]} is {left.shape[1]}x{left.shape[0]}; the sequence's first image is "
                f"{self.camera.width}x{self.camera.height}"
            )
        return left, right

    def __iter__(self):
        for k in range(len(self)):
            yield self.pair(k)

    def poses_4x4(self) -> np.ndarray | None:
        """Ground-truth camera poses as ``(N, 4, 4)`` matrices, or None."""
        return None if self.poses is None else as_homogeneous(self.poses)


def _image_files(folder: Path) -> list[Path]:
    if not folder.is_dir():
        raise SequenceError(f"{folder}: missing image folder")
    return sorted(p for p in folder.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES)


def read_sequence(path) -> Sequence:
    """Read and check a sequence folder (KITTI layout plus ``odometry.txt``)."""
    root = Path(path)
    if not root.is_dir():
        raise SequenceError(f"{root}: sequence folder not found")
    left, right = _image_files(root / "image_0"), _image_files(root / "image_1")
    if not left:
        raise SequenceError(f"{root / 'image_0'}: no images")
    if len(left) != len(right):
        raise SequenceError(
            f"{root}: image_0 has {len(left)} images but image_1 has {len(right)}; expected equal counts"
        )
    calib = root / "calib.txt"
    if not calib.is_file():
        raise SequenceError(f"{calib}: missing (needs P0 and P1 lines)")
    first_left, first_right = load_image(left[0]), load_image(right[0])
    if first_left.shape != first_right.shape:
        raise SequenceError(
            f"{right[0]} is {first_right.shape[1]}x{first_right.shape[0]} but {left[0]} is "
            f"{first_left.shape[1]}x{first_left.shape[0]}; left and right must have the same size"
        )
    h, w = first_left.shape
    P0, P1 = read_calib(calib)
    try:
        camera = StereoCamera.from_projection_matrices(P0, P1, w, h)
    except ValueError as exc:
        raise SequenceError(f"{calib}: {exc}") from None
    times_path = root / "times.txt"
    if not times_path.is_file():
        raise SequenceError(f"{times_path}: missing (one timestamp per frame)")
    times = read_times(times_path)
    n = len(left)
    if len(times) != n:
        raise SequenceError(f"{times_path} has {len(times)} timestamps but there are {n} images")
    poses = odometry = None
    poses_path, odo_path = root / "poses.txt", root / "odometry.txt"
    if poses_path.is_file():
        poses = read_rows(poses_path, 12, "a 3x4 pose").reshape(-1, 3, 4)
        if len(poses) != n:
            raise SequenceError(f"{poses_path} has {len(poses)} poses but there are {n} images")
    if odo_path.is_file():
        odometry = read_rows(odo_path, 2, "delta_u_left delta_u_right")
        if len(odometry) != n:
            raise SequenceError(f"{odo_path} has {len(odometry)} lines but there are {n} images")
    manifest_path = root / "manifest.json"
    manifest = json.loads(manifest_path.read_text()) if manifest_path.is_file() else {}
    return Sequence(root, camera, times, left, right, poses, odometry, manifest)


def _format_row(values) -> str:
    return " ".join(repr(float(v)) for v in values)


def replace_folder(complete: Path, target: Path) -> Path:
    """Rename the finished folder ``complete`` to ``target``, replacing any folder there."""
    if target.exists():
        old = target.with_name(f".{target.name}.old-{os.getpid()}")
        os.replace(target, old)
        os.replace(complete, target)
        shutil.rmtree(old, ignore_errors=True)
    else:
        os.replace(complete, target)
    return target


class SequenceWriter:
    """Write a sequence frame by frame into a temporary folder, renamed on :meth:`close`.

    Use as a context manager; if the block raises, the temporary folder is removed and any
    existing sequence at ``path`` is left untouched.
    """

    def __init__(self, path, camera: StereoCamera):
        self.path = Path(path)
        self.camera = camera
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._tmp = Path(tempfile.mkdtemp(prefix=f".{self.path.name}.", suffix=".tmp", dir=self.path.parent))
        (self._tmp / "image_0").mkdir()
        (self._tmp / "image_1").mkdir()
        self.count = 0

    def add(self, left: np.ndarray, right: np.ndarray) -> None:
        for folder, img in (("image_0", left), ("image_1", right)):
            if img.dtype != np.uint8 or img.ndim != 2:
                raise ValueError(f"{folder} images must be 2-D uint8 grey; got {img.dtype} {img.shape}")
            cv2.imwrite(str(self._tmp / folder / f"{self.count:06d}.png"), img)
        self.count += 1

    def close(self, times, poses=None, odometry=None, manifest: dict | None = None) -> Path:
        times = np.asarray(times, dtype=float)
        if len(times) != self.count:
            raise ValueError(f"times has {len(times)} entries for {self.count} frames")
        P0, P1 = self.camera.projection_matrices()
        (self._tmp / "calib.txt").write_text(
            f"P0: {_format_row(P0.ravel())}\nP1: {_format_row(P1.ravel())}\n"
        )
        (self._tmp / "times.txt").write_text("".join(f"{t!r}\n" for t in times.tolist()))
        if poses is not None:
            poses = np.asarray(poses, dtype=float)[:, :3, :].reshape(-1, 12)
            (self._tmp / "poses.txt").write_text("".join(_format_row(p) + "\n" for p in poses))
        if odometry is not None:
            odometry = np.asarray(odometry, dtype=float).reshape(-1, 2)
            (self._tmp / "odometry.txt").write_text("".join(_format_row(o) + "\n" for o in odometry))
        if manifest is not None:
            (self._tmp / "manifest.json").write_text(json.dumps(manifest, indent=2, sort_keys=True) + "\n")
        return replace_folder(self._tmp, self.path)

    def abort(self) -> None:
        shutil.rmtree(self._tmp, ignore_errors=True)

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        if exc_type is not None or self._tmp.exists():
            self.abort()
        return False


def write_sequence(path, camera, left_images, right_images, times, poses=None, odometry=None, manifest=None):
    """Write a whole sequence at once (see :class:`SequenceWriter`)."""
    if len(left_images) != len(right_images):
        raise ValueError(f"{len(left_images)} left images but {len(right_images)} right images")
    with SequenceWriter(path, camera) as writer:
        for left, right in zip(left_images, right_images, strict=True):
            writer.add(left, right)
        return writer.close(times, poses, odometry, manifest)
