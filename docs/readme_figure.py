"""Make the README's figure: the picture ``python -m vo_lib run`` draws of its default run.

    python docs/readme_figure.py

Runs the default sample as ``python -m vo_lib run`` does (rendering it on first use) into a
temporary folder and copies its ``trajectory.png`` to ``docs/default_run.png``.
"""

from __future__ import annotations

import pathlib
import shutil
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parents[1]
FIGURE = ROOT / "docs" / "default_run.png"


def main() -> int:
    from vo_lib.cli.run import run_command

    with tempfile.TemporaryDirectory() as tmp:
        run_command(None, str(pathlib.Path(tmp) / "run"), None, False)
        shutil.copyfile(pathlib.Path(tmp) / "run" / "trajectory.png", FIGURE)
    print(f"wrote {FIGURE.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
