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
