//! `ftsmc tune`: robust gains for any declared controller on any scenario.
//!
//! A CMA-ES search ([`cmaes`]) over the controller's declared parameters
//! ([`space`], `crate::controllers::tunable`), scored by a cost built from
//! the statistics of a handful of Monte Carlo flights per candidate
//! ([`cost`]). Every candidate flies the same draws (common random
//! numbers: run indices `0..runs` of the scenario's `[montecarlo]`, seeded
//! by the tune's seed), each generation's flights in parallel on the
//! current rayon pool. The start (the scenario's own gains) is flown first,
//! so the result is never worse than it on the training draws. The result
//! and the start are then judged on a fresh Monte Carlo whose run indices
//! start at [`HELD_OUT_OFFSET`] and whose seeds are checked against the
//! training seeds ([`held_out_indices`]): the search never sees them.
//!
//! Determinism: candidates are drawn on the calling thread from one
//! ChaCha8 stream seeded by the tune's seed, flights are collected in
//! order, costs computed in order: the same scenario, controller, budget
//! and seed give the same history and result whatever the thread count.

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
pub use cost::{Flight, FlightStats};
pub use space::{Dim, Space};

/// First run index of the held-out Monte Carlo (training uses `0..runs`).
pub const HELD_OUT_OFFSET: u64 = 1 << 40;

/// Run indices of the training flights: `0..runs`.
pub fn training_indices(runs: u64) -> Vec<u64> {
    (0..runs).collect()
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
    /// Training flights the search may fly (the start's included).
    pub budget: u64,
    /// Seed of the search (CMA-ES stream) and of the Monte Carlo draws.
    pub seed: u64,
}

/// One evaluated candidate (a row of `history.csv`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Evaluated {
    /// Generation (0: the start point).
    pub generation: u64,
    /// Index in its generation.
    pub candidate: usize,
    /// Parameter values, in [`Space::dims`] order.
    pub values: Vec<f64>,
    /// Cost (with the bound penalty added when the CMA-ES point lay outside the box).
    pub cost: f64,
    /// Statistics of its training flights.
    pub stats: FlightStats,
    /// Training flights flown so far, this candidate's included.
    pub flights: u64,
    /// Why it could not fly (invalid gains), if so.
    pub error: Option<String>,
}

/// Training and held-out statistics of the start and the tuned gains.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Comparison {
    /// The scenario's own gains (the start).
    pub start: FlightStats,
    /// The tuned gains.
    pub tuned: FlightStats,
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
    /// Index of the best candidate in `history`.
    pub best: usize,
    /// The scenario flown at the start (the input, `controllers = [controller]`).
    pub start: Scenario,
    /// The scenario with the best parameters applied.
    pub tuned: Scenario,
    /// Training statistics (the training draws).
    pub training: Comparison,
    /// Held-out statistics (`None` with `validation_runs = 0`).
    pub held_out: Option<Comparison>,
    /// Run indices of the training flights.
    pub training_indices: Vec<u64>,
    /// Run indices of the held-out flights.
    pub held_out_indices: Vec<u64>,
    /// Training flights flown.
    pub training_flights: u64,
    /// Held-out flights flown (start and tuned).
    pub held_out_flights: u64,
}

impl TuneResult {
    /// The best candidate.
    pub fn best(&self) -> &Evaluated {
        &self.history[self.best]
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
) -> Result<Vec<Vec<Flight>>, String> {
    crate::registry::check_name(controller)?;
    // Work items: a scenario and a run of its indices, a few lanes' worth each.
    let per_task = DEFAULT_LANES * 2;
    let tasks: Vec<(usize, &[u64])> =
        (0..scenarios.len()).flat_map(|k| indices.chunks(per_task.max(1)).map(move |c| (k, c))).collect();
    let options = RunOptions { record: false, ..Default::default() };
    let flown: Vec<Vec<Flight>> = tasks
        .par_iter()
        .map(|&(k, chunk)| {
            let sampled: Vec<Scenario> =
                chunk.iter().map(|&index| spec.sample(&scenarios[k], master, index).0).collect();
            let refs: Vec<&Scenario> = sampled.iter().collect();
            let outs = crate::batch::montecarlo::fly(controller, &refs, DEFAULT_LANES, options);
            progress(outs.len() as u64);
            outs.iter().map(Flight::of).collect()
        })
        .collect();
    let flights: Vec<Flight> = flown.into_iter().flatten().collect();
    Ok(flights.chunks(indices.len().max(1)).map(|c| c.to_vec()).collect())
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
) -> Result<Vec<FlightStats>, String> {
    let Some(first) = scenarios.first() else { return Ok(Vec::new()) };
    let spec = first.montecarlo.clone().unwrap_or_default();
    let flown = fly(scenarios, &spec, indices, master, controller, progress)?;
    Ok(flown.iter().zip(scenarios).map(|(f, s)| FlightStats::of(f, s.duration)).collect())
}

/// Where a tune's flights are flown: given candidate scenarios and the
/// Monte Carlo run indices, the [`FlightStats`] of each (as [`evaluate`]
/// with the tune's controller and seed).
pub type Evaluator<'a> = dyn Fn(&[Scenario], &[u64]) -> Result<Vec<FlightStats>, String> + Sync + 'a;

/// Tune `options.controller` on `base` (see the module docs). `progress`
/// receives every flight flown (training and held-out).
pub fn tune(base: &Scenario, options: &TuneOptions, progress: &(dyn Fn(u64) + Sync)) -> Result<TuneResult, String> {
    let local = |s: &[Scenario], i: &[u64]| evaluate(s, &options.controller, options.seed, i, progress);
    tune_with(base, options, &local)
}

/// [`tune`] with the flights flown by `evaluator` (e.g. a Dask cluster);
/// the same result as [`tune`] as long as the evaluator returns what
/// [`evaluate`] would.
pub fn tune_with(base: &Scenario, options: &TuneOptions, evaluator: &Evaluator<'_>) -> Result<TuneResult, String> {
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
    let mut es =
        cmaes::Cmaes::new(space.start_unit(), settings.sigma, settings.population.map(|p| p as usize), options.seed);
    let lambda = es.population() as u64;
    if options.budget < runs * (1 + lambda) {
        return Err(format!(
            "--budget {} is too small: the start and one generation of {lambda} candidates need {} flights ({runs} per candidate, `tune.runs`)",
            options.budget,
            runs * (1 + lambda)
        ));
    }

    let mut history = Vec::new();
    // `flights`: training flights flown. `charged`: the budget spent, every
    // candidate charged its `runs` flights whether it flew or was refused
    // (invalid gains), so every generation spends `lambda × runs` and the
    // loop ends within the budget whatever the candidates are.
    let mut flights = 0u64;
    let mut charged;
    // Generation 0: the start.
    let start_values = space.start_values();
    let start_stats = one(evaluator(std::slice::from_ref(&start), &train)?, 1)?[0];
    flights += runs;
    charged = runs;
    history.push(Evaluated {
        generation: 0,
        candidate: 0,
        values: start_values,
        cost: start_stats.cost(&settings),
        stats: start_stats,
        flights,
        error: None,
    });
    let mut generation = 0u64;
    while charged + lambda * runs <= options.budget {
        generation += 1;
        charged += lambda * runs;
        let points = es.ask();
        let values: Vec<Vec<f64>> = points.iter().map(|u| space.values(u)).collect();
        let built: Vec<Result<Scenario, String>> = values.iter().map(|v| space.apply(&start, v)).collect();
        let ok: Vec<Scenario> = built.iter().filter_map(|b| b.as_ref().ok().cloned()).collect();
        let flown = one(evaluator(&ok, &train)?, ok.len())?;
        let mut flown = flown.into_iter();
        let mut costs = Vec::with_capacity(points.len());
        for (k, (point, b)) in points.iter().zip(&built).enumerate() {
            let outside: f64 = point.iter().map(|u| (u - u.clamp(0.0, 1.0)).powi(2)).sum();
            let penalty = 10.0 * outside;
            let (stats, cost, error) = match b {
                Ok(_) => {
                    let st = flown.next().expect("one statistics per built candidate (checked)");
                    flights += runs;
                    (st, st.cost(&settings) + penalty, None)
                }
                Err(e) => {
                    let st = FlightStats::of(&[], duration);
                    (st, settings.divergence * 2.0 + 1.0 + penalty, Some(e.clone()))
                }
            };
            costs.push(cost);
            history.push(Evaluated {
                generation,
                candidate: k,
                values: values[k].clone(),
                cost,
                stats,
                flights,
                error,
            });
        }
        es.tell(&points, &costs);
        debug_assert_eq!(es.mean().len(), n);
    }
    let best = (0..history.len())
        .min_by(|&a, &b| history[a].cost.total_cmp(&history[b].cost).then(a.cmp(&b)))
        .expect("the start is always evaluated");
    // The start is flown as given (an extra key's start may have been
    // clamped into its range, which the scenario itself is not).
    let mut tuned = if best == 0 { start.clone() } else { space.apply(&start, &history[best].values)? };
    tuned.controllers = vec![options.controller.clone()];
    let training = Comparison { start: history[0].stats, tuned: history[best].stats };
    let held = held_out_indices(options.seed, runs, settings.validation_runs);
    let (held_out, held_out_flights) = if held.is_empty() {
        (None, 0)
    } else {
        let both = one(evaluator(&[start.clone(), tuned.clone()], &held)?, 2)?;
        let c = Comparison { start: both[0], tuned: both[1] };
        (Some(c), 2 * held.len() as u64)
    };
    Ok(TuneResult {
        controller: options.controller.clone(),
        space,
        settings,
        options: options.clone(),
        history,
        best,
        start,
        tuned,
        training,
        held_out,
        training_indices: train,
        held_out_indices: held,
        training_flights: flights,
        held_out_flights,
    })
}

/// `stats` when it holds `n` entries, else the evaluator's error.
fn one(stats: Vec<FlightStats>, n: usize) -> Result<Vec<FlightStats>, String> {
    if stats.len() == n {
        Ok(stats)
    } else {
        Err(format!("the evaluator returned {} statistics for {n} candidates", stats.len()))
    }
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
) -> Result<FlightStats, String> {
    crate::registry::check_name(controller)
        .map_err(|known| format!("unknown controller `{controller}` (known: {known})"))?;
    let spec = scenario.montecarlo.clone().unwrap_or_default();
    let held = held_out_indices(master, training_runs, runs);
    let flights = fly(std::slice::from_ref(scenario), &spec, &held, master, controller, progress)?;
    Ok(FlightStats::of(&flights[0], scenario.duration))
}

/// The tuned scenario file: `extends = "<extends>"`, a new name
/// (`<scenario>-<controller>-tuned`), `controllers = [controller]` and only
/// the keys the tune changed, after comment lines recording the command,
/// the cost weights, budget, seed, parameters and the training and held-out
/// statistics. User text in the comments (`command`, names) is escaped
/// ([`toml_comment`]): it cannot end a comment line and add a key.
pub fn tuned_toml(result: &TuneResult, extends: &str, command: &str) -> Result<String, String> {
    let base = space::scenario_table(&result.start)?;
    let tuned = space::scenario_table(&result.tuned)?;
    let mut changed = space::changed(&base, &tuned);
    changed.remove("controllers");
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
        "# Budget {} training flights ({} flown, {} per candidate, same draws for all), seed {}, {} held-out flights per gain set.",
        result.options.budget, result.training_flights, s.runs, result.options.seed, result.held_out_indices.len()
    ));
    line(format!(
        "# Cost: divergence {} × mean(2 − t/T) + envelope {} × failures/runs + rms {} × p90 RMS [m] + thrust_activity {} × median [N/s] + torque_activity {} × median [N·m/s] + saturated {} × median fraction.",
        s.divergence, s.envelope, s.rms, s.thrust_activity, s.torque_activity, s.saturated
    ));
    line(format!(
        "# Best: generation {}, candidate {}, cost {:.6} (start {:.6}).",
        b.generation, b.candidate, b.cost, result.history[0].cost
    ));
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
    let describe = |name: &str, st: &FlightStats| {
        format!(
            "#   {name}: success {}/{}, completed {}, crashed {}, RMS median {:.4} m, p95 {:.4} m, thrust activity {:.1} N/s, torque activity {:.2} N·m/s, saturated {:.4}",
            st.success, st.runs, st.completed, st.crashed, st.rms_median, st.rms_p95, st.thrust_activity, st.torque_activity, st.saturated
        )
    };
    line("# Training draws:".to_string());
    line(describe("start", &result.training.start));
    line(describe("tuned", &result.training.tuned));
    if let Some(h) = &result.held_out {
        line("# Held-out draws:".to_string());
        line(describe("start", &h.start));
        line(describe("tuned", &h.tuned));
    }
    let mut head = toml::Table::new();
    head.insert("extends".into(), toml::Value::String(extends.to_string()));
    head.insert("name".into(), toml::Value::String(format!("{}-{}-tuned", result.start.name, result.controller)));
    head.insert("controllers".into(), toml::Value::Array(vec![toml::Value::String(result.controller.clone())]));
    out.push_str(&toml::to_string(&head).map_err(|e| e.to_string())?);
    out.push('\n');
    out.push_str(&toml::to_string(&changed).map_err(|e| e.to_string())?);
    Ok(out)
}
