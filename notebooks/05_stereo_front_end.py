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
# # 05 · The stereo front end: FAST corners, binary descriptors, matching along rows
#
# Before any motion can be estimated, each stereo pair must become a list of points with a pixel
# position and a disparity, w = (u, v, d). [Zhao] detects corners with FAST and matches them by
# Hamming distance. This notebook builds that front end step by step on a rendered pair whose
# true disparity we know, and measures each step.
#
# **You will learn**
# - how a stereo pair gives depth (triangulation), why rectified pairs are matched along rows
#   (epipolar lines), and how the depth error grows with depth;
# - how FAST finds corners, and why they are spread over the image by grid bucketing;
# - what a binary descriptor is, and why the Hamming distance separates true from false matches;
# - how rectification turns stereo matching into a search along one row, and how an equiangular
#   (V-shaped) fit to the matching cost gives sub-pixel disparity;
# - what each stage costs in time at 640×480.
#
# **Prerequisites**: notebook 04 (the rendered world and its ground truth).
#
# **Run time**: about 15 seconds.

# %% [markdown]
# **References**
#
# - X. Zhao, J. Kan, C. Zhan, *1-Point RANSAC Application: an Independent Positioning Method for
#   Crawler Mobile Robots Based on Binocular Stereo Vision* [Zhao]: §III.A.1, binocular stereo
#   processing (FAST corners, Hamming matching).
# - E. Rosten, T. Drummond, *Machine learning for high-speed corner detection* [Rosten 2006]: FAST.
# - E. Rublee, V. Rabaud, K. Konolige, G. Bradski, *ORB: an efficient alternative to SIFT or SURF*
#   [Rublee 2011]: the rotated binary descriptor (rBRIEF) matched by Hamming distance.

# %%
import vo_lib  # noqa: F401 (first: NumPy and OpenCV then use the same BLAS kernels on every CPU)

# isort: split
import math
import time

import cv2
import numpy as np
from IPython.display import display

from vo_book.demo_front_end import front_end_on
from vo_book.nb05 import (
    cells_covered,
    matching_rows,
    plot_corner_sets,
    plot_depth_error,
    plot_disparity_errors,
    plot_epipolar_lines,
    plot_hamming,
)
from vo_book.prose import Markdown
from vo_book.widgets import offer, slider
from vo_lib.camera import StereoCamera
from vo_lib.comparison import Verdict, over_seeds
from vo_lib.geometry import camera_mount, planar_to_matrix
from vo_lib.sim.render import SensorEffects, StereoRenderer
from vo_lib.sim.world import indoor_lab
from vo_lib.stereo_vo.features import ROW_TOLERANCE, StereoFrontEnd, bucket, hamming

SEED = 5
rng = np.random.default_rng(SEED)
np.set_printoptions(precision=3, suppress=True)

camera = StereoCamera.bumblebee2()
renderer = StereoRenderer(indoor_lab(), camera, SensorEffects(noise_sigma=1.0))
pose = planar_to_matrix((-3.0, 0.3, 0.2)) @ camera_mount(height=0.5)
left, right, depth = renderer.render_pair(pose, rng, with_depth=True)
true_disparity = camera.fx * camera.baseline / depth

# %% [markdown]
# ## 0 · Stereo geometry: a primer
#
# **Triangulation.** Two pinhole cameras with the same intrinsics (focal lengths f_x, f_y,
# principal point (u₀, v₀)) look the same way, the right one B metres to the right of the left.
# A point at depth Z appears in the right image shifted left by the *disparity*
# d = u − u_r = f_x B / Z, so from (u, v, d) the point is ([Zhao], eq. 13, which has one focal
# length f; here generalised to f_x ≠ f_y)
#
#   X = B (u − u₀)/d,   Y = B (v − v₀)/d · f_x/f_y,   Z = f_x B / d.
#
# The renderer gives the true depth of every pixel of the pair above; triangulating its true
# disparity gives that depth back:

# %%
rows_px, cols_px = np.mgrid[40:480:80, 40:640:80]
w_true = np.column_stack([cols_px.ravel(), rows_px.ravel(), true_disparity[rows_px, cols_px].ravel()])
points_true = camera.backproject(w_true)
assert np.allclose(points_true[:, 2], depth[rows_px, cols_px].ravel(), rtol=1e-6)  # depth is float32
print(f"{len(w_true)} pixels: depths {points_true[:, 2].min():.2f}–{points_true[:, 2].max():.2f} m recovered")

# %% [markdown]
# **Rectification and epipolar lines.** For a pixel of the left image, its match in the right one
# must lie on a line, the *epipolar line*: the image of the left pixel's ray. It follows from the
# fundamental matrix F = K⁻ᵀ [t]ₓ R K⁻¹ of the rig (R and t take left-camera points to the right
# camera; K holds the intrinsics): a match x′ of x satisfies x′ᵀ F x = 0. When the two image
# planes are coplanar and their rows aligned — a *rectified* pair, what calibration and
# resampling make of a real rig, and what our renderer produces — every epipolar line is the
# image row of its pixel, and matching becomes a search along one row (section 3). A right
# camera pitched by only 1° tilts and shifts them:

# %%
K = np.array([[camera.fx, 0, camera.cx], [0, camera.fy, camera.cy], [0, 0, 1]])
K_inv = np.linalg.inv(K)
t_rig = np.array([-camera.baseline, 0.0, 0.0])  # x_right = R x_left + t: the right camera is B to the right
t_cross = np.array([[0, -t_rig[2], t_rig[1]], [t_rig[2], 0, -t_rig[0]], [-t_rig[1], t_rig[0], 0]])  # [t]x
pitch_1deg = cv2.Rodrigues(np.array([math.radians(1.0), 0.0, 0.0]))[0]
# the fundamental matrix F = K^-T [t]x R K^-1 of each rig
rigs = {"rectified": np.eye(3), "right camera pitched 1°": pitch_1deg}
rigs = {name: K_inv.T @ t_cross @ R @ K_inv for name, R in rigs.items()}
probe = np.array([[100.0, 80.0, 1], [320.0, 240.0, 1], [540.0, 400.0, 1], [200.0, 420.0, 1]])
# each probe pixel's line F x: (a, b, c) of the line a u' + b v' + c = 0 in the right image
epipolar = {name: probe @ F.T for name, F in rigs.items()}
plot_epipolar_lines(epipolar, probe, camera.width, camera.height)
lines_rect = epipolar["rectified"]
lines_tilt = epipolar["right camera pitched 1°"]
row_offset = np.abs(-(lines_tilt[:, 0] * probe[:, 0] + lines_tilt[:, 2]) / lines_tilt[:, 1] - probe[:, 1])
assert np.allclose(lines_rect[:, 0], 0) and np.allclose(-lines_rect[:, 2] / lines_rect[:, 1], probe[:, 1])
display(
    Markdown(
        f"In the rectified rig each epipolar line is its pixel's row; with the right camera pitched by "
        f"1° the match of a pixel lies {row_offset.min():.1f}–{row_offset.max():.1f} px off that row, "
        f"far beyond the ±{ROW_TOLERANCE:.0f} px of rows the front end searches (section 3)."
    )
)

# %% [markdown]
# **Disparity against depth, and how its error grows.** Depth is inversely proportional to
# disparity, so a fixed disparity error σ_d costs more the farther the point:
# σ_Z ≈ |∂Z/∂d| σ_d = Z² σ_d / (f_x B), quadratic in depth. With our rig and σ_d = 0.5 px, the
# formula against a Monte Carlo of noisy disparities:

# %%
SIGMA_D = 0.5  # px
depths_m = np.array([1.0, 2.0, 5.0, 10.0, 20.0])
predicted = depths_m**2 * SIGMA_D / (camera.fx * camera.baseline)
mc_rng = np.random.default_rng(SEED)
measured_sd = np.array(
    [
        np.std(
            camera.fx
            * camera.baseline
            / (camera.fx * camera.baseline / z + SIGMA_D * mc_rng.standard_normal(20000))
        )
        for z in depths_m
    ]
)
zs = np.linspace(0.5, 20, 200)
disparity_of_z = camera.fx * camera.baseline / zs  # d = f_x B / Z
sigma_z_of_z = zs**2 * SIGMA_D / (camera.fx * camera.baseline)  # σ_Z = Z² σ_d / (f_x B)
plot_depth_error(zs, disparity_of_z, sigma_z_of_z, depths_m, measured_sd, SIGMA_D)
print(" Z [m]   d [px]   σ_Z formula [m]   σ_Z Monte Carlo [m]")
for z, p_, m_ in zip(depths_m, predicted, measured_sd, strict=True):
    print(f" {z:5.1f}  {camera.fx * camera.baseline / z:7.2f}   {p_:15.4f}   {m_:19.4f}")
near = depths_m <= 10  # beyond, d is a few px and the first-order formula underestimates
assert np.allclose(measured_sd[near], predicted[near], rtol=0.1)
assert measured_sd[-1] > predicted[-1]  # at 20 m the curvature of 1/d adds to the error
display(
    Markdown(
        f"At 1 m the depth error is {100 * measured_sd[0]:.2f} cm; at 10 m it is "
        f"{measured_sd[3]:.2f} m, {measured_sd[3] / measured_sd[0]:.0f} times more for a depth ten "
        "times larger. This is why far points say little about the distance travelled (ρ) and why "
        "the pipeline weighs each point by its own uncertainty (notebooks 03 and 06)."
    )
)
assert 80 < measured_sd[3] / measured_sd[0] < 120  # quadratic: 10² = 100

# %% [markdown]
# ## 1 · FAST corners, spread by bucketing
#
# FAST calls a pixel a corner when a contiguous arc of at least 9 of the 16 pixels on a circle of
# radius 3 around it is brighter, or darker, than it by a threshold. It is fast because most
# pixels fail on four test pixels. A textured scene gives many corners (this image's count is
# printed below), clustered where contrast is high; motion estimation prefers fewer corners spread
# over the whole image, so we
# keep the strongest few per cell of an 8×6 grid.

# %%
fast = cv2.FastFeatureDetector_create(40, True)
keypoints = fast.detect(left)
points = cv2.KeyPoint_convert(keypoints)
response = np.array([k.response for k in keypoints])
kept = bucket(points, response, camera.width, camera.height, grid=(8, 6), max_features=600)
strongest = np.argsort(-response)[:600]
plot_corner_sets(left, points, {"600 strongest corners": strongest, f"{len(kept)} after 8×6 bucketing": kept})
print(
    f"{len(keypoints)} FAST corners; grid cells covered: strongest {cells_covered(points[strongest])}, "
    f"bucketed {cells_covered(points[kept])} of 48"
)

# %% [markdown]
# ## 2 · Binary descriptors and the Hamming distance
#
# A binary descriptor (here ORB's rBRIEF) compares 256 pairs of smoothed pixels around a corner
# and stores one bit per comparison: 32 bytes. Two descriptors are compared by counting differing
# bits, the Hamming distance — an XOR and a population count. The same corner seen by the left and
# the right camera should differ in few bits; two unrelated corners in about half of them.

# %%
front = StereoFrontEnd(camera)
features = front.process(left, right)
orb = cv2.ORB_create(nlevels=1, edgeThreshold=16)
# true pairs: every FAST corner of section 1 and the right pixel its true disparity points to,
# whether or not the matcher would accept the pair (class_id keeps the pairing through ORB's
# border filter)
u_c, v_c = np.rint(points[:, 0]).astype(int), np.rint(points[:, 1]).astype(int)
u_right = points[:, 0] - true_disparity[v_c, u_c]
right_points = np.column_stack([u_right, points[:, 1]])
pairs_left = [cv2.KeyPoint(float(x), float(y), 31.0, -1, 0, 0, i) for i, (x, y) in enumerate(points)]
pairs_right = [cv2.KeyPoint(float(x), float(y), 31.0, -1, 0, 0, i) for i, (x, y) in enumerate(right_points)]
left_kps, left_des = orb.compute(left, pairs_left)
right_kps, right_des = orb.compute(right, pairs_right)
left_row = {k.class_id: i for i, k in enumerate(left_kps)}
right_row = {k.class_id: i for i, k in enumerate(right_kps)}
common = sorted(left_row.keys() & right_row.keys())
left_des = left_des[[left_row[c] for c in common]]
right_des = right_des[[right_row[c] for c in common]]
same = hamming(left_des, right_des)
shuffled = hamming(left_des, right_des[rng.permutation(len(right_des))])
plot_hamming(same, shuffled, ceiling=60)
print(
    f"{len(common)} true pairs (every corner whose true right image lies inside the frame); median "
    f"distance: same corner {np.median(same):.0f} bits, unrelated {np.median(shuffled):.0f} bits; "
    f"{np.mean(same > 60):.0%} of the true pairs lie above the ceiling"
)

# %% [markdown]
# ## 3 · Matching along rows, and sub-pixel disparity
#
# In a rectified pair, a point's two images lie on the same row, and its right image is to the
# left by the disparity d = f·B/z. So each left corner is compared only with right corners within
# one pixel of its row and within the disparity range (0.5 to 64 px: depths from f·B/64 on, just
# under a metre for our rig). The
# nearest descriptor wins if it is below the ceiling, clearly nearer than the second nearest
# (ratio 0.85), and if the left corner is also the right corner's nearest (mutual check).
#
# FAST corners sit on whole pixels, so the disparity is first an integer. An equiangular fit (two
# lines of equal and opposite slope) to the block-matching cost (sum of absolute differences of
# 7×7 patches) at d−1, d and d+1 puts its minimum between pixels.

# %%
u_i, v_i = np.rint(features.w[:, 0]).astype(int), np.rint(features.w[:, 1]).astype(int)
truth = true_disparity[v_i, u_i]
err_subpixel = features.w[:, 2] - truth
err_integer = np.rint(features.w[:, 2]) - truth
plot_disparity_errors(truth, features.w[:, 2], err_integer, err_subpixel)
stereo_median_err = np.median(np.abs(err_subpixel))
stereo_wrong = np.mean(np.abs(err_subpixel) > 2)
print(
    f"median |error|: integer {np.median(np.abs(err_integer)):.3f} px, "
    f"sub-pixel {stereo_median_err:.3f} px; wrong matches (> 2 px): {stereo_wrong:.1%}"
)

# %% [markdown]
# ## 4 · What it costs
#
# [Zhao]'s Table 1 puts stereo processing at 22.165 ms (320×240) to 48.969 ms (640×480) per
# frame (including grabbing, grey conversion, smoothing, distortion correction, feature
# extraction and matching on its robot's computer). Ours, on rendered rectified images,
# per stage (median of 20 frames along a drive):

# %%
timings = []
for k in range(20):
    frame_pose = planar_to_matrix((-3.0 + 0.01 * k, 0.3, 0.2 + 0.002 * k)) @ camera_mount(height=0.5)
    pair = renderer.render_pair(frame_pose, rng)
    t0 = time.perf_counter()
    f = front.process(*pair)
    timings.append({**f.timings, "total": (time.perf_counter() - t0) * 1e3, "features": len(f)})
for key in ("detect", "describe", "stereo_match", "total"):
    print(f"  {key:<14s}{np.median([t[key] for t in timings]):7.2f} ms")
print(f"  features      {np.median([t['features'] for t in timings]):7.0f}")
frontend_ms = np.median([t["total"] for t in timings])

# %% [markdown]
# Times are measured, not asserted: `python -m vo_lib bench frontend` is the benchmark.
#
# ## 5 · From one frame to the next: guided or brute force
#
# Temporal matching pairs the features of consecutive frames. Brute force compares every pair.
# Guided matching moves each previous feature by the motion the filter predicts (notebook 07),
# projects it, and compares only with current features inside a window of three predicted
# standard deviations. We run both on consecutive frames of a drive, with a prediction that is
# off by 0.1° and 5 mm, and judge each match by the true motion (`matching_rows`); then on twenty
# more drives along the same path, each with its own image noise.

# %%
mount = camera_mount(height=0.5)
drive = [np.array([-3.0 + 0.012 * k, 0.3 + 0.001 * k, 0.2 + 0.003 * k]) for k in range(11)]
stats = matching_rows(drive, renderer, front, camera, mount, rng)
print(f" {'':12s}{'matches':>9s}{'wrong':>8s}{'pairs compared':>16s}{'time [ms]':>11s}")
for name, rows in stats.items():
    a = np.array(rows)
    print(
        f" {name:12s}{np.median(a[:, 0]):9.0f}{np.mean(a[:, 1]):8.1%}"
        f"{np.median(a[:, 2]):16.0f}{np.median(a[:, 3]):11.2f}"
    )
guided, brute = np.array(stats["guided"]), np.array(stats["brute force"])
pair_share = np.median(guided[:, 2]) / np.median(brute[:, 2])
correct_guided = np.median(guided[:, 0] * (1 - guided[:, 1]))
correct_brute = np.median(brute[:, 0] * (1 - brute[:, 1]))
wrong_guided, wrong_brute = np.mean(guided[:, 1]), np.mean(brute[:, 1])
# the wrong-match rates over 20 drives, each with its own image noise
WRONG_SEEDS = range(SEED + 500, SEED + 520)
by_seed = over_seeds(
    lambda s: {
        k: float(np.mean(v[:, 1]))
        for k, v in matching_rows(drive, renderer, front, camera, mount, np.random.default_rng(s)).items()
    },
    WRONG_SEEDS,
)
median_diff, diff_low, diff_high = (100 * v for v in by_seed.difference("guided", "brute force"))
wrong_verdict = by_seed.verdict("guided", "brute force")
rate_words = {
    Verdict.BETTER: "lower",
    Verdict.WORSE: "higher",
    Verdict.NOT_RELIABLE: "not reliably different",
}[wrong_verdict]
display(
    Markdown(
        f"Guided matching compares {pair_share:.1%} of the pairs brute force compares; on this "
        f"drive it finds {correct_guided:.0f} correct matches per frame and brute force "
        f"{correct_brute:.0f} (one drive, which ranks neither). Its "
        f"wrong-match rate, {wrong_guided:.1%} against {wrong_brute:.1%} on this drive, is {rate_words} "
        f"over {len(by_seed)} drives with their own image noise (lower in "
        f"{by_seed.share('guided', 'brute force')} of them; median difference {median_diff:+.1f} "
        f"percentage points, 95 % CI {diff_low:+.1f} to {diff_high:+.1f}). "
        "A wrong partner far away, in repeated texture, never enters the small window; the "
        "outliers that remain, neighbours with no rival inside the window, are RANSAC's job "
        "(notebook 06)."
    )
)

# %% [markdown]
# ## 6 · Try the knobs
#
# `front_end(threshold, max_features)` reruns the front end on the same pair and reports the
# number of stereo matches, how well they cover the image, and their disparity error.


# %%
front_end = front_end_on(camera, left, right, true_disparity)
count = front_end()

# %%
knobs = offer(
    front_end,
    threshold=slider(40, 10, 100, 5, "FAST threshold"),
    max_features=slider(600, 100, 1500, 50, "max features"),
)

# %% [markdown]
# ## Summary

# %%
display(
    Markdown(
        f"""- FAST finds {len(keypoints):,} corners in this textured scene; bucketing keeps
  {len(kept)} of them spread over the image.
- Hamming distances of binary descriptors separate true matches (median {np.median(same):.0f} bits
  of 256) from unrelated ones (median {np.median(shuffled):.0f} bits) on this scene; a ceiling, a
  ratio test and a mutual check are the matcher's guards against the rest.
- Row-constrained matching plus the equiangular sub-pixel fit gives disparities with a median
  error of {stereo_median_err:.2f} px, with {stereo_wrong:.1%} wrong matches (off by more than
  2 px), in {frontend_ms:.0f} ms per pair on this machine (section 4)."""
    )
)

# %% [markdown]
# ## Exercises
#
# Easy to hard, with the points each is worth. Each exercise asks for a function (the cell
# under it names it); the test cell after it checks it. The grader also calls your functions
# with inputs of its own, and without the `vo_lib` function that does the same job.

# %% [markdown]
# ### Exercise 1 · the Hamming distance *(easy, 2 points)*
#
# Write `hamming_distance(a, b)` for two arrays of binary descriptors (`(N, 32)` bytes each, as
# `features.descriptors`), returning the number of differing bits of each row pair, without
# calling `vo_lib`'s `hamming` or OpenCV's Hamming norm and matchers.
#
# *Hint:* `np.bitwise_xor` and `np.unpackbits`.


# %% nbgrader={"grade": false, "grade_id": "ex1", "locked": false, "schema_version": 3, "solution": true}
### BEGIN SOLUTION
def hamming_distance(a, b):
    """Differing bits of each pair of rows of two uint8 descriptor arrays."""
    return np.unpackbits(np.bitwise_xor(a, b), axis=1).sum(axis=1)


### END SOLUTION

# %% nbgrader={"grade": true, "grade_id": "ex1_test", "locked": true, "points": 2, "schema_version": 3, "solution": false}
# Exercise 1: autograder test
other = features.descriptors[rng.permutation(len(features.descriptors))]
assert np.array_equal(hamming_distance(features.descriptors, other), hamming(features.descriptors, other)), (
    "not the number of differing bits of each pair"
)
assert np.all(hamming_distance(other, other) == 0), "a descriptor differs from itself in no bit"
### BEGIN HIDDEN TESTS
import cv2
import numpy as np

from coursework import grading
from vo_lib.stereo_vo import features as features_module
from vo_lib.stereo_vo import matching_core, matching_plain

_h51_a, _h51_b = np.random.default_rng(5011).integers(0, 256, (2, 500, 32), dtype=np.uint8)
_h51_a[0], _h51_b[0] = 0, 255  # a pair differing in all 256 bits: a count in 8 bits wraps to 0
_h51_no = grading.library_functions(
    features_module, matching_core, matching_plain, cv2.norm, cv2.batchDistance
)
_h51_no += [getattr(cv2.DescriptorMatcher, m) for m in ("match", "knnMatch", "radiusMatch")]
with grading.unavailable(*_h51_no):
    _h51_got = hamming_distance(_h51_a, _h51_b)
assert grading.equal(_h51_got, features_module.hamming(_h51_a, _h51_b)), "not each pair's differing bits"
### END HIDDEN TESTS

# %% [markdown]
# ### Exercise 2 · parabola or V? *(medium, 3 points)*
#
# Write `quadratic_offset(c_minus, c_zero, c_plus)`: the position of the vertex of the parabola
# through the costs sampled at −1, 0 and +1. Then sample a V-shaped (absolute-difference) cost
# |x − s| at x = −1, 0, 1 for true minima s in `true_minima` below, and store the largest error
# of your parabola in `parabola_worst` and that of `vo_lib`'s `equiangular_offset` (the
# front end's fit) in `library_worst`. Which fits a SAD cost, and what does the other do?
#
# *Hint:* solve a x² + b x + c through the three samples; the vertex is −b / (2a).

# %%
from vo_lib.stereo_vo.features import equiangular_offset

true_minima = np.linspace(-0.45, 0.45, 19)


# %% nbgrader={"grade": false, "grade_id": "ex2", "locked": false, "schema_version": 3, "solution": true}
### BEGIN SOLUTION
def quadratic_offset(c_minus, c_zero, c_plus):
    """Vertex of the parabola through costs at -1, 0, +1."""
    return 0.5 * (c_minus - c_plus) / (c_minus - 2.0 * c_zero + c_plus)


v_costs = [np.abs(x - true_minima) for x in (-1.0, 0.0, 1.0)]
parabola_worst = float(np.abs(quadratic_offset(*v_costs) - true_minima).max())
library_worst = float(np.abs(equiangular_offset(*v_costs) - true_minima).max())
print(
    f"worst error on a V-shaped cost: parabola {parabola_worst:.3f} px, vo_lib's fit {library_worst:.1e} px"
)
### END SOLUTION

# %% nbgrader={"grade": true, "grade_id": "ex2_test", "locked": true, "points": 3, "schema_version": 3, "solution": false}
# Exercise 2: autograder test
squares = [(x - true_minima) ** 2 for x in (-1.0, 0.0, 1.0)]
assert np.allclose(quadratic_offset(*squares), true_minima), "exact on a parabola"
assert library_worst < 1e-9 < 0.05 < parabola_worst, "the V fit is exact on a SAD cost; a parabola is not"
### BEGIN HIDDEN TESTS
import numpy as np

from coursework import grading  # noqa: E402

_h52 = np.random.default_rng(5021).uniform([-1.5, 0.1, 0], [1.5, 50, 100], (50, 3))  # vertices off ±0.5 too
_h52_costs = [_h52[:, 1] * (x - _h52[:, 0]) ** 2 + _h52[:, 2] for x in (-1.0, 0.0, 1.0)]  # c (x - v)² + f
_h52_got = quadratic_offset(*(c.copy() for c in _h52_costs))
_h52_a, _h52_b, _h52_c = np.polyfit([-1.0, 0.0, 1.0], np.array(_h52_costs), 2)
assert grading.close(_h52_got, -_h52_b / (2 * _h52_a)), "not the vertex of other parabolas (which side?)"
_h52_costs = [np.abs(x - true_minima) for x in (-1.0, 0.0, 1.0)]
assert grading.close(parabola_worst, np.abs(quadratic_offset(*_h52_costs) - true_minima).max()), "worst"
### END HIDDEN TESTS

# %% [markdown]
# ### Exercise 3 · bucketing by hand *(hard, 4 points)*
#
# Write `strongest_per_cell(points, response, width, height, grid, per_cell)`: the sorted
# indices of the `per_cell` strongest corners of each cell of a `grid = (columns, rows)` over a
# `width` × `height` image (a corner belongs to the cell its pixel position falls in), without
# calling `vo_lib`'s `bucket`. FAST scores are whole numbers and many corners share one: of two
# corners with the same response, keep the one with the smaller index first. Check it on
# section 1's FAST corners.
#
# *Hint:* give each corner a cell number, then sort by cell and, within a cell, by response
# (`np.argsort(..., kind="stable")` keeps equal responses in index order).


# %% nbgrader={"grade": false, "grade_id": "ex3", "locked": false, "schema_version": 3, "solution": true}
### BEGIN SOLUTION
def strongest_per_cell(points, response, width, height, grid, per_cell):
    """Sorted indices of the ``per_cell`` strongest points of every grid cell."""
    column = np.minimum((points[:, 0] * grid[0] / width).astype(int), grid[0] - 1)
    row = np.minimum((points[:, 1] * grid[1] / height).astype(int), grid[1] - 1)
    cell = row * grid[0] + column
    keep = []
    for c in np.unique(cell):
        members = np.flatnonzero(cell == c)
        keep.extend(members[np.argsort(-response[members], kind="stable")[:per_cell]])
    return np.sort(np.array(keep, dtype=int))


### END SOLUTION

# %% nbgrader={"grade": true, "grade_id": "ex3_test", "locked": true, "points": 4, "schema_version": 3, "solution": false}
# Exercise 3: autograder test
for grid, per_cell in (((8, 6), 12), ((4, 3), 5), ((16, 12), 1)):
    mine = strongest_per_cell(points, response, camera.width, camera.height, grid, per_cell)
    assert np.array_equal(
        mine, bucket(points, response, camera.width, camera.height, grid, per_cell * grid[0] * grid[1])
    ), f"not the {per_cell} strongest corners of every cell of a {grid} grid"


### BEGIN HIDDEN TESTS
import numpy as np

from coursework import grading
from vo_lib.stereo_vo import features as features_module

_h53 = np.random.default_rng(5031)
_h53_points, _h53_response = _h53.uniform(0, [900, 700], (800, 2)), _h53.integers(1, 30, 800).astype(float)
with grading.unavailable(features_module.bucket):
    _h53_got = strongest_per_cell(_h53_points.copy(), _h53_response.copy(), 900, 700, (7, 5), 3)
_h53_expected = features_module.bucket(_h53_points, _h53_response, 900, 700, (7, 5), 3 * 7 * 5)
assert grading.equal(_h53_got, _h53_expected), "not the strongest few of every cell (per cell? ties?)"
### END HIDDEN TESTS

# %% [markdown]
# ### Stretch goals (not graded)
#
# - Lower the FAST threshold to 15 and raise the cap to 1,500. What happens to the time and to
#   the share of wrong matches? Why does the ratio test matter more then?
# - Add motion blur (`SensorEffects(blur_px=6)`) and repeat section 3. Which stage suffers?
# - Refine corner positions to sub-pixel (`cv2.cornerSubPix`): how does the disparity error
#   change, and what does it cost?
