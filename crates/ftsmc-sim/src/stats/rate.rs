//! Intervals for a rate: `k` successes in `n` independent trials with the
//! same probability `p` (a binomial count).

use super::{check_confidence, normal_quantile, Interval, StatsError};
use statrs::distribution::{Beta, ContinuousCDF};

fn check(k: u64, n: u64) -> Result<(), StatsError> {
    if k > n {
        Err(StatsError::Counts { successes: k, trials: n })
    } else {
        Ok(())
    }
}

/// Wilson's score interval (Wilson 1927; Agresti & Coull 1998, Eq. 2) at
/// `confidence`: the `p` whose score test does not reject, without
/// continuity correction,
/// `(k + z²/2)/(n + z²) ± z/(n + z²)·√(k(n−k)/n + z²/4)`, `z` the
/// normal quantile of `(1 + confidence)/2`. The estimate is `k/n`.
/// Its coverage oscillates around the nominal level and dips below it
/// near `p = 0` or `1` (about 93 % at `n = 200`, `p = 0.02`, 95 %
/// nominal; docs/statistics.md). With `n = 0`: `[0, 1]` around `NaN`.
pub fn wilson(k: u64, n: u64, confidence: f64) -> Result<Interval, StatsError> {
    check_confidence(confidence)?;
    check(k, n)?;
    if n == 0 {
        return Ok(Interval { estimate: f64::NAN, lo: 0.0, hi: 1.0 });
    }
    let z = normal_quantile(0.5 + confidence / 2.0);
    let (kf, nf) = (k as f64, n as f64);
    let z2 = z * z;
    let centre = (kf + z2 / 2.0) / (nf + z2);
    let half = z / (nf + z2) * (kf * (nf - kf) / nf + z2 / 4.0).sqrt();
    let estimate = kf / nf;
    // Exact at the ends (k = 0 or n), and never past the estimate by rounding.
    let lo = if k == 0 { 0.0 } else { (centre - half).max(0.0).min(estimate) };
    let hi = if k == n { 1.0 } else { (centre + half).min(1.0).max(estimate) };
    Ok(Interval { estimate, lo, hi })
}

/// The Clopper–Pearson ("exact") interval (Clopper & Pearson 1934): the
/// `α/2` quantile of Beta(k, n−k+1) and the `1 − α/2` quantile of
/// Beta(k+1, n−k), `α = 1 − confidence`. Its coverage is at least the
/// nominal level for every `p` (conservative: often 97–99 % at 95 %).
pub fn clopper_pearson(k: u64, n: u64, confidence: f64) -> Result<Interval, StatsError> {
    check_confidence(confidence)?;
    check(k, n)?;
    if n == 0 {
        return Ok(Interval { estimate: f64::NAN, lo: 0.0, hi: 1.0 });
    }
    let alpha = 1.0 - confidence;
    let (kf, nf) = (k as f64, n as f64);
    let beta_q = |a: f64, b: f64, q: f64| Beta::new(a, b).map(|d| d.inverse_cdf(q)).unwrap_or(f64::NAN);
    let estimate = kf / nf;
    let lo = if k == 0 { 0.0 } else { beta_q(kf, nf - kf + 1.0, alpha / 2.0).min(estimate) };
    let hi = if k == n { 1.0 } else { beta_q(kf + 1.0, nf - kf, 1.0 - alpha / 2.0).max(estimate) };
    Ok(Interval { estimate, lo, hi })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wilson_matches_a_worked_value() {
        // 10/10 at 95 %: [0.7225, 1] (the bound a reader sees in reproduce).
        let w = wilson(10, 10, 0.95).unwrap();
        assert!((w.lo - 0.722_467_2).abs() < 1e-6, "{w:?}");
        assert_eq!(w.hi, 1.0);
        // 5/10: symmetric about 0.5.
        let w = wilson(5, 10, 0.95).unwrap();
        assert!((w.lo + w.hi - 1.0).abs() < 1e-12);
        assert!((w.lo - 0.236_593_3).abs() < 1e-6, "{w:?}");
    }

    #[test]
    fn clopper_pearson_matches_a_worked_value() {
        // 0/10: upper bound 1 − 0.025^(1/10).
        let c = clopper_pearson(0, 10, 0.95).unwrap();
        assert!((c.hi - (1.0 - ftsmc_core::math::powf(0.025, 0.1))).abs() < 1e-9, "{c:?}");
        let c = clopper_pearson(5, 10, 0.95).unwrap();
        assert!((c.lo - 0.187_086_4).abs() < 1e-6, "{c:?}");
    }

    #[test]
    fn bad_input_is_an_error() {
        assert!(wilson(11, 10, 0.95).is_err());
        assert!(wilson(1, 10, 1.0).is_err());
        assert!(clopper_pearson(1, 10, f64::NAN).is_err());
    }
}
