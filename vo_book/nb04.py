"""Figures of notebook 04 (world and sequences), kept out of its story cells.

Nothing here computes results: the functions draw what the notebook computed.
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np

from vo_book.plotting import new_axes, plot_robot, plot_world

#: Disparity errors beyond this many pixels are drawn in the histogram's end bins.
DISPARITY_CLIP_PX = 2.0
#: The colour scale of the ground-truth disparity, px.
DISPARITY_MAX_PX = 40


def panel_grid(n: int, columns: int = 3, size: float = 4.6):
    """``n`` square panels in rows of ``columns``, large enough for their legends; spares hidden.

    Returns the figure and its ``n`` axes.
    """
    rows = -(-n // columns)
    fig, grid = plt.subplots(rows, columns, figsize=(size * columns, size * rows), constrained_layout=True)
    grid = np.atleast_1d(grid).ravel()
    for spare in grid[n:]:
        spare.set_visible(False)
    return fig, grid[:n]


def plot_worlds(worlds: dict) -> None:
    """The floor plan of every world ``{name: World}``, one panel each; the corridor's panel
    carries the legend of the segments' kinds."""
    _, axes = panel_grid(len(worlds))
    for ax, world in zip(axes, worlds.values(), strict=True):
        plot_world(ax, world)
    axes[list(worlds).index("corridor")].legend(fontsize="small", loc="lower right")
    plt.show()


def plot_stereo_pair(left: np.ndarray, true_disparity: np.ndarray, disparity_error: np.ndarray) -> None:
    """The left image, its ground-truth disparity, and the histogram of the errors of semi-global
    matching against it (``disparity_error``, px, on the textured pixels; clipped to ±2 px)."""
    fig, axes = new_axes(3, width=5.0, height=3.6)
    axes[0].imshow(left, cmap="gray")
    axes[0].set_title("left image")
    im = axes[1].imshow(true_disparity, cmap="magma", vmin=0, vmax=DISPARITY_MAX_PX)
    axes[1].set_title("ground-truth disparity [px]")
    fig.colorbar(im, ax=axes[1], shrink=0.7)
    axes[2].hist(np.clip(disparity_error, -DISPARITY_CLIP_PX, DISPARITY_CLIP_PX), bins=80)
    axes[2].set_title("semi-global matching − truth")
    axes[2].set_xlabel("disparity error [px]")
    axes[2].set_ylabel("pixels")
    for ax in axes[:2]:
        ax.axis("off")
    plt.show()


def plot_scan(world, pose: np.ndarray, end_points: np.ndarray) -> None:
    """The plan of ``world`` with the robot at ``pose`` and its laser scan's ``end_points``
    (world frame, ``(K, 2)``)."""
    _, ax = new_axes(width=7, height=4.5)
    plot_world(ax, world, "laser scan from the same pose")
    ax.plot(end_points[:, 0], end_points[:, 1], ".", ms=2, color="C3", label="scan end points")
    plot_robot(ax, pose)
    ax.legend(fontsize="x-small", loc="lower right")
    plt.show()


def plot_drives(worlds: dict, drives: dict, samples: dict) -> None:
    """One panel per world ``{name: World}``: the plan, and the true path (solid) and odometry's
    belief (dotted, same colour) of every sample ``{name: (drive, believed poses)}`` driven in it;
    ``samples`` names each sample's world (``SAMPLES``)."""
    _, axes = panel_grid(len(worlds))
    for ax, (world_name, world) in zip(axes, worlds.items(), strict=True):
        plot_world(ax, world, f"samples in {world_name}")
        for name, (drive, believed) in drives.items():
            if samples[name].world == world_name:
                (line,) = ax.plot(*drive.poses[:, :2].T, lw=2, label=f"{name} (truth)")
                ax.plot(*believed[:, :2].T, ls=":", color=line.get_color(), label=f"{name} (odometry)")
        ax.legend(fontsize="small", loc="upper left")
    plt.show()


def plot_spot_turn(t: np.ndarray, heading: np.ndarray, believed: np.ndarray, slip: np.ndarray) -> None:
    """The spot turn over time ``t``: the true ``heading`` and odometry's ``believed`` one
    (radians, unwrapped and drawn in degrees), and the slip of each track (``(K, 2)`` shares,
    drawn in per cent from the second frame on)."""
    _, axes = new_axes(2, width=5.5, height=3.5)
    axes[0].plot(t, np.degrees(np.unwrap(heading)), label="truth")
    axes[0].plot(t, np.degrees(np.unwrap(believed)), label="odometry")
    axes[0].set_xlabel("time [s]")
    axes[0].set_ylabel("heading [deg]")
    axes[0].legend()
    axes[0].set_title("spot turn")
    axes[1].plot(t[1:], 100 * slip[1:, 0], label="left track")
    axes[1].plot(t[1:], 100 * slip[1:, 1], label="right track")
    axes[1].set_xlabel("time [s]")
    axes[1].set_ylabel("slip [%]")
    axes[1].legend()
    axes[1].set_title("slip of each track")
    plt.show()


def plot_frames(shown: list, stats: dict) -> None:
    """The frames ``[(title, image)]`` one above the other, each titled with its statistics
    ``{title: ImageStatistics}``: the share of cells without a corner, the corners per 640×480,
    the share of flat pixels."""
    _, axes = plt.subplots(
        len(shown), 1, figsize=(11, 3.3 * len(shown)), squeeze=False, constrained_layout=True
    )
    for ax, (title, image) in zip(axes[:, 0], shown, strict=True):
        st = stats[title]
        ax.imshow(image, cmap="gray", vmin=0, vmax=255)
        ax.set_title(
            f"{title}: {st.empty_cells:.2f} of cells without a corner, {st.corners_per_vga:,.0f} corners "
            f"per 640×480, {st.low_gradient:.2f} flat pixels",
            fontsize="small",
        )
        ax.axis("off")
    plt.show()
