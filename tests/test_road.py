"""The road drive: its geometry, what it writes, and that the command line reads it as a car's."""

import numpy as np
import pytest

from vo_lib.formats.sequence import read_sequence
from vo_lib.geometry import relative_planar, wrap_angle
from vo_lib.sim import road
from vo_lib.sim.samples import SAMPLES, generate, render_sample
from vo_lib.sim.world import road_world
from vo_lib.stereo_vo.config import CAR
from vo_lib.stereo_vo.pipeline import StereoOdometry, run_frames
from vo_lib.stereo_vo.vehicle import KITTI_CAMERA_IN_IMU, car_odometry_model, vehicle_of


def test_rig_and_odometry_are_the_ones_the_car_pipeline_assumes():
    assert road.CAMERA_IN_VEHICLE == KITTI_CAMERA_IN_IMU
    assert road.CAR_ODOMETRY == car_odometry_model()
    height = road.VEHICLE_ORIGIN_HEIGHT + road.CAMERA_IN_VEHICLE[2]
    assert abs(height - 1.65) < 1e-9
    assert SAMPLES["road_drive"].resolution == (1242, 375)


def test_drive_has_two_sharp_bends_at_car_speeds_a_climb_and_a_bank():
    path = road.planned_path()
    heading = np.degrees(np.unwrap(path[:, 2]))
    speed = np.linalg.norm(np.diff(path[:, :2], axis=0), axis=1) * road.RATE
    assert 5.0 <= speed.min() and speed.max() <= 15.0
    assert heading.max() - heading[0] > 89.9  # left bend
    assert heading.max() - heading[-1] > 89.9  # then right bend
    poses = road.vehicle_poses(path)
    rise = poses[:, 2, 3].max() - poses[:, 2, 3].min()
    assert 1.5 < rise < 1.7  # 4 % over 40 m, as much again over the vertical curves
    roll = np.degrees(np.arctan2(poses[:, 2, 1], poses[:, 2, 2]))
    assert abs(roll.max() - np.degrees(np.arctan(road.BANK_CROSSFALL))) < 0.01


def test_road_world_has_a_continuous_road_and_traffic_that_moves():
    world = road_world()
    ends = [np.asarray(p.outline) for p in world.patches]
    for a, b in zip(ends[:-1], ends[1:], strict=True):
        np.testing.assert_allclose(a[1], b[0], atol=1e-9)  # pieces share their edges: no gaps
        np.testing.assert_allclose(a[2], b[3], atol=1e-9)
    assert len(world.movers) == 3
    for mover in world.movers:
        assert mover.start >= 0.0  # on its path from the start, not waiting at its beginning
        (p0, _), (p1, _) = mover.pose(1.0), mover.pose(2.0)
        assert abs(np.linalg.norm(p1 - p0) - mover.speed) < 0.05 * mover.speed


def test_generated_road_drive_is_read_as_a_car_with_wheel_odometry(tmp_path):
    out = generate("road_drive", tmp_path / "road", frames=4, resolution=(311, 94), progress=False)
    seq = read_sequence(out)
    # at another shape too, the pixels stay square: the copy of another size reads back
    square = read_sequence(
        generate("road_drive", tmp_path / "sq", frames=2, resolution=(64, 64), progress=False)
    )
    assert square.camera.fx == square.camera.fy == pytest.approx(road.KITTI_RIG[0] * 64 / 1242)
    vehicle = vehicle_of(seq)
    assert (vehicle.kind, vehicle.motion, vehicle.odometry_source) == ("car", "full", "odometry.txt")
    np.testing.assert_allclose(vehicle.mount[:3, 3], KITTI_CAMERA_IN_IMU)
    # ground truth: the camera moves 1.2 m per frame on the first straight
    step = np.linalg.norm(np.diff(seq.poses[:, :3, 3], axis=0), axis=1)
    np.testing.assert_allclose(step, 12.0 / road.RATE, rtol=0.02)
    # the odometry: two wheels 1.6 m apart, each about 1.2 m per frame on the straight
    np.testing.assert_allclose(seq.odometry[1:], 1.2, rtol=0.05)


def test_full_pipeline_through_the_banked_bend():
    """Frames 160-179 of the road drive (the right bend, banked 2.9 deg, 5.5 m/s, traffic), rendered
    in memory, through the 6-DoF pipeline with the wheel odometry. Measured: nothing flagged,
    final position error 1.2 cm of 10.5 m (0.12 %), heading error at most 0.07 deg."""
    rendered, frames = render_sample("road_drive", 20, first=160)
    odometer = StereoOdometry(rendered.camera, CAR, road.CAR_ODOMETRY, rendered.mount)
    result = run_frames(frames, rendered.camera, odometer=odometer)
    truth = relative_planar(rendered.truth()[0], rendered.truth())
    distance = np.sum(np.linalg.norm(np.diff(truth[:, :2], axis=0), axis=1))
    error = np.linalg.norm(result.poses[-1, :2] - truth[-1, :2])
    heading = np.degrees(np.abs(wrap_angle(result.poses[:, 2] - truth[:, 2]))).max()
    print(f"flagged {result.flagged.tolist()}, {error:.4f} m of {distance:.2f} m, heading {heading:.3f} deg")
    assert len(result.flagged) <= 2
    assert error < 0.01 * distance
    assert heading < 1.0


def test_road_images_are_as_hard_as_real_road_images():
    """Six frames spread over the drive fall within the real road sequences' range (the outdoor
    range of ``bench realism``). Measured: 0.62 of cells without a corner, 0.48 low-gradient pixels."""
    from vo_lib.bench.bench_realism import OUTDOOR_RANGE, sample_statistics

    stats = sample_statistics("road_drive", 6)
    (e0, e1), (g0, g1) = OUTDOOR_RANGE
    assert e0 <= stats.empty_cells <= e1
    assert g0 <= stats.low_gradient <= g1
