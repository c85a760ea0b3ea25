"""Laser-based pose tracking (LBPT) and its visual-odometry-assisted form (VOAPT), [Yuan]
section III.

LBPT: sample poses around the odometry's prediction ``P_odom``, score each against the likelihood
field (eq. 8-10), take the best. VOAPT judges the scores (``D_s``, ``R_s``, ``C_s``, eq. 11-13)
and the corrections (control limits, eq. 14-15) into the credibility ``T_s`` (eq. 16); when not
credible, it replaces the laser's correction along the direction of largest error (PCA of the
best quarter of the samples, eq. 17-20) by the visual odometer's (eq. 21-23).

Readings of garbled printed forms (docs/errata.md, notebook 10):

* eq. 11: ``D_s = V_max - V_med``, as its name "range-median difference" says (printed
  ``V_max - V_lq - V_med``).
* eq. 12 as printed is at least 1 for any sample set (the paper's threshold 0.7 never fails); we
  keep it and calibrate its threshold.
* eq. 14 swaps two names; with eq. 15 and Table II: ``UCL = mu + 3 sigma``, ``CL = mu``,
  ``LCL = max(0, mu - 3 sigma)``.
* eq. 16 joins the limit tests with "or", which never flags a jump of the laser pose while the
  visual correction is normal: we require ``C_s`` and both. The visual odometer's pose is carried
  from the last credible update and both limits widen with the square root of the updates since.
* eq. 22: the corrected displacement moves only along ``v_s``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from vo_lib.geometry import compose_planar, wrap_angle

#: Samples per update and their spread in the robot frame (odometry errs most along the travel).
DEFAULT_SAMPLES = 500
SAMPLE_SIGMA = (0.10, 0.03, math.radians(0.5))
#: Heading gate of eq. 18: the top-quartile samples' RMS heading difference to the best.
THETA_LIMIT = math.radians(1.0)


def posterior(scores) -> np.ndarray:
    """Eq. 8-10: the samples' posterior probabilities ``exp(S_i) / sum_j exp(S_j)``, a score
    (bounded, so an unmapped obstacle cannot veto a pose) read as a log-likelihood."""
    s = np.asarray(scores, dtype=float)
    p = np.exp(s - s.max())
    return p / p.sum()


@dataclass(frozen=True)
class ScoreStatistics:
    """Box-plot values of the normalised scores (eq. 10, scaled to mean 1) and their indicators."""

    v_max: float
    v_uq: float
    v_med: float
    v_lq: float
    v_min: float

    @classmethod
    def from_scores(cls, scores) -> ScoreStatistics:
        """From the samples' raw scores (sums of the likelihood field)."""
        s = posterior(scores) * len(scores)  # eq. 10, times n: the mean is 1 whatever n is
        v_min, v_lq, v_med, v_uq, v_max = np.percentile(s, [0, 25, 50, 75, 100])
        return cls(float(v_max), float(v_uq), float(v_med), float(v_lq), float(v_min))

    @property
    def d_s(self) -> float:
        """Range-median difference (eq. 11, as read above): ``V_max - V_med``."""
        return self.v_max - self.v_med

    @property
    def d_s_printed(self) -> float:
        """Eq. 11 as printed: ``V_max - V_lq - V_med``."""
        return self.v_max - self.v_lq - self.v_med

    @property
    def r_s(self) -> float:
        """Range-quantile ratio (eq. 12): ``(V_max - V_lq) / (V_uq - V_lq)``."""
        return (self.v_max - self.v_lq) / max(self.v_uq - self.v_lq, 1e-12)


@dataclass(frozen=True)
class Thresholds:
    """``V_th1, V_th2, V_th3`` of eq. 13 on our normalised scores."""

    v_max: float
    d_s: float
    r_s: float

    def composite(self, stats: ScoreStatistics) -> bool:
        """``C_s`` (eq. 13): all three indicators at or above their thresholds."""
        return stats.v_max >= self.v_max and stats.d_s >= self.d_s and stats.r_s >= self.r_s


@dataclass(frozen=True)
class ControlLimits:
    """Shewhart limits of a correction's length (eq. 14-15)."""

    mean: float
    std: float

    @classmethod
    def from_corrections(cls, lengths) -> ControlLimits:
        lengths = np.asarray(lengths, dtype=float)
        if lengths.size < 2:
            raise ValueError(f"control limits need at least 2 corrections; got {lengths.size}")
        return cls(float(lengths.mean()), float(lengths.std(ddof=1)))

    @property
    def upper(self) -> float:
        return self.mean + 3 * self.std

    @property
    def centre(self) -> float:
        return self.mean

    @property
    def lower(self) -> float:
        return max(0.0, self.mean - 3 * self.std)

    def contains(self, value: float, updates: int = 1) -> bool:
        """Within the limits, widened by ``sqrt(updates)`` for a correction accumulated over as
        many independent updates."""
        half = 3 * self.std * math.sqrt(updates)
        return max(0.0, self.mean - half) <= value <= self.mean + half


@dataclass(frozen=True)
class Calibration:
    """What a normal run teaches VOAPT: thresholds and the two corrections' control limits."""

    thresholds: Thresholds
    laser: ControlLimits
    vo: ControlLimits


def sample_poses(prediction, n: int, rng: np.random.Generator):
    """``n`` poses around ``prediction`` (the first is the prediction itself)."""
    noise = rng.standard_normal((n, 3)) * SAMPLE_SIGMA
    noise[0] = 0.0
    return compose_planar(prediction, noise)


def principal_error_direction(corrections, scores):
    """Eq. 17-20: the unit eigenvector of the largest eigenvalue of the covariance of the
    top-quartile samples' translational corrections, or ``None`` when their headings spread more
    than :data:`THETA_LIMIT` around the best sample's (eq. 18)."""
    corrections = np.asarray(corrections, dtype=float)
    scores = np.asarray(scores, dtype=float)
    top = corrections[scores >= np.percentile(scores, 75)]  # eq. 17 (scores or posteriors: same order)
    best = corrections[np.argmax(scores)]
    if np.mean(wrap_angle(best[2] - top[:, 2]) ** 2) > THETA_LIMIT**2:  # eq. 18
        return None
    centred = top[:, :2] - top[:, :2].mean(axis=0)  # eq. 19
    values, vectors = np.linalg.eigh(centred.T @ centred / len(centred))  # eq. 20
    v = vectors[:, np.argmax(values)]
    return v if v[np.argmax(np.abs(v))] > 0 else -v  # a fixed sign, for plots and tests


def compensate(t_best, direction, t_vo) -> np.ndarray:
    """Eq. 21-22: keep the laser's correction across ``direction`` and take the visual
    odometer's along it: ``T' = T_best + (v . T_vo - v . T_best) v``."""
    t_best, v, t_vo = (np.asarray(a, dtype=float) for a in (t_best, direction, t_vo))
    return t_best + (v @ t_vo - v @ t_best) * v


@dataclass
class TrackingStep:
    """What one update saw and did (for plots and statistics)."""

    stats: ScoreStatistics
    c_s: bool
    laser_correction: float
    vo_correction: float
    laser_ok: bool
    vo_ok: bool
    credible: bool
    compensated: bool
    direction: np.ndarray | None


class PoseTracker:
    """LBPT, and VOAPT when given a calibration (``compensate_errors=False``: LBPT judged by
    ``T_s``). The visual odometer's pose is the last credible one carried by the visual increments."""

    def __init__(self, field, start, calibration: Calibration | None, compensate_errors: bool, rng):
        self.field = field
        self.pose = np.asarray(start, dtype=float).copy()
        self.vo_pose = self.pose.copy()
        self.updates_since_credible = 0
        self.calibration = calibration
        self.compensate_errors = compensate_errors
        self.rng = rng

    def update(self, odometry_increment, scan_points, vo_increment=None) -> TrackingStep:
        """One update: predict with the odometry, score samples, judge, correct (eq. 8-23)."""
        p_odom = compose_planar(self.pose, odometry_increment)
        samples = sample_poses(p_odom, DEFAULT_SAMPLES, self.rng)
        scores = self.field.score(samples, scan_points)
        stats = ScoreStatistics.from_scores(scores)
        corrections = samples - p_odom
        corrections[:, 2] = wrap_angle(corrections[:, 2])
        best = corrections[np.argmax(scores)]
        if vo_increment is not None:
            self.vo_pose = compose_planar(self.vo_pose, vo_increment)
        self.updates_since_credible += 1
        t_vo = self.vo_pose[:2] - p_odom[:2]  # the visual odometer's correction to the odometer
        laser_len, vo_len = float(np.hypot(*best[:2])), float(np.hypot(*t_vo))
        cal = self.calibration
        c_s = cal.thresholds.composite(stats) if cal else True
        n = self.updates_since_credible
        laser_ok = cal is None or cal.laser.contains(laser_len, n)
        vo_ok = cal is None or cal.vo.contains(vo_len, n)
        # T_s (eq. 16, as read above): C_s holds and both corrections to the odometer are within limits
        ok = c_s and laser_ok and vo_ok
        direction = None
        correction = best.copy()
        compensated = not ok and self.compensate_errors and vo_increment is not None
        if compensated:
            direction = principal_error_direction(corrections, scores)
            if direction is not None:
                correction[:2] = compensate(best[:2], direction, t_vo)  # eq. 21-22
            else:
                correction[:2] = t_vo  # headings disagree: trust the visual displacement
        self.pose = p_odom + correction  # eq. 23
        self.pose[2] = wrap_angle(self.pose[2])
        if ok:
            self.vo_pose = self.pose.copy()
            self.updates_since_credible = 0
        return TrackingStep(stats, c_s, laser_len, vo_len, laser_ok, vo_ok, ok, compensated, direction)
