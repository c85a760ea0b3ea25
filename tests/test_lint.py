"""ruff is part of the suite, so CI fails on lint as it fails on a wrong number."""

import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]


def test_ruff_check_is_clean():
    proc = subprocess.run(
        [sys.executable, "-m", "ruff", "check", "--no-cache", str(ROOT)],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr


def test_import_contracts_are_kept():
    """Layers, independence of the wings, viz importing no wing: the contracts in pyproject.toml."""
    lint_imports = pathlib.Path(sys.executable).with_name("lint-imports")
    proc = subprocess.run(
        [str(lint_imports) if lint_imports.exists() else "lint-imports", "--no-cache"],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
