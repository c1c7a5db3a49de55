//! `ftsmc.Scenario`: a validated scenario, loaded by the same resolver as
//! the CLI (built-in name, file, or TOML text), with dotted-key overrides
//! applied at TOML level and re-validated.

use std::path::Path;

use ftsmc_sim::scenario::resolve::{self, Loaded};
use pyo3::exceptions::PyUserWarning;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

use crate::value_error;

/// The resolved scenario as TOML: every field, every default filled in.
/// The one place the package serializes a scenario (the CLI's
/// `scenario.toml` uses the same `Scenario::to_toml`).
pub(crate) fn scenario_toml(scenario: &ftsmc_sim::Scenario) -> Result<String, String> {
    scenario.to_toml().map_err(|e| format!("cannot write the scenario as TOML: {e}"))
}

/// An error and its sources, `a: b: c`, as the CLI prints them (`{:#}`).
pub(crate) fn chain_message(err: &dyn std::error::Error) -> String {
    let mut text = err.to_string();
    let mut source = err.source();
    while let Some(s) = source {
        text.push_str(": ");
        text.push_str(&s.to_string());
        source = s.source();
    }
    text
}

/// A validated scenario (see docs/scenarios.md for the file format and
/// docs/python.md for this class).
#[pyclass(module = "ftsmc", name = "Scenario", frozen)]
#[derive(Clone)]
pub struct Scenario {
    pub(crate) inner: ftsmc_sim::Scenario,
}

/// Issue the loader's unit-slip warnings as Python `UserWarning`s (the CLI
/// prints them as `warning: …` lines).
pub(crate) fn warn_all(py: Python<'_>, loaded: Loaded) -> PyResult<Scenario> {
    for w in &loaded.warnings {
        PyErr::warn(py, &py.get_type::<PyUserWarning>(), &std::ffi::CString::new(w.as_str())?, 2)?;
    }
    Ok(Scenario { inner: loaded.scenario })
}

#[pymethods]
impl Scenario {
    /// A built-in scenario by name (`.toml` optional): any name `ftsmc list`
    /// shows, e.g. `paper-scenario-1`, `realistic-calm-2`; the error for an
    /// unknown name lists them all.
    #[staticmethod]
    fn builtin(py: Python<'_>, name: &str) -> PyResult<Self> {
        let Some((file, text)) = resolve::built_in(name) else {
            return Err(value_error(format!(
                "no built-in scenario `{name}` (built-in: {})",
                resolve::built_in_names().collect::<Vec<_>>().join(", ")
            )));
        };
        let loaded = ftsmc_sim::Scenario::from_toml_str_with_warnings(text, file, &[])
            .map_err(|e| value_error(chain_message(&e)))?;
        warn_all(py, loaded)
    }

    /// The names of every built-in scenario, in `ftsmc list` order (the
    /// simulator's one list, `ftsmc_sim::scenario::BUILT_IN_SCENARIOS`).
    #[staticmethod]
    fn builtin_names() -> Vec<&'static str> {
        resolve::built_in_names().collect()
    }

    /// Read, resolve (`extends`) and validate a scenario file.
    #[staticmethod]
    fn from_file(py: Python<'_>, path: std::path::PathBuf) -> PyResult<Self> {
        let loaded = ftsmc_sim::Scenario::load_with_warnings(Path::new(&path), &[])
            .map_err(|e| value_error(chain_message(&e)))?;
        warn_all(py, loaded)
    }

    /// Parse and validate TOML text; `path` names it in error messages and
    /// relative `extends` paths resolve against its directory.
    #[staticmethod]
    #[pyo3(signature = (text, path = "<string>"))]
    fn from_toml(py: Python<'_>, text: &str, path: &str) -> PyResult<Self> {
        // The CLI's size limit on a scenario file, before the text is parsed.
        ftsmc_sim::limits::check_file_size(&ftsmc_sim::limits::Limits::default(), text.len() as u64)
            .map_err(|e| value_error(format!("{}: {e}", ftsmc_sim::scenario::show_str(path))))?;
        let loaded = ftsmc_sim::Scenario::from_toml_str_with_warnings(text, path, &[])
            .map_err(|e| value_error(chain_message(&e)))?;
        warn_all(py, loaded)
    }

    /// The resolved scenario as TOML text (what the CLI writes as
    /// `scenario.toml`; `Scenario.from_toml` of it gives this scenario back).
    fn to_toml(&self) -> PyResult<String> {
        scenario_toml(&self.inner).map_err(value_error)
    }

    /// A new scenario with dotted keys set (`{"payload.mass": 0.5,
    /// "ftaftsmc.z.lambda2": 0.8}`), validated as a file would be: the
    /// resolved TOML of this scenario with each key set (missing tables
    /// created), loaded again. Values: bool, int, float, str, lists and
    /// dicts of them (a dict is a TOML table, e.g. a whole signal).
    fn with_overrides(&self, py: Python<'_>, overrides: &Bound<'_, PyDict>) -> PyResult<Self> {
        let mut sets = Vec::new();
        let mut budget = MAX_OVERRIDE_VALUES;
        for (key, value) in overrides.iter() {
            let key: String = key.extract().map_err(|_| value_error("override keys must be strings"))?;
            // Error messages quote at most the first characters of a key.
            if key.chars().count() > MAX_KEY_CHARS {
                return Err(value_error(format!(
                    "override `{}…`: a dotted key is at most {MAX_KEY_CHARS} characters and {MAX_KEY_PARTS} parts",
                    key.chars().take(40).collect::<String>()
                )));
            }
            let value =
                to_toml_value(&value, &mut budget).map_err(|m| value_error(format!("override `{key}`: {m}")))?;
            sets.push((key, value));
        }
        // The simulator's one implementation, also behind the CLI's `--set`.
        let loaded = self.inner.with_overrides(&sets).map_err(|e| value_error(chain_message(&e)))?;
        warn_all(py, loaded)
    }

    /// Scenario name (used in result paths).
    #[getter]
    fn name(&self) -> String {
        self.inner.name.clone()
    }

    /// The mission its gains were tuned for (`[tune] mission` of a tuned
    /// file: `hover`, `figure-eight`, `waypoints`, or `steps`); None when
    /// the file states none (the scenario's own reference).
    #[getter]
    fn tune_mission(&self) -> Option<String> {
        self.inner.tune.as_ref().and_then(|t| t.mission.clone())
    }

    /// Free-text description.
    #[getter]
    fn description(&self) -> String {
        self.inner.description.clone()
    }

    /// Simulated time, s.
    #[getter]
    fn duration(&self) -> f64 {
        self.inner.duration
    }

    /// Master seed of every random stream.
    #[getter]
    fn seed(&self) -> u64 {
        self.inner.seed
    }

    /// The scenario's controller list (registry names).
    #[getter]
    fn controllers(&self) -> Vec<String> {
        self.inner.controllers.clone()
    }

    /// Control period 1/`simulation.control_rate`, s.
    #[getter]
    fn control_period(&self) -> f64 {
        self.inner.control_period()
    }

    /// True when the scenario has a `[montecarlo]` section.
    #[getter]
    fn has_montecarlo(&self) -> bool {
        self.inner.montecarlo.is_some()
    }

    fn __eq__(&self, other: &Self) -> bool {
        self.inner == other.inner
    }

    fn __repr__(&self) -> String {
        format!(
            "Scenario(name={:?}, duration={}, controllers={:?})",
            self.inner.name, self.inner.duration, self.inner.controllers
        )
    }
}

/// A Python value as a TOML value.
/// Deepest nesting of an override value (dicts and lists); a scenario's
/// deepest key is a handful of levels down.
pub const MAX_OVERRIDE_DEPTH: usize = 32;
/// Most values (dict entries, list items, scalars) in all overrides of one call.
pub const MAX_OVERRIDE_VALUES: usize = 1_000_000;
pub use ftsmc_sim::scenario::overrides::{MAX_KEY_CHARS, MAX_KEY_PARTS};

/// [`to_toml_value`] within [`MAX_OVERRIDE_DEPTH`] and a budget of
/// [`MAX_OVERRIDE_VALUES`] values, so that a self-referencing or hugely
/// nested dict raises `ValueError` instead of exhausting the stack.
pub(crate) fn to_toml_value(value: &Bound<'_, PyAny>, budget: &mut usize) -> Result<toml::Value, String> {
    to_toml_value_at(value, 0, budget)
}

fn to_toml_value_at(value: &Bound<'_, PyAny>, depth: usize, budget: &mut usize) -> Result<toml::Value, String> {
    if depth > MAX_OVERRIDE_DEPTH {
        return Err(format!("nested deeper than {MAX_OVERRIDE_DEPTH} levels (a dict or list that contains itself?)"));
    }
    if *budget == 0 {
        return Err(format!("more than {MAX_OVERRIDE_VALUES} values in the overrides"));
    }
    *budget -= 1;
    if value.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(value.extract().map_err(|e: PyErr| e.to_string())?));
    }
    if value.is_instance_of::<PyInt>() {
        if let Ok(v) = value.extract::<i64>() {
            return Ok(toml::Value::Integer(v));
        }
        // A u64 beyond i64 (a seed >= 2^63): TOML has no such integer; the
        // seed reads it back from its decimal string.
        return value
            .extract::<u64>()
            .map(|v| toml::Value::String(v.to_string()))
            .map_err(|_| "an integer that does not fit 64 bits".to_string());
    }
    if value.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(value.extract().map_err(|e: PyErr| e.to_string())?));
    }
    if value.is_instance_of::<PyString>() {
        return Ok(toml::Value::String(value.extract().map_err(|e: PyErr| e.to_string())?));
    }
    if let Ok(dict) = value.cast::<PyDict>() {
        let mut table = toml::Table::new();
        for (k, v) in dict.iter() {
            let k: String = k.extract().map_err(|_| "table keys must be strings".to_string())?;
            table.insert(k, to_toml_value_at(&v, depth + 1, budget)?);
        }
        return Ok(toml::Value::Table(table));
    }
    if value.is_instance_of::<PyList>()
        || value.is_instance_of::<PyTuple>()
        || value.hasattr("__array__").unwrap_or(false)
    {
        let mut items = Vec::new();
        for item in value.try_iter().map_err(|e| e.to_string())? {
            items.push(to_toml_value_at(&item.map_err(|e| e.to_string())?, depth + 1, budget)?);
        }
        return Ok(toml::Value::Array(items));
    }
    // numpy scalars and other numbers: through float().
    if let Ok(x) = value.extract::<f64>() {
        return Ok(toml::Value::Float(x));
    }
    let type_name = value.get_type().name().map(|n| n.to_string()).unwrap_or_else(|_| "?".into());
    Err(format!(
        "a value of type {type_name} cannot be written to a scenario (use bool, int, float, str, list or dict)"
    ))
}
