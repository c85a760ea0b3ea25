"""Every notebook is a test: read the jupytext .py, execute it in a fresh kernel, fail on any error.

The story cells keep the asserts that check a derivation. The checks of the notebooks' measured
claims (the figures a sentence states) live in ``tests/notebook_checks/<notebook>.py``: each part
starts with ``# after: TEXT`` and runs, in the same kernel, right after the one code cell holding
TEXT, so it sees the values that sentence describes.

Each cell runs under a timeout; kernels talk over IPC sockets rather than TCP ports, which stall
when several start at once; and an exception inside any cell fails the test with its traceback.
"""

from __future__ import annotations

import ast
import os
import pathlib
import re
import subprocess
import sys

import jupytext
import nbformat
import pytest
from jupyter_client.kernelspec import KernelSpecManager
from jupyter_client.manager import KernelManager
from nbclient import NotebookClient
from nbclient.exceptions import CellExecutionError, CellTimeoutError

ROOT = pathlib.Path(__file__).resolve().parents[1]
NOTEBOOK_DIR = ROOT / "notebooks"
NOTEBOOKS = sorted(NOTEBOOK_DIR.glob("[0-9][0-9]_*.py"))
CELL_TIMEOUT_S = 300
CHECKS_DIR = ROOT / "tests" / "notebook_checks"
#: Real KITTI-layout sequences beside the repository: notebooks read them through VO_LIB_REALDATA.
REALDATA = ROOT.parent / "shared" / "realdata"


def test_there_are_notebooks():
    assert len(NOTEBOOKS) >= 3, f"expected notebooks under {NOTEBOOK_DIR}"


def with_checks(nb: nbformat.NotebookNode, path: pathlib.Path) -> int:
    """Insert each part of the notebook's checks file after the code cell its ``# after:`` names."""
    checks = CHECKS_DIR / path.name
    if not checks.exists():
        return 0
    preamble, *parts = re.split(r"^# after: (.+)$", checks.read_text(), flags=re.M)
    assert all(isinstance(n, ast.Expr) for n in ast.parse(preamble).body), (
        f"{checks.name}: code before the first '# after:' line would never run"
    )
    places = []
    for anchor, code in zip(parts[::2], parts[1::2], strict=True):
        hits = [i for i, c in enumerate(nb.cells) if c.cell_type == "code" and anchor.strip() in c.source]
        assert len(hits) == 1, f"{checks.name}: '# after: {anchor}' is in {len(hits)} code cells, not one"
        compile(code, f"{checks.name}, after {anchor}", "exec")  # a slip fails here, not an hour later
        places.append((hits[0], code.strip()))
    for index, code in reversed(sorted(places, key=lambda p: p[0])):  # the last first: indices hold
        nb.cells.insert(index + 1, nbformat.v4.new_code_cell(code))
    return len(places)


@pytest.mark.notebook
@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_executes(path, kernel_dir, tmp_path, monkeypatch):
    if REALDATA.is_dir() and not os.environ.get("VO_LIB_REALDATA"):
        monkeypatch.setenv("VO_LIB_REALDATA", str(REALDATA))  # the kernel inherits it
    nb = jupytext.read(path)
    with_checks(nb, path)
    ksm = KernelSpecManager(kernel_dirs=[str(kernel_dir)], ensure_native_kernel=False)
    km = KernelManager(
        kernel_name=nb.metadata["kernelspec"]["name"],  # the kernel the notebook names, in kernel_dir
        kernel_spec_manager=ksm,
        transport="ipc",
        ip=str(tmp_path / "kernel"),
    )
    client = NotebookClient(
        nb,
        km=km,
        timeout=CELL_TIMEOUT_S,
        allow_errors=False,
        resources={"metadata": {"path": str(NOTEBOOK_DIR)}},
    )
    try:
        client.execute()
    except CellTimeoutError as exc:
        pytest.fail(f"{path.name}: a cell ran longer than {CELL_TIMEOUT_S} s\n{exc}")
    except CellExecutionError as exc:
        pytest.fail(f"{path.name} failed:\n{exc}")
    finally:
        if km.has_kernel:  # the client does not own a kernel manager it is given: stop the kernel here
            km.shutdown_kernel(now=True)
    codes = [c for c in nb.cells if c.cell_type == "code"]
    assert codes and all(c.get("execution_count") for c in codes), "some code cells did not run"


def test_every_checks_file_finds_its_notebook_and_cells():
    for checks in CHECKS_DIR.glob("*.py"):
        path = NOTEBOOK_DIR / checks.name
        assert path.exists(), f"{checks.name}: no notebook of that name in notebooks/"
        assert with_checks(jupytext.read(path), path) >= 1, f"{checks.name}: no '# after:' line"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_conventions(path):
    """Header cell, a seed in the first code cell, no IPython magics, exercises at the end."""
    nb = jupytext.read(path)
    cells = nb.cells
    assert cells[0].cell_type == "markdown" and cells[0].source.startswith("# "), "first cell: title"
    header = cells[0].source.lower()
    for word in ("you will learn", "prerequisites", "run time"):
        assert word in header, f"first markdown cell must say {word!r}"
    first_code = next(c for c in cells if c.cell_type == "code")
    assert re.search(r"default_rng\(|SEED\s*=", first_code.source), "first code cell must seed"
    for c in cells:
        if c.cell_type == "code":
            assert not re.search(r"^\s*[%!]", c.source, re.M), f"magic in {path.name}: {c.source[:60]}"
    run_time = re.search(r"\*\*Run time\*\*: about (\d+) seconds", cells[0].source)
    mapped = re.search(rf"^\| {path.name[:2]} \|.* \| (\d+) s[ |]", (ROOT / "README.md").read_text(), re.M)
    assert run_time and mapped, "the header says 'Run time: about N seconds', the README's map 'N s'"
    assert run_time[1] == mapped[1], f"run time: the header says {run_time[1]} s, the README {mapped[1]} s"
    exercises = [
        i for i, c in enumerate(cells) if c.cell_type == "markdown" and c.source.startswith("## Exercises")
    ]
    assert exercises, "an '## Exercises' section must close the notebook"
    later = [c.source.splitlines()[0] for c in cells[exercises[-1] + 1 :] if c.source.startswith("## ")]
    assert not later, f"sections after the exercises: {later}"
    long_lines = [
        line for line in path.read_text().splitlines() if len(line) > 110 and not line.startswith("# %% ")
    ]
    assert not long_lines, f"lines over 110 characters (only nbgrader cell headers may be): {long_lines[0]!r}"


def test_derivation_notebook_runs_as_plain_script(tmp_path):
    env = dict(os.environ, MPLBACKEND="Agg")
    script = NOTEBOOK_DIR / "02_circular_motion_derivation.py"
    proc = subprocess.run(
        [sys.executable, str(script)],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]


#: Notebooks that use real data when VO_LIB_REALDATA names it, and a rendered stand-in otherwise.
READS_REAL = [p for p in NOTEBOOKS if "VO_LIB_REALDATA" in p.read_text()]


@pytest.mark.notebook
@pytest.mark.parametrize("path", READS_REAL, ids=[p.stem for p in READS_REAL])
def test_notebook_executes_without_real_data(path, tmp_path):
    """The stand-in path (how a reader without KITTI, and the site's build, runs it) passes its
    asserts and its claim checks: the notebook with its checks, run as a script in notebooks/."""
    env = {**os.environ, "VO_LIB_REALDATA": "", "VO_LIB_HEADLESS": "1", "MPLBACKEND": "Agg"}
    nb = jupytext.read(path)
    with_checks(nb, path)
    script = tmp_path / path.name
    script.write_text(jupytext.writes(nb, fmt="py:percent"), encoding="utf-8")
    done = subprocess.run(
        [sys.executable, str(script)], cwd=NOTEBOOK_DIR, env=env, capture_output=True, text=True, timeout=600
    )
    assert "real data not found" in done.stdout or "no real frame" in done.stdout, done.stdout[-2000:]
    assert done.returncode == 0, f"{path.name} without real data:\n{done.stderr[-3000:]}"
