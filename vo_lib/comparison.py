"""Comparisons over seeds: the one way this project says that one method beats another.

A single random draw never carries a comparative sentence. :func:`over_seeds` runs every method
on the same draw for each of N seeds (a paired comparison); :class:`Comparison` says in how many
seeds A beats B, the median difference A − B with its interval, and the sentence with its
figures. The median's interval is distribution-free (:func:`median_interval`): two of the sorted
differences, chosen by the binomial law of how many fall below the true median, so that ten seeds
cannot carry more confidence than ten seeds hold. Sentences drawn from one study form a
``family``: each interval is widened (Bonferroni) so that the whole family holds at
:data:`CONFIDENCE`.

Consistency uses one χ² rule (:func:`chi2_band`): the average of ``count`` independent χ²(dof)
values lies in ``chi2.ppf([α/2, 1 − α/2], dof·count) / count``. Independent means across
Monte-Carlo runs at one time step (NEES), or across one run's steps only where the values are
white (the NIS of a consistent filter); a NEES averaged over one run's steps is correlated in time:
judge it by the seeds' bootstrap interval of its mean against ``dof`` (:func:`bootstrap_interval`).
"""

from __future__ import annotations

import enum
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass

import numpy as np
from scipy.stats import binom, chi2

#: Confidence of every interval and band, and bootstrap resamples (fixed seed: same figures).
CONFIDENCE = 0.95
RESAMPLES = 4000
BOOTSTRAP_SEED = 20240611


class Verdict(enum.Enum):
    """Outcome of a paired comparison of ``a`` against ``b`` (lower is better): ``a is <value> b``."""

    BETTER = "better than"
    WORSE = "worse than"
    NOT_RELIABLE = "not reliably different from"


def bootstrap_interval(
    values: Iterable[float], statistic: Callable = np.median, confidence: float = CONFIDENCE
) -> tuple[float, float]:
    """Percentile bootstrap interval of ``statistic`` over ``values`` (one value per seed)."""
    x = np.asarray(list(values), dtype=float)
    rng = np.random.default_rng(BOOTSTRAP_SEED)
    draws = rng.integers(0, len(x), size=(RESAMPLES, len(x)))
    try:  # NumPy's reductions take an axis: every resample in one call
        stats = np.asarray(statistic(x[draws], axis=1), dtype=float)
    except TypeError:  # a statistic of one sample at a time
        stats = np.apply_along_axis(statistic, 1, x[draws])
    low, high = np.quantile(stats, [(1 - confidence) / 2, (1 + confidence) / 2])
    return float(low), float(high)


def median_interval(values: Iterable[float], confidence: float = CONFIDENCE) -> tuple[float, float]:
    """Distribution-free interval of the median of ``values`` (one per seed): the ``k``-th lowest
    and the ``k``-th highest, ``k`` the largest with ``P(B < k) <= (1 - confidence) / 2`` for
    ``B ~ Binomial(n, 1/2)``, the count of values below the true median. ``(nan, nan)`` where ``n``
    is too few for ``confidence`` (``2 / 2**n`` is the least risk ``n`` values can give)."""
    x = np.sort(np.asarray(list(values), dtype=float))
    # P(B <= j) for j = 0..n; k - 1 is the last j within the risk allowed on each side
    below = int(np.sum(binom.cdf(np.arange(len(x) + 1), len(x), 0.5) <= (1 - confidence) / 2))
    return (float("nan"),) * 2 if below == 0 else (float(x[below - 1]), float(x[len(x) - below]))


def shown_digits(values: Iterable[float], digits: int, most: int = 4) -> int:
    """Decimals, from ``digits`` up to ``most``, that print no figure of ``values`` other than zero
    as zero (an interval "-0.00 to -0.00" that lies below zero reads as if it touched it)."""
    small = [abs(v) for v in values if np.isfinite(v) and v != 0]
    return digits if not small else max(digits, min(most, -int(np.floor(np.log10(min(small))))))


def interval_text(low: float, high: float, digits: int) -> str:
    """``"low-high"`` with ``digits`` decimals, or ``"undefined"`` where there is no spread (one seed)."""
    return "undefined" if np.isnan(low) or np.isnan(high) else f"{low:.{digits}f}-{high:.{digits}f}"


def chi2_band(dof: int, count: int) -> tuple[float, float]:
    """Band of the average of ``count`` independent χ²(``dof``) values (see the module's rule)."""
    low, high = chi2.ppf([(1 - CONFIDENCE) / 2, (1 + CONFIDENCE) / 2], dof * count) / count
    return float(low), float(high)


@dataclass(frozen=True)
class Comparison:
    """Per-seed figures of several methods on the same draws; lower is better."""

    seeds: tuple[int, ...]
    figures: Mapping[str, np.ndarray]  #: a method's name -> its figures, one per seed in order
    family: int = 1  #: the comparisons judged together on these draws (the module's Bonferroni rule)

    def __len__(self) -> int:
        return len(self.seeds)

    @property
    def confidence(self) -> float:
        """Each interval's confidence, ``1 - (1 - CONFIDENCE) / family`` (Bonferroni)."""
        return 1 - (1 - CONFIDENCE) / self.family

    def paired(self, a: str, b: str) -> np.ndarray:
        """Per-seed differences ``a − b``."""
        return np.asarray(self.figures[a], float) - np.asarray(self.figures[b], float)

    def share(self, a: str, b: str) -> int:
        """Number of seeds in which ``a``'s figure is strictly lower than ``b``'s."""
        return int(np.sum(self.paired(a, b) < 0))

    def difference(self, a: str, b: str) -> tuple[float, float, float]:
        """Median of ``a − b`` over seeds, and its :func:`median_interval` (low, high)."""
        d = self.paired(a, b)
        return (float(np.median(d)), *median_interval(d, self.confidence))

    def varies(self, a: str, b: str) -> bool:
        """Whether the seeds move ``a − b`` (else the N figures are one result repeated); a change
        below a millionth of the figures' size is arithmetic's (sums in another order), not the draws'."""
        return self._moves(self.paired(a, b), a, b)

    def _moves(self, values: np.ndarray, a: str, b: str) -> bool:
        size = max(float(np.max(np.abs(self.figures[k]))) for k in (a, b))
        return bool(np.ptp(values) > 1e-6 * size)

    def verdict(self, a: str, b: str) -> Verdict:
        """``BETTER`` when the whole interval of ``a − b`` is below zero, ``WORSE`` above, else
        ``NOT_RELIABLE``, as also where the seeds do not move ``a − b`` (:meth:`varies`) and where they
        are too few for an interval at the family's confidence."""
        if not self.varies(a, b):
            return Verdict.NOT_RELIABLE
        _, low, high = self.difference(a, b)
        return Verdict.BETTER if high < 0 else Verdict.WORSE if low > 0 else Verdict.NOT_RELIABLE

    def sentence(self, a: str, b: str, unit: str = "", scale: float = 1.0, digits: int = 2) -> str:
        """The comparative sentence with its figures, e.g. "fused is better than VO: lower in 17 of
        20 seeds (median difference -0.80 cm, 95 % CI -1.10 to -0.50 cm)"; one of a family of 17
        says "99.7 % CI, one of 17 comparisons". Where the seeds do not move the difference
        (:meth:`varies`): the two figures and that they are one result, or, where the figures
        themselves move, the one difference every seed gives."""
        u = f" {unit}" if unit else ""
        if not self.varies(a, b):
            return self._one_result(a, b, u, scale, digits)
        median, low, high = (scale * v for v in self.difference(a, b))
        digits = shown_digits((median, low, high), digits)
        level = f"{100 * CONFIDENCE:.0f} %" if self.family == 1 else f"{100 * self.confidence:.1f} %"
        among = "" if self.family == 1 else f", one of {self.family} comparisons"
        interval = (
            f"{level} CI {low:+.{digits}f} to {high:+.{digits}f}{u}"
            if np.isfinite(low)
            else f"too few seeds for a {level} CI"
        )
        return (
            f"{a} is {self.verdict(a, b).value} {b}: lower in {self.share(a, b)} of {len(self)} seeds "
            f"(median difference {median:+.{digits}f}{u}, {interval}{among})"
        )

    def _one_result(self, a: str, b: str, u: str, scale: float, digits: int) -> str:
        """The sentence where the seeds do not move ``a − b``: the two figures, one result; or, where
        the figures themselves move, that every seed gives them equal or one difference apart."""
        n, (va, vb) = len(self), (scale * float(np.median(self.figures[k])) for k in (a, b))
        if not any(self._moves(np.asarray(self.figures[k], float), a, b) for k in (a, b)):
            return (
                f"{a} against {b}: {va:.{digits}f} against {vb:.{digits}f}{u} in every one of the "
                f"{n} seeds, so this is one result, which the seeds do not test"
            )
        d = scale * float(np.median(self.paired(a, b)))
        if d == 0:
            return f"{a} against {b}: equal in every one of the {n} seeds (median {va:.{digits}f}{u})"
        return (
            f"{a} against {b}: {a} minus {b} is {d:+.{digits}f}{u} in every one of the {n} seeds "
            f"(medians {va:.{digits}f} and {vb:.{digits}f}{u}), one result, which the seeds do not test"
        )


def over_seeds(
    run: Callable[[int], Mapping[str, float]], seeds: Iterable[int], family: int = 1
) -> Comparison:
    """Run ``run(seed)`` for every seed, which draws once and returns ``{method name: figure}`` for
    every method on that draw (lower is better); ``family``: the comparisons judged together."""
    seeds = tuple(int(s) for s in seeds)
    rows = [dict(run(s)) for s in seeds]
    names = list(rows[0])
    if any(list(r) != names for r in rows):
        raise ValueError("every seed must return the same methods in the same order")
    if int(family) < 1:
        raise ValueError(f"family must be a count of comparisons, at least 1; got {family}")
    return Comparison(seeds, {n: np.array([r[n] for r in rows], float) for n in names}, int(family))
