"""Write the student edition of the notebooks, and the nbgrader course folder that grades it.

    python coursework/build.py [NN ...] [--out DIR] [--check [NN ...]] [--repeat N]

The jupytext sources in ``notebooks/`` carry nbgrader's cell metadata: solution cells (code
between ``### BEGIN SOLUTION`` and ``### END SOLUTION``) and locked autograder test cells. This
script converts them to ``.ipynb`` in a course folder and lets ``nbgrader generate_assignment``
strip the solutions, one assignment per notebook. It writes, under ``--out`` (default: the
repository):

- ``student/NN_topic/NN_topic.ipynb``: the release, without solutions or hidden tests;
- ``grading/``: nbgrader's course folder (``source/`` with solutions and tests, ``release/``,
  ``gradebook.db``, ``nbgrader_config.py``), where ``nbgrader autograde`` grades submissions.

Each is built under a temporary name beside its destination and renamed when complete, under the
output rules of ``vo_lib.outputs``. A destination is replaced only if it holds exactly the files
an earlier build wrote (its marker ``.vo_lib_output.json`` lists them with their checksums), so
submissions copied into ``grading/`` or notebooks a student edited in ``student/`` are never
overwritten.

``--check`` then autogrades, in a temporary copy of the course folder, the solutions (every test
must pass, with every answer also writing to stderr), the unanswered student edition and the
adversarial answers of ``submissions/`` (every exercise must score zero, while every cell outside
the exercises runs without error; an answer of kind ``flagged`` must be named "to be reviewed" by
the integrity report of ``coursework/grading.py``, which reads it without running it, and no
other answer may be). It prints the integrity report, the score table and the seconds each
submission took, and fails if one took longer than 1.5 times its notebook's own run time (its
solutions, graded in the same run) plus 30 s; ``--repeat N`` grades the whole set N times over.
Two notebooks are graded at a time, and the kernels share one store of rendered sample frames
(see :func:`shared_frame_store`).
"""

from __future__ import annotations

import argparse
import concurrent.futures
import contextlib
import html as html_module
import json
import os
import pathlib
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import unittest.mock
import zipfile

import jupytext
import nbformat

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # this checkout's vo_lib, whatever copy is installed
from coursework.grading import report  # noqa: E402
from vo_lib.arguments import OneLineParser  # noqa: E402
from vo_lib.outputs import (  # noqa: E402
    OutputError,
    OutputFolder,
    check_target,
)

NOTEBOOK_DIR = ROOT / "notebooks"
NOTEBOOK_GLOB = "[0-9][0-9]_*.py"
CONFIG = pathlib.Path(__file__).with_name("nbgrader_config.py")
STUDENT_DIR, GRADING_DIR, HANDOUT_DIR = "student", "grading", "handout"
WRITTEN_BY = "python coursework/build.py"
#: What the handout's wheel is built from, copied apart so that a stale ``build/`` folder of the
#: checkout cannot slip modules that no longer exist into it.
PACKAGES = ("vo_lib", "vo_book")
WHEEL_SOURCES = ("pyproject.toml", "README.md", *PACKAGES)
CACHES = shutil.ignore_patterns("__pycache__", "*.pyc")
SUBMISSIONS_DIR = pathlib.Path(__file__).with_name("submissions")
ADVERSARIAL_KINDS = ("constant", "library", "wrong")  # and "unanswered": the release itself
FLAGGED_KIND = "flagged"  # answers the integrity report must name: optional, any exercise
#: The course's tools beside nbgrader_config.py: the hidden tests' guard, the autograder's steps.
TOOLS = tuple(pathlib.Path(__file__).with_name(name) for name in ("grading.py", "autograde_steps.py"))
# what the autograder's kernels may not read, beside the course folder's own solutions: the
# notebooks, the trial answers, the mark scheme, the history and the reading edition (its worked
# solutions are folded away, not left out) of this checkout and of the one the installed vo_lib
# comes from (an editable install of another); listed in the course folder's hidden.txt
SOLUTION_FILES = ("notebooks", "coursework/submissions", "coursework/answer_key.md", ".git", "docs/_build")
HIDDEN_LIST = "hidden.txt"
# a line that opens a solution, hidden tests or a mark scheme (not a mention of one in prose)
MARKER_LINE = re.compile(
    r"^\s*(### BEGIN SOLUTION|### BEGIN HIDDEN TESTS|=== BEGIN MARK SCHEME ===)\s*$", re.M
)
ANSWER_HEADER = re.compile(r"^# %% (\S+) (\S+)[ \t]*\n", re.M)  # "# %% ex1 wrong_sign" opens an answer
SCORE_COLUMNS = ("correct", "unanswered", *ADVERSARIAL_KINDS, FLAGGED_KIND)
SOLUTIONS_STUDENT, UNANSWERED_STUDENT = "solutions", "unanswered"
REGIONS = [  # nbgrader's markers: solution code, and tests kept from the student edition
    re.compile(rf"^\s*### BEGIN {what}\s*$(.*?)^\s*### END {what}\s*$", re.M | re.S)
    for what in ("SOLUTION", "HIDDEN TESTS")
]
EXIT_FAILED, EXIT_USAGE = 1, 2
START_HERE = """# Start here

These are the student notebooks of the vo-notebooks course, without their solutions.

1. Make a virtual environment and install the requirements (they include `vo_lib`, the
   course's package, as the wheel `{wheel}` in this folder):

       python -m venv .venv && . .venv/bin/activate
       python -m pip install -r requirements.txt

2. Start Jupyter in this folder (`jupyter lab`) and open `notebooks/01_crawler_odometry.ipynb`.
3. Each notebook ends with exercises: write your answer in the cell under each one and run the
   test cell after it. The grader also runs tests you do not see, on inputs of its own.
"""


class UsageError(Exception):
    """Bad input: reported in one line, exit status 2."""


class BuildError(Exception):
    """nbgrader failed, or a check found a problem: exit status 1."""


def notebook_paths(numbers: list[str] | None = None) -> list[pathlib.Path]:
    """The notebooks' jupytext sources, all of them or those whose two-digit number is given."""
    paths = sorted(NOTEBOOK_DIR.glob(NOTEBOOK_GLOB))
    if not numbers:
        return paths
    by_number = {p.name[:2]: p for p in paths}
    unknown = [n for n in numbers if n.zfill(2) not in by_number]
    if unknown:
        raise UsageError(f"no notebook numbered {unknown[0]!r}: expected one of {', '.join(by_number)}")
    return [by_number[n.zfill(2)] for n in numbers]


def solution_lines(nb: nbformat.NotebookNode) -> set[str]:
    """Lines of solution text in ``nb`` that a student edition must not contain.

    Every line of a solution region or of a hidden-test region, and every line of a written
    (markdown) solution cell, stripped; lines that also occur elsewhere in the notebook (a blank,
    an ``else:``, a print shared with the body) are left out, since finding them proves nothing.
    """
    hidden: list[str] = []
    for cell in nb.cells:
        meta = cell.metadata.get("nbgrader", {})
        if cell.cell_type == "markdown" and meta.get("solution"):
            hidden.append(cell.source)
            continue
        for pattern in REGIONS:
            hidden.extend(m.group(1) for m in pattern.finditer(cell.source))
    visible = "\n".join(cell.source for cell in nb.cells)
    for text in hidden:
        visible = visible.replace(text, "\n")
    elsewhere = {line.strip() for line in visible.splitlines()}
    return {
        line.strip() for text in hidden for line in text.splitlines() if line.strip() not in elsewhere
    } - {""}


def leftover_solution_text(source: nbformat.NotebookNode, student: nbformat.NotebookNode) -> list[str]:
    """Solution lines of ``source`` still present in the student edition ``student``."""
    released = {line.strip() for cell in student.cells for line in cell.source.splitlines()}
    return sorted(solution_lines(source) & released)


#: What nbgrader may fail on that says nothing of the notebooks: a kernel's message garbled on its
#: way (jupyter_client's check of its signature). The command is run once more, saying so.
TRANSPORT_FAILURES = ("Invalid Signature",)


def run_nbgrader(course: pathlib.Path, *args: str) -> None:
    """Run one nbgrader command in the course folder ``course``; raise BuildError if it fails."""
    for attempt in (1, 2):
        proc = subprocess.run(
            [sys.executable, "-m", "nbgrader", *args],
            cwd=course,
            capture_output=True,
            text=True,
            env=dict(os.environ, MPLBACKEND="Agg"),
        )
        garbled = [f for f in TRANSPORT_FAILURES if f in proc.stderr]
        if proc.returncode == 0 or not garbled or attempt == 2:
            break
        print(f"nbgrader {args[0]}: {garbled[0]} (a kernel's message garbled): run again", file=sys.stderr)
    errors = [line for line in proc.stderr.splitlines() if "| ERROR]" in line or "Error" in line]
    if "Exception while loading config file" in proc.stderr:  # nbgrader goes on without it
        raise BuildError(f"nbgrader {args[0]}: the course's nbgrader_config.py does not load: {errors[-1:]}")
    if proc.returncode != 0:
        raise BuildError(f"nbgrader {args[0]} failed: " + " / ".join(errors[-3:] or [proc.stderr[-500:]]))


def kernels_checkout(course: pathlib.Path) -> pathlib.Path | None:
    """The folder holding the ``vo_lib`` that the graded kernels import, as a fresh interpreter in
    ``course`` finds it (this process finds this checkout's first); None where none is installed."""
    ask = [sys.executable, "-c", "import vo_lib; print(vo_lib.__file__)"]
    proc = subprocess.run(ask, cwd=course, capture_output=True, text=True, check=False)
    return pathlib.Path(proc.stdout.strip()).resolve().parents[1] if proc.returncode == 0 else None


def write_course(course: pathlib.Path, paths: list[pathlib.Path]) -> None:
    """Fill ``course`` (an empty folder) with nbgrader's course layout and generate the release."""
    shutil.copy2(CONFIG, course / "nbgrader_config.py")
    installed = kernels_checkout(course)
    roots = dict.fromkeys([ROOT, *([installed] if installed and (installed / "notebooks").is_dir() else [])])
    (course / HIDDEN_LIST).write_text(
        "".join(f"{root / path}\n" for root in roots for path in SOLUTION_FILES)
    )
    (course / "coursework").mkdir()
    for tool in TOOLS:
        shutil.copy2(tool, course / "coursework" / tool.name)
    for path in paths:
        folder = course / "source" / path.stem
        folder.mkdir(parents=True)
        nbformat.write(jupytext.read(path), folder / f"{path.stem}.ipynb")
    run_nbgrader(course, "generate_assignment", "*", "--force")
    for path in paths:
        source = nbformat.read(course / "source" / path.stem / f"{path.stem}.ipynb", as_version=4)
        student = nbformat.read(course / "release" / path.stem / f"{path.stem}.ipynb", as_version=4)
        left = leftover_solution_text(source, student)
        if left:
            raise BuildError(f"{path.name}: the student edition still holds solution text: {left[0]!r}")


def refuse_unless_replaceable(dest: pathlib.Path) -> None:
    """Raise UsageError unless ``dest`` is absent or holds exactly what an earlier build wrote."""
    try:
        check_target(dest, written_by=WRITTEN_BY)
    except OutputError as exc:
        raise UsageError(str(exc)) from None


def exercise_cell(cell: nbformat.NotebookNode) -> bool:
    """True for nbgrader's solution and autograder cells: the ones an unanswered exercise may fail."""
    meta = cell.metadata.get("nbgrader", {})
    return bool(meta.get("solution") or meta.get("grade"))


def answer_ids(nb: nbformat.NotebookNode) -> list[str]:
    """grade_id of every autograded exercise: a code solution cell followed by its test cell."""
    return [
        c.metadata["nbgrader"]["grade_id"]
        for c in nb.cells
        if c.cell_type == "code" and c.metadata.get("nbgrader", {}).get("solution")
    ]


def read_submissions(path: pathlib.Path, ids: list[str]) -> dict[str, dict[str, str]]:
    """The adversarial answers of notebook ``path``: ``{exercise: {kind: code}}``, checked complete.

    Every autograded exercise needs each of ``ADVERSARIAL_KINDS``; an exercise with no ``vo_lib``
    function to call says why under ``no_library`` instead of giving a library-calling answer.
    """
    file = SUBMISSIONS_DIR / f"{path.stem}.answers"
    if not file.is_file():
        raise BuildError(f"{path.name}: no adversarial submissions ({file.relative_to(ROOT)} is missing)")
    answers: dict[str, dict[str, str]] = {}
    parts = ANSWER_HEADER.split(file.read_text())
    for exercise, kind, code in zip(parts[1::3], parts[2::3], parts[3::3], strict=True):
        if kind in answers.setdefault(exercise, {}):
            raise BuildError(f"{file.name}: {exercise} {kind} is given twice")
        answers[exercise][kind] = code
    problems = sorted(set(answers) ^ set(ids))
    if problems:
        raise BuildError(f"{file.name}: exercises {problems} do not match the notebook's {ids}")
    for exercise, kinds in answers.items():
        for kind in ADVERSARIAL_KINDS:
            if not any(k == kind or k.startswith(kind + "_") for k in kinds):
                if not (kind == "library" and "no_library" in kinds):
                    raise BuildError(f"{file.name}: [{exercise}] has no {kind!r} answer")
        kinds.pop("no_library", None)
    return answers


WARNING_WRAPPER = """
import functools as _functools
import warnings as _warnings

_quiet_{name} = {name}


@_functools.wraps(_quiet_{name})
def {name}(*args, **kwargs):
    _warnings.warn("a correct answer that warns at every call", UserWarning, stacklevel=2)
    return _quiet_{name}(*args, **kwargs)
"""


def stderr_answer(solution: str) -> str:
    """The solution ``solution`` (its markers taken out) writing to stderr, there and in its tests.

    It warns once, and its first function is wrapped in one that warns at every call, so the test
    cell writes to stderr too; a correct answer must still score full marks.
    """
    code = "\n".join(
        line
        for line in solution.splitlines()
        if line.strip() not in ("### BEGIN SOLUTION", "### END SOLUTION")
    )
    code += '\nimport warnings as _warnings\n\n_warnings.warn("progress 100%", UserWarning, stacklevel=1)\n'
    defined = re.search(r"^def (\w+)\(", code, re.M)
    return code + (WARNING_WRAPPER.format(name=defined.group(1)) if defined else "")


def adversarial_notebooks(
    release: nbformat.NotebookNode, answers: dict[str, dict[str, str]], name: str = "adversarial"
) -> list[tuple[str, nbformat.NotebookNode, dict[str, str]]]:
    """The release with its answer cells filled in, as few notebooks as cover every answer.

    Submission ``j`` gives exercise ``i`` its answer number ``(i + j) mod n``, ``n`` the largest
    number of answers of any exercise; an exercise with fewer is left unanswered in the others.
    Returns ``(student name, notebook, {exercise: kind})`` for each, the students named ``name``
    and a number.
    """
    ids = list(answers)
    count = max((len(kinds) for kinds in answers.values()), default=0)
    made = []
    for j in range(count):
        nb = nbformat.from_dict(json.loads(json.dumps(release)))
        given = {}
        for i, exercise in enumerate(ids):
            kinds = list(answers[exercise])
            k = (i + j) % count
            if k < len(kinds):
                given[exercise] = kinds[k]
        for cell in nb.cells:
            exercise = cell.metadata.get("nbgrader", {}).get("grade_id")
            if cell.cell_type == "code" and exercise in given:
                cell.source = answers[exercise][given[exercise]].strip("\n")
        made.append((f"{name}{j + 1}", nb, given))
    return made


def exercise_scores(sub, ids: list[str]) -> dict[str, tuple[float, float]]:
    """Autograded (score, maximum) of each exercise of one graded submission notebook."""
    scores = {}
    for exercise in ids:
        tests = [g for g in sub.grades if g.name == f"{exercise}_test" and g.auto_score is not None]
        scores[exercise] = (sum(g.auto_score for g in tests), sum(g.max_score for g in tests))
    return scores


def feedback_leaks(course: pathlib.Path, path: pathlib.Path, student: str) -> list[str]:
    """Generate ``student``'s feedback on notebook ``path``; return the hidden-test lines it shows."""
    run_nbgrader(course, "generate_feedback", path.stem, f"--student={student}", "--force")
    html = (course / "feedback" / student / path.stem / f"{path.stem}.html").read_text()
    source = nbformat.read(course / "source" / path.stem / f"{path.stem}.ipynb", as_version=4)
    hidden = {
        line.strip()
        for cell in source.cells
        for m in REGIONS[1].finditer(cell.source)
        for line in m.group(1).splitlines()
        if len(line.strip()) > 20 and not line.strip().startswith("#")
    }
    shown = {line.strip() for line in re.sub(r"<[^>]+>", "", html_module.unescape(html)).splitlines()}
    # a line the student wrote in their own answer (the same call as a test's) is theirs to see
    submitted = nbformat.read(course / "submitted" / student / path.stem / f"{path.stem}.ipynb", as_version=4)
    own = {line.strip() for cell in submitted.cells for line in cell.source.splitlines()}
    return sorted((hidden - own) & shown)


def check(course: pathlib.Path, paths: list[pathlib.Path], repeat: int = 1) -> list[str]:
    """Autograde the solutions, the unanswered edition and the adversarial answers of ``paths``.

    In a copy of ``course``, ``repeat`` times over: the solutions must score every autograded
    point, and so must every ``correct_*`` answer of ``coursework/submissions/``; every other
    submission (unanswered, constant or truth-copying, library-calling, plausibly wrong) must score
    0 in each exercise, while cells outside the exercises run without error; every flagged answer
    must be named by the integrity report (read, not run), and no other; and no submission may
    take longer than :data:`SLACK_FACTOR` times the solutions of its notebook (the notebook's own
    run time, measured in the same repetition) plus :data:`SLACK_SECONDS`. Returns the score
    table (one line per exercise), why each adversarial answer failed, the integrity report
    (answers to be reviewed), and the seconds each submission took; raises BuildError naming
    every problem found.
    """
    problems: list[str] = []
    times: dict[tuple[str, str], list[float]] = {}
    with shared_frame_store():  # one store for every repetition: the frames are the same
        for repetition in range(repeat):
            rows, reasons, events, took, found = grade_once(course, paths)
            problems += [f"repetition {repetition + 1}: {p}" if repeat > 1 else p for p in found]
            for key, seconds in took.items():
                times.setdefault(key, []).append(seconds)
    timing = [
        f"seconds per submission (autograde, nbgrader's start included), against the notebook's own "
        f"run time (its solutions, graded in the same repetition) x {SLACK_FACTOR:g} + {SLACK_SECONDS:g} s:"
    ]
    for (number, student), seconds in times.items():
        limits = [SLACK_FACTOR * own + SLACK_SECONDS for own in times[(number, SOLUTIONS_STUDENT)]]
        over = [f"{t:.1f} s > {limit:.1f} s" for t, limit in zip(seconds, limits, strict=True) if t > limit]
        shown = " ".join(f"{t:6.1f}" for t in seconds)
        timing.append(f"{number} {student:<14} {shown}   limit {' '.join(f'{x:.1f}' for x in limits)}")
        if over and student != SOLUTIONS_STUDENT:
            problems.append(
                f"{number} {student}: took longer than its notebook's run time with slack: {over[0]}"
            )
    report = rows + reasons + events + timing
    if problems:
        raise BuildError("\n".join(report + problems))
    return report


#: A submission may take its notebook's own run time times SLACK_FACTOR plus SLACK_SECONDS: a
#: loop that never ends is caught, a machine that is busier for one submission than for the
#: solutions is not (on a loaded 2-core machine a correct answer took up to 1.25 times as long).
SLACK_FACTOR, SLACK_SECONDS = 1.5, 30.0
FRAME_STORE, STARTUP = "VO_LIB_FRAME_STORE", ROOT / "tests" / "startup"


@contextlib.contextmanager
def shared_frame_store():
    """Let every kernel started inside share one store of rendered frames (``vo_lib.sim.frame_store``).

    A sample that a notebook runs is then rendered by its first submission and read back by the
    others: the same images, bit for bit, without rendering them a dozen times over.
    ``tests/startup/sitecustomize.py`` (put on the kernels' ``PYTHONPATH``) points the store at the
    folder named by ``VO_LIB_FRAME_STORE``; a test session that set one already keeps its own.
    """
    if os.environ.get(FRAME_STORE):
        yield
        return
    with tempfile.TemporaryDirectory(prefix="vo-coursework-frames-") as folder:
        path = os.pathsep.join(filter(None, [str(STARTUP), os.environ.get("PYTHONPATH")]))
        with unittest.mock.patch.dict(os.environ, {FRAME_STORE: folder, "PYTHONPATH": path}):
            yield


def grade_once(
    course: pathlib.Path, paths: list[pathlib.Path]
) -> tuple[list[str], list[str], list[str], dict[tuple[str, str], float], list[str]]:
    """One autograding of every submission of ``paths``, :data:`GRADERS` notebooks at a time.

    Each notebook is graded in a copy of ``course`` of its own, so the gradebooks of notebooks
    graded side by side never meet, and its submissions run one after another, so its solutions'
    run time (its submissions' limit) is measured beside the same neighbours as they are. The
    heaviest notebooks start first. Returns the score table, why each adversarial answer failed,
    the integrity report, the seconds of each ``(notebook number, student)`` and the problems found.
    """
    rows = [f"{'exercise':<40} {'points':>6}  " + "  ".join(f"{k:>10}" for k in SCORE_COLUMNS)]
    reasons = ["why each adversarial answer failed:"]
    events = ["to be reviewed (the integrity report):"]
    times: dict[tuple[str, str], float] = {}
    problems: list[str] = []
    order = sorted(paths, key=lambda p: -GRADING_WEIGHT.get(p.stem[:2], 1))
    with concurrent.futures.ThreadPoolExecutor(GRADERS) as pool:  # each thread waits on nbgrader
        graded = dict(zip(order, pool.map(lambda p: grade_notebook(course, p), order), strict=True))
    for path in paths:  # reported in notebook order, whatever finished first
        part = graded[path]
        rows += part[0]
        reasons += part[1]
        events += part[2]
        times.update(part[3])
        problems += part[4]
    return rows, reasons, events, times, problems


#: Notebooks graded side by side (two cores: one kernel each), and the notebooks that take longest
#: to run (seconds of a solutions run, roughly), started first so that none is left alone at the end.
GRADERS = 2
GRADING_WEIGHT = {"08": 100, "09": 45, "10": 35, "07": 15, "12": 15, "04": 13, "06": 12}


def grade_notebook(
    course: pathlib.Path, path: pathlib.Path
) -> tuple[list[str], list[str], list[str], dict[tuple[str, str], float], list[str]]:
    """Autograde every submission of notebook ``path`` in a copy of ``course`` of its own.

    Returns its rows of the score table, why each adversarial answer failed, its integrity report,
    the seconds of each ``(notebook number, student)`` and the problems found.
    """
    from nbgrader.api import Gradebook  # only the check needs nbgrader's database layer

    problems: list[str] = []
    rows: list[str] = []
    reasons: list[str] = []
    events: list[str] = []
    times: dict[tuple[str, str], float] = {}
    with tempfile.TemporaryDirectory(prefix="vo-coursework-check-") as tmp:
        work = pathlib.Path(tmp) / "course"
        shutil.copytree(course, work)
        name = f"{path.stem}.ipynb"
        source = nbformat.read(work / "source" / path.stem / name, as_version=4)
        release = nbformat.read(work / "release" / path.stem / name, as_version=4)
        ids = answer_ids(source)
        # the solutions, every answer also writing to stderr (a warning where it runs and at each
        # call of its function, its tests' calls included): they must still score every point
        solutions = nbformat.from_dict(json.loads(json.dumps(source)))
        for cell in solutions.cells:
            if cell.cell_type == "code" and cell.metadata.get("nbgrader", {}).get("grade_id") in ids:
                cell.source = stderr_answer(cell.source)
        subs = [(SOLUTIONS_STUDENT, solutions, dict.fromkeys(ids, "correct"))]
        subs.append((UNANSWERED_STUDENT, release, dict.fromkeys(ids, "unanswered")))
        answers = read_submissions(path, ids)
        table: dict[str, dict[str, list]] = {exercise: {} for exercise in ids}
        kinds_of = {  # flagged answers apart: they are read, not run (below)
            flagged: {
                exercise: {k: a for k, a in kinds.items() if k.startswith(FLAGGED_KIND) == flagged}
                for exercise, kinds in answers.items()
            }
            for flagged in (False, True)
        }
        subs += adversarial_notebooks(release, kinds_of[False])
        reviewed = adversarial_notebooks(release, kinds_of[True], FLAGGED_KIND)
        # the integrity report reads each answer's text; for a flagged answer the report alone
        # fails its test (autograde_steps.AfterRun, tests/test_grading.py), so running it proves nothing more
        for student, nb, given in subs + reviewed:
            flagged = report(nb)
            events += [f"{path.stem[:2]} {student} {e}: " + "; ".join(w) for e, w in flagged.items()]
            for exercise, kind in given.items():
                if (exercise in flagged) != kind.startswith(FLAGGED_KIND):
                    problems.append(
                        f"{path.name} {exercise}: the {kind} answer ({student}) is "
                        + ("flagged" if exercise in flagged else "not flagged")
                    )
        for _, _, given in reviewed:
            for exercise in given:
                table[exercise].setdefault(FLAGGED_KIND, []).append("rev")
        for student, nb, _ in subs:
            folder = work / "submitted" / student / path.stem
            folder.mkdir(parents=True)
            nbformat.write(nb, folder / name)
            started = time.monotonic()
            run_nbgrader(work, "autograde", path.stem, f"--student={student}", "--force")
            times[(path.stem[:2], student)] = time.monotonic() - started
        with Gradebook(f"sqlite:///{work / 'gradebook.db'}") as gradebook:
            top = {}
            for student, _, given in subs:
                sub = gradebook.find_submission_notebook(path.stem, path.stem, student)
                graded = nbformat.read(
                    work / "autograded" / student / path.stem / f"{path.stem}.ipynb", as_version=4
                )
                for index, cell in enumerate(graded.cells):
                    errors = [o for o in cell.get("outputs", []) if o.get("output_type") == "error"]
                    grade_id = cell.metadata.get("nbgrader", {}).get("grade_id", "")
                    test_of = grade_id.removesuffix("_test") if grade_id.endswith("_test") else ""
                    if errors and not given.get(test_of, "correct").startswith(("correct", "unanswered")):
                        why = f"{errors[0]['ename']}: {errors[0]['evalue']}".splitlines()[0][:90]
                        reasons.append(f"{path.stem[:2]} {test_of} {given[test_of]}: {why}")
                    if errors and (student == SOLUTIONS_STUDENT or not exercise_cell(cell)):
                        head = cell.source[:60]
                        problems.append(f"{path.name} ({student}): cell {index} fails: {head!r}")
                for exercise, (got, most) in exercise_scores(sub, ids).items():
                    top[exercise] = most
                    if exercise not in given:
                        continue
                    kind = given[exercise]
                    table[exercise].setdefault(kind.split("_")[0], []).append(got)
                    if most == 0:
                        problems.append(f"{path.name}: {exercise} has no autograded points")
                    elif (got != most) if kind.startswith("correct") else (got != 0):
                        problems.append(
                            f"{path.name} {exercise}: the {kind} answer ({student}) "
                            f"scores {got:g} of {most:g}"
                        )
            leaked = feedback_leaks(work, path, subs[-1][0])
            if leaked:
                problems.append(f"{path.name}: the feedback shows hidden test text: {leaked[0]!r}")
            for exercise in ids:
                cells = [
                    "/".join(g if isinstance(g, str) else f"{g:g}" for g in table[exercise][k])
                    if k in table[exercise]
                    else "-"
                    for k in SCORE_COLUMNS
                ]
                label = f"{path.stem[:2]} {exercise}"
                rows.append(f"{label:<40} {top[exercise]:>6g}  " + "  ".join(f"{c:>10}" for c in cells))
    return rows, reasons, events, times, problems


def write_handout(folder: pathlib.Path, course: pathlib.Path, paths: list[pathlib.Path]) -> None:
    """Fill ``folder`` with what a teacher gives out, and refuse if any of it holds solution text.

    ``notebooks/NN_topic.ipynb`` (the student edition), ``vo_lib`` with the notebooks' helpers
    ``vo_book`` as one wheel (the packages only: no notebook sources), ``requirements.txt`` (what
    the notebooks need: see :func:`handout_requirements`) and ``START_HERE.md``.
    """
    (folder / "notebooks").mkdir()
    for path in paths:
        shutil.copy2(course / "release" / path.stem / f"{path.stem}.ipynb", folder / "notebooks")
    with tempfile.TemporaryDirectory() as source:  # only what the wheel is made of: no stale build/
        for name in WHEEL_SOURCES:
            if (ROOT / name).is_dir():
                shutil.copytree(ROOT / name, pathlib.Path(source) / name, ignore=CACHES)
            else:
                shutil.copy2(ROOT / name, source)
        proc = subprocess.run(
            [sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "--wheel-dir", str(folder), source],
            capture_output=True,
            text=True,
        )
    wheels = sorted(folder.glob("vo_lib-*.whl"))
    if proc.returncode != 0 or len(wheels) != 1:
        raise BuildError(
            "the vo_lib wheel could not be built: " + (proc.stderr.strip().splitlines() or ["?"])[-1]
        )
    (folder / "requirements.txt").write_text(handout_requirements(wheels[0].name))
    (folder / "START_HERE.md").write_text(START_HERE.format(wheel=wheels[0].name))
    lines = set()
    for path in paths:
        lines |= solution_lines(
            nbformat.read(course / "source" / path.stem / f"{path.stem}.ipynb", as_version=4)
        )
    # a line the packages themselves have (a generic "cases.append(") proves nothing about the wheel
    leaks = handout_leaks(folder, {line for line in lines - library_lines() if len(line) > 12})
    if leaks:
        raise BuildError(f"the handout holds solution text: {leaks[0]}")


def library_lines() -> set[str]:
    """Every stripped line of the packages the wheel holds (:data:`PACKAGES`)."""
    files = [f for name in PACKAGES for f in (ROOT / name).rglob("*.py")]
    return {line.strip() for f in files for line in f.read_text().splitlines()}


def handout_requirements(wheel: str) -> str:
    """The handout's ``requirements.txt``: ``requirements-student.txt`` with the wheel for the package.

    Its ``-e .[extras]`` (the repository, editable) becomes ``./<wheel>[extras]``; the other
    folders of the repository it installs are left out: the JupyterLab settings, which open ``.py``
    notebooks (the handout's are ``.ipynb``), and ``coursework``, which only hidden tests import
    (the handout has none). So are its comments, which speak of the repository.
    """
    lines = ["# What the notebooks need: vo_lib (the wheel in this folder) and JupyterLab with its kernel."]
    for line in (ROOT / "requirements-student.txt").read_text().splitlines():
        requirement = line.split("#", 1)[0].strip()
        package = re.fullmatch(r"-e \.(\[[\w,]+\])?", requirement)
        if package:
            requirement = f"./{wheel}{package.group(1) or ''}"
        elif not requirement or requirement.removeprefix("-e ").startswith("./"):
            continue
        lines.append(requirement)
    if not any(line.startswith(f"./{wheel}") for line in lines):
        raise BuildError(
            "requirements-student.txt does not install the package (-e .[...]): the handout would lack it"
        )
    return "\n".join([*lines, ""])


def handout_leaks(folder: pathlib.Path, lines: set[str]) -> list[str]:
    """``file: line`` for every solution line (or nbgrader marker) in a file of ``folder`` or the wheel."""
    texts = []
    for file in sorted(p for p in folder.rglob("*") if p.is_file()):
        if file.suffix == ".whl":
            with zipfile.ZipFile(file) as wheel:
                texts += [
                    (f"{file.name}/{n}", wheel.read(n).decode("utf-8", "replace")) for n in wheel.namelist()
                ]
        elif file.suffix == ".ipynb":
            nb = nbformat.read(file, as_version=4)
            texts.append((str(file.relative_to(folder)), "\n".join(cell.source for cell in nb.cells)))
        else:
            texts.append((str(file.relative_to(folder)), file.read_text("utf-8", "replace")))
    found = []
    for name, text in texts:
        shown = {line.strip() for line in text.splitlines()}
        found += [f"{name}: {line!r}" for line in sorted(lines & shown)]
        found += [f"{name}: {m.group(0).strip()!r}" for m in MARKER_LINE.finditer(text)]
    return found


def build(
    out: pathlib.Path, paths: list[pathlib.Path], check_paths: list[pathlib.Path], repeat: int = 1
) -> None:
    """Write ``out/grading``, ``out/student`` and ``out/handout``; autograde ``check_paths`` first
    (``repeat`` times over)."""
    with contextlib.ExitStack() as stack:  # refused before an hour of work, not after it
        try:
            course, student, handout = (
                stack.enter_context(OutputFolder(out / name, WRITTEN_BY))
                for name in (GRADING_DIR, STUDENT_DIR, HANDOUT_DIR)
            )
        except OutputError as exc:
            raise UsageError(str(exc)) from None
        write_course(course.path, paths)
        if check_paths:
            for line in check(course.path, check_paths, repeat):
                print(line)
        shutil.copytree(course.path / "release", student.path, dirs_exist_ok=True)
        write_handout(handout.path, course.path, paths)
        for name in (GRADING_DIR, STUDENT_DIR, HANDOUT_DIR):  # none is replaced unless all may be
            refuse_unless_replaceable(out / name)
        for folder in (course, student, handout):
            folder.commit()


class Parser(OneLineParser):
    """Argument errors as one line (a UsageError), not argparse's usage block."""

    raises = UsageError


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    parser = Parser(
        prog="python coursework/build.py",
        description="Write handout/ (what students get), student/ (notebooks without solutions) and grading/ "
        "(nbgrader's course folder).",
    )
    parser.add_argument("notebooks", nargs="*", metavar="NN", help="only these notebooks (default: all)")
    parser.add_argument(
        "--out", type=pathlib.Path, default=ROOT, help="where to write (default: the repository)"
    )
    parser.add_argument(
        "--repeat",
        type=int,
        default=1,
        metavar="N",
        help="with --check: autograde every submission N times over, each against its notebook's run time",
    )
    parser.add_argument(
        "--check",
        nargs="*",
        metavar="NN",
        help="autograde the solutions and the unanswered edition (of these notebooks; default: all built)",
    )
    return parser.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(128 + signal.SIGTERM))
    try:
        args = parse_args(argv)
        if not args.out.is_dir():
            raise UsageError(f"--out {args.out}: expected an existing folder")
        if not os.access(args.out, os.W_OK | os.X_OK):
            raise UsageError(f"--out {args.out}: not writable")
        paths = notebook_paths(args.notebooks)
        check_paths = [] if args.check is None else notebook_paths(args.check) if args.check else paths
        missing = [p.name for p in check_paths if p not in paths]
        if missing:
            raise UsageError(f"--check {missing[0][:2]}: that notebook is not among those built")
        if args.repeat < 1:
            raise UsageError(f"--repeat {args.repeat}: expected 1 or more")
        build(args.out.resolve(), paths, check_paths, args.repeat)
    except (UsageError, OutputError) as exc:
        print(f"coursework/build.py: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except BuildError as exc:
        print(f"coursework/build.py: {exc}", file=sys.stderr)
        return EXIT_FAILED
    except PermissionError as exc:
        print(f"coursework/build.py: {exc.filename}: permission denied", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        print("coursework/build.py: interrupted; nothing written", file=sys.stderr)
        return 130
    written = ", ".join(str(args.out / name) for name in (STUDENT_DIR, HANDOUT_DIR, GRADING_DIR))
    print(f"wrote {written} ({len(paths)} notebooks)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
