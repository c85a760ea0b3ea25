"""The notation table is linked and names θ's three meanings; every notebook cites its papers."""

import pathlib
import re

import jupytext
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("[0-9][0-9]_*.py"))
PAPERS = {
    "[Zhao]": "1-Point RANSAC Application",
    "[Yan 2020]": "EKF-SLAM Algorithm Based on Dichotomy",
    "[Yuan]": "A Novel Visual Odometer Assisted Pose Tracking Method",
}


def test_notation_table_is_linked_and_says_which_theta_is_which():
    text = (ROOT / "docs" / "notation.md").read_text(encoding="utf-8")
    assert "(docs/notation.md)" in (ROOT / "README.md").read_text(encoding="utf-8")
    theta = text[text.index("## θ: three meanings") : text.index("## φ and Φ")]
    rows = [line for line in theta.splitlines() if line.startswith("| **")]
    assert [re.match(r"\| \*\*(\w+)", row).group(1) for row in rows] == ["heading", "deflection", "bearing"]
    flat = re.sub(r"\s+", " ", text)
    for title in PAPERS.values():
        assert title in flat
    for notebook in ("01", "02", "06", "09"):  # each row says which letter the notebooks use
        assert sum(re.search(rf"\b{notebook}\b", row) is not None for row in rows) >= 1


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_every_notebook_cites_the_papers_it_draws_on(path):
    cells = jupytext.read(path).cells
    references = next(c.source for c in cells[:3] if c.source.startswith("**References**"))
    references = re.sub(r"\s+", " ", references)
    cited = {seed for seed, title in PAPERS.items() if title in references and seed in references}
    assert cited, f"{path.name}: no paper cited"
    assert re.search(r"§[IV\d]", references), f"{path.name}: no section named"
    assert "/work/" not in references and ".txt" not in references  # citations, not file paths
