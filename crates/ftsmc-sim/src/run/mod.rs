//! The run loop: a controller on its own clock (zero-order hold at the
//! control period), the plant integrated by RK4 between control ticks
//! (restarting at each tick, where the input jumps), metrics accumulated
//! online and an optional time series recorded at a lower rate.
//!
//! A run that diverges is an outcome ([`ExitStatus::Diverged`] with the
//! reason and time), never a panic.

use ftsmc_core::allocation::{forces_from_squared_speeds, residual_speed, rotor_speeds};
use ftsmc_core::cascade::{Controller, Telemetry};
use ftsmc_core::model::{Command, QuadState, QuadrotorParams, Reference};

use crate::environment::{Environment, TimeVarying};
use crate::metrics::{Metrics, MetricsAccumulator};
use crate::scenario::Scenario;
use crate::vehicle::paper::{derivative, rk4_step};

mod exit;
mod recording;
pub mod summary;
pub mod truth;

use exit::check_divergence;
pub use exit::{Divergence, ExitStatus};
pub use recording::{push_number, recording_columns, Recording, MAX_RECORDING_COLUMNS};
use recording::{Recorder, Tick};
use std::sync::atomic::{AtomicBool, Ordering};

/// Result of one flight.
#[derive(Clone, Debug)]
pub struct RunOutput {
    /// Controller name.
    pub controller: String,
    /// Scenario name.
    pub scenario: String,
    /// How the run ended.
    pub exit: ExitStatus,
    /// Metrics up to the end (or divergence).
    pub metrics: Metrics,
    /// Time series (empty when recording is off).
    pub recording: Recording,
    /// Control steps executed.
    pub steps: u64,
    /// The success envelope's verdict (`None`: the scenario has no `[envelope]`).
    pub envelope: Option<crate::envelope::Verdict>,
}

impl RunOutput {
    /// Completed and inside the scenario's envelope (just completed without one).
    pub fn success(&self) -> bool {
        self.envelope.as_ref().map_or(self.exit.is_completed(), |v| v.success)
    }
}

/// The reference of `scenario` at time `t`.
#[inline]
pub fn reference_at(scenario: &Scenario, t: f64) -> Reference {
    let r = &scenario.reference;
    let (x, y, z, psi) = (r.x.sample(t), r.y.sample(t), r.z.sample(t), r.psi.sample(t));
    Reference {
        position: [x.value, y.value, z.value],
        velocity: [x.rate, y.rate, z.rate],
        acceleration: [x.acceleration, y.acceleration, z.acceleration],
        yaw: psi.value,
        yaw_rate: psi.rate,
        yaw_acceleration: psi.acceleration,
    }
}

/// Options of one run (construct with `RunOptions { record: false, ..Default::default() }`).
#[derive(Clone, Copy)]
pub struct RunOptions<'a> {
    /// Record the time series at `simulation.record_rate`.
    pub record: bool,
    /// Called with the number of control steps flown since the last call,
    /// every [`PROGRESS_EVERY`] steps and once at the end (the remainder of
    /// the planned steps, so a diverged run still adds its planned total).
    pub progress: Option<&'a (dyn Fn(u64) + Sync)>,
    /// Cancellation: when set to `true` (by another thread, e.g. on Ctrl-C),
    /// the run stops within [`PROGRESS_EVERY`] control steps with
    /// [`ExitStatus::Interrupted`].
    pub cancel: Option<&'a AtomicBool>,
}

/// Control steps between two [`RunOptions::progress`] calls.
pub const PROGRESS_EVERY: u64 = 1000;

impl Default for RunOptions<'_> {
    fn default() -> Self {
        Self { record: true, progress: None, cancel: None }
    }
}

impl RunOptions<'_> {
    /// After control step `executed` (1-based): report [`PROGRESS_EVERY`]
    /// steps when `executed` is a multiple of it, and then also check the
    /// cancellation flag. True when the run must stop (cancelled).
    pub(crate) fn step_done(&self, executed: u64) -> bool {
        if executed % PROGRESS_EVERY != 0 {
            return false;
        }
        if let Some(progress) = self.progress {
            progress(PROGRESS_EVERY);
        }
        self.cancelled()
    }

    /// True when [`RunOptions::cancel`] is set.
    pub fn cancelled(&self) -> bool {
        self.cancel.is_some_and(|c| c.load(Ordering::Relaxed))
    }

    /// At the end of a flight of `planned` steps that stopped after
    /// `executed`: report the rest of the planned total.
    pub(crate) fn flight_done(&self, planned: u64, executed: u64) {
        if let Some(progress) = self.progress {
            progress(planned - executed / PROGRESS_EVERY * PROGRESS_EVERY);
        }
    }
}

impl core::fmt::Debug for RunOptions<'_> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("RunOptions")
            .field("record", &self.record)
            .field("progress", &self.progress.is_some())
            .field("cancel", &self.cancel.is_some())
            .finish()
    }
}

/// Control steps a flight of `scenario` plans (its progress total).
pub fn planned_steps(scenario: &Scenario) -> u64 {
    (scenario.duration / scenario.control_period()).round() as u64
}

/// The command as the rotors deliver it: the applied thrust and torques
/// (after the rotor-speed limits, when set), the rotor speeds (rad/s) and
/// their residual Ω̄.
fn realise(command: &Command, plant: &QuadrotorParams, max_rotor_speed: Option<f64>) -> (Command, [f64; 4], f64) {
    let omega = rotor_speeds(plant, command, max_rotor_speed.unwrap_or(f64::INFINITY));
    let applied = match max_rotor_speed {
        Some(_) => forces_from_squared_speeds(plant, &omega.map(|o| o * o)),
        None => *command,
    };
    (applied, omega, residual_speed(&omega))
}

/// Tracking errors `[e_x, e_y, e_z, e_φ, e_θ, e_ψ]` the metrics integrate:
/// position against the reference, roll and pitch against the attitude
/// reference the controller tracks (its telemetry), yaw against ψ_d.
/// `state` is `[x, y, z, φ, θ, ψ, …]`.
fn tracking_errors(state: &[f64; 12], reference: &Reference, telemetry: &Telemetry) -> [f64; 6] {
    [
        state[0] - reference.position[0],
        state[1] - reference.position[1],
        state[2] - reference.position[2],
        state[3] - telemetry.attitude_reference[0],
        state[4] - telemetry.attitude_reference[1],
        state[5] - reference.yaw,
    ]
}

/// Fly `controller` through `scenario`.
pub fn simulate(scenario: &Scenario, controller: &mut dyn Controller, options: RunOptions<'_>) -> RunOutput {
    // Hook (issue 11): rigid body, real actuators or a ground fly the realistic loop.
    if truth::is_realistic(scenario) {
        return truth::simulate_realistic(scenario, controller, options);
    }
    let sim = &scenario.simulation;
    let dt = scenario.control_period();
    let steps = (scenario.duration / dt).round() as u64;
    let h = dt / sim.substeps as f64;

    let mut env = Environment::new(scenario.environment());
    let mut x = scenario.initial_state.state().to_array();
    let mut metrics = MetricsAccumulator::new(dt, sim.settling_band, sim.settling_floor, sim.steady_state_after)
        .with_window(sim.metrics_window);
    let mut recorder = Recorder::new(scenario, options.record, steps, controller);
    let mut exit = ExitStatus::Completed;
    let mut executed = 0;
    let mut envelope = crate::envelope::Tracker::new(scenario.envelope); // issue 11 hook
    envelope.observe(0.0, &x[0..3], &reference_at(scenario, 0.0).position, &x[3..5]);

    // Time-varying plant inputs are evaluated once per substep boundary and
    // interpolated linearly inside the substep (RK4 stage times); this keeps
    // the integration second-order in the inputs' time variation while
    // evaluating each sinusoid once per substep instead of four times.
    let mut tv_now = env.time_varying(0.0);
    let mut reference = reference_at(scenario, 0.0);
    for k in 0..steps {
        let t = k as f64 * dt;
        let state = QuadState::from_array(&x);
        let command = controller.update(&state, &reference, dt);
        let telemetry = controller.telemetry();
        env.next_period();
        let plant_now = env.params_with(&tv_now);
        let (applied, omega, omega_bar) = realise(&command, &plant_now, sim.max_rotor_speed);

        let errors = tracking_errors(&x, &reference, telemetry);
        let u = [applied.thrust, applied.torque[0], applied.torque[1], applied.torque[2]];
        if !(u.iter().all(|v| v.is_finite())) {
            exit = ExitStatus::Diverged { divergence: Divergence::NonFinite, time: t };
            break;
        }
        metrics.observe(t, &errors, &u);

        if recorder.due(k) {
            recorder.push(&Tick {
                t,
                state: x,
                reference: &reference,
                telemetry,
                applied: u,
                command: &command,
                omega,
                omega_bar,
                nominal_mass: scenario.plant.mass,
                mass: plant_now.mass,
                inertia: plant_now.inertia,
                disturbance: tv_now.disturbance,
            });
        }

        // Plant between ticks: RK4 substeps with the command held.
        for j in 0..sim.substeps {
            let t0 = t + j as f64 * h;
            let tv_next = env.time_varying(t0 + h);
            let (a, b, env_ref) = (tv_now, tv_next, &env);
            let f = |tau: f64, s: &[f64; 12]| {
                let tv = TimeVarying::lerp(&a, &b, (tau - t0) / h);
                derivative(s, &applied, omega_bar, &env_ref.params_with(&tv), &tv.disturbance)
            };
            x = rk4_step(f, t0, &x, h);
            tv_now = tv_next;
        }
        executed = k + 1;
        if options.step_done(executed) {
            exit = ExitStatus::Interrupted { time: (k + 1) as f64 * dt };
            break;
        }

        let t_next = (k + 1) as f64 * dt;
        reference = reference_at(scenario, t_next);
        envelope.observe(t_next, &x[0..3], &reference.position, &x[3..5]);
        if let Some(divergence) = check_divergence(scenario, &x, &reference) {
            exit = ExitStatus::Diverged { divergence, time: t_next };
            break;
        }
    }

    options.flight_done(steps, executed);
    RunOutput {
        controller: controller.name().to_string(),
        scenario: scenario.name.clone(),
        envelope: envelope.verdict((!exit.is_completed()).then(|| exit.to_string())),
        exit,
        metrics: metrics.finish(),
        recording: recorder.recording,
        steps: executed,
    }
}
