"""A stereo rig as it records, in the ASL layout of EuRoC and Kalibr (``ROOT/mav0/cam0``, ``cam1``,
optional ground truth; ``docs/real_data.md``): images paired by timestamp, rectified as they are
read, a 6-DoF truth moved into the rectified left camera. A problem raises one :class:`AslError`.
"""

from __future__ import annotations

import contextlib
import os
import re
from pathlib import Path

import numpy as np

from vo_lib.atomic import notice
from vo_lib.evaluation import to_camera
from vo_lib.formats.asl_calibration import AslError, read_camera_yaml, rectify, truth_extrinsic
from vo_lib.formats.groundtruth import NANOSECONDS, covering, paired_apart, read_groundtruth
from vo_lib.formats.images import check_headers
from vo_lib.formats.poses import data_lines
from vo_lib.formats.sequence import Sequence, check_frame_spacing

#: Ground-truth files looked for under ``mav0``, in order: 6-DoF first, then positions only.
GROUND_TRUTH_FILES = (
    "state_groundtruth_estimate0/groundtruth.tum",
    "state_groundtruth_estimate0/data.csv",
    "vicon0/data.csv",
    "mocap0/data.csv",  # TUM-VI's name
    "leica0/data.csv",
)


def mav0_of(path) -> Path | None:
    """The ``mav0`` folder of an ASL recording at ``path`` (``mav0`` or the folder holding it), or None."""
    path = Path(path)
    for candidate in (path / "mav0", path):
        if (candidate / "cam0").is_dir() or (candidate / "cam1").is_dir():
            return candidate
    return None


def asl_near_miss(path) -> str | None:
    """Why ``path``, no recording, looks like part of one or a folder above one; else None."""
    path = Path(path)
    if (path / "mav0").is_dir() or path.name == "mav0":
        mav0 = path if path.name == "mav0" else path / "mav0"
        return f"{mav0}: no cam0 or cam1 folder; expected the ASL layout (mav0/cam0 and mav0/cam1)"
    if path.name in ("cam0", "cam1") and mav0_of(path.parent) is not None:
        return f"{path}: one camera of an ASL recording; give the folder holding mav0, or mav0 itself"
    inside = next((p for p in path.parents if p.name == "mav0" and mav0_of(p) is not None), None)
    if inside is not None:  # mav0/cam0/data, or deeper
        return f"{path}: inside the ASL recording {inside.parent}; give that folder, or its mav0"
    return _recordings_below(path)


def _recordings_below(path: Path) -> str | None:
    """Why ``path`` is the folder above one ASL recording or several; else None."""
    below = []
    with contextlib.suppress(OSError):
        below = sorted(p for p in path.iterdir() if p.is_dir() and mav0_of(p) is not None)
    if len(below) == 1:
        return f"{path}: holds the ASL recording {below[0]}; give that folder"
    if below:
        names = ", ".join(p.name for p in below[:3]) + (", ..." if len(below) > 3 else "")
        return f"{path}: holds {len(below)} ASL recordings ({names}); give one of them"
    return None


def _image_row(csv_path: Path, n: int, line: str) -> tuple[int, str]:
    """``(timestamp in ns, file name)`` of line ``n`` of a camera's ``data.csv``, checked."""
    stamp, sep, name = (part.strip() for part in line.partition(","))
    if "," in name:  # a third column, or a trailing comma: not part of the file name
        columns = len(line.split(","))
        raise AslError(f"{csv_path}, line {n}: {columns} columns; expected 2, 'timestamp [ns],filename'")
    if not sep or not name or not re.fullmatch(r"[-+]?[0-9]*\.?[0-9]+([eE][-+]?[0-9]+)?", stamp):
        raise AslError(f"{csv_path}, line {n}: expected 'timestamp [ns],filename', got {cut(line)}")
    if not re.fullmatch(r"[0-9]{1,19}", stamp) or int(stamp) >= 2**63:  # a number, but not an int64 of ns
        raise AslError(
            f"{csv_path}, line {n}: timestamp {cut(stamp)}; expected whole nanoseconds from 0 to 2^63 - 1"
        )
    if Path(name).is_absolute() or ".." in Path(name).parts:  # a name stays inside data/
        raise AslError(f"{csv_path}, line {n}: {cut(name)}; expected a file name inside data/")
    return int(stamp), name


def cut(text: str, width: int = 50) -> str:
    """``text`` quoted for an error message, its first ``width`` characters and "..." if longer."""
    return repr(text) if len(text) <= width else f"{text[:width]!r}..."


def read_image_list(camera_dir: Path) -> tuple[np.ndarray, list[Path], list[int]]:
    """``(timestamps in ns, image files, their lines)`` of one camera from its ``data.csv``."""
    csv_path = camera_dir / "data.csv"
    stamps, files, lines, listed = [], [], [], {}
    rows = data_lines(csv_path, "one line 'timestamp [ns],filename' per image")
    _check_row_count(csv_path, len(rows))
    for n, line in rows:
        if n == 1 and line[0].isalpha():  # a header without '#'
            continue
        stamp, name = _image_row(csv_path, n, line)
        if listed.setdefault(name, n) != n:  # two frames of one image: the pairs would mix frames
            raise AslError(f"{csv_path}, line {n}: {cut(name)} listed again (line {listed[name]})")
        stamps.append(stamp)
        files.append(camera_dir / "data" / name)
        lines.append(n)
    if not stamps:
        raise AslError(f"{csv_path}: no images listed")
    _check_increasing(csv_path, stamps, lines)
    return np.array(stamps, dtype=np.int64), files, lines


def _check_row_count(csv_path: Path, rows: int) -> None:
    """More rows than files in ``data/`` (and a header), refused before each row is checked (where
    ``data/`` holds folders, the rows may name files in them)."""
    with contextlib.suppress(OSError):
        entries = list(os.scandir(csv_path.parent / "data"))
        if rows > (files := len(entries)) + 1 and not any(entry.is_dir() for entry in entries):
            raise AslError(f"{csv_path}: {rows} rows for {files} files in data/; expected one per image")


def _check_increasing(csv_path: Path, stamps: list[int], lines: list[int]) -> None:
    """One line naming the first timestamp of ``data.csv`` that does not come after the one before."""
    if np.any(np.diff(stamps) <= 0):
        k = int(np.flatnonzero(np.diff(stamps) <= 0)[0]) + 1
        raise AslError(
            f"{csv_path}, line {lines[k]}: timestamp {stamps[k]} does not come after {stamps[k - 1]} "
            f"(line {lines[k - 1]}); expected increasing timestamps"
        )


def pair_by_timestamp(mav0: Path) -> tuple[np.ndarray, list[Path], list[Path]]:
    """Left and right images of equal timestamps; a timestamp on one side only is an error."""
    (t0, left, lines0), (t1, right, lines1) = (read_image_list(mav0 / side) for side in ("cam0", "cam1"))
    only = np.setxor1d(t0, t1)
    if len(only):
        ours, theirs, lines, side = (t0, t1, lines0, "cam0") if only[0] in t0 else (t1, t0, lines1, "cam1")
        nearest = theirs[np.argmin(np.abs(theirs.astype(float) - float(only[0])))]
        offset_us = (int(nearest) - int(only[0])) / 1e3
        raise AslError(
            f"{mav0 / side / 'data.csv'}, line {lines[int(np.searchsorted(ours, only[0]))]}: timestamp "
            f"{int(only[0])} has no image of the same timestamp on the other camera (the nearest is "
            f"{abs(offset_us):g} microsecond{'s' * (abs(offset_us) != 1)} "
            f"{'later' if offset_us > 0 else 'earlier'}; {len(only)} unpaired); the two cameras must be "
            "triggered together, with equal timestamps"
        )
    for side, files, lines in (("cam0", left, lines0), ("cam1", right, lines1)):
        _check_images_there(mav0 / side / "data.csv", files, lines)
    return t0, left, right


def _check_images_there(csv_path: Path, files: list[Path], lines: list[int]) -> None:
    """One line naming the first image that ``data.csv`` lists and is not a file."""
    for path, line in zip(files, lines, strict=True):
        if not path.is_file():  # one stat per image; a second only for the one that fails
            if path.exists():  # a folder, a pipe, a device
                what = "a folder" if path.is_dir() else "not a regular file"
                raise AslError(f"{csv_path}, line {line}: {path} is {what}; expected an image")
            raise AslError(
                f"{csv_path}, line {line}: {path.name} is missing from {path.parent} "
                f"(data.csv names each image by its path inside {csv_path.parent / 'data'})"
            )


def _cameras(path) -> tuple[Path, list]:
    """The ``mav0`` folder of the recording at ``path`` and its two cameras' calibrations."""
    mav0 = mav0_of(path)
    if mav0 is None:
        raise AslError(f"{path}: no mav0/cam0 or cam0 folder; expected the ASL layout")
    for side in ("cam0", "cam1"):
        if not (mav0 / side).is_dir():
            raise AslError(f"{mav0 / side}: missing camera folder (data/, data.csv, sensor.yaml)")
    return mav0, [read_camera_yaml(mav0 / side / "sensor.yaml") for side in ("cam0", "cam1")]


def body_to_rectified_camera(path) -> np.ndarray:
    """``T_body_rect``: the rectified left camera of the ASL recording at ``path`` in its body frame."""
    mav0, calib = _cameras(path)
    return rectify(*calib, mav0).T_body_rect


def tracked_to_camera(truth_path, T_body_rect, tracker_of=None) -> np.ndarray:
    """``X``, the rectified left camera in the frame a ground-truth file tracks (the body, or the
    prism of the ``sensor.yaml`` beside it, else of ``tracker_of``'s ``leica0``): ``W_k X`` is the
    camera's pose, ``X^-1``'s translation the tracked point in the camera (a lever arm)."""
    truth_path = Path(truth_path)
    if tracker_of is not None and not (truth_path.parent / "sensor.yaml").is_file():
        sensor = mav0_of(tracker_of) / "leica0" / "sensor.yaml"
        if sensor.is_file():  # said, since the positions' file does not name it
            notice(f"{truth_path}: positions of the prism of {sensor} (its T_BS is the lever arm)")
            truth_path = sensor.parent / truth_path.name
    return np.linalg.inv(truth_extrinsic(truth_path)) @ T_body_rect


def read_asl(path, groundtruth=None, frames: int | None = None, truth: bool = True) -> Sequence:
    """The first ``frames`` pairs of an ASL recording, rectified; the 6-DoF truth (``groundtruth`` or
    the first of :data:`GROUND_TRUTH_FILES`) in ``poses`` (the rectified left camera in its first
    pose), or position-only truth in ``manifest["positions"]``; with ``truth=False``, only a
    ``groundtruth`` named here is read."""
    root = Path(path)
    mav0, calib = _cameras(root)
    others = sorted(p.name for p in mav0.glob("cam*") if p.is_dir() and p.name not in ("cam0", "cam1"))
    if others:  # a rig of more cameras
        notice(f"{mav0}: {', '.join(others)} not read; the stereo pair is cam0 (left) and cam1 (right)")
    stamps, left, right = (x[:frames] for x in pair_by_timestamp(mav0))
    width, height = check_headers(left, right)  # every image, before the run: none fails late
    if (width, height) != calib[0].resolution:
        raise AslError(
            f"{left[0]}: {width}x{height} image but {mav0 / 'cam0' / 'sensor.yaml'} says resolution "
            f"{calib[0].resolution[0]}x{calib[0].resolution[1]}"
        )
    rect = rectify(*calib, mav0)  # once the images are known to be of the calibrated size
    seconds = stamps * NANOSECONDS
    check_frame_spacing(mav0 / "cam0" / "data.csv", seconds)
    manifest = {
        "layout": "asl",
        "time_origin_s": float(seconds[0]),
        "T_body_camera": rect.T_body_rect.tolist(),
    }
    # a truth there in any form (a folder, a broken link, its folder a file) is named by the reader
    stated = [mav0 / name for name in GROUND_TRUTH_FILES]
    found = (p for p in stated if p.exists() or p.is_symlink() or p.parent.is_file())
    truth_path = Path(groundtruth) if groundtruth else (next(found, None) if truth else None)
    _unread_truth(mav0, looked=truth_path is None and truth)
    poses = None
    # as evaluate: errors of two poses mean nothing (and a single pair is refused by its reader)
    if truth_path is not None and len(seconds) == 2:
        notice(f"{truth_path}: not read for 2 frames; an evaluation needs at least 3")
    elif truth_path is not None and len(seconds) > 2:
        poses = _truth_into_camera(truth_path, seconds, rect.T_body_rect, manifest)
    since_first = (stamps - stamps[0]) * NANOSECONDS  # from whole nanoseconds: exact to 1 ns
    return Sequence(root, rect.camera, since_first, left, right, poses, None, manifest, rect, truth_path)


def _unread_truth(mav0: Path, looked: bool) -> None:
    """Where a truth was ``looked`` for and none found: a notice for the files of a ground truth's
    folder, none of :data:`GROUND_TRUTH_FILES`."""
    if not looked:
        return
    for folder in dict.fromkeys(name.split("/")[0] for name in GROUND_TRUTH_FILES):
        if files := sorted(p.name for p in (mav0 / folder).glob("*") if p.name != "sensor.yaml"):
            expected = " or ".join(n.split("/")[1] for n in GROUND_TRUTH_FILES if n.startswith(folder + "/"))
            notice(
                f"{mav0 / folder}: {', '.join(files)} not read as ground truth; expected {expected} "
                "(evaluate --gt FILE --extrinsic-of RECORDING reads any name)"
            )


def _truth_into_camera(truth_path: Path, seconds, T_body_rect, manifest: dict):
    """The 6-DoF truth at the images, in the rectified left camera; or None, positions and lever arm
    put into ``manifest``."""
    truth = read_groundtruth(truth_path)
    i_img, i_gt = covering(truth, seconds)
    if said := paired_apart(truth, seconds[i_img] - truth.times[i_gt]):
        notice(said)
    X = tracked_to_camera(truth_path, T_body_rect)
    if truth.poses is not None:
        return to_camera(truth.poses[i_gt], X)
    lever = np.linalg.inv(X)[:, 3]  # the prism in the rectified camera
    manifest["positions"] = {
        "file": str(truth_path),
        "frames": i_img.tolist(),
        "xyz": truth.positions[i_gt].tolist(),
        "lever_arm_camera": lever[:3].tolist(),
    }
    return None
