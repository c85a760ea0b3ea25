"""Crawler drives with slipping tracks: ground truth and what the track encoders report.

A drive is a list of legs (frames, speed, turn rate) followed over the ground as a driver steering
to a plan would. To move a track by ``g`` when it slips by ``s``, the motor turns it by
``g / (1 - s)``; the encoders count that, with random-walk noise. Slip is small and nearly equal
when driving, strong and unequal in spot turns (the cause [Zhao] gives for its spot-turn heading
errors). Slip changes only what the encoders read; :class:`TrackGround` also moves the body (skid,
a wandering turning centre, pitch and roll on losses of contact).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.signal import lfilter

from vo_lib.geometry import wrap_angle
from vo_lib.models.track_odometry import TrackOdometry

#: Seconds over which speed changes between legs are smoothed (the crawler's acceleration).
RAMP_SECONDS = 0.4


@dataclass(frozen=True)
class Leg:
    """Constant speed (m/s) and turn rate (rad/s, counter-clockwise) for ``frames`` frames."""

    frames: int
    speed: float
    turn_rate: float = 0.0


@dataclass(frozen=True)
class SlipModel:
    """Per-track slip: a mean, a left/right difference and a slowly varying random part (in a spot
    turn, track speeds of opposite sign, the spot-turn values)."""

    mean: float = 0.01
    difference: float = 0.004
    sigma: float = 0.003
    spot_turn_mean: float = 0.06
    spot_turn_difference: float = 0.04
    correlation_frames: float = 30.0

    def sample(self, commands: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Slip ``(N, 2)`` (left, right) for track distances ``(N, 2)``."""
        spot = (commands[:, 0] * commands[:, 1]) < 0
        mean = np.where(spot, self.spot_turn_mean, self.mean)
        diff = np.where(spot, self.spot_turn_difference, self.difference)
        base = np.column_stack([mean + diff / 2, mean - diff / 2])
        return base + _ar1(len(commands), self.sigma, self.correlation_frames, rng, 2)


def _ar1(n: int, sigma: float, frames: float, rng: np.random.Generator, dim: int = 1) -> np.ndarray:
    """``(n, dim)`` AR(1) series, stationary standard deviation ``sigma``, correlation ``frames``."""
    a = np.exp(-1.0 / frames)
    steps = rng.normal(0.0, sigma * np.sqrt(1 - a * a), (n, dim))
    start = rng.normal(0.0, sigma, dim)
    return lfilter([1.0], [1.0, -a], steps, axis=0, zi=a * start[None, :])[0]  # x_k = a x_(k-1) + step_k


@dataclass(frozen=True)
class TrackGround:
    """How the tracks meet the ground: skid, a wandering turning centre and brief losses of contact.

    Skid-steer kinematics after Martínez et al. (2005), "Approximating kinematics for tracked mobile
    robots", Int. J. Robotics Research 24(10), 867-878: the body turns about an ICR at
    ``(x_icr, v_x / omega)``, so its centre moves sideways with ``v_y = -x_icr * omega``; the tracks'
    own ICRs are the slip of :class:`SlipModel`. After Mandow et al. (2007), "Experimental
    kinematics for wheeled skid-steer mobile robots", IROS, 1222-1227, ``x_icr`` grows linearly with
    ``|omega|`` and wanders slowly around that (AR(1)).

    A track loses contact at random (Poisson, per metre it travels) for ``contact_frames`` frames,
    keeping ``contact_grip`` of its traction while its encoder counts on; the body rolls towards
    that side and pitches by an angle drawn in ``tilt_deg`` (a half-sine bump). ``roughness_deg``
    adds the slow pitch and roll of uneven ground: a camera above the contact point moves sideways
    and up and down, so [Zhao]'s planar model no longer holds exactly.
    """

    icr_offset: float = 0.02  #: ``x_icr`` at zero turn rate, metres ahead of the track centre
    icr_per_rate: float = 0.06  #: growth of ``x_icr`` per rad/s of turn rate, metres
    icr_sigma: float = 0.01  #: standard deviation of the ICR's wander, metres
    icr_frames: float = 60.0  #: its correlation time, frames
    contact_rate: float = 0.0  #: losses of contact per metre a track travels
    contact_frames: int = 4  #: frames a loss lasts
    contact_grip: float = 0.5  #: share of a track's traction kept during a loss
    tilt_deg: tuple[float, float] = (2.0, 5.0)  #: range of the peak roll (and pitch, either sign), degrees
    roughness_deg: float = 0.0  #: standard deviation of the ground's pitch and roll, degrees
    roughness_frames: float = 15.0  #: their correlation time, frames

    def icr(self, turn_rate: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """``x_icr`` (metres) per step for turn rates ``turn_rate`` (rad/s)."""
        n = len(turn_rate)
        wander = _ar1(n, self.icr_sigma, max(self.icr_frames, 1.0), rng)[:, 0] if self.icr_sigma else 0.0
        return self.icr_offset + wander + self.icr_per_rate * np.abs(turn_rate)

    def contact(self, ground: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """Per-step grip ``(N, 2)`` of each track and body attitude ``(N, 2)`` (pitch, roll; radians)."""
        n = len(ground)
        grip, attitude = np.ones((n, 2)), np.zeros((n, 2))
        if self.contact_rate > 0:
            # a loss starts on a track with probability rate * distance in a step (Poisson, thinned)
            starts = rng.random((n, 2)) < self.contact_rate * np.abs(ground)
            length = int(self.contact_frames)
            bump = np.sin(np.pi * (np.arange(length) + 0.5) / length)
            low, high = np.radians(self.tilt_deg)
            for k, side in zip(*np.nonzero(starts), strict=True):
                stop = min(n, k + length)
                grip[k:stop, side] = np.minimum(grip[k:stop, side], self.contact_grip)
                roll = rng.uniform(low, high) * (1.0 if side == 1 else -1.0)  # down on the lost side
                pitch = rng.uniform(low, high) * rng.choice((-1.0, 1.0))
                attitude[k:stop] += np.column_stack([pitch, roll]) * bump[: stop - k, None]
        if self.roughness_deg > 0:
            attitude += _ar1(n, np.radians(self.roughness_deg), self.roughness_frames, rng, 2)
        return grip, attitude


#: Ground that holds the tracks exactly: no skid, no wander, no losses of contact.
RIGID_GROUND = TrackGround(icr_offset=0.0, icr_per_rate=0.0, icr_sigma=0.0)
#: A lab floor: the crawler skids in turns, but the floor is flat.
LAB_FLOOR = TrackGround()
#: Outdoor paving: skid, two losses of contact per ten metres a track travels (each 4 frames,
#: 0.13 s, at half grip), and 0.15 degrees of slow pitch and roll from the unevenness.
ROUGH_GROUND = TrackGround(contact_rate=0.2, roughness_deg=0.15, roughness_frames=30.0)


def integrate_body(steps: np.ndarray, start) -> np.ndarray:
    """Poses ``(K + 1, 3)`` from body-frame steps ``(K, 3)`` ``(forward, left, turn)``, each taken
    at constant velocity (the exact SE(2) exponential)."""
    steps = np.asarray(steps, dtype=float)
    fx, fy, w = steps.T
    small = np.abs(w) < 1e-9
    ws = np.where(small, 1.0, w)
    a = np.where(small, 1.0 - w * w / 6.0, np.sin(ws) / ws)
    b = np.where(small, w / 2.0, (1.0 - np.cos(ws)) / ws)
    local = np.column_stack([a * fx - b * fy, b * fx + a * fy])
    theta = float(start[2]) + np.concatenate([[0.0], np.cumsum(w)])
    c, s = np.cos(theta[:-1]), np.sin(theta[:-1])
    world = np.column_stack([c * local[:, 0] - s * local[:, 1], s * local[:, 0] + c * local[:, 1]])
    xy = np.asarray(start[:2], float) + np.vstack([np.zeros((1, 2)), np.cumsum(world, axis=0)])
    return np.column_stack([xy, wrap_angle(theta)])


@dataclass(frozen=True)
class Drive:
    """A simulated drive: one row per frame (frame 0 is the start, with zero motion)."""

    rate: float
    poses: np.ndarray  # (N, 3) true planar robot poses
    odometry: np.ndarray  # (N, 2) encoder readings: track distances since the previous frame
    slip: np.ndarray  # (N, 2)
    attitude: np.ndarray | None = None  # (N, 2) body pitch and roll (radians), None: level
    icr: np.ndarray | None = None  # (N,) longitudinal ICR offset x_icr of each step (metres)
    grip: np.ndarray | None = None  # (N, 2) share of traction each track had in each step

    @property
    def times(self) -> np.ndarray:
        return np.arange(len(self.poses)) / self.rate


def command_profile(legs, rate: float) -> tuple[np.ndarray, np.ndarray]:
    """Per-step speed and turn rate of ``legs``, with changes smoothed over :data:`RAMP_SECONDS`."""
    if not legs:
        raise ValueError("a drive needs at least one leg")
    speed = np.concatenate([np.full(leg.frames, leg.speed, float) for leg in legs])
    turn = np.concatenate([np.full(leg.frames, leg.turn_rate, float) for leg in legs])
    ramp = max(1, int(round(RAMP_SECONDS * rate)))
    if ramp > 1 and len(speed) > ramp:
        kernel, pad = np.ones(ramp) / ramp, ((ramp - 1) // 2, ramp // 2)
        speed, turn = (np.convolve(np.pad(x, pad, mode="edge"), kernel, mode="valid") for x in (speed, turn))
    return speed, turn


def simulate_drive(
    legs,
    rate: float,
    start,
    rng: np.random.Generator,
    odometry: TrackOdometry | None = None,
    slip: SlipModel | None = None,
    surface: TrackGround | None = None,
) -> Drive:
    """Drive ``legs`` at ``rate`` frames per second from ``start`` (x, y, yaw): ``sum(leg.frames) + 1``
    frames. Without ``surface`` the truth follows the plan's arcs exactly; with it the body skids,
    its turning centre wanders and it pitches and rolls (:class:`TrackGround`)."""
    if rate <= 0:
        raise ValueError(f"rate must be > 0 frames per second; got {rate!r}")
    odometry = odometry or TrackOdometry()
    slip = slip or SlipModel()
    speed, turn = command_profile(legs, rate)
    ground = odometry.controls_for(speed / rate, turn / rate)
    slips = slip.sample(ground, rng)
    turned = ground / (1.0 - slips)  # what the motors turned and the encoders count
    noise_sd = odometry.encoder_sigma * np.sqrt(np.abs(turned))
    readings = turned + rng.normal(size=turned.shape) * noise_sd
    zero = np.zeros((1, 2))
    measured = [np.vstack([zero, x]) for x in (readings, slips)]
    if surface is None:
        return Drive(rate, odometry.integrate(ground, start=start, exact=True), *measured)
    # the tracks move the ground by what they planned, less what they lose in contact; the body
    # turns by their difference over the gauge and skids sideways about the shifted ICR
    grip, attitude = surface.contact(ground, rng)
    forward, turn = odometry.increment(ground * grip)
    x_icr = surface.icr(turn * rate, rng)
    poses = integrate_body(np.column_stack([forward, -x_icr * turn, turn]), start)
    icr = np.concatenate([[surface.icr_offset], x_icr])
    return Drive(rate, poses, *measured, np.vstack([zero, attitude]), icr, np.vstack([np.ones((1, 2)), grip]))
