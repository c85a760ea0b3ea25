"""Every sample's images are as hard as real ones by the statistics of ``python -m vo_lib bench
realism``: outdoor samples and the road within the range of real road sequences, indoor samples
with at least a quarter of their cells empty. Twenty frames of each sample are rendered, about
half a minute in all, so these tests carry the ``samples`` mark (``.ci/run`` runs them)."""

from __future__ import annotations

import pytest

from vo_lib.bench.bench_realism import sample_range, sample_statistics
from vo_lib.sim.samples import SAMPLES, is_indoor

pytestmark = pytest.mark.samples


@pytest.mark.parametrize("name", list(SAMPLES))
def test_sample_images_fall_in_the_range_of_real_ones(name):
    stats = sample_statistics(name)
    (empty_low, empty_high), (flat_low, flat_high) = sample_range(is_indoor(name))
    assert empty_low <= stats.empty_cells <= empty_high, stats
    assert flat_low <= stats.low_gradient <= flat_high, stats
