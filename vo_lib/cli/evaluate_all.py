"""``python -m vo_lib evaluate-all ROOT``: the stereo pipeline on every sequence under a folder.

Sequences are found as KITTI lays them out (``ROOT/sequences/NN``), or as any folder under ROOT
(ROOT itself included) holding ``image_0/``. Each sequence is one sweep task
(:mod:`vo_lib.cli.sweep`: in this process or on Dask, finished sequences kept and skipped on a
re-run); each runs the pipeline without odometry (``run_sequence(seq, use_odometry=False)``) and
is scored against its ``poses.txt``. A sequence is read under a shared lock (``generate`` does not
replace it meanwhile), and its files' names, sizes and times are taken before and after the run:
a sequence changed by anything else while it was read fails with :class:`SequenceChanged` (no
figure of mixed data), and one changed since an earlier sweep is run again (the snapshot is one of
the task's parameters) with KITTI's segment errors: translation in per cent of the
segment length, rotation in degrees per 100 m, averaged over every segment of KITTI's lengths
(100, 200, ..., 800 m). A sequence whose path is shorter than :data:`SHORT_PATH` metres has few or
no such segments: it is scored on :data:`SHORT_LENGTHS` instead, and the table says so. The
overall row averages every segment of every sequence, as KITTI's benchmark does.
"""

from __future__ import annotations

import hashlib
import math
import os
from pathlib import Path

import numpy as np

from vo_lib.cli.sweep import Experiment, SweepError, print_aggregate, run_sweep

KITTI_LENGTHS = (100, 200, 300, 400, 500, 600, 700, 800)
#: Lengths for a sequence whose path is shorter than SHORT_PATH metres.
SHORT_LENGTHS = (25, 50, 100)
SHORT_PATH = 400.0
#: How deep below ROOT sequences are looked for.
MAX_DEPTH = 4


def find_sequences(root) -> list[Path]:
    """Sequence folders under ``root`` (folders holding ``image_0/``), in name order; KITTI's
    ``sequences/NN`` among them. Hidden folders and folders inside a sequence are not searched."""
    root = Path(root)
    if not root.is_dir():
        what = "a file, not a folder" if root.exists() else "folder not found"
        raise SweepError(f"{root}: {what}")
    found = []
    for here, dirs, _ in os.walk(root):
        depth = len(Path(here).relative_to(root).parts)
        if "image_0" in dirs:
            found.append(Path(here))
            dirs[:] = []
            continue
        dirs[:] = sorted(d for d in dirs if not d.startswith(".")) if depth < MAX_DEPTH else []
    return sorted(found, key=lambda p: p.relative_to(root).parts)


class SequenceChanged(RuntimeError):
    """A sequence's files changed while the pipeline read them."""


def snapshot(path) -> str:
    """A digest of the folder ``path`` and of every file in it and in its subfolders (name, size,
    modification time): a replaced folder or an added, removed or edited file changes it."""
    path = Path(path).resolve()
    folders = [path, *(Path(e.path) for e in os.scandir(path) if e.is_dir())]
    files = sorted(
        (f.name, e.name, e.stat().st_size, e.stat().st_mtime_ns) for f in folders for e in os.scandir(f)
    )
    return hashlib.sha1(repr((os.stat(path).st_ino, files)).encode(errors="surrogateescape")).hexdigest()[:16]


def segment_figures(gt, est) -> dict:
    """Per-sequence KITTI errors: ``t_pct`` (translation %), ``r_deg_100m`` (rotation deg/100 m),
    ``segments`` (how many), ``lengths`` ("kitti" or "short"), path length."""
    from vo_lib.evaluation import kitti_segment_errors, path_lengths

    length = float(path_lengths(gt)[-1])
    kind, lengths = ("kitti", KITTI_LENGTHS) if length >= SHORT_PATH else ("short", SHORT_LENGTHS)
    seg = kitti_segment_errors(gt, est, lengths)
    n = sum(c for _, _, c in seg.values())
    t = sum(t * c for t, _, c in seg.values()) / n if n else math.nan
    r = sum(r * c for _, r, c in seg.values()) / n if n else math.nan
    return {"path_m": length, "lengths": kind, "segments": n, "t_pct": t, "r_deg_100m": 100.0 * r}


def sequence_task(params: dict, context=None) -> dict:
    """Run the pipeline on one sequence and score it against its ground truth; the sequence must
    be as ``params["snapshot"]`` found it, from the start of the run to its end."""
    from vo_lib.outputs import reading

    with reading(params["path"]):
        _unchanged(params, "before")
        figures = _score(params)
        _unchanged(params, "while")
    return figures


def _unchanged(params: dict, when: str) -> None:
    if snapshot(params["path"]) != params["snapshot"]:
        raise SequenceChanged(
            f"{params['path']}: its files changed {when} it was read; run evaluate-all again"
        )


def _score(params: dict) -> dict:
    """The pipeline on the sequence ``params["path"]``, scored with KITTI's segment errors."""
    from vo_lib.formats.sequence import read_sequence
    from vo_lib.geometry import camera_poses_from_planar
    from vo_lib.stereo_vo.pipeline import run_sequence
    from vo_lib.stereo_vo.vehicle import vehicle_of

    seq = read_sequence(params["path"], odometry=False)
    if seq.poses is None:
        raise ValueError(f"{seq.path}: no poses.txt, nothing to score against")
    n = len(seq) if params.get("frames") is None else min(int(params["frames"]), len(seq))
    result = run_sequence(seq, frames=n, use_odometry=False, seed=int(params.get("seed", 0)))
    if result.camera_poses is not None:
        est = result.camera_poses
    else:
        est = camera_poses_from_planar(result.poses, vehicle_of(seq, use_odometry=False).mount)
    gt = seq.poses_4x4()[:n]
    return {"frames": n, **segment_figures(gt, est), "flagged": len(result.flagged)}


EVALUATE_ALL = Experiment("evaluate-all", sequence_task, None, "stereo VO on every sequence")


def overall(rows: list[dict]) -> tuple[float, float, int]:
    """Translation % and rotation deg/100 m over every segment of every scored sequence."""
    ok = [r["figures"] for r in rows if not r.get("error") and r["figures"].get("segments")]
    n = sum(f["segments"] for f in ok)
    if not n:
        return math.nan, math.nan, 0
    t = sum(f["t_pct"] * f["segments"] for f in ok) / n
    r = sum(f["r_deg_100m"] * f["segments"] for f in ok) / n
    return t, r, n


def evaluate_all_command(root, frames=None, workers=None, scheduler=None, out=None, force=False):
    sequences = find_sequences(root)
    if not sequences:
        raise SweepError(f"{root}: no sequence folder (one holding image_0/) found")
    root = Path(root)
    name = root.resolve().name or "root"
    target = Path(out) if out else Path("sweeps") / f"evaluate-all-{name}"
    tasks = [
        {
            "sequence": str(s.relative_to(root)) if s != root else s.resolve().name,
            "path": str(s.resolve()),
            "frames": frames,
            "snapshot": snapshot(s),
        }
        for s in sequences
    ]
    result = run_sweep(EVALUATE_ALL, tasks, target, workers, scheduler, force=force, inputs=[root])
    print(f"{len(tasks)} sequence(s) under {root}" + (f" ({result.workers})" if result.workers else ""))
    print(f"wrote {result.path}")
    print(
        f"\n  {'sequence':<32s}{'frames':>7s}{'path [m]':>10s}{'trans. [%]':>12s}"
        f"{'rot. [deg/100m]':>17s}  lengths"
    )
    for row in result.rows:
        p, f = row["params"], row["figures"]
        if row.get("error"):
            print(f"  {p['sequence']:<32s} failed: {row['error']}")
            continue
        lengths = KITTI_LENGTHS if f["lengths"] == "kitti" else SHORT_LENGTHS
        which = f"{'KITTI' if f['lengths'] == 'kitti' else 'short'} {'/'.join(str(x) for x in lengths)} m"
        print(
            f"  {p['sequence']:<32s}{f['frames']:7d}{f['path_m']:10.1f}{f['t_pct']:12.3f}"
            f"{f['r_deg_100m']:17.4f}  {which} ({f['segments']} segments)"
        )
    t, r, n = overall(result.rows)
    kinds = {row["figures"].get("lengths") for row in result.rows if not row.get("error")}
    note = (
        ""
        if kinds <= {"kitti"}
        else (
            f"; sequences under {SHORT_PATH:.0f} m scored on "
            f"{'/'.join(str(x) for x in SHORT_LENGTHS)} m segments"
        )
    )
    print(f"  {'overall':<32s}{'':7s}{'':10s}{t:12.3f}{r:17.4f}  {n} segments{note}")
    if result.failed:
        print_aggregate(result)
    if np.isnan(t):
        print("  no segment could be scored")
    if result.failed:
        raise SweepError(
            f"{len(result.failed)} of {len(result.rows)} sequence(s) failed (their errors are in the "
            f"table above and in {result.path})"
        )
