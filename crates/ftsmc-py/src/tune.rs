//! `ftsmc.tune(...)`: the `ftsmc tune` search from Python
//! ([`ftsmc_sim::tune::tune`], the same code and results as the command).

use pyo3::prelude::*;

use crate::scenario::{chain_message, Scenario};
use crate::value_error;

/// Tune `controller` on `scenario` with a `budget` of training flights and
/// `seed` (default: the scenario's), on `threads` workers (default: all
/// cores; the result does not depend on it), with the GIL released.
/// Returns `(tuned scenario, tuned TOML text extending `extends`, JSON
/// summary)`; the JSON has the parameters, every candidate
/// (`history`) and the training and held-out statistics.
#[pyfunction]
#[pyo3(signature = (scenario, controller, budget=2000, seed=None, threads=None, extends=None))]
pub fn tune_native(
    py: Python<'_>,
    scenario: PyRef<'_, Scenario>,
    controller: String,
    budget: u64,
    seed: Option<u64>,
    threads: Option<usize>,
    extends: Option<String>,
) -> PyResult<(Scenario, String, String)> {
    let base = scenario.inner.clone();
    ftsmc_sim::registry::check_name(&controller)
        .map_err(|known| value_error(format!("unknown controller `{controller}` (known: {known})")))?;
    if threads == Some(0) {
        return Err(value_error("threads must be at least 1"));
    }
    let settings = base.tune.clone().unwrap_or_default();
    ftsmc_sim::limits::check_batch(&base.flight_size(), budget + 2 * settings.validation_runs, 1)
        .map_err(|e| value_error(chain_message(&e)))?;
    if let Some(n) = threads {
        ftsmc_sim::limits::check_threads(&base.limits, n).map_err(|e| value_error(chain_message(&e)))?;
    }
    let options = ftsmc_sim::tune::TuneOptions { controller, budget, seed: seed.unwrap_or(base.seed) };
    let extends = extends.unwrap_or_else(|| base.name.clone());
    let result = py.detach(move || {
        let mut builder = rayon::ThreadPoolBuilder::new();
        if let Some(t) = threads {
            builder = builder.num_threads(t);
        }
        let pool = builder.build().map_err(|e| format!("cannot start the thread pool: {e}"))?;
        pool.install(|| ftsmc_sim::tune::tune(&base, &options, &|_| {}))
    });
    let result = result.map_err(value_error)?;
    let text = ftsmc_sim::tune::tuned_toml(&result, &extends, "ftsmc.tune (Python)").map_err(value_error)?;
    let names: Vec<&str> = result.space.dims.iter().map(|d| d.name.as_str()).collect();
    let summary = serde_json::json!({
        "controller": result.controller,
        "parameters": names,
        "best": result.best(),
        "start_cost": result.history[0].cost,
        "training": result.training,
        "held_out": result.held_out,
        "training_flights": result.training_flights,
        "held_out_flights": result.held_out_flights,
        "history": result.history,
    });
    let json = serde_json::to_string(&summary).map_err(value_error)?;
    Ok((Scenario { inner: result.tuned }, text, json))
}
