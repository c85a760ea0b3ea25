"""Demonstration scaffolding of notebook 03 (circular motion, numeric checks), kept out of its story.

The Monte Carlo widget of one match's θ, the scene draws of the off-axis camera and the tilted
rig. The model itself is :mod:`vo_lib.stereo_vo.circular_motion`.
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from scipy.spatial.transform import Rotation

from vo_book.plotting import new_axes
from vo_lib.camera import StereoCamera
from vo_lib.geometry import camera_motion, camera_mount
from vo_lib.stereo_vo import circular_motion as cm
from vo_lib.stereo_vo.synthetic import matches_under_transform

#: The notebook's base seed: the widget's Monte Carlo draws from it.
SEED = 3
camera = StereoCamera.bumblebee2()
#: A camera 0.3 m ahead of the turning axis, 0.5 m up: the off-axis mount of section 5.
offset_mount = camera_mount(forward=0.3, height=0.5)
#: The planar motion (θ = 3°, ρ = 8 cm) to which section 6 adds pitch and roll.
tilt_theta, tilt_rho = np.radians(3.0), 0.08


def robust_sd(values: np.ndarray) -> float:
    """Median absolute deviation scaled to a Gaussian standard deviation."""
    return 1.4826 * np.median(np.abs(values - np.median(values)))


def theta_spread(v_offset_px=60.0, u_offset_px=100.0, depth_m=5.0, noise_px=0.5, theta_deg=2.0, rho_m=0.08):
    """Monte Carlo spread of eq. 14's theta for one match, against the first-order model."""
    local = np.random.default_rng(SEED)
    w = np.array([[camera.cx + u_offset_px, camera.cy + v_offset_px, camera.fx * camera.baseline / depth_m]])
    P = camera.backproject(w)
    P2 = cm.apply_motion(P, np.radians(theta_deg), rho_m)
    w2 = camera.project(P2)
    runs = 5000
    a = np.repeat(w, runs, axis=0) + local.normal(0, noise_px, (runs, 3))
    b = np.repeat(w2, runs, axis=0) + local.normal(0, noise_px, (runs, 3))
    th_runs = np.degrees(cm.theta_from_pixels(a, b, camera))
    sigma_model = np.degrees(cm.theta_standard_deviation(w, w2, camera, noise_px)[0])
    sigma_mc = 1.4826 * np.median(np.abs(th_runs - np.median(th_runs)))
    fig, ax = new_axes(width=6, height=3.5)
    lim = theta_deg + np.array([-5, 5]) * max(sigma_model, 1e-3)
    ax.hist(np.clip(th_runs, *lim), bins=80, range=tuple(lim), density=True, alpha=0.7)
    ax.axvline(theta_deg, color="k", lw=1, label="true θ")
    ax.set_xlabel("θ from one match [deg]")
    ax.set_title(f"σθ: Monte Carlo {sigma_mc:.3f}°, first-order model {sigma_model:.3f}°")
    ax.legend(fontsize="small")
    plt.show()
    return sigma_mc, sigma_model


def offset_share(seed):
    """Median |θ error| / θ of an arc and of a spot turn seen from the same scene draw."""
    out = {}
    for label, chord in (("the spot turn", 0.0), ("the arc", 0.08)):
        T = camera_motion(np.zeros(3), cm.robot_increment(np.radians(2), chord), offset_mount)
        mm = matches_under_transform(camera, 1000, T, np.random.default_rng(seed))
        ok = ~cm.degenerate_theta_mask(mm.w_prev, mm.w_curr, camera, min_pixels=20)
        out[label] = np.median(np.abs(cm.theta_from_pixels(mm.w_prev, mm.w_curr, camera)[ok] - np.radians(2)))
    return {k: v / np.radians(2) for k, v in out.items()}


def tilted_matches(pitch_deg, roll_deg, rng, noise_px=0.0, n=400):
    """Matches of the planar motion (tilt_theta, tilt_rho) with a pitch and roll added to it."""
    R, T = cm.motion_matrices(tilt_theta, tilt_rho)
    M = np.eye(4)
    M[:3, :3] = R @ Rotation.from_euler("xz", [pitch_deg, roll_deg], degrees=True).as_matrix()
    M[:3, 3] = T
    return matches_under_transform(camera, n, M, rng, noise_px=noise_px)
