//! The agent's side of the loop: a [`Controller`] that holds the agent's
//! normalised action and turns it into the command of every control period
//! (collective thrust and body rates through a body-rate loop, or the four
//! rotor speeds; the equations are in the [`super`] module docs).

use ftsmc_core::cascade::{Controller, Telemetry};
use ftsmc_core::model::{Command, QuadState, Reference};

use crate::scenario::Scenario;
use crate::vehicle::rigid_body::euler_rates_to_body_rates;

use super::{ActionMode, RateLoop, ACTION_LEN};

/// Rotor speed range and thrust scale of an action, from the scenario.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ActionScale {
    /// Lowest rotor speed ω_min, rad/s.
    pub min_rotor_speed: f64,
    /// Highest rotor speed ω_max, rad/s (`√2 ω_hover` without a limit).
    pub max_rotor_speed: f64,
    /// Thrust at `a₀ = 1` in [`ActionMode::Ctbr`]: `U1_max = Σ A₀ᵢ ω_max²`, N.
    pub max_thrust: f64,
    /// Allocation `[U1, u2, u3, u4]ᵀ = A ω²` of the truth.
    pub allocation: [[f64; 4]; 4],
}

impl ActionScale {
    /// The scale of `scenario` (module docs of [`super`]).
    pub fn of(scenario: &Scenario) -> Self {
        let (allocation, _) = scenario.truth_allocation();
        let lift: f64 = allocation[0].iter().sum();
        let actuators = scenario.actuators.unwrap_or_default();
        let limit = Some(actuators.max_rotor_speed)
            .filter(|w| w.is_finite())
            .or(scenario.simulation.max_rotor_speed.filter(|w| w.is_finite()));
        let truth = scenario.true_vehicle();
        let (mass, gravity) = match scenario.vehicle.model {
            crate::vehicle::VehicleModel::Paper => (truth.mass, truth.gravity),
            crate::vehicle::VehicleModel::RigidBody => {
                let rb = scenario.rigid_body_params();
                (rb.mass, rb.gravity)
            }
        };
        let hover = (mass * gravity / lift).sqrt();
        let max_rotor_speed = limit.unwrap_or(core::f64::consts::SQRT_2 * hover);
        Self {
            min_rotor_speed: actuators.min_rotor_speed.min(max_rotor_speed),
            max_rotor_speed,
            max_thrust: lift * max_rotor_speed * max_rotor_speed,
            allocation,
        }
    }
}

/// The agent as a [`Controller`]: [`Agent::set_action`] between two
/// environment steps, one [`Controller::update`] per control period.
#[derive(Clone, Debug)]
pub struct Agent {
    mode: ActionMode,
    scale: ActionScale,
    rate_loop: RateLoop,
    /// Nominal `[plant]` inertia `[I1, I2, I3]`, kg·m².
    inertia: [f64; 3],
    action: [f64; ACTION_LEN],
    telemetry: Telemetry,
}

impl Agent {
    /// An agent flying `scenario` in `mode`, holding action 0 until set.
    pub fn new(scenario: &Scenario, mode: ActionMode, rate_loop: RateLoop) -> Self {
        Self {
            mode,
            scale: ActionScale::of(scenario),
            rate_loop,
            inertia: scenario.plant.inertia,
            action: [0.0; ACTION_LEN],
            telemetry: Telemetry::default(),
        }
    }

    /// Hold `action` (each entry clipped to [−1, 1]; NaN counts as 0) from
    /// the next control period on.
    pub fn set_action(&mut self, action: [f64; ACTION_LEN]) {
        self.action = action.map(|a| if a.is_nan() { 0.0 } else { a.clamp(-1.0, 1.0) });
    }

    /// The action held, after clipping.
    pub fn action(&self) -> [f64; ACTION_LEN] {
        self.action
    }

    /// The action scale.
    pub fn scale(&self) -> &ActionScale {
        &self.scale
    }

    /// The command of action `a` at measured state `state`.
    pub fn command(&self, state: &QuadState) -> Command {
        let a = self.action;
        match self.mode {
            ActionMode::Ctbr => {
                let thrust = 0.5 * (a[0] + 1.0) * self.scale.max_thrust;
                let omega = euler_rates_to_body_rates(&state.attitude, &state.angular_rate);
                let mut torque = [0.0; 3];
                for i in 0..3 {
                    let target = a[i + 1] * self.rate_loop.max_rate[i];
                    torque[i] = self.inertia[i] * self.rate_loop.gain[i] * (target - omega[i]);
                }
                Command { thrust, torque }
            }
            ActionMode::Motors => {
                let (lo, hi) = (self.scale.min_rotor_speed, self.scale.max_rotor_speed);
                let w2 = a.map(|ai| {
                    let w = lo + 0.5 * (ai + 1.0) * (hi - lo);
                    w * w
                });
                let m = &self.scale.allocation;
                let row = |r: usize| m[r][0] * w2[0] + m[r][1] * w2[1] + m[r][2] * w2[2] + m[r][3] * w2[3];
                Command { thrust: row(0), torque: [row(1), row(2), row(3)] }
            }
        }
    }
}

impl Controller for Agent {
    fn name(&self) -> &'static str {
        "agent"
    }

    fn update(&mut self, state: &QuadState, _reference: &Reference, _dt: f64) -> Command {
        self.command(state)
    }

    fn telemetry(&self) -> &Telemetry {
        &self.telemetry
    }

    fn reset(&mut self) {
        self.action = [0.0; ACTION_LEN];
    }
}
