"""Crawler track odometry ([Zhao], eq. 2-11) and its covariance propagation.

A crawler turns about an instantaneous centre on its lateral axis. In one sampling interval the
left and right tracks travel ``du_left`` and ``du_right``; with the effective gauge ``D + 2b``
(distance between the tracks plus twice a track's width) the pose advances by

    du     = (du_right + du_left) / 2                          eq. 5
    dtheta = (du_right - du_left) / (D + 2b)                   eq. 4
    dx     = du * cos(theta + dtheta / 2)                      eq. 2
    dy     = du * sin(theta + dtheta / 2)                      eq. 3

The paper writes this as ``x_k = F_k x_{k-1} + B_k u_k`` (eq. 6) with ``F_k = I`` (eq. 9) and the
control matrix ``B_k`` of eq. 10, whose angle ``phi_k = dtheta / 2`` (eq. 11) itself depends on
``u_k``. That form is exact for the mean but it is *not* the linearisation a Kalman filter needs
for the covariance: :meth:`TrackOdometry.jacobians` gives the true ``df/dx`` and ``df/du``.
All functions broadcast over leading batch dimensions (many robots, or many time steps).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from vo_lib.geometry import wrap_angle

#: Our crawler's dimensions (the paper does not print the Voyager-II's): 0.40 m between the
#: track centre lines' inner edges and 0.10 m wide tracks, an effective gauge of 0.60 m.
DEFAULT_TRACK_DISTANCE = 0.40
DEFAULT_TRACK_WIDTH = 0.10
#: Encoder noise: standard deviation of a track's distance per square-root metre travelled.
DEFAULT_ENCODER_SIGMA = 0.01


def _controls(u) -> tuple[np.ndarray, np.ndarray]:
    u = np.asarray(u, dtype=float)
    if u.shape[-1:] != (2,):
        raise ValueError(f"u must end in an axis of length 2 (du_left, du_right); got shape {u.shape}")
    return u[..., 0], u[..., 1]


def _states(state) -> np.ndarray:
    state = np.asarray(state, dtype=float)
    if state.shape[-1:] != (3,):
        raise ValueError(f"state must end in an axis of length 3 (x, y, theta); got shape {state.shape}")
    return state


@dataclass(frozen=True)
class TrackOdometry:
    """Dead reckoning of a differential-drive crawler from its two track distances.

    Parameters
    ----------
    track_distance, track_width : float
        ``D``, distance between the two tracks, and ``b``, width of one track, in metres.
    encoder_sigma : float
        Standard deviation of a track's measured distance per square-root metre it travels.
    """

    track_distance: float = DEFAULT_TRACK_DISTANCE
    track_width: float = DEFAULT_TRACK_WIDTH
    encoder_sigma: float = DEFAULT_ENCODER_SIGMA

    def __post_init__(self):
        for name in ("track_distance", "track_width"):
            value = float(getattr(self, name))
            if not math.isfinite(value) or value < 0:
                raise ValueError(f"{name} must be a finite number >= 0 metres; got {value!r}")
        if not self.gauge > 0:
            raise ValueError("track_distance + 2 * track_width (the gauge) must be > 0")
        if not (math.isfinite(self.encoder_sigma) and self.encoder_sigma >= 0):
            raise ValueError(f"encoder_sigma must be a finite number >= 0; got {self.encoder_sigma!r}")

    @property
    def gauge(self) -> float:
        """Effective gauge ``D + 2b`` of eq. 4."""
        return self.track_distance + 2.0 * self.track_width

    # ------------------------------------------------------------------ eq. 4, 5
    def increment(self, u):
        """``(du, dtheta)``: distance of the centre and heading change (eq. 5 and eq. 4)."""
        du_left, du_right = _controls(u)
        return 0.5 * (du_right + du_left), (du_right - du_left) / self.gauge

    def controls_for(self, du, dtheta) -> np.ndarray:
        """Track distances ``(du_left, du_right)`` that produce ``du`` and ``dtheta``: eq. 4-5 inverted."""
        du = np.asarray(du, dtype=float)
        half = 0.5 * self.gauge * np.asarray(dtheta, dtype=float)
        return np.stack(np.broadcast_arrays(du - half, du + half), axis=-1)

    # ------------------------------------------------------------------ eq. 2-6
    def predict(self, state, u) -> np.ndarray:
        """``x_k = F_k x_{k-1} + B_k u_k`` with ``F_k = I`` (eq. 6, 9, 10): the midpoint step of eq. 2-5."""
        state = _states(state)
        du, dtheta = self.increment(u)
        a = state[..., 2] + 0.5 * dtheta
        x, y = state[..., 0] + du * np.cos(a), state[..., 1] + du * np.sin(a)
        return np.stack(np.broadcast_arrays(x, y, wrap_angle(state[..., 2] + dtheta)), axis=-1)

    # ------------------------------------------------------------------ linearisation
    def jacobians(self, state, u) -> tuple[np.ndarray, np.ndarray]:
        """``(F_x, F_u)``: derivatives of :meth:`predict` by the state and the controls; ``F_x``
        differs from eq. 9's identity in its last column, ``F_u`` from eq. 10's ``B_k`` by
        ``+-du sin/cos(theta + phi) / (2 (D + 2b))``, as ``phi_k`` depends on the controls."""
        state = _states(state)
        du, dtheta = self.increment(u)
        a = state[..., 2] + 0.5 * dtheta
        c, s = np.cos(a), np.sin(a)
        g = self.gauge
        shape = np.broadcast_shapes(state.shape[:-1], np.shape(du))
        F_x = np.broadcast_to(np.eye(3), shape + (3, 3)).copy()
        F_x[..., 0, 2] = -du * s
        F_x[..., 1, 2] = du * c
        F_u = np.empty(shape + (3, 2))
        F_u[..., 0, 0] = 0.5 * c + du * s / (2.0 * g)
        F_u[..., 0, 1] = 0.5 * c - du * s / (2.0 * g)
        F_u[..., 1, 0] = 0.5 * s - du * c / (2.0 * g)
        F_u[..., 1, 1] = 0.5 * s + du * c / (2.0 * g)
        F_u[..., 2, 0] = -1.0 / g
        F_u[..., 2, 1] = 1.0 / g
        return F_x, F_u

    def step(self, state, u) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`predict` and :meth:`jacobians` of one pose and control pair, in scalar arithmetic."""
        x, y, theta = (float(v) for v in state)
        du_left, du_right = float(u[0]), float(u[1])
        g = self.gauge
        du, dtheta = 0.5 * (du_right + du_left), (du_right - du_left) / g
        a = theta + 0.5 * dtheta
        c, s = math.cos(a), math.sin(a)
        new = np.array([x + du * c, y + du * s, float(wrap_angle(theta + dtheta))])
        F_x = np.array([[1.0, 0.0, -du * s], [0.0, 1.0, du * c], [0.0, 0.0, 1.0]])
        k = du / (2.0 * g)
        F_u = np.array(
            [[0.5 * c + k * s, 0.5 * c - k * s], [0.5 * s - k * c, 0.5 * s + k * c], [-1.0 / g, 1.0 / g]]
        )
        return new, F_x, F_u

    def control_covariance(self, u) -> np.ndarray:
        """Covariance ``M`` of the measured track distances: independent, variance ``sigma^2 |du_i|``."""
        du_left, du_right = _controls(u)
        var = self.encoder_sigma**2
        M = np.zeros(np.shape(du_left) + (2, 2))
        M[..., 0, 0] = var * np.abs(du_left)
        M[..., 1, 1] = var * np.abs(du_right)
        return M

    def propagate(self, state, P, u) -> tuple[np.ndarray, np.ndarray]:
        """One Kalman prediction: mean by eq. 6, covariance ``F_x P F_x^T + F_u M F_u^T``."""
        F_x, F_u = self.jacobians(state, u)
        M = self.control_covariance(u)
        P_new = F_x @ P @ np.swapaxes(F_x, -1, -2) + F_u @ M @ np.swapaxes(F_u, -1, -2)
        return self.predict(state, u), P_new

    # ------------------------------------------------------------------ whole paths
    def integrate(self, controls, start=(0.0, 0.0, 0.0), exact: bool = False) -> np.ndarray:
        """Dead-reckoned poses ``(K + 1, 3)`` from ``K`` control pairs: cumulative sums of eq. 4 and
        eq. 2-3, or, when ``exact``, of the arc's chord ``du * sin(dtheta/2) / (dtheta/2)`` (eq. 2-3
        take the arc ``du`` for it: a relative error of about ``dtheta**2 / 24`` per step)."""
        controls = np.asarray(controls, dtype=float)
        if controls.ndim != 2 or controls.shape[1] != 2:
            raise ValueError(f"controls must have shape (K, 2); got {controls.shape}")
        start = _states(start)
        du, dtheta = self.increment(controls)
        theta = start[2] + np.concatenate([[0.0], np.cumsum(dtheta)])
        step = du * np.sinc(dtheta / (2.0 * np.pi)) if exact else du
        a = theta[:-1] + 0.5 * dtheta
        x, y = (np.concatenate([[0.0], np.cumsum(step * f(a))]) for f in (np.cos, np.sin))
        return np.column_stack([start[0] + x, start[1] + y, wrap_angle(theta)])


def apply_slip(u, slip_left: float = 0.0, slip_right: float = 0.0) -> np.ndarray:
    """Ground distances of tracks that slip: each travels ``(1 - slip)`` of what its encoder reads
    (the paper's cause of its spot-turn heading errors)."""
    u = np.asarray(u, dtype=float)
    return u * np.array([1.0 - slip_left, 1.0 - slip_right])
