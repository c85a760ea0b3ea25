"""Notebook 01's seed study, kept out of its story: section 5's Monte Carlo drawn again."""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from vo_lib.models.track_odometry import TrackOdometry


def dead_reckoning_seeds(
    odo: TrackOdometry,
    u: np.ndarray,
    runs: int,
    steps: int,
    models: tuple[np.ndarray, np.ndarray],
    seeds: Iterable[int],
) -> dict[str, np.ndarray]:
    """Section 5's Monte Carlo (``runs`` noisy drives of ``steps`` equal controls ``u``) once per
    seed, against the section's two covariances after the last step, ``models`` = (full
    Jacobians, eq. 9's F = I): ``relative``, the Frobenius distance of the full one from the
    cloud's over the cloud's size; ``spread``, the cloud's lateral σ over the one F = I gives."""
    P_full, P_eq9 = models
    sd = odo.encoder_sigma * np.sqrt(np.abs(u))
    relative, spread = [], []
    for seed in seeds:
        rng = np.random.default_rng(seed)
        samples = np.zeros((runs, 3))
        for _ in range(steps):
            samples = odo.predict(samples, u + rng.normal(size=(runs, 2)) * sd)
        cloud = np.cov(samples.T)
        relative.append(np.linalg.norm(P_full - cloud) / np.linalg.norm(cloud))
        spread.append(np.sqrt(cloud[1, 1] / P_eq9[1, 1]))
    return {"relative": np.array(relative), "spread": np.array(spread)}
