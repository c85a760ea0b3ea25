"""Trajectory errors: ATE, RPE, KITTI segment errors, and the statistics [Zhao] reports.

Poses are ``(N, 4, 4)`` (or ``(N, 3, 4)``) camera-to-world matrices, estimate and ground truth
frame by frame, or planar ``(x, y, yaw)`` rows for the planar variants. ATE: position errors after
Umeyama's least-squares alignment. RPE: motions over ``delta`` frames compared,
``E_i = (Q_i^-1 Q_{i+d})^-1 (P_i^-1 P_{i+d})``. KITTI: segments of given path lengths, translation
in per cent and rotation in degrees per metre. Key positions ([Zhao], IV): mean and standard
deviation of the x, y and heading errors at chosen frames. Timestamps are associated as evo does.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

import numpy as np
from scipy.spatial.transform import Rotation

from vo_lib.geometry import as_homogeneous, rigid_inverse, wrap_angle


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
        figures = (np.sqrt(np.mean(e**2)), e.mean(), np.median(e), e.std(), e.max())
        return cls(*(float(x) for x in figures), int(e.size))


def rotation_angle(R) -> np.ndarray:
    """Angle in radians of rotation matrices ``(..., 3, 3)``, as SciPy's ``2 atan2(|q_xyz|, |q_w|)``:
    stable near 0, where ``arccos((trace R - 1) / 2)`` loses half the digits."""
    return Rotation.from_matrix(R).magnitude()


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
    spread = float(np.mean(np.sum(xs**2, axis=1)))
    s = 1.0
    if with_scale:  # no scale unless both move: NaN, not a division by zero or a collapse onto one point
        s = float(np.trace(np.diag(d) @ S) / spread) if spread > 0 and xt.any() else float("nan")
    return R, mu_t - s * R @ mu_s, s


def _pair(gt, est) -> tuple[np.ndarray, np.ndarray]:
    """Ground truth and estimate as ``(N, 4, 4)`` matrices, checked to match."""
    gt, est = as_homogeneous(gt), as_homogeneous(est)
    for T in (gt, est):
        if T.ndim != 3 or T.shape[1:] != (4, 4):
            raise ValueError(f"poses must have shape (N, 3, 4) or (N, 4, 4); got {T.shape}")
    return _check_pair(gt, est)


def _check_pair(gt, est):
    """``(gt, est)`` as given, once they hold as many poses, at least two."""
    gt, est = np.asarray(gt, float), np.asarray(est, float)
    if len(gt) != len(est):
        raise ValueError(f"ground truth has {len(gt)} poses but the estimate has {len(est)}; expected equal")
    if len(gt) < 2:
        raise ValueError("at least two poses are needed")
    return gt, est


class Alignment(str, Enum):
    """How an estimate is aligned to the truth before its absolute errors are taken."""

    NONE = "none"  #: both start in the same frame
    SE3 = "SE(3)"  #: rotation and translation (a trajectory whose scale is observable: stereo)
    SIM3 = "Sim(3)"  #: rotation, translation and scale: the shape alone

    def __str__(self) -> str:
        return self.value


def _ate(p_gt: np.ndarray, p_est: np.ndarray, alignment: Alignment) -> tuple[ErrorStats, np.ndarray]:
    """Position errors ``(N, 2)`` or ``(N, 3)`` after Umeyama's least-squares ``alignment`` of the
    estimate onto the truth (Umeyama 1991, eq. 40-42; evo's ``align``/``correct_scale``)."""
    if alignment is not Alignment.NONE:
        R, t, s = umeyama(p_est, p_gt, with_scale=alignment is Alignment.SIM3)
        p_est = s * p_est @ R.T + t
    errors = np.linalg.norm(p_est - p_gt, axis=1)
    return ErrorStats.of(errors), errors


def ate(gt, est, alignment: Alignment = Alignment.SE3) -> tuple[ErrorStats, np.ndarray]:
    """Absolute trajectory error of positions after an ``alignment`` (SE(3) by default);
    ``(stats, per-pose errors)``, as evo's APE of the translation part."""
    G, E = _pair(gt, est)
    return _ate(G[:, :3, 3], E[:, :3, 3], alignment)


def carried_point(poses: np.ndarray, point) -> np.ndarray:
    """``(N, 3)`` positions of ``point`` (in the posed frame: a prism on the camera) along ``poses``."""
    return poses[:, :3, :3] @ np.asarray(point, float) + poses[:, :3, 3]


def ate_positions(
    positions, est, lever_arm=(0.0, 0.0, 0.0), alignment: Alignment = Alignment.SE3
) -> tuple[ErrorStats, np.ndarray]:
    """ATE against position-only truth ``(N, 3)`` (a tracked prism, an antenna) in its own frame:
    the point ``lever_arm`` (in the estimate's camera frame) is carried along the estimated poses
    and aligned to the positions."""
    p_gt, E = _check_pair(positions, as_homogeneous(est))
    return _ate(p_gt, carried_point(E, lever_arm), alignment)


def ate_planar(gt_planar, est_planar, align: bool = True) -> tuple[ErrorStats, np.ndarray]:
    """ATE of planar ``(x, y, yaw)`` trajectories after a rotation and translation in the plane."""
    g, e = _check_pair(gt_planar, est_planar)
    return _ate(g[:, :2], e[:, :2], Alignment.SE3 if align else Alignment.NONE)


def rpe(gt, est, delta: int = 1, rotation: bool = False) -> tuple[ErrorStats, np.ndarray]:
    """Relative pose error over ``delta`` frames: translation norm (m) or rotation angle (deg), of
    pairs starting every ``delta`` frames (0-d, d-2d, ...), as evo counts them by default."""
    G, E = _pair(gt, est)
    if not 1 <= delta < len(G):
        raise ValueError(f"delta must lie in 1..{len(G) - 1}; got {delta}")
    first = np.arange(0, len(G) - delta, delta)
    rel_gt, rel_est = (rigid_inverse(T[first]) @ T[first + delta] for T in (G, E))
    err = rigid_inverse(rel_gt) @ rel_est
    errors = np.degrees(rotation_angle(err[:, :3, :3])) if rotation else np.linalg.norm(err[:, :3, 3], axis=1)
    return ErrorStats.of(errors), errors


def path_length(xyz) -> float:
    """Length of the path through positions ``(N, 3)``."""
    return float(np.linalg.norm(np.diff(np.asarray(xyz, float), axis=0), axis=1).sum())


def path_lengths(poses) -> np.ndarray:
    """Cumulative distance travelled at each pose."""
    p = as_homogeneous(poses)[:, :3, 3]
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])


#: A drive turns on the spot when its mean turning radius (metres per radian) is below this and it
#: turns by more than SPOT_TURN_MIN_DEGREES: position errors then say little, heading errors all.
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
    tight = planar_path_length(poses_planar) < SPOT_TURN_MAX_RADIUS * np.radians(turned)
    return tight and turned > SPOT_TURN_MIN_DEGREES


@dataclass(frozen=True)
class FinalError:
    """Where a planar drive ends against where it truly ends; the distance is the truth's path."""

    position_m: float
    percent: float  # of the distance travelled; NaN if the truth does not move
    heading_deg: float
    distance_m: float


def final_error(truth_planar, est_planar) -> FinalError:
    """Final position (metres, per cent of the truth's planar path) and heading (degrees, wrapped)
    errors of planar trajectories ``(N, 3)``."""
    g, e = _check_pair(truth_planar, est_planar)
    distance = planar_path_length(g)
    position = float(np.hypot(*(e[-1, :2] - g[-1, :2])))
    heading = float(np.degrees(np.abs(wrap_angle(e[-1, 2] - g[-1, 2]))))
    percent = 100.0 * position / distance if distance > 0 else float("nan")
    return FinalError(position, percent, heading, distance)


@dataclass(frozen=True)
class FinalError3D:
    """Where the estimate ends against the truth, in 3-D from the same start, and both path lengths."""

    position_m: float
    percent: float  # of the distance travelled; NaN if the truth does not move
    rotation_deg: float
    distance_m: float
    estimate_distance_m: float


def final_error_3d(gt, est) -> FinalError3D:
    """Final 3-D position and rotation errors of camera poses ``(N, 4, 4)``, each trajectory in
    the frame of its first pose (no alignment: what a run that starts at the truth ends with)."""
    G, E = _pair(gt, est)
    G, E = rigid_inverse(G[0]) @ G, rigid_inverse(E[0]) @ E
    distance = float(path_lengths(G)[-1])
    position = float(np.linalg.norm(E[-1, :3, 3] - G[-1, :3, 3]))
    rotation = float(np.degrees(rotation_angle(G[-1, :3, :3].T @ E[-1, :3, :3])))
    percent = 100.0 * position / distance if distance > 0 else float("nan")
    return FinalError3D(position, percent, rotation, distance, float(path_lengths(E)[-1]))


#: The KITTI odometry benchmark's segment lengths (metres) and the frames between segment starts.
KITTI_LENGTHS = (100.0, 200.0, 300.0, 400.0, 500.0, 600.0, 700.0, 800.0)
KITTI_STEP = 10
#: A sequence shorter than KITTI's segments is scored over these fractions of its path instead.
SHORT_FRACTIONS = (0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8)


@dataclass(frozen=True)
class KittiErrors:
    """The KITTI benchmark's figures: translation error in per cent and rotation error in degrees
    per 100 m, averaged over every segment of the ``lengths`` (metres) that start every
    :data:`KITTI_STEP` frames; ``count`` segments in all."""

    translation_pct: float
    rotation_deg_per_100m: float
    lengths: tuple[float, ...]
    count: int

    def label(self) -> str:
        """The lengths, as a table prints them: ``100-800 m`` or ``0.33, 0.66, ... m``."""
        text = ", ".join(f"{x:.3g}" for x in self.lengths)
        return f"{text} m" if len(self.lengths) < 4 else f"{self.lengths[0]:.3g}-{self.lengths[-1]:.3g} m"


def segment_lengths(gt) -> tuple[float, ...]:
    """KITTI's lengths that fit in the truth's path; for a shorter path, its
    :data:`SHORT_FRACTIONS` rounded to two significant digits."""
    total = float(path_lengths(gt)[-1])
    fits = tuple(x for x in KITTI_LENGTHS if x < total)
    return fits or tuple(float(f"{f * total:.2g}") for f in SHORT_FRACTIONS if f * total > 0)


def segment_pairs(gt, length: float, step: int = KITTI_STEP) -> np.ndarray:
    """``(first, last)`` frames of the segments of ``length`` metres, as KITTI's devkit picks them:
    a start every ``step`` frames, the end at the first frame at least ``length`` further along;
    shape ``(n, 2)``, in order, stopping at the first start whose segment runs past the end."""
    dist = path_lengths(gt)
    first = np.arange(0, len(dist), step)
    last = np.searchsorted(dist, dist[first] + length)
    past = np.flatnonzero(last >= len(dist))
    n = past[0] if len(past) else len(first)
    return np.column_stack([first[:n], last[:n]]).astype(int)


def segment_errors(G: np.ndarray, E: np.ndarray, length: float, step: int = KITTI_STEP) -> np.ndarray:
    """The KITTI odometry benchmark's error of every segment of ``length`` metres (Geiger et al.
    2012; the devkit's ``calcSequenceErrors``): ``E = (P_i^-1 P_j)^-1 (Q_i^-1 Q_j)``, as rows of
    translation ``|t(E)| / length`` and rotation ``angle(E) / length`` (degrees per metre)."""
    first, last = segment_pairs(G, length, step).T
    err = rigid_inverse(rigid_inverse(E[first]) @ E[last]) @ (rigid_inverse(G[first]) @ G[last])
    translation = np.linalg.norm(err[:, :3, 3], axis=-1) / length
    return np.column_stack([translation, np.degrees(rotation_angle(err[:, :3, :3])) / length])


def kitti_errors(gt, est, lengths=None) -> KittiErrors | None:
    """The KITTI benchmark's translation (%) and rotation (deg/100 m) errors, averaged over every
    segment of every length (:func:`segment_errors`); ``lengths`` default to
    :func:`segment_lengths`. None where no segment fits."""
    G, E = _pair(gt, est)
    lengths = tuple(float(x) for x in (segment_lengths(G) if lengths is None else lengths))
    errors = np.concatenate([np.zeros((0, 2))] + [segment_errors(G, E, length) for length in lengths])
    if not len(errors):
        return None
    t_err, r_err = 100.0 * errors.mean(axis=0)
    return KittiErrors(float(t_err), float(r_err), lengths, len(errors))


def kitti_segment_errors(gt, est, lengths=KITTI_LENGTHS, step: int = KITTI_STEP) -> dict:
    """:func:`segment_errors` per length: ``{length: (translation %, rotation deg/m, count)}``;
    lengths where no segment fits are left out (short sequences: pass e.g. 1, 2, 5 m)."""
    G, E = _pair(gt, est)
    out = {}
    for length in lengths:
        errors = segment_errors(G, E, length, step)
        if len(errors):
            out[length] = (100.0 * float(errors[:, 0].mean()), float(errors[:, 1].mean()), len(errors))
    return out


def key_position_errors(gt_planar, est_planar, frames) -> dict:
    """[Zhao]'s statistics: mean and standard deviation of x, y (mm) and heading (deg) errors at
    the key ``frames``, estimate minus truth, in the frame of the start."""
    idx = np.asarray(frames, dtype=int)
    d = np.asarray(est_planar, float)[idx] - np.asarray(gt_planar, float)[idx]
    errors = {"x_mm": 1000 * d[:, 0], "y_mm": 1000 * d[:, 1], "theta_deg": np.degrees(wrap_angle(d[:, 2]))}
    return {name: (float(np.mean(v)), float(np.std(v))) for name, v in errors.items()}


def shown(value: float, spec: str) -> str:
    """``value`` as ``spec`` formats it, or "undefined" (the percentage of a truth that does not
    move, the scale of an alignment when either trajectory stands still)."""
    return format(value, spec) if np.isfinite(value) else "undefined"


@dataclass(frozen=True)
class StandardErrors:
    """The field's errors of a 6-DoF estimate against 6-DoF truth, every one in 3-D."""

    final: FinalError3D
    ate_se3: ErrorStats  #: metres, after an SE(3) alignment
    ate_sim3: ErrorStats  #: metres, after a Sim(3) alignment
    sim3_scale: float  #: the scale the Sim(3) alignment applied to the estimate
    rpe_m: ErrorStats  #: 1 frame, translation (metres)
    rpe_deg: ErrorStats  #: 1 frame, rotation (degrees)
    kitti: KittiErrors | None

    def rows(self) -> list[tuple[str, str]]:
        """``(label, value)`` rows as the run's table and ``evaluate`` print them."""
        f = self.final
        distances = f"{f.distance_m:.3f} / {f.estimate_distance_m:.3f}"
        sim3 = f"ATE (Sim(3) alignment, scale {shown(self.sim3_scale, '.4f')}): rmse [m]"
        rows = [
            ("final position error, 3-D [m]", f"{f.position_m:.4f}"),
            ("  of distance travelled [%]", shown(f.percent, ".2f")),
            ("final rotation error, 3-D [deg]", f"{f.rotation_deg:.3f}"),
            ("distance travelled, 3-D, truth / estimate [m]", distances),
            ("ATE (SE(3) alignment): rmse [m]", f"{self.ate_se3.rmse:.4f}"),
            (sim3, shown(self.ate_sim3.rmse, ".4f")),
            ("RPE RMSE, 1 frame: translation [m]", f"{self.rpe_m.rmse:.5f}"),
            ("RPE RMSE, 1 frame: rotation [deg]", f"{self.rpe_deg.rmse:.4f}"),
        ]
        k = self.kitti
        if k is None:
            rows.append(("KITTI segment errors", "no segment fits"))
        else:
            where = f"{k.label()}, {k.count} segment{'s' * (k.count != 1)}"
            rows.append((f"KITTI translation ({where}) [%]", f"{k.translation_pct:.3f}"))
            rows.append((f"KITTI rotation ({where}) [deg/100 m]", f"{k.rotation_deg_per_100m:.3f}"))
        return rows


def standard_errors(gt, est, lengths=None) -> StandardErrors:
    """Every 3-D error of :class:`StandardErrors` of camera poses ``est`` against ``gt``."""
    G, E = _pair(gt, est)
    _, _, scale = umeyama(E[:, :3, 3], G[:, :3, 3], with_scale=True)
    return StandardErrors(
        final_error_3d(G, E),
        ate(G, E)[0],
        ate(G, E, alignment=Alignment.SIM3)[0],
        float(scale),
        rpe(G, E)[0],
        rpe(G, E, rotation=True)[0],
        kitti_errors(G, E, lengths),
    )


#: Largest time difference (s) at which a ground-truth sample is associated with an image: evo's
#: default ``max_diff``.
MAX_TIME_DIFF_S = 0.01


def associate(query_times, truth_times, max_diff: float = MAX_TIME_DIFF_S) -> tuple[np.ndarray, np.ndarray]:
    """Indices ``(i_query, i_truth)`` of the pairs whose times differ by at most ``max_diff``
    seconds, each query time taking its nearest truth time, as evo's ``associate_trajectories``."""
    q, t = np.asarray(query_times, float), np.asarray(truth_times, float)
    right = np.clip(np.searchsorted(t, q), 1, len(t) - 1) if len(t) > 1 else np.zeros(len(q), int)
    left = np.maximum(right - 1, 0)
    nearest = np.where(np.abs(t[left] - q) <= np.abs(t[right] - q), left, right)
    keep = np.abs(t[nearest] - q) <= max_diff
    return np.flatnonzero(keep), nearest[keep]


def to_camera(poses, T_body_camera) -> np.ndarray:
    """Poses of a body frame in the world ``(N, 4, 4)`` made poses of a camera fixed on it,
    relative to the camera's first pose: ``C_k = (W_0 X)^-1 W_k X`` with ``X = T_body_camera``."""
    C = np.asarray(poses, float) @ np.asarray(T_body_camera, float)
    return np.linalg.inv(C[0]) @ C
