"""The one helper for comparisons over seeds, and the χ² band rule."""

import numpy as np
import pytest
from scipy.stats import chi2

from vo_lib.comparison import Verdict, bootstrap_interval, chi2_band, median_interval, over_seeds


def _draws(seed: int, gap: float) -> dict[str, float]:
    rng = np.random.default_rng(seed)
    noise = rng.normal(size=2)
    return {"A": 1.0 + 0.1 * noise[0], "B": 1.0 + gap + 0.1 * noise[1]}


def test_a_clear_difference_is_reliable_and_counted():
    c = over_seeds(lambda s: _draws(s, gap=0.5), range(20))
    assert c.share("A", "B") == 20
    median, low, high = c.difference("A", "B")
    assert low <= median <= high < 0
    assert c.verdict("A", "B") is Verdict.BETTER and c.verdict("B", "A") is Verdict.WORSE
    assert "in 20 of 20 seeds" in c.sentence("A", "B") and "is better than" in c.sentence("A", "B")


def test_a_family_of_comparisons_widens_each_interval_to_hold_together():
    """A small gap, reliable as one comparison at 95 %, is not within a family of 17, whose
    intervals are each at 1 - 0.05/17 (99.7 %); the sentence says so."""
    alone = over_seeds(lambda s: _draws(s, gap=0.07), range(40))
    family = over_seeds(lambda s: _draws(s, gap=0.07), range(40), family=17)
    assert alone.confidence == 0.95 and family.confidence == pytest.approx(1 - 0.05 / 17)
    (_, low_a, high_a), (_, low_f, high_f) = alone.difference("A", "B"), family.difference("A", "B")
    assert low_f < low_a <= high_a < high_f
    assert alone.verdict("A", "B") is Verdict.BETTER and family.verdict("A", "B") is Verdict.NOT_RELIABLE
    assert "99.7 % CI" in family.sentence("A", "B") and "one of 17 comparisons" in family.sentence("A", "B")
    assert "95 % CI" in alone.sentence("A", "B") and "comparisons" not in alone.sentence("A", "B")
    with pytest.raises(ValueError, match="family"):
        over_seeds(lambda s: _draws(s, gap=0.0), range(3), family=0)


def test_no_difference_is_not_reliable():
    c = over_seeds(lambda s: _draws(s, gap=0.0), range(20))
    assert c.verdict("A", "B") is Verdict.NOT_RELIABLE
    assert "not reliably different" in c.sentence("A", "B", unit="m")


def test_figures_the_seeds_do_not_move_are_one_result_not_a_ranking():
    c = over_seeds(lambda s: {"A": 0.1256, "B": 0.1318 + 1e-17 * s}, range(10))
    sentence = c.sentence("A", "B", unit="m", digits=4)
    assert not c.varies("A", "B") and over_seeds(lambda s: _draws(s, 0.5), range(5)).varies("A", "B")
    assert c.verdict("A", "B") is Verdict.NOT_RELIABLE  # A is lower in every seed, by one result
    # arithmetic's changes (sums in another order) are not the draws': 5e-9 m on 5 cm
    rounding = over_seeds(lambda s: {"A": 0.05 + 5e-9 * (s % 3), "B": 0.055}, range(10))
    assert not rounding.varies("A", "B") and "one result" in rounding.sentence("A", "B")
    # while a small figure's real spread is (1e-6 rad on 1e-4 rad)
    assert over_seeds(lambda s: {"A": 1e-4 + 1e-6 * (s % 3), "B": 2e-4}, range(10)).varies("A", "B")
    assert sentence == (
        "A against B: 0.1256 against 0.1318 m in every one of the 10 seeds, "
        "so this is one result, which the seeds do not test"
    )


def test_figures_that_move_by_one_difference_say_so():
    c = over_seeds(lambda s: {"A": 0.01 * s, "B": 0.01 * s, "C": 0.01 * s + 0.002}, range(10))
    assert not c.varies("A", "B") and c.verdict("A", "B") is Verdict.NOT_RELIABLE
    assert c.sentence("A", "B", unit="m", digits=3) == (
        "A against B: equal in every one of the 10 seeds (median 0.045 m)"
    )
    assert "A minus C is -0.002 m" in c.sentence("A", "C", unit="m", digits=3)


def test_same_seeds_same_figures():
    a = over_seeds(lambda s: _draws(s, gap=0.05), range(10))
    b = over_seeds(lambda s: _draws(s, gap=0.05), range(10))
    assert a.sentence("A", "B") == b.sentence("A", "B")


def test_methods_must_agree_across_seeds():
    with pytest.raises(ValueError, match="same methods"):
        over_seeds(lambda s: {"A": 1.0} if s else {"B": 1.0}, range(2))


def test_bootstrap_interval_covers_the_median_of_a_known_sample():
    x = np.random.default_rng(3).normal(2.0, 1.0, size=200)
    low, high = bootstrap_interval(x)
    assert low < 2.0 < high and high - low < 0.5


def test_chi2_band_is_the_average_of_independent_draws():
    low, high = chi2_band(3, 20)
    assert (low, high) == pytest.approx(tuple(chi2.ppf([0.025, 0.975], 60) / 20))
    means = np.random.default_rng(0).chisquare(3, size=(4000, 20)).mean(axis=1)
    inside = np.mean((means > low) & (means < high))
    assert 0.93 < inside < 0.97


def test_the_bootstrap_gives_the_same_interval_with_or_without_an_axis_argument():
    values = np.random.default_rng(3).normal(size=15)
    one_at_a_time = bootstrap_interval(values, statistic=lambda v: float(np.median(v)))
    assert bootstrap_interval(values) == one_at_a_time


def test_the_median_interval_is_two_order_statistics_chosen_by_the_binomial_law():
    """20 values at 95 %: P(B <= 5) = 0.021 <= 0.025 < P(B <= 6) for B ~ Binomial(20, 1/2), so the
    6th lowest and the 6th highest; shuffled, the same."""
    values = np.random.default_rng(0).permutation(np.arange(1.0, 21.0))
    assert median_interval(values) == (6.0, 15.0)
    assert np.mean(values) == pytest.approx(10.5)  # not changed in place


def test_ten_seeds_carry_no_verdict_in_a_family_of_thirty():
    """Even 10 of 10 lower is a 2-in-1,024 chance of a fair coin: beyond the 0.05 / 30 a family of
    thirty allows on each comparison. The sentence says the seeds are too few; the same seeds alone
    give a verdict."""
    draws = range(10)
    family = over_seeds(lambda s: _draws(s, gap=0.5), draws, family=30)
    assert family.share("A", "B") == 10 and family.verdict("A", "B") is Verdict.NOT_RELIABLE
    assert np.isnan(median_interval(family.paired("A", "B"), family.confidence)).all()
    assert "too few seeds for a 99.8 % CI" in family.sentence("A", "B")
    assert over_seeds(lambda s: _draws(s, gap=0.5), draws).verdict("A", "B") is Verdict.BETTER


def test_a_small_reliable_difference_prints_its_interval_clear_of_zero():
    """Differences of a few thousandths, all below zero: with two decimals the interval would read
    "-0.00 to -0.00"; the sentence takes the decimals that show it."""
    c = over_seeds(lambda s: {"A": 1.0 - 0.004 - 0.001 * (s % 3), "B": 1.0}, range(20))
    sentence = c.sentence("A", "B", unit="°")
    assert c.verdict("A", "B") is Verdict.BETTER
    assert "95 % CI -0.006 to -0.004 °" in sentence and "-0.00 to" not in sentence
