"""Execute one jupytext notebook for the reading edition, in a process of its own.

    python docs/execute_notebook.py NOTEBOOK KERNELS OUTPUT

Runs NOTEBOOK (a percent-format .py file) in its own folder, in the kernel ``vo-notebooks-site``
of the kernel spec folder KERNELS, and writes the executed notebook to OUTPUT (nbformat JSON,
through a temporary name). ``docs/build.py`` runs several of these at once: one kernel client per
process, so that each cleans up its own kernel on Ctrl-C. On failure the first line on stderr is
the error (``Name: message``), the rest its traceback, and the exit status is 1.
"""

from __future__ import annotations

import os
import pathlib
import re
import sys
import tempfile
import traceback

NOTEBOOK_FORMAT = "py:percent"  # as nb_custom_formats in conf.py: the cache keys must agree
KERNEL_NAME = "vo-notebooks-site"
CELL_TIMEOUT_S = 300  # as in tests/test_notebooks.py
ANSI_ESCAPE = re.compile(r"\x1b\[[0-9;]*m")  # the colours of IPython's tracebacks


def read_notebook(path: pathlib.Path):
    """The notebook as MyST-NB reads it (conf.py's nb_custom_formats)."""
    import jupytext

    return jupytext.reads(path.read_text(encoding="utf-8"), fmt=NOTEBOOK_FORMAT)


def execute(path: pathlib.Path, kernels: pathlib.Path):
    """Execute the notebook at ``path`` in its folder; return it with its outputs.

    The notebook keeps the metadata it was read with (the cache keys it by its code cells, their
    metadata and the kernel spec), and no widget state: the site shows the figure each widget
    draws at its defaults, not the widget (conf.py).
    """
    from jupyter_client.kernelspec import KernelSpecManager
    from jupyter_client.manager import KernelManager
    from nbclient import NotebookClient

    nb = read_notebook(path)
    kernelspec = nb.metadata.get("kernelspec")
    with tempfile.TemporaryDirectory(prefix="vo-site-kernel-") as ipc:
        ksm = KernelSpecManager(kernel_dirs=[str(kernels)], ensure_native_kernel=False)
        # IPC sockets rather than TCP ports, which stall when several kernels start at once.
        km = KernelManager(kernel_name=KERNEL_NAME, kernel_spec_manager=ksm, transport="ipc", ip=f"{ipc}/k")
        client = NotebookClient(nb, km=km, timeout=CELL_TIMEOUT_S, allow_errors=False, record_timing=False)
        try:
            client.execute(cwd=str(path.parent))
        finally:
            if km.has_kernel:  # the client does not own a kernel manager it is given
                km.shutdown_kernel(now=True)
    nb.metadata.pop("kernelspec", None)
    if kernelspec is not None:
        nb.metadata["kernelspec"] = kernelspec
    nb.metadata.pop("widgets", None)
    return nb


def summary(exc) -> str:
    """One line for a cell's error: its name and message, and the line of the cell that raised it
    (a bare ``assert`` has no message)."""
    arrows = [line for line in ANSI_ESCAPE.sub("", exc.traceback).splitlines() if "--->" in line]
    head = f"{exc.ename}: {exc.evalue}" if exc.evalue else exc.ename
    if not arrows:
        return head
    number, _, code = arrows[-1].split("--->", 1)[1].strip().partition(" ")
    return f"{head}, at line {number} of the cell: {code.strip()}"


def main(argv: list[str]) -> int:
    import nbformat
    from nbclient.exceptions import CellExecutionError, CellTimeoutError

    if len(argv) != 3:
        print("usage: python docs/execute_notebook.py NOTEBOOK KERNELS OUTPUT", file=sys.stderr)
        return 2
    path, kernels, output = (pathlib.Path(a) for a in argv)
    try:
        nb = execute(path, kernels)
    except CellTimeoutError as exc:
        print(f"CellTimeoutError: a cell ran longer than {CELL_TIMEOUT_S} s\n{exc}", file=sys.stderr)
        return 1
    except CellExecutionError as exc:
        print(f"{summary(exc)}\n{ANSI_ESCAPE.sub('', str(exc))}", file=sys.stderr)
        return 1
    except Exception as exc:  # the kernel or its client failing
        print(f"{type(exc).__name__}: {exc}\n{traceback.format_exc()}", file=sys.stderr)
        return 1
    staging = output.with_name(f".{output.name}.tmp")
    nbformat.write(nb, staging)
    os.replace(staging, output)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
