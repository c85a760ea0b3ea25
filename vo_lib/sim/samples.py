"""Named sample sequences that mirror the experiments of [Zhao] (and the corridor of [Yuan]).

Each is a world, a rig, a drive and a rate; :func:`generate` renders one in the KITTI layout with
truth, track odometry and a ``manifest.json`` that states everything needed to make it again.
"""

from __future__ import annotations

import hashlib
import time
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np
from scipy.signal import lfilter
from scipy.spatial.transform import Rotation
from tqdm.auto import tqdm

from vo_lib.camera import StereoCamera
from vo_lib.formats.frame_files import CAMERA_MOUNTS
from vo_lib.formats.sequence_writer import SequenceWriter
from vo_lib.geometry import camera_mount, planar_to_matrix
from vo_lib.models.track_odometry import TrackOdometry
from vo_lib.sim import frame_store, road
from vo_lib.sim.render import SensorEffects, StereoRenderer
from vo_lib.sim.textures import TEXTURE_VERSION
from vo_lib.sim.trajectories import LAB_FLOOR, ROUGH_GROUND, Leg, SlipModel, TrackGround, simulate_drive
from vo_lib.sim.world import WORLDS

#: Height of the camera above the floor; it sits above the crawler's turning axis (notebook 03).
CAMERA_HEIGHT = 0.5
DEFAULT_RESOLUTION = (640, 480)
#: Sensor noise, grey levels: what Immerkaer's estimator measures on the flat parts of KITTI's
#: images (1.0-1.4 over drive 0001); rendered images carry no noise of their own.
SENSOR_NOISE = 1.2
#: Auto-exposure: the gain of frame k is ``exp(g_k)``, ``g`` a slowly varying random walk pulled
#: back to 0 (AR(1) with this stationary deviation and :data:`EXPOSURE_FRAMES` correlation).
EXPOSURE_SIGMA = 0.04
EXPOSURE_FRAMES = 20.0
#: Seconds between progress lines when ``progress="lines"``.
PROGRESS_EVERY_S = 10.0
#: Wheel slip of a car on dry asphalt: small and nearly equal on both sides.
CAR_SLIP = SlipModel(mean=0.003, difference=0.001, sigma=0.002, spot_turn_mean=0.0, spot_turn_difference=0.0)


def exposure_gains(n: int, sigma: float, rng: np.random.Generator) -> np.ndarray:
    """Per-frame exposure gains of an auto-exposure camera: ``exp`` of an AR(1) series, frame 0 at 1."""
    a = np.exp(-1.0 / EXPOSURE_FRAMES)
    steps = rng.normal(0.0, sigma * np.sqrt(1 - a * a), n)
    steps[0] = 0.0
    return np.exp(lfilter([1.0], [1.0, -a], steps))  # g_k = a g_(k-1) + step_k


def _sensor_effects(sample, n: int) -> list[SensorEffects]:
    """Sensor noise and auto-exposure gain of each of the sample's first ``n`` frames."""
    gains = exposure_gains(n, sample.exposure_sigma, np.random.default_rng(sample.seed + 3))
    return [SensorEffects(noise_sigma=sample.sensor_noise, exposure_gain=float(g)) for g in gains]


@dataclass(frozen=True)
class Sample:
    """Everything that defines a sample sequence."""

    name: str
    purpose: str
    mirrors: str
    world: str
    start: tuple[float, float, float]
    rate: float
    legs: tuple[Leg, ...]
    seed: int
    slip: SlipModel = field(default_factory=SlipModel)
    sensor_noise: float = SENSOR_NOISE
    exposure_sigma: float = EXPOSURE_SIGMA
    rig: str = "crawler"  # or "car": KITTI's rig on a car (vo_lib.sim.road)
    resolution: tuple[int, int] = DEFAULT_RESOLUTION
    #: how the tracks meet the ground (skid, losses of contact); None: the plan's exact arcs
    surface: TrackGround | None = None

    @property
    def frames(self) -> int:
        return sum(leg.frames for leg in self.legs) + 1


def _turns_pattern(signs, rate_deg: float) -> tuple[Leg, ...]:
    """200 frames straight, then 200 turning the way of each sign, at 0.5 m/s."""
    return tuple(leg for sign in signs for leg in (Leg(200, 0.5), Leg(200, 0.5, np.radians(rate_deg) * sign)))


def _yard(name: str, purpose: str, mirrors: str, start, legs, seed: int) -> Sample:
    """A crawler's sample in the outdoor yard, at 30 Hz on rough ground."""
    return Sample(name, purpose, mirrors, "outdoor_yard", start, 30.0, legs, seed, surface=ROUGH_GROUND)


SAMPLES: dict[str, Sample] = {
    s.name: s
    for s in (
        Sample(
            "indoor_linear",
            "straight forward and back: relative error of linear motion",
            "[Zhao], IV.A.2 (200 frames forward, 200 back)",
            "indoor_lab",
            (-3.5, 0.5, 0.0),
            30.0,
            (Leg(200, 0.3), Leg(200, -0.3)),
            seed=101,
            surface=LAB_FLOOR,
        ),
        Sample(
            "indoor_free",
            "arcs and straights in the lab: heading and position at key positions",
            "[Zhao], IV.A.3 (free motion), with a trolley pushed through the lab",
            "indoor_lab_cart",
            (-4.5, -0.8, 0.0),
            30.0,
            (
                Leg(120, 0.3),
                Leg(150, 0.3, np.radians(30)),
                Leg(150, 0.3),
                Leg(150, 0.3, np.radians(30)),
                Leg(100, 0.3),
                Leg(130, 0.3, np.radians(-20)),
            ),
            seed=102,
            surface=LAB_FLOOR,
        ),
        _yard(
            "outdoor_linear",
            "long straight forward and back in an open yard: low parallax",
            "[Zhao], IV.B.1 (600 frames forward, 600 back)",
            (-6.0, -2.0, 0.0),
            (Leg(600, 0.5), Leg(600, -0.5)),
            103,
        ),
        _yard(
            "spot_turn",
            "turning on the spot, with strong unequal track slip",
            "[Zhao], IV.B.2 (1800 frames of spot turns)",
            (0.0, 0.0, 0.0),
            (Leg(1800, 0.0, np.radians(18)),),
            104,
        ),
        _yard(
            "outdoor_free",
            "free driving in the yard: errors at key positions (Table 2)",
            "[Zhao], IV.B.3 (about 1400 frames)",
            (-10.0, -4.0, 0.3),
            _turns_pattern((1, -1, 1), 12) + (Leg(200, 0.5),),
            105,
        ),
        _yard(
            "spot_turn_2",
            "turning on the spot the other way, for longer: the paper's second set",
            "[Zhao], IV.B.2 (2400 frames of spot turns, second set)",
            (0.0, 0.0, 0.0),
            (Leg(2400, 0.0, np.radians(-15)),),
            107,
        ),
        _yard(
            "outdoor_free_2",
            "a longer tour of the yard, quarter turns both ways: Table 2, set 2",
            "[Zhao], IV.B.3 (2419 frames, second set)",
            (-18.0, 14.0, 3.14),
            (Leg(218, 0.5),)
            + _turns_pattern((1, 1, -1, -1), 13.5)
            + (Leg(200, 0.5), Leg(200, 0.5, np.radians(-13.5)), Leg(200, 0.5, np.radians(13.5))),
            108,
        ),
        _yard(
            "outdoor_free_3",
            "the longest tour, at the far end of the yard: Table 2, set 3",
            "[Zhao], IV.B.3 (2670 frames, third set)",
            # from the open south end: the tour sees sky and far fronts (bench realism in range)
            (0.0, -35.0, 0.524),
            (Leg(269, 0.5),) + _turns_pattern((-1, 1, 1, -1, 1, 1), 15),
            109,
        ),
        _yard(
            "long_run",
            "ten laps of an oval, 10,000 frames: the timing run (render it in memory: bench long)",
            "[Zhao], IV.A.1 (10000 frames, elapsed time per frame)",
            (-22.0, 2.0, 1.57),
            # ten laps of an oval: 5 m straights joined by half turns of 1 m radius
            (Leg(300, 0.5), Leg(180, 0.5, np.radians(30))) * 20 + (Leg(399, 0.5),),
            110,
        ),
        Sample(
            "road_drive",
            "a car on a road: two sharp bends, a climb, a banked bend, passing traffic",
            "the real road sequences (KITTI's rig, 10 Hz, 5-12 m/s)",
            "road",
            road.START,
            road.RATE,
            road.LEGS,
            seed=111,
            slip=CAR_SLIP,
            rig="car",
            resolution=(road.KITTI_RIG[4], road.KITTI_RIG[5]),
        ),
        Sample(
            "corridor",
            "along a corridor whose cross features are hidden over a stretch",
            "[Yuan], corridor experiment",
            "corridor",
            (1.0, 0.0, 0.0),
            10.0,
            (Leg(540, 0.5),),
            seed=106,
            # the sensor [Yuan]'s figures were measured with (README, Table III): noise of
            # 1 grey level, fixed exposure
            sensor_noise=1.0,
            exposure_sigma=0.0,
        ),
    )
}


def is_sample(name: str) -> bool:
    """Whether ``name`` is a sample's (and no folder of that name is there instead)."""
    return name in SAMPLES and not Path(name).exists()


def fingerprint(name: str) -> str:
    """A short hash of everything that shapes a sample's images (its definition but its prose, its
    world, the texture version): a cached sample whose manifest carries another is out of date."""
    sample = replace(get_sample(name), purpose="", mirrors="")
    text = repr(sample) + repr(WORLDS[sample.world]()) + f"textures {TEXTURE_VERSION}"
    return hashlib.sha1(text.encode()).hexdigest()[:16]


def get_sample(name: str) -> Sample:
    if name not in SAMPLES:
        raise KeyError(f"unknown sample {name!r}; known samples: {', '.join(SAMPLES)}")
    return SAMPLES[name]


@dataclass(frozen=True)
class RenderedSample:
    """A sample's rig and truth: ``vehicle_poses`` ``(N, 4, 4)`` in the world (tilted on rough
    ground, a car's on the road), ``mount`` the left camera on the vehicle."""

    camera: StereoCamera
    mount: np.ndarray
    drive: object
    frames: int
    vehicle_poses: np.ndarray
    first: int = 0  # the drive's frame the rendered frames start at

    def truth(self) -> np.ndarray:
        """True planar vehicle poses of the frames."""
        return self.drive.poses[self.first : self.first + self.frames]

    def camera_poses(self) -> np.ndarray:
        """World poses ``(N, 4, 4)`` of the left camera."""
        return self.vehicle_poses[self.first : self.first + self.frames] @ self.mount


def sample_camera(sample: Sample, resolution=None) -> StereoCamera:
    """The sample's rig at ``resolution`` (default: the sample's own)."""
    width, height = sample.resolution if resolution is None else resolution
    if sample.rig == "car":  # KITTI's lens on a sensor of this size: its horizontal view, square pixels
        f, cx, cy, baseline, w0, h0 = road.KITTI_RIG
        camera = StereoCamera(f, f, cx, cy, baseline, w0, h0).scaled(width, height)
        return replace(camera, fy=camera.fx)
    return StereoCamera.bumblebee2(width, height)


def _world_poses(sample: Sample, drive) -> np.ndarray:
    """Vehicle poses ``(N, 4, 4)``: a car's on the road, a crawler's pitched and rolled about its
    contact point."""
    if sample.rig == "car":
        return road.vehicle_poses(drive.poses)
    poses = np.stack([planar_to_matrix(p) for p in drive.poses])
    if drive.attitude is not None:
        poses[:, :3, :3] = poses[:, :3, :3] @ Rotation.from_euler("YX", drive.attitude).as_matrix()
    return poses


def render_sample(name: str, frames: int | None = None, resolution=None, first: int = 0):
    """A sample rendered in memory (and the frame store, if set): ``(RenderedSample, iterator of
    (left, right, odometry or None))`` from the drive's frame ``first``, at ``(width, height)``."""
    sample = get_sample(name)
    if not 0 <= first < sample.frames:
        raise ValueError(f"first must lie in 0..{sample.frames - 1} for {name}; got {first}")
    n = sample.frames - first if frames is None else int(frames)
    if not 1 <= n <= sample.frames - first:
        raise ValueError(
            f"frames must lie in 1..{sample.frames - first} for {name} from frame {first}; got {frames}"
        )
    camera = sample_camera(sample, resolution)
    car = sample.rig == "car"
    odometry = road.CAR_ODOMETRY if car else TrackOdometry()
    rng = np.random.default_rng(sample.seed)
    drive = simulate_drive(sample.legs, sample.rate, sample.start, rng, odometry, sample.slip, sample.surface)
    mount = road.camera_in_vehicle() if car else camera_mount(height=CAMERA_HEIGHT)
    rendered = RenderedSample(camera, mount, drive, n, _world_poses(sample, drive), first)
    store = None  # the fingerprint is worked out only for a frame store
    if frame_store.FOLDER:
        key = f"{name}-{fingerprint(name)}-{camera.width}x{camera.height}-from{first}"
        store = Path(frame_store.FOLDER) / key
    effects = _sensor_effects(sample, first + n)
    return rendered, _frames(sample, rendered, effects, np.random.default_rng(sample.seed + 1), store)


def _frames(sample: Sample, rendered: RenderedSample, effects, image_rng, store: Path | None):
    """``(left, right, odometry or None)`` of each frame: from the frame store where it holds them,
    else rendered (and stored); ``image_rng`` as if every frame had been rendered."""
    renderer = None  # built at the first frame the store does not hold (textures take a second)
    first = rendered.first
    for k in range(first, first + rendered.frames):
        stored = frame_store.get(store, k) if store else None
        if stored:
            left, right, state = stored
            image_rng.bit_generator.state = state
        else:
            renderer = renderer or StereoRenderer(WORLDS[sample.world](), rendered.camera)
            renderer.effects = effects[k]
            left, right = renderer.render_pair(
                rendered.vehicle_poses[k] @ rendered.mount, image_rng, time=k / sample.rate
            )
            if store:
                frame_store.put(store, k, left, right, image_rng.bit_generator.state)
        yield left, right, (None if k == first else rendered.drive.odometry[k])


def is_indoor(name: str) -> bool:
    """Whether a sample's world has a ceiling (indoor) or open sky."""
    return WORLDS[get_sample(name).world]().ceiling_height is not None


def render_left_images(name: str, indices, resolution=None) -> list[np.ndarray]:
    """Left images of frames ``indices`` of a sample, rendered in memory with their sensor noise drawn
    afresh (seeded): they differ from the written sample's by the noise only."""
    sample = get_sample(name)
    rendered, _ = render_sample(name, None, resolution)
    renderer = StereoRenderer(WORLDS[sample.world](), rendered.camera)
    rng = np.random.default_rng(sample.seed + 2)
    cameras = rendered.camera_poses()
    effects = _sensor_effects(sample, sample.frames)
    return [
        effects[k].apply(renderer.render(cameras[k], time=k / sample.rate), rng) for k in map(int, indices)
    ]


def generate(
    name: str,
    out,
    frames: int | None = None,
    resolution: tuple[int, int] | None = None,
    progress: bool = True,
    force: bool = False,
) -> Path:
    """Render the first ``frames`` of sample ``name`` at ``(width, height)`` into ``out`` (``force``
    as :class:`~vo_lib.formats.sequence_writer.SequenceWriter` takes it); returns it.
    ``progress``: a tqdm bar (True), a line every :data:`PROGRESS_EVERY_S` seconds (``"lines"``),
    or nothing (False)."""
    sample = get_sample(name)
    rendered, frame_iter = render_sample(name, frames, resolution)
    camera, drive, n = rendered.camera, rendered.drive, rendered.frames
    with SequenceWriter(out, camera, force=force) as writer:
        for left, right, _ in _with_progress(frame_iter, n, f"rendering {name}", progress):
            writer.add(left, right)
        # a crawler's camera states its height; a car's where it sits in the car (no height_m)
        car = sample.rig == "car"
        rig = {"in_vehicle_m": list(road.CAMERA_IN_VEHICLE)} if car else {"height_m": CAMERA_HEIGHT}
        manifest = {
            "sample": name,
            "fingerprint": fingerprint(name),
            "purpose": sample.purpose,
            "mirrors": sample.mirrors,
            "world": sample.world,
            "frames": n,
            "frames_full": sample.frames,
            "rate_hz": sample.rate,
            "resolution": [camera.width, camera.height],
            "legs": [asdict(leg) for leg in sample.legs],
            "start_pose": list(sample.start),
            "camera": {
                **{key: getattr(camera, key) for key in ("fx", "fy", "cx", "cy", "baseline")},
                **rig,
                "mount": CAMERA_MOUNTS[car],
            },
            "track_odometry": asdict(road.CAR_ODOMETRY if car else TrackOdometry()),
            "slip": asdict(sample.slip),
            "surface": None if sample.surface is None else asdict(sample.surface),
            "sensor_noise_grey": sample.sensor_noise,
            "exposure_sigma": sample.exposure_sigma,
            "seed": sample.seed,
            "robot_poses": drive.poses[:n].tolist(),
        }
        cameras = rendered.camera_poses()
        poses = np.linalg.inv(cameras[0]) @ cameras  # camera k in camera 0's frame
        return writer.close(drive.times[:n], poses, drive.odometry[:n], manifest)


def _with_progress(frames, total: int, label: str, progress):
    """Yield ``frames``, showing progress as :func:`generate` describes."""
    if progress is True or not progress:  # a bar, or nothing
        yield from tqdm(frames, total=total, desc=label, unit="frame", disable=not progress)
        return
    print(f"{label}: {total} frames (the first takes longest: the world's textures are built)", flush=True)
    start = last = time.perf_counter()
    for done, item in enumerate(frames, 1):
        yield item
        now = time.perf_counter()
        if now - last >= PROGRESS_EVERY_S or done == total:
            left = (total - done) * (now - start) / done
            print(
                f"{label}: {done}/{total} frames, {now - start:.0f} s"
                + (f", about {left:.0f} s to go" if done < total else ", done"),
                flush=True,
            )
            last = now
