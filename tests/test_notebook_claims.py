"""The notebooks' helper modules, and the bookkeeping claims their story cells no longer assert.

The story cells of the notebooks keep the asserts that check a derivation or stand beside a
comparative sentence; what only guards the scaffolding (a widget's default run succeeds, a
helper counts what it says) is checked here, on the helper modules the notebooks import.
"""

from __future__ import annotations

import math
import pathlib
import re

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
import skimage.data  # noqa: E402
import sympy as sp  # noqa: E402

from vo_book import (  # noqa: E402
    demo_corridor,
    demo_fusion,
    demo_one_point,
    demo_pipeline,
    demo_worlds,
    nb03,
    nb04,
    nb05,
    nb06,
    nb09,
    nb11,
)
from vo_lib.camera import StereoCamera  # noqa: E402
from vo_lib.formats.sequence import read_sequence  # noqa: E402
from vo_lib.sim.laser import LaserScanner  # noqa: E402
from vo_lib.sim.samples import generate, render_sample  # noqa: E402
from vo_lib.stereo_vo.ransac import DEFAULT_PARAMS  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[1]


@pytest.fixture(autouse=True)
def _no_figures_left():
    yield
    plt.close("all")


# --- notebook 06 -----------------------------------------------------------------------------


def test_realistic_matches_carry_the_stated_outlier_mix():
    rng = np.random.default_rng(0)
    n = 300
    w_prev, w_curr, inliers = demo_one_point.realistic_matches(n, math.radians(3), 0.08, rng)
    assert w_prev.shape == w_curr.shape == (n, 3) and inliers.shape == (n,)
    stated = demo_one_point.RANDOM_SHARE + demo_one_point.NEAR_MISS_SHARE + demo_one_point.MOVER_SHARE
    assert abs(np.mean(~inliers) - stated) <= 0.02
    moved = np.abs(w_curr[:, 0] - w_prev[:, 0])
    # the inliers keep their draw; a near miss or a mover only shifts u
    assert np.all(np.isfinite(moved))


def test_realistic_matches_repeat_with_the_seed():
    a = demo_one_point.realistic_matches(200, 0.02, 0.05, np.random.default_rng(4))
    b = demo_one_point.realistic_matches(200, 0.02, 0.05, np.random.default_rng(4))
    assert all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))


def test_the_widget_trial_succeeds_at_its_default_setting():
    """The notebook's `ransac_trial()` at 40 % outliers and 0.5 px (its widget's start)."""
    assert demo_one_point.ransac_trial() >= 0.95


def test_draws_to_first_good_is_one_over_the_good_share():
    rng = np.random.default_rng(1)
    good = np.zeros(1000, bool)
    good[:250] = True
    assert demo_one_point.draws_to_first_good(np.arange(1000), np.ones(1000, bool), rng) == 1.0
    assert abs(demo_one_point.draws_to_first_good(np.arange(1000), good, rng) - 4.0) < 0.4


def test_side_of_band_names_a_side_only_for_a_whole_interval():
    band = (2.0, 4.0)
    assert nb06.side_of_band(3.0, 2.5, 3.5, band) == "inside the band"
    assert nb06.side_of_band(1.0, 0.5, 1.5, band).startswith("below")
    assert "over-confident" in nb06.side_of_band(9.0, 8.0, 10.0, band)
    for low, high in ((3.0, 5.0), (1.0, 3.0), (1.0, 5.0)):  # the interval overlaps the band
        assert nb06.side_of_band(3.5, low, high, band).startswith("at the band's edge")


def test_notebook_06_constants_are_the_library_defaults():
    """Notebook 06 says the library uses the same values as its constants."""
    text = next((ROOT / "notebooks").glob("06_*.py")).read_text(encoding="utf-8")
    names = ("PIXEL_SIGMA", "GATE_SIGMAS", "CONFIDENCE", "POOL_FRACTION", "MIN_POOL")
    names += ("REFINE_ITERATIONS", "REFINE_ROUNDS", "WHITENED_GATE")
    for name in names:
        typed = re.search(rf"^{name} = ([0-9.]+)", text, re.M)
        assert typed, f"notebook 06 types no {name}"
        assert float(typed.group(1)) == getattr(DEFAULT_PARAMS, name.lower()), name


# --- notebook 07 -----------------------------------------------------------------------------


def test_the_fuse_widget_shows_odometry_running_away_in_the_spot_turn():
    """The notebook's `fuse()` at its defaults: the slip runs odometry's heading away."""
    errors = demo_fusion.fuse()
    assert set(errors) == set(demo_fusion.ESTIMATORS)
    assert errors["odometry"] > 5 * errors["fused"]  # a wide margin: the slip's mean is 6 % of the turn


def test_heading_error_wraps():
    est = np.array([[0, 0, math.radians(179)]])
    truth = np.array([[0, 0, math.radians(-179)]])
    assert np.allclose(demo_fusion.heading_error(est, truth), [-2.0])
    assert np.allclose(demo_pipeline.heading_error(est, truth), [-2.0])


# --- notebook 08 -----------------------------------------------------------------------------


def test_rms_does_not_cancel_and_frames_follow_the_mode():
    assert demo_pipeline.rms((3.0, 4.0)) == 5.0 and demo_pipeline.rms((-3.0, 4.0)) == 5.0
    assert demo_pipeline.frames_for("spot_turn", 7, full=False) == 7
    assert demo_pipeline.frames_for("spot_turn", 7, full=True) > 7


def test_sides_names_above_and_below():
    ratio = {("a", "x_mm"): 2.0, ("a", "y_mm"): 0.5}
    words = demo_pipeline.sides(["a"], ratio, ("x_mm", "y_mm", "theta_deg"))
    assert words == "`a` above in x_mm, below in y_mm"


# --- notebook 09 -----------------------------------------------------------------------------


def test_differing_entries_and_finite_differences():
    x = sp.symbols("x")
    derived, printed = sp.Matrix([[sp.sin(x), 2 * x]]), sp.Matrix([[sp.sin(x), -2 * x]])
    assert [(i, j) for i, j, *_ in nb09.differing_entries(derived, printed)] == [(0, 1)]
    jac = nb09.finite_difference(lambda v: np.array([v[0] ** 2, v[0] * v[1]]), [3.0, 2.0])
    assert np.allclose(jac, [[6.0, 0.0], [2.0, 3.0]], atol=1e-6)
    to_derived, to_printed = nb09.judge("f", np.array([[math.sin(1.0), 2.0]]), derived, printed, {x: 1.0})
    assert to_derived < 1e-12 and abs(to_printed - 4.0) < 1e-12


# --- notebook 10 -----------------------------------------------------------------------------


def test_auc_and_box_statistics():
    assert demo_corridor.auc([2, 3], [0, 1]) == 1.0 and demo_corridor.auc([0, 1], [2, 3]) == 0.0
    a, b = np.random.default_rng(2).normal(size=(2, 50))
    assert math.isclose(demo_corridor.auc(a, b) + demo_corridor.auc(b, a), 1.0)
    s = demo_corridor.box_statistics(np.arange(101.0))
    assert s["v_max"] == 100 and s["d_s"] == 50 and s["d_s_printed"] == 25 and s["r_s"] == 1.5


def test_rate_sentence_states_the_verdict_the_interval_gives():
    nominal = {"laser": 0.01}

    def words(mean, low, high):
        return demo_corridor.rate_sentence("laser", {"laser": (mean, low, high)}, nominal)

    assert "not reliably different" in words(0.01, 0.0, 0.02)
    assert "5.0 to 9.0 times it" in words(0.07, 0.05, 0.09)
    assert "below the nominal" in words(0.001, 0.0, 0.005)


# --- notebook 04: a sequence on disk reads back as it was rendered ---


def test_a_generated_sequence_reads_back_as_rendered(tmp_path):
    """Notebook 04, section 6: five corridor frames at 320x240 written and read again."""
    path = generate("corridor", tmp_path / "corridor", frames=5, resolution=(320, 240), progress=False)
    seq = read_sequence(path)
    rendered, frames = render_sample("corridor", 5, (320, 240))
    left, right, _ = next(iter(frames))
    assert np.allclose(seq.odometry, rendered.drive.odometry[:5], atol=1e-9)
    full = StereoCamera.bumblebee2()
    assert np.isclose(seq.camera.baseline, full.baseline) and np.isclose(seq.camera.fx, full.fx / 2)
    first_left, first_right = seq.pair(0)
    assert np.array_equal(first_left, left) and np.array_equal(first_right, right)


# --- notebooks 04, 05, 11 --------------------------------------------------------------------


def test_panel_grid_hides_the_spares():
    fig, axes = nb04.panel_grid(4)
    assert len(axes) == 4 and sum(ax.get_visible() for ax in fig.axes) == 4


def test_cells_covered_counts_distinct_cells():
    points = np.array([[1.0, 1.0], [79.0, 79.0], [81.0, 1.0], [1.0, 161.0]])
    assert nb05.cells_covered(points) == 3


def test_errors_against_the_truth():
    truth = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.1]])
    final_errors = nb11.errors_against(truth)
    assert final_errors(truth) == (0.0, 0.0, 0.0)
    metres, percent, heading = final_errors(truth[:2] + [0.0, 0.1, 0.0])
    assert math.isclose(metres, 0.1) and math.isclose(percent, 10.0) and heading == 0.0


def test_image_statistics_of_a_blank_image_and_a_photograph():
    blank = nb11.image_statistics(np.zeros((64, 64), np.uint8))
    assert blank["empty"] == 1.0 and blank["flat"] == 1.0 and len(blank["corners"]) == 0
    photo = skimage.data.camera()  # a 512x512 photograph: corners on the man and the tripod
    stats = nb11.image_statistics(photo)
    assert len(stats["corners"]) > 100 and stats["empty"] < 1.0 and stats["occupied"].shape == (32, 32)


def test_the_walk_widget_sees_the_corridor_from_its_default_pose():
    """Notebook 04's `view_from()`: about half of the scanner's beams or more end on a wall."""
    scanner = LaserScanner()
    beams = int(round(scanner.fov / scanner.angular_step)) + 1
    assert demo_worlds.view_from() > 0.49 * beams


def test_local_exponent_reads_a_power_law():
    centres = np.array([1.0, 2.0, 4.0, 8.0])
    measured = 3.0 * centres**-1.5
    assert all(math.isclose(nb03.local_exponent(measured, centres, i), 1.5) for i in range(3))
