//! How sure a batch is: each contestant's rates, RMS position error
//! median, p95 and mean with their intervals ([`Intervals`]), and the
//! paired verdict of every pair of contestants ([`pairwise`]) — McNemar
//! on success, Wilcoxon on RMS position error, Holm over all of them
//! (`crate::stats`, docs/statistics.md).
//!
//! **Pairing.** A batch draws run `i`'s scenario once
//! ([`crate::scenario::distributions::MonteCarloSpec::sample`] of the
//! master seed and `i`) and every contestant flies that same scenario and
//! seed: the same vehicle, wind, noise streams and initial state. So row
//! `i` of two contestants is a matched pair (`tests/verdicts.rs` checks
//! that two copies of one controller fly bit-identical rows).

use serde::Serialize;

use crate::metrics::Metrics;
use crate::stats::mean::mean_interval;
use crate::stats::order::quantile_of;
use crate::stats::paired::{error_test, success_test, verdicts, PairTest, PairedMetric, Verdict};
use crate::stats::rate::wilson;
use crate::stats::{Interval, StatsError};

/// RMS position error `√(rms_x² + rms_y² + rms_z²)` of a flight, m: the
/// headline metric of every command.
pub fn rms_position_error(m: &Metrics) -> f64 {
    (m.rms.x * m.rms.x + m.rms.y * m.rms.y + m.rms.z * m.rms.z).sqrt()
}

/// [`rms_position_error`] from `(name, value)` metric pairs
/// ([`Metrics::flat`]); `NaN` if a component is missing.
pub fn rms_position_error_flat(flat: &[(String, f64)]) -> f64 {
    let get = |n: &str| flat.iter().find(|(k, _)| k == n).map_or(f64::NAN, |(_, v)| *v);
    let (x, y, z) = (get("rms_x"), get("rms_y"), get("rms_z"));
    (x * x + y * y + z * z).sqrt()
}

/// One contestant's outcome per run, in run order (the pairing).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Outcomes {
    /// Completed and inside the envelope.
    pub success: Vec<bool>,
    /// Completed (no divergence, no crash).
    pub completed: Vec<bool>,
    /// Hit the ground too fast.
    pub crashed: Vec<bool>,
    /// RMS position error (m) of a completed run; `NaN` otherwise.
    pub rms: Vec<f64>,
}

impl Outcomes {
    /// Add one run.
    pub fn push(&mut self, success: bool, completed: bool, crashed: bool, rms: f64) {
        self.success.push(success);
        self.completed.push(completed);
        self.crashed.push(crashed);
        self.rms.push(if completed { rms } else { f64::NAN });
    }

    /// Runs recorded.
    pub fn runs(&self) -> usize {
        self.success.len()
    }
}

/// A contestant's numbers with their intervals at `confidence`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Intervals {
    /// The confidence level of every interval here.
    pub confidence: f64,
    /// Runs.
    pub runs: usize,
    /// Successes.
    pub successes: usize,
    /// Success rate, Wilson.
    pub success_rate: Interval,
    /// Completed rate, Wilson.
    pub completed_rate: Interval,
    /// Crashed rate, Wilson.
    pub crashed_rate: Interval,
    /// Diverged rate, Wilson.
    pub diverged_rate: Interval,
    /// Median RMS position error of the completed runs (m), order statistics.
    pub rms_median: Option<Interval>,
    /// p95 RMS position error of the completed runs (m), order statistics.
    pub rms_p95: Option<Interval>,
    /// Mean RMS position error of the completed runs (m), t interval.
    pub rms_mean: Option<Interval>,
}

/// [`Intervals`] of `o` at `confidence`.
pub fn intervals(o: &Outcomes, confidence: f64) -> Result<Intervals, StatsError> {
    let n = o.runs() as u64;
    let count = |v: &[bool]| v.iter().filter(|b| **b).count() as u64;
    let (s, c, k) = (count(&o.success), count(&o.completed), count(&o.crashed));
    Ok(Intervals {
        confidence,
        runs: o.runs(),
        successes: s as usize,
        success_rate: wilson(s, n, confidence)?,
        completed_rate: wilson(c, n, confidence)?,
        crashed_rate: wilson(k, n, confidence)?,
        diverged_rate: wilson(n - c - k, n, confidence)?,
        rms_median: quantile_of(&o.rms, 0.5, confidence)?,
        rms_p95: quantile_of(&o.rms, 0.95, confidence)?,
        rms_mean: mean_interval(&o.rms, confidence)?,
    })
}

/// The verdict of one pair on one metric.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PairVerdict {
    /// Contestant A.
    pub a: String,
    /// Contestant B.
    pub b: String,
    /// The test (effect: `p_A − p_B` for success; median of `A − B` for RMS
    /// position error, m) before the correction.
    #[serde(flatten)]
    pub test: PairTest,
    /// Holm-adjusted p-value over every test of the comparison.
    pub p_holm: f64,
    /// `A better`, `B better` or `no difference shown` at `1 − confidence`.
    pub verdict: Verdict,
}

impl PairVerdict {
    /// `A better` / `B better` with the names, or `no difference shown`.
    pub fn sentence(&self) -> String {
        match self.verdict {
            Verdict::ABetter => format!("{} better", self.a),
            Verdict::BBetter => format!("{} better", self.b),
            Verdict::NoDifference => "no difference shown".to_string(),
        }
    }
}

/// The paired tests of every pair `(i, j)`, `i < j`, of `contestants`
/// (success, then RMS position error), in order, before any correction.
pub fn pair_tests(
    contestants: &[(String, &Outcomes)],
    confidence: f64,
) -> Result<Vec<(usize, usize, PairTest)>, StatsError> {
    let mut out = Vec::new();
    for i in 0..contestants.len() {
        for j in i + 1..contestants.len() {
            let (a, b) = (contestants[i].1, contestants[j].1);
            out.push((i, j, success_test(&a.success, &b.success, confidence)?));
            out.push((i, j, error_test(&a.rms, &b.rms, confidence)?));
        }
    }
    Ok(out)
}

/// Every pair's verdicts on success and RMS position error, Holm over all
/// of them at family-wise level `1 − confidence`.
pub fn pairwise(contestants: &[(String, &Outcomes)], confidence: f64) -> Result<Vec<PairVerdict>, StatsError> {
    let tests = pair_tests(contestants, confidence)?;
    let plain: Vec<PairTest> = tests.iter().map(|t| t.2.clone()).collect();
    let v = verdicts(&plain, confidence)?;
    Ok(tests
        .into_iter()
        .zip(v)
        .map(|((i, j, test), (p_holm, verdict))| PairVerdict {
            a: contestants[i].0.clone(),
            b: contestants[j].0.clone(),
            test,
            p_holm,
            verdict,
        })
        .collect())
}

/// The name of a [`PairedMetric`] in tables: `success`, `RMS pos. err.`.
pub fn metric_label(m: PairedMetric) -> &'static str {
    match m {
        PairedMetric::Success => "success",
        PairedMetric::Error => "RMS pos. err.",
    }
}
