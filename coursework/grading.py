"""The course's grading tools: what hidden tests use, and what the autograder adds to nbgrader.

Nothing here ships to students (the ``vo_lib`` wheel holds no grading code). A hidden test uses::

    from coursework import grading

    with grading.unavailable(ransac.hypotheses_needed):   # the function the student must write
        got = hypotheses_for(0.5, 0.99, 3)

The autograder (``nbgrader_config.py``) adds the preprocessors below: output on stderr never costs
a mark, a flagged answer scores 0 until the teacher has read it, and feedback shows a test's
verdict and message only. ``python coursework/grading.py FOLDER`` prints the integrity report of
every notebook under ``FOLDER`` (a course's ``submitted/``).
"""

from __future__ import annotations

import ast
import contextlib
import enum
import os
import pathlib
import shlex
import shutil
import subprocess
import sys
import types
from collections.abc import Callable, Iterator

import nbformat

try:
    from nbgrader.preprocessors import NbGraderPreprocessor
except ModuleNotFoundError:  # a reader of the notebooks needs the hidden tests' tools only
    NbGraderPreprocessor = object


class GradingError(AssertionError):
    """A hidden test's answer called a function the exercise asks the student to write."""


class _Names:
    """A dictionary of names seen as an object, so that ``setattr`` writes into it."""

    def __init__(self, names: dict) -> None:
        self.__dict__ = names


@contextlib.contextmanager
def unavailable(*functions: Callable) -> Iterator[None]:
    """Make ``functions`` raise :class:`GradingError` while the block runs.

    Every loaded module (the notebook's namespace among them) and every class a module defines
    that holds one of ``functions`` under some name gets, for that name, a function that raises
    (a method, ``VoKalmanFilter.update`` say, is refused on every object of its class); all are
    restored when the block ends. This stops an answer that calls the library, under its own name
    or an alias. It is a guard for honest mistakes, not a sandbox: the integrity report is what
    catches deliberate workarounds.
    """
    wanted = {id(f) for f in functions}

    def refuse(*args, **kwargs):
        raise GradingError("this calls a library function that the exercise asks you to write yourself")

    owners = [m for m in list(sys.modules.values()) if isinstance(getattr(m, "__dict__", None), dict)]
    owners += [
        c
        for m in owners[:]
        for c in list(vars(m).values())
        if isinstance(c, type) and c.__module__ == m.__name__
    ]
    shell = getattr(sys.modules.get("IPython"), "get_ipython", lambda: None)()
    owners += [_Names(shell.user_ns)] if shell else []  # the notebook's own names
    swapped = [(o, n, v) for o in owners for n, v in list(vars(o).items()) if id(v) in wanted]
    for owner, name, _ in swapped:
        setattr(owner, name, refuse)
    try:
        yield
    finally:
        for owner, name, value in swapped:
            setattr(owner, name, value)


def library_functions(*owners: types.ModuleType | type | Callable) -> list[Callable]:
    """What a hidden test refuses, from modules, classes and functions.

    A function stands for itself; a class for its methods; a module for the functions and the
    classes' methods it defines itself (not imports), and those of every loaded module whose name
    extends its name (``ransac`` covers ``ransac_*``).
    """
    names = tuple(o.__name__ for o in owners if isinstance(o, types.ModuleType))
    modules = [
        m for n, m in list(sys.modules.items()) if names and n.startswith(names) and hasattr(m, "__dict__")
    ]
    defined = [
        value
        for module in modules
        for value in vars(module).values()
        if callable(value)
        and str(getattr(getattr(value, "py_func", value), "__module__", "")).startswith(names)
    ]
    classes = [c for c in (*owners, *defined) if isinstance(c, type)]
    methods = [
        v
        for c in classes
        for v in vars(c).values()
        if isinstance(v, (types.FunctionType, staticmethod, classmethod))
    ]
    functions = [f for f in (*owners, *defined) if not isinstance(f, (type, types.ModuleType))]
    return functions + methods


class Reason(enum.Enum):
    """Why an answer cell is to be reviewed: constructs no honest answer to an exercise needs."""

    FILE = "opens a file"
    NETWORK = "reaches the network"
    KERNEL = "uses the kernel (get_ipython)"
    FRAME = "inspects frames, code or source (sys._getframe, inspect, linecache)"
    LOW_LEVEL = "uses ctypes, gc or importlib"
    PROCESS = "starts threads or processes, or ends the interpreter"
    FAKE_NUMBER = "subclasses a built-in number or defines __array__"
    REBINDS = "rebinds a name of NumPy, of an imported module or of the grader"


MODULES = {
    "socket": Reason.NETWORK, "urllib": Reason.NETWORK, "http": Reason.NETWORK, "requests": Reason.NETWORK,
    "inspect": Reason.FRAME, "linecache": Reason.FRAME, "ctypes": Reason.LOW_LEVEL, "gc": Reason.LOW_LEVEL,
    "importlib": Reason.LOW_LEVEL, "threading": Reason.PROCESS, "multiprocessing": Reason.PROCESS,
    "subprocess": Reason.PROCESS, "concurrent": Reason.PROCESS, "_thread": Reason.PROCESS,
    "builtins": Reason.REBINDS, "coursework": Reason.REBINDS, "pathlib": Reason.FILE, "shutil": Reason.FILE,
    "glob": Reason.FILE, "io": Reason.FILE,
}  # fmt: skip
NAMES = {
    "open": Reason.FILE, "get_ipython": Reason.KERNEL, "_getframe": Reason.FRAME, "f_back": Reason.FRAME,
    "f_globals": Reason.FRAME, "f_locals": Reason.FRAME, "__code__": Reason.FRAME,
    "settrace": Reason.FRAME, "setprofile": Reason.FRAME, "_exit": Reason.PROCESS,
    "system": Reason.PROCESS, "popen": Reason.PROCESS, "fork": Reason.PROCESS,
    "__array__": Reason.FAKE_NUMBER, "__import__": Reason.LOW_LEVEL, "exec": Reason.LOW_LEVEL,
    "eval": Reason.LOW_LEVEL, "exit": Reason.PROCESS, "quit": Reason.PROCESS,
}  # fmt: skip
PROTECTED = {"np", "numpy", "grading", "assert_allclose"}
NUMBER_TYPES = {"float", "int", "complex", "bool"}


def review(source: str) -> list[tuple[int, Reason]]:
    """``(line, reason)`` for every construct of ``source`` that no honest answer needs.

    A static read (:mod:`ast`): nothing runs. Source that does not parse is not flagged (it fails
    its tests anyway); IPython magics (``%``, ``!``) are flagged as kernel use.
    """
    found = [
        (n, Reason.KERNEL)
        for n, line in enumerate(source.splitlines(), 1)
        if line.lstrip().startswith(("%", "!"))
    ]
    try:
        tree = ast.parse(
            "\n".join("" if line.lstrip().startswith(("%", "!")) else line for line in source.splitlines())
        )
    except SyntaxError:
        return found
    imported = {  # names the cell binds to modules: assigning to their attributes patches a library
        (alias.asname or alias.name).split(".")[0]
        for node in ast.walk(tree)
        if isinstance(node, ast.Import)
        for alias in node.names
    }
    for node in ast.walk(tree):
        reason = None
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            roots = [(node.module or "") if isinstance(node, ast.ImportFrom) else a.name for a in node.names]
            reason = next((MODULES[r.split(".")[0]] for r in roots if r.split(".")[0] in MODULES), None)
            if isinstance(node, ast.ImportFrom) and (node.module or "").split(".")[0] in ("numpy", "os"):
                reason = reason or next((NAMES[a.name] for a in node.names if a.name in NAMES), None)
        elif isinstance(node, ast.Name) and node.id in NAMES:
            reason = NAMES[node.id]
        elif isinstance(node, ast.Attribute) and node.attr in NAMES and node.attr not in ("system",):
            reason = NAMES[node.attr]
        elif isinstance(node, ast.Attribute) and node.attr == "system" and _named(node.value, "os"):
            reason = Reason.PROCESS
        elif isinstance(node, ast.FunctionDef) and node.name in NAMES:
            reason = NAMES[node.name]
        elif isinstance(node, ast.ClassDef) and any(_named(b, *NUMBER_TYPES) for b in node.bases):
            reason = Reason.FAKE_NUMBER
        elif isinstance(node, (ast.Assign, ast.AugAssign, ast.Delete)):
            targets = node.targets if isinstance(node, (ast.Assign, ast.Delete)) else [node.target]
            if any(_rebinds(t) for t in targets) or any(
                isinstance(t, ast.Attribute) and _named(t.value, *imported) for t in targets
            ):
                reason = Reason.REBINDS
        if reason is not None:
            found.append((node.lineno, reason))
    return sorted(set(found), key=lambda item: (item[0], item[1].value))


def _named(node: ast.AST, *names: str) -> bool:
    return isinstance(node, ast.Name) and node.id in names


def _rebinds(target: ast.AST) -> bool:
    """A target that is a protected name, or an attribute of one (``np.allclose = ...``)."""
    if isinstance(target, (ast.Tuple, ast.List)):
        return any(_rebinds(t) for t in target.elts)
    while isinstance(target, (ast.Attribute, ast.Subscript)):
        target = target.value
        if _named(target, *PROTECTED):
            return True
    return _named(target, *PROTECTED)


def report(nb: nbformat.NotebookNode) -> dict[str, list[str]]:
    """``{grade_id: ["line N: reason", ...]}`` for every answer cell of ``nb`` that is to be reviewed."""
    flagged = {}
    for cell in nb.cells:
        meta = cell.metadata.get("nbgrader", {})
        if cell.cell_type == "code" and meta.get("solution") and (found := review(cell.source)):
            lines = cell.source.splitlines()
            flagged[meta["grade_id"]] = [
                f"line {n}: {why.value}: {lines[n - 1].strip()[:70]}" for n, why in found
            ]
    return flagged


class QuietStderr(NbGraderPreprocessor):
    """Drop stderr from answer and test cells: a warning or a progress bar never costs a mark."""

    def preprocess_cell(self, cell, resources, index):
        if cell.cell_type == "code" and cell.metadata.get("nbgrader"):
            cell.outputs = [o for o in cell.get("outputs", []) if o.get("name") != "stderr"]
        return cell, resources


class ToBeReviewed(NbGraderPreprocessor):
    """A test of a flagged answer fails with the report's lines: 0 points until the teacher has read it."""

    def preprocess(self, nb, resources):
        self.flagged = report(nb)
        return super().preprocess(nb, resources)

    def preprocess_cell(self, cell, resources, index):
        exercise = cell.metadata.get("nbgrader", {}).get("grade_id", "").removesuffix("_test")
        if cell.metadata.get("nbgrader", {}).get("grade") and exercise in self.flagged:
            why = f"the answer {exercise} is to be reviewed by the teacher: " + "; ".join(
                self.flagged[exercise]
            )
            cell.outputs.append(
                nbformat.v4.new_output(
                    "error", ename="ToBeReviewed", evalue=why, traceback=[f"ToBeReviewed: {why}"]
                )
            )
        return cell, resources


class VerdictOnly(NbGraderPreprocessor):
    """Feedback of a test cell: its error's one-line message, no traceback and nothing it printed."""

    def preprocess_cell(self, cell, resources, index):
        if cell.cell_type == "code" and cell.metadata.get("nbgrader", {}).get("grade"):
            errors = [o for o in cell.get("outputs", []) if o.get("output_type") == "error"]
            for output in errors:
                output["traceback"] = [f"{output['ename']}: {output['evalue']}"]
            cell.outputs = errors
        return cell, resources


def can_isolate() -> bool:
    """True if this machine lets an unprivileged user make a user and mount namespace (``unshare``)."""
    found = shutil.which("unshare")
    return bool(found) and subprocess.run([found, "-rm", "true"], capture_output=True).returncode == 0


def isolated_kernel(kernel_args: list[str], hidden: list[str]) -> None:
    """Replace this process by an IPython kernel (``-f CONNECTION_FILE`` and the rest of
    ``kernel_args``) that sees each path of ``hidden`` empty.

    The kernel runs in its own user and mount namespace (``unshare -rm``), where an empty tmpfs
    is mounted over each hidden folder and ``/dev/null`` over each hidden file; outside it,
    nothing changes. The paths come from ``VO_HIDDEN`` (``os.pathsep``-separated).
    """
    mounts = [
        f"mount {'-t tmpfs none' if os.path.isdir(path) else '--bind /dev/null'} {shlex.quote(path)}"
        for path in hidden
        if os.path.exists(path)
    ]
    kernel = shlex.join([sys.executable, "-m", "ipykernel_launcher", "-f", *kernel_args])
    os.execvp("unshare", ["unshare", "-rm", "--", "sh", "-c", " && ".join([*mounts, f"exec {kernel}"])])


def main(argv: list[str]) -> int:
    """Print the integrity report of every notebook under the folder ``argv[0]``; or, with
    ``--kernel CONNECTION_FILE``, start the autograder's isolated kernel."""
    if len(argv) >= 2 and argv[0] == "--kernel":
        isolated_kernel(argv[1:], [p for p in os.environ.get("VO_HIDDEN", "").split(os.pathsep) if p])
    if len(argv) != 1 or not pathlib.Path(argv[0]).is_dir():
        print(
            "coursework/grading.py: expected one argument, a folder of submitted notebooks", file=sys.stderr
        )
        return 2
    for path in sorted(pathlib.Path(argv[0]).rglob("*.ipynb")):
        for exercise, lines in report(nbformat.read(path, as_version=4)).items():
            print(f"to be reviewed: {path.relative_to(argv[0])} {exercise}: " + "; ".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
