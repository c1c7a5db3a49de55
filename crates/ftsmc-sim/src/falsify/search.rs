//! The worst case in a box: minimise the margin over `[0, 1]^d` with
//! CMA-ES (the tuner's ask/tell [`Cmaes`]) and IPOP restarts (Auger &
//! Hansen 2005, "A restart CMA evolution strategy with increasing
//! population size", CEC: each restart doubles the population and starts
//! from a uniform random point), and the same budget of uniform random
//! draws beside it.
//!
//! Box constraint: a candidate outside the box is flown at its projection
//! onto the box and told to CMA-ES with the cost `margin + ‖x − proj(x)‖²`
//! (a quadratic penalty that pulls the mean back inside). A restart begins
//! when σ falls below 1e-4 (the search has converged) or the best margin of
//! the run has not improved for `10 + ⌈30 d / λ⌉` generations (Hansen's
//! "TolHistFun"-like stagnation). The last generation is cut to the budget.
//!
//! Every random number comes from ChaCha streams of the search seed, drawn
//! on the calling thread, and the objective returns margins in order, so a
//! search gives the same history on any number of threads.

use rand::RngExt;

use super::Objective;
use crate::rng::chacha_stream;
use crate::tune::cmaes::Cmaes;

/// One flown point of a search.
#[derive(Clone, Debug, PartialEq)]
pub struct Evaluation {
    /// Flights so far, this one included (1-based).
    pub flight: u64,
    /// CMA-ES run it belongs to (0: the first; always 0 for random search).
    pub restart: u32,
    /// The point flown, in the unit box.
    pub point: Vec<f64>,
    /// Its margin ([`crate::margin`]).
    pub margin: f64,
}

/// The flights of one search, in the order flown.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct History {
    /// Every flight.
    pub evaluations: Vec<Evaluation>,
}

impl History {
    /// The flight with the lowest margin (the first of equals; NaN never).
    pub fn best(&self) -> Option<&Evaluation> {
        self.evaluations.iter().filter(|e| !e.margin.is_nan()).fold(None, |b: Option<&Evaluation>, e| match b {
            Some(b) if b.margin <= e.margin => Some(b),
            _ => Some(e),
        })
    }

    /// The first flight with a negative margin (a violation), if any.
    pub fn first_violation(&self) -> Option<&Evaluation> {
        self.evaluations.iter().find(|e| e.margin < 0.0)
    }

    /// Flights with a negative margin.
    pub fn violations(&self) -> usize {
        self.evaluations.iter().filter(|e| e.margin < 0.0).count()
    }

    fn push(&mut self, restart: u32, point: Vec<f64>, margin: f64) {
        let flight = self.evaluations.len() as u64 + 1;
        self.evaluations.push(Evaluation { flight, restart, point, margin });
    }
}

/// Initial CMA-ES step size in the unit box.
pub const SIGMA0: f64 = 0.3;

/// Minimise the margin of `objective` with CMA-ES and restarts, `budget`
/// flights, the search seed `seed`; the first run starts at `start` (the
/// nominal point; `None`: the centre of the box).
pub fn cmaes(objective: &dyn Objective, budget: u64, seed: u64, start: Option<Vec<f64>>) -> History {
    let d = objective.dim();
    let mut history = History::default();
    let mut starts = chacha_stream(seed, 1);
    let default_lambda = 4 + (3.0 * ftsmc_core::math::ln(d.max(1) as f64)).floor() as usize;
    let mut restart: u32 = 0;
    while (history.evaluations.len() as u64) < budget {
        let mean: Vec<f64> = match (&start, restart) {
            (Some(s), 0) => s.clone(),
            (None, 0) => vec![0.5; d],
            _ => (0..d).map(|_| starts.random_range(0.0..1.0)).collect(),
        };
        let lambda = default_lambda.max(2) << restart.min(6);
        let es_seed = chacha_stream(seed, 2 + u64::from(restart)).random::<u64>();
        let mut es = Cmaes::new(mean, SIGMA0, Some(lambda), es_seed);
        let patience = 10 + (30 * d).div_ceil(lambda);
        let (mut best, mut stall) = (f64::INFINITY, 0usize);
        loop {
            let left = budget - history.evaluations.len() as u64;
            if left == 0 {
                break;
            }
            let candidates = es.ask();
            let take = candidates.len().min(left as usize);
            let projected: Vec<Vec<f64>> =
                candidates[..take].iter().map(|c| c.iter().map(|v| v.clamp(0.0, 1.0)).collect()).collect();
            let margins = objective.margins(&projected);
            let mut costs = Vec::with_capacity(take);
            for ((c, p), m) in candidates.iter().zip(&projected).zip(&margins) {
                let penalty: f64 = c.iter().zip(p).map(|(a, b)| (a - b) * (a - b)).sum();
                costs.push(m + penalty);
                history.push(restart, p.clone(), *m);
            }
            if take < candidates.len() {
                break;
            }
            es.tell(&candidates, &costs);
            let generation_best = margins.iter().copied().filter(|m| !m.is_nan()).fold(f64::INFINITY, f64::min);
            if generation_best < best {
                best = generation_best;
                stall = 0;
            } else {
                stall += 1;
            }
            if es.sigma() < 1e-4 || stall >= patience {
                break;
            }
        }
        restart += 1;
    }
    history
}

/// Points drawn per call of the objective in [`random`] (the history does
/// not depend on it).
const RANDOM_BATCH: usize = 64;

/// `budget` uniform random points of the unit box (ChaCha stream 0 of
/// `seed`), flown in order.
pub fn random(objective: &dyn Objective, budget: u64, seed: u64) -> History {
    let d = objective.dim();
    let mut rng = chacha_stream(seed, 0);
    let mut history = History::default();
    while (history.evaluations.len() as u64) < budget {
        let n = (budget - history.evaluations.len() as u64).min(RANDOM_BATCH as u64) as usize;
        let points: Vec<Vec<f64>> = (0..n).map(|_| (0..d).map(|_| rng.random_range(0.0..1.0)).collect()).collect();
        let margins = objective.margins(&points);
        for (p, m) in points.into_iter().zip(margins) {
            history.push(0, p, m);
        }
    }
    history
}
