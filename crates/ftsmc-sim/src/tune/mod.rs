//! `ftsmc tune`: robust gains for any declared controller on any scenario.
//!
//! A CMA-ES search ([`cmaes`]) over the controller's declared parameters
//! ([`space`], `crate::controllers::tunable`), scored by a cost built from
//! the statistics of a handful of Monte Carlo flights per candidate
//! ([`cost`]). Every candidate flies the same draws (common random
//! numbers: run indices [`training_indices`] of the scenario's
//! `[montecarlo]`, seeded by the tune's seed), each generation's flights in
//! parallel on the current rayon pool. The start (the scenario's own gains)
//! is flown first. The initial step is a factor ×1.4 per parameter
//! ([`space::DEFAULT_LOG_STEP`]); the search restarts when it makes no
//! progress or converges (the policy is on `tune_inner`). Before choosing,
//! the start and the best few candidates are re-flown on fresh training
//! draws ([`race_indices`], racing), so the winner is not the one the
//! training draws flattered most; if the start wins, the result says so
//! ([`TuneResult::improved`]). The result and the start are then judged
//! on a fresh Monte Carlo whose run indices start at [`HELD_OUT_OFFSET`]:
//! the search never sees them. Training, race and held-out run indices
//! lie far above any index `montecarlo` flies, so the tuned file's own
//! Monte Carlo never re-flies one of them.
//!
//! Determinism: candidates are drawn on the calling thread from ChaCha8
//! streams seeded by the tune's seed, flights are collected in order,
//! costs computed in order: the same scenario, controller, budget and seed
//! give the same history and result whatever the thread count.

pub mod cmaes;
pub mod cost;
pub mod space;

use rayon::prelude::*;
use serde::Serialize;

use crate::batch::montecarlo::{run_seed, MonteCarloSpec, DEFAULT_LANES};
use crate::escape::toml_comment;
use crate::run::RunOptions;
use crate::scenario::tune_section::TuneSection;
use crate::scenario::Scenario;
pub use cost::{FlightOutcome, OutcomeStats};
pub use space::{Dim, Space};

/// First run index of the held-out Monte Carlo.
pub const HELD_OUT_OFFSET: u64 = 1 << 40;

/// First run index of the training flights. Far above any run index a
/// Monte Carlo flies (`montecarlo`, `merge`, `compare` number their runs
/// from 0; 2⁴¹ ≈ 2.2 × 10¹² runs, against a default limit of 10⁶), so the tuned file's own Monte Carlo, with
/// the default seed or any other, never re-flies a training draw: a run's
/// draws are keyed by the master seed *and* its index.
pub const TRAINING_OFFSET: u64 = 1 << 41;

/// First run index of the racing flights (fresh training draws on which
/// the best candidates are re-flown before the winner is chosen).
pub const RACE_OFFSET: u64 = 1 << 42;

/// Run indices of the training flights: `TRAINING_OFFSET..TRAINING_OFFSET + runs`.
pub fn training_indices(runs: u64) -> Vec<u64> {
    (TRAINING_OFFSET..TRAINING_OFFSET.saturating_add(runs)).collect()
}

/// Run indices of the racing flights: `RACE_OFFSET..RACE_OFFSET + runs`.
pub fn race_indices(runs: u64) -> Vec<u64> {
    (RACE_OFFSET..RACE_OFFSET.saturating_add(runs)).collect()
}

/// Run indices of `runs` held-out flights: from [`HELD_OUT_OFFSET`] on,
/// skipping any index whose run seed ([`run_seed`]) equals the seed of a
/// training flight (`training_runs` of them), so that no held-out flight
/// shares its draws and noise with a training one.
pub fn held_out_indices(master: u64, training_runs: u64, runs: u64) -> Vec<u64> {
    let training: std::collections::HashSet<u64> =
        training_indices(training_runs).into_iter().map(|i| run_seed(master, i)).collect();
    (HELD_OUT_OFFSET..).filter(|&i| !training.contains(&run_seed(master, i))).take(runs as usize).collect()
}

/// What to tune and with which budget.
#[derive(Clone, Debug, PartialEq)]
pub struct TuneOptions {
    /// Registry name of the controller.
    pub controller: String,
    /// Training flights the search may fly (the start's and the race's included).
    pub budget: u64,
    /// Seed of the search (CMA-ES stream) and of the Monte Carlo draws.
    pub seed: u64,
}

/// One evaluated candidate (a row of `history.csv`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Evaluated {
    /// Generation (0: the start point), counted across restarts.
    pub generation: u64,
    /// Index in its generation: the samples first, then the mean, then
    /// the anchor.
    pub candidate: usize,
    /// What it is: the start, a CMA-ES sample, the search distribution's
    /// mean or the run's anchor.
    pub role: Role,
    /// Parameter values, in [`Space::dims`] order.
    pub values: Vec<f64>,
    /// Cost on the training draws.
    pub cost: f64,
    /// Statistics of its training flights.
    pub stats: OutcomeStats,
    /// Training flights flown so far, this candidate's included.
    pub flights: u64,
    /// Why it could not fly (invalid gains), if so.
    pub error: Option<String>,
    /// The CMA-ES run it belongs to (0: the first; each restart adds 1).
    pub restart: u64,
}

impl Evaluated {
    /// Invalid gains, or at least one training flight diverged or crashed.
    pub fn failed(&self) -> bool {
        self.error.is_some() || self.stats.completed < self.stats.runs
    }
}

/// What an evaluated point is. Every generation flies, on its own fresh
/// draws, the λ samples CMA-ES asked for, the distribution's mean (not
/// told to CMA-ES: the search's current estimate of the best gains, the
/// recommendation under noise, Hansen 2016, and a race contender) and,
/// in a run's second and third generations, the run's start point (the
/// anchor the no-progress test compares the samples with).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Role {
    /// The scenario's own gains (generation 0).
    Start,
    /// A CMA-ES sample.
    Sample,
    /// The search distribution's mean.
    Mean,
    /// The run's start point, flown beside its next generations.
    Anchor,
}

impl Role {
    /// Its name in `history.csv` and `summary.json`.
    pub fn name(self) -> &'static str {
        match self {
            Role::Start => "start",
            Role::Sample => "sample",
            Role::Mean => "mean",
            Role::Anchor => "anchor",
        }
    }
}

/// Why the search restarted (see [`tune`]'s restart policy).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RestartReason {
    /// No sample of the run beat its anchor (the point it started from,
    /// flown on the same draws) within [`NO_PROGRESS_GENERATIONS`]
    /// generations: the step is too large for the landscape here (a
    /// cliff). Restart from the anchor with half the initial step.
    NoProgress,
    /// The step collapsed ([`COLLAPSED_STEP`]): a local optimum. Restart
    /// from the run's final mean with the initial step and twice the
    /// population.
    Collapsed,
    /// The median of the run's generation medians over the last
    /// [`STALL_GENERATIONS`] generations is no lower than over the
    /// [`STALL_GENERATIONS`] before them (`stalled`): a plateau or a local
    /// optimum. Restart as for `Collapsed`.
    Stalled,
}

/// One generation's summary: how the search went.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Generation {
    /// Generation number (from 1).
    pub generation: u64,
    /// CMA-ES run (restart) it belongs to.
    pub restart: u64,
    /// Population λ.
    pub population: usize,
    /// Step σ · max(D) at which it was drawn (step units: 1 = the initial step).
    pub step: f64,
    /// Samples with invalid gains or a diverged or crashed training flight.
    pub failed: usize,
    /// The generation's lowest sample cost (on its own draws).
    pub best_cost: f64,
    /// The cost of the distribution's mean on the same draws.
    pub mean_cost: f64,
    /// Set when the search restarted after this generation.
    pub restarted: Option<RestartReason>,
}

/// One raced candidate: re-flown on fresh training draws.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Raced {
    /// Index in the history (0: the start).
    pub index: usize,
    /// Cost on the screening draws.
    pub screen_cost: f64,
    /// Statistics of its screening flights.
    pub screen_stats: OutcomeStats,
    /// Cost on the final draws (the start and the finalists only).
    pub cost: Option<f64>,
    /// Statistics of its final flights (the start and the finalists only).
    pub stats: Option<OutcomeStats>,
}

/// Training and held-out statistics of the start and the tuned gains.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Comparison {
    /// The scenario's own gains (the start).
    pub start: OutcomeStats,
    /// The tuned gains.
    pub tuned: OutcomeStats,
}

/// The outcome of [`tune`].
#[derive(Clone, Debug)]
pub struct TuneResult {
    /// Controller tuned.
    pub controller: String,
    /// The searched dimensions.
    pub space: Space,
    /// The `[tune]` settings used (the scenario's, or the defaults).
    pub settings: TuneSection,
    /// Options given.
    pub options: TuneOptions,
    /// Every evaluated candidate, in order.
    pub history: Vec<Evaluated>,
    /// Every generation's summary, in order.
    pub generations: Vec<Generation>,
    /// The raced candidates (the start first), empty without a race.
    pub race: Vec<Raced>,
    /// Index of the chosen candidate in `history` (0: the start).
    pub best: usize,
    /// The tuned gains beat the start on the headline, judged on the
    /// held-out draws ([`headline`]): more successes (McNemar), or no fewer
    /// and a lower RMS position error (Wilcoxon signed-rank), Holm over the
    /// two tests. False when the chosen gains are the start's.
    pub improved: bool,
    /// Why [`TuneResult::improved`] is what it is, one sentence naming its
    /// tests (`held-out success 199/200 against the start's 200/200 …`).
    pub improved_reason: String,
    /// The scenario flown at the start (the input, `controllers = [controller]`).
    pub start: Scenario,
    /// The scenario with the best parameters applied.
    pub tuned: Scenario,
    /// Training statistics (the training draws).
    pub training: Comparison,
    /// Held-out statistics (`None` with `validation_runs = 0`).
    pub held_out: Option<Comparison>,
    /// The held-out flights themselves (start, tuned), in run order, when
    /// the tune was flown locally ([`tune`]); `None` through an evaluator.
    pub held_out_runs: Option<[Vec<FlightOutcome>; 2]>,
    /// Run indices of the training flights.
    pub training_indices: Vec<u64>,
    /// Run indices of the racing flights.
    pub race_indices: Vec<u64>,
    /// Run indices of the held-out flights.
    pub held_out_indices: Vec<u64>,
    /// Training flights flown by the search (the start's included).
    pub training_flights: u64,
    /// Training flights flown by the race.
    pub race_flights: u64,
    /// Held-out flights flown (start and tuned).
    pub held_out_flights: u64,
}

impl TuneResult {
    /// The chosen candidate.
    pub fn best(&self) -> &Evaluated {
        &self.history[self.best]
    }

    /// The chosen candidate's race entry, if it was raced.
    pub fn best_raced(&self) -> Option<&Raced> {
        self.race.iter().find(|r| r.index == self.best)
    }
}

/// Fly `controller` on every scenario of `scenarios` with the Monte Carlo
/// draws `indices` of `spec` (seeded by `master`), all flights in parallel,
/// [`DEFAULT_LANES`] side by side ([`crate::batch::montecarlo::fly`]); the
/// flights of scenario k in index order at position k.
fn fly(
    scenarios: &[Scenario],
    spec: &MonteCarloSpec,
    indices: &[u64],
    master: u64,
    controller: &str,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Vec<Vec<FlightOutcome>>, String> {
    crate::registry::check_name(controller)?;
    // Work items: a scenario and a run of its indices, a few lanes' worth each.
    let per_task = DEFAULT_LANES * 2;
    let tasks: Vec<(usize, &[u64])> =
        (0..scenarios.len()).flat_map(|k| indices.chunks(per_task.max(1)).map(move |c| (k, c))).collect();
    let options = RunOptions { record: false, ..Default::default() };
    let flown: Vec<Vec<FlightOutcome>> = tasks
        .par_iter()
        .map(|&(k, chunk)| {
            let sampled: Vec<Scenario> =
                chunk.iter().map(|&index| spec.sample(&scenarios[k], master, index).0).collect();
            let refs: Vec<&Scenario> = sampled.iter().collect();
            let outs = crate::batch::montecarlo::fly(controller, &refs, DEFAULT_LANES, options);
            progress(outs.len() as u64);
            outs.iter().map(FlightOutcome::of).collect()
        })
        .collect();
    let flights: Vec<FlightOutcome> = flown.into_iter().flatten().collect();
    Ok(flights.chunks(indices.len().max(1)).map(|c| c.to_vec()).collect())
}

/// The flights of `controller` flown on each of `scenarios` with the Monte
/// Carlo draws `indices` of the first scenario's `[montecarlo]` spec,
/// seeded by `master` (what [`evaluate`] summarises), one list per
/// scenario, in run order.
pub fn flights(
    scenarios: &[Scenario],
    controller: &str,
    master: u64,
    indices: &[u64],
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Vec<Vec<FlightOutcome>>, String> {
    let Some(first) = scenarios.first() else { return Ok(Vec::new()) };
    let spec = first.montecarlo.clone().unwrap_or_default();
    fly(scenarios, &spec, indices, master, controller, progress)
}

/// The statistics of `controller` flown on each of `scenarios` with the
/// Monte Carlo draws `indices` of the scenario's own `[montecarlo]` spec,
/// seeded by `master`, all flights in parallel (the current rayon pool):
/// the objective of a tune, one entry per scenario, in order. The result
/// depends only on the arguments, so it may be computed anywhere (a Dask
/// worker, `ftsmc.tune(..., client=...)`) and gives the same bits.
pub fn evaluate(
    scenarios: &[Scenario],
    controller: &str,
    master: u64,
    indices: &[u64],
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Vec<OutcomeStats>, String> {
    let flown = flights(scenarios, controller, master, indices, progress)?;
    Ok(flown.iter().zip(scenarios).map(|(f, s)| OutcomeStats::of(f, s.duration)).collect())
}

/// Where a tune's flights are flown: given candidate scenarios and the
/// Monte Carlo run indices, the [`OutcomeStats`] of each (as [`evaluate`]
/// with the tune's controller and seed).
pub type Evaluator<'a> = dyn Fn(&[Scenario], &[u64]) -> Result<Vec<OutcomeStats>, String> + Sync + 'a;

/// Where the held-out flights are flown when the flights themselves are
/// wanted (as [`flights`] with the tune's controller and seed).
pub type Flyer<'a> = dyn Fn(&[Scenario], &[u64]) -> Result<Vec<Vec<FlightOutcome>>, String> + Sync + 'a;

/// Generations without a candidate better than the run's starting cost
/// before a [`RestartReason::NoProgress`] restart.
pub const NO_PROGRESS_GENERATIONS: u64 = 3;

/// Generations without improvement of the run's best before a
/// [`RestartReason::Stalled`] restart.
pub const STALL_GENERATIONS: u64 = 12;

/// `σ · max(D)` (in step units) below which the step has collapsed
/// ([`RestartReason::Collapsed`]): candidates then differ by less than
/// 1 % of a factor ×1.4.
pub const COLLAPSED_STEP: f64 = 0.03;

/// Smallest initial step of a run after [`RestartReason::NoProgress`]
/// restarts (step units).
pub const MIN_RESTART_STEP: f64 = 0.125;

/// `base` flown for `mission`, to be tuned on: the mission's scenario
/// (`crate::analysis::missions::mission_scenario` with its default
/// settling window and band — the scenario `ftsmc compare --mission`
/// flies) with `[tune] mission` set, so the tuned file states it. `steps`
/// returns `base` unchanged (no `mission` key: the tuned file is the one a
/// tune without a mission writes). Refused with the scenario's error when
/// the vehicle cannot fly the mission.
pub fn mission_base(
    base: &Scenario,
    mission: crate::analysis::missions::Mission,
) -> Result<Scenario, crate::scenario::ScenarioError> {
    use crate::analysis::missions::{mission_scenario, Mission, MissionOptions};
    if mission == Mission::Steps {
        return Ok(base.clone());
    }
    let mut s = mission_scenario(base, mission, MissionOptions::default())?;
    s.tune.get_or_insert_with(TuneSection::default).mission = Some(mission.name().to_string());
    Ok(s)
}

/// Tune `options.controller` on `base` (see the module docs). `progress`
/// receives every flight flown (training, race and held-out).
pub fn tune(base: &Scenario, options: &TuneOptions, progress: &(dyn Fn(u64) + Sync)) -> Result<TuneResult, String> {
    let local = |s: &[Scenario], i: &[u64]| evaluate(s, &options.controller, options.seed, i, progress);
    let flyer = |s: &[Scenario], i: &[u64]| flights(s, &options.controller, options.seed, i, progress);
    tune_inner(base, options, &local, Some(&flyer))
}

/// [`tune`] with the flights flown by `evaluator` (e.g. a Dask cluster);
/// the same result as [`tune`] as long as the evaluator returns what
/// [`evaluate`] would (without the held-out flights themselves).
pub fn tune_with(base: &Scenario, options: &TuneOptions, evaluator: &Evaluator<'_>) -> Result<TuneResult, String> {
    tune_inner(base, options, evaluator, None)
}

/// The CMA-ES search with restarts, then the race, then the held-out judgement.
///
/// Restart policy (IPOP-style, after Auger & Hansen, "A Restart CMA
/// Evolution Strategy With Increasing Population Size", CEC 2005): each
/// run starts from the best point so far. When no candidate of a run beats
/// the cost it started from within [`NO_PROGRESS_GENERATIONS`] generations
/// (the step is too large: the start sits near a cliff), the next run
/// halves the initial step (down to [`MIN_RESTART_STEP`]) and keeps the
/// population. When the step collapses ([`COLLAPSED_STEP`]) or the run's
/// best stalls for [`STALL_GENERATIONS`] generations (a local optimum of a
/// multimodal landscape), the next run takes the initial step again and
/// twice the population. Each run draws from its own ChaCha8 stream
/// (`run_seed(seed, restart)`).
fn tune_inner(
    base: &Scenario,
    options: &TuneOptions,
    evaluator: &Evaluator<'_>,
    flyer: Option<&Flyer<'_>>,
) -> Result<TuneResult, String> {
    crate::registry::check_name(&options.controller)
        .map_err(|known| format!("unknown controller `{}` (known: {known})", options.controller))?;
    let settings = base.tune.clone().unwrap_or_default();
    settings.check().map_err(|(k, e)| format!("`tune.{k}` = {} is invalid (expected {})", e.value, e.expected))?;
    let mut start = base.clone();
    start.controllers = vec![options.controller.clone()];
    let space = Space::new(&options.controller, &start, &settings)?;
    let runs = settings.runs;
    let train = training_indices(runs);
    let duration = start.duration;
    let n = space.dims.len();
    let default_lambda =
        settings.population.map(|p| p as usize).unwrap_or(cmaes::Cmaes::new(vec![0.0; n], 1.0, None, 0).population());
    let lambda0 = default_lambda as u64;
    if options.budget < runs * (2 + lambda0) {
        return Err(format!(
            "--budget {} is too small: the start and one generation of {lambda0} candidates and their mean need {} flights ({runs} per candidate, `tune.runs`)",
            options.budget,
            runs * (2 + lambda0)
        ));
    }
    // The race, on at most a tenth of the budget (`race_draws`).
    let (screen_runs, final_runs) = race_draws(&settings, options.budget);
    let finalists = settings.race.min(RACE_FINALISTS);
    let search_budget = options.budget - (1 + settings.race) * screen_runs - (1 + finalists) * final_runs;

    let mut history = Vec::new();
    let mut generations = Vec::new();
    // `flights`: training flights flown. `charged`: the budget spent, every
    // entry charged its `runs` flights whether it flew or was refused
    // (invalid gains), so the loop ends within the budget whatever the
    // candidates are.
    let mut flights = 0u64;
    let start_values = space.start_values();
    let start_stats = one(evaluator(std::slice::from_ref(&start), &train)?, 1)?[0];
    if start_stats.completed == 0 {
        return Err(unfit_start(&start, &options.controller, &start_stats));
    }
    flights += runs;
    let mut charged = runs;
    history.push(Evaluated {
        generation: 0,
        candidate: 0,
        role: Role::Start,
        values: start_values,
        cost: start_stats.cost(&settings),
        stats: start_stats,
        flights,
        error: None,
        restart: 0,
    });
    // Where the next run starts (step coordinates), its initial step and population.
    let mut origin = vec![0.0; n];
    let mut restart = 0u64;
    let mut run_step = 1.0f64;
    let mut lambda = default_lambda;
    let mut generation = 0u64;
    'runs: loop {
        let mut es = cmaes::Cmaes::new(origin.clone(), run_step, Some(lambda), run_seed(options.seed, restart));
        let anchor = origin.clone();
        let mut run_generations = 0u64;
        let mut progressed = false;
        // Each generation's median cost, for the stall test.
        let mut medians: Vec<f64> = Vec::new();
        loop {
            run_generations += 1;
            // The anchor (the run's start) flies beside the first
            // generations after the first, where the mean has moved from it.
            let with_anchor = run_generations > 1 && run_generations <= NO_PROGRESS_GENERATIONS;
            let entries = lambda as u64 + 1 + u64::from(with_anchor);
            if charged + entries * runs > search_budget {
                break 'runs;
            }
            generation += 1;
            charged += entries * runs;
            let step = es.max_std();
            let mut points = es.ask();
            let samples = points.len();
            points.push(es.mean().to_vec());
            if with_anchor {
                points.push(anchor.clone());
            }
            let draws = generation_indices(generation, runs);
            let values: Vec<Vec<f64>> = points.iter().map(|x| space.values_at_step(x)).collect();
            let built: Vec<Result<Scenario, String>> = values.iter().map(|v| space.apply(&start, v)).collect();
            let ok: Vec<Scenario> = built.iter().filter_map(|b| b.as_ref().ok().cloned()).collect();
            let flown = one(evaluator(&ok, &draws)?, ok.len())?;
            let mut flown = flown.into_iter();
            let mut costs = Vec::with_capacity(points.len());
            let first = history.len();
            for (k, b) in built.iter().enumerate() {
                let (stats, cost, error) = match b {
                    Ok(_) => {
                        let st = flown.next().expect("one statistics per built candidate (checked)");
                        flights += runs;
                        (st, st.cost(&settings), None)
                    }
                    Err(e) => {
                        let st = OutcomeStats::of(&[], duration);
                        (st, settings.divergence * 2.0 + 1.0, Some(e.clone()))
                    }
                };
                costs.push(cost);
                let role = match k {
                    k if k < samples => Role::Sample,
                    k if k == samples => Role::Mean,
                    _ => Role::Anchor,
                };
                history.push(Evaluated {
                    generation,
                    candidate: k,
                    role,
                    values: values[k].clone(),
                    cost,
                    stats,
                    flights,
                    error,
                    restart,
                });
            }
            es.tell(&points[..samples], &costs[..samples]);
            debug_assert_eq!(es.mean().len(), n);
            // Progress: a sample better than the run's start on the same
            // draws (the mean in the run's first generation, the anchor in
            // the next ones).
            let reference = if run_generations == 1 { costs[samples] } else { *costs.last().unwrap_or(&f64::NAN) };
            if run_generations <= NO_PROGRESS_GENERATIONS && costs[..samples].iter().any(|&c| c < reference) {
                progressed = true;
            }
            medians.push(median(&costs[..samples]));
            let failed = history[first..first + samples].iter().filter(|e| e.failed()).count();
            let reason = if !progressed && run_generations >= NO_PROGRESS_GENERATIONS {
                Some(RestartReason::NoProgress)
            } else if es.max_std() < COLLAPSED_STEP {
                Some(RestartReason::Collapsed)
            } else if stalled(&medians) {
                Some(RestartReason::Stalled)
            } else {
                None
            };
            let best_cost = costs[..samples].iter().copied().fold(f64::INFINITY, f64::min);
            generations.push(Generation {
                generation,
                restart,
                population: lambda,
                step,
                failed,
                best_cost,
                mean_cost: costs[samples],
                restarted: reason,
            });
            if let Some(r) = reason {
                restart += 1;
                match r {
                    RestartReason::NoProgress => {
                        run_step = (run_step * 0.5).max(MIN_RESTART_STEP);
                        origin = anchor;
                    }
                    RestartReason::Collapsed | RestartReason::Stalled => {
                        run_step = 1.0;
                        origin = es.mean().to_vec();
                        lambda = (lambda * 2).min(1000);
                        // A population the remaining budget cannot fly once
                        // would end the search: keep the largest that fits.
                        let left = (search_budget.saturating_sub(charged) / runs.max(1)).saturating_sub(2);
                        if (lambda as u64) > left && left >= default_lambda as u64 {
                            lambda = left as usize;
                        }
                    }
                }
                continue 'runs;
            }
        }
    }
    let (race, race_idx, race_flights, pick) =
        run_race(&history, &space, &start, &settings, evaluator, screen_runs, final_runs)?;
    // The start is flown as given (an extra key's start may have been
    // clamped into its range, which the scenario itself is not).
    let mut tuned = if pick == 0 { start.clone() } else { space.apply(&start, &history[pick].values)? };
    tuned.controllers = vec![options.controller.clone()];
    let training = Comparison { start: history[0].stats, tuned: history[pick].stats };
    let held = held_out_indices(options.seed, runs, settings.validation_runs);
    let (held_out, held_out_runs, held_out_flights) = if held.is_empty() {
        (None, None, 0)
    } else if let Some(fly) = flyer {
        let both = fly(&[start.clone(), tuned.clone()], &held)?;
        let [a, b]: [Vec<FlightOutcome>; 2] =
            both.try_into().map_err(|_| "the flyer returned a wrong number of flight lists".to_string())?;
        let c = Comparison { start: OutcomeStats::of(&a, start.duration), tuned: OutcomeStats::of(&b, tuned.duration) };
        (Some(c), Some([a, b]), 2 * held.len() as u64)
    } else {
        let both = one(evaluator(&[start.clone(), tuned.clone()], &held)?, 2)?;
        let c = Comparison { start: both[0], tuned: both[1] };
        (Some(c), None, 2 * held.len() as u64)
    };
    let (improved, improved_reason) = if pick == 0 {
        (false, "the search found nothing better than the start on the training draws and in the race".to_string())
    } else {
        headline(held_out_runs.as_ref(), held_out.as_ref(), crate::stats::DEFAULT_CONFIDENCE)
    };
    Ok(TuneResult {
        controller: options.controller.clone(),
        space,
        settings,
        options: options.clone(),
        history,
        generations,
        race,
        best: pick,
        improved,
        improved_reason,
        start,
        tuned,
        training,
        held_out,
        held_out_runs,
        training_indices: training_indices((generation + 1) * runs),
        race_indices: race_idx,
        held_out_indices: held,
        training_flights: flights,
        race_flights,
        held_out_flights,
    })
}

/// The words that mark [`tune`]'s refusal of start gains that fail every
/// first training draw (`ftsmc tune -c all` skips such a controller and
/// goes on with the others).
pub const UNFIT_START: &str = "its start gains fail all";

/// The refusal of a start whose every first training draw diverged or
/// crashed: no candidate near it flies either, so the search would spend
/// its budget on failures and write junk gains.
fn unfit_start(start: &Scenario, controller: &str, s: &OutcomeStats) -> String {
    let vehicle =
        start.vehicle.preset.map_or_else(|| "this vehicle".to_string(), |p| format!("the {} preset", p.name()));
    let section = crate::controllers::DECLARED.iter().find(|d| d.name == controller).map_or(controller, |d| d.section);
    format!(
        "{controller} on {}: {UNFIT_START} {} first training draws ({} crashed, {} diverged); give `[{section}]` \
         gains that fly {vehicle}{}, or tune a controller that flies it (`ftsmc compare … -c all` shows which)",
        start.name,
        s.runs,
        s.crashed,
        s.diverged,
        if section == "pid" { " (`ftsmc px4 import` converts a PX4 vehicle's)" } else { "" },
    )
}

/// Whether tuned gains beat the start on the headline, on the paired
/// held-out draws at `confidence`: held-out success first (McNemar's exact
/// test), then RMS position error (Wilcoxon signed-rank), Holm over the two
/// ([`crate::batch::verdicts::pairwise`]). Improved when success is
/// significantly higher, or when it is no lower and the RMS position error
/// is significantly lower. Without per-run held-out flights (a remote
/// evaluator) the counts and medians are compared without a test, which the
/// reason says; without held-out draws at all, the training cost decided.
pub fn headline(runs: Option<&[Vec<FlightOutcome>; 2]>, stats: Option<&Comparison>, confidence: f64) -> (bool, String) {
    use crate::batch::verdicts::{pairwise, Outcomes};
    use crate::stats::paired::Verdict;
    let Some(c) = stats else {
        return (true, "no held-out draws (`tune.validation_runs` = 0): the training cost decided".to_string());
    };
    let counts = format!(
        "held-out success {}/{} against the start's {}/{}, RMS median {:.4} m against {:.4} m",
        c.tuned.success, c.tuned.runs, c.start.success, c.start.runs, c.tuned.rms_median, c.start.rms_median
    );
    let Some([a, b]) = runs else {
        let better = c.tuned.success > c.start.success
            || (c.tuned.success == c.start.success && c.tuned.rms_median < c.start.rms_median);
        return (better, format!("{counts} (per-run flights not kept: compared without a test)"));
    };
    let outcomes = |f: &[FlightOutcome]| {
        let mut o = Outcomes::default();
        for x in f {
            o.push(x.success, x.completed, x.crashed, x.rms);
        }
        o
    };
    let (oa, ob) = (outcomes(a), outcomes(b));
    let v = match pairwise(&[("start".to_string(), &oa), ("tuned".to_string(), &ob)], confidence) {
        Ok(v) if v.len() == 2 => v,
        Ok(_) | Err(_) => return (false, format!("{counts} (the paired tests could not be computed)")),
    };
    let said = |p: &crate::batch::verdicts::PairVerdict, test: &str| {
        let q = p.p_holm;
        let q = if q < 0.001 { format!("{q:.1e}") } else { format!("{q:.3}") };
        format!("{test}: {}, Holm p = {q}", p.sentence())
    };
    let tests = format!("{}; {}", said(&v[0], "McNemar on success"), said(&v[1], "Wilcoxon on RMS"));
    let improved = match v[0].verdict {
        Verdict::BBetter => true,
        Verdict::ABetter => false,
        Verdict::NoDifference => c.tuned.success >= c.start.success && v[1].verdict == Verdict::BBetter,
    };
    (improved, format!("{counts} ({tests}, at {:.0} % confidence)", 100.0 * confidence))
}

/// `stats` when it holds `n` entries, else the evaluator's error.
fn one(stats: Vec<OutcomeStats>, n: usize) -> Result<Vec<OutcomeStats>, String> {
    if stats.len() == n {
        Ok(stats)
    } else {
        Err(format!("the evaluator returned {} statistics for {n} candidates", stats.len()))
    }
}

/// Run indices of generation `generation`'s training flights:
/// `TRAINING_OFFSET + generation · runs + (0..runs)` (generation 0 is the
/// start's). Each generation flies fresh draws, common to all its entries.
pub fn generation_indices(generation: u64, runs: u64) -> Vec<u64> {
    let first = TRAINING_OFFSET.saturating_add(generation.saturating_mul(runs));
    (first..first.saturating_add(runs)).collect()
}

/// Median of `costs` (NaN counted as +∞; +∞ when empty).
fn median(costs: &[f64]) -> f64 {
    let mut c: Vec<f64> = costs.iter().map(|&x| if x.is_nan() { f64::INFINITY } else { x }).collect();
    c.sort_by(f64::total_cmp);
    match c.len() {
        0 => f64::INFINITY,
        n if n % 2 == 1 => c[n / 2],
        n => 0.5 * (c[n / 2 - 1] + c[n / 2]),
    }
}

/// The stall test of a run: its generations' median costs (each on its
/// own draws) over the last [`STALL_GENERATIONS`] generations are, in
/// their median, no lower than over the [`STALL_GENERATIONS`] before them
/// (after Hansen's `TolStagnation`, on medians because every generation
/// flies other draws).
fn stalled(medians: &[f64]) -> bool {
    let w = STALL_GENERATIONS as usize;
    let n = medians.len();
    n >= 2 * w && median(&medians[n - w..]) >= median(&medians[n - 2 * w..n - w])
}

/// Screening and final draws of the race for a budget: `race_runs` and
/// `race_final_runs`, halved together until the race (the start and
/// `race` challengers screened, the start and [`RACE_FINALISTS`] in the
/// final) fits in a tenth of the budget; `(0, 0)` (no race) when even one
/// and four draws do not fit, or without challengers.
pub fn race_draws(settings: &TuneSection, budget: u64) -> (u64, u64) {
    if settings.race == 0 {
        return (0, 0);
    }
    let finalists = settings.race.min(RACE_FINALISTS);
    let cost = |s: u64, f: u64| (1 + settings.race) * s + (1 + finalists) * f;
    let (mut s, mut f) = (settings.race_runs, settings.race_final_runs);
    while cost(s, f) > budget / 10 {
        if s <= 1 && f <= 1 {
            return (0, 0);
        }
        s = s.div_ceil(2);
        f = f.div_ceil(2);
    }
    (s, f)
}

/// Challengers that survive the race's screening into its final.
pub const RACE_FINALISTS: u64 = 2;

/// The race's challengers: the final search-distribution mean of each
/// CMA-ES run, newest first (at most half the places, rounded down), then the best
/// sample of each generation, newest first, until `race` distinct valid
/// candidates (indices into `history`).
fn race_pool(history: &[Evaluated], race: u64) -> Vec<usize> {
    let race = race as usize;
    let valid = |i: usize| history[i].error.is_none();
    let mut means: Vec<usize> = Vec::new();
    let mut last_restart = None;
    for i in (1..history.len()).rev() {
        if history[i].role == Role::Mean && last_restart != Some(history[i].restart) {
            last_restart = Some(history[i].restart);
            if valid(i) {
                means.push(i);
            }
        }
    }
    // Each generation's lowest-cost valid sample (ties: the earlier),
    // newest generation first: a generation's entries are contiguous.
    let mut winners: Vec<usize> = Vec::new();
    let mut g = u64::MAX;
    for i in (1..history.len()).rev() {
        let e = &history[i];
        if e.role != Role::Sample || !valid(i) {
            continue;
        }
        match winners.last_mut() {
            Some(best) if e.generation == g => {
                if e.cost.total_cmp(&history[*best].cost).is_le() {
                    *best = i;
                }
            }
            _ => {
                g = e.generation;
                winners.push(i);
            }
        }
    }
    let mut pool: Vec<usize> = Vec::new();
    let push = |pool: &mut Vec<usize>, i: usize| {
        if pool.len() < race && !pool.iter().any(|&j| history[j].values == history[i].values) {
            pool.push(i);
        }
    };
    for &i in means.iter().take(race / 2) {
        push(&mut pool, i);
    }
    for &i in &winners {
        push(&mut pool, i);
    }
    pool
}

/// The race: the start and the challengers of [`race_pool`] fly `screen`
/// fresh draws; the start and the [`RACE_FINALISTS`] lowest-cost
/// challengers then fly `last` further fresh draws, and the lowest cost on
/// those alone wins (ties: the start, then screening order). Returns the
/// raced entries (the start first), the race's run indices, its flights
/// and the chosen history index (0: the start).
fn run_race(
    history: &[Evaluated],
    space: &Space,
    start: &Scenario,
    settings: &TuneSection,
    evaluator: &Evaluator<'_>,
    screen: u64,
    last: u64,
) -> Result<(Vec<Raced>, Vec<u64>, u64, usize), String> {
    let pool = race_pool(history, settings.race);
    if screen == 0 {
        // No race: the last mean, when it cost less on its draws than the
        // start on its own.
        let last = history.iter().rposition(|e| e.role == Role::Mean && e.error.is_none());
        let pick = last.filter(|&i| history[i].cost < history[0].cost).unwrap_or(0);
        return Ok((Vec::new(), Vec::new(), 0, pick));
    }
    if pool.is_empty() {
        return Ok((Vec::new(), Vec::new(), 0, 0));
    }
    let scenario = |i: usize| if i == 0 { Ok(start.clone()) } else { space.apply(start, &history[i].values) };
    // Screening draws first, the final's after them.
    let indices = race_indices(screen + last);
    let (screen_idx, final_idx) = indices.split_at(screen as usize);
    let mut contenders = vec![0usize];
    contenders.extend(&pool);
    let scenarios: Vec<Scenario> = contenders.iter().map(|&i| scenario(i)).collect::<Result<_, _>>()?;
    let stats = one(evaluator(&scenarios, screen_idx)?, scenarios.len())?;
    let mut race: Vec<Raced> = contenders
        .iter()
        .zip(stats)
        .map(|(&index, st)| Raced { index, screen_cost: st.cost(settings), screen_stats: st, cost: None, stats: None })
        .collect();
    let mut order: Vec<usize> = (1..race.len()).collect();
    order.sort_by(|&a, &b| race[a].screen_cost.total_cmp(&race[b].screen_cost).then(a.cmp(&b)));
    let mut finalists = vec![0usize];
    finalists.extend(order.iter().take(RACE_FINALISTS as usize));
    let scenarios: Vec<Scenario> = finalists.iter().map(|&k| scenario(race[k].index)).collect::<Result<_, _>>()?;
    let stats = one(evaluator(&scenarios, final_idx)?, scenarios.len())?;
    for (&k, st) in finalists.iter().zip(stats) {
        race[k].cost = Some(st.cost(settings));
        race[k].stats = Some(st);
    }
    let flights = contenders.len() as u64 * screen + finalists.len() as u64 * last;
    let winner = finalists
        .iter()
        .copied()
        .min_by(|&a, &b| race[a].cost.unwrap_or(f64::INFINITY).total_cmp(&race[b].cost.unwrap_or(f64::INFINITY)))
        .map_or(0, |k| race[k].index);
    Ok((race, indices, flights, winner))
}

/// Fly `scenario`'s controller `controller` on `runs` held-out draws of
/// seed `master` (the indices of [`held_out_indices`] with `training_runs`
/// training flights) and return their statistics: how `reproduce` judges
/// a committed tuned file without re-tuning.
pub fn judge(
    scenario: &Scenario,
    controller: &str,
    master: u64,
    training_runs: u64,
    runs: u64,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<OutcomeStats, String> {
    let flights = judge_flights(scenario, controller, master, training_runs, runs, progress)?;
    Ok(OutcomeStats::of(&flights, scenario.duration))
}

/// The flights [`judge`] summarises, in run order: every gain set judged
/// with the same `master`, `training_runs` and `runs` flies the same
/// draws, so run `i` of two of them is a matched pair.
pub fn judge_flights(
    scenario: &Scenario,
    controller: &str,
    master: u64,
    training_runs: u64,
    runs: u64,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Vec<FlightOutcome>, String> {
    crate::registry::check_name(controller)
        .map_err(|known| format!("unknown controller `{controller}` (known: {known})"))?;
    let spec = scenario.montecarlo.clone().unwrap_or_default();
    let held = held_out_indices(master, training_runs, runs);
    let mut flights = fly(std::slice::from_ref(scenario), &spec, &held, master, controller, progress)?;
    Ok(flights.pop().unwrap_or_default())
}

/// The tuned scenario file: the complete scenario the gains were tuned on
/// (its vehicle, wind and draws, whatever `--set` or `with_overrides`
/// changed) with the tuned gains, a new name (`<scenario>-<controller>-tuned`)
/// and `controllers = [controller]`, after comment lines recording the
/// command, the vehicle, the cost weights, budget, seed, parameters, the
/// headline verdict and the training and held-out statistics.
///
/// When `base` names a built-in scenario the file `extends` it and holds
/// only the keys that differ from it (readable, and it loads wherever the
/// file is moved); the text is loaded back and must give the tuned scenario
/// exactly, else (and without a built-in `base`) the file holds every key
/// and extends nothing. A file therefore never depends on a path. User
/// text in the comments (`command`, names) is escaped ([`toml_comment`]):
/// it cannot end a comment line and add a key.
pub fn tuned_toml(result: &TuneResult, base: Option<&str>, command: &str) -> Result<String, String> {
    let mut tuned_scenario = result.tuned.clone();
    tuned_scenario.name = format!("{}-{}-tuned", result.start.name, result.controller);
    let tuned = space::scenario_table(&tuned_scenario)?;
    let s = &result.settings;
    let b = result.best();
    let mut out = String::new();
    let mut line = |l: String| {
        out.push_str(&l);
        out.push('\n');
    };
    line(format!(
        "# {} tuned on {} by `ftsmc tune` (ftsmc {}).",
        toml_comment(&result.controller),
        toml_comment(&result.start.name),
        env!("CARGO_PKG_VERSION")
    ));
    line(format!("# Made by: {}", toml_comment(command)));
    line(format!(
        "# Budget {} training flights ({} flown: {} by the search, {} per candidate, fresh draws each generation, common to its candidates; {} by the race), seed {}, {} held-out flights per gain set.",
        result.options.budget,
        result.training_flights + result.race_flights,
        result.training_flights,
        s.runs,
        result.race_flights,
        result.options.seed,
        result.held_out_indices.len()
    ));
    line(format!(
        "# Cost: divergence {} × mean(2 − t/T) + envelope {} × failures/runs + margin {} × mean shortfall below {} + rms {} × p90 RMS [m] + thrust_activity {} × median [N/s] + torque_activity {} × median [N·m/s] + saturated {} × median fraction.",
        s.divergence, s.envelope, s.margin, cost::MARGIN_TARGET, s.rms, s.thrust_activity, s.torque_activity, s.saturated
    ));
    let restarts = result.generations.iter().filter(|g| g.restarted.is_some()).count();
    line(format!(
        "# Search: {} generations, {restarts} restart{}; race of {} gain sets on {} fresh training draws, the start and {} finalists on {} more.",
        result.generations.len(),
        if restarts == 1 { "" } else { "s" },
        result.race.len(),
        result.race.first().map_or(0, |r| r.screen_stats.runs),
        result.race.iter().filter(|r| r.cost.is_some()).count().saturating_sub(1),
        result.race.first().and_then(|r| r.stats).map_or(0, |st| st.runs),
    ));
    line(format!(
        "# Chosen: generation {}, candidate {} ({}), training cost {:.6} on its generation's draws (start {:.6} on its own){}.",
        b.generation,
        b.candidate,
        b.role.name(),
        b.cost,
        result.history[0].cost,
        match (result.best_raced().and_then(|w| w.cost), result.race.first().and_then(|s0| s0.cost)) {
            (Some(w), Some(s0)) => format!("; final race cost {w:.6} (start {s0:.6})"),
            _ => String::new(),
        }
    ));
    line(format!("# Vehicle: {}", toml_comment(&vehicle_line(&result.tuned))));
    line(format!("# Improved: {} ({})", result.improved, toml_comment(&result.improved_reason)));
    if result.best == 0 {
        line(
            "# The search found nothing better than the start: these are the scenario's own gains (try a larger --budget or `[tune] sigma`)."
                .to_string(),
        );
    } else if !result.improved {
        line(
            "# The chosen gains won on the cost (weights above) but not on the headline: the start's gains may serve you better."
                .to_string(),
        );
    }
    for (d, v) in result.space.dims.iter().zip(&b.values) {
        line(format!(
            "#   {} = {} (searched {} … {}{})",
            toml_comment(&d.name),
            v,
            d.low,
            d.high,
            if d.log { ", log" } else { "" }
        ));
    }
    let describe = |name: &str, st: &OutcomeStats| {
        let w = crate::stats::rate::wilson(st.success as u64, st.runs as u64, crate::stats::DEFAULT_CONFIDENCE)
            .map_or_else(|_| "—".to_string(), |i| format!("[{:.1}, {:.1}] %", 100.0 * i.lo, 100.0 * i.hi));
        format!(
            "#   {name}: success {}/{} (95 % Wilson {w}), completed {}, crashed {}, RMS median {:.4} m, p95 {:.4} m, thrust activity {:.1} N/s, torque activity {:.2} N·m/s, saturated {:.4}",
            st.success, st.runs, st.completed, st.crashed, st.rms_median, st.rms_p95, st.thrust_activity, st.torque_activity, st.saturated
        )
    };
    line("# Training draws:".to_string());
    line(describe("start", &result.training.start));
    line(describe("tuned", &result.training.tuned));
    if let (Some(s0), Some(w)) = (result.race.first().and_then(|r| r.stats), result.best_raced().and_then(|r| r.stats))
    {
        line(format!("# Race's final draws ({} fresh training draws):", s0.runs));
        line(describe("start", &s0));
        line(describe("tuned", &w));
    }
    if let Some(h) = &result.held_out {
        line("# Held-out draws:".to_string());
        line(describe("start", &h.start));
        line(describe("tuned", &h.tuned));
    }
    if let Some(body) = base.and_then(|b| extending_body(b, &tuned, &tuned_scenario)) {
        out.push_str(&body);
        return Ok(out);
    }
    line("# Complete: every key of the scenario, so the file flies the same wherever it is moved.".to_string());
    out.push_str(&toml::to_string(&tuned).map_err(|e| e.to_string())?);
    Ok(out)
}

/// The vehicle of `s` in one line: its preset (or `custom`), model, mass
/// and top rotor speed, for file headers.
pub fn vehicle_line(s: &Scenario) -> String {
    let v = s.true_vehicle();
    format!(
        "{} ({} model, {:.4} kg, arm {:.4} m{})",
        s.vehicle.preset.map_or("custom", |p| p.name()),
        s.vehicle.model.name(),
        v.mass,
        v.arm_length,
        s.actuators.as_ref().map_or(String::new(), |a| format!(", rotors up to {} rad/s", a.max_rotor_speed))
    )
}

/// `extends = "<base>"`, the name, the controller and the keys of `tuned`
/// that differ from the built-in scenario `base`, if that text loads back
/// to exactly `scenario`.
fn extending_body(base: &str, tuned: &toml::Table, scenario: &Scenario) -> Option<String> {
    let (file, text) = crate::scenario::resolve::built_in(base)?;
    let parent = Scenario::from_toml_str(text, file).ok()?;
    let mut changed = space::changed(&space::scenario_table(&parent).ok()?, tuned);
    changed.remove("name");
    changed.remove("controllers");
    // Gain sections at their vehicle-derived defaults follow the vehicle
    // when loaded: writing them would only repeat them.
    for key in scenario.gains.keys_at_defaults(&scenario.nominal_vehicle()) {
        changed.remove(key);
    }
    let mut head = toml::Table::new();
    head.insert("extends".into(), toml::Value::String(base.strip_suffix(".toml").unwrap_or(base).to_string()));
    head.insert("name".into(), toml::Value::String(scenario.name.clone()));
    head.insert(
        "controllers".into(),
        toml::Value::Array(scenario.controllers.iter().cloned().map(toml::Value::String).collect()),
    );
    let mut body = toml::to_string(&head).ok()?;
    body.push('\n');
    body.push_str(&toml::to_string(&changed).ok()?);
    let back = Scenario::from_toml_str(&body, "tuned.toml").ok()?;
    (space::scenario_table(&back).ok()? == *tuned).then_some(body)
}
