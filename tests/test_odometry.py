import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from vo_lib.models.track_odometry import TrackOdometry, apply_slip

ODO = TrackOdometry(track_distance=0.4, track_width=0.1, encoder_sigma=0.01)
small = st.floats(-0.2, 0.2, allow_nan=False)


def phi(u):
    """``phi_k = (du_right - du_left) / (2 (D + 2b))``, half the heading change (eq. 11)."""
    return (u[1] - u[0]) / (2.0 * ODO.gauge)


def control_matrix(theta_prev, u):
    """``B_k`` of eq. 10, evaluated at ``phi_k`` of ``u`` (eq. 11)."""
    c, s, k = np.cos(theta_prev + phi(u)), np.sin(theta_prev + phi(u)), 1.0 / ODO.gauge
    return np.array([[0.5 * c, 0.5 * c], [0.5 * s, 0.5 * s], [-k, k]])


def predict_exact(x, u):
    """One exact circular-arc step."""
    return ODO.integrate([u], start=x, exact=True)[-1]


def test_gauge_is_d_plus_2b():
    assert ODO.gauge == pytest.approx(0.6)


def test_straight_and_spot_turn_increments():
    du, dth = ODO.increment([0.1, 0.1])
    assert du == pytest.approx(0.1) and dth == 0.0
    du, dth = ODO.increment([-0.03, 0.03])
    assert du == 0.0 and dth == pytest.approx(0.06 / 0.6)
    assert phi([-0.03, 0.03]) == pytest.approx(dth / 2)


@given(small, small, st.floats(-3, 3))
def test_eq6_with_eq10_matrix_equals_eq2_to_5(ul, ur, theta):
    x = np.array([1.0, -2.0, theta])
    u = np.array([ul, ur])
    via_matrix = x + control_matrix(theta, u) @ u  # F_k = I, eq. 9
    step = ODO.predict(x, u)
    np.testing.assert_allclose(via_matrix[:2], step[:2], atol=1e-12)
    assert np.isclose(np.cos(via_matrix[2] - step[2]), 1.0)


@given(small, small, st.floats(-3, 3))
def test_forward_then_reverse_returns_to_start(ul, ur, theta):
    x = np.array([0.5, 0.2, theta])
    back = ODO.predict(ODO.predict(x, [ul, ur]), [-ul, -ur])
    np.testing.assert_allclose(back[:2], x[:2], atol=1e-12)
    assert abs(np.sin(back[2] - x[2])) < 1e-12


def test_jacobians_match_finite_differences(rng):
    for _ in range(20):
        x = np.array([*rng.normal(size=2), rng.uniform(-3, 3)])
        u = rng.uniform(-0.3, 0.3, 2)
        F_x, F_u = ODO.jacobians(x, u)
        h = 1e-6
        num_x = np.column_stack(
            [(ODO.predict(x + h * e, u) - ODO.predict(x - h * e, u)) / (2 * h) for e in np.eye(3)]
        )
        num_u = np.column_stack(
            [(ODO.predict(x, u + h * e) - ODO.predict(x, u - h * e)) / (2 * h) for e in np.eye(2)]
        )
        np.testing.assert_allclose(F_x, num_x, atol=1e-8)
        np.testing.assert_allclose(F_u, num_u, atol=1e-8)


def test_eq10_is_not_the_control_jacobian_when_turning():
    x, u = np.array([0.0, 0.0, 0.3]), np.array([0.1, 0.3])
    _, F_u = ODO.jacobians(x, u)
    B = control_matrix(x[2], u)
    np.testing.assert_allclose(F_u[2], B[2])
    du = 0.2
    a = x[2] + phi(u)
    np.testing.assert_allclose(F_u[0] - B[0], [du * np.sin(a) / 1.2, -du * np.sin(a) / 1.2])


def test_exact_arc_against_many_small_steps():
    x0 = np.array([0.0, 0.0, 0.2])
    u = np.array([0.2, 0.5])
    fine = x0
    for _ in range(2000):
        fine = ODO.predict(fine, u / 2000)
    exact = predict_exact(x0, u)
    midpoint = ODO.predict(x0, u)
    np.testing.assert_allclose(exact, fine, atol=1e-7)
    # the midpoint step overshoots by about dtheta^2/24 of the step length
    du, dth = ODO.increment(u)
    overshoot = np.linalg.norm(midpoint[:2] - x0[:2]) - np.linalg.norm(exact[:2] - x0[:2])
    assert overshoot == pytest.approx(du * dth**2 / 24, rel=0.01)


def test_integrate_is_the_loop_of_predict(rng):
    controls = rng.uniform(-0.05, 0.1, (300, 2))
    poses = ODO.integrate(controls, start=(1.0, 2.0, 3.0))
    x = np.array([1.0, 2.0, 3.0])
    for k, u in enumerate(controls):
        x = ODO.predict(x, u)
        np.testing.assert_allclose(poses[k + 1, :2], x[:2], atol=1e-10)
        assert abs(np.sin(poses[k + 1, 2] - x[2])) < 1e-10
    exact = ODO.integrate(controls, exact=True)
    x = np.zeros(3)
    for u in controls:
        x = predict_exact(x, u)
    np.testing.assert_allclose(exact[-1, :2], x[:2], atol=1e-10)


def test_propagated_covariance_matches_monte_carlo(rng):
    steps, runs = 60, 20000
    u = np.array([0.04, 0.06])  # a gentle left arc
    x = np.zeros(3)
    P = np.zeros((3, 3))
    for _ in range(steps):
        x, P = ODO.propagate(x, P, u)
    samples = np.zeros((runs, 3))
    sd = ODO.encoder_sigma * np.sqrt(np.abs(u))
    for _ in range(steps):
        samples = ODO.predict(samples, u + rng.normal(size=(runs, 2)) * sd)
    C = np.cov(samples.T)
    # the linearised mean misses a second-order shrinkage (E[cos] < 1) of about 0.04 % of the path
    path_length = steps * 0.05
    assert np.linalg.norm(samples.mean(axis=0)[:2] - x[:2]) < 1e-3 * path_length
    assert np.linalg.norm(C - P) / np.linalg.norm(P) < 0.05
    # eq. 9's identity F_k ignores how heading error moves the position: far too small in y
    P_eq9 = np.zeros((3, 3))
    x = np.zeros(3)
    for _ in range(steps):
        _, F_u = ODO.jacobians(x, u)
        P_eq9 = P_eq9 + F_u @ ODO.control_covariance(u) @ F_u.T
        x = ODO.predict(x, u)
    assert P_eq9[1, 1] < 0.5 * C[1, 1]


def test_controls_for_inverts_increment():
    u = ODO.controls_for(0.1, 0.2)
    du, dth = ODO.increment(u)
    assert (du, dth) == pytest.approx((0.1, 0.2))


def test_slip_of_one_track_turns_the_robot():
    commanded = np.tile([0.05, 0.05], (100, 1))
    ground = apply_slip(commanded, slip_left=0.1)
    path = ODO.integrate(ground)
    # left track covers 10 % less ground: the robot curves left by 0.1 * 5 m / 0.6 m
    assert path[-1, 2] == pytest.approx(0.1 * 5.0 / 0.6)
    assert ODO.integrate(commanded)[-1, 2] == 0.0


def test_bad_arguments():
    with pytest.raises(ValueError, match=r"track_width must be a finite number >= 0"):
        TrackOdometry(track_width=-1)
    with pytest.raises(ValueError, match=r"gauge\) must be > 0"):
        TrackOdometry(track_distance=0, track_width=0)
    with pytest.raises(ValueError, match=r"u must end in an axis of length 2"):
        ODO.increment([1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match=r"state must end in an axis of length 3"):
        ODO.predict([0.0, 0.0], [0.1, 0.1])
    with pytest.raises(ValueError, match=r"controls must have shape \(K, 2\)"):
        ODO.integrate(np.zeros(4))


def test_scalar_step_equals_the_vectorised_methods(rng):
    for _ in range(20):
        x = np.array([*rng.normal(size=2), rng.uniform(-3, 3)])
        u = rng.uniform(-0.2, 0.2, 2)
        new, F_x, F_u = ODO.step(x, u)
        np.testing.assert_allclose(new, ODO.predict(x, u), atol=1e-15)
        J_x, J_u = ODO.jacobians(x, u)
        np.testing.assert_allclose(F_x, J_x, atol=1e-15)
        np.testing.assert_allclose(F_u, J_u, atol=1e-15)
