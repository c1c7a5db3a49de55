//! `ftsmc._ftsmc`: the native module of the `ftsmc` Python package
//! (python/ftsmc). The Python layer (`python/ftsmc/__init__.py`) wraps it
//! in the documented API; this module stays small and typed by the
//! hand-written stub `python/ftsmc/_ftsmc.pyi`.
//!
//! Every flight goes through the same `ftsmc-sim` entry points as the
//! `ftsmc` command ([`ftsmc_sim::registry::run`], [`ftsmc_sim::run::simulate`],
//! [`ftsmc_sim::batch::montecarlo::run_batch`]), with the same checks, so a
//! result from Python equals the CLI's for the same scenario.

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

mod compare;
mod controller;
mod falsify;
mod flight;
mod gym;
mod kinematics;
mod logs;
mod progress;
mod scenario;
mod stats;
mod trajectory;
mod tune;

/// A `ValueError` carrying `message` (the text the CLI prints after `error: `).
pub(crate) fn value_error(message: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(message.to_string())
}

/// The library's [`ftsmc_sim::registry::ControllerList::check_known`] of
/// the controller `names` a Python function received as `argument`
/// (`controllers`, `controller`, `contestants`): an empty list, an empty
/// or blank name, or an unregistered one is a `ValueError` naming the
/// argument and the value — the same check, and words, as the CLI's `-c`.
pub(crate) fn check_controllers(argument: &str, names: &[String]) -> PyResult<()> {
    ftsmc_sim::registry::ControllerList { argument, names }.check_known().map_err(value_error)
}

/// [`check_controllers`] from Python, for the paths that do not reach the
/// native flight functions at once (a Dask batch is planned in Python first).
#[pyfunction]
#[pyo3(name = "check_controllers")]
fn check_controllers_py(argument: &str, names: Vec<String>) -> PyResult<()> {
    check_controllers(argument, &names)
}

/// The module `ftsmc._ftsmc`.
#[pymodule]
fn _ftsmc(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // The campaign defaults of `ftsmc_sim::defaults`, the one place they
    // are written (the wrappers and `python/tests/test_defaults.py` read them).
    let defaults = pyo3::types::PyDict::new(m.py());
    for (name, value) in ftsmc_sim::defaults::ALL {
        if name == "confidence" {
            defaults.set_item(name, value)?;
        } else {
            defaults.set_item(name, value as u64)?;
        }
    }
    m.add("DEFAULTS", defaults)?;
    m.add_class::<scenario::Scenario>()?;
    m.add_class::<controller::NativeController>()?;
    m.add_class::<flight::RunData>()?;
    m.add_class::<gym::GymBatch>()?;
    m.add_class::<trajectory::NativeTrajectory>()?;
    m.add_function(wrap_pyfunction!(trajectory::vehicle_arm_length, m)?)?;
    m.add_function(wrap_pyfunction!(flight::simulate_native, m)?)?;
    m.add_function(wrap_pyfunction!(flight::simulate_python, m)?)?;
    m.add_function(wrap_pyfunction!(flight::montecarlo_columns, m)?)?;
    m.add_function(wrap_pyfunction!(gym::gym_check_envs, m)?)?;
    m.add_function(wrap_pyfunction!(tune::tune_native, m)?)?;
    m.add_function(wrap_pyfunction!(falsify::falsify_native, m)?)?;
    m.add_function(wrap_pyfunction!(falsify::failure_probability_native, m)?)?;
    m.add_function(wrap_pyfunction!(tune::tune_evaluate, m)?)?;
    m.add_function(wrap_pyfunction!(kinematics::kinematics_euler_from_quaternion, m)?)?;
    m.add_function(wrap_pyfunction!(kinematics::kinematics_quaternion_from_euler, m)?)?;
    m.add_function(wrap_pyfunction!(kinematics::kinematics_euler_rates, m)?)?;
    m.add_function(wrap_pyfunction!(kinematics::kinematics_body_rates, m)?)?;
    m.add_function(wrap_pyfunction!(compare::compare_native, m)?)?;
    m.add_function(wrap_pyfunction!(compare::stats_intervals, m)?)?;
    m.add_function(wrap_pyfunction!(stats::stats_wilson, m)?)?;
    m.add_function(wrap_pyfunction!(stats::stats_clopper_pearson, m)?)?;
    m.add_function(wrap_pyfunction!(stats::stats_binomial_quantile, m)?)?;
    m.add_function(wrap_pyfunction!(stats::stats_mcnemar_exact, m)?)?;
    m.add_function(wrap_pyfunction!(stats::stats_wilcoxon, m)?)?;
    m.add_function(wrap_pyfunction!(logs::log_columns, m)?)?;
    m.add_function(wrap_pyfunction!(logs::log_identify, m)?)?;
    m.add_function(wrap_pyfunction!(logs::log_validate, m)?)?;
    m.add_function(wrap_pyfunction!(logs::log_synthetic, m)?)?;
    m.add_function(wrap_pyfunction!(controller_names, m)?)?;
    m.add_function(wrap_pyfunction!(check_controllers_py, m)?)?;
    m.add_function(wrap_pyfunction!(controller_label, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}

/// Every registered controller as `(name, description)`, in registry order.
#[pyfunction]
fn controller_names() -> Vec<(String, String)> {
    ftsmc_sim::registry::CONTROLLERS.iter().map(|(n, d)| (n.to_string(), d.to_string())).collect()
}

/// Human-readable label of controller `name` (figures, tables).
#[pyfunction]
fn controller_label(name: &str) -> String {
    ftsmc_sim::registry::label(name).to_string()
}
