"""Kalman filter fusing crawler track odometry with visual odometry ([Zhao], eq. 1-11, III.A.2-4).

The state is the planar pose ``(x, y, yaw)``. Visual odometry measures the *relative* motion
between two frames, ``(theta, rho)`` of the circular-motion model, which depends on the current
pose and on the previous one. To update the current pose with it consistently, the filter keeps a
copy of the previous pose in the state while the frame is processed (stochastic cloning): a
6-dimensional state ``[pose_k, pose_k-1]`` whose cross-covariance records how the two are tied.

* **predict** clones the pose and moves the first copy with the track odometry (eq. 6-11, full
  Jacobians, encoder noise plus slip), or, without odometry, with the last motion repeated
  (constant velocity) and a wider process noise;
* **motion_prior** is the predicted ``(theta, rho)`` with its covariance, the prior that guides
  temporal matching and is scored by the 1-point RANSAC;
* **update** applies the VO measurement through filterpy's ``ExtendedKalmanFilter.update``
  (Joseph-form covariance update);
* a frame without a VO measurement keeps the prediction (covariance grows) and is flagged.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from filterpy.kalman import ExtendedKalmanFilter

from vo_lib.geometry import compose_planar, relative_planar, wrap_angle, yaw_matrix
from vo_lib.models.track_odometry import TrackOdometry
from vo_lib.stereo_vo.temporal import MotionPrior

#: Slip as a standard deviation per metre a track travels (on top of the encoder noise).
SLIP_SIGMA = 0.01
#: How far (metres) a motion may stray from the chord of the circular-motion model: skid and
#: model error of the crawler, observed as a zero pseudo-measurement in every VO update.
SIDEWAYS_SIGMA = 0.002
#: Constant-velocity process noise grows by this fraction of the last motion per frame...
CV_RELATIVE = 0.6
#: ...and the heading may change by this much per metre travelled (radians).
CV_TURN_PER_METRE = 0.15
#: Constant-velocity process noise per frame: (along, across, yaw) standard deviations. With the
#: two lines above, wide enough that the changes of a true motion from one frame to the next stay
#: within one standard deviation (RMS) on both development recordings down to a quarter of their
#: frame rates (the drone at 5 Hz turns the fastest: 0.77 sigma in yaw). A third of each of the
#: three left the drone's turns at 2.5 sigma, and the filter pulled each turn's first frames back
#: towards the last motion (docs/real_data.md).
CV_SIGMA = (0.03, 0.015, math.radians(0.9))


def constant_velocity_sigma(increment) -> np.ndarray:
    """Standard deviations ``(along, across, yaw)`` of the change of a frame's motion from the last
    one, ``increment`` = ``(dx, dy, dyaw)``: the floor, plus a fraction of each component (velocity
    changes scale with the velocity), plus a turn per metre travelled."""
    step = math.hypot(increment[0], increment[1])
    return np.asarray(CV_SIGMA) + CV_RELATIVE * np.array(
        [step, step, abs(increment[2]) + CV_TURN_PER_METRE * step]
    )


def constrained_measurement(state6: np.ndarray) -> np.ndarray:
    """``(theta, rho, sideways)``: the VO measurement and the deviation of the motion from its chord.

    The circular-motion model ([Zhao], eq. 15) puts the motion on the chord at ``theta / 2``; the
    third component measures how far the increment strays from it, and the update observes it as
    zero: the nonholonomic constraint of a crawler, which (theta, rho) alone leave unobserved.
    """
    return chord_measurement(relative_planar(state6[3:], state6[:3]))  # previous pose to current


def chord_measurement(increment) -> np.ndarray:
    """``(theta, rho, sideways)`` of a planar increment ``(dx, dy, dyaw)``: its yaw, its length
    along the chord at ``theta / 2`` (eq. 15) and its deviation across that chord."""
    dx, dy, theta = (float(v) for v in increment)
    sp, cp = math.sin(0.5 * theta), math.cos(0.5 * theta)
    return np.array([theta, dx * cp + dy * sp, -dx * sp + dy * cp])


def constrained_jacobian(state6: np.ndarray) -> np.ndarray:
    """Analytic 3x6 derivative of :func:`constrained_measurement`."""
    dx, dy, theta = relative_planar(state6[3:], state6[:3])
    sp, cp = math.sin(0.5 * theta), math.cos(0.5 * theta)
    a = float(state6[5]) + 0.5 * theta
    ca, sa = math.cos(a), math.sin(a)
    d_rho = 0.5 * (dy * cp - dx * sp)
    d_side = -0.5 * (dx * cp + dy * sp)
    return np.array(
        [
            [0.0, 0.0, 1.0, 0.0, 0.0, -1.0],
            [ca, sa, d_rho, -ca, -sa, d_rho],
            [-sa, ca, d_side, sa, -ca, d_side],
        ]
    )


def measurement(state6: np.ndarray) -> np.ndarray:
    """``(theta, rho)`` of the motion from the cloned previous pose to the current one."""
    return constrained_measurement(state6)[:2]


def _residual(z, hx):
    y = np.asarray(z, float) - hx
    y[0] = wrap_angle(y[0])
    return y


@dataclass
class StepFlags:
    """What the last frame used: ``odometry`` or constant velocity, and whether VO updated it."""

    odometry: bool = False
    vo_update: bool = False


class VoKalmanFilter:
    """Planar pose filter: track odometry (eq. 2-11, with its encoder noise) predicts, visual
    odometry corrects; the initial ``covariance`` is nearly certain by default.

    ``lateral_sigma`` is the sideways motion per metre travelled that the odometry cannot see, as
    process noise across the chord (0 for the crawler, whose tracks hold it on the chord; a car's
    odometry frame is aligned with its direction of travel only to a fraction of a degree).
    """

    def __init__(
        self,
        odometry: TrackOdometry | None = None,
        pose=(0.0, 0.0, 0.0),
        covariance=None,
        sideways_sigma: float = SIDEWAYS_SIGMA,
        lateral_sigma: float = 0.0,
    ):
        self.odometry = odometry or TrackOdometry()
        self.lateral_sigma = float(lateral_sigma)
        self.sideways_sigma = float(sideways_sigma)
        self.ekf = ExtendedKalmanFilter(dim_x=6, dim_z=3)  # (theta, rho, sideways), see update
        P = np.diag([1e-8, 1e-8, 1e-10]) if covariance is None else np.asarray(covariance, float)
        self.ekf.x = np.tile(np.asarray(pose, float), 2)
        self.ekf.P = np.block([[P, P], [P, P]])
        self.last_increment = np.zeros(3)
        self.flags = StepFlags()

    # ------------------------------------------------------------------ state
    @property
    def pose(self) -> np.ndarray:
        return self.ekf.x[:3].copy()

    @property
    def covariance(self) -> np.ndarray:
        return self.ekf.P[:3, :3].copy()

    @property
    def increment(self) -> np.ndarray:
        """``(dx, dy, dyaw)`` from the cloned reference pose to the current one, in its frame."""
        return relative_planar(self.ekf.x[3:], self.ekf.x[:3])

    def control_covariance(self, u) -> np.ndarray:
        """Encoder noise (random walk) plus slip, independent per track."""
        enc, slip = self.odometry.encoder_sigma**2, SLIP_SIGMA**2
        return np.diag([enc * abs(u[0]) + slip * u[0] ** 2, enc * abs(u[1]) + slip * u[1] ** 2])

    # ------------------------------------------------------------------ predict
    def predict(self, u=None, keep_reference: bool = False, steps: int = 1) -> None:
        """Clone the pose and move the clone's twin with odometry ``u`` (or constant velocity).

        With ``keep_reference`` the clone of an earlier frame is kept (it was not updated since):
        the current pose moves on, its cross-covariance with the reference is carried along, and
        the next VO measurement is the motion from that reference frame to the current one.
        Without odometry, ``steps`` frame intervals of constant velocity are predicted at once.
        """
        x, P = self.ekf.x[:3], self.ekf.P[:3, :3]
        ref = slice(3, 6) if keep_reference else slice(0, 3)  # the kept clone, or the pose cloned now
        if u is not None:
            u = np.asarray(u, float)
            x_new, F, G = self.odometry.step(x, u)  # eq. 6-11 and their full Jacobians (notebook 01)
            Q = G @ self.control_covariance(u) @ G.T
            if self.lateral_sigma > 0:
                across = np.array([-math.sin(x_new[2]), math.cos(x_new[2]), 0.0])
                Q = Q + (self.lateral_sigma * 0.5 * abs(u[0] + u[1])) ** 2 * np.outer(across, across)
        else:
            inc = total = self.last_increment
            for _ in range(steps - 1):  # the same increment, interval after interval
                total = compose_planar(total, inc)
            x_new = compose_planar(x, total)
            c, s = math.cos(x[2]), math.sin(x[2])
            F = np.array(
                [
                    [1.0, 0.0, -s * total[0] - c * total[1]],
                    [0.0, 1.0, c * total[0] - s * total[1]],
                    [0, 0, 1.0],
                ]
            )
            Rw = yaw_matrix(x[2])
            sigma = steps * constant_velocity_sigma(inc)  # a velocity that is off is off over every interval
            Q = Rw @ np.diag(sigma**2) @ Rw.T
        self.flags = StepFlags(odometry=u is not None)
        self.ekf.x = np.concatenate([x_new, self.ekf.x[ref]])
        P6 = np.empty((6, 6))  # filled block by block: np.block costs more than the filter's algebra
        P6[:3, :3] = F @ P @ F.T + Q
        P6[:3, 3:] = F @ self.ekf.P[:3, ref]  # the cross-covariance, carried along
        P6[3:, :3] = P6[:3, 3:].T
        P6[3:, 3:] = self.ekf.P[ref, ref]
        self.ekf.P = P6

    def predict_increment(self, increment) -> None:
        """Put the predicted pose at ``increment`` = ``(dx, dy, dyaw)`` from the reference clone,
        its covariance kept: a constant velocity that the motion model keeps better than the
        filter (from the last frame's measured motion rather than the reference's)."""
        self.ekf.x[:3] = compose_planar(self.ekf.x[3:], increment)

    def motion_prior(self) -> MotionPrior:
        """Predicted ``(theta, rho)`` of this frame and its covariance ``H P H^T``."""
        H = constrained_jacobian(self.ekf.x)[:2]
        z = measurement(self.ekf.x)
        return MotionPrior(float(z[0]), float(z[1]), H @ self.ekf.P @ H.T)

    # ------------------------------------------------------------------ update
    def update(self, theta: float, rho: float, covariance, sideways: float = 0.0) -> None:
        """Correct with a VO measurement ``(theta, rho)`` of the motion since the reference, and the
        circular-motion constraint that the motion lies on its chord (sideways deviation zero).

        A 3x3 ``covariance`` means the vision measured the sideways deviation too (6-DoF motion):
        then ``(theta, rho, sideways)`` is the measurement and the constraint is not applied.
        """
        covariance = np.asarray(covariance, float)
        if covariance.shape == (3, 3):
            R = covariance
        else:
            R = np.diag([0.0, 0.0, self.sideways_sigma**2])
            R[:2, :2] = covariance
        z = np.array([theta, rho, sideways])
        self.ekf.update(z, constrained_jacobian, constrained_measurement, R=R, residual=_residual)
        self.ekf.x[2] = wrap_angle(self.ekf.x[2])
        self.flags.vo_update = True

    def snapshot(self) -> tuple[np.ndarray, np.ndarray]:
        """A copy of the state and its covariance, for :meth:`restore`."""
        return self.ekf.x.copy(), self.ekf.P.copy()

    def restore(self, snapshot: tuple[np.ndarray, np.ndarray]) -> None:
        """Go back to a :meth:`snapshot` (an update that is not to be kept); the snapshot stays apart."""
        self.ekf.x, self.ekf.P = snapshot[0].copy(), snapshot[1].copy()

    def widen(self, sigma) -> None:
        """Add independent uncertainty ``sigma = (x, y, yaw)`` (standard deviations) to the pose."""
        self.ekf.P[:3, :3] += np.diag(sigma) ** 2

    def finish_frame(self, frames_since_reference: int = 1) -> None:
        """Remember the motion per frame (for constant velocity) before the next predict."""
        if self.flags.vo_update or self.flags.odometry:
            self.last_increment = self.increment / max(frames_since_reference, 1)

    def nees(self, true_pose) -> float:
        """Normalised estimation error squared of the pose against ``true_pose``."""
        e = np.asarray(true_pose, float) - self.pose
        e[2] = wrap_angle(e[2])
        return float(e @ np.linalg.solve(self.covariance, e))


def nis(innovation, innovation_covariance) -> float:
    """Normalised innovation squared, νᵀ S⁻¹ ν: the consistency check that needs no ground truth.

    A consistent filter's innovation ν is zero-mean with covariance S = H P Hᵀ + R, so the NIS is
    χ² with as many degrees of freedom as ν has components. After :meth:`VoKalmanFilter.update`,
    the VO's own components are ``ekf.y[:2]`` and ``ekf.S[:2, :2]`` (the third is the sideways
    constraint).
    """
    nu = np.atleast_1d(np.asarray(innovation, float))
    S = np.atleast_2d(np.asarray(innovation_covariance, float))
    if S.shape != (nu.size, nu.size):
        raise ValueError(f"innovation has {nu.size} components, its covariance is {S.shape}")
    return float(nu @ np.linalg.solve(S, nu))


#: Initial uncertainty of each track's scale (true over counted distance; a slip of up to ~10 %).
SCALE_SIGMA = 0.05
#: How far the scales may drift per frame (random walk): slip changes with the ground and the
#: manoeuvre, from about 1 % when driving to about 6 % in a spot turn.
SCALE_DRIFT = 0.0005
#: Weight of the newest update in the running mean of the scale updates' normalised innovation
#: squared (about the last 1 / NIS_MEMORY updates count).
NIS_MEMORY = 0.02


class SlipCalibratedFilter(VoKalmanFilter):
    """:class:`VoKalmanFilter` whose track odometry is corrected by the slip's mean, learnt online.

    Slip makes the encoders over-count (a track slipping by ``s`` turns ``1 / (1 - s)`` times as far
    as it moves), a *mean* error that zero-mean process noise does not model. Each track therefore
    has a scale, ``c = (c_left, c_right)``, ground over counted distance, a random walk
    (``SCALE_DRIFT`` per frame). The VO motion since the reference is linear in them: with the
    counted distances ``(u_l, u_r)`` and the gauge ``b`` ([Zhao], eq. 4–5), ``theta = (c_r u_r −
    c_l u_l) / b`` and ``rho = (c_l u_l + c_r u_r) / 2 · sinc(theta / 2)`` (eq. 15's chord of an
    arc), so a linear Kalman update learns ``c``; the prediction then moves the pose with the
    corrected distances. Equal scales model a slip of the whole motion (the spot turn), unequal ones
    the turn that unequal slip adds when driving.

    Lest the scales follow the noise of a VO variance smaller than its real error, the VO covariance
    is inflated by the excess over 2 of the running mean of the updates' normalised innovation
    squared; the counted distances' own noise, carried through the scales, joins the innovation's,
    or the scales would shrink to explain it away. The scales are estimated apart from the pose
    (two stages): the correlation of their shared VO measurement is not carried, which is small
    while slip changes slowly against the frame rate (the NEES over seeds checks it).
    """

    def __init__(self, *args, scale_sigma: float = SCALE_SIGMA, scale_drift: float = SCALE_DRIFT, **kwargs):
        super().__init__(*args, **kwargs)
        self.scales = np.ones(2)  # (c_left, c_right)
        self.scale_covariance = np.eye(2) * float(scale_sigma) ** 2
        self.scale_drift = float(scale_drift)
        self.innovation_nis = 2.0  # running mean of the scale updates' NIS (2 if consistent)
        self._counted: np.ndarray | None = None  # (left, right) counted since the reference

    def predict(self, u=None, keep_reference: bool = False) -> None:
        """Scale each track's counted distance by its learnt factor, then predict as the parent."""
        if u is None:
            self._counted = None
            super().predict(None, keep_reference)
            return
        u = np.asarray(u, float)
        self._counted = u + (self._counted if keep_reference and self._counted is not None else 0.0)
        self.scale_covariance = self.scale_covariance + np.eye(2) * self.scale_drift**2
        super().predict(self.scales * u, keep_reference)

    def control_covariance(self, u) -> np.ndarray:
        """The parent's encoder and slip noise of the corrected distances ``u``, plus what the
        scales' own uncertainty adds to them: ``diag(counted) P_c diag(counted)``."""
        counted = np.asarray(u, float) / self.scales
        return super().control_covariance(u) + np.diag(counted) @ self.scale_covariance @ np.diag(counted)

    def update(self, theta: float, rho: float, covariance, sideways: float = 0.0) -> None:
        """Learn the scales from ``(theta, rho)`` against the counted motion, then update the pose."""
        covariance = np.asarray(covariance, float)
        if self._counted is not None:
            left, right = self._counted
            gauge, chord = self.odometry.gauge, float(np.sinc(0.5 * theta / math.pi))
            H = np.array([[-left / gauge, right / gauge], [0.5 * left * chord, 0.5 * right * chord]])
            # the counts are noisy too (encoder noise and slip's random part): their noise, through
            # the scales, joins the VO's in the innovation, else the scales would shrink to explain it
            J = H / np.where(self._counted == 0.0, 1.0, self._counted) * self.scales
            R = covariance[:2, :2] * max(1.0, self.innovation_nis / 2.0)
            R = R + J @ VoKalmanFilter.control_covariance(self, self._counted) @ J.T
            innovation = np.array([theta, rho]) - H @ self.scales
            S = H @ self.scale_covariance @ H.T + R
            self.innovation_nis += NIS_MEMORY * (nis(innovation, S) - self.innovation_nis)
            K = self.scale_covariance @ H.T @ np.linalg.inv(S)
            self.scales = self.scales + K @ innovation
            I_KH = np.eye(2) - K @ H
            self.scale_covariance = I_KH @ self.scale_covariance @ I_KH.T + K @ R @ K.T
        super().update(theta, rho, covariance, sideways)
