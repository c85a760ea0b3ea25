"""EKF-SLAM with one feature point per line landmark ([Yan 2020], eq. 1-13): bicycle prediction,
updates, Mahalanobis data association and state augmentation.

The state ``X = [x_v, y_v, phi, x_1, y_1, ..., x_N, y_N]`` (eq. 1-3) holds the vehicle pose and
one feature point per line landmark, and grows as landmarks are found. A wall is observed through
its feature point's range and bearing (``range_bearing.POINT``, eq. 10, the paper's filter) or as
the line seen from the robot (``line_observation.LINE``). Eq. 13's ``V`` is taken as the
innovation covariance ``S = H P H^T + R``: the paper calls it "the variance caused by the
observation", but the difference between a mapped and an observed feature point is also
uncertain through the pose and the map.
"""

from __future__ import annotations

import numpy as np

from vo_lib.geometry import wrap_angle
from vo_lib.line_slam.range_bearing import POINT
from vo_lib.models.bicycle import bicycle_jacobians, bicycle_step

#: Associate when the squared Mahalanobis distance (eq. 13) is below the chi-square 99 % point
#: for 2 degrees of freedom; add a new landmark only when it exceeds 25 (p < 4e-6). Between the
#: two an observation is ambiguous and is dropped.
GATE_ASSOCIATE = 9.21
GATE_AUGMENT = 25.0
#: Euclidean association (the comparison of notebook 09): same landmark within this many metres.
GATE_EUCLIDEAN = 2.0

NEW = -1
DROPPED = -2


class EkfSlam:
    """Extended Kalman filter over the vehicle pose and the landmarks' feature points.

    Parameters
    ----------
    pose : (3,) array_like
        Initial pose ``(x, y, phi)``; it defines the map frame and is known exactly unless
        ``pose_cov`` says otherwise.
    control_cov : (2, 2) array_like
        Covariance ``Q`` of the measured speed and steering angle.
    observation_cov : (2, 2) array_like
        Covariance ``R`` of a range-bearing observation.
    period : float
        Control period ``T``, seconds.
    wheelbase : float
        ``L``, metres.
    pose_cov : (3, 3) array_like, optional
    model : observation model, optional
        ``range_bearing.POINT`` (default) or ``line_observation.LINE``; ``observation_cov`` is the
        default covariance of one observation, which :meth:`observe` may override per observation.
    """

    def __init__(self, pose, control_cov, observation_cov, period, wheelbase, pose_cov=None, model=POINT):
        self.x = np.asarray(pose, dtype=float).copy()
        self.P = np.zeros((3, 3)) if pose_cov is None else np.asarray(pose_cov, dtype=float).copy()
        self.Q = np.asarray(control_cov, dtype=float)
        self.R = np.asarray(observation_cov, dtype=float)
        self.period = float(period)
        self.wheelbase = float(wheelbase)
        self.model = model

    # ------------------------------------------------------------------ state access
    @property
    def pose(self) -> np.ndarray:
        return self.x[:3]

    @property
    def pose_cov(self) -> np.ndarray:
        return self.P[:3, :3]

    @property
    def n_landmarks(self) -> int:
        return (self.x.size - 3) // 2

    def landmark(self, j: int) -> np.ndarray:
        return self.x[3 + 2 * j : 5 + 2 * j]

    def landmark_cov(self, j: int) -> np.ndarray:
        k = 3 + 2 * j
        return self.P[k : k + 2, k : k + 2]

    # ------------------------------------------------------------------ prediction, eq. 4-7
    def predict(self, speed: float, steer: float) -> None:
        """Move the pose by eq. 5 with the measured controls; only the pose rows of ``P`` change.

        ``P_vv <- F_x P_vv F_x^T + F_u Q F_u^T`` and ``P_vm <- F_x P_vm`` (landmarks are static).
        """
        f_x, f_u = bicycle_jacobians(self.x[:3], speed, steer, self.period, self.wheelbase)
        self.x[:3] = bicycle_step(self.x[:3], speed, steer, self.period, self.wheelbase)
        P = self.P
        P[:3, :3] = f_x @ P[:3, :3] @ f_x.T + f_u @ self.Q @ f_u.T
        if P.shape[0] > 3:
            P[:3, 3:] = f_x @ P[:3, 3:]
            P[3:, :3] = P[:3, 3:].T

    # ------------------------------------------------------------------ observation, eq. 8-12
    def _innovation(self, z, j: int, R=None):
        """Innovation, its Jacobian rows (2 x 5), their state indices, ``S = H P H^T + R`` and the
        observation's covariance ``R`` (aligned with the prediction) for landmark ``j``."""
        k = 3 + 2 * j
        point = self.x[k : k + 2]
        predicted = self.model.predict(self.x[:3], point)
        z, R = self.model.align(z, self.R if R is None else np.asarray(R, dtype=float), predicted)
        h_pose, h_point = self.model.jacobians(self.x[:3], point)
        nu = z - predicted
        nu[1] = wrap_angle(nu[1])
        # Only five columns of H are non-zero: use the matching blocks of P.
        idx = np.r_[0:3, k : k + 2]
        h_small = np.hstack([h_pose, h_point])
        S = h_small @ self.P[np.ix_(idx, idx)] @ h_small.T + R
        return nu, h_small, idx, S, R

    def mahalanobis(self, z, R=None) -> np.ndarray:
        """Squared Mahalanobis distance (eq. 13) of observation ``z`` to every landmark:
        ``D^2 = nu^T S^-1 nu`` with ``S`` the innovation covariance."""
        innovations = (self._innovation(z, j, R) for j in range(self.n_landmarks))
        return np.array([nu @ np.linalg.solve(S, nu) for nu, _, _, S, _ in innovations], dtype=float)

    def euclidean(self, z) -> np.ndarray:
        """Plain distance, in metres, from the observed feature point (placed with the estimated
        pose) to every landmark's: the association [Yan 2020] argues against."""
        point, _, _ = self.model.invert(self.x[:3], z)
        marks = self.x[3:].reshape(-1, 2)
        return np.hypot(marks[:, 0] - point[0], marks[:, 1] - point[1])

    def associate(self, observations, method: str = "mahalanobis", covariances=None) -> list[int]:
        """For each observation: a landmark index, :data:`NEW` or :data:`DROPPED`."""
        if method not in ("mahalanobis", "euclidean"):
            raise ValueError(f"method must be 'mahalanobis' or 'euclidean'; got {method!r}")
        covariances = covariances if covariances is not None else [None] * len(observations)
        out = []
        for z, R in zip(observations, covariances, strict=True):
            if self.n_landmarks == 0:
                out.append(NEW)
                continue
            if method == "mahalanobis":
                dist = self.mahalanobis(z, R)
                near, far = GATE_ASSOCIATE, GATE_AUGMENT
            else:
                dist = self.euclidean(z)
                near = far = GATE_EUCLIDEAN
            j = int(np.argmin(dist))
            out.append(j if dist[j] < near else NEW if dist[j] > far else DROPPED)
        return out

    def update(self, observations, indices, covariances=None) -> None:
        """EKF update with every observation associated to a known landmark, all at once."""
        covariances = covariances if covariances is not None else [None] * len(observations)
        triples = [(z, j, c) for z, j, c in zip(observations, indices, covariances, strict=True) if j >= 0]
        if not triples:
            return
        n = self.x.size
        H = np.zeros((2 * len(triples), n))
        nu = np.empty(2 * len(triples))
        R = np.zeros((2 * len(triples), 2 * len(triples)))
        for i, (z, j, c) in enumerate(triples):
            rows = slice(2 * i, 2 * i + 2)
            nu[rows], h_small, idx, _, R[rows, rows] = self._innovation(z, j, c)
            H[rows, idx] = h_small
        PHt = self.P @ H.T
        S = H @ PHt + R
        K = np.linalg.solve(S, PHt.T).T
        self.x = self.x + K @ nu
        self.x[2] = wrap_angle(self.x[2])
        # Joseph form: stays symmetric and positive semi-definite despite rounding.
        I_KH = np.eye(n) - K @ H
        self.P = I_KH @ self.P @ I_KH.T + K @ R @ K.T

    def augment(self, z, R=None) -> int:
        """Add the landmark seen at ``z``; its covariance follows from the inverse observation
        model: ``P_mm = G_v P_vv G_v^T + G_z R G_z^T``, ``P_mX = G_v P_vX``."""
        R = self.R if R is None else np.asarray(R, dtype=float)
        point, g_pose, g_z = self.model.invert(self.x[:3], z)
        cross = g_pose @ self.P[:3, :]
        P_mm = g_pose @ self.P[:3, :3] @ g_pose.T + g_z @ R @ g_z.T
        self.x = np.concatenate([self.x, point])
        self.P = np.block([[self.P, cross.T], [cross, P_mm]])
        return self.n_landmarks - 1

    def observe(self, observations, method: str = "mahalanobis", covariances=None) -> list[int]:
        """Associate, update with the known landmarks, then add the new ones; returns the
        landmark index of each observation (new ones included) or :data:`DROPPED`.
        ``covariances`` (one 2x2 per observation) default to the filter's ``R``."""
        covariances = covariances if covariances is not None else [None] * len(observations)
        indices = self.associate(observations, method, covariances)
        self.update(observations, indices, covariances)
        for i, (z, j, c) in enumerate(zip(observations, indices, covariances, strict=True)):
            if j == NEW:
                indices[i] = self.augment(z, c)
        return indices

    def pose_nees(self, true_pose) -> float:
        """Normalised estimation error squared of the pose, heading error wrapped."""
        e = np.asarray(true_pose, dtype=float) - self.x[:3]
        e[2] = wrap_angle(e[2])
        return float(e @ np.linalg.solve(self.P[:3, :3], e))


def diagonal_cov(*sigmas: float) -> np.ndarray:
    """Covariance of independent noises: ``Q`` of the measured speed and steering angle, ``R`` of a
    range-bearing sensor."""
    return np.diag([sigma**2 for sigma in sigmas])
