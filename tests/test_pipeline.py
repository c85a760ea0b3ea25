"""The pipeline on rendered samples (in memory): the figures it must reach on each kind of drive."""

import functools
import math

import numpy as np
import pytest

from vo_lib.geometry import relative_planar, wrap_angle
from vo_lib.models.track_odometry import TrackOdometry
from vo_lib.sim.samples import render_sample
from vo_lib.sim.textures import corner_texture
from vo_lib.stereo_vo.frames import Reason
from vo_lib.stereo_vo.pipeline import frame_steps, run_frames


def run_sample(name, frames=None, use_odometry=True):
    rendered, frames_iter = render_sample(name, frames)
    if not use_odometry:
        frames_iter = ((left, right, None) for left, right, _ in frames_iter)
    result = run_frames(frames_iter, rendered.camera)
    truth = relative_planar(rendered.truth()[0], rendered.truth())  # the pipeline starts at the origin
    return rendered, result, truth


def heading_errors(poses, truth):
    return np.degrees(np.abs(wrap_angle(poses[:, 2] - truth[:, 2])))


def test_indoor_linear_final_error_within_one_percent_of_distance():
    _, result, truth = run_sample("indoor_linear")
    assert len(result.poses) == len(truth) == 401
    distance = np.sum(np.linalg.norm(np.diff(truth[:, :2], axis=0), axis=1))
    final = np.linalg.norm(result.poses[-1, :2] - truth[-1, :2])
    assert final <= 0.01 * distance
    # painted walls and plain panels leave a third of the lab's cells without a corner: the median
    # inlier count fell from above 200 (corner texture everywhere) to 136 on the present lab
    assert np.median([d.inliers for d in result.diagnostics[1:]]) >= 110
    assert len(result.flagged) == 0


def test_free_motion_mean_heading_error():
    _, result, truth = run_sample("indoor_free")
    # 2.58 deg and a median of 110 inliers on the lab of painted walls, doors and posters, with a
    # crawler that skids in its turns (sideslip biases eq. 14: notebook 08, section 6); 0.25 deg
    # when the truth followed the planned arcs exactly
    assert heading_errors(result.poses, truth).mean() <= 3.0
    assert np.median([d.inliers for d in result.diagnostics[1:]]) >= 100


def test_spot_turn_fused_heading_holds_where_odometry_drifts():
    # one full turn on the spot: odometry over-counts it by the slip (about 6 %, 23.8 degrees here);
    # the fusion's worst is 3.0 degrees, from the skid about a turning centre ahead of the tracks'
    rendered, result, truth = run_sample("spot_turn", 600)
    odometry = TrackOdometry().integrate(rendered.drive.odometry[1:600])
    odometry_end = heading_errors(odometry[-1:], truth[-1:])[0]
    assert odometry_end >= 5.0
    assert heading_errors(result.poses, truth).max() <= min(4.0, odometry_end / 5)


def test_without_odometry_constant_velocity_still_tracks():
    _, result, truth = run_sample("indoor_linear", 120, use_odometry=False)
    assert not any(d.odometry for d in result.diagnostics)
    assert np.linalg.norm(result.poses[-1, :2] - truth[-1, :2]) < 0.02
    assert heading_errors(result.poses, truth).max() < 0.5


class MovingObject:
    """A textured board at ``depth`` over the left ``fraction`` of the view, sliding 6 px a frame."""

    def __init__(self, camera, depth=1.5, fraction=0.5, speed_px=6.0, seed=99):
        self.disparity = int(round(camera.fx * camera.baseline / depth))
        self.width, self.speed = int(round(fraction * camera.width)), speed_px
        self.texture = corner_texture(camera.height, self.width + 4 * camera.width, seed)

    def occlude(self, left, right, step):
        left, right = left.copy(), right.copy()
        board = self.texture[:, int(round(step * self.speed)) :][:, : self.width]
        left[:, : self.width] = board
        right[:, : self.width - self.disparity] = board[:, self.disparity :]
        return left, right


def test_blank_noise_and_moving_object_frames_are_flagged_exactly():
    """10 blank frames, 10 frames of noise, and an object covering half the view for 10 frames."""
    rendered, frames_iter = render_sample("indoor_free", 100)
    rng = np.random.default_rng(1)
    board = MovingObject(rendered.camera, depth=1.5, fraction=0.5)
    blank, noisy, moving = range(30, 40), range(40, 50), range(60, 70)

    def disturbed():
        for k, (left, right, odo) in enumerate(frames_iter):
            if k in blank:
                left, right = np.full(left.shape, 128, np.uint8), np.full(left.shape, 128, np.uint8)
            elif k in noisy:
                left, right = rng.integers(0, 256, (2, *left.shape), dtype=np.uint8)
            elif k in moving:
                left, right = board.occlude(left, right, k - moving.start)
            yield left, right, odo

    result = run_frames(disturbed(), rendered.camera)
    assert len(result.poses) == 100
    assert result.flagged.tolist() == sorted([*blank, *noisy, *moving])
    truth = relative_planar(rendered.truth()[0], rendered.truth())
    assert heading_errors(result.poses, truth).max() <= 2.0
    reasons = {d.reason for d in result.diagnostics if d.fallback}
    assert any("view lost" in r for r in reasons) and "too few stereo features" in reasons


def test_pipeline_is_deterministic():
    a = run_sample("indoor_linear", 40)[1]
    b = run_sample("indoor_linear", 40)[1]
    np.testing.assert_array_equal(a.poses, b.poses)


def test_timing_table_has_the_paper_columns():
    _, result, _ = run_sample("indoor_linear", 20)
    table = result.timing_table()
    assert set(table) == {"stereo", "prediction", "matching", "estimation", "refinement", "kalman", "total"}
    assert table["total"] >= table["stereo"] > 0
    assert math.isfinite(table["estimation"])
    assert table["refinement"] == 0.0  # the planar pipeline has no 6-DoF refinement
    assert all(v >= 0 for t in result.timings for v in vars(t).values())  # no negative stage times


@pytest.mark.parametrize("bad", ["nan", "missing"])
def test_missing_or_bad_odometry_falls_back_to_constant_velocity(bad):
    rendered, frames_iter = render_sample("indoor_linear", 30)

    def frames():
        for k, (left, right, odo) in enumerate(frames_iter):
            if 10 <= k < 20:
                odo = np.array([np.nan, 0.01]) if bad == "nan" else None
            yield left, right, odo

    result = run_frames(frames(), rendered.camera)
    assert [d.odometry for d in result.diagnostics[10:20]] == [False] * 10
    assert len(result.flagged) == 0


@functools.lru_cache(maxsize=1)
def kitti_like_yard_run():
    """A car-like drive through the photographic yard seen by KITTI's rig (1241x376, 0.54 m
    baseline, camera 1.65 m up and 1.1 m ahead of the axis, 10 m/s at 10 Hz, no odometry): 20
    frames straight, then 20 frames of a 20 deg/s turn, through the car pipeline (6-DoF, pyramid
    front end). Returns the result, the true planar poses and the distance driven."""
    from vo_lib.camera import StereoCamera
    from vo_lib.geometry import camera_mount, planar_to_matrix
    from vo_lib.sim.render import SensorEffects, StereoRenderer
    from vo_lib.sim.trajectories import Leg, SlipModel, simulate_drive
    from vo_lib.sim.world import outdoor_yard
    from vo_lib.stereo_vo.config import CAR
    from vo_lib.stereo_vo.pipeline import StereoOdometry

    camera = StereoCamera(718.856, 718.856, 607.1928, 185.2157, 0.5371657, 1241, 376)
    mount = camera_mount(forward=1.1, height=1.65)
    no_slip = SlipModel(mean=0, difference=0, sigma=0, spot_turn_mean=0, spot_turn_difference=0)
    drive = simulate_drive(
        [Leg(20, 10.0), Leg(20, 10.0, math.radians(20))],
        10.0,
        (-30.0, -10.0, 0.0),
        np.random.default_rng(0),
        slip=no_slip,
    )
    renderer = StereoRenderer(outdoor_yard(), camera, SensorEffects(noise_sigma=1.0))
    rng = np.random.default_rng(1)
    frames = ((*renderer.render_pair(planar_to_matrix(p) @ mount, rng), None) for p in drive.poses)
    result = run_frames(frames, camera, odometer=StereoOdometry(camera, CAR, mount=mount))
    truth = relative_planar(drive.poses[0], drive.poses)
    distance = np.sum(np.linalg.norm(np.diff(truth[:, :2], axis=0), axis=1))
    return result, truth, distance


def test_kitti_like_rig_without_odometry():
    """The straight part is tracked frame by frame and the drive ends within 1 % of its distance
    (measured: 0.05 m of 40 m, 0.12 %)."""
    result, truth, distance = kitti_like_yard_run()
    flagged = set(result.flagged.tolist())
    assert not flagged & set(range(2, 26)), sorted(flagged)
    assert np.linalg.norm(result.poses[-1, :2] - truth[-1, :2]) < 0.01 * distance


def test_kitti_like_rig_keeps_its_matches_through_the_turn():
    """The 20 deg/s turn towards the yard's brick fronts: the courses are regular but the bricks'
    greys, the weathering and the windows are not, so every frame keeps its matches (measured:
    nothing flagged, the heading within 0.5 deg). With the fronts tiled from a mirrored photograph,
    whose slanted courses met in zigzags, the turn lost its matches from frame 26 on."""
    result, truth, _ = kitti_like_yard_run()
    assert set(result.flagged.tolist()) <= {1}  # frame 1 (10 inliers) is flagged on the straight too
    assert heading_errors(result.poses, truth).max() < 0.5


def test_presets_differ_where_the_vehicles_do_and_auto_picks_one():
    from dataclasses import fields, replace

    from vo_lib.camera import StereoCamera
    from vo_lib.stereo_vo.config import CAR, CRAWLER, PRESETS
    from vo_lib.stereo_vo.pipeline import StereoOdometry
    from vo_lib.stereo_vo.planar_motion import PlanarMotion
    from vo_lib.stereo_vo.six_dof import SixDofMotion
    from vo_lib.stereo_vo.vehicle import Motion

    differ = {f.name for f in fields(CRAWLER) if getattr(CRAWLER, f.name) != getattr(CAR, f.name)}
    shared_names = {"recent_frames", "key_distance", "key_angle", "key_max_gap", "retry_fraction"}
    assert shared_names <= differ and "vo_covariance_scale" in differ
    assert PRESETS[Motion.PLANAR] is CRAWLER and PRESETS[Motion.FULL] is CAR
    camera = StereoCamera(400.0, 400.0, 320.0, 240.0, 0.1, 640, 480)
    assert isinstance(StereoOdometry(camera).motion, PlanarMotion)
    assert isinstance(StereoOdometry(camera, CAR, mount=np.eye(4)).motion, SixDofMotion)
    with pytest.raises(ValueError, match="mount"):
        StereoOdometry(camera, CAR)
    with pytest.raises(ValueError, match="motion must be one of planar, full; got 'six'"):
        replace(CAR, motion="six")
    swept = StereoOdometry(camera, replace(CRAWLER, key_distance=0.0))
    assert swept.config.key_distance == 0.0 and CRAWLER.key_distance > 0


def test_restart_reasons_are_reasons_and_a_misspelt_one_is_refused():
    import dataclasses

    from vo_lib.stereo_vo.config import CAR, CRAWLER
    from vo_lib.stereo_vo.frames import LOST_REFERENCE, Reason

    assert CAR.restart_reasons == LOST_REFERENCE and Reason.FEW_INLIERS in CAR.restart_reasons
    by_text = dataclasses.replace(CRAWLER, restart_reasons=("too few inliers", Reason.LOW_INLIER_RATIO))
    assert by_text.restart_reasons == {Reason.FEW_INLIERS, Reason.LOW_INLIER_RATIO}
    with pytest.raises(ValueError, match="restart_reasons: 'too few inlier' is not a valid Reason"):
        dataclasses.replace(CRAWLER, restart_reasons=("too few inlier",))


def test_stopwatch_adds_each_stage_and_counts_the_whole():
    import time

    from vo_lib.stereo_vo.frames import Stopwatch

    watch = Stopwatch()
    for _ in range(2):
        with watch("a"):
            time.sleep(0.01)
    with pytest.raises(KeyError), watch("b"):
        raise KeyError("the stage is timed all the same")
    assert watch.ms["a"] >= 20.0 and "b" in watch.ms
    assert watch.total() >= watch.ms["a"] + watch.ms["b"]


def test_frame_steps_count_the_intervals_a_dropped_frame_leaves():
    """Gaps in units of the median gap, rounded: timing jitter stays one step, a dropped frame is two."""
    times = [0.0, 0.1, 0.21, 0.4, 0.49, 0.8, 0.9]
    assert frame_steps(times).tolist() == [1, 1, 1, 2, 1, 3, 1]
    assert frame_steps([5.0]).tolist() == [1]
    assert frame_steps([0.0, 0.0, 0.0]).tolist() == [1, 1, 1]  # no spacing to measure: one step each
    # repeats a millisecond after their frame: 0 intervals, and the next frame counts from the
    # frame they repeat; sent after every frame, they do not halve the interval
    assert frame_steps([0.0, 0.1, 0.101, 0.3, 0.3005, 0.4]).tolist() == [1, 1, 0, 2, 0, 1]
    every_one = np.repeat(np.arange(5) / 10, 2) + np.tile([0, 1e-3], 5)
    assert frame_steps(every_one).tolist() == [1, 0] + [1, 0] * 4
    # a third of the gaps hold a drop: the interval is still the short gap
    third_dropped = [0, 0.1, 0.3, 0.4, 0.5, 0.7, 0.8, 0.9, 1.1, 1.2]
    assert frame_steps(third_dropped).tolist() == [1, 1, 2, 1, 1, 2, 1, 1, 2, 1]


def test_a_pause_in_the_recording_runs_through_with_its_motion_unknown():
    """Timestamps a day apart in the middle of a drive: the frame after the pause is matched with
    its motion unknown (no constant velocity stepped across a day), and the run goes on."""
    rendered, frames_iter = render_sample("indoor_linear", 40)
    times = np.arange(40) / 30.0
    times[20:] += 86400.0
    assert frame_steps(times)[20] > 1_000_000
    result = run_frames(frames_iter, rendered.camera, times=times)
    assert len(result.poses) == 40 and np.all(np.isfinite(result.poses))
    assert not result.diagnostics[20].fallback  # measured, matched without a prediction
    truth = relative_planar(rendered.truth()[0], rendered.truth())
    assert np.linalg.norm(result.poses[-1, :2] - truth[-1, :2]) < 0.05  # the camera did not move in the pause


def test_a_restart_after_failed_frames_keeps_the_motion_per_interval():
    """The view turned upside down matches nothing, so the pipeline restarts from such a frame. The
    frame remembers the odometry's motion since the old reference divided by the intervals it
    spans (0.01 m a frame at 0.3 m/s and 30 Hz), not by one more."""
    import dataclasses

    from vo_lib.stereo_vo.config import CRAWLER
    from vo_lib.stereo_vo.pipeline import StereoOdometry

    rendered, frames_iter = render_sample("indoor_linear", 20)
    vo = StereoOdometry(rendered.camera, dataclasses.replace(CRAWLER, restart_gap=2))
    restarts = []
    for k, (left, right, odo) in enumerate(frames_iter):
        if k >= 12:
            left, right = np.flipud(left), np.flipud(right)  # the view upside down: nothing matches
        _, _, diag, _ = vo.process(left, right, odo)
        if diag.fallback and vo.gap == 1:  # this failed frame became the reference
            restarts.append((k, float(np.hypot(*vo.kf.last_increment[:2]))))
    assert restarts, "the upside-down view never made the reference stale"
    k, per_interval = restarts[0]
    assert per_interval == pytest.approx(0.01, rel=0.1), k


def test_a_pair_repeated_at_its_time_is_flagged_and_moves_nothing():
    """The same pair again at its time (after the first frame, a keyframe, a frame measured against
    an older reference), carrying half of the next frame's odometry: it keeps the last pose, and
    every other frame's pose is the plain run's. A pair repeated a whole interval later is a view
    of its own time (a standing camera rendered without noise gives such pairs): it is measured."""
    rendered, frames_iter = render_sample("indoor_linear", 30)
    frames = list(frames_iter)
    plain = run_frames(iter(frames), rendered.camera, times=np.arange(30) / 30.0)

    after = (0, 4, 6, 7, 15)  # frames followed by a repeat (4: a keyframe; 6, 7: measured, not keys)
    inserted, times = [], []
    for k, (left, right, odo) in enumerate(frames):
        if k - 1 in after:  # this frame's odometry shared with the repeat before it
            inserted[-1], odo = (*inserted[-1][:2], 0.5 * odo), 0.5 * odo
        inserted.append((left, right, odo))
        times.append(k / 30.0)
        if k in after:
            inserted.append((left, right, None))
            times.append(k / 30.0 + 0.001)
    result = run_frames(iter(inserted), rendered.camera, times=np.array(times))
    repeats = [j for j in range(1, len(inserted)) if inserted[j][0] is inserted[j - 1][0]]
    assert result.flagged.tolist() == repeats
    assert {result.diagnostics[j].reason for j in repeats} == {Reason.REPEATED}
    np.testing.assert_array_equal(result.poses[repeats], result.poses[np.array(repeats) - 1])
    np.testing.assert_allclose(np.delete(result.poses, repeats, axis=0), plain.poses, atol=1e-12)

    replaced = [*frames[:20], (*frames[19][:2], frames[20][2]), *frames[21:]]
    result = run_frames(iter(replaced), rendered.camera, times=np.arange(30) / 30.0)
    assert result.diagnostics[20].reason is not Reason.REPEATED
