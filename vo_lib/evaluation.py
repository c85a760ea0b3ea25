"""Trajectory errors: ATE, RPE, KITTI segment errors, and the statistics [Zhao] reports.

Poses are ``(N, 4, 4)`` camera-to-world matrices (or ``(N, 3, 4)``), estimate and ground truth
frame by frame, or planar ``(x, y, yaw)`` rows for the planar variants.

* **ATE** (absolute trajectory error): align the estimated positions to the true ones with the
  least-squares rigid motion (Umeyama), then take the position differences.
* **RPE** (relative pose error): compare motions over ``delta`` frames,
  ``E_i = (Q_i^-1 Q_{i+d})^-1 (P_i^-1 P_{i+d})``, by their translation (or rotation angle).
* **KITTI segment errors**: for segments of given path lengths starting every ``step`` frames,
  translation error in percent of the length and rotation error in degrees per metre.
* **Key-position statistics** ([Zhao], IV): mean and standard deviation of the x, y and
  heading errors at chosen frames.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vo_lib.geometry import as_homogeneous, wrap_angle


@dataclass(frozen=True)
class ErrorStats:
    """Summary of a set of errors (metres or degrees)."""

    rmse: float
    mean: float
    median: float
    std: float
    max: float
    count: int

    @classmethod
    def of(cls, errors) -> ErrorStats:
        e = np.asarray(errors, dtype=float)
        if e.size == 0:
            nan = float("nan")
            return cls(nan, nan, nan, nan, nan, 0)
        return cls(
            float(np.sqrt(np.mean(e**2))),
            float(e.mean()),
            float(np.median(e)),
            float(e.std()),
            float(e.max()),
            int(e.size),
        )


def rotation_angle(R) -> np.ndarray:
    """Angle in radians of rotation matrices ``(..., 3, 3)``, stable at every angle.

    ``theta = atan2(|vee(R - R^T)| / 2, (trace R - 1) / 2)``: the sine from the skew part, the
    cosine from the trace (Rodrigues' formula, ``R = I + sin(theta) [k]x + (1 - cos(theta)) [k]x^2``).
    ``arccos((trace R - 1) / 2)`` alone loses half the digits near 0: a rounding of ``1e-9`` in a
    written rotation becomes an angle of ``4e-5`` rad. Here a symmetric error (rounding, a matrix
    not quite orthonormal) leaves the sine untouched and moves the cosine only to second order.
    """
    R = np.asarray(R, dtype=float)
    skew = np.stack(
        [R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0], R[..., 1, 0] - R[..., 0, 1]], axis=-1
    )
    sin = 0.5 * np.linalg.norm(skew, axis=-1)
    cos = 0.5 * (np.trace(R, axis1=-2, axis2=-1) - 1.0)
    return np.arctan2(sin, cos)


def umeyama(source: np.ndarray, target: np.ndarray, with_scale: bool = False):
    """Least-squares ``(R, t, s)`` with ``target ~ s R source + t`` (Umeyama 1991), any dimension."""
    mu_s, mu_t = source.mean(axis=0), target.mean(axis=0)
    xs, xt = source - mu_s, target - mu_t
    cov = xt.T @ xs / len(source)
    U, d, Vt = np.linalg.svd(cov)
    S = np.eye(source.shape[1])
    if np.linalg.det(U) * np.linalg.det(Vt) < 0:
        S[-1, -1] = -1.0
    R = U @ S @ Vt
    s = float(np.trace(np.diag(d) @ S) / np.mean(np.sum(xs**2, axis=1))) if with_scale else 1.0
    return R, mu_t - s * R @ mu_s, s


def _pair(gt, est) -> tuple[np.ndarray, np.ndarray]:
    """Ground truth and estimate as ``(N, 4, 4)`` matrices, checked to match."""
    gt, est = as_homogeneous(gt), as_homogeneous(est)
    for T in (gt, est):
        if T.ndim != 3 or T.shape[1:] != (4, 4):
            raise ValueError(f"poses must have shape (N, 3, 4) or (N, 4, 4); got {T.shape}")
    _check_pair(gt, est)
    return gt, est


def _check_pair(gt, est):
    if len(gt) != len(est):
        raise ValueError(f"ground truth has {len(gt)} poses but the estimate has {len(est)}; expected equal")
    if len(gt) < 2:
        raise ValueError("at least two poses are needed")


def ate(gt, est, align: bool = True) -> tuple[ErrorStats, np.ndarray]:
    """Absolute trajectory error of positions after SE(3) alignment; ``(stats, per-pose errors)``."""
    G, E = _pair(gt, est)
    p_gt, p_est = G[:, :3, 3], E[:, :3, 3]
    if align:
        R, t, _ = umeyama(p_est, p_gt)
        p_est = p_est @ R.T + t
    errors = np.linalg.norm(p_est - p_gt, axis=1)
    return ErrorStats.of(errors), errors


def ate_planar(gt_planar, est_planar, align: bool = True) -> tuple[ErrorStats, np.ndarray]:
    """ATE of planar ``(x, y, yaw)`` trajectories after a rotation and translation in the plane."""
    g, e = np.asarray(gt_planar, float), np.asarray(est_planar, float)
    _check_pair(g, e)
    p_est = e[:, :2]
    if align:
        R, t, _ = umeyama(p_est, g[:, :2])
        p_est = p_est @ R.T + t
    errors = np.linalg.norm(p_est - g[:, :2], axis=1)
    return ErrorStats.of(errors), errors


def rpe(
    gt, est, delta: int = 1, rotation: bool = False, all_pairs: bool = False
) -> tuple[ErrorStats, np.ndarray]:
    """Relative pose error over ``delta`` frames: translation norm (m) or rotation angle (deg).

    Pairs start every ``delta`` frames (0-d, d-2d, ...), as evo counts them by default; with
    ``all_pairs`` every frame starts one.
    """
    G, E = _pair(gt, est)
    if not 1 <= delta < len(G):
        raise ValueError(f"delta must lie in 1..{len(G) - 1}; got {delta}")
    first = np.arange(0, len(G) - delta, 1 if all_pairs else delta)
    rel_gt = np.linalg.inv(G[first]) @ G[first + delta]
    rel_est = np.linalg.inv(E[first]) @ E[first + delta]
    err = np.linalg.inv(rel_gt) @ rel_est
    if rotation:
        errors = np.degrees(rotation_angle(err[:, :3, :3]))
    else:
        errors = np.linalg.norm(err[:, :3, 3], axis=1)
    return ErrorStats.of(errors), errors


def path_lengths(poses) -> np.ndarray:
    """Cumulative distance travelled at each pose."""
    p = as_homogeneous(poses)[:, :3, 3]
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])


#: A drive counts as turning on the spot when its path is shorter than this many metres per radian
#: it turns (a mean turning radius below it: a skidding crawler's centre circles a few centimetres
#: about its turning centre) while it turns by more than SPOT_TURN_MIN_DEGREES: position errors
#: then say little, heading errors all.
SPOT_TURN_MAX_RADIUS = 0.1
SPOT_TURN_MIN_DEGREES = 45.0


def planar_path_length(poses_planar) -> float:
    """Length in metres of a planar path ``(K, 3)``: the sum of its steps in x and y."""
    p = np.asarray(poses_planar, float)
    return float(np.sum(np.hypot(*np.diff(p[:, :2], axis=0).T)))


def turned_degrees(poses_planar) -> float:
    """Total heading change in degrees, counting every turn, left and right: ``sum |d yaw|``."""
    yaw = np.asarray(poses_planar, float)[:, 2]
    return float(np.degrees(np.sum(np.abs(wrap_angle(np.diff(yaw))))))


def is_spot_turn(poses_planar) -> bool:
    """Does the path turn on the spot (see ``SPOT_TURN_MAX_RADIUS``, ``SPOT_TURN_MIN_DEGREES``)?"""
    turned = turned_degrees(poses_planar)
    return (
        planar_path_length(poses_planar) < SPOT_TURN_MAX_RADIUS * np.radians(turned)
        and turned > SPOT_TURN_MIN_DEGREES
    )


@dataclass(frozen=True)
class FinalError:
    """Where a drive ends against where it truly ends: the one final error every command and
    test reports. Planar vehicle poses ``(x, y, yaw)``; the distance is the truth's planar path."""

    position_m: float
    percent: float  # of the distance travelled; NaN if the truth does not move
    heading_deg: float
    distance_m: float


def final_error(truth_planar, est_planar) -> FinalError:
    """Final position error (metres, and per cent of the planar distance the truth travels) and
    final heading error (degrees, wrapped) of planar trajectories ``(N, 3)``."""
    g, e = np.asarray(truth_planar, float), np.asarray(est_planar, float)
    _check_pair(g, e)
    distance = planar_path_length(g)
    position = float(np.hypot(*(e[-1, :2] - g[-1, :2])))
    heading = float(np.degrees(np.abs(wrap_angle(e[-1, 2] - g[-1, 2]))))
    percent = 100.0 * position / distance if distance > 0 else float("nan")
    return FinalError(position, percent, heading, distance)


def kitti_segment_errors(gt, est, lengths=(100, 200, 300, 400, 500, 600, 700, 800), step: int = 10) -> dict:
    """KITTI odometry errors per segment length: ``{length: (translation %, rotation deg/m, count)}``.

    Short sequences have no long segments; pass lengths that fit (e.g. 1, 2, 5 m).
    """
    G, E = _pair(gt, est)
    dist = path_lengths(G)
    out = {}
    for length in lengths:
        t_err, r_err = [], []
        for first in range(0, len(G), step):
            last = int(np.searchsorted(dist, dist[first] + length))
            if last >= len(G):
                break
            rel_gt = np.linalg.inv(G[first]) @ G[last]
            rel_est = np.linalg.inv(E[first]) @ E[last]
            err = np.linalg.inv(rel_est) @ rel_gt
            t_err.append(np.linalg.norm(err[:3, 3]) / length)
            r_err.append(np.degrees(rotation_angle(err[:3, :3])) / length)
        if t_err:
            out[length] = (100.0 * float(np.mean(t_err)), float(np.mean(r_err)), len(t_err))
    return out


def key_position_errors(gt_planar, est_planar, frames) -> dict:
    """[Zhao]'s statistics: mean and standard deviation of x, y (mm) and heading (deg) errors at
    the key ``frames``, estimate minus truth, in the frame of the start."""
    g, e = np.asarray(gt_planar, float), np.asarray(est_planar, float)
    idx = np.asarray(frames, dtype=int)
    dx, dy = 1000 * (e[idx, 0] - g[idx, 0]), 1000 * (e[idx, 1] - g[idx, 1])
    dth = np.degrees(wrap_angle(e[idx, 2] - g[idx, 2]))
    return {
        name: (float(np.mean(v)), float(np.std(v)))
        for name, v in (("x_mm", dx), ("y_mm", dy), ("theta_deg", dth))
    }
