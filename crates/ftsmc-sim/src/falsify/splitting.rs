//! Adaptive multilevel splitting (AMS) of `P(margin < 0)`: failures driven
//! by the whole random input of a flight — turbulence, sensor noise, drag
//! and motor noise, the `[montecarlo]` draws — not only by the few
//! `[falsify]` parameters the cross-entropy proposal of [`super::rare`]
//! moves.
//!
//! # Why splitting, and not subset simulation
//!
//! A flight's randomness is many ChaCha streams read through
//! [`crate::noise::NoiseStream`] (four sensor sources, three turbulence
//! axes, six drag coefficients, the motors), each keyed by the scenario's
//! seed, drawn period by period — hundreds of thousands of standard-normal
//! draws per flight, not a vector anything could hold or move. Subset
//! simulation with preconditioned Crank–Nicolson MCMC (Au & Beck 2001,
//! "Estimation of small failure probabilities in high dimensions by subset
//! simulation", Probab. Eng. Mech. 16) would need every source to read its
//! normals from a supplied vector (`z' = ρ z + √(1 − ρ²) ξ` over all of
//! them, stored or regenerated per chain state). Splitting needs much less:
//! a flight is deterministic given its seed, so a copy of a flight's whole
//! state at control step `k` (truth, controller, sensors' latency lines,
//! wind filters, motors, observers) is obtained by flying it again to `k`,
//! and fresh noise from `k` on is one call,
//! [`crate::run::Flight::reseed_noise`], that rekeys every source's stream.
//! No state is serialised, no source changes how it draws, and the bits
//! stay a function of the keys alone. The price is the replay: every
//! branched flight costs one whole flight of CPU, which [`Estimate::flights`]
//! counts.
//!
//! # The algorithm (Cérou & Guyader 2007; Bréhier, Lelièvre & Rousset 2016)
//!
//! The score of a flight is its **running margin** `m(k)` ([`crate::margin`]:
//! the envelope margin over the boundaries flown so far, never increasing;
//! `≤ −1` once crashed or diverged); it fails when its final margin `m < 0`.
//! One repetition with `N` particles and `K` killed per iteration
//! (Cérou & Guyader 2007, "Adaptive multilevel splitting for rare event
//! analysis", Stoch. Anal. Appl. 25; the generalised, unbiased variant of
//! Bréhier, Lelièvre & Rousset 2016, "Analysis of adaptive multilevel
//! splitting algorithms in an idealized setting" and Bréhier, Gazeau,
//! Goudenège, Lelièvre & Rousset 2016, "Unbiasedness of some generalized
//! adaptive multilevel splitting algorithms", Ann. Appl. Probab. 26):
//!
//! ```text
//! fly N independent flights (their whole random input fresh)
//! loop q = 1, 2, …:
//!     ℓ_q = the K-th largest final margin
//!     if ℓ_q ≤ 0: stop                               (the failure level is reached)
//!     kill every particle with margin ≥ ℓ_q          (K_q ≥ K of them: ties are killed too)
//!     if K_q = N: p̂ = 0, stop                        (extinction)
//!     for each killed particle: pick a survivor uniformly, copy it at the
//!         first boundary where its running margin < ℓ_q, continue with fresh noise
//! p̂ = Π_q (1 − K_q/N) · #{margin < 0}/N
//! ```
//!
//! `p̂` is an unbiased estimator of `p` for any `N ≥ 2`, `K` and any score
//! (Bréhier et al. 2016, Theorem 4.1): killing every tie and branching at
//! the *first* step strictly below the level are what the theorem needs,
//! and both are done here. The score's quality (how well the running
//! margin predicts failure) only affects the variance.
//!
//! # The interval: independent repetitions
//!
//! `R` independent repetitions give unbiased `p̂_1 … p̂_R`; the estimate is
//! their mean `p̄` and the interval Student's t interval
//!
//! ```text
//! p̄ ± t_{R−1, 1−α/2} s/√R,   s² = (1/(R−1)) Σ (p̂_r − p̄)²     (clipped to [0, 1])
//! ```
//!
//! which holds when `p̄` is close to normal (central limit theorem over
//! the repetitions). It uses no asymptotic formula for one run's variance
//! (the idealised `Var p̂ ≈ p² (−ln p)/N` of Bréhier et al. 2016 holds only
//! for the optimal score, the committor, and underestimates otherwise): the
//! spread of the repetitions measures the variance the score actually gives.
//! Splitting `R·N` particles into repetitions costs little: one run's
//! variance is ∝ 1/N, so the mean of `R` runs of `N` has about the variance
//! of one run of `R·N`.
//!
//! # Reliability
//!
//! The estimate is **reliable** when at least [`MIN_REPETITIONS`]
//! repetitions ran, every one reached the failure level within the flight
//! budget, and at most a fifth ended in extinction (`p̂_r = 0`): otherwise
//! the spread of the repetitions is a poor estimate of the variance (a few
//! nonzero values among zeros make a skewed mean whose t interval
//! undercovers). An unreliable estimate gives no plain-Monte-Carlo
//! equivalent; [`Estimate::suggested`] says what to try.
//!
//! # Determinism
//!
//! Every random input is keyed: repetition `r` reads one ChaCha stream of
//! the seed ([`repetition_stream`]) on the calling thread, in order — the
//! keys of its `N` first flights, then per killed particle the survivor it
//! copies and the key of its fresh noise. The flights of an iteration are
//! flown in parallel, each a function of its key and its parent only, and
//! collected in order, so the bits do not depend on the number of threads
//! or how rayon schedules them.

use rand::{Rng, RngExt};
use rayon::prelude::*;
use serde::Serialize;

use crate::rng::chacha_stream;

/// Fewest repetitions for a reliable estimate: Student's t interval over
/// fewer has too few degrees of freedom to estimate a skewed spread.
pub const MIN_REPETITIONS: usize = 5;
/// Largest share of extinct repetitions (`p̂_r = 0`) of a reliable estimate.
pub const MAX_EXTINCT_SHARE: f64 = 0.2;
/// First ChaCha stream of the repetitions (stream `FIRST_STREAM + r` of the
/// seed for repetition `r`), far above the streams of [`super::rare`].
pub const FIRST_STREAM: u64 = 1 << 40;

/// The ChaCha stream of repetition `r` of `seed` (module documentation).
pub fn repetition_stream(seed: u64, r: usize) -> rand_chacha::ChaCha8Rng {
    chacha_stream(seed, FIRST_STREAM + r as u64)
}

/// A random process with a running margin that splitting can start and branch.
pub trait Splitting: Sync {
    /// One particle: whatever is needed to fly it again (its keys and
    /// branch points) and its running margin's record.
    type Path: Clone + Send + Sync;
    /// A fresh particle whose whole random input is keyed by `key`.
    fn start(&self, key: u64) -> Self::Path;
    /// The particle's final margin (`< 0`: failed; `NaN` counts as `+∞`).
    fn margin(&self, path: &Self::Path) -> f64;
    /// A copy of `parent` at the first step where its running margin is
    /// below `level` (`parent`'s final margin is), continued from there with
    /// fresh noise keyed by `key`.
    fn branch(&self, parent: &Self::Path, level: f64, key: u64) -> Self::Path;
}

/// Settings of [`estimate`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Settings {
    /// Particles `N` of a repetition (≥ 2).
    pub particles: usize,
    /// Particles killed per iteration `K` (at least; ties are killed too), `1 ≤ K < N`.
    pub kill: usize,
    /// Independent repetitions `R` (≥ 1; [`MIN_REPETITIONS`] for a reliable estimate).
    pub repetitions: usize,
    /// Most flights of all repetitions together (each repetition stops at
    /// its share, `budget / R`, and is then unreliable).
    pub budget: u64,
    /// Confidence level of the interval, in (0, 1).
    pub confidence: f64,
}

impl Settings {
    /// `particles` particles and `repetitions` repetitions, a tenth of the
    /// particles killed per iteration (at least 1), within `budget` flights.
    pub fn new(particles: usize, repetitions: usize, budget: u64, confidence: f64) -> Self {
        Self { particles, kill: (particles / 10).max(1), repetitions, budget, confidence }
    }

    /// Why these settings cannot run, if they cannot.
    pub fn check(&self) -> Result<(), String> {
        if self.particles < 2 {
            return Err(format!("particles = {}: expected at least 2", self.particles));
        }
        if self.kill < 1 || self.kill >= self.particles {
            return Err(format!(
                "kill = {}: expected 1 to {} (fewer than the particles)",
                self.kill,
                self.particles - 1
            ));
        }
        if self.repetitions < 1 {
            return Err(format!("repetitions = {}: expected at least 1", self.repetitions));
        }
        if !(self.confidence > 0.0 && self.confidence < 1.0) {
            return Err(format!("confidence = {}: expected a level strictly between 0 and 1", self.confidence));
        }
        let first = (self.particles as u64).saturating_mul(self.repetitions as u64);
        if self.budget < first {
            return Err(format!(
                "budget = {} flights: the {} repetitions of {} particles need at least {first} to start",
                self.budget, self.repetitions, self.particles
            ));
        }
        Ok(())
    }
}

/// One repetition's outcome.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Repetition {
    /// Its unbiased estimate `p̂_r`.
    pub p: f64,
    /// Iterations (levels) before it stopped.
    pub iterations: u64,
    /// Flights it flew (its `N` first and one per branch).
    pub flights: u64,
    /// It reached the failure level (`false`: stopped by the budget; its
    /// `p̂_r` is then the product so far times the failing share, biased low).
    pub finished: bool,
    /// Every particle was killed at some level: `p̂_r = 0`.
    pub extinct: bool,
    /// The last level `ℓ` it split at (`+∞` before any).
    pub last_level: f64,
}

/// A splitting estimate of `P(margin < 0)` over independent repetitions.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Estimate {
    /// `p̄`, the mean of the repetitions' estimates.
    pub p: f64,
    /// Lower bound of Student's t interval (module documentation).
    pub lo: f64,
    /// Upper bound.
    pub hi: f64,
    /// Confidence level of the interval.
    pub confidence: f64,
    /// Standard error `s/√R` of `p̄` (`NaN` for one repetition).
    pub std_error: f64,
    /// Every flight flown, branches included (a branch replays its parent
    /// to the branch point: each costs one flight).
    pub flights: u64,
    /// The settings it ran with.
    pub settings: Settings,
    /// Mean iterations (levels) per repetition.
    pub mean_levels: f64,
    /// The repetitions, in order.
    pub repetitions: Vec<Repetition>,
    /// The interval can be trusted (module documentation, *Reliability*).
    pub reliable: bool,
}

impl Estimate {
    /// Plain Monte Carlo flights with the same variance, `p̄(1 − p̄)/s_p̄²`
    /// (`NaN` when unreliable or `p̄ = 0`).
    pub fn plain_mc_equivalent(&self) -> f64 {
        if self.reliable && self.p > 0.0 && self.std_error > 0.0 {
            self.p * (1.0 - self.p) / (self.std_error * self.std_error)
        } else {
            f64::NAN
        }
    }

    /// Flights this estimator needs for a coefficient of variation `cov`
    /// (standard error over `p`): `flights · (c.o.v. / cov)²` (the
    /// variance falls as 1/flights); `NaN` when unreliable or `p̄ = 0`.
    pub fn flights_for_cov(&self, cov: f64) -> f64 {
        if self.reliable && self.p > 0.0 {
            let c = self.std_error / self.p;
            self.flights as f64 * (c / cov) * (c / cov)
        } else {
            f64::NAN
        }
    }

    /// Settings to try for a reliable estimate (`None` when reliable):
    /// twice the particles (and at least [`MIN_REPETITIONS`] repetitions)
    /// and a budget of four times the flights spent (at least the new settings' start).
    pub fn suggested(&self) -> Option<Settings> {
        if self.reliable {
            return None;
        }
        let s = self.settings;
        let particles = s.particles * 2;
        let repetitions = s.repetitions.max(MIN_REPETITIONS);
        let start = (particles * repetitions) as u64;
        Some(Settings {
            particles,
            kill: (particles / 10).max(1),
            repetitions,
            budget: (self.flights.max(s.budget) * 4).max(start * 4),
            confidence: s.confidence,
        })
    }
}

/// A margin as the levels compare it: `NaN` is `+∞` (never failed).
fn key_of(m: f64) -> f64 {
    if m.is_nan() {
        f64::INFINITY
    } else {
        m
    }
}

/// One repetition of AMS (module documentation) on `rng`'s keys, within `budget` flights.
fn repetition<P: Splitting + ?Sized>(
    problem: &P,
    settings: &Settings,
    mut rng: rand_chacha::ChaCha8Rng,
    budget: u64,
) -> Repetition {
    let n = settings.particles;
    let keys: Vec<u64> = (0..n).map(|_| rng.next_u64()).collect();
    let mut particles: Vec<P::Path> = keys.par_iter().map(|&k| problem.start(k)).collect();
    let mut margins: Vec<f64> = particles.iter().map(|p| key_of(problem.margin(p))).collect();
    let mut flights = n as u64;
    let mut log_factor = 0.0;
    let mut iterations = 0;
    let mut last_level = f64::INFINITY;
    let (finished, extinct) = loop {
        let mut sorted = margins.clone();
        sorted.sort_by(|a, b| b.total_cmp(a));
        let level = sorted[settings.kill - 1];
        if level <= 0.0 {
            break (true, false);
        }
        let killed: Vec<usize> = (0..n).filter(|&i| margins[i] >= level).collect();
        if killed.len() == n {
            break (true, true);
        }
        if flights + killed.len() as u64 > budget {
            break (false, false);
        }
        let survivors: Vec<usize> = (0..n).filter(|&i| margins[i] < level).collect();
        let plan: Vec<(usize, usize, u64)> = killed
            .iter()
            .map(|&slot| {
                let parent = survivors[rng.random_range(0..survivors.len())];
                (slot, parent, rng.next_u64())
            })
            .collect();
        let children: Vec<P::Path> =
            plan.par_iter().map(|&(_, parent, key)| problem.branch(&particles[parent], level, key)).collect();
        for ((slot, _, _), child) in plan.iter().zip(children) {
            margins[*slot] = key_of(problem.margin(&child));
            particles[*slot] = child;
        }
        flights += killed.len() as u64;
        log_factor += ftsmc_core::math::ln(1.0 - killed.len() as f64 / n as f64);
        iterations += 1;
        last_level = level;
    };
    let failing = margins.iter().filter(|m| **m < 0.0).count();
    let p = if extinct { 0.0 } else { ftsmc_core::math::exp(log_factor) * failing as f64 / n as f64 };
    Repetition { p, iterations, flights, finished, extinct, last_level }
}

/// AMS estimate of `P(margin < 0)` of `problem`: `settings.repetitions`
/// independent repetitions keyed by `seed` (module documentation), run in
/// parallel on the current rayon pool; the bits do not depend on it.
/// Settings that [`Settings::check`] refuses give that error.
pub fn estimate<P: Splitting + ?Sized>(problem: &P, settings: Settings, seed: u64) -> Result<Estimate, String> {
    settings.check()?;
    let share = settings.budget / settings.repetitions as u64;
    let reps: Vec<Repetition> = (0..settings.repetitions)
        .into_par_iter()
        .map(|r| repetition(problem, &settings, repetition_stream(seed, r), share))
        .collect();
    let rn = reps.len() as f64;
    let p = reps.iter().map(|r| r.p).sum::<f64>() / rn;
    let std_error = if reps.len() > 1 {
        let var = reps.iter().map(|r| (r.p - p) * (r.p - p)).sum::<f64>() / (rn - 1.0);
        ftsmc_core::math::sqrt(var / rn)
    } else {
        f64::NAN
    };
    let values: Vec<f64> = reps.iter().map(|r| r.p).collect();
    let t = crate::stats::mean::mean_interval(&values, settings.confidence).map_err(|e| e.to_string())?;
    let (lo, hi) = t.map_or((0.0, 1.0), |i| (i.lo, i.hi));
    let extinct = reps.iter().filter(|r| r.extinct).count() as f64;
    let reliable = reps.len() >= MIN_REPETITIONS
        && reps.iter().all(|r| r.finished)
        && extinct <= MAX_EXTINCT_SHARE * rn
        && p > 0.0;
    Ok(Estimate {
        p,
        lo: lo.clamp(0.0, 1.0),
        hi: hi.clamp(0.0, 1.0),
        confidence: settings.confidence,
        std_error,
        flights: reps.iter().map(|r| r.flights).sum(),
        settings,
        mean_levels: reps.iter().map(|r| r.iterations as f64).sum::<f64>() / rn,
        repetitions: reps,
        reliable,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A particle that is a single draw `x ~ N(0, 1)` with margin `b − x`
    /// held from the start: branching copies it (the first step below the
    /// level is step 0) and so never moves it. AMS then extinguishes or
    /// stops at once, which the estimate must say.
    struct Frozen(f64);

    impl Splitting for Frozen {
        type Path = f64;
        fn start(&self, key: u64) -> f64 {
            let mut rng = chacha_stream(key, 0);
            self.0 - crate::gauss::standard_normal(&mut rng)
        }
        fn margin(&self, path: &f64) -> f64 {
            *path
        }
        fn branch(&self, parent: &f64, _level: f64, _key: u64) -> f64 {
            *parent
        }
    }

    #[test]
    fn settings_are_checked() {
        assert!(Settings::new(1, 5, 100, 0.95).check().is_err());
        assert!(Settings::new(10, 0, 100, 0.95).check().is_err());
        assert!(Settings::new(10, 5, 49, 0.95).check().unwrap_err().contains("at least 50"));
        assert!(Settings::new(10, 5, 50, 1.0).check().is_err());
        assert!(Settings::new(10, 5, 50, 0.95).check().is_ok());
        assert!(estimate(&Frozen(3.0), Settings::new(10, 5, 49, 0.95), 1).is_err());
    }

    /// Copies that never move: the killed particles come back with the
    /// survivors' margins, so the levels still descend (the copies of
    /// survivors are survivors), but the estimate is that of N draws; with
    /// b = 8 none fails and every repetition ends extinct or at zero.
    #[test]
    fn no_failure_is_an_unreliable_zero() {
        let e = estimate(&Frozen(8.0), Settings::new(20, 6, 100_000, 0.95), 3).unwrap();
        assert_eq!(e.p, 0.0);
        assert!(!e.reliable);
        assert!(e.suggested().is_some());
        assert!(e.plain_mc_equivalent().is_nan());
    }
}
