"""[Yuan]: likelihood field, score statistics and their readings, principal error direction,
the PnP visual odometer, and the corridor experiment's acceptance over 20 seeds."""

from __future__ import annotations

import math
import os
import pathlib
import re

import numpy as np
import pytest

from vo_lib.lidar_tracking.corridor_experiment import (
    LOST_ERROR,
    TIM551,
    corridor_visual_odometry,
    run_experiment,
    statistics_table,
    without_umbrella,
)
from vo_lib.lidar_tracking.likelihood_field import LikelihoodField
from vo_lib.lidar_tracking.pose_tracking import (
    ControlLimits,
    ScoreStatistics,
    Thresholds,
    compensate,
    posterior,
    principal_error_direction,
    sample_poses,
)
from vo_lib.sim.world import corridor

SEEDS = range(20)


@pytest.fixture(scope="module")
def world():
    return corridor()


@pytest.fixture(scope="module")
def field(world):
    return LikelihoodField.from_world(world)


def lookup(field, points: np.ndarray) -> np.ndarray:
    """The field at world points ``(..., 2)``, nearest cell, 0 off the grid: ``score`` by a mask."""
    col = np.rint((points[..., 0] - field.origin[0]) / field.resolution).astype(np.intp)
    row = np.rint((points[..., 1] - field.origin[1]) / field.resolution).astype(np.intp)
    rows, cols = field.field.shape
    inside = (row >= 0) & (row < rows) & (col >= 0) & (col < cols)
    out = np.zeros(points.shape[:-1], np.float32)
    out[inside] = field.field[row[inside], col[inside]]
    return out


def test_likelihood_field_peaks_on_mapped_walls_only(world, field):
    on_wall = np.array([[10.0, 1.5], [10.0, -1.5]])
    assert np.allclose(lookup(field, on_wall), 1.0, atol=0.05)
    assert lookup(field, np.array([[10.0, 0.0]]))[0] < 1e-6  # the corridor's axis is 1.5 m from walls
    umbrella_tip = np.array([[13.35, 0.95]])  # unmapped: only the field of the nearby wall
    assert lookup(field, umbrella_tip)[0] < 0.01
    # The true pose scores higher than poses beside it.
    scan = TIM551.scan(world.segments_array(), (3.0, 0.0, 0.0), np.random.default_rng(0))
    poses = np.array([[3.0, 0.0, 0.0], [3.0, 0.1, 0.0], [3.0, 0.0, 0.05], [3.2, 0.0, 0.0]])
    s = field.score(poses, scan.points())
    assert np.argmax(s) == 0 and s[0] > 0.9 * scan.valid.sum()


def test_score_reads_the_field_like_lookup(world, field):
    rng = np.random.default_rng(7)
    for x in (0.5, 9.0, 40.0, -5.0):  # the last two put many end points off the grid
        pts = TIM551.scan(world.segments_array(), (x, 0.0, 0.0), rng).points()
        poses = np.column_stack([x + rng.normal(0, 3, 200), rng.normal(0, 3, 200), rng.normal(0, 1, 200)])
        c, s = np.cos(poses[:, 2:3]), np.sin(poses[:, 2:3])
        placed = np.stack(
            [poses[:, :1] + c * pts[:, 0] - s * pts[:, 1], poses[:, 1:2] + s * pts[:, 0] + c * pts[:, 1]], -1
        )
        np.testing.assert_array_equal(
            field.score(poses, pts), lookup(field, placed).sum(axis=1, dtype=np.float64)
        )


def test_printed_eq10_is_nearly_uniform_where_the_posterior_is_not(world, field):
    """Eq. 10 as printed (S_i / sum S_j) keeps every sample within a few tens of per cent of 1/n."""
    rng = np.random.default_rng(8)
    pts = TIM551.scan(world.segments_array(), (3.0, 0.0, 0.0), rng).points()
    scores = field.score(sample_poses(np.array([3.03, 0.0, 0.0]), 500, rng), pts)
    printed = scores / scores.sum() * len(scores)
    assert printed.max() < 1.25 and abs(printed.sum() - len(scores)) < 1e-9
    assert posterior(scores).max() * len(scores) > 10


def test_constant_velocity_prediction_either_way():
    """Eq. 2-3: T_vel = T_curr T_prev^-1 (world frame), T_next = T_vel T_curr, is what the odometer
    predicts with its body-frame velocity."""
    from vo_lib.camera import StereoCamera
    from vo_lib.geometry import planar_to_matrix
    from vo_lib.lidar_tracking.pnp_odometry import PnpVisualOdometry

    t_prev = planar_to_matrix(np.array([1.0, 2.0, 0.3]))
    t_curr = planar_to_matrix(np.array([1.4, 2.3, 0.5]))
    t_curr[:3, 3] += (0.0, 0.0, 0.02)  # not only planar
    vo = PnpVisualOdometry(StereoCamera.bumblebee2())
    vo.pose, vo.velocity = t_curr, np.linalg.inv(t_prev) @ t_curr
    printed = (t_curr @ np.linalg.inv(t_prev)) @ t_curr
    np.testing.assert_allclose(vo.predicted_pose(), printed, atol=1e-12)
    assert not np.allclose(vo.predicted_pose(), t_curr @ t_curr @ np.linalg.inv(t_prev), atol=1e-3)


def test_posterior_and_statistics():
    p = posterior([0.0, 1.0, 2.0])
    assert p.sum() == pytest.approx(1.0) and p[2] / p[1] == pytest.approx(math.e)
    st = ScoreStatistics.from_scores(np.log(np.arange(1, 101)))  # posterior proportional to 1..100
    scaled = np.arange(1, 101) / np.arange(1, 101).sum() * 100
    assert st.v_max == pytest.approx(scaled.max()) and st.v_med == pytest.approx(np.median(scaled))
    assert st.d_s == pytest.approx(st.v_max - st.v_med)
    assert st.d_s_printed == pytest.approx(st.v_max - st.v_lq - st.v_med)
    assert st.r_s == pytest.approx((st.v_max - st.v_lq) / (st.v_uq - st.v_lq))
    # Eq. 12 as printed can never fall below 1: the paper's threshold of 0.7 could never fail.
    rng = np.random.default_rng(1)
    assert min(ScoreStatistics.from_scores(rng.normal(0, 3, 200)).r_s for _ in range(50)) >= 1.0
    assert Thresholds(1.0, 0.5, 1.0).composite(st) and not Thresholds(1e9, 0.0, 0.0).composite(st)


def test_control_limits_follow_table_two():
    # Table II (a): mean 0.0228 m, standard deviation 0.0319 m -> UCL 0.1185 m, LCL 0 m.
    lim = ControlLimits(0.0228, 0.0319)
    assert lim.upper == pytest.approx(0.1185) and lim.lower == 0.0 and lim.centre == 0.0228
    assert lim.contains(0.1) and not lim.contains(0.2) and lim.contains(0.2, updates=4)
    with pytest.raises(ValueError, match="at least 2 corrections"):
        ControlLimits.from_corrections([0.1])


def test_principal_direction_and_compensation():
    rng = np.random.default_rng(2)
    corr = np.column_stack([rng.normal(0, 0.3, 400), rng.normal(0, 0.02, 400), rng.normal(0, 0.001, 400)])
    scores = -np.abs(corr[:, 1]) * 100  # the score cares about y only: x is unobservable
    v = principal_error_direction(corr, scores)
    assert abs(v[0]) > 0.99
    # The heading gate (eq. 18) refuses samples whose headings scatter.
    corr_bad = corr.copy()
    corr_bad[:, 2] = rng.normal(0, 0.2, 400)
    assert principal_error_direction(corr_bad, scores) is None
    # Eq. 21-22: keep the across part of the laser's correction, take the along part from VO.
    t = compensate([0.5, 0.03], [1.0, 0.0], [0.05, -0.2])
    np.testing.assert_allclose(t, [0.05, 0.03])


def test_samples_spread_along_the_robot_heading():
    s = sample_poses(np.array([1.0, 2.0, math.pi / 2]), 4000, np.random.default_rng(3))
    assert np.allclose(s[0], [1.0, 2.0, math.pi / 2])
    assert np.std(s[:, 1]) > 2.5 * np.std(s[:, 0])  # heading +y: along-track spread lies in y


def test_without_umbrella_removes_only_unmapped(world):
    normal = without_umbrella(world)
    assert all(s.mapped for s in normal.segments)
    assert len(normal.segments) == sum(s.mapped for s in world.segments)


@pytest.fixture(scope="module")
def visual_odometry(shared):
    return shared("corridor-visual-odometry", corridor_visual_odometry)


@pytest.fixture(scope="module")
def experiment(shared, visual_odometry):
    return shared("corridor-experiment", lambda: run_experiment(SEEDS, visual_odometry[0]))


def test_pnp_odometer_on_the_corridor(visual_odometry):
    from vo_lib.lidar_tracking.corridor_experiment import corridor_drive

    vo, seconds = visual_odometry
    truth, _ = corridor_drive(0)
    travelled = np.hypot(*(truth[-1, :2] - truth[0, :2]))
    # Measured: 1.5 cm after 27 m.
    assert np.hypot(*(vo[-1, :2] - truth[-1, :2])) < 0.005 * travelled
    assert abs(vo[-1, 2] - truth[-1, 2]) < math.radians(0.5)


def test_voapt_beats_lbpt_along_the_corridor(experiment):
    max_ratio = experiment.spread("max")["VOAPT"][0] / experiment.spread("max")["LBPT"][0]
    mean_ratio = experiment.spread("mean")["VOAPT"][0] / experiment.spread("mean")["LBPT"][0]
    print(f"max ratio {max_ratio:.3f}, mean ratio {mean_ratio:.3f}")
    assert max_ratio <= 0.3
    assert mean_ratio <= 0.2
    # The LBPT really loses its way: an along-corridor error beyond 1 m in some seeds.
    assert max(np.abs(r.errors[:, 0]).max() for r in experiment.lbpt) > 1.0


def test_credibility_flags_lost_frames_and_few_others(experiment):
    assert experiment.flagged_when_lost() >= 0.9
    assert experiment.false_alarms() <= 0.1


README = pathlib.Path(__file__).resolve().parents[1] / "README.md"


def _near(quoted, ours) -> bool:
    """Quoted figures equal ours to their printed precision, with a margin for small changes of the
    visual odometer."""
    return all(abs(q - o) <= 0.003 + 0.05 * o for q, o in zip(quoted, ours, strict=True))


def test_readme_quotes_the_experiment(experiment):
    """The README's Table III rows, T_s shares and lost seeds are this experiment's. VOAPT's figures
    move with OpenBLAS's kernels: they are checked where vo_lib chose the Haswell ones (every x86-64
    CPU with AVX2), and the README's comparison of VOAPT with LBPT everywhere."""
    text = README.read_text(encoding="utf-8")
    keys = ("max", "mean", "median", "std")
    quoted = {}
    for method in ("LBPT", "VOAPT"):
        row = re.search(rf"\| {method} X, ours \(paper\) \|(.*)\|", text)
        assert row, f"README: no Table III row for {method}"
        quoted[method] = [float(v) for v in re.findall(r"([0-9.]+) m \(", row.group(1))]
    ours = {method: [experiment.table(0)[method][k] for k in keys] for method in ("LBPT", "VOAPT")}
    assert _near(quoted["LBPT"], ours["LBPT"]), (quoted["LBPT"], ours["LBPT"])
    shares = re.search(r"T_s flags ([0-9.]+) % of LBPT's updates.*? and ([0-9.]+) % of VOAPT's", text, re.S)
    assert shares, "README: no T_s sentence"
    assert abs(float(shares.group(1)) - 100 * experiment.flagged_when_lost()) <= 0.5
    lost = re.search(
        r"In ([0-9]+) of the ([0-9]+) seeds VOAPT's median error along the\s+corridor exceeds 0\.2 m", text
    )
    assert lost, "README: no sentence on the seeds VOAPT lost"
    medians = [statistics_table(r.errors[:, 0])["median"] for r in experiment.voapt]
    assert int(lost.group(2)) == len(medians)
    bound = re.search(
        r"VOAPT's\s+maximum error,\s+averaged over the seeds,\s+is at most ([0-9.]+) of LBPT's, and its mean"
        r"\s+at most ([0-9.]+)\.",
        text,
    )
    assert bound, "README: no comparison of VOAPT with LBPT"
    below = re.search(
        r"its\s+maximum\s+X\s+error\s+is\s+below\s+LBPT's\s+in\s+([0-9]+)\s+of\s+them,\s+its\s+mean\s+in\s+([0-9]+)\.",
        text,
    )
    assert below, "README: no count of the seeds where VOAPT is below LBPT"
    assert ours["VOAPT"][0] <= float(bound.group(1)) * ours["LBPT"][0]
    assert ours["VOAPT"][1] <= float(bound.group(2)) * ours["LBPT"][1]
    if os.environ.get("OPENBLAS_CORETYPE") == "Haswell":
        assert _near(quoted["VOAPT"], ours["VOAPT"]), (quoted["VOAPT"], ours["VOAPT"])
        assert abs(float(shares.group(2)) - 100 * experiment.false_alarms()) <= 0.5
        assert int(lost.group(1)) == sum(m > LOST_ERROR for m in medians)
        for k, statistic in ((1, "max"), (2, "mean")):
            lower = sum(
                statistics_table(v.errors[:, 0])[statistic] < statistics_table(b.errors[:, 0])[statistic]
                for v, b in zip(experiment.voapt, experiment.lbpt, strict=True)
            )
            assert int(below.group(k)) == lower, (statistic, lower)
