import cv2
import numpy as np
import pytest

from vo_lib.camera import StereoCamera
from vo_lib.geometry import camera_mount, planar_to_matrix
from vo_lib.sim.render import SensorEffects, StereoRenderer
from vo_lib.sim.textures import corner_texture
from vo_lib.sim.world import WORLDS, Segment, World, box, corridor


def plane_world(distance=3.0, slant=(2.0,)):
    """One textured wall ahead of the origin, slanted by moving its right end ``slant`` metres."""
    return World(
        "plane",
        (Segment((distance, -6.0), (distance + slant[0], 6.0), 6.0, texture_seed=5),),
        (-1, 8, -8, 8),
        1,
    )


def test_texture_is_deterministic_by_seed():
    a, b, c = corner_texture(64, 80, 3), corner_texture(64, 80, 3), corner_texture(64, 80, 4)
    assert a.dtype == np.uint8 and a.shape == (64, 80)
    np.testing.assert_array_equal(a, b)
    assert np.mean(a != c) > 0.5
    with pytest.raises(ValueError, match="texture size must be positive"):
        corner_texture(0, 10, 1)


@pytest.mark.parametrize("target", ["wall", "floor"])
def test_fast_finds_hundreds_of_well_spread_corners(target):
    cam = StereoCamera.bumblebee2()
    if target == "wall":
        world, mount = plane_world(2.5, (0.0,)), camera_mount(height=1.5)
    else:  # look down at the floor
        world = World("floor", (), (-10, 10, -10, 10), 4)
        mount = camera_mount(height=1.2)
        tilt = cv2.Rodrigues(np.array([0.0, 0.9, 0.0]))[0]  # +rotation about robot y tips x down
        mount[:3, :3] = tilt @ mount[:3, :3]
    image = StereoRenderer(world, cam).render(planar_to_matrix((0, 0, 0)) @ mount)
    keypoints = cv2.FastFeatureDetector_create(20).detect(image)
    assert len(keypoints) >= 300
    pts = np.array([k.pt for k in keypoints])
    cells = np.unique((pts[:, 0] // 160).astype(int) * 10 + (pts[:, 1] // 120).astype(int))
    assert len(cells) >= 14  # of the 4 x 4 grid cells


def test_depth_of_a_frontal_wall_and_of_the_floor():
    cam = StereoCamera.bumblebee2()
    world = World("wall", (Segment((4.0, -10.0), (4.0, 10.0), 1.0, texture_seed=1),), (-5, 20, -20, 20), 2)
    height = 0.5
    image, depth = StereoRenderer(world, cam).render(
        planar_to_matrix((0, 0, 0)) @ camera_mount(height=height), with_depth=True
    )
    # rows above the wall top (1.0 m) show the sky; rows of the wall read 4 m everywhere
    row_wall = int(cam.cy) - 20
    np.testing.assert_allclose(depth[row_wall], 4.0, rtol=1e-5)
    assert np.isinf(depth[0]).all()
    # the floor in front of the wall: z = h * fy / (v - cy)
    v = np.arange(int(cam.cy) + 70, cam.height)
    expected = height * cam.fy / (v - cam.cy)
    np.testing.assert_allclose(depth[v, 320], expected, rtol=1e-4)
    assert image.dtype == np.uint8 and image.shape == (480, 640)


def test_block_matching_agrees_with_ground_truth_disparity():
    cam = StereoCamera.bumblebee2()
    renderer = StereoRenderer(plane_world(), cam)
    left, right, depth = renderer.render_pair(
        planar_to_matrix((0, 0, 0)) @ camera_mount(height=1.0), with_depth=True
    )
    truth = cam.fx * cam.baseline / depth
    sgbm = cv2.StereoSGBM_create(0, 64, 5, P1=200, P2=800, uniquenessRatio=5, mode=cv2.STEREO_SGBM_MODE_HH)
    measured = sgbm.compute(left, right).astype(np.float32) / 16
    textured = (np.abs(cv2.Sobel(left, cv2.CV_32F, 1, 0, ksize=3)) > 20) & (measured > 0) & np.isfinite(truth)
    textured[:, :64] = False  # no disparity search possible at the left border
    err = np.abs(measured - truth)[textured]
    assert textured.sum() > 30000
    assert np.median(err) < 0.25
    assert np.mean(err < 0.5) > 0.95


def test_right_image_is_the_left_camera_moved_by_the_baseline():
    cam = StereoCamera.bumblebee2()
    renderer = StereoRenderer(WORLDS["indoor_lab"](), cam)
    T = planar_to_matrix((-3, 0, 0.2)) @ camera_mount(height=0.5)
    left, right = renderer.render_pair(T)
    shifted = T.copy()
    shifted[:3, 3] += T[:3, 0] * cam.baseline
    np.testing.assert_array_equal(right, renderer.render(shifted))
    assert not np.array_equal(left, right)


def test_sensor_effects():
    img = np.full((10, 10), 100, np.uint8)
    assert (SensorEffects(exposure_gain=1.5).apply(img, None) == 150).all()
    with pytest.raises(ValueError, match="sensor noise needs an rng"):
        SensorEffects(noise_sigma=2).apply(img, None)
    a = SensorEffects(noise_sigma=2).apply(img, np.random.default_rng(1))
    b = SensorEffects(noise_sigma=2).apply(img, np.random.default_rng(1))
    np.testing.assert_array_equal(a, b)
    assert 1.0 < a.astype(float).std() < 3.0


def test_worlds_and_building_blocks():
    assert set(WORLDS) == {"indoor_lab", "indoor_lab_cart", "outdoor_yard", "corridor", "road"}
    c = corridor()
    kinds = [s.kind for s in c.segments]
    assert kinds.count("pillar") == 8 and "fire hydrant" in kinds and "umbrella" in kinds
    assert (
        len(c.segments_array(mapped_only=True)) == len(c.segments) - 6
    )  # the umbrella (6 pieces of canopy) is unmapped
    sides = box((0, 0), (2, 1), 0.0, 1.0, 0)
    assert sum(s.length for s in sides) == pytest.approx(6.0)
    with pytest.raises(ValueError, match="has zero length"):
        Segment((1, 1), (1, 1))
    with pytest.raises(ValueError, match="height must be > 0"):
        Segment((0, 0), (1, 1), height=0)


def test_movers_move_and_nothing_else_does():
    """The lab's trolley is where its path says at each time; the static lab renders the same."""
    from vo_lib.sim.world import indoor_lab_cart

    world = indoor_lab_cart()
    cart = world.movers[0]
    (p0, yaw0), (p1, _) = cart.pose(0.0), cart.pose(2.0)
    np.testing.assert_allclose(p1 - p0, [2 * cart.speed, 0.0, 0.0], atol=1e-9)
    assert yaw0 == 0.0
    cam = StereoCamera.bumblebee2(160, 120)
    T = planar_to_matrix((-3.0, 0.0, np.pi / 2)) @ camera_mount(height=0.5)  # facing the north side
    moving = StereoRenderer(world, cam)
    _, d0 = moving.render(T, with_depth=True, time=0.0)
    _, d1 = moving.render(T, with_depth=True, time=2.0)
    still = StereoRenderer(WORLDS["indoor_lab"](), cam)
    np.testing.assert_array_equal(still.render(T, time=0.0), still.render(T, time=2.0))
    changed = np.abs(d1 - d0) > 0.1
    assert 0.01 < changed.mean() < 0.5  # the trolley's pixels, not the whole view
    # where the trolley is in view, it stands 3.0 m away (the path's y) less half its width
    near = np.minimum(d0, d1)[changed]
    assert abs(np.percentile(near, 5) - (3.0 - cart.size[1] / 2)) < 0.3
