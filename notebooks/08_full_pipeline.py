# ---
# jupyter:
#   jupytext:
#     formats: py:percent
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # 08 · The full pipeline, and the paper's experiments beside ours
#
# Everything so far comes together: stereo front end (05), 1-point RANSAC (06) and the Kalman
# filter fed by track odometry (07), frame after frame (`vo_lib.stereo_vo.pipeline`). We rerun seed 000's
# experiments on the sample sequences that mirror them — processing time per resolution
# (Table 1), linear motion, free motion, spot turns with slip, outdoor free motion (Table 2) — and
# put the paper's figures beside ours.
#
# **You will learn**
# - what the pipeline does per frame, and what it does with a frame it cannot trust;
# - why it measures motion against a *keyframe* rather than the previous frame;
# - how its errors and times compare with the paper's, and why they differ.
#
# **Prerequisites**: notebooks 04–07.
#
# **Run time**: about 2 minutes in quick mode (the default). Set the environment variable
# `VO_NOTEBOOKS_FULL=1` for the full sequences (several minutes); the checks hold in both.

# %% [markdown]
# **References**
#
# - X. Zhao, J. Kan, C. Zhan, *1-Point RANSAC Application: an Independent Positioning Method for
#   Crawler Mobile Robots Based on Binocular Stereo Vision* (seed 000): §III.A, the procedure
#   (Fig. 3), and §IV, Table 1, Table 2, Fig. 6 and Fig. 9.

# %%
import math
import os

import matplotlib.pyplot as plt
import numpy as np

from vo_lib.evaluation import key_position_errors
from vo_lib.geometry import relative_planar, wrap_angle
from vo_lib.models.track_odometry import TrackOdometry
from vo_lib.sim.samples import SAMPLES, render_sample
from vo_lib.stereo_vo.pipeline import KEY_ANGLE, KEY_DISTANCE, run_frames
from vo_lib.viz.plotting import draw_flowchart, new_axes, plot_paths

SEED = 8
rng = np.random.default_rng(SEED)
np.set_printoptions(precision=3, suppress=True)
FULL = os.environ.get("VO_NOTEBOOKS_FULL") == "1"
print("full run" if FULL else "quick mode: shortened sequences (VO_NOTEBOOKS_FULL=1 for the full ones)")


def frames_for(name, quick):
    return SAMPLES[name].frames if FULL else quick


def run(name, frames, use_odometry=True, resolution=(640, 480)):
    """Render a sample in memory and run the pipeline; returns (result, truth from the start, odometry)."""
    rendered, frame_iter = render_sample(name, frames, resolution)
    if not use_odometry:
        frame_iter = ((left, right, None) for left, right, _ in frame_iter)
    result = run_frames(frame_iter, rendered.camera, seed=SEED)
    truth = relative_planar(rendered.truth()[0], rendered.truth())
    odometry = TrackOdometry().integrate(rendered.drive.odometry[1:frames])
    return result, truth, odometry


def heading_error(poses, truth):
    return np.degrees(wrap_angle(poses[:, 2] - truth[:, 2]))


# %% [markdown]
# ## 1 · One frame, and the frames it cannot trust
#
# Per frame: stereo features → prediction from track odometry (or constant velocity) → guided
# matching against the reference frame → 1-point RANSAC → Kalman update. A frame is flagged, and
# the filter keeps its prediction, when it has too few features, matches or inliers, when the
# inliers are too small a share of the matches, when its motion contradicts the prediction, or
# when half its view suddenly stops agreeing (an occluder, a large moving object).
#
# **Keyframes.** Our crawler moves a centimetre per frame: the disparity of a point 3 m away
# changes by 0.07 px, and most image motion is below a pixel. Measured frame to frame, such
# motions are dominated by sub-pixel errors of the feature positions, which do not average out:
# in our first version they shortened the measured motion by several per cent. The pipeline
# therefore measures each frame against a *keyframe* until the motion since it exceeds
# `KEY_DISTANCE` or `KEY_ANGLE`, applying each frame's update to a copy of the filter so that
# the keyframe's own errors are counted once.

# %%
print(f"new keyframe after {KEY_DISTANCE * 100:.0f} cm or {math.degrees(KEY_ANGLE):.1f}° of motion")
result, truth, _ = run("indoor_linear", 60)
reasons = {d.reason for d in result.diagnostics if d.fallback}
end_error = np.hypot(*(result.poses[-1, :2] - truth[-1, :2]))
travelled_60 = np.sum(np.hypot(*np.diff(truth[:, :2], axis=0).T))
print(
    f"{len(result.poses)} frames in, {len(result.poses)} poses out; "
    f"flagged: {len(result.flagged)} {reasons or ''}; "
    f"error after {travelled_60 * 100:.0f} cm: {end_error * 1000:.2f} mm"
)
# a clean, well-textured start: no frame needs the fallback, and the pose stays on the truth
assert len(result.flagged) == 0 and end_error < 0.01 * travelled_60

# the paper's Fig. 3 (the procedure), as our pipeline runs it; the timed stages are its boxes
fig, ax = new_axes(width=7, height=5)
draw_flowchart(
    ax,
    [
        "stereo pair k (rectified)",
        "stereo processing: FAST, descriptors, row matching, disparity  [stereo]",
        "Kalman prediction: track odometry (eq. 6-11) or constant velocity",
        "observation prediction: matching against the keyframe in predicted windows  [matching]",
        "1-point RANSAC: θ (eq. 14, gate eq. 20), then ρ (eq. 17, gate eq. 21)  [estimation]",
        "Kalman update with (θ, ρ) and the chord constraint  [kalman]",
        "pose k; a new keyframe after enough motion",
    ],
    side=[(2, 4, "prior (θ, ρ)\nand its covariance")],
)
ax.set_title("Fig. 3: the VO procedure, per frame")
plt.show()
assert {"stereo", "matching", "estimation", "kalman"} <= set(result.timing_table())

# %% [markdown]
# ## 2 · Table 1: time per stage at five resolutions
#
# The paper times its sub-procedures on 640×480 down to 256×192 images. We render the same drive
# at each resolution (same field of view) and time ours. Our "stereo processing" starts from
# rendered, rectified grey images; the paper's includes grabbing, colour conversion, smoothing,
# rectification and edge detection on its robot's computer.

# %%
paper_table1 = {  # stereo processing, parameter estimation, Kalman filtering (ms)
    (640, 480): (48.969, 0.874, 0.161),
    (512, 384): (39.851, 0.664, 0.157),
    (400, 300): (31.970, 0.754, 0.158),
    (320, 240): (22.165, 0.662, 0.168),
    (256, 192): (22.460, 0.610, 0.153),
}
n_table = frames_for("indoor_linear", 40)
rows, features = [], {}
for res in paper_table1:
    r, _, _ = run("indoor_linear", n_table, resolution=res)
    t = r.timing_table()
    features[res] = np.median([d.features for d in r.diagnostics])
    rows.append((res, t, paper_table1[res]))
print(
    " resolution   stereo [ms] (paper)   matching [ms]   estimation [ms] (paper)"
    "   Kalman [ms] (paper)   features"
)
for (w, h), t, p in rows:
    print(
        f" {w:4d}x{h:<4d} {t['stereo']:8.2f} ({p[0]:6.2f}) {t['matching']:12.2f}"
        f" {t['estimation']:12.2f} ({p[1]:5.3f})"
        f" {t['kalman']:12.2f} ({p[2]:5.3f}) {features[(w, h)]:10.0f}"
    )
counts = np.array([features[res] for res in paper_table1])
pixels = np.array([w * h for w, h in paper_table1])
fig, ax = new_axes(width=5.5, height=3.4)
ax.plot(pixels / 1e3, counts, "o-")
for (w, h), p_, c_ in zip(paper_table1, pixels, counts, strict=True):
    ax.annotate(f"{w}×{h}", (p_ / 1e3, c_), fontsize="x-small", xytext=(3, 3), textcoords="offset points")
ax.set_xlabel("pixels per image [thousands]")
ax.set_ylabel("stereo features (median per frame)")
ax.set_title("Fig. 6: stereo features against resolution")
ax.set_ylim(0, 1.1 * counts.max())
plt.show()
frame_ms = sum(rows[0][1][k] for k in ("stereo", "matching", "estimation", "kalman"))
print(f"640x480: {frame_ms:.1f} ms per frame for the four stages, {1000 / frame_ms:.0f} frames per second")
print(
    "paper's time / ours, stereo processing: "
    + ", ".join(f"{w}x{h} {p[0] / t['stereo']:.1f}" for (w, h), t, p in rows)
    + "; parameter estimation: "
    + ", ".join(f"{p[1] / t['estimation']:.1f}" for _, t, p in rows)
)
# the painted lab does not fill the cap: every step down in resolution loses features
assert np.all(np.diff(counts) < 0) and counts[-1] < 0.6 * counts[0]

# %% [markdown]
# The paper's Fig. 6 shows fewer stereo features at lower resolutions, and so do ours. Our front
# end keeps the strongest few corners per cell of a grid and caps their number; in a lab covered
# edge to edge with corner texture the cap set the count at every size but the smallest. The
# lab's painted walls, tiled floor and plain ceiling leave many cells without a corner, so the
# cap is not reached and each smaller image loses the corners that fall below FAST's threshold
# as they shrink.
#
# The ratios of the paper's times to ours are printed above (different work, different computer,
# and our images need no rectification); our Kalman column, with a 6-dimensional state for the
# keyframe, is printed beside the paper's. Timings here are single runs of a notebook, and on a
# busy or shared machine they inflate; `python -m vo_lib bench pipeline` measures them with
# repeats. The paper also timed a 10,000-frame run (mean 26.55 ms, s.d. 4.55 ms per frame):
# `python -m vo_lib bench long` repeats it on ten laps of an oval in the yard, rendering each
# frame in memory outside the timed stages, and prints our mean and spread beside the paper's.
#
# ## 3 · Linear motion (seed 000, IV.A.2)
#
# 200 frames forward, 200 back. The paper reports a relative error under 5 %, and mean x and y
# errors of −31.5 mm (s.d. 22.6) and −65.2 mm (s.d. 16.0).

# %%
n_lin = SAMPLES["indoor_linear"].frames  # forward and back needs the whole drive
result, truth, odo = run("indoor_linear", n_lin)
fig, axes = new_axes(2, width=5.5, height=3.4)
frames_axis = np.arange(n_lin)
for ax, col, name in ((axes[0], 0, "x"), (axes[1], 1, "y")):
    ax.plot(frames_axis, truth[:, col] * 1000, label="truth")
    ax.plot(frames_axis, result.poses[:, col] * 1000, "--", label="visual odometry")
    ax.set_xlabel("frame")
    ax.set_ylabel(f"{name} [mm]")
axes[0].legend(fontsize="small")
plt.show()
keys = np.arange(20, n_lin, 20)
stats = key_position_errors(truth, result.poses, keys)
travelled = np.sum(np.linalg.norm(np.diff(truth[:, :2], axis=0), axis=1))
relative = np.linalg.norm(result.poses[-1, :2] - truth[-1, :2]) / travelled
print(
    f"errors at key positions: x {stats['x_mm'][0]:.1f} mm (s.d. {stats['x_mm'][1]:.1f}), "
    f"y {stats['y_mm'][0]:.1f} mm (s.d. {stats['y_mm'][1]:.1f}); paper: x -31.5 (22.6), y -65.2 (16.0)"
)
print(f"final position error {relative:.2%} of the {travelled:.2f} m travelled; paper: under 5 %")
assert relative <= 0.01

# %% [markdown]
# Outdoors (IV.B.1, Fig. 9) the paper drove 600 frames forward and 600 back, five times, with
# mean x and y errors of 15.8 mm (s.d. 53.0) and 124.5 mm (s.d. 40.3). Our `outdoor_linear` sample
# drives the same in the yard, whose far buildings give the low parallax of an open site; quick
# mode runs its first 200 frames (forward only), the full mode all of it.

# %%
n_out = frames_for("outdoor_linear", 200)
result_o, truth_o, _ = run("outdoor_linear", n_out)
fig, ax = new_axes(width=7, height=3.2)
for col, name in ((0, "x"), (1, "y")):
    ax.plot(np.arange(n_out), (result_o.poses[:, col] - truth_o[:, col]) * 1000, label=f"{name} error")
ax.set_xlabel("frame")
ax.set_ylabel("error [mm]")
ax.set_title(f"Fig. 9: outdoor linear motion, {n_out} frames")
ax.legend(fontsize="small")
plt.show()
stats_o = key_position_errors(truth_o, result_o.poses, np.arange(20, n_out, 20))
travelled_o = np.sum(np.linalg.norm(np.diff(truth_o[:, :2], axis=0), axis=1))
relative_o = np.linalg.norm(result_o.poses[-1, :2] - truth_o[-1, :2]) / travelled_o
print(
    f"errors at key positions: x {stats_o['x_mm'][0]:.1f} mm (s.d. {stats_o['x_mm'][1]:.1f}), "
    f"y {stats_o['y_mm'][0]:.1f} mm (s.d. {stats_o['y_mm'][1]:.1f}); paper: x 15.8 (53.0), y 124.5 (40.3)"
)
print(f"final position error {relative_o:.2%} of the {travelled_o:.2f} m travelled; paper: under 5 %")
assert relative_o < 0.05

# %% [markdown]
# Outdoors the x error grows with the distance driven: in the open yard most matches are far,
# their disparities small, and the distance per frame is measured a little short or long, a
# scale error of a fraction of the distance (printed). A pure scale error cancels over a drive
# forward and back by the same distance, as the paper's sets were, so their end-point errors
# hide it; the error plot above shows it. It stays well within the paper's 5 %.

# %% [markdown]
# ## 4 · Spot turns with slip (seed 000, IV.B.2)
#
# Turning on the spot, the tracks scrub and slip unequally; the paper reports heading errors of
# 6.38° (s.d. 6.38°) and 4.09° (s.d. 8.17°) and blames unequal track grip. Our sample slips 6 % on
# average, strongly and unequally; we compare odometry alone, vision alone and the fusion.

# %%
n_spot = frames_for("spot_turn", 300)
fused, truth_s, odo_s = run("spot_turn", n_spot)
vision, _, _ = run("spot_turn", n_spot, use_odometry=False)
t = np.arange(n_spot) / SAMPLES["spot_turn"].rate
fig, ax = new_axes(width=7, height=3.4)
ax.plot(t, heading_error(odo_s, truth_s), label="track odometry only")
ax.plot(t, heading_error(vision.poses, truth_s), label="visual odometry only")
ax.plot(t, heading_error(fused.poses, truth_s), label="fused")
ax.set_xlabel("time [s]")
ax.set_ylabel("heading error [deg]")
ax.legend(fontsize="small")
plt.show()
err_odo = abs(heading_error(odo_s[-1:], truth_s[-1:])[0])
err_fused = np.abs(heading_error(fused.poses, truth_s))
turned = math.degrees(np.sum(np.abs(np.diff(np.unwrap(truth_s[:, 2])))))
print(
    f"after {turned:.0f}° of turning: odometry "
    f"{err_odo:.1f}°, fused mean {err_fused.mean():.2f}° (s.d. {err_fused.std():.2f}°), "
    f"max {err_fused.max():.2f}°; "
    "paper: 6.38° (6.38°) and 4.09° (8.17°)"
)
assert err_odo >= 5.0 and err_fused.max() <= 1.0

# %% [markdown]
# The paper ran two sets, 1,800 and 2,400 frames, on two grounds. Our `spot_turn_2` turns the
# other way, more slowly, for 2,400 frames; quick mode runs the first 100 frames of it, the full
# mode both sets whole. The fused heading error of each set, beside the paper's:

# %%
paper_spot = {"spot_turn": (6.38, 6.38), "spot_turn_2": (4.09, 8.17)}
spot_sets = {"spot_turn": (fused, truth_s, odo_s)}
spot_sets["spot_turn_2"] = run("spot_turn_2", frames_for("spot_turn_2", 100))
print(f" {'set':12s}{'frames':>7s}{'turned':>9s}{'odometry':>10s}   fused |error|: mean / s.d. / max   paper")
for name, (res, tr, odo) in spot_sets.items():
    err = np.abs(heading_error(res.poses, tr))
    turned_deg = math.degrees(np.sum(np.abs(np.diff(np.unwrap(tr[:, 2])))))
    odo_end = abs(heading_error(odo[-1:], tr[-1:])[0])
    print(
        f" {name:12s}{len(tr):7d}{turned_deg:8.0f}°{odo_end:9.1f}°   {err.mean():10.2f}° / "
        f"{err.std():.2f}° / {err.max():.2f}°    {paper_spot[name][0]:.2f}° / {paper_spot[name][1]:.2f}°"
    )
    assert err.max() <= 1.0  # the fusion holds the heading through every set

# %% [markdown]
# ## 5 · Free motion indoors (IV.A.3) and outdoors (IV.B.3, Table 2)
#
# Statistics of the x, y and heading errors at key positions, beside the paper's: indoors, and
# Table 2's three outdoor sets (1,403, 2,419 and 2,670 frames in the paper; `outdoor_free`,
# `outdoor_free_2` and `outdoor_free_3` here, whole in the full mode, shortened in quick mode).

# %%
paper_free = {
    "indoor_free": {"x_mm": (-1.5, 47.4), "y_mm": (7.4, 8.5), "theta_deg": (0.05, 0.56)},
    "outdoor_free": {"x_mm": (47.1, 36.4), "y_mm": (268.4, 287.7), "theta_deg": (2.32, 2.57)},
    "outdoor_free_2": {"x_mm": (-326.2, 818.1), "y_mm": (-1057.3, 950.6), "theta_deg": (16.68, 5.32)},
    "outdoor_free_3": {"x_mm": (-25.4, 135.8), "y_mm": (-131.9, 115.1), "theta_deg": (2.43, 3.68)},
}
quick_frames = {"indoor_free": 400, "outdoor_free": 400, "outdoor_free_2": 150, "outdoor_free_3": 150}
fig, axes = new_axes(4, width=4.2, height=4.0)
table = {}
for ax, name in zip(axes, paper_free, strict=True):
    n = frames_for(name, quick_frames[name])
    res_f, truth_f, odo_f = run(name, n)
    plot_paths(
        ax, {"truth": truth_f, "track odometry": odo_f, "visual odometry": res_f.poses}, f"{name}, {n} frames"
    )
    keys_f = np.arange(50, n, 50)
    ax.plot(*truth_f[keys_f, :2].T, "ko", ms=4, mfc="none", label="key positions (truth)")
    ax.plot(*res_f.poses[keys_f, :2].T, "k+", ms=6, label="key positions (VO)")
    ax.legend(fontsize="x-small")
    table[name] = key_position_errors(truth_f, res_f.poses, keys_f)
    table[name]["mean_heading"] = float(np.abs(heading_error(res_f.poses, truth_f)).mean())
plt.show()
print(f" {'':14s}{'x [mm] AVG / S.D.':>22s}{'y [mm] AVG / S.D.':>22s}{'θ [deg] AVG / S.D.':>22s}")
for name, ours in table.items():
    for label, vals in (("ours", ours), ("paper", paper_free[name])):
        print(
            f" {name if label == 'ours' else '':14s}"
            + "".join(
                f"{vals[k][0]:12.1f} /{vals[k][1]:7.1f}"
                if k != "theta_deg"
                else f"{vals[k][0]:12.2f} /{vals[k][1]:7.2f}"
                for k in ("x_mm", "y_mm", "theta_deg")
            )
            + f"   ({label})"
        )
assert table["indoor_free"]["mean_heading"] <= 0.2
# section 6: indoors our mean heading error is not below the paper's, but its spread is a tenth
assert table["indoor_free"]["theta_deg"][0] > paper_free["indoor_free"]["theta_deg"][0]
assert table["indoor_free"]["theta_deg"][1] < 0.2 * paper_free["indoor_free"]["theta_deg"][1]
for name in ("outdoor_free", "outdoor_free_2", "outdoor_free_3"):  # outdoors, every set's heading
    assert table[name]["mean_heading"] < paper_free[name]["theta_deg"][0]

# %% [markdown]
# ## 6 · Where we are better, and why that is not the whole story
#
# Most of our figures are smaller than the paper's, several times over. One is not: the mean
# heading error of indoor free motion (see the table), although its spread is a fraction of the
# paper's. Neither is a verdict on the method: our images are rendered from an exact pinhole
# model with a known calibration, no lens distortion, perfectly rectified pairs, a camera
# exactly above the turning axis (notebook 03 shows what an offset costs), static rich
# texture, no lighting change, and slip that follows our own statistical model. Every one of
# those is a source of error on a real robot. What the comparison does show is that the
# pipeline itself — front end, 1-point RANSAC with the corrected eq. 17, and the filter — adds
# little error of its own, and that fusing odometry and vision removes the drift each has alone.
#
# ### Scaling up
#
# Table 1 here is one run per resolution in this process. `python -m vo_lib sweep table1 --seeds 20`
# repeats it over seeds on a local Dask cluster (or `--scheduler tcp://host:8786`), and
# `python -m vo_lib evaluate-all ROOT` runs the pipeline on every sequence of a KITTI-style folder
# and prints the KITTI table (README, "Sweeps").
#
# ## Summary
#
# - The pipeline gives one pose per frame, flags the frames whose vision it cannot trust, and runs
#   at a speed per frame printed in section 2 (`python -m vo_lib bench pipeline` for a measurement).
# - Measuring against keyframes, not the previous frame, is what makes centimetre-per-frame motion
#   measurable.
# - Linear, free and spot-turn motion all stay within the accuracy targets; odometry alone drifts
#   by the slip.

# %% [markdown]
# ## Exercises
#
# Easy to hard, with the points each is worth. Each exercise asks for a function (the cell
# under it names it) and then uses it; the test cell after it checks both. The grader also
# calls your functions with inputs of its own, and without `vo_lib`'s own versions at hand.
# The cell below makes the trajectories they share: a drive of 400 steps of 1 cm with a gentle
# curve, and an estimate of it whose heading drifts by 0.01° per step.

# %%
from vo_lib.evaluation import ate_planar, path_lengths
from vo_lib.geometry import compose_planar

ex_steps, ex_step_length, ex_drift = 400, 0.01, np.radians(0.01)


def drive_steps(increment, n):
    """Poses (n + 1, 3) of n equal planar increments from the origin."""
    poses = [np.zeros(3)]
    for _ in range(n):
        poses.append(compose_planar(poses[-1], increment))
    return np.array(poses)


ex_truth = drive_steps(np.array([ex_step_length, 0.0, np.radians(0.05)]), ex_steps)
ex_estimate = drive_steps(np.array([ex_step_length, 0.0, np.radians(0.05) + ex_drift]), ex_steps)

# %% [markdown]
# ### Exercise 1 · final error as a share of the distance *(easy, 2 points)*
#
# The README reports the error at the last frame as a share of the distance travelled. Write
# `final_error_percent(estimate, truth)` for planar trajectories `(K, 3)`, in per cent, without
# `vo_lib.evaluation`, and store it for `ex_estimate` against `ex_truth` in `final_error_pct`.
#
# *Hint:* the distance travelled is the length of the true path, not the start-to-end distance.


# %% nbgrader={"grade": false, "grade_id": "ex1", "locked": false, "schema_version": 3, "solution": true}
### BEGIN SOLUTION
def final_error_percent(estimate, truth):
    """Final position error in per cent of the length of the true path."""
    travelled = np.sum(np.linalg.norm(np.diff(truth[:, :2], axis=0), axis=1))
    return float(100 * np.linalg.norm(estimate[-1, :2] - truth[-1, :2]) / travelled)


final_error_pct = final_error_percent(ex_estimate, ex_truth)
print(f"final error {final_error_pct:.2f} %")
### END SOLUTION

# %% nbgrader={"grade": true, "grade_id": "ex1_test", "locked": true, "points": 2, "schema_version": 3, "solution": false}
# Exercise 1: autograder test
from vo_lib.geometry import planar_to_matrix


def reference_percent(estimate, truth):
    gap = np.linalg.norm(estimate[-1, :2] - truth[-1, :2])
    return 100 * gap / path_lengths(np.array([planar_to_matrix(p) for p in truth]))[-1]


assert np.isclose(final_error_pct, reference_percent(ex_estimate, ex_truth)), (
    "not the final error in per cent"
)
### BEGIN HIDDEN TESTS
import vo_lib.evaluation as evaluation_module  # noqa: E402


def refuse(*args, **kwargs):
    raise AssertionError("final_error_percent calls vo_lib.evaluation; the exercise asks you to write it")


fresh = np.random.default_rng()  # new drives at every grading
cases = []
for _ in range(4):
    n_ = int(fresh.integers(50, 300))
    truth_ = drive_steps(np.array([fresh.uniform(0.01, 0.1), 0.0, fresh.uniform(0.005, 0.05)]), n_)
    estimate_ = truth_ + fresh.normal(scale=0.05, size=truth_.shape)
    cases.append((estimate_, truth_, reference_percent(estimate_, truth_)))
helpers = [evaluation_module.path_lengths, evaluation_module.planar_path_length]
saved = [f.__code__ for f in helpers]
for f in helpers:
    f.__code__ = refuse.__code__
try:
    got = [float(final_error_percent(e, t)) for e, t, _ in cases]
finally:
    for f, code in zip(helpers, saved, strict=True):
        f.__code__ = code
for g, (_, _, expected) in zip(got, cases, strict=True):
    assert np.isclose(g, expected), "final_error_percent differs on other drives (the length of the path?)"
### END HIDDEN TESTS

# %% [markdown]
# ### Exercise 2 · the absolute trajectory error *(medium, 3 points)*
#
# The ATE first moves the whole estimate by the rotation and translation in the plane that fit
# it best to the truth (least squares), then takes the RMS of the position errors. Write that
# alignment yourself (2-D Kabsch: centre both, SVD of the cross-covariance, mind the sign of the
# determinant) as `ate_rmse_of(truth, estimate)` for planar trajectories `(K, 3)`, without
# `vo_lib.evaluation`, and store it for `ex_truth`, `ex_estimate` in `ate_rmse`.
#
# *Hint:* R = V diag(1, det(V Uᵀ)) Uᵀ for the SVD U S Vᵀ of Σ (p_est − mean)(p_true − mean)ᵀ.


# %% nbgrader={"grade": false, "grade_id": "ex2", "locked": false, "schema_version": 3, "solution": true}
### BEGIN SOLUTION
def ate_rmse_of(truth, estimate):
    """RMS position error after the least-squares rigid alignment in the plane (2-D Kabsch)."""
    est_xy, true_xy = estimate[:, :2], truth[:, :2]
    est_mean, true_mean = est_xy.mean(axis=0), true_xy.mean(axis=0)
    U, _, Vt = np.linalg.svd((est_xy - est_mean).T @ (true_xy - true_mean))
    R_fit = Vt.T @ np.diag([1.0, np.linalg.det(Vt.T @ U.T)]) @ U.T
    aligned = (est_xy - est_mean) @ R_fit.T + true_mean
    return float(np.sqrt(np.mean(np.sum((aligned - true_xy) ** 2, axis=1))))


ate_rmse = ate_rmse_of(ex_truth, ex_estimate)
print(
    f"ATE {ate_rmse * 100:.3f} cm (final error {np.linalg.norm(ex_estimate[-1, :2] - ex_truth[-1, :2]) * 100:.2f} cm)"
)
### END SOLUTION

# %% nbgrader={"grade": true, "grade_id": "ex2_test", "locked": true, "points": 3, "schema_version": 3, "solution": false}
# Exercise 2: autograder test
assert np.isclose(ate_rmse, ate_planar(ex_truth, ex_estimate)[0].rmse, rtol=1e-9), (
    "not the ATE after alignment"
)
assert ate_rmse < np.linalg.norm(ex_estimate[-1, :2] - ex_truth[-1, :2]), "alignment spreads the drift"
### BEGIN HIDDEN TESTS
import vo_lib.evaluation as evaluation_module  # noqa: E402


def refuse(*args, **kwargs):
    raise AssertionError("ate_rmse_of calls vo_lib's alignment; the exercise asks you to write it")


fresh = np.random.default_rng()  # new drives, turned and shifted, at every grading
cases = []
for _ in range(4):
    n_ = int(fresh.integers(50, 300))
    truth_ = drive_steps(np.array([fresh.uniform(0.01, 0.1), 0.0, fresh.uniform(0.005, 0.05)]), n_)
    estimate_ = compose_planar(fresh.uniform([-5, -5, -np.pi], [5, 5, np.pi]), truth_)
    estimate_ = estimate_ + fresh.normal(scale=0.03, size=truth_.shape)
    cases.append((truth_, estimate_, ate_planar(truth_, estimate_)[0].rmse))
helpers = [evaluation_module.umeyama, evaluation_module.ate_planar, evaluation_module.ate]
saved = [f.__code__ for f in helpers]
for f in helpers:
    f.__code__ = refuse.__code__
try:
    got = [float(ate_rmse_of(t, e)) for t, e, _ in cases]
finally:
    for f, code in zip(helpers, saved, strict=True):
        f.__code__ = code
for g, (_, _, expected) in zip(got, cases, strict=True):
    assert np.isclose(g, expected, rtol=1e-6), (
        "ate_rmse_of differs on other drives (rotation and translation?)"
    )
### END HIDDEN TESTS

# %% [markdown]
# ### Exercise 3 · how heading drift becomes position error *(hard, 4 points)*
#
# On a straight drive of n steps of length s, a heading error growing by ε per step leaves the
# end of the path off sideways by about s ε n(n + 1)/2 ... or is it n(n − 1)/2? Derive the
# first-order sideways error of the last pose from compose_planar's midpoint-free step (each
# step goes straight along the heading *before* it turns), write `sideways_error(s, eps, n)`,
# and show that it matches a drive with `drive_steps` to 1 % for s = 1 cm, ε = 0.01°, n = 400.
#
# *Hint:* after k steps the heading is off by k ε; which heading does step k + 1 use?


# %% nbgrader={"grade": false, "grade_id": "ex3", "locked": false, "schema_version": 3, "solution": true}
### BEGIN SOLUTION
def sideways_error(s, eps, n):
    """First-order lateral offset after n steps whose heading drifts by eps per step."""
    return s * eps * n * (n - 1) / 2  # step k + 1 goes along heading k eps, k = 0 .. n - 1


drifting = drive_steps(np.array([ex_step_length, 0.0, ex_drift]), ex_steps)
print(
    f"sideways after {ex_steps} steps: {drifting[-1, 1] * 100:.3f} cm, "
    f"first order {sideways_error(ex_step_length, ex_drift, ex_steps) * 100:.3f} cm"
)
### END SOLUTION

# %% nbgrader={"grade": true, "grade_id": "ex3_test", "locked": true, "points": 4, "schema_version": 3, "solution": false}
# Exercise 3: autograder test
for n in (50, 400):
    straight_drift = drive_steps(np.array([0.01, 0.0, np.radians(0.01)]), n)
    assert np.isclose(sideways_error(0.01, np.radians(0.01), n), straight_drift[-1, 1], rtol=0.01), (
        f"not the sideways error of {n} steps to first order"
    )
assert np.isclose(sideways_error(0.01, 1e-4, 2), 0.01 * 1e-4), "two steps: only the second is off"
### BEGIN HIDDEN TESTS
fresh = np.random.default_rng()  # new steps and drifts at every grading
# short drives (n <= 50), where n(n - 1)/2 and n(n + 1)/2 differ by 4 % or more, and small
# drifts, where the first order is good to 1e-4
for s_, eps_, n_ in zip(
    fresh.uniform(0.005, 0.5, 10), fresh.uniform(1e-6, 1e-4, 10), fresh.integers(3, 51, 10), strict=True
):
    exact = drive_steps(np.array([s_, 0.0, eps_]), int(n_))[-1, 1]
    assert np.isclose(float(sideways_error(s_, eps_, int(n_))), exact, rtol=1e-3), (
        "sideways_error differs from other drifting drives (which heading does each step use?)"
    )
### END HIDDEN TESTS

# %% [markdown]
# ### Stretch goals (not graded)
#
# - Set `vo_lib.stereo_vo.pipeline.KEY_DISTANCE` to 0 (a new keyframe every frame) and rerun
#   section 3. How large is the final error now, and in which direction?
# - Move the camera 0.3 m ahead of the turning axis in `vo_lib.sim.samples` and rerun section 4.
# - Run `python -m vo_lib run --sequence outdoor_free --no-odometry` and compare with section 5.
# - With KITTI odometry data, run the pipeline on sequence 00 (README). Which assumption of the
#   circular-motion model does a car break first?
