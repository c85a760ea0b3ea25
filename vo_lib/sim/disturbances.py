"""Frames a real camera also delivers: blank, pure noise, and a large object moving through the view.

Used to test that the pipeline never stops and flags exactly the frames it cannot trust.
"""

from __future__ import annotations

import numpy as np

from vo_lib.camera import StereoCamera
from vo_lib.sim.textures import corner_texture

BLANK_GREY = 128


def blank_pair(shape, grey: int = BLANK_GREY) -> tuple[np.ndarray, np.ndarray]:
    """A lens cap, a dark room, a wall too close: two uniform images."""
    img = np.full(shape, grey, np.uint8)
    return img, img.copy()


def noise_pair(shape, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Interference: two independent images of uniform noise."""
    return rng.integers(0, 256, shape, dtype=np.uint8), rng.integers(0, 256, shape, dtype=np.uint8)


class MovingObject:
    """A textured board at a fixed depth covering a fraction of the view, sliding sideways.

    It appears in both images with the disparity of its depth, so its corners stereo-match and
    carry depth like the world's; its motion across the image is its own.
    """

    def __init__(
        self,
        camera: StereoCamera,
        depth: float = 1.5,
        fraction: float = 0.5,
        speed_px: float = 6.0,
        seed: int = 99,
    ):
        self.camera = camera
        self.disparity = int(round(camera.fx * camera.baseline / depth))
        self.width = int(round(fraction * camera.width))
        self.speed = speed_px
        self.texture = corner_texture(camera.height, self.width + 4 * camera.width, seed)

    def occlude(self, left: np.ndarray, right: np.ndarray, step: int) -> tuple[np.ndarray, np.ndarray]:
        """Frames ``left, right`` with the board drawn over their left part, ``step`` frames in."""
        left, right = left.copy(), right.copy()
        offset = int(round(step * self.speed))
        board = self.texture[:, offset : offset + self.width]
        left[:, : self.width] = board
        # the right camera sees the board shifted left by its disparity
        right[:, : self.width - self.disparity] = board[:, self.disparity :]
        return left, right
