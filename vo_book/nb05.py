"""Small measurements of notebook 05 (stereo front end), kept out of its story cells."""

from __future__ import annotations

import math

import numpy as np

from vo_lib.geometry import camera_motion, planar_to_matrix
from vo_lib.stereo_vo.circular_motion import apply_motion, circular_motion_from_transform
from vo_lib.stereo_vo.temporal import MotionPrior, match_temporal


def cells_covered(points: np.ndarray, cell: int = 80) -> int:
    """Number of ``cell``-pixel grid cells that hold at least one of the image ``points`` (u, v)."""
    return len(np.unique((points[:, 0] // cell).astype(int) * 10 + (points[:, 1] // cell).astype(int)))


def matching_rows(drive, renderer, front, camera, mount, rng) -> dict[str, np.ndarray]:
    """Section 5 on one drive (planar poses ``drive``, the images' noise drawn from ``rng``): for
    each pair of consecutive frames and each matcher (guided, by a prediction off by 0.1° and
    5 mm; brute force), a row of the matches, the share of them more than 3 px from where the
    true motion puts them, the pairs compared and the milliseconds."""
    frames = [front.process(*renderer.render_pair(planar_to_matrix(p) @ mount, rng)) for p in drive]
    rows = {"guided": [], "brute force": []}
    for k in range(1, len(frames)):
        theta, rho = circular_motion_from_transform(camera_motion(drive[k - 1], drive[k], mount))
        prior = MotionPrior(
            theta + math.radians(0.1), rho + 0.005, np.diag([math.radians(0.3) ** 2, 0.01**2])
        )
        for name, predicted in (("guided", prior), ("brute force", None)):
            mt = match_temporal(frames[k - 1], frames[k], camera, predicted)
            moved = camera.project(apply_motion(camera.backproject(mt.w_prev), theta, rho))
            wrong = np.linalg.norm(moved[:, :2] - mt.w_curr[:, :2], axis=1) > 3.0
            rows[name].append((len(mt), wrong.mean(), mt.candidates, mt.timings["temporal_match"]))
    return {name: np.array(r) for name, r in rows.items()}
