"""Stereo sequences on disk in the KITTI odometry layout, plus our ``odometry.txt``.

::

    SEQ/image_0/000000.png ...  left, rectified, 8-bit grey
    SEQ/image_1/000000.png ...  right
    SEQ/calib.txt               "P0: 12 numbers" and "P1: 12 numbers" (other lines are ignored)
    SEQ/times.txt               one timestamp in seconds per frame
    SEQ/poses.txt               optional: 12 numbers per frame, 3x4 pose of camera 0 in frame 0
                                (KITTI's odometry set keeps them apart: sequences/NN -> poses/NN.txt)
    SEQ/odometry.txt            optional: "delta_u_left delta_u_right" per frame, metres
    SEQ/manifest.json           optional: how a sample was made (rate, speeds, rig, world)

A real KITTI odometry sequence loads unchanged. Images are read by :mod:`vo_lib.formats.images`,
text files by :mod:`vo_lib.formats.frame_files`; a problem raises one :class:`SequenceError`.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from vo_lib.camera import StereoCamera
from vo_lib.formats.frame_files import (
    MAX_FOCAL_WIDTHS,
    MIN_BASELINE_M,
    SequenceError,
    beyond,
    check_manifest,
    check_metres,
    focal_problem,
    read_calib,
    read_manifest,
    read_per_frame,
    read_poses,
    read_rows,
    read_times,
)
from vo_lib.formats.images import check_headers, image_files, load_image, unpaired
from vo_lib.formats.poses import check_file
from vo_lib.geometry import as_homogeneous

#: Largest wheel distance between two frames in ``odometry.txt``, metres: beyond, the file is damaged.
MAX_ODOMETRY_M = 1000.0
#: Median time between frames (s): outside, times in another unit (or frames too far apart to track).
MIN_FRAME_SPACING_S, MAX_FRAME_SPACING_S = 1e-3, 10.0
#: Largest offset of the right camera off the rows, per metre of baseline, in a rectified pair's
#: projection matrices (KITTI's colour pair is 0.7 % off).
MAX_OFF_ROW = 0.05
#: Fastest median track speed of ``odometry.txt`` (m/s): beyond it, distances in another unit.
MAX_TRACK_SPEED_M_S = 50.0


def check_frame_spacing(path: Path, seconds) -> None:
    """Refuse frames (of ``path``) closer or farther apart than the bounds above (median), or one
    pause longer than the upper bound (nothing tracks, nor integrates odometry, across it)."""
    low, high = MIN_FRAME_SPACING_S, MAX_FRAME_SPACING_S
    steps = np.diff(seconds)
    spacing = float(np.median(steps)) if len(seconds) > 1 else low
    if not low <= spacing <= high:
        unit = "microseconds" if spacing < 1 else "milliseconds or nanoseconds"
        raise SequenceError(
            f"{path}: frames {beyond(spacing, low if spacing < 1 else high, 3)} s apart (median); "
            f"expected {low:g} to {high:g} s ({unit}?)"
        )
    if len(steps) and steps.max() > high:
        k = int(np.argmax(steps))
        raise SequenceError(
            f"{path}: the frame at {seconds[k + 1]:.9g} s comes {beyond(steps[k], high, 3)} s after the "
            f"one before; expected at most {high:g} s between frames"
        )


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
    #: The file the ground truth was read from, where the layout offers several (an ASL recording's).
    truth_file: Path | None = None
    #: A drive of KITTI's raw set: its OXTS packets, one per frame, and its raw calibration's folder.
    oxts: np.ndarray | None = None
    raw_calib: Path | None = None

    #: Frames decoded ahead, on a reader thread, of the one asked for (0: none).
    read_ahead: int = 2
    #: Milliseconds each frame's pair took to decode (and rectify), by frame, wherever it was decoded.
    decoding_ms: dict = field(default_factory=dict, init=False, repr=False, compare=False)
    _ahead: dict = field(default_factory=dict, init=False, repr=False, compare=False)
    _reader: ThreadPoolExecutor | None = field(default=None, init=False, repr=False, compare=False)

    def __len__(self) -> int:
        return len(self.left_files)

    def pair(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """Left and right images of frame ``k`` (rectified where needed), the next ``read_ahead``
        decoded meanwhile on a reader thread."""
        if self.read_ahead > 0 and self._reader is None:
            self._reader = ThreadPoolExecutor(max_workers=1, thread_name_prefix="vo_lib-reader")
        for j in range(k + 1, min(k + 1 + self.read_ahead, len(self))):
            if j not in self._ahead:
                self._ahead[j] = self._reader.submit(self._decoded_ahead, j)
        for j in [j for j in self._ahead if j < k and self.read_ahead > 0]:  # the caller went back
            self._ahead.pop(j).cancel()
        ahead = self._ahead.pop(k, None)
        decoded = ahead.result() if ahead is not None else None
        return decoded if decoded is not None else self._decoded(k)

    def _decoded_ahead(self, k: int) -> tuple[np.ndarray, np.ndarray] | None:
        """Frame ``k``, or None: a bad frame is decoded again, and reported, by the caller's thread."""
        try:
            return self._decoded(k)
        except SequenceError:
            return None

    def _decoded(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        start = time.perf_counter()
        left, right = load_image(self.left_files[k], k), load_image(self.right_files[k], k)
        for path, img in ((self.left_files[k], left), (self.right_files[k], right)):
            if img.shape != (self.camera.height, self.camera.width):
                raise SequenceError(
                    f"{path}, frame {k}: {img.shape[1]}x{img.shape[0]} image; the sequence's images are "
                    f"{self.camera.width}x{self.camera.height}"
                )
        pair = (left, right) if self.rectify is None else self.rectify(left, right)
        self.decoding_ms[k] = 1000.0 * (time.perf_counter() - start)
        return pair

    def __iter__(self):
        return map(self.pair, range(len(self)))

    def poses_4x4(self) -> np.ndarray | None:
        """Ground-truth camera poses as ``(N, 4, 4)`` matrices, or None."""
        return None if self.poses is None else as_homogeneous(self.poses)


def checked_camera(
    calib: Path, P0, P1, size: tuple[int, int], keys: tuple[str, str] = ("P0", "P1")
) -> StereoCamera:
    """The rig of the rectified projection matrices ``P0``, ``P1`` (lines ``keys`` of ``calib``) for
    images of ``size``; one line naming ``calib`` where it cannot be theirs (a baseline not in metres
    or too short, a principal point outside, a focal length in other units, a pair not rectified)."""
    (w, h), (left, right) = size, keys
    try:
        camera = StereoCamera.from_projection_matrices(P0, P1, w, h)
    except ValueError as exc:
        raise SequenceError(f"{calib}: {exc}") from None
    claim = f"{right} puts the right camera {{}} from the left (baseline = ({left}[0,3] - {right}[0,3]) / fx)"
    check_metres(calib, claim, camera.baseline)
    if not (0 <= camera.cx <= w and 0 <= camera.cy <= h):
        raise SequenceError(
            f"{calib}: {left}'s principal point ({camera.cx:g}, {camera.cy:g}) lies outside the "
            f"{w}x{h} images"
        )
    if max(camera.fx, camera.fy) > MAX_FOCAL_WIDTHS * w:
        raise SequenceError(
            f"{calib}: {left}'s focal length {max(camera.fx, camera.fy):g} px is over {MAX_FOCAL_WIDTHS} "
            f"image widths ({w} px): a field of view under 0.6 degrees; expected pixels of these images"
        )
    _check_rectified(calib, camera, (P0, P1), keys, claim)
    return camera


def _check_rectified(calib: Path, camera: StereoCamera, projections, keys: tuple[str, str], claim: str):
    """Refuse projection matrices (lines ``keys`` of ``calib``) of no rectified stereo rig: focal
    lengths of no camera, two intrinsic matrices, cameras in one place (``claim``: the baseline) or
    off the rows."""
    left, right = keys
    P0, P1 = (np.asarray(P, float).reshape(3, 4) for P in projections)
    if problem := focal_problem(camera.fx, camera.fy, camera.width):
        raise SequenceError(f"{calib}: {left}'s {problem}")
    if not all(np.allclose(P[:, :3], camera.K, rtol=1e-5, atol=1e-6) for P in (P0, P1)):
        raise SequenceError(
            f"{calib}: {left} and {right} are not a rectified pair: expected one intrinsic matrix "
            "[[fx 0 cx] [0 fy cy] [0 0 1]] as the first three columns of both"
        )
    if camera.baseline < MIN_BASELINE_M:
        raise SequenceError(
            f"{calib}: {claim.format(beyond(camera.baseline, MIN_BASELINE_M))}; expected a stereo rig, "
            f"at least {MIN_BASELINE_M:g} m"
        )
    offset = np.linalg.solve(camera.K, P0[:, 3] - P1[:, 3])  # the right camera from the left
    if np.hypot(offset[1], offset[2]) > MAX_OFF_ROW * abs(offset[0]):
        raise SequenceError(
            f"{calib}: {right} puts the right camera at ({', '.join(f'{x:g}' for x in offset)}) from "
            f"the left; expected a rectified pair, the right camera along the rows (x)"
        )


def image_pairs(root: Path, sides: tuple[str, str] = ("image_0", "image_1")) -> tuple[list[Path], list[Path]]:
    """The left and right images of a sequence folder (in its folders ``sides``), paired by name."""
    if not root.is_dir():
        what = "a file, not a sequence folder" if root.exists() else "sequence folder not found"
        raise SequenceError(f"{root}: {what}")
    left, right = image_files(root / sides[0]), image_files(root / sides[1])
    if not left:
        raise SequenceError(f"{root / sides[0]}: no images")
    if [p.name for p in left] != [p.name for p in right]:
        raise SequenceError(f"{root}: {unpaired(left, right, sides)}")
    return left, right


def _odometry(path: Path, times: np.ndarray) -> np.ndarray:
    """``odometry.txt``: a row of track distances per frame, at a speed a vehicle reaches."""
    odo = read_per_frame(
        path, len(times), "rows", lambda p: read_rows(p, 2, "delta_u_left delta_u_right", MAX_ODOMETRY_M)
    )
    if len(times) > 1:
        speeds = np.abs(odo[1:]).max(axis=1) / np.diff(times)
        median = float(np.median(speeds))
        claim = "the tracks move {} per second (median, with times.txt)"
        check_metres(path, claim, median, MAX_TRACK_SPEED_M_S, " m/s")
        k = int(np.argmax(speeds))  # one damaged row among good ones
        if speeds[k] > MAX_TRACK_SPEED_M_S:
            raise SequenceError(
                f"{path}: frame {k + 1}: the tracks move {speeds[k]:g} m/s (with times.txt); expected at "
                f"most {MAX_TRACK_SPEED_M_S:g} m/s"
            )
    return odo


def truth_path(root: Path) -> Path:
    """A sequence's ``poses.txt``; where it has none and sits in KITTI's odometry set as that set is
    downloaded (``dataset/sequences/NN``), that sequence's ``dataset/poses/NN.txt``, if there."""
    kitti = root.parent.parent / "poses" / f"{root.name}.txt"
    here = root / "poses.txt"
    return kitti if not here.exists() and root.parent.name == "sequences" and kitti.is_file() else here


def read_sequence(path, odometry: bool = True, truth: bool = True) -> Sequence:
    """Read and check a sequence folder (``odometry=False``: ``odometry.txt`` is not read;
    ``truth=False``: neither ``poses.txt`` nor the manifest's positions)."""
    root = Path(path)
    left, right = image_pairs(root)
    calib = root / "calib.txt"
    check_file(calib, "the calibration, P0 and P1 lines")
    camera = checked_camera(calib, *read_calib(calib), check_headers(left, right))
    n = len(left)
    check_file(root / "times.txt", "one timestamp per frame")
    times = read_per_frame(root / "times.txt", n, "timestamps", read_times)
    check_frame_spacing(root / "times.txt", times)
    poses = odo = None
    truth_file = truth_path(root)
    if truth and check_file(truth_file, "the ground-truth poses", optional=True):
        poses = read_per_frame(truth_file, n, "poses", read_poses)
    if odometry and check_file(root / "odometry.txt", "the odometry", optional=True):
        odo = _odometry(root / "odometry.txt", times)
    manifest_path = root / "manifest.json"
    manifest = (
        read_manifest(manifest_path) if check_file(manifest_path, "the manifest", optional=True) else {}
    )
    if not truth:
        manifest.pop("positions", None)
    check_manifest(manifest_path, manifest, n)
    kept_apart = truth_file if poses is not None and truth_file.parent != root else None
    return Sequence(root, camera, times, left, right, poses, odo, manifest, truth_file=kept_apart)
