"""Crawler drives with slipping tracks: ground truth and what the track encoders report.

A drive is a list of legs (frames, speed, turn rate) that the robot follows over the ground, as a
driver steering to a plan would. To move a track by ``g`` over the ground when it slips by ``s``,
the motor turns it by ``g / (1 - s)``; the encoders count that turning, with random-walk noise.
Slip is small and nearly equal on both tracks when driving, strong and unequal in spot turns,
where the tracks scrub sideways (the cause seed 000 gives for its spot-turn heading errors).
Truth integrates the ground motion with the exact circular arc; odometry integrates the encoders.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

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
    """Per-track slip: a mean, a left/right difference and a slowly varying random part.

    In a spot turn (track speeds of opposite sign) the spot-turn values apply instead.
    """

    mean: float = 0.01
    difference: float = 0.004
    sigma: float = 0.003
    spot_turn_mean: float = 0.06
    spot_turn_difference: float = 0.04
    correlation_frames: float = 30.0

    def sample(self, commands: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Slip ``(N, 2)`` (left, right) for track distances ``(N, 2)``."""
        n = len(commands)
        spot = (commands[:, 0] * commands[:, 1]) < 0
        mean = np.where(spot, self.spot_turn_mean, self.mean)
        diff = np.where(spot, self.spot_turn_difference, self.difference)
        base = np.column_stack([mean + diff / 2, mean - diff / 2])
        # AR(1) noise with the stated correlation time and stationary standard deviation sigma
        a = np.exp(-1.0 / self.correlation_frames)
        e = rng.normal(0.0, self.sigma * np.sqrt(1 - a * a), (n, 2))
        noise = np.zeros((n, 2))
        state = rng.normal(0.0, self.sigma, 2)
        for k in range(n):
            state = a * state + e[k]
            noise[k] = state
        return base + noise


@dataclass(frozen=True)
class Drive:
    """A simulated drive: one row per frame (frame 0 is the start, with zero motion)."""

    rate: float
    poses: np.ndarray  # (N, 3) true planar robot poses
    odometry: np.ndarray  # (N, 2) encoder readings: track distances since the previous frame
    ground: np.ndarray  # (N, 2) distances the tracks moved over the ground
    slip: np.ndarray  # (N, 2)

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
        kernel = np.ones(ramp) / ramp
        pad = ((ramp - 1) // 2, ramp // 2)
        speed = np.convolve(np.pad(speed, pad, mode="edge"), kernel, mode="valid")
        turn = np.convolve(np.pad(turn, pad, mode="edge"), kernel, mode="valid")
    return speed, turn


def simulate_drive(
    legs,
    rate: float,
    start,
    rng: np.random.Generator,
    odometry: TrackOdometry | None = None,
    slip: SlipModel | None = None,
) -> Drive:
    """Drive ``legs`` at ``rate`` frames per second from ``start`` (x, y, yaw).

    Returns ``sum(leg.frames) + 1`` frames: the start and one per step.
    """
    if rate <= 0:
        raise ValueError(f"rate must be > 0 frames per second; got {rate!r}")
    odometry = odometry or TrackOdometry()
    slip = slip or SlipModel()
    speed, turn = command_profile(legs, rate)
    ground = odometry.controls_for(speed / rate, turn / rate)
    slips = slip.sample(ground, rng)
    turned = ground / (1.0 - slips)  # what the motors turned and the encoders count
    poses = odometry.integrate(ground, start=start, exact=True)
    noise_sd = odometry.encoder_sigma * np.sqrt(np.abs(turned))
    readings = turned + rng.normal(size=turned.shape) * noise_sd
    zero = np.zeros((1, 2))
    return Drive(
        rate, poses, np.vstack([zero, readings]), np.vstack([zero, ground]), np.vstack([zero, slips])
    )
