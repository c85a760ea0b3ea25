"""Is the fused filter consistent? Monte Carlo runs drawn from exactly the noise it assumes.

One run of :func:`monte_carlo_run` drives the crawler along a gentle S, draws the start, the
measured controls and the VO increments from the filter's own covariances, and records the pose
NEES and the VO update's NIS at every step; ``python -m vo_lib sweep nees`` runs one per seed.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.stats import chi2

from vo_lib.comparison import chi2_band
from vo_lib.models.track_odometry import TrackOdometry
from vo_lib.stereo_vo.kalman import VoKalmanFilter, measurement, nis

#: VO noise of the runs: deflection angle θ (rad²) and chord ρ (m²).
R_VO = np.diag([math.radians(0.05) ** 2, 0.002**2])
#: Initial pose covariance: x, y (m²) and heading (rad²).
P0 = np.diag([0.01**2, 0.01**2, math.radians(0.5) ** 2])


def monte_carlo_run(seed: int, steps: int = 150) -> tuple[np.ndarray, np.ndarray]:
    """Pose NEES and VO NIS at each of ``steps`` steps of one run drawn with ``seed``: χ²(3) and
    χ²(2) for a consistent filter ([Zhao], eq. 1-11)."""
    r = np.random.default_rng(seed)
    odometry = TrackOdometry()
    f = VoKalmanFilter(odometry, covariance=P0)
    x_true = f.pose + r.multivariate_normal(np.zeros(3), P0)
    nees, nis_values = np.zeros(steps), np.zeros(steps)
    for k in range(steps):
        u_true = odometry.controls_for(0.02 + 0.01 * math.sin(k / 20), math.radians(1.0) * math.sin(k / 30))
        u_meas = u_true + r.multivariate_normal(np.zeros(2), f.control_covariance(u_true))
        x_prev, x_true = x_true, odometry.predict(x_true, u_true)
        f.predict(u_meas)
        z = measurement(np.concatenate([x_true, x_prev])) + r.multivariate_normal(np.zeros(2), R_VO)
        f.update(z[0], z[1], R_VO)
        nis_values[k] = nis(f.ekf.y[:2], f.ekf.S[:2, :2])
        f.finish_frame()
        nees[k] = f.nees(x_true)
    return nees, nis_values


def nees_figures(seed: int) -> dict[str, float]:
    """One run's mean and final pose NEES and share of steps inside χ²(3)'s 95 % interval (a task
    of ``sweep nees``)."""
    nees, _ = monte_carlo_run(seed)
    low, high = chi2.ppf([0.025, 0.975], 3)
    return {
        "nees_mean": float(nees.mean()),
        "nees_final": float(nees[-1]),
        "inside_95": float(np.mean((nees > low) & (nees < high))),
    }


def nees_report(table, stats) -> None:
    """What ``sweep nees`` prints below its summary: the mean NEES beside a consistent band."""
    low, high = chi2_band(3, len(table))
    mean = stats.loc["nees_mean", "mean"]
    print(
        f"NEES averaged over {len(table)} run{'s' * (len(table) != 1)}: {mean:.3f}; "
        f"consistent runs give {low:.3f}-{high:.3f} (95 %)"
    )
