"""Build the reading edition: the notebooks executed, with the README, errata and benchmarks, as a
website (Sphinx, MyST-NB, the book theme).

    python docs/build.py [--out DIR] [--notebooks DIR] [--student] [--jobs N] [--rerun]

Everything is written under ``--out`` (default ``docs/_build``; ``docs/_build/student`` with
``--student``), a folder the build claims under the output rules of ``vo_lib.outputs``: new,
empty or built before (its marker ``.vo_lib_output.json`` says so), never any other folder:

- ``source/``: the pages Sphinx reads, copied from the repository (README, docs pages,
  data/README.md) and from ``--notebooks`` (default ``notebooks/``);
- ``.jupyter_cache/``: every notebook executed, keyed by its code cells (jupyter-cache). Notebooks
  not in it are executed first, ``--jobs`` at a time, longest first, so a rebuild after one edit
  runs only that notebook. The key is the notebook's code, not ``vo_lib``'s: after changing the
  package, ``--rerun`` executes every notebook again;
- ``doctrees/``, ``jupyter_execute/``: Sphinx's and MyST-NB's intermediate files;
- ``html/``: the site (open ``html/index.html``). It is built as ``html.tmp`` and renamed when
  complete, so an interrupted or failed build leaves the previous site as it was;
- ``reports/``: the traceback of any notebook that failed.

Sphinx runs in nitpicky mode with warnings as errors: a notebook's exception, a missing figure or
a broken link fails the build. Exit status: 0 built, 1 build failed, 2 bad arguments, 130
interrupted (143 terminated); each failure is one line on stderr.
"""

from __future__ import annotations

import argparse
import asyncio
import hashlib
import json
import os
import pathlib
import re
import shutil
import signal
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
sys.path.insert(0, str(DOCS))  # execute_notebook.py, beside this file (already there when run as a script)
from execute_notebook import KERNEL_NAME, read_notebook  # noqa: E402

sys.path.insert(0, str(ROOT))  # this checkout's vo_lib, whatever copy is installed
from vo_lib.arguments import OneLineParser  # noqa: E402
from vo_lib.outputs import OutputError, claim_folder, swap_in  # noqa: E402

DEFAULT_OUT = DOCS / "_build"
STUDENT_SUBFOLDER = "student"
NOTEBOOK_GLOB = "[0-9][0-9]_*.py"  # the notebooks tests/test_notebooks.py executes
RELEASE_GLOB = "[0-9][0-9]_*/[0-9][0-9]_*.ipynb"  # the student edition, as coursework/build.py writes it
WRITTEN_BY = "python docs/build.py"
CONF_STAMP = "conf.py.sha256"  # in doctrees/: the conf.py the pages were read with
# Pages of the site that are files of the repository: path in the site's source tree -> file.
PAGES = {
    "index.md": DOCS / "index.md",
    "README.md": ROOT / "README.md",
    "docs/default_run.png": DOCS / "default_run.png",
    "docs/command_line.md": DOCS / "command_line.md",
    "docs/outputs.md": DOCS / "outputs.md",
    "docs/real_data.md": DOCS / "real_data.md",
    "docs/samples.md": DOCS / "samples.md",
    "docs/benchmarks.md": DOCS / "benchmarks.md",
    "docs/layout.md": DOCS / "layout.md",
    "docs/errata.md": DOCS / "errata.md",
    "docs/notation.md": DOCS / "notation.md",
    "docs/references.md": DOCS / "references.md",
    "docs/course.md": DOCS / "course.md",
    "data/README.md": ROOT / "data" / "README.md",
}
TITLE = "vo-notebooks"
STUDENT_TITLE = "vo-notebooks (student edition)"


class BuildError(Exception):
    """A build step failed; the message is the one line shown to the user."""


class UsageError(Exception):
    """A bad argument; the message is the one line shown to the user."""


class Parser(OneLineParser):
    """Argument errors as one line (a UsageError) rather than argparse's usage block."""

    raises = UsageError


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    parser = Parser(
        prog="python docs/build.py",
        description="Build the notebooks, executed, as a website under --out (html/index.html).",
    )
    parser.add_argument("--out", type=pathlib.Path, metavar="DIR", help="build folder (default docs/_build)")
    parser.add_argument(
        "--notebooks",
        type=pathlib.Path,
        metavar="DIR",
        help="folder of jupytext notebooks NN_topic.py, or the student edition's NN_topic/NN_topic.ipynb "
        "(default notebooks/)",
    )
    parser.add_argument(
        "--student",
        action="store_true",
        help="the student edition: needs --notebooks; default --out docs/_build/student",
    )
    parser.add_argument(
        "--jobs",
        type=int,
        metavar="N",
        default=os.cpu_count() or 1,
        help="notebooks run at once (default: cores)",
    )
    parser.add_argument("--rerun", action="store_true", help="execute every notebook, cached or not")
    args = parser.parse_args(argv)
    if args.student and args.notebooks is None:
        raise UsageError("--student needs --notebooks DIR: the folder of the student notebooks")
    if args.jobs < 1:
        raise UsageError(f"--jobs: expected a whole number >= 1, got {args.jobs}")
    if args.out is None:
        args.out = DEFAULT_OUT / STUDENT_SUBFOLDER if args.student else DEFAULT_OUT
    if args.notebooks is None:
        args.notebooks = ROOT / "notebooks"
    args.out = args.out.resolve()
    args.notebooks = args.notebooks.resolve()
    return args


def find_notebooks(folder: pathlib.Path) -> list[pathlib.Path]:
    """The notebooks of ``folder``, in order; a usage error when there are none."""
    if not folder.is_dir():
        raise UsageError(f"--notebooks {folder}: not a folder")
    notebooks = sorted(folder.glob(NOTEBOOK_GLOB)) or sorted(folder.glob(RELEASE_GLOB))
    if not notebooks:
        raise UsageError(f"--notebooks {folder}: no notebooks named {NOTEBOOK_GLOB} or {RELEASE_GLOB} in it")
    return notebooks


HIDDEN_TESTS = re.compile(
    r"^[ \t]*### BEGIN HIDDEN TESTS[ \t]*\n.*?^[ \t]*### END HIDDEN TESTS[ \t]*\n?", re.M | re.S
)
SOLUTION_MARKER = re.compile(r"^[ \t]*### (BEGIN|END) SOLUTION[ \t]*\n?", re.M)


def reading_copy(source: pathlib.Path, copy: pathlib.Path) -> None:
    """Write the notebook ``source`` as the public reading edition's page ``copy``.

    Hidden tests and mark schemes are taken out (a written answer's cell says it is graded by
    hand); a solution cell keeps its code, folded behind a "show code" toggle (the
    ``hide-input`` tag), without nbgrader's markers.
    """
    import jupytext

    nb = jupytext.read(source)
    for cell in nb.cells:
        meta = cell.metadata.get("nbgrader", {})
        if cell.cell_type == "markdown" and meta.get("solution"):
            cell.source = "*The written answer goes here; it is graded by hand.*"
        elif cell.cell_type == "code":
            cell.source = HIDDEN_TESTS.sub("", cell.source).rstrip("\n")
            if meta.get("solution"):
                cell.source = SOLUTION_MARKER.sub("", cell.source).strip("\n")
                cell.metadata["tags"] = sorted({*cell.metadata.get("tags", []), "hide-input"})
    copy.write_text(jupytext.writes(nb, fmt="py:percent"), encoding="utf-8")
    shutil.copystat(source, copy)


def student_copy(release: pathlib.Path, copy: pathlib.Path) -> None:
    """Write the student notebook ``release`` (.ipynb) as the jupytext page ``copy`` (.py).

    The exercises are unanswered there: their answer and test cells are tagged
    ``raises-exception``, so that their NotImplementedError is shown rather than failing the build.
    """
    import jupytext
    import nbformat

    nb = nbformat.read(release, as_version=4)
    for cell in nb.cells:
        if cell.cell_type == "code" and "nbgrader" in cell.metadata:
            cell.metadata["tags"] = sorted({*cell.metadata.get("tags", []), "raises-exception"})
    copy.write_text(jupytext.writes(nb, fmt="py:percent"), encoding="utf-8")
    shutil.copystat(release, copy)


def claim_build_folder(out: pathlib.Path) -> None:
    """Make ``out`` ours: new, empty, or built before; any other folder is one UsageError."""
    try:
        claim_folder(out, WRITTEN_BY, option="--out")
    except OutputError as exc:
        raise UsageError(str(exc)) from None


def lay_out_sources(out: pathlib.Path, notebooks: list[pathlib.Path]) -> pathlib.Path:
    """The source tree Sphinx reads: copies of the repository's pages and of the notebooks.

    Copies rather than links, so that relative links resolve inside the tree (MyST resolves an
    included file's links from its real path). Each copy keeps its file's time, so Sphinx re-reads
    only what changed.
    """
    tree = out / "source"
    staging = out / "source.tmp"
    shutil.rmtree(staging, ignore_errors=True)
    files = {**PAGES, **{f"notebooks/{nb.stem}.py": nb for nb in notebooks}}
    for name, original in files.items():
        copy = staging / name
        copy.parent.mkdir(parents=True, exist_ok=True)
        if original.suffix == ".ipynb":
            student_copy(original, copy)
        elif name.startswith("notebooks/"):
            reading_copy(original, copy)
        else:
            shutil.copy2(original, copy)
    swap_in(staging, tree)
    return tree


def write_kernel_spec(out: pathlib.Path) -> pathlib.Path:
    """A kernel spec that runs this interpreter, whatever kernels the user has registered."""
    kernels = out / "kernels"
    spec = kernels / KERNEL_NAME
    spec.mkdir(parents=True, exist_ok=True)
    argv = [sys.executable, "-m", "ipykernel_launcher", "-f", "{connection_file}"]
    spec.joinpath("kernel.json").write_text(
        json.dumps({"argv": argv, "display_name": "vo-notebooks (site)", "language": "python"})
    )
    return kernels


async def run_notebook_process(path: pathlib.Path, kernels: pathlib.Path, staging: pathlib.Path):
    """Execute one notebook in a process of its own (execute_notebook.py).

    Returns (path, the executed notebook or None when it failed, the error, seconds).
    """
    import nbformat

    output = staging / f"{path.stem}.ipynb"
    start = time.perf_counter()
    process = await asyncio.create_subprocess_exec(
        sys.executable,
        str(DOCS / "execute_notebook.py"),
        str(path),
        str(kernels),
        str(output),
        stdout=asyncio.subprocess.DEVNULL,
        stderr=asyncio.subprocess.PIPE,
    )
    try:
        _, stderr = await process.communicate()
    except asyncio.CancelledError:
        if process.returncode is None:
            process.terminate()  # the kernel sees its parent gone and stops
            await process.wait()
        raise
    seconds = time.perf_counter() - start
    if process.returncode != 0:
        error = stderr.decode(errors="replace").strip() or f"exit status {process.returncode}"
        return path, None, error, seconds
    nb = nbformat.read(output, as_version=4)
    output.unlink()
    return path, nb, "", seconds


async def execute_in_parallel(todo, kernels: pathlib.Path, staging: pathlib.Path, jobs: int, on_done) -> None:
    """Execute ``todo`` with at most ``jobs`` notebooks at once, starting in the order given;
    ``on_done(path, nb, error, seconds)`` receives each as it finishes. Ctrl-C or SIGTERM stops
    every notebook and raises KeyboardInterrupt or Terminated."""
    slots = asyncio.Semaphore(jobs)

    async def run(path: pathlib.Path):
        async with slots:
            return await run_notebook_process(path, kernels, staging)

    main = asyncio.current_task()
    stopped_by: list[int] = []

    def stop(signum: int) -> None:
        stopped_by.append(signum)
        main.cancel()

    for signum in (signal.SIGINT, signal.SIGTERM):
        asyncio.get_running_loop().add_signal_handler(signum, stop, signum)
    tasks = [asyncio.create_task(run(path)) for path in todo]
    try:
        for finished in asyncio.as_completed(tasks):
            on_done(*(await finished))
    except asyncio.CancelledError:
        if not stopped_by:
            raise
    finally:
        for task in tasks:
            task.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)
    if stopped_by:
        raise KeyboardInterrupt if stopped_by[0] == signal.SIGINT else Terminated


def execute_missing(
    cache_dir: pathlib.Path, notebooks: list[pathlib.Path], kernels: pathlib.Path, jobs: int, rerun: bool
) -> None:
    """Execute into the cache every notebook whose code is not in it (all of them with ``rerun``)."""
    from jupyter_cache import get_cache
    from jupyter_cache.base import CacheBundleIn

    cache = get_cache(str(cache_dir))
    keys = {nb_path: cache.create_hashed_notebook(read_notebook(nb_path))[1] for nb_path in notebooks}
    cached = {record.hashkey for record in cache.list_cache_records()}
    todo = [nb_path for nb_path in notebooks if rerun or keys[nb_path] not in cached]
    print(f"notebooks: {len(notebooks) - len(todo)} cached, {len(todo)} to execute, {jobs} at a time")
    if not todo:
        return
    # Longest first, by the last run of the same notebook; new ones first, later ones first (the
    # later notebooks run whole pipelines and take longest).
    last_seconds = {r.uri: r.data.get("execution_seconds", 0.0) for r in cache.list_cache_records()}
    todo.sort(key=lambda p: (last_seconds.get(str(p), float("inf")), p.name), reverse=True)
    failures = []

    def on_done(nb_path: pathlib.Path, nb, error: str, seconds: float) -> None:
        if nb is None:
            report = cache_dir.parent / "reports" / f"{nb_path.stem}.err.log"
            report.parent.mkdir(parents=True, exist_ok=True)
            report.write_text(error, encoding="utf-8")
            first_line = error.splitlines()[0] if error else "failed"
            print(f"  FAILED {nb_path.name}: {first_line} (traceback in {report})", flush=True)
            failures.append(f"{nb_path.name}: {first_line}")
            return
        if cache.create_hashed_notebook(nb)[1] != keys[nb_path]:
            raise BuildError(f"{nb_path.name}: the executed notebook no longer matches its source")
        for record in cache.list_cache_records():  # one cached copy per notebook
            if record.uri == str(nb_path):
                cache.remove_cache(record.pk)
        bundle = CacheBundleIn(nb, str(nb_path), data={"execution_seconds": seconds})
        cache.cache_notebook_bundle(bundle, check_validity=False, overwrite=True)
        print(f"  executed {nb_path.name} in {seconds:.0f} s", flush=True)

    staging = cache_dir.parent / "executing"
    shutil.rmtree(staging, ignore_errors=True)
    staging.mkdir()
    try:
        asyncio.run(execute_in_parallel(todo, kernels, staging, jobs, on_done))
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    if failures:
        raise BuildError(f"{len(failures)} notebook(s) failed: " + "; ".join(failures))


def run_sphinx(out: pathlib.Path, tree: pathlib.Path, jobs: int, title: str) -> pathlib.Path:
    """Sphinx, nitpicky, warnings as errors, into html.tmp; renamed to html when it succeeded.

    Sphinx re-reads only pages whose files changed; after a change to conf.py (whose code, such
    as the widget transform, Sphinx does not track) it re-reads all of them (``-E``), from the
    cache.
    """
    staging = out / "html.tmp"
    shutil.rmtree(staging, ignore_errors=True)
    doctrees = out / "doctrees"
    conf_stamp = doctrees / CONF_STAMP
    conf_hash = hashlib.sha256((DOCS / "conf.py").read_bytes()).hexdigest()
    conf_changed = not conf_stamp.is_file() or conf_stamp.read_text() != conf_hash
    command = [
        sys.executable,
        "-m",
        "sphinx",
        "-b",
        "html",
        "-n",
        "-W",
        "--keep-going",
        "-q",
        "-j",
        str(jobs),
        "-c",
        str(DOCS),
        *(["-E"] if conf_changed else []),
        "-d",
        str(doctrees),
        "-D",
        f"nb_execution_cache_path={out / '.jupyter_cache'}",
        "-D",
        f"html_title={title}",
        str(tree),
        str(staging),
    ]
    returncode = None
    try:
        returncode = subprocess.run(command, check=False).returncode
    finally:
        if returncode != 0:  # failed or interrupted: no half-written site is left
            shutil.rmtree(staging, ignore_errors=True)
    if returncode != 0:
        raise BuildError(f"Sphinx reported errors or warnings (exit {returncode}; see above)")
    conf_stamp.write_text(conf_hash)
    site = out / "html"
    swap_in(staging, site)
    return site


def build(args: argparse.Namespace) -> pathlib.Path:
    notebooks = find_notebooks(args.notebooks)
    claim_build_folder(args.out)
    tree = lay_out_sources(args.out, notebooks)
    kernels = write_kernel_spec(args.out)
    # The kernels import this checkout's vo_lib, whatever copy is installed.
    os.environ["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))
    # A backend chosen for scripts (MPLBACKEND=Agg) would keep every figure out of the pages.
    os.environ.pop("MPLBACKEND", None)
    execute_missing(
        args.out / ".jupyter_cache",
        sorted(tree.joinpath("notebooks").glob("*.py")),
        kernels,
        args.jobs,
        args.rerun,
    )
    return run_sphinx(args.out, tree, args.jobs, STUDENT_TITLE if args.student else TITLE)


class Terminated(BaseException):
    """SIGTERM, raised where the build is so that it cleans up as after Ctrl-C."""


def on_sigterm(signum, frame):
    raise Terminated


def main(argv: list[str] | None = None) -> int:
    start = time.perf_counter()
    signal.signal(signal.SIGTERM, on_sigterm)
    try:
        args = parse_args(argv)
        site = build(args)
    except UsageError as exc:
        print(f"docs/build.py: {exc}", file=sys.stderr)
        return 2
    except BuildError as exc:
        print(f"docs/build.py: site not built: {exc}", file=sys.stderr)
        return 1
    except (KeyboardInterrupt, Terminated) as exc:
        print("docs/build.py: interrupted; the previous site, if any, is unchanged", file=sys.stderr)
        return 143 if isinstance(exc, Terminated) else 130
    print(f"site built in {time.perf_counter() - start:.0f} s: {site / 'index.html'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
