//! `ftsmc.trajectory`: the simulator's trajectories
//! ([`ftsmc_sim::trajectory`]) from Python — minimum snap through numpy
//! waypoints (Mellinger and Kumar 2011; the closed form of Richter, Bry and
//! Roy 2016, Eq. 31) and the parametric library (hover, circle, …) — sampled
//! at numpy times, and flown by putting them into a scenario's
//! `[reference] trajectory`. A spec the simulator refuses is a `ValueError`
//! with its message (the key, the value, what is expected), never a panic.

use ftsmc_sim::trajectory::{Trajectory, TrajectorySpec, MAX_WAYPOINTS};
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::scenario::{chain_message, Scenario};
use crate::value_error;

/// Most sample times one call takes (each sample is 19 numbers; 10⁷ of
/// them is 1.5 GB): beyond this, sample in chunks.
pub const MAX_SAMPLES: usize = 10_000_000;

/// A built trajectory (`ftsmc.Trajectory` wraps it).
#[pyclass(module = "ftsmc._ftsmc", name = "NativeTrajectory", frozen)]
pub struct NativeTrajectory {
    inner: Trajectory,
}

/// `Err` with the simulator's refusal as `` trajectory `key` = value is
/// invalid (expected …) ``, or the built trajectory.
fn built(spec: TrajectorySpec) -> PyResult<NativeTrajectory> {
    let inner = Trajectory::new(spec);
    inner.check().map_err(|(key, value, expected)| {
        value_error(format!("trajectory `{key}` = {value} is invalid (expected {expected})"))
    })?;
    Ok(NativeTrajectory { inner })
}

/// A TOML table into a spec; serde's message (unknown type or key, wrong
/// kind of value) otherwise.
fn from_table(table: toml::Table) -> PyResult<TrajectorySpec> {
    toml::Value::Table(table).try_into::<TrajectorySpec>().map_err(|e| value_error(format!("trajectory: {e}")))
}

fn float_array(values: impl IntoIterator<Item = f64>) -> toml::Value {
    toml::Value::Array(values.into_iter().map(toml::Value::Float).collect())
}

#[pymethods]
impl NativeTrajectory {
    /// Minimum snap through `waypoints` (N × 3, m; or N × 4 with the heading
    /// ψ in rad as the fourth column), with exactly one time rule: `speed`
    /// (m/s), `duration` (s) or `times` (s, one per waypoint); `yaw` (N
    /// headings, rad) only with N × 3 waypoints. `start` and
    /// `min_segment_time` as in docs/scenarios.md (None: the file's defaults).
    #[staticmethod]
    #[pyo3(signature = (waypoints, yaw=None, speed=None, duration=None, times=None, start=None, min_segment_time=None))]
    #[allow(clippy::too_many_arguments)]
    fn min_snap(
        waypoints: PyReadonlyArray2<'_, f64>,
        yaw: Option<PyReadonlyArray1<'_, f64>>,
        speed: Option<f64>,
        duration: Option<f64>,
        times: Option<PyReadonlyArray1<'_, f64>>,
        start: Option<f64>,
        min_segment_time: Option<f64>,
    ) -> PyResult<Self> {
        let [n, cols] = [waypoints.shape()[0], waypoints.shape()[1]];
        // Priced before anything is copied: a huge array is refused by its shape.
        if n > MAX_WAYPOINTS {
            return Err(value_error(format!(
                "trajectory `waypoints` = {n} waypoints is invalid (expected at most {MAX_WAYPOINTS} waypoints; split the mission into shorter trajectories)"
            )));
        }
        if cols != 3 && cols != 4 {
            return Err(value_error(format!(
                "trajectory `waypoints` of shape ({n}, {cols}) is invalid (expected N × 3 [x, y, z] m, or N × 4 [x, y, z, ψ] with ψ in rad)"
            )));
        }
        if cols == 4 && yaw.is_some() {
            return Err(value_error(
                "trajectory `yaw` is given twice (the fourth column of the waypoints and `yaw`): give one",
            ));
        }
        let w = waypoints.as_array();
        let mut table = toml::Table::new();
        table.insert("type".into(), "min-snap".into());
        table.insert(
            "waypoints".into(),
            toml::Value::Array((0..n).map(|i| float_array((0..3).map(|j| w[[i, j]]))).collect()),
        );
        if cols == 4 {
            table.insert("yaw".into(), float_array((0..n).map(|i| w[[i, 3]])));
        } else if let Some(y) = yaw {
            table.insert("yaw".into(), float_array(y.as_array().iter().copied()));
        }
        for (key, value) in
            [("speed", speed), ("duration", duration), ("start", start), ("min_segment_time", min_segment_time)]
        {
            if let Some(v) = value {
                table.insert(key.into(), toml::Value::Float(v));
            }
        }
        if let Some(t) = times {
            table.insert("times".into(), float_array(t.as_array().iter().copied()));
        }
        built(from_table(table)?)
    }

    /// A library shape: `kind` (`hover`, `circle`, `oval`, `figure-eight`,
    /// `lissajous`, `helix`, `star`, `trefoil`, `ramp`) with its keys as in
    /// a scenario file (docs/scenarios.md, "Shapes").
    #[staticmethod]
    #[pyo3(signature = (kind, params=None))]
    fn shape(kind: &str, params: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let mut table = toml::Table::new();
        if let Some(p) = params {
            let mut budget = crate::scenario::MAX_OVERRIDE_VALUES;
            for (key, value) in p.iter() {
                let key: String = key.extract().map_err(|_| value_error("trajectory keys must be strings"))?;
                if key == "type" {
                    return Err(value_error("trajectory: the shape is the first argument, not a `type` key"));
                }
                let v = crate::scenario::to_toml_value(&value, &mut budget)
                    .map_err(|m| value_error(format!("trajectory `{key}`: {m}")))?;
                table.insert(key, v);
            }
        }
        if kind == "min-snap" {
            return Err(value_error("trajectory: `min-snap` takes waypoints: ftsmc.trajectory(waypoints, speed=…)"));
        }
        table.insert("type".into(), kind.into());
        built(from_table(table)?)
    }

    /// The shape names of the library, in documentation order.
    #[staticmethod]
    fn shape_names() -> Vec<&'static str> {
        use ftsmc_sim::trajectory::library::Kind;
        [
            Kind::Hover,
            Kind::Circle,
            Kind::Oval,
            Kind::FigureEight,
            Kind::Lissajous,
            Kind::Helix,
            Kind::Star,
            Kind::Trefoil,
            Kind::Ramp,
        ]
        .map(Kind::name)
        .to_vec()
    }

    /// `"min-snap"` or the shape's name.
    #[getter]
    fn kind(&self) -> String {
        match toml::Value::try_from(self.inner.spec()) {
            Ok(toml::Value::Table(t)) => t.get("type").and_then(|v| v.as_str()).unwrap_or("").to_string(),
            _ => String::new(),
        }
    }

    /// Time the trajectory starts, s.
    #[getter]
    fn start(&self) -> f64 {
        self.inner.start()
    }

    /// Time it comes to rest for good, s (None: a shape without `laps` never does).
    #[getter]
    fn end(&self) -> Option<f64> {
        self.inner.end()
    }

    /// Minimum snap: the time of every waypoint, s (None for a shape).
    fn knot_times<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        self.inner.plan().map(|p| PyArray1::from_slice(py, &p.times))
    }

    /// Minimum snap: the snap cost `Σ_i ∫ (d⁴q/dt⁴)² dt` of output `o`
    /// (0–3: x, y, z, ψ), the quantity it minimises (None for a shape).
    fn snap_cost(&self, o: usize) -> PyResult<Option<f64>> {
        if o > 3 {
            return Err(value_error(format!("output {o} does not exist (expected 0–3: x, y, z, ψ)")));
        }
        Ok(self.inner.plan().map(|p| p.cost(o)))
    }

    /// The trajectory at times `t` (s, 1-D): `(position (N, 3) m, velocity
    /// m/s, acceleration m/s², jerk m/s³, snap m/s⁴ (each (N, 3)), ψ (N,)
    /// rad, ψ̇ rad/s, ψ̈ rad/s²)`. Before its start it holds its first point,
    /// after its end its last, at rest.
    fn sample<'py>(&self, py: Python<'py>, t: PyReadonlyArray1<'py, f64>) -> PyResult<Bound<'py, PyTuple>> {
        let t = t.as_array();
        let n = t.len();
        if n > MAX_SAMPLES {
            return Err(value_error(format!("{n} sample times: at most {MAX_SAMPLES} per call (sample in chunks)")));
        }
        let times: Vec<f64> = t.iter().copied().collect();
        let traj = &self.inner;
        let (vectors, scalars) = py.detach(|| {
            let mut vectors: [Vec<f64>; 5] = std::array::from_fn(|_| Vec::with_capacity(3 * n));
            let mut scalars: [Vec<f64>; 3] = std::array::from_fn(|_| Vec::with_capacity(n));
            for &tk in &times {
                let f = traj.sample(tk);
                for (out, v) in vectors.iter_mut().zip([f.pos, f.vel, f.acc, f.jerk, f.snap]) {
                    out.extend_from_slice(&v);
                }
                for (out, v) in scalars.iter_mut().zip([f.yaw, f.yaw_rate, f.yaw_acc]) {
                    out.push(v);
                }
            }
            (vectors, scalars)
        });
        let mut items: Vec<Bound<'py, PyAny>> = Vec::with_capacity(8);
        for v in vectors {
            items.push(PyArray1::from_vec(py, v).reshape([n, 3])?.into_any());
        }
        for s in scalars {
            items.push(PyArray1::from_vec(py, s).into_any());
        }
        PyTuple::new(py, items)
    }

    /// The spec as a TOML inline table, as `[reference] trajectory = …`
    /// takes it in a scenario file.
    fn to_toml(&self) -> PyResult<String> {
        toml::Value::try_from(self.inner.spec())
            .map(|v| v.to_string())
            .map_err(|e| value_error(format!("cannot write the trajectory as TOML: {e}")))
    }

    /// `scenario` flying this trajectory: its `[reference]` replaced by it
    /// (`time_scale` `"fixed"` refuses one the vehicle cannot fly, `"fit"`
    /// slows it until it can, with a warning saying by how much) and, with
    /// `start_on_it`, its initial state at rest on the trajectory's first
    /// point, heading ψ there. Validated as a file would be (feasibility at load).
    // The Python method's name (`Trajectory.into_scenario`) reads as a
    // conversion into a scenario; it does not consume the trajectory.
    #[allow(clippy::wrong_self_convention)]
    #[pyo3(signature = (scenario, time_scale="fixed", start_on_it=true))]
    fn into_scenario(
        &self,
        py: Python<'_>,
        scenario: PyRef<'_, Scenario>,
        time_scale: &str,
        start_on_it: bool,
    ) -> PyResult<Scenario> {
        if !matches!(time_scale, "fixed" | "fit") {
            return Err(value_error(format!(
                "`time_scale` = {time_scale:?} is invalid (expected \"fixed\" or \"fit\")"
            )));
        }
        let spec = toml::Value::try_from(self.inner.spec())
            .map_err(|e| value_error(format!("cannot write the trajectory as TOML: {e}")))?;
        let mut reference = toml::Table::new();
        reference.insert("trajectory".into(), spec);
        reference.insert("time_scale".into(), time_scale.into());
        let mut overrides: Vec<(String, toml::Value)> = vec![("reference".into(), toml::Value::Table(reference))];
        if start_on_it {
            let f = self.inner.sample(self.inner.start());
            overrides.push(("initial_state.position".into(), float_array(f.pos)));
            overrides.push(("initial_state.velocity".into(), float_array([0.0; 3])));
            overrides.push(("initial_state.attitude".into(), float_array([0.0, 0.0, f.yaw])));
            overrides.push(("initial_state.angular_rate".into(), float_array([0.0; 3])));
        }
        let loaded = scenario.inner.with_overrides(&overrides).map_err(|e| value_error(chain_message(&e)))?;
        crate::scenario::warn_all(py, loaded)
    }
}

/// Arm length of the scenario's true vehicle, m (rotor centre to the body
/// centre: `plant.arm_length`, or the rigid body's geometry), for drawing it to scale.
#[pyfunction]
pub fn vehicle_arm_length(scenario: PyRef<'_, Scenario>) -> f64 {
    scenario.inner.truth_allocation().1.arm_length
}
