"""The package's shape: no module imports another that imports it back, and one pipeline class."""

from __future__ import annotations

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


def test_every_module_is_in_its_package_map():
    """Each subpackage's ``__init__`` docstring names every module and subpackage in it."""
    import importlib
    import pathlib

    root = pathlib.Path(importlib.import_module("vo_lib").__file__).parent
    missing = []
    for init in sorted(root.rglob("__init__.py")):
        doc = importlib.import_module(".".join(init.parent.relative_to(root.parent).parts)).__doc__ or ""
        for child in sorted(init.parent.iterdir()):
            name = child.stem if child.suffix == ".py" else child.name
            is_module = child.suffix == ".py" and not name.startswith("__")
            is_package = child.is_dir() and (child / "__init__.py").is_file()
            named = (f"``{name}``", f"{name}/", f"{name}.py")
            if (is_module or is_package) and not any(n in doc for n in named):
                missing.append(f"{init.parent.relative_to(root.parent)}/{child.name}")
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
