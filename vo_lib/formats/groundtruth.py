"""Ground truth in the formats of ``docs/real_data.md`` (KITTI poses, TUM, EuRoC CSV, positions
only): a CSV is EuRoC's (nanoseconds), a text file's times are seconds. Every problem raises one
:class:`TrajectoryError` naming the file and line.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from vo_lib.atomic import notice
from vo_lib.evaluation import MAX_TIME_DIFF_S, associate
from vo_lib.formats.poses import TrajectoryError, read_rows
from vo_lib.geometry import as_homogeneous

NANOSECONDS = 1e-9
#: Smallest median step of a CSV's timestamps (ns): no tracker samples at over 1 MHz.
MIN_STEP_NS = 1000.0
#: Latest time a text file's seconds may reach (the year 5138): beyond, they are nanoseconds.
MAX_SECONDS = 1e11
TUM_WITH_COMMAS = "; a TUM file? its numbers are separated by spaces, not commas"
#: A header field naming a quaternion component: ``qw``, ``q_w``, ``q_RS_w []``, ``qx`` ...
QUATERNION_FIELD = re.compile(r"q(?:_[a-z0-9]+)*?_?([wxyz])(?=$|[\s\[(])")


@dataclass(frozen=True)
class GroundTruth:
    """``times`` in seconds (None for KITTI poses: one per image), ``positions`` ``(N, 3)``, ``poses``
    ``(N, 4, 4)`` (None for positions only); ``csv``: EuRoC's CSV (poses of the body)."""

    path: Path
    times: np.ndarray | None
    positions: np.ndarray
    poses: np.ndarray | None = None
    csv: bool = False


def header_quaternion_order(path: Path, first_row_line: int) -> tuple[str, int]:
    """The quaternion's components as the last header line before the first row orders them
    (``"wxyz"``, ...) and that line's number; ``("", 0)`` where none names all four."""
    order, found = "", 0
    with open(path, encoding="utf-8-sig", errors="replace") as fh:
        for n, line in enumerate(fh, start=1):
            if n >= first_row_line:
                break
            fields = re.split(r"[,\s]+", line.lstrip("#% \t").strip().lower())
            names = "".join(m.group(1) for f in fields if (m := QUATERNION_FIELD.match(f)))
            if sorted(names) == list("wxyz"):
                order, found = names, n
    return order, found


def _in_nanoseconds(path: Path, a: np.ndarray, lines: list[int]) -> bool:
    """Whether a text file's times are nanoseconds: every one beyond any second (as ORB-SLAM3 writes
    EuRoC's), said in a notice; some beyond and some not are refused."""
    if np.abs(a[:, 0]).max() <= MAX_SECONDS:
        return False
    if a[:, 0].min() > MAX_SECONDS:
        notice(f"{path}: every time is beyond {MAX_SECONDS:g} s (the year 5138): read as nanoseconds")
        return True
    i = int(np.argmax(np.abs(a[:, 0]) > MAX_SECONDS))
    raise TrajectoryError(
        f"{path}, line {lines[i]}: time {a[i, 0]:.4g}; a text file's times are read as seconds "
        "(TUM's t x y z qx qy qz qw), at most 1e11, or as nanoseconds where every one is beyond"
    )


def _check_columns(path: Path, a: np.ndarray, lines: list[int], comma: bool) -> bool:
    """A CSV (EuRoC's, times in ns) or a text file (TUM's, times in s) as its header, times and
    widths say; True where the times are nanoseconds (a CSV's, or a text file's beyond any second)."""
    width = a.shape[1]
    nanoseconds = comma or (width != 12 and _in_nanoseconds(path, a, lines))
    order, line = header_quaternion_order(path, lines[0]) if width >= 8 else ("", 0)
    if order not in ("", "wxyz" if comma else "xyzw"):
        csv = "a CSV is read as EuRoC's t[ns], x, y, z, qw, qx, qy, qz" + TUM_WITH_COMMAS * (order == "xyzw")
        read_as = csv if comma else "a text file is read as TUM's t x y z qx qy qz qw"
        raise TrajectoryError(
            f"{path}, line {line}: the header orders the quaternion {' '.join(order)}; {read_as}"
        )
    step = float(np.median(np.diff(a[:, 0]))) if len(a) > 1 else np.inf
    if comma and step < MIN_STEP_NS:
        raise TrajectoryError(
            f"{path}, line {lines[1]}: the times step by {step:.3g}; a CSV's times are read as "
            "nanoseconds (EuRoC's t[ns], x, y, z[, qw, qx, qy, qz]), and no sensor samples more "
            "often than every microsecond" + (TUM_WITH_COMMAS if width == 8 else "")
        )
    if comma and 4 < width < 8:
        raise TrajectoryError(
            f"{path}, line {lines[0]}: {width} numbers; expected t[ns], x, y, z (positions) "
            "or t[ns], x, y, z, qw, qx, qy, qz (EuRoC)"
        )
    return nanoseconds


def read_groundtruth(path, min_poses: int = 2) -> GroundTruth:
    """A KITTI, TUM, EuRoC CSV or position-only ground truth of at least ``min_poses`` rows."""
    path = Path(path)
    a, lines, comma = read_rows(path, min_poses)
    nanoseconds = _check_columns(path, a, lines, comma)
    width = a.shape[1]
    if width == 12 and not comma:
        poses = as_homogeneous(a.reshape(-1, 3, 4))
        return GroundTruth(path, None, poses[:, :3, 3].copy(), poses)
    times, positions = a[:, 0] * (NANOSECONDS if nanoseconds else 1.0), a[:, 1:4]
    if width == 4:
        return GroundTruth(path, times, positions, csv=comma)
    quat_xyzw = a[:, [5, 6, 7, 4]] if comma else a[:, 4:8]  # EuRoC: qw qx qy qz
    poses = np.tile(np.eye(4), (len(positions), 1, 1))
    # normalised here, against the rounding of the file's numbers (scaled first: no overflow in the norm)
    q = quat_xyzw / np.max(np.abs(quat_xyzw), axis=1, keepdims=True)
    poses[:, :3, :3] = Rotation.from_quat(q).as_matrix()
    poses[:, :3, 3] = positions
    return GroundTruth(path, times, positions, poses, csv=comma)


def read_trajectory(path, min_poses: int = 1) -> tuple[np.ndarray | None, np.ndarray]:
    """A KITTI (12 numbers a line), TUM (8) or EuRoC CSV pose file: ``(times or None, (N, 4, 4) poses)``."""
    truth = read_groundtruth(path, min_poses)
    if truth.poses is None:
        raise TrajectoryError(
            f"{path}: positions only; expected poses, 12 numbers (KITTI) or 8 (TUM) separated by spaces, "
            "or EuRoC's CSV (t[ns], x, y, z, qw, qx, qy, qz)"
        )
    return truth.times, truth.poses


#: What to do about a recording's ground truth that does not cover its images.
UNCOVERED_HINT = (
    " (run --frames N runs only the first N images; run or convert --no-truth reads none, and "
    "evaluate --gt ... --extrinsic-of RECORDING then scores the frames it covers)"
)


def _times_of(truth: GroundTruth) -> np.ndarray:
    """The truth's times; KITTI poses, one per image of a sequence without a clock, have none."""
    if truth.times is None:
        raise TrajectoryError(
            f"{truth.path}: KITTI poses (12 numbers a row) carry no times to pair them with the images; "
            "expected TUM (t x y z qx qy qz qw), EuRoC's CSV or positions (t x y z)"
        )
    return truth.times


#: Median seconds between images and the 6-DoF truth's poses paired with them from which a note says
#: so: the body moves meanwhile (a truth slower than the cameras, or on another clock).
PAIRED_APART_S = 1e-3


def paired_apart(truth: GroundTruth, gaps) -> str:
    """What to say of a 6-DoF truth whose poses are paired with the images ``gaps`` seconds apart, a
    median of :data:`PAIRED_APART_S` or more; else ''."""
    gaps = np.abs(np.asarray(gaps, float))
    if truth.poses is None or len(gaps) == 0 or np.median(gaps) < PAIRED_APART_S:
        return ""
    return (
        f"{truth.path}: its poses are paired with the images {1e3 * np.median(gaps):.1f} ms apart at the "
        f"median (at most {1e3 * gaps.max():.1f} ms): the body moves meanwhile, and the errors (RPE most) "
        "count that motion; a truth at the images' times, or sampled faster, has none of it"
    )


def covering(truth: GroundTruth, times, max_diff: float = MAX_TIME_DIFF_S) -> tuple[np.ndarray, np.ndarray]:
    """:func:`associate` the images at ``times`` (seconds) with ``truth``, which must span them (a
    6-DoF truth: match every one)."""
    truth_times, times = _times_of(truth), np.asarray(times, float)
    if len(times) < 3:  # --frames 2: the truth is fine, the images too few
        raise TrajectoryError(
            f"{truth.path}: {len(times)} images to compare with it; an evaluation needs at least 3 "
            "(run --frames 3 or more)"
        )
    t0, t1 = truth_times[0], truth_times[-1]
    if times[0] < t0 - max_diff or times[-1] > t1 + max_diff:
        raise TrajectoryError(
            f"{truth.path}: covers {t0:.3f} to {t1:.3f} s but the images span {times[0]:.3f} to "
            f"{times[-1]:.3f} s; the ground truth must cover every image{UNCOVERED_HINT}"
        )
    i_img, i_gt = associate(times, truth_times, max_diff)
    if truth.poses is not None and len(i_img) < len(times):
        missing = int(np.setdiff1d(np.arange(len(times)), i_img)[0])
        raise TrajectoryError(
            f"{truth.path}: no pose within {max_diff} s of image {missing} (t = {times[missing]:.3f} s); "
            f"the ground truth must cover every image{UNCOVERED_HINT}"
        )
    if len(i_img) < 3:
        raise TrajectoryError(
            f"{truth.path}: only {len(i_img)} positions within {max_diff} s of an image; need at least 3"
        )
    return i_img, i_gt
