"""Interactive wrappers for the notebooks; plain functions do the work and are tested directly.

The notebook pattern: a pure ``f(**params)`` computes and draws; the notebook
calls it once with its defaults, so that static renders and CI show the figure and any error
fails the run (ipywidgets swallows exceptions raised inside ``interact``), and then offers it here.
"""

from __future__ import annotations

import os
from collections.abc import Callable

HEADLESS_VARIABLE = "VO_LIB_HEADLESS"  # set: offer() shows nothing (a kernel without a browser)


def in_kernel() -> bool:
    """True inside a Jupyter kernel, False in a plain ``python notebooks/NN_x.py`` run."""
    try:
        from IPython import get_ipython
    except ImportError:  # pragma: no cover - IPython comes with ipykernel
        return False
    shell = get_ipython()
    return shell is not None and hasattr(shell, "kernel")


def slider(value: float, lo: float, hi: float, step: float, description: str):
    """A float slider that recomputes on release rather than on every pixel of the drag."""
    import ipywidgets

    return ipywidgets.FloatSlider(
        value=value,
        min=lo,
        max=hi,
        step=step,
        description=description,
        continuous_update=False,
        style={"description_width": "initial"},
    )


def offer(function: Callable[..., object], **controls):
    """Show ``function`` with ``controls`` (ipywidgets or abbreviations) inside Jupyter.

    Outside a kernel nothing is shown and ``None`` is returned, so notebooks run as scripts; so
    too in a kernel with no front end to show it (``VO_LIB_HEADLESS`` set, as the autograder
    does), where a widget would only wait for a browser that never comes.
    """
    if not in_kernel() or os.environ.get(HEADLESS_VARIABLE):
        return None
    import ipywidgets
    from IPython.display import display

    widget = ipywidgets.interactive(function, **controls)
    display(widget)
    return widget


def show_math(label: str, expr) -> None:
    """Display ``label = expr`` as typeset maths in Jupyter, as plain text elsewhere."""
    import sympy as sp

    if in_kernel():
        from IPython.display import Math, display

        display(Math(f"{label} = {sp.latex(expr)}"))
    else:
        print(f"{label} =\n{sp.pretty(expr)}\n")
