"""The teacher's release-and-collect workflow of docs/course.md, end to end on a local exchange.

One tiny assignment (a function to write, its autograder test with hidden tests, a written
answer graded by hand) goes through every nbgrader command a course runs, in the order
docs/course.md gives them: the roster is imported, the assignment is generated and released
into an exchange folder, two students fetch and submit it from their own folders, the teacher
collects, autogrades, grades the written parts, returns feedback that a student fetches, and
turns the exported grades into course grades with the script of docs/course.md. The course
folder's settings are the project's own (``coursework/nbgrader_config.py``) plus the exchange
settings docs/course.md gives; kernels talk over IPC sockets, as the project's settings ask.
"""

from __future__ import annotations

import datetime
import os
import pathlib
import re
import shutil
import subprocess
import sys

import nbformat
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
PROJECT_CONFIG = ROOT / "coursework" / "nbgrader_config.py"
COURSE_PAGE = ROOT / "docs" / "course.md"
COURSE_ID = "vo-notebooks"
ASSIGNMENT = "squares"
ROSTER = "id,first_name,last_name,email\nalice,Alice,Adams,alice@example.org\nbob,Bob,Brown,bob@example.org\n"
TEST_POINTS, WRITTEN_POINTS = 2, 1
NBGRADER_TIMEOUT_S = 120  # one command; the whole workflow takes well under a minute


def grader(grade_id: str, *, points: int | None = None, solution: bool, locked: bool) -> dict:
    """nbgrader's metadata of one cell (schema 3)."""
    meta = {"grade": points is not None, "grade_id": grade_id, "locked": locked}
    meta |= {"schema_version": 3, "solution": solution}
    if points is not None:
        meta["points"] = points
    return {"nbgrader": meta}


def assignment_notebook() -> nbformat.NotebookNode:
    """A function to write, its test (visible and hidden asserts), a question answered in words."""
    nb = nbformat.v4.new_notebook()
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
    nb.cells = [
        nbformat.v4.new_markdown_cell("# Squares\n\nWrite `square(x)`, the square of `x`."),
        nbformat.v4.new_code_cell(
            "def square(x):\n    ### BEGIN SOLUTION\n    return x * x\n    ### END SOLUTION",
            metadata=grader("square", solution=True, locked=False),
        ),
        nbformat.v4.new_code_cell(
            "assert square(3) == 9\n"
            "### BEGIN HIDDEN TESTS\n"
            "import random\n"
            "for x in [-random.uniform(1, 5) for _ in range(5)]:  # fresh, negative inputs\n"
            "    assert square(x) == x * x, 'square of a negative number'\n"
            "### END HIDDEN TESTS",
            metadata=grader("square_test", points=TEST_POINTS, solution=False, locked=True),
        ),
        nbformat.v4.new_markdown_cell("Why is the square of a real number never negative?"),
        nbformat.v4.new_markdown_cell(
            "=== BEGIN MARK SCHEME ===\n\nA product of two factors of the same sign.\n\n"
            "=== END MARK SCHEME ===",
            metadata=grader("square_why", points=WRITTEN_POINTS, solution=True, locked=False),
        ),
    ]
    return nb


def answer(nb: nbformat.NotebookNode, code: str, words: str) -> nbformat.NotebookNode:
    """``nb`` as a student leaves it: ``code`` in the solution cell, ``words`` in the written one."""
    for cell in nb.cells:
        grade_id = cell.metadata.get("nbgrader", {}).get("grade_id")
        if grade_id == "square":
            cell.source = code
        elif grade_id == "square_why":
            cell.source = words
    return nb


@pytest.fixture
def course(tmp_path, kernel_dir):
    """Folders and an environment for each role: ``run(role, *nbgrader args)`` runs one command."""
    exchange = tmp_path / "exchange"
    exchange.mkdir()
    exchange.chmod(0o777)  # nbgrader's exchange is writable by everyone (students submit into it)
    teacher = tmp_path / "course"
    (teacher / "source" / ASSIGNMENT).mkdir(parents=True)
    # the project's grading settings, and the lines docs/course.md has a teacher add
    teacher.joinpath("nbgrader_config.py").write_text(
        PROJECT_CONFIG.read_text()
        + f"\nc.Exchange.root = {str(exchange)!r}\n"
        + "c.ExchangeCollect.check_owner = False  # one Unix user plays every role here\n"
    )
    (teacher / "coursework").mkdir()  # the grading tools, as coursework/build.py lays them out
    for tool in ("grading.py", "autograde_steps.py"):
        shutil.copy2(PROJECT_CONFIG.with_name(tool), teacher / "coursework" / tool)
    homes, ran = {"course": teacher}, []
    for student in ("alice", "bob"):
        homes[student] = tmp_path / student
        homes[student].mkdir()
        homes[student].joinpath("nbgrader_config.py").write_text(
            f"c = get_config()  # noqa: F821\nc.CourseDirectory.course_id = {COURSE_ID!r}\n"
            f"c.Exchange.root = {str(exchange)!r}\n"
            # on a shared server nbgrader takes the Unix user name; here one user plays both students
            f"c.CourseDirectory.student_id = {student!r}\n"
        )

    def run(role: str, *args: str) -> str:
        ran.append(" ".join(a for a in args[:3] if not a.startswith("-") and a != ASSIGNMENT))
        env = dict(
            os.environ,
            JUPYTER_PATH=str(kernel_dir.parent),  # the python3 kernel of the tests' environment
            JUPYTER_CONFIG_DIR=str(tmp_path / f"{role}-config"),  # no user settings
            JUPYTER_DATA_DIR=str(tmp_path / f"{role}-data"),  # each role's own submission cache
            MPLBACKEND="Agg",
        )
        proc = subprocess.run(
            [sys.executable, "-m", "nbgrader", *args],
            cwd=homes[role],
            env=env,
            capture_output=True,
            text=True,
            timeout=NBGRADER_TIMEOUT_S,
        )
        assert proc.returncode == 0, f"nbgrader {' '.join(args)} ({role}) failed:\n{proc.stderr[-2000:]}"
        return proc.stdout + proc.stderr

    run.commands = ran
    return homes, exchange, run


def test_the_project_settings_start_kernels_over_ipc():
    from traitlets.config.loader import PyFileConfigLoader

    config = PyFileConfigLoader(PROJECT_CONFIG.name, path=str(PROJECT_CONFIG.parent)).load_config()
    assert config.KernelManager.transport == "ipc", "TCP ports stall when several kernels start at once"


@pytest.mark.notebook
@pytest.mark.course
def test_release_fetch_submit_collect_autograde_feedback(course):
    from nbgrader.api import Gradebook

    homes, exchange, run = course
    teacher = homes["course"]
    nbformat.write(assignment_notebook(), teacher / "source" / ASSIGNMENT / f"{ASSIGNMENT}.ipynb")

    # The teacher: the roster, the assignment with a due date a week ahead, the release.
    teacher.joinpath("roster.csv").write_text(ROSTER)
    run("course", "db", "student", "import", "roster.csv")
    week_ahead = datetime.datetime.now(datetime.timezone.utc) + datetime.timedelta(days=7)
    run("course", "db", "assignment", "add", ASSIGNMENT, f"--duedate={week_ahead.isoformat()}")
    run("course", "generate_assignment", ASSIGNMENT)
    run("course", "release_assignment", ASSIGNMENT)
    assert (exchange / COURSE_ID / "outbound" / ASSIGNMENT / f"{ASSIGNMENT}.ipynb").is_file()

    # The students fetch it into their own folders: no solution, the hidden tests gone.
    for student in ("alice", "bob"):
        run(student, "fetch_assignment", ASSIGNMENT)
    released = (homes["alice"] / ASSIGNMENT / f"{ASSIGNMENT}.ipynb").read_text()
    assert "return x * x" not in released and "HIDDEN TESTS" not in released and "MARK SCHEME" not in released
    assert "Why is the square" in released, "the written question stays visible"

    # Alice answers right and submits in time; Bob's answer passes the visible test only (the hidden
    # ones try negative numbers) and arrives after the deadline. Rather than wait for a real
    # deadline, the teacher moves it to the moment between the two submissions.
    def submit(student: str, code: str, words: str) -> None:
        path = homes[student] / ASSIGNMENT / f"{ASSIGNMENT}.ipynb"
        nbformat.write(answer(nbformat.read(path, as_version=4), code, words), path)
        run(student, "submit", ASSIGNMENT)

    submit("alice", "def square(x):\n    return x * x", "A product of two factors of the same sign.")
    deadline = datetime.datetime.now(datetime.timezone.utc)
    run("course", "db", "assignment", "add", ASSIGNMENT, f"--duedate={deadline.isoformat()}")
    submit("bob", "def square(x):\n    return x * abs(x)", "It is positive.")

    run("course", "collect", ASSIGNMENT)
    for student in ("alice", "bob"):
        assert (teacher / "submitted" / student / ASSIGNMENT / f"{ASSIGNMENT}.ipynb").is_file()
    run("course", "autograde", ASSIGNMENT)

    with Gradebook(f"sqlite:///{teacher / 'gradebook.db'}") as gb:
        assert sorted(s.id for s in gb.students) == ["alice", "bob"], "the roster"
        assert gb.find_assignment(ASSIGNMENT).duedate == deadline.replace(tzinfo=None), "stored in UTC"
        alice = gb.find_submission(ASSIGNMENT, "alice")
        bob = gb.find_submission(ASSIGNMENT, "bob")
        assert alice.total_seconds_late == 0, "Alice submitted before the deadline"
        assert bob.total_seconds_late > 0, "Bob's submission is recorded as late"
        # the project's policy (docs/course.md): lateness is recorded, no points are taken off
        assert not bob.notebooks[0].late_submission_penalty
        tests = {s: gb.find_grade("square_test", ASSIGNMENT, ASSIGNMENT, s) for s in ("alice", "bob")}
        assert (tests["alice"].score, tests["alice"].max_score) == (TEST_POINTS, TEST_POINTS)
        assert tests["bob"].score == 0, "the hidden tests catch the answer the visible test lets pass"
        # the written part waits for the teacher, then counts once graded by hand (formgrader's job)
        written = gb.find_grade("square_why", ASSIGNMENT, ASSIGNMENT, "alice")
        assert written.needs_manual_grade and written.manual_score is None
        written.manual_score, written.needs_manual_grade = WRITTEN_POINTS, False  # as formgrader saves it
        gb.db.commit()
    with Gradebook(f"sqlite:///{teacher / 'gradebook.db'}") as gb:
        assert gb.find_submission(ASSIGNMENT, "alice").score == TEST_POINTS + WRITTEN_POINTS

    # Feedback: generated, released into the exchange, fetched by the student.
    run("course", "generate_feedback", ASSIGNMENT)
    run("course", "release_feedback", ASSIGNMENT)
    run("alice", "fetch_feedback", ASSIGNMENT)
    feedback = list((homes["alice"] / ASSIGNMENT / "feedback").rglob(f"{ASSIGNMENT}.html"))
    assert len(feedback) == 1, "Alice receives one feedback page"
    total = TEST_POINTS + WRITTEN_POINTS
    assert f"Score: {total:.1f} / {total:.1f}" in feedback[0].read_text(), "the feedback shows the grade"

    # The course grade: nbgrader's export, then the script docs/course.md gives; Bob's written part
    # is not graded yet, so he has no grade yet.
    run("course", "export")
    script = re.findall(r"```python\n(.*?)```", COURSE_PAGE.read_text(encoding="utf-8"), re.S)
    script = [block for block in script if "grades.csv" in block]
    assert len(script) == 1, "docs/course.md gives one script that reads grades.csv"
    proc = subprocess.run(
        [sys.executable, "-c", script[0]], cwd=teacher, capture_output=True, text=True, check=True
    )
    assert proc.stdout.splitlines() == [
        f"alice: {total} of {total} points, 100.0 %, grade A",
        f"bob: no grade yet ({WRITTEN_POINTS} of the points still to be graded by hand)",
    ]
    # every command run here is one the course page gives
    page = COURSE_PAGE.read_text(encoding="utf-8")
    missing = sorted({command for command in run.commands if f"nbgrader {command}" not in page})
    assert not missing, f"docs/course.md does not give these steps: {missing}"
