"""Writing a sequence in the KITTI odometry layout, plus our ``odometry.txt`` and ``manifest.json``,
under the rules of :mod:`vo_lib.outputs` (whole or not at all, never over a folder not ours).
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


class SequenceWriter(OutputFolder):
    """An :class:`~vo_lib.outputs.OutputFolder` that a sequence is written into frame by frame, put
    in place at ``path`` by :meth:`close`."""

    def __init__(self, path, camera: StereoCamera, written_by: str = "vo_lib generate", **check):
        super().__init__(path, written_by, **check)  # check: as :func:`~vo_lib.outputs.check_target`
        self.camera, self.count = camera, 0
        (self.path / "image_0").mkdir()
        (self.path / "image_1").mkdir()

    def add(self, left: np.ndarray, right: np.ndarray) -> None:
        for folder, img in (("image_0", left), ("image_1", right)):
            if img.dtype != np.uint8 or img.ndim != 2:
                raise ValueError(f"{folder} images must be 2-D uint8 grey; got {img.dtype} {img.shape}")
            ok, encoded = cv2.imencode(".png", img)
            if not ok:
                raise ValueError(f"{folder}: frame {self.count} cannot be encoded as PNG")
            self._write(self.path / folder / f"{self.count:06d}.png", encoded.tobytes())
        self.count += 1

    def _write(self, path: Path, data: bytes) -> None:
        """Write one file; a failure (a full disk) raises :class:`~vo_lib.outputs.OutputError` naming the
        output folder, not the temporary one."""
        try:
            path.write_bytes(data)
        except OSError as exc:
            why = "no space left on device" if exc.errno == errno.ENOSPC else (exc.strerror or str(exc))
            raise OutputError(
                f"{self.label}: cannot write the sequence ({why}); nothing was written"
            ) from None

    def carry(self, source: Path, packets=None, raw_calib: Path | None = None) -> None:
        """Copy those of :data:`CARRIED` that ``source`` holds into the sequence, unchanged (of a
        folder, its ``calib_*.txt`` files). A drive of KITTI's raw set gives its OXTS ``packets``
        (written as ``oxts.txt``) and the folder of its ``raw_calib`` instead."""
        for name in CARRIED:
            src = Path(raw_calib) if name == "raw_calib" and raw_calib else Path(source) / name
            try:
                self._copy(src, self.path / name)
            except OSError as exc:
                raise OutputError(
                    f"{self.label}: cannot copy {exc.filename or src} "
                    f"({exc.strerror or str(exc)[:120]}); nothing was written"
                ) from None
        if packets is not None:
            self._write(self.path / "oxts.txt", _format_rows(packets, 30).encode())

    @staticmethod
    def _copy(src: Path, dst: Path) -> None:
        """A file as it is; ``raw_calib``, a folder, as its ``calib_*.txt`` files; nothing if absent."""
        if src.is_dir() and dst.name != "raw_calib":
            raise OutputError(f"{src}: a folder, where a file should be")
        if src.is_dir():  # raw_calib: what is read of it, not what else it holds
            dst.mkdir()  # with the umask's permissions, not src's: it can be replaced
            for file in [f for f in sorted(src.glob("calib_*.txt")) if f.is_file()]:
                shutil.copyfile(file, dst / file.name)
        elif src.is_file() and dst.name == "raw_calib":
            raise OutputError(f"{src}: a file, where the folder of KITTI's raw calibration should be")
        elif src.is_file():
            shutil.copyfile(src, dst)

    def close(
        self, times, poses=None, odometry=None, manifest: dict | None = None, camera_from_body=None
    ) -> Path:
        """Write the text files and move the finished sequence into place; returns its path. With
        ``camera_from_body`` (4x4), ``calib.txt`` holds all of KITTI's keys: ``P2`` and ``P3`` repeat
        ``P0`` and ``P1``, ``Tr`` is the body into the left camera (KITTI's, its laser scanner)."""
        times = np.asarray(times, dtype=float)
        if len(times) != self.count:
            raise ValueError(f"times has {len(times)} entries for {self.count} frames")
        P0, P1 = self.camera.projection_matrices()
        calib = f"P0: {_format_rows(P0, 12)}P1: {_format_rows(P1, 12)}"
        if camera_from_body is not None:
            Tr = np.asarray(camera_from_body, float)[:3]
            calib += f"P2: {_format_rows(P0, 12)}P3: {_format_rows(P1, 12)}Tr: {_format_rows(Tr, 12)}"
        files = {
            "calib.txt": calib,
            "times.txt": "".join(f"{t!r}\n" for t in times.tolist()),
            "poses.txt": None if poses is None else _format_rows(np.asarray(poses, float)[:, :3, :], 12),
            "odometry.txt": None if odometry is None else _format_rows(odometry, 2),
            "manifest.json": None
            if manifest is None
            else json.dumps(manifest, indent=2, sort_keys=True) + "\n",
        }
        for name, text in files.items():
            if text is not None:
                self._write(self.path / name, text.encode())
        return self.commit(frames=self.count)


def write_sequence(path, camera, left_images, right_images, times, poses=None, odometry=None, manifest=None):
    """Write a whole sequence at once (see :class:`SequenceWriter`)."""
    with SequenceWriter(path, camera) as writer:
        for left, right in zip(left_images, right_images, strict=True):
            writer.add(left, right)
        return writer.close(times, poses, odometry, manifest)
