"""6-DoF refinement, the vehicle frame, compiled matching, KITTI raw files and the rigid pipeline."""

from __future__ import annotations

import numpy as np
import pytest

from vo_lib.camera import StereoCamera
from vo_lib.formats.kitti_raw import camera_in_imu_frame, read_oxts, wheel_distances_from_oxts
from vo_lib.formats.sequence import SequenceError
from vo_lib.geometry import camera_mount
from vo_lib.stereo_vo.kalman import chord_measurement
from vo_lib.stereo_vo.rigid_motion import (
    refine_rigid_motion,
    rotation_matrix,
    scaled_motion,
    se3_exp,
    se3_log,
)
from vo_lib.stereo_vo.six_dof import (
    vehicle_increment,
    with_planar_increment,
)
from vo_lib.stereo_vo.temporal import predict_features
from vo_lib.stereo_vo.vehicle import CAR_GAUGE, car_odometry_model


@pytest.fixture
def kitti_camera() -> StereoCamera:
    return StereoCamera(fx=721.5, fy=721.5, cx=609.6, cy=172.9, baseline=0.537, width=1242, height=375)


def motion(rotvec, t) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = rotation_matrix(rotvec), t
    return T


def scene(rng, n=300) -> np.ndarray:
    return np.column_stack([rng.uniform(-15, 15, n), rng.uniform(-3, 1.6, n), rng.uniform(4, 60, n)])


def test_refinement_recovers_a_known_motion_and_rejects_outliers(kitti_camera, rng):
    P = scene(rng)
    T = motion([0.004, -0.03, 0.002], [0.05, -0.02, -1.2])
    w_prev = kitti_camera.project(P)
    w_curr = kitti_camera.project(P @ T[:3, :3].T + T[:3, 3])
    w_curr[:, :2] += rng.normal(0, 0.2, (len(P), 2))
    bad = rng.choice(len(P), 60, replace=False)
    w_curr[bad, :2] += rng.uniform(5, 40, (60, 2)) * rng.choice([-1, 1], (60, 2))
    guess = motion([0, -0.02, 0], [0, 0, -1.0])  # roughly what 1-point RANSAC gives
    result = refine_rigid_motion(w_prev, w_curr, kitti_camera, guess)
    assert result.success
    assert np.allclose(result.R, T[:3, :3], atol=2e-4)
    assert np.allclose(result.t, T[:3, 3], atol=0.01)
    assert not result.inliers[bad].any()
    assert result.inliers.sum() >= 0.9 * (len(P) - 60)
    assert 0.1 < result.rms_pixels < 0.5
    sd = np.sqrt(np.diag(result.covariance))
    assert np.all(sd > 0) and sd[5] < 0.01  # forward translation known to centimetres


def test_refinement_fails_cleanly_with_too_few_matches(kitti_camera, rng):
    P = scene(rng, 4)
    w = kitti_camera.project(P)
    result = refine_rigid_motion(w, w, kitti_camera, np.eye(4))
    assert not result.success and np.isinf(result.covariance).all()


def test_prediction_and_scaled_motion(kitti_camera, rng):
    P = scene(rng, 50)
    T = motion([0.0, 0.02, 0.0], [0.0, 0.0, -1.0])
    twice = scaled_motion(T, 2.0)
    pred, ok = predict_features(kitti_camera.project(P), kitti_camera, twice)
    assert ok.all()
    assert np.allclose(pred, kitti_camera.project(P @ (T @ T)[:3, :3].T + (T @ T)[:3, 3]), atol=1e-6)


@pytest.mark.parametrize("angle", [0.0, 1e-7, 1e-3, 0.3, 2.5])
def test_closed_form_se3_log_and_exp_agree_with_logm_and_expm(angle):
    from scipy.linalg import expm, logm

    rng = np.random.default_rng(int(angle * 1e7) % 2**32)
    axis = rng.normal(size=3)
    w, v = angle * axis / np.linalg.norm(axis), rng.normal(0, 0.5, 3)
    hat = np.zeros((4, 4))
    hat[:3, :3] = [[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]]
    hat[:3, 3] = v
    T = se3_exp(w, v)
    np.testing.assert_allclose(T, expm(hat), atol=1e-12)
    w2, v2 = se3_log(T)
    np.testing.assert_allclose(np.r_[w2, v2], np.r_[w, v], atol=1e-10)
    if angle > 0:
        np.testing.assert_allclose(np.real(logm(T)), hat, atol=1e-8)
    for factor in (0.5, 1.0 / 3.0, 2.0, 3.0):
        np.testing.assert_allclose(scaled_motion(T, factor), np.real(expm(factor * hat)), atol=1e-10)
    assert not np.allclose(scaled_motion(T, 2.0), T) or angle == 0.0 and np.allclose(v, 0)


def test_vehicle_increment_of_a_camera_ahead_of_the_axis():
    mount = camera_mount(forward=1.2, height=1.6)
    # the vehicle turns by 0.1 rad about its origin, moving 1 m along the chord
    theta = 0.1
    inc = np.array([np.cos(theta / 2), np.sin(theta / 2), theta])
    V = np.eye(4)
    c, s = np.cos(theta), np.sin(theta)
    V[:2, :2] = [[c, -s], [s, c]]
    V[:2, 3] = inc[:2]
    T_cam = np.linalg.inv(np.linalg.inv(mount) @ V @ mount)  # curr-from-prev of the camera
    assert np.allclose(vehicle_increment(T_cam, mount), inc)
    assert np.allclose(chord_measurement(inc), [theta, 1.0, 0.0])
    # replacing the planar part by itself changes nothing; by another, gives that one back
    assert np.allclose(with_planar_increment(T_cam, mount, inc), T_cam)
    other = np.array([0.8, 0.01, -0.05])
    assert np.allclose(vehicle_increment(with_planar_increment(T_cam, mount, other), mount), other)


def test_oxts_reader_names_file_and_line(tmp_path):
    path = tmp_path / "oxts.txt"
    path.write_text(" ".join(["1"] * 30) + "\n" + " ".join(["1"] * 29) + "\n")
    with pytest.raises(SequenceError, match=r"oxts.txt, line 2: an OXTS packet needs 30 numbers, got 29"):
        read_oxts(path)
    path.write_text(" ".join(["1"] * 29 + ["nan"]) + "\n")
    with pytest.raises(SequenceError, match="line 1: an OXTS packet holds a NaN or infinite value"):
        read_oxts(path)
    path.write_text(" ".join(["1"] * 8 + ["1e300"] + ["1"] * 21) + "\n")  # a speed that overflows the filter
    with pytest.raises(SequenceError, match="line 1: a number beyond"):
        read_oxts(path)
    path.write_text(" ".join(["x"] * 30) + "\n")
    with pytest.raises(SequenceError, match="line 1: an OXTS packet holds a non-number"):
        read_oxts(path)


def test_wheel_distances_give_back_speed_and_yaw_rate():
    times = np.arange(5) * 0.1
    oxts = np.zeros((5, 30))
    oxts[:, 8] = [10, 10, 12, 12, 12]  # forward speed
    oxts[:, 19] = [0.0, 0.1, 0.1, -0.2, -0.2]  # yaw rate
    u = wheel_distances_from_oxts(oxts, times, CAR_GAUGE)
    assert np.allclose(u[0], 0)
    model = car_odometry_model(CAR_GAUGE)
    s, dpsi = model.increment(u[1:])
    assert np.allclose(s, [1.0, 1.1, 1.2, 1.2])
    assert np.allclose(dpsi, [0.005, 0.01, -0.005, -0.02])


def test_camera_in_imu_frame_from_raw_calibration(tmp_path):
    (tmp_path / "calib_imu_to_velo.txt").write_text("R: 1 0 0 0 1 0 0 0 1\nT: -0.8 0.3 -0.8\n")
    # velodyne (x fwd, y left, z up) to camera (x right, y down, z fwd)
    (tmp_path / "calib_velo_to_cam.txt").write_text("R: 0 -1 0 0 0 -1 1 0 0\nT: 0 -0.08 -0.27\n")
    (tmp_path / "calib_cam_to_cam.txt").write_text("R_rect_00: 1 0 0 0 1 0 0 0 1\n")
    T = camera_in_imu_frame(tmp_path)
    assert np.allclose(T[:3, :3], [[0, 0, 1], [-1, 0, 0], [0, -1, 0]])
    assert np.allclose(T[:3, 3], [0.8 + 0.27, -0.3, 0.8 - 0.08])  # velodyne in IMU, plus camera in velodyne
    (tmp_path / "calib_cam_to_cam.txt").write_text("R_rect_01: 1 0 0 0 1 0 0 0 1\n")
    with pytest.raises(SequenceError, match="no line starting with 'R_rect_00:'"):
        camera_in_imu_frame(tmp_path)


@pytest.mark.parametrize("yaw_deg", [0.0, 4.0, 9.0])
def test_one_point_ransac_seen_from_the_turning_axis_keeps_every_match_in_a_sharp_turn(kitti_camera, yaw_deg):
    """A car's camera a metre ahead of the axis slides sideways in a turn: seen from the camera
    itself the circular-motion gates lose true matches (more, the sharper the turn); seen from
    the virtual camera on the axis they keep them all, and theta and rho are the vehicle's."""
    from scipy.spatial.transform import Rotation

    from vo_lib.geometry import camera_motion
    from vo_lib.stereo_vo.ransac import one_point_ransac
    from vo_lib.stereo_vo.six_dof import turning_axis_transform, turning_axis_view
    from vo_lib.stereo_vo.synthetic import matches_under_transform

    mount = camera_mount(forward=1.08, height=1.73, left=-0.31)
    mount[:3, :3] = Rotation.from_euler("y", 0.5, degrees=True).as_matrix() @ mount[:3, :3]  # tilted
    theta, rho = np.radians(yaw_deg), 1.0
    T = camera_motion(np.zeros(3), [rho * np.cos(theta / 2), rho * np.sin(theta / 2), theta], mount)
    to_axis = turning_axis_transform(mount)
    recall = {}
    for view in ("camera", "axis"):
        found = []
        for seed in range(3):
            rng = np.random.default_rng(seed)
            m = matches_under_transform(kitti_camera, 300, T, rng, (4.0, 60.0), 0.5, 0.2)
            a, b = m.w_prev, m.w_curr
            if view == "axis":
                a, b = (turning_axis_view(w, kitti_camera, to_axis) for w in (a, b))
            est = one_point_ransac(a, b, kitti_camera, rng=rng, pixel_sigma=1.0)
            found.append((est.inliers & m.inliers).sum() / m.inliers.sum())
            assert not (est.inliers & ~m.inliers).any()
            if view == "axis":
                assert est.theta == pytest.approx(theta, abs=2e-4)
                assert est.rho == pytest.approx(rho, abs=5e-3)
        recall[view] = np.mean(found)
    assert recall["axis"] >= 0.98
    if yaw_deg >= 4.0:
        assert recall["camera"] < 0.8  # what the virtual camera is for


@pytest.mark.parametrize("pitch_deg", [0.0, 1.0])
def test_a_pitching_car_still_gets_a_hypothesis_with_its_inliers(kitti_camera, pitch_deg):
    """Over a bump the vehicle pitches: the planar 1-point model keeps no match (at 1 deg), the
    general 3-point RANSAC takes over, and the refinement recovers the true 6-DoF motion."""
    from scipy.spatial.transform import Rotation

    from vo_lib.geometry import camera_motion
    from vo_lib.stereo_vo.config import CAR
    from vo_lib.stereo_vo.pipeline import StereoOdometry
    from vo_lib.stereo_vo.synthetic import Scene, matches_under_transform

    mount = camera_mount(forward=1.08, height=1.73, left=-0.31)
    theta = np.radians(3.0)
    T = camera_motion(np.zeros(3), [np.cos(theta / 2), np.sin(theta / 2), theta], mount)
    D = np.eye(4)
    D[:3, :3] = Rotation.from_euler("y", pitch_deg, degrees=True).as_matrix()  # the vehicle pitches
    T = np.linalg.inv(mount) @ D @ mount @ T
    road = Scene(camera_height=1.73, top=4.0)
    m = matches_under_transform(kitti_camera, 300, T, np.random.default_rng(3), (4.0, 60.0), 0.5, 0.2, road)
    odometer = StereoOdometry(kitti_camera, CAR, mount=mount, seed=5)
    guess, start, ratio = odometer.motion.hypothesis(m.w_prev, m.w_curr, None, odometer.rng)
    assert ratio >= CAR.min_inlier_ratio
    assert start is not None and (start & m.inliers).sum() >= 0.7 * m.inliers.sum()
    assert (start & ~m.inliers).sum() <= 2
    motion = refine_rigid_motion(m.w_prev, m.w_curr, kitti_camera, guess, start)
    # a road scene (points above the road, crowded near the horizon): mm-level, well below the
    # 0.017 a missed 1-degree pitch would leave
    assert np.allclose(motion.matrix, T, atol=6e-3)
    assert not (motion.inliers & ~m.inliers).any()
    # the same draws give the same answer
    again_odometer = StereoOdometry(kitti_camera, CAR, mount=mount, seed=5)
    again = again_odometer.motion.hypothesis(m.w_prev, m.w_curr, None, again_odometer.rng)
    assert np.array_equal(again[0], guess) and np.array_equal(again[1], start)


def test_car_gauge_gives_the_measured_yaw_noise_of_the_oxts_yaw_rate():
    import os
    from pathlib import Path

    from vo_lib.formats.kitti_raw import VF
    from vo_lib.stereo_vo.vehicle import CAR_DISTANCE_SIGMA, gauge_for_yaw_noise

    default = Path(__file__).resolve().parents[1].parent / "shared" / "realdata"
    root = Path(os.environ.get("VO_LIB_REALDATA") or default)
    drive = root / "kitti_raw_2011_09_26_drive_0001"
    if not (drive / "oxts.txt").is_file():
        pytest.skip(f"no KITTI raw drive 0001 with oxts.txt under {root}")
    times = np.loadtxt(drive / "times.txt")
    oxts = read_oxts(drive / "oxts.txt")
    u = wheel_distances_from_oxts(oxts, times, CAR_GAUGE)
    s, dpsi = car_odometry_model(CAR_GAUGE).increment(u[1:])
    heading_change = np.diff(np.unwrap(oxts[:, 5]))  # field 6: the OXTS heading
    gauge = gauge_for_yaw_noise(s, dpsi - heading_change, CAR_DISTANCE_SIGMA)
    assert gauge == pytest.approx(CAR_GAUGE, rel=0.05)
    assert np.allclose(s, 0.5 * (oxts[1:, VF] + oxts[:-1, VF]) * np.diff(times))
    with pytest.raises(ValueError, match="some error"):
        gauge_for_yaw_noise(s, np.zeros_like(s), CAR_DISTANCE_SIGMA)
    assert gauge_for_yaw_noise([1.0, 1.0], [0.01, 0.01], 0.02) == pytest.approx(0.02 * np.sqrt(2 * 2 / 2e-4))


def test_a_free_body_gets_general_hypotheses_without_the_planar_model(kitti_camera, monkeypatch):
    """The drone's preset: a motion that rolls and climbs, the general 3-point RANSAC alone (the
    planar 1-point RANSAC is not called), its inliers the true matches."""
    from vo_lib.stereo_vo import six_dof
    from vo_lib.stereo_vo.config import HOVER
    from vo_lib.stereo_vo.pipeline import StereoOdometry
    from vo_lib.stereo_vo.synthetic import matches_under_transform

    T = motion([0.02, -0.03, 0.05], [0.05, -0.04, 0.3])
    m = matches_under_transform(kitti_camera, 300, T, np.random.default_rng(4), (4.0, 40.0), 0.5, 0.3)

    def refuse(*args, **kwargs):
        raise AssertionError("the planar 1-point RANSAC was called")

    monkeypatch.setattr(six_dof, "one_point_ransac", refuse)
    odometer = StereoOdometry(kitti_camera, HOVER, mount=camera_mount(forward=0.0, height=0.0), seed=5)
    guess, start, ratio = odometer.motion.hypothesis(m.w_prev, m.w_curr, None, odometer.rng)
    assert start is not None and ratio == pytest.approx(start.mean())
    assert (start & m.inliers).sum() >= 0.8 * m.inliers.sum() and (start & ~m.inliers).sum() <= 2
    refined = refine_rigid_motion(m.w_prev, m.w_curr, kitti_camera, guess, start)
    assert np.allclose(refined.matrix, T, atol=6e-3)


def test_the_drone_predicts_from_the_last_frame_not_from_the_reference(kitti_camera):
    """Constant velocity steps on from the last frame's motion since the reference (measured or
    guessed), so frames measured against an older reference keep what they found; a new
    reference starts the count again."""
    from vo_lib.stereo_vo.config import HOVER
    from vo_lib.stereo_vo.kalman import VoKalmanFilter
    from vo_lib.stereo_vo.parts import Prediction
    from vo_lib.stereo_vo.six_dof import SixDofMotion

    model, kf = SixDofMotion(kitti_camera, camera_mount(forward=0.0, height=0.0), HOVER), VoKalmanFilter()
    V, M = motion([0.0, 0.02, 0.0], [0.0, 0.0, 0.1]), motion([0.01, -0.05, 0.0], [0.02, 0.0, 0.05])
    model.velocity = V
    model.place(kf, None, Prediction(kf.motion_prior(), True, M))  # the last frame, since the reference
    assert np.allclose(model.predict(kf).motion, V @ M)  # not V repeated for each frame since the reference
    model.commit(kf, None, 3)
    assert np.allclose(model.predict(kf).motion, V)


def second_frame_with(kitti_camera, monkeypatch, T, guided_matches, unguided_matches, **settings):
    """The drone's pipeline (``HOVER`` with ``settings``) on two frames whose temporal matches are
    given: ``guided_matches`` when the prediction ``T`` guides the windows, ``unguided_matches`` when
    every pair is matched. Returns the second frame's diagnostics, whether each attempt was
    guided, and the odometer."""
    from dataclasses import replace

    from vo_lib.stereo_vo import six_dof
    from vo_lib.stereo_vo.config import HOVER
    from vo_lib.stereo_vo.features import StereoFeatures
    from vo_lib.stereo_vo.pipeline import StereoOdometry
    from vo_lib.stereo_vo.temporal import TemporalMatches

    guided = []

    def match(self, reference, features, prediction, recent):
        guided.append(prediction.motion is not None)
        m = guided_matches if prediction.motion is not None else unguided_matches
        index = np.arange(len(m.w_prev))
        return TemporalMatches(index, index, m.w_prev, m.w_curr, len(index))

    class FrontEnd:
        def process(self, left, right):
            w = unguided_matches.w_curr
            return StereoFeatures(w, np.zeros((len(w), 32), np.uint8))

    monkeypatch.setattr(six_dof.SixDofMotion, "match", match)
    config = replace(HOVER, subpixel_tracking=False, **settings)
    odometer = StereoOdometry(
        kitti_camera, config, mount=camera_mount(0.0, 0.0), front_end=FrontEnd(), seed=1
    )
    odometer.process(None, None)  # the reference
    odometer.motion.velocity = T  # a prediction, to guide the windows
    _, _, diag, _ = odometer.process(None, None)
    return diag, guided, odometer


def test_a_frame_whose_windows_give_too_few_inliers_is_matched_again_without_them(kitti_camera, monkeypatch):
    """A prediction that sends the matching windows astray (a turn that reverses) leaves a frame
    with matches that agree on nothing; the pipeline matches every pair again and keeps the frame."""
    from vo_lib.stereo_vo.synthetic import matches_under_transform

    rng = np.random.default_rng(8)
    T = motion([0.0, 0.04, 0.0], [0.02, 0.0, 0.2])
    good = matches_under_transform(kitti_camera, 200, T, rng, (4.0, 40.0), 0.3)
    astray = matches_under_transform(kitti_camera, 200, T, rng, (4.0, 40.0), 0.3, outlier_ratio=1.0)
    diag, guided, odometer = second_frame_with(kitti_camera, monkeypatch, T, astray, good)
    assert guided == [True, False]
    assert not diag.fallback and diag.inliers >= 0.8 * len(good.w_prev)
    assert np.allclose(odometer.camera_pose, np.linalg.inv(T), atol=2e-3)


def test_a_blurred_frame_is_judged_with_the_wider_gate_on_its_last_attempt_only(kitti_camera):
    """Matches too noisy for six of them to lie within a pixel of their motion, as in a fast turn's
    blur: the refinement fails with the usual gate; the frame's last attempt (matched without
    windows) is refined again within ``LAST_RESORT_GATE`` and keeps the motion; an attempt inside
    predicted windows, which the pipeline still retries without them, does not."""
    from vo_lib.stereo_vo.config import HOVER
    from vo_lib.stereo_vo.kalman import VoKalmanFilter
    from vo_lib.stereo_vo.parts import Prediction
    from vo_lib.stereo_vo.six_dof import LAST_RESORT_GATE, SixDofMotion
    from vo_lib.stereo_vo.synthetic import matches_under_transform
    from vo_lib.stereo_vo.temporal import TemporalMatches

    T = motion([0.01, 0.15, 0.0], [0.05, 0.0, 0.1])  # 8.6 degrees of turn
    m = matches_under_transform(kitti_camera, 16, T, np.random.default_rng(3), (2.0, 20.0), 0.8)
    assert not refine_rigid_motion(m.w_prev, m.w_curr, kitti_camera, T).success
    assert refine_rigid_motion(m.w_prev, m.w_curr, kitti_camera, T, gate=LAST_RESORT_GATE).success
    index = np.arange(len(m.w_prev))
    matches = TemporalMatches(index, index, m.w_prev, m.w_curr, len(index))
    model = SixDofMotion(kitti_camera, camera_mount(forward=0.0, height=0.0), HOVER)
    prior = VoKalmanFilter().motion_prior()
    unguided = model.estimate(matches, Prediction(prior, True), np.random.default_rng(0))
    guided = model.estimate(matches, Prediction(prior, True, T), np.random.default_rng(0))
    assert unguided.success and unguided.inliers >= 6 and not guided.success
    assert np.allclose(unguided.motion, T, atol=0.02)


@pytest.mark.parametrize("last_attempt_ratio", [0.0, None])
def test_the_drone_waives_the_inlier_ratio_on_a_frames_last_attempt_only(
    kitti_camera, monkeypatch, last_attempt_ratio
):
    """Matches of which 30 % agree on the motion, as unguided matching pairs blurred images: the
    guided attempt is judged by the ratio and retried without windows, where the drone's preset
    keeps the motion whatever the ratio; with the ratio kept there (the car's rule), the frame is
    flagged."""
    from vo_lib.stereo_vo.config import HOVER
    from vo_lib.stereo_vo.frames import Reason
    from vo_lib.stereo_vo.synthetic import matches_under_transform

    T = motion([0.0, 0.04, 0.0], [0.02, 0.0, 0.2])
    m = matches_under_transform(
        kitti_camera, 200, T, np.random.default_rng(8), (4.0, 40.0), 0.3, outlier_ratio=0.7
    )
    diag, guided, odometer = second_frame_with(
        kitti_camera, monkeypatch, T, m, m, last_attempt_ratio=last_attempt_ratio
    )
    assert guided == [True, False] and diag.inlier_ratio < HOVER.min_inlier_ratio
    if last_attempt_ratio is None:
        assert diag.fallback and diag.reason is Reason.LOW_INLIER_RATIO
    else:
        assert not diag.fallback and diag.inliers >= 0.6 * m.inliers.sum()
        assert np.allclose(odometer.camera_pose, np.linalg.inv(T), atol=2e-3)
