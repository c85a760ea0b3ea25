"""[Yuan]'s VO-assisted LIDAR pose tracking: ``python -m vo_lib bench tracking|odometers``."""

from __future__ import annotations

import math

import numpy as np

from vo_lib.bench.common import BENCH_SEED, format_row, median_seconds, met


def bench_tracking() -> dict[str, float]:
    """[Yuan]: scoring 500 sample poses against a 271-beam scan, vectorised and pose by pose."""
    from vo_lib.lidar_tracking.corridor_experiment import TIM551
    from vo_lib.lidar_tracking.likelihood_field import LikelihoodField
    from vo_lib.lidar_tracking.pose_tracking import sample_poses
    from vo_lib.sim.world import corridor

    world = corridor()
    field = LikelihoodField.from_world(world)
    rng = np.random.default_rng(BENCH_SEED)
    scan = TIM551.scan(world.segments_array(), (9.0, 0.0, 0.0), rng)
    points = scan.points()
    samples = sample_poses(np.array([9.0, 0.0, 0.0]), 500, rng)
    vectorised = median_seconds(lambda: field.score(samples, points), repeat=15, min_time=0.3)
    loop = median_seconds(lambda: [field.score(p[None], points) for p in samples], repeat=5, min_time=0.3)
    print(f"LBPT scoring: 500 samples x {len(scan.bearings)} beams ({len(points)} echoes), likelihood field")
    print(format_row("pose by pose (baseline)", loop, loop))
    print(format_row("vectorised LikelihoodField.score", vectorised, loop))
    print(f"  target <= 10 ms: {met(vectorised <= 0.01)}")
    return {"score 500": vectorised}


def bench_odometers() -> dict[str, float]:
    """[Yuan]'s PnP visual odometer beside [Zhao]'s 1-point pipeline on the rendered corridor."""
    from vo_lib.geometry import planar_from_camera_poses
    from vo_lib.lidar_tracking.pnp_odometry import run_pnp_odometry
    from vo_lib.sim.samples import render_sample
    from vo_lib.stereo_vo.pipeline import run_frames

    rendered, frame_iter = render_sample("corridor")
    images = list(frame_iter)  # render first: only the odometers are timed
    truth = rendered.truth() - rendered.truth()[0]
    travelled = float(np.hypot(*truth[-1, :2]))
    poses, times, _ = run_pnp_odometry(rendered.camera, images)
    pnp_planar = planar_from_camera_poses(poses, rendered.mount)
    one = run_frames(iter([(a, b, None) for a, b, _ in images]), rendered.camera)
    one_planar = one.poses - one.poses[0]
    print(f"corridor sample, {len(images)} frames, {travelled:.1f} m, 640x480, no wheel odometry")
    print(f"  {'odometer':<36s}{'ms/frame':>10s}{'final error':>14s}{'heading':>10s}")
    rows = {
        "PnP + local map [Yuan]": (float(np.median(times)), pnp_planar),
        "1-point RANSAC + Kalman [Zhao]": (one.timing_table()["total"] / 1e3, one_planar),
    }
    for name, (t, p) in rows.items():
        err = float(np.hypot(*(p[-1, :2] - truth[-1, :2])))
        head = math.degrees(abs(float(p[-1, 2] - truth[-1, 2])))
        print(f"  {name:<36s}{t * 1e3:10.1f}{err * 100:10.2f} cm ({100 * err / travelled:.2f} %){head:8.3f}°")
    return {name: t for name, (t, _) in rows.items()}
