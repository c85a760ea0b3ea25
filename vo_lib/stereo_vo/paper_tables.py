"""[Zhao]'s printed timings, stored once: the command line, the benchmarks and the notebooks read
them from here; :func:`stage_times` measures Table 1 again."""

from __future__ import annotations

import numpy as np

#: [Zhao], Table 1: mean milliseconds of stereo processing, parameter estimation and Kalman
#: filtering at each of the five resolutions the paper timed, by (width, height).
PAPER_TABLE1 = {
    (640, 480): {"stereo": 48.969, "estimation": 0.874, "kalman": 0.161},
    (512, 384): {"stereo": 39.851, "estimation": 0.664, "kalman": 0.157},
    (400, 300): {"stereo": 31.970, "estimation": 0.754, "kalman": 0.158},
    (320, 240): {"stereo": 22.165, "estimation": 0.662, "kalman": 0.168},
    (256, 192): {"stereo": 22.460, "estimation": 0.610, "kalman": 0.153},
}
#: [Zhao], IV.A.1: the long run's frames, and the mean and standard deviation of the whole frame
#: over them (ms; resolution not stated).
PAPER_LONG_RUN = (10_000, 26.5511, 4.551)


def stage_times(seed: int, resolution: str = "640x480", frames: int = 40) -> dict[str, float]:
    """Table 1 measured (a task of ``python -m vo_lib sweep table1``): median milliseconds per
    stage on ``frames`` rendered frames of the ``indoor_linear`` drive at ``resolution``, and the
    median count of stereo features."""
    from vo_lib.sim.samples import render_sample
    from vo_lib.stereo_vo.pipeline import run_frames

    width, height = (int(x) for x in resolution.split("x"))
    rendered, images = render_sample("indoor_linear", frames, (width, height))
    result = run_frames(images, rendered.camera, seed=seed)
    out = {f"{stage}_ms": ms for stage, ms in result.timing_table().items()}
    out["features"] = float(np.median([d.features for d in result.diagnostics]))
    return out
