"""Demonstration scaffolding of notebook 12 (a real drive), kept out of its story cells.

Frame-to-frame motions of a sequence read three ways by the circular-motion model and the 6-DoF
refinement, chained into planar poses.
"""

from __future__ import annotations

import numpy as np

from vo_lib.geometry import compose_planar
from vo_lib.stereo_vo import rigid_motion
from vo_lib.stereo_vo.circular_motion import motion_transform, robot_increment
from vo_lib.stereo_vo.ransac import one_point_ransac
from vo_lib.stereo_vo.six_dof import PREDICTED_RATIO, WINDOW_PIXELS, vehicle_increment, windows
from vo_lib.stereo_vo.temporal import match_features, predict_features


def chain_models(seq, mount: np.ndarray, camera_path, ransac_rng: np.random.Generator, frame_features):
    """Planar vehicle poses from frame-to-frame motions read three ways: the circular model for a
    camera on the turning axis, the same circular camera motion carried through ``mount``, and the
    6-DoF refinement of RANSAC's inliers carried through ``mount``; 1-point RANSAC draws from
    ``ransac_rng`` on the frames' features ``frame_features``, matched around ``camera_path``."""
    names = ("circular, camera on the axis", "circular, through the mount", "6-DoF, through the mount")
    chains = {name: [np.zeros(3)] for name in names}
    prev = frame_features[0]
    for k in range(1, len(seq)):
        curr = frame_features[k]
        T_pred = np.linalg.inv(camera_path[k]) @ camera_path[k - 1]
        predicted, _ = predict_features(prev.w, seq.camera, T_pred)
        mt = match_features(prev, curr, predicted, windows(predicted, WINDOW_PIXELS), PREDICTED_RATIO)
        est = one_point_ransac(mt.w_prev, mt.w_curr, seq.camera, rng=ransac_rng, pixel_sigma=1.0)
        guess = motion_transform(est.theta, est.rho)
        refined = rigid_motion.refine_rigid_motion(mt.w_prev, mt.w_curr, seq.camera, guess, est.inliers)
        increments = (
            robot_increment(est.theta, est.rho),
            vehicle_increment(guess, mount),
            vehicle_increment(refined.matrix, mount),
        )
        for name, inc in zip(names, increments, strict=True):
            chains[name].append(compose_planar(chains[name][-1], inc))
        prev = curr
    return {name: np.array(poses) for name, poses in chains.items()}
