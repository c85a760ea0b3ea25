# ---
# jupyter:
#   jupytext:
#     formats: py:percent
#   kernelspec:
#     display_name: Python 3 (ipykernel)
#     language: python
#     name: python3
# ---

# %% [markdown]
# # 04 · One world, several sensors: the simulated robot and its sample sequences
#
# The papers ran real robots; we cannot ship their data, and nothing may be downloaded at run
# time. So we build one simulated world and let every sensor look at it: a stereo camera for the
# visual odometry of [Zhao], a 2-D laser scanner for the line-feature SLAM of [Yan 2020] and the
# pose tracking of [Yuan], and the crawler's track encoders. This notebook shows the world, the
# rig, the drives that mirror the paper's experiments, and the sequence files they produce.
#
# **You will learn**
# - how a floor plan of line segments becomes textured 3-D planes, and why the textures are
#   built for corner detectors;
# - how a stereo pair is rendered with ground-truth depth, and that block matching on it recovers
#   the true disparity;
# - that the laser scanner and the camera agree, because they see the same world;
# - what track slip does to odometry in each sample, and what a sequence looks like on disk.
#
# **Prerequisites**: notebooks 01 (odometry and slip) and 03 (why the camera sits above the
# turning axis).
#
# **Run time**: about 10 seconds.

# %% [markdown]
# **References**
#
# - X. Zhao, J. Kan, C. Zhan, *1-Point RANSAC Application: an Independent Positioning Method for
#   Crawler Mobile Robots Based on Binocular Stereo Vision* [Zhao]: §IV, the indoor and
#   outdoor experiments the sample drives mirror.
# - R. Yuan, F. Zhang, Y. Zhu, Y. Fu, *A Novel Visual Odometer Assisted Pose Tracking Method for
#   Mobile Robots* [Yuan]: §IV, the occluded corridor.
# - E. Rosten, T. Drummond, *Machine learning for high-speed corner detection* [Rosten 2006]:
#   FAST, the corners the rendered textures must offer (notebook 05).
# - A. Geiger, P. Lenz, C. Stiller, R. Urtasun, *Vision meets Robotics: The KITTI Dataset*,
#   International Journal of Robotics Research, 2013: the raw drives and the odometry layout.

# %%
import vo_lib  # noqa: F401 (first: NumPy and OpenCV then use the same BLAS kernels on every CPU)

# isort: split
import tempfile
from pathlib import Path

import cv2
import numpy as np
from IPython.display import display

from vo_book.demo_worlds import view_from
from vo_book.nb04 import plot_drives, plot_frames, plot_scan, plot_spot_turn, plot_stereo_pair, plot_worlds
from vo_book.prose import Markdown
from vo_book.widgets import offer, slider
from vo_lib.camera import StereoCamera
from vo_lib.formats.sequence import read_sequence
from vo_lib.geometry import camera_mount, planar_to_matrix, wrap_angle
from vo_lib.models.track_odometry import TrackOdometry
from vo_lib.sim.laser import LaserScanner
from vo_lib.sim.render import StereoRenderer
from vo_lib.sim.samples import CAMERA_HEIGHT, SAMPLES, generate
from vo_lib.sim.trajectories import simulate_drive
from vo_lib.sim.world import WORLDS

SEED = 4
rng = np.random.default_rng(SEED)
np.set_printoptions(precision=4, suppress=True)

# %% [markdown]
# ## 1 · The world
#
# A world is a list of vertical segments on a floor plan — walls, pillars, boxes — each with a
# height and a texture seed, plus a textured floor (and a ceiling indoors). The worlds: a lab (once
# more with a trolley pushed through it), an open yard with far buildings (low parallax, as
# outdoors in [Zhao]), the corridor of [Yuan] with its pillars, cross walls, fire hydrant, and
# an **unmapped** umbrella (dashed) that the laser will see but the map does not know, and a road
# for a car, laid along the car's drive (its surface and its traffic are seen by the camera only,
# so the plan shows the buildings, trees, fences and parked cars beside it).

# %%
worlds = {name: make() for name, make in WORLDS.items()}
plot_worlds(worlds)
for world in worlds.values():
    print(
        f"{world.name:13s} {len(world.segments):3d} segments, floor {world.floor_extent}, "
        f"ceiling {world.ceiling_height}"
    )

# %% [markdown]
# ## 2 · The rig and a stereo pair
#
# The camera is like the paper's Bumblebee2: 640×480, the largest of the resolutions the paper times
# (Table 1; it states no native resolution); a 66° horizontal field of view and a 12 cm baseline,
# which the paper does not give, are our choice, those of a common Bumblebee2 model. It is mounted
# 0.5 m up, looking forward, above the turning axis. The renderer maps each textured plane into the
# image with one homography and keeps the nearest surface per pixel in an inverse-depth buffer,
# which doubles as ground truth.

# %%
camera = StereoCamera.bumblebee2()
mount = camera_mount(height=CAMERA_HEIGHT)
lab_renderer = StereoRenderer(worlds["indoor_lab"], camera)
pose = np.array([-3.0, 0.3, np.radians(10)])
left, right, depth = lab_renderer.render_pair(planar_to_matrix(pose) @ mount, rng, with_depth=True)
true_disparity = camera.fx * camera.baseline / depth

sgbm = cv2.StereoSGBM_create(0, 64, 5, P1=200, P2=800, uniquenessRatio=5, mode=cv2.STEREO_SGBM_MODE_HH)
measured = sgbm.compute(left, right).astype(np.float32) / 16
textured = (np.abs(cv2.Sobel(left, cv2.CV_32F, 1, 0, ksize=3)) > 20) & (measured > 0) & np.isfinite(depth)
textured[:, :64] = False
err = np.abs(measured - true_disparity)[textured]

plot_stereo_pair(left, true_disparity, (measured - true_disparity)[textured])
print(
    f"{textured.sum()} textured pixels: median |error| {np.median(err):.3f} px, "
    f"{np.mean(err < 0.5):.1%} within 0.5 px"
)

# %% [markdown]
# Block matching recovers the rendered geometry to a fraction of a pixel: the images are
# consistent with their ground truth, so later notebooks can measure feature matching and
# motion estimation against it.
#
# ## 3 · The laser scanner sees the same world
#
# The scanner (270°, 1/3° steps, 10 m: the field and range of the SICK TIM551 that [Yuan] names,
# at a finer step than the TIM551's 1°, which notebook 10 uses) casts 811 rays against
# the same segments. Straight ahead, the beam leaves from the point below the camera; at the
# image row of the camera's own height, the rendered depth of that column is the same distance.

# %%
scanner = LaserScanner(range_sigma=0.0, max_range=30.0)  # longer than 10 m: no wall is cut off
scan = scanner.scan(worlds["indoor_lab"].segments_array(), pose)
ahead = int(np.argmin(np.abs(scan.bearings)))
col, row = int(round(camera.cx)), int(round(camera.cy))
pixel_width = depth[row, col] / camera.fx  # the width of wall one pixel covers at that range
print(
    f"laser straight ahead: {scan.ranges[ahead]:.4f} m; rendered depth at the image centre: "
    f"{depth[row, col]:.4f} m; one pixel covers {pixel_width * 100:.2f} cm of wall there"
)

noisy = LaserScanner(range_sigma=0.01).scan(worlds["indoor_lab"].segments_array(), pose, rng)
pts = noisy.points()
c, s = np.cos(pose[2]), np.sin(pose[2])
world_pts = pts @ np.array([[c, s], [-s, c]]) + pose[:2]  # from the scanner's frame into the world's
plot_scan(worlds["indoor_lab"], pose, world_pts)

# %% [markdown]
# ## 4 · Drives that mirror the paper's experiments
#
# Each sample sequence is a world, a drive and a rate. A drive is a list of legs (frames, speed,
# turn rate) that the robot follows over the ground; the encoders count what the motors turned,
# which is more than the ground moved by the track slip (`vo_lib.sim.trajectories.SlipModel`: a
# small mean when driving, a larger one, unequal between the tracks, when turning on the spot;
# section 5 prints what it does to the odometry). The crawler also skids sideways in its
# turns and, on the yard's rough ground, briefly loses track contact while its body pitches and
# rolls (`vo_lib.sim.trajectories.TrackGround`); the encoders see none of that.
#
# The paper gives neither the rate at which its camera recorded nor the speeds and turn rates of
# its runs (its thirty frames per second is how fast it processed them). The rate, speeds and turn
# rates of every drive below are our choices, so where notebook 08 runs the paper's numbers of
# frames, the distances and turns they cover are ours too.

# %%
odometry = TrackOdometry()
drives, rows = {}, []
for name, sample in SAMPLES.items():
    drive = simulate_drive(
        sample.legs,
        sample.rate,
        sample.start,
        np.random.default_rng(sample.seed),
        slip=sample.slip,
        surface=sample.surface,
    )
    believed = odometry.integrate(drive.odometry[1:], start=sample.start)
    drives[name] = (drive, believed)
    rows.append(
        (
            name,
            sample.frames,
            np.linalg.norm(believed[-1, :2] - drive.poses[-1, :2]),
            np.degrees(wrap_angle(believed[-1, 2] - drive.poses[-1, 2])),
        )
    )
plot_drives(worlds, drives, SAMPLES)
print(" sample           frames   odometry end error [m]   heading error [deg]")
for name, frames, pos_err, head_err in rows:
    print(f" {name:15s} {frames:6d}   {pos_err:22.2f}   {head_err:19.1f}")
spot_heading_error = abs(dict((r[0], r[3]) for r in rows)["spot_turn"])
corridor_error = dict((r[0], r[2]) for r in rows)["corridor"]
corridor_length = np.sum(np.linalg.norm(np.diff(drives["corridor"][0].poses[:, :2], axis=0), axis=1))
spot_total_turn = np.degrees(np.abs(np.unwrap(drives["spot_turn"][0].poses[:, 2])[-1]))

# %% [markdown]
# ## 5 · Track slip, made visible

# %%
display(
    Markdown(
        f"In the spot turn the robot turns {spot_total_turn:.0f}° on the spot; the encoders "
        "over-count by the slip and the odometry's heading runs ahead of the truth — "
        f"{spot_heading_error:.0f}° by the end. In the corridor the small left/right slip "
        f"difference bends the believed path, {corridor_error:.1f} m off after {corridor_length:.0f} m."
    )
)

# %%
spot, spot_believed = drives["spot_turn"]
plot_spot_turn(spot.times, spot.poses[:, 2], spot_believed[:, 2], spot.slip)
over_count = (np.unwrap(spot_believed[:, 2])[-1] - spot_believed[0, 2]) / (
    np.unwrap(spot.poses[:, 2])[-1] - spot.poses[0, 2]
)
print(f"odometry turned {over_count:.3f} times the true angle")

# %% [markdown]
# ## 6 · A sequence on disk
#
# `python -m vo_lib generate NAME` (or `vo_lib.data.load_sequence(NAME)`) renders a sample into the
# KITTI odometry layout, plus our `odometry.txt` and a `manifest.json`. We write five frames of
# the corridor at 320×240 into a temporary folder and read them back.

# %%
with tempfile.TemporaryDirectory() as tmp:
    path = generate("corridor", Path(tmp) / "corridor", frames=5, resolution=(320, 240), progress=False)
    print(sorted(p.name for p in path.iterdir()))
    print((path / "calib.txt").read_text())
    seq = read_sequence(path)
    print(f"{len(seq)} frames, camera {seq.camera}, rate {seq.manifest['rate_hz']} Hz")
    print("first odometry rows (left, right track distance, m):\n", seq.odometry[:3])
# What is read back is what the simulation made (the encoders' readings, the rig at half the
# resolution, the images): the notebook tests write and read the same five frames and compare.

# %% [markdown]
# ## 7 · Walk through the world
#
# `view_from` renders the left image and the depth at any pose of any world, and draws the laser
# scan there. Try the corridor near the umbrella (x ≈ 11, y = 0): the camera sees it, and the laser
# loses the second pillar behind it.


# %%
beams = view_from()

# %%
walk_widget = offer(
    view_from,
    world_name=list(worlds),
    x=slider(11.0, -40.0, 40.0, 0.25, "x [m]"),
    y=slider(0.0, -40.0, 40.0, 0.25, "y [m]"),
    yaw_deg=slider(0.0, -180.0, 180.0, 5.0, "yaw [deg]"),
)

# %% [markdown]
# ## 8 · Real images are harder
#
# A rendered frame and a real one, side by side, with three numbers that say how hard an image is
# for a corner-based front end (`vo_lib.sim.realism`): the share of 16×16-pixel cells holding no
# FAST corner, the FAST corners per 640×480 pixels, and the share of flat pixels (Sobel gradient
# below 20). The rendered frame is from the road drive, whose renderer was tuned toward these
# numbers on KITTI raw drive 2011_09_26_0001 (`vo_lib.sim.realism`); one frame of each is
# compared. The real frame is the middle one of the first KITTI-layout sequence in the folder
# named by the environment variable
# `VO_LIB_REALDATA`; without it, only the rendered frame is shown. If that sequence is drive 0001
# itself, as it is in this project's development data, the comparison below is made on the data
# the renderer was tuned to: it shows how close the tuning came, not how the renderer generalises.
# The printed title names the sequence.

# %%
import os

from vo_lib.sim.realism import image_statistics
from vo_lib.sim.samples import render_left_images

ROAD_FRAME = 60
shown = [(f"rendered: road_drive, frame {ROAD_FRAME}", render_left_images("road_drive", [ROAD_FRAME])[0])]
real_root = Path(os.environ.get("VO_LIB_REALDATA") or "no-real-data")
real_folders = (
    sorted(p for p in real_root.iterdir() if (p / "image_0").is_dir()) if real_root.is_dir() else []
)
if real_folders:
    real_seq = read_sequence(real_folders[0], odometry=False)
    shown.append(
        (f"real: {real_folders[0].name}, frame {len(real_seq) // 2}", real_seq.pair(len(real_seq) // 2)[0])
    )
else:
    print("no real frame: set VO_LIB_REALDATA to a folder of KITTI-layout sequences to see one here")
frame_stats = {title: image_statistics(image) for title, image in shown}
plot_frames(shown, frame_stats)
road_stats = frame_stats[shown[0][0]]

# %%
if len(shown) == 2:
    real_stats = frame_stats[shown[1][0]]
    gaps = {
        "cells without a corner": (road_stats.empty_cells, real_stats.empty_cells),
        "flat pixels": (road_stats.low_gradient, real_stats.low_gradient),
    }
    corners = (road_stats.corners_per_vga, real_stats.corners_per_vga)
    # within a tenth on both shares, and within a quarter in corners
    alike = all(abs(a - b) < 0.1 for a, b in gaps.values()) and 0.8 < corners[0] / corners[1] < 1.25
    verdict = "look alike" if alike else "differ"
    tuned_on = "2011_09_26_drive_0001" in real_folders[0].name  # the drive the renderer was tuned to
    display(
        Markdown(
            f"On these numbers the two {verdict}: "
            + "; ".join(f"{k} {a:.2f} rendered, {b:.2f} real" for k, (a, b) in gaps.items())
            + f"; corners per 640×480 {corners[0]:,.0f} rendered, {corners[1]:,.0f} real (one frame of "
            "each). Sky and road leave cells empty and pixels flat in both. "
            + (
                "This real frame is from the drive the renderer was tuned on, so this says how close "
                "the tuning came, not how the renderer generalises."
                if tuned_on
                else "This real drive was not used to tune the renderer."
            )
        )
    )
else:
    display(
        Markdown(
            "No real frame is shown, so this run cannot compare them: set `VO_LIB_REALDATA` to a "
            "folder of KITTI-layout sequences to see one."
        )
    )

# %% [markdown]
# What the numbers do not show is why real images are still harder:
#
# - **the camera**: the renderer is a perfect pinhole with exact rectification; a real rig has
#   residual lens distortion, a calibration error of a fraction of a pixel that biases every
#   depth, vignetting, and a rolling or not quite simultaneous exposure of the two cameras;
# - **light**: rendered surfaces are matte and lit the same from every side; real ones reflect
#   (car paint, windows, wet road), cast shadows that move with the car, and flare in the sun, so
#   a corner can look different from the next frame and from the other camera;
# - **what moves**: here three boxes drive along the road; real scenes have cyclists, people,
#   swaying trees and shadows of clouds, often filling much of the view;
# - **structure**: rendered walls are exact planes with textures that repeat only where we tiled
#   them; real fences, windows and lane markings repeat with no pattern a matcher can rely on, and
#   foliage has corners at every scale that change with the viewpoint.

# %% [markdown]
# ## Summary
#
# - One floor plan of segments feeds the renderer, the laser scanner and (later) the SLAM and
#   pose-tracking notebooks; the sensors agree where they look at the same surface.
# - Rendered stereo pairs are consistent with their ground-truth depth to a fraction of a pixel.
# - The samples mirror the paper's experiments; track slip makes odometry drift in every one of
#   them (section 4's table). In the spot turn the encoders over-count the turn by the slip, so
#   the odometry's heading runs ahead of the truth; the rendered sequences carry that error for
#   vision to correct. (Which sample drifts most is one draw of each, and this notebook does not
#   rank them.)
# - Sequences are stored in the KITTI layout, so the same code reads real KITTI data.

# %% [markdown]
# ## Exercises
#
# Easy to hard, with the points each is worth. Each exercise asks for a function (the cell
# under it names it) and then uses it; the test cell after it checks both. The grader also
# calls your functions with inputs of its own, so an answer must compute, not quote a number.

# %% [markdown]
# ### Exercise 1 · depth from disparity *(easy, 2 points)*
#
# A stereo matcher reads every disparity too small by a fixed number of pixels, so every depth
# comes out too large. Write `depth_error(z, disparity_error, camera)`: by how many metres the
# depth of a point at true depth `z` comes out too large when the disparity reads
# `disparity_error` pixels too small (exactly, not to first order). Store it for 0.25 px and
# the `camera` of section 2 at 2 m and at 10 m in `depth_error_2m` and `depth_error_10m`.
#
# *Hint:* z = f_x B / d; `camera.depth_from_disparity`.


# %% nbgrader={"grade": false, "grade_id": "ex1", "locked": false, "schema_version": 3, "solution": true}
### BEGIN SOLUTION
def depth_error(z, disparity_error, camera):
    """Depth error (m) at true depth ``z`` of a disparity ``disparity_error`` px too small (eq. 13)."""
    d = camera.fx * camera.baseline / z
    return float(camera.depth_from_disparity(d - disparity_error) - z)


depth_error_2m, depth_error_10m = depth_error(2.0, 0.25, camera), depth_error(10.0, 0.25, camera)
print(f"0.25 px of disparity: {depth_error_2m * 100:.2f} cm at 2 m, {depth_error_10m * 100:.1f} cm at 10 m")
### END SOLUTION

# %% nbgrader={"grade": true, "grade_id": "ex1_test", "locked": true, "points": 2, "schema_version": 3, "solution": false}
# Exercise 1: autograder test
first_order = 0.25 / (camera.fx * camera.baseline)  # dz = z^2 dd / (f B)
assert np.isclose(depth_error_2m, 4 * first_order, rtol=0.05), "at 2 m: about z² dd / (f_x B)"
assert np.isclose(depth_error_10m, 100 * first_order, rtol=0.15), "the error grows with z²"
### BEGIN HIDDEN TESTS
import numpy as np

from coursework import grading  # noqa: E402

_h41_cam = StereoCamera(fx=650.0, fy=500.0, cx=320.0, cy=240.0, baseline=0.3)  # f_x B = 195 px m
_h41_z, _h41_dd = np.random.default_rng(4011).uniform([1.0, 0.05], [20.0, 1.0], (10, 2)).T
_h41_got = [depth_error(z, dd, _h41_cam) for z, dd in zip(_h41_z, _h41_dd, strict=True)]
assert grading.close(_h41_got, 195 / (195 / _h41_z - _h41_dd) - _h41_z, rtol=1e-6), "not the exact error"
### END HIDDEN TESTS

# %% [markdown]
# ### Exercise 2 · a laser ahead of the axis *(medium, 3 points)*
#
# A scanner mounted at `mount` = (x, y, yaw) in the robot frame (x forward, y left, origin at
# the robot's centre, yaw counter-clockwise) returns echoes in its own frame. Write
# `to_robot_frame(points, mount)` returning the points `(K, 2)` in the robot frame, with NumPy
# alone (no function of `vo_lib`, whose pose helpers do it). Then mount the scanner 0.3 m ahead
# of the robot's centre (`LaserScanner(range_sigma=0.0, max_range=30.0, mount=(0.3, 0.0, 0.0))`),
# scan the lab from `pose`, and store every echo in the robot frame in `robot_points`.
#
# *Hint:* `scan.points()` are in the sensor's frame; rotate by the yaw, then shift.


# %% nbgrader={"grade": false, "grade_id": "ex2", "locked": false, "schema_version": 3, "solution": true}
### BEGIN SOLUTION
def to_robot_frame(points, mount):
    """Points ``(K, 2)`` of a sensor mounted at ``mount`` = (x, y, yaw), in the robot frame."""
    x, y, yaw = mount
    rotation = np.array([[np.cos(yaw), -np.sin(yaw)], [np.sin(yaw), np.cos(yaw)]])
    return np.asarray(points, float) @ rotation.T + np.array([x, y])


front_mount = (0.3, 0.0, 0.0)
front_scan = LaserScanner(range_sigma=0.0, max_range=30.0, mount=front_mount).scan(
    worlds["indoor_lab"].segments_array(), pose
)
robot_points = to_robot_frame(front_scan.points(), front_mount)
### END SOLUTION

# %% nbgrader={"grade": true, "grade_id": "ex2_test", "locked": true, "points": 3, "schema_version": 3, "solution": false}
# Exercise 2: autograder test: every echo, carried into the world, lies on a wall
walls = worlds["indoor_lab"].segments_array()  # rows (x1, y1, x2, y2)


def gap_to_walls(points_robot, robot_pose):
    """Distance of every point (robot frame) from the nearest wall of the lab."""
    cos_yaw, sin_yaw = np.cos(robot_pose[2]), np.sin(robot_pose[2])
    on_map = points_robot @ np.array([[cos_yaw, sin_yaw], [-sin_yaw, cos_yaw]]) + robot_pose[:2]
    wall_start, wall_end = walls[None, :, :2], walls[None, :, 2:]
    span = wall_end - wall_start
    along = np.clip(np.sum((on_map[:, None] - wall_start) * span, -1) / np.sum(span**2, -1), 0, 1)
    return np.linalg.norm(on_map[:, None] - (wall_start + along[..., None] * span), axis=-1).min(axis=1)


assert robot_points.shape[1] == 2 and len(robot_points) > 400, "one (x, y) per echo"
assert gap_to_walls(robot_points, pose).max() < 1e-6, "an echo carried into the world misses the walls"


### BEGIN HIDDEN TESTS
import numpy as np

import vo_lib  # noqa: F811
from coursework import grading
from vo_lib import geometry as geometry_module

_h42 = np.random.default_rng(4021)
_h42_points, _h42_mount = _h42.uniform(-10, 10, (50, 2)), _h42.uniform([-0.4, -0.3, -3], [0.4, 0.3, 3])
with grading.unavailable(*grading.library_functions(vo_lib)):  # the SLAM's inverse observation too
    _h42_got = to_robot_frame(_h42_points.copy(), tuple(_h42_mount))
_h42_expected = geometry_module.compose_planar(_h42_mount, np.column_stack([_h42_points, np.zeros(50)]))
assert grading.close(_h42_got, _h42_expected[:, :2]), "not the echoes of a turned and shifted scanner"
_h42_scan = LaserScanner(range_sigma=0.0, max_range=30.0, mount=(0.3, 0.0, 0.0)).scan(walls, pose)
assert grading.close(robot_points, _h42_scan.points() + [0.3, 0.0]), "robot_points: the scanner 0.3 m ahead?"
### END HIDDEN TESTS

# %% [markdown]
# ### Exercise 3 · the laser and the camera agree everywhere *(hard, 4 points)*
#
# Section 3 compared one beam with one pixel. Compare every beam of `scan` (the on-axis scanner)
# that falls inside the image. Write `beam_in_image(ranges, bearings, camera)` returning two
# arrays: each beam's depth z in the camera's frame and the (not rounded) image column u it falls
# on at the row of the camera's height. Then store, for every valid beam whose column lies in
# the image, the absolute differences of its z from the rendered `depth` there in `depth_gaps`
# (metres, one per such beam).
#
# *Hint:* a beam's bearing is counter-clockwise (to the left), the image's u grows to the right;
# z = r cos(bearing).


# %% nbgrader={"grade": false, "grade_id": "ex3", "locked": false, "schema_version": 3, "solution": true}
### BEGIN SOLUTION
def beam_in_image(ranges, bearings, camera):
    """Depth z and image column u of laser beams in the plane of the camera's optical axis."""
    ranges, bearings = np.asarray(ranges, float), np.asarray(bearings, float)
    return ranges * np.cos(bearings), camera.cx - camera.fx * np.tan(bearings)


z_all, u_beam = beam_in_image(scan.ranges, scan.bearings, camera)
in_view = (np.abs(scan.bearings) < np.radians(80)) & (u_beam >= 0) & (u_beam <= camera.width - 1) & scan.valid
depth_gaps = np.abs(z_all[in_view] - depth[int(round(camera.cy)), np.round(u_beam[in_view]).astype(int)])
print(f"{len(depth_gaps)} beams in view: median gap {np.median(depth_gaps) * 1000:.1f} mm")
### END SOLUTION

# %% nbgrader={"grade": true, "grade_id": "ex3_test", "locked": true, "points": 4, "schema_version": 3, "solution": false}
# Exercise 3: autograder test
field_of_view = 2 * np.arctan(camera.width / 2 / camera.fx)
assert abs(len(depth_gaps) - field_of_view / np.radians(1 / 3)) < 5, "every beam in view, once"
assert np.median(depth_gaps) < 0.005 and np.percentile(depth_gaps, 90) < 0.03, "laser and camera disagree"
# the gaps are those of the beams beam_in_image places in the image (quartiles to 0.1 mm)
_z, _u = beam_in_image(scan.ranges, scan.bearings, camera)
_seen = scan.valid & (_z > 0) & (_u > -0.5) & (_u < camera.width - 0.5)
_gaps = np.abs(_z[_seen] - depth[round(camera.cy), np.round(_u[_seen]).astype(int)])
_quartiles = np.percentile(_gaps, [25, 50, 75])
assert np.allclose(np.percentile(depth_gaps, [25, 50, 75]), _quartiles, atol=1e-4), "not these beams' gaps"
### BEGIN HIDDEN TESTS
import numpy as np

from coursework import grading  # noqa: E402

_h43_cam = StereoCamera(fx=610.0, fy=500.0, cx=290.0, cy=240.0, baseline=0.12)
_h43_range, _h43_bearing = np.random.default_rng(4031).uniform([0.5, -1.0], [30.0, 1.0], (50, 2)).T
_h43_z, _h43_u = beam_in_image(_h43_range.copy(), _h43_bearing.copy(), _h43_cam)
assert grading.close(_h43_z, _h43_range * np.cos(_h43_bearing)), "not the depth along the optical axis"
assert grading.close(_h43_u, 290.0 - 610.0 * np.tan(_h43_bearing)), "not the column of another camera's image"
### END HIDDEN TESTS

# %% [markdown]
# ### Stretch goals (not graded)
#
# - Raise the texture's block sizes (`vo_lib.sim.textures.BLOCK_LAYERS`) and count FAST corners
#   on a wall at 1, 5 and 15 m. Which block size serves which distance?
# - Write a sample of your own, a figure-eight in the lab, and check that it stays clear of the
#   walls.
