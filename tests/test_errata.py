"""docs/errata.md has one row per numbered equation of [Zhao], [Yan 2020] and [Yuan], a verdict from the
fixed list, and checks that exist: named tests in their files, notebook sections in their notebooks."""

from __future__ import annotations

import pathlib
import re

ROOT = pathlib.Path(__file__).resolve().parents[1]
ERRATA = ROOT / "docs" / "errata.md"
EQUATIONS = {"000": 21, "002": 13, "004": 23}
VERDICTS = ("correct", "wrong entry", "ambiguous", "garbled in transcription")


def rows():
    out = []
    for line in ERRATA.read_text(encoding="utf-8").splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 6 and cells[0] in EQUATIONS:
            out.append(cells)
    return out


def test_every_numbered_equation_has_one_row():
    seen = {paper: sorted(int(r[1]) for r in rows() if r[0] == paper) for paper in EQUATIONS}
    for paper, count in EQUATIONS.items():
        assert seen[paper] == list(range(1, count + 1)), (paper, seen[paper])


def test_verdicts_come_from_the_list():
    for paper, eq, *_, verdict, _ in rows():
        assert verdict.startswith(VERDICTS), (paper, eq, verdict)


def test_every_check_exists():
    for paper, eq, *_, checks in rows():
        named = re.findall(r"`(tests/[\w/]+\.py)::(\w+)`", checks)
        notebooks = re.findall(r"`(notebooks/\w+\.py)` ((?:§\d+(?:, )?)+)", checks)
        assert named or notebooks, (paper, eq, "no check")
        for path, name in named:
            source = (ROOT / path).read_text(encoding="utf-8")
            assert re.search(rf"^def {name}\(", source, re.M), (paper, eq, path, name)
        for path, sections in notebooks:
            source = (ROOT / path).read_text(encoding="utf-8")
            for number in re.findall(r"§(\d+)", sections):
                assert re.search(rf"^# ## {number}\b", source, re.M), (paper, eq, path, number)


def test_readme_links_the_errata():
    assert "docs/errata.md" in (ROOT / "README.md").read_text(encoding="utf-8")


def test_bold_signs_render_as_bold():
    """A bold sign glued to the next letter (``**−**TV``) is not emphasis in CommonMark and would
    show its asterisks on the site, hiding the very sign the row is about."""
    from markdown_it import MarkdownIt

    html = MarkdownIt("commonmark").enable("table").render(ERRATA.read_text(encoding="utf-8"))
    literal = re.findall(r".{0,25}\*\*.{0,25}", html)
    assert not literal, f"asterisks left unrendered: {literal}"
