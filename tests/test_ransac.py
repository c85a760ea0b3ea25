import math

import numpy as np
import pytest

from vo_lib.stereo_vo.baselines import essential_ransac, kabsch, pnp_ransac, rigid_ransac
from vo_lib.stereo_vo.circular_motion import motion_matrices
from vo_lib.stereo_vo.ransac import (
    gate_angles,
    histogram_voting,
    hypotheses_needed,
    hypothesis_draws,
    one_point_ransac,
    rho_gate_error,
    theta_gate_and_slope,
    theta_gate_error,
)
from vo_lib.stereo_vo.refinement import both_directions, refine_motion, reprojection
from vo_lib.stereo_vo.synthetic import synthetic_matches
from vo_lib.stereo_vo.temporal import MotionPrior


def test_hypotheses_formula():
    # log(1 - p) / log(1 - w^s)
    assert hypotheses_needed(0.6, 0.99, 1) == math.ceil(math.log(0.01) / math.log(0.4))
    assert hypotheses_needed(0.6, 0.99, 3) == math.ceil(math.log(0.01) / math.log(1 - 0.216))
    assert hypotheses_needed(0.6, 0.99, 5) > hypotheses_needed(0.6, 0.99, 3) > hypotheses_needed(0.6, 0.99, 1)
    assert hypotheses_needed(1.0) == 1


def test_gates_are_zero_for_true_matches(camera, rng):
    m = synthetic_matches(camera, 400, 0.07, -0.1, rng, outlier_ratio=0.3)
    e_theta = theta_gate_error(m.w_prev, m.w_curr, 0.07, camera)
    assert np.nanmax(e_theta[m.inliers]) < 1e-9
    assert np.nanmedian(e_theta[~m.inliers]) > 1e-2
    P, Q = camera.backproject(m.w_prev), camera.backproject(m.w_curr)
    e_rho = rho_gate_error(P, Q, 0.07, -0.1)
    assert e_rho[m.inliers].max() < 1e-12 and np.median(e_rho[~m.inliers]) > 0.3
    # under a wrong theta the gate of eq. 20 no longer vanishes
    assert np.nanmedian(theta_gate_error(m.w_prev, m.w_curr, 0.09, camera)[m.inliers]) > 1e-3


def test_the_theta_gates_slope_is_the_derivative_of_eq_20(camera, rng):
    """The closed form the gate's width uses, against a central difference of the signed error."""
    m = synthetic_matches(camera, 200, 0.05, 0.1, rng, outlier_ratio=0.3)
    (ta, ba), (tb, bb) = gate_angles(m.w_prev, camera), gate_angles(m.w_curr, camera)
    h = 1e-6

    def signed(theta):
        return tb / ta - np.sin(bb - theta / 2) / np.sin(ba + theta / 2)

    for theta in (-0.08, 0.0, 0.05):
        numeric = (signed(theta + h) - signed(theta - h)) / (2 * h)
        np.testing.assert_allclose(
            theta_gate_and_slope(tb / ta, ba, bb, theta)[1], numeric, rtol=1e-3
        )  # near poles too


def test_the_theta_models_gate_is_eq_20_within_k_sigma_of_its_slope(camera, rng):
    """The gate RANSAC applies (eq. 20's error over its slope, an angle) keeps the same matches as
    the error held to k times its slope times sigma, as theta_gate_and_slope gives them."""
    from vo_lib.stereo_vo.ransac import ThetaModel, match_angles

    m = synthetic_matches(camera, 300, 0.05, 0.1, rng, outlier_ratio=0.4, noise_px=0.5)
    model = ThetaModel(m.w_prev, m.w_curr, camera, 0.5)
    for theta, var_ref, k in ((0.05, 1e-8, 3.0), (0.0, 1e-6, 2.0), (-0.1, 0.0, 3.0)):
        e, slope = theta_gate_and_slope(*match_angles(m.w_prev, m.w_curr, camera), theta)
        var = model.variances + var_ref
        expected = (e * e <= k * k * slope * slope * var) & ((model.values - theta) ** 2 <= k * k * var)
        got = model.gate_pass(theta, var_ref, k * k)
        assert np.array_equal(got, expected) and (theta != 0.05 or got[m.inliers].mean() > 0.9)


def test_the_refinements_jacobians_are_the_derivatives_of_its_residuals(camera, rng):
    """Forward and backward reprojection residuals (disparity space) and their analytic
    Jacobians in theta and rho, against central differences."""
    m = synthetic_matches(camera, 50, 0.04, 0.08, rng, outlier_ratio=0.0, noise_px=0.5)
    P, Q = camera.backproject(m.w_prev), camera.backproject(m.w_curr)
    points, targets = both_directions(P, Q, m.w_prev, m.w_curr, camera)
    theta, rho, h = 0.03, 0.07, 1e-7
    r, J_theta, J_rho = reprojection(theta, rho, points, targets, camera)
    assert r.shape == J_theta.shape == J_rho.shape == (2, 3, 50)
    for J, (dt, dr) in ((J_theta, (h, 0.0)), (J_rho, (0.0, h))):
        plus = reprojection(theta + dt, rho + dr, points, targets, camera)[0]
        minus = reprojection(theta - dt, rho - dr, points, targets, camera)[0]
        np.testing.assert_allclose(J, (plus - minus) / (2 * h), rtol=1e-5, atol=1e-4)
    # at the true motion of noise-free matches the residuals vanish
    clean = synthetic_matches(camera, 50, 0.04, 0.08, rng, outlier_ratio=0.0, noise_px=0.0)
    P, Q = camera.backproject(clean.w_prev), camera.backproject(clean.w_curr)
    assert (
        np.abs(
            reprojection(0.04, 0.08, *both_directions(P, Q, clean.w_prev, clean.w_curr, camera), camera)[0]
        ).max()
        < 1e-8
    )


def test_acceptance_synthetic_matches_over_many_seeds(camera):
    """300 matches, 40 % outliers, 0.5 px noise on u, v, d of both views, depths 1.5-15 m,
    steps 3-12 cm and up to 5 degrees."""
    recall, theta_err, rho_err, ls_theta, ls_rho = [], [], [], [], []
    for seed in range(80):
        rng = np.random.default_rng(seed)
        theta, rho = math.radians(rng.uniform(-5, 5)), rng.uniform(0.03, 0.12)
        m = synthetic_matches(
            camera, 300, theta, rho, rng, depth_range=(1.5, 15.0), noise_px=0.5, outlier_ratio=0.4
        )
        r = one_point_ransac(m.w_prev, m.w_curr, camera, rng=rng)
        assert r.success
        recall.append((r.inliers & m.inliers).sum() / m.inliers.sum())
        theta_err.append(abs(r.theta - theta))
        rho_err.append(abs(r.rho - rho) / rho)
        t_ls, r_ls, _ = refine_motion(m.w_prev[m.inliers], m.w_curr[m.inliers], theta, rho, camera)
        ls_theta.append(abs(t_ls - theta))
        ls_rho.append(abs(r_ls - rho) / rho)
    assert min(recall) >= 0.95
    assert math.degrees(max(theta_err)) <= 0.03
    assert np.median(rho_err) <= 0.015 and max(rho_err) <= 0.05
    assert max(theta_err) <= 1.5 * max(ls_theta)
    assert np.median(rho_err) <= 1.5 * np.median(ls_rho) and max(rho_err) <= 1.5 * max(ls_rho)


def test_prior_is_used_and_failure_falls_back(camera, rng):
    m = synthetic_matches(camera, 200, 0.02, 0.05, rng, noise_px=0.5, outlier_ratio=0.3)
    prior = MotionPrior(0.021, 0.049, np.diag([1e-6, 1e-5]))
    r = one_point_ransac(m.w_prev, m.w_curr, camera, prior=prior, rng=1)
    assert r.success and abs(r.theta - 0.02) < 5e-4
    few = one_point_ransac(m.w_prev[:2], m.w_curr[:2], camera, prior=prior, rng=1)
    assert not few.success and few.theta == 0.021 and not few.inliers.any()
    assert "fewer than 3" in few.diagnostics["reason"]


def test_same_seed_same_result(camera, rng):
    m = synthetic_matches(camera, 300, 0.02, 0.05, rng, noise_px=0.5, outlier_ratio=0.5)
    a = one_point_ransac(m.w_prev, m.w_curr, camera, rng=7)
    b = one_point_ransac(m.w_prev, m.w_curr, camera, rng=7)
    assert (a.theta, a.rho) == (b.theta, b.rho) and np.array_equal(a.inliers, b.inliers)


def test_draws_given_explicitly_make_the_same_estimate_as_the_seed(camera, rng):
    m = synthetic_matches(camera, 200, 0.03, 0.08, rng, noise_px=0.5, outlier_ratio=0.4)
    by_seed = one_point_ransac(m.w_prev, m.w_curr, camera, rng=11)
    draws = hypothesis_draws(11)
    assert draws.shape == (2, 200) and np.all((draws >= 0) & (draws < 1))
    by_draws = one_point_ransac(m.w_prev, m.w_curr, camera, rng=999, draws=draws)
    assert np.array_equal(by_seed.inliers, by_draws.inliers)
    assert (by_seed.theta, by_seed.rho) == (by_draws.theta, by_draws.rho)
    # other draws are other hypotheses: the phase-1 pick changes when every draw points at one match
    stuck = one_point_ransac(m.w_prev, m.w_curr, camera, draws=np.zeros((2, 200)), refine=False)
    assert stuck.theta != by_seed.theta
    with pytest.raises(ValueError, match=r"draws must have shape \(2, max_hypotheses\) = \(2, 200\)"):
        one_point_ransac(m.w_prev, m.w_curr, camera, draws=np.zeros(400))


def test_bad_input(camera):
    with pytest.raises(ValueError, match=r"w_prev must have shape \(N, 3\)"):
        one_point_ransac(np.zeros((4, 2)), np.zeros((4, 3)), camera)
    with pytest.raises(ValueError, match="same shape"):
        one_point_ransac(np.ones((4, 3)), np.ones((5, 3)), camera)


def test_histogram_voting(camera, rng):
    m = synthetic_matches(camera, 300, 0.03, 0.08, rng, noise_px=0.3, outlier_ratio=0.3)
    theta, rho, votes = histogram_voting(m.w_prev, m.w_curr, camera)
    assert abs(theta - 0.03) < math.radians(0.1) and abs(rho - 0.08) < 0.02
    assert votes[m.inliers].mean() > votes[~m.inliers].mean()


def test_kabsch_recovers_a_rigid_motion(rng):
    P = rng.normal(size=(20, 3))
    R, t = motion_matrices(0.3, 0.5)
    R2, t2 = kabsch(P, P @ R.T + t)
    np.testing.assert_allclose(R2, R, atol=1e-12)
    np.testing.assert_allclose(t2, t, atol=1e-12)


@pytest.mark.parametrize("estimator", [rigid_ransac, pnp_ransac])
def test_six_dof_baselines_recover_the_motion(camera, rng, estimator):
    m = synthetic_matches(camera, 300, 0.05, 0.1, rng, noise_px=0.3, outlier_ratio=0.3)
    kwargs = {"rng": 1} if estimator is rigid_ransac else {}
    est = estimator(m.w_prev, m.w_curr, camera, **kwargs)
    assert est.success
    # general-purpose 6-DoF fits on noisy 3-D points: a few tenths of a degree
    assert abs(est.theta - 0.05) < math.radians(0.5) and abs(est.rho - 0.1) < 0.02
    assert est.inliers[~m.inliers].mean() < 0.05


def test_essential_matrix_gives_rotation_and_direction(camera, rng):
    m = synthetic_matches(camera, 300, 0.05, 0.1, rng, noise_px=0.3, outlier_ratio=0.3)
    est = essential_ransac(m.w_prev, m.w_curr, camera)
    assert est.success and abs(est.theta - 0.05) < math.radians(0.5)
    assert np.linalg.norm(est.t) == pytest.approx(1.0)  # no scale from one camera


class _Offsets:
    """A one-point model of a 1-D offset: every value is a hypothesis, residual ``value - h``."""

    def __init__(self, values, variances):
        self.values, self.variances = values, variances

    def each_match(self):
        return self.values, self.variances

    def squared_residuals(self, h):
        return (self.values[None, :] - h[:, None]) ** 2


def test_the_hypothesis_search_takes_any_one_point_model(rng):
    from vo_lib.stereo_vo.ransac import DEFAULT_PARAMS, reestimate, search, supporters

    values = np.r_[2.0 + rng.normal(0, 0.01, 60), rng.uniform(-10, 10, 40)]
    model = _Offsets(values, np.full(100, 0.01**2))
    h, var_h, tried = search(model, hypothesis_draws(3)[0], None, DEFAULT_PARAMS)
    support = supporters(model, h, var_h, DEFAULT_PARAMS)
    assert abs(h - 2.0) < 0.03 and support[:60].mean() > 0.95 and support[60:].sum() <= 2
    # the first batch is sized for half inliers; 60 % found needs no more (eq. 19's count)
    assert tried == hypotheses_needed(0.5, DEFAULT_PARAMS.confidence) == 10
    assert hypotheses_needed(support.sum() / 100, DEFAULT_PARAMS.confidence) < tried
    mean, var = reestimate(model, support)
    assert abs(mean - 2.0) < 0.005 and var == pytest.approx(0.01**2 / support.sum())
    # a prior that nothing supports loses to the drawn hypotheses
    assert abs(search(model, hypothesis_draws(3)[0], (-50.0, 1e-4), DEFAULT_PARAMS)[0] - 2.0) < 0.03


def test_reestimate_without_supporters_gives_no_estimate():
    """No supporter: NaN with infinite variance (the caller then finds too few inliers), no error."""
    from vo_lib.stereo_vo.ransac import reestimate

    class Model:
        def each_match(self):
            return np.array([0.1, 0.2]), np.array([1e-4, 1e-4])

    value, variance = reestimate(Model(), np.zeros(2, bool))
    assert math.isnan(value) and variance == math.inf
    assert reestimate(Model(), np.array([True, True])) == pytest.approx((0.15, 5e-5))


def test_point_variances_follow_eq_13s_jacobian_for_pixels_that_are_not_square():
    """The first-order variance of a back-projected pair is J J^T sigma^2 summed over both views, J
    the derivative of eq. 13 in (u, v, d): by finite differences, on a camera with fy != fx."""
    from vo_lib.camera import StereoCamera
    from vo_lib.stereo_vo.ransac import points_and_variances

    camera = StereoCamera(fx=500.0, fy=350.0, cx=320.0, cy=240.0, baseline=0.12)
    w = np.array([[100.0, 50.0, 8.0], [400.0, 300.0, 20.0], [320.0, 240.0, 3.0]])
    points, variances = points_and_variances(w, w[::-1], camera, pixel_sigma=0.5)
    np.testing.assert_allclose(points[0, :3].T, camera.backproject(w), rtol=1e-12)
    h, expected = 1e-6, np.zeros(len(w))
    for view in (w, w[::-1]):
        for axis in range(3):
            step = np.zeros(3)
            step[axis] = h
            J = (camera.backproject(view + step) - camera.backproject(view - step)) / (2 * h)
            expected += 0.5**2 * np.sum(J * J, axis=1)
    np.testing.assert_allclose(variances, expected, rtol=1e-6)
