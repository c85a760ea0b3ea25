import subprocess
import sys

from vo_lib.cli.main import main


def test_bench_geometry_prints_table(capsys):
    assert main(["bench", "geometry"]) == 0
    out = capsys.readouterr().out
    assert "vo_lib theta_from_pixels + rho_from_pixels" in out and "python loop (baseline)" in out


def test_unknown_bench_exits_2():
    proc = subprocess.run([sys.executable, "-m", "vo_lib", "bench", "nope"], capture_output=True, text=True)
    assert proc.returncode == 2
    assert "invalid choice: 'nope'" in proc.stderr


def test_command_line_and_file_code_stay_small():
    """Every function of the command line, the file formats, the output folders and the
    evaluation stays within complexity 12 and 50 statements (ruff C901, PLR0915)."""
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    paths = ["vo_lib/cli", "vo_lib/formats", "vo_lib/outputs.py", "vo_lib/arguments.py"]
    paths += ["vo_lib/evaluation.py", "vo_lib/data.py"]
    proc = subprocess.run(
        [sys.executable, "-m", "ruff", "check", "--no-cache", "--select", "C901,PLR0915"]
        + ["--config", "lint.mccabe.max-complexity=12", "--config", "lint.pylint.max-statements=50"]
        + [str(root / p) for p in paths],
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
