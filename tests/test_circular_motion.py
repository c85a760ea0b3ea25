import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vo_lib.camera import StereoCamera
from vo_lib.geometry import camera_motion, camera_mount, compose_planar
from vo_lib.stereo_vo import circular_motion as cm
from vo_lib.stereo_vo.ransac import rho_gate_error
from vo_lib.stereo_vo.synthetic import synthetic_matches


def test_noise_free_recovery_of_1000_matches(camera, rng):
    for _ in range(20):
        theta = rng.uniform(-np.radians(20), np.radians(20))
        rho = rng.uniform(-0.5, 0.5)
        m = synthetic_matches(camera, 1000, theta, rho, rng)
        th = cm.theta_from_pixels(m.w_prev, m.w_curr, camera)
        ok = ~cm.degenerate_theta_mask(m.w_prev, m.w_curr, camera, min_pixels=1.0)
        assert np.max(np.abs(th[ok] - theta)) <= 1e-9
        r = cm.rho_from_pixels(m.w_prev, m.w_curr, theta, camera)
        assert np.max(np.abs(r - rho)) <= 1e-9


@settings(max_examples=60, deadline=None)
@given(st.floats(-0.6, 0.6), st.floats(-1.0, 1.0), st.integers(0, 2**31))
def test_recovery_property(theta, rho, seed):
    cam = StereoCamera(520.0, 500.0, 300.0, 250.0, 0.2, 640, 480)  # unequal focal lengths
    m = synthetic_matches(cam, 50, theta, rho, np.random.default_rng(seed), depth_range=(2.0, 30.0))
    ok = ~cm.degenerate_theta_mask(m.w_prev, m.w_curr, cam, min_pixels=2.0)
    th = cm.theta_from_pixels(m.w_prev, m.w_curr, cam)
    np.testing.assert_allclose(th[ok], theta, atol=1e-8)
    np.testing.assert_allclose(cm.rho_from_pixels(m.w_prev, m.w_curr, theta, cam), rho, atol=1e-8)


def test_printed_eq17_sign_is_wrong_for_straight_motion(camera, rng):
    m = synthetic_matches(camera, 100, 0.0, 0.1, rng)
    a, b = m.w_prev, m.w_curr
    B, f = camera.baseline, camera.fx
    printed = B / a[:, 2] * f + B / b[:, 2] * f  # phi = 0: the printed eq. 17 gives z + z'
    assert np.all(printed > 2.0)
    np.testing.assert_allclose(cm.rho_from_pixels(a, b, 0.0, camera), 0.1, atol=1e-12)


def test_theta_is_the_robot_yaw_increment(camera, rng):
    """Drive a robot a planar step, render with a forward camera on its turning axis, recover."""
    mount = camera_mount(height=0.6)
    for dyaw in (-0.2, -0.01, 0.0, 0.05, 0.3):
        start = np.array([2.0, -1.0, 0.7])
        end = compose_planar(start, cm.robot_increment(dyaw, 0.12))
        T = camera_motion(start, end, mount)  # maps points of camera 0 into camera 1
        theta, rho = cm.circular_motion_from_transform(T)
        assert theta == pytest.approx(dyaw, abs=1e-12) and rho == pytest.approx(0.12, abs=1e-12)
        R, t = cm.motion_matrices(theta, rho)
        np.testing.assert_allclose(T[:3, :3], R, atol=1e-12)
        np.testing.assert_allclose(T[:3, 3], t, atol=1e-12)
        # a point straight ahead drifts right in the image when the robot turns left
        P = np.array([[0.0, 0.3, 5.0]])
        w0, w1 = camera.project(P), camera.project(cm.apply_motion(P, theta, rho))
        drift = w1[0, 0] - w0[0, 0]
        assert np.sign(drift) == np.sign(dyaw) if dyaw else abs(drift) < 1e-9
        assert cm.yaw_increment(theta) == pytest.approx(dyaw)


def test_robot_increment_round_trip():
    inc = cm.robot_increment(np.array([0.1, -0.3]), np.array([0.2, -0.05]))
    theta, rho = cm.circular_motion_from_increment(inc)
    np.testing.assert_allclose(theta, [0.1, -0.3])
    np.testing.assert_allclose(rho, [0.2, -0.05])
    # backwards motion has negative rho and still satisfies phi = theta / 2
    assert inc[1, 0] < 0


def test_motion_matrices_vectorised():
    R, T = cm.motion_matrices(np.array([0.0, 0.2]), np.array([1.0, 2.0]))
    assert R.shape == (2, 3, 3) and T.shape == (2, 3)
    np.testing.assert_allclose(R[1] @ R[1].T, np.eye(3), atol=1e-15)
    np.testing.assert_allclose(T[0], [0, 0, -1.0])
    np.testing.assert_allclose(np.linalg.norm(T[1]), 2.0)


def test_degenerate_matches_at_camera_height(camera):
    w_prev = np.array([[100.0, camera.cy, 5.0], [300.0, 300.0, 5.0]])
    w_curr = np.array([[110.0, camera.cy, 5.5], [310.0, 305.0, 5.5]])
    th = cm.theta_from_pixels(w_prev, w_curr, camera)
    assert np.isnan(th[0]) and np.isfinite(th[1])
    np.testing.assert_array_equal(cm.degenerate_theta_mask(w_prev, w_curr, camera), [True, False])


def test_zero_disparity_is_fine_for_theta_but_not_rho(camera):
    w_prev = np.array([[100.0, 300.0, 0.0]])
    w_curr = np.array([[110.0, 300.0, 0.0]])
    assert np.isfinite(cm.theta_from_pixels(w_prev, w_curr, camera)[0])
    with pytest.raises(ValueError, match=r"w_prev\[:, 2\] \(disparity\) must be > 0 to give rho; row 0"):
        cm.rho_from_pixels(w_prev, w_curr, 0.0, camera)


def test_shape_errors(camera):
    with pytest.raises(ValueError, match=r"w_prev must have shape \(N, 3\)"):
        cm.theta_from_pixels(np.zeros((3, 2)), np.zeros((3, 3)), camera)
    with pytest.raises(ValueError, match=r"same shape; got \(3, 3\) and \(4, 3\)"):
        cm.theta_from_pixels(np.ones((3, 3)), np.ones((4, 3)), camera)
    with pytest.raises(ValueError, match=r"w_curr must be finite"):
        cm.rho_from_pixels(np.ones((1, 3)), [[1.0, np.inf, 1.0]], 0.0, camera)


def test_synthetic_matches_refuses_motion_without_overlap(camera, rng):
    with pytest.raises(ValueError, match="leaves .almost. no point visible in both views"):
        synthetic_matches(camera, 10, np.radians(120), 0.0, rng)


def test_motion_residuals_zero_for_truth(camera, rng):
    m = synthetic_matches(camera, 200, 0.05, 0.1, rng, outlier_ratio=0.2)
    res = rho_gate_error(camera.backproject(m.w_prev), camera.backproject(m.w_curr), 0.05, 0.1)
    assert np.max(res[m.inliers]) < 1e-12
    assert np.median(res[~m.inliers]) > 0.5


def test_theta_standard_deviation_matches_monte_carlo(camera, rng):
    m = synthetic_matches(camera, 1, 0.03, 0.1, rng, depth_range=(4.0, 4.1))
    base_prev, base_curr = np.repeat(m.w_prev, 20000, 0), np.repeat(m.w_curr, 20000, 0)
    sigma = 0.5
    noisy_prev, noisy_curr = base_prev.copy(), base_curr.copy()
    noisy_prev[:, :2] += rng.normal(0, sigma, (20000, 2))
    noisy_curr[:, :2] += rng.normal(0, sigma, (20000, 2))
    spread = np.std(cm.theta_from_pixels(noisy_prev, noisy_curr, camera))
    predicted = cm.theta_standard_deviation(m.w_prev, m.w_curr, camera, sigma)[0]
    assert spread == pytest.approx(predicted, rel=0.05)


def test_matches_under_transform_validates_and_reports_motion(camera, rng):
    with pytest.raises(ValueError, match=r"T_curr_from_prev must be a 4x4 matrix"):
        from vo_lib.stereo_vo.synthetic import matches_under_transform

        matches_under_transform(camera, 5, np.eye(3), rng)
    m = synthetic_matches(camera, 5, 0.1, 0.2, rng)
    assert (m.theta, m.rho) == pytest.approx((0.1, 0.2))


@pytest.mark.parametrize("pitch_deg", [0.0, 8.0, 20.0])
def test_synthetic_scene_has_no_point_below_the_floor(camera, rng, pitch_deg):
    from vo_lib.stereo_vo.synthetic import Scene

    scene = Scene(pitch=np.radians(pitch_deg))
    m = synthetic_matches(camera, 3000, np.radians(4.0), 0.1, rng, scene=scene)
    height = scene.height_above_floor(m.points)
    assert height.min() >= -1e-9 and height.max() <= scene.top + 1e-9
    # the floor is seen (points on it), and the rows spread over the image: far surfaces near the
    # principal row, the floor below it
    assert np.mean(np.abs(height) < 1e-9) > 0.1
    rows = np.histogram(m.w_prev[:, 1], bins=4, range=(0, camera.height))[0]
    assert np.all(rows > 0.05 * len(m.points))
    # the robot's motion is reported, not the pitched camera's
    assert (m.theta, m.rho) == pytest.approx((np.radians(4.0), 0.1))


def test_pitched_camera_breaks_the_planar_model_and_a_level_one_does_not(camera, rng):
    from vo_lib.stereo_vo.synthetic import Scene

    level = synthetic_matches(camera, 500, np.radians(4.0), 0.1, rng)
    pitched = synthetic_matches(camera, 500, np.radians(4.0), 0.1, rng, scene=Scene(pitch=np.radians(10)))
    errors = []
    for m in (level, pitched):
        ok = ~cm.degenerate_theta_mask(m.w_prev, m.w_curr, camera, min_pixels=20.0)
        errors.append(np.median(np.abs(cm.theta_from_pixels(m.w_prev[ok], m.w_curr[ok], camera) - m.theta)))
    assert errors[0] < 1e-9 < 1e-4 < errors[1]


def test_scene_rejects_impossible_settings():
    from vo_lib.stereo_vo.synthetic import Scene

    with pytest.raises(ValueError, match="camera_height"):
        Scene(camera_height=0.0)
    with pytest.raises(ValueError, match="floor_share"):
        Scene(floor_share=1.5)
