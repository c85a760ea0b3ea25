"""Sample sequences on demand: generated into ``data/`` on first use, reused afterwards.

``load_sequence("indoor_linear")`` renders the named sample once (deterministically) into the data
folder and loads it; ``load_sequence("/path/to/kitti/00")`` loads any folder in the KITTI layout,
and a folder in EuRoC's ASL layout (holding ``mav0``) is undistorted and rectified on reading.
The data folder is ``$VO_LIB_DATA`` if set, else the repository's ``data/`` (in a checkout), else
``vo_lib/data`` in the user's cache folder (an installed package). A sample is written there
under the rules of :mod:`vo_lib.outputs`: a folder of that name that this package did not
write is never replaced.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from vo_lib.formats.euroc import mav0_of, read_asl
from vo_lib.formats.sequence import Sequence, read_sequence
from vo_lib.sim.samples import SAMPLES, fingerprint, generate


def data_dir() -> Path:
    env = os.environ.get("VO_LIB_DATA")
    if env:
        return Path(env)
    checkout = Path(__file__).resolve().parents[1] / "data"
    if checkout.is_dir():
        return checkout
    cache = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(cache) / "vo_lib" / "data"


def real_sequence_path(name: str) -> Path | None:
    """The folder ``name`` under ``$VO_LIB_REALDATA`` (real recordings, kept out of the repository),
    or None when the variable is unset or the folder is not there."""
    root = os.environ.get("VO_LIB_REALDATA", "")
    return Path(root) / name if root and (Path(root) / name).is_dir() else None


def sample_path(name: str, frames: int | None = None, resolution=None) -> Path:
    """Folder of a generated sample: the full sample at its own size keeps its plain name."""
    full = frames is None or frames == SAMPLES[name].frames
    tag = name if full else f"{name}_{frames}f"
    if resolution is not None and tuple(resolution) != SAMPLES[name].resolution:
        tag += f"_{resolution[0]}x{resolution[1]}"
    return data_dir() / tag


def is_rendered(name: str, path) -> bool:
    """Whether sample ``name`` is rendered in ``path`` with the sample's current fingerprint."""
    try:
        manifest = json.loads((Path(path) / "manifest.json").read_text())
    except (OSError, ValueError):
        return False
    return manifest.get("fingerprint") == fingerprint(name)


def load_sequence(
    name_or_path,
    frames: int | None = None,
    resolution=None,
    progress: bool = True,
    odometry: bool = True,
) -> Sequence:
    """Load a named sample (generating it on first use) or a KITTI-layout folder.

    ``progress`` while a sample renders: a bar (True), a line every few seconds (``"lines"``), or
    nothing (False); see :func:`vo_lib.sim.samples.generate`.

    ``frames``: a sample rendered with that many frames, or the first ``frames`` pairs of an ASL
    recording (its ground truth need cover only those); a KITTI-layout folder is read whole.

    ``odometry=False`` ignores the sequence's ``odometry.txt`` (it is not read at all).
    """
    key = str(name_or_path)
    if key in SAMPLES and not Path(key).exists():
        path = sample_path(key, frames, resolution)
        if not is_rendered(key, path):
            generate(key, path, frames, None if resolution is None else tuple(resolution), progress)
        return read_sequence(path, odometry=odometry)
    if mav0_of(key) is not None:  # a rig as it records (ASL layout): rectified on reading
        return read_asl(key, frames=frames)
    return read_sequence(Path(key), odometry=odometry)
