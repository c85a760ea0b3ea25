"""Coursework: nbgrader's cell metadata in the jupytext sources, the student edition, the autograder.

The student edition of every notebook is generated once per session (``coursework/build.py``)
and searched for solution text. Autograding both ways (solutions score full marks; the
unanswered edition runs and fails only its exercises) executes notebooks, so it is done twice
for one small notebook under the ``course`` mark (``python -m pytest -m course``, outside the
default suite); ``.ci/run`` runs that and grades all of them, and then installs the handout in a
fresh environment from its requirements and checks that it holds all the notebooks need (minutes:
the suite skips it unless ``VO_NOTEBOOKS_HANDOUT`` names a built handout).
"""

from __future__ import annotations

import ast
import concurrent.futures
import importlib.util
import json
import os
import pathlib
import re
import shutil
import subprocess
import sys
import sysconfig
import venv
import zipfile

import jupytext
import nbformat
import pytest

from vo_lib.outputs import MARKER, OutputFolder

ROOT = pathlib.Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("[0-9][0-9]_*.py"))
AUTOGRADED_TWICE = ("03",)  # a small, quick notebook; coursework/build.py --check grades every one
DIFFICULTIES = ("easy", "medium", "hard")


def load_build():
    spec = importlib.util.spec_from_file_location("coursework_build", ROOT / "coursework" / "build.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


build = load_build()


def grading_cells(nb):
    return [c for c in nb.cells if "nbgrader" in c.metadata]


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_nbgrader_metadata_survives_the_round_trip(path):
    """.py -> notebook -> .py -> notebook and -> .ipynb keep every cell's nbgrader metadata."""
    nb = jupytext.read(path)
    again = jupytext.reads(jupytext.writes(nb, "py:percent"), "py:percent")
    ipynb = nbformat.reads(nbformat.writes(nb), as_version=4)
    expected = [c.metadata.get("nbgrader") for c in nb.cells]
    assert [c.metadata.get("nbgrader") for c in again.cells] == expected
    assert [c.metadata.get("nbgrader") for c in ipynb.cells] == expected
    assert any(expected), f"{path.name} has no nbgrader cells"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_exercises_are_graded_easy_to_hard(path):
    """Exercises last: each a heading with difficulty, points and a hint, its solution, its test."""
    cells = jupytext.read(path).cells
    start = max(i for i, c in enumerate(cells) if c.source.startswith("## Exercises"))
    assert all("nbgrader" not in c.metadata for c in cells[:start]), "the body carries no grading cells"
    headings = [c.source for c in cells[start:] if c.source.startswith("### Exercise")]
    levels = [next(d for d in DIFFICULTIES if f"*({d}," in h) for h in headings]
    assert len(headings) >= 2 and levels == sorted(levels, key=DIFFICULTIES.index), headings
    assert all("*Hint:*" in h for h in headings)
    heading, total = None, 0
    for i, cell in enumerate(cells[start:], start):
        meta = cell.metadata.get("nbgrader", {})
        if cell.source.startswith("### Exercise"):
            heading = cell.source.splitlines()[0]
        if cell.cell_type == "code" and meta.get("solution"):
            assert "### BEGIN SOLUTION" in cell.source and "### END SOLUTION" in cell.source
            test = cells[i + 1].metadata.get("nbgrader", {})
            assert test.get("grade_id") == meta["grade_id"] + "_test", (
                f"the test of {meta['grade_id']} follows it"
            )
        if cell.cell_type == "code" and meta.get("grade"):
            assert meta["locked"] and not meta["solution"]
            assert f"{meta['points']} point" in heading, f"{heading!r} must state {meta['points']} points"
            total += meta["points"]
    assert total >= 5


def build_coursework(out: pathlib.Path) -> pathlib.Path:
    proc = subprocess.run(
        [sys.executable, str(ROOT / "coursework" / "build.py"), "--out", str(out)],
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    return out


@pytest.fixture(scope="session")
def built(shared) -> pathlib.Path:
    return shared("coursework", build_coursework, folder=True)


def test_student_edition_holds_no_solution_text(built):
    released = sorted((built / "student").glob("*/*.ipynb"))
    assert [p.stem for p in released] == [p.stem for p in NOTEBOOKS]
    for path in NOTEBOOKS:
        source = jupytext.read(path)
        student = nbformat.read(built / "student" / path.stem / f"{path.stem}.ipynb", as_version=4)
        lines = build.solution_lines(source)
        assert len(lines) >= 5, f"{path.name}: too little solution text to check"
        assert build.leftover_solution_text(source, student) == []
        text = "\n".join(c.source for c in student.cells)
        assert "BEGIN SOLUTION" not in text and "BEGIN HIDDEN TESTS" not in text and "MARK SCHEME" not in text
        stubs = [c for c in student.cells if c.metadata.get("nbgrader", {}).get("solution")]
        assert stubs and all(
            "NotImplementedError" in c.source or "YOUR ANSWER HERE" in c.source for c in stubs
        )


def test_the_course_folder_lists_the_checkouts_solutions_for_the_kernels_to_find_empty(built, tmp_path):
    """This checkout's, and those of the checkout the kernels' vo_lib is installed from (an editable
    install of another checkout left its worked solutions readable). The kernels import it from
    outside this checkout, so it is asked of an interpreter started elsewhere, not of this one."""
    ask = [sys.executable, "-c", "import vo_lib; print(vo_lib.__file__)"]
    found = subprocess.run(ask, cwd=tmp_path, capture_output=True, text=True, check=True).stdout.strip()
    listed = (built / "grading" / "hidden.txt").read_text().splitlines()
    installed = pathlib.Path(found).resolve().parents[1]
    roots = {ROOT, installed} if (installed / "notebooks").is_dir() else {ROOT}
    assert set(listed) == {str(root / p) for root in roots for p in build.SOLUTION_FILES}
    assert {str(ROOT / "notebooks"), str(ROOT / ".git"), str(ROOT / "docs" / "_build")} <= set(listed)


def test_solution_lines_skip_text_shared_with_the_body():
    nb = nbformat.v4.new_notebook()
    nb.cells = [
        nbformat.v4.new_code_cell("print(x)\nanswer = 6 * 7"),
        nbformat.v4.new_code_cell("### BEGIN SOLUTION\nprint(x)\nanswer = 2 * 21\n### END SOLUTION"),
    ]
    assert build.solution_lines(nb) == {"answer = 2 * 21"}


def test_build_refuses_a_folder_it_did_not_write_or_that_changed(tmp_path):
    folder = tmp_path / "student"
    folder.mkdir()
    (folder / "notes.txt").write_text("mine")
    with pytest.raises(build.UsageError, match="it was not written by this program"):
        build.refuse_unless_replaceable(folder)
    folder.joinpath("notes.txt").unlink()
    with OutputFolder(folder, build.WRITTEN_BY) as out:  # as a build writes it
        (out.path / "notes.txt").write_text("mine")
        (out.path / "sub").mkdir()
        (out.path / "sub" / "a.ipynb").write_text("{}")
        out.commit()
    build.refuse_unless_replaceable(folder)  # unchanged: may be replaced
    (folder / "notes.txt").write_text("edited")
    with pytest.raises(build.UsageError, match="notes.txt was added, changed or removed"):
        build.refuse_unless_replaceable(folder)
    (folder / "notes.txt").write_text("mine")
    (folder / "sub" / "submitted.ipynb").write_text("{}")  # a submission copied in
    with pytest.raises(build.UsageError, match="sub/submitted.ipynb was added"):
        build.refuse_unless_replaceable(folder)


def test_a_rebuild_replaces_its_own_build_and_refuses_over_collected_submissions(built, tmp_path):
    for name in ("grading", "handout", "student"):  # a copy of the session's build, markers and all
        shutil.copytree(built / name, tmp_path / name)
    script = [sys.executable, str(ROOT / "coursework" / "build.py"), "03", "--out", str(tmp_path)]
    proc = subprocess.run(script, capture_output=True, text=True, timeout=600)  # replaces that build
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert [p.name for p in (tmp_path / "student").iterdir() if p.is_dir()] == [NOTEBOOKS[2].stem], "only 03"
    submitted = tmp_path / "grading" / "submitted" / "ada" / "03" / "03.ipynb"
    submitted.parent.mkdir(parents=True)
    submitted.write_text("{}")
    proc = subprocess.run(script, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 2 and len(proc.stderr.strip().splitlines()) == 1, proc.stderr
    assert "grading: the folder exists and submitted/ada/03/03.ipynb was added" in proc.stderr
    assert submitted.read_text() == "{}"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["grading", "handout", "student"]  # no temporary


def test_bad_arguments_exit_2_with_one_line(tmp_path, monkeypatch, capsys):
    proc = subprocess.run(  # the script itself, once; the other cases in this process
        [sys.executable, str(ROOT / "coursework" / "build.py"), "--bogus"], capture_output=True, text=True
    )
    assert proc.returncode == 2 and len(proc.stderr.strip().splitlines()) == 1, proc.stderr
    monkeypatch.setattr(build.signal, "signal", lambda *args: None)  # leave pytest's handlers alone
    for args in (["99"], ["--out", str(tmp_path / "missing")], ["--check", "99"], ["--repeat", "0"]):
        assert build.main(args) == 2, args
        err = capsys.readouterr().err
        assert len(err.strip().splitlines()) == 1 and err.startswith("coursework/build.py: "), (args, err)


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_every_exercise_has_adversarial_answers_and_seeded_hidden_tests(path):
    """Each autograded exercise: a constant, a library-calling (or why none) and a wrong answer
    in coursework/submissions, and a hidden test whose every draw comes from a fixed seed."""
    nb = jupytext.read(path)
    ids = build.answer_ids(nb)
    answers = build.read_submissions(path, ids)  # raises BuildError when a kind is missing
    assert list(answers) == ids
    tests = {c.metadata["nbgrader"]["grade_id"]: c.source for c in grading_cells(nb) if c.cell_type == "code"}
    for exercise in ids:
        hidden = "".join(m.group(1) for m in build.REGIONS[1].finditer(tests[f"{exercise}_test"]))
        assert re.search(r"default_rng\(\d+\)", hidden), f"{path.name} {exercise}: no seeded inputs"
        assert "default_rng()" not in hidden, f"{path.name} {exercise}: an unseeded draw changes a regrade"
        assert "vo_lib.grading" not in hidden and "intact(" not in hidden
    made = build.adversarial_notebooks(nbformat.v4.new_notebook(), answers)
    given = [(exercise, kind) for _, _, kinds in made for exercise, kind in kinds.items()]
    assert sorted(given) == sorted((e, k) for e, kinds in answers.items() for k in kinds), "each answer once"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_written_questions_stay_visible(path):
    """A written answer cell (replaced by nbgrader's stub) holds only the mark scheme; its question,
    with its points, is in the markdown cell before it, which the student edition keeps."""
    cells = jupytext.read(path).cells
    for i, cell in enumerate(cells):
        meta = cell.metadata.get("nbgrader", {})
        if cell.cell_type == "markdown" and meta.get("solution"):
            assert cell.source.startswith("=== BEGIN MARK SCHEME ==="), cell.source[:80]
            question = cells[i - 1]
            assert "nbgrader" not in question.metadata and f"{meta['points']} point" in question.source


def test_adversarial_answers_fill_the_release_one_kind_per_exercise():
    release = nbformat.v4.new_notebook()
    release.cells = [
        nbformat.v4.new_code_cell(
            "raise NotImplementedError()", metadata={"nbgrader": {"grade_id": e, "solution": True}}
        )
        for e in ("ex1", "ex2")
    ]
    answers = {"ex1": {"constant": "a = 1", "wrong_sign": "a = -2"}, "ex2": {"library": "b = f()"}}
    made = build.adversarial_notebooks(release, answers)
    assert [given for _, _, given in made] == [{"ex1": "constant"}, {"ex1": "wrong_sign", "ex2": "library"}]
    assert [c.source for c in made[1][1].cells] == ["a = -2", "b = f()"]
    assert release.cells[0].source == "raise NotImplementedError()", "the release itself is left alone"


@pytest.mark.parametrize(
    ("failures", "calls", "raises"),
    [
        (["Invalid Signature: b'f12a'"], 2, False),  # garbled once: run again, and it holds
        (["Invalid Signature: b'f12a'"] * 2, 2, True),  # garbled twice: the failure stands
        (["AssertionError: a test failed"], 1, True),  # anything else: never run again
    ],
)
def test_nbgrader_is_run_again_only_when_a_kernel_message_was_garbled(monkeypatch, failures, calls, raises):
    ran = []

    def fake_run(argv, **kwargs):
        ran.append(argv)
        failed = len(ran) <= len(failures)
        stderr = f"[AutogradeApp | ERROR] {failures[len(ran) - 1]}" if failed else ""
        return subprocess.CompletedProcess(argv, int(failed), "", stderr)

    monkeypatch.setattr(build.subprocess, "run", fake_run)
    if raises:
        with pytest.raises(build.BuildError, match="autograde failed"):
            build.run_nbgrader(ROOT, "autograde", "03")
    else:
        build.run_nbgrader(ROOT, "autograde", "03")
    assert len(ran) == calls


@pytest.mark.notebook
@pytest.mark.course
def test_autograder_scores_only_correct_answers_and_a_regrade_gives_identical_marks(built):
    """Solutions score every autograded point; the unanswered edition and every adversarial
    answer (constant, library-calling, wrong) score 0 per exercise. Hidden tests draw from fixed
    seeds: a second grading of every submission gives the same score table and the same reasons
    for each failure."""
    paths = [p for p in NOTEBOOKS if p.name[:2] in AUTOGRADED_TWICE]
    with concurrent.futures.ThreadPoolExecutor(2) as pool:  # two gradings side by side, each in a copy
        first, second = pool.map(lambda _: build.grade_once(built / "grading", paths), range(2))
    assert first[4] == [] and second[4] == [], first[4] + second[4]  # the problems found
    assert first[0] == second[0] and sorted(first[1]) == sorted(second[1])
    # table rows: "NN exK" and the points columns (the lines naming why an answer failed follow
    # the exercise's name with a colon)
    row = re.compile(rf"^(?:{'|'.join(p.name[:2] for p in paths)}) ex\w+\s{{2,}}\d")
    rows = [line for line in first[0] if row.match(line)]
    assert len(rows) == sum(len(build.answer_ids(jupytext.read(p))) for p in paths)


def test_handout_holds_notebooks_wheel_requirements_and_no_solution(built):
    handout = built / "handout"
    assert sorted(p.stem for p in (handout / "notebooks").glob("*.ipynb")) == [p.stem for p in NOTEBOOKS]
    wheels = list(handout.glob("vo_lib-*.whl"))
    assert len(wheels) == 1 and (handout / "START_HERE.md").is_file()
    requirements = (handout / "requirements.txt").read_text().splitlines()
    local = [line for line in requirements if line.startswith(("./", "-e"))]
    assert local == [f"./{wheels[0].name}[notebooks]"], "the wheel with the notebooks' extras, no other path"
    assert not any(line.startswith(("-e", "./jupyterlab-settings")) for line in requirements), requirements
    with zipfile.ZipFile(wheels[0]) as wheel:
        names = wheel.namelist()
    assert names and all(n.startswith(("vo_lib/", "vo_book/", "vo_lib-")) for n in names), "the packages only"
    assert "vo_book/widgets.py" in names, "the notebooks' helpers travel with the library"
    lines = set().union(*(build.solution_lines(jupytext.read(p)) for p in NOTEBOOKS))
    own = {line for line in lines if len(line) > 12} - build.library_lines()
    assert build.handout_leaks(handout, own) == []


def test_handout_leaks_finds_a_solution_line_and_a_marker(tmp_path):
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell("x = 1\nanswer = secret_formula(x)")]
    nbformat.write(nb, tmp_path / "a.ipynb")
    with zipfile.ZipFile(tmp_path / "vo_lib-0-py3-none-any.whl", "w") as wheel:
        wheel.writestr("vo_lib/m.py", "def f():\n    ### BEGIN HIDDEN TESTS\n    pass\n")
    leaks = build.handout_leaks(tmp_path, {"answer = secret_formula(x)"})
    assert leaks == [
        "a.ipynb: 'answer = secret_formula(x)'",
        "vo_lib-0-py3-none-any.whl/vo_lib/m.py: '### BEGIN HIDDEN TESTS'",
    ]


@pytest.mark.notebook
def test_handout_wheel_installs_in_a_fresh_venv_and_runs_a_student_notebook(built, tmp_path):
    """The wheel, not the repository, provides vo_lib; notebook 03's non-exercise cells run."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}  # not this checkout's vo_lib
    venv_dir = tmp_path / "venv"
    venv.create(venv_dir, with_pip=False)
    python = venv_dir / "bin" / "python"
    site = subprocess.run(
        [str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
        capture_output=True,
        text=True,
        check=True,
    ).stdout.strip()
    wheel = next((built / "handout").glob("vo_lib-*.whl"))
    subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "--python",
            str(python),
            "install",
            "--quiet",
            "--no-deps",
            "--no-index",
            str(wheel),
        ],
        check=True,
        capture_output=True,
        env=env,
    )
    # then the other requirements, from this environment (saves a download): vo_lib is already the wheel's
    pathlib.Path(site, "requirements_from_test_env.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    notebook = built / "handout" / "notebooks" / f"{NOTEBOOKS[2].stem}.ipynb"
    script = (
        "import sys, nbformat, vo_lib\n"
        f"assert vo_lib.__file__.startswith({str(venv_dir)!r}), vo_lib.__file__\n"
        f"nb = nbformat.read({str(notebook)!r}, as_version=4)\n"
        "namespace = {}\n"
        "for cell in nb.cells:\n"
        "    if cell.cell_type == 'code' and 'nbgrader' not in cell.metadata:\n"
        "        exec(compile(cell.source, 'cell', 'exec'), namespace)\n"
        "print('ran', vo_lib.__file__)\n"
    )
    proc = subprocess.run(
        [str(python), "-c", script],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        env={**env, "MPLBACKEND": "Agg"},
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert f"ran {venv_dir}" in proc.stdout


def test_a_folder_that_is_not_writable_or_a_damaged_marker_is_one_line_exit_2(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(build.os, "access", lambda path, mode: False)
    assert build.main(["--out", str(tmp_path)]) == 2
    assert capsys.readouterr().err.strip() == f"coursework/build.py: --out {tmp_path}: not writable"
    monkeypatch.undo()
    folder = tmp_path / "student"
    folder.mkdir()
    (folder / MARKER).write_text("{ not json")
    with pytest.raises(build.UsageError, match="is damaged"):
        build.refuse_unless_replaceable(folder)
    (folder / MARKER).write_text(json.dumps({"written_by": build.WRITTEN_BY, "contents": [], "files": 3}))
    with pytest.raises(build.UsageError, match="is damaged"):
        build.refuse_unless_replaceable(folder)


def test_offer_shows_no_widget_in_the_autograders_kernels(monkeypatch):
    """nbgrader's kernels have no browser: the config marks them headless and offer() does nothing."""
    from vo_book import widgets

    config = (ROOT / "coursework" / "nbgrader_config.py").read_text()
    assert f'os.environ["{widgets.HEADLESS_VARIABLE}"] = "1"' in config
    assert 'c.KernelManager.transport = "ipc"' in config and "allow_errors" not in config
    monkeypatch.setattr(widgets, "in_kernel", lambda: True)
    monkeypatch.setenv(widgets.HEADLESS_VARIABLE, "1")
    assert widgets.offer(lambda x: x, x=(0.0, 1.0)) is None


def test_course_page_states_the_points_the_notebooks_carry():
    points = sum(
        c.metadata["nbgrader"]["points"]
        for p in NOTEBOOKS
        for c in grading_cells(jupytext.read(p))
        if c.metadata["nbgrader"].get("grade")
    )
    by_hand = sum(
        c.metadata["nbgrader"]["points"]
        for p in NOTEBOOKS
        for c in grading_cells(jupytext.read(p))
        if c.metadata["nbgrader"].get("grade") and c.cell_type == "markdown"
    )
    course = (ROOT / "docs" / "course.md").read_text()
    assert f"{points} points in all" in course and by_hand == 2 and "one written point each" in course


HANDOUT_VARIABLE = "VO_NOTEBOOKS_HANDOUT"  # a built handout/ folder: .ci/run sets it


#: Student notebooks whose cells outside the exercises the installed handout runs: the first, and
#: the one that renders sample frames. The autograder check of .ci/run runs every notebook's cells
#: outside the exercises (its "unanswered" submissions); what only the handout can break (a file
#: missing from the wheel, a library missing from its requirements) is checked for every notebook.
HANDOUT_RUNS = ("01", "04")


@pytest.mark.notebook
def test_handout_installs_from_its_requirements_with_all_the_notebooks_need(tmp_path):
    """A fresh virtual environment, nothing but ``pip install -r requirements.txt`` in the handout
    (the wheel and the package index: no package of this environment, no checkout of this
    repository). Then, from it: every file of the packages is installed, every module of the
    packages and every library a student notebook imports is importable, and the cells outside the
    exercises of :data:`HANDOUT_RUNS` run, in one IPython.

    Minutes (the install): .ci/run runs it on the handout that ``coursework/build.py --check``
    wrote; the suite skips it unless the variable names one.
    """
    if not os.environ.get(HANDOUT_VARIABLE):
        pytest.skip(f"{HANDOUT_VARIABLE} names no built handout (.ci/run sets it after coursework/build.py)")
    source = pathlib.Path(os.environ[HANDOUT_VARIABLE]).resolve()
    assert (source / "requirements.txt").is_file(), f"{source} is not a handout"
    handout = tmp_path / "handout"  # a copy: the run leaves nothing in the teacher's folder
    shutil.copytree(source, handout)
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    venv_dir = tmp_path / "venv"
    venv.create(venv_dir, with_pip=True)
    python = str(venv_dir / "bin" / "python")
    install = subprocess.run(
        [python, "-m", "pip", "install", "--quiet", "-r", "requirements.txt"],
        cwd=handout,
        capture_output=True,
        text=True,
        env=env,
        timeout=1800,
    )
    assert install.returncode == 0, install.stderr[-3000:]
    notebooks = sorted((handout / "notebooks").glob("*.ipynb"))
    assert [p.stem for p in notebooks] == [p.stem for p in NOTEBOOKS]
    files = sorted(
        str(f.relative_to(ROOT))
        for package in build.PACKAGES
        for f in (ROOT / package).rglob("*")
        if f.is_file() and "__pycache__" not in f.parts
    )
    libraries = sorted(set().union(*(notebook_imports(p) for p in notebooks)))
    script = f"""
import importlib, pathlib, pkgutil, sys, nbformat, vo_lib
import matplotlib.pyplot as plt
from IPython.core.interactiveshell import InteractiveShell
site = pathlib.Path(vo_lib.__file__).parents[1]
assert str(site).startswith({str(venv_dir)!r}), vo_lib.__file__
missing = [f for f in {files!r} if not (site / f).is_file()]
assert not missing, f"not installed: {{missing}}"
for package in {list(build.PACKAGES)!r}:
    for module in pkgutil.walk_packages(importlib.import_module(package).__path__, package + "."):
        if not module.name.endswith("__main__"):
            importlib.import_module(module.name)
for library in {libraries!r}:
    importlib.import_module(library)
shell = InteractiveShell.instance()
for path in sorted(pathlib.Path(".").glob("*.ipynb")):  # run where Jupyter runs them
    if not path.name.startswith({HANDOUT_RUNS!r}):
        continue
    shell.reset(new_session=True)
    for index, cell in enumerate(nbformat.read(path, as_version=4).cells):
        if cell.cell_type == "code" and "nbgrader" not in cell.metadata:
            result = shell.run_cell(cell.source, silent=True)
            if not result.success:
                error = result.error_before_exec or result.error_in_exec
                sys.exit(f"{{path.name}}: cell {{index + 1}} failed: {{error!r}}")
    plt.close("all")
    print("ran", path.name, flush=True)
"""
    proc = subprocess.run(
        [python, "-c", script],
        capture_output=True,
        text=True,
        cwd=handout / "notebooks",
        env={**env, "MPLBACKEND": "Agg"},
        timeout=1800,
    )
    assert proc.returncode == 0, (proc.stdout[-1000:], proc.stderr[-3000:])
    assert [line.split()[1] for line in proc.stdout.splitlines() if line.startswith("ran ")] == [
        p.name for p in notebooks if p.name.startswith(HANDOUT_RUNS)
    ]


def notebook_imports(path: pathlib.Path) -> set[str]:
    """The top-level names of the modules a notebook's code cells import (IPython's ``%`` lines aside)."""
    names = set()
    for cell in nbformat.read(path, as_version=4).cells:
        if cell.cell_type != "code":
            continue
        lines = cell.source.splitlines()
        code = "\n".join(line for line in lines if not line.lstrip().startswith(("%", "!")))
        for node in ast.walk(ast.parse(code)):
            if isinstance(node, ast.Import):
                names |= {alias.name.split(".")[0] for alias in node.names}
            elif isinstance(node, ast.ImportFrom) and node.level == 0:
                names.add(node.module.split(".")[0])
    return names


def test_notebook_imports_reads_every_form_of_import(tmp_path):
    nb = nbformat.v4.new_notebook()
    nb.cells = [
        nbformat.v4.new_code_cell("%matplotlib inline\nimport numpy as np, sympy\nfrom vo_lib import K"),
        nbformat.v4.new_markdown_cell("import nothing"),
        nbformat.v4.new_code_cell("def f():\n    import ipywidgets.widgets"),
    ]
    nbformat.write(nb, tmp_path / "a.ipynb")
    assert notebook_imports(tmp_path / "a.ipynb") == {"numpy", "sympy", "vo_lib", "ipywidgets"}


def marked_lines(text: str, begin: str, end: str) -> int:
    """The non-blank lines between each ``### BEGIN ...`` marker and its ``### END ...``."""
    count, inside = 0, False
    for line in (s.strip() for s in text.splitlines()):
        inside = (inside or line.endswith(begin)) and not line.endswith(end)
        count += inside and bool(line) and not line.endswith(begin)
    return count


def test_grading_stays_in_proportion_to_what_it_grades():
    """Hidden tests take at most 1.27 lines per line of solution (1.25 until each compared the answer
    itself through grading.close or grading.equal, which take only plain numbers); the grading code
    beside the course (grading.py, autograde_steps.py and nbgrader_config.py) at most 520 lines (420
    until the report read every cell a student added or changed, not only the answer cells; 450 until
    the hidden tests compared arrays by grading.close, which an empty answer cannot pass; 475 until
    answers compared only as plain numbers and graded kernels kept no history on disk; 495 until it
    read modules reached as another module's attributes, the shell's hooks, a class's methods taken
    from the class and imported functions kept in objects and containers)."""
    texts = [p.read_text() for p in NOTEBOOKS]
    solution = sum(marked_lines(t, "BEGIN SOLUTION", "END SOLUTION") for t in texts)
    hidden = sum(marked_lines(t, "BEGIN HIDDEN TESTS", "END HIDDEN TESTS") for t in texts)
    assert (
        marked_lines(
            "a\n### BEGIN SOLUTION\nx = 1\n\ny = 2\n### END SOLUTION\nb", "BEGIN SOLUTION", "END SOLUTION"
        )
        == 2
    )
    assert 0 < hidden <= 1.27 * solution, (hidden, solution)
    tools = [*build.TOOLS, build.CONFIG]
    assert sum(len(p.read_text().splitlines()) for p in tools) <= 520
