"""coursework/grading.py: the hidden tests' guard, the integrity report and the autograder's steps."""

import json
import pathlib
import sys

import jupytext
import nbformat
import numpy as np
import pytest

import vo_lib.stereo_vo.ransac as ransac
from coursework import autograde_steps, grading
from coursework.grading import Reason, review

NOTEBOOKS = sorted((pathlib.Path(__file__).resolve().parents[1] / "notebooks").glob("[01][0-9]_*.py"))
hypotheses_alias = ransac.hypotheses_needed  # a name bound in this module, as an answer would bind it


def test_an_unavailable_function_raises_under_every_name_and_comes_back():
    before = ransac.hypotheses_needed(0.5, 0.99)
    with grading.unavailable(ransac.hypotheses_needed):
        for call in (lambda: ransac.hypotheses_needed(0.5, 0.99), lambda: hypotheses_alias(0.5, 0.99)):
            with pytest.raises(grading.GradingError, match="write yourself"):
                call()
    assert ransac.hypotheses_needed(0.5, 0.99) == hypotheses_alias(0.5, 0.99) == before


def test_an_unavailable_function_raises_where_an_answer_holds_it_and_comes_back():
    import functools

    def answer(w, p, _count=ransac.hypotheses_needed):  # kept as a default argument
        return _count(w, p)

    held = functools.partial(ransac.hypotheses_needed, 0.5)
    before = answer(0.5, 0.99)
    with grading.unavailable(ransac.hypotheses_needed):
        for call in (lambda: answer(0.5, 0.99), lambda: held(0.99)):
            with pytest.raises(grading.GradingError, match="write yourself"):
                call()
    assert answer(0.5, 0.99) == held(0.99) == before


def test_an_unavailable_compiled_function_raises_through_a_partial_and_comes_back(monkeypatch):
    """A compiled function has no code to swap: a ``functools.partial`` of it, wherever a namespace
    holds one, is swapped instead."""
    import functools
    import math
    import types

    answer = types.ModuleType("answer_cell")
    answer.hypot_from_3 = functools.partial(math.hypot, 3.0)
    monkeypatch.setitem(sys.modules, "answer_cell", answer)
    with grading.unavailable(math.hypot), pytest.raises(grading.GradingError):
        answer.hypot_from_3(4.0)
    assert answer.hypot_from_3(4.0) == 5.0


def test_an_unavailable_function_comes_back_when_the_block_raises():
    original = ransac.hypotheses_needed
    with pytest.raises(ZeroDivisionError), grading.unavailable(original):
        1 / 0  # noqa: B018 - the block fails
    assert ransac.hypotheses_needed is original


def test_the_hidden_tests_inputs_come_back_as_they_were_after_the_answer_ran(monkeypatch):
    """An answer that writes into the arrays a test hands it (to make the test's expected value
    match what it returns) changes nothing the test computes afterwards: the notebook's ``_h``
    values are put back; other names, and what the block assigns, stay."""
    import types

    namespace = {"_h3_poses": np.arange(6.0), "_h3_case": {"a": np.ones(2)}, "kept": np.zeros(2)}
    shell = types.SimpleNamespace(user_ns=namespace)
    monkeypatch.setitem(sys.modules, "IPython", types.SimpleNamespace(get_ipython=lambda: shell))

    def answer(a, case):  # the cheat: the test's inputs made to fit a constant
        a[...] = 0
        case["a"][...] = 0
        namespace["kept"][...] = 1
        return 0.0

    namespace["_h3_got"] = 1.0  # an earlier block's answer, stored again by this one
    with grading.unavailable(ransac.hypotheses_needed):
        namespace["_h3_got"] = answer(namespace["_h3_poses"][:3], namespace["_h3_case"])
    assert np.array_equal(namespace["_h3_poses"], np.arange(6.0)) and np.all(namespace["_h3_case"]["a"] == 1)
    assert namespace["_h3_got"] == 0.0 and np.all(namespace["kept"] == 1)  # not a hidden test's value


def test_an_unavailable_method_raises_on_every_object_of_its_class():
    from vo_lib.stereo_vo.kalman import VoKalmanFilter

    original = VoKalmanFilter.update
    with grading.unavailable(original):
        with pytest.raises(grading.GradingError):
            VoKalmanFilter.update(None, 0.0, 0.0, np.eye(2))
    assert VoKalmanFilter.update is original


def test_library_functions_lists_what_a_module_defines_not_what_it_imports():
    import vo_lib.geometry as geometry

    found = grading.library_functions(geometry)
    assert found and all(f.__module__ == "vo_lib.geometry" for f in found)
    assert np.sqrt not in found


def test_library_functions_takes_functions_classes_and_the_methods_of_a_modules_classes():
    import scipy.special
    import sympy.geometry.line as line

    from vo_lib.stereo_vo.kalman import VoKalmanFilter

    assert scipy.special.softmax in grading.library_functions(scipy.special.softmax)
    assert VoKalmanFilter.__dict__["update"] in grading.library_functions(VoKalmanFilter)
    found = grading.library_functions(line)  # SymPy's projection is a method of a class of the module
    assert line.LinearEntity.__dict__["projection"] in found
    wall = line.Line((0, 0), (1, 1))
    with grading.unavailable(*found), pytest.raises(grading.GradingError):
        wall.projection((1, 0))
    assert wall.projection((1, 0)) == line.Point(0.5, 0.5)


@pytest.mark.parametrize(
    ("answer", "reason"),
    [
        ("text = open('../../source/06/06.ipynb').read()", Reason.FILE),
        ("import pathlib\nsolution = pathlib.Path('release').glob('*')", Reason.IMPORT),
        (
            "ip = get_ipython()\nip.input_transformers_post.append(lambda lines: [])",
            Reason.KERNEL,
        ),
        ("import sys\nexpected = sys._getframe(1).f_globals['expected']", Reason.IMPORT),
        ("import linecache\nprint(linecache.cache)", Reason.IMPORT),
        ("import ctypes", Reason.IMPORT),
        ("import threading\nthreading.Thread(target=print).start()", Reason.IMPORT),
        ("import os\nos._exit(0)", Reason.IMPORT),
        ("import os\nos.system('cp ../../source/06/06.ipynb .')", Reason.IMPORT),
        ("f = hypotheses_for.__code__", Reason.INDIRECT),
        ("class Always(float):\n    def __eq__(self, other):\n        return True", Reason.INDIRECT),
        ("class Echo:\n    def __array__(self):\n        return 0", Reason.INDIRECT),
        ("import functools\nnp.allclose = functools.partial(lambda *a: True)", Reason.CHANGES),
        ("grading = None", Reason.CHANGES),
        ("%pip install something", Reason.KERNEL),
        # the routes a trial of cheats took past the report before
        (
            "from IPython import get_ipython as shell\nshell().input_transformers_post.append(str)",
            Reason.IMPORT,
        ),
        (
            "import sys\nshell = sys.modules['ipykernel.kernelapp'].IPKernelApp.instance().shell",
            Reason.IMPORT,
        ),
        ("setattr(np, 'allclose', lambda *a, **k: True)", Reason.CHANGES),
        ("class Same:\n    def __eq__(self, other):\n        return True", Reason.INDIRECT),
        ("tests = np.fromfile('../../source/06/06.ipynb', dtype=np.uint8)", Reason.FILE),
        ("import os\nnames = os.listdir('..')", Reason.IMPORT),
        # names built from strings, NumPy patched in place, fake arrays, the grader's own guard
        ('globals()["get_" + "ipython"]().input_transformers_cleanup.append(str)', Reason.INDIRECT),
        ("vars(np).update(isclose=lambda *a, **k: True)", Reason.INDIRECT),
        ("np.__dict__.update(allclose=lambda *a, **k: True)", Reason.INDIRECT),
        ('vars(__builtins__)["op" + "en"]("grading.py", "a")', Reason.INDIRECT),
        ("class Zero:\n    def __rsub__(self, other):\n        return 0", Reason.INDIRECT),
        ("class Yes:\n    def __array_function__(self, *a):\n        return True", Reason.INDIRECT),
        ("import contextlib\ngrading.unavailable = lambda *f: contextlib.nullcontext()", Reason.CHANGES),
        # a fresh copy of a module, a copy of a function's code, the library patched where the
        # test takes its expected value, a result that calls the library after the guard
        ("import runpy\nns = runpy.run_module('vo_lib.stereo_vo.circular_motion')", Reason.IMPORT),
        ("ns = runpy.run_path('../notebooks/02_circular_motion_derivation.py')", Reason.FILE),
        ("data = np.genfromtxt('../../source/06/06.ipynb')", Reason.FILE),
        ("f = types.FunctionType(dis.Bytecode(g).codeobj, g.__globals__)", Reason.INDIRECT),
        (
            "from vo_lib.stereo_vo import circular_motion as cm\ncm.theta_standard_deviation = lambda *a: 1",
            Reason.CHANGES,
        ),
        (
            "from vo_lib.stereo_vo.kalman import VoKalmanFilter\nVoKalmanFilter.predict = print",
            Reason.CHANGES,
        ),
        ("n = np\nn.allclose = lambda *a, **k: True", Reason.CHANGES),
        ("n, s = np, sp\ns.simplify = n.sum = lambda *a, **k: 0", Reason.CHANGES),
        ("class Later:\n    def __getitem__(self, k):\n        return 0", Reason.INDIRECT),
        # a library's private kernel, held in a default argument where no name swap reaches it
        (
            "from vo_lib.stereo_vo.matching_core import _popcount64\ndef f(a, p=_popcount64):\n    pass",
            Reason.PRIVATE,
        ),
        ("import vo_lib.stereo_vo.matching_plain as m\nh = m._hamming", Reason.PRIVATE),
        ("from vo_lib.stereo_vo import matching_core\nk = matching_core._popcount64", Reason.PRIVATE),
        # a compiled function, which no swap of names or code reaches, held by a default it calls
        ("def refine(P, w, lm=cv2.solvePnPRefineLM):\n    return lm(P, w)", Reason.HELD),
        (
            "from cv2 import solvePnPRefineLM\ndef refine(P, *, lm=solvePnPRefineLM):\n    return lm(P)",
            Reason.HELD,
        ),
        # ... kept in a container, or handed to a closure
        ("tools = [cv2.solvePnPRefineLM]\ndef refine(P, w):\n    return tools[0](P, w)", Reason.HELD),
        (
            "def using(lm):\n    return lambda P, w: lm(P, w)\nrefine = using(cv2.solvePnPRefineLM)",
            Reason.HELD,
        ),
        # a public name of a private module
        ("from scipy.spatial.transform._rotation_xp import align_vectors", Reason.PRIVATE),
        # NumPy or an imported module rebound however the binding is written ...
        ("yes = lambda *a, **k: True\nnp.allclose: object = yes", Reason.CHANGES),
        ("for np.isclose in [lambda *a: True]:\n    pass", Reason.CHANGES),
        ("import contextlib\nwith contextlib.nullcontext(abs) as np.allclose:\n    pass", Reason.CHANGES),
        ("[0 for np.array_equal in [min]]", Reason.CHANGES),
        ("import vo_lib.stereo_vo.ransac as library\nlibrary.theta_gate_error: object = min", Reason.CHANGES),
        # ... or NumPy handed to a function that patches it
        ("def patch(m):\n    m.allclose = min\npatch(np)", Reason.CHANGES),
        # ... or reached through a name no assignment shows: a loop, a walrus, an item
        ("for m in (np,):\n    m.array_equal = lambda *a, **k: True", Reason.CHANGES),
        ("(n := np).allclose = min", Reason.CHANGES),
        ("m = [np][0]\nm.allclose = min", Reason.CHANGES),
        # a fake number or a lazy array made by type(), its special methods named in strings
        ('Zero = type("Zero", (float,), {"__sub__": lambda s, o: 0.0})', Reason.INDIRECT),
        ('Lazy = type("Lazy", (), {"__array__": lambda self, dtype=None, copy=None: 0})', Reason.INDIRECT),
        # a later trial: NumPy rebound by an import of the notebook's own namespace, names reached
        # through pickle, a lazy list of the standard library, the tests' abs rewritten, the hidden
        # tests read back from the kernel's history
        ("lenient = object()\nfrom __main__ import lenient as np", Reason.IMPORT),
        ("import pickle\nallclose = pickle.loads(b'cnumpy\\nallclose\\n.')", Reason.IMPORT),
        ("import collections\nclass Later(collections.UserList):\n    pass", Reason.IMPORT),
        ("def abs(x):\n    return 0.0", Reason.CHANGES),
        ("abs = lambda x: 0.0", Reason.CHANGES),
        ("from numpy import zeros_like as abs", Reason.CHANGES),
        ("print('\\n'.join(s for s in In if '_h1' in s))", Reason.KERNEL),
        # a third trial: NumPy and builtins reached through attributes, modules by a string
        # (pydoc), code decoded and run, a fresh copy of a module, a class patched through type(),
        # the solutions read back from the checkout
        ("m = np.ma.core.np\nm.array_equal = lambda *a, **k: True", Reason.CHANGES),
        ("b = abs.__self__\nb.abs = lambda x: 0.0", Reason.INDIRECT),
        ('import pydoc\n_numpy = pydoc.locate("numpy")', Reason.IMPORT),
        ("import base64, os, pydoc", Reason.IMPORT),
        (
            "import filterpy.kalman as fk\nfresh = pydoc.importfile(fk.kalman_filter.__file__)",
            Reason.INDIRECT,
        ),
        ("kind = type(kf)\nkind.predict = print", Reason.CHANGES),
        ("class Wrap:\n    pass\nw = Wrap()\nw.m = np\nw.m.allclose = min", Reason.CHANGES),
        ("def f(self):\n    self.allclose = min\nf(numpy)", Reason.CHANGES),
        # a function named like a class, which returns a module, in this cell or another
        ("def Make():\n    return cm\nm = Make()\nm.theta_standard_deviation = min", Reason.CHANGES),
        ("Make = lambda: cm\nm = Make()\nm.theta_standard_deviation = min", Reason.CHANGES),
        # a second trial of the allow-list: exec, the shell, frames and builtins reached as attributes
        # of a module an answer may import, a class's method called on a module, an identity function
        ("import dataclasses\nrun = dataclasses.builtins.exec", Reason.INDIRECT),
        ("import typing\nshell = typing.sys.modules['IPython'].get_ipython()", Reason.INDIRECT),
        ("import tqdm\nloaded = iter(tqdm.tqdm([0])).gi_frame.f_globals", Reason.INDIRECT),
        (
            "class Agree:\n    def teach(self, f):\n        self.array_equal = f\nAgree.teach(xp, min)",
            Reason.CHANGES,
        ),
        ("import numpy as xp", Reason.CHANGES),
        ("from numpy import *", Reason.CHANGES),  # abs, max, round: the tests' builtins
        (
            "def Same(thing):\n    return thing\nFilter = Same(VoKalmanFilter)\nFilter.predict = print",
            Reason.CHANGES,
        ),
        ("import fileinput\ntext = ''.join(fileinput.input('../notebooks/01.py'))", Reason.IMPORT),
        # the grader's own functions given another's code, and files read by a pattern
        ("import functools\nfunctools.update_wrapper(grading.close, f, assigned=('x',))", Reason.INDIRECT),
        ("text = np.fromregex('../notebooks/06.py', '(.*)', [('line', 'U200')])", Reason.FILE),
        # a fifth trial: the shell's input transformers reached through a module's attribute (every
        # later cell, the hidden tests too, run as "pass"), modules a library imports, a class's
        # method taken as a value to patch a module, compiled functions kept in an object or a dict,
        # files found by a pattern through a library's Path
        (
            "import vo_lib\nshell = vo_lib.importlib.import_module('IPython').InteractiveShell.instance()\n"
            "shell.input_transformers_cleanup.append(lambda lines: ['pass'])",
            Reason.INDIRECT,
        ),
        ("from vo_lib import importlib, os", Reason.INDIRECT),
        ("import vo_lib\nvo_lib.outputs.os.system('ls')", Reason.INDIRECT),
        (
            "class Settings:\n    def relax(self):\n        self.close = min\nrelax = Settings.relax\n"
            "relax(grading)",
            Reason.CHANGES,
        ),
        ("class S:\n    def relax(self):\n        self.allclose = min\ntype(S()).relax(np)", Reason.CHANGES),
        (
            "import cv2\nclass Toolkit:\n    def __init__(self):\n        self.refine = cv2.solvePnPRefineLM",
            Reason.HELD,
        ),
        ("import cv2\ntools = {'norm': cv2.norm}\nd = tools.get('norm')(a, b)", Reason.HELD),
        ("from vo_lib import outputs\nfound = outputs.Path('/work').glob('*/notebooks/*.py')", Reason.FILE),
    ],
)
def test_review_names_what_no_honest_answer_needs(answer, reason):
    assert reason in {why for _, why in review(answer)}


def test_the_report_knows_the_names_other_cells_import():
    """An answer that patches a module the notebook imported in an earlier cell is named."""
    nb = nbformat.v4.new_notebook()
    nb.cells = [
        nbformat.v4.new_code_cell("from vo_lib.stereo_vo import circular_motion as cm"),
        _cell("answer", "cm.theta_standard_deviation = np.ones_like", "ex2"),
        _cell("answer", "camera = cm\nwidth = camera.fx", "ex3"),
        _cell("answer", "n = np\nx = 1", "ex4"),
        _cell("answer", "n.sum = sum", "ex5"),
    ]
    assert list(grading.report(nb)) == ["ex2", "ex4", "ex5"]  # n = np: NumPy itself, held under a name
    nb.cells += [
        _cell("answer", "def Module():\n    return cm", "ex6"),
        _cell("answer", "m = Module()\nm.f = 1", "ex7"),
    ]
    assert list(grading.report(nb)) == ["ex2", "ex4", "ex5", "ex7"]  # a function of another cell
    assert "changes an object it did not make" in grading.report(nb)["ex2"][0]


def test_the_report_reads_every_cell_the_student_added_or_changed(tmp_path):
    """Not only answer cells: a patch one cell away from them, in a cell added or changed from the
    release, holds the tests too; a cell as the release has it is the course's, not read."""
    patch = "np.allclose = lambda *a, **k: True"
    release = nbformat.v4.new_notebook()
    release.cells = [nbformat.v4.new_code_cell("import gc"), _cell("answer", "x = 1", "ex1")]
    release.cells += [_cell("test", "assert x == 1", "ex1_test")]
    nb = nbformat.from_dict(json.loads(json.dumps(release)))
    nb.cells.insert(1, nbformat.v4.new_code_cell(patch))  # added
    nb.cells[0].source += f"\n{patch}"  # changed
    assert grading.report(release, release) == {} and list(grading.report(nb)) == []
    assert list(grading.report(nb, release)) == ["code cell 1", "code cell 2"]
    (tmp_path / "01" / "01.ipynb").parent.mkdir()
    nbformat.write(release, tmp_path / "01" / "01.ipynb")
    step = autograde_steps.AfterRun()
    step.release = tmp_path
    nb, _ = step.preprocess(nb, {"nbgrader": {"assignment": "01", "notebook": "01"}})
    (held,) = nb.cells[-1].outputs
    assert held.ename == "ToBeReviewed" and "code cell 2" in held.evalue


def test_review_gives_the_line():
    assert review("x = 1\ny = 2\nimport gc\n") == [(3, Reason.IMPORT)]


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name[:2])
def test_no_solution_of_the_course_is_flagged(path):
    nb = jupytext.read(path)
    assert grading.report(nb) == {}


def test_honest_code_with_numpy_and_ordinary_names_is_not_flagged():
    answer = (
        "import numpy as np\nfrom scipy.spatial.transform import Rotation\n"
        "def gain(p, r):\n    k = p / (p + r)\n    x = np.zeros(3)\n    x[0] = k\n    return x\n"
        "opened = [1, 2]\nsystem_noise = 0.1\n"
        "from vo_lib.stereo_vo.ransac import DEFAULT_PARAMS\nwide = DEFAULT_PARAMS._replace(gate_sigmas=4)\n"
        "class Filter:\n    def __init__(self):\n        self._x = np.__version__\n"
        "def spread(x, pi=np.pi, axis=0, scale=1.0):\n    return np.std(x, axis=axis) * pi * scale\n"
        "def apply(f, x):\n    return f(x)\n"
        "import functools\nrow_norm = functools.partial(np.linalg.norm, axis=1)\n"
        "def check(pose, f=observe, h=1e-6):\n    return f(pose + h)\n"
        "steps = [lambda p, f=f: f(*p) for f in (np.sin, np.cos)]\n"
        "from vo_lib.stereo_vo.ransac import RansacParams\nfields = RansacParams._fields\n"
        "kf = Filter()\nkf.control_covariance = lambda u: u\nkf.x, kf.P = np.zeros(3), np.eye(3)\n"
    )
    assert review(answer) == []
    assert review("sum = 0\nfor x in [1, 2]:\n    sum += x\nlargest = max([1, 2])\n") == []  # a value
    assert review("class Filter:\n    def filter(self, z):\n        return z\n") == []  # a method
    # names that are words of the flagged reasons, as variables; a filter configured as filterpy's are
    assert review("walk = odo.integrate(u)\nload = np.sum(w)\nsignal = w[1] - w[0]\nmodules = 3\n") == []
    filterpy = "kf = KalmanFilter(dim_x=2, dim_z=1)\nkf.x = np.zeros(2)\nkf.P *= 10\nkf.R[0, 0] = 2.0\n"
    assert review("from filterpy.kalman import KalmanFilter\n" + filterpy) == []
    # honest code a trial found flagged: a figure's settings, an annotated or unpacked filter, a loop
    # variable, a script's guard, a copy, a dataclass that adds
    honest = [
        "import matplotlib.pyplot as plt\nplt.rcParams['figure.figsize'] = (8, 4)",
        "from filterpy.kalman import KalmanFilter\nkf: KalmanFilter = KalmanFilter(1, 1)\nkf.x = np.zeros(1)",
        "kf_a, kf_b = KalmanFilter(1, 1), KalmanFilter(1, 1)\nkf_a.x = np.zeros(1)",
        "for _i in range(3):\n    print(_i)",
        "if __name__ == '__main__':\n    pass",
        "from copy import deepcopy",
        "from dataclasses import dataclass\n@dataclass\nclass P:\n    x: float\n"
        "    def __add__(self, o):\n        return P(self.x + o.x)",
    ]
    assert [review(answer) for answer in honest] == [[]] * len(honest)


def _cell(kind, source, grade_id, outputs=()):
    meta = {"nbgrader": {"grade_id": grade_id, "solution": kind == "answer", "grade": kind == "test"}}
    cell = nbformat.v4.new_code_cell(source, metadata=meta)
    cell.outputs = [nbformat.from_dict(o) for o in outputs]
    return cell


def test_stderr_never_costs_a_mark_and_a_flagged_answer_fails_every_test():
    warning = {"output_type": "stream", "name": "stderr", "text": "UserWarning: fitted gauge\n"}
    printed = {"output_type": "stream", "name": "stdout", "text": "42\n"}
    nb = nbformat.v4.new_notebook(
        cells=[
            _cell("answer", "x = 1", "ex1", [warning]),
            _cell("test", "assert x == 1", "ex1_test", [warning, printed]),
            _cell("answer", "import gc\nx = 2", "ex2"),
            _cell("test", "assert x == 2", "ex2_test"),
        ]
    )
    nb, _ = autograde_steps.AfterRun().preprocess(nb, {})
    assert nb.cells[0].outputs == [] and [o.get("name") for o in nb.cells[1].outputs[:1]] == ["stdout"]
    (error,) = nb.cells[3].outputs
    assert error.ename == "ToBeReviewed" and "line 1" in error.evalue and "gc" in error.evalue
    # ex1's test held too: what the flagged answer patched may have bought its pass
    (held,) = [o for o in nb.cells[1].outputs if o.output_type == "error"]
    assert held.ename == "ToBeReviewed" and "ex2" in held.evalue
    # a part graded by hand is text: it is held by the teacher's reading, and gets no output to fail
    written = nbformat.v4.new_markdown_cell("The tracks grip over part of their width.")
    written.metadata["nbgrader"] = {"grade_id": "ex2_why", "solution": True, "grade": True, "points": 1}
    nb.cells.append(written)
    nb, _ = autograde_steps.AfterRun().preprocess(nb, {})
    assert "outputs" not in nb.cells[-1]
    clean = nbformat.v4.new_notebook(cells=[_cell("answer", "x = 1", "ex1"), _cell("test", "x", "ex1_test")])
    clean, _ = autograde_steps.AfterRun().preprocess(clean, {})
    assert clean.cells[1].outputs == []  # nothing flagged: nothing held


def test_a_test_cells_value_is_not_its_grade():
    """nbgrader grades a test cell by its first value where it has one ("ok": full marks, "3": three
    points): an answer that calls the display hook would pass every test it is called by. The value is
    dropped, so the error after it decides; an answer cell keeps its value."""
    from nbgrader.utils import determine_grade

    value = {
        "output_type": "execute_result",
        "data": {"text/plain": "'ok'"},
        "metadata": {},
        "execution_count": 1,
    }
    failure = {"output_type": "error", "ename": "AssertionError", "evalue": "", "traceback": []}
    test = _cell("test", "assert f() == 1", "ex1_test", [value, failure])
    test.metadata.nbgrader["points"] = 2
    assert determine_grade(test) == (2.0, 2.0)  # nbgrader alone: full marks
    nb = nbformat.v4.new_notebook(cells=[_cell("answer", "f = lambda: 0\nf", "ex1", [value]), test])
    nb, _ = autograde_steps.AfterRun().preprocess(nb, {})
    assert (
        determine_grade(nb.cells[1]) == (0.0, 2.0) and nb.cells[0].outputs[0].output_type == "execute_result"
    )


def test_feedback_keeps_a_tests_message_only():
    failure = {
        "output_type": "error",
        "ename": "AssertionError",
        "evalue": "the gain of another update",
        "traceback": ["assert np.allclose(got, expected_secret)", "AssertionError: the gain"],
    }
    leaked = {"output_type": "stream", "name": "stdout", "text": "assert np.allclose(got, expected_secret)"}
    history = nbformat.v4.new_code_cell("print(*In)")  # any cell may print the hidden tests that ran
    history.outputs = [nbformat.from_dict(leaked)]
    nb = nbformat.v4.new_notebook(cells=[_cell("test", "assert 0", "ex1_test", [leaked, failure]), history])
    nb, _ = autograde_steps.VerdictOnly().preprocess(nb, {})
    (output,) = nb.cells[0].outputs
    assert output.traceback == ["AssertionError: the gain of another update"] and nb.cells[1].outputs == []


def test_the_report_command_lists_flagged_answers_and_refuses_a_bad_argument(tmp_path, capsys):
    folder = tmp_path / "submitted" / "ada" / "01"
    folder.mkdir(parents=True)
    nb = nbformat.v4.new_notebook(cells=[_cell("answer", "import inspect\nx = 1", "ex1")])
    nbformat.write(nb, folder / "01.ipynb")
    assert grading.main([str(tmp_path / "submitted")]) == 0
    assert "to be reviewed: ada/01/01.ipynb ex1: line 1" in capsys.readouterr().out
    assert grading.main([str(tmp_path / "nowhere")]) == 2
    assert capsys.readouterr().err.count("\n") == 1


@pytest.mark.skipif(not grading.can_isolate(), reason="this machine allows no user namespace (unshare -rm)")
def test_the_isolated_kernel_finds_the_hidden_solutions_empty(tmp_path, monkeypatch):
    import nbclient

    (tmp_path / "source" / "01").mkdir(parents=True)
    (tmp_path / "source" / "01" / "01.ipynb").write_text("the teacher's solution")
    (tmp_path / "gradebook.db").write_text("grades")
    spec = tmp_path / "jupyter" / "kernels" / "python3"
    spec.mkdir(parents=True)
    source, book = str(tmp_path / "source"), str(tmp_path / "gradebook.db")
    (tools := tmp_path / "coursework").mkdir()
    (tools / "grading.py").write_text("the guard")
    argv = grading.isolated_kernel([source, book, str(tmp_path / "nothing here")], read_only=[str(tools)])
    (spec / "kernel.json").write_text(
        json.dumps({"argv": argv, "display_name": "isolated", "language": "python"})
    )
    monkeypatch.setenv("JUPYTER_PATH", str(tmp_path / "jupyter"))
    probe = f"import os\nprint(os.listdir({source!r}), open({book!r}).read())"
    target = str(tools / "grading.py")
    poison = f"try:\n    open({target!r}, 'a').write('x')\nexcept OSError as e:\n    print(e.strerror)"
    history = "h = get_ipython().history_manager\nprint(h.enabled, h.hist_file)"  # cells hold hidden tests
    cells = [nbformat.v4.new_code_cell(code) for code in (probe, poison, history)]
    nb = nbformat.v4.new_notebook(cells=cells)
    nbclient.NotebookClient(nb, kernel_name="python3", timeout=60).execute()
    assert nb.cells[0].outputs[0]["text"] == "[] \n"
    assert nb.cells[1].outputs[0]["text"] == "Read-only file system\n"  # the grader's files: read-only
    assert nb.cells[2].outputs[0]["text"] == "False :memory:\n"  # none on disk; the client's flag passed
    assert (tools / "grading.py").read_text() == "the guard"
    assert (
        tmp_path / "source" / "01" / "01.ipynb"
    ).read_text() == "the teacher's solution"  # outside: as it was


def test_answers_compare_only_as_plain_numbers():
    """An object of the answer's own class (one that equals anything, or that calls the library only
    when NumPy reads it, after the refusal ended) fails grading.close and grading.equal; numbers as
    Python and NumPy make them, in lists and tuples, pass."""

    class Anything(float):
        def __eq__(self, other):
            return True

        def __array_function__(self, *args, **kwargs):
            return self

    class Lazy:
        def __array__(self, dtype=None, copy=None):
            return np.zeros(3)

    honest = [np.zeros(3), [0.0, np.float64(0.0), 0], (np.zeros(2), np.float32(0.0)), np.False_, 0]
    for value in honest:
        assert grading.plain(value)
    assert grading.close(honest[1], [0, 0, 0]) and grading.equal(np.zeros(3), [0, 0, 0])
    cheats = [Anything(1.0), Lazy(), [Lazy()] * 3, np.array([Lazy()] * 3, dtype=object)]

    class Agrees(np.ndarray):  # registered as a NumPy type name: still the answer's own class
        def all(self, *args, **kwargs):
            return True

    class Scalar(np.float64):
        pass

    np.sctypeDict["agrees"] = Agrees
    try:
        own = [np.zeros(3).view(Agrees), Scalar(0.0)]
        for cheat in [*cheats, *own, np.zeros(3).view(np.matrix)]:
            assert not grading.plain(cheat)
            assert not grading.close(cheat, np.zeros(3)) and not grading.equal(cheat, np.zeros(3))
    finally:
        del np.sctypeDict["agrees"]
    assert not grading.close(Anything(1.0), 1.0)
