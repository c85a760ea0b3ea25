"""Small measurements of notebook 05 (stereo front end), kept out of its story cells."""

from __future__ import annotations

import numpy as np


def cells_covered(points: np.ndarray, cell: int = 80) -> int:
    """Number of ``cell``-pixel grid cells that hold at least one of the image ``points`` (u, v)."""
    return len(np.unique((points[:, 0] // cell).astype(int) * 10 + (points[:, 1] // cell).astype(int)))
