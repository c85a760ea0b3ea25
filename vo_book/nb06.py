"""Tables and figures of notebook 06 (1-point RANSAC), kept out of its story cells.

Nothing here estimates anything: the functions print or draw figures the notebook computed.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

import numpy as np

from vo_book.plotting import new_axes
from vo_lib.comparison import Comparison


def print_ladder(theta: Comparison, rho: Comparison) -> None:
    """One row per estimator: median and 90th percentile of |θ error| (radians in, degrees out),
    and the median relative ρ error, over the seeds of the two comparisons."""
    print(f" {'':28s}{'median |θ err| [deg]':>21s}{'90th pct':>10s}{'median ρ err':>14s}   seeds")
    for name in theta.figures:
        t_deg = np.degrees(theta.figures[name])
        print(
            f" {name:28s}{np.median(t_deg):21.4f}{np.percentile(t_deg, 90):10.4f}"
            f"{np.median(rho.figures[name]):14.2%}{len(theta):8d}"
        )


def median_time(fn: Callable[[], object], repeats: int = 15) -> float:
    """Median wall time of ``fn()`` over ``repeats`` calls, milliseconds."""
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return 1e3 * float(np.median(times))


def plot_hypotheses(theta_each: np.ndarray, inliers: np.ndarray, theta_true_deg: float) -> None:
    """Histogram of the θ each match proposes, inliers and outliers apart."""
    import matplotlib.pyplot as plt

    _, ax = new_axes(width=6.5, height=3.4)
    bins = np.linspace(-10, 15, 120)
    ax.hist(np.clip(np.degrees(theta_each[inliers]), -10, 15), bins=bins, alpha=0.7, label="inliers")
    ax.hist(np.clip(np.degrees(theta_each[~inliers]), -10, 15), bins=bins, alpha=0.7, label="outliers")
    ax.axvline(theta_true_deg, color="k", lw=1)
    ax.set_xlabel("θ proposed by one match [deg]")
    ax.set_ylabel("matches")
    ax.set_title(f"One hypothesis per match (true θ = {theta_true_deg:g}°)")
    ax.legend(fontsize="small")
    plt.show()


def plot_gate_spread(raw: np.ndarray, normalised: np.ndarray) -> None:
    """The raw θ gate of true matches (log scale) beside the gate over each match's own σ, with
    the half-normal density it should follow."""
    import matplotlib.pyplot as plt

    _, axes = new_axes(2, width=5.2, height=3.4)
    axes[0].hist(np.log10(raw), bins=50)
    axes[0].set_xlabel("log10 error_θ of true matches")
    axes[0].set_ylabel("matches")
    axes[0].set_title("The raw θ gate")
    axes[1].hist(np.clip(normalised, 0, 5), bins=50, density=True, label="true matches")
    zs = np.linspace(0, 5, 200)
    axes[1].plot(zs, 2 * np.exp(-0.5 * zs**2) / math.sqrt(2 * math.pi), "C1", label="half-normal")
    axes[1].set_xlabel("error_θ / its own σ")
    axes[1].set_ylabel("density")
    axes[1].set_title("Normalised by each match's σ")
    axes[1].legend(fontsize="small")
    plt.show()


def plot_trial(
    errors_deg: list[float], outlier_ratio: float, noise_px: float, hits: int, median_ms: float
) -> None:
    """Histogram of one trial's |θ errors| with its success count and median time in the title."""
    import matplotlib.pyplot as plt

    _, ax = new_axes(width=5.5, height=3.2)
    ax.hist(errors_deg, bins=20)
    ax.set_xlabel("|θ error| [deg]")
    ax.set_ylabel("match sets")
    ax.set_title(
        f"{outlier_ratio:.0%} outliers, {noise_px} px: {hits}/{len(errors_deg)} within 0.05° "
        f"and 5 %, {median_ms:.2f} ms"
    )
    plt.show()


def said(comparison: Comparison, a: str, b: str, unit: str = "", scale: float = 1.0, digits: int = 2) -> str:
    """:meth:`Comparison.sentence`, or, when ``a`` and ``b`` gave the same figure in every seed,
    a sentence that says so (no interval to report)."""
    if np.all(comparison.paired(a, b) == 0):
        return f"{a} changes nothing against {b}: the same figure in all {len(comparison)} seeds"
    return comparison.sentence(a, b, unit=unit, scale=scale, digits=digits)


def plot_row_errors(row_px: np.ndarray, error_deg: np.ndarray) -> None:
    """|θ error| of each true match's own θ against its distance from the principal row."""
    import matplotlib.pyplot as plt

    _, ax = new_axes(width=6.5, height=3.2)
    ax.semilogy(row_px, error_deg, ".", ms=2, alpha=0.4)
    ax.set_xlabel("distance of the match from the principal row [px]")
    ax.set_ylabel("|θ of one true match − θ| [deg]")
    ax.set_title("A true match's own θ: useless near the camera's height")
    plt.show()


def print_nees(
    rows: dict[str, tuple[float, float, float, float]], band: tuple[float, float], sets: int
) -> None:
    """One row per variance: mean z², its seed interval, the χ² band and the share with |z| > 3."""
    print(f" variance of θ̂            mean z² (95 % seed CI)    χ²(1) band, mean of {sets}  |z| > 3")
    for name, (mean, low, high, miss) in rows.items():
        print(f" {name:26s}{mean:9.2f} ({low:.2f}–{high:.2f}){'':8s}{band[0]:.2f}–{band[1]:.2f}{miss:18.0%}")


def side_of_band(mean: float, low: float, high: float, band: tuple[float, float]) -> str:
    """Where a mean z² and its seed interval ``low``-``high`` lie against the χ² band, in words: a
    side only when the whole interval is beyond the band."""
    if low > band[1]:
        return f"above the band, over-confident by a factor of about {mean:.1f} in variance"
    if high < band[0]:
        return "below the band, under-confident"
    if band[0] <= low and high <= band[1]:
        return "inside the band"
    return "at the band's edge (its interval overlaps the band)"
