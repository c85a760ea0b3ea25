"""Benchmarks, run as ``python -m vo_lib bench NAME``: each prints its times beside a baseline.

Times are medians of repeated runs on data drawn once with a fixed seed, so a run compares
like with like; they are measurements to read, never assertions.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

import numpy as np

BENCH_SEED = 20261121


def median_seconds(fn: Callable[[], object], repeat: int = 50, min_time: float = 0.2) -> float:
    """Median wall time of one call of ``fn`` over ``repeat`` batches lasting about ``min_time`` in all."""
    fn()  # warm caches and lazy imports
    t0 = time.perf_counter()
    fn()
    once = max(time.perf_counter() - t0, 1e-7)
    number = max(1, int(min_time / repeat / once))
    samples = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(number):
            fn()
        samples.append((time.perf_counter() - t0) / number)
    return float(np.median(samples))


def format_row(name: str, seconds: float, baseline: float | None = None) -> str:
    """One table row: name, time in milliseconds and the speed-up over the baseline."""
    ratio = "" if baseline is None else f"{baseline / seconds:10.1f}x"
    return f"  {name:<46s}{seconds * 1e3:12.4f} ms{ratio}"


def bench_geometry(n: int = 10_000) -> dict[str, float]:
    """theta (eq. 14) and rho (eq. 17) for ``n`` matches: vectorised, 3-D route, pure-Python loop."""
    from vo_lib.camera import StereoCamera
    from vo_lib.stereo_vo.circular_motion import rho_from_pixels, theta_from_pixels
    from vo_lib.stereo_vo.synthetic import synthetic_matches

    cam = StereoCamera.bumblebee2()
    m = synthetic_matches(cam, n, 0.04, 0.08, np.random.default_rng(BENCH_SEED))
    a, b = m.w_prev, m.w_curr

    def vectorised():
        theta = theta_from_pixels(a, b, cam)
        return rho_from_pixels(a, b, theta, cam)

    def via_points():
        # eq. 12 on back-projected points, then eq. 16 on the same points
        P, Q = cam.backproject(a), cam.backproject(b)
        phi = np.arctan((Q[:, 0] * P[:, 1] - P[:, 0] * Q[:, 1]) / (P[:, 1] * Q[:, 2] + Q[:, 1] * P[:, 2]))
        s, c = np.sin(phi), np.cos(phi)
        return -s * P[:, 0] + c * P[:, 2] - s * Q[:, 0] - c * Q[:, 2]

    rows = [tuple(r) for r in np.column_stack([a, b]).tolist()]
    u0, v0, f, B = cam.cx, cam.cy, cam.fx, cam.baseline

    def python_loop():
        out = []
        for u, v, d, u2, v2, d2 in rows:
            phi = math.atan(((u2 - u0) * (v - v0) - (u - u0) * (v2 - v0)) / (f * (v + v2 - 2 * v0)))
            s, c = math.sin(phi), math.cos(phi)
            out.append(B / d * (-s * (u - u0) + c * f) - B / d2 * (s * (u2 - u0) + c * f))
        return out

    loop = median_seconds(python_loop, repeat=7)
    times = {
        "python loop (baseline)": loop,
        "3-D points, eq. 12 + 16": median_seconds(via_points),
        "vo_lib theta_from_pixels + rho_from_pixels": median_seconds(vectorised),
    }
    print(f"theta and rho for {n} matches (median time per call; speed-up over the loop)")
    for name, t in times.items():
        print(format_row(name, t, loop))
    target = 1e-3
    t = times["vo_lib theta_from_pixels + rho_from_pixels"]
    print(f"  target < {target * 1e3:.1f} ms: {'met' if t < target else 'NOT met'} ({t / target:.2f} of it)")
    return times


def bench_sensors() -> dict[str, float]:
    """Stereo pairs per second of the renderer in each world; time of one 811-beam laser scan."""
    from vo_lib.camera import StereoCamera
    from vo_lib.geometry import camera_mount, planar_to_matrix
    from vo_lib.sim.laser import LaserScanner
    from vo_lib.sim.render import StereoRenderer
    from vo_lib.sim.world import WORLDS

    cam = StereoCamera.bumblebee2()
    mount = camera_mount(height=0.5)
    views = {"indoor_lab": (-3.0, 0.0, 0.2), "outdoor_yard": (0.0, 0.0, 0.3), "corridor": (2.0, 0.0, 0.0)}
    times = {}
    print("stereo renderer, 640x480 pairs (median over repeated renders)")
    for name, pose in views.items():
        renderer = StereoRenderer(WORLDS[name](), cam)
        T = planar_to_matrix(pose) @ mount
        t = median_seconds(lambda r=renderer, T=T: r.render_pair(T), repeat=15, min_time=1.0)
        times[f"render {name}"] = t
        print(f"  {name:<14s}{t * 1e3:9.2f} ms per pair {1 / t:8.1f} pairs/s (target >= 20)")
    rng = np.random.default_rng(BENCH_SEED)
    segments = rng.uniform(-10, 10, (100, 4))
    scanner = LaserScanner()
    beams = len(scanner.bearings)

    def loop_scan():
        # baseline: one ray at a time against all segments
        from vo_lib.sim.laser import cast_rays

        return [cast_rays(segments, (0.0, 0.0), np.array([b])) for b in scanner.bearings]

    base = median_seconds(loop_scan, repeat=5)
    t = median_seconds(lambda: scanner.scan(segments, (0.0, 0.0, 0.0), rng))
    times["laser scan"] = t
    print(f"laser scan, {beams} beams x {len(segments)} segments")
    print(format_row("ray by ray (baseline)", base, base))
    print(format_row("vectorised LaserScanner.scan", t, base))
    print(f"  target <= 2 ms: {'met' if t <= 2e-3 else 'NOT met'}")
    return times


def bench_ransac(sets: int = 15, n: int = 300) -> dict[str, float]:
    """1-point RANSAC against 3-point rigid RANSAC and solvePnPRansac on the same matches."""
    import math

    from vo_lib.camera import StereoCamera
    from vo_lib.stereo_vo.baselines import pnp_ransac, rigid_ransac
    from vo_lib.stereo_vo.ransac import one_point_ransac
    from vo_lib.stereo_vo.synthetic import synthetic_matches

    cam = StereoCamera.bumblebee2()
    rng = np.random.default_rng(BENCH_SEED)
    cases = []
    for _ in range(sets):
        theta, rho = math.radians(rng.uniform(-5, 5)), rng.uniform(0.03, 0.12)
        cases.append(
            (theta, rho, synthetic_matches(cam, n, theta, rho, rng, noise_px=0.5, outlier_ratio=0.4))
        )
    methods = {
        "1-point RANSAC + refinement": lambda m: one_point_ransac(m.w_prev, m.w_curr, cam, rng=1),
        "3-point rigid RANSAC (3-D to 3-D)": lambda m: rigid_ransac(m.w_prev, m.w_curr, cam, rng=1),
        "OpenCV solvePnPRansac (6 DoF)": lambda m: pnp_ransac(m.w_prev, m.w_curr, cam),
    }
    results = {}
    for name, fn in methods.items():
        times, t_err, r_err = [], [], []
        for theta, rho, m in cases:
            times.append(median_seconds(lambda fn=fn, m=m: fn(m), repeat=7, min_time=0.05))
            est = fn(m)
            t_err.append(abs(est.theta - theta))
            r_err.append(abs(est.rho - rho) / rho)
        results[name] = (
            float(np.median(times)),
            math.degrees(float(np.median(t_err))),
            math.degrees(float(np.max(t_err))),
            float(np.median(r_err)),
        )
    base = results["1-point RANSAC + refinement"][0]
    print(f"{sets} sets of {n} matches, 40 % outliers, 0.5 px noise (median over sets, same matches)")
    print(
        f"  {'method':<38s}{'time':>10s}{'x 1-point':>11s}{'med |dθ|':>11s}"
        f"{'max |dθ|':>11s}{'med |dρ|/ρ':>12s}"
    )
    for name, (t, tm, tx, rm) in results.items():
        print(f"  {name:<38s}{t * 1e3:8.3f} ms{t / base:10.1f}x{tm:10.4f}°{tx:10.4f}°{100 * rm:10.2f} %")
    print(
        f"  target: 1-point <= 0.3 ms ({'met' if base <= 3e-4 else 'NOT met'}: {base * 1e3:.3f} ms); "
        f"solvePnPRansac / 1-point >= 10 ({results['OpenCV solvePnPRansac (6 DoF)'][0] / base:.1f})"
    )
    return {name: r[0] for name, r in results.items()}


def bench_frontend(frames: int = 30) -> dict[str, float]:
    """Per-stage medians of the stereo front end at 640x480 along a rendered drive, and one Kalman step."""
    from vo_lib.camera import StereoCamera
    from vo_lib.geometry import camera_motion, camera_mount, planar_to_matrix
    from vo_lib.sim.render import SensorEffects, StereoRenderer
    from vo_lib.sim.samples import SAMPLES
    from vo_lib.sim.trajectories import simulate_drive
    from vo_lib.sim.world import WORLDS
    from vo_lib.stereo_vo.circular_motion import circular_motion_from_transform
    from vo_lib.stereo_vo.features import StereoFrontEnd
    from vo_lib.stereo_vo.kalman import VoKalmanFilter
    from vo_lib.stereo_vo.temporal import MotionPrior, match_temporal

    cam = StereoCamera.bumblebee2()
    sample = SAMPLES["indoor_free"]
    drive = simulate_drive(sample.legs, sample.rate, sample.start, np.random.default_rng(sample.seed))
    renderer = StereoRenderer(WORLDS[sample.world](), cam, SensorEffects(noise_sigma=1.0))
    mount = camera_mount(height=0.5)
    rng = np.random.default_rng(BENCH_SEED)
    poses = drive.poses[100 : 100 + frames]
    pairs = [renderer.render_pair(planar_to_matrix(p) @ mount, rng) for p in poses]
    front = StereoFrontEnd(cam)
    stages = {"detect": [], "describe": [], "stereo_match": [], "total": []}
    feats = []
    for left, right in pairs:
        for _ in range(3):  # repeated, the median of three is the frame's time
            t0 = time.perf_counter()
            f = front.process(left, right)
            stages["total"].append((time.perf_counter() - t0) * 1e3)
            for k in ("detect", "describe", "stereo_match"):
                stages[k].append(f.timings[k])
        feats.append(f)
    guided, brute = [], []
    for k in range(1, len(feats)):
        T = camera_motion(poses[k - 1], poses[k], mount)
        theta, rho = circular_motion_from_transform(T)
        prior = MotionPrior(theta, rho, np.diag([np.radians(0.5) ** 2, 0.01**2]))
        guided.append(match_temporal(feats[k - 1], feats[k], cam, prior).timings["temporal_match"])
        brute.append(match_temporal(feats[k - 1], feats[k], cam, None).timings["temporal_match"])
    kf = VoKalmanFilter()
    u, R = np.array([0.01, 0.011]), np.diag([1e-6, 1e-6])

    def kalman_step():
        kf.predict(u)
        kf.update(0.002, 0.01, R)
        kf.finish_frame()

    t_kf = median_seconds(kalman_step)
    print(f"stereo front end at 640x480, {frames} rendered frames of indoor_free (median ms)")
    for k, v in stages.items():
        print(f"  {k:<28s}{np.median(v):8.2f} ms")
    print(f"  stereo features per frame   {np.median([len(f) for f in feats]):8.0f}")
    print(
        f"  temporal matching, guided   {np.median(guided):8.2f} ms   (brute force {np.median(brute):.2f} ms)"
    )
    print(f"  Kalman step (predict+update) {t_kf * 1e3:7.3f} ms")
    total = float(np.median(stages["total"]))
    print(
        f"  targets: front end <= 8 ms ({'met' if total <= 8 else 'NOT met'}: {total:.2f}); "
        f"Kalman <= 0.1 ms ({'met' if t_kf <= 1e-4 else 'NOT met'}: {t_kf * 1e3:.3f})"
    )
    return {"front_end": total / 1e3, "kalman": t_kf}


def bench_pipeline(frames: int = 200) -> dict[str, float]:
    """The whole pipeline per frame at 640x480 on a rendered indoor drive (images in memory)."""
    from vo_lib.sim.samples import render_sample
    from vo_lib.stereo_vo.pipeline import run_frames

    rendered, frame_iter = render_sample("indoor_free", frames)
    images = list(frame_iter)  # render first: only the pipeline is timed
    result = run_frames(iter(images), rendered.camera)
    table = result.timing_table()
    print(f"stereo VO pipeline, {frames} frames of indoor_free at 640x480 (median ms per frame)")
    for key, label in (
        ("stereo", "stereo processing"),
        ("prediction", "prediction"),
        ("matching", "guided temporal matching"),
        ("estimation", "1-point RANSAC"),
        ("kalman", "Kalman filtering"),
        ("total", "whole frame"),
    ):
        print(f"  {label:<28s}{table[key]:8.2f} ms")
    fps = 1000.0 / table["total"]
    inliers = float(np.median([d.inliers for d in result.diagnostics[1:]]))
    print(
        f"  frames per second {fps:.0f} (target >= 60: {'met' if fps >= 60 else 'NOT met'}); "
        f"median inliers {inliers:.0f} (target >= 200: {'met' if inliers >= 200 else 'NOT met'})"
    )
    return {"frame": table["total"] / 1e3}


def bench_observers(laps: int = 3) -> dict[str, float]:
    """Seed 002's observers on every (segment, pose) call of one simulated lap, and whole laps."""
    from vo_lib.line_slam.lap import LineSlamScenario, simulate_lap
    from vo_lib.line_slam.line_landmarks import paper_world
    from vo_lib.line_slam.segment_observers import DEFAULT_TOLERANCE, OBSERVERS

    calls = []
    for extended in (False, True):
        run = simulate_lap(BENCH_SEED, scenario=LineSlamScenario(extended=extended))
        segs = [(s.start, s.end) for s in paper_world(extended).segments]
        calls += [(a, b, tuple(run.truth[k, :2])) for k in run.observed_at for a, b in segs]

    def all_calls(fn):
        return lambda: [fn(a, b, g, 30.0, DEFAULT_TOLERANCE) for a, b, g in calls]

    per_call = {
        name: median_seconds(all_calls(fn), repeat=7, min_time=0.5) / len(calls)
        for name, fn in OBSERVERS.items()
    }
    lap = {
        name: float(np.median([simulate_lap(BENCH_SEED + i, name).seconds for i in range(laps)]))
        for name in OBSERVERS
    }
    base = per_call["point_by_point"]
    print(
        f"{len(calls)} observer calls (4 segments x every observation of a lap, normal and out-of-range "
        f"landmark 3), tolerance {DEFAULT_TOLERANCE * 100:.0f} cm"
    )
    print(
        f"  {'observer':<18s}{'per call':>12s}{'point/this':>12s}{'one lap':>10s}   paper (MATLAB, one run)"
    )
    paper = {"point_by_point": "42.2-44.8 s", "bisection": "8.6-9.6 s", "closed_form": "-"}
    for name in OBSERVERS:
        print(
            f"  {name:<18s}{per_call[name] * 1e6:9.2f} µs{base / per_call[name]:11.1f}x"
            f"{lap[name]:9.2f} s   {paper[name]}"
        )
    ratio_b, ratio_c = base / per_call["bisection"], base / per_call["closed_form"]
    print(
        f"  targets: point/bisection >= 4.5 ({'met' if ratio_b >= 4.5 else 'NOT met'}: {ratio_b:.1f}; "
        f"paper about 5); point/closed form >= 20 ({'met' if ratio_c >= 20 else 'NOT met'}: {ratio_c:.1f}); "
        f"lap with closed form <= 3 s ({'met' if lap['closed_form'] <= 3 else 'NOT met'}: "
        f"{lap['closed_form']:.2f} s)"
    )
    return {**{f"call {k}": v for k, v in per_call.items()}, **{f"lap {k}": v for k, v in lap.items()}}


def bench_tracking() -> dict[str, float]:
    """Seed 004: scoring 500 sample poses against a 271-beam scan, vectorised and pose by pose."""
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
    print(f"  target <= 10 ms: {'met' if vectorised <= 0.01 else 'NOT met'}")
    return {"score 500": vectorised}


def bench_odometers(frames: int | None = None) -> dict[str, float]:
    """Seed 004's PnP visual odometer beside seed 000's 1-point pipeline on the rendered corridor."""
    from vo_lib.geometry import planar_from_camera_poses
    from vo_lib.lidar_tracking.pnp_odometry import run_pnp_odometry
    from vo_lib.sim.samples import render_sample
    from vo_lib.stereo_vo.pipeline import run_frames

    rendered, frame_iter = render_sample("corridor", frames)
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
        "PnP + local map (seed 004)": (float(np.median(times)), pnp_planar),
        "1-point RANSAC + Kalman (seed 000)": (one.timing_table()["total"] / 1e3, one_planar),
    }
    for name, (t, p) in rows.items():
        err = float(np.hypot(*(p[-1, :2] - truth[-1, :2])))
        head = math.degrees(abs(float(p[-1, 2] - truth[-1, 2])))
        print(f"  {name:<36s}{t * 1e3:10.1f}{err * 100:10.2f} cm ({100 * err / travelled:.2f} %){head:8.3f}°")
    return {name: t for name, (t, _) in rows.items()}


BENCHES: dict[str, Callable[[], dict[str, float]]] = {
    "pipeline": bench_pipeline,
    "ransac": bench_ransac,
    "frontend": bench_frontend,
    "geometry": bench_geometry,
    "sensors": bench_sensors,
    "observers": bench_observers,
    "tracking": bench_tracking,
    "odometers": bench_odometers,
}
