//! Controllers across the language boundary, both ways:
//!
//! - [`NativeController`]: one of ftsmc's controllers (built by name from a
//!   scenario's gains) called step by step from Python — how other
//!   simulators (RotorPy) fly them;
//! - [`PythonController`]: a Python object with `update(state, reference,
//!   dt) -> command` flown by ftsmc's run loop in place of a built-in one.
//!
//! Conventions of the vectors (ftsmc-core's `QuadState`, `Reference`,
//! `Command`): world frame z up, position m, velocity m/s; attitude the
//! Z-Y-X Euler angles `[φ, θ, ψ]` (roll, pitch, yaw), rad, and
//! `angular_rate` their time derivatives `[φ̇, θ̇, ψ̇]`, rad/s (not body
//! rates); thrust U1 along body z, N; torques about body x, y, z, N·m.

use std::sync::Mutex;

use ftsmc_core::cascade::{Controller, Telemetry};
use ftsmc_core::model::{Command, QuadState, Reference};
use ftsmc_sim::registry::{self, BoxedController};
use pyo3::prelude::*;

use crate::scenario::Scenario;
use crate::value_error;

/// `N` floats from any iterable (tuple, list, numpy array).
pub(crate) fn floats<const N: usize>(value: &Bound<'_, PyAny>, what: &str) -> PyResult<[f64; N]> {
    let mut out = [0.0; N];
    let mut n = 0;
    for item in value.try_iter().map_err(|_| value_error(format!("`{what}` must be a sequence of {N} numbers")))? {
        let item = item?;
        if n < N {
            out[n] = item.extract().map_err(|_| value_error(format!("`{what}` must hold numbers, found {item}")))?;
        }
        n += 1;
    }
    if n != N {
        return Err(value_error(format!("`{what}` must have {N} elements, found {n}")));
    }
    Ok(out)
}

/// Build a registry controller, with the CLI's message for an unknown name.
pub(crate) fn build(name: &str, scenario: &ftsmc_sim::Scenario) -> PyResult<BoxedController> {
    crate::check_controllers("controller", &[name.to_string()])?;
    registry::build(name, scenario).map_err(value_error)
}

/// `(attitude_reference, attitude_reference_rate, sliding, alpha_hat)`;
/// the last two `None` for a controller without sliding surfaces (PID, SE(3)).
type TelemetryTuple = ([f64; 3], [f64; 3], Option<[f64; 6]>, Option<f64>);

/// One of ftsmc's controllers, stepped from Python (`ftsmc.Controller`
/// wraps it with dataclasses).
#[pyclass(module = "ftsmc._ftsmc", name = "NativeController")]
pub struct NativeController {
    name: String,
    inner: Mutex<BoxedController>,
}

#[pymethods]
impl NativeController {
    #[new]
    fn new(name: &str, scenario: PyRef<'_, Scenario>) -> PyResult<Self> {
        Ok(Self { name: name.to_string(), inner: Mutex::new(build(name, &scenario.inner)?) })
    }

    /// The registry name.
    #[getter]
    fn name(&self) -> String {
        self.name.clone()
    }

    /// One control period: state (12 floats: position, attitude, velocity,
    /// attitude rates), reference (12 floats: position, velocity,
    /// acceleration, yaw, yaw rate, yaw acceleration), `dt` s; returns
    /// `(thrust, roll torque, pitch torque, yaw torque)`. A NaN or infinite
    /// state or reference value is a `ValueError` naming it
    /// (`ftsmc_core::update_checked`), and the controller is not updated.
    fn update(
        &self,
        state: &Bound<'_, PyAny>,
        reference: &Bound<'_, PyAny>,
        dt: f64,
    ) -> PyResult<(f64, f64, f64, f64)> {
        let s: [f64; 12] = floats(state, "state")?;
        let r: [f64; 12] = floats(reference, "reference")?;
        if !(dt.is_finite() && dt > 0.0) {
            return Err(value_error(format!("`dt` = {dt} is invalid (expected a positive time step, s)")));
        }
        let state = QuadState::from_array(&s);
        let reference = Reference {
            position: [r[0], r[1], r[2]],
            velocity: [r[3], r[4], r[5]],
            acceleration: [r[6], r[7], r[8]],
            yaw: r[9],
            yaw_rate: r[10],
            yaw_acceleration: r[11],
        };
        let mut c = self.inner.lock().map_err(|_| value_error("controller poisoned by an earlier panic"))?;
        let u = ftsmc_core::update_checked(&mut **c, &state, &reference, dt).map_err(|e| {
            value_error(format!(
                "Controller.update: {e}; every state and reference value must be finite (the controller was not \
                 updated)"
            ))
        })?;
        Ok((u.thrust, u.torque[0], u.torque[1], u.torque[2]))
    }

    /// Restore the initial internal states.
    fn reset(&self) -> PyResult<()> {
        self.inner.lock().map_err(|_| value_error("controller poisoned by an earlier panic"))?.reset();
        Ok(())
    }

    /// What the last update computed: `(attitude_reference[3] rad,
    /// attitude_reference_rate[3] rad/s, sliding[6], alpha_hat)`; `sliding`
    /// and `alpha_hat` are `None` for PID and SE(3) (no sliding surfaces).
    fn telemetry(&self) -> PyResult<TelemetryTuple> {
        let c = self.inner.lock().map_err(|_| value_error("controller poisoned by an earlier panic"))?;
        let t = c.telemetry();
        let sm = t.sliding_mode;
        Ok((t.attitude_reference, t.attitude_reference_rate, sm.map(|s| s.sliding), sm.map(|s| s.alpha_hat)))
    }
}

/// A Python object flown by ftsmc's run loop: each control period calls
/// `obj.update(State(...), Reference(...), dt)` and reads `thrust` and
/// `torque` of what it returns. A Python exception ends the flight (the
/// command is NaN, so the loop stops at once with a non-finite exit) and
/// is re-raised by [`crate::flight::simulate_python`].
pub(crate) struct PythonController<'py> {
    obj: Bound<'py, PyAny>,
    state_cls: Bound<'py, PyAny>,
    reference_cls: Bound<'py, PyAny>,
    telemetry: Telemetry,
    pub(crate) error: Option<PyErr>,
}

impl<'py> PythonController<'py> {
    pub(crate) fn new(obj: Bound<'py, PyAny>, state_cls: Bound<'py, PyAny>, reference_cls: Bound<'py, PyAny>) -> Self {
        Self { obj, state_cls, reference_cls, telemetry: Telemetry::default(), error: None }
    }

    fn call(&self, state: &QuadState, reference: &Reference, dt: f64) -> PyResult<Command> {
        let t3 = |a: [f64; 3]| (a[0], a[1], a[2]);
        let s = self.state_cls.call1((
            t3(state.position),
            t3(state.attitude),
            t3(state.velocity),
            t3(state.angular_rate),
        ))?;
        let r = self.reference_cls.call1((
            t3(reference.position),
            t3(reference.velocity),
            t3(reference.acceleration),
            reference.yaw,
            reference.yaw_rate,
            reference.yaw_acceleration,
        ))?;
        let out = self.obj.call_method1(pyo3::intern!(self.obj.py(), "update"), (s, r, dt))?;
        let thrust: f64 = out
            .getattr(pyo3::intern!(out.py(), "thrust"))
            .and_then(|v| v.extract())
            .map_err(|_| value_error("the controller's update() must return a command with a float `thrust`"))?;
        let torque = out
            .getattr(pyo3::intern!(out.py(), "torque"))
            .map_err(|_| value_error("the controller's update() must return a command with `torque` (3 floats)"))?;
        Ok(Command { thrust, torque: floats(&torque, "torque")? })
    }
}

impl Controller for PythonController<'_> {
    fn name(&self) -> &'static str {
        "python"
    }

    fn update(&mut self, state: &QuadState, reference: &Reference, dt: f64) -> Command {
        // Ctrl-C (or any pending signal handler that raises) stops the run:
        // the NaN command ends it at once and the error is raised.
        if self.error.is_none() {
            if let Err(e) = self.obj.py().check_signals() {
                self.error = Some(e);
            }
        }
        if self.error.is_none() {
            match self.call(state, reference, dt) {
                Ok(command) => return command,
                Err(e) => self.error = Some(e),
            }
        }
        Command { thrust: f64::NAN, torque: [f64::NAN; 3] }
    }

    fn telemetry(&self) -> &Telemetry {
        &self.telemetry
    }

    fn reset(&mut self) {
        if self.obj.hasattr("reset").unwrap_or(false) {
            if let Err(e) = self.obj.call_method0("reset") {
                self.error.get_or_insert(e);
            }
        }
    }
}
