//! How rare is failure: `p = P(margin < 0)` under the scenario's own random
//! draws, by cross-entropy importance sampling (Rubinstein & Kroese 2004,
//! "The Cross-Entropy Method", ch. 3; de Boer et al. 2005, "A tutorial on
//! the cross-entropy method", Ann. Oper. Res. 134).
//!
//! Each `[falsify]` parameter is written as a standard normal coordinate
//! `z` (its nominal distribution's quantile of `Φ(z)`), so the nominal law
//! of the searched part is `N(0, I)`. Everything else of a flight — the
//! `[montecarlo]` draws, the turbulence, sensor and motor noise — is drawn
//! as `ftsmc montecarlo` draws run `i` (its own seed from the master seed
//! and `i`), never changed by the proposal. The proposal is
//! `q = N(μ, diag σ²)` over `z` only, so the likelihood ratio is
//!
//! ```text
//! w(z) = φ(z)/q(z) = Π_i σ_i exp(−z_i²/2 + ((z_i − μ_i)/σ_i)²/2)
//! ```
//!
//! and `E_q[1{margin < 0} w] = p` exactly (the other draws have the same law
//! under both): the estimator is unbiased.
//!
//! **Levels** (multilevel CE): draw a level's flights from `q`, take the
//! `ρ = 0.1` quantile `γ` of their margins (not below 0), and refit `μ`, `σ`
//! to the draws with `margin ≤ γ`, weighted by `w` (the CE update for a
//! Gaussian family; σ smoothed by [`SMOOTHING`] and kept above
//! [`SIGMA_FLOOR`]); stop when `γ = 0`, after [`MAX_LEVELS`] or when the
//! levels have used half the budget. A level is `budget/20` flights (at
//! least 10). **Not rare**: when already the first level (drawn from the
//! nominal law) has `γ = 0` — at least `ρ` of its draws fail — importance
//! sampling has nothing to gain over plain Monte Carlo, and the whole
//! budget is flown at the nominal law and pooled (Wilson score interval, no
//! level recorded). **Estimate**: the remaining flights (at least
//! half the budget) from the last `q`; only they enter
//!
//! ```text
//! p̂ = (1/N) Σ 1{margin_k < 0} w_k,   s² = sample variance of the terms,
//! interval p̂ ± z_{1−α/2} s/√N   (central limit theorem, clipped to [0, 1])
//! ```
//!
//! **Defensive mixture** (Hesterberg 1995, "Weighted average importance
//! sampling and defensive mixture distributions", Technometrics 37): the
//! final flights are drawn from `q_α = α N(0, I) + (1 − α) q` with
//! `α =` [`DEFENSIVE_SHARE`], a share of nominal draws, so every weight
//! `w = φ/q_α ≤ 1/α`: a proposal fitted to a few elite draws cannot give the
//! rare huge weights that make `s²` — and the interval — far too small.
//!
//! With no failing draw the estimate is 0 and the interval is the
//! **one-sided** zero-failure bound `[0, min(1, (1 − α_c^{1/N}) max w)]`
//! (`α_c = 1 − confidence`; Clopper–Pearson's bound for a count of zero,
//! scaled by the largest weight drawn, itself at most `1/α`), stated as
//! one-sided. The effective sample size is Kish's `(Σ w)²/Σ w²` over the
//! failing draws. Below [`MIN_ESS`] (or with no failing draw) the
//! estimate is marked **unreliable**: its variance estimate rests on too
//! few effective failures to hold, so no plain-Monte-Carlo equivalent is
//! given and [`Estimate::suggested_budget`] says what to try.
//! `plain_mc_equivalent = p̂(1 − p̂)/(s²/N)` is the number of plain Monte
//! Carlo flights with the same variance, for reliable estimates only.

use rand::RngExt;
use serde::Serialize;
use statrs::distribution::{ContinuousCDF, Normal};

use crate::rng::chacha_stream;

/// Most CE levels before the final estimate.
pub const MAX_LEVELS: usize = 8;
/// Elite fraction ρ of each level.
pub const RHO: f64 = 0.1;
/// Smallest proposal standard deviation (per coordinate, in `z`): the
/// estimator's variance `E_q[w²] − p²` is finite only when every σ_i² > 1/2
/// (`∫ φ²/q dz` diverges otherwise: a narrower proposal's tails fall faster
/// than the nominal's), and a proposal near that bound has rare huge
/// weights that make the interval too short; 0.75 keeps clear of it.
pub const SIGMA_FLOOR: f64 = 0.75;
/// Share α of nominal draws in the final, defensive-mixture proposal
/// (module documentation): weights stay below `1/α = 10`.
pub const DEFENSIVE_SHARE: f64 = 0.1;
/// Smallest effective sample size of the failing draws for a reliable
/// importance-sampling estimate: the normal-approximation interval needs
/// enough effectively independent failures for `s²` to be estimated
/// (Owen 2013, "Monte Carlo theory, methods and examples", §9.3, uses Kish's
/// ESS this way; 30 is the usual rule for the central limit theorem).
pub const MIN_ESS: f64 = 30.0;
/// Smoothing of the standard deviation's update: `σ ← a σ_fit + (1 − a) σ`
/// (Rubinstein & Kroese 2004, §3.6: without it σ shrinks faster than the
/// mean moves and the levels stall short of the failure region).
pub const SMOOTHING: f64 = 0.5;

/// Flights of draws `first..first + z.len()` with the searched coordinates `z`.
pub trait RareObjective: Sync {
    /// Number of searched coordinates.
    fn dim(&self) -> usize;
    /// The margins of draw `first + k` with the standard normal
    /// coordinates `z[k]`, in order; independent of threads and splits.
    fn margins(&self, first: u64, z: &[Vec<f64>]) -> Vec<f64>;
}

/// One CE level.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Level {
    /// Flights of the level.
    pub flights: u64,
    /// The level's threshold γ (≥ 0).
    pub gamma: f64,
    /// The proposal's mean after the level, per coordinate.
    pub mean: Vec<f64>,
    /// Its standard deviation.
    pub std: Vec<f64>,
}

/// A failure-probability estimate.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Estimate {
    /// `p̂`.
    pub p: f64,
    /// Lower bound of the interval.
    pub lo: f64,
    /// Upper bound.
    pub hi: f64,
    /// Confidence level of the interval.
    pub confidence: f64,
    /// Every flight, levels included.
    pub flights: u64,
    /// Flights of the final estimate.
    pub final_flights: u64,
    /// Failing flights of the final estimate.
    pub failures: u64,
    /// Kish's effective sample size of the failing flights' weights.
    pub ess: f64,
    /// Flights plain Monte Carlo needs for the same variance (`NaN` when `p̂ = 0`
    /// or the estimate is unreliable).
    pub plain_mc_equivalent: f64,
    /// The interval is one-sided, `[0, hi]` (no failing draw).
    pub one_sided: bool,
    /// The interval can be trusted: plain Monte Carlo (Wilson), or
    /// importance sampling with at least [`MIN_ESS`] effective failures.
    pub reliable: bool,
    /// The CE levels (empty for plain Monte Carlo).
    pub levels: Vec<Level>,
}

impl Estimate {
    /// A budget to try for a reliable estimate: the flights flown scaled by
    /// [`MIN_ESS`] over the effective sample size (ten times the flights
    /// with no failing draw); `None` when already reliable.
    pub fn suggested_budget(&self) -> Option<u64> {
        if self.reliable {
            return None;
        }
        let factor = if self.ess >= 1.0 { (MIN_ESS / self.ess).ceil() } else { 10.0 };
        Some((self.flights as f64 * factor.max(2.0)) as u64)
    }

    /// Half the interval's width over `p̂` (`inf` when `p̂ = 0`).
    pub fn relative_half_width(&self) -> f64 {
        if self.p > 0.0 {
            0.5 * (self.hi - self.lo) / self.p
        } else {
            f64::INFINITY
        }
    }
}

fn draw(rng: &mut rand_chacha::ChaCha8Rng, mean: &[f64], std: &[f64]) -> Vec<f64> {
    mean.iter().zip(std).map(|(m, s)| m + s * crate::gauss::standard_normal(rng)).collect()
}

/// `ln w(z)` of the proposal `(mean, std)` (module documentation).
pub fn log_weight(z: &[f64], mean: &[f64], std: &[f64]) -> f64 {
    z.iter()
        .zip(mean.iter().zip(std))
        .map(|(&z, (&m, &s))| {
            let u = (z - m) / s;
            ftsmc_core::math::ln(s) - 0.5 * z * z + 0.5 * u * u
        })
        .sum()
}

/// `w(z) = φ(z)/q_α(z)` of the defensive mixture `q_α = α φ + (1 − α) q`
/// (`q` the proposal `(mean, std)`): `1/(α + (1 − α)/w_q)` with `w_q = φ/q`
/// ([`log_weight`]), at most `1/α`.
pub fn mixture_weight(z: &[f64], mean: &[f64], std: &[f64]) -> f64 {
    let inv_wq = ftsmc_core::math::exp(-log_weight(z, mean, std));
    1.0 / (DEFENSIVE_SHARE + (1.0 - DEFENSIVE_SHARE) * inv_wq)
}

/// Cross-entropy importance sampling of `P(margin < 0)` with `budget`
/// flights (at least 20), proposal draws from ChaCha streams of `seed`.
pub fn cross_entropy(objective: &dyn RareObjective, budget: u64, seed: u64, confidence: f64) -> Estimate {
    let d = objective.dim();
    let (mut mean, mut std) = (vec![0.0; d], vec![1.0; d]);
    let per_level = (budget / 20).max(10);
    let mut next: u64 = 0;
    let mut levels = Vec::new();
    let mut rng = chacha_stream(seed, 1);
    while levels.len() < MAX_LEVELS && next + per_level <= budget / 2 {
        let z: Vec<Vec<f64>> = (0..per_level).map(|_| draw(&mut rng, &mean, &std)).collect();
        let margins = objective.margins(next, &z);
        next += per_level;
        let mut sorted: Vec<f64> = margins.iter().map(|m| if m.is_nan() { f64::INFINITY } else { *m }).collect();
        sorted.sort_by(f64::total_cmp);
        let k = ((RHO * per_level as f64).ceil() as usize).clamp(1, sorted.len()) - 1;
        let gamma = sorted[k].max(0.0);
        if levels.is_empty() && gamma <= 0.0 {
            // Not rare: at least ρ of the first level's draws, drawn from
            // the nominal law, fail. Importance sampling cannot beat plain
            // Monte Carlo there (its weights only add variance), so the
            // whole budget is spent at the nominal law and pooled.
            return not_rare(objective, margins, budget, seed, confidence);
        }
        let elite: Vec<(&Vec<f64>, f64)> = z
            .iter()
            .zip(&margins)
            .filter(|(_, m)| **m <= gamma)
            .map(|(z, _)| (z, log_weight(z, &mean, &std)))
            .collect();
        if elite.is_empty() {
            break;
        }
        // Weights relative to the largest, for range.
        let top = elite.iter().map(|e| e.1).fold(f64::NEG_INFINITY, f64::max);
        let w: Vec<f64> = elite.iter().map(|e| ftsmc_core::math::exp(e.1 - top)).collect();
        let total: f64 = w.iter().sum();
        let new_mean: Vec<f64> =
            (0..d).map(|i| elite.iter().zip(&w).map(|(e, w)| w * e.0[i]).sum::<f64>() / total).collect();
        let new_std: Vec<f64> = (0..d)
            .map(|i| {
                let v = elite.iter().zip(&w).map(|(e, w)| w * (e.0[i] - new_mean[i]).powi(2)).sum::<f64>() / total;
                (SMOOTHING * v.sqrt() + (1.0 - SMOOTHING) * std[i]).max(SIGMA_FLOOR)
            })
            .collect();
        mean = new_mean;
        std = new_std;
        levels.push(Level { flights: per_level, gamma, mean: mean.clone(), std: std.clone() });
        if gamma <= 0.0 {
            break;
        }
    }
    let n = budget.saturating_sub(next).max(1);
    let mut rng = chacha_stream(seed, 2);
    let (nominal_mean, nominal_std) = (vec![0.0; d], vec![1.0; d]);
    // The defensive mixture: a share of the draws from the nominal law.
    let z: Vec<Vec<f64>> = (0..n)
        .map(|_| {
            let nominal = rng.random_range(0.0..1.0) < DEFENSIVE_SHARE;
            if nominal {
                draw(&mut rng, &nominal_mean, &nominal_std)
            } else {
                draw(&mut rng, &mean, &std)
            }
        })
        .collect();
    let margins = objective.margins(next, &z);
    let weights: Vec<f64> = z.iter().map(|z| mixture_weight(z, &mean, &std)).collect();
    let mut estimate = summarise(&margins, &weights, confidence);
    estimate.reliable = estimate.failures > 0 && estimate.ess >= MIN_ESS;
    if !estimate.reliable {
        estimate.plain_mc_equivalent = f64::NAN;
    }
    estimate.flights = next + n;
    estimate.levels = levels;
    estimate
}

/// The estimate when the first level shows failure is not rare: its
/// `first` margins (draws `0..`, nominal law) and the rest of the budget,
/// draws from `first.len()` on at the nominal law (stream 2), pooled; the
/// Wilson score interval, as [`plain`]. No level is recorded.
fn not_rare(objective: &dyn RareObjective, first: Vec<f64>, budget: u64, seed: u64, confidence: f64) -> Estimate {
    let d = objective.dim();
    let done = first.len() as u64;
    let rest = budget.saturating_sub(done);
    let mut rng = chacha_stream(seed, 2);
    let (mean, std) = (vec![0.0; d], vec![1.0; d]);
    let z: Vec<Vec<f64>> = (0..rest).map(|_| draw(&mut rng, &mean, &std)).collect();
    let mut margins = first;
    margins.extend(objective.margins(done, &z));
    let n = margins.len() as u64;
    let mut e = summarise(&margins, &vec![1.0; margins.len()], confidence);
    if let Ok(i) = crate::stats::rate::wilson(e.failures, n, confidence) {
        e.lo = i.lo;
        e.hi = i.hi;
    }
    e.flights = n;
    e
}

/// Plain Monte Carlo of `P(margin < 0)`: `n` flights at the nominal law
/// (`z ~ N(0, I)`, weights 1), the Wilson score interval.
pub fn plain(objective: &dyn RareObjective, n: u64, seed: u64, confidence: f64) -> Estimate {
    let d = objective.dim();
    let mut rng = chacha_stream(seed, 2);
    let (mean, std) = (vec![0.0; d], vec![1.0; d]);
    let z: Vec<Vec<f64>> = (0..n).map(|_| draw(&mut rng, &mean, &std)).collect();
    let margins = objective.margins(0, &z);
    let mut e = summarise(&margins, &vec![1.0; margins.len()], confidence);
    if let Ok(i) = crate::stats::rate::wilson(e.failures, n, confidence) {
        e.lo = i.lo;
        e.hi = i.hi;
    }
    e.flights = n;
    e
}

fn summarise(margins: &[f64], weights: &[f64], confidence: f64) -> Estimate {
    let n = margins.len().max(1) as f64;
    let terms: Vec<f64> = margins.iter().zip(weights).map(|(m, w)| if *m < 0.0 { *w } else { 0.0 }).collect();
    let p = terms.iter().sum::<f64>() / n;
    let var = terms.iter().map(|t| (t - p).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    let z = crate::stats::normal_quantile(0.5 + 0.5 * confidence);
    let half = z * (var / n).sqrt();
    let failing: Vec<f64> = terms.iter().copied().filter(|t| *t > 0.0).collect();
    let (sw, sw2) = failing.iter().fold((0.0, 0.0), |(a, b), w| (a + w, b + w * w));
    let (lo, hi) = if failing.is_empty() {
        let max_w = weights.iter().copied().fold(0.0, f64::max);
        (0.0, ((1.0 - ftsmc_core::math::powf(1.0 - confidence, 1.0 / n)) * max_w).min(1.0))
    } else {
        ((p - half).max(0.0), (p + half).min(1.0))
    };
    Estimate {
        p,
        lo,
        hi,
        confidence,
        flights: margins.len() as u64,
        final_flights: margins.len() as u64,
        failures: failing.len() as u64,
        ess: if sw2 > 0.0 { sw * sw / sw2 } else { 0.0 },
        plain_mc_equivalent: if var > 0.0 { p * (1.0 - p) / (var / n) } else { f64::NAN },
        one_sided: failing.is_empty(),
        // Weights 1 (plain Monte Carlo): the Wilson interval the callers
        // put in holds at any count. Importance sampling sets its own.
        reliable: true,
        levels: Vec::new(),
    }
}

/// The value of a parameter with bounds `[low, high]` and nominal law
/// `nominal` at the standard normal coordinate `z`: the nominal quantile of
/// `Φ(z)` (uniform: `low + Φ(z)(high − low)`; truncated normal: its inverse CDF).
pub fn nominal_value(z: f64, low: f64, high: f64, nominal: crate::scenario::falsify_section::Nominal) -> f64 {
    use crate::scenario::falsify_section::Nominal;
    let std = Normal::standard();
    let u = std.cdf(z);
    let x = match nominal {
        Nominal::Uniform => low + u * (high - low),
        Nominal::Normal { mean, std: s } => {
            let a = std.cdf((low - mean) / s);
            let b = std.cdf((high - mean) / s);
            mean + s * std.inverse_cdf(a + u * (b - a))
        }
    };
    x.clamp(low, high)
}
