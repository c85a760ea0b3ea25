"""vo_lib.grading: refused functions stay refused by every route, and are restored afterwards."""

import inspect
import threading
import types

import numpy as np
import pytest

import vo_lib.stereo_vo.ransac as ransac
import vo_lib.stereo_vo.ransac_core as ransac_core
from vo_lib.camera import StereoCamera
from vo_lib.grading import intact, kernel_hooks, refused

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
        lambda: ransac_core.hypotheses_needed,
        lambda: in_thread(copied()),
    ],
    ids=["captured", "function-copy", "exec-source", "compiled-twin", "thread"],
)
def test_every_route_to_a_refused_function_fails_and_is_restored(route):
    function = route()
    expected = int(ransac.hypotheses_needed(0.5, 0.99))
    with pytest.raises((AssertionError, TypeError, IndexError)):
        with refused(ransac.hypotheses_needed, ransac_core.hypotheses_needed):
            function(0.5, 0.99)
    assert (
        int(ransac.hypotheses_needed(0.5, 0.99)) == expected == int(ransac_core.hypotheses_needed(0.5, 0.99))
    )
    assert int(function(0.5, 0.99)) == expected


def test_a_method_is_refused_and_other_code_runs():
    with refused(StereoCamera.backproject):
        assert np.sqrt(4.0) == 2.0
        with pytest.raises(AssertionError):
            CAMERA.backproject(PIXELS)
    assert CAMERA.backproject(PIXELS).shape == (2, 3)


def test_switching_the_watch_off_fails():
    with pytest.raises(AssertionError, match="switched off"):
        with refused(ransac.hypotheses_needed):
            import sys

            sys.setprofile(None)


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
    answer = (
        "def hypotheses_for(e, p, s):\n    return math.ceil(math.log(1 - p) / math.log(1 - (1 - e) ** s))\n"
    )
    assert kernel_hooks(answer) == []
