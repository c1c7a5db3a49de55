//! Flights from Python: one run (a registry controller with the GIL
//! released, or a Python controller), and Monte Carlo batches whose rows
//! are `runs.csv`'s.

use ftsmc_sim::batch::montecarlo::{run_batch, BatchOptions, McRun};
use ftsmc_sim::batch::runs_table::{runs_table, Column};
use ftsmc_sim::run::{RunOptions, RunOutput};
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyList};

use crate::controller::{build, PythonController};
use crate::scenario::{chain_message, Scenario};
use crate::value_error;

/// One flight's results (`ftsmc.Run` wraps it).
#[pyclass(module = "ftsmc._ftsmc", name = "RunData", frozen)]
pub struct RunData {
    out: RunOutput,
}

#[pymethods]
impl RunData {
    /// Controller name as flown.
    #[getter]
    fn controller(&self) -> String {
        self.out.controller.clone()
    }

    /// Scenario name.
    #[getter]
    fn scenario(&self) -> String {
        self.out.scenario.clone()
    }

    /// Control steps executed.
    #[getter]
    fn steps(&self) -> u64 {
        self.out.steps
    }

    /// The exit status as JSON (`{"status": "completed"}`, or with
    /// `time` and the reason), as in `summary.json`'s `exit_status`.
    fn exit_json(&self) -> PyResult<String> {
        serde_json::to_string(&self.out.exit).map_err(value_error)
    }

    /// The exit as text (`completed`, `diverged at …`), as `summary.json`'s `exit`.
    fn exit_text(&self) -> String {
        self.out.exit.to_string()
    }

    /// The run's entry of `summary.json` as JSON text.
    fn metrics_json(&self) -> PyResult<String> {
        serde_json::to_string(&ftsmc_sim::run::summary::run_json(&self.out)).map_err(value_error)
    }

    /// The time-series column names (the CSV header).
    fn column_names(&self) -> Vec<String> {
        self.out.recording.names.clone()
    }

    /// The time-series columns, as 1-D float64 arrays (copies).
    fn columns<'py>(&self, py: Python<'py>) -> Vec<Bound<'py, PyArray1<f64>>> {
        self.out.recording.columns.iter().map(|c| PyArray1::from_slice(py, c)).collect()
    }

    /// The time series as the CLI writes it to `<controller>.csv`.
    fn csv<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
        let bytes = py.detach(|| self.out.recording.to_csv());
        PyBytes::new(py, &bytes)
    }
}

/// Fly registry controller `controller` through `scenario` with the GIL
/// released; the same checks and options as `ftsmc run` (cost limit,
/// recording on).
#[pyfunction]
pub fn simulate_native(py: Python<'_>, scenario: PyRef<'_, Scenario>, controller: &str) -> PyResult<RunData> {
    let scenario = scenario.inner.clone();
    build(controller, &scenario)?;
    scenario.check_cost(1).map_err(|e| value_error(chain_message(&e)))?;
    let name = controller.to_string();
    let out = with_ctrl_c(py, |cancel| {
        ftsmc_sim::registry::run(&name, &scenario, RunOptions { cancel: Some(cancel), ..Default::default() })
    })?;
    Ok(RunData { out: out.map_err(value_error)? })
}

/// Run `work` on a worker thread without the GIL while this thread checks
/// for signals every [`crate::progress::SIGNAL_POLL`] ([`Python::check_signals`]): on Ctrl-C
/// the cancellation flag is set, the worker stops (within
/// [`ftsmc_sim::run::PROGRESS_EVERY`] control steps), and the signal's
/// exception (`KeyboardInterrupt`) is raised.
fn with_ctrl_c<T: Send>(py: Python<'_>, work: impl FnOnce(&std::sync::atomic::AtomicBool) -> T + Send) -> PyResult<T> {
    use std::sync::atomic::{AtomicBool, Ordering};
    let cancel = AtomicBool::new(false);
    std::thread::scope(|scope| {
        let cancel = &cancel;
        let worker = scope.spawn(move || work(cancel));
        let mut interrupted = None;
        while !worker.is_finished() {
            py.detach(|| std::thread::sleep(crate::progress::SIGNAL_POLL));
            if let Err(e) = py.check_signals() {
                cancel.store(true, Ordering::Relaxed);
                interrupted = Some(e);
                break;
            }
        }
        let result = py.detach(|| worker.join());
        if let Some(e) = interrupted {
            return Err(e);
        }
        result.map_err(|_| pyo3::exceptions::PyRuntimeError::new_err("the flight thread panicked"))
    })
}

/// Fly the Python object `controller` (see [`PythonController`]) through
/// `scenario`; `state_cls(position, attitude, velocity, angular_rate)` and
/// `reference_cls(position, velocity, acceleration, yaw, yaw_rate,
/// yaw_acceleration)` build its arguments. The run's controller name is `name`.
#[pyfunction]
pub fn simulate_python(
    scenario: PyRef<'_, Scenario>,
    controller: Bound<'_, PyAny>,
    state_cls: Bound<'_, PyAny>,
    reference_cls: Bound<'_, PyAny>,
    name: String,
) -> PyResult<RunData> {
    scenario.inner.check_cost(1).map_err(|e| value_error(chain_message(&e)))?;
    let mut flyer = PythonController::new(controller, state_cls, reference_cls);
    let out = ftsmc_sim::run::Flight::new(scenario.inner.clone(), &mut flyer, RunOptions::default()).named(name).run();
    if let Some(err) = flyer.error.take() {
        return Err(err);
    }
    Ok(RunData { out })
}

/// A Monte Carlo batch as `runs.csv`'s columns: `(names, columns)`, each
/// column a numpy array (`uint64` integers, `float64` numbers with NaN for
/// an empty cell, `bool`) or a list of str. Same checks, seed handling and
/// rows as `ftsmc montecarlo`; flown with the GIL released on a pool of
/// `threads` workers (default: all cores); the rows do not depend on it.
/// `run_range = (start, end)` flies only the runs with index in
/// `start..end` of the `runs`-run batch (a shard, for Dask tasks): their
/// rows are bit-identical to those rows of the whole batch.
/// `progress(done, total)`, when given, is called about every 0.2 s with
/// the control steps flown and planned (crate::progress).
#[pyfunction]
#[pyo3(signature = (scenario, runs, seed=None, controllers=None, threads=None, run_range=None, progress=None))]
// The arguments are Python's keyword arguments, one each.
#[allow(clippy::too_many_arguments)]
pub fn montecarlo_columns<'py>(
    py: Python<'py>,
    scenario: PyRef<'_, Scenario>,
    runs: u64,
    seed: Option<u64>,
    controllers: Option<Vec<String>>,
    threads: Option<usize>,
    run_range: Option<(u64, u64)>,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<(Vec<String>, Vec<Bound<'py, PyAny>>)> {
    let mut scenario = scenario.inner.clone();
    let names = controllers.unwrap_or_else(|| scenario.controllers.clone());
    crate::check_controllers("controllers", &names)?;
    if runs < 1 {
        return Err(value_error("runs must be at least 1"));
    }
    if threads == Some(0) {
        return Err(value_error("threads must be at least 1"));
    }
    let (start, end) = run_range.unwrap_or((0, runs));
    if start >= end || end > runs {
        return Err(value_error(format!("run_range ({start}, {end}) must satisfy 0 <= start < end <= runs ({runs})")));
    }
    ftsmc_sim::limits::check_batch(&scenario.flight_size(), end - start, names.len())
        .map_err(|e| value_error(chain_message(&e)))?;
    ftsmc_sim::batch::gains_fit::check(&scenario, &names).map_err(|e| value_error(e.to_string()))?;
    if let Some(n) = threads {
        ftsmc_sim::limits::check_threads(&scenario.limits, n).map_err(|e| value_error(chain_message(&e)))?;
    }
    scenario.seed = seed.unwrap_or(scenario.seed);
    scenario.controllers = names;
    let spec = scenario.montecarlo.clone().unwrap_or_default();
    let total = (end - start)
        .saturating_mul(scenario.controllers.len() as u64)
        .saturating_mul(ftsmc_sim::run::planned_steps(&scenario));

    let rows = crate::progress::with_progress(py, total, progress.as_ref(), move |cancel, tick| {
        let mut builder = rayon::ThreadPoolBuilder::new();
        if let Some(t) = threads {
            builder = builder.num_threads(t);
        }
        let pool = builder.build().map_err(|e| format!("cannot start the thread pool: {e}"))?;
        pool.install(|| {
            run_batch(
                &scenario,
                &spec,
                &scenario.controllers,
                BatchOptions {
                    runs: start..end,
                    progress: Some(tick),
                    cancel: Some(cancel),
                    ..BatchOptions::new(0, scenario.seed)
                },
            )
            .map_err(|known| format!("unknown controller (known: {known})"))
        })
    })?;
    runs_columns(py, &rows.map_err(value_error)?)
}

/// The Monte Carlo rows as `runs.csv`'s columns for a DataFrame: numbers as
/// NumPy arrays (an empty number NaN), text as a list of `str` or `None`
/// for an empty cell. Shared by `montecarlo` and `compare`.
pub(crate) fn runs_columns<'py>(py: Python<'py>, rows: &[McRun]) -> PyResult<(Vec<String>, Vec<Bound<'py, PyAny>>)> {
    let table = runs_table(rows);
    let mut columns = Vec::with_capacity(table.columns.len());
    for column in table.columns {
        columns.push(match column {
            Column::Integer(v) => PyArray1::from_vec(py, v).into_any(),
            Column::Number(v) => PyArray1::from_iter(py, v.into_iter().map(|x| x.unwrap_or(f64::NAN))).into_any(),
            Column::Boolean(v) => PyArray1::from_vec(py, v).into_any(),
            Column::Text(v) => PyList::new(py, v.into_iter().map(|s| (!s.is_empty()).then_some(s)))?.into_any(),
        });
    }
    Ok((table.names, columns))
}
