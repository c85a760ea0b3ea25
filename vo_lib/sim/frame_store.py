"""Rendered frames kept on disk, so that processes rendering the same sample render it once.

Processes that render the same samples in memory (``render_sample``), each from frame 0, can
share the work: with :data:`FOLDER` naming a folder, every frame rendered is written there, and
a later request for the same frame of the same sample (same fingerprint, resolution and first
frame) reads it back instead of rendering it. The sensor noise of frame ``k`` is drawn from a
generator that frames ``first..k-1`` advanced, so each stored frame carries the generator's state
after it: a request that finds frames 0-99 stored and needs 100-399 reads the first hundred,
restores the state and renders the rest, the same images as one uninterrupted render.

Frames are written under a temporary name and renamed, so a reader never sees half a frame and
two processes rendering the same frame at once leave one whole file. The store holds nothing but
what was rendered into it. The test suite sets :data:`FOLDER` in every process it starts (its
notebook kernels and command-line runs too) and removes the folder at the end.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from pathlib import Path

import numpy as np

#: The folder of the frame store (None: rendered frames are not kept).
FOLDER: Path | None = None


class FrameStore:
    """The stored frames of one rendering of a sample: ``key`` names its fingerprint, resolution
    and first frame."""

    def __init__(self, folder: Path, key: str):
        self.folder = Path(folder) / key

    @staticmethod
    def current(key: Callable[[], str]) -> FrameStore | None:
        """The store of ``key()`` in :data:`FOLDER`, or None when it is unset (``key`` is only
        called then)."""
        return FrameStore(FOLDER, key()) if FOLDER else None

    def _path(self, k: int) -> Path:
        return self.folder / f"{k:06d}.npz"

    def get(self, k: int) -> tuple[np.ndarray, np.ndarray, dict] | None:
        """Left and right images of frame ``k`` and the noise generator's state after them, or None."""
        try:
            with np.load(self._path(k)) as data:
                return data["left"], data["right"], json.loads(str(data["rng_state"]))
        except (OSError, KeyError, ValueError):
            return None  # not stored (or unreadable): render it

    def put(self, k: int, left: np.ndarray, right: np.ndarray, rng_state: dict) -> None:
        """Store frame ``k``; a store that cannot be written is skipped, never an error."""
        path = self._path(k)
        tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
            with open(tmp, "wb") as f:
                np.savez(f, left=left, right=right, rng_state=np.array(json.dumps(rng_state)))
            os.replace(tmp, path)
        except BaseException as exc:  # unwritable or interrupted: no temporary left behind
            tmp.unlink(missing_ok=True)
            if not isinstance(exc, OSError):
                raise
