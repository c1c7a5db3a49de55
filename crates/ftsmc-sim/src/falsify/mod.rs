//! Worst cases and rare failures of a controller on a scenario
//! (docs/falsification.md).
//!
//! - [`search`]: minimise the robustness margin ([`crate::margin`]) over
//!   the `[falsify]` box with CMA-ES and restarts, and the same budget of
//!   uniform random draws beside it;
//! - [`rare`]: the probability that the margin is negative under the
//!   scenario's own random draws, by cross-entropy importance sampling
//!   of the `[falsify]` parameters;
//! - [`splitting`]: the same probability by adaptive multilevel splitting
//!   on the flight's running margin, acting on its whole random input
//!   (turbulence, sensor, drag and motor noise, the `[montecarlo]` draws).
//!
//! Both run on an [`Objective`]: points in, margins out, many at a time.
//! [`Problem`] is the objective of a real scenario and controller; tests
//! plug in synthetic ones.

pub mod rare;
pub mod search;
pub mod splitting;

use std::sync::Arc;

use rayon::prelude::*;

use crate::margin::Margin;
use crate::run::{RunOptions, RunOutput};
use crate::scenario::falsify_section::{apply, Nominal, Param};
use crate::scenario::Scenario;

/// Lanes a batch of falsification flights is flown on (the bits do not depend on it).
pub const LANES: usize = 4;

/// Why a search cannot start.
#[derive(Debug, thiserror::Error)]
pub enum FalsifyError {
    /// The scenario has no `[falsify]` section.
    #[error("scenario `{0}` has no [falsify] section: declare the searched parameters and their bounds (docs/falsification.md)")]
    NoSearchSpace(String),
    /// The scenario's envelope limits nothing, so no flight has a margin.
    #[error("scenario `{0}`: the margin needs an [envelope] with max_position_error or max_tilt")]
    NoEnvelope(String),
    /// Unknown controller.
    #[error("{0}")]
    Controller(String),
    /// A budget of 0 or more than the limit.
    #[error("budget = {0}: expected 1 to {1} flights")]
    Budget(u64, u64),
}

/// Something whose margin is minimised or whose failure probability is
/// estimated: evaluates points of a `dim`-dimensional space.
pub trait Objective: Sync {
    /// Number of coordinates.
    fn dim(&self) -> usize;
    /// The margins of `points` in the unit box `[0, 1]^dim` (`search`),
    /// in order. Must not depend on how the calls are split or on threads.
    fn margins(&self, points: &[Vec<f64>]) -> Vec<f64>;
}

/// A scenario, its `[falsify]` space and a controller: flies points of the space.
#[derive(Clone, Debug)]
pub struct Problem {
    /// The scenario as given (its seed: the turbulence and noise of every search flight).
    pub base: Scenario,
    /// The controller's registry name.
    pub controller: String,
    /// The searched coordinates, in the order of every point.
    pub params: Vec<Param>,
}

impl Problem {
    /// The problem of `base` flown by `controller`; refused without a
    /// `[falsify]` section, an envelope with a limit, or a known controller.
    pub fn new(base: &Scenario, controller: &str) -> Result<Self, FalsifyError> {
        crate::registry::check_name(controller).map_err(FalsifyError::Controller)?;
        let section = base.falsify.as_ref().ok_or_else(|| FalsifyError::NoSearchSpace(base.name.clone()))?;
        let env = base.envelope.unwrap_or_default();
        if env.max_position_error.is_none() && env.max_tilt.is_none() {
            return Err(FalsifyError::NoEnvelope(base.name.clone()));
        }
        Ok(Self { base: base.clone(), controller: controller.to_string(), params: section.params() })
    }

    /// The values of the point `u` of the unit box: `low + u (high − low)`
    /// per coordinate (`u` clamped to `[0, 1]`).
    pub fn values(&self, u: &[f64]) -> Vec<f64> {
        self.params
            .iter()
            .zip(u)
            .map(|(p, &u)| {
                let u = u.clamp(0.0, 1.0);
                p.bounds.low + u * (p.bounds.high - p.bounds.low)
            })
            .collect()
    }

    /// The nominal values: each parameter's nominal mean (the middle of
    /// its bounds when uniform), as a point of the unit box.
    pub fn nominal_point(&self) -> Vec<f64> {
        self.params
            .iter()
            .map(|p| match p.bounds.nominal {
                Nominal::Uniform => 0.5,
                Nominal::Normal { mean, .. } => {
                    ((mean - p.bounds.low) / (p.bounds.high - p.bounds.low)).clamp(0.0, 1.0)
                }
            })
            .collect()
    }

    /// The scenario of the values `x` (one per parameter), flown by this
    /// problem's controller only: what a replay file holds.
    pub fn scenario(&self, x: &[f64]) -> Scenario {
        let mut s = apply(&self.base, &self.params, x);
        s.controllers = vec![self.controller.clone()];
        s
    }

    /// Fly `scenarios` ([`LANES`] at a time, batches in parallel on the
    /// current rayon pool), in order.
    pub fn fly(&self, scenarios: &[Scenario]) -> Vec<RunOutput> {
        let options = RunOptions { record: false, ..Default::default() };
        scenarios
            .par_chunks(LANES)
            .flat_map_iter(|chunk| {
                let refs: Vec<&Scenario> = chunk.iter().collect();
                crate::batch::montecarlo::fly(&self.controller, &refs, LANES, options)
            })
            .collect()
    }
}

/// A flight's margin as the search reads it: `NaN` (never the minimum)
/// if it has none, which [`Problem::new`] rules out.
pub fn margin_of(out: &RunOutput) -> f64 {
    out.margin.map_or(f64::NAN, |m: Margin| m.value)
}

impl Objective for Problem {
    fn dim(&self) -> usize {
        self.params.len()
    }

    fn margins(&self, points: &[Vec<f64>]) -> Vec<f64> {
        let scenarios: Vec<Scenario> = points.iter().map(|u| self.scenario(&self.values(u))).collect();
        self.fly(&scenarios).iter().map(margin_of).collect()
    }
}

/// A [`Problem`] under the scenario's own random draws, for
/// [`rare::cross_entropy`]: draw `i` is run `i` of `ftsmc montecarlo` with
/// master seed `master` (its `[montecarlo]` draws and its own seed: new
/// turbulence and noise), with the `[falsify]` parameters at the nominal
/// quantiles of the standard normal coordinates `z`.
#[derive(Clone, Debug)]
pub struct RareProblem {
    /// The scenario, controller and searched parameters.
    pub problem: Problem,
    /// Master seed of the draws.
    pub master: u64,
}

impl RareProblem {
    /// The values of the coordinates `z` ([`rare::nominal_value`] per parameter).
    pub fn values(&self, z: &[f64]) -> Vec<f64> {
        self.problem
            .params
            .iter()
            .zip(z)
            .map(|(p, &z)| rare::nominal_value(z, p.bounds.low, p.bounds.high, p.bounds.nominal))
            .collect()
    }

    /// The scenario of draw `index` at `z`.
    pub fn scenario(&self, index: u64, z: &[f64]) -> Scenario {
        let base = &self.problem.base;
        let drawn = match &base.montecarlo {
            Some(spec) => spec.sample(base, self.master, index).0,
            None => {
                let mut s = base.clone();
                s.seed = crate::scenario::distributions::run_seed(self.master, index);
                s
            }
        };
        let mut s = apply(&drawn, &self.problem.params, &self.values(z));
        s.controllers = vec![self.problem.controller.clone()];
        s
    }
}

/// A [`Problem`] under its whole random input, for [`splitting::estimate`]:
/// particle `key` is draw 0 of `ftsmc montecarlo` with master seed `key`
/// (its `[montecarlo]` draws and its own seed: turbulence, sensor, drag and
/// motor noise) with the `[falsify]` parameters at the nominal quantiles
/// ([`rare::nominal_value`]) of standard normal coordinates drawn from
/// stream [`SPLITTING_Z_STREAM`] of `key` — the same law as
/// [`RareProblem`]'s draws at `z ~ N(0, I)`, so both estimate the same
/// `P(margin < 0)`. A branch flies its parent again to the branch
/// boundary and rekeys every noise source there ([`crate::run::Flight::reseed_noise`]).
#[derive(Clone, Debug)]
pub struct FlightSplitting {
    /// The scenario, controller and searched parameters.
    pub problem: Problem,
}

/// True when flights of `scenario` draw noise period by period — sensor
/// noise, Dryden turbulence, drag noise (paper plant) or motor noise —
/// which the cross-entropy proposal of [`rare`] never moves and
/// [`splitting`] does: `ftsmc failure-probability` then defaults to splitting.
pub fn noise_driven(scenario: &Scenario) -> bool {
    scenario.sensors.is_some_and(|s| !s.controller_sees_truth())
        || scenario.wind.as_ref().is_some_and(|w| w.turbulence.is_some())
        || (scenario.drag_noise.is_some() && scenario.vehicle.model == crate::vehicle::VehicleModel::Paper)
        || crate::run::actuators(scenario).noise.is_some()
}

/// ChaCha stream (of a particle's key) of its `[falsify]` coordinates.
pub const SPLITTING_Z_STREAM: u64 = 7;

/// One particle of [`FlightSplitting`]: its scenario (the draw it started
/// from), where its noise was rekeyed, and its running margin's record.
#[derive(Clone, Debug)]
pub struct FlightPath {
    /// The drawn scenario (its seed keys the noise up to the first reseed).
    pub scenario: Arc<Scenario>,
    /// `(k, seed)`: from period boundary `k` on, the noise is keyed by `seed`; increasing `k`.
    pub reseeds: Vec<(u64, u64)>,
    /// `(k, m)`: the boundaries `k` where the running margin fell, to `m` (1).
    pub record: Vec<(u64, f64)>,
    /// The flight's final margin ([`margin_of`]; `NaN`: none).
    pub margin: f64,
}

impl FlightSplitting {
    /// Fly `scenario` with the noise rekeyed at `reseeds`, recording the running margin.
    pub fn fly(&self, scenario: Arc<Scenario>, reseeds: Vec<(u64, u64)>) -> FlightPath {
        let controller = crate::registry::build(&self.problem.controller, &scenario).expect("checked by Problem::new");
        let options = RunOptions { record: false, ..Default::default() };
        let mut flight = crate::run::Flight::new(scenario.clone(), controller, options);
        let mut record: Vec<(u64, f64)> = Vec::new();
        let mut last = f64::INFINITY;
        let mut next = 0;
        loop {
            let k = flight.steps_flown();
            let m = flight.running_margin().unwrap_or(f64::INFINITY);
            if m < last {
                record.push((k, m));
                last = m;
            }
            while next < reseeds.len() && reseeds[next].0 <= k {
                flight.reseed_noise(reseeds[next].1);
                next += 1;
            }
            if flight.step() == crate::run::StepOutcome::Done {
                break;
            }
        }
        let k = flight.steps_flown();
        let out = flight.finish();
        let margin = margin_of(&out);
        if margin < last {
            record.push((k, margin));
        }
        FlightPath { scenario, reseeds, record, margin }
    }
}

impl splitting::Splitting for FlightSplitting {
    type Path = FlightPath;

    fn start(&self, key: u64) -> FlightPath {
        let mut rng = crate::rng::chacha_stream(key, SPLITTING_Z_STREAM);
        let z: Vec<f64> = (0..self.problem.params.len()).map(|_| crate::gauss::standard_normal(&mut rng)).collect();
        let draws = RareProblem { problem: self.problem.clone(), master: key };
        self.fly(Arc::new(draws.scenario(0, &z)), Vec::new())
    }

    fn margin(&self, path: &FlightPath) -> f64 {
        path.margin
    }

    fn branch(&self, parent: &FlightPath, level: f64, key: u64) -> FlightPath {
        // The first boundary below the level; the parent's final margin is, so one exists.
        let k = parent.record.iter().find(|(_, m)| *m < level).map_or(u64::MAX, |r| r.0);
        let mut reseeds: Vec<(u64, u64)> = parent.reseeds.iter().copied().filter(|r| r.0 < k).collect();
        reseeds.push((k, key));
        self.fly(parent.scenario.clone(), reseeds)
    }
}

impl rare::RareObjective for RareProblem {
    fn dim(&self) -> usize {
        self.problem.params.len()
    }

    fn margins(&self, first: u64, z: &[Vec<f64>]) -> Vec<f64> {
        let scenarios: Vec<Scenario> = z.iter().enumerate().map(|(k, z)| self.scenario(first + k as u64, z)).collect();
        self.problem.fly(&scenarios).iter().map(margin_of).collect()
    }
}
