//! Monte Carlo robustness: a scenario's `[montecarlo]` section declares
//! distributions for plant parameters, payload, disturbances and initial
//! state; each run draws its own values from generators derived from the
//! master seed and the run index only (never from thread state), so results
//! are identical whatever the thread count.

use rayon::prelude::*;
use serde::Serialize;

use crate::metrics::Metrics;
use crate::run::{ExitStatus, RunOptions, RunOutput};
pub use crate::scenario::distributions::{run_seed, Dist, MonteCarloSpec, SAMPLED_COLUMNS};
use crate::scenario::Scenario;

/// One row of a batch.
#[derive(Clone, Debug)]
pub struct McRun {
    /// Run index in the batch.
    pub index: u64,
    /// Seed of this run (drag noise and sampling).
    pub seed: u64,
    /// Sampled values ([`SAMPLED_COLUMNS`]).
    pub sampled: [f64; 12],
    /// Controller name.
    pub controller: String,
    /// Exit status.
    pub exit: ExitStatus,
    /// Metrics.
    pub metrics: Metrics,
    /// Completed and inside the scenario's `[envelope]` ([`RunOutput::success`](crate::RunOutput::success)).
    pub success: bool,
    /// Tilt, saturation and rotor statistics of the flight (observed, not recorded).
    pub stats: crate::run::FlightStats,
    /// Robustness margin to the envelope ([`crate::margin`]).
    pub margin: Option<crate::margin::Margin>,
}

/// How a batch is flown ([`run_batch`]): which runs, from which master
/// seed, how many flights side by side, with what progress report and
/// cancellation. `BatchOptions::new(runs, master_seed)` flies runs
/// `0..runs` on [`DEFAULT_LANES`] lanes; set the other fields with struct
/// update syntax.
#[derive(Clone)]
pub struct BatchOptions<'a> {
    /// The run indices flown (a shard of a campaign:
    /// [`crate::batch::shard::Shard::range`]). Run `i` draws from
    /// [`run_seed`]`(master_seed, i)` alone, so its rows are bit-identical
    /// to those of run `i` in the whole batch.
    pub runs: std::ops::Range<u64>,
    /// The master seed of the runs' draws.
    pub master_seed: u64,
    /// Flights each thread flies side by side, one of [`LANE_COUNTS`]
    /// (1 flies each flight alone). The rows do not depend on it.
    pub lanes: usize,
    /// Receives control steps flown, from inside each flight
    /// ([`RunOptions::progress`]); a batch adds up to
    /// `runs × controllers × planned_steps(base)`.
    pub progress: Option<&'a (dyn Fn(u64) + Sync)>,
    /// When set: no new flight starts, flights under way stop within
    /// [`crate::run::PROGRESS_EVERY`] steps, and the batch returns
    /// `Err(INTERRUPTED)` (no partial rows).
    pub cancel: Option<&'a std::sync::atomic::AtomicBool>,
}

impl BatchOptions<'_> {
    /// Runs `0..runs` from `master_seed` on [`DEFAULT_LANES`] lanes, no
    /// progress report, no cancellation.
    pub fn new(runs: u64, master_seed: u64) -> Self {
        Self { runs: 0..runs, master_seed, lanes: DEFAULT_LANES, progress: None, cancel: None }
    }
}

/// Message of a batch stopped through its cancellation flag
/// ([`BatchOptions::cancel`]).
pub const INTERRUPTED: &str = "interrupted";

/// The lane counts a batch can fly side by side ([`BatchOptions::lanes`]):
/// one flight alone, or four (one AVX2 register of `f64`). Two lanes flew
/// fewer steps per CPU-second than four on every Monte Carlo cell measured,
/// and eight fewer than four on all but one (docs/results.md), so neither
/// width is built.
pub const LANE_COUNTS: [usize; 2] = [1, 4];

/// Flights a batch flies side by side unless told otherwise: four `f64`
/// lanes, one AVX2 register.
pub const DEFAULT_LANES: usize = 4;

/// Most runs a worker takes at a time: enough to keep its lanes full as
/// flights end at different times ([`runs_per_task`]).
const RUNS_PER_TASK: usize = 16;

/// Runs per work item for `runs` runs on `lanes` lanes: at least one lane
/// set, at most [`RUNS_PER_TASK`], and small enough that every thread of
/// the pool gets about two items (a short batch still uses every core).
/// The rows do not depend on it.
fn runs_per_task(runs: usize, lanes: usize) -> usize {
    let share = runs.div_ceil(2 * rayon::current_num_threads().max(1));
    share.clamp(lanes.max(1), RUNS_PER_TASK.max(lanes))
}

/// Fly the runs of `options` (randomised copies of `base` drawn from
/// `spec`) with each controller, in parallel on the current rayon pool,
/// `options.lanes` flights side by side ([`crate::run::Flights::new_lanes`]):
/// a lane whose flight ends starts the next run. The output order is (run
/// index, controller), and every row has exactly the bits it has whatever
/// the lane count, the lane it lands in and the thread count.
pub fn run_batch(
    base: &Scenario,
    spec: &MonteCarloSpec,
    controllers: &[String],
    options: BatchOptions<'_>,
) -> Result<Vec<McRun>, String> {
    let BatchOptions { runs: indices, master_seed, lanes, progress, cancel } = options;
    for name in controllers {
        crate::registry::check_name(name)?;
    }
    if !LANE_COUNTS.contains(&lanes) {
        return Err(format!("lanes = {lanes}: expected one of {LANE_COUNTS:?}"));
    }
    let options = RunOptions { record: false, progress, cancel, stream: None };
    let indices: Vec<u64> = indices.collect();
    let rows: Vec<Vec<McRun>> = indices
        .par_chunks(runs_per_task(indices.len(), lanes))
        .map(|chunk| {
            if options.cancelled() {
                return Vec::new();
            }
            let samples: Vec<(u64, Scenario, u64, [f64; 12])> = chunk
                .iter()
                .map(|&index| {
                    let (scenario, seed, sampled) = spec.sample(base, master_seed, index);
                    (index, scenario, seed, sampled)
                })
                .collect();
            let scenarios: Vec<&Scenario> = samples.iter().map(|s| &s.1).collect();
            let mut flown: Vec<std::vec::IntoIter<RunOutput>> =
                controllers.iter().map(|name| fly(name, &scenarios, lanes, options).into_iter()).collect();
            let mut out = Vec::with_capacity(samples.len() * controllers.len());
            for &(index, _, seed, sampled) in &samples {
                for (name, outputs) in controllers.iter().zip(&mut flown) {
                    let out_run = outputs.next().expect("one output per run");
                    out.push(McRun {
                        index,
                        seed,
                        sampled,
                        controller: name.clone(),
                        exit: out_run.exit,
                        success: out_run.success(),
                        metrics: out_run.metrics,
                        stats: out_run.stats,
                        margin: out_run.margin,
                    });
                }
            }
            out
        })
        .collect();
    if options.cancelled() {
        return Err(INTERRUPTED.to_string());
    }
    Ok(rows.into_iter().flatten().collect())
}

/// Fly controller `name` through each of `scenarios` (in order), `lanes`
/// at a time (one of [`LANE_COUNTS`]; scenarios that may not share lanes,
/// [`crate::registry::lane_compatible`], fly one by one), on this thread.
/// Each output has exactly the bits of the flight flown alone.
///
/// # Panics
/// If `name` is not a declared controller ([`crate::registry::check_name`]).
pub fn fly(name: &str, scenarios: &[&Scenario], lanes: usize, options: RunOptions<'_>) -> Vec<RunOutput> {
    let one = |s: &&Scenario| crate::registry::run(name, s, options).expect("controller names checked above");
    let together = scenarios.iter().all(|s| crate::registry::lane_compatible(scenarios[0], s));
    match lanes {
        4 if together => fly_lanes::<4>(name, scenarios, options),
        _ => scenarios.iter().map(one).collect(),
    }
}

/// [`fly`] on `N` lanes: each lane flies the next run when its flight ends.
fn fly_lanes<const N: usize>(name: &str, scenarios: &[&Scenario], options: RunOptions<'_>) -> Vec<RunOutput> {
    use crate::run::Flights;
    use ftsmc_core::cascade::Controller;
    use ftsmc_core::lanes::Lanes;
    let n = scenarios.len();
    if n == 0 {
        return Vec::new();
    }
    let controller = crate::registry::build_lanes::<N>(name, scenarios[0]).expect("controller names checked above");
    let first: Vec<std::sync::Arc<Scenario>> = (0..N).map(|i| (*scenarios[i.min(n - 1)]).clone().into()).collect();
    let mut flight =
        Flights::<Box<dyn Controller<Lanes<N>> + Send>, Lanes<N>>::new_lanes(first, controller, options).named(name);
    // The run each lane flies (`None`: idle).
    let mut run_of: [Option<usize>; N] = core::array::from_fn(|i| (i < n).then_some(i));
    for (i, run) in run_of.iter().enumerate() {
        if run.is_none() {
            flight.stop_lane(i);
        }
    }
    let mut next = N.min(n);
    let mut out: Vec<Option<RunOutput>> = (0..n).map(|_| None).collect();
    loop {
        for (i, slot) in run_of.iter_mut().enumerate() {
            let Some(run) = *slot else { continue };
            if flight.lane_flying(i) {
                continue;
            }
            out[run] = Some(flight.lane_output(i));
            *slot = None;
            if next < n {
                flight.start_lane(i, (*scenarios[next]).clone());
                *slot = Some(next);
                next += 1;
            }
        }
        if run_of.iter().all(Option::is_none) {
            break;
        }
        flight.step();
    }
    out.into_iter().map(|o| o.expect("every run flown")).collect()
}

/// Order statistics of one metric over the completed runs of a controller.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Stats {
    /// Median (nearest rank).
    pub median: f64,
    /// 5th percentile (nearest rank).
    pub p5: f64,
    /// 95th percentile (nearest rank).
    pub p95: f64,
    /// Largest value (worst for an error metric).
    pub worst: f64,
    /// Number of finite values the statistics are over.
    pub count: usize,
}

/// Nearest-rank statistics of the finite values (`None` if there are none).
pub fn stats(values: &[f64]) -> Option<Stats> {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let rank = |q: f64| v[((q * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1];
    Some(Stats { median: rank(0.5), p5: rank(0.05), p95: rank(0.95), worst: v[v.len() - 1], count: v.len() })
}

/// Per-controller summary of a batch.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ControllerSummary {
    /// Runs flown.
    pub runs: usize,
    /// Runs that diverged (every run neither completed nor crashed:
    /// [`crate::run::ExitCategory::Diverged`], and the rare interrupted run).
    pub diverged: usize,
    /// Runs that ended on the ground, hitting it too fast or landing and
    /// staying there ([`crate::run::ExitCategory::Crashed`]; docs/statistics.md,
    /// "Exit categories").
    pub crashed: usize,
    /// Runs that completed but left the scenario's `[envelope]`.
    pub envelope_failures: usize,
    /// Fraction of runs that succeeded: completed and inside the
    /// `[envelope]` (without one: the fraction that completed).
    pub success_rate: f64,
    /// Fraction of runs that completed (no divergence, no crash).
    pub completed_rate: f64,
    /// Statistics of every metric over the completed runs (settling times:
    /// over the runs that settled).
    pub metrics: std::collections::BTreeMap<String, Stats>,
    /// The rates and the RMS position error with their intervals
    /// ([`crate::batch::verdicts::intervals`]).
    pub intervals: crate::batch::verdicts::Intervals,
}

/// What [`summarize`] reads of one row of a batch: its controller, how it
/// ended and its metrics as [`crate::metrics::Metrics::flat`] gives them
/// (`NaN` for a value that does not apply). `ftsmc merge` rebuilds these
/// from the `runs.csv` of shards, so a merged summary is computed by the
/// same code, from the same numbers, as the unsharded one.
#[derive(Clone, Debug, PartialEq)]
pub struct RowOutcome {
    /// Controller name.
    pub controller: String,
    /// The run completed (no divergence, no crash).
    pub completed: bool,
    /// The run ended on the ground, crashed or landed
    /// ([`crate::run::ExitStatus::is_crashed`]).
    pub crashed: bool,
    /// Completed and inside the scenario's `[envelope]`.
    pub success: bool,
    /// `(metric name, value)` in [`crate::metrics::Metrics::flat`] order.
    pub metrics: Vec<(String, f64)>,
}

impl From<&McRun> for RowOutcome {
    fn from(r: &McRun) -> Self {
        Self {
            controller: r.controller.clone(),
            completed: r.exit.is_completed(),
            crashed: r.exit.is_crashed(),
            success: r.success,
            metrics: r.metrics.flat(),
        }
    }
}

/// Summaries per controller, in the order the controllers were given.
/// Intervals at [`crate::stats::DEFAULT_CONFIDENCE`].
pub fn summarize(rows: &[McRun], controllers: &[String]) -> Vec<(String, ControllerSummary)> {
    summarize_at(rows, controllers, crate::stats::DEFAULT_CONFIDENCE)
}

/// [`summarize`] with intervals at `confidence`, which the caller checks
/// ([`crate::stats::check_confidence`]; a level outside (0, 1) gives the
/// intervals at 0.95, and the level recorded with them says so).
pub fn summarize_at(rows: &[McRun], controllers: &[String], confidence: f64) -> Vec<(String, ControllerSummary)> {
    let outcomes: Vec<RowOutcome> = rows.iter().map(RowOutcome::from).collect();
    summarize_outcomes_at(&outcomes, controllers, confidence)
}

/// [`summarize`] over [`RowOutcome`]s (the rows of a batch, or of the
/// merged shards of a campaign).
pub fn summarize_outcomes(rows: &[RowOutcome], controllers: &[String]) -> Vec<(String, ControllerSummary)> {
    summarize_outcomes_at(rows, controllers, crate::stats::DEFAULT_CONFIDENCE)
}

/// [`summarize_outcomes`] with intervals at `confidence`.
pub fn summarize_outcomes_at(
    rows: &[RowOutcome],
    controllers: &[String],
    confidence: f64,
) -> Vec<(String, ControllerSummary)> {
    controllers
        .iter()
        .map(|name| {
            let mine: Vec<&RowOutcome> = rows.iter().filter(|r| &r.controller == name).collect();
            let completed: Vec<&RowOutcome> = mine.iter().copied().filter(|r| r.completed).collect();
            let mut metrics = std::collections::BTreeMap::new();
            if let Some(first) = completed.first() {
                for (k, (n, _)) in first.metrics.iter().enumerate() {
                    let values: Vec<f64> =
                        completed.iter().map(|r| r.metrics.get(k).map_or(f64::NAN, |m| m.1)).collect();
                    if let Some(st) = stats(&values) {
                        metrics.insert(n.clone(), st);
                    }
                }
            }
            let runs = mine.len();
            let crashed = mine.iter().filter(|r| r.crashed).count();
            let diverged = runs - completed.len() - crashed;
            let successes = mine.iter().filter(|r| r.success).count();
            let envelope_failures = completed.iter().filter(|r| !r.success).count();
            let rate = |n: usize| if runs > 0 { n as f64 / runs as f64 } else { 0.0 };
            let (success_rate, completed_rate) = (rate(successes), rate(completed.len()));
            let mut outcomes = crate::batch::verdicts::Outcomes::default();
            for r in &mine {
                let rms = crate::batch::verdicts::rms_position_error_flat(&r.metrics);
                outcomes.push(r.success, r.completed, r.crashed, rms);
            }
            let intervals = crate::batch::verdicts::intervals(&outcomes, confidence)
                .unwrap_or_else(|_| crate::batch::verdicts::intervals(&outcomes, 0.95).expect("0.95 is a valid level"));
            let summary = ControllerSummary {
                runs,
                diverged,
                crashed,
                envelope_failures,
                success_rate,
                completed_rate,
                metrics,
                intervals,
            };
            (name.clone(), summary)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn nearest_rank_statistics() {
        let v: Vec<f64> = (1..=100).map(f64::from).chain([f64::NAN]).collect();
        let s = stats(&v).unwrap();
        assert_eq!((s.median, s.p5, s.p95, s.worst, s.count), (50.0, 5.0, 95.0, 100.0, 100));
        assert!(stats(&[f64::NAN]).is_none());
    }

    #[test]
    fn distributions_respect_their_bounds_and_are_seeded() {
        let d = Dist::Normal { mean: 1.0, std: 5.0, low: Some(0.5), high: Some(1.5) };
        let mut a = ChaCha8Rng::seed_from_u64(7);
        let mut b = ChaCha8Rng::seed_from_u64(7);
        for _ in 0..1000 {
            let x = d.sample(&mut a);
            assert!((0.5..=1.5).contains(&x));
            assert_eq!(x, d.sample(&mut b));
        }
        let u = Dist::Uniform { low: -2.0, high: 3.0 };
        let xs: Vec<f64> = (0..2000).map(|_| u.sample(&mut a)).collect();
        assert!(xs.iter().all(|x| (-2.0..=3.0).contains(x)));
        let mean = xs.iter().sum::<f64>() / xs.len() as f64;
        assert!((mean - 0.5).abs() < 0.1, "{mean}");
        assert!(Dist::Uniform { low: 1.0, high: 0.0 }.check().is_err());
        assert!(Dist::LogNormal { mu: 0.0, sigma: -1.0, low: None, high: None }.check().is_err());
    }

    #[test]
    fn run_seeds_depend_only_on_master_and_index() {
        assert_eq!(run_seed(1, 5), run_seed(1, 5));
        assert_ne!(run_seed(1, 5), run_seed(1, 6));
        assert_ne!(run_seed(1, 5), run_seed(2, 5));
    }
}
