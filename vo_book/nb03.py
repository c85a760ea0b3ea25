"""Small measurements of notebook 03 (circular motion, numeric checks), kept out of its story."""

from __future__ import annotations

import numpy as np


def local_exponent(measured: np.ndarray, centres: np.ndarray, i: int) -> float:
    """p of σ ∝ |v − v₀|^−p between bins ``i`` and ``i + 1``: the slope of the measured σ against
    the bins' ``centres`` on log-log axes."""
    return float(-np.log(measured[i + 1] / measured[i]) / np.log(centres[i + 1] / centres[i]))
