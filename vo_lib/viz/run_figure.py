"""The figure ``python -m vo_lib run`` writes: what the run did, against the truth where known.

Left, the plan view of the paths (truth wide and pale underneath, the estimate dashed on top; a
straight drive's narrow axis stretched so that centimetres of drift show), or a spot turn's heading
against time. Right, with truth, the position and heading errors over time (for a body with no
ground plane, a drone: 3-D position and rotation angle).
"""

from __future__ import annotations

import numpy as np

from vo_lib.evaluation import is_spot_turn, rotation_angle, turned_degrees
from vo_lib.geometry import wrap_angle

TRUTH_STYLE = {"color": "0.55", "lw": 5.0, "alpha": 0.45, "solid_capstyle": "round", "zorder": 1}
#: Position-only truth (a tracker's prism): its samples, not a line between them.
TRACKED_STYLE = {"color": "0.3", "ls": "none", "marker": ".", "ms": 5, "zorder": 2}
ESTIMATE_STYLE = {"color": "C0", "lw": 1.3, "ls": "--", "zorder": 3}
ODOMETRY_STYLE = {"color": "C1", "lw": 1.0, "zorder": 2}


#: A path whose narrow side is below this share of its long side has the narrow axis stretched
#: to the paths' spread (a straight drive: the drift across it is the point).
THIN_PATH = 0.15


def _paths(estimate, truth, odometry, odometry_label, tracked=None):
    """``(label, poses, style)`` of each path given: truth, tracked positions, odometry, estimate."""
    fused = "visual odometry (fused with odometry)" if odometry is not None else "visual odometry"
    paths = [
        ("ground truth", truth, TRUTH_STYLE),
        ("tracked point (ground truth, aligned)", tracked, TRACKED_STYLE),
        (odometry_label, odometry, ODOMETRY_STYLE),
    ]
    return [p for p in paths if p[1] is not None] + [(fused, estimate, ESTIMATE_STYLE)]


def _mark_ends(ax, xs, ys, name):
    """Start and end of the first path, ``name``."""
    ax.plot(xs[0], ys[0], "o", color="green", ms=8, zorder=5, label="start")
    ax.plot(xs[-1], ys[-1], "s", mfc="none", mec="k", ms=9, mew=1.5, zorder=5, label=f"end ({name})")


def _plan_view(ax, paths, title):
    for label, poses, style in paths:
        ax.plot(poses[:, 0], poses[:, 1], label=label, **style)
    ends = paths[0][1]
    _mark_ends(ax, ends[:, 0], ends[:, 1], paths[0][0])
    estimate = paths[-1][1]
    if len(paths) > 1:  # the end of the estimate, beside the truth's (or the odometry's)
        ax.plot(
            estimate[-1, 0], estimate[-1, 1], "x", color="C0", ms=9, mew=2, zorder=6, label="end (estimate)"
        )
    labels = ["x [m]", "y [m]"]
    spans = np.ptp(ends[:, :2], axis=0)
    narrow = int(np.argmin(spans))
    if spans[narrow] < THIN_PATH * spans[1 - narrow]:
        values = np.concatenate([poses[:, narrow] for _, poses, _ in paths])
        low, high = values.min(), values.max()
        pad = max(0.15 * (high - low), 0.005)
        (ax.set_ylim if narrow else ax.set_xlim)(low - pad, high + pad)
        labels[narrow] += ", not to scale"
    else:
        ax.set_aspect("equal", adjustable="datalim")
    ax.set(xlabel=labels[0], ylabel=labels[1], title=title)


def _heading_view(ax, times, paths, title):
    for label, poses, style in paths:
        ax.plot(times, np.degrees(np.unwrap(poses[:, 2])), label=label, **style)
    truth = np.degrees(np.unwrap(paths[0][1][:, 2]))
    _mark_ends(ax, times, truth, paths[0][0])
    ax.set(xlabel="time [s]", ylabel="heading, unwrapped [deg]", title=title)


def plot_run(
    fig,
    times,
    estimate,
    truth=None,
    odometry=None,
    title: str = "",
    odometry_label: str = "track odometry",
    camera_poses=None,
    tracked=None,
) -> dict:
    """Draw a run's figure on the matplotlib figure ``fig``: ``times`` (K,) in seconds, planar poses
    ``(x, y, yaw)`` (K, 3), ``truth`` and ``odometry`` optional (``odometry_label`` says which).
    ``camera_poses``: the estimate's and the truth's 4x4 camera poses, for errors in 3-D (a drone).
    ``tracked``: position-only truth ``(K, 2)`` aligned to ``estimate``, drawn as points.

    Returns ``main`` (the path or heading axes), ``errors`` (the error axes, empty without truth)
    and ``spot_turn`` (whether the heading view was drawn).
    """
    times, estimate = np.asarray(times, float), np.asarray(estimate, float)
    truth, odometry, tracked = (
        None if x is None else np.asarray(x, float) for x in (truth, odometry, tracked)
    )
    paths = _paths(estimate, truth, odometry, odometry_label, tracked)
    spot = truth is not None and is_spot_turn(truth)
    if truth is None:
        main, errors = fig.add_subplot(1, 1, 1), []
    else:
        grid = fig.add_gridspec(2, 2, width_ratios=(1.25, 1.0))
        main = fig.add_subplot(grid[:, 0])
        errors = [fig.add_subplot(grid[0, 1])]
        errors.append(fig.add_subplot(grid[1, 1], sharex=errors[0]))
    if spot:
        _heading_view(main, times, paths, f"{title}: {turned_degrees(truth):.0f}° turned on the spot")
    else:
        _plan_view(main, paths, title)
    main.grid(True, alpha=0.3)
    main.legend(loc="best", fontsize="x-small")
    if errors and camera_poses is not None:
        _errors_3d(errors, times, *camera_poses)
    elif errors:
        _error_views(errors, times, paths)
    return {"main": main, "errors": errors, "spot_turn": spot}


def _error_views(errors, times, paths) -> None:
    """Position and heading errors of every path against the truth (``paths[0]``)."""
    truth = paths[0][1]
    for label, poses, style in paths[1:]:
        line = {k: v for k, v in style.items() if k != "zorder"}
        position = 100 * np.hypot(*(poses[:, :2] - truth[:, :2]).T)
        heading = np.degrees(wrap_angle(poses[:, 2] - truth[:, 2]))
        errors[0].plot(times, position, label=label, **line)
        errors[1].plot(times, heading, label=label, **line)
    errors[0].set(ylabel="position error [cm]", title="errors against ground truth")
    errors[1].set(ylabel="heading error [deg]", xlabel="time [s]")
    errors[1].axhline(0.0, color="0.5", lw=0.8)
    _grid_and_legend(errors)


def _errors_3d(errors, times, estimate, truth) -> None:
    """3-D position error and rotation angle of the estimate's camera poses against the truth's."""
    E, T = np.asarray(estimate, float), np.asarray(truth, float)
    position = 100 * np.linalg.norm(E[:, :3, 3] - T[:, :3, 3], axis=1)
    line = {k: v for k, v in ESTIMATE_STYLE.items() if k != "zorder"}
    errors[0].plot(times, position, label="visual odometry", **line)
    errors[1].plot(times, np.degrees(rotation_angle(np.swapaxes(T[:, :3, :3], 1, 2) @ E[:, :3, :3])), **line)
    errors[0].set(ylabel="3-D position error [cm]", title="errors against ground truth")
    errors[1].set(ylabel="rotation error [deg]", xlabel="time [s]")
    _grid_and_legend(errors)


def _grid_and_legend(errors) -> None:
    """The two error views' grid, and the legend of the upper one."""
    for ax in errors:
        ax.grid(True, alpha=0.3)
    errors[0].legend(loc="best", fontsize="x-small")
