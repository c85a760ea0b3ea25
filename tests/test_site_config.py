"""The reading edition's configuration, checked without building it (tests/test_site.py opens the
built site): every notebook is a page, the README's notebook map lists exactly the notebooks, the
pages the site is made of exist, and the build command refuses bad arguments in one line."""

from __future__ import annotations

import importlib.util
import pathlib
import re
import runpy

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
NOTEBOOKS = sorted((ROOT / "notebooks").glob("[0-9][0-9]_*.py"))
MAP_ROW = re.compile(r"^\| (\d\d) \| \[[^]]+\]\(notebooks/(\d\d_\w+)\.py\) \|", re.M)


def load_build_script():
    spec = importlib.util.spec_from_file_location("site_build", DOCS / "build.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def build_script():
    return load_build_script()


def toctree_entries(text: str) -> list[str]:
    """The entries of every ``{toctree}`` block of a MyST page (options and blank lines left out)."""
    entries = []
    for block in re.findall(r"```\{toctree\}\n(.*?)```", text, re.S):
        entries += [line.strip() for line in block.splitlines() if line.strip() and not line.startswith(":")]
    return entries


def test_the_notebook_map_lists_exactly_the_notebooks_in_order():
    rows = MAP_ROW.findall((ROOT / "README.md").read_text(encoding="utf-8"))
    assert [stem for _, stem in rows] == [nb.stem for nb in NOTEBOOKS]
    assert all(stem.startswith(number) for number, stem in rows)


def test_every_notebook_is_in_the_toctree_and_every_page_exists(build_script):
    index = (DOCS / "index.md").read_text(encoding="utf-8")
    entries = toctree_entries(index)
    assert "notebooks/*" in entries and ":glob:" in index  # every notebook of the folder, by name
    # The glob takes every notebook build.py copies into the tree: those tests/test_notebooks.py runs.
    assert build_script.find_notebooks(ROOT / "notebooks") == NOTEBOOKS
    pages = {
        name.removesuffix(".md")
        for name in build_script.PAGES
        if name.endswith(".md") and name not in ("index.md", "README.md")  # pictures are no pages
    }
    assert pages == {e for e in entries if e != "notebooks/*"}, "a page of the site outside the toctree"
    for name, path in build_script.PAGES.items():
        assert path.is_file(), f"{name}: {path} is missing"


def test_landing_page_is_the_readme_and_the_benchmarks_a_page_of_their_own():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    index = (DOCS / "index.md").read_text(encoding="utf-8")
    assert index.startswith("```{include} README.md\n```")  # the whole README, the site's first page
    assert "## Benchmarks" not in readme
    assert "`python -m vo_lib bench pipeline`" in (DOCS / "benchmarks.md").read_text(encoding="utf-8")
    assert "docs/errata.md" in readme


def test_sphinx_configuration_executes_reads_and_fails_as_intended(build_script):
    pytest.importorskip("myst_nb", reason="Sphinx and MyST-NB are not installed")
    conf = runpy.run_path(str(DOCS / "conf.py"))
    assert conf["nb_execution_mode"] == "cache"
    assert conf["nb_execution_raise_on_error"] is True
    assert conf["nitpicky"] is True
    import execute_notebook  # beside build.py, which put docs/ on the path

    assert conf["nb_custom_formats"] == {".py": ["jupytext.reads", {"fmt": execute_notebook.NOTEBOOK_FORMAT}]}
    assert conf["nb_ipywidgets_js"] == {}, "no widget JavaScript from a CDN"
    mathjax = conf["mathjax_files"]()
    assert (mathjax / conf["MATHJAX_ENTRY"]).is_file()
    assert (mathjax / "output" / "chtml" / "fonts" / "woff-v2").is_dir()


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--student"], "--student needs --notebooks DIR"),
        (["--jobs", "0"], "--jobs: expected a whole number >= 1"),
        (["--jobs", "many"], "argument --jobs: invalid int value: 'many'"),
        (["--notebooks", "{tmp}/absent"], "not a folder"),
        (["--notebooks", "{tmp}"], "no notebooks named"),
    ],
)
def test_bad_arguments_exit_2_with_one_line(build_script, tmp_path, capsys, argv, message):
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    assert build_script.main([*argv, "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1, err
    assert not (tmp_path / "out").exists(), "nothing is written for a bad argument"


def test_a_folder_that_is_not_a_build_folder_is_refused_untouched(build_script, tmp_path, capsys):
    precious = tmp_path / "thesis"
    precious.mkdir()
    (precious / "chapter1.tex").write_text("mine")
    assert build_script.main(["--out", str(precious)]) == 2
    err = capsys.readouterr().err
    assert "the folder exists and it was not written by this program" in err and err.count("\n") == 1, err
    assert [p.name for p in precious.iterdir()] == ["chapter1.tex"]


def test_the_build_folder_is_claimed_once_and_kept(build_script, tmp_path):
    """An earlier build is the build's own and is kept with its caches; another command's output
    is not, and neither is an unmarked folder."""
    from vo_lib.outputs import MARKER, read_marker

    out = tmp_path / "site"
    build_script.claim_build_folder(out)
    (out / ".jupyter_cache").mkdir()
    build_script.claim_build_folder(out)  # claimed again: the cache stays
    assert read_marker(out)["written_by"] == build_script.WRITTEN_BY and (out / ".jupyter_cache").is_dir()
    old = tmp_path / "old"
    old.mkdir()
    (old / "html").mkdir()
    with pytest.raises(build_script.UsageError, match="not written by this program"):
        build_script.claim_build_folder(old)
    assert sorted(p.name for p in old.iterdir()) == ["html"]
    (out / MARKER).write_text('{"written_by": "vo_lib run", "contents": "*"}')
    with pytest.raises(build_script.UsageError, match="holds the output of `vo_lib run`"):
        build_script.claim_build_folder(out)


def test_an_exception_in_a_notebook_fails_the_build_in_one_line(build_script, tmp_path, capsys):
    """The notebook runs in a kernel of its own; its error is the last line, its traceback a report."""
    notebooks = tmp_path / "notebooks"
    notebooks.mkdir()
    (notebooks / "01_broken.py").write_text(
        '# %%\nraise ValueError("a deliberate error")\n', encoding="utf-8"
    )
    out = tmp_path / "site"
    assert build_script.main(["--notebooks", str(notebooks), "--out", str(out), "--jobs", "1"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert "01_broken.py: ValueError: a deliberate error" in err
    assert "a deliberate error" in (out / "reports" / "01_broken.err.log").read_text(encoding="utf-8")
    assert not (out / "html").exists() and not (out / "executing").exists()


def test_an_out_folder_that_is_not_writable_is_a_usage_error(build_script, tmp_path, monkeypatch):
    def refuse(*args, **kwargs):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(pathlib.Path, "mkdir", refuse)
    with pytest.raises(build_script.UsageError, match="cannot write there"):
        build_script.claim_build_folder(tmp_path / "site")


def test_reading_edition_folds_solutions_and_leaves_out_hidden_tests_and_mark_schemes(build_script, tmp_path):
    import jupytext

    source = ROOT / "notebooks" / "06_one_point_ransac.py"
    build_script.reading_copy(source, tmp_path / "06.py")
    text = (tmp_path / "06.py").read_text()
    assert "HIDDEN TESTS" not in text and "MARK SCHEME" not in text and "BEGIN SOLUTION" not in text
    cells = jupytext.read(tmp_path / "06.py").cells
    solutions = [c for c in cells if c.cell_type == "code" and c.metadata.get("nbgrader", {}).get("solution")]
    assert solutions and all("hide-input" in c.metadata["tags"] and c.source for c in solutions)


def test_student_site_reads_the_student_edition_layout(build_script, tmp_path):
    import nbformat

    folder = tmp_path / "student" / "03_x"
    folder.mkdir(parents=True)
    nb = nbformat.v4.new_notebook()
    nb.cells = [
        nbformat.v4.new_code_cell("x = 1"),
        nbformat.v4.new_code_cell("raise NotImplementedError()", metadata={"nbgrader": {"solution": True}}),
    ]
    nbformat.write(nb, folder / "03_x.ipynb")
    assert build_script.find_notebooks(tmp_path / "student") == [folder / "03_x.ipynb"]
    build_script.student_copy(folder / "03_x.ipynb", tmp_path / "03_x.py")
    import jupytext

    cells = jupytext.read(tmp_path / "03_x.py").cells
    assert [c.metadata.get("tags", []) for c in cells] == [[], ["raises-exception"]]
