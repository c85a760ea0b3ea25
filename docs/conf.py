"""Sphinx configuration of the reading edition: the README, every notebook executed, the errata.

Sphinx runs on a source tree that ``docs/build.py`` lays out under the build folder (the README,
the notebooks and this folder's pages, linked in place) with this folder as its configuration
directory, so the repository's own files are never written to. Build with
``python docs/build.py``; the options below that depend on the build folder arrive as
``-D name=value`` from that script.
"""

from __future__ import annotations

import importlib.util
import pathlib

from docutils import nodes
from sphinx.transforms import SphinxTransform
from sphinx.util.fileutil import copy_asset

project = "vo-notebooks"
author = "the vo-notebooks authors"
html_title = "vo-notebooks"

extensions = ["myst_nb"]
# The README is the landing page's text, included by index.md rather than read as a page.
exclude_patterns = ["README.md"]

# Notebooks are jupytext percent-format .py files; MyST-NB reads them directly.
nb_custom_formats = {".py": ["jupytext.reads", {"fmt": "py:percent"}]}
# build.py has executed every notebook into this cache before Sphinx starts (in parallel, longest
# first); Sphinx then only reads the executed copies, and a notebook whose code changed is run again.
nb_execution_mode = "cache"
nb_execution_cache_path = "_build/.jupyter_cache"  # build.py passes the build folder's cache
nb_execution_timeout = 300  # seconds per cell, as in tests/test_notebooks.py
nb_execution_raise_on_error = True
nb_execution_show_tb = True
nb_merge_streams = True
# No widget JavaScript from a CDN: the static page shows each widget's default figure, which the
# notebooks draw by calling the widget's function once; the widget itself becomes a short note.
nb_ipywidgets_js: dict[str, dict[str, str]] = {}

myst_enable_extensions = ["dollarmath", "amsmath"]
myst_heading_anchors = 3

# Every warning fails the build (build.py passes -W --keep-going), and so does every unresolved
# reference (-n).
nitpicky = True

html_theme = "sphinx_book_theme"
html_theme_options = {
    "home_page_in_toc": True,
    "show_navbar_depth": 1,
    "use_download_button": True,
}
html_last_updated_fmt = None

# MathJax 3 from the django-static-mathjax package (no Django needed: it only ships MathJax's
# files), copied into the site so that maths renders without a network.
MATHJAX_PACKAGE = "mathjax"
MATHJAX_BUNDLE = "static/mathjax/es5"
MATHJAX_ENTRY = "tex-mml-chtml.js"
mathjax_path = f"mathjax/{MATHJAX_ENTRY}"
mathjax3_config = {"tex": {"inlineMath": [["\\(", "\\)"]], "displayMath": [["\\[", "\\]"]]}}

WIDGET_VIEW_MIMETYPE = "application/vnd.jupyter.widget-view+json"
WIDGET_NOTE = (
    "An interactive widget in Jupyter (it needs a running kernel); "
    "this page shows its figure at the default settings."
)


def mathjax_files() -> pathlib.Path:
    """The folder of MathJax's browser bundle inside the installed package."""
    spec = importlib.util.find_spec(MATHJAX_PACKAGE)
    if spec is None or not spec.submodule_search_locations:
        raise RuntimeError("MathJax files not found: install django-static-mathjax (environment.txt)")
    folder = pathlib.Path(next(iter(spec.submodule_search_locations))) / MATHJAX_BUNDLE
    if not (folder / MATHJAX_ENTRY).is_file():
        raise RuntimeError(f"MathJax files not found: {folder / MATHJAX_ENTRY} is missing")
    return folder


def copy_mathjax(app, exception) -> None:
    """Copy MathJax next to the pages once the build has succeeded."""
    if exception is None and app.builder.format == "html":
        copy_asset(mathjax_files(), pathlib.Path(app.outdir) / "_static" / "mathjax")


class StaticWidgets(SphinxTransform):
    """Replace each embedded widget view, which needs a live kernel, by a one-line note.

    build.py executes without storing widget state, so no state is embedded in the page either.
    """

    default_priority = 400

    def apply(self, **kwargs) -> None:
        for raw in list(self.document.findall(nodes.raw)):
            if f'type="{WIDGET_VIEW_MIMETYPE}"' in raw.astext():
                note = nodes.paragraph(classes=["widget-note"])
                note += nodes.emphasis(text=WIDGET_NOTE)
                raw.replace_self(note)


def setup(app):
    app.add_transform(StaticWidgets)
    app.connect("build-finished", copy_mathjax)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
