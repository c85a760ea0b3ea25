"""Small measurements and figures of notebook 05 (stereo front end), kept out of its story cells.

The figures draw what the notebook computed; nothing they draw is computed here.
"""

from __future__ import annotations

import math

import matplotlib.pyplot as plt
import numpy as np

from vo_book.plotting import new_axes
from vo_lib.geometry import camera_motion, planar_to_matrix
from vo_lib.stereo_vo.circular_motion import apply_motion, circular_motion_from_transform
from vo_lib.stereo_vo.temporal import MotionPrior, match_temporal

#: Disparity errors beyond this many pixels are drawn in the histogram's end bins.
DISPARITY_CLIP_PX = 1.5
#: The end of the diagonal drawn over matched against true disparity, px.
DIAGONAL_END_PX = 50


def cells_covered(points: np.ndarray, cell: int = 80) -> int:
    """Number of ``cell``-pixel grid cells that hold at least one of the image ``points`` (u, v)."""
    return len(np.unique((points[:, 0] // cell).astype(int) * 10 + (points[:, 1] // cell).astype(int)))


def matching_rows(drive, renderer, front, camera, mount, rng) -> dict[str, np.ndarray]:
    """Section 5 on one drive (planar poses ``drive``, the images' noise drawn from ``rng``): for
    each pair of consecutive frames and each matcher (guided, by a prediction off by 0.1° and
    5 mm; brute force), a row of the matches, the share of them more than 3 px from where the
    true motion puts them, the pairs compared and the milliseconds."""
    frames = [front.process(*renderer.render_pair(planar_to_matrix(p) @ mount, rng)) for p in drive]
    rows = {"guided": [], "brute force": []}
    for k in range(1, len(frames)):
        theta, rho = circular_motion_from_transform(camera_motion(drive[k - 1], drive[k], mount))
        prior = MotionPrior(
            theta + math.radians(0.1), rho + 0.005, np.diag([math.radians(0.3) ** 2, 0.01**2])
        )
        for name, predicted in (("guided", prior), ("brute force", None)):
            mt = match_temporal(frames[k - 1], frames[k], camera, predicted)
            moved = camera.project(apply_motion(camera.backproject(mt.w_prev), theta, rho))
            wrong = np.linalg.norm(moved[:, :2] - mt.w_curr[:, :2], axis=1) > 3.0
            rows[name].append((len(mt), wrong.mean(), mt.candidates, mt.timings["temporal_match"]))
    return {name: np.array(r) for name, r in rows.items()}


def plot_epipolar_lines(lines: dict[str, np.ndarray], probe: np.ndarray, width: int, height: int) -> None:
    """One panel per rig ``{name: (N, 3) lines}``: each probe pixel of the left image (a cross at
    ``probe``'s (u, v)) and its epipolar line a u′ + b v′ + c = 0 across the right image."""
    _, axes = new_axes(2, width=5.2, height=3.6)
    us = np.array([0, width - 1])
    for ax, (name, rig_lines) in zip(axes, lines.items(), strict=True):
        for (a, b, c), x in zip(rig_lines, probe, strict=True):
            ax.plot(us, -(a * us + c) / b, lw=1)
            ax.plot(*x[:2], "k+")
        ax.set_xlim(0, width - 1)
        ax.set_ylim(height - 1, 0)
        ax.set_title(f"epipolar lines, {name}", fontsize="small")
        ax.set_xlabel("u′ [px]")
    axes[0].set_ylabel("v′ [px] (+: the left pixel)")
    plt.show()


def plot_depth_error(
    zs: np.ndarray,
    disparity: np.ndarray,
    sigma_z: np.ndarray,
    depths: np.ndarray,
    measured_sd: np.ndarray,
    sigma_d: float,
) -> None:
    """Disparity against depth ``zs``, and the depth error the first-order formula gives
    (``sigma_z``, log-log) beside its Monte Carlo at ``depths`` (``measured_sd``), for a
    disparity noise of ``sigma_d`` px."""
    _, axes = new_axes(2, width=5.2, height=3.4)
    axes[0].plot(zs, disparity)
    axes[0].set_xlabel("depth Z [m]")
    axes[0].set_ylabel("disparity d [px]")
    axes[0].set_title("d = f_x B / Z", fontsize="small")
    axes[1].loglog(zs, sigma_z, label="Z² σ_d / (f_x B)")
    axes[1].loglog(depths, measured_sd, "o", label="Monte Carlo")
    axes[1].set_xlabel("depth Z [m]")
    axes[1].set_ylabel("σ_Z [m]")
    axes[1].set_title(f"depth error for σ_d = {sigma_d} px", fontsize="small")
    axes[1].legend(fontsize="small")
    plt.show()


def plot_corner_sets(image: np.ndarray, points: np.ndarray, selections: dict[str, np.ndarray]) -> None:
    """One panel per selection ``{title: indices}`` of the corners ``points`` (u, v), each drawn
    as a cross over ``image``."""
    _, axes = new_axes(len(selections), width=6, height=4.4)
    for ax, (title, sel) in zip(axes, selections.items(), strict=True):
        ax.imshow(image, cmap="gray")
        ax.plot(points[sel, 0], points[sel, 1], "+", color="C1", ms=4)
        ax.set_title(title)
        ax.axis("off")
    plt.show()


def plot_hamming(same: np.ndarray, unrelated: np.ndarray, ceiling: int) -> None:
    """Histograms of the Hamming distances of the same corner seen left and right (``same``) and
    of unrelated corners, with the matcher's ``ceiling`` dashed."""
    _, ax = new_axes(width=6, height=3.4)
    ax.hist(same, bins=40, range=(0, 256), alpha=0.7, label="same corner (true disparity), left vs right")
    ax.hist(unrelated, bins=40, range=(0, 256), alpha=0.7, label="unrelated corners")
    ax.axvline(ceiling, color="k", lw=1, ls="--", label=f"our ceiling ({ceiling})")
    ax.set_xlabel("Hamming distance [bits of 256]")
    ax.legend(fontsize="small")
    plt.show()


def plot_disparity_errors(
    truth: np.ndarray, matched: np.ndarray, err_integer: np.ndarray, err_subpixel: np.ndarray
) -> None:
    """Matched against true disparity for every stereo match, and the histograms of the
    disparity errors of the integer and the sub-pixel disparities (clipped to ±1.5 px)."""
    _, axes = new_axes(2, width=5.5, height=3.8)
    axes[0].plot(truth, matched, ".", ms=3)
    axes[0].plot([0, DIAGONAL_END_PX], [0, DIAGONAL_END_PX], "k", lw=0.8)
    axes[0].set_xlabel("true disparity [px]")
    axes[0].set_ylabel("matched disparity [px]")
    axes[0].set_title(f"{len(matched)} stereo matches")
    clip = DISPARITY_CLIP_PX
    axes[1].hist(np.clip(err_integer, -clip, clip), bins=60, alpha=0.6, label="integer")
    axes[1].hist(np.clip(err_subpixel, -clip, clip), bins=60, alpha=0.6, label="sub-pixel")
    axes[1].set_xlabel("disparity error [px]")
    axes[1].legend(fontsize="small")
    plt.show()
