"""Numba compilation, as every compiled core of the package uses it, and the switch to the plain twins.

Compiled code is cached where it can be written (Numba's choice: in ``NUMBA_CACHE_DIR`` if set,
else beside the module, else in the user's cache folder), so only the first call in a fresh
environment pays for compilation. Where no cache folder can be written (a read-only install and
home) the functions are compiled afresh in each process instead of failing.

Every compiled kernel that Python code calls names its *plain twin* (``jit(twin=...)``): short
NumPy or Python, in a ``*_plain`` module beside the kernel, that computes the same result and
that a reader can step through in a debugger. :func:`choose` returns the twin instead of the
kernel when the environment variable ``VO_LIB_PLAIN`` is set to anything but ``""`` or ``"0"``,
or when the caller asks for it. Functions compiled with ``jit(step_of=...)`` are steps that only
run inside another kernel; that kernel's twin stands for them.
"""

from __future__ import annotations

import importlib
import os
from collections.abc import Callable

from numba import njit

#: Every compiled function of the package, by ``module.name``: the kernels and their steps.
COMPILED: dict[str, object] = {}
#: Kernel name -> ``module.name`` of its plain twin.
TWINS: dict[str, str] = {}
#: Step name -> the kernel it runs inside.
STEPS: dict[str, str] = {}


def kernel_name(function) -> str:
    """``module.name`` of a function or of a compiled function."""
    function = getattr(function, "py_func", function)
    return f"{function.__module__}.{function.__qualname__}"


def _compile(function):
    try:
        return njit(cache=True, error_model="numpy")(function)
    except RuntimeError as exc:  # Numba found no writable cache folder
        if "cannot cache" not in str(exc):
            raise
        return njit(error_model="numpy")(function)


def jit(function=None, *, twin: str | None = None, step_of: str | None = None):
    """Compile with NumPy semantics for division by zero (inf / nan, no exception), cached where a
    cache folder can be written, uncached otherwise.

    Parameters
    ----------
    function : callable
        Python source of the kernel (usable as ``@jit`` or ``@jit(twin=...)``).
    twin : str, optional
        ``module.name`` of the kernel's plain twin (imported only when it is chosen).
    step_of : str, optional
        ``module.name`` of the kernel this function is a step of; it is then not called from
        Python and has no twin of its own.
    """
    if function is None:
        return lambda f: jit(f, twin=twin, step_of=step_of)
    compiled = _compile(function)
    name = kernel_name(function)
    COMPILED[name] = compiled
    if twin is not None:
        TWINS[name] = twin
    if step_of is not None:
        STEPS[name] = step_of
    return compiled


def plain_wanted(plain: bool | None = None) -> bool:
    """``plain`` if given, else whether ``VO_LIB_PLAIN`` asks for the plain twins."""
    if plain is not None:
        return bool(plain)
    return os.environ.get("VO_LIB_PLAIN", "").strip() not in ("", "0")


def twin_of(kernel) -> Callable:
    """The plain twin of compiled ``kernel``."""
    module, _, name = TWINS[kernel_name(kernel)].rpartition(".")
    return getattr(importlib.import_module(module), name)


def choose(kernel, plain: bool | None = None) -> Callable:
    """The compiled ``kernel``, or its plain twin when :func:`plain_wanted`."""
    return twin_of(kernel) if plain_wanted(plain) else kernel
