"""Demonstration scaffolding of notebook 10 (VO-assisted laser tracking), kept out of its story.

Score profiles and sample scores of the simulated corridor, the box statistics of eq. 11-13 on
any set of values, and the ROC area that compares them. The tracker itself is
:mod:`vo_lib.lidar_tracking.pose_tracking`.
"""

from __future__ import annotations

import numpy as np

from vo_lib.lidar_tracking.corridor_experiment import TIM551, statistics_table, unoccluded
from vo_lib.lidar_tracking.pose_tracking import sample_poses


def flat_positions(world_, field, offsets: np.ndarray) -> np.ndarray:
    """Positions (3-18 m) whose noise-free score profile along the corridor, over the pose
    ``offsets`` along it, varies by less than 0.5."""
    xs = np.arange(3.0, 18.0, 0.1)
    flat = []
    for x in xs:
        pts = TIM551.scan(world_.segments_array(), (x, 0.0, 0.0)).points()
        poses = np.column_stack([x + offsets, np.zeros_like(offsets), np.zeros_like(offsets)])
        flat.append(np.ptp(field.score(poses, pts)) < 0.5)
    return xs[np.array(flat)]


def scores_at(x: float, world_, field, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """500 sample poses around a scan taken at ``x`` on the corridor's axis, and their scores."""
    pose = np.array([x, 0.0, 0.0])
    pts = TIM551.scan(world_.segments_array(), pose, rng).points()
    samples = sample_poses(pose + (0.03, 0.0, 0.0), 500, rng)
    return samples, field.score(samples, pts)


def auc(positive, negative) -> float:
    """Probability that a random positive scores above a random negative (ties count half)."""
    positive, negative = np.asarray(positive), np.asarray(negative)
    return float(
        np.mean(positive[:, None] > negative[None, :]) + 0.5 * np.mean(positive[:, None] == negative[None, :])
    )


def corridor_scan(world_, field, rng: np.random.Generator) -> dict[str, list[np.ndarray]]:
    """The raw sample scores of scans at 120 places along the corridor (section 3), by kind:
    ``"normal"`` (an unoccluded stretch) and ``"occluded"`` (x 7-12.5 m); the others are scanned
    too, so that ``rng`` moves on the same way, and left out."""
    raws = {"normal": [], "occluded": []}
    for x in np.linspace(1.5, 27.5, 120):
        raw = scores_at(x, world_, field, rng)[1]
        if 7.0 <= x <= 12.5:
            raws["occluded"].append(raw)
        elif unoccluded(np.array([x]))[0]:
            raws["normal"].append(raw)
    return raws


def printed_eq11_auc(world_, field, seed: int) -> float:
    """The AUC of the printed eq. 11 on the raw scores of one :func:`corridor_scan` seeded by
    ``seed``: normal frames against the occluded stretch."""
    raws = corridor_scan(world_, field, np.random.default_rng(seed))
    normal, occluded = ([box_statistics(r)["d_s_printed"] for r in raws[k]] for k in ("normal", "occluded"))
    return auc(normal, occluded)


def box_statistics(values) -> dict[str, float]:
    """V_max, D_s (ours and printed, [Yuan] eq. 11) and R_s (eq. 12) of any set of sample values."""
    v_lq, v_med, v_uq, v_max = np.percentile(values, [25, 50, 75, 100])
    return {
        "v_max": v_max,
        "d_s": v_max - v_med,
        "d_s_printed": v_max - v_lq - v_med,
        "r_s": (v_max - v_lq) / max(v_uq - v_lq, 1e-12),
    }


def x_figure(run, statistic: str) -> float:
    """One statistic of a run's X errors, as Table III prints it."""
    return statistics_table(run.errors[:, 0])[statistic]


def rate_sentence(name: str, alarm: dict, nominal: dict) -> str:
    """A held-out false-alarm rate with its seed interval, against the nominal rate, in words."""
    mean_, low_, high_ = alarm[name]
    if low_ > nominal[name]:
        verdict_ = (
            f"above the nominal {nominal[name]:.2%}: {low_ / nominal[name]:.1f} to "
            f"{high_ / nominal[name]:.1f} times it, by the interval's ends"
        )
    elif high_ < nominal[name]:
        verdict_ = f"below the nominal {nominal[name]:.2%}"
    else:
        verdict_ = f"not reliably different from the nominal {nominal[name]:.2%}"
    return f"the {name}'s {mean_:.2%} (95 % CI over seeds {low_:.2%}–{high_:.2%}), {verdict_}"
