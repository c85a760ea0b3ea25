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
# # 07 · Fusing track odometry and visual odometry with a Kalman filter
#
# Track odometry is smooth but drifts with slip; visual odometry does not drift with slip but is
# noisy frame to frame and fails where the camera sees nothing. [Zhao] lets a Kalman filter
# predict with the odometry and correct with the visual motion, and uses the prediction to guide
# matching and RANSAC. This notebook writes that filter out in NumPy, from a one-dimensional one
# up, checks it against filterpy and `vo_lib`, runs it on drives with slip, and checks that its
# covariance tells the truth.
#
# **You will learn**
# - the Kalman filter's predict and update, written out: first in one dimension, then for the
#   planar pose (F, B, Q, H, K, the Joseph form), checked against filterpy and `vo_lib`;
# - how a *relative* measurement (the motion between two frames) updates an *absolute* pose,
#   consistently, by keeping a copy of the previous pose in the state (stochastic cloning);
# - how the prediction becomes the prior (θ, ρ) that guides matching and RANSAC;
# - what the third, "sideways" measurement of every update is, and when it matters;
# - how odometry alone, VO alone and the fused filter compare when the tracks slip, over seeds:
#   where fusion helps, where it hurts, and why; a filter that learns the slip's mean;
# - how to test a filter's consistency with the NEES and its χ² band.
#
# **Prerequisites**: notebooks 01 (odometry, its Jacobians), 06 (the VO measurement).
#
# **Run time**: about 10 seconds (section 4's seed study is stored; with another `SEED` it is
# run here, which takes about ten minutes more on two cores).

# %% [markdown]
# **References**
#
# - X. Zhao, J. Kan, C. Zhan, *1-Point RANSAC Application: an Independent Positioning Method for
#   Crawler Mobile Robots Based on Binocular Stereo Vision* [Zhao]: §II, eq. 1–11 (the
#   odometry the filter predicts with), and §III.A.2, the Kalman filter's prediction and
#   observation matching.

# %%
import vo_lib  # noqa: F401 (first: NumPy and OpenCV then use the same BLAS kernels on every CPU)

# isort: split
import math
import os

import numpy as np
from IPython.display import display
from scipy.stats import chi2

from vo_book.demo_fusion import (
    CONDITIONS,
    ESTIMATORS,
    STUDY_FAMILY,
    STUDY_SEEDS,
    fuse,
    heading_error,
    nees_words,
    run_drive,
    said,
    seed_figures,
)
from vo_book.nb07 import plot_heading_errors, plot_nees, plot_outage
from vo_book.prose import Markdown
from vo_book.widgets import offer, slider
from vo_lib.camera import StereoCamera
from vo_lib.comparison import CONFIDENCE, bootstrap_interval, over_seeds
from vo_lib.geometry import relative_planar, wrap_angle
from vo_lib.models.track_odometry import TrackOdometry
from vo_lib.sim.samples import SAMPLES
from vo_lib.sim.trajectories import simulate_drive
from vo_lib.stereo_vo import circular_motion as cm
from vo_lib.stereo_vo.kalman import (
    SIDEWAYS_SIGMA,
    SLIP_SIGMA,
    VoKalmanFilter,
    constrained_jacobian,
    constrained_measurement,
    measurement,
)
from vo_lib.stereo_vo.ransac import one_point_ransac
from vo_lib.stereo_vo.synthetic import synthetic_matches

SEED = 7
FULL = os.environ.get("VO_NOTEBOOKS_FULL") == "1"  # run section 4's seed study, not read it
rng = np.random.default_rng(SEED)
np.set_printoptions(precision=5, suppress=True)
camera = StereoCamera.bumblebee2()
odometry = TrackOdometry()

# %% [markdown]
# ## 1 · A Kalman filter in one dimension
#
# Before the pose filter, the smallest one: a robot on a rail at position x. Odometry reports the
# distance u it moved, with variance q; a sensor measures the position z, with variance r.
#
# * **predict**: x⁻ = F x + B u and P⁻ = F P Fᵀ + Q, here with F = B = 1 and Q = q;
# * **update**: the innovation y = z − H x⁻ has variance S = H P⁻ Hᵀ + R (H = 1, R = r), the gain
#   is K = P⁻Hᵀ/S, and x = x⁻ + K y. The covariance in Joseph form,
#   P = (1 − KH) P⁻ (1 − KH)ᵀ + K R Kᵀ, equals the shorter (1 − KH)P⁻ for the optimal K, but stays
#   symmetric and positive when K is off by rounding.
#
# We write both steps out, run them for 30 steps beside filterpy's `KalmanFilter`, and compare.

# %%
from filterpy.kalman import ExtendedKalmanFilter, KalmanFilter

RAIL_Q, RAIL_R = 0.02**2, 0.05**2  # odometry and position-sensor variances [m^2]
rail_rng = np.random.default_rng(SEED + 1)
true_x, x_hat, P_hat = 0.0, 0.0, 0.1**2
rail = KalmanFilter(dim_x=1, dim_z=1)
rail.x, rail.P = np.array([[x_hat]]), np.array([[P_hat]])
rail.F, rail.B, rail.H = np.eye(1), np.eye(1), np.eye(1)
rail.Q, rail.R = np.array([[RAIL_Q]]), np.array([[RAIL_R]])
rail_log = []
for _ in range(30):
    moved = 0.1
    true_x += moved
    u_rail = moved + rail_rng.normal(scale=math.sqrt(RAIL_Q))  # odometry
    z_rail = true_x + rail_rng.normal(scale=math.sqrt(RAIL_R))  # position sensor
    x_hat, P_hat = x_hat + u_rail, P_hat + RAIL_Q  # predict
    K_rail = P_hat / (P_hat + RAIL_R)  # update
    x_hat = x_hat + K_rail * (z_rail - x_hat)
    P_hat = (1 - K_rail) * P_hat * (1 - K_rail) + K_rail * RAIL_R * K_rail
    rail.predict(u=np.array([[u_rail]]))
    rail.update(np.array([[z_rail]]))
    rail_log.append((true_x, x_hat, P_hat))
    assert abs(x_hat - rail.x[0, 0]) < 1e-12 and abs(P_hat - rail.P[0, 0]) < 1e-12
rail_log = np.array(rail_log)
steady = RAIL_Q / 2 * (math.sqrt(1 + 4 * RAIL_R / RAIL_Q) - 1)  # fixed point of P = (P + q) r / (P + q + r)
print(f"after 30 steps: error {rail_log[-1, 1] - rail_log[-1, 0]:+.4f} m, sigma {math.sqrt(P_hat):.4f} m")
print(f"steady-state variance (P + q) r / (P + q + r) = P: {steady:.3e} m^2; reached {P_hat:.3e}")
assert abs(P_hat - steady) < 1e-6 * steady

# %% [markdown]
# The variance settles where what the prediction adds (q) is what the update removes: P solves
# P = (P + q)r/(P + q + r), printed above. The pose filter has the same two steps, with matrices.
#
# ## 2 · The pose filter, written out
#
# The state is the pose (x, y, yaw) **and a copy of the previous pose**, because the VO measures
# the motion between two frames (stochastic cloning). For one frame:
#
# * **predict** (eq. 6–11): copy the pose, then move the first copy with the track distances
#   u = (Δs_L, Δs_R). With F = ∂f/∂pose and B = ∂f/∂u of eq. 6 (notebook 01), the 6-state moves by
#   x⁻ = [f(pose, u), pose] and its Jacobian is F₆ = [[F, 0], [I, 0]]; the process noise is
#   Q₆ = [[B M Bᵀ, 0], [0, 0]], with M the encoder noise plus slip of each track
#   (σ²_enc|Δs| + σ²_slip Δs²).
# * **update** with z = (θ, ρ, 0): h(x) is the increment from the copy to the pose, expressed as the
#   circular-motion model sees it: its yaw θ, its length along the chord at θ/2 (ρ), and its
#   deviation across that chord, which the crawler's tracks hold at zero (the *sideways*
#   pseudo-measurement, variance σ²_side). Then S = HPHᵀ + R, K = PHᵀS⁻¹, x = x⁻ + K(z − h(x⁻))
#   with the θ residual wrapped to (−π, π], and the Joseph form for P.
#
# The paper describes its filter in words: the odometry update predicts the pose (§II, eq. 6),
# and matching happens "in the observation prediction period" of the filter (§III.A.2). That the
# VO motion is the measurement which corrects it is our reading. The cloned state and the sideways
# pseudo-measurement are **this notebook's design**, one way to make a relative measurement
# update an absolute pose; the paper does not say how it does it.


# %%
def predict_by_hand(x6, P6, u):
    """Clone the pose and move it with the track distances u (eq. 6-11): (x6, P6)."""
    pose = x6[:3]
    ds = 0.5 * (u[0] + u[1])
    dyaw = (u[1] - u[0]) / odometry.gauge
    a = pose[2] + dyaw / 2
    moved = np.array([pose[0] + ds * math.cos(a), pose[1] + ds * math.sin(a), wrap_angle(pose[2] + dyaw)])
    F = np.array([[1, 0, -ds * math.sin(a)], [0, 1, ds * math.cos(a)], [0, 0, 1]])
    k = ds / (2 * odometry.gauge)
    B = np.array(
        [
            [math.cos(a) / 2 + k * math.sin(a), math.cos(a) / 2 - k * math.sin(a)],
            [math.sin(a) / 2 - k * math.cos(a), math.sin(a) / 2 + k * math.cos(a)],
            [-1 / odometry.gauge, 1 / odometry.gauge],
        ]
    )
    M = np.diag(odometry.encoder_sigma**2 * np.abs(u) + SLIP_SIGMA**2 * np.asarray(u) ** 2)
    F6 = np.block([[F, np.zeros((3, 3))], [np.eye(3), np.zeros((3, 3))]])
    Q6 = np.zeros((6, 6))
    Q6[:3, :3] = B @ M @ B.T
    return np.concatenate([moved, pose]), F6 @ P6 @ F6.T + Q6, F6, Q6


def chord_h(x6):
    """h(x): (theta, rho, sideways) of the increment from the copy (x6[3:]) to the pose (x6[:3])."""
    c, s = math.cos(x6[5]), math.sin(x6[5])
    dx = c * (x6[0] - x6[3]) + s * (x6[1] - x6[4])  # the increment in the previous robot frame
    dy = -s * (x6[0] - x6[3]) + c * (x6[1] - x6[4])
    theta = wrap_angle(x6[2] - x6[5])
    sp, cp = math.sin(theta / 2), math.cos(theta / 2)
    return np.array([theta, dx * cp + dy * sp, -dx * sp + dy * cp]), (dx, dy, theta)


def chord_H(x6):
    """Jacobian of chord_h: rows theta, rho, sideways; columns the pose, then its copy."""
    _, (dx, dy, theta) = chord_h(x6)
    sp, cp = math.sin(theta / 2), math.cos(theta / 2)
    ca, sa = math.cos(x6[5] + theta / 2), math.sin(x6[5] + theta / 2)  # the chord's world direction
    d_rho, d_side = (dy * cp - dx * sp) / 2, -(dx * cp + dy * sp) / 2  # through theta = yaw - yaw'
    return np.array(
        [
            [0, 0, 1, 0, 0, -1],
            [ca, sa, d_rho, -ca, -sa, d_rho],
            [-sa, ca, d_side, sa, -ca, d_side],
        ]
    )


def update_by_hand(x6, P6, theta, rho, cov2):
    """Correct with the VO's (theta, rho) and the zero sideways deviation: (x6, P6)."""
    R = np.zeros((3, 3))
    R[:2, :2], R[2, 2] = cov2, SIDEWAYS_SIGMA**2
    H = chord_H(x6)
    y = np.array([theta, rho, 0.0]) - chord_h(x6)[0]
    y[0] = wrap_angle(y[0])
    S = H @ P6 @ H.T + R
    K = P6 @ H.T @ np.linalg.inv(S)
    x6 = x6 + K @ y
    x6[2] = wrap_angle(x6[2])
    I_KH = np.eye(6) - K @ H
    return x6, I_KH @ P6 @ I_KH.T + K @ R @ K.T


probe = np.array([0.3, -0.2, 0.4, 0.25, -0.22, 0.35])
numeric = np.column_stack([(chord_h(probe + e)[0] - chord_h(probe - e)[0]) / 2e-7 for e in 1e-7 * np.eye(6)])
assert np.allclose(chord_H(probe), numeric, atol=1e-8)  # the Jacobian, by central differences
assert np.allclose(chord_H(probe), constrained_jacobian(probe), rtol=0, atol=1e-15)

# %% [markdown]
# Now a few frames of a run: the first frames of the `indoor_free` sample, its encoder readings
# for the prediction and 1-point RANSAC on matches of the true motion for the update. Three
# filters take the same inputs: ours above, filterpy's `ExtendedKalmanFilter` given our F₆, Q₆, h
# and H, and `VoKalmanFilter`. They must agree in state and covariance to 1e-12.

# %%
sample = SAMPLES["indoor_free"]
drive = simulate_drive(
    sample.legs, sample.rate, sample.start, np.random.default_rng(sample.seed), odometry, sample.slip
)
start = drive.poses[0]
library_kf = VoKalmanFilter(odometry, pose=start)
x6, P6 = library_kf.snapshot()


class ClonedPoseEKF(ExtendedKalmanFilter):
    """filterpy's EKF, its state prediction the cloning motion (filterpy's default is F x + B u)."""

    predicted = None

    def predict_x(self, u=0):
        self.x = self.predicted.copy()


reference_ekf = ClonedPoseEKF(dim_x=6, dim_z=3)
reference_ekf.x, reference_ekf.P = x6.copy(), P6.copy()
match_rng = np.random.default_rng(SEED + 2)
worst_x = worst_P = 0.0
for k in range(1, 6):
    u = drive.odometry[k]
    x6, P6, F6, Q6 = predict_by_hand(x6, P6, u)
    reference_ekf.F, reference_ekf.Q = F6, Q6
    reference_ekf.predicted = x6
    reference_ekf.predict()
    library_kf.predict(u)
    prior = library_kf.motion_prior()
    th, rh = cm.circular_motion_from_increment(relative_planar(drive.poses[k - 1], drive.poses[k]))
    m = synthetic_matches(camera, 300, th, rh, match_rng, noise_px=0.5, outlier_ratio=0.3)
    vo = one_point_ransac(m.w_prev, m.w_curr, camera, prior=prior, rng=match_rng)
    x6, P6 = update_by_hand(x6, P6, vo.theta, vo.rho, vo.covariance)
    R3 = np.zeros((3, 3))
    R3[:2, :2], R3[2, 2] = vo.covariance, SIDEWAYS_SIGMA**2
    reference_ekf.update(
        np.array([vo.theta, vo.rho, 0.0]),
        chord_H,
        lambda x: chord_h(x)[0],
        R=R3,
        residual=lambda a, b: np.array([wrap_angle(a[0] - b[0]), a[1] - b[1], a[2] - b[2]]),
    )
    reference_ekf.x[2] = wrap_angle(reference_ekf.x[2])
    library_kf.update(vo.theta, vo.rho, vo.covariance)
    library_kf.finish_frame()
    for other in (reference_ekf, library_kf.ekf):
        worst_x = max(worst_x, np.max(np.abs(other.x - x6)))
        worst_P = max(worst_P, np.max(np.abs(other.P - P6)))
print(f"pose after 5 frames {x6[:3]} (truth {drive.poses[5]})")
print(f"largest difference to filterpy and to VoKalmanFilter: state {worst_x:.1e}, covariance {worst_P:.1e}")
assert worst_x <= 1e-12 and worst_P <= 1e-12

# %% [markdown]
# ## 3 · One step with `VoKalmanFilter`
#
# The same step through the library's filter, built on filterpy. For each frame it (1) copies the
# pose, (2) moves the copy with the track odometry of eq. 6–11 — using the full Jacobians of
# notebook 01, with encoder noise plus a slip whose standard deviation is 1 % of each step's length
# as process noise — and (3) corrects it with the VO measurement (θ, ρ) of the motion between the
# two copies. The 6×6 covariance keeps the two copies tied.

# %%
kf = VoKalmanFilter(odometry)
u = odometry.controls_for(0.05, math.radians(2.0))  # the encoders report 5 cm and 2 degrees
kf.predict(u)
prior = kf.motion_prior()
print(
    "predicted pose",
    kf.pose,
    "\npredicted variances",
    np.array2string(np.diag(kf.covariance), formatter={"float_kind": "{:.2e}".format}),
)
print(
    f"prior for matching: theta {math.degrees(prior.theta):.3f}°, rho {prior.rho * 100:.2f} cm, "
    f"sigma {math.degrees(math.sqrt(prior.covariance[0, 0])):.3f}°, "
    f"{math.sqrt(prior.covariance[1, 1]) * 1000:.2f} mm"
)
vo_theta, vo_rho, vo_cov = math.radians(1.9), 0.049, np.diag([math.radians(0.01) ** 2, 0.0005**2])
kf.update(vo_theta, vo_rho, vo_cov)
print(
    "corrected pose",
    kf.pose,
    "\ncorrected variances",
    np.array2string(np.diag(kf.covariance), formatter={"float_kind": "{:.2e}".format}),
)
certainty_ratio = vo_cov[0, 0] / prior.covariance[0, 0]  # VO's θ variance over the prediction's
moved_share = (measurement(kf.ekf.x)[0] - prior.theta) / (vo_theta - prior.theta)
# the scalar gain 1/(1 + ratio) is what a θ-only update would move; the sideways row and the
# ρ correlations move it a little further or less, hence a band, not an equality
assert certainty_ratio < 0.1 and abs(moved_share - 1 / (1 + certainty_ratio)) < 0.05
display(
    Markdown(
        f"The correction moved the turn {moved_share:.1%} of the way from the prediction's "
        f"{math.degrees(prior.theta):.3f}° to the VO's {math.degrees(vo_theta):.1f}°, because the "
        f"VO is far more certain about the turn: its variance is {certainty_ratio:.1%} of the "
        "prediction's, and a scalar update would move the share 1/(1 + that ratio). "
        "filterpy performs the update with the Joseph form, (I − KH)P(I − KH)ᵀ + KRKᵀ, which "
        "stays symmetric and positive."
    )
)

# %% [markdown]
# ## 4 · A drive with slip: odometry vs VO vs fused, over seeds
#
# We take the first 300 frames of the `spot_turn` sample (18°/s on the spot, 6 % slip that the
# encoders over-count) and of `indoor_free`. For every frame we draw 300 matches of the true
# motion (0.5 px noise, 30 % outliers), estimate the VO motion with 1-point RANSAC using the
# filter's prior, and run the estimators side by side: odometry alone, VO alone (integrating its
# own increments, and repeating the last one while it sees nothing), the fused filter, and a
# fused filter that learns the slip's mean (`SlipCalibratedFilter`, below). One seed draws the
# drive's slip and encoder noise and the matches; a claim that one estimator beats another is
# made over the seeds `range(SEED, SEED + STUDY_SEEDS)` (120), with `vo_lib.comparison`, never
# on one draw.
#
# **NEES.** To ask whether a filter's covariance P tells the truth we use the normalised
# estimation error squared, NEES = eᵀP⁻¹e for the pose error e = truth − estimate: if the error
# is Gaussian with covariance P, the NEES is χ² with 3 degrees of freedom and its mean is 3.
# Above 3 the filter is over-confident, below it too cautious. Section 6 says which band judges
# which average of it.


# %%
spot = run_drive("spot_turn", 300, seed=SEED)
t = np.arange(301) / SAMPLES["spot_turn"].rate
plot_heading_errors(t, {k: heading_error(spot[k], spot["truth"]) for k in ESTIMATORS}, "spot turn, one draw")

# %% [markdown]
# The picture is one draw. The questions it raises (is the fused filter closer than VO alone?
# does fusion ever help?) are answered over seeds, in five conditions: the two drives as
# sampled; *weak vision*, 40 matches with 2 px noise, as on a low-texture floor; and a VO outage
# of 100 frames in the spot turn. The figures are the final heading error (degrees) and the
# final position error (cm).
#
# 120 seeds of five conditions, and the sideways study of the next section, take several times as
# long as the rest of the notebook. `seed_figures` therefore reads their figures from
# `vo_book/demo_fusion.json`, stored by `python -m vo_book.demo_fusion` for the
# base seed 7 (`pytest -m samples` runs the study again and must find the same figures). With
# another `SEED`, or with `VO_NOTEBOOKS_FULL=1`, it runs them here.
#
# The section draws twenty-one verdicts from this one study (`STUDY_FAMILY`): seventeen
# comparisons and four time-averaged NEES against 3. At 95 % each, about one in twenty of the
# differences that are not there would still be called reliable, so among twenty-one a borderline
# verdict reads one way on these seeds and the other on the next 120. Each interval is therefore
# one of a family (Bonferroni, `vo_lib.comparison`): each is widened so that the twenty-one hold
# together at 95 %, and each sentence names its own confidence.

# %%
SEEDS = range(SEED, SEED + STUDY_SEEDS)
study = seed_figures(SEEDS, fresh=FULL)  # stored for SEED = 7, run for any other
draws = {c: {s: study["conditions"][c][str(s)] for s in SEEDS} for c in CONDITIONS}
heading_cmp, position_cmp = (
    {c: over_seeds(lambda s, c=c, q=q: draws[c][s][q], SEEDS, STUDY_FAMILY) for c in CONDITIONS}
    for q in ("heading", "position")
)
print(f"{'condition':24s}{'median final heading error [deg]':>44s}{'median final position error [cm]':>44s}")
print(" " * 24 + "".join(f"{k:>11s}" for k in ESTIMATORS) * 2)
for c in CONDITIONS:
    cells = [np.median(heading_cmp[c].figures[k]) for k in ESTIMATORS]
    cells += [np.median(position_cmp[c].figures[k]) for k in ESTIMATORS]
    print(f"{c:24s}" + "".join(f"{v:11.3f}" for v in cells))
fused_vo = max(np.max(np.abs(heading_cmp[c].paired("fused", "VO"))) for c in ("spot turn", "indoor"))
print(f"fused against VO, final heading errors as sampled: at most {fused_vo:.3f}° apart in any seed")


display(
    Markdown(
        "Odometry alone: "
        + "; ".join(
            f"{c}: {said(position_cmp[c], 'fused', 'odometry', 'cm')}" for c in ("spot turn", "indoor")
        )
        + f". In heading, spot turn: {said(heading_cmp['spot turn'], 'fused', 'odometry', '°')}.\n\n"
        "Vision alone, with vision as good as the samples give it: "
        + "; ".join(
            f"{c}: {said(heading_cmp[c], 'fused', 'VO', '°')} in heading" for c in ("spot turn", "indoor")
        )
        + ".\n\nWith weak vision: "
        + "; ".join(
            f"{c}: {said(heading_cmp[c], 'fused', 'VO', '°')} in heading, "
            f"{said(position_cmp[c], 'fused', 'VO', 'cm')} in position"
            for c in ("indoor, weak vision", "spot turn, weak vision")
        )
        + ".\n\nThrough the VO outage of the spot turn: "
        + said(heading_cmp["spot turn, VO outage"], "fused", "VO", "°")
        + " in heading."
    )
)

# %% [markdown]
# **Why.** The filter's state holds no velocity: each frame it has two independent estimates of
# the same motion, the odometry's increment (predict) and the VO's (update), and the fused
# increment is their average weighted by the inverse of the variances the filter assumes for
# them. Fusion therefore helps where the two errors are independent noise of comparable size,
# and hurts where one of them has an error the filter does not model:
#
# - the encoders over-count every turn by the slip, and the filter models slip as *zero-mean*
#   noise, so odometry's heading runs away while the fused heading does not;
# - with vision as good as the samples give it, VO's θ variance is a small fraction of the
#   odometry's, the average is nearly VO's own, and the slip's mean can leak in only with the
#   small weight the filter gives the odometry: over the seeds the two differ by a few hundredths
#   of a degree at most, one way or the other (printed under the table), and whether the leak shows as a
#   reliable difference is what the sentences above say;
# - with weak vision the weights become comparable. Odometry's distance carries little bias (1 %
#   slip when driving; on the spot the two tracks' counts cancel), so averaging can remove VO's
#   noise from the position; whether it does, drive by drive, is what the sentences above measure;
# - odometry's turn, though, carries the slip's mean, 6 % in the spot turn: with weak vision the
#   odometry's weight grows and so does the bias that comes with it, which pulls the fused heading
#   toward the odometry's. Through an outage the fused filter moves on the biased odometry alone,
#   while VO alone repeats its last motion, which a turn at a constant rate keeps close to right.
#
# The cure for the bias is to model it. `SlipCalibratedFilter` gives each track a scale, ground
# over counted distance, as a random walk. The VO's (θ, ρ) of each frame is linear in the two
# scales ([Zhao], eq. 4–5 for the turn and the distance, eq. 15 for the chord), so a small
# linear Kalman update learns them, with the counts' own noise in its innovation and the VO's
# variance inflated when the update's running NIS says it is too small; the prediction then moves
# the pose with the corrected distances. Equal scales model a slip that scales the whole motion
# (the spot turn), unequal ones the turn that unequal slip adds when driving.

# %%
display(
    Markdown(
        "The slip-calibrated filter against the plain one, in heading: "
        + "; ".join(
            f"{c}: {said(heading_cmp[c], 'calibrated', 'fused', '°')}"
            for c in ("spot turn", "spot turn, weak vision", "spot turn, VO outage", "indoor, weak vision")
        )
        + ". In position, indoor: "
        + said(position_cmp["indoor"], "calibrated", "fused", "cm")
        + "; indoor, weak vision: "
        + said(position_cmp["indoor, weak vision"], "calibrated", "fused", "cm")
        + ". Its learnt scale at the end of the spot turn, the mean of the two tracks', has a median "
        f"of {np.median([d['turn_scale'] for d in draws['spot turn'].values()]):.3f} over the seeds, "
        f"against 1 − {SAMPLES['spot_turn'].slip.spot_turn_mean:.2f} for the sampled slip."
    )
)

# %% [markdown]
# Where learning the slip pays, over the seeds, is what the sentences above say
# condition by condition. The reasoning to hold them against: a slip can be worth learning where it
# is large (6 % in the spot turn) and the vision cannot correct it frame by frame (weak vision, an
# outage). On the indoor floor the slip it would remove is about 1 %, and the VO of one frame cannot
# resolve so little. The scales drift (a random walk, so that they can follow the slip from one
# manoeuvre to the next) and each frame's measurement pulls them only a little, so they wander with
# the VO's noise: on the indoor floor with weak vision by an amount of the order of the slip they
# are meant to find (the cell below prints both); the corrected odometry carries that wander into
# the pose.

# %%
scale_sigma = {c: np.median([d["scale_sigma"] for d in draws[c].values()]) for c in CONDITIONS}
display(
    Markdown(
        "The learnt scale's standard deviation at the end of the run, median over the seeds: "
        + ", ".join(f"{100 * v:.1f} % in {c}" for c, v in scale_sigma.items())
        + f"; the sampled slip's mean is {100 * SAMPLES['indoor_free'].slip.mean:.0f} % when driving and "
        f"{100 * SAMPLES['spot_turn'].slip.spot_turn_mean:.0f} % in a spot turn. A calibration can only "
        "correct what its sensor can resolve."
    )
)

# %% [markdown]
# Does the filters' covariance tell the truth on these drives? Each draw gives one NEES per frame;
# the frames of one run are correlated, so its time average has no χ² band. The seeds are
# independent, so the time-averaged NEES of each seed is one sample, and the bootstrap interval of
# their mean, at the confidence of the study's family, is set against 3.

# %%
NEES_CONFIDENCE = 1 - (1 - CONFIDENCE) / STUDY_FAMILY  # four of the study's family of verdicts
nees_rows = {}
for c in ("spot turn", "indoor"):
    for key, label in (("nees", "fused"), ("nees_calibrated", "calibrated")):
        per_seed = [d[key] for d in draws[c].values()]
        low_, high_ = bootstrap_interval(per_seed, np.mean, NEES_CONFIDENCE)
        nees_rows[(c, label)] = (float(np.mean(per_seed)), low_, high_)
        print(
            f"{c:10s} {label:11s} time-averaged NEES {np.mean(per_seed):7.2f}  {100 * NEES_CONFIDENCE:.2f} % "
            f"interval over {len(SEEDS)} seeds {low_:.2f}–{high_:.2f}  (3 if consistent)"
        )


display(
    Markdown(
        "Time-averaged NEES over the seeds: "
        + "; ".join(f"{label} filter, {c}: {nees_words(*v)}" for (c, label), v in nees_rows.items())
        + ". The plain filter models slip as zero-mean noise; where its mean is large it is "
        "over-confident. The calibrated filter learns the slip but does not carry the correlation "
        "between its scales and its pose (both are corrected by the same VO measurements), so its "
        "covariance can claim more than it knows; its intervals above say how much on these drives."
    )
)

# %% [markdown]
# ### The third measurement: the motion lies on its chord
#
# (θ, ρ) are two numbers; the motion between two frames, (Δx, Δy, Δyaw), has three. The
# circular-motion model (eq. 15) says the third is fixed: the robot moves along the chord at
# θ/2, so its displacement *across* the chord is zero. Every update of `VoKalmanFilter` therefore
# observes a third component, the sideways deviation of the increment from its chord
# (`constrained_measurement`), as a pseudo-measurement of value 0 with σ = `SIDEWAYS_SIGMA`
# (2 mm: skid and model error of a crawler). Without it the sideways component of each increment
# is left to the prediction.
#
# With track odometry the prediction already puts the motion on the chord: eq. 2–3 move the
# robot along θ + Δθ/2, and encoder noise only changes Δu and Δθ, so the predicted increment has
# no sideways uncertainty at all and the pseudo-measurement adds nothing. Without odometry the
# filter predicts with constant velocity, whose noise moves the robot in every direction: then
# the pseudo-measurement is the only thing that keeps the motion on its chord.

# %%
sideways_sigma = {}
for label, u in (
    ("track odometry", odometry.controls_for(0.05, math.radians(2.0))),
    ("constant velocity", None),
):
    f_ = VoKalmanFilter(odometry)
    f_.last_increment = np.array([0.05, 0.0, math.radians(2.0)])
    f_.predict(u)
    h3 = constrained_jacobian(f_.ekf.x)[2]
    sideways_sigma[label] = math.sqrt(max(h3 @ f_.ekf.P @ h3, 0.0))  # rounding may leave -1e-20
    print(
        f"predicted sideways deviation with {label:17s}: "
        f"{constrained_measurement(f_.ekf.x)[2] * 1000:.3f} mm, "
        f"σ {sideways_sigma[label] * 1000:.4f} mm"
    )
assert (
    sideways_sigma["track odometry"]
    < 0.01 * SIDEWAYS_SIGMA
    < SIDEWAYS_SIGMA
    < sideways_sigma["constant velocity"]
)

sideways_cmp = over_seeds(lambda s: study["sideways"][str(s)], SEEDS, STUDY_FAMILY)
for name_, values in sideways_cmp.figures.items():
    print(f" {name_:30s} median final position error {np.median(values):.2f} cm")
same_end = float(
    np.max(np.abs(sideways_cmp.paired("odometry with the sideways row", "odometry without the sideways row")))
)
assert same_end < 1e-2  # equal but for rounding in every seed; a tenth of a millimetre (in cm)

# %%
display(
    Markdown(
        f"With odometry the runs with and without the sideways measurement end at most "
        f"{same_end * 10:.4f} mm apart over the seeds. In final position, "
        + said(
            sideways_cmp,
            "constant velocity with the sideways row",
            "constant velocity without the sideways row",
            "cm",
        )
        + "."
    )
)

# %% [markdown]
# The pipeline of notebook 08 runs without odometry
# whenever the encoders are missing (`--no-odometry`): then nothing but this third row keeps the
# motion on its chord, and the sentence above says whether, over these seeds, that reliably
# changes where the drive ends.

# %% [markdown]
# ## 5 · When vision goes blind
#
# Frames 200–260 of the spot turn have no usable matches (a blank wall, darkness). The filter
# carries on with odometry alone, flags those frames, and its heading uncertainty grows. When
# vision returns, the uncertainty grows far more slowly but does not shrink back: VO measures the motion
# between frames, not the heading itself, so drift already accumulated cannot be undone — only
# an absolute reference (a map, a landmark seen again) could.

# %%
gap_run = run_drive("spot_turn", 400, seed=SEED, outage=set(range(200, 261)))
yaw_sigma, flagged = gap_run["yaw_sigma"], gap_run["flagged"]
plot_outage(yaw_sigma, (200, 260))
print(
    f"{len(flagged)} frames flagged; heading σ {np.degrees(yaw_sigma[199]):.3f}° before, "
    f"{np.degrees(yaw_sigma[260]):.3f}° at the end of the gap, {np.degrees(yaw_sigma[300]):.3f}° after"
)

# %% [markdown]
# ## 6 · Does the filter believe its own covariance? NEES and NIS
#
# If the filter is consistent, the normalised estimation error squared, NEES = eᵀP⁻¹e for the 3-D
# pose error e, follows a χ² distribution with 3 degrees of freedom. At one step, averaged over
# N independent runs, it lies in [χ²₀.₀₂₅(3N)/N, χ²₀.₉₇₅(3N)/N] 95 % of the time: that band
# judges the *per-step* run average, step by step. The average over the steps as well is a
# different statistic: the steps of one run are correlated, so its spread is measured from the
# runs themselves, each run's time-averaged NEES being one independent sample.
#
# NEES needs the truth. The normalised innovation squared, NIS = νᵀS⁻¹ν of each update's
# innovation ν = z − h(x⁻) with its predicted covariance S = HPHᵀ + R (`vo_lib.stereo_vo.kalman.nis`),
# needs only the filter's own numbers, so it also works on real data (notebook 11). For the VO's
# two components it follows χ² with 2 degrees of freedom.
#
# We run 50 seeded Monte Carlo runs of 150 steps, the truth's start drawn from the filter's
# initial covariance, with odometry and VO measurements drawn from exactly the noise the filter
# assumes.

# %%
from vo_lib.stereo_vo.consistency import monte_carlo_run

runs, steps = 50, 150
pairs = [monte_carlo_run(1000 + run, steps) for run in range(runs)]  # (NEES, NIS) per step of each run
nees, nis_runs = np.array([p[0] for p in pairs]), np.array([p[1] for p in pairs])
avg = nees.mean(axis=0)
lo, hi = chi2.ppf([0.025, 0.975], 3 * runs) / runs
plot_nees(avg, (lo, hi), runs)
inside = np.mean((avg > lo) & (avg < hi))
run_means = nees.mean(axis=1)  # one independent sample per run
nees_mean, nees_se = run_means.mean(), run_means.std(ddof=1) / math.sqrt(runs)
nis_run_means = nis_runs.mean(axis=1)
nis_mean, nis_se = nis_run_means.mean(), nis_run_means.std(ddof=1) / math.sqrt(runs)
print(f"per step: {inside:.0%} of the steps' run averages inside the band {lo:.2f}–{hi:.2f}")
print(
    f"NEES over runs and steps: {nees_mean:.2f} ± {nees_se:.2f} "
    f"(standard error over {runs} runs); 3 if consistent"
)
print(f"NIS over runs and steps:  {nis_mean:.2f} ± {nis_se:.2f}; 2 if consistent")
assert inside >= 0.9  # 95 % expected; a few steps may fall out
assert abs(nees_mean - 3) < 2.5 * nees_se  # within 2.5 standard errors of its expectation
assert abs(nis_mean - 2) < 2.5 * nis_se  # a statistical band: its width is set by the spread

# %% [markdown]
# ## 7 · Play with slip, noise and outages
#
# `fuse(slip_scale, vo_noise_px, outage_frames)` reruns 300 frames of the spot turn.


# %%
widget_errors = fuse()

# %%
fuse_widget = offer(
    fuse,
    slip_scale=slider(1.0, 0.0, 3.0, 0.1, "slip × sample's"),
    vo_noise_px=slider(0.5, 0.1, 3.0, 0.1, "VO pixel noise [px]"),
    outage_frames=slider(0, 0, 150, 10, "frames without VO"),
    seed=slider(SEED, 0, 100, 1, "seed"),
)

# %% [markdown]
# ### Scaling up
#
# The NEES above averages 50 runs in this process. For a paper's confidence intervals,
# `python -m vo_lib sweep nees --seeds 1000` runs one task per seed on a local Dask cluster (one
# worker process per core), or on a lab's cluster with `--scheduler tcp://host:8786`; each run
# draws from its own seed, so the figures are the same serially and on any cluster; it prints each
# figure's mean and its 95 % interval over the seeds (`docs/command_line.md`, "Sweeps").
#
# ## Summary
#
# - A relative VO measurement updates the absolute pose consistently when the previous pose is
#   cloned into the state for the frame; the prediction gives the prior (θ, ρ) for matching.
# - (θ, ρ) leave the sideways part of the motion unobserved; a zero pseudo-measurement of it
#   (the motion lies on its chord) observes it. Track odometry already keeps the motion on its
#   chord; constant velocity does not, and the row takes its place (what it changes in the final
#   position of the indoor drive is printed over seeds).
# - With slipping tracks, odometry's heading drifts by the slip fraction of every turn. The fused
#   increment is an average of odometry's and VO's weighted by their assumed variances: against
#   vision alone it can remove noise where the vision is weak, and it lets in the slip's mean where
#   odometry carries one and the vision is weak or lost (the spot turn); section 4 measures both
#   over seeds, in position and in heading, on drives whose tracks do not skid, and says where
#   each shows. Learning the slip's
#   mean online can remove that bias; section 4 prints, condition by condition, where it does so
#   reliably over the seeds and where it costs position (indoors, the slip is too small for the
#   VO to resolve).
# - When the noise is the one the filter assumes (section 6), its NEES and its NIS average to their
#   degrees of freedom within their spread over the runs: the covariance tells the truth. On the
#   section 4 drives, whose slip has a mean the filter does not model, section 4 prints the
#   time-averaged NEES with its interval over seeds.

# %% [markdown]
# ## Exercises
#
# Easy to hard, with the points each is worth. Each exercise asks for a function (the cell
# under it names it) and then uses it; the test cell after it checks both. The grader also
# calls your functions with inputs of its own, so an answer must compute, not quote a number.

# %% [markdown]
# ### Exercise 1 · one update in one dimension *(easy, 2 points)*
#
# Write `update_1d(mean, variance, measured, measurement_variance)` returning the gain, the
# updated mean and the updated variance of a one-dimensional Kalman update, by hand (no
# library). A filter believes a robot is 2.0 m along a corridor with variance 0.5 m²; a
# measurement says 2.6 m with variance 0.25 m²: store its update in `gain_1d, mean_1d, var_1d`.
#
# *Hint:* K = P / (P + R).


# %% nbgrader={"grade": false, "grade_id": "ex1", "locked": false, "schema_version": 3, "solution": true}
### BEGIN SOLUTION
def update_1d(mean, variance, measured, measurement_variance):
    """Gain, mean and variance after one scalar Kalman update."""
    gain = variance / (variance + measurement_variance)
    return gain, mean + gain * (measured - mean), (1 - gain) * variance


gain_1d, mean_1d, var_1d = update_1d(2.0, 0.5, 2.6, 0.25)
print(f"K = {gain_1d:.3f}, mean {mean_1d:.3f} m, variance {var_1d:.4f} m²")
### END SOLUTION

# %% nbgrader={"grade": true, "grade_id": "ex1_test", "locked": true, "points": 2, "schema_version": 3, "solution": false}
# Exercise 1: autograder test
from filterpy.kalman import update as filterpy_update

mean_ref, var_ref = filterpy_update(
    np.array([2.0]), np.array([[0.5]]), np.array([2.6]), np.array([[0.25]]), np.eye(1)
)
assert np.isclose(mean_1d, mean_ref[0]) and np.isclose(var_1d, var_ref[0, 0]), (
    "not the updated mean and variance"
)
assert 0 < gain_1d < 1 and var_1d < min(0.5, 0.25), "fusing two estimates beats both"
### BEGIN HIDDEN TESTS
import filterpy.kalman  # noqa: E402

import vo_lib.line_slam.ekf_slam as ekf_module  # noqa: E402
import vo_lib.stereo_vo.kalman as kalman_module  # noqa: E402
from coursework import grading  # noqa: E402

_h1_m, _h1_p, _h1_z, _h1_r = np.random.default_rng(7011).uniform([-10, 0.01, -10, 0.01], [10, 5, 10, 5])
with grading.unavailable(*grading.library_functions(filterpy, kalman_module, ekf_module)):
    _h1_got = [float(np.squeeze(v)) for v in update_1d(_h1_m, _h1_p, _h1_z, _h1_r)]
_h1_k = _h1_p / (_h1_p + _h1_r)
_h1_expected = [_h1_k, _h1_m + _h1_k * (_h1_z - _h1_m), (1 - _h1_k) * _h1_p]
assert grading.close(_h1_got, _h1_expected), "update_1d: another update's gain, mean or variance (P/(P+R)?)"
### END HIDDEN TESTS

# %% [markdown]
# ### Exercise 2 · the NEES band *(medium, 3 points)*
#
# Section 6 judges the filter by its NEES averaged over N runs against a 95 % χ² band. Write
# `nees_band(n_runs, dim)` returning the band's (lower, upper) limits for the average NEES of a
# `dim`-dimensional state over `n_runs` runs, and `average_nees(errors, covariance)` returning,
# for the errors `(E, N, dim)` of E experiments of N runs each of an estimator that reports
# `covariance`, each experiment's NEES averaged over its runs (shape `(E,)`). The cell below
# draws 2,000 experiments of 50 runs of a *consistent* 3-D estimator (errors drawn from the
# covariance it reports): store the share of them inside the band in `share_inside`. Compute the
# band from SciPy's χ² distribution, not with `vo_lib`'s `chi2_band` (notebook 06 uses it).
#
# *Hint:* the sum of N independent χ²(d) values is χ²(N·d); `scipy.stats.chi2.ppf`.

# %%
band_rng = np.random.default_rng(7)
reported = np.diag([0.04, 0.01, 0.003])
experiment_errors = band_rng.multivariate_normal(np.zeros(3), reported, size=(2000, 50))


# %% nbgrader={"grade": false, "grade_id": "ex2", "locked": false, "schema_version": 3, "solution": true}
### BEGIN SOLUTION
def nees_band(n_runs, dim):
    """95 % band of the NEES of a ``dim``-state averaged over ``n_runs`` runs."""
    return tuple(chi2.ppf([0.025, 0.975], n_runs * dim) / n_runs)


def average_nees(errors, covariance):
    """NEES e^T C^-1 e of every run, averaged over the runs of each experiment."""
    errors = np.asarray(errors, float)
    return np.einsum("eri,ij,erj->er", errors, np.linalg.inv(covariance), errors).mean(axis=1)


low, high = nees_band(50, 3)
nees_each = average_nees(experiment_errors, reported)
share_inside = float(np.mean((nees_each > low) & (nees_each < high)))
print(f"band [{low:.2f}, {high:.2f}]; {share_inside:.1%} of the experiments inside")
### END SOLUTION

# %% nbgrader={"grade": true, "grade_id": "ex2_test", "locked": true, "points": 3, "schema_version": 3, "solution": false}
# Exercise 2: autograder test
low_check, high_check = nees_band(50, 3)
assert low_check < 3 < high_check, "the band holds the expected average NEES, the dimension"
assert abs(share_inside - 0.95) < 0.02, "a consistent estimator stays inside a 95 % band 95 % of the time"
assert nees_band(1000, 3)[1] - nees_band(1000, 3)[0] < high_check - low_check, "more runs, a narrower band"
assert np.shape(average_nees(experiment_errors[:10], reported)) == (10,), "one average per experiment"
### BEGIN HIDDEN TESTS
import scipy.stats  # noqa: E402

import vo_lib.comparison as comparison_module  # noqa: E402
import vo_lib.stereo_vo.consistency as consistency_module  # noqa: E402
import vo_lib.stereo_vo.kalman as kalman_module  # noqa: E402
from coursework import grading  # noqa: E402

_h2_rng = np.random.default_rng(7021)  # errors of a 4-D estimator with a full covariance
_h2_cov = np.cov(_h2_rng.normal(size=(4, 10)))
_h2_errors = _h2_rng.multivariate_normal(np.zeros(4), _h2_cov, size=(6, 20))
with grading.unavailable(
    *grading.library_functions(consistency_module, comparison_module.chi2_band, kalman_module.nis)
):
    _h2_band, _h2_nees = nees_band(37, 4), average_nees(_h2_errors, _h2_cov)
_h2_expected = np.einsum("eri,ij,erj->er", _h2_errors, np.linalg.inv(_h2_cov), _h2_errors).mean(axis=1)
assert grading.close(_h2_nees, _h2_expected), "average_nees: not each experiment's mean of eᵀ C⁻¹ e"
_h2_expected = scipy.stats.chi2.ppf([0.025, 0.975], 4 * 37) / 37
assert grading.close(_h2_band, _h2_expected), "nees_band: not the 95 % band (quantiles? degrees of freedom?)"
_h2_var = np.array([0.04, 0.01, 0.003])  # the experiments of the cell above, drawn again
_h2_drawn = np.random.default_rng(7).multivariate_normal(np.zeros(3), np.diag(_h2_var), (2000, 50))
_h2_each = (_h2_drawn**2 / _h2_var).sum(axis=2).mean(axis=1)
_h2_low, _h2_high = scipy.stats.chi2.ppf([0.025, 0.975], 150) / 50
assert grading.equal(share_inside, np.mean((_h2_each > _h2_low) & (_h2_each < _h2_high))), "share_inside"
### END HIDDEN TESTS

# %% [markdown]
# ### Exercise 3 · the covariance of a relative measurement *(hard, 4 points)*
#
# Stochastic cloning keeps two poses, a (the reference) and b (now), with a joint 6×6
# covariance, because visual odometry measures b relative to a. Write `relative_jacobian(a, b)`
# returning the 3×6 Jacobian of `relative_planar(a, b)` with respect to (a, b), in closed form
# (the grader checks it without `relative_planar` at hand). For the poses and covariance below
# store it at the mean in `J_rel`, and the first-order covariance of the relative pose in
# `cov_rel`. A Monte Carlo test checks both.
#
# *Hint:* d = Rᵀ(a_yaw) (b_xy − a_xy); differentiate by hand or with sympy.

# %%
pose_a, pose_b = np.array([1.0, 2.0, 0.4]), np.array([1.6, 2.5, 0.7])
joint_cov = np.diag([0.02, 0.03, 0.01, 0.025, 0.02, 0.012]) ** 2
joint_cov[2, 5] = joint_cov[5, 2] = 0.8 * 0.01 * 0.012  # the clone shares the heading error


# %% nbgrader={"grade": false, "grade_id": "ex3", "locked": false, "schema_version": 3, "solution": true}
### BEGIN SOLUTION
def relative_jacobian(a, b):
    """3x6 Jacobian of ``relative_planar(a, b)`` with respect to ``(a, b)``."""
    c_a, s_a = math.cos(a[2]), math.sin(a[2])
    delta = np.asarray(b[:2], float) - np.asarray(a[:2], float)
    R_t = np.array([[c_a, s_a], [-s_a, c_a]])  # rotates world into a's frame
    dR_t = np.array([[-s_a, c_a], [-c_a, -s_a]])  # its derivative in a's yaw
    J = np.zeros((3, 6))
    J[:2, :2], J[:2, 2], J[:2, 3:5] = -R_t, dR_t @ delta, R_t
    J[2, 2], J[2, 5] = -1.0, 1.0
    return J


J_rel = relative_jacobian(pose_a, pose_b)
cov_rel = J_rel @ joint_cov @ J_rel.T
### END SOLUTION

# %% nbgrader={"grade": true, "grade_id": "ex3_test", "locked": true, "points": 4, "schema_version": 3, "solution": false}
# Exercise 3: autograder test
mc_rng = np.random.default_rng(11)
draws = mc_rng.multivariate_normal(np.r_[pose_a, pose_b], joint_cov, size=200_000)
rel = relative_planar(draws[:, :3], draws[:, 3:])
assert J_rel.shape == (3, 6) and np.allclose(cov_rel, cov_rel.T), "J is 3 x 6; a covariance is symmetric"
mc_cov = np.cov(rel.T)
assert np.linalg.norm(cov_rel - mc_cov) < 0.02 * np.linalg.norm(mc_cov), "first order, against Monte Carlo"
### BEGIN HIDDEN TESTS
import vo_lib.geometry as geometry_module  # noqa: E402
import vo_lib.models.track_odometry as odometry_module  # noqa: E402
import vo_lib.stereo_vo.kalman as kalman_module  # noqa: E402
from coursework import grading  # noqa: E402

_h3_poses = np.random.default_rng(7031).uniform([-5, -5, -1.2] * 2, [5, 5, 1.2] * 2)  # new poses a, b
with grading.unavailable(*grading.library_functions(geometry_module, odometry_module, kalman_module)):
    _h3_J = relative_jacobian(_h3_poses[:3], _h3_poses[3:])
_h3c, _h3s, _h3d = math.cos(_h3_poses[2]), math.sin(_h3_poses[2]), _h3_poses[3:5] - _h3_poses[:2]
_h3R, _h3w = np.array([[_h3c, _h3s], [-_h3s, _h3c]]), np.array([[-_h3s, _h3c], [-_h3c, -_h3s]]) @ _h3d
_h3_expected = np.block([[-_h3R, _h3w[:, None], _h3R, np.zeros((2, 1))], [np.eye(1, 6, 5) - np.eye(1, 6, 2)]])
assert grading.close(_h3_J, _h3_expected, rtol=0, atol=1e-12), "relative_jacobian: not the exact derivative"
### END HIDDEN TESTS

# %% [markdown]
# ### Exercise 4 · the filter's predict and update *(hard, 4 points)*
#
# Write the two steps of this notebook's filter yourself, without `VoKalmanFilter` or filterpy.
# `ekf_predict(x, P, u, Q_u, odometry)` takes the pose belief `x` (3,), `P` (3×3), the track
# readings `u` and their covariance `Q_u`; it moves the pose with `odometry.step(x, u)` (which
# also returns F = ∂f/∂x and G = ∂f/∂u, eq. 6–11) and clones the previous pose: it returns the
# state [x′, x] (6,) and its covariance, [[F P Fᵀ + G Q_u Gᵀ, F P], [P Fᵀ, P]]. Then
# `ekf_update(x6, P6, z, R)` corrects that state with the measurement z = (θ, ρ, 0) (the last
# component: the motion stays on its chord) of covariance `R` (3×3): h = `constrained_measurement`,
# H = `constrained_jacobian`, the residual's θ wrapped to (−π, π], gain K = P Hᵀ S⁻¹ with
# S = H P Hᵀ + R, the covariance in Joseph form (I − KH) P (I − KH)ᵀ + K R Kᵀ, and the current
# yaw wrapped. Store the prediction of `ex_belief` below in `x6_pred, P6_pred`, and its update
# with `ex_z`, `ex_R` in `x6_post, P6_post`.
#
# *Hint:* `np.block` builds P6; `wrap_angle` wraps an angle.

# %%
ex_odometry = TrackOdometry(track_distance=0.45, track_width=0.08, encoder_sigma=0.004)
ex_belief = (np.array([1.0, 2.0, 0.3]), np.diag([0.01, 0.02, 0.002]))
ex_u = np.array([0.10, 0.13])
ex_z, ex_R = np.array([0.069, 0.116, 0.0]), np.diag([0.002**2, 0.003**2, SIDEWAYS_SIGMA**2])


# %% nbgrader={"grade": false, "grade_id": "ex4", "locked": false, "schema_version": 3, "solution": true}
### BEGIN SOLUTION
def ekf_predict(x, P, u, Q_u, odometry):
    """The pose moved by odometry ``u`` and the previous pose cloned: ``(x6, P6)``."""
    x, P = np.asarray(x, float), np.asarray(P, float)
    x_new, F, G = odometry.step(x, u)
    P6 = np.block([[F @ P @ F.T + G @ np.asarray(Q_u, float) @ G.T, F @ P], [P @ F.T, P]])
    return np.concatenate([x_new, x]), P6


def ekf_update(x6, P6, z, R):
    """The cloned state corrected by the measurement ``z = (theta, rho, 0)`` (Joseph form)."""
    x6, P6, R = np.asarray(x6, float), np.asarray(P6, float), np.asarray(R, float)
    H = constrained_jacobian(x6)
    y = np.asarray(z, float) - constrained_measurement(x6)
    y[0] = wrap_angle(y[0])
    K = P6 @ H.T @ np.linalg.inv(H @ P6 @ H.T + R)
    x_post = x6 + K @ y
    x_post[2] = wrap_angle(x_post[2])
    I_KH = np.eye(6) - K @ H
    return x_post, I_KH @ P6 @ I_KH.T + K @ R @ K.T


x6_pred, P6_pred = ekf_predict(*ex_belief, ex_u, ex_odometry.control_covariance(ex_u), ex_odometry)
x6_post, P6_post = ekf_update(x6_pred, P6_pred, ex_z, ex_R)
print(f"predicted pose {x6_pred[:3].round(4)}, corrected {x6_post[:3].round(4)}")
### END SOLUTION

# %% nbgrader={"grade": true, "grade_id": "ex4_test", "locked": true, "points": 4, "schema_version": 3, "solution": false}
# Exercise 4: autograder test
assert np.shape(x6_pred) == (6,) and np.shape(P6_pred) == (6, 6), "a cloned state of six"
assert np.allclose(x6_pred[3:], ex_belief[0]) and np.allclose(P6_pred[3:, 3:], ex_belief[1]), "the clone"
assert np.allclose(P6_post, P6_post.T) and np.trace(P6_post[:3, :3]) < np.trace(P6_pred[:3, :3]), (
    "an update makes the current pose surer"
)
### BEGIN HIDDEN TESTS
import filterpy  # noqa: E402

import vo_lib.line_slam.ekf_slam as ekf_module  # noqa: E402
import vo_lib.models.track_odometry as odometry_module  # noqa: E402
import vo_lib.stereo_vo.kalman as kalman_module  # noqa: E402
from coursework import grading  # noqa: E402

_h4_rng = np.random.default_rng(7041)  # a new belief, then a straight step from a yaw next to -π
_h4_x, _h4_P = _h4_rng.uniform(-3, 3, 3), np.diag(_h4_rng.uniform(0.001, 0.01, 3))
_h4_u, _h4_R = _h4_rng.uniform(0.05, 0.2, 2), np.diag(_h4_rng.uniform(0.001, 0.01, 3) ** 2)
_h4_cases = ((_h4_x, _h4_u, 0.05 - math.tau), (np.r_[1, 2, 0.002 - np.pi], np.full(2, 0.1), math.tau - 0.03))
for _h4_pose, _h4_step, _h4_turn in _h4_cases:  # measured turns written 2π away; the second crosses ±π
    _h4_kf = kalman_module.VoKalmanFilter(odometry_module.TrackOdometry(), pose=_h4_pose, covariance=_h4_P)
    _h4_Q, _h4_z = _h4_kf.control_covariance(_h4_step), np.array([_h4_turn, 0.1, 0.0])
    with grading.unavailable(*grading.library_functions(kalman_module.VoKalmanFilter, filterpy, ekf_module)):
        _h4_x6, _h4_P6 = ekf_predict(_h4_pose, _h4_P, _h4_step, _h4_Q, _h4_kf.odometry)
        _h4_x6_post, _h4_P6_post = ekf_update(_h4_x6, _h4_P6, _h4_z, _h4_R)
    _h4_kf.predict(_h4_step)  # the library's predict and update, after the answer ran
    assert grading.close(_h4_x6, _h4_kf.ekf.x), "ekf_predict: not [moved pose, previous pose]"
    assert grading.close(_h4_P6, _h4_kf.ekf.P), "ekf_predict: not the cloned covariance (cross terms F P?)"
    _h4_kf.update(_h4_z[0], _h4_z[1], _h4_R)
    assert grading.close(_h4_x6_post, _h4_kf.ekf.x), "ekf_update: not the corrected state (θ, yaw wrapped?)"
    assert grading.close(_h4_P6_post, _h4_kf.ekf.P), "ekf_update: not the corrected covariance"
### END HIDDEN TESTS

# %% [markdown]
# ### Stretch goals (not graded)
#
# - Replace the full Jacobians of the prediction by eq. 9's F = I and repeat section 6: what
#   happens to the NEES, and why?
# - The slip in our drives has a mean, not only noise. Augment the state with the slip fraction
#   and estimate it online. How fast does it converge in the spot turn?
# - Without odometry the filter predicts with constant velocity: run section 4's drive with
#   `kf.predict(None)` and compare the growth of the predicted covariance, which sets the size of
#   the guided matching windows of notebook 05.
