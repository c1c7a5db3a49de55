//! Distribution-free intervals for a quantile (median, p95) between two
//! order statistics (David & Nagaraja 2003, §7.1; Conover 1999, §3.2).
//!
//! Of `n` independent draws from any continuous distribution, the number
//! `B` below its `q`-quantile `ξ_q` is Binomial(n, q). So the interval
//! `[x₍ₗ₎, x₍ᵤ₎]` between the `l`-th and `u`-th smallest draws holds `ξ_q`
//! with probability `P(l ≤ B ≤ u − 1)`, whatever the distribution. The
//! ranks are binomial quantiles: `l` the smallest `k` with
//! `P(B ≤ k) ≥ α/2` and `u − 1` the smallest with `P(B ≤ k) ≥ 1 − α/2`
//! ([`binomial_quantile`], SciPy's `binom.ppf`), so each side misses with
//! probability at most `α/2`. A rank outside `1..=n` is a bound the data
//! cannot give: `−∞` or `+∞` (10 runs cannot bound a p95 from above).

use super::{check_confidence, Interval, StatsError};
use statrs::distribution::{Binomial, DiscreteCDF};

/// The smallest `k` in `0..=n` with `P(B ≤ k) ≥ prob`, `B ~ Binomial(n, p)`
/// (SciPy's `binom.ppf(prob, n, p)` for `0 < prob < 1`), found by
/// bisection on statrs's cumulative distribution (a regularised beta
/// function), which increases with `k`.
pub fn binomial_quantile(prob: f64, n: u64, p: f64) -> u64 {
    let Ok(d) = Binomial::new(p, n) else { return 0 };
    let (mut lo, mut hi) = (0u64, n);
    while lo < hi {
        let mid = lo + (hi - lo) / 2;
        if d.cdf(mid) >= prob {
            hi = mid;
        } else {
            lo = mid + 1;
        }
    }
    lo
}

/// The ranks `(l, u)` (1-based; `0` and `n + 1` stand for the infinite
/// bounds) of the order-statistic interval for the `q`-quantile of `n`
/// draws at `confidence`, and its exact coverage `P(l ≤ B ≤ u − 1)`.
pub fn quantile_ranks(n: u64, q: f64, confidence: f64) -> Result<(u64, u64, f64), StatsError> {
    check_confidence(confidence)?;
    let alpha = 1.0 - confidence;
    let l = binomial_quantile(alpha / 2.0, n, q);
    let u = binomial_quantile(1.0 - alpha / 2.0, n, q) + 1;
    let coverage = match Binomial::new(q, n) {
        Ok(d) => {
            let below_l = if l == 0 { 0.0 } else { d.cdf(l - 1) };
            d.cdf(u - 1) - below_l
        }
        Err(_) => f64::NAN,
    };
    Ok((l, u.min(n + 1), coverage))
}

/// The nearest-rank `q`-quantile of `sorted` (ascending, finite) with its
/// order-statistic interval at `confidence`. `None` for no values.
pub fn quantile_interval(sorted: &[f64], q: f64, confidence: f64) -> Result<Option<Interval>, StatsError> {
    let n = sorted.len();
    if n == 0 {
        check_confidence(confidence)?;
        return Ok(None);
    }
    let rank = ((q * n as f64).ceil() as usize).clamp(1, n);
    let estimate = sorted[rank - 1];
    let (l, u, _) = quantile_ranks(n as u64, q, confidence)?;
    let lo = if l == 0 { f64::NEG_INFINITY } else { sorted[l as usize - 1].min(estimate) };
    let hi = if u as usize > n { f64::INFINITY } else { sorted[u as usize - 1].max(estimate) };
    Ok(Some(Interval { estimate, lo, hi }))
}

/// [`quantile_interval`] of the finite values of `values` (any order).
pub fn quantile_of(values: &[f64], q: f64, confidence: f64) -> Result<Option<Interval>, StatsError> {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    v.sort_by(f64::total_cmp);
    quantile_interval(&v, q, confidence)
}

/// The finite values of `values`, ascending (the input of [`quantile_interval`]
/// and [`interpolated_quantile`]).
pub fn finite_sorted(mut values: Vec<f64>) -> Vec<f64> {
    values.retain(|x| x.is_finite());
    values.sort_by(f64::total_cmp);
    values
}

/// The `q`-quantile (`0 ≤ q ≤ 1`) of `sorted` (ascending) by linear
/// interpolation between order statistics, `x₍ᵢ₎ + (h − i)(x₍ᵢ₊₁₎ − x₍ᵢ₎)`
/// with `h = q (n − 1)` (0-based; Hyndman & Fan 1996, "Sample quantiles in
/// statistical packages", Am. Stat. 50, definition 7 — R's and NumPy's
/// default). `None` for no values. The ladder table's medians and p95s use
/// it; [`quantile_interval`]'s estimate is the nearest-rank one.
pub fn interpolated_quantile(sorted: &[f64], q: f64) -> Option<f64> {
    match sorted.len() {
        0 => None,
        1 => Some(sorted[0]),
        n => {
            let x = q * (n - 1) as f64;
            let i = x.floor() as usize;
            let j = (i + 1).min(n - 1);
            Some(sorted[i] + (x - i as f64) * (sorted[j] - sorted[i]))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolated_quantile_is_hyndman_fan_type_7() {
        assert_eq!(interpolated_quantile(&[], 0.5), None);
        assert_eq!(interpolated_quantile(&[3.0], 0.95), Some(3.0));
        assert_eq!(interpolated_quantile(&[1.0, 2.0, 3.0, 4.0], 0.5), Some(2.5));
        let ramp: Vec<f64> = (0..=100).map(f64::from).collect();
        assert_eq!(interpolated_quantile(&ramp, 0.95), Some(95.0));
        assert_eq!(interpolated_quantile(&[0.0, 10.0], 0.25), Some(2.5));
        assert_eq!(finite_sorted(vec![2.0, f64::NAN, -1.0, f64::INFINITY]), vec![-1.0, 2.0]);
    }

    #[test]
    fn median_of_ten_uses_the_second_and_ninth_values() {
        let v: Vec<f64> = (1..=10).map(f64::from).collect();
        let i = quantile_interval(&v, 0.5, 0.95).unwrap().unwrap();
        assert_eq!((i.lo, i.estimate, i.hi), (2.0, 5.0, 9.0));
        let (_, _, coverage) = quantile_ranks(10, 0.5, 0.95).unwrap();
        // P(2 ≤ B ≤ 8), B ~ Bin(10, 1/2) = 1 − 2·11/1024.
        assert!((coverage - (1.0 - 22.0 / 1024.0)).abs() < 1e-12);
    }

    #[test]
    fn ten_runs_cannot_bound_a_p95_from_above() {
        let v: Vec<f64> = (1..=10).map(f64::from).collect();
        let i = quantile_interval(&v, 0.95, 0.95).unwrap().unwrap();
        assert_eq!(i.hi, f64::INFINITY);
        assert!(i.lo <= i.estimate);
    }

    #[test]
    fn binomial_quantile_matches_hand_values() {
        // Bin(10, 1/2): P(B ≤ 1) = 11/1024 < 0.025 ≤ P(B ≤ 2) = 56/1024.
        assert_eq!(binomial_quantile(0.025, 10, 0.5), 2);
        assert_eq!(binomial_quantile(0.975, 10, 0.5), 8);
        assert_eq!(binomial_quantile(0.5, 0, 0.5), 0);
    }
}
