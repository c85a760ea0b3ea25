"""Rendered frames kept on disk, so that processes rendering the same sample render it once.

With :data:`FOLDER` set (the test suite sets it), ``render_sample`` writes every frame there with
the noise generator's state after it; a later request reads it back and goes on from that state,
giving the same images as one uninterrupted render. Frames are renamed into place whole.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

#: The folder of the frame store (None: rendered frames are not kept).
FOLDER: Path | None = None


def get(folder: Path, k: int) -> tuple[np.ndarray, np.ndarray, dict] | None:
    """Left and right images of frame ``k`` in ``folder`` and the noise state after them, or None."""
    try:
        with np.load(folder / f"{k:06d}.npz") as data:
            return data["left"], data["right"], json.loads(str(data["rng_state"]))
    except (OSError, KeyError, ValueError):
        return None  # not stored (or unreadable): render it


def put(folder: Path, k: int, left: np.ndarray, right: np.ndarray, rng_state: dict) -> None:
    """Store frame ``k`` in ``folder``; a store that cannot be written is skipped, never an error."""
    path = folder / f"{k:06d}.npz"
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with open(tmp, "wb") as f:
            np.savez(f, left=left, right=right, rng_state=np.array(json.dumps(rng_state)))
        os.replace(tmp, path)
    except BaseException as exc:  # unwritable or interrupted: no temporary left behind
        tmp.unlink(missing_ok=True)
        if not isinstance(exc, OSError):
            raise
