"""The walk-through widget of notebook 04 (world and sequences), kept out of its story cells.

One pose in one world: the left image and ground-truth depth the renderer gives there, and the
laser scan on the floor plan.
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np

from vo_book.plotting import new_axes, plot_robot, plot_world
from vo_lib.camera import StereoCamera
from vo_lib.geometry import camera_mount, planar_to_matrix
from vo_lib.sim.laser import LaserScanner
from vo_lib.sim.render import StereoRenderer
from vo_lib.sim.samples import CAMERA_HEIGHT
from vo_lib.sim.world import WORLDS

#: The notebook's base seed: the laser's range noise draws from it.
SEED = 4
camera = StereoCamera.bumblebee2()
mount = camera_mount(height=CAMERA_HEIGHT)


def view_from(world_name: str = "corridor", x: float = 11.0, y: float = 0.0, yaw_deg: float = 0.0) -> int:
    """Left image, ground-truth depth and laser scan of a robot at ``(x, y, yaw)`` in a world of
    :data:`vo_lib.sim.world.WORLDS`; returns the number of beams that hit something."""
    world = WORLDS[world_name]()
    robot = np.array([x, y, np.radians(yaw_deg)])
    image, depth_map = StereoRenderer(world, camera).render(planar_to_matrix(robot) @ mount, with_depth=True)
    scan = LaserScanner().scan(world.segments_array(), robot, np.random.default_rng(SEED))
    fig, axes = new_axes(3, width=4.6, height=3.4)
    axes[0].imshow(image, cmap="gray")
    axes[0].set_title("left image")
    axes[1].imshow(np.where(np.isfinite(depth_map), depth_map, np.nan), cmap="viridis", vmin=0, vmax=15)
    axes[1].set_title("depth [m] (0-15)")
    for ax in axes[:2]:
        ax.axis("off")
    plot_world(axes[2], world, "plan and laser scan")
    c, s = np.cos(robot[2]), np.sin(robot[2])
    end = scan.points() @ np.array([[c, s], [-s, c]]) + robot[:2]
    axes[2].plot(end[:, 0], end[:, 1], ".", ms=1.5, color="C3")
    plot_robot(axes[2], robot)
    plt.show()
    return int(scan.valid.sum())
