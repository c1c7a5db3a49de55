//! How sure a result is: confidence intervals for the numbers that come
//! from random draws, and paired tests between controllers flown on the
//! same draws. Pure arithmetic on counts and samples; nothing of the
//! simulator is used (floor 0).
//!
//! - [`rate`]: a success (completed, crashed, …) rate — Wilson score
//!   (Wilson 1927) and Clopper–Pearson (1934) intervals;
//! - [`order`]: a quantile (median, p95) — the distribution-free interval
//!   between two order statistics, with ranks from binomial quantiles
//!   (David & Nagaraja 2003, §7.1);
//! - [`mean`]: a mean — Student's t interval;
//! - [`paired`]: two controllers on the same draws — McNemar's exact test
//!   for success, the Wilcoxon signed-rank test for a per-run metric, Holm's
//!   correction over all pairs (Holm 1979), and the [`paired::Verdict`];
//! - [`sequential`]: the alpha spent at each look of a campaign that stops
//!   as soon as every pair is decided (Lan & DeMets 1983).
//!
//! Distributions and their quantiles come from the `statrs` crate; what is
//! written here is what it does not provide (the intervals and tests
//! themselves, the exact null distribution of the signed-rank statistic).
//! docs/statistics.md explains each and its assumptions.

pub mod mean;
pub mod order;
pub mod paired;
pub mod rate;
pub mod sequential;

use serde::Serialize;

/// The confidence level every interval of a report shares (`--confidence`):
/// default 0.95.
pub const DEFAULT_CONFIDENCE: f64 = 0.95;

/// Why a statistic could not be computed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum StatsError {
    /// A confidence level outside (0, 1).
    #[error("confidence = {0}: expected a level strictly between 0 and 1 (e.g. 0.95)")]
    Confidence(f64),
    /// More successes than trials.
    #[error("{successes} successes out of {trials} trials: successes cannot exceed trials")]
    Counts {
        /// Successes given.
        successes: u64,
        /// Trials given.
        trials: u64,
    },
}

/// Check a confidence level: strictly between 0 and 1.
pub fn check_confidence(confidence: f64) -> Result<f64, StatsError> {
    if confidence.is_finite() && confidence > 0.0 && confidence < 1.0 {
        Ok(confidence)
    } else {
        Err(StatsError::Confidence(confidence))
    }
}

/// An estimate with its confidence interval `[lo, hi]`, `lo ≤ estimate ≤ hi`.
/// A bound the data cannot give (a p95 upper bound from 10 runs) is
/// infinite (`null` in JSON).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Interval {
    /// Point estimate.
    pub estimate: f64,
    /// Lower bound.
    pub lo: f64,
    /// Upper bound.
    pub hi: f64,
}

impl Interval {
    /// `lo ≤ x ≤ hi`.
    pub fn contains(&self, x: f64) -> bool {
        self.lo <= x && x <= self.hi
    }

    /// `hi − lo` (infinite if a bound is).
    pub fn width(&self) -> f64 {
        self.hi - self.lo
    }

    /// The three numbers multiplied by `k > 0` (a rate as a percentage).
    pub fn scaled(&self, k: f64) -> Self {
        Self { estimate: self.estimate * k, lo: self.lo * k, hi: self.hi * k }
    }

    /// `estimate [lo, hi]` with `decimals` decimals (`∞` for a bound the
    /// data cannot give, `–` for a missing estimate).
    pub fn display(&self, decimals: usize) -> String {
        let f = |x: f64| {
            if x.is_nan() {
                "–".to_string()
            } else if x.is_infinite() {
                if x > 0.0 {
                    "∞".to_string()
                } else {
                    "−∞".to_string()
                }
            } else {
                format!("{x:.decimals$}")
            }
        };
        format!("{} [{}, {}]", f(self.estimate), f(self.lo), f(self.hi))
    }
}

/// The standard normal quantile `z` with `P(Z ≤ z) = p`.
pub fn normal_quantile(p: f64) -> f64 {
    use statrs::distribution::{ContinuousCDF, Normal};
    Normal::standard().inverse_cdf(p)
}

/// The standard normal upper tail `P(Z ≥ z)`.
pub fn normal_sf(z: f64) -> f64 {
    use statrs::distribution::{ContinuousCDF, Normal};
    Normal::standard().sf(z)
}

#[cfg(test)]
mod tests {
    #[test]
    fn normal_quantile_is_accurate() {
        let z = super::normal_quantile(0.975);
        println!("z = {z:.17} sf = {:.17e}", 2.0 * super::normal_sf(z));
        assert!((z - 1.959_963_984_540_054).abs() < 1e-12, "{z}");
    }
}
