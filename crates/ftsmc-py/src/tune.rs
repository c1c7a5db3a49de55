//! `ftsmc.tune(...)`: the `ftsmc tune` search from Python
//! ([`ftsmc_sim::tune::tune`], the same code and results as the command).

use pyo3::prelude::*;

use ftsmc_sim::tune::OutcomeStats;

use crate::scenario::{chain_message, scenario_toml, Scenario};
use crate::value_error;

/// `evaluator(tomls, indices)` (Python, e.g. [`tune_evaluate`] as Dask
/// tasks): the statistics of each candidate scenario (sent as TOML text) on
/// the Monte Carlo run `indices`, as lists of [`OutcomeStats::VALUES`]
/// numbers. Its exceptions become the tune's error.
fn call_evaluator(
    f: &Py<PyAny>,
    scenarios: &[ftsmc_sim::Scenario],
    indices: &[u64],
) -> Result<Vec<OutcomeStats>, String> {
    let texts: Vec<String> = scenarios.iter().map(scenario_toml).collect::<Result<_, _>>()?;
    let values: Vec<Vec<f64>> = Python::attach(|py| {
        f.call1(py, (texts, indices.to_vec()))
            .and_then(|r| r.extract::<Vec<Vec<f64>>>(py))
            .map_err(|e| format!("the tune's evaluator failed: {e}"))
    })?;
    values
        .iter()
        .map(|v| {
            OutcomeStats::from_values(v).ok_or_else(|| {
                format!("the tune's evaluator returned {} numbers, not {} statistics", v.len(), OutcomeStats::VALUES)
            })
        })
        .collect()
}

/// The objective of a tune, for one batch of candidates (a Dask task of
/// `ftsmc.tune(..., client=...)`): `controller` flown on each scenario of
/// `tomls` (resolved TOML text) with the Monte Carlo draws `indices` of
/// master seed `master`, on `threads` workers (default 1), the GIL
/// released. Returns each scenario's statistics as
/// [`OutcomeStats::VALUES`] numbers (`OutcomeStats::to_values`): a pure
/// function of its arguments, so a retried task gives the same numbers.
#[pyfunction]
#[pyo3(signature = (tomls, controller, master, indices, threads=None))]
pub fn tune_evaluate(
    py: Python<'_>,
    tomls: Vec<String>,
    controller: String,
    master: u64,
    indices: Vec<u64>,
    threads: Option<usize>,
) -> PyResult<Vec<Vec<f64>>> {
    crate::check_controllers("controller", std::slice::from_ref(&controller))?;
    if threads == Some(0) {
        return Err(value_error("threads must be at least 1"));
    }
    let scenarios: Vec<ftsmc_sim::Scenario> = tomls
        .iter()
        .enumerate()
        .map(|(k, t)| {
            ftsmc_sim::Scenario::from_toml_str(t, &format!("<candidate {k} sent to a Dask worker>"))
                .map_err(|e| value_error(chain_message(&e)))
        })
        .collect::<PyResult<_>>()?;
    if let Some(s) = scenarios.first() {
        ftsmc_sim::limits::check_batch(
            &s.flight_size(),
            (scenarios.len() as u64).saturating_mul(indices.len() as u64),
            1,
        )
        .map_err(|e| value_error(chain_message(&e)))?;
    }
    let stats = py.detach(move || {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads.unwrap_or(1))
            .build()
            .map_err(|e| format!("cannot start the thread pool: {e}"))?;
        pool.install(|| ftsmc_sim::tune::evaluate(&scenarios, &controller, master, &indices, &|_| {}))
    });
    let stats = stats.map_err(value_error)?;
    Ok(stats.iter().map(|s| s.to_values().to_vec()).collect())
}

/// Tune `controller` on `scenario` with a `budget` of training flights and
/// `seed` (default: the scenario's), on `threads` workers (default: all
/// cores; the result does not depend on it), with the GIL released, flown
/// for `mission` (`steps`, `hover`, `figure-eight`, `waypoints`; None:
/// `steps`) as `ftsmc tune --mission` ([`ftsmc_sim::tune::mission_base`]).
/// Returns `(tuned scenario, tuned TOML text extending `extends`, JSON
/// summary)`; the JSON has the parameters, every candidate
/// (`history`) and the training and held-out statistics.
#[pyfunction]
#[pyo3(signature = (scenario, controller, budget=ftsmc_sim::defaults::TUNE_BUDGET, seed=None, threads=None, extends=None, evaluator=None, mission=None))]
#[allow(clippy::too_many_arguments)]
pub fn tune_native(
    py: Python<'_>,
    scenario: PyRef<'_, Scenario>,
    controller: String,
    budget: u64,
    seed: Option<u64>,
    threads: Option<usize>,
    extends: Option<String>,
    evaluator: Option<Py<PyAny>>,
    mission: Option<String>,
) -> PyResult<(Scenario, String, String)> {
    use ftsmc_sim::analysis::missions::Mission;
    let mission = match mission.as_deref() {
        None => Mission::Steps,
        Some(name) => Mission::from_name(name).ok_or_else(|| {
            value_error(format!("mission = {name:?} is invalid (expected one of {})", Mission::names_joined()))
        })?,
    };
    let base = ftsmc_sim::tune::mission_base(&scenario.inner, mission).map_err(|e| value_error(chain_message(&e)))?;
    crate::check_controllers("controller", std::slice::from_ref(&controller))?;
    if threads == Some(0) {
        return Err(value_error("threads must be at least 1"));
    }
    let settings = base.tune.clone().unwrap_or_default();
    ftsmc_sim::limits::check_batch(&base.flight_size(), budget.saturating_add(2 * settings.validation_runs), 1)
        .map_err(|e| value_error(chain_message(&e)))?;
    if let Some(n) = threads {
        ftsmc_sim::limits::check_threads(&base.limits, n).map_err(|e| value_error(chain_message(&e)))?;
    }
    let options = ftsmc_sim::tune::TuneOptions { controller, budget, seed: seed.unwrap_or(base.seed) };
    // A built-in scenario to extend: the one named, else the scenario's own
    // name when it is one; otherwise the file holds every key.
    // (the name given, not the mission's `<name>-<mission>`).
    let extends = extends.or_else(|| Some(scenario.inner.name.clone()));
    let result = py.detach(move || {
        let mut builder = rayon::ThreadPoolBuilder::new();
        if let Some(t) = threads {
            builder = builder.num_threads(t);
        }
        let pool = builder.build().map_err(|e| format!("cannot start the thread pool: {e}"))?;
        match &evaluator {
            None => pool.install(|| ftsmc_sim::tune::tune(&base, &options, &|_| {})),
            Some(f) => {
                let remote = |s: &[ftsmc_sim::Scenario], i: &[u64]| call_evaluator(f, s, i);
                ftsmc_sim::tune::tune_with(&base, &options, &remote)
            }
        }
    });
    let result = result.map_err(value_error)?;
    let text = ftsmc_sim::tune::tuned_toml(&result, extends.as_deref(), "ftsmc.tune (Python)").map_err(value_error)?;
    let names: Vec<&str> = result.space.dims.iter().map(|d| d.name.as_str()).collect();
    let summary = serde_json::json!({
        "controller": result.controller,
        "parameters": names,
        "best": result.best(),
        "improved": result.improved,
        "improved_reason": result.improved_reason,
        "start_cost": result.history[0].cost,
        "training": result.training,
        "held_out": result.held_out,
        "training_flights": result.training_flights,
        "race_flights": result.race_flights,
        "held_out_flights": result.held_out_flights,
        "generations": result.generations,
        "race": result.race,
        "history": result.history,
    });
    let json = serde_json::to_string(&summary).map_err(value_error)?;
    Ok((Scenario { inner: result.tuned }, text, json))
}
