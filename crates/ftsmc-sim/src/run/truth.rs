//! The realistic run loop: the paper's controllers flying a truth model
//! through real actuators, with an optional ground.
//!
//! [`crate::run::simulate`] hands a flight to [`simulate_realistic`]
//! when [`is_realistic`]: `[vehicle] model = "rigid-body"`, non-ideal
//! `[actuators]`, or `[ground] enabled = true`. Otherwise today's paper loop
//! runs unchanged (the paper scenarios stay bit-identical).
//!
//! # One control period
//!
//! 1. The controller sees the Euler state: the paper plant's state as is, or
//!    [`to_quad_state`] of the rigid body (Z-Y-X angles, Euler rates from body rates).
//! 2. Its command goes through [`Mixer::mix`] (priority thrust > roll/pitch >
//!    yaw, rotor limits `[ω_min, ω_max]` of `[actuators]`); the mixer's
//!    `saturated` flag is passed to `controller.actuator_feedback`. With the
//!    paper truth model and ideal actuators the command is applied directly,
//!    as in the paper loop (negative thrust included).
//! 3. The motors follow the mixer's rotor-speed commands with the exact
//!    first-order lag (τ_up / τ_down): inside each RK4 substep the rotor
//!    speeds at every stage time are [`Motors::speeds_after`] (the exact
//!    solution, not held per substep), times the period's motor noise
//!    (one standard-normal draw per rotor per period, its own ChaCha stream
//!    [`crate::actuators::motor_noise_rng`]).
//! 4. The truth model integrates the actual rotor speeds: the rigid body's
//!    per-rotor forces, or paper Eq. 1 with the thrust and torques of the
//!    actual speeds (paper Eq. 2) and their Ω̄.
//! 5. Ground contact after every substep ([`crate::environment::ground`]).
//!
//! With `[wind]` the air moves: the wind (mean, gusts, Dryden turbulence of
//! [`crate::environment::wind`]) is sampled once per RK4 substep, held over
//! it, and acts through air-relative drag in both truth models (the rigid
//! body's parasitic and rotor drag; Eq. 1's `K_f1` drag on `v − w`).
//!
//! With `[sensors]` (not perfect) the controller of step 1 sees
//! [`Sensors::measure`] of the state (noise, bias, sample-and-hold,
//! latency); metrics, the envelope and the recording use the truth.
//!
//! # The scenario's plant variations on the rigid body
//!
//! The paper's disturbances are accelerations: `D_x, D_y, D_z` become a world
//! force `m D` (true mass), `D_φ, D_θ, D_ψ` a body torque `J D`. The latter is
//! an approximation: in Eq. 1 they add to the Euler-angle accelerations,
//! which equal body-rate accelerations only at small angles. Payload adds to
//! the rigid body's mass and the inertia variation scales its inertia matrix,
//! both updated once per control period. The paper's linear drags
//! (`K_f1`, `K_f2`) and their noise act on the paper truth model only; the
//! rigid body uses its own aerodynamics (`[vehicle.rigid_body]`).
//!
//! # Recorded and measured
//!
//! `thrust … yaw_torque` are the mixer's applied command (what the rotors are
//! asked for), `*_cmd` the controller's command, `omega_1..4` the actual rotor
//! speeds (lag and noise) at the tick. The metrics' control signals
//! (chattering, energy) use the mixer's applied command. Two more metrics:
//! `peak_rotor_speed_demand` (largest rotor speed the controller's command
//! asks for with no limit, [`ftsmc_core::allocation::rotor_speeds`]) and
//! `saturation_fraction` (control periods in which the mixer saturated).

use ftsmc_core::allocation::{forces_from_squared_speeds, residual_speed, rotor_speeds};
use ftsmc_core::cascade::Controller;
use ftsmc_core::model::{Command, QuadState};

use crate::actuators::{motor_noise_rng, ActuatorParams, Mixer, Motors};
use crate::envelope::Tracker;
use crate::environment::wind::Wind;
use crate::environment::{Environment, TimeVarying};
use crate::metrics::MetricsAccumulator;
use crate::scenario::Scenario;
use crate::vehicle::paper::{derivative_in_wind, rk4_step};
use crate::vehicle::VehicleModel;

use super::exit::check_divergence;
use super::recording::{Recorder, Tick};
use super::{reference_at, tracking_errors, Divergence, ExitStatus, RunOptions, RunOutput};
use crate::sensors::Sensors;
use crate::vehicle::rigid_body::{normalize_quaternion, RigidBodyState};
use crate::vehicle::{from_quad_state, to_quad_state, RigidBody, RigidBodyInput, RigidBodyParams};

/// True when the flight needs the realistic loop.
pub fn is_realistic(scenario: &Scenario) -> bool {
    scenario.vehicle.model == VehicleModel::RigidBody
        || scenario.actuators.is_some_and(|a| a != ActuatorParams::default())
        || scenario.ground.is_some_and(|g| g.enabled)
        || scenario.sensors.is_some_and(|s| !s.is_perfect())
        || scenario.wind.is_some()
}

/// The actuators of a realistic flight: `[actuators]`, or ideal ones with
/// the legacy `simulation.max_rotor_speed` as ω_max.
pub fn actuators(scenario: &Scenario) -> ActuatorParams {
    scenario.actuators.unwrap_or(ActuatorParams {
        max_rotor_speed: scenario.simulation.max_rotor_speed.unwrap_or(f64::INFINITY),
        ..ActuatorParams::default()
    })
}

// One value per flight, on the stack: the size difference does not matter.
#[allow(clippy::large_enum_variant)]
enum Truth {
    Paper([f64; 12]),
    Rigid { body: RigidBody, base: RigidBodyParams, key: (f64, f64), x: RigidBodyState },
}

impl Truth {
    fn quad_state(&self) -> QuadState {
        match self {
            Truth::Paper(x) => QuadState::from_array(x),
            Truth::Rigid { x, .. } => to_quad_state(x),
        }
    }
}

/// Fly `controller` through `scenario` on the realistic path (module docs).
pub fn simulate_realistic(scenario: &Scenario, controller: &mut dyn Controller, options: RunOptions<'_>) -> RunOutput {
    let sim = &scenario.simulation;
    let dt = scenario.control_period();
    let steps = (scenario.duration / dt).round() as u64;
    let h = dt / sim.substeps as f64;
    let ground = scenario.ground.filter(|g| g.enabled);
    let act = actuators(scenario);
    let ideal = act == ActuatorParams::default();
    let (allocation, demand_params) = scenario.truth_allocation();
    let mixer = Mixer::new(allocation, &act).expect("validated by Scenario::validate");
    let base_plant = scenario.actual_plant.unwrap_or(scenario.plant);

    let mut env = Environment::new(scenario.environment());
    let initial = scenario.initial_state.state();
    // An invalid rigid body (Scenario::validate refuses it; a caller may
    // skip validation) stops the run at t = 0 with the reason.
    let mut invalid_body = None;
    let mut truth = match scenario.vehicle.model {
        VehicleModel::Paper => Truth::Paper(initial.to_array()),
        VehicleModel::RigidBody => {
            let base = scenario.rigid_body_params();
            match RigidBody::new(base) {
                Ok(body) => Truth::Rigid { body, base, key: (1.0, 0.0), x: from_quad_state(&initial) },
                Err(_) => {
                    invalid_body = Some(Divergence::RigidBodyOutOfRange { mass: base.mass, inertia_scale: 1.0 });
                    Truth::Paper(initial.to_array())
                }
            }
        }
    };
    let paper_direct = ideal && matches!(truth, Truth::Paper(_));
    let hover = match &truth {
        Truth::Rigid { base, .. } => base.hover_rotor_speed(),
        Truth::Paper(_) => (base_plant.mass * base_plant.gravity / (4.0 * base_plant.lift_coefficient)).sqrt(),
    };
    let mut motors = Motors::new(&act, [hover; 4]);
    let mut noise_rng = motor_noise_rng(scenario.seed);
    // `[wind]`: mean + 1−cos gusts + Dryden turbulence (its own streams of the
    // seed), sampled once per RK4 substep and held over it.
    let mut wind = scenario.wind.clone().and_then(|w| Wind::new(w, h, scenario.seed).ok());
    // What the controller sees (`[sensors]`; its own streams 20-23 of the seed).
    let mut sensors =
        scenario.sensors.filter(|s| !s.is_perfect()).map(|s| Sensors::new(s, sim.control_rate, scenario.seed));

    let mut metrics = MetricsAccumulator::new(dt, sim.settling_band, sim.settling_floor, sim.steady_state_after)
        .with_window(sim.metrics_window);
    let mut envelope = Tracker::new(scenario.envelope);
    let mut recorder = Recorder::new(scenario, options.record, steps, controller);
    let mut exit = ExitStatus::Completed;
    let mut executed = 0;
    let mut peak_demand = 0.0f64;
    let mut saturated_periods = 0u64;

    let mut tv_now = env.time_varying(0.0);
    let mut reference = reference_at(scenario, 0.0);
    {
        let s = truth.quad_state();
        envelope.observe(0.0, &s.position, &reference.position, &s.attitude);
    }
    if let Some(divergence) = invalid_body {
        exit = ExitStatus::Diverged { divergence, time: 0.0 };
    }
    'periods: for k in 0..steps {
        if invalid_body.is_some() {
            break;
        }
        let t = k as f64 * dt;
        let state = truth.quad_state();
        // The controller flies on the measurement; metrics, the envelope and
        // the recording keep the truth.
        let measured = sensors.as_mut().map_or(state, |s| s.measure(&state));
        let command = controller.update(&measured, &reference, dt);
        env.next_period();
        let plant_now = env.params_with(&tv_now);
        let demand = rotor_speeds(&demand_params, &command, f64::INFINITY);
        peak_demand = demand.iter().fold(peak_demand, |m, &w| if w.is_finite() { m.max(w) } else { m });
        let (applied, target, saturated) = if paper_direct {
            (command, rotor_speeds(&plant_now, &command, f64::INFINITY), false)
        } else {
            let m = mixer.mix(&command);
            (m.applied, m.rotor_speeds, m.saturated)
        };
        saturated_periods += u64::from(saturated);
        controller.actuator_feedback(saturated);
        let telemetry = controller.telemetry();
        let z = motors.sample_noise(&mut noise_rng);
        let omega_now = if paper_direct { target } else { motors.with_noise(&motors.speeds(), &z) };

        // Rigid body: mass and inertia of this period.
        if let Truth::Rigid { body, base, key, .. } = &mut truth {
            let added = tv_now.mass - base_plant.mass;
            let scale = tv_now.inertia[0] / base_plant.inertia[0];
            if (added, scale) != *key {
                let mut p = *base;
                p.mass += added;
                p.inertia = p.inertia.map(|r| r.map(|v| v * scale));
                match RigidBody::new(p) {
                    Ok(b) => *body = b,
                    // Never fly a mass or inertia other than the recorded one.
                    Err(_) => {
                        let divergence = Divergence::RigidBodyOutOfRange { mass: p.mass, inertia_scale: scale };
                        exit = ExitStatus::Diverged { divergence, time: t };
                        break 'periods;
                    }
                }
                *key = (added, scale);
            }
        }

        let errors = tracking_errors(&state.to_array(), &reference, telemetry);
        let u = [applied.thrust, applied.torque[0], applied.torque[1], applied.torque[2]];
        if !(u.iter().all(|v| v.is_finite())) {
            exit = ExitStatus::Diverged { divergence: Divergence::NonFinite, time: t };
            break;
        }
        metrics.observe(t, &errors, &u);

        if recorder.due(k) {
            recorder.push(&Tick {
                t,
                state: state.to_array(),
                reference: &reference,
                telemetry,
                applied: u,
                command: &command,
                omega: omega_now,
                omega_bar: residual_speed(&omega_now),
                nominal_mass: scenario.plant.mass,
                mass: plant_now.mass,
                inertia: plant_now.inertia,
                disturbance: tv_now.disturbance,
            });
        }

        for j in 0..sim.substeps {
            let t0 = t + j as f64 * h;
            let wind_now = wind.as_mut().map_or([0.0; 3], |w| w.step(t0));
            let tv_next = env.time_varying(t0 + h);
            let (a, b, env_ref, motors_ref) = (tv_now, tv_next, &env, &motors);
            let speeds_at = |tau: f64| motors_ref.with_noise(&motors_ref.speeds_after(&target, tau - t0), &z);
            let z_prev;
            let (zr, vzr): (&mut f64, &mut f64) = match &mut truth {
                Truth::Paper(x) => {
                    z_prev = x[2];
                    *x = if paper_direct {
                        let omega_bar = residual_speed(&target);
                        let f = |tau: f64, s: &[f64; 12]| {
                            let tv = TimeVarying::lerp(&a, &b, (tau - t0) / h);
                            let p = env_ref.params_with(&tv);
                            derivative_in_wind(s, &applied, omega_bar, &p, &tv.disturbance, &wind_now)
                        };
                        rk4_step(f, t0, x, h)
                    } else {
                        let f = |tau: f64, s: &[f64; 12]| {
                            let tv = TimeVarying::lerp(&a, &b, (tau - t0) / h);
                            let p = env_ref.params_with(&tv);
                            let w = speeds_at(tau);
                            let delivered: Command = forces_from_squared_speeds(&p, &w.map(|o| o * o));
                            derivative_in_wind(s, &delivered, residual_speed(&w), &p, &tv.disturbance, &wind_now)
                        };
                        rk4_step(f, t0, x, h)
                    };
                    let (head, tail) = x.split_at_mut(8);
                    (&mut head[2], &mut tail[0])
                }
                Truth::Rigid { body, x, .. } => {
                    z_prev = x[2];
                    let body = &*body;
                    let inertia = body.params().inertia;
                    let mass = body.params().mass;
                    let f = |tau: f64, s: &RigidBodyState| {
                        let tv = TimeVarying::lerp(&a, &b, (tau - t0) / h);
                        let d = tv.disturbance;
                        let input = RigidBodyInput {
                            rotor_speeds: speeds_at(tau),
                            wind: wind_now,
                            force: [mass * d[0], mass * d[1], mass * d[2]],
                            torque: core::array::from_fn(|r| (0..3).map(|c| inertia[r][c] * d[3 + c]).sum()),
                        };
                        body.derivative(s, &input)
                    };
                    *x = rk4_step(f, t0, x, h);
                    normalize_quaternion(x);
                    let (head, tail) = x.split_at_mut(5);
                    (&mut head[2], &mut tail[0])
                }
            };
            if let Some(g) = &ground {
                if let Some((fraction, impact_speed)) = g.contact(z_prev, zr, vzr) {
                    exit = ExitStatus::Crashed { time: t0 + fraction * h, impact_speed };
                    executed = k + 1;
                    break 'periods;
                }
            }
            motors.advance(&target, h);
            tv_now = tv_next;
        }
        executed = k + 1;
        if options.step_done(executed) {
            exit = ExitStatus::Interrupted { time: (k + 1) as f64 * dt };
            break;
        }

        let t_next = (k + 1) as f64 * dt;
        reference = reference_at(scenario, t_next);
        let s = truth.quad_state();
        envelope.observe(t_next, &s.position, &reference.position, &s.attitude);
        if let Some(divergence) = check_divergence(scenario, &s.to_array(), &reference) {
            exit = ExitStatus::Diverged { divergence, time: t_next };
            break;
        }
    }

    options.flight_done(steps, executed);
    let mut metrics = metrics.finish();
    metrics.peak_rotor_speed_demand = Some(peak_demand);
    metrics.saturation_fraction = Some(if executed > 0 { saturated_periods as f64 / executed as f64 } else { 0.0 });
    RunOutput {
        controller: controller.name().to_string(),
        scenario: scenario.name.clone(),
        envelope: envelope.verdict((!exit.is_completed()).then(|| exit.to_string())),
        exit,
        metrics,
        recording: recorder.recording,
        steps: executed,
    }
}
