"""The image statistics that compare rendered frames with real ones, on images whose answer is known."""

import numpy as np
import pytest

from vo_lib.sim.realism import (
    ImageStatistics,
    gradient_magnitude,
    image_statistics,
    occupied_cells,
    spread_frames,
)


def test_a_uniform_image_has_no_corner_and_no_gradient():
    s = image_statistics(np.full((48, 64), 90, np.uint8))
    assert s == ImageStatistics(empty_cells=1.0, corners_per_vga=0.0, low_gradient=1.0)


def test_bright_dots_give_one_corner_each_in_their_own_cells():
    image = np.full((96, 128), 50, np.uint8)
    dots = [(20, 20), (70, 30), (100, 80), (104, 84)]  # the last two share a 16x16 cell
    for u, v in dots:
        image[v, u] = 200  # a lone bright pixel: all 16 circle pixels are darker
    s = image_statistics(image)
    assert s.empty_cells == pytest.approx(1 - 3 / 48)  # 3 of 6 x 8 cells occupied
    assert s.corners_per_vga == pytest.approx(4 * 640 * 480 / image.size)
    assert 0.9 < s.low_gradient < 1.0  # only the pixels around the dots are steep


def test_gradient_is_the_unnormalised_sobel_magnitude():
    ramp = np.tile(np.arange(0, 64, 1, dtype=np.uint8) * 3, (32, 1))  # 3 grey levels per pixel
    g = gradient_magnitude(ramp)[5:-5, 5:-5]
    np.testing.assert_allclose(g, 8 * 3)  # Sobel sums 1-2-1 weights of central differences 2 apart
    gentle = np.tile((np.arange(64) * 2).astype(np.uint8), (32, 1))  # 2 levels/px: magnitude 16 < 20
    assert image_statistics(gentle).low_gradient > 0.9
    assert image_statistics(ramp).low_gradient < 0.1


def test_partial_cells_at_the_border_count():
    grid = occupied_cells((40, 50), np.array([[49.0, 39.0]]))
    assert grid.shape == (3, 4) and grid[2, 3] and grid.sum() == 1


def test_bad_input_and_frame_spread():
    with pytest.raises(ValueError, match="grey uint8"):
        image_statistics(np.zeros((10, 10, 3), np.uint8))
    with pytest.raises(ValueError, match="at least one image"):
        ImageStatistics.mean([])
    np.testing.assert_array_equal(spread_frames(5), np.arange(5))
    idx = spread_frames(108)
    assert len(idx) == 20 and idx[0] == 0 and idx[-1] == 107
