//! Reinforcement-learning environments (the engine of the Python package's
//! Gymnasium environments, `ftsmc.gym`): an agent outside the loop flies a
//! scenario through the same [`crate::run::Flight`] as every other flight
//! — its sensor stage, actuator stage (limits, lag, mixer), truth model,
//! wind and ground — and N such flights are stepped in one call ([`Batch`]).
//!
//! # One environment step
//!
//! An environment step is `n = control_rate / agent_rate` control periods
//! (an integer: [`GymSpec::new`] refuses anything else). The agent's action
//! is held over them; an inner loop ([`agent`]) turns it into the command
//! (thrust U1, torques u2..u4) of every control period, which then goes
//! through the scenario's actuator stage like any controller's command:
//!
//! - [`ActionMode::Ctbr`] (collective thrust and body rates, the
//!   `cmd_ctbr` abstraction of RotorPy, Folk et al. 2023):
//!   `a ∈ [-1, 1]⁴` → `U1 = (a₀ + 1)/2 · U1_max`,
//!   `Ω_cmd = (a₁, a₂, a₃) ⊙ Ω_max`; the body-rate loop
//!   `u = J k_Ω ⊙ (Ω_cmd − Ω̃)` (RotorPy's `cmd_ctbr`, `rotorpy/vehicles/multirotor.py`)
//!   runs at the control rate on the measured body rates Ω̃, with J the
//!   nominal `[plant]` inertia.
//! - [`ActionMode::Motors`] (the four rotor speeds):
//!   `ω_i = ω_min + (a_i + 1)/2 · (ω_max − ω_min)`, turned into
//!   `[U1, u2, u3, u4] = A ω²` with the truth's allocation `A`, so that the
//!   mixer gives back the same speeds whenever they are within its limits.
//!
//! `ω_min`, `ω_max` are `[actuators]` (or `simulation.max_rotor_speed`);
//! without a rotor limit `ω_max = √2 ω_hover` (thrust-to-weight 2) and
//! `U1_max = Σ_i A₀ᵢ ω_max²`.
//!
//! # Observation ([`OBSERVATION_NAMES`], 18 numbers)
//!
//! From the sensor stage (the measurement the controller stage would be
//! given; [`Observe::Truth`] for the true state): position error
//! `p − p_d` (m) and velocity error `v − v_d` (m/s) in the world frame
//! (z up), the rows of the body-to-world rotation `R = Rz(ψ) Ry(θ) Rx(φ)`
//! (Z-Y-X Euler angles, paper Eq. 1), and the body rates `Ω = (p, q, r)`
//! (rad/s), all at the start of the environment step.
//!
//! # Reward ([`RewardWeights`]) and episode end
//!
//! Computed on the truth at the end of the step:
//! `r = alive − w_p ‖p − p_d‖ − w_v ‖v − v_d‖ − w_ψ |ψ − ψ_d| − w_Ω ‖Ω‖ − w_a ‖a‖²`,
//! minus `crash` when the step ends the episode by a crash or divergence.
//! *Terminated*: the flight crashed (`[ground]`) or diverged
//! (`simulation.max_position_error`, `max_tilt`, a non-finite state);
//! *truncated*: the flight reached the scenario's `duration` (or the
//! environment's maximum episode time, which replaces it).

pub mod agent;
mod batch;
mod lane;

pub use batch::{Batch, StepResult};
pub use lane::{observation, Env, EnvStep, Pose};

use crate::scenario::Scenario;
use crate::signal::Signal;

/// Length of the observation vector.
pub const OBSERVATION_LEN: usize = 18;

/// Length of the action vector.
pub const ACTION_LEN: usize = 4;

/// The observation's entries in order (units in the module docs).
pub const OBSERVATION_NAMES: [&str; OBSERVATION_LEN] = [
    "ex", "ey", "ez", "evx", "evy", "evz", "r11", "r12", "r13", "r21", "r22", "r23", "r31", "r32", "r33", "p", "q", "r",
];

/// What the agent commands (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ActionMode {
    /// Collective thrust and body rates, through a body-rate loop.
    Ctbr,
    /// The four rotor speeds.
    Motors,
}

/// What the agent observes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Observe {
    /// The sensor stage's output (`[sensors]`; the truth with perfect sensors).
    Sensors,
    /// The true state.
    Truth,
}

/// The task.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Task {
    /// Hold the point `target` (m, world frame, z up) with yaw 0: the
    /// scenario's reference is replaced by that constant and the flight
    /// starts there at rest (at the scenario's initial attitude).
    Hover {
        /// The hover point `[x, y, z]`, m.
        target: [f64; 3],
    },
    /// Track the scenario's own reference from its initial state.
    Track,
}

/// Reward weights (module docs; each ≥ 0 and finite).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RewardWeights {
    /// Reward per step for being in flight.
    pub alive: f64,
    /// Per metre of position error, 1/m.
    pub position: f64,
    /// Per m/s of velocity error, s/m.
    pub velocity: f64,
    /// Per radian of yaw error (wrapped to [−π, π]), 1/rad.
    pub yaw: f64,
    /// Per rad/s of body rate, s/rad.
    pub rate: f64,
    /// Per unit of squared action norm.
    pub action: f64,
    /// Once, when the episode is terminated by a crash or divergence.
    pub crash: f64,
}

impl Default for RewardWeights {
    fn default() -> Self {
        Self { alive: 1.0, position: 1.0, velocity: 0.1, yaw: 0.1, rate: 0.01, action: 0.01, crash: 10.0 }
    }
}

impl RewardWeights {
    /// The weights by name, in the order of the fields.
    pub fn named(&self) -> [(&'static str, f64); 7] {
        [
            ("alive", self.alive),
            ("position", self.position),
            ("velocity", self.velocity),
            ("yaw", self.yaw),
            ("rate", self.rate),
            ("action", self.action),
            ("crash", self.crash),
        ]
    }
}

/// Inner-loop settings of [`ActionMode::Ctbr`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RateLoop {
    /// Body-rate loop gains `k_Ω`, 1/s (default 20 on each axis; RotorPy's `k_w` is 1).
    pub gain: [f64; 3],
    /// Body rates at `|a| = 1`, rad/s (default `[7, 7, 3]`, RotorPy's `QuadrotorEnv`).
    pub max_rate: [f64; 3],
}

impl Default for RateLoop {
    fn default() -> Self {
        Self { gain: [20.0; 3], max_rate: [7.0, 7.0, 3.0] }
    }
}

/// Everything an environment is made of; checked once by [`GymSpec::new`].
#[derive(Clone, Debug)]
pub struct GymSpec {
    /// The scenario flown (the task already applied to it).
    pub scenario: Scenario,
    /// The action mode.
    pub action: ActionMode,
    /// What is observed.
    pub observe: Observe,
    /// Control periods per environment step.
    pub periods_per_step: u64,
    /// Reward weights.
    pub reward: RewardWeights,
    /// Body-rate loop ([`ActionMode::Ctbr`]).
    pub rate_loop: RateLoop,
    /// Draw the plant from the scenario's `[montecarlo]` at every reset.
    pub randomize: bool,
}

/// Settings of [`GymSpec::new`] besides the scenario.
#[derive(Clone, Copy, Debug)]
pub struct GymSettings {
    /// The task.
    pub task: Task,
    /// The action mode.
    pub action: ActionMode,
    /// What is observed.
    pub observe: Observe,
    /// Agent (environment step) rate, Hz; must divide `simulation.control_rate`.
    pub agent_rate: f64,
    /// Episode length, s (`None`: the scenario's `duration`).
    pub max_episode_time: Option<f64>,
    /// Reward weights.
    pub reward: RewardWeights,
    /// Body-rate loop.
    pub rate_loop: RateLoop,
    /// Monte Carlo draws of the plant at every reset.
    pub randomize: bool,
}

impl Default for GymSettings {
    fn default() -> Self {
        Self {
            task: Task::Track,
            action: ActionMode::Ctbr,
            observe: Observe::Sensors,
            agent_rate: 100.0,
            max_episode_time: None,
            reward: RewardWeights::default(),
            rate_loop: RateLoop::default(),
            randomize: false,
        }
    }
}

fn finite_nonnegative(name: &str, v: f64) -> Result<(), String> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(format!("`{name}` = {v} is invalid (expected a finite number ≥ 0)"))
    }
}

impl GymSpec {
    /// Apply `settings` to `scenario` (named `path` in errors) and check
    /// the result: the scenario's own validation, the agent rate, the
    /// episode time, the weights and gains. Errors name the setting and value.
    pub fn new(mut scenario: Scenario, path: &str, settings: GymSettings) -> Result<Self, String> {
        if let Task::Hover { target } = settings.task {
            if !target.iter().all(|v| v.is_finite()) {
                return Err(format!("`target` = {target:?} is invalid (expected three finite numbers, m)"));
            }
            scenario.reference.x = Signal::constant(target[0]);
            scenario.reference.y = Signal::constant(target[1]);
            scenario.reference.z = Signal::constant(target[2]);
            scenario.reference.psi = Signal::constant(0.0);
            scenario.initial_state.position = target;
            scenario.initial_state.velocity = [0.0; 3];
            scenario.initial_state.angular_rate = [0.0; 3];
        }
        if let Some(t) = settings.max_episode_time {
            if !(t.is_finite() && t > 0.0) {
                return Err(format!("`max_episode_time` = {t} is invalid (expected a finite time > 0, s)"));
            }
            scenario.duration = t;
        }
        // An environment records no time series (the agent gets every step).
        scenario.simulation.record_rate = 0.0;
        scenario.validate(path).map_err(|e| e.to_string())?;
        if settings.randomize && scenario.montecarlo.is_none() {
            return Err(format!("`randomize` = True needs a [montecarlo] section in scenario {path} (it has none)"));
        }
        let rate = settings.agent_rate;
        let control_rate = scenario.simulation.control_rate;
        let ratio = control_rate / rate;
        if !(rate.is_finite() && rate > 0.0) || ratio < 1.0 || (ratio - ratio.round()).abs() > 1e-9 * ratio {
            return Err(format!(
                "`agent_rate` = {rate} Hz is invalid (expected a rate that divides simulation.control_rate = {control_rate} Hz)"
            ));
        }
        for (name, w) in settings.reward.named() {
            finite_nonnegative(&format!("reward.{name}"), w)?;
        }
        for i in 0..3 {
            finite_nonnegative("rate_gain", settings.rate_loop.gain[i])?;
            finite_nonnegative("max_rate", settings.rate_loop.max_rate[i])?;
        }
        Ok(Self {
            scenario,
            action: settings.action,
            observe: settings.observe,
            periods_per_step: ratio.round() as u64,
            reward: settings.reward,
            rate_loop: settings.rate_loop,
            randomize: settings.randomize,
        })
    }

    /// The scenario of an episode seeded `seed`: the spec's scenario with
    /// `seed` as its seed (sensor noise, wind), or with `randomize` its
    /// Monte Carlo draw of run 0 under master seed `seed`.
    pub fn episode_scenario(&self, seed: u64) -> Scenario {
        match (&self.scenario.montecarlo, self.randomize) {
            (Some(mc), true) => mc.sample(&self.scenario, seed, 0).0,
            _ => {
                let mut s = self.scenario.clone();
                s.seed = seed;
                s
            }
        }
    }

    /// Environment step, s.
    pub fn step_time(&self) -> f64 {
        self.periods_per_step as f64 * self.scenario.control_period()
    }
}
