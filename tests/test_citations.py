"""The papers are named by citation key, and every key has its full reference on docs/references.md.

A key is the first author's surname and, where the paper prints one, the year: ``[Zhao]``,
``[Yan 2020]``, ``[Yuan]`` in prose, ``zhao``, ``yan2020``, ``yuan`` in names. The papers were
once named by the number of their text file after the word "seed", the word the code also uses for
random seeds; that form must not come back.
"""

from __future__ import annotations

import io
import pathlib
import re
import subprocess
import tokenize

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
REFERENCES = ROOT / "docs" / "references.md"
TEXT_SUFFIXES = {".py", ".md", ".txt", ".toml", ".json", ".cfg", ".ini", ".yml", ".yaml", ".answers"}

#: A paper named by its file number: the word, then 000, 001, 002 or 004, written apart, hyphened,
#: underscored or glued ("Seed 000's", "seeds 000 and 002", "seed-004", "seed002_landmarks").
OLD_NAME = re.compile(r"(?<![A-Za-z])seeds?(?:[ \t]*\n[ \t]*#?[ \t]*|[ \t_-]*)00[0124](?!\d)", re.I)
#: A citation key in prose: a capitalised name in brackets, maybe a year; not a link's text
#: ("[text](target)"), not an index ("x[None]").
KEY = re.compile(r"(?<![\w\]\[])\[([A-Z][a-z]+(?: \d{4}[a-z]?)?)\](?![(\[])")
#: An entry of the references page: "- **[Key]** Authors. *Title*. ..."
ENTRY = re.compile(r"^- \*\*\[([^\]]+)\]\*\* (.+?)(?=^- \*\*\[|\Z)", re.M | re.S)


def tracked_text_files() -> list[pathlib.Path]:
    """The repository's text files: those git tracks, or, outside a git checkout, the folders'."""
    try:
        out = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, check=True)
        names = [n for n in out.stdout.decode().split("\0") if n]
    except (OSError, subprocess.CalledProcessError):
        names = [str(p.relative_to(ROOT)) for p in ROOT.rglob("*") if ".git" not in p.parts]
    paths = [ROOT / n for n in names]
    return [p for p in paths if p.suffix in TEXT_SUFFIXES and p.is_file()]


def prose_of(path: pathlib.Path) -> str:
    """What a reader reads: a Python file's comments and strings (docstrings, notebook prose,
    messages), every other file whole."""
    text = path.read_text(encoding="utf-8")
    return prose_of_text(text) if path.suffix == ".py" else text


def prose_of_text(text: str) -> str:
    """The comments and strings of Python source ``text``."""
    tokens = tokenize.generate_tokens(io.StringIO(text).readline)
    return "\n".join(t.string for t in tokens if t.type in (tokenize.COMMENT, tokenize.STRING))


def references() -> dict[str, str]:
    text = REFERENCES.read_text(encoding="utf-8")
    return {key: " ".join(body.split()) for key, body in ENTRY.findall(text)}


#: The three papers the project implements.
PAPERS = ("Zhao", "Yan 2020", "Yuan")
#: The works each early notebook takes an idea from, which its prose must cite ([Zhao]'s own
#: references [10] and [11], RANSAC, the five-point solver, FAST and ORB).
SOURCES = {
    "01_crawler_odometry.py": ("Scaramuzza 2009",),
    "02_circular_motion_derivation.py": ("Scaramuzza 2009",),
    "03_circular_motion_numeric_checks.py": ("Scaramuzza 2009",),
    "04_world_and_sequences.py": ("Rosten 2006",),
    "05_stereo_front_end.py": ("Rosten 2006", "Rublee 2011"),
    "06_one_point_ransac.py": ("Fischler 1981", "Scaramuzza 2009", "Civera 2010", "Nister 2004"),
}
#: Every tracked text file but this one, whose examples ("[Key]", "x[None]") are not citations.
FILES = [p for p in tracked_text_files() if p.name != "test_citations.py"]


def test_the_old_paper_numbers_are_gone():
    this = pathlib.Path(__file__).resolve()
    found = []
    for path in FILES:
        text = path.read_text(encoding="utf-8")
        for m in OLD_NAME.finditer(text) if path.resolve() != this else ():
            found.append(f"{path.relative_to(ROOT)}:{text[: m.start()].count(chr(10)) + 1}: {m.group()!r}")
        if OLD_NAME.search(path.name):
            found.append(f"{path.relative_to(ROOT)}: the file's name")
    assert not found, "name the paper by its key (docs/references.md):\n" + "\n".join(found)


def test_the_guard_knows_the_old_forms_and_spares_random_seeds():
    old = [
        "seed 000, eq. 14",
        "Seed 002's lap",
        "seeds 000 and 004",
        "seed-004",
        "seed002_world",
        "seed\n000",
    ]
    assert all(OLD_NAME.search(t) for t in old)
    seeds = ["SEED = 0", "--seed 0", "default_rng(seed)", "same seed, same result", "seed=2", "seed 10"]
    assert not any(OLD_NAME.search(t) for t in seeds)
    prose = "as [Zhao] shows, [Yan 2020], eq. 6; see [the errata](errata.md), x[None]"
    assert KEY.findall(prose) == ["Zhao", "Yan 2020"]
    code = '"""[Yuan]: tracking."""\nflags = [None] * 3  # [Zhao]\n'
    assert KEY.findall(prose_of_text(code)) == ["Yuan", "Zhao"]  # the list in code is no citation


def test_every_reference_is_complete():
    entries = references()
    assert set(entries) == set(PAPERS) | {key for keys in SOURCES.values() for key in keys}
    for key, body in entries.items():
        surname, _, year = key.partition(" ")
        authors = re.sub(r"\s*\([^)]*\)", "", body).split(".")[0]  # names in another script aside
        assert authors.split(",")[0].split()[-1] == surname, f"[{key}]: the key is the first author's surname"
        assert re.search(r"\*[^*]{20,}\*", body), f"[{key}]: no title"
        if year:
            assert year in body, f"[{key}]: the year of the key is not in the reference"
        else:
            assert "not printed" in body, f"[{key}]: a key without a year says the paper prints none"
    assert "doi:10.19306/j.cnki.2095-8110.2020.03.011" in entries["Yan 2020"].replace("doi:[", "doi:")


@pytest.mark.parametrize("path", FILES, ids=[str(p.relative_to(ROOT)) for p in FILES])
def test_every_key_used_is_on_the_references_page(path):
    unknown = sorted(set(KEY.findall(prose_of(path))) - set(references()))
    assert not unknown, f"{path.relative_to(ROOT)}: keys without a reference on docs/references.md: {unknown}"


def test_every_reference_is_cited_and_the_page_is_linked():
    used = {key for p in FILES if p != REFERENCES for key in KEY.findall(prose_of(p))}
    assert set(references()) <= used, "a reference nothing cites"
    assert "(docs/references.md)" in (ROOT / "README.md").read_text(encoding="utf-8")


@pytest.mark.parametrize("notebook", sorted(SOURCES))
def test_the_early_notebooks_cite_where_their_ideas_come_from(notebook):
    cited = set(KEY.findall(prose_of(ROOT / "notebooks" / notebook)))
    missing = sorted(set(SOURCES[notebook]) - cited)
    assert not missing, f"notebooks/{notebook} does not cite {missing} (docs/references.md)"


def test_the_sources_entries_carry_a_doi_and_the_papers_own_numbers():
    entries = references()
    for key in {key for keys in SOURCES.values() for key in keys}:
        assert re.search(r"doi:\[?10\.\d{4,5}/", entries[key]), f"[{key}]: no doi"
    assert "reference [10]" in entries["Scaramuzza 2009"] and "reference [11]" in entries["Civera 2010"]
