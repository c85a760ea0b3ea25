"""Small measurements and figures of notebook 03 (circular motion, numeric checks), kept out of
its story cells.

The figures draw what the notebook computed; nothing they draw is computed here. The scene
draws and the θ widget are :mod:`vo_book.demo_circular`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import matplotlib.pyplot as plt
import numpy as np

from vo_book.plotting import new_axes


def local_exponent(measured: np.ndarray, centres: np.ndarray, i: int) -> float:
    """p of σ ∝ |v − v₀|^−p between bins ``i`` and ``i + 1``: the slope of the measured σ against
    the bins' ``centres`` on log-log axes."""
    return float(-np.log(measured[i + 1] / measured[i]) / np.log(centres[i + 1] / centres[i]))


def plot_match_errors(theta: tuple, rho: tuple) -> None:
    """Section 2's per-match errors, log-log. ``theta = (row_offset, err_theta, centres, measured,
    model)``: each match's |θ error| (radians, drawn in degrees) against its |v − v₀|, with the
    measured spread and the first-order model per bin at the bins' ``centres``. ``rho = (depth,
    err_rho, depth_centres, measured, zz, model)``: each match's |ρ error| against its depth, the
    measured spread per depth bin, and the model √2 z² σ_d / (f B) at the depths ``zz``."""
    row_offset, err_theta, centres, measured, model = theta
    depth, err_rho, depth_centres, rho_measured, zz, rho_model = rho
    _, axes = new_axes(2, width=5.5, height=4)
    axes[0].loglog(row_offset, np.degrees(np.abs(err_theta)), ".", ms=1, alpha=0.3, color="0.5")
    axes[0].loglog(centres, np.degrees(measured), "o-", label="measured spread per bin")
    axes[0].loglog(centres, np.degrees(model), "s--", label="first-order model")
    axes[0].set_xlabel("|v − v₀| (mean of both views) [px]")
    axes[0].set_ylabel("|θ error| [deg]")
    axes[0].set_title("Per-match θ from eq. 14, 0.5 px noise")
    axes[0].legend(fontsize="small")
    axes[1].loglog(depth, np.abs(err_rho), ".", ms=1, alpha=0.3, color="0.5")
    axes[1].loglog(depth_centres, rho_measured, "o-", label="measured spread per bin")
    axes[1].loglog(zz, rho_model, "C1--", label="√2 z² σ_d / (f B)")
    axes[1].set_xlabel("depth [m]")
    axes[1].set_ylabel("|ρ error| [m]")
    axes[1].set_title("Per-match ρ from eq. 17, 0.5 px noise")
    axes[1].legend(fontsize="small")
    plt.show()


def plot_offset_share(
    depth_ranges: Sequence[tuple[float, float]],
    fraction: Mapping[tuple[float, float], float],
    predicted: Mapping[tuple[float, float], float],
) -> None:
    """Section 5's spot turn seen by a camera ahead of the axis: the median |θ error| / θ
    ``fraction[(a, near)]`` against a · median(1/z) ``predicted[(a, near)]``, in per cent, one
    marker per offset ``a`` and a point per scene depth range ``(near, far)``, beside the
    diagonal."""
    _, ax = new_axes(width=5.5, height=4)
    offsets = dict.fromkeys(a for a, _ in fraction)
    for a, marker in zip(offsets, ("o", "s"), strict=True):
        xs = [predicted[(a, near)] for near, _ in depth_ranges]
        ys = [fraction[(a, near)] for near, _ in depth_ranges]
        ax.loglog(np.array(xs) * 100, np.array(ys) * 100, marker, label=f"camera {a:.1f} m ahead")
        for (near, far), x_, y_ in zip(depth_ranges, xs, ys, strict=True):
            ax.annotate(f"{near:g}–{far:g} m", (x_ * 100, y_ * 100), fontsize="x-small")
    ax.loglog([0.2, 30], [0.2, 30], "k:", lw=0.8, label="equal")
    ax.set_xlabel("a · median(1/z) [%]")
    ax.set_ylabel("median |θ error| / θ [%]")
    ax.set_title("Spot turn, camera ahead of the axis: error share against scene depth")
    ax.legend(fontsize="small")
    plt.show()
