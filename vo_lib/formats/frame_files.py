"""The text files of a sequence folder: ``calib.txt``, ``times.txt``, ``poses.txt``,
``odometry.txt`` (one line per frame) and ``manifest.json``. Every problem raises one
:class:`SequenceError` naming the file (and line) and what was expected.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from vo_lib.formats.groundtruth import read_trajectory
from vo_lib.formats.poses import TrajectoryError, data_lines, read_text, rigid_problem

SequenceError = TrajectoryError


#: Farthest apart two sensors of one vehicle may be (metres): beyond, a file in millimetres.
MAX_RIG_M = 10.0
#: Focal lengths accepted, in image widths (horizontal fields of view of 169 down to 0.57 degrees),
#: and the largest ratio of the two (pixels twice as tall as wide, or as wide as tall).
MIN_FOCAL_WIDTHS, MAX_FOCAL_WIDTHS, MAX_FOCAL_RATIO = 0.05, 100, 2.0
#: Shortest distance between a stereo rig's cameras (metres).
MIN_BASELINE_M = 1e-3
#: Bytes a line of a per-frame file may take on average (a KITTI pose line about 200, an OXTS packet 300).
MAX_LINE_BYTES = 1024


def beyond(value: float, bound: float, digits: int = 4) -> str:
    """``value`` in the fewest significant digits, from ``digits``, that tell it from ``bound``."""
    return next(t for d in range(digits, 18) if float(t := f"{value:.{d}g}") != bound or d == 17)


def check_metres(path: Path, claim: str, value: float, most: float = MAX_RIG_M, unit: str = "") -> None:
    """Refuse a ``value`` beyond ``most``: a file not in metres (``claim``'s ``{}`` is the value)."""
    if value > most:
        claim = claim.format(beyond(value, most))
        raise SequenceError(f"{path}: {claim}; expected metres, at most {most:g}{unit} (millimetres?)")


def focal_problem(fx: float, fy: float, width: float) -> str:
    """What makes focal lengths ``fx``, ``fy`` (pixels) no camera's for images ``width`` wide, or ''."""
    low, high = min(fx, fy), max(fx, fy)
    if MIN_FOCAL_WIDTHS * width <= low and high <= MAX_FOCAL_WIDTHS * width and high <= MAX_FOCAL_RATIO * low:
        return ""
    return (
        f"focal lengths fx={fx:g}, fy={fy:g} px; expected pixels of these {width:g} px wide images: "
        f"{MIN_FOCAL_WIDTHS:g} to {MAX_FOCAL_WIDTHS:g} image widths, fy/fx from 0.5 to 2"
    )


def numbers(path: Path, line_no: int, text: str, count: int, what: str) -> np.ndarray:
    parts = text.split()
    if len(parts) != count:
        plural = "s" if count != 1 else ""
        raise SequenceError(f"{path}, line {line_no}: {what} needs {count} number{plural}, got {len(parts)}")
    if odd := next((p for p in parts if "_" in p or not p.isascii()), None):  # Python's float reads them
        raise SequenceError(f"{path}, line {line_no}: {what} holds {odd!r}; expected plain numbers (0-9 . e)")
    try:
        values = np.array([float(p) for p in parts])
    except ValueError as exc:
        raise SequenceError(f"{path}, line {line_no}: {what} holds a non-number ({exc})") from None
    if not np.all(np.isfinite(values)):
        raise SequenceError(f"{path}, line {line_no}: {what} holds a NaN or infinite value")
    return values


def calib_values(path: Path, key: str, count: int, missing: str = "") -> np.ndarray:
    """The ``count`` numbers of the one line ``key: ...`` of a calibration file; else one line
    (``missing`` says what the key holds)."""
    found = [(n, line) for n, line in data_lines(path, f"a line '{key}:'") if line.startswith(key + ":")]
    if not found:
        raise SequenceError(
            f"{path}: no {key} line ({missing})" if missing else f"{path}: no line starting with '{key}:'"
        )
    (line_no, line), *others = found
    if others:
        raise SequenceError(f"{path}, line {others[0][0]}: a second {key} line (the first is line {line_no})")
    return numbers(path, line_no, line.split(":", 1)[1], count, key)


def read_calib(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """``(P0, P1)`` 3x4 matrices from a KITTI ``calib.txt``; raises :class:`SequenceError`."""
    return tuple(
        calib_values(path, key, 12, f"{side} camera projection, 12 numbers").reshape(3, 4)
        for key, side in (("P0", "left"), ("P1", "right"))
    )


def read_times(path: Path) -> np.ndarray:
    """Timestamps in seconds, one a line, strictly increasing; raises :class:`SequenceError`."""
    return read_rows(path, 1, "a timestamp", increasing=True)[:, 0]


def read_rows(path: Path, count: int, what: str, bound: float = np.inf, increasing=False) -> np.ndarray:
    """``(N, count)`` finite numbers within ``±bound``, one row a line (with ``increasing``, times
    first, each after the one before); raises :class:`SequenceError`."""
    rows = []
    for n, text in data_lines(path):
        rows.append(row := numbers(path, n, text, count, what))
        if np.abs(row).max(initial=0.0) > bound:
            raise SequenceError(f"{path}, line {n}: a number beyond ±{bound:g}; expected {what}")
        if increasing and len(rows) > 1 and not row[0] > (before := rows[-2][0]):
            raise SequenceError(f"{path}, line {n}: time {row[0]} is not after {before} on the line before")
    return np.array(rows).reshape(-1, count)


def read_poses(path: Path) -> np.ndarray:
    """``(N, 3, 4)`` poses of a KITTI ``poses.txt``; raises :class:`SequenceError`."""
    times, poses = read_trajectory(path)
    if times is not None:
        raise SequenceError(f"{path}: TUM rows (8 numbers); a sequence's poses.txt holds KITTI rows of 12")
    return poses[:, :3, :]


def read_manifest(path: Path) -> dict:
    """The JSON object of a ``manifest.json``; raises :class:`SequenceError`."""
    text = read_text(path)  # outside the try: its own errors (not UTF-8, too large) say what they are
    try:
        manifest = json.loads(text)
    except (ValueError, RecursionError) as exc:  # JSON's errors, a number too long, nesting too deep
        bad = isinstance(exc, json.JSONDecodeError)
        deep = "nested too deep" if isinstance(exc, RecursionError) else "a number too long"
        why = f"{exc.msg} at line {exc.lineno}, column {exc.colno}" if bad else deep
        raise SequenceError(f"{path}: not valid JSON ({why})") from None
    if not isinstance(manifest, dict):
        raise SequenceError(f"{path}: expected a JSON object {{...}}, got a {type(manifest).__name__}")
    return manifest


def shown(value, width: int = 40) -> str:
    """``value`` as JSON for an error message, cut to ``width`` characters (with a count of values)."""
    text = json.dumps(value, default=str)
    if len(text) <= width:
        return text
    if not isinstance(value, (list, tuple, dict)):
        return f"{text[:width]}..."
    count, items = 0, [value]  # every value of the nested lists and maps: NaN and texts too
    while items:
        item = items.pop()
        if isinstance(item, (list, tuple, dict)):
            items.extend(item.values() if isinstance(item, dict) else item)
        else:
            count += 1
    return f"{count} values, {text[:width]}..."


def _plain_numbers(value) -> bool:
    """Whether every value of the nested lists ``value`` is a number as the file wrote it: not
    ``true`` (a bool is an int in Python) and not a text such as ``"458.6"`` (numpy would read it)."""
    if isinstance(value, (list, tuple)):
        return all(map(_plain_numbers, value))
    return isinstance(value, (int, float, np.number, np.ndarray)) and not isinstance(value, (bool, np.bool_))


def numbers_at(path: Path, key: str, value, shape: tuple, what=None, bounds=(-np.inf, np.inf)) -> np.ndarray:
    """``value`` at ``key`` of ``path`` as finite numbers of ``shape`` within ``bounds`` (``what``
    they are, by default a number within them); else one :class:`SequenceError`."""
    what = what or f"a number from {bounds[0]:g} to {bounds[1]:g}"
    if value is None:
        raise SequenceError(f"{path}: key {key} missing; expected {what}")
    try:
        a = np.array(value, dtype=float)
    except (TypeError, ValueError, OverflowError):  # OverflowError: an integer of hundreds of digits
        a = np.array([])
    within = np.all(np.isfinite(a) & (bounds[0] <= a) & (a <= bounds[1]))
    if a.shape != shape or not within or not _plain_numbers(value):  # of a known shape: a shallow walk
        raise SequenceError(f"{path}: key {key}: expected {what}, got {_first_bad(value, shape, bounds)}")
    return a


def _first_bad(value, shape: tuple, bounds) -> str:
    """``value`` as :func:`shown` gives it; for a flat list of the expected length, its first entry
    that is not a number within ``bounds``, by its place (a long list is cut before it)."""
    if not isinstance(value, list) or len(shape) != 1 or len(value) != shape[0]:
        return shown(value)
    for k, x in enumerate(value, 1):
        if isinstance(x, (list, tuple)) or not (
            _plain_numbers(x) and np.isfinite(x) and bounds[0] <= x <= bounds[1]
        ):
            return f"entry {k} of {len(value)}: {shown(x)}"
    return shown(value)


#: The camera mounts a manifest may state (a crawler's, planar; a car's); any other is refused.
CAMERA_MOUNTS = ("above turning axis", "car: ahead of the rear axle (vo_lib.sim.road)")


#: The keys a manifest may hold, at its top and in its objects: what ``generate`` and ``convert``
#: write. A key outside them (``camera.heigth_m``) is refused: read as absent, it would change the run.
MANIFEST_KEYS = {
    "": {
        *("sample", "fingerprint", "purpose", "mirrors", "world", "frames", "frames_full", "rate_hz"),
        *("resolution", "legs", "start_pose", "camera", "track_odometry", "slip", "surface"),
        *("sensor_noise_grey", "exposure_sigma", "seed", "robot_poses"),
        *("time_origin_s", "T_body_camera", "positions"),
    },
    "camera.": {"fx", "fy", "cx", "cy", "baseline", "height_m", "forward_m", "in_vehicle_m", "mount"},
    "positions.": {"file", "frames", "xyz", "lever_arm_camera"},
    "track_odometry.": {"track_distance", "track_width", "encoder_sigma"},
}
#: Bounds of what a run reads from a manifest (beyond, a figure would overflow): metres (a position-only
#: truth may be in a map's UTM coordinates, up to 10,000 km), track odometry's metres and noise per root m.
MAX_MOUNT_M, MAX_POSITION_M = 1e3, 1e8
TRACK_BOUNDS = {"track_distance": (0.0, 1e3), "track_width": (0.0, 1e3), "encoder_sigma": (0.0, 1.0)}


def check_manifest(path: Path, manifest: dict, frames: int) -> None:
    """Raise :class:`SequenceError` unless ``manifest.json`` holds only :data:`MANIFEST_KEYS` and its
    (optional) keys that a run reads hold numbers of the shape and range below, ``T_body_camera`` a
    rigid transform."""
    camera, positions, track = (manifest.get(key, {}) for key in ("camera", "positions", "track_odometry"))
    objects = {"camera": camera, "positions": positions, "track_odometry": track}
    if bad := [key for key, value in objects.items() if not isinstance(value, dict)]:
        raise SequenceError(f"{path}: key {bad[0]}: expected an object {{...}}, got {shown(objects[bad[0]])}")
    prefixed = {"": manifest, **{f"{key}.": value for key, value in objects.items()}}
    if unknown := [(p, key) for p, keys in prefixed.items() for key in sorted(set(keys) - MANIFEST_KEYS[p])]:
        prefix, key = unknown[0]
        known = ", ".join(prefix + name for name in sorted(MANIFEST_KEYS[prefix]))
        raise SequenceError(f"{path}: key {prefix}{key} is not a manifest's; expected some of {known}")
    index = positions.get("frames")
    n = len(index) if isinstance(index, list) else -1
    mount, near, last = (-MAX_MOUNT_M, MAX_MOUNT_M), f"within ±{MAX_MOUNT_M:g} m", frames - 1
    body = manifest.get("T_body_camera", np.eye(4))
    xyz, lever = positions.get("xyz"), positions.get("lever_arm_camera")
    wanted = [  # key, value, shape, what (None: a number within the bounds), bounds
        # seconds: to the year 2286, so that a run's TUM times stay within what evaluate reads (1e11)
        ("time_origin_s", manifest.get("time_origin_s", 0), (), None, (-1e10, 1e10)),
        ("camera.height_m", camera.get("height_m", 0), (), None, (0.0, 10.0)),  # metres
        ("camera.forward_m", camera.get("forward_m", 0), (), None, (-10.0, 10.0)),
        ("T_body_camera", body, (4, 4), f"4 rows of 4 numbers {near}", mount),
    ]
    wanted += [(f"track_odometry.{key}", track[key], (), None, TRACK_BOUNDS[key]) for key in sorted(track)]
    if positions:  # the position-only truth of frames 0 .. frames - 1
        far = f"within ±{MAX_POSITION_M:g} m"
        wanted += [
            ("positions.frames", index, (max(n, 3),), f"3 or more frame numbers 0 to {last}", (0, last)),
            ("positions.xyz", xyz, (n, 3), f"{n} rows of x y z {far}", (-MAX_POSITION_M, MAX_POSITION_M)),
            ("positions.lever_arm_camera", lever, (3,), f"3 numbers {near}", mount),
        ]
    _check_values(path, positions, {row[0]: numbers_at(path, *row) for row in wanted}, frames)


def _check_values(path: Path, positions: dict, found: dict, frames: int) -> None:
    """What :func:`check_manifest` checks beyond shapes and bounds."""
    numbered = found.get("positions.frames", np.zeros(0))
    if np.any(numbered % 1) or np.any(np.diff(numbered) <= 0):
        raise SequenceError(
            f"{path}: key positions.frames: expected increasing frame numbers 0 to {frames - 1}"
        )
    if not isinstance(positions.get("file", ""), str):
        raise SequenceError(f"{path}: key positions.file: expected a text, got {shown(positions['file'])}")
    if problem := rigid_problem(found["T_body_camera"]):
        raise SequenceError(f"{path}: key T_body_camera: {problem}; expected a rigid transform")


def read_per_frame(path: Path, frames: int, noun: str, read) -> np.ndarray:
    """``read(path)`` of a file of one line per frame, its size checked before and its length after;
    ``noun`` names the rows ("timestamps", "poses")."""
    size, limit = Path(path).stat().st_size, MAX_LINE_BYTES * frames + 65536
    if size > limit:
        raise SequenceError(
            f"{path}: {size:,} bytes, far more than {frames} lines of {noun} take (at most {limit:,}); "
            "expected one line per frame"
        )
    rows = read(path)
    if len(rows) != frames:
        raise SequenceError(f"{path} has {len(rows)} {noun} but there are {frames} images")
    return rows
