import numpy as np
import pytest

from vo_lib.geometry import wrap_angle
from vo_lib.models.track_odometry import TrackOdometry
from vo_lib.sim.samples import SAMPLES, _world_poses
from vo_lib.sim.trajectories import RIGID_GROUND, ROUGH_GROUND, Leg, SlipModel, TrackGround, simulate_drive
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
    drive = simulate_drive(
        s.legs, s.rate, s.start, np.random.default_rng(s.seed), slip=s.slip, surface=s.surface
    )
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


NO_SLIP = SlipModel(mean=0, difference=0, sigma=0, spot_turn_mean=0, spot_turn_difference=0)


def _drive(legs, surface, seed=3, slip=NO_SLIP):
    odo = TrackOdometry(encoder_sigma=0.0)
    return odo, simulate_drive(legs, 30.0, (0, 0, 0), np.random.default_rng(seed), odo, slip, surface)


def test_rigid_ground_follows_the_plan_like_no_ground():
    legs = [Leg(90, 0.3), Leg(120, 0.3, np.radians(25)), Leg(60, 0.0, np.radians(-18))]
    _, plain = _drive(legs, None)
    _, rigid = _drive(legs, RIGID_GROUND)
    np.testing.assert_allclose(rigid.poses, plain.poses, atol=1e-9)
    np.testing.assert_array_equal(rigid.odometry, plain.odometry)
    np.testing.assert_array_equal(rigid.attitude, 0.0)


def test_turning_body_skids_outward_by_the_icr_offset():
    # a steady left arc: the body moves sideways at -x_icr * omega, outward of the turn, and the
    # encoders (no slip) see only the arc
    surface = TrackGround(icr_offset=0.03, icr_per_rate=0.1, icr_sigma=0.0)
    omega, speed = np.radians(20), 0.4
    odo, drive = _drive([Leg(300, speed, omega)], surface)
    x_icr = 0.03 + 0.1 * omega
    np.testing.assert_allclose(drive.icr[50:250], x_icr, rtol=1e-12)
    steps = np.diff(drive.poses[100:200], axis=0)
    heading = drive.poses[100:199, 2] + steps[:, 2] / 2
    lateral = -np.sin(heading) * steps[:, 0] + np.cos(heading) * steps[:, 1]
    np.testing.assert_allclose(lateral, -x_icr * omega / 30.0, rtol=1e-3)
    believed = odo.integrate(drive.odometry[1:])
    np.testing.assert_allclose(believed[:, 2], drive.poses[:, 2], atol=1e-9)  # same turning
    assert np.hypot(*(believed[-1, :2] - drive.poses[-1, :2])) > 0.5 * x_icr


def test_spot_turn_centre_circles_the_shifted_icr_which_moves_with_turn_rate():
    surface = TrackGround(icr_offset=0.02, icr_per_rate=0.06, icr_sigma=0.0)
    radii = []
    for rate_deg in (10.0, 30.0):
        _, drive = _drive([Leg(1200, 0.0, np.radians(rate_deg))], surface)
        xy = drive.poses[30:1170, :2]
        centre = xy.mean(axis=0)  # whole turns: the circle's centre
        radii.append(np.linalg.norm(xy - centre, axis=1).mean())
        assert radii[-1] == pytest.approx(0.02 + 0.06 * np.radians(rate_deg), rel=0.02)
    assert radii[1] > radii[0] + 0.5 * 0.06 * np.radians(20)


def test_loss_of_contact_turns_the_body_and_tilts_it_unseen_by_encoders():
    surface = TrackGround(icr_sigma=0.0, contact_rate=2.0, tilt_deg=(2.0, 5.0))
    odo, drive = _drive([Leg(600, 0.5)], surface, seed=5)
    lost = drive.grip < 1.0
    assert lost.any(axis=0).all()  # both tracks lost contact at least once in 10 m
    tilt = np.degrees(np.abs(drive.attitude))
    assert 2.0 * np.sin(np.pi * 2.5 / 6) <= tilt.max() <= 2 * 5.0  # half-sine peaks; losses may overlap
    np.testing.assert_array_equal(tilt[~lost.any(axis=1)], 0.0)  # flat ground between losses
    believed = odo.integrate(drive.odometry[1:])
    np.testing.assert_allclose(believed[:, 2], 0.0, atol=1e-12)  # encoders: straight ahead
    assert np.degrees(np.abs(drive.poses[:, 2]).max()) > 0.5  # the body was swung round
    assert drive.poses[-1, 0] < believed[-1, 0] - 0.01  # and fell behind the encoders


def test_rough_sample_tilts_the_camera_off_the_plane():
    s = SAMPLES["outdoor_free"]
    drive = simulate_drive(
        s.legs, s.rate, s.start, np.random.default_rng(s.seed), slip=s.slip, surface=s.surface
    )
    poses = _world_poses(s, drive)
    up = np.degrees(np.arccos(np.clip(poses[:, 2, 2], -1, 1)))
    assert 2.0 < up.max() < 10.0 and np.median(up) < 1.5
    np.testing.assert_allclose(poses[:, :2, 3], drive.poses[:, :2], atol=1e-12)  # tilt about contact
    assert s.surface is ROUGH_GROUND and SAMPLES["indoor_free"].surface.contact_rate == 0


def test_same_seed_same_skid():
    legs = [Leg(200, 0.5, 0.2)]
    a = _drive(legs, ROUGH_GROUND, seed=9)[1]
    b = _drive(legs, ROUGH_GROUND, seed=9)[1]
    np.testing.assert_array_equal(a.poses, b.poses)
    np.testing.assert_array_equal(a.attitude, b.attitude)


def test_a_skidding_spot_turn_still_counts_as_one():
    from vo_lib.evaluation import is_spot_turn, planar_path_length

    paths = {}
    for name in ("spot_turn", "outdoor_free"):
        s = SAMPLES[name]
        rng = np.random.default_rng(s.seed)
        paths[name] = simulate_drive(s.legs, s.rate, s.start, rng, slip=s.slip, surface=s.surface).poses
    assert planar_path_length(paths["spot_turn"]) > 0.1  # the centre circles its turning centre
    assert is_spot_turn(paths["spot_turn"]) and not is_spot_turn(paths["outdoor_free"])
