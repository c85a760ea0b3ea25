"""The simulated sensors: ``python -m vo_lib bench sensors``."""

from __future__ import annotations

import numpy as np

from vo_lib.bench.common import BENCH_SEED, format_row, median_seconds, met


def bench_sensors() -> dict[str, float]:
    """Stereo pairs per second of the renderer in each world; time of one 811-beam laser scan."""
    from vo_lib.camera import StereoCamera
    from vo_lib.geometry import camera_mount, planar_to_matrix
    from vo_lib.sim.laser import LaserScanner, cast_rays
    from vo_lib.sim.render import StereoRenderer
    from vo_lib.sim.world import WORLDS

    cam = StereoCamera.bumblebee2()
    # pose (x, y, yaw) and camera height: the crawler's 0.5 m, a car's 1.65 m on the road
    views = {
        "indoor_lab": ((-3.0, 0.0, 0.2), 0.5),
        "outdoor_yard": ((0.0, 0.0, 0.3), 0.5),
        "corridor": ((2.0, 0.0, 0.0), 0.5),
        "road": ((20.0, 0.0, 0.0), 1.75),
    }
    times = {}
    print("stereo renderer, 640x480 pairs (median over repeated renders)")
    for name, (pose, height) in views.items():
        renderer = StereoRenderer(WORLDS[name](), cam)
        T = planar_to_matrix(pose) @ camera_mount(height=height)
        t = median_seconds(lambda r=renderer, T=T: r.render_pair(T), repeat=15, min_time=1.0)
        times[f"render {name}"] = t
        print(
            f"  {name:<14s}{t * 1e3:9.2f} ms per pair {1 / t:8.1f} pairs/s (target >= 20: {met(1 / t >= 20)})"
        )
    rng = np.random.default_rng(BENCH_SEED)
    segments = rng.uniform(-10, 10, (100, 4))
    scanner = LaserScanner()

    def one_ray_at_a_time():  # the baseline: each ray against all segments
        return [cast_rays(segments, (0.0, 0.0), np.array([b])) for b in scanner.bearings]

    base = median_seconds(one_ray_at_a_time, repeat=5)
    t = median_seconds(lambda: scanner.scan(segments, (0.0, 0.0, 0.0), rng))
    times["laser scan"] = t
    print(f"laser scan, {len(scanner.bearings)} beams x {len(segments)} segments")
    print(format_row("ray by ray (baseline)", base, base))
    print(format_row("vectorised LaserScanner.scan", t, base))
    print(f"  target <= 2 ms: {met(t <= 2e-3)}")
    return times
