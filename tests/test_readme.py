"""The README as a newcomer reads it: short, a picture first, the two commands, and installs that
match what it says (the student's brings no tool for tests, sites or grading)."""

from __future__ import annotations

import pathlib
import re

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10: jupytext brings tomli
    import tomli as tomllib

ROOT = pathlib.Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")
MAIN = "python -m pip install -r environment.txt && python -m vo_lib run"
TESTS = "python -m pip install -r environment.txt && python -m pytest"
#: Tools a student never needs: tests, lint, the reading edition, the browser, the grader, sweeps.
NOT_FOR_STUDENTS = {
    "pytest",
    "ruff",
    "import-linter",
    "evo",
    "sphinx",
    "myst-nb",
    "playwright",
    "nbgrader",
    "dask",
}


def requirement_names(lines) -> set[str]:
    names = set()
    for line in lines:
        line = line.split("#", 1)[0].strip()
        m = re.match(r"([A-Za-z0-9_.-]+)", line)
        if m and not line.startswith(("-", ".")):
            names.add(m.group(1).lower())
    return names


def project():
    return tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]


def test_readme_is_short_and_opens_with_its_picture():
    lines = README.splitlines()
    assert len(lines) <= 250, len(lines)
    first_screen = "\n".join(lines[:15])
    figure = re.search(r"!\[[^]]+\]\((docs/[\w.]+\.png)\)", first_screen)
    assert figure, "no figure on the first screen"
    assert (ROOT / figure.group(1)).is_file()
    assert (ROOT / "docs" / "readme_figure.py").is_file()  # what redraws it


def test_the_two_commands_come_in_a_virtual_environment_and_ci_runs_them_verbatim():
    venv = README.index("python -m venv .venv")
    assert venv < README.index(MAIN) < README.index(TESTS)
    ci = (ROOT / ".ci" / "run").read_text()
    assert MAIN in ci and TESTS in ci


def test_the_student_install_brings_the_notebooks_tools_and_nothing_else():
    student = (ROOT / "requirements-student.txt").read_text().splitlines()
    installs = [line.split("#", 1)[0].strip() for line in student if line.split("#", 1)[0].strip()]
    # coursework: the small module the notebooks' hidden tests import (nbgrader is not needed to read)
    assert installs == ["-e .[notebooks]", "./jupyterlab-settings", "-e ./coursework"]
    meta = project()
    names = requirement_names([*meta["dependencies"], *meta["optional-dependencies"]["notebooks"]])
    assert {"jupyterlab", "jupytext", "ipykernel", "numpy", "numba"} <= names
    assert not names & NOT_FOR_STUDENTS, names & NOT_FOR_STUDENTS
    assert "requirements-student.txt" in README


def test_the_full_install_holds_the_student_one_and_every_tool():
    lines = (ROOT / "environment.txt").read_text().splitlines()
    installs = [line.split("#", 1)[0].strip() for line in lines]
    assert "-e .[notebooks,sweeps]" in installs and "./jupyterlab-settings" in installs
    names = requirement_names(lines) | requirement_names(project()["optional-dependencies"]["sweeps"])
    assert NOT_FOR_STUDENTS <= names, NOT_FOR_STUDENTS - names
