"""The module entry points of the other two papers: ``--help``, ``--seeds``, one-line errors."""

import re

import pytest

from vo_lib.lidar_tracking import corridor_experiment
from vo_lib.line_slam import lap


@pytest.mark.parametrize("module", [lap, corridor_experiment], ids=["lap", "corridor"])
def test_help_names_the_command_and_the_readme_default(module, capsys):
    with pytest.raises(SystemExit) as exit_info:
        module.main(["--help"])
    assert exit_info.value.code == 0
    out = capsys.readouterr().out
    assert out.startswith(f"usage: python -m {module.__name__}")
    assert "--seeds" in out and "default 20" in out


@pytest.mark.parametrize("module", [lap, corridor_experiment], ids=["lap", "corridor"])
@pytest.mark.parametrize(
    "argv,message",
    [
        (["--seeds", "0"], "argument --seeds: expected a whole number >= 1 (seeds); got '0'"),
        (["--seeds", "many"], "argument --seeds: expected a whole number (seeds); got 'many'"),
        (["--laps", "3"], "unrecognized arguments: --laps 3"),
    ],
)
def test_bad_arguments_give_one_line_and_status_2(module, argv, message, capsys):
    with pytest.raises(SystemExit) as exit_info:
        module.main(argv)
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert err == f"python -m {module.__name__}: error: {message}\n"


def test_defaults_are_the_seed_counts_the_readme_quotes():
    assert lap._arguments([]).seeds == 20 and lap._arguments([]).extended_seeds == 10
    assert corridor_experiment._arguments([]).seeds == 20


def test_lap_statistics_over_the_seeds_asked_for(capsys):
    lap.main(["--seeds", "1", "--extended-seeds", "0"])
    out = capsys.readouterr().out
    m = re.search(r"over (\d+) laps: EKF-SLAM ends ([0-9.]+) ± ([0-9.]+) m", out)
    assert m and m.group(1) == "1" and m.group(3) == "0.000"  # one lap: no spread
    assert m.group(2) == f"{lap.simulate_lap(seed=0).final_error():.3f}"
    assert "extended landmark" not in out
