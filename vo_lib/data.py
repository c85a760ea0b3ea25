"""Sample sequences on demand: ``load_sequence(NAME)`` renders a named sample once into the data
folder (under the rules of :mod:`vo_lib.outputs`) and loads it; ``load_sequence(PATH)`` reads a
KITTI-layout folder or an ASL recording.
"""

from __future__ import annotations

import os
from pathlib import Path

from vo_lib.arguments import UsageError
from vo_lib.formats.euroc import AslError, asl_near_miss, mav0_of, read_asl
from vo_lib.formats.kitti_raw import raw_drive_of, raw_near_miss, read_kitti_raw
from vo_lib.formats.sequence import Sequence, read_sequence
from vo_lib.outputs import read_marker
from vo_lib.sim.samples import SAMPLES, fingerprint, generate, is_sample

#: A checkout's sample folder (where the package is not installed alone).
CHECKOUT_DATA = Path(__file__).resolve().parents[1] / "data"


def data_dir() -> Path:
    """``$VO_LIB_DATA``, else a checkout's ``data/``, else ``vo_lib/data`` in the user's cache."""
    env = os.environ.get("VO_LIB_DATA")
    if env:
        if Path(env).exists() and not Path(env).is_dir():
            raise UsageError(f"VO_LIB_DATA={env}: not a folder; expected the folder the samples are kept in")
        return Path(env)
    if CHECKOUT_DATA.is_dir():
        return CHECKOUT_DATA
    cache = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(cache) / "vo_lib" / "data"


def kept_data_folder() -> dict[Path, str]:
    """The samples' folders as :func:`vo_lib.outputs.check_target`'s ``keep`` takes them, never
    replaced: :func:`data_dir`, and a checkout's ``data/`` where ``$VO_LIB_DATA`` points elsewhere."""
    kept = {data_dir(): "the sample data folder"}
    if CHECKOUT_DATA.is_dir():
        kept.setdefault(CHECKOUT_DATA, "the checkout's sample data folder")
    return kept


def real_sequence_path(name: str) -> Path | None:
    """The folder ``name`` under ``$VO_LIB_REALDATA`` (real recordings, not in the repository), or None."""
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
    return (read_marker(path, "manifest.json") or {}).get("fingerprint") == fingerprint(name)


def load_sequence(
    name_or_path,
    frames: int | None = None,
    resolution=None,
    progress: bool = True,
    odometry: bool = True,
    truth: bool = True,
) -> Sequence:
    """A named sample (rendered on first use, ``progress`` as :func:`vo_lib.sim.samples.generate`
    shows it) or a folder. ``frames``: a sample of that many frames, or an ASL recording's first
    pairs (a KITTI-layout folder is read whole); ``odometry=False``: ``odometry.txt`` is not read;
    ``truth=False``: no ground truth is read."""
    key = str(name_or_path)
    if is_sample(key):
        path = sample_path(key, frames, resolution)
        if not is_rendered(key, path):
            generate(key, path, frames, None if resolution is None else tuple(resolution), progress)
        return read_sequence(path, odometry=odometry, truth=truth)
    return read_folder(Path(key), frames, odometry, truth)


def read_folder(path: Path, frames: int | None, odometry: bool, truth: bool) -> Sequence:
    """The sequence in ``path``, in whichever layout it is (:func:`load_sequence`)."""
    if mav0_of(path) is not None:  # a rig as it records (ASL layout): rectified on reading
        return read_asl(path, frames=frames, truth=truth)
    if raw_drive_of(path) is not None:  # a drive of KITTI's raw set, as it is stored
        return read_kitti_raw(path, truth=truth, odometry=odometry)
    if not (path / "image_0").is_dir() and (why := asl_near_miss(path) or raw_near_miss(path)):
        raise AslError(why)
    return read_sequence(path, odometry=odometry, truth=truth)
