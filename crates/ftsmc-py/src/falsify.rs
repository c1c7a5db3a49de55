//! `ftsmc.falsify(...)` and `ftsmc.failure_probability(...)`: the
//! `ftsmc falsify` search and the cross-entropy estimate from Python
//! ([`ftsmc_sim::falsify`], the same code and results as the commands).

use pyo3::prelude::*;
use serde_json::json;

use ftsmc_sim::falsify::rare::cross_entropy;
use ftsmc_sim::falsify::search::{cmaes, random, History};
use ftsmc_sim::falsify::{Problem, RareProblem};

use crate::scenario::{chain_message, scenario_toml, Scenario};
use crate::value_error;

fn pool(threads: Option<usize>) -> PyResult<rayon::ThreadPool> {
    if threads == Some(0) {
        return Err(value_error("threads must be at least 1"));
    }
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(t) = threads {
        builder = builder.num_threads(t);
    }
    builder.build().map_err(|e| value_error(format!("cannot start the thread pool: {e}")))
}

fn problem(scenario: &ftsmc_sim::Scenario, controller: &str, budget: u64) -> PyResult<Problem> {
    use ftsmc_sim::scenario::falsify_section::MAX_BUDGET;
    crate::check_controllers("controller", &[controller.to_string()])?;
    if !(1..=MAX_BUDGET).contains(&budget) {
        return Err(value_error(format!("budget = {budget}: expected 1 to {MAX_BUDGET} flights")));
    }
    let p = Problem::new(scenario, controller).map_err(|e| value_error(e.to_string()))?;
    ftsmc_sim::limits::check_batch(&scenario.flight_size(), budget.saturating_mul(2), 1)
        .map_err(|e| value_error(chain_message(&e)))?;
    Ok(p)
}

fn history_json(p: &Problem, h: &History) -> serde_json::Value {
    let rows: Vec<serde_json::Value> = h
        .evaluations
        .iter()
        .map(|e| json!({"flight": e.flight, "restart": e.restart, "margin": e.margin, "values": p.values(&e.point)}))
        .collect();
    json!({
        "lowest_margin": h.best().map(|e| e.margin),
        "lowest_flight": h.best().map(|e| e.flight),
        "first_violation_flight": h.first_violation().map(|e| e.flight),
        "violations": h.violations(),
        "history": rows,
    })
}

/// The search of `ftsmc falsify` (CMA-ES with restarts and uniform random
/// draws, `budget` flights each, search seed `seed`, default the
/// scenario's) as JSON text: `parameters`, `falsify`, `random` (lowest
/// margin, its flight, the first violation, every flight) and `worst_toml`,
/// the worst case as a scenario file.
#[pyfunction]
#[pyo3(signature = (scenario, controller, budget=ftsmc_sim::defaults::FALSIFY_BUDGET, seed=None, threads=None))]
pub fn falsify_native(
    py: Python<'_>,
    scenario: PyRef<'_, Scenario>,
    controller: String,
    budget: u64,
    seed: Option<u64>,
    threads: Option<usize>,
) -> PyResult<String> {
    let base = scenario.inner.clone();
    let p = problem(&base, &controller, budget)?;
    let seed = seed.unwrap_or(base.seed);
    let pool = pool(threads)?;
    let (search, uniform) =
        py.detach(|| pool.install(|| (cmaes(&p, budget, seed, Some(p.nominal_point())), random(&p, budget, seed))));
    let worst = search.best().map(|b| p.scenario(&p.values(&b.point)));
    let worst_toml = worst.as_ref().map(scenario_toml).transpose().map_err(value_error)?;
    let out = json!({
        "scenario": base.name,
        "controller": controller,
        "budget": budget,
        "search_seed": seed,
        "turbulence_seed": base.seed,
        "parameters": p.params.iter().map(|q| q.name.clone()).collect::<Vec<_>>(),
        "falsify": history_json(&p, &search),
        "random": history_json(&p, &uniform),
        "worst_toml": worst_toml,
    });
    Ok(out.to_string())
}

/// `ftsmc failure-probability`: `P(margin < 0)` by cross-entropy
/// importance sampling with `budget` flights, as JSON text (`p`, `lo`,
/// `hi`, `confidence`, `flights`, `failures`, `ess`, `plain_mc_equivalent`,
/// `one_sided`, `reliable`, `levels`).
#[pyfunction]
#[pyo3(signature = (scenario, controller, budget=ftsmc_sim::defaults::FAILURE_PROBABILITY_BUDGET, confidence=ftsmc_sim::defaults::CONFIDENCE, seed=None, threads=None))]
pub fn failure_probability_native(
    py: Python<'_>,
    scenario: PyRef<'_, Scenario>,
    controller: String,
    budget: u64,
    confidence: f64,
    seed: Option<u64>,
    threads: Option<usize>,
) -> PyResult<String> {
    if !(confidence > 0.0 && confidence < 1.0) {
        return Err(value_error(format!("confidence = {confidence}: expected a level strictly between 0 and 1")));
    }
    if budget < 20 {
        return Err(value_error(format!("budget = {budget}: cross-entropy sampling needs at least 20 flights")));
    }
    let base = scenario.inner.clone();
    let rare = RareProblem { problem: problem(&base, &controller, budget)?, master: base.seed };
    let seed = seed.unwrap_or(base.seed);
    let pool = pool(threads)?;
    let e = py.detach(|| pool.install(|| cross_entropy(&rare, budget, seed, confidence)));
    serde_json::to_string(&e).map_err(value_error)
}
