"""Figure layout of notebook 04 (world and sequences), kept out of its story cells."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np


def panel_grid(n: int, columns: int = 3, size: float = 4.6):
    """``n`` square panels in rows of ``columns``, large enough for their legends; spares hidden.

    Returns the figure and its ``n`` axes.
    """
    rows = -(-n // columns)
    fig, grid = plt.subplots(rows, columns, figsize=(size * columns, size * rows), constrained_layout=True)
    grid = np.atleast_1d(grid).ravel()
    for spare in grid[n:]:
        spare.set_visible(False)
    return fig, grid[:n]
