"""Tools for the notebooks' autograder tests: run a student's code with some functions refused.

An exercise that asks for a function ``vo_lib`` already has must check that the student's answer
does not simply call it. Replacing the module attribute is not enough: an answer may hold a
reference taken earlier, a copy made with ``types.FunctionType(f.__code__, ...)``, a copy
recompiled by ``importlib.reload`` or ``exec(inspect.getsource(f))``, or a compiled (Numba) twin
of the same computation. :func:`refused` covers all of these while a block runs::

    with refused(hypotheses_needed, ransac_core.hypotheses_needed):
        got = hypotheses_for(0.5, 0.99, 3)

- a Python function's code is swapped for one that raises, and every call of a function whose
  byte code matches (copies, reloaded or re-executed sources) raises too (through a profile hook);
- a Numba dispatcher loses its compiled versions (and may not compile new ones) until the block
  ends;
- a built-in (C) function, such as an OpenCV routine, raises when called, and so does a method of
  a built-in class (``cv2.DescriptorMatcher.match``) called on any of its objects.

Everything is restored when the block ends, also when it raises. Refusal raises
:class:`AssertionError`, so a graded test cell fails.
"""

from __future__ import annotations

import contextlib
import sys
import threading
import types
from collections.abc import Callable, Iterator

__all__ = [
    "KERNEL_HOOKS",
    "Refused",
    "cell_label",
    "frozen",
    "intact",
    "kernel_hooks",
    "kernel_state",
    "library_functions",
    "refused",
]


WRITE_IT = "which the exercise asks you to write yourself"


class Refused(AssertionError):
    """Raised when code running inside :func:`refused` calls a refused function."""


def _refuse(*args, **kwargs):  # runs with the refused function's globals: only built-in names
    raise AssertionError("this calls a library function the exercise asks you to write yourself")


def _fingerprint(code: types.CodeType) -> tuple:
    """What stays the same when a function's source is copied, reloaded or re-executed (its byte
    code may not: compiler flags change some instructions)."""
    consts = tuple(_fingerprint(c) if isinstance(c, types.CodeType) else repr(c) for c in code.co_consts)
    return code.co_argcount, code.co_varnames, code.co_names, consts


def _python_function(target) -> types.FunctionType | None:
    if isinstance(target, types.MethodType):
        target = target.__func__
    if isinstance(target, (staticmethod, classmethod)):
        target = target.__func__
    return target if isinstance(target, types.FunctionType) else None


def _is_dispatcher(target) -> bool:
    return hasattr(target, "overloads") and hasattr(target, "py_func") and hasattr(target, "_clear")


@contextlib.contextmanager
def refused(*targets: Callable) -> Iterator[None]:
    """Make ``targets`` (and every copy of them) raise :class:`Refused` while the block runs.

    Parameters
    ----------
    *targets
        Python functions or methods, Numba dispatchers (their ``py_func`` is refused too) and
        built-in functions.

    Raises
    ------
    Refused
        When refused code runs inside the block; when the block switched off the profile hook
        that watches for copies (even for one call), started another process or a thread (where
        the hook does not reach), or changed this module's functions (which the tests check with
        after the block).
    """
    functions, dispatchers, builtins = _sort_targets(targets)
    own_code, its_code = _own_code, _own_code.__code__  # held here, where the block cannot rebind them
    own = own_code()
    watch = _watcher(functions, builtins, sys._getframe(0).f_code)
    swapped, emptied = _disarm(functions, dispatchers)
    previous, previous_threads = sys.getprofile(), getattr(threading, "_profile_hook", None)
    sys.setprofile(watch)
    threading.setprofile(watch)
    try:
        yield
        if sys.getprofile() is not watch:
            raise Refused("the code under test switched off the check for refused functions")
        if own_code.__code__ is not its_code or own_code() != own:
            raise Refused("the code under test changed the grader's own functions")
    finally:
        sys.setprofile(previous)
        threading.setprofile(previous_threads)
        _rearm(swapped, emptied)


def _own_code() -> dict:
    """The code of every function of this module as it is now (a context manager's own too), and
    its classes: what :func:`refused` compares when its block ends."""
    found: dict[str, object] = {}
    for name, value in list(globals().items()):
        if isinstance(value, types.FunctionType):
            inner = getattr(value, "__wrapped__", None)
            found[name] = (value.__code__, getattr(inner, "__code__", None))
        elif isinstance(value, type):
            found[name] = value
    return found


def _sort_targets(targets) -> tuple[list, list, list]:
    """Python functions (a dispatcher's ``py_func`` among them), Numba dispatchers, built-ins."""
    functions, dispatchers, builtins = [], [], []
    for target in targets:
        if _is_dispatcher(target):
            dispatchers.append(target)
            functions.append(target.py_func)
        elif (function := _python_function(target)) is not None:
            functions.append(function)
        else:
            builtins.append(target)
    return list({id(f): f for f in functions}.values()), dispatchers, builtins


def _watcher(functions: list, builtins: list, own: types.CodeType):
    """A profile hook that raises :class:`Refused` when a refused function, or a copy of its
    code, is called, or when code other than ``own`` (the :func:`refused` block's) switches
    the hook off, even for one call and back on."""
    prints = {_fingerprint(f.__code__) for f in functions}
    codes = {id(f.__code__) for f in functions}
    builtin_ids = {id(b) for b in builtins}
    switches = {id(sys.setprofile), id(sys.settrace)}
    switch_codes = {id(threading.setprofile.__code__), id(threading.settrace.__code__)}
    elsewhere = {id(f) for f in _elsewhere()}
    raw_thread = {id(getattr(sys.modules.get("_thread"), "start_new_thread", None))}  # threading's too
    seen: dict[int, tuple[types.CodeType, bool]] = {}

    def copied(code: types.CodeType) -> bool:
        if id(code) not in seen:
            seen[id(code)] = code, id(code) in codes or _fingerprint(code) in prints
        return seen[id(code)][1]

    def refused_builtin(arg) -> bool:
        if id(arg) in builtin_ids:
            return True
        # a method of a built-in object (a matcher's match) is bound afresh at every call: refused
        # if its class's method is
        owner = getattr(arg, "__self__", None)
        if not builtin_ids or owner is None or isinstance(owner, types.ModuleType):
            return False
        try:
            return id(getattr(type(owner), arg.__name__, None)) in builtin_ids
        except Exception:  # noqa: BLE001 - an odd owner is not a refused one
            return False

    def watch(frame, event, arg):
        if event == "call" and copied(frame.f_code):
            raise Refused(f"this calls {frame.f_code.co_name}, {WRITE_IT}")
        if event == "c_call" and refused_builtin(arg):
            raise Refused(f"this calls {getattr(arg, '__name__', arg)}, {WRITE_IT}")
        caller = frame.f_code if event == "c_call" else getattr(frame.f_back, "f_code", None)
        switching = (event == "c_call" and id(arg) in switches) or (
            event == "call" and id(frame.f_code) in switch_codes
        )
        if switching and caller is not own:
            raise Refused("the code under test switched off the check for refused functions")
        if event == "c_call" and (id(arg) in elsewhere or id(arg) in raw_thread):
            raise Refused(
                f"this calls {getattr(arg, '__name__', arg)}: another process or thread, where the check "
                "for refused functions does not reach"
            )

    return watch


def _elsewhere() -> list:
    """The built-ins that start another process (``subprocess``, ``multiprocessing`` and
    ``os.system`` all come down to one of them), where a refused function would run unrefused."""
    import os

    names = ("fork", "forkpty", "system", "posix_spawn", "posix_spawnp", "execv", "execve")
    found = [getattr(os, name) for name in names if hasattr(os, name)]
    posix_subprocess = sys.modules.get("_posixsubprocess")
    if posix_subprocess is None:
        with contextlib.suppress(ImportError):
            import _posixsubprocess as posix_subprocess
    if posix_subprocess is not None:
        found.append(posix_subprocess.fork_exec)
    return found


def _disarm(functions: list, dispatchers: list) -> tuple[list, list]:
    """Give each function the code of :func:`_refuse` and empty each dispatcher's compiled
    versions; returns what :func:`_rearm` puts back."""
    swapped = []
    for function in functions:
        if not function.__code__.co_freevars:
            swapped.append((function, function.__code__))
            function.__code__ = _refuse.__code__
    emptied = []
    for dispatcher in dispatchers:
        emptied.append((dispatcher, list(dispatcher.overloads.values()), dispatcher._can_compile))
        dispatcher.overloads.clear()
        dispatcher._clear()
        dispatcher._can_compile = False
    return swapped, emptied


def _rearm(swapped: list, emptied: list) -> None:
    for function, code in swapped:
        function.__code__ = code
    for dispatcher, overloads, can_compile in emptied:
        dispatcher._can_compile = can_compile
        for compiled in overloads:
            dispatcher.add_overload(compiled)


def library_functions(*owners) -> list:
    """Every function a module or class of ``owners`` defines, for :func:`refused` to refuse all
    of them: an exercise that asks for something a library computes must not reach it through a
    neighbour (a class's method, a private helper, a compiled twin, a higher-level function
    whose result contains the answer).

    Parameters
    ----------
    *owners
        Modules (their own functions and classes, not what they import), classes (their
        methods, static and class methods, and properties) and functions themselves.

    Returns
    -------
    list
        Python functions and Numba dispatchers, each once, with the functions they wrap
        (``__wrapped__``); not code a library generated (a dataclass's ``__eq__``), which every
        class of its kind shares.
    """
    found: dict[int, object] = {}
    for owner in owners:
        if isinstance(owner, (types.ModuleType, type)):
            home = owner.__name__ if isinstance(owner, types.ModuleType) else owner.__module__
            _collect_owner(found, owner, home, set())
        else:
            _collect_function(found, owner)
    return list(found.values())


def _collect_function(found: dict[int, object], value, file: str | None = None) -> None:
    """Add ``value`` to ``found`` with the functions it wraps, if it is a function of ``file``."""
    while value is not None and id(value) not in found:
        function = value.py_func if _is_dispatcher(value) else _python_function(value)
        if function is None or file not in (None, function.__code__.co_filename):
            return  # not a function, or code that is not the module's own (a dataclass's __eq__)
        found[id(value)] = value
        value, file = getattr(value, "__wrapped__", None), None


def _collect_owner(found: dict[int, object], owner, home: str, seen: set) -> None:
    """Add the functions, methods and properties module ``home`` defines in ``owner`` (a module
    or a class), and those of its classes."""
    if id(owner) in seen:
        return
    seen.add(id(owner))
    file = getattr(sys.modules.get(home), "__file__", None)
    for value in list(vars(owner).values()):
        if isinstance(value, property):
            for accessor in (value.fget, value.fset, value.fdel):
                _collect_function(found, accessor, file)
        elif isinstance(value, (staticmethod, classmethod)):
            _collect_function(found, value.__func__, file)
        elif isinstance(value, type):
            if value.__module__ == home:
                _collect_owner(found, value, home, seen)
        elif getattr(value, "__module__", None) == home:
            _collect_function(found, value, file)


def frozen(values):
    """A read-only copy of ``values`` (an array of floats, or of what it holds), which no code
    can make writable again: the inputs a test keeps to compute its expected values after the
    code under test ran, which that code gets copies of.

    Parameters
    ----------
    values
        Anything :func:`numpy.asarray` takes.

    Returns
    -------
    numpy.ndarray
        Same shape and type, backed by an immutable ``bytes`` buffer.
    """
    import numpy

    array = numpy.ascontiguousarray(values)
    return numpy.frombuffer(array.tobytes(), dtype=array.dtype).reshape(array.shape)


WATCHED_MODULES = (
    "builtins",
    "math",
    "numpy",
    "numpy.random",
    "numpy.random.bit_generator",  # its randbits seeds every default_rng()
    "secrets",
    "random",
    "os",
    "numpy.linalg",
    "numpy.testing",
    "scipy.special",
)


def _installed_roots() -> tuple[str, ...]:
    """Folders that hold installed code: Python's own, the environment's, and this package's."""
    import os

    package = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    folders = (sys.prefix, sys.base_prefix, sys.exec_prefix, package)
    return tuple({os.path.abspath(folder) + os.sep for folder in folders})


def _foreign(value, roots: tuple[str, ...]) -> bool:
    """True for a function whose code is not installed code (a notebook's, or an ``exec``'s)."""
    function = _python_function(value)
    if function is None:
        return type(value).__module__ == "__main__" and callable(value) and not isinstance(value, type)
    file = function.__code__.co_filename  # "<string>" for code generated by a library (dataclasses)
    return function.__module__ == "__main__" or not file.startswith((*roots, "<"))


def _genuine(value) -> bool:
    """True if ``value`` is what its module says it is: that module's attribute of its name."""
    module = sys.modules.get(getattr(value, "__module__", None) or "")
    name = getattr(value, "__name__", None)
    if module is None or module.__name__ == "__main__" or name is None:
        return False
    return getattr(module, name, None) is value


def intact(namespace: dict, names: tuple[str, ...] = (), modules: tuple[str, ...] = WATCHED_MODULES) -> None:
    """Check that the code under test left the tools of the tests alone.

    Every module a notebook's ``namespace`` names must be the imported module itself, each of
    ``names`` must still be the library function or class it was imported as, and no function of
    ``modules`` (NumPy's, ``math``'s, the built-ins) or of this package (its modules and their
    classes) may have been replaced by one written elsewhere, such as an ``np.allclose`` that
    always agrees, an ``np.random.default_rng`` with a known seed, or a wrapper of a library
    function that records the answers the tests compute with it.

    Parameters
    ----------
    namespace
        The notebook's globals.
    names
        Names of the notebook the test uses for library functions or classes.
    modules
        Names of the modules whose functions must be their own.

    Raises
    ------
    AssertionError
        Naming the first name or function found replaced.
    """
    _constants_intact()
    roots = _installed_roots()
    package = __name__.partition(".")[0]
    ours = [name for name in list(sys.modules) if name == package or name.startswith(package + ".")]
    _namespace_intact(namespace, names, roots)
    for module_name in (*modules, *ours):
        if (module := sys.modules.get(module_name)) is not None:
            _module_intact(module_name, module, roots)


def _constants_intact() -> None:
    import math

    import numpy

    for name, value in (("pi", 3.141592653589793), ("e", 2.718281828459045), ("inf", float("inf"))):
        for module in (numpy, math):
            if getattr(module, name) != value:
                raise AssertionError(f"{module.__name__}.{name} was changed; the tests need the original")


def _namespace_intact(namespace: dict, names: tuple[str, ...], roots: tuple[str, ...]) -> None:
    for name, value in list(namespace.items()):
        if isinstance(value, types.ModuleType) and sys.modules.get(value.__name__) is not value:
            raise AssertionError(f"{name!r} is not the module it claims to be; the tests need the original")
    for name in names:
        if not _genuine(namespace.get(name)) or _foreign(namespace.get(name), roots):
            raise AssertionError(f"{name!r} no longer names the library's own; the tests need the original")


def _module_intact(module_name: str, module, roots: tuple[str, ...]) -> None:
    for name, value in list(vars(module).items()):
        if name.startswith("__"):
            continue
        if _foreign(value, roots):
            raise AssertionError(f"{module_name}.{name} was replaced; the tests need the original")
        if isinstance(value, type) and value.__module__ == module_name:
            for attribute, member in list(vars(value).items()):
                if not attribute.startswith("__") and _foreign(member, roots):
                    raise AssertionError(
                        f"{module_name}.{name}.{attribute} was replaced; the tests need the original"
                    )


KERNEL_HOOKS = frozenset(
    {
        "input_transformers_cleanup",  # rewrite (or empty) every later cell, tests included
        "input_transformers_post",
        "ast_transformers",
        "register",  # get_ipython().events.register: run code around every later cell
        "set_custom_exc",  # swallow the tests' failures
        "setprofile",  # switch off refused()'s watch
        "settrace",
        "_exit",  # end the kernel before the tests run
        "register_magic_function",
        "showtraceback",  # hide the tests' failures from the graded notebook
        "_showtraceback",
        "excepthook",
        "run_cell",  # run the tests some other way, or not at all
        "run_code",
        "run_ast_nodes",
        "transform_cell",
        "builtins",  # replace all(), float() or isinstance() that the tests use
        "__builtins__",
    }
)


def kernel_hooks(source: str) -> list[str]:
    """The hooks into the kernel that an answer's code reaches for, which no test in a cell can undo.

    A student's cell runs in the kernel before the tests; one that registers an input transformer
    or an event handler changes the test cells themselves, so the grader must look at the answer's
    code instead. This reads ``source`` (a cell's Python) and names every attribute of
    :data:`KERNEL_HOOKS` it uses, also through ``getattr(obj, "name")``.

    Parameters
    ----------
    source
        The code of one answer cell.

    Returns
    -------
    list of str
        The hooks used, in order of appearance; empty for an ordinary answer. Code that does not
        parse (IPython magics, say) is read word by word instead.
    """
    import ast
    import re

    try:
        tree = ast.parse(source)
    except SyntaxError:
        return [word for word in re.findall(r"[A-Za-z_]+", source) if word in KERNEL_HOOKS]
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and node.attr in KERNEL_HOOKS:
            found.append((node.lineno, node.col_offset, node.attr))
        elif isinstance(node, ast.Name) and node.id in KERNEL_HOOKS:
            found.append((node.lineno, node.col_offset, node.id))
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            modules = [alias.name for alias in node.names] + [getattr(node, "module", None) or ""]
            found += [(node.lineno, node.col_offset, m) for m in modules if m in KERNEL_HOOKS]
        elif isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value in KERNEL_HOOKS:
            found.append((node.lineno, node.col_offset, node.value))
    return [name for *_, name in sorted(found)]


def kernel_state() -> dict[str, str]:
    """What a cell could change in the kernel to get round the tests, each part as a short digest.

    The grader takes this before and after a student's answer cell runs (as a user expression,
    which no input transformer or event handler sees); a part that differs names the tampering:
    input or AST transformers added, event handlers registered, a trace or profile function set,
    built-ins replaced, or the shell's own methods (``showtraceback``, ``run_cell``) replaced by
    code of the notebook.

    Returns
    -------
    dict of str to str
        A digest of each part, by what it is; empty outside IPython.
    """
    import builtins
    import hashlib

    from IPython import get_ipython

    shell = get_ipython()
    if shell is None:
        return {}
    roots = _installed_roots()
    trapped = {"exit", "quit", "get_ipython", "display", "__IPYTHON__", "_", "__", "___"}
    parts = {
        "input transformers": [
            id(f) for f in (*shell.input_transformers_cleanup, *shell.input_transformers_post)
        ],
        "AST transformers": [id(t) for t in shell.ast_transformers],
        "event handlers": sorted(
            (event, id(f)) for event, handlers in shell.events.callbacks.items() for f in handlers
        ),
        "custom exception handler": [repr(shell.custom_exceptions)],
        "trace function": [id(sys.gettrace()), id(getattr(threading, "_trace_hook", None))],
        "profile function": [id(sys.getprofile()), id(getattr(threading, "_profile_hook", None))],
        "built-ins": sorted((k, id(v)) for k, v in vars(builtins).items() if k not in trapped),
        "the shell's methods": sorted(
            (owner.__name__ if isinstance(owner, type) else "shell", name)
            for owner in (shell, *type(shell).__mro__)
            for name, value in list(vars(owner).items())
            if _foreign(value, roots)
        ),
        "the grader's tools": _replaced_tools(),
    }
    return {what: hashlib.sha1(repr(value).encode()).hexdigest()[:12] for what, value in parts.items()}


def _replaced_tools() -> list[str]:
    """What a hidden test loads its tools with (``importlib.reload``, ``runpy.run_path``) and
    this module, as loaded in the kernel, that is no longer its own: a ``reload`` that returns a
    module whose ``refused`` lets everything through, or ``vo_lib.grading.intact`` replaced by
    one that agrees. Empty while all are genuine, whether this module is loaded or not.

    Read afresh from this file (``runpy.run_path``, as the grader calls :func:`kernel_state`),
    ``__file__`` is this file, whatever the kernel's modules say.
    """
    import contextlib
    import importlib
    import os
    import runpy

    def own(value, module) -> bool:
        """A function of ``module``'s file (or frozen copy), or a context manager made of one."""
        if not isinstance(value, types.FunctionType):
            return False
        if value.__code__.co_filename in (module.__file__, f"<frozen {module.__name__}>"):
            return True
        inside = [c.cell_contents for c in value.__closure__ or ()]
        made = [f for f in inside if isinstance(f, types.FunctionType)]
        wrapper = value.__code__.co_filename == contextlib.__file__
        return wrapper and bool(made) and all(own(f, module) for f in made)

    replaced = [
        f"{module.__name__}.{name}"
        for module, name in ((importlib, "reload"), (importlib, "import_module"), (runpy, "run_path"))
        if not own(getattr(module, name, None), module)
    ]
    loaded = sys.modules.get("vo_lib.grading")
    if loaded is None:
        return replaced
    try:
        same_file = os.path.samefile(loaded.__file__, __file__)
    except (AttributeError, TypeError, OSError):
        same_file = False
    if not isinstance(loaded, types.ModuleType) or not same_file:
        return [*replaced, "vo_lib.grading"]
    package = sys.modules.get(loaded.__name__.rpartition(".")[0])
    if package is not None and getattr(package, "grading", loaded) is not loaded:
        replaced.append("vo_lib.grading")
    for name in __all__:
        value = getattr(loaded, name, None)
        if isinstance(value, type):
            genuine = value.__module__ == loaded.__name__
        elif isinstance(value, (frozenset, set)):
            genuine = value == globals()[name]
        else:
            genuine = own(value, loaded)
        if not genuine:
            replaced.append(f"vo_lib.grading.{name}")
    return replaced


def cell_label(cell: dict, index: int) -> str:
    """How a report names a notebook cell: its grade id (or cell id), number and first line.

    Parameters
    ----------
    cell
        The cell, as nbformat reads it.
    index
        Its position in the notebook, from 0.

    Returns
    -------
    str
        For example ``cell 41 "ex2" (def spot_homography(theta, camera):)``.
    """
    name = cell.get("metadata", {}).get("nbgrader", {}).get("grade_id") or cell.get("id")
    lines = [line.strip() for line in cell.get("source", "").splitlines() if line.strip()]
    first = lines[0] if lines else ""
    first = first if len(first) <= 60 else first[:57] + "..."
    return f"cell {index + 1}" + (f' "{name}"' if name else "") + (f" ({first})" if first else "")
