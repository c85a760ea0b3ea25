"""Numba compilation, as every compiled kernel of the package uses it.

A kernel sits beside its NumPy reference (``matching_plain`` beside ``matching_core``,
``composite_plain`` beside ``composite``), which the tests hold it equal to; it stays only where
the reference makes the whole frame more than 1.5x slower (``python -m vo_lib bench kernels``).
Compiled code is cached where Numba can write (``NUMBA_CACHE_DIR``, beside the module, or the
user's cache folder); where nothing can be written, each process compiles afresh.
"""

from __future__ import annotations

from numba import njit


def jit(function):
    """``function`` compiled with NumPy semantics for division by zero (inf / nan, no exception)."""
    try:
        return njit(cache=True, error_model="numpy")(function)
    except RuntimeError as exc:  # Numba found no writable cache folder
        if "cannot cache" not in str(exc):
            raise
        return njit(error_model="numpy")(function)
