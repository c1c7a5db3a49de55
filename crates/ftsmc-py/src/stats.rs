//! `ftsmc._ftsmc.stats_*`: the statistics module of `ftsmc-sim`
//! (`ftsmc_sim::stats`, docs/statistics.md) for Python, so `ftsmc.stats`
//! prints the same intervals and p-values as the CLI (and the tests can
//! check them against SciPy).

use ftsmc_sim::stats::{order, paired, rate};
use pyo3::prelude::*;

use crate::value_error;

/// Wilson score interval of `k` successes in `n` trials: `(estimate, lo, hi)`.
#[pyfunction]
pub(crate) fn stats_wilson(k: u64, n: u64, confidence: f64) -> PyResult<(f64, f64, f64)> {
    let i = rate::wilson(k, n, confidence).map_err(value_error)?;
    Ok((i.estimate, i.lo, i.hi))
}

/// Clopper–Pearson interval of `k` successes in `n` trials: `(estimate, lo, hi)`.
#[pyfunction]
pub(crate) fn stats_clopper_pearson(k: u64, n: u64, confidence: f64) -> PyResult<(f64, f64, f64)> {
    let i = rate::clopper_pearson(k, n, confidence).map_err(value_error)?;
    Ok((i.estimate, i.lo, i.hi))
}

/// The smallest `k` with `P(B ≤ k) ≥ prob`, `B ~ Binomial(n, p)`.
#[pyfunction]
pub(crate) fn stats_binomial_quantile(prob: f64, n: u64, p: f64) -> PyResult<u64> {
    if !(prob > 0.0 && prob < 1.0 && (0.0..=1.0).contains(&p)) {
        return Err(value_error(format!("prob = {prob}, p = {p}: expected 0 < prob < 1 and 0 ≤ p ≤ 1")));
    }
    Ok(order::binomial_quantile(prob, n, p))
}

/// Two-sided p-value of McNemar's exact test on `b` and `c` discordant pairs.
#[pyfunction]
pub(crate) fn stats_mcnemar_exact(b: u64, c: u64) -> f64 {
    paired::mcnemar_exact(b, c)
}

/// Wilcoxon signed-rank test of `diffs`: `(p, r_plus, r_minus, exact)`.
#[pyfunction]
pub(crate) fn stats_wilcoxon(diffs: Vec<f64>) -> (f64, f64, f64, bool) {
    let w = paired::wilcoxon(&diffs);
    (w.p, w.r_plus, w.r_minus, w.exact)
}
