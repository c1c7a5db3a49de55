"""How sure a result is: the intervals and paired tests of ``ftsmc``
(docs/statistics.md), the very code the ``ftsmc`` command uses.

>>> from ftsmc import stats
>>> stats.wilson(10, 10)   # 10/10 successes: (1.0, 0.7225, 1.0)
"""

from __future__ import annotations

from typing import NamedTuple, Sequence

from . import _ftsmc


class Interval(NamedTuple):
    """An estimate and its confidence interval ``[lo, hi]``."""

    estimate: float
    lo: float
    hi: float


class SignedRank(NamedTuple):
    """A Wilcoxon signed-rank test: two-sided ``p``, the rank sums, and
    whether ``p`` is exact (else the normal approximation with tie and
    continuity corrections)."""

    p: float
    r_plus: float
    r_minus: float
    exact: bool


def wilson(k: int, n: int, confidence: float = 0.95) -> Interval:
    """Wilson score interval of ``k`` successes in ``n`` trials."""
    return Interval(*_ftsmc.stats_wilson(k, n, confidence))


def clopper_pearson(k: int, n: int, confidence: float = 0.95) -> Interval:
    """Clopper–Pearson interval of ``k`` successes in ``n`` trials (coverage ≥ the level)."""
    return Interval(*_ftsmc.stats_clopper_pearson(k, n, confidence))


def binomial_quantile(prob: float, n: int, p: float) -> int:
    """Smallest ``k`` with ``P(B ≤ k) ≥ prob``, ``B ~ Binomial(n, p)`` (the
    ranks of the order-statistic intervals of medians and p95)."""
    return _ftsmc.stats_binomial_quantile(prob, n, p)


def mcnemar_exact(b: int, c: int) -> float:
    """Two-sided p of McNemar's exact test: ``b`` pairs only A succeeded, ``c`` only B."""
    return _ftsmc.stats_mcnemar_exact(b, c)


def wilcoxon(diffs: Sequence[float]) -> SignedRank:
    """Wilcoxon signed-rank test of paired differences ``A − B``."""
    return SignedRank(*_ftsmc.stats_wilcoxon([float(d) for d in diffs]))
