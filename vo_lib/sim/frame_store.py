"""Rendered frames kept on disk, so that processes rendering the same sample render it once.

With :data:`FOLDER` set (the test suite sets it in every process it starts), every frame
``render_sample`` renders is written there with the noise generator's state after it, and a later
request for the same frame of the same sample reads it back and goes on rendering from that state:
the same images as one uninterrupted render. Frames are renamed into place whole.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

#: The folder of the frame store (None: rendered frames are not kept).
FOLDER: Path | None = None


class FrameStore:
    """The stored frames of one rendering (``key``: fingerprint, resolution, first frame)."""

    def __init__(self, folder: Path, key: str):
        self.folder = Path(folder) / key

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
