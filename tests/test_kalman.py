import math

import numpy as np
import pytest
from scipy.stats import chi2

from vo_lib.geometry import compose_planar
from vo_lib.models.track_odometry import TrackOdometry
from vo_lib.stereo_vo.kalman import VoKalmanFilter, measurement, nis

ODO = TrackOdometry()
R_VO = np.diag([math.radians(0.05) ** 2, 0.002**2])


P0 = np.diag([0.01**2, 0.01**2, math.radians(0.5) ** 2])


def simulate(kf, rng, steps, vo_every=1, odometry=True):
    truth, nees = kf.pose + rng.multivariate_normal(np.zeros(3), kf.covariance), []
    for k in range(steps):
        u_true = ODO.controls_for(0.02 + 0.01 * math.sin(k / 20), math.radians(1.0) * math.sin(k / 30))
        u_meas = u_true + rng.multivariate_normal(np.zeros(2), kf.control_covariance(u_true))
        prev, truth = truth, ODO.predict(truth, u_true)
        kf.predict(u_meas if odometry else None)
        if vo_every and k % vo_every == 0:
            z = measurement(np.concatenate([truth, prev])) + rng.multivariate_normal(np.zeros(2), R_VO)
            kf.update(z[0], z[1], R_VO)
        kf.finish_frame()
        nees.append(kf.nees(truth))
    return np.array(nees)


def test_nees_of_fused_filter_lies_in_the_95_percent_band():
    runs, steps = 50, 200
    # the initial truth is drawn from the initial covariance, so NEES is chi-square(3) from the start
    nees = np.array(
        [
            simulate(VoKalmanFilter(ODO, covariance=P0), np.random.default_rng(1000 + r), steps)
            for r in range(runs)
        ]
    )
    avg = nees.mean(axis=0)
    lo, hi = chi2.ppf([0.025, 0.975], 3 * runs) / runs
    assert lo < avg.mean() < hi
    assert np.mean((avg > lo) & (avg < hi)) >= 0.9


def test_odometry_only_covariance_grows_and_frames_are_flagged():
    kf = VoKalmanFilter(ODO)
    rng = np.random.default_rng(3)
    simulate(kf, rng, 50, vo_every=0)
    first = kf.covariance.trace()
    assert not kf.flags.vo_update and kf.flags.odometry
    simulate(kf, rng, 50, vo_every=0)
    assert kf.covariance.trace() > first


def test_vo_update_shrinks_the_uncertainty():
    kf_odo, kf_fused = VoKalmanFilter(ODO), VoKalmanFilter(ODO)
    simulate(kf_odo, np.random.default_rng(4), 100, vo_every=0)
    simulate(kf_fused, np.random.default_rng(4), 100, vo_every=1)
    assert kf_fused.covariance[2, 2] < 0.2 * kf_odo.covariance[2, 2]


def test_constant_velocity_without_odometry():
    kf = VoKalmanFilter(ODO)
    kf.predict(None)
    kf.update(0.01, 0.05, R_VO)
    kf.finish_frame()
    kf.predict(None)  # repeats the last motion
    prior = kf.motion_prior()
    assert prior.theta == pytest.approx(0.01, abs=1e-3) and prior.rho == pytest.approx(0.05, abs=2e-3)
    assert not kf.flags.odometry


def test_constant_velocity_over_a_gap_moves_and_spreads_as_many_intervals():
    """``steps`` intervals at once: the pose moves by the last increment ``steps`` times over, and
    the added spread is ``steps`` times one interval's (one velocity error, over every interval)."""
    kfs = []
    for steps in (1, 3):
        kf = VoKalmanFilter(ODO)
        kf.last_increment = np.array([0.05, 0.002, 0.01])
        kf.ekf.P[:] = 0.0
        kf.predict(None, steps=steps)
        kfs.append(kf)
    one, three = kfs
    x = np.zeros(3)
    for _ in range(3):
        x = compose_planar(x, one.last_increment)
    assert np.allclose(three.pose, x)
    assert np.allclose(np.diag(three.covariance), 9 * np.diag(one.covariance), rtol=1e-9)


def test_prior_matches_odometry_prediction():
    kf = VoKalmanFilter(ODO)
    u = ODO.controls_for(0.05, 0.02)
    kf.predict(u)
    prior = kf.motion_prior()
    # eq. 2-3 move the centre by du along the midpoint heading: the chord of eq. 15 is du itself
    assert prior.theta == pytest.approx(0.02) and prior.rho == pytest.approx(0.05, rel=1e-9)
    assert prior.covariance[0, 0] > 0 and prior.covariance[1, 1] > 0


def test_reference_kept_across_frames_without_vision():
    """Three frames without VO, then a measurement of the motion from the last seen frame."""
    rng = np.random.default_rng(8)
    kf = VoKalmanFilter(ODO, covariance=P0)
    truth = kf.pose.copy()
    reference = truth.copy()
    for k in range(4):
        u = ODO.controls_for(0.03, 0.01)
        truth = ODO.predict(truth, u)
        kf.predict(u + rng.normal(0, 1e-4, 2), keep_reference=k > 0)
        kf.finish_frame()
    assert np.allclose(kf.ekf.x[3:], reference)  # the clone is still the reference frame's pose
    before = kf.covariance[2, 2]
    z = measurement(np.concatenate([truth, reference]))  # the motion over all four frames
    kf.update(z[0], z[1], R_VO)
    assert kf.covariance[2, 2] < before
    assert abs(wrap_angle_deg(kf.pose[2] - truth[2])) < 0.05


def wrap_angle_deg(a):
    return math.degrees((a + math.pi) % (2 * math.pi) - math.pi)


def test_constrained_jacobian_matches_finite_differences(rng):
    from vo_lib.stereo_vo.kalman import constrained_jacobian, constrained_measurement

    for _ in range(20):
        x = np.concatenate(
            [rng.normal(size=2), [rng.uniform(-3, 3)], rng.normal(size=2), [rng.uniform(-3, 3)]]
        )
        num = np.column_stack(
            [
                (constrained_measurement(x + 1e-6 * e) - constrained_measurement(x - 1e-6 * e)) / 2e-6
                for e in np.eye(6)
            ]
        )
        np.testing.assert_allclose(constrained_jacobian(x), num, atol=1e-6)


def test_nis_needs_no_truth_and_tells_a_wrong_noise_model():
    """The VO components' NIS averages to 2 when the filter's R is the noise drawn, far from it
    when the filter is told a noise ten times smaller (a standard deviation a tenth)."""

    def mean_nis(r_assumed, runs=20, steps=100):
        values = []
        for run in range(runs):
            rng = np.random.default_rng(2000 + run)
            kf = VoKalmanFilter(ODO, covariance=P0)
            truth = kf.pose + rng.multivariate_normal(np.zeros(3), P0)
            for k in range(steps):
                u_true = ODO.controls_for(0.02, math.radians(1.0) * math.sin(k / 30))
                u_meas = u_true + rng.multivariate_normal(np.zeros(2), kf.control_covariance(u_true))
                prev, truth = truth, ODO.predict(truth, u_true)
                kf.predict(u_meas)
                z = measurement(np.concatenate([truth, prev])) + rng.multivariate_normal(np.zeros(2), R_VO)
                kf.update(z[0], z[1], r_assumed)
                values.append(nis(kf.ekf.y[:2], kf.ekf.S[:2, :2]))
                kf.finish_frame()
        return np.mean(values), runs * steps

    matched, n = mean_nis(R_VO)
    lo, hi = chi2.ppf([0.0005, 0.9995], 2 * n) / n
    assert lo < matched < hi
    told_less, _ = mean_nis(R_VO / 100)
    assert told_less > 2 * hi  # S is mostly the prediction's, so R alone moves the NIS less than R
    with pytest.raises(ValueError):
        nis([1.0, 2.0], np.eye(3))


def test_snapshot_restore_and_widen_keep_the_state_inside_the_filter():
    kf = VoKalmanFilter(TrackOdometry())
    kf.predict(np.array([0.05, 0.06]))
    saved = kf.snapshot()
    pose, cov = kf.pose, kf.covariance
    kf.update(0.01, 0.05, np.diag([1e-6, 1e-6]))
    assert not np.allclose(kf.covariance, cov)
    kf.restore(saved)
    assert np.array_equal(kf.pose, pose) and np.array_equal(kf.covariance, cov)
    saved[0][:] = 99.0  # the snapshot is a copy: changing it later does not reach the filter
    kf.restore(kf.snapshot())
    assert np.array_equal(kf.pose, pose)
    kf.widen((1.0, 2.0, 0.5))
    assert np.allclose(np.diag(kf.covariance) - np.diag(cov), [1.0, 4.0, 0.25])


# --- the slip-calibrated filter ----------------------------------------------------------------


def _spot_turn(kf, slip, rng, steps=300, outage=()):
    """A spot turn whose encoders over-count by ``1 / (1 - slip)``; VO sees the true turn.
    Returns the final heading error (rad)."""
    from vo_lib.stereo_vo.kalman import SlipCalibratedFilter  # noqa: F401  (the class under test)

    truth = np.zeros(3)
    for k in range(steps):
        u_true = ODO.controls_for(0.0, math.radians(0.6))
        prev, truth = truth, ODO.predict(truth, u_true)
        kf.predict(u_true / (1.0 - slip))
        if k not in outage:
            z = measurement(np.concatenate([truth, prev])) + rng.multivariate_normal(np.zeros(2), R_VO)
            kf.update(z[0], z[1], R_VO)
        kf.finish_frame()
    return abs(math.remainder(kf.pose[2] - truth[2], math.tau))


def test_slip_calibration_learns_the_turn_scale():
    from vo_lib.stereo_vo.kalman import SlipCalibratedFilter

    kf = SlipCalibratedFilter(ODO)
    _spot_turn(kf, 0.06, np.random.default_rng(3))
    mean_scale = kf.scales.mean()  # the turn of a spot turn scales with both tracks' mean
    sigma = math.sqrt(np.ones(2) @ kf.scale_covariance @ np.ones(2)) / 2
    assert abs(mean_scale - 0.94) < 3 * sigma  # ground over counted distance, 1 - slip, within 3σ
    assert sigma < 0.01 and abs(mean_scale - 1.0) > 3 * sigma  # and told apart from no slip


def test_slip_calibration_learns_unequal_slip_when_driving():
    """Unequal slip while driving adds a turn the encoders count and the ground does not; the
    learnt scales tell the tracks apart."""
    from vo_lib.stereo_vo.kalman import SlipCalibratedFilter

    kf, rng = SlipCalibratedFilter(ODO), np.random.default_rng(6)
    truth, slip = np.zeros(3), np.array([0.01, 0.05])
    for _ in range(400):
        u_true = ODO.controls_for(0.05, 0.0)
        prev, truth = truth, ODO.predict(truth, u_true)
        kf.predict(u_true / (1.0 - slip) + rng.normal(0.0, 1e-4, 2))
        z = measurement(np.concatenate([truth, prev])) + rng.multivariate_normal(np.zeros(2), R_VO)
        kf.update(z[0], z[1], R_VO)
        kf.finish_frame()
    sigma = np.sqrt(np.diag(kf.scale_covariance))
    assert np.all(np.abs(kf.scales - (1.0 - slip)) < 3 * sigma)  # each track within 3σ
    apart = np.array([1.0, -1.0])
    assert kf.scales @ apart > 3 * math.sqrt(apart @ kf.scale_covariance @ apart)  # the two told apart


def test_slip_calibration_removes_the_bias_through_an_outage():
    """Through 100 frames without VO the plain filter drifts by the slip of every turn; the
    calibrated one by what is left of its learnt scale's error."""
    from vo_lib.stereo_vo.kalman import SlipCalibratedFilter

    gap = set(range(150, 250))
    plain = _spot_turn(VoKalmanFilter(ODO), 0.06, np.random.default_rng(4), outage=gap)
    calibrated = _spot_turn(SlipCalibratedFilter(ODO), 0.06, np.random.default_rng(4), outage=gap)
    assert plain > math.radians(3.0)  # 6 % of 100 frames of 0.6°
    assert calibrated < 0.5 * plain  # most of the bias is learnt


def test_slip_calibration_without_freedom_is_the_plain_filter():
    from vo_lib.stereo_vo.kalman import SlipCalibratedFilter

    a, b = VoKalmanFilter(ODO), SlipCalibratedFilter(ODO, scale_sigma=0.0, scale_drift=0.0)
    simulate(a, np.random.default_rng(5), 50)
    simulate(b, np.random.default_rng(5), 50)
    assert np.allclose(a.ekf.x, b.ekf.x, atol=1e-12) and np.allclose(a.ekf.P, b.ekf.P, atol=1e-15)
    assert np.all(b.scales == 1.0)
