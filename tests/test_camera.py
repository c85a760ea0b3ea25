import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from vo_lib.camera import StereoCamera


def test_bumblebee2_like_rig(camera):
    assert camera.width == 640 and camera.height == 480
    hfov = 2 * np.degrees(np.arctan(camera.width / 2 / camera.fx))
    assert hfov == pytest.approx(66.0)
    assert camera.baseline == pytest.approx(0.12)


@given(
    st.floats(-5, 5),
    st.floats(-3, 3),
    st.floats(0.5, 80.0),
)
def test_project_backproject_round_trip(x, y, z):
    cam = StereoCamera(500.0, 480.0, 320.5, 240.5, 0.12)
    P = np.array([[x, y, z]])
    np.testing.assert_allclose(cam.backproject(cam.project(P)), P, rtol=1e-10, atol=1e-10)


def test_eq13_as_printed_when_fx_equals_fy():
    cam = StereoCamera(400.0, 400.0, 200.0, 150.0, 0.12)
    u, v, d = 260.0, 100.0, 8.0
    P = cam.backproject([[u, v, d]])[0]
    B, f = 0.12, 400.0
    np.testing.assert_allclose(P, [B * (u - 200) / d, B * (v - 150) / d, B * f / d])


def test_disparity_is_left_minus_right_column():
    cam = StereoCamera.bumblebee2()
    P = np.array([[0.4, -0.2, 3.0]])
    w = cam.project(P)
    # right camera: same intrinsics, centre at +B on x
    u_right = cam.cx + cam.fx * (P[0, 0] - cam.baseline) / P[0, 2]
    assert w[0, 2] == pytest.approx(w[0, 0] - u_right)


def test_projection_matrices_round_trip():
    cam = StereoCamera(718.856, 718.856, 607.1928, 185.2157, 0.5371657, 1241, 376)
    P0, P1 = cam.projection_matrices()
    again = StereoCamera.from_projection_matrices(P0, P1, 1241, 376)
    assert again.baseline == pytest.approx(cam.baseline, rel=1e-12)
    assert (again.fx, again.fy, again.cx, again.cy) == (cam.fx, cam.fy, cam.cx, cam.cy)


def test_scaled_keeps_field_of_view():
    cam = StereoCamera.bumblebee2()
    small = cam.scaled(320, 240)
    assert small.fx == pytest.approx(cam.fx / 2)
    # the same ray lands on the same fraction of the image
    P = np.array([[0.7, -0.3, 4.0]])
    big_w, small_w = cam.project(P)[0], small.project(P)[0]
    assert (small_w[0] + 0.5) / 320 == pytest.approx((big_w[0] + 0.5) / 640)
    assert small_w[2] == pytest.approx(big_w[2] / 2)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(fx=0.0), r"fx \(focal length in pixels\) must be a finite number > 0"),
        (dict(fy=-3.0), r"fy \(focal length in pixels\) must be a finite number > 0"),
        (dict(baseline=0.0), r"baseline \(metres\) must be a finite number > 0"),
        (dict(baseline=-0.1), r"baseline \(metres\) must be a finite number > 0"),
        (dict(cx=np.nan), r"cx \(principal point\) must be finite"),
        (dict(width=0), r"width must be a positive whole number"),
    ],
)
def test_invalid_parameters(kwargs, message):
    params = dict(fx=500.0, fy=500.0, cx=320.0, cy=240.0, baseline=0.12)
    params.update(kwargs)
    with pytest.raises(ValueError, match=message):
        StereoCamera(**params)


def test_bad_arrays_and_disparities(camera):
    with pytest.raises(ValueError, match=r"w must have shape \(N, 3\)"):
        camera.backproject(np.zeros((5, 2)))
    with pytest.raises(ValueError, match=r"w\[:, 2\] \(disparity\) must be > 0.*row 1 has d=0.0"):
        camera.backproject([[100, 100, 5.0], [100, 100, 0.0]])
    with pytest.raises(ValueError, match=r"disparity\) must be > 0.*d=-2.0"):
        camera.backproject([[100, 100, -2.0]])
    with pytest.raises(ValueError, match=r"points must lie in front of the camera \(z > 0\); row 0"):
        camera.project([[0.0, 0.0, -1.0]])
    with pytest.raises(ValueError, match=r"P1 must place the right camera at \+x"):
        P0, P1 = camera.projection_matrices()
        StereoCamera.from_projection_matrices(P0, P0)


def test_in_image(camera):
    w = np.array([[0, 0, 1], [639, 479, 1], [640, 10, 1], [-0.5, 10, 1], [320, 240, 1]], float)
    np.testing.assert_array_equal(camera.in_image(w), [True, True, False, False, True])
    np.testing.assert_array_equal(camera.in_image(w, margin=5), [False, False, False, False, True])


def test_a_wide_fisheye_lens_keeps_its_focal_length_and_every_rectified_pixel():
    """An equidistant lens of 160 degrees across an 848x800 image (as small tracking cameras carry):
    the rectified pinhole view keeps its focal length and shows only what the lens saw."""
    import cv2

    from vo_lib.camera import rectify_stereo

    K = np.array([[286.0, 0.0, 424.0], [0.0, 286.0, 400.0], [0.0, 0.0, 1.0]])
    lens = (K, np.array([-0.007, 0.045, -0.043, 0.008]))
    T_right_left = np.eye(4)
    T_right_left[0, 3] = -0.064  # the right camera 6.4 cm to the right
    rect = rectify_stereo(lens, lens, (848, 800), T_right_left, np.eye(4), fisheye=True)
    assert rect.camera.fx == pytest.approx(286.0) and rect.camera.baseline == pytest.approx(0.064)
    x, y = cv2.fisheye.initUndistortRectifyMap(
        *lens, np.eye(3), rect.projections[0], (848, 800), cv2.CV_32FC1
    )
    assert ((x >= 0) & (x <= 847) & (y >= 0) & (y <= 799)).all()
    assert 0.25 < rect.valid_shares[0] < 0.9  # the centre of the lens's image, not all of it
