"""Figures the notebooks share, kept out of the reader's way. Nothing here computes results."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.patches import Arc, Ellipse


def new_axes(ncols: int = 1, width: float = 5.0, height: float = 4.0, **kw):
    """A row of ``ncols`` axes with a sensible size; returns ``(fig, axes)``."""
    fig, axes = plt.subplots(1, ncols, figsize=(width * ncols, height), constrained_layout=True, **kw)
    return fig, axes


def covariance_ellipse(ax, mean, cov, n_sigma: float = 2.0, **style):
    """Draw the ``n_sigma`` ellipse of a 2x2 covariance centred on ``mean``."""
    vals, vecs = np.linalg.eigh(np.asarray(cov, dtype=float)[:2, :2])
    vals = np.clip(vals, 0.0, None)
    angle = np.degrees(np.arctan2(vecs[1, 1], vecs[0, 1]))
    width, height = 2 * n_sigma * np.sqrt(vals[::-1])
    style = {"fill": False, "lw": 1.2, **style}
    ax.add_patch(Ellipse(mean[:2], width, height, angle=angle, **style))


def plot_paths(ax, paths: dict, title: str = "", every: int = 0):
    """Plan view of planar paths ``{label: (K, 3) poses}``; arrows every ``every`` poses."""
    for label, poses in paths.items():
        poses = np.asarray(poses)
        (line,) = ax.plot(poses[:, 0], poses[:, 1], label=label)
        if every:
            p = poses[::every]
            ax.quiver(
                p[:, 0],
                p[:, 1],
                np.cos(p[:, 2]),
                np.sin(p[:, 2]),
                color=line.get_color(),
                angles="xy",
                scale=25,
                width=0.004,
            )
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(True, alpha=0.3)
    if title:
        ax.set_title(title)
    ax.legend(loc="best", fontsize="small")


KIND_COLOURS = {
    "wall": "0.2",
    "end wall": "0.2",
    "building": "0.35",
    "pillar": "C0",
    "box": "C2",
    "crate": "C2",
    "cabinet": "C2",
    "fire hydrant": "C3",
    "cross wall": "C4",
    "umbrella": "C1",
}


def plot_world(ax, world, title: str = ""):
    """Plan view of a world's segments, coloured by kind; unmapped ones dashed."""
    seen = set()
    for seg in world.segments:
        colour = KIND_COLOURS.get(seg.kind, "0.4")
        label = seg.kind if seg.kind not in seen else None
        seen.add(seg.kind)
        ax.plot(
            [seg.start[0], seg.end[0]],
            [seg.start[1], seg.end[1]],
            color=colour,
            lw=2,
            ls="--" if not seg.mapped else "-",
            label=label,
        )
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title or world.name)


def plot_robot(ax, pose, size: float = 0.4, colour: str = "k"):
    """A triangle at a planar pose, pointing along its heading."""
    x, y, yaw = pose
    pts = np.array([[size, 0], [-size / 2, size / 2.5], [-size / 2, -size / 2.5]])
    c, s = np.cos(yaw), np.sin(yaw)
    pts = pts @ np.array([[c, s], [-s, c]]) + (x, y)
    ax.fill(pts[:, 0], pts[:, 1], color=colour, alpha=0.8)


def _angle_arc(ax, centre, start_dir, end_dir, radius: float, label: str, colour: str = "C1"):
    """An arc at ``centre`` from direction ``start_dir`` to ``end_dir`` (the smaller angle), labelled."""
    a0 = np.degrees(np.arctan2(start_dir[1], start_dir[0]))
    a1 = np.degrees(np.arctan2(end_dir[1], end_dir[0]))
    if (a1 - a0) % 360 > 180:
        a0, a1 = a1, a0
    ax.add_patch(Arc(centre, 2 * radius, 2 * radius, theta1=a0, theta2=a1, color=colour, lw=1.2))
    mid = np.radians(a0 + ((a1 - a0) % 360) / 2)
    ax.text(
        *(np.asarray(centre) + 1.35 * radius * np.array([np.cos(mid), np.sin(mid)])),
        label,
        color=colour,
        ha="center",
        va="center",
    )


def draw_chord_geometry(ax, theta: float = 0.5, rho: float = 1.0, point=(1.2, 3.0)) -> dict:
    """Plan view of the reconstructed Fig. 5 of [Zhao]: the camera moves from C to C' along a
    chord at phi = theta/2; a point X is seen at angle gamma from the chord at C and gamma' at C',
    at horizontal ranges r and r'. Coordinates: x right, z forward of the first camera.

    Returns the drawn ``gamma``, ``gamma2`` (radians), ``r`` and ``r2``."""
    phi = theta / 2
    C = np.array([0.0, 0.0])
    C2 = rho * np.array([-np.sin(phi), np.cos(phi)])
    X = np.asarray(point, float)
    ax.plot(*zip(C, C2, strict=True), "k-", lw=2, label="chord, length ρ")
    ext = C2 + 0.8 * (C2 - C) / rho
    ax.plot(*zip(C2, ext, strict=True), "k:", lw=1)
    for P, name in ((C, "C"), (C2, "C'")):
        ax.plot(*zip(P, X, strict=True), "C0-", lw=1)
        ax.plot(*P, "ko")
        ax.annotate(name, P, textcoords="offset points", xytext=(-14, -4))
    ax.plot(*X, "C3o")
    ax.annotate("X", X, textcoords="offset points", xytext=(6, 0))
    # optical axes
    for P, yaw in ((C, 0.0), (C2, -theta)):
        d = np.array([np.sin(yaw), np.cos(yaw)])
        ax.annotate("", P + 0.7 * d, P, arrowprops={"arrowstyle": "->", "color": "0.5"})
    # the angles between the chord's direction and the rays to X
    u = (C2 - C) / rho
    _angle_arc(ax, C, u, X - C, 0.35 * rho, "γ")
    _angle_arc(ax, C2, u, X - C2, 0.25 * rho, "γ'")
    # foot of the perpendicular from X to the chord line: the distance both ends share
    foot = C + ((X - C) @ u) * u
    ax.plot(*zip(X, foot, strict=True), "C2--", lw=1, label="h = r sin γ = r' sin γ'")
    ax.text(*(0.5 * (C + X) + (0.1, -0.1)), "r")
    ax.text(*(0.5 * (C2 + X) + (-0.25, 0.05)), "r'")
    ax.set_aspect("equal")
    ax.set_xlabel("x (right) [m]")
    ax.set_ylabel("z (forward) [m]")
    ax.legend(fontsize="x-small", loc="lower right")

    def angle(v):
        return float(np.arccos(np.clip(u @ v / np.linalg.norm(v), -1.0, 1.0)))

    return {
        "gamma": angle(X - C),
        "gamma2": angle(X - C2),
        "r": float(np.linalg.norm(X - C)),
        "r2": float(np.linalg.norm(X - C2)),
    }


def draw_depression_geometry(ax, r: float, r2: float, drop: float = 0.5) -> dict:
    """Side view of the reconstructed Fig. 5 of [Zhao]: the two rays to X, each unfolded into its
    own vertical plane, leave C and C' at the camera's height and fall by ``drop`` to the point
    at horizontal ranges ``r`` and ``r2``: depression angles alpha and alpha'.

    Returns the drawn ``alpha`` and ``alpha2`` (radians)."""
    X = np.array([0.0, -drop])
    for rng_, name, colour, radius in ((r, "C", "C0", 0.3 * r), (r2, "C'", "C1", 0.3 * r2)):
        P = np.array([-rng_, 0.0])
        ax.plot(*zip(P, X, strict=True), "-", color=colour, lw=1)
        ax.plot(*P, "ko")
        ax.annotate(name, P, textcoords="offset points", xytext=(-6, 6))
        _angle_arc(ax, P, (1.0, 0.0), X - P, radius, "α" if name == "C" else "α'", colour)
    ax.axhline(0.0, color="0.5", lw=0.8, ls=":", label="camera height (planar motion keeps it)")
    ax.plot(*zip(X, (0.0, 0.0), strict=True), "C2--", lw=1, label="r tan α = r' tan α'")
    ax.plot(*X, "C3o")
    ax.annotate("X", X, textcoords="offset points", xytext=(6, 0))
    ax.set_aspect("equal")
    ax.set_xlabel("horizontal range from X [m]")
    ax.set_ylabel("height [m]")
    ax.legend(fontsize="x-small", loc="lower left")
    return {"alpha": float(np.arctan2(drop, r)), "alpha2": float(np.arctan2(drop, r2))}


def plot_line_slam(ax, run, world, title: str = ""):
    """[Yan 2020]'s Fig. 6/8: true path and segments, estimated path, feature points and segments."""
    for i, seg in enumerate(world.segments):
        ax.plot(
            *np.transpose([seg.start, seg.end]), color="C3", lw=2.5, label="true lines" if i == 0 else None
        )
        ax.annotate(str(i + 1), np.mean([seg.start, seg.end], axis=0), color="C3", fontsize=11)
    ax.plot(run.truth[:, 0], run.truth[:, 1], color="C3", lw=1, ls="--", label="true path")
    ax.plot(run.estimate[:, 0], run.estimate[:, 1], color="C0", lw=1, label="estimated path")
    ax.plot(run.dead_reckoning[:, 0], run.dead_reckoning[:, 1], color="0.6", lw=1, label="dead reckoning")
    for n, seg in enumerate(run.landmark_of_segment):
        ends = run.estimated_segment(seg)
        ax.plot(ends[:, 0], ends[:, 1], color="C0", lw=1.5, label="estimated lines" if n == 0 else None)
        j = run.landmark_of_segment[seg]
        ax.plot(*run.true_landmarks[seg], "o", color="C3", ms=5)
        ax.plot(*run.landmarks[j], "x", color="C0", ms=7)
        covariance_ellipse(ax, run.landmarks[j], run.landmark_cov[j], 2.0, color="C0")
    ax.plot(0, 0, "k+", ms=10)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper left", fontsize="small")
    if title:
        ax.set_title(title)


def plot_pose_errors(axes, run, heading_errors):
    """[Yan 2020]'s Fig. 7/9: x, y and heading errors over time with the filter's 2-sigma bounds."""
    t = np.arange(len(run.truth)) * run.scenario.period
    errors = [run.estimate[:, 0] - run.truth[:, 0], run.estimate[:, 1] - run.truth[:, 1], heading_errors]
    sigmas = np.sqrt(np.stack([run.pose_cov[:, i, i] for i in range(3)]))
    labels = ["x error [m]", "y error [m]", "heading error [deg]"]
    for i, ax in enumerate(axes):
        scale = np.degrees(1.0) if i == 2 else 1.0
        ax.plot(t, scale * errors[i], color="C0", lw=1, label="error")
        ax.fill_between(t, -2 * scale * sigmas[i], 2 * scale * sigmas[i], color="C0", alpha=0.15, label="±2σ")
        ax.set_ylabel(labels[i])
        ax.set_xlabel("time [s]")
        ax.grid(True, alpha=0.3)
    axes[0].legend(loc="upper left", fontsize="small")


def draw_observer_case(ax, a, b, centre, max_range: float, part, title: str = ""):
    """A segment, the laser's range circle, the foot of the perpendicular and the visible part."""
    a, b, centre = (np.asarray(v, dtype=float) for v in (a, b, centre))
    d = b - a
    t_foot = (centre - a) @ d / (d @ d)
    foot = a + t_foot * d
    ang = np.linspace(0, 2 * np.pi, 200)
    ax.plot(centre[0] + max_range * np.cos(ang), centre[1] + max_range * np.sin(ang), color="0.7", lw=1)
    ax.plot(*np.transpose([a, b]), color="0.3", lw=2)
    ax.plot(*np.transpose([a - 0.3 * d, b + 0.3 * d]), color="0.3", lw=0.5, ls=":")
    ax.plot(*np.transpose([centre, foot]), color="C2", lw=1, ls="--")
    if part is not None:
        seen = a + np.outer(part, d)
        ax.plot(seen[:, 0], seen[:, 1], color="C1", lw=4, alpha=0.8, label="visible part")
    for name, p in (("A", a), ("B", b), ("G", centre), ("O", foot)):
        ax.annotate(name, p, xytext=(4, 4), textcoords="offset points")
    ax.plot(*centre, "k^")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.3)
    if title:
        ax.set_title(title)


def draw_circular_motion(ax, theta: float = 0.6, radius: float = 2.0, offset: float = 0.0) -> dict:
    """[Zhao]'s Fig. 2, plan view of the first camera frame (x right, z forward): the robot
    turns by ``theta`` (left positive) about the instantaneous centre of rotation (ICR) at
    ``radius`` to the left of its turning axis, and the camera, ``offset`` ahead of that axis,
    moves from C to C' along a chord of length rho at the angle phi from its optical axis.

    With ``offset = 0`` (the paper's assumption) the camera is on the turning axis, rho is
    ``2 radius sin(theta / 2)`` and phi is ``theta / 2``; with an offset the camera runs on a wider
    circle and the chord leans by more than ``theta / 2``.

    Returns ``C2`` (the second camera centre, (x, z)), ``rho`` and ``phi`` as drawn, and
    ``labels``, the texts of the drawn angles and lengths."""
    C = np.array([0.0, 0.0])
    A = C - offset * np.array([0.0, 1.0])  # the robot's turning axis, behind the camera
    icr = A + np.array([-radius, 0.0])
    A2 = icr + radius * np.array([np.cos(theta), np.sin(theta)])
    C2 = A2 + offset * np.array([-np.sin(theta), np.cos(theta)])
    arc = np.linspace(0.0, theta, 50)
    ax.plot(icr[0] + radius * np.cos(arc), icr[1] + radius * np.sin(arc), color="0.6", lw=1, ls="--")
    ax.plot(*zip(icr, A, strict=True), color="0.5", lw=1)
    ax.plot(*zip(icr, A2, strict=True), color="0.5", lw=1, label="R_ICR")
    ax.plot(*icr, "k+", ms=10)
    ax.annotate("ICR", icr, textcoords="offset points", xytext=(4, -12))
    ax.plot(*zip(C, C2, strict=True), "k-", lw=2, label="chord, length ρ")
    ax.text(*(0.5 * (C + C2) + (0.06 * radius, -0.06 * radius)), "ρ", ha="center", va="center")
    if offset:
        for P, Pa in ((C, A), (C2, A2)):
            ax.plot(*zip(Pa, P, strict=True), color="C2", lw=1.5, ls=":")
            ax.plot(*Pa, "s", color="C2", ms=5)
        ax.plot([], [], color="C2", ls=":", label="camera offset from the turning axis")
        ax.text(*(0.5 * (A + C) + (0.05 * radius, 0.0)), "offset", color="C2", fontsize="small")
    for P, yaw, name in ((C, 0.0, "C"), (C2, theta, "C'")):
        axis = np.array([-np.sin(yaw), np.cos(yaw)])  # the optical axis z, turned left by yaw
        tip = P + 0.45 * radius * axis
        ax.annotate("", tip, P, arrowprops={"arrowstyle": "->", "color": "C0"})
        ax.plot(*tip, linestyle="none")  # keeps the arrow inside the axes' limits
        ax.plot(*P, "ko")
        ax.annotate(name, P, textcoords="offset points", xytext=(6, -6))
    chord = C2 - C
    rho = float(np.hypot(*chord))
    _angle_arc(ax, C, (0.0, 1.0), chord, 0.25 * radius, "φ")
    _angle_arc(ax, icr, (1.0, 0.0), A2 - icr, 0.3 * radius, "θ")
    ax.set_aspect("equal")
    ax.set_xlabel("x (right) [m]")
    ax.set_ylabel("z (forward) [m]")
    ax.legend(fontsize="x-small", loc="upper left")
    phi = float(np.arccos(chord[1] / rho))
    labels = [t.get_text() for t in ax.texts]
    return {"C2": C2, "rho": rho, "phi": phi, "labels": labels}


def draw_flowchart(ax, stages, side=None) -> dict:
    """Boxes for ``stages`` top to bottom, joined by arrows; ``side`` is an optional list of
    ``(from, to, label)`` stage indices for arrows drawn to the right (feedback, priors).

    Returns ``boxes`` (the stage texts, top to bottom) and ``arrows`` (the arrow annotations)."""
    boxes, arrows = [], []
    n = len(stages)
    ys = np.linspace(0.95, 0.05, n)
    for i, (y, text) in enumerate(zip(ys, stages, strict=True)):
        box = ax.text(
            0.4,
            y,
            text,
            ha="center",
            va="center",
            fontsize="small",
            bbox={"boxstyle": "round,pad=0.4", "fc": "white", "ec": "0.3"},
        )
        boxes.append(box)
        if i:
            arrows.append(
                ax.annotate("", (0.4, y + 0.045), (0.4, ys[i - 1] - 0.045), arrowprops={"arrowstyle": "->"})
            )
    for a, b, label in side or []:
        arrow = ax.annotate(
            "",
            (0.78, ys[b]),
            (0.78, ys[a]),
            arrowprops={"arrowstyle": "->", "color": "C1", "connectionstyle": "arc3,rad=-0.4"},
        )
        arrows.append(arrow)
        ax.text(0.86, 0.5 * (ys[a] + ys[b]), label, color="C1", fontsize="x-small", va="center")
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1)
    ax.axis("off")
    return {"boxes": boxes, "arrows": arrows}
