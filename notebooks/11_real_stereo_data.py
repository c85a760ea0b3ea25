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
# # 11 · Real stereo images and the front end they need
#
# Everything so far ran on images that `vo_lib` renders itself. Here the front end meets real
# recordings: KITTI raw drive 2011_09_26_0001, a car in a Karlsruhe suburb, and the Middlebury
# *Motorcycle* pair with ground-truth disparity (shipped by scikit-image). We look at what is
# different about real images, in numbers, and at the front end built for them: ORB corners in a
# pyramid, matched along rows, with sub-pixel disparities judged against ground truth and beside
# OpenCV's semi-global matcher. Notebook 12 then runs the motion estimation on the real drive.
#
# **You will learn**
# - how real images differ from rendered ones, in numbers (empty cells, corners, flat regions);
# - how a front end adapts to them (a FAST threshold lowered from frame to frame, a pyramid);
# - how accurate our sub-pixel disparities are on real images, beside OpenCV's semi-global matcher,
#   and where the tail of the error comes from (depth edges).
#
# **Prerequisites**: notebooks 04 and 05.
#
# **Run time**: about 10 seconds of computing on two cores (longer on a busy machine).
# The real recording is KITTI raw drive 2011_09_26_drive_0001 in the KITTI odometry layout with
# its `oxts.txt` and `raw_calib/` (see the README's "Real data"); it is not part of the repository:
# set `VO_LIB_REALDATA` to the folder that holds it. Without it the notebook says so and runs the
# same sections on the Motorcycle pair and a short rendered sample (rendered on first use).

# %% [markdown]
# **References**
#
# - X. Zhao, J. Kan, C. Zhan, *1-Point RANSAC Application: an Independent Positioning Method for
#   Crawler Mobile Robots Based on Binocular Stereo Vision* [Zhao]: §III.A, the front end, applied to
#   real images.
# - A. Geiger, P. Lenz, C. Stiller, R. Urtasun, *Vision meets Robotics: The KITTI Dataset*,
#   International Journal of Robotics Research, 2013: the raw drives and the odometry layout.
# - D. Scharstein et al., *High-Resolution Stereo Datasets with Subpixel-Accurate Ground Truth*,
#   GCPR 2014: the Motorcycle pair.

# %%
import math
import os
from pathlib import Path

import cv2
import matplotlib.pyplot as plt
import numpy as np
import skimage.data
from IPython.display import display
from scipy.ndimage import maximum_filter, minimum_filter

import vo_lib
from vo_lib.camera import StereoCamera
from vo_lib.data import load_sequence
from vo_lib.geometry import (
    planar_from_camera_poses,
    wrap_angle,
)
from vo_lib.stereo_vo.features import PATCH_HALF, StereoFrontEnd
from vo_lib.stereo_vo.pyramid_features import LEVELS, SCALE_FACTOR, PyramidFrontEnd
from vo_lib.stereo_vo.vehicle import vehicle_of
from vo_lib.viz.plotting import new_axes
from vo_lib.viz.prose import Markdown

SEED = 0
rng = np.random.default_rng(SEED)
cv2.setRNGSeed(SEED)
np.set_printoptions(precision=4, suppress=True)


def find_repo(start: Path) -> Path:
    """The folder holding ``vo_lib`` (the notebook runs in notebooks/, a script may run anywhere)."""
    for folder in (start, *start.parents):
        if (folder / "vo_lib").is_dir():
            return folder
    return Path(vo_lib.__file__).resolve().parents[1]


REPO = find_repo(Path.cwd())
REAL_ROOT = os.environ.get("VO_LIB_REALDATA", "")  # the folder of real sequences, if any
REAL_DIR = Path(REAL_ROOT) / "kitti_raw_2011_09_26_drive_0001"
REAL = bool(REAL_ROOT) and (REAL_DIR / "poses.txt").is_file()
rendered = load_sequence("indoor_linear", frames=60, progress=False)
if REAL:
    seq = load_sequence(REAL_DIR)
    print(f"real data: {REAL_DIR.name}, {len(seq)} frames of {seq.camera.width}x{seq.camera.height}")
else:
    seq = rendered
    print(
        f"real data not found (VO_LIB_REALDATA={REAL_ROOT!r} holds no {REAL_DIR.name}): the sections that "
        f"need it run on the rendered sample "
        f"{rendered.path.name} and on the Motorcycle pair instead"
    )
vehicle = vehicle_of(seq)
truth = planar_from_camera_poses(seq.poses, vehicle.mount)  # vehicle (x, y, yaw), frame 0 at the origin
travelled = float(np.sum(np.linalg.norm(np.diff(truth[:, :2], axis=0), axis=1)))
print(f"{vehicle.kind}: {travelled:.1f} m travelled; odometry from {vehicle.odometry_source}")


def final_errors(poses):
    """Final position error (m, and % of the distance so far) and heading error (deg) of planar poses."""
    n = len(poses)
    metres = float(np.linalg.norm(poses[-1, :2] - truth[n - 1, :2]))
    heading = math.degrees(wrap_angle(poses[-1, 2] - truth[n - 1, 2]))
    distance = float(np.sum(np.linalg.norm(np.diff(truth[:n, :2], axis=0), axis=1)))
    return metres, 100 * metres / distance, heading


# %% [markdown]
# ## 1 · Real images against ours
#
# Three numbers per image: the share of 16×16 cells without a single FAST corner at threshold 20,
# the number of corners scaled to a 640×480 image, and the share of pixels whose intensity
# gradient is below 8 grey levels per pixel (sky, road, plain walls, where no corner can be).

# %%
CELL = 16


def image_statistics(image, threshold=20, low_gradient=8.0):
    """Empty-cell share, corners per 640x480, low-gradient share and the occupancy grid."""
    h, w = image.shape
    keypoints = cv2.FastFeatureDetector_create(threshold, True).detect(image)
    corners = np.array([k.pt for k in keypoints]).reshape(-1, 2)
    occupied = np.zeros((h // CELL, w // CELL), bool)
    col, row = (corners // CELL).astype(int).T
    inside = (row < occupied.shape[0]) & (col < occupied.shape[1])
    occupied[row[inside], col[inside]] = True
    gradient = np.hypot(cv2.Sobel(image, cv2.CV_32F, 1, 0), cv2.Sobel(image, cv2.CV_32F, 0, 1)) / 8
    return {
        "empty": 1 - occupied.mean(),
        "per_vga": len(corners) * 640 * 480 / (h * w),
        "flat": float(np.mean(gradient < low_gradient)),
        "corners": corners,
        "occupied": occupied,
    }


moto_left, moto_right, moto_truth = skimage.data.stereo_motorcycle()
moto_left, moto_right = (cv2.cvtColor(x, cv2.COLOR_RGB2GRAY) for x in (moto_left, moto_right))
if REAL:
    real_name, real_images = "KITTI drive 0001", [seq.pair(k)[0] for k in range(0, len(seq), 10)]
else:
    real_name, real_images = "Motorcycle (left)", [moto_left]
rendered_images = [rendered.pair(k)[0] for k in range(0, len(rendered), 10)]
stats = {}
print(f" {'images':22s} {'empty 16x16 cells':>18s} {'corners per 640x480':>20s} {'low-gradient pixels':>20s}")
for name, images in ((real_name, real_images), ("rendered indoor_linear", rendered_images)):
    rows = [image_statistics(img) for img in images]
    stats[name] = {k: float(np.mean([r[k] for r in rows])) for k in ("empty", "per_vga", "flat")}
    s = stats[name]
    print(f" {name:22s} {s['empty']:18.1%} {s['per_vga']:20.0f} {s['flat']:20.1%}")
assert stats[real_name]["empty"] > 0.2  # a real frame leaves many cells without a corner
empty_real, empty_rendered = stats[real_name]["empty"], stats["rendered indoor_linear"]["empty"]
flat_real, flat_rendered = stats[real_name]["flat"], stats["rendered indoor_linear"]["flat"]


def show_corners(ax, image, title):
    """An image with its FAST corners and, shaded, the cells that have none."""
    st = image_statistics(image)
    ny, nx = st["occupied"].shape
    ax.imshow(image, cmap="gray")
    ax.imshow(~st["occupied"], cmap="Reds", alpha=0.35, vmin=0, vmax=1.5, extent=(0, nx * CELL, ny * CELL, 0))
    ax.plot(st["corners"][:, 0], st["corners"][:, 1], ".", ms=1, color="yellow")
    ax.set_xlim(0, image.shape[1])
    ax.set_ylim(image.shape[0], 0)
    ax.set_xlabel("u [px]")
    ax.set_ylabel("v [px]")
    ax.set_title(f"{title}: {st['empty']:.0%} of cells without a corner")


ratios = [img.shape[1] / img.shape[0] for img in (real_images[0], rendered_images[0])]
fig, axes = plt.subplots(1, 2, figsize=(3.2 * sum(ratios), 3.8), width_ratios=ratios, constrained_layout=True)
show_corners(axes[0], real_images[0], real_name)
show_corners(axes[1], rendered_images[0], "rendered")
plt.show()

# %%
similar_empty = abs(empty_real - empty_rendered) < 0.1  # "about as many": within ten points
more_flat = flat_real > flat_rendered
display(
    Markdown(
        f"A real frame leaves {empty_real:.1%} of its cells empty, the rendered frames "
        f"{empty_rendered:.1%}: "
        + ("about as many. " if similar_empty else "not the same share. ")
        + f"Its flat pixels ({flat_real:.1%} against {flat_rendered:.1%}) are "
        + ("more" if more_flat else "not more")
        + " of the image, and they come in large regions (sky, road) rather than spread out."
    )
)

# %% [markdown]
# A front end that takes the strongest corners of the whole image then crowds
# them into the textured parts (parked cars, trees), and one that takes a fixed number per cell
# gets none from the sky and the road. The pyramid front end
# (`vo_lib.stereo_vo.pyramid_features`) adapts instead: its FAST threshold is lowered from frame
# to frame while an image gives fewer corners than its budget, and the budget scales with the
# image area.
#
# ## 2 · The front end on real images: ORB in a pyramid, disparity to a fraction of a pixel
#
# The crawler's camera moves centimetres per frame; a car's moves a metre, so a wall ahead grows
# by several per cent between frames. `PyramidFrontEnd` finds FAST corners in an image pyramid
# (OpenCV's ORB; its levels and scale step are printed below), matches them along rows by Hamming
# distance with a ratio and a mutual check, and refines each disparity on the SAD cost of 7×7
# patches. Corners of an upper level sit on that level's coarser grid, so the whole-pixel
# disparity is searched ±2 px before the sub-pixel fit.
#
# The Motorcycle pair has ground-truth disparity (inf where unknown). We measure the error of
# every matched feature and, at the same pixels, that of OpenCV's semi-global block matcher.

# %%
h, w = moto_left.shape
moto_cam = StereoCamera(fx=700.0, fy=700.0, cx=w / 2, cy=h / 2, baseline=0.2, width=w, height=h)
sgbm = cv2.StereoSGBM_create(
    0, 64, 5, P1=8 * 25, P2=32 * 25, uniquenessRatio=10, mode=cv2.STEREO_SGBM_MODE_HH
)
sgbm_disp = sgbm.compute(moto_left, moto_right).astype(np.float64) / 16  # fixed point, 4 fraction bits


def disparity_errors(front_end):
    """Our |disparity error| and SGBM's at the same pixels, where both the truth and SGBM have one."""
    fw = front_end.process(moto_left, moto_right).w
    ui, vi = np.rint(fw[:, 0]).astype(int), np.rint(fw[:, 1]).astype(int)
    gt, sg = moto_truth[vi, ui], sgbm_disp[vi, ui]
    both = np.isfinite(gt) & (sg > 0)
    return len(fw), np.abs(fw[both, 2] - gt[both]), np.abs(sg[both] - gt[both]), fw[both]


print(f"pyramid: {LEVELS} levels, each {SCALE_FACTOR} times smaller than the one below")
front_ends = {
    "pyramid (ORB)": PyramidFrontEnd(moto_cam, max_disparity=70),
    "single scale (FAST)": StereoFrontEnd(moto_cam, max_disparity=70),
}
errors = {}
print(f" {'front end':24s} {'features':>8s} {'scored':>7s} {'ours: median':>13s} {'> 1 px':>7s}", end="")
print(f" {'SGBM: median':>13s}")
for name, fe in front_ends.items():
    n, ours, theirs, where = disparity_errors(fe)
    errors[name] = (ours, theirs, where)
    print(
        f" {name:24s} {n:8d} {len(ours):7d} {np.median(ours):10.3f} px {np.mean(ours > 1):7.1%}"
        f" {np.median(theirs):10.3f} px"
    )
ours, theirs, where = errors["pyramid (ORB)"]
assert len(ours) >= 100  # enough scored features for a median; the count is printed
assert np.median(ours) <= np.median(theirs)  # at least as accurate as SGBM at the same pixels
assert np.median(ours) <= np.median(errors["single scale (FAST)"][0])

fig, axes = new_axes(2, width=6, height=4)
axes[0].imshow(moto_left, cmap="gray")
sc = axes[0].scatter(where[:, 0], where[:, 1], c=np.minimum(ours, 1.0), s=8, cmap="viridis")
fig.colorbar(sc, ax=axes[0], label="|disparity error| [px] (clipped at 1)")
axes[0].set_xlabel("u [px]")
axes[0].set_ylabel("v [px]")
axes[0].set_title("Motorcycle: our matched features")
bins = np.linspace(0, 1.5, 31)
axes[1].hist(ours, bins, alpha=0.6, label=f"ours, median {np.median(ours):.2f} px")
axes[1].hist(theirs, bins, alpha=0.6, label=f"SGBM at the same pixels, median {np.median(theirs):.2f} px")
axes[1].set_xlabel("|disparity error| [px]")
axes[1].set_ylabel("features")
axes[1].set_title("Disparity error against ground truth")
axes[1].legend(fontsize="small")
plt.show()

# %% [markdown]
# Where is the tail of the histogram (the share above 1 px is printed)? A disparity is measured on
# a 7×7 patch; where the true disparity changes by more than 2 px inside that patch, the feature
# sits on a depth edge (the outline of the bike), and the patch mixes two depths.

# %%
known = np.isfinite(moto_truth)
size = 2 * PATCH_HALF + 1
spread = maximum_filter(np.where(known, moto_truth, -np.inf), size) - minimum_filter(
    np.where(known, moto_truth, np.inf), size
)
on_edge = spread[np.rint(where[:, 1]).astype(int), np.rint(where[:, 0]).astype(int)] > 2
for name, sel_edge in (("on depth edges", on_edge), ("elsewhere", ~on_edge)):
    e = ours[sel_edge]
    print(f"{name:15s}: {sel_edge.sum():4d} features, median {np.median(e):.3f} px, ", end="")
    print(f"{np.mean(e > 1):5.1%} above 1 px")
tail = ours > 1
print(f"of the {tail.sum()} features off by more than 1 px, {np.mean(on_edge[tail]):.0%} are on depth edges")
assert np.mean(on_edge[tail]) >= 0.8 and np.median(ours[~on_edge]) < 0.15

# %% [markdown]
# Nearly all of the tail is on depth edges, where a patch cannot have one disparity; elsewhere our
# disparities are good to about a tenth of a pixel. Such features give wrong 3-D points, which the
# temporal checks (1-point RANSAC, the 6-DoF refinement) must remove later.
#
# On the sequence itself: the number of stereo features per frame of both front ends.


# %%
counts = {name: [] for name in ("pyramid", "single scale")}
pyramid_fe, single_fe = PyramidFrontEnd(seq.camera), StereoFrontEnd(seq.camera)
for k in range(0, len(seq), max(1, len(seq) // 6)):
    left, right = seq.pair(k)
    counts["pyramid"].append(len(pyramid_fe.process(left, right)))
    counts["single scale"].append(len(single_fe.process(left, right)))
for name, c in counts.items():
    print(f"{name:13s} stereo features per frame: median {np.median(c):.0f} (min {min(c)}, max {max(c)})")
if REAL:
    assert np.median(counts["pyramid"]) > 2 * np.median(counts["single scale"])

# %% [markdown]
# ## Summary
#
# - Real frames leave a large share of their cells without a corner and most of their pixels flat;
#   a front end with a fixed threshold or a fixed grid either starves or crowds. The pyramid front
#   end adapts its threshold and finds corners at three scales, and its sub-pixel disparities on
#   the Motorcycle pair are at least as accurate as OpenCV's semi-global matcher at the same pixels.
# - The tail of the disparity error sits on depth edges, where a patch mixes two depths; such
#   features give wrong 3-D points that the temporal checks must remove (notebook 12).

# %% [markdown]
# ## Exercises
#
# Easy to hard, with the points each is worth. Each exercise asks for a function (the cell
# under it names it) and then uses it; the test cell after it checks both. The grader also
# calls your functions with inputs of its own, so an answer must compute, not quote a number.

# %% [markdown]
# ### Exercise 1 · a lower threshold *(easy, 2 points)*
#
# Write `empty_shares(image, thresholds)`: the share of the cells without a corner (section 1's
# `image_statistics`) of `image` at each FAST threshold of `thresholds`, as a list. Store the
# shares of the first real image of section 1 at thresholds 20 and 10 in `at_20, at_10`.
#
# *Hint:* `image_statistics(image, threshold=...)["empty"]`.


# %% nbgrader={"grade": false, "grade_id": "ex1", "locked": false, "schema_version": 3, "solution": true}
### BEGIN SOLUTION
def empty_shares(image, thresholds):
    """Share of the cells without a FAST corner at each threshold."""
    return [image_statistics(image, threshold=t)["empty"] for t in thresholds]


at_20, at_10 = empty_shares(real_images[0], [20, 10])
print(f"cells without a corner: {at_20:.1%} at threshold 20, {at_10:.1%} at threshold 10")
### END SOLUTION

# %% nbgrader={"grade": true, "grade_id": "ex1_test", "locked": true, "points": 2, "schema_version": 3, "solution": false}
# Exercise 1: autograder test
assert 0 <= at_10 < at_20 <= 1, "a lower threshold fills some cells, but the flat ones stay empty"
### BEGIN HIDDEN TESTS
import importlib  # noqa: E402

import vo_lib.grading  # noqa: E402

grading = importlib.reload(vo_lib.grading)  # fresh from its file, whatever the answer did to it


def hidden_test_ex1(grading, detector, answer):
    """A new image and thresholds at every grading. The expected shares are computed after the
    answer ran, from an image it gets a copy of, by the test's own count of section 1's cells
    (16 px), not by the notebook's image_statistics, which an answer cell can redefine."""
    import numpy as np

    grading.intact(globals())  # the answer left NumPy and vo_lib alone
    assert type(detector).__name__ == "builtin_function_or_method", "OpenCV's FAST detector was replaced"

    fresh = np.random.default_rng()
    texture = (fresh.random((240, 320)) * 255).astype(np.uint8)
    flat = np.zeros((240, 320), np.uint8)
    flat[:, : int(fresh.integers(40, 280))] = texture[:, :1]  # a flat part, a textured part
    image = grading.frozen(
        cv2.GaussianBlur(np.maximum(texture * (flat == 0), flat), (0, 0), fresh.uniform(0.5, 2.0))
    )
    thresholds = sorted(int(t) for t in fresh.integers(5, 60, 3))
    with grading.refused():  # nothing to refuse; no other process, no change to the grader's tools
        got = np.asarray(answer(image.copy(), list(thresholds)), float)
    grading.intact(globals())

    # the references only now: the answer, called above, could read its caller's frame
    def empty(image, threshold, cell=16):
        keypoints = detector(threshold, True).detect(image)
        corners = np.array([k.pt for k in keypoints]).reshape(-1, 2)
        occupied = np.zeros((image.shape[0] // cell, image.shape[1] // cell), bool)
        col, row = (corners // cell).astype(int).T
        inside = (row < occupied.shape[0]) & (col < occupied.shape[1])
        occupied[row[inside], col[inside]] = True
        return 1 - occupied.mean()

    assert np.isclose(at_20, empty(real_images[0], 20)) and np.isclose(at_10, empty(real_images[0], 10)), (
        "at_20, at_10: not the shares of the first real image"
    )
    assert np.allclose(got, [empty(image, t) for t in thresholds]), (
        "empty_shares differs on another image (the share of empty cells, at each threshold?)"
    )


hidden_test_ex1(grading, cv2.FastFeatureDetector_create, empty_shares)
### END HIDDEN TESTS
