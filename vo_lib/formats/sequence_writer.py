"""Writing a sequence in the KITTI odometry layout, plus our ``odometry.txt`` and ``manifest.json``.

:class:`SequenceWriter` writes into a temporary folder renamed when complete, under the rules of
:mod:`vo_lib.outputs`: nothing is written over a folder this package did not write, and a failed
write leaves nothing behind.
"""

from __future__ import annotations

import errno
import json
import shutil
from pathlib import Path

import cv2
import numpy as np

from vo_lib.camera import StereoCamera
from vo_lib.outputs import OutputError, OutputFolder

#: Files and folders of a source sequence that a copy carries as they are: the crawler's wheel
#: odometry, a KITTI raw drive's GPS/IMU packets and its raw calibration (the camera's mount).
CARRIED = ("odometry.txt", "oxts.txt", "raw_calib")


def _format_rows(values, count: int) -> str:
    """One line of ``count`` numbers per row, each written exactly (``repr``)."""
    rows = np.asarray(values, dtype=float).reshape(-1, count)
    return "".join(" ".join(repr(float(v)) for v in row) + "\n" for row in rows)


class SequenceWriter:
    """A sequence written frame by frame into a temporary folder, renamed on :meth:`close`; a
    context manager that leaves nothing behind if its block raises. ``path`` and ``force`` follow
    :mod:`vo_lib.outputs` (:class:`~vo_lib.outputs.OutputError` before anything is written)."""

    def __init__(
        self,
        path,
        camera: StereoCamera,
        force: bool = False,
        option: str | None = None,
        written_by: str = "vo_lib generate",
        inputs=(),
    ):
        self.path = Path(path)
        self.camera = camera
        self._out = OutputFolder(self.path, written_by, force=force, inputs=inputs, option=option)
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
                f"{self._out.label}: cannot write the sequence ({why}); nothing was written"
            ) from None

    def carry(self, source: Path, names=CARRIED) -> None:
        """Copy those of ``names`` that ``source`` holds into the sequence, unchanged (of a folder,
        its ``calib_*.txt`` files)."""
        for name in names:
            src = Path(source) / name
            try:
                if src.is_dir():  # raw_calib: what is read of it, not what else it holds
                    (self._tmp / name).mkdir()  # with the umask's permissions, not src's: it can be replaced
                    for file in [f for f in sorted(src.glob("calib_*.txt")) if f.is_file()]:
                        shutil.copyfile(file, self._tmp / name / file.name)
                elif src.is_file():
                    shutil.copyfile(src, self._tmp / name)
            except OSError as exc:
                raise OutputError(
                    f"{self._out.label}: cannot copy {exc.filename or src} "
                    f"({exc.strerror or str(exc)[:120]}); nothing was written"
                ) from None

    def close(self, times, poses=None, odometry=None, manifest: dict | None = None) -> Path:
        """Write the text files and move the finished sequence into place; returns its path."""
        times = np.asarray(times, dtype=float)
        if len(times) != self.count:
            raise ValueError(f"times has {len(times)} entries for {self.count} frames")
        P0, P1 = self.camera.projection_matrices()
        files = {
            "calib.txt": f"P0: {_format_rows(P0, 12)}P1: {_format_rows(P1, 12)}",
            "times.txt": "".join(f"{t!r}\n" for t in times.tolist()),
            "poses.txt": None if poses is None else _format_rows(np.asarray(poses, float)[:, :3, :], 12),
            "odometry.txt": None if odometry is None else _format_rows(odometry, 2),
            "manifest.json": None
            if manifest is None
            else json.dumps(manifest, indent=2, sort_keys=True) + "\n",
        }
        for name, text in files.items():
            if text is not None:
                self._write(self._tmp / name, text.encode())
        return self._out.commit(frames=self.count)

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        self._out.discard()
        return False


def write_sequence(
    path, camera, left_images, right_images, times, poses=None, odometry=None, manifest=None, force=False
):
    """Write a whole sequence at once (see :class:`SequenceWriter`)."""
    with SequenceWriter(path, camera, force=force) as writer:
        for left, right in zip(left_images, right_images, strict=True):
            writer.add(left, right)
        return writer.close(times, poses, odometry, manifest)
