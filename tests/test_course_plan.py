"""docs/course.md and coursework/answer_key.md against the notebooks they describe.

The points of every notebook's graded exercises live in nbgrader's cell metadata (``"points": N``
on the ``# %% nbgrader={...}`` lines of ``notebooks/*.py``). The course page's points table, its
thirteen-week plan and objectives, and the answer key of the written questions are written by hand;
these tests fail as soon as a notebook's exercises change and the pages do not follow.
"""

from __future__ import annotations

import pathlib
import re

import jupytext
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("[0-9][0-9]_*.py"))
COURSE = ROOT / "docs" / "course.md"
ANSWER_KEY = ROOT / "coursework" / "answer_key.md"
WEEKS = 13
KEY_HEADING = re.compile(r"^## (\d\d) · (\S+) · (\d+(?:\.\d+)?) points?$", re.M)


def graded_cells(path: pathlib.Path) -> list[tuple[dict, str, str]]:
    """``(nbgrader metadata, cell source, source of the cell before)`` of every graded cell."""
    cells = jupytext.read(path).cells
    return [
        (c.metadata["nbgrader"], c.source, cells[i - 1].source if i else "")
        for i, c in enumerate(cells)
        if c.metadata.get("nbgrader", {}).get("grade")
    ]


def notebook_points(path: pathlib.Path) -> tuple[float, float]:
    """(autograded, graded by hand) points: test cells, and answer cells that are also graded."""
    auto = sum(m["points"] for m, _, _ in graded_cells(path) if not m.get("solution"))
    by_hand = sum(m["points"] for m, _, _ in graded_cells(path) if m.get("solution"))
    return auto, by_hand


def written_questions() -> dict[tuple[str, str], tuple[float, str]]:
    """``{(NN, grade_id): (points, question)}`` of every answer cell graded by hand.

    The question is the cell above the answer cell: the written question stays visible in the
    student edition, the answer cell is replaced.
    """
    return {
        (path.name[:2], meta["grade_id"]): (meta["points"], question)
        for path in NOTEBOOKS
        for meta, _, question in graded_cells(path)
        if meta.get("solution")
    }


def table(text: str, first_header: str) -> list[list[str]]:
    """The body rows of the markdown table whose first column is headed ``first_header``."""
    match = re.search(rf"^\| {re.escape(first_header)} \|.*\n\|[-| ]+\|\n((?:\|.*\|\n)+)", text, re.M)
    assert match, f"no table headed {first_header!r}"
    return [[cell.strip() for cell in row.strip("|").split("|")] for row in match.group(1).splitlines()]


def number(cell: str) -> float:
    return float(cell.strip("*"))


def normalised(markdown: str) -> str:
    """Text without blockquote marks and with single spaces, to compare a quote with its source."""
    return " ".join(re.sub(r"^> ?", "", markdown, flags=re.M).split())


@pytest.fixture(scope="module")
def course_text() -> str:
    return COURSE.read_text(encoding="utf-8")


def test_points_table_agrees_with_the_notebooks(course_text):
    rows = table(course_text, "notebook")
    body, total = rows[:-1], rows[-1]
    assert [row[0].strip("`") for row in body] == [p.stem for p in NOTEBOOKS], "one row per notebook"
    for row, path in zip(body, NOTEBOOKS, strict=True):
        auto, by_hand = notebook_points(path)
        assert auto > 0, f"{path.name} has no autograded points"
        assert (number(row[1]), number(row[2])) == (auto, by_hand), (
            f"docs/course.md gives {path.stem} {row[1]} autograded and {row[2]} written points; "
            f"the notebook's exercises carry {auto:g} and {by_hand:g}"
        )
        assert number(row[3]) == auto + by_hand, f"{path.stem}: the total is not the sum"
    assert total[0] == "**all**"
    sums = [sum(number(row[i]) for row in body) for i in (1, 2, 3)]
    assert [number(cell) for cell in total[1:4]] == sums, "the last row is not the sum of the others"


def test_the_grading_script_applies_the_scale_of_the_table(course_text):
    rows = table(course_text, "share of all points")
    floors = [float(re.match(r"[\d.]+", row[0]).group()) if row[0][0].isdigit() else 0.0 for row in rows]
    assert floors == sorted(set(floors), reverse=True) and floors[-1] == 0, "bands from the top down to 0"
    scale = ", ".join(f'({floor:g}, "{row[1][0]}")' for floor, row in zip(floors, rows, strict=True))
    assert re.findall(r"^SCALE = \[(.*)\]$", course_text, re.M) == [scale]


def test_thirteen_weeks_one_notebook_each_in_order_and_hours_that_add_up(course_text):
    rows = table(course_text, "week")
    body, total = rows[:-1], rows[-1]
    assert [int(row[0]) for row in body] == list(range(1, WEEKS + 1))
    planned = [row[1].strip("`") for row in body if row[1].startswith("`")]
    assert planned == [p.stem for p in NOTEBOOKS], "every notebook once, in the order of their numbers"
    for row in body:
        assert number(row[3]) + number(row[4]) == number(row[5]), f"week {row[0]}: hours do not add up"
    assert [number(c) for c in total[3:6]] == [sum(number(row[i]) for row in body) for i in (3, 4, 5)]


def test_objectives_for_every_notebook(course_text):
    section = course_text.split("\n## Learning objectives\n")[1].split("\n## ")[0]
    objectives = re.findall(r"^\*\*(\d\d) · ", section, re.M)
    assert objectives == [p.name[:2] for p in NOTEBOOKS], "one paragraph of objectives per notebook"


def test_every_written_question_has_one_answer_key_entry_and_no_entry_is_orphaned():
    key = ANSWER_KEY.read_text(encoding="utf-8")
    headings = KEY_HEADING.findall(key)
    entries = {(nn, grade_id): float(points) for nn, grade_id, points in headings}
    assert len(entries) == len(headings), "an entry is given twice"
    questions = written_questions()
    missing = sorted(set(questions) - set(entries))
    orphaned = sorted(set(entries) - set(questions))
    assert not missing, f"written questions without an answer-key entry: {missing}"
    assert not orphaned, f"answer-key entries whose question is not in the notebooks: {orphaned}"
    sections = re.split(r"^## ", key, flags=re.M)[1:]
    for (nn, grade_id), (points, question) in questions.items():
        assert entries[nn, grade_id] == points, f"{nn} {grade_id}: {points} points in the notebook"
        section = next(s for s in sections if s.startswith(f"{nn} · {grade_id} · "))
        quote = "\n".join(line for line in section.splitlines() if line.startswith(">"))
        assert normalised(quote) == normalised(question), f"{nn} {grade_id}: the question changed"
        assert "**Model answer.**" in section and "**Mark scheme.**" in section, f"{nn} {grade_id}"
        marks = [float(m) for m in re.findall(r"^- (\d+(?:\.\d+)?) points?:", section, re.M)]
        assert max(marks) == points and min(marks) == 0, f"{nn} {grade_id}: marks from 0 to {points}"


def test_the_answer_key_is_on_no_site_and_in_no_student_edition():
    import importlib.util

    spec = importlib.util.spec_from_file_location("docs_build", ROOT / "docs" / "build.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    pages = [pathlib.Path(p).resolve() for p in module.PAGES.values()]
    assert ANSWER_KEY.resolve() not in pages
    assert not any(p.is_relative_to(ROOT / "coursework") for p in pages), "a teacher's file on the site"
