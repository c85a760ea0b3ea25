"""vo_lib.grading: refused functions stay refused by every route, and are restored afterwards."""

import inspect
import threading
import types

import numpy as np
import pytest

import vo_lib.stereo_vo.baselines as baselines
import vo_lib.stereo_vo.ransac as ransac
from vo_lib.camera import StereoCamera
from vo_lib.grading import frozen, intact, kernel_hooks, library_functions, refused

CAMERA = StereoCamera(fx=500.0, fy=500.0, cx=320.0, cy=240.0, baseline=0.2, width=640, height=480)
PIXELS = np.array([[100.0, 300.0, 10.0], [400.0, 200.0, 20.0]])


def copied():
    original = ransac.hypotheses_needed
    return types.FunctionType(original.__code__, original.__globals__, None, original.__defaults__)


def executed():
    space = dict(vars(ransac))
    exec(inspect.getsource(ransac.hypotheses_needed), space)  # noqa: S102 - the cheat under test
    return space["hypotheses_needed"]


def in_thread(function):
    def run(*args):
        out = []
        worker = threading.Thread(target=lambda: out.append(function(*args)))
        worker.start()
        worker.join()
        return out[0]

    return run


@pytest.mark.filterwarnings("ignore::pytest.PytestUnhandledThreadExceptionWarning")
@pytest.mark.parametrize(
    "route",
    [
        lambda: ransac.hypotheses_needed,
        copied,
        executed,
        lambda: baselines.hypotheses_needed,
        lambda: in_thread(copied()),
    ],
    ids=["captured", "function-copy", "exec-source", "re-exported", "thread"],
)
def test_every_route_to_a_refused_function_fails_and_is_restored(route):
    function = route()
    expected = int(ransac.hypotheses_needed(0.5, 0.99))
    with pytest.raises((AssertionError, TypeError, IndexError)):
        with refused(ransac.hypotheses_needed):
            function(0.5, 0.99)
    assert int(ransac.hypotheses_needed(0.5, 0.99)) == expected == int(baselines.hypotheses_needed(0.5, 0.99))
    assert int(function(0.5, 0.99)) == expected


def test_a_method_is_refused_and_other_code_runs():
    with refused(StereoCamera.backproject):
        assert np.sqrt(4.0) == 2.0
        with pytest.raises(AssertionError):
            CAMERA.backproject(PIXELS)
    assert CAMERA.backproject(PIXELS).shape == (2, 3)


def test_a_method_of_a_builtin_class_is_refused_on_every_object():
    cv2 = pytest.importorskip("cv2")
    made_before = cv2.BFMatcher(cv2.NORM_HAMMING)
    a, b = np.zeros((1, 32), np.uint8), np.full((1, 32), 255, np.uint8)
    with refused(cv2.DescriptorMatcher.match, cv2.norm):
        assert np.bitwise_xor(a, b).sum() > 0 and [1, 2].count(1) == 1  # other built-ins run
    for call in (
        lambda: made_before.match(a, b),
        lambda: cv2.BFMatcher(cv2.NORM_HAMMING).match(a, b),
        lambda: cv2.norm(a, b, cv2.NORM_HAMMING),
    ):
        with pytest.raises(AssertionError, match="which the exercise asks you to write yourself"):
            with refused(cv2.DescriptorMatcher.match, cv2.norm):
                call()
    assert made_before.match(a, b)[0].distance == 256


def test_library_functions_refuses_a_module_by_every_neighbour_and_not_other_code():
    import dataclasses

    import vo_lib.lidar_tracking.pose_tracking as tracking

    functions = library_functions(tracking)
    names = {getattr(f, "__qualname__", "") for f in functions}
    # the function, a classmethod, a property and a method all count; imports and generated code do not
    neighbours = {"posterior", "ControlLimits.from_corrections", "ControlLimits.upper", "PoseTracker.update"}
    assert neighbours <= names
    assert not any(name.endswith(("__eq__", "__repr__")) for name in names)
    assert all(f.__module__ == tracking.__name__ for f in functions)
    limits = tracking.ControlLimits.from_corrections([0.1, 0.2, 0.3])
    with refused(*functions):
        assert dataclasses.asdict(tracking.ControlLimits(0.2, 0.1)) == {"mean": 0.2, "std": 0.1}
        with pytest.raises(AssertionError):
            limits.upper  # noqa: B018 - a property refused
        with pytest.raises(AssertionError):
            copied_posterior = types.FunctionType(tracking.posterior.__code__, tracking.posterior.__globals__)
            copied_posterior([1.0, 2.0])
    assert limits.upper > limits.centre


def test_frozen_inputs_stay_as_they_were():
    kept = frozen(np.arange(6.0).reshape(2, 3))
    with pytest.raises(ValueError):
        kept[0, 0] = 1.0
    with pytest.raises(ValueError):
        kept.setflags(write=True)
    assert kept.shape == (2, 3) and kept.sum() == 15.0


def test_switching_the_watch_off_fails():
    with pytest.raises(AssertionError, match="switched off"):
        with refused(ransac.hypotheses_needed):
            import sys

            sys.setprofile(None)


def test_switching_the_watch_off_for_one_call_fails():
    """A copy the swapped code misses, run with the watch off for that one call and on again."""
    import sys

    switch = getattr(sys, "set" + "profile")
    function = copied()

    def unwatched(*args):
        watching = sys.getprofile()
        switch(None)
        try:
            return function(*args)
        finally:
            switch(watching)

    with pytest.raises(AssertionError, match="switched off"):
        with refused(ransac.hypotheses_needed):
            unwatched(0.5, 0.99)
    with pytest.raises(AssertionError, match="switched off"):
        with refused(ransac.hypotheses_needed):
            threading.setprofile(None)
    assert sys.getprofile() is None and int(unwatched(0.5, 0.99)) == 7


def test_another_process_or_an_unwatched_thread_is_refused():
    """A copy run in a thread started below threading (which the watch is not on), or the
    library run in another process, where nothing is refused."""
    import _thread
    import subprocess
    import sys
    import time

    function = copied()

    def in_raw_thread(*args):
        out = []
        _thread.start_new_thread(lambda: out.append(function(*args)), ())
        while not out:
            time.sleep(0.001)
        return out[0]

    with pytest.raises(AssertionError, match="another process or thread"):
        with refused(ransac.hypotheses_needed):
            in_raw_thread(0.5, 0.99)
    with pytest.raises(AssertionError, match="another process or thread"):
        with refused(ransac.hypotheses_needed):
            subprocess.run([sys.executable, "-c", "print(7)"], capture_output=True)
    assert int(in_raw_thread(0.5, 0.99)) == 7 and in_thread(function)(0.5, 0.99) == 7


def test_changing_the_graders_own_functions_in_a_refused_block_fails():
    import vo_lib.grading as grading

    real = grading.intact.__code__
    try:
        with pytest.raises(AssertionError, match="changed the grader"):
            with refused(ransac.hypotheses_needed):
                grading.intact.__code__ = (lambda namespace, names=(), modules=(): None).__code__
    finally:
        grading.intact.__code__ = real
    with refused(ransac.hypotheses_needed):  # and an ordinary block passes
        assert np.sqrt(9.0) == 3.0


def notebook_function(source):
    """A function as a notebook cell defines it (module ``__main__``)."""
    return eval(source, {"__name__": "__main__"})  # noqa: S307 - a fixed test string


def test_intact_finds_replaced_tools(monkeypatch):
    namespace = {"np": np, "hypotheses_needed": ransac.hypotheses_needed}
    intact(namespace)
    for owner, name, value in [
        (np, "allclose", notebook_function("lambda *a, **k: True")),
        (np.random, "default_rng", notebook_function("lambda *a: None")),
        (np, "pi", 0.0),
        (ransac, "hypotheses_needed", notebook_function("lambda *a: 1")),
        (StereoCamera, "backproject", notebook_function("lambda *a: None")),
    ]:
        with monkeypatch.context() as patch:
            patch.setattr(owner, name, value)
            with pytest.raises(AssertionError, match=name):
                intact(namespace)
    replaced = {**namespace, "hypotheses_needed": notebook_function("lambda *a: 1")}
    intact(replaced)  # a name the test does not rely on may be anything
    with pytest.raises(AssertionError, match="hypotheses_needed"):
        intact(replaced, ("hypotheses_needed",))
    intact(namespace, ("hypotheses_needed",))
    with pytest.raises(AssertionError, match="np"):
        intact({"np": types.ModuleType("numpy")})


def test_kernel_hooks_are_named_and_ordinary_answers_pass():
    transformer = (
        "get_ipython().input_transformers_cleanup.append(lambda lines: [])\n"
        "getattr(get_ipython(), 'set_custom_exc')((Exception,), None)\n"
    )
    assert kernel_hooks(transformer) == ["input_transformers_cleanup", "set_custom_exc"]
    assert kernel_hooks(
        "import os\nget_ipython().events.register('pre_run_cell', lambda *a: os._exit(0))"
    ) == [
        "register",
        "_exit",
    ]
    assert kernel_hooks("%timeit x = 1\nsys.settrace(None)") == ["settrace"]
    assert kernel_hooks("import builtins\nbuiltins.all = lambda *a: True") == ["builtins", "builtins"]
    assert kernel_hooks("get_ipython().showtraceback = print") == ["showtraceback"]
    answer = (
        "def hypotheses_for(e, p, s):\n    return math.ceil(math.log(1 - p) / math.log(1 - (1 - e) ** s))\n"
    )
    assert kernel_hooks(answer) == []


def guarded_execute():
    """The autograder's Execute preprocessor, as the course's nbgrader_config.py defines it."""
    import pathlib
    import runpy

    from traitlets.config import Config

    config = pathlib.Path(__file__).resolve().parents[1] / "coursework" / "nbgrader_config.py"
    return runpy.run_path(str(config), init_globals={"get_config": Config})["GuardedExecute"]


def graded_cell(source, grade_id, answer):
    import nbformat

    meta = {"grade_id": grade_id, "solution": answer, "grade": not answer, "locked": not answer}
    return nbformat.v4.new_code_cell(source, metadata={"nbgrader": meta})


def errors_of(cell):
    return [(o["ename"], o["evalue"]) for o in cell.outputs if o["output_type"] == "error"]


def run_guarded(cells, timeout=60):
    import nbformat

    nb = nbformat.v4.new_notebook(cells=cells)
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
    executor = guarded_execute()(timeout=timeout, kernel_name="python3")
    executor.preprocess(nb, {"metadata": {"path": "."}})
    return nb.cells


@pytest.mark.notebook
def test_the_autograder_refuses_kernel_hooks_and_stops_at_a_changed_kernel():
    """An answer that names a hook is not run (its test fails saying why); one that hides it is
    caught by comparing the kernel before and after, and no later test runs; others pass."""
    cells = run_guarded(
        [
            graded_cell("x = 1\nget_ipython().input_transformers_cleanup.append(lambda l: [])", "ex1", True),
            graded_cell("assert x == 1", "ex1_test", False),
            graded_cell("y = 2", "ex2", True),
            graded_cell("assert y == 2", "ex2_test", False),
            graded_cell(
                "z = 3\nimport vo_lib.grading as g\nfrozen = g.kernel_state()\n"
                "g.kernel_state = lambda: frozen  # the state it saw, whatever comes next\n"
                "getattr(get_ipython(), 'input_transformers' + '_post').append(lambda l: l)",
                "ex3",
                True,
            ),
            graded_cell("assert z == 3", "ex3_test", False),
        ]
    )
    assert [e[0] for e in errors_of(cells[0])] == ["KernelHook"]
    assert (
        errors_of(cells[1])[0][0] == "KernelHook"
        and "input_transformers_cleanup" in errors_of(cells[1])[0][1]
    )
    assert errors_of(cells[2]) == errors_of(cells[3]) == [], "an ordinary answer is graded as before"
    (kind, why), *_ = errors_of(cells[4])
    assert kind == "KernelHook" and '"ex3"' in why and "input transformers" in why
    assert errors_of(cells[5])[0][0] == "NotRun"


@pytest.mark.notebook
def test_a_test_that_lets_an_answer_replace_the_graders_tools_fails_and_no_later_test_runs():
    """An answer whose function, once a test calls it, replaces what the next hidden test loads
    its tools with (a reload that hands back a grader that refuses nothing): that test fails."""
    swap = (
        "import importlib, types\n"
        "def f():\n"
        "    fake = types.ModuleType('vo_lib.grading')\n"
        "    importlib.reload = lambda module: fake\n"
        "    return 1\n"
    )
    cells = run_guarded(
        [
            graded_cell(swap, "ex1", True),
            graded_cell("assert f() == 1", "ex1_test", False),
            graded_cell("y = 2", "ex2", True),
            graded_cell("assert y == 2", "ex2_test", False),
        ]
    )
    assert errors_of(cells[0]) == [], "defining the function changes nothing yet"
    (kind, why), *_ = errors_of(cells[1])
    assert kind == "KernelHook" and '"ex1_test"' in why and "the grader's tools" in why
    assert [e[0] for e in errors_of(cells[2])] == ["NotRun"] and errors_of(cells[3])[0][0] == "NotRun"


def test_the_graders_tools_are_found_replaced_wherever_they_are_loaded_from():
    import contextlib
    import importlib
    import runpy

    import vo_lib.grading

    def replaced():  # as the grader reads it: afresh from the file
        return runpy.run_path(vo_lib.grading.__file__)["_replaced_tools"]()

    assert replaced() == []
    reload, refused_now = importlib.reload, vo_lib.grading.refused
    try:
        importlib.reload = lambda module: module
        vo_lib.grading.refused = contextlib.contextmanager(lambda *targets: (yield))
        assert replaced() == ["importlib.reload", "vo_lib.grading.refused"]
    finally:
        importlib.reload, vo_lib.grading.refused = reload, refused_now
    assert replaced() == []


@pytest.mark.notebook
def test_a_dead_kernel_fails_every_later_cell_naming_the_cell_it_died_in():
    cells = run_guarded(
        [
            graded_cell("import os, signal\nos.kill(os.getpid(), signal.SIGKILL)", "ex1", True),
            graded_cell("assert True", "ex1_test", False),
        ]
    )
    assert errors_of(cells[0])[-1] == ("KernelDied", 'the kernel died in cell 1 "ex1" (import os, signal)')
    assert errors_of(cells[1]) == [("NotRun", 'not run: the kernel died in cell 1 "ex1" (import os, signal)')]


@pytest.mark.notebook
def test_a_timed_out_cell_is_named_and_the_notebook_goes_on():
    cells = run_guarded(
        [
            graded_cell("import time\ntime.sleep(60)", "ex1", True),
            graded_cell("assert 'time' in globals()", "ex1_test", False),
        ],
        timeout=3,
    )
    assert errors_of(cells[0])[-1] == (
        "CellTimeoutError",
        'cell 1 "ex1" (import time) was still running after 3 s and was stopped',
    )
    assert errors_of(cells[1]) == []


def test_the_adversarial_set_tampers_with_the_kernel_every_way_the_grader_guards_against():
    """coursework/submissions holds answers (kind "kernel_...") that hook into or end the kernel,
    which coursework/build.py --check requires to score 0."""
    import pathlib
    import re

    folder = pathlib.Path(__file__).resolve().parents[1] / "coursework" / "submissions"
    header = re.compile(r"^# %% (\S+) (kernel_\S*)[ \t]*\n", re.M)
    answers = [
        part for file in sorted(folder.glob("*.answers")) for part in header.split(file.read_text())[3::3]
    ]
    ways = {
        "an input transformer": r"input_transformers",
        "an event handler after every cell": r"register\(\"post_run_cell\"",
        "replaced built-ins": r"import builtins",
        "a trace function": r"sys\.settrace\(",
        "os._exit": r"os\._exit\(",
        "SystemExit": r"raise SystemExit",
        "a crash": r"ctypes\.string_at\(0\)",
        "a hook the code hides from a reader": r"getattr\(get_ipython\(\), \"input_transformers\" \+",
    }
    missing = [way for way, pattern in ways.items() if not any(re.search(pattern, a) for a in answers)]
    assert missing == [], missing
