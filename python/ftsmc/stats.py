"""How sure a result is: the intervals and paired tests of ``ftsmc``
(docs/statistics.md), the very code the ``ftsmc`` command uses.

>>> from ftsmc import stats
>>> stats.wilson(10, 10)   # 10/10 successes: (1.0, 0.7225, 1.0)
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple, Sequence

from . import _ftsmc

if TYPE_CHECKING:
    import pandas


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


def summary(runs: "pandas.DataFrame", confidence: float = 0.95) -> "pandas.DataFrame":
    """The intervals of a Monte Carlo batch, one row per controller.

    ``runs`` holds the rows of ``runs.csv`` (as :func:`ftsmc.montecarlo`
    returns them). Each controller's row has ``runs``, ``successes`` and
    ``<x>``, ``<x>_lo``, ``<x>_hi`` for the rates ``success``,
    ``completed``, ``crashed``, ``diverged`` (Wilson) and the RMS position
    error ``√(rms_x² + rms_y² + rms_z²)`` of the completed runs, m:
    ``rms_median``, ``rms_p95`` (order statistics; ``inf`` where the runs
    cannot give a bound) and ``rms_mean`` (t). The same code and numbers
    as the ``intervals`` of ``ftsmc montecarlo``'s summary.json.
    """
    import numpy as np
    import pandas

    rows = {}
    for name, group in runs.groupby("controller", sort=False):
        rms = np.sqrt(group["rms_x"] ** 2 + group["rms_y"] ** 2 + group["rms_z"] ** 2)
        row = _ftsmc.stats_intervals(
            [bool(v) for v in group["success"]],
            [bool(v) for v in group["completed"]],
            [bool(v) for v in group["crashed"]],
            [float(v) for v in rms],
            confidence,
        )
        rows[str(name)] = dict(row)
    table = pandas.DataFrame.from_dict(rows, orient="index")
    table.index.name = "controller"
    return table.astype({"runs": "int64", "successes": "int64"})
