//! Stopping a campaign as soon as its pairs are decided, without raising
//! the error rate: group-sequential alpha spending (Lan & DeMets 1983)
//! with the O'Brien–Fleming-type spending function
//! `α(t) = 2 − 2Φ(z_{1−α/2}/√t)` over the information fraction
//! `t = runs flown / most runs` (Jennison & Turnbull 2000, §7.2).
//!
//! Look `j` may spend `α(t_j) − α(t_{j−1})`. Each look tests the whole
//! family of pairs with Holm's correction at that share, and a pair is
//! decided at the first look that rejects it. The chance of any false
//! verdict over the whole campaign is at most the sum of the shares,
//! `α(1) = α` (a union bound over looks: valid for exact tests and any
//! dependence between looks, at some cost in power against the
//! boundaries computed from the joint normal distribution of the looks).
//! O'Brien–Fleming-type spending keeps almost all of `α` for the last
//! look, so a campaign that runs to its maximum loses little power.

use super::{normal_quantile, normal_sf};

/// `α(t)`: the error rate spent by information fraction `t ∈ [0, 1]`.
pub fn obrien_fleming_spent(t: f64, alpha: f64) -> f64 {
    if t <= 0.0 {
        return 0.0;
    }
    if t >= 1.0 {
        // Exactly α at the end (statrs's normal tail is good to ~1e-11).
        return alpha;
    }
    let z = normal_quantile(1.0 - alpha / 2.0);
    (2.0 * normal_sf(z / t.sqrt())).min(alpha)
}

/// The share of `alpha` a look at `runs` runs may spend when the last look
/// was at `previous` runs and the campaign stops at `max_runs` at most.
pub fn look_alpha(previous: u64, runs: u64, max_runs: u64, alpha: f64) -> f64 {
    let t = |r: u64| if max_runs == 0 { 1.0 } else { r as f64 / max_runs as f64 };
    (obrien_fleming_spent(t(runs), alpha) - obrien_fleming_spent(t(previous), alpha)).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spending_reaches_alpha_at_the_end_and_little_early() {
        assert!((obrien_fleming_spent(1.0, 0.05) - 0.05).abs() < 1e-12);
        assert!(obrien_fleming_spent(0.25, 0.05) < 1e-4);
        let total: f64 = (1..=10).map(|j| look_alpha((j - 1) * 20, j * 20, 200, 0.05)).sum();
        assert!((total - 0.05).abs() < 1e-12);
    }
}

/// A campaign of paired tests looked at after each batch of runs: which
/// tests are decided, at which look, with what verdict.
#[derive(Clone, Debug)]
pub struct Campaign {
    /// Most runs the campaign may fly (the information fraction's 1).
    pub max_runs: u64,
    /// Family-wise error rate over the whole campaign (`1 − confidence`).
    pub alpha: f64,
    previous: u64,
    decided: Vec<Option<(super::paired::Verdict, u64)>>,
}

impl Campaign {
    /// A campaign of `tests` paired tests, at most `max_runs` runs, error
    /// rate `alpha`.
    pub fn new(tests: usize, max_runs: u64, alpha: f64) -> Self {
        Self { max_runs, alpha, previous: 0, decided: vec![None; tests] }
    }

    /// Look at the tests over the first `runs` runs (in the order given to
    /// [`Campaign::new`]; `runs` grows from look to look). The whole family
    /// is tested with Holm at this look's share of `alpha`; a test
    /// rejected for the first time is decided at this look. Returns the
    /// share spent.
    pub fn look(&mut self, runs: u64, tests: &[super::paired::PairTest]) -> f64 {
        use super::paired::{verdicts_at, Verdict};
        let share = look_alpha(self.previous, runs.min(self.max_runs), self.max_runs, self.alpha);
        self.previous = runs.min(self.max_runs);
        if let Ok(v) = verdicts_at(tests, share) {
            for (slot, (_, verdict)) in self.decided.iter_mut().zip(v) {
                if slot.is_none() && verdict != Verdict::NoDifference {
                    *slot = Some((verdict, runs));
                }
            }
        }
        share
    }

    /// Verdict of each test so far and the runs at which it was decided.
    pub fn decided(&self) -> &[Option<(super::paired::Verdict, u64)>] {
        &self.decided
    }

    /// Every maximum reached: no look is left.
    pub fn exhausted(&self) -> bool {
        self.previous >= self.max_runs
    }
}
