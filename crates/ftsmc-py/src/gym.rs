//! The engine of `ftsmc.gym` (python/ftsmc/gym.py): N environments of one
//! scenario stepped in Rust in one call ([`ftsmc_sim::gym::Batch`]), with
//! the GIL released while they fly. The Python layer makes Gymnasium's
//! `Env` (N = 1) and `VectorEnv` of it and draws the seeds.

use std::collections::HashMap;
use std::sync::Mutex;

use ftsmc_sim::gym::agent::ActionScale;
use ftsmc_sim::gym::{
    ActionMode, Batch, GymSettings, GymSpec, Observe, RateLoop, RewardWeights, StepResult, Task, ACTION_LEN,
    OBSERVATION_LEN, OBSERVATION_NAMES,
};
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyList, PyTuple};

use crate::scenario::Scenario;
use crate::value_error;

/// N environments (docs/python.md, "Gymnasium environments").
/// Price `num_envs` environments of `scenario` before anything is
/// allocated for them ([`ftsmc_sim::limits::check_envs`]): `ValueError`
/// naming `num_envs`, the limit and the bound.
#[pyfunction]
pub fn gym_check_envs(scenario: PyRef<'_, Scenario>, num_envs: u64) -> PyResult<()> {
    if num_envs < 1 {
        return Err(value_error(format!("`num_envs` = {num_envs} is invalid (expected at least 1 environment)")));
    }
    ftsmc_sim::limits::check_envs(&scenario.inner.limits, num_envs as f64)
        .map_err(|e| value_error(format!("`num_envs` = {num_envs}: {e}")))
}

#[pyclass(module = "ftsmc._ftsmc", name = "GymBatch", frozen)]
pub struct GymBatch {
    batch: Mutex<Batch>,
    scale: ActionScale,
    mass: f64,
}

fn three(name: &str, v: Option<Vec<f64>>, default: [f64; 3]) -> PyResult<[f64; 3]> {
    match v {
        None => Ok(default),
        Some(v) => <[f64; 3]>::try_from(v.as_slice())
            .map_err(|_| value_error(format!("`{name}` = {v:?} is invalid (expected three numbers)"))),
    }
}

fn weights(given: Option<HashMap<String, f64>>) -> PyResult<RewardWeights> {
    let mut w = RewardWeights::default();
    for (key, value) in given.unwrap_or_default() {
        let slot = match key.as_str() {
            "alive" => &mut w.alive,
            "position" => &mut w.position,
            "velocity" => &mut w.velocity,
            "yaw" => &mut w.yaw,
            "rate" => &mut w.rate,
            "action" => &mut w.action,
            "crash" => &mut w.crash,
            _ => {
                let known: Vec<&str> = w.named().iter().map(|(n, _)| *n).collect();
                return Err(value_error(format!("unknown reward weight `{key}` (known: {})", known.join(", "))));
            }
        };
        *slot = value;
    }
    Ok(w)
}

impl GymBatch {
    fn lock(&self) -> std::sync::MutexGuard<'_, Batch> {
        // A panic inside a step would poison the lock; the batch is then
        // still whole (each lane is replaced or stepped atomically).
        self.batch.lock().unwrap_or_else(|e| e.into_inner())
    }
}

fn outputs<'py>(py: Python<'py>, out: StepResult) -> PyResult<Bound<'py, PyTuple>> {
    let n = out.reward.len();
    let obs = PyArray1::from_vec(py, out.observation).reshape([n, OBSERVATION_LEN])?;
    let items: Vec<Bound<'py, PyAny>> = vec![
        obs.into_any(),
        PyArray1::from_vec(py, out.reward).into_any(),
        PyArray1::from_vec(py, out.terminated).into_any(),
        PyArray1::from_vec(py, out.truncated).into_any(),
        PyList::new(py, out.reason)?.into_any(),
        PyArray1::from_vec(py, out.time).into_any(),
        PyArray1::from_vec(py, out.reset).into_any(),
    ];
    PyTuple::new(py, items)
}

#[pymethods]
impl GymBatch {
    /// `len(seeds)` environments of `scenario`, lane `i` seeded `seeds[i]`
    /// (the equations and defaults: docs/python.md).
    #[new]
    #[pyo3(signature = (scenario, seeds, task="track", target=None, action="ctbr", observe="sensors",
        agent_rate=100.0, max_episode_time=None, reward=None, rate_gain=None, max_rate=None, randomize=false,
        hover_radius=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        scenario: PyRef<'_, Scenario>,
        seeds: Vec<u64>,
        task: &str,
        target: Option<Vec<f64>>,
        action: &str,
        observe: &str,
        agent_rate: f64,
        max_episode_time: Option<f64>,
        reward: Option<HashMap<String, f64>>,
        rate_gain: Option<Vec<f64>>,
        max_rate: Option<Vec<f64>>,
        randomize: bool,
        hover_radius: Option<f64>,
    ) -> PyResult<Self> {
        if seeds.is_empty() {
            return Err(value_error("`num_envs` = 0 is invalid (expected at least 1 environment)"));
        }
        let task = match task {
            "hover" => Task::Hover { target: three("target", target, [0.0, 0.0, 1.0])? },
            "track" if target.is_none() => Task::Track,
            "track" => return Err(value_error("`target` is only for task = \"hover\"")),
            other => {
                return Err(value_error(format!("`task` = {other:?} is invalid (expected \"hover\" or \"track\")")))
            }
        };
        let action = match action {
            "ctbr" => ActionMode::Ctbr,
            "motors" => ActionMode::Motors,
            other => {
                return Err(value_error(format!("`action` = {other:?} is invalid (expected \"ctbr\" or \"motors\")")))
            }
        };
        let observe = match observe {
            "sensors" => Observe::Sensors,
            "truth" => Observe::Truth,
            other => {
                return Err(value_error(format!(
                    "`observe` = {other:?} is invalid (expected \"sensors\" or \"truth\")"
                )))
            }
        };
        let defaults = RateLoop::default();
        let settings = GymSettings {
            task,
            action,
            observe,
            agent_rate,
            max_episode_time,
            reward: weights(reward)?,
            rate_loop: RateLoop {
                gain: three("rate_gain", rate_gain, defaults.gain)?,
                max_rate: three("max_rate", max_rate, defaults.max_rate)?,
            },
            randomize,
        };
        let path = scenario.inner.name.clone();
        let mut flown = scenario.inner.clone();
        // A hover episode ends (terminated, "diverged (position error)")
        // once the vehicle is more than `hover_radius` m from the target
        // along any axis: the scenario's own divergence limit, tightened.
        match (hover_radius, matches!(settings.task, Task::Hover { .. })) {
            (Some(r), true) if r.is_finite() && r > 0.0 => {
                flown.simulation.max_position_error = flown.simulation.max_position_error.min(r)
            }
            (Some(r), true) => {
                return Err(value_error(format!("`hover_radius` = {r} is invalid (expected a finite distance > 0, m)")))
            }
            (Some(_), false) => return Err(value_error("`hover_radius` is only for task = \"hover\"")),
            (None, _) => {}
        }
        let spec = GymSpec::new(flown, &path, settings).map_err(value_error)?;
        spec.scenario.check_cost(1).map_err(|e| value_error(crate::scenario::chain_message(&e)))?;
        let scale = ActionScale::of(&spec.scenario);
        let mass = spec.scenario.plant.mass;
        let batch = py.detach(move || Batch::new(spec, &seeds));
        Ok(Self { batch: Mutex::new(batch), scale, mass })
    }

    /// Number of environments.
    #[getter]
    fn num_envs(&self) -> usize {
        self.lock().len()
    }

    /// Start a new episode in every environment, lane `i` seeded
    /// `seeds[i]`; returns what `step` returns (rewards 0).
    fn reset<'py>(&self, py: Python<'py>, seeds: PyReadonlyArray1<'py, u64>) -> PyResult<Bound<'py, PyTuple>> {
        let seeds = seeds.as_slice()?.to_vec();
        let mut batch = self.lock();
        if seeds.len() != batch.len() {
            return Err(value_error(format!("{} seeds for {} environments", seeds.len(), batch.len())));
        }
        let mut out = StepResult::default();
        let b: &mut Batch = &mut batch;
        py.detach(|| b.reset(&seeds, &mut out));
        outputs(py, out)
    }

    /// One step of every environment: `actions` is `(N, 4)` float64 in
    /// [−1, 1] (clipped; NaN counts as 0); an environment whose episode
    /// ended at the last call is reset instead, seeded `reset_seeds[i]`.
    /// Returns `(observation (N, 18) float32, reward, terminated,
    /// truncated, reason (list of str, "" while flying), time (s), reset)`.
    fn step<'py>(
        &self,
        py: Python<'py>,
        actions: PyReadonlyArray2<'py, f64>,
        reset_seeds: PyReadonlyArray1<'py, u64>,
    ) -> PyResult<Bound<'py, PyTuple>> {
        let mut batch = self.lock();
        let n = batch.len();
        if actions.shape() != [n, ACTION_LEN] {
            return Err(value_error(format!(
                "actions of shape {:?} for {n} environments (expected ({n}, {ACTION_LEN}))",
                actions.shape()
            )));
        }
        let seeds = reset_seeds.as_slice()?;
        if seeds.len() != n {
            return Err(value_error(format!("{} reset seeds for {n} environments", seeds.len())));
        }
        let actions = actions.as_slice()?;
        let mut out = StepResult::default();
        let b: &mut Batch = &mut batch;
        py.detach(|| b.step(actions, seeds, &mut out));
        outputs(py, out)
    }

    /// Which environments ended their episode at the last step (they are
    /// reset at the next one).
    fn done<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<bool>> {
        PyArray1::from_slice(py, self.lock().done())
    }

    /// The true pose of environment `i`, for drawing it: `(position (m),
    /// Z-Y-X Euler angles φ, θ, ψ (rad), reference position (m))`, world
    /// frame z up.
    #[allow(clippy::type_complexity)]
    fn pose(&self, i: usize) -> PyResult<([f64; 3], [f64; 3], [f64; 3])> {
        let mut batch = self.lock();
        if i >= batch.len() {
            return Err(value_error(format!("environment {i} of {} does not exist", batch.len())));
        }
        let p = batch.pose(i);
        Ok((p.position, p.attitude, p.reference))
    }

    /// The seed of each environment's current episode.
    fn seeds<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u64>> {
        let batch = self.lock();
        let v: Vec<u64> = (0..batch.len()).map(|i| batch.seed(i)).collect();
        PyArray1::from_vec(py, v)
    }

    /// Environment step, s.
    #[getter]
    fn step_time(&self) -> f64 {
        self.lock().spec().step_time()
    }

    /// Episode length, s (the scenario's duration or `max_episode_time`).
    #[getter]
    fn episode_time(&self) -> f64 {
        self.lock().spec().scenario.duration
    }

    /// The divergence limit on each axis of the position error, m
    /// (`simulation.max_position_error`, tightened by `hover_radius`).
    #[getter]
    fn max_position_error(&self) -> f64 {
        self.lock().spec().scenario.simulation.max_position_error
    }

    /// Thrust at a₀ = 1 (action "ctbr"), N.
    #[getter]
    fn max_thrust(&self) -> f64 {
        self.scale.max_thrust
    }

    /// Rotor speeds at a = −1 and a = 1 (action "motors"), rad/s.
    #[getter]
    fn rotor_speed_range(&self) -> (f64, f64) {
        (self.scale.min_rotor_speed, self.scale.max_rotor_speed)
    }

    /// Nominal (`[plant]`) mass, kg.
    #[getter]
    fn mass(&self) -> f64 {
        self.mass
    }

    /// Body rates at |a| = 1 (action "ctbr"), rad/s.
    #[getter]
    fn max_rate(&self) -> [f64; 3] {
        self.lock().spec().rate_loop.max_rate
    }

    /// The reward weights in force.
    #[getter]
    fn reward_weights(&self) -> HashMap<String, f64> {
        self.lock().spec().reward.named().iter().map(|(n, v)| (n.to_string(), *v)).collect()
    }

    /// Names of the 18 observation entries.
    #[staticmethod]
    fn observation_names() -> Vec<&'static str> {
        OBSERVATION_NAMES.to_vec()
    }
}
