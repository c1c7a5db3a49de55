//! Paired comparisons of two controllers flown on the same draws (run `i`
//! of each controller flies the same sampled vehicle, wind and noise), so
//! each run is a matched pair and the tests look at within-pair
//! differences only:
//!
//! - success: McNemar's exact test (McNemar 1947; the exact conditional
//!   binomial form, Fagerland et al. 2013) on the discordant pairs;
//! - a per-run metric where lower is better (RMS position error): the
//!   Wilcoxon signed-rank test (Wilcoxon 1945) on the differences `A − B`,
//!   with the Hodges–Lehmann shift (Hodges & Lehmann 1963, "Estimates of
//!   location based on rank tests", Ann. Math. Stat. 34) as the effect and
//!   the interval that inverts the same test, `{δ : p(A − B − δ) > α}`
//!   ([`hodges_lehmann`]): a verdict "better" (Holm p ≤ α, so the plain p ≤
//!   α) therefore never stands beside an effect interval containing 0;
//! - Holm's step-down correction over every test of a comparison
//!   (Holm 1979), so the chance of any false verdict stays at most `α`.

use super::rate::clopper_pearson;
use super::{check_confidence, normal_sf, Interval, StatsError};
use serde::Serialize;
use statrs::distribution::{Binomial, DiscreteCDF};

/// Two-sided p-value of McNemar's exact test: `b` pairs where only A
/// succeeded, `c` where only B did. Under "no difference" each discordant
/// pair is equally likely either way, so `min(b, c)` is Binomial(b + c, ½):
/// `p = min(1, 2·P(X ≤ min(b, c)))` (SciPy's
/// `binomtest(min(b, c), b + c, 0.5).pvalue`). `1` when `b + c = 0`.
pub fn mcnemar_exact(b: u64, c: u64) -> f64 {
    let m = b + c;
    if m == 0 {
        return 1.0;
    }
    let d = Binomial::new(0.5, m).expect("p = 0.5 is a valid probability");
    (2.0 * d.cdf(b.min(c))).min(1.0)
}

/// The difference of success rates `p_A − p_B` over `n` pairs with its
/// interval, conditional on the `b + c` discordant pairs: `(b − c)/n =
/// (b + c)/n · (2π − 1)` with `π` the share of discordant pairs A wins,
/// bounded by its Clopper–Pearson interval (the interval that inverts the
/// exact test above).
pub fn rate_difference(b: u64, c: u64, n: u64, confidence: f64) -> Result<Interval, StatsError> {
    check_confidence(confidence)?;
    let m = b + c;
    if n == 0 {
        return Ok(Interval { estimate: f64::NAN, lo: -1.0, hi: 1.0 });
    }
    let share = m as f64 / n as f64;
    let estimate = (b as f64 - c as f64) / n as f64;
    if m == 0 {
        return Ok(Interval { estimate: 0.0, lo: 0.0, hi: 0.0 });
    }
    let pi = clopper_pearson(b, m, confidence)?;
    Ok(Interval {
        estimate,
        lo: (share * (2.0 * pi.lo - 1.0)).min(estimate),
        hi: (share * (2.0 * pi.hi - 1.0)).max(estimate),
    })
}

/// The outcome of a Wilcoxon signed-rank test.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SignedRank {
    /// Non-zero differences ranked (zeros dropped: Wilcoxon's convention).
    pub n: usize,
    /// Sum of the ranks of the positive differences.
    pub r_plus: f64,
    /// Sum of the ranks of the negative differences.
    pub r_minus: f64,
    /// Two-sided p-value.
    pub p: f64,
    /// `true`: from the exact null distribution; `false`: the normal
    /// approximation.
    pub exact: bool,
}

/// Most non-zero differences for which [`wilcoxon`] uses the exact null
/// distribution (SciPy's `method="auto"` threshold).
pub const WILCOXON_EXACT_MAX: usize = 50;

/// The Wilcoxon signed-rank test of "the differences are symmetric about
/// 0" on `diffs` (`A − B` per pair; non-finite values skipped). Zeros are
/// dropped, the absolute values ranked (ties get their average rank).
///
/// - With at most [`WILCOXON_EXACT_MAX`] differences, no zero and no tie:
///   the exact null distribution of `R⁺` (every sign pattern equally
///   likely, counted by dynamic programming), `p = min(1, 2·P(T ≤
///   min(R⁺, R⁻)))`.
/// - Otherwise the normal approximation: mean `n(n+1)/4`, variance
///   `n(n+1)(2n+1)/24 − Σ(t³ − t)/48` over tie groups of size `t`, and a
///   continuity correction of ½ towards the mean.
///
/// Agrees with SciPy's `wilcoxon(d, method="exact")` and
/// `wilcoxon(d, method="approx", correction=True)` respectively.
pub fn wilcoxon(diffs: &[f64]) -> SignedRank {
    let d: Vec<f64> = diffs.iter().copied().filter(|x| x.is_finite()).collect();
    let zeros = d.iter().filter(|x| **x == 0.0).count();
    let mut nz: Vec<f64> = d.into_iter().filter(|x| *x != 0.0).collect();
    nz.sort_by(|a, b| a.abs().total_cmp(&b.abs()));
    let n = nz.len();
    if n == 0 {
        return SignedRank { n: 0, r_plus: 0.0, r_minus: 0.0, p: 1.0, exact: true };
    }
    // Average ranks of tied absolute values.
    let mut ranks = vec![0.0; n];
    let mut tie_term = 0.0;
    let mut i = 0;
    while i < n {
        let mut j = i + 1;
        while j < n && nz[j].abs() == nz[i].abs() {
            j += 1;
        }
        let avg = (i + 1 + j) as f64 / 2.0;
        ranks[i..j].iter_mut().for_each(|r| *r = avg);
        let t = (j - i) as f64;
        tie_term += t * t * t - t;
        i = j;
    }
    let r_plus: f64 = nz.iter().zip(&ranks).filter(|(x, _)| **x > 0.0).map(|(_, r)| r).sum();
    let total = (n * (n + 1)) as f64 / 2.0;
    let r_minus = total - r_plus;
    let exact = n <= WILCOXON_EXACT_MAX && zeros == 0 && tie_term == 0.0;
    let p = if exact {
        let t = r_plus.min(r_minus) as usize;
        (2.0 * signed_rank_cdf(n, t)).min(1.0)
    } else {
        let nf = n as f64;
        let mean = nf * (nf + 1.0) / 4.0;
        let var = nf * (nf + 1.0) * (2.0 * nf + 1.0) / 24.0 - tie_term / 48.0;
        let dev = (r_plus - mean).abs();
        let dev = if dev > 0.0 { dev - 0.5 } else { 0.0 };
        if var > 0.0 {
            (2.0 * normal_sf(dev / var.sqrt())).min(1.0)
        } else {
            1.0
        }
    };
    SignedRank { n, r_plus, r_minus, p, exact }
}

/// `P(R⁺ ≤ t)` under the null for `n` untied ranks: the number of subsets
/// of `{1, …, n}` with sum at most `t`, over `2ⁿ`.
pub fn signed_rank_cdf(n: usize, t: usize) -> f64 {
    let max = n * (n + 1) / 2;
    // counts[s]: subsets with sum s (as f64: exact below 2⁵³, n ≤ 50 gives ≤ 2⁵⁰).
    let mut counts = vec![0.0f64; max + 1];
    counts[0] = 1.0;
    for k in 1..=n {
        for s in (k..=k * (k + 1) / 2).rev() {
            counts[s] += counts[s - k];
        }
    }
    let below: f64 = counts[..=t.min(max)].iter().sum();
    below / 2f64.powi(n as i32)
}

/// Holm's step-down adjusted p-values (Holm 1979), in the order given:
/// sorted ascending, the `j`-th (from 1) of `m` is multiplied by
/// `m − j + 1`, made non-decreasing and capped at 1. Rejecting where the
/// adjusted value is at most `α` keeps the family-wise error rate at most
/// `α` whatever the dependence between the tests.
pub fn holm(p: &[f64]) -> Vec<f64> {
    let m = p.len();
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by(|&a, &b| p[a].total_cmp(&p[b]));
    let mut out = vec![0.0; m];
    let mut running: f64 = 0.0;
    for (j, &i) in order.iter().enumerate() {
        running = running.max(((m - j) as f64 * p[i]).min(1.0));
        out[i] = running;
    }
    out
}

/// What a paired test concludes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Verdict {
    /// A is better, at the family-wise level.
    #[serde(rename = "A better")]
    ABetter,
    /// B is better, at the family-wise level.
    #[serde(rename = "B better")]
    BBetter,
    /// The runs flown do not show a difference (not: "they are equal").
    #[serde(rename = "no difference shown")]
    NoDifference,
}

impl Verdict {
    /// `A better`, `B better`, `no difference shown`.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::ABetter => "A better",
            Self::BBetter => "B better",
            Self::NoDifference => "no difference shown",
        }
    }
}

/// The metric a paired test is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PairedMetric {
    /// Success (higher is better): McNemar's exact test; effect `p_A − p_B`.
    Success,
    /// A per-run error (lower is better): Wilcoxon signed-rank; effect the
    /// Hodges–Lehmann shift of `A − B` over the pairs where both have a
    /// value, with the interval inverting the signed-rank test.
    Error,
}

/// One paired test between two contestants, before the correction.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PairTest {
    /// Metric.
    pub metric: PairedMetric,
    /// Pairs the test is over.
    pub pairs: usize,
    /// Effect size with its interval: `p_A − p_B` (success) or the
    /// Hodges–Lehmann shift of `A − B` (error, in the metric's unit).
    pub effect: Interval,
    /// Two-sided p-value, uncorrected.
    pub p: f64,
    /// Which way the data lean: `true` if A looks better.
    pub a_leads: bool,
}

/// McNemar's test and the rate difference of paired successes (`a[i]`,
/// `b[i]` of pair `i`).
pub fn success_test(a: &[bool], b: &[bool], confidence: f64) -> Result<PairTest, StatsError> {
    let n = a.len().min(b.len());
    let only_a = (0..n).filter(|&i| a[i] && !b[i]).count() as u64;
    let only_b = (0..n).filter(|&i| !a[i] && b[i]).count() as u64;
    let effect = rate_difference(only_a, only_b, n as u64, confidence)?;
    Ok(PairTest {
        metric: PairedMetric::Success,
        pairs: n,
        effect,
        p: mcnemar_exact(only_a, only_b),
        a_leads: only_a > only_b,
    })
}

/// Wilcoxon's test and the median difference of a paired error metric
/// (pairs where either value is not finite are left out).
pub fn error_test(a: &[f64], b: &[f64], confidence: f64) -> Result<PairTest, StatsError> {
    let diffs: Vec<f64> = a.iter().zip(b).filter(|(x, y)| x.is_finite() && y.is_finite()).map(|(x, y)| x - y).collect();
    let w = wilcoxon(&diffs);
    let effect = hodges_lehmann(&diffs, confidence)?;
    Ok(PairTest { metric: PairedMetric::Error, pairs: diffs.len(), effect, p: w.p, a_leads: w.r_minus > w.r_plus })
}

/// An `f64` as a `u64` in the same order (`-inf < … < -0 < 0 < … < inf`),
/// for bisection over every representable value.
fn ordered_bits(x: f64) -> u64 {
    let b = x.to_bits();
    if b >> 63 == 1 {
        !b
    } else {
        b | (1 << 63)
    }
}

/// The inverse of [`ordered_bits`].
fn from_ordered_bits(u: u64) -> f64 {
    f64::from_bits(if u >> 63 == 1 { u & !(1 << 63) } else { !u })
}

/// The smallest `x` in `[lo, hi]` (as representable values, `pred(hi)`
/// true) with `pred(x)` true, for a `pred` false below some point and true
/// above it: bisection over the ordered bit patterns, exact.
fn first_true(lo: f64, hi: f64, pred: impl Fn(f64) -> bool) -> f64 {
    let (mut a, mut b) = (ordered_bits(lo), ordered_bits(hi));
    while a < b {
        let m = a + (b - a) / 2;
        if pred(from_ordered_bits(m)) {
            b = m;
        } else {
            a = m + 1;
        }
    }
    from_ordered_bits(a)
}

/// The `k`-th smallest (1-based) Walsh sum `d_i + d_j`, `i ≤ j`, of the
/// sorted `d`, without forming the `n(n+1)/2` sums: bisection on the value
/// with an O(n) two-pointer count.
fn walsh_sum(d: &[f64], k: usize) -> f64 {
    let count = |t: f64| {
        let (mut c, mut r) = (0usize, d.len());
        for i in 0..d.len() {
            while r > 0 && d[i] + d[r - 1] > t {
                r -= 1;
            }
            if r <= i {
                break;
            }
            c += r - i;
        }
        c
    };
    let (lo, hi) = (d[0] + d[0], d[d.len() - 1] + d[d.len() - 1]);
    first_true(lo, hi, |t| count(t) >= k)
}

/// The Hodges–Lehmann shift of paired differences `diffs` (non-finite
/// values left out) — the median of the Walsh averages `(d_i + d_j)/2`,
/// `i ≤ j` — with the interval `{δ : wilcoxon(d − δ).p > 1 − confidence}`,
/// the shifts the signed-rank test ([`wilcoxon`], its exact or normal form
/// as there) does not reject (Hollander, Wolfe & Chicco 2014,
/// "Nonparametric Statistical Methods", §3.2). Each bound is found by exact
/// bisection between the estimate and a shift past every difference; a
/// side where even that is not rejected (too few pairs) is infinite.
/// Consistent with the test by construction: `0` lies outside the interval
/// exactly when the test at `0` rejects (up to the test's own monotonicity
/// in `δ`, which holds for the exact form and, away from ties, the normal one).
pub fn hodges_lehmann(diffs: &[f64], confidence: f64) -> Result<Interval, StatsError> {
    let alpha = 1.0 - check_confidence(confidence)?;
    let mut d: Vec<f64> = diffs.iter().copied().filter(|x| x.is_finite()).collect();
    if d.is_empty() {
        return Ok(Interval { estimate: f64::NAN, lo: f64::NEG_INFINITY, hi: f64::INFINITY });
    }
    d.sort_by(f64::total_cmp);
    let m = d.len() * (d.len() + 1) / 2;
    let estimate = if m % 2 == 1 {
        0.5 * walsh_sum(&d, m.div_ceil(2))
    } else {
        0.25 * (walsh_sum(&d, m / 2) + walsh_sum(&d, m / 2 + 1))
    };
    let rejects = |delta: f64| {
        let shifted: Vec<f64> = d.iter().map(|x| x - delta).collect();
        wilcoxon(&shifted).p <= alpha
    };
    let span = (d[d.len() - 1] - d[0]).abs().max(d[0].abs()).max(d[d.len() - 1].abs()).max(f64::MIN_POSITIVE);
    let (below, above) = (d[0] - span, d[d.len() - 1] + span);
    let lo = if rejects(below) { first_true(below, estimate, |x| !rejects(x)) } else { f64::NEG_INFINITY };
    // The upper bound: the last shift not rejected, i.e. just below the
    // first rejected one above the estimate.
    let hi = if rejects(above) {
        let first = first_true(estimate, above, rejects);
        from_ordered_bits(ordered_bits(first) - 1).max(estimate)
    } else {
        f64::INFINITY
    };
    Ok(Interval { estimate, lo, hi })
}

/// The verdicts of a family of tests at family-wise level `1 − confidence`
/// (Holm): `(adjusted p, verdict)` per test, in order.
pub fn verdicts(tests: &[PairTest], confidence: f64) -> Result<Vec<(f64, Verdict)>, StatsError> {
    let alpha = 1.0 - check_confidence(confidence)?;
    verdicts_at(tests, alpha)
}

/// [`verdicts`] at family-wise level `alpha` (the share a sequential look
/// spends, [`super::sequential`]).
pub fn verdicts_at(tests: &[PairTest], alpha: f64) -> Result<Vec<(f64, Verdict)>, StatsError> {
    let adjusted = holm(&tests.iter().map(|t| t.p).collect::<Vec<_>>());
    Ok(tests
        .iter()
        .zip(adjusted)
        .map(|(t, p)| {
            let v = if p > alpha {
                Verdict::NoDifference
            } else if t.a_leads {
                Verdict::ABetter
            } else {
                Verdict::BBetter
            };
            (p, v)
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hodges_lehmann_worked_values() {
        // Walsh averages of (1, 2, 4): 1, 1.5, 2, 2.5, 3, 4: median 2.25.
        let e = hodges_lehmann(&[4.0, 1.0, 2.0], 0.95).unwrap();
        assert_eq!(e.estimate, 2.25);
        // Three pairs cannot reject anything at 5 %: both sides infinite.
        assert!(e.lo == f64::NEG_INFINITY && e.hi == f64::INFINITY);
        // A symmetric sample's shift is its centre.
        let d: Vec<f64> = (0..41).map(|i| 0.5 + (i as f64 - 20.0) * 0.01).collect();
        let e = hodges_lehmann(&d, 0.95).unwrap();
        assert!((e.estimate - 0.5).abs() < 1e-12 && e.lo < 0.5 && e.hi > 0.5, "{e:?}");
        assert!(e.lo > 0.0, "all differences positive: 0 is rejected");
    }

    proptest::proptest! {
        /// "better" never stands beside an effect interval containing 0: the
        /// interval excludes 0 exactly when the test at 0 rejects.
        #[test]
        fn the_effect_interval_agrees_with_the_signed_rank_test(
            d in proptest::collection::vec(-1.0f64..1.0, 1..120),
            shift in -0.5f64..0.5,
        ) {
            let d: Vec<f64> = d.iter().map(|x| x + shift).collect();
            let e = hodges_lehmann(&d, 0.95).unwrap();
            let rejects = wilcoxon(&d).p <= 0.05;
            proptest::prop_assert_eq!(rejects, !(e.lo <= 0.0 && 0.0 <= e.hi), "{:?} p {}", e, wilcoxon(&d).p);
            proptest::prop_assert!(e.lo <= e.estimate && e.estimate <= e.hi);
        }
    }

    #[test]
    fn mcnemar_worked_values() {
        // 0 vs 6 discordant pairs: 2/64.
        assert!((mcnemar_exact(0, 6) - 2.0 / 64.0).abs() < 1e-12);
        assert_eq!(mcnemar_exact(3, 3), 1.0);
        assert_eq!(mcnemar_exact(0, 0), 1.0);
    }

    #[test]
    fn signed_rank_distribution_sums_to_one_and_is_symmetric() {
        assert!((signed_rank_cdf(10, 55) - 1.0).abs() < 1e-15);
        // P(R⁺ ≤ 0) = 2⁻ⁿ; n = 5: P(R⁺ ≤ 3) = 5/32 ({}, {1}, {2}, {3}, {1,2}).
        assert!((signed_rank_cdf(5, 3) - 5.0 / 32.0).abs() < 1e-15);
    }

    #[test]
    fn wilcoxon_all_positive_small_sample() {
        let w = wilcoxon(&[1.0, 2.0, 3.0, 4.0, 5.0]);
        assert!(w.exact);
        assert!((w.p - 2.0 / 32.0).abs() < 1e-15);
        assert_eq!((w.r_plus, w.r_minus), (15.0, 0.0));
    }

    #[test]
    fn holm_adjusts_step_down() {
        let a = holm(&[0.01, 0.04, 0.03]);
        assert!((a[0] - 0.03).abs() < 1e-15);
        assert!((a[2] - 0.06).abs() < 1e-15);
        assert!((a[1] - 0.06).abs() < 1e-15);
    }

    #[test]
    fn verdict_follows_direction() {
        let a: Vec<f64> = (0..40).map(|i| 1.0 + f64::from(i) * 0.01).collect();
        let b: Vec<f64> = a.iter().map(|x| x + 0.5).collect();
        let t = error_test(&a, &b, 0.95).unwrap();
        assert!(t.a_leads && t.effect.hi < 0.0);
        let v = verdicts(&[t], 0.95).unwrap();
        assert_eq!(v[0].1, Verdict::ABetter);
    }
}
