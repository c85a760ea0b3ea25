"""[Yan 2020]'s line-feature EKF-SLAM: ``python -m vo_lib bench observers``."""

from __future__ import annotations

import numpy as np

from vo_lib.bench.common import BENCH_SEED, median_seconds, met


def bench_observers(laps: int = 3) -> dict[str, float]:
    """[Yan 2020]'s observers on every (segment, pose) call of one simulated lap, and whole laps."""
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
        f"  targets: point/bisection >= 4.5 ({met(ratio_b >= 4.5)}: {ratio_b:.1f}; paper about 5); "
        f"point/closed form >= 20 ({met(ratio_c >= 20)}: {ratio_c:.1f}); "
        f"lap with closed form <= 3 s ({met(lap['closed_form'] <= 3)}: {lap['closed_form']:.2f} s)"
    )
    return {**{f"call {k}": v for k, v in per_call.items()}, **{f"lap {k}": v for k, v in lap.items()}}
