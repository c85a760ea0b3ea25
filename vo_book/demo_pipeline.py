"""Tables and runs of notebook 08 (full pipeline), kept out of its story cells.

The stored full-length runs of the paper's sets beside the paper's own figures: RMS of the
key-position errors, the table of AVG / S.D. / RMS, and which RMS lie above or below the paper's;
the samples rendered in memory and run through the pipeline. The figures are :mod:`vo_book.nb08`.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence

import numpy as np

from vo_lib.geometry import relative_planar, wrap_angle
from vo_lib.models.track_odometry import TrackOdometry
from vo_lib.sim.samples import SAMPLES, render_sample
from vo_lib.stereo_vo import paper_sets
from vo_lib.stereo_vo.pipeline import run_frames


def heading_error(poses: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """Heading error of each planar pose against ``truth``, degrees in (-180, 180]."""
    return np.degrees(wrap_angle(poses[:, 2] - truth[:, 2]))


def rms(values: Sequence[float]) -> float:
    """Root mean square of the key-position errors from their AVG and S.D.: √(AVG² + S.D.²).
    Signed errors of opposite signs cancel in an average; they do not in an RMS."""
    return math.hypot(values[0], values[1])


def rms_of(stored: dict, name: str, quantity: str, source: str = "fused") -> float:
    """RMS of a stored set (source 'fused' or 'odometry') or of the paper's figures ('paper')."""
    values = paper_sets.PAPER[name].get(quantity) if source == "paper" else stored[name][source][quantity]
    return math.nan if values is None else rms(values)


def stored_table(stored: dict, names: Iterable[str], quantities: Sequence[str]) -> None:
    """Print ours (fused), track odometry's and the paper's AVG / S.D. and RMS of each set."""
    heads = "".join(f"{q + ' AVG / S.D. / RMS':>30s}" for q in quantities)
    print(f" {'set':15s}{'frames':>7s}{'flagged':>8s}  {'':10s}" + heads)
    for name in names:
        row, ref = stored[name], paper_sets.PAPER[name]
        for label, values in (("ours", row["fused"]), ("odometry", row["odometry"]), ("paper", ref)):
            head = f" {name:15s}{row['frames']:7d}{row['flagged']:8d}" if label == "ours" else " " * 31
            cells = "".join(
                f"{values[q][0]:11.2f} /{values[q][1]:7.2f} /{rms(values[q]):8.2f}"
                if q in values
                else f"{'—':>30s}"
                for q in quantities
            )
            print(f"{head}  {label:10s}{cells}")


def sides(names: Iterable[str], ratio: dict, quantities: Sequence[str]) -> str:
    """Which RMS of each set lie above and below the paper's (``ratio`` ours / paper), in words."""
    words = []
    for name in names:
        above = [q for q in quantities if ratio.get((name, q), 0) > 1]
        below = [q for q in quantities if 0 < ratio.get((name, q), 2) < 1]
        words.append(f"`{name}` above in {', '.join(above) or 'none'}, below in {', '.join(below) or 'none'}")
    return "; ".join(words)


def frames_for(name: str, quick: int, full: bool) -> int:
    """The frames of a sample the notebook runs: all of them in a full run, else ``quick``."""
    return SAMPLES[name].frames if full else quick


#: The notebook's base seed: the pipeline's RANSAC draws from it unless another is given.
SEED = 8


def run(
    name: str,
    frames: int,
    use_odometry: bool = True,
    resolution: tuple[int, int] = (640, 480),
    seed: int = SEED,
):
    """Render a sample in memory and run the pipeline (RANSAC drawing from ``seed``; the sample's
    images and drive are its own); returns (result, truth from the start, odometry)."""
    rendered, frame_iter = render_sample(name, frames, resolution)
    if not use_odometry:
        frame_iter = ((left, right, None) for left, right, _ in frame_iter)
    result = run_frames(frame_iter, rendered.camera, seed=seed)
    truth = relative_planar(rendered.truth()[0], rendered.truth())
    odometry = TrackOdometry().integrate(rendered.drive.odometry[1:frames])
    return result, truth, odometry
