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
    from vo_lib.circular_motion import rho_from_pixels, theta_from_pixels
    from vo_lib.synthetic import synthetic_matches

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
    from vo_lib.laser import LaserScanner
    from vo_lib.render import StereoRenderer
    from vo_lib.world import WORLDS

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
        from vo_lib.laser import cast_rays

        return [cast_rays(segments, (0.0, 0.0), np.array([b])) for b in scanner.bearings]

    base = median_seconds(loop_scan, repeat=5)
    t = median_seconds(lambda: scanner.scan(segments, (0.0, 0.0, 0.0), rng))
    times["laser scan"] = t
    print(f"laser scan, {beams} beams x {len(segments)} segments")
    print(format_row("ray by ray (baseline)", base, base))
    print(format_row("vectorised LaserScanner.scan", t, base))
    print(f"  target <= 2 ms: {'met' if t <= 2e-3 else 'NOT met'}")
    return times


BENCHES: dict[str, Callable[[], dict[str, float]]] = {
    "geometry": bench_geometry,
    "sensors": bench_sensors,
}
