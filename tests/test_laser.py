import numpy as np
import pytest

from vo_lib.sim.laser import LaserScanner, cast_rays
from vo_lib.sim.world import corridor

SQUARE = np.array([[-2, -2, 2, -2], [2, -2, 2, 2], [2, 2, -2, 2], [-2, 2, -2, -2]], float)


def test_ranges_in_a_square_room_are_exact():
    scanner = LaserScanner(
        fov=np.radians(360) - 1e-9, angular_step=np.radians(1), max_range=10, range_sigma=0
    )
    scan = scanner.scan(SQUARE, (0.0, 0.0, 0.0))
    b = scan.bearings
    expected = 2.0 / np.maximum(np.abs(np.cos(b)), np.abs(np.sin(b)))
    np.testing.assert_allclose(scan.ranges, expected, rtol=1e-12)
    assert scan.valid.all()


def test_sick_tim551_like_defaults():
    scanner = LaserScanner()
    assert len(scanner.bearings) == 811
    assert np.degrees(scanner.bearings[-1] - scanner.bearings[0]) == pytest.approx(270)


def test_nearer_segments_occlude_and_max_range_invalidates():
    segs = np.array([[5.0, -1.0, 5.0, 1.0], [2.0, -0.2, 2.0, 0.2]])
    r = cast_rays(segs, (0.0, 0.0), np.array([0.0, 0.15, np.pi]))
    assert r[0] == pytest.approx(2.0) and r[1] == pytest.approx(5.0 / np.cos(0.15)) and np.isinf(r[2])
    scan = LaserScanner(max_range=4.0, range_sigma=0).scan(segs, (0, 0, 0))
    ahead = np.argmin(np.abs(scan.bearings))
    assert scan.valid[ahead] and not scan.valid[ahead + 30]  # 10 degrees left: only the far wall
    assert np.isinf(scan.ranges[~scan.valid]).all()


def test_pose_and_mount_move_the_beams():
    scanner = LaserScanner(range_sigma=0, mount=(0.2, 0.0, 0.0))
    segs = np.array([[3.0, -5.0, 3.0, 5.0]])
    ahead = np.argmin(np.abs(scanner.bearings))
    assert scanner.scan(segs, (0.0, 0.0, 0.0)).ranges[ahead] == pytest.approx(2.8)
    # robot turned by 90 degrees looking at y: a wall at y = 3
    assert scanner.scan(np.array([[-5, 3.0, 5, 3.0]]), (0, 0, np.pi / 2)).ranges[ahead] == pytest.approx(2.8)


def test_noise_is_seeded_and_scaled():
    scanner = LaserScanner(range_sigma=0.05)
    segs = corridor().segments_array()
    a = scanner.scan(segs, (5.0, 0.0, 0.0), np.random.default_rng(3))
    b = scanner.scan(segs, (5.0, 0.0, 0.0), np.random.default_rng(3))
    exact = scanner.scan(segs, (5.0, 0.0, 0.0))
    np.testing.assert_array_equal(a.ranges, b.ranges)
    both = a.valid & exact.valid
    assert np.std(a.ranges[both] - exact.ranges[both]) == pytest.approx(0.05, rel=0.15)
    assert a.points().shape == (a.valid.sum(), 2)


def test_bad_parameters():
    with pytest.raises(ValueError, match="max_range must be > 0"):
        LaserScanner(max_range=0)
    with pytest.raises(ValueError, match="range_sigma must be >= 0"):
        LaserScanner(range_sigma=-1)
