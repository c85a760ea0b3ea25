"""Demonstration scaffolding of notebook 06 (1-point RANSAC), kept out of its story cells.

Match sets with a real front end's kinds of outliers, and the interactive trial of the library's
1-point RANSAC. The estimator itself is :mod:`vo_lib.stereo_vo.ransac`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

import numpy as np

from vo_book.nb06 import plot_trial
from vo_lib.camera import StereoCamera
from vo_lib.stereo_vo.ransac import hypothesis_draws, one_point_ransac
from vo_lib.stereo_vo.synthetic import synthetic_matches

#: The notebook's base seed; the trial's match sets are drawn from seeds beside it.
SEED = 6
camera = StereoCamera.bumblebee2()
#: Shares of all matches that are random pixels, near misses and points on a moving object.
RANDOM_SHARE, NEAR_MISS_SHARE, MOVER_SHARE = 0.10, 0.15, 0.15
#: A near miss moves its current point by 2-8 px along its row; the moving object slides 6 px.
NEAR_MISS_PX, MOVER_PX = (2.0, 8.0), 6.0


def realistic_matches(n, theta, rho, rng, noise_px=0.5):
    """n matches of (θ, ρ) with random, near-miss and moving-object outliers: (w_prev, w_curr, inliers)."""
    s = synthetic_matches(camera, n, theta, rho, rng, noise_px=noise_px, outlier_ratio=RANDOM_SHARE)
    w_curr, inliers = s.w_curr.copy(), s.inliers.copy()
    good = np.flatnonzero(inliers)
    near = rng.choice(good, int(NEAR_MISS_SHARE * n), replace=False)
    w_curr[near, 0] += rng.choice([-1.0, 1.0], len(near)) * rng.uniform(*NEAR_MISS_PX, len(near))
    rest = np.setdiff1d(good, near)
    mover = rest[np.argsort(s.w_prev[rest, 0])[: int(MOVER_SHARE * n)]]  # the left of the view
    w_curr[mover, 0] += MOVER_PX
    inliers[near] = inliers[mover] = False
    return s.w_prev, w_curr, inliers


def ransac_trial(outlier_ratio=0.4, noise_px=0.5):
    """Success rate and median time of 1-point RANSAC over 20 seeded match sets."""
    hits, times, errs = 0, [], []
    for seed in range(SEED + 500, SEED + 520):
        t_rng = np.random.default_rng(seed)
        th, rh = math.radians(t_rng.uniform(-5, 5)), t_rng.uniform(0.03, 0.12)
        mm = synthetic_matches(camera, 300, th, rh, t_rng, noise_px=noise_px, outlier_ratio=outlier_ratio)
        t0 = time.perf_counter()
        est = one_point_ransac(mm.w_prev, mm.w_curr, camera, rng=t_rng, pixel_sigma=max(noise_px, 0.1))
        times.append((time.perf_counter() - t0) * 1e3)
        errs.append(math.degrees(abs(est.theta - th)))
        hits += est.success and errs[-1] < 0.05 and abs(est.rho - rh) < 0.05 * rh
    plot_trial(errs, outlier_ratio, noise_px, hits, float(np.median(times)))
    return hits / 20


def draws_to_first_good(
    candidates: np.ndarray, good: np.ndarray, rng: np.random.Generator, repeats: int = 2000
) -> float:
    """Mean number of uniform draws from ``candidates`` until one is a good hypothesis (``good``
    marks the matches that give one), over ``repeats`` trials."""
    picks = rng.integers(0, len(candidates), (repeats, 200))
    hit = good[candidates][picks]
    return float(np.mean(np.argmax(hit, axis=1) + 1))


def adaptive_run(
    seed: int, theta_phase: Callable, pool_fraction: float, tried: dict[bool, list]
) -> dict[str, float]:
    """|θ error| of the θ phase with a fixed batch and with adaptive N_h on one set of 80 % outliers.

    ``theta_phase(w_prev, w_curr, draws, pool_fraction, adaptive)`` is the notebook's θ phase,
    returning (θ, hypotheses tried); the counts are appended to ``tried[adaptive]``.
    """
    r = np.random.default_rng(seed)
    th, rh = math.radians(r.uniform(-5, 5)), r.uniform(0.03, 0.12)
    s80 = synthetic_matches(camera, 300, th, rh, r, noise_px=0.5, outlier_ratio=0.8)
    out = {}
    for adaptive, name in ((True, "adaptive N_h"), (False, "a fixed batch")):
        draws_k = hypothesis_draws(seed)
        est, count = theta_phase(s80.w_prev, s80.w_curr, draws_k, pool_fraction, adaptive)
        tried[adaptive].append(count)
        out[name] = abs(est - th)
    return out
