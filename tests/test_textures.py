"""Texture styles: photographs tiled without seams, painted surfaces without corners, determinism."""

import numpy as np
import pytest

from vo_lib.sim.realism import image_statistics
from vo_lib.sim.textures import STYLES, mirrored_tiling, surface_texture


def test_mirrored_tiling_has_no_seam():
    tile = np.random.default_rng(0).uniform(0, 255, (16, 24)).astype(np.float32)
    out = mirrored_tiling(tile, 100, 130, np.random.default_rng(1))
    assert out.shape == (100, 130)
    # across every seam the neighbouring columns repeat (mirror), so no jump is bigger than inside a tile
    jumps = np.abs(np.diff(out, axis=1)).max(axis=0)
    assert jumps.max() <= np.abs(np.diff(tile, axis=1)).max()


@pytest.mark.parametrize("style", STYLES)
def test_every_style_is_deterministic_uint8(style):
    a = surface_texture(style, 120, 160, 0.01, 7)
    b = surface_texture(style, 120, 160, 0.01, 7)
    assert a.dtype == np.uint8 and a.shape == (120, 160)
    np.testing.assert_array_equal(a, b)


def test_paint_is_empty_and_photographs_are_not():
    plain = image_statistics(surface_texture("plain", 240, 320, 0.01, 1))
    gravel = image_statistics(surface_texture("gravel", 240, 320, 0.005, 1))
    assert plain.empty_cells == 1.0 and plain.low_gradient > 0.99
    assert gravel.empty_cells < 0.5
    with pytest.raises(ValueError, match="unknown texture style 'marble'"):
        surface_texture("marble", 10, 10, 0.01, 1)
