"""The README's results on the sample sequences are what the pipeline gives now.

Every row of the README's sample tables (``| `NAME` | frames | distance | final position error |
mean / max heading error | frames flagged | odometry alone |``) is run again, as
``python -m vo_lib run --sequence NAME`` runs it, and each figure is compared with the printed
one. Rendering every sample and running it takes minutes, so these tests carry the ``samples``
mark: the default suite leaves them out and ``.ci/run`` runs them (``python -m pytest -m
samples``). On a mismatch the message carries the row as it should read.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from vo_lib.data import load_sequence
from vo_lib.sim.samples import SAMPLES
from vo_lib.stereo_vo.pipeline import run_sequence
from vo_lib.stereo_vo.run_report import error_report, truth_and_odometry
from vo_lib.stereo_vo.vehicle import vehicle_of

README = Path(__file__).resolve().parents[1] / "README.md"
ROW = re.compile(r"^\| `(?P<name>[a-z0-9_]+)` \| (?P<frames>\d+) \|(?P<rest>.*)\|\s*$")
#: Relative margin on top of the printed rounding: OpenCV and NumPy builds differ in the last bits,
#: and a run of a thousand frames carries that on. A stale figure is off by far more.
RELATIVE = 0.05

pytestmark = pytest.mark.samples


def readme_rows() -> dict[str, list[str]]:
    rows = {}
    for line in README.read_text(encoding="utf-8").splitlines():
        m = ROW.match(line)
        if m and m["name"] in SAMPLES:
            cells = [c.strip() for c in m["rest"].split("|")]
            rows[m["name"]] = [m["frames"], *cells]
    return rows


ROWS = readme_rows()


def quantities(cell: str) -> list[tuple[float, str, int]]:
    """``(value in SI units or degrees or %, unit, decimals printed)`` of each number in a cell."""
    out = []
    for number, unit in re.findall(r"(-?\d+(?:\.\d+)?)\s*(cm|m|°|%)", cell):
        decimals = len(number.split(".")[1]) if "." in number else 0
        value = float(number)
        if unit == "cm":
            value, decimals = value / 100, decimals + 2
        out.append((value, "m" if unit == "cm" else unit, decimals))
    return out


def agrees(quoted: tuple[float, str, int], ours: float) -> bool:
    value, _, decimals = quoted
    return abs(value - ours) <= 0.5 * 10.0**-decimals + RELATIVE * abs(ours) + 1e-12


def as_row(name: str, frames: int, report: dict, flagged: int) -> str:
    """The README row these figures make."""

    def length(m: float) -> str:
        return f"{100 * m:.2f} cm" if m < 0.1 else f"{100 * m:.1f} cm" if m < 1 else f"{m:.2f} m"

    def deg(x: float) -> str:
        return f"{x:.3f}°" if x < 0.1 else f"{x:.2f}°"

    vo, odo = report["vo"], report.get("odometry")
    if report["spot_turn"]:
        distance = f"{report['turned_deg']:.0f}° on the spot"
        final = length(vo["final_position_error_m"])
        alone = "-" if odo is None else f"{odo['final_heading_error_deg']:.1f}° heading"
    else:
        distance = f"{report['distance_m']:.2f} m"
        final = f"{length(vo['final_position_error_m'])} ({vo['final_position_error_pct']:.2f} %)"
        alone = (
            "-"
            if odo is None
            else f"{length(odo['final_position_error_m'])}, {odo['final_heading_error_deg']:.1f}°"
        )
    heading = f"{deg(vo['heading_error_mean_deg'])} / {deg(vo['heading_error_max_deg'])}"
    return f"| `{name}` | {frames} | {distance} | {final} | {heading} | {flagged} | {alone} |"


def test_the_readme_has_rows_to_check():
    assert {"indoor_linear", "road_drive"} <= set(ROWS), sorted(ROWS)


@pytest.mark.parametrize("name", sorted(ROWS))
def test_readme_row_is_what_the_pipeline_gives(name):
    seq = load_sequence(name, progress=False)
    result = run_sequence(seq)
    report = error_report(result, *truth_and_odometry(seq, vehicle_of(seq), len(seq)))
    expected = as_row(name, len(seq), report, len(result.flagged))
    frames, distance, final, heading, flagged, alone = ROWS[name]
    vo, odo = report["vo"], report.get("odometry")
    checks = [(int(frames), len(seq)), (int(flagged), len(result.flagged))]
    figures = [
        (distance, [report["turned_deg"] if report["spot_turn"] else report["distance_m"]]),
        (
            final,
            [vo["final_position_error_m"]]
            if report["spot_turn"]
            else [vo["final_position_error_m"], vo["final_position_error_pct"]],
        ),
        (heading, [vo["heading_error_mean_deg"], vo["heading_error_max_deg"]]),
    ]
    if odo is not None:
        ours = [odo["final_heading_error_deg"]]
        if not report["spot_turn"]:
            ours.insert(0, odo["final_position_error_m"])
        figures.append((alone, ours))
    message = f"README row of {name} should read:\n{expected}"
    assert all(a == b for a, b in checks), message
    for cell, ours in figures:
        quoted = quantities(cell)
        assert len(quoted) == len(ours), f"{cell!r}: expected {len(ours)} figures. {message}"
        assert all(agrees(q, o) for q, o in zip(quoted, ours, strict=True)), f"{cell!r}. {message}"
    assert np.isfinite(result.poses).all()
