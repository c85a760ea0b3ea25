"""Numba compilation, as every compiled core of the package uses it.

Compiled code is cached where it can be written (Numba's choice: in ``NUMBA_CACHE_DIR`` if set,
else beside the module, else in the user's cache folder), so only the first call in a fresh
environment pays for compilation. Where no cache folder can be written (a read-only install and
home) the functions are compiled afresh in each process instead of failing.
"""

from __future__ import annotations

from numba import njit


def jit(function):
    """Compile with NumPy semantics for division by zero (inf / nan, no exception), cached where a
    cache folder can be written, uncached otherwise."""
    try:
        return njit(cache=True, error_model="numpy")(function)
    except RuntimeError as exc:  # Numba found no writable cache folder
        if "cannot cache" not in str(exc):
            raise
        return njit(error_model="numpy")(function)
