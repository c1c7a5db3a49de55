//! One environment: a [`Flight`] that owns its scenario and its agent, and
//! the episode around it (observation, reward, end).

use ftsmc_core::model::{QuadState, Reference};

use crate::run::{ExitStatus, Flight, RunOptions, StepOutcome};
use crate::vehicle::rigid_body::euler_rates_to_body_rates;

use super::agent::Agent;
use super::{GymSpec, Observe, ACTION_LEN, OBSERVATION_LEN};

/// What one environment step gave.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvStep {
    /// Reward of the step.
    pub reward: f64,
    /// The episode ended by a crash or divergence.
    pub terminated: bool,
    /// The episode reached its end time.
    pub truncated: bool,
    /// Why the episode ended (`ExitStatus` text: `crashed at …`, `diverged at …`, `completed`).
    pub reason: Option<String>,
}

/// The true pose of an environment's vehicle ([`Env::pose`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Position, m (world frame, z up).
    pub position: [f64; 3],
    /// Z-Y-X Euler angles (φ, θ, ψ), rad (paper Eq. 1).
    pub attitude: [f64; 3],
    /// Reference position, m.
    pub reference: [f64; 3],
}

/// One environment: its current episode.
pub struct Env {
    /// The episode's flight; it owns its scenario and the agent.
    flight: Flight<'static, Agent>,
    observe: Observe,
    periods: u64,
    /// Control period, s.
    dt: f64,
    /// Episode seed.
    seed: u64,
}

fn wrap_angle(a: f64) -> f64 {
    let two_pi = core::f64::consts::TAU;
    a - two_pi * ((a + core::f64::consts::PI) / two_pi).floor()
}

fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// The observation of `state` against `reference` (module docs of [`super`]).
pub fn observation(state: &QuadState, reference: &Reference) -> [f64; OBSERVATION_LEN] {
    let mut o = [0.0; OBSERVATION_LEN];
    for i in 0..3 {
        o[i] = state.position[i] - reference.position[i];
        o[3 + i] = state.velocity[i] - reference.velocity[i];
    }
    let [phi, theta, psi] = state.attitude;
    let (sf, cf) = ftsmc_core::math::sin_cos(phi);
    let (st, ct) = ftsmc_core::math::sin_cos(theta);
    let (sp, cp) = ftsmc_core::math::sin_cos(psi);
    let r = [
        [cp * ct, cp * st * sf - sp * cf, cp * st * cf + sp * sf],
        [sp * ct, sp * st * sf + cp * cf, sp * st * cf - cp * sf],
        [-st, ct * sf, ct * cf],
    ];
    for i in 0..3 {
        for j in 0..3 {
            o[6 + 3 * i + j] = r[i][j];
        }
    }
    let omega = euler_rates_to_body_rates(&state.attitude, &state.angular_rate);
    o[15..18].copy_from_slice(&omega);
    o
}

impl Env {
    /// A new episode of `spec` seeded `seed`.
    pub fn new(spec: &GymSpec, seed: u64) -> Self {
        let scenario = spec.episode_scenario(seed);
        let agent = Agent::new(&scenario, spec.action, spec.rate_loop);
        let dt = scenario.control_period();
        let flight = Flight::new(scenario, agent, RunOptions { record: false, ..RunOptions::default() });
        Self { flight, observe: spec.observe, periods: spec.periods_per_step, dt, seed }
    }

    /// The episode's seed.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// Time flown in this episode, s.
    pub fn time(&self) -> f64 {
        let dt = self.dt;
        self.flight.steps_flown() as f64 * dt
    }

    /// The observation now (the measurement the next control tick gets,
    /// or the truth with [`Observe::Truth`]); a non-finite entry (only
    /// after a divergence ended the episode) reads 0.
    pub fn observe(&mut self) -> [f64; OBSERVATION_LEN] {
        let observe = self.observe;
        let f = &mut self.flight;
        let state = match observe {
            Observe::Sensors => f.measurement(),
            Observe::Truth => *f.truth_state(),
        };
        observation(&state, f.reference()).map(|v| if v.is_finite() { v } else { 0.0 })
    }

    /// The true pose now, for drawing: position (m, world frame z up),
    /// Z-Y-X Euler angles (φ, θ, ψ, rad) and the reference position (m).
    pub fn pose(&mut self) -> Pose {
        let f = &self.flight;
        let truth = *f.truth_state();
        Pose { position: truth.position, attitude: truth.attitude, reference: f.reference().position }
    }

    /// Fly one environment step with `action` held; the reward is scored
    /// with `spec`'s weights on the truth at the end of the step.
    pub fn step(&mut self, spec: &GymSpec, action: [f64; ACTION_LEN]) -> EnvStep {
        let periods = self.periods;
        let f = &mut self.flight;
        f.controller_mut().set_action(action);
        let applied = f.controller_mut().action();
        let mut outcome = StepOutcome::Flying;
        for _ in 0..periods {
            outcome = f.step();
            if outcome == StepOutcome::Done {
                break;
            }
        }
        let w = &spec.reward;
        let truth = *f.truth_state();
        let reference = *f.reference();
        let e = observation(&truth, &reference);
        let yaw_error = wrap_angle(truth.attitude[2] - reference.yaw);
        let action_sq: f64 = applied.iter().map(|a| a * a).sum();
        let mut reward = w.alive
            - w.position * norm([e[0], e[1], e[2]])
            - w.velocity * norm([e[3], e[4], e[5]])
            - w.yaw * yaw_error.abs()
            - w.rate * norm([e[15], e[16], e[17]]);
        reward -= w.action * action_sq;
        let (mut terminated, mut truncated, mut reason) = (false, false, None);
        if outcome == StepOutcome::Done {
            let exit = f.exit().cloned().unwrap_or(ExitStatus::Completed);
            if exit.is_completed() {
                truncated = true;
            } else {
                terminated = true;
                reward -= w.crash;
            }
            reason = Some(exit.to_string());
        }
        if !reward.is_finite() {
            // A non-finite truth ends the flight (divergence): keep the reward finite.
            reward = -w.crash;
        }
        EnvStep { reward, terminated, truncated, reason }
    }
}
