"""Notebook 01's seed study, kept out of its story: section 5's Monte Carlo drawn again."""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from vo_lib.models.track_odometry import TrackOdometry


def dead_reckoning_seeds(
    odo: TrackOdometry, u: np.ndarray, runs: int, steps: int, seeds: Iterable[int]
) -> dict[str, np.ndarray]:
    """Section 5's Monte Carlo (``runs`` noisy drives of ``steps`` equal controls ``u``) once per
    seed: ``relative``, the Frobenius distance of the full Jacobians' covariance from the cloud's
    after the last step over the cloud's size; ``spread``, the cloud's lateral σ over the one eq. 9
    (F = I) gives."""
    mean, P_full, P_eq9 = np.zeros(3), np.zeros((3, 3)), np.zeros((3, 3))
    for _ in range(steps):  # the two covariance models: no draws
        _, F_u = odo.jacobians(mean, u)
        P_eq9 = P_eq9 + F_u @ odo.control_covariance(u) @ F_u.T
        mean, P_full = odo.propagate(mean, P_full, u)
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
