"""Checks and timings of notebook 09 (line-feature EKF-SLAM), kept out of its story cells.

The helpers compare matrices and time functions the notebook passes in; they know nothing of SLAM.
"""

from __future__ import annotations

import timeit
from collections.abc import Callable, Sequence

import numpy as np
import sympy as sp


def differing_entries(derived: sp.Matrix, printed: sp.Matrix) -> list[tuple]:
    """Entries (row, column, derived, printed) where a derived and a printed matrix are not identical."""
    return [
        (i, j, derived[i, j], printed[i, j])
        for i in range(derived.rows)
        for j in range(derived.cols)
        if sp.simplify(derived[i, j] - printed[i, j]) != 0
    ]


def finite_difference(fn: Callable[[np.ndarray], np.ndarray], at, eps: float = 1e-6) -> np.ndarray:
    """Central finite-difference Jacobian of ``fn`` at ``at``, one column per input."""
    at = np.asarray(at, dtype=float)
    return np.column_stack([(fn(at + eps * e) - fn(at - eps * e)) / (2 * eps) for e in np.eye(at.size)])


def judge(
    name: str, numeric: np.ndarray, derived: sp.Matrix, printed: sp.Matrix, values: dict
) -> tuple[float, float]:
    """Print and return the largest gap of the finite differences ``numeric`` to the derived and
    to the printed Jacobian, both evaluated at ``values``."""
    d = np.array(derived.subs(values), dtype=float)
    p = np.array(printed.subs(values), dtype=float)
    to_derived, to_printed = float(abs(numeric - d).max()), float(abs(numeric - p).max())
    print(f"{name}: |finite diff - derived| = {to_derived:.1e}, |finite diff - printed| = {to_printed:.1e}")
    return to_derived, to_printed


def seconds_per_call(fn: Callable, tol: float, calls: Sequence[tuple]) -> float:
    """Best of three timings of ``fn(start, end, position, 30 m range, tol)`` over ``calls``, per call."""

    def run_all():
        return [fn(a_, b_, g_, 30.0, tol) for a_, b_, g_ in calls]

    return min(timeit.repeat(run_all, number=1, repeat=3)) / len(calls)
