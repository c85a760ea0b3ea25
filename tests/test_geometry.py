import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from vo_lib.geometry import (
    R_ROBOT_FROM_CAMERA,
    as_match_array,
    compose_planar,
    matrix_to_planar,
    planar_to_matrix,
    relative_planar,
    rigid_inverse,
    wrap_angle,
)

angles = st.floats(-50.0, 50.0, allow_nan=False)
coords = st.floats(-100.0, 100.0, allow_nan=False)


@given(angles)
def test_wrap_angle_range_and_equivalence(a):
    w = wrap_angle(a)
    assert -np.pi <= w < np.pi
    assert np.isclose(np.cos(w), np.cos(a), atol=1e-9) and np.isclose(np.sin(w), np.sin(a), atol=1e-9)


def test_wrap_angle_vectorised_and_boundaries():
    out = wrap_angle([np.pi, -np.pi, 3 * np.pi, 0.5])
    np.testing.assert_allclose(out, [-np.pi, -np.pi, -np.pi, 0.5])


@given(coords, coords, angles, coords, coords, angles)
def test_relative_inverts_compose(x, y, a, dx, dy, da):
    pose = np.array([x, y, wrap_angle(a)])
    inc = np.array([dx, dy, wrap_angle(da)])
    back = relative_planar(pose, compose_planar(pose, inc))
    np.testing.assert_allclose(back[:2], inc[:2], atol=1e-9)
    assert abs(wrap_angle(back[2] - inc[2])) < 1e-9


def test_compose_matches_matrices():
    a, b = np.array([1.0, -2.0, 0.7]), np.array([0.3, 0.4, -1.2])
    M = planar_to_matrix(a) @ planar_to_matrix(b)
    np.testing.assert_allclose(matrix_to_planar(M), compose_planar(a, b), atol=1e-12)


def test_camera_axes_in_robot_frame():
    # optical axis (camera z) is the robot's forward x; camera x (right) is robot -y; y (down) is -z
    np.testing.assert_array_equal(R_ROBOT_FROM_CAMERA @ [0, 0, 1], [1, 0, 0])
    np.testing.assert_array_equal(R_ROBOT_FROM_CAMERA @ [1, 0, 0], [0, -1, 0])
    np.testing.assert_array_equal(R_ROBOT_FROM_CAMERA @ [0, 1, 0], [0, 0, -1])
    assert np.isclose(np.linalg.det(R_ROBOT_FROM_CAMERA), 1.0)


def test_as_match_array_errors_name_the_argument():
    with pytest.raises(ValueError, match=r"w_prev must have shape \(N, 3\).*\(4,\)"):
        as_match_array("w_prev", np.zeros(4))
    with pytest.raises(ValueError, match="w_curr must be finite; row 1"):
        as_match_array("w_curr", [[1, 2, 3], [1, np.nan, 3]])


def test_one_pose_gives_the_batched_result_bit_for_bit():
    """One pose takes a path of plain floats (the filter's hot path): it must not differ at all
    from the batched arrays, whose results the rest of the library sees."""
    rng = np.random.default_rng(3)
    a, b = rng.normal(0.0, 4.0, (500, 3)), rng.normal(0.0, 4.0, (500, 3))
    a[:20, 2], b[20:40, 2] = np.pi, -np.pi  # the wrap's edges
    for f in (relative_planar, compose_planar):
        one = np.array([f(p, q) for p, q in zip(a, b, strict=True)])
        assert np.array_equal(one, f(a, b))
    angles = np.concatenate([a[:, 2], [np.pi, -np.pi, 3 * np.pi, 0.0]])
    assert np.array_equal([wrap_angle(float(x)) for x in angles], wrap_angle(angles))


def test_rigid_inverse_is_the_matrix_inverse_batched_and_single(rng):
    from scipy.spatial.transform import Rotation

    T = np.tile(np.eye(4), (50, 1, 1))
    T[:, :3, :3] = Rotation.random(50, random_state=rng).as_matrix()
    T[:, :3, 3] = rng.normal(0, 100, (50, 3))
    np.testing.assert_allclose(rigid_inverse(T), np.linalg.inv(T), atol=1e-12)
    np.testing.assert_allclose(rigid_inverse(T[7]) @ T[7], np.eye(4), atol=1e-12)
