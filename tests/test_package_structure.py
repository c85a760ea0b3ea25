"""The package's shape: no import cycle, one pipeline class, small functions, and the package map
of docs/layout.md naming every module."""

from __future__ import annotations

import functools
import re

import grimp


def test_no_import_cycle_anywhere_in_vo_lib():
    graph = grimp.build_graph("vo_lib", include_external_packages=False)
    cycles = []
    for module in sorted(graph.modules):
        for imported in graph.find_modules_directly_imported_by(module):
            # a path back from what the module imports to the module itself closes a cycle
            back = graph.find_shortest_chain(importer=imported, imported=module)
            if back:
                cycles.append(" -> ".join([module, *back]))
    assert cycles == []


def test_stereo_vo_has_one_pipeline_class():
    from vo_lib.stereo_vo import pipeline

    classes = [
        name
        for name, obj in vars(pipeline).items()
        if isinstance(obj, type) and obj.__module__ == pipeline.__name__
    ]
    assert classes == ["StereoOdometry"]


def layout_sections(text: str) -> dict[str, str]:
    """The package map of docs/layout.md by folder: ``"vo_lib/stereo_vo"`` -> the lines of that
    folder's entry (the folder's line and the more indented lines below it)."""
    import re

    block = text.split("```")[1].splitlines()
    sections, stack = {}, []
    for k, line in enumerate(block):
        entry = re.match(r"( *)(\S+)/(\s|$)", line)
        if not entry:
            continue
        depth = len(entry[1])
        stack = [(d, n) for d, n in stack if d < depth] + [(depth, entry[2])]
        below = [x for x in block[k + 1 :]]
        end = next(
            (i for i, x in enumerate(below) if x.strip() and len(x) - len(x.lstrip()) <= depth), len(below)
        )
        sections["/".join(n for _, n in stack)] = "\n".join([line, *below[:end]])
    return sections


def test_every_module_is_in_the_package_map():
    """docs/layout.md names every module and subpackage of vo_lib and vo_book in its folder's entry."""
    import pathlib
    import re

    repo = pathlib.Path(__file__).resolve().parents[1]
    sections = layout_sections((repo / "docs" / "layout.md").read_text(encoding="utf-8"))
    missing = []
    for path in sorted([*(repo / "vo_lib").rglob("*"), *(repo / "vo_book").rglob("*")]):
        folder = path.parent.relative_to(repo).as_posix()
        if path.suffix == ".py" and not path.name.startswith("__"):
            name = path.name
        elif path.is_dir() and (path / "__init__.py").is_file():
            name = path.name + "/"
        else:
            continue
        if not re.search(rf"(?<![\w.]){re.escape(name)}", sections.get(folder, "")):
            missing.append(path.relative_to(repo).as_posix())
    assert missing == []


def test_functions_of_vo_lib_are_small_enough_to_read():
    """ruff's C901 (complexity at most 12) and PLR0915 (at most 50 statements), limits in pyproject.toml."""
    import pathlib
    import subprocess
    import sys

    root = pathlib.Path(__file__).resolve().parents[1]
    proc = subprocess.run(
        [sys.executable, "-m", "ruff", "check", "--no-cache", "--select", "C901,PLR0915", "vo_lib"],
        capture_output=True,
        text=True,
        cwd=root,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr


@functools.cache  # one ruff run serves both tests
def complexities() -> tuple[tuple[int, str, str], ...]:
    """``(McCabe complexity, module, function)`` of every function of vo_lib (ruff C901 at 0)."""
    import json
    import pathlib
    import subprocess
    import sys

    root = pathlib.Path(__file__).resolve().parents[1]
    proc = subprocess.run(
        [sys.executable, "-m", "ruff", "check", "--no-cache", "--select", "C901", "--output-format", "json"]
        + ["--config", "lint.mccabe.max-complexity=0", "vo_lib"],
        capture_output=True,
        text=True,
        cwd=root,
    )
    found = []
    for finding in json.loads(proc.stdout):
        message = re.search(r"`(.+)` is too complex \((\d+) > 0\)", finding["message"])
        assert message, f"ruff's message is no longer 'NAME is too complex (N > 0)': {finding['message']}"
        module = pathlib.Path(finding["filename"]).relative_to(root).as_posix()
        found.append((int(message.group(2)), module, message.group(1)))
    assert len(found) > 100, proc.stderr
    return tuple(found)


def test_no_module_is_more_complex_than_the_pipeline():
    """Summed McCabe complexity per module: none above the pipeline's, which strings the whole
    method together."""
    import collections

    summed = collections.Counter()
    for complexity, module, _ in complexities():
        summed[module] += complexity
    pipeline = summed.pop("vo_lib/stereo_vo/pipeline.py")
    assert pipeline > 0 and {m: c for m, c in summed.items() if c > pipeline} == {}


#: Modules that read, write, configure, run, time or show rather than estimate: command line, files,
#: outputs, the samples' catalogue and frame store, settings, the choice of vehicle, the papers'
#: experiments and tables, benchmarks, reports and figures.
MACHINERY = re.compile(
    r"vo_lib/(__main__|cli/|formats/|bench/|viz/|outputs|atomic|arguments|data|compiled|sim/(samples|frame_store)"
    r"|stereo_vo/(run_report|vehicle|config|paper_sets|paper_tables)|lidar_tracking/corridor_experiment)"
)


def test_at_least_half_of_the_most_complex_functions_are_algorithms():
    """Of the ten most complex functions, at least five are algorithms, however ties at the tenth
    place are broken (against the algorithms here)."""
    ranked = sorted(complexities(), reverse=True)
    tenth = ranked[9][0]
    above = [f for f in ranked if f[0] > tenth]
    tied_machinery = sum(1 for c, module, _ in ranked if c == tenth and MACHINERY.match(module))
    algorithms = sum(1 for _, module, _ in above if not MACHINERY.match(module))
    algorithms += max(0, 10 - len(above) - tied_machinery)
    assert algorithms >= 5, ranked[:15]


def _openblas_cores() -> dict[str, str]:
    """Each OpenBLAS loaded in this process (NumPy's, OpenCV's) and the kernels it runs."""
    import ctypes

    cores = {}
    for line in open("/proc/self/maps", encoding="ascii", errors="replace"):
        path = line.split()[-1]
        if "openblas" not in path or path in cores or not path.endswith(".so"):
            continue
        library = ctypes.CDLL(path)
        for name in ("scipy_openblas_get_corename64_", "openblas_get_corename"):
            if hasattr(library, name):
                function = getattr(library, name)
                function.restype = ctypes.c_char_p
                cores[path] = function().decode()
    return cores


def test_openblas_runs_one_kernel_set_on_every_cpu_with_avx2():
    """vo_lib/__init__.py has OpenBLAS use its Haswell kernels, which conftest.py gets in before
    NumPy loads them: NumPy's and OpenCV's OpenBLAS both run them here."""
    import os

    import cv2  # noqa: F401  (loads OpenCV's OpenBLAS)
    import numpy  # noqa: F401
    import pytest

    # vo_lib leaves the variable unset without AVX2 on Linux, and keeps a value the user set
    if (chosen := os.environ.get("OPENBLAS_CORETYPE")) != "Haswell":
        pytest.skip(f"OPENBLAS_CORETYPE is {chosen!r}: no AVX2 on Linux here, or the user chose the kernels")
    cores = _openblas_cores()
    assert cores and set(cores.values()) == {"Haswell"}, cores
