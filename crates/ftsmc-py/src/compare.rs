//! `ftsmc._ftsmc.compare_native` and `stats_intervals`: `ftsmc compare`
//! (`ftsmc_sim::batch::compare`, docs/statistics.md) and the interval rows
//! of `ftsmc montecarlo`'s summary for Python, flattened into columns that
//! `python/ftsmc/__init__.py` turns into pandas DataFrames.

use std::path::Path;

use ftsmc_sim::batch::compare::{compare, Contestant, Plan};
use ftsmc_sim::batch::verdicts::{intervals, Intervals, Outcomes, PairVerdict};
use ftsmc_sim::stats::paired::PairedMetric;
use ftsmc_sim::stats::Interval;
use pyo3::prelude::*;

use crate::flight::runs_columns;
use crate::scenario::{chain_message, Scenario};
use crate::value_error;

/// One contestant's [`Intervals`] as `(column, value)` pairs: `runs`,
/// `successes`, then `<rate>`, `<rate>_lo`, `<rate>_hi` for `success`,
/// `completed`, `crashed`, `diverged` (fractions), and `rms_median`,
/// `rms_p95`, `rms_mean` (m; NaN without a completed run; an upper bound
/// the runs cannot give is `inf`).
fn interval_row(i: &Intervals) -> Vec<(String, f64)> {
    let mut row = vec![("runs".to_string(), i.runs as f64), ("successes".to_string(), i.successes as f64)];
    let nan = Interval { estimate: f64::NAN, lo: f64::NAN, hi: f64::NAN };
    let parts = [
        ("success", Some(i.success_rate)),
        ("completed", Some(i.completed_rate)),
        ("crashed", Some(i.crashed_rate)),
        ("diverged", Some(i.diverged_rate)),
        ("rms_median", i.rms_median),
        ("rms_p95", i.rms_p95),
        ("rms_mean", i.rms_mean),
    ];
    for (name, v) in parts {
        let v = v.unwrap_or(nan);
        row.push((name.to_string(), v.estimate));
        row.push((format!("{name}_lo"), v.lo));
        row.push((format!("{name}_hi"), v.hi));
    }
    row
}

/// One verdict: `(a, b, metric, verdict)` and `(pairs, effect, effect_lo,
/// effect_hi, p, p_holm)`.
type VerdictRow = ((String, String, String, String), (u64, f64, f64, f64, f64, f64));

fn verdict_row(v: &PairVerdict) -> VerdictRow {
    let metric = match v.test.metric {
        PairedMetric::Success => "success",
        PairedMetric::Error => "rms_position_error",
    };
    let e = v.test.effect;
    (
        (v.a.clone(), v.b.clone(), metric.to_string(), v.sentence()),
        (v.test.pairs as u64, e.estimate, e.lo, e.hi, v.test.p, v.p_holm),
    )
}

/// What `compare_native` returns: the runs' columns `(names, columns)`,
/// the contestants' names and interval rows, the verdict rows, the runs
/// flown per contestant and whether every pair was decided.
type Compared<'py> =
    ((Vec<String>, Vec<Bound<'py, PyAny>>), Vec<String>, Vec<Vec<(String, f64)>>, Vec<VerdictRow>, u64, bool);

/// `ftsmc compare` on `scenario`: `contestants` are built-in controller
/// names, scenario files (their controller section) or `Scenario` objects.
/// `runs` runs each, or with `until_decided` batches of `batch` runs until
/// every pair is decided or `max_runs` is reached (alpha spending). Same
/// checks, draws, rows and verdicts as the command; flown with the GIL
/// released on `threads` workers (default: all cores).
#[pyfunction]
#[pyo3(signature = (scenario, contestants, runs, until_decided, batch, max_runs, confidence, seed=None, threads=None, allow_other_vehicle=false, progress=None))]
// The arguments are Python's keyword arguments, one each.
#[allow(clippy::too_many_arguments)]
pub fn compare_native<'py>(
    py: Python<'py>,
    scenario: PyRef<'_, Scenario>,
    contestants: Vec<Bound<'py, PyAny>>,
    runs: u64,
    until_decided: bool,
    batch: u64,
    max_runs: u64,
    confidence: f64,
    seed: Option<u64>,
    threads: Option<usize>,
    allow_other_vehicle: bool,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Compared<'py>> {
    let mut base = scenario.inner.clone();
    base.seed = seed.unwrap_or(base.seed);
    ftsmc_sim::stats::check_confidence(confidence).map_err(|e| value_error(format!("confidence: {e}")))?;
    // The names as given (a `Scenario` by its name), refused when the list
    // or a name is empty, as the CLI's `-c`; the unknown ones below, since a
    // contestant may also be a file.
    let given: Vec<String> = contestants
        .iter()
        .map(|c| {
            c.extract::<PyRef<'_, Scenario>>()
                .map_or_else(|_| c.extract::<String>().unwrap_or_default(), |s| s.inner.name.clone())
        })
        .collect();
    ftsmc_sim::registry::ControllerList { argument: "contestants", names: &given }.check().map_err(value_error)?;
    let mut list: Vec<Contestant> = Vec::new();
    for c in &contestants {
        let contestant = if let Ok(file) = c.extract::<PyRef<'_, Scenario>>() {
            Contestant::from_file(&base, &file.inner.name, &file.inner, allow_other_vehicle).map_err(value_error)?
        } else if let Ok(name) = c.extract::<String>() {
            if ftsmc_sim::registry::check_name(&name).is_ok() {
                Contestant::built_in(&base, &name)
            } else if Path::new(&name).is_file() {
                let loaded = ftsmc_sim::Scenario::load_with_warnings(Path::new(&name), &[])
                    .map_err(|e| value_error(chain_message(&e)))?;
                let short = Path::new(&name).file_name().map_or(name.clone(), |f| f.to_string_lossy().into_owned());
                Contestant::from_file(&base, &short, &loaded.scenario, allow_other_vehicle).map_err(value_error)?
            } else {
                let known = ftsmc_sim::registry::check_name("").err().unwrap_or_default();
                return Err(value_error(format!(
                    "unknown contestant `{name}`: neither a controller (known: {known}) nor an existing file"
                )));
            }
        } else {
            return Err(value_error(format!(
                "a contestant is a controller name, a scenario file's path or a Scenario, not a {}",
                c.get_type().name()?
            )));
        };
        if list.iter().any(|o| o.name == contestant.name) {
            return Err(value_error(format!("contestant `{}` is given twice", contestant.name)));
        }
        list.push(contestant);
    }
    if list.len() < 2 {
        return Err(value_error(format!("{} contestant(s): a comparison needs at least two", list.len())));
    }
    let plan = if until_decided { Plan::UntilDecided { batch, max_runs } } else { Plan::Fixed { runs } };
    let most = if until_decided { max_runs } else { runs };
    if most < 1 {
        return Err(value_error("runs (and max_runs) must be at least 1"));
    }
    ftsmc_sim::limits::check_batch(&base.flight_size(), most, list.len())
        .map_err(|e| value_error(chain_message(&e)))?;
    for c in &list {
        ftsmc_sim::batch::gains_fit::check(&c.scenario, std::slice::from_ref(&c.controller))
            .map_err(|e| value_error(e.to_string()))?;
    }
    if let Some(n) = threads {
        if n == 0 {
            return Err(value_error("threads must be at least 1"));
        }
        ftsmc_sim::limits::check_threads(&base.limits, n).map_err(|e| value_error(chain_message(&e)))?;
    }
    let spec = base.montecarlo.clone().unwrap_or_default();
    let total = most.saturating_mul(list.len() as u64).saturating_mul(ftsmc_sim::run::planned_steps(&base));
    // A comparison is not cancellable: Ctrl-C is raised once it has finished.
    let result = crate::progress::with_progress(py, total, progress.as_ref(), |_cancel, tick| {
        let mut builder = rayon::ThreadPoolBuilder::new();
        if let Some(t) = threads {
            builder = builder.num_threads(t);
        }
        let pool = builder.build().map_err(|e| format!("cannot start the thread pool: {e}"))?;
        let lanes = ftsmc_sim::batch::montecarlo::DEFAULT_LANES;
        pool.install(|| compare(&list, &spec, base.seed, plan, confidence, lanes, tick))
    })?
    .map_err(value_error)?;
    let (column_names, columns) = runs_columns(py, &result.rows)?;
    let names = result.intervals.iter().map(|(n, _)| n.clone()).collect();
    let rows = result.intervals.iter().map(|(_, i)| interval_row(i)).collect();
    let verdicts = result.verdicts.iter().map(verdict_row).collect();
    Ok(((column_names, columns), names, rows, verdicts, result.runs, result.all_decided))
}

/// The interval row of one controller's runs (the numbers of `ftsmc
/// montecarlo`'s summary): `success`, `completed`, `crashed` per run and the
/// RMS position error (m) of each run (ignored where not completed).
#[pyfunction]
pub fn stats_intervals(
    success: Vec<bool>,
    completed: Vec<bool>,
    crashed: Vec<bool>,
    rms: Vec<f64>,
    confidence: f64,
) -> PyResult<Vec<(String, f64)>> {
    let n = success.len();
    if completed.len() != n || crashed.len() != n || rms.len() != n {
        return Err(value_error("success, completed, crashed and rms must have one entry per run"));
    }
    let mut o = Outcomes::default();
    for i in 0..n {
        o.push(success[i], completed[i], crashed[i], rms[i]);
    }
    let i = intervals(&o, confidence).map_err(|e| value_error(format!("confidence: {e}")))?;
    Ok(interval_row(&i))
}
