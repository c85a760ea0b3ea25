"""One kernel name: the notebooks' metadata, the notebook tests, CI and the README agree on it."""

from __future__ import annotations

import pathlib
import re

import jupytext
from conftest import NOTEBOOK_KERNEL

ROOT = pathlib.Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("[0-9][0-9]_*.py"))


def test_every_notebook_names_the_same_kernel():
    names = {p.name: jupytext.read(p).metadata["kernelspec"]["name"] for p in NOTEBOOKS}
    assert set(names.values()) == {NOTEBOOK_KERNEL}, names


def test_ci_and_readme_name_no_other_kernel():
    ci = (ROOT / ".ci" / "run").read_text()
    readme = (ROOT / "README.md").read_text()
    for text in (ci, readme):
        installed = re.findall(r"ipykernel install[^\n]*--name[ =](\S+)", text)
        assert set(installed) <= {NOTEBOOK_KERNEL}, installed
        assert 'vo-notebooks" ' not in text and "--name vo-notebooks" not in text
    assert f"`{NOTEBOOK_KERNEL}`" in readme, "the README names the kernel the notebooks use"
