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

/// Practical-difference margins per metric for `ftsmc compare
/// --min-effect`: a difference smaller than these does not matter to the
/// user, whatever its p-value.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct MinEffect {
    /// Success-rate margin Δ, as a fraction (0.02: two percentage points).
    pub success: f64,
    /// RMS position error margin Δ, m.
    pub rms: f64,
}

impl MinEffect {
    /// Parse `success=0.02` / `rms=0.005` entries (either may be left
    /// out: margin 0); a clear error names a bad entry.
    pub fn parse(entries: &[String]) -> Result<Self, String> {
        let mut m = Self { success: 0.0, rms: 0.0 };
        for e in entries {
            let (k, v) = e.split_once('=').ok_or_else(|| {
                format!("--min-effect {e}: expected METRIC=MARGIN (success=0.02 as a fraction, rms=0.005 in m)")
            })?;
            let v: f64 = v.trim().parse().map_err(|_| format!("--min-effect {e}: `{v}` is not a number"))?;
            if !(v.is_finite() && v >= 0.0) {
                return Err(format!("--min-effect {e}: a margin is a finite number ≥ 0"));
            }
            match k.trim() {
                "success" if v < 1.0 => m.success = v,
                "success" => return Err(format!("--min-effect {e}: a success margin is a fraction below 1")),
                "rms" => m.rms = v,
                other => return Err(format!("--min-effect {e}: unknown metric `{other}` (expected success or rms)")),
            }
        }
        Ok(m)
    }
}

/// A verdict judged against a practical margin ([`practical`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Practical {
    /// A is better, and by more than the margin (the whole interval beyond it).
    #[serde(rename = "A better by more than the margin")]
    ABetter,
    /// B is better, and by more than the margin.
    #[serde(rename = "B better by more than the margin")]
    BBetter,
    /// Equivalent: the whole interval within ± the margin.
    #[serde(rename = "equivalent within the margin")]
    Equivalent,
    /// Neither shown: more runs, or a difference near the margin.
    #[serde(rename = "not decided at this margin")]
    Undecided,
}

/// `v` against the margin `m` of its metric. With the effect turned so
/// that positive favours A (success: `p_A − p_B`; error: `B − A`) and its
/// interval `[lo, hi]` at the comparison's level: **A better** when the
/// test says so (Holm) and `lo > Δ`; **B better** likewise with `hi < −Δ`;
/// **equivalent** when `−Δ < lo` and `hi < Δ` — the two one-sided tests of
/// Schuirmann (1987, "A comparison of the two one-sided tests procedure
/// and the power approach for assessing the equivalence of average
/// bioavailability", J. Pharmacokinet. Biopharm. 15) each at
/// `(1 − confidence)/2`, so conservative at the stated level; otherwise
/// undecided. With `Δ = 0` "equivalent" cannot happen and "better" needs
/// the interval to exclude 0, which the test's own verdict implies.
pub fn practical(v: &PairVerdict, m: &MinEffect) -> Practical {
    let (delta, sign) = match v.test.metric {
        PairedMetric::Success => (m.success, 1.0),
        PairedMetric::Error => (m.rms, -1.0),
    };
    let e = v.test.effect;
    let (lo, hi) = if sign > 0.0 { (e.lo, e.hi) } else { (-e.hi, -e.lo) };
    if v.verdict == Verdict::ABetter && lo > delta {
        Practical::ABetter
    } else if v.verdict == Verdict::BBetter && hi < -delta {
        Practical::BBetter
    } else if delta > 0.0 && -delta < lo && hi < delta {
        Practical::Equivalent
    } else {
        Practical::Undecided
    }
}

#[cfg(test)]
mod practical_tests {
    use super::*;

    fn error_verdict(lo: f64, est: f64, hi: f64, verdict: Verdict) -> PairVerdict {
        PairVerdict {
            a: "a".into(),
            b: "b".into(),
            test: PairTest {
                metric: PairedMetric::Error,
                pairs: 50,
                effect: Interval { estimate: est, lo, hi },
                p: 0.001,
                a_leads: est < 0.0,
            },
            p_holm: 0.002,
            verdict,
        }
    }

    #[test]
    fn a_tiny_real_difference_is_not_a_practical_one() {
        let m = MinEffect { success: 0.02, rms: 1e-3 };
        // 1.8e-11 m better: significant, meaningless at a 1 mm margin: equivalent.
        let v = error_verdict(-2.0e-11, -1.8e-11, -1.6e-11, Verdict::ABetter);
        assert_eq!(practical(&v, &m), Practical::Equivalent);
        // 5 mm better, interval [−6, −4] mm: better beyond the margin.
        let v = error_verdict(-6e-3, -5e-3, -4e-3, Verdict::ABetter);
        assert_eq!(practical(&v, &m), Practical::ABetter);
        // B better on error: a positive A − B beyond the margin.
        let v = error_verdict(4e-3, 5e-3, 6e-3, Verdict::BBetter);
        assert_eq!(practical(&v, &m), Practical::BBetter);
        // An interval straddling the margin: undecided.
        let v = error_verdict(-2e-3, -1e-3, -1e-4, Verdict::ABetter);
        assert_eq!(practical(&v, &m), Practical::Undecided);
        // Margin 0: only the test's verdict.
        let zero = MinEffect { success: 0.0, rms: 0.0 };
        let v = error_verdict(-2.0e-11, -1.8e-11, -1.6e-11, Verdict::ABetter);
        assert_eq!(practical(&v, &zero), Practical::ABetter);
    }

    #[test]
    fn margins_parse_or_are_refused_by_name() {
        let m = MinEffect::parse(&["rms=0.005".into(), "success=0.02".into()]).unwrap();
        assert_eq!(m, MinEffect { success: 0.02, rms: 0.005 });
        for bad in ["rms", "rms=x", "rms=-1", "success=1.5", "tilt=0.1", "rms=inf"] {
            let e = MinEffect::parse(&[bad.to_string()]).unwrap_err();
            assert!(e.starts_with(&format!("--min-effect {bad}")), "{e}");
        }
    }
}
