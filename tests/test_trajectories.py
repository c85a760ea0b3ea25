import numpy as np
import pytest

from vo_lib.geometry import wrap_angle
from vo_lib.models.track_odometry import TrackOdometry
from vo_lib.sim.samples import SAMPLES
from vo_lib.sim.trajectories import Leg, SlipModel, simulate_drive
from vo_lib.sim.world import WORLDS


def test_drive_follows_the_plan_and_encoders_over_read():
    odo = TrackOdometry(encoder_sigma=0.0)
    slip = SlipModel(mean=0.05, difference=0.0, sigma=0.0)
    drive = simulate_drive([Leg(300, 0.3)], 30.0, (0, 0, 0), np.random.default_rng(1), odo, slip)
    assert len(drive.poses) == 301
    np.testing.assert_allclose(drive.poses[:, 1:], 0.0, atol=1e-12)  # straight along x
    assert drive.poses[-1, 0] == pytest.approx(3.0, rel=0.02)
    reading = odo.integrate(drive.odometry[1:])
    assert reading[-1, 0] == pytest.approx(drive.poses[-1, 0] / 0.95, rel=1e-9)


def test_spot_turn_slip_makes_odometry_over_turn():
    odo = TrackOdometry(encoder_sigma=0.0)
    slip = SlipModel(spot_turn_mean=0.06, spot_turn_difference=0.0, sigma=0.0)
    drive = simulate_drive(
        [Leg(600, 0.0, np.radians(18))], 30.0, (0, 0, 0), np.random.default_rng(2), odo, slip
    )
    truth = np.sum(np.diff(np.unwrap(drive.poses[:, 2])))
    believed = np.sum(odo.increment(drive.odometry)[1])
    assert believed == pytest.approx(truth / 0.94, rel=1e-9)
    assert np.degrees(believed - truth) > 5.0


def test_same_seed_same_drive():
    a = simulate_drive([Leg(50, 0.3, 0.2)], 30.0, (0, 0, 0), np.random.default_rng(7))
    b = simulate_drive([Leg(50, 0.3, 0.2)], 30.0, (0, 0, 0), np.random.default_rng(7))
    np.testing.assert_array_equal(a.odometry, b.odometry)
    np.testing.assert_array_equal(a.poses, b.poses)


@pytest.mark.parametrize("name", list(SAMPLES))
def test_samples_stay_clear_of_walls(name):
    s = SAMPLES[name]
    drive = simulate_drive(s.legs, s.rate, s.start, np.random.default_rng(s.seed))
    segs = WORLDS[s.world]().segments_array()
    a, b = segs[:, :2], segs[:, 2:]
    ab = b - a
    p = drive.poses[:, None, :2]
    t = np.clip(((p - a) * ab).sum(-1) / (ab * ab).sum(-1), 0, 1)
    clearance = np.linalg.norm(a + t[..., None] * ab - p, axis=-1).min()
    assert clearance > 0.35, f"{name} passes {clearance:.2f} m from a wall"
    assert np.isfinite(wrap_angle(drive.poses[:, 2])).all()


def test_empty_or_bad_drives():
    with pytest.raises(ValueError, match="at least one leg"):
        simulate_drive([], 30.0, (0, 0, 0), np.random.default_rng(0))
    with pytest.raises(ValueError, match="rate must be > 0"):
        simulate_drive([Leg(5, 0.1)], 0.0, (0, 0, 0), np.random.default_rng(0))
