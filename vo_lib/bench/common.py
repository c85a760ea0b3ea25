"""Timing helpers shared by the benchmarks: median wall times, table rows, verdicts, one seed."""

from __future__ import annotations

import gc
import time
import timeit
from collections.abc import Callable

import numpy as np

BENCH_SEED = 20261121


def median_seconds(fn: Callable[[], object], repeat: int = 50, min_time: float = 0.2) -> float:
    """Median wall time of one call of ``fn`` over ``repeat`` batches lasting about ``min_time`` in all."""
    fn()  # warm caches and lazy imports
    once = max(timed_ms(fn)[1] / 1e3, 1e-7)
    number = max(1, int(min_time / repeat / once))
    # timeit turns the garbage collector off while it times; gc.enable as its setup keeps it on, as in use
    return float(np.median(timeit.repeat(fn, gc.enable, repeat=repeat, number=number))) / number


def timed_ms(fn: Callable, *args) -> tuple[object, float]:
    """``fn(*args)`` and the milliseconds it took."""
    t0 = time.perf_counter()
    out = fn(*args)
    return out, (time.perf_counter() - t0) * 1e3


def met(ok) -> str:
    """The verdict printed beside a target."""
    return "met" if ok else "NOT met"


def format_row(name: str, seconds: float, baseline: float) -> str:
    """One table row: name, time in milliseconds and the speed-up over the baseline."""
    return f"  {name:<46s}{seconds * 1e3:12.4f} ms{baseline / seconds:10.1f}x"
