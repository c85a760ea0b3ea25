"""What carries the camera: where it is mounted, which odometry it has, which motion model fits.

* **The crawler** of the rendered samples [Zhao]: the camera above the turning axis on a flat
  floor, so the planar circular-motion model (eq. 12-17) is exact; track odometry.
* **A car** (KITTI): the camera 1.6 m up and about a metre ahead of the turning axis on a road
  that climbs and banks: a 6-DoF motion. Odometry from ``odometry.txt``, else from the OXTS
  packets' speed and yaw rate, turned into the distances of two wheels :data:`CAR_GAUGE` apart.
* **A drone** or hand-held rig (ASL layout), turning about its own origin, without odometry.

The vehicle's frame is x forward, y left, z up; a KITTI car's origin is the IMU, near the rear
axle, where ``raw_calib/`` places the camera (else :data:`KITTI_CAMERA_IN_IMU`).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, replace
from enum import Enum

import numpy as np

from vo_lib.formats.frame_files import CAMERA_MOUNTS, SequenceError, read_per_frame
from vo_lib.formats.kitti_raw import camera_in_imu_frame, read_oxts, wheel_distances_from_oxts
from vo_lib.formats.poses import check_file
from vo_lib.geometry import camera_mount
from vo_lib.models.track_odometry import TrackOdometry

#: Gauge of the two wheels that turn OXTS speed and yaw rate into wheel distances, metres. It sets
#: only the modelled yaw noise, ``2 CAR_DISTANCE_SIGMA**2 s / gauge**2`` over ``s`` metres, made the
#: measured one: on KITTI raw drive 0001 the yaw-rate increment differs from the heading's by
#: 0.0092 deg rms per 1.0 m frame, which :func:`gauge_for_yaw_noise` turns into 176 m (a real
#: 1.6 m track would model a gyro a hundred times noisier than it is).
CAR_GAUGE = 176.0
#: The rendered road car's wheel gauge (``vo_lib.sim.road``), metres, which models its ``odometry.txt``.
ROAD_CAR_GAUGE = 1.6
#: Noise of a wheel distance from the OXTS speed, per square-root metre: on KITTI raw drive 0001 the
#: distance per frame differs from the vision's by 1.4 % rms (the speed lags when braking), 0.019
#: per wheel; a tighter figure lets the filter reject good vision for a lagging speed.
CAR_DISTANCE_SIGMA = 0.02
#: The narrowest gauge a manifest's track odometry may state, metres.
MIN_GAUGE_M = 0.01
#: Camera position in the vehicle frame (forward, left, up), metres, for KITTI without raw_calib.
KITTI_CAMERA_IN_IMU = (1.08, -0.31, 0.73)


class VehicleKind(str, Enum):
    """What carries the camera."""

    CRAWLER = "crawler"  #: the tracked robot of [Zhao]
    CAR = "car"
    DRONE = "drone"  #: a rig read as it records (ASL layout): a hand-held camera or a drone

    def __str__(self) -> str:
        return self.value


class Motion(str, Enum):
    """The model of the motion between two frames that fits a vehicle."""

    PLANAR = "planar"  #: circular motion on a flat floor, camera above the turning axis (eq. 12-17)
    FULL = "full"  #: six degrees of freedom (``six_dof``)
    HOVER = "hover"  #: six degrees of freedom, no odometry: nothing predicts the motion well

    def __str__(self) -> str:
        return self.value


@dataclass
class Vehicle:
    """The rig around the camera."""

    kind: VehicleKind
    mount: np.ndarray  #: ``T_vehicle_camera``: the left camera's pose in the vehicle frame
    odometry_model: TrackOdometry  #: gauge and noise of the odometry ([Zhao], eq. 2-11)
    odometry: np.ndarray | None  #: left and right distances per frame (row 0 unused)
    odometry_source: str  #: where the odometry came from, for reports
    motion: Motion  #: the motion model that fits


def gauge_for_yaw_noise(distances: np.ndarray, yaw_errors: np.ndarray, distance_sigma: float) -> float:
    """The gauge at which the track-odometry model's yaw noise is the measured one.

    From the metres ``s`` of each frame and its yaw increment's error ``e`` (radians):
    ``distance_sigma * sqrt(2 sum(s) / sum(e^2))``, whose modelled variance
    ``2 distance_sigma^2 s / gauge^2`` per frame sums to ``sum(e^2)`` ([Zhao], eq. 4-11, ``b = 0``).
    """
    s, e = np.abs(np.asarray(distances, float)), np.asarray(yaw_errors, float)
    if s.shape != e.shape or len(s) == 0 or not np.any(e):
        raise ValueError("distances and yaw errors must be non-empty, of one length, with some error")
    return float(distance_sigma * np.sqrt(2.0 * s.sum() / np.sum(e**2)))


def car_odometry_model(gauge: float = ROAD_CAR_GAUGE) -> TrackOdometry:
    """Two wheels ``gauge`` apart: ``D + 2b`` with ``b = 0`` (:data:`CAR_GAUGE` for OXTS odometry)."""
    return TrackOdometry(track_distance=gauge, track_width=0.0, encoder_sigma=CAR_DISTANCE_SIGMA)


def drone_mount(T_body_camera: np.ndarray) -> np.ndarray:
    """The mount of a camera on a body that turns about its own origin (a drone's IMU, a hand-held
    rig): the vehicle frame's axes are the camera's, only its origin the body's (the offset is
    approximate for a tilted camera, but a few centimetres on a compact rig)."""
    origin_in_camera = np.linalg.inv(T_body_camera)[:3, 3]
    right, down, forward = -origin_in_camera  # the camera seen from the body origin
    return camera_mount(forward=forward, height=-down, left=-right)


def vehicle_of(sequence, use_odometry: bool = True, motion: str = "auto") -> Vehicle:
    """The vehicle of a :class:`~vo_lib.formats.sequence.Sequence`, from its manifest and files.

    ``use_odometry=False`` reads no odometry. With ``motion="hover"`` a sequence that names no free
    body turns about its camera (a hand-held rig, or a drone whose body is not known), and no
    odometry is read: the model is of a body without it.
    """
    camera = sequence.manifest.get("camera", {}) if isinstance(sequence.manifest, dict) else {}
    if "T_body_camera" in sequence.manifest:
        mount = drone_mount(np.asarray(sequence.manifest["T_body_camera"], float))  # no odometry
        return Vehicle(VehicleKind.DRONE, mount, car_odometry_model(), None, "none", Motion.HOVER)
    if "height_m" in camera:  # a rendered sample: the crawler of [Zhao]
        vehicle = _crawler(sequence, camera, use_odometry)
    else:
        vehicle = _car(sequence, use_odometry)
    if motion == Motion.HOVER:
        return replace(
            vehicle,
            kind=VehicleKind.DRONE,
            mount=drone_mount(np.eye(4)),
            odometry=None,
            odometry_source="none",
            motion=Motion.HOVER,
        )
    return vehicle


def _crawler(sequence, camera: dict, use_odometry: bool) -> Vehicle:
    """A rendered sample's crawler: its mount and track odometry as the manifest states them."""
    mount = camera_mount(forward=float(camera.get("forward_m", 0.0)), height=float(camera["height_m"]))
    manifest = sequence.path / "manifest.json"
    try:
        model = TrackOdometry(**sequence.manifest.get("track_odometry", {}))
    except (TypeError, ValueError) as exc:  # an unknown key, a value that is not a length
        raise SequenceError(
            f"{manifest}: key track_odometry: expected track_distance, track_width, encoder_sigma ({exc})"
        ) from None
    if model.gauge < MIN_GAUGE_M:  # the turn is the tracks' difference over the gauge: no gauge, no turn
        raise SequenceError(
            f"{manifest}: key track_odometry: track_distance + 2 track_width is "
            f"{model.gauge:g} m; expected at least {MIN_GAUGE_M:g} m"
        )
    mount_text = camera.get("mount", CAMERA_MOUNTS[0])
    if mount_text not in CAMERA_MOUNTS:  # a misspelt crawler's mount is not taken for another
        raise SequenceError(
            f"{manifest}: key camera.mount: expected "
            f"{' or '.join(map(repr, CAMERA_MOUNTS))}, got {json.dumps(mount_text)[:40]}"
        )
    odometry = sequence.odometry if use_odometry else None
    source = "odometry.txt" if odometry is not None else "none"
    motion = Motion.PLANAR if mount_text == CAMERA_MOUNTS[0] else Motion.FULL
    return Vehicle(VehicleKind.CRAWLER, mount, model, odometry, source, motion)


def _car(sequence, use_odometry: bool) -> Vehicle:
    """A car in the KITTI layout: the camera in its IMU frame, wheel distances from
    ``odometry.txt`` or the OXTS packets."""
    root = sequence.path
    raw_calib = sequence.raw_calib or root / "raw_calib"  # a raw drive's, else a KITTI-layout folder's
    if raw_calib.exists() or raw_calib.is_symlink():  # a file or a broken link: named by the reader
        mount = camera_in_imu_frame(raw_calib)
    else:
        forward, left, up = KITTI_CAMERA_IN_IMU
        mount = camera_mount(forward=forward, height=up, left=left)
    model = car_odometry_model()
    odometry = sequence.odometry if use_odometry else None
    source = "odometry.txt" if odometry is not None else "none"
    if odometry is None and use_odometry:
        packets, packets_file = _oxts_packets(sequence)
        if packets is not None:
            odometry = wheel_distances_from_oxts(packets, sequence.times, CAR_GAUGE)
            model = car_odometry_model(CAR_GAUGE)
            source = f"{packets_file} (speed and yaw rate)"
    return Vehicle(VehicleKind.CAR, mount, model, odometry, source, Motion.FULL)


def _oxts_packets(sequence) -> tuple[np.ndarray | None, str]:
    """A car's OXTS packets, one per frame, and their file (a raw drive's, else ``oxts.txt``);
    ``(None, "")`` where there are none."""
    if sequence.oxts is not None:
        return sequence.oxts, "oxts/data"
    oxts = sequence.path / "oxts.txt"
    if not check_file(oxts, "the OXTS packets", optional=True):
        return None, ""
    return read_per_frame(oxts, len(sequence), "packets", read_oxts), "oxts.txt"
