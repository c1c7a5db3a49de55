"""ftsmc's statistics against an independent implementation (SciPy), to 1e-10:
the Wilson interval, the binomial quantile of the order-statistic intervals,
McNemar's exact p and Wilcoxon's p (exact and normal approximation)."""

from __future__ import annotations

import numpy as np
import pytest

scipy_stats = pytest.importorskip("scipy.stats")

from ftsmc import stats  # noqa: E402


@pytest.mark.parametrize("k,n", [(0, 10), (3, 10), (10, 10), (4, 200), (100, 200), (196, 200), (17, 33)])
@pytest.mark.parametrize("confidence", [0.9, 0.95, 0.99])
def test_wilson_matches_scipy(k: int, n: int, confidence: float) -> None:
    ci = scipy_stats.binomtest(k, n).proportion_ci(confidence_level=confidence, method="wilson")
    ours = stats.wilson(k, n, confidence)
    assert ours.lo == pytest.approx(ci.low, abs=1e-10)
    assert ours.hi == pytest.approx(ci.high, abs=1e-10)


@pytest.mark.parametrize("n", [10, 20, 57, 200, 1000])
@pytest.mark.parametrize("p", [0.5, 0.95, 0.05])
@pytest.mark.parametrize("prob", [0.025, 0.975, 0.005, 0.995])
def test_binomial_quantile_matches_scipy(n: int, p: float, prob: float) -> None:
    assert stats.binomial_quantile(prob, n, p) == int(scipy_stats.binom.ppf(prob, n, p))


@pytest.mark.parametrize("b,c", [(0, 6), (3, 9), (10, 10), (1, 30), (45, 70)])
def test_mcnemar_matches_scipy(b: int, c: int) -> None:
    expected = scipy_stats.binomtest(min(b, c), b + c, 0.5).pvalue
    assert stats.mcnemar_exact(b, c) == pytest.approx(expected, abs=1e-10)


def test_wilcoxon_matches_scipy() -> None:
    rng = np.random.default_rng(36)
    for n in (6, 12, 30, 50):
        d = rng.normal(0.2, 1.0, n)
        ours = stats.wilcoxon(list(d))
        assert ours.exact
        want = scipy_stats.wilcoxon(d, method="exact").pvalue
        assert ours.p == pytest.approx(want, abs=1e-10)
    for n in (80, 200):
        # Ties (rounded values) and zeros: the normal approximation.
        d = np.round(rng.normal(0.1, 1.0, n), 1)
        ours = stats.wilcoxon(list(d))
        assert not ours.exact
        want = scipy_stats.wilcoxon(d, method="approx", correction=True, zero_method="wilcox").pvalue
        assert ours.p == pytest.approx(want, abs=1e-10)
