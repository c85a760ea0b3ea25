"""``python -m vo_lib bench realism``: the statistics of :mod:`vo_lib.sim.realism` over :data:`FRAMES`
left images of every KITTI-layout sequence in ``$VO_LIB_REALDATA`` and of every sample (rendered in
memory), each sample beside the range it must meet.
"""

from __future__ import annotations

from dataclasses import asdict

#: Frames measured per sequence, spread evenly over it.
FRAMES = 20
#: Ranges the samples must meet: (empty cells low, high), (low-gradient low, high).
OUTDOOR_RANGE = ((0.35, 0.65), (0.30, 0.50))
INDOOR_RANGE = ((0.25, 1.0), (0.0, 1.0))


def sample_range(indoor: bool):
    return INDOOR_RANGE if indoor else OUTDOOR_RANGE


def sample_statistics(name: str, frames: int = FRAMES):
    """Mean :class:`~vo_lib.sim.realism.ImageStatistics` of ``frames`` left images spread over
    sample ``name``, rendered in memory."""
    from vo_lib.sim.realism import ImageStatistics, image_statistics, spread_frames
    from vo_lib.sim.samples import SAMPLES, render_left_images

    images = render_left_images(name, spread_frames(SAMPLES[name].frames, frames))
    return ImageStatistics.mean(image_statistics(img) for img in images)


def bench_realism(frames: int = FRAMES) -> dict[str, float]:
    """Print the realism table of every sample and real sequence; returns its figures by name."""
    from vo_lib.bench.bench_real import realdata_folders
    from vo_lib.formats.sequence import read_sequence
    from vo_lib.sim.realism import ImageStatistics, image_statistics, spread_frames
    from vo_lib.sim.samples import SAMPLES, is_indoor

    rows = []
    folders = [p for p in realdata_folders() if (p / "image_0").is_dir()]
    for folder in folders:
        seq = read_sequence(folder, odometry=False)
        picked = spread_frames(len(seq), frames)
        stats = ImageStatistics.mean(image_statistics(seq.pair(int(k))[0]) for k in picked)
        rows.append((f"real: {folder.name}", stats, None))
    rows += [(f"sample {n}", sample_statistics(n, frames), sample_range(is_indoor(n))) for n in SAMPLES]
    print(
        f"{frames} left images spread over each sequence; FAST-9/16 at threshold 20 with non-maximum "
        "suppression; gradient: 3x3 Sobel magnitude"
    )
    if not folders:
        print("  (no real sequences: set VO_LIB_REALDATA to a folder of KITTI-layout sequences)")
    header = f"{'cells without a corner':>24s}{'corners per 640x480':>21s}{'low-gradient pixels':>21s}"
    print(f"  {'sequence':<46s}{header}")
    out = {}
    for label, s, wanted in rows:
        verdict = ""
        if wanted is not None:
            (e0, e1), (g0, g1) = wanted
            ok = e0 <= s.empty_cells <= e1 and g0 <= s.low_gradient <= g1
            verdict = "  in range" if ok else "  OUT of range"
        print(f"  {label:<46s}{s.empty_cells:24.2f}{s.corners_per_vga:21,.0f}{s.low_gradient:21.2f}{verdict}")
        out.update({f"{label}:{key}": value for key, value in asdict(s).items()})
    print(
        "  ranges: outdoor samples and the road 0.35-0.65 cells without a corner and 0.30-0.50 "
        "low-gradient pixels; indoor samples at least 0.25 cells without a corner"
    )
    return out
