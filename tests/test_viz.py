"""The figures of vo_book.plotting and vo_lib.viz draw what they say: [Zhao]'s Fig. 2 and 3, a run."""

import math

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
import pytest

from vo_book.plotting import draw_circular_motion, draw_flowchart
from vo_lib.viz.run_figure import plot_run


@pytest.fixture
def fig():
    figure = plt.figure(figsize=(8, 4))
    yield figure
    plt.close(figure)


def test_fig2_on_the_turning_axis_has_the_papers_chord(fig):
    ax = fig.add_subplot()
    drawn = draw_circular_motion(ax, theta=0.6, radius=2.0)
    assert {"θ", "φ", "ρ", "ICR", "C", "C'"} <= set(drawn["labels"])
    assert drawn["rho"] == pytest.approx(2 * 2.0 * math.sin(0.3)) and drawn["phi"] == pytest.approx(0.3)
    assert "offset" not in drawn["labels"]
    assert len(ax.patches) == 2  # the arcs of theta and phi


def test_fig2_with_a_camera_offset_widens_the_circle_and_leans_the_chord(fig):
    ax = fig.add_subplot()
    drawn = draw_circular_motion(ax, theta=0.6, radius=2.0, offset=0.5)
    assert "offset" in drawn["labels"]
    assert drawn["rho"] == pytest.approx(2 * math.hypot(2.0, 0.5) * math.sin(0.3))
    assert drawn["phi"] == pytest.approx(0.3 + math.atan2(0.5, 2.0))  # leans by the offset's angle
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "camera offset from the turning axis" in legend


def test_fig3_flowchart_has_one_box_per_stage_and_the_feedback_arrow(fig):
    ax = fig.add_subplot()
    stages = ["stereo pair", "stereo processing", "prediction", "RANSAC", "update"]
    drawn = draw_flowchart(ax, stages, side=[(2, 3, "prior")])
    assert [b.get_text() for b in drawn["boxes"]] == stages
    assert len(drawn["arrows"]) == len(stages) - 1 + 1
    ys = [b.get_position()[1] for b in drawn["boxes"]]
    assert ys == sorted(ys, reverse=True)  # top to bottom
    assert "prior" in [t.get_text() for t in ax.texts]


def _drive(turn_only: bool):
    t = np.linspace(0.0, 10.0, 101)
    if turn_only:
        truth = np.column_stack([0.001 * np.sin(t), np.zeros_like(t), np.radians(36.0) * t])
    else:
        truth = np.column_stack([0.2 * t, 0.05 * t**2, 0.1 * t])
    estimate = truth + [0.01, -0.005, math.radians(0.2)]
    odometry = truth + np.column_stack([0.003 * t, 0.002 * t, np.radians(0.5) * t])
    return t, truth, estimate, odometry


def test_run_figure_plan_view_marks_start_and_end_above_a_visible_truth(fig):
    t, truth, estimate, odometry = _drive(turn_only=False)
    drawn = plot_run(fig, t, estimate, truth, odometry, "drive")
    assert not drawn["spot_turn"] and len(drawn["errors"]) == 2
    lines = {line.get_label(): line for line in drawn["main"].get_lines()}
    assert {"ground truth", "track odometry", "visual odometry (fused with odometry)", "start"} <= set(lines)
    assert (
        lines["ground truth"].get_linewidth()
        > 2 * lines["visual odometry (fused with odometry)"].get_linewidth()
    )
    assert lines["visual odometry (fused with odometry)"].get_linestyle() == "--"
    assert lines["ground truth"].get_zorder() < lines["visual odometry (fused with odometry)"].get_zorder()
    np.testing.assert_allclose(lines["start"].get_xydata(), [truth[0, :2]])
    errors = {line.get_label(): line.get_ydata() for line in drawn["errors"][0].get_lines()}
    np.testing.assert_allclose(errors["visual odometry (fused with odometry)"], 100 * math.hypot(0.01, 0.005))
    assert drawn["errors"][1].get_ylabel() == "heading error [deg]"


def test_run_figure_of_a_spot_turn_plots_heading_against_truth(fig):
    t, truth, estimate, odometry = _drive(turn_only=True)
    drawn = plot_run(fig, t, estimate, truth, odometry, "turn")
    assert drawn["spot_turn"]
    assert drawn["main"].get_ylabel() == "heading, unwrapped [deg]"
    assert "360° turned on the spot" in drawn["main"].get_title()
    lines = {line.get_label(): line for line in drawn["main"].get_lines()}
    assert lines["ground truth"].get_ydata()[-1] == pytest.approx(360.0)  # unwrapped, not folded
    heading_errors = {line.get_label(): line.get_ydata() for line in drawn["errors"][1].get_lines()}
    assert heading_errors["track odometry"][-1] == pytest.approx(5.0)


def test_run_figure_without_truth_is_one_plan_view(fig):
    t, _, estimate, _ = _drive(turn_only=False)
    drawn = plot_run(fig, t, estimate, title="no truth")
    assert drawn["errors"] == [] and len(fig.axes) == 1 and not drawn["spot_turn"]
    # one end marked, the estimate's: not a second marker of the same point under another name
    labels = drawn["main"].get_legend_handles_labels()[1]
    assert labels == ["visual odometry", "start", "end (visual odometry)"]


def test_run_figure_of_a_drone_draws_its_errors_in_3d(fig):
    """Given camera poses (a body with no ground plane), the errors are the 3-D position error and
    the angle of the rotation error, whatever the planar paths say."""
    from scipy.spatial.transform import Rotation

    t, truth, estimate, _ = _drive(turn_only=False)
    T = np.tile(np.eye(4), (len(t), 1, 1))
    E = T.copy()
    E[:, :3, :3] = Rotation.from_rotvec(np.outer(np.linspace(0, 0.02, len(t)), [1.0, 0, 0])).as_matrix()
    E[:, 2, 3] = 0.03  # 3 cm off along the camera's axis, which no plan view of the ground shows
    drawn = plot_run(fig, t, estimate, truth, camera_poses=(E, T))
    position, rotation = (ax.lines[0].get_ydata() for ax in drawn["errors"])
    assert np.allclose(position, 3.0) and np.isclose(rotation[-1], math.degrees(0.02))
    assert drawn["errors"][1].get_ylabel() == "rotation error [deg]"
