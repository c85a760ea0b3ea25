"""Every sample's images are as hard as real ones by the statistics of ``python -m vo_lib bench
realism``: outdoor samples and the road within the range of real road sequences, indoor samples
with at least a quarter of their cells empty. Twenty frames of each sample are rendered, about
half a minute in all, so these tests carry the ``samples`` mark (``.ci/run`` runs them)."""

from __future__ import annotations

import pytest

from vo_lib.cli.bench.bench_realism import FRAMES, sample_range
from vo_lib.sim.realism import ImageStatistics, image_statistics, spread_frames
from vo_lib.sim.samples import SAMPLES, is_indoor, render_left_images

pytestmark = pytest.mark.samples


@pytest.mark.parametrize("name", list(SAMPLES))
def test_sample_images_fall_in_the_range_of_real_ones(name):
    images = render_left_images(name, spread_frames(SAMPLES[name].frames, FRAMES))
    stats = ImageStatistics.mean(image_statistics(image) for image in images)
    (empty_low, empty_high), (flat_low, flat_high) = sample_range(is_indoor(name))
    assert empty_low <= stats.empty_cells <= empty_high, stats
    assert flat_low <= stats.low_gradient <= flat_high, stats
