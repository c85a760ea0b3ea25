"""The course's grading tools, none shipped to students: the hidden tests' guard, the integrity report
(``python coursework/grading.py FOLDER``) and the kernels' isolation (docs/course.md). Every graded
kernel imports it: the standard library only (the steps that need nbgrader: ``autograde_steps.py``)."""

from __future__ import annotations

import ast
import builtins
import contextlib
import copy
import enum
import functools
import os
import pathlib
import shlex
import subprocess
import sys
import types
from collections.abc import Callable, Iterator

#: The modules an answer may import: the course's own, and the libraries of its numbers and figures.
COURSE_MODULES = set(
    "numpy scipy sympy math cmath statistics fractions itertools functools dataclasses typing warnings copy "
    "cv2 filterpy vo_lib vo_book matplotlib pandas skimage evo tqdm".split()
)


class GradingError(AssertionError):
    """A hidden test's answer called a function the exercise asks the student to write."""


def _refused(*args, **kwargs):  # the code a refused function runs, under its own globals: builtins only
    raise __import__("coursework.grading", fromlist=["GradingError"]).GradingError(
        "this calls a library function that the exercise asks you to write yourself"
    )


@contextlib.contextmanager
def unavailable(*functions: Callable) -> Iterator[None]:
    """Make ``functions`` raise :class:`GradingError` while the block runs: under every name (in loaded
    modules, their classes, the notebook, a ``partial``) and, for a Python function, wherever it is held
    (its code is swapped); a guard for honest mistakes, not a sandbox. The test's ``_h`` values are put
    back unless the block stored them anew: an answer that writes into its inputs cannot fit the test."""
    wanted = {id(f) for f in functions}
    modules = [m for m in list(sys.modules.values()) if isinstance(getattr(m, "__dict__", None), dict)]
    owned = [(m, k) for m in modules for k in vars(m).values() if isinstance(k, type)]
    classes = [k for m, k in owned if k.__module__ == m.__name__]  # each class once, where defined
    shell = getattr(sys.modules.get("IPython"), "get_ipython", lambda: None)()
    spaces = [vars(m) for m in modules] + ([shell.user_ns] if shell else [])  # dicts, written in place
    held = {n: v for n, v in (shell.user_ns.items() if shell else ()) if n.startswith("_h")}
    copies = {n: _copy(v) for n, v in held.items()}
    swapped = [(c, n, v) for c in classes for n, v in list(vars(c).items()) if id(v) in wanted]

    def refused(v) -> bool:  # one of them, or a partial of one (a compiled function has no code to swap)
        return id(v) in wanted or (isinstance(v, functools.partial) and id(v.func) in wanted)

    swapped += [(d, n, v) for d in spaces for n, v in list(d.items()) if refused(v)]
    put = {True: dict.__setitem__, False: setattr}
    for owner, name, _ in swapped:
        put[isinstance(owner, dict)](owner, name, _refused)
    bare = [getattr(f, "__func__", f) for f in functions]  # a static or class method: its function
    codes = [
        (f, f.__code__) for f in bare if isinstance(f, types.FunctionType) and not f.__code__.co_freevars
    ]
    for f, _ in codes:
        f.__code__ = _refused.__code__
    try:
        yield
    finally:
        for owner, name, value in swapped:
            put[isinstance(owner, dict)](owner, name, value)
        for f, code in codes:
            f.__code__ = code
        if shell:
            shell.user_ns.update({n: v for n, v in copies.items() if shell.user_ns.get(n) is held[n]})


def plain(value) -> bool:
    """Numbers as Python and NumPy make them, in arrays, lists and tuples: no object of the answer's own
    class (one that equals anything, or calls the library when NumPy reads it, after the refusal)."""
    import numpy as np

    if type(value) in (list, tuple):
        return all(map(plain, value))
    numbers = (bool, int, float, complex, *(t for t in np.sctypeDict.values() if t.__module__ == "numpy"))
    return type(value) in numbers or type(value) is np.ndarray and value.dtype.kind in "biufc"


def close(got, expected, **tolerance) -> bool:
    """``numpy.allclose`` of a :func:`plain` answer with as many numbers as expected (an empty answer
    broadcasts to any shape)."""
    import numpy as np

    return plain(got) and np.size(got) == np.size(expected) and bool(np.allclose(got, expected, **tolerance))


def equal(got, expected) -> bool:
    """``numpy.array_equal`` of a :func:`plain` answer: the same shape and the same numbers."""
    import numpy as np

    return plain(got) and bool(np.array_equal(got, expected))


def _copy(value):  # a deep copy, or the value itself where it has none (a module, a compiled object)
    with contextlib.suppress(Exception):
        return copy.deepcopy(value)
    return value


def library_functions(*owners: types.ModuleType | type | Callable) -> list[Callable]:
    """What a hidden test refuses: a function itself, a class's methods, and a module's functions and
    its classes' methods (defined there, not imported), with every loaded module named after it."""
    names = tuple(o.__name__ for o in owners if isinstance(o, types.ModuleType))
    modules = [m for n, m in list(sys.modules.items()) if names and n.startswith(names)]
    values = [(v, getattr(v, "py_func", v)) for m in modules for v in vars(m).values() if callable(v)]
    defined = [v for v, f in values if str(getattr(f, "__module__", "")).startswith(names)]  # f: compiled v
    kinds = (types.FunctionType, staticmethod, classmethod)
    found = [*owners, *defined]
    methods = [v for c in found if isinstance(c, type) for v in vars(c).values() if isinstance(v, kinds)]
    return [f for f in found if not isinstance(f, (type, types.ModuleType))] + methods


class Reason(enum.Enum):
    """Why an answer is to be reviewed: its text, and the names that show it."""

    IMPORT = "imports a module no exercise needs (not one of COURSE_MODULES)", ""
    KERNEL = "uses the kernel or its history", "get_ipython In Out _ih _oh _dh __ ___"
    INDIRECT = (
        "reaches names, code, frames or modules indirectly (exec, getattr, vars, a __special__ name, type())",
        "exec eval compile getattr setattr delattr globals locals vars breakpoint memoryview exit quit sys "
        "builtins gi_frame cr_frame ag_frame tb_frame f_back f_globals f_locals f_builtins update_wrapper "
        # modules no exercise imports, reached as another module's attribute (vo_lib.importlib), and the
        # shell's hooks that rewrite or skip the cells after the answer (the hidden tests among them)
        "os importlib import_module subprocess ctypes IPython ipykernel InteractiveShell run_cell user_ns "
        "input_transformers_cleanup input_transformers_post ast_transformers",
    )
    FILE = (
        "reads, writes or runs files",
        "open fromfile fromregex load loadtxt genfromtxt memmap read_csv read_fwf read_table read_json "
        "read_pickle run_path tofile glob rglob iterdir read_text read_bytes write_text write_bytes",
    )
    CHANGES = "changes an object it did not make (a module, a class, an argument) or a builtin's name", ""
    PRIVATE = "reaches a private name (a leading underscore) of an imported module", ""
    HELD = "calls a function held where a test cannot refuse it (an item, a closure, a default)", ""

    def __init__(self, text: str, words: str) -> None:
        self.text, self.words = text, words.split()


FLAGGED = {word: reason for reason in (Reason.KERNEL, Reason.INDIRECT) for word in reason.words}
#: Special names honest answers use: a class's own, and arithmetic (comparison, subtraction fake closeness).
SPECIAL = set(
    "__init__ __post_init__ __repr__ __str__ __name__ __doc__ __version__ __main__ __add__ __radd__ __mul__ "
    "__rmul__ __matmul__ __truediv__ __neg__".split()
)
PROTECTED = {"np", "numpy", "grading", "assert_allclose"}  # names an answer must not rebind
BUILTINS = set(dir(builtins))  # an answer that rebinds abs rewrites the tests that call it
MODULES = ("np", "numpy", "grading")  # used only as np.f: bare, they are handed, held or iterated
NAMED_TUPLE = {"_replace", "_asdict", "_make", "_fields", "_field_defaults"}  # public, though underscored


def review(source: str, bound=frozenset(), imported=frozenset()) -> list[tuple[int, Reason]]:
    """``(line, reason)`` for every construct of ``source`` outside what honest answers use, read with
    :mod:`ast` (nothing runs): the course's modules, no special names, no changes to objects the cell did
    not make; the notebook's functions and variables ``bound`` (:func:`_made`), names ``imported``."""
    magic = [n for n, line in enumerate(source.splitlines(), 1) if line.lstrip().startswith(("%", "!"))]
    found = [(n, Reason.KERNEL) for n in magic]
    if (tree := _tree(source)) is None:
        return found
    cell = _imports(tree)  # a name another cell imports is refused by the tests where it is held
    values = {id(n.value) for n in ast.walk(tree) if isinstance(n, ast.Attribute)}  # the np of np.f
    classes = [c for c in ast.walk(tree) if isinstance(c, ast.ClassDef)]
    methods, names = {id(f) for c in classes for f in c.body}, {c.name for c in classes}
    plain_methods = {  # called through their class, not an object of it, they take any first argument
        f.name for c in classes for f in c.body if isinstance(f, ast.FunctionDef) and not f.decorator_list
    }
    held = _held_values(tree, cell | imported)
    scopes = [f for f in ast.walk(tree) if isinstance(f, (ast.FunctionDef, ast.ClassDef))]
    nested = {id(c) for f in scopes for c in ast.walk(f) if c is not f}  # a method's name shadows nothing
    made = _made(tree, bound | _bound(tree))
    for node in ast.walk(tree):
        line = getattr(node, "lineno", 0) or getattr(getattr(node, "target", None), "lineno", 0)
        changes = (
            id(node) not in nested and _shadows(node) or _named(node, *MODULES) and id(node) not in values
        )
        changes = changes or any(_changes(t, made) for t in _targets(node))
        methodless = isinstance(node, ast.FunctionDef) and id(node) not in methods  # def f(self): self.x = 1
        changes |= methodless and "self" in [a.arg for a in node.args.args]
        # Cls.m or type(x).m, a method of the cell's class taken from the class: its self is any object
        kind = getattr(node, "value", None)
        taken = _named(kind, *names) or isinstance(kind, ast.Call) and _named(kind.func, "type")
        changes |= isinstance(node, ast.Attribute) and node.attr in plain_methods and taken
        found += [(line, Reason.CHANGES)] if changes else []
        found += [(line, why) for why in _reasons(node)]
        found += [(line, Reason.PRIVATE)] if _private(node, cell) else []
        found += [(line, Reason.HELD)] if _held(node, cell) or id(node) in held else []
    return sorted(set(found), key=lambda item: (item[0], item[1].text))


def _tree(source: str) -> ast.AST | None:
    """The syntax tree of a cell, its magic lines blanked; None where it does not parse."""
    lines = ["" if line.lstrip().startswith(("%", "!")) else line for line in source.splitlines()]
    with contextlib.suppress(SyntaxError):
        return ast.parse("\n".join(lines))
    return None


def _imports(tree: ast.AST) -> set[str]:
    imports = [a for n in ast.walk(tree) if isinstance(n, (ast.Import, ast.ImportFrom)) for a in n.names]
    return {(a.asname or a.name).split(".")[0] for a in imports}


def _reasons(node: ast.AST) -> list[Reason]:
    """The reasons to review one syntax node, by the module it imports or the name it uses."""
    if isinstance(node, ast.alias):  # an import that takes a builtin's name (from m import zeros as abs)
        bound = node.asname or node.name.split(".")[0]  # or NumPy under another name than np
        numpy, name = node.name == "numpy", node.name.split(".")[-1]  # from vo_lib import importlib
        if name in FLAGGED:
            return [FLAGGED[name]]
        return [Reason.CHANGES] if bound in BUILTINS | {"*"} or (bound in PROTECTED) != numpy else []
    if isinstance(node, (ast.Import, ast.ImportFrom)):
        roots = [a.name for a in node.names] if isinstance(node, ast.Import) else [node.module or "."]
        return [Reason.IMPORT] if any(r.split(".")[0] not in COURSE_MODULES for r in roots) else []
    name = getattr(node, "id", None) or getattr(node, "attr", None) or getattr(node, "name", None)
    name = node.value if isinstance(node, ast.Constant) else name  # type("F", (), {"__sub__": ...})
    if isinstance(name, str) and name[:2] == name[-2:] == "__" and len(name) > 4 and name not in SPECIAL:
        return [Reason.INDIRECT]
    if isinstance(node, ast.Call) and _named(node.func, "type") and len(node.args) > 1:
        return [Reason.INDIRECT]  # a class made by type(), its methods named in strings
    if isinstance(node, ast.Attribute) and name in Reason.FILE.words or _named(node, "open"):
        return [Reason.FILE]
    return [FLAGGED[name]] if isinstance(node, (ast.Name, ast.Attribute)) and name in FLAGGED else []


def _made(tree: ast.AST, bound: set[str]) -> set[str]:
    """Names the cell binds to a new object of a class (``kf = KalmanFilter(2, 1)``): a callee named
    like one, not ``bound`` (a function or a variable of the notebook's, which may return a module)."""
    pairs = [(t, n.value) for n in ast.walk(tree) if isinstance(n, ast.Assign) for t in n.targets]
    pairs += [(n.target, n.value) for n in ast.walk(tree) if isinstance(n, ast.AnnAssign)]
    tuples = [zip(t.elts, v.elts, strict=False) for t, v in pairs if {type(t), type(v)} == {ast.Tuple}]
    pairs += [p for z in tuples for p in z]
    calls = {t.id: v.func for t, v in pairs if isinstance(t, ast.Name) and isinstance(v, ast.Call)}
    callee = {n: getattr(f, "attr", None) or getattr(f, "id", "") for n, f in calls.items()}
    return {n for n, c in callee.items() if c.lstrip("_")[:1].isupper() and c not in bound}


def _bound(tree: ast.AST) -> set[str]:
    """Names a cell binds but by an import or a class: its functions and variables."""
    stored = {getattr(n, "id", "") for n in ast.walk(tree) if isinstance(getattr(n, "ctx", None), ast.Store)}
    return stored | {n.name for n in ast.walk(tree) if isinstance(n, ast.FunctionDef)}


def _changes(target: ast.AST, made: set[str]) -> bool:
    """A target that changes what the cell did not make: an attribute of anything but ``made`` or ``self``
    (one level down: ``kf.x = ...``), or a protected name."""
    if isinstance(target, (ast.Tuple, ast.List, ast.Starred)):
        return any(_changes(t, made) for t in getattr(target, "elts", [getattr(target, "value", None)]))
    if isinstance(target, ast.Attribute):
        return not (_named(target.value, *made) or _named(target.value, "self"))
    return _named(_root(target), *PROTECTED)  # an item of what the cell did not make: plt.rcParams["..."]


def _shadows(node: ast.AST) -> bool:
    """A builtin's name given to a function where the tests see it: ``def abs``, ``abs = lambda x: 0``."""
    function = isinstance(node, ast.Assign) and isinstance(node.value, (ast.Lambda, ast.Name))  # not sum = 0
    named = [node.name] if isinstance(node, (ast.FunctionDef, ast.ClassDef)) else []
    return bool({*named, *(getattr(t, "id", "") for t in (node.targets if function else ()))} & BUILTINS)


def _targets(node: ast.AST) -> list[ast.AST]:
    """What ``node`` binds: ``=``, ``+=``, ``x: T =``, ``del``, ``for``, ``with ... as``, comprehensions."""
    if isinstance(node, (ast.With, ast.AsyncWith)):
        return [item.optional_vars for item in node.items if item.optional_vars is not None]
    binds = (ast.Assign, ast.Delete, ast.AugAssign, ast.AnnAssign, ast.For, ast.AsyncFor, ast.comprehension)
    return (getattr(node, "targets", None) or [node.target]) if isinstance(node, binds) else []


def _private(node: ast.AST, imported: set[str]) -> bool:
    """``from m import _x``, ``from m._p import x`` or ``m._x`` of an imported ``m`` (a private kernel)."""
    imports = isinstance(node, (ast.Import, ast.ImportFrom))
    paths = [str(getattr(node, "module", "")), *(a.name for a in node.names)] if imports else []
    names = [part for path in paths for part in path.split(".")] or [getattr(node, "attr", "")]
    inside = imports or _named(_root(node), *imported)
    return inside and any(n[:1] == "_" and n[-2:] != "__" and n not in NAMED_TUPLE for n in names)


def _held(node: ast.AST, imported: set[str]) -> bool:
    """A call of an item (``fs[0](x)``), of a parameter in a nested function, or of a default holding
    ``m.f`` or an imported ``f``: a compiled function (OpenCV's) held so escapes a test's refusal."""
    if isinstance(node, ast.Call):
        return isinstance(node.func, ast.Subscript)
    a = getattr(node, "args", None)
    if not isinstance(a, ast.arguments):
        return False
    named = (a.posonlyargs + a.args)[len(a.posonlyargs + a.args) - len(a.defaults) :]  # those with defaults
    pairs = [*zip(named, a.defaults, strict=True), *zip(a.kwonlyargs, a.kw_defaults, strict=True)]
    held = {p.arg for p, d in pairs if isinstance(d, ast.Attribute) or _named(d, *imported)}
    inner = [f for f in ast.walk(node) if f is not node and isinstance(getattr(f, "args", 0), ast.arguments)]
    closed = {p.arg for p in a.posonlyargs + a.args + a.kwonlyargs}  # called in a nested function
    nested = [c for f in inner for c in ast.walk(f) if isinstance(c, ast.Call) and _named(c.func, *closed)]
    return bool(nested) or any(isinstance(c, ast.Call) and _named(c.func, *held) for c in ast.walk(node))


def _held_values(tree: ast.AST, imported: set[str]) -> set[int]:
    """Ids of imported modules' attributes (``cv2.norm``; no test refuses NumPy's or math's) kept as values in
    a list, a tuple, a set, a dict or an object's attribute or item, where no test's refusal reaches them."""
    kept = [e for n in ast.walk(tree) if isinstance(n, (ast.List, ast.Tuple, ast.Set)) for e in n.elts]
    kept += [v for n in ast.walk(tree) if isinstance(n, ast.Dict) for v in n.values]
    pairs = [(t, n.value) for n in ast.walk(tree) if isinstance(n, ast.Assign) for t in n.targets]
    pairs += [(n.target, n.value) for n in ast.walk(tree) if isinstance(n, ast.AnnAssign)]
    kept += [v for t, v in pairs if isinstance(t, ast.Attribute | ast.Subscript)]  # x.f = cv2.f
    modules = imported - {"np", "numpy", "math"}
    return {id(v) for v in kept if isinstance(v, ast.Attribute) and _named(_root(v), *modules)}


def _root(node: ast.AST) -> ast.AST:
    """``a`` of ``a.b.c`` and of ``a[k].b``."""
    while isinstance(node, (ast.Attribute, ast.Subscript)):
        node = node.value
    return node


def _named(node: ast.AST, *names: str) -> bool:
    return isinstance(node, ast.Name) and node.id in names


def report(nb, released=None) -> dict[str, list[str]]:
    """``{grade_id or "code cell N": ["line N: reason: code", ...]}`` for every answer cell of ``nb`` to be
    reviewed, and every other code cell but a test that is not in the release ``released`` as it is there."""
    flagged, code_cells = {}, [cell for cell in nb.cells if cell.cell_type == "code"]
    given = {c.source for c in released.cells if c.cell_type == "code"} if released else None
    trees = [tree for c in code_cells if (tree := _tree(c.source))]
    bound, imported = (frozenset().union(*map(f, trees)) for f in (_bound, _imports))
    for k, cell in enumerate(code_cells, 1):
        meta = cell.metadata.get("nbgrader", {})
        changed = given is not None and not meta.get("grade") and cell.source not in given
        if (meta.get("solution") or changed) and (found := review(cell.source, bound, imported)):
            code = cell.source.splitlines()
            key = meta["grade_id"] if meta.get("solution") else f"code cell {k}"
            flagged[key] = [f"line {n}: {r.text}: {code[n - 1].strip()[:70]}" for n, r in found]
    return flagged


def can_isolate() -> bool:
    """True if an unprivileged user may make a user and mount namespace here (``unshare -rm``)."""
    with contextlib.suppress(OSError):  # no unshare at all
        return subprocess.run(["unshare", "-rm", "true"], capture_output=True).returncode == 0
    return False


def isolated_kernel(hidden: list[str], read_only: list[str] = ()) -> list[str]:
    """A kernel spec's ``argv``: an IPython kernel in its own user and mount namespace (``unshare -rm``),
    with an empty tmpfs over each hidden folder, ``/dev/null`` over each hidden file, each path of
    ``read_only`` (the grader's own files) bound over itself read-only, and no history on disk."""
    mounts = [
        f"mount {'-t tmpfs none' if os.path.isdir(p) else '--bind /dev/null'} {shlex.quote(p)}"
        for p in hidden
        if os.path.exists(p)
    ]
    mounts += [
        f"mount --bind {q} {q} && mount -o remount,bind,ro {q}"
        for q in map(shlex.quote, filter(os.path.exists, read_only))
    ]
    # no history on disk (cells hold solutions, hidden tests); the client's arguments as "$@" ($0: "sh")
    kernel = shlex.join([sys.executable, "-m", "ipykernel_launcher", "--HistoryManager.enabled=False"])
    script = " && ".join([*mounts, f"exec {kernel} -f '{{connection_file}}' \"$@\""])
    return ["unshare", "-rm", "--", "sh", "-c", script, "sh"]


def main(argv: list[str]) -> int:
    """Print the integrity report of every notebook under the folder ``argv[0]``."""
    if len(argv) != 1 or not pathlib.Path(argv[0]).is_dir():
        print("coursework/grading.py: expected one argument, a folder of submissions", file=sys.stderr)
        return 2
    import nbformat

    for path in sorted(pathlib.Path(argv[0]).rglob("*.ipynb")):
        release = pathlib.Path(argv[0]).resolve().parent / "release" / path.parent.name / path.name
        released = nbformat.read(release, as_version=4) if release.is_file() else None
        for exercise, lines in report(nbformat.read(path, as_version=4), released).items():
            print(f"to be reviewed: {path.relative_to(argv[0])} {exercise}: " + "; ".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
