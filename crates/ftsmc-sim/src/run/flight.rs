//! [`Flight`]: one flight as a steppable object. [`crate::run::simulate`]
//! builds one and steps it to the end; anything that needs to drive a
//! flight tick by tick (an external agent, a batch of lanes) uses it directly.
//!
//! # One control tick ([`Flight::step`])
//!
//! 1. **Sensors**: the controller is given the measurement of the truth's
//!    Euler state (`[sensors]`; the truth itself with perfect sensors).
//! 2. **Controller** on its own clock: one update per control period
//!    `dt = 1 / simulation.control_rate`, its command held over the period.
//! 3. **Environment**: the period's drag noise; the true plant of the tick.
//! 4. **Actuator stage** ([`super::actuation`]): ideal, per-rotor clamp, or
//!    mixer + lagged noisy motors; its saturation flag goes back to the
//!    controller (`actuator_feedback`).
//! 5. **Observers** ([`super::observer`]) see the whole tick: metrics,
//!    recording, flight statistics (and the envelope at the period boundaries).
//! 6. **Truth model** integrated over the period by `simulation.substeps`
//!    RK4 substeps ([`super::truth`]), with the wind sampled once per
//!    substep and the ground checked after each.
//! 7. The next reference; divergence checks.

use ftsmc_core::allocation::{residual_speed, rotor_speeds};
use ftsmc_core::cascade::Controller;
use ftsmc_core::measured::{BodyAttitude, Measurement};
use ftsmc_core::model::{QuadState, QuadrotorParams, Reference};

use crate::envelope::Tracker;
use crate::environment::ground::GroundSettings;
use crate::environment::wind::Wind;
use crate::environment::{Environment, TimeVarying};
use crate::metrics::MetricsAccumulator;
use crate::scenario::Scenario;
use crate::sensors::Sensors;
use crate::signal::grid::GridSignal;

use super::actuation::{ActuatorStage, Delivered};
use super::exit::check_divergence;
use super::observer::{FlightStats, Observer, Tick};
use super::recording::Recorder;
use super::truth::{truth_of, Substep, TruthModel, TruthSetup};
use super::{tracking_errors, Divergence, ExitStatus, RunOptions, RunOutput};

/// The scenario's reference signals `x, y, z, ψ` on the control grid
/// `t_k = k·dt`: [`super::reference_at`] with the sines and cosines rotated
/// along the grid ([`crate::signal::grid`]), equal to it to rounding.
struct ReferenceGrid {
    x: GridSignal,
    y: GridSignal,
    z: GridSignal,
    psi: GridSignal,
}

impl ReferenceGrid {
    fn new(scenario: &Scenario, dt: f64) -> Self {
        let r = &scenario.reference;
        let g = |s| GridSignal::new(s, dt);
        Self { x: g(&r.x), y: g(&r.y), z: g(&r.z), psi: g(&r.psi) }
    }

    /// The reference at control step `k`, whose time the loop computed as `t` (s).
    fn at(&mut self, k: u64, t: f64) -> Reference {
        super::reference_of([self.x.sample(k, t), self.y.sample(k, t), self.z.sample(k, t), self.psi.sample(k, t)])
    }
}

/// What one [`Flight::step`] did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StepOutcome {
    /// The period was flown; the flight goes on.
    Flying,
    /// The flight is over (completed, diverged or crashed: [`Flight::exit`]).
    Done,
}

/// One flight of a controller through a scenario, advanced one control
/// period at a time.
pub struct Flight<'s, C: Controller + ?Sized> {
    scenario: &'s Scenario,
    controller: &'s mut C,
    options: RunOptions<'s>,
    dt: f64,
    h: f64,
    steps: u64,
    k: u64,
    env: Environment<'s>,
    truth: Box<dyn TruthModel + Send>,
    /// The truth's Euler state at the current period boundary (converted once per period).
    state: QuadState,
    /// The truth's quaternion and body rates at the same boundary, if it has them.
    body: Option<BodyAttitude>,
    /// The controller flies [`Measurement::body`] (`Controller::uses_body_attitude`).
    wants_body: bool,
    actuators: ActuatorStage,
    demand_params: QuadrotorParams,
    base_plant: QuadrotorParams,
    sensors: Option<Sensors>,
    wind: Option<Wind>,
    ground: Option<GroundSettings>,
    tv_now: TimeVarying,
    reference: Reference,
    reference_grid: ReferenceGrid,
    metrics: MetricsAccumulator,
    recorder: Recorder,
    envelope: Tracker,
    stats: FlightStats,
    observers: Vec<&'s mut dyn Observer>,
    legacy_rotor_metrics: bool,
    peak_demand: f64,
    saturated_periods: u64,
    exit: Option<ExitStatus>,
    /// The measurement of the coming tick when it was taken ahead of
    /// [`Flight::step`] by [`Flight::measurement`].
    measured_ahead: Option<QuadState>,
    /// Its body attitude (full-state controllers only).
    body_ahead: Option<BodyAttitude>,
}

/// True when the two rotor metrics of [`crate::metrics::Metrics`]
/// (`peak_rotor_speed_demand`, `saturation_fraction`) are reported: any
/// model beyond the paper's (rigid body, `[actuators]`, ground, sensors,
/// wind). [`RunOutput::stats`] has them for every flight.
fn reports_rotor_metrics(scenario: &Scenario) -> bool {
    scenario.vehicle.model != crate::vehicle::VehicleModel::Paper
        || scenario.actuators.is_some_and(|a| a != crate::actuators::ActuatorParams::default())
        || scenario.ground.is_some_and(|g| g.enabled)
        || scenario.sensors.is_some_and(|s| !s.is_perfect())
        || scenario.wind.is_some()
}

impl<'s, C: Controller + ?Sized> Flight<'s, C> {
    /// A flight of `controller` through `scenario` at `t = 0` (the scenario
    /// validated: `Scenario::validate`).
    pub fn new(scenario: &'s Scenario, controller: &'s mut C, options: RunOptions<'s>) -> Self {
        let sim = &scenario.simulation;
        let dt = scenario.control_period();
        let steps = super::planned_steps(scenario);
        let h = dt / sim.substeps as f64;
        let TruthSetup { truth, allocation, demand: demand_params, hover, invalid } = truth_of(scenario);
        let actuators = ActuatorStage::of(scenario, allocation, hover, h);
        let mut env_params = scenario.environment();
        if scenario.vehicle.model == crate::vehicle::VehicleModel::RigidBody {
            // The paper's drag coefficients (and their noise) act on Eq. 1 only:
            // no draws that feed nothing.
            env_params.drag_noise = None;
        }
        // Sampled at the substep boundaries t_m = m·h: the sinusoids rotate along the grid.
        let mut env = Environment::new(env_params).on_grid(h);
        let wind = scenario.wind.clone().and_then(|w| Wind::new(w, h, scenario.seed).ok());
        let sensors =
            scenario.sensors.filter(|s| !s.is_perfect()).map(|s| Sensors::new(s, sim.control_rate, scenario.seed));
        let metrics = MetricsAccumulator::new(dt, sim.settling_band, sim.settling_floor, sim.steady_state_after)
            .with_window(sim.metrics_window);
        let recorder = Recorder::new(scenario, options.record, steps, &*controller);
        let tv_now = env.time_varying_on_grid(0, 0.0);
        let mut reference_grid = ReferenceGrid::new(scenario, dt);
        let reference = reference_grid.at(0, 0.0);
        let wants_body = controller.uses_body_attitude();
        let mut flight = Self {
            scenario,
            controller,
            options,
            dt,
            h,
            steps,
            k: 0,
            env,
            state: truth.quad_state(),
            body: if wants_body { truth.body_attitude() } else { None },
            wants_body,
            truth,
            actuators,
            demand_params,
            base_plant: scenario.true_plant(),
            sensors,
            wind,
            ground: scenario.ground.filter(|g| g.enabled),
            tv_now,
            reference,
            reference_grid,
            metrics,
            recorder,
            envelope: Tracker::new(scenario.envelope),
            stats: FlightStats::default(),
            observers: Vec::new(),
            legacy_rotor_metrics: reports_rotor_metrics(scenario),
            peak_demand: 0.0,
            saturated_periods: 0,
            exit: None,
            measured_ahead: None,
            body_ahead: None,
        };
        flight.boundary(0.0);
        if let Some(divergence) = invalid {
            flight.exit = Some(ExitStatus::Diverged { divergence, time: 0.0 });
        }
        flight
    }

    /// Add an observer of every tick and period boundary from now on; it
    /// first sees the boundary the flight is at (`t = 0` for a new flight).
    pub fn observe_with(&mut self, observer: &'s mut dyn Observer) {
        if self.exit.is_none() {
            observer.boundary(self.k as f64 * self.dt, &self.state, &self.reference);
        }
        self.observers.push(observer);
    }

    /// Control steps flown so far.
    pub fn steps_flown(&self) -> u64 {
        self.k
    }

    /// Control steps the flight plans.
    pub fn planned_steps(&self) -> u64 {
        self.steps
    }

    /// How the flight ended (`None` while it is flying).
    pub fn exit(&self) -> Option<&ExitStatus> {
        self.exit.as_ref()
    }

    /// The measurement the controller will be given at the coming tick
    /// (the sensor stage's output; the truth with perfect sensors), taken
    /// now and handed to the next [`Flight::step`]: an agent outside the
    /// loop sees exactly what the controller stage sees. The sensors are
    /// read once per tick however often this is called.
    pub fn measurement(&mut self) -> QuadState {
        if let Some(m) = self.measured_ahead {
            return m;
        }
        let m = self.measure();
        self.measured_ahead = Some(m.euler);
        self.body_ahead = m.body;
        m.euler
    }

    /// The sensor stage's reading of the truth at the current boundary.
    fn measure(&mut self) -> Measurement {
        let truth = Measurement { euler: self.state, body: self.body };
        match self.sensors.as_mut() {
            Some(s) => s.measure_full(&truth),
            None => truth,
        }
    }

    /// The truth's Euler state at the current period boundary.
    pub fn truth_state(&self) -> &QuadState {
        &self.state
    }

    /// The reference at the current period boundary.
    pub fn reference(&self) -> &Reference {
        &self.reference
    }

    /// The controller being flown (e.g. to hand an external agent's
    /// command to it between two steps).
    pub fn controller_mut(&mut self) -> &mut C {
        self.controller
    }

    fn boundary(&mut self, t: f64) {
        let s = self.state;
        self.envelope.boundary(t, &s, &self.reference);
        self.stats.boundary(t, &s, &self.reference);
        for o in &mut self.observers {
            o.boundary(t, &s, &self.reference);
        }
    }

    fn end(&mut self, exit: ExitStatus) -> StepOutcome {
        self.exit = Some(exit);
        StepOutcome::Done
    }

    /// Fly one control period (module docs); [`StepOutcome::Done`] once the
    /// flight is over (and on every later call).
    pub fn step(&mut self) -> StepOutcome {
        if self.exit.is_some() {
            return StepOutcome::Done;
        }
        if self.k >= self.steps {
            return self.end(ExitStatus::Completed);
        }
        let (k, dt, h) = (self.k, self.dt, self.h);
        let t = k as f64 * dt;
        let state = self.state;
        let (measured, command) = if self.wants_body {
            let reading = match self.measured_ahead.take() {
                Some(euler) => Measurement { euler, body: self.body_ahead.take() },
                None => self.measure(),
            };
            (reading.euler, self.controller.update_measured(&reading, &self.reference, dt))
        } else {
            // The Euler state alone: no body attitude is built or copied.
            let measured = match self.measured_ahead.take() {
                Some(m) => m,
                None => self.sensors.as_mut().map_or(state, |s| s.measure(&state)),
            };
            (measured, self.controller.update(&measured, &self.reference, dt))
        };
        let measured = &measured;
        self.env.next_period();
        let plant_now = self.env.params_with(&self.tv_now);
        let delivered: Delivered = self.actuators.deliver(&command, &plant_now);
        let demand = delivered.demand.unwrap_or_else(|| rotor_speeds(&self.demand_params, &command, f64::INFINITY));
        if self.legacy_rotor_metrics {
            self.peak_demand = demand.iter().fold(self.peak_demand, |m, &w| if w.is_finite() { m.max(w) } else { m });
            self.saturated_periods += u64::from(delivered.saturated);
        }
        self.controller.actuator_feedback(delivered.saturated);
        if let Err(divergence) = self.truth.begin_period(0, &self.tv_now, &self.base_plant) {
            return self.end(ExitStatus::Diverged { divergence, time: t });
        }

        let applied = delivered.applied;
        let u = [applied.thrust, applied.torque[0], applied.torque[1], applied.torque[2]];
        if !(u.iter().all(|v| v.is_finite())) {
            return self.end(ExitStatus::Diverged { divergence: Divergence::NonFinite, time: t });
        }
        {
            let telemetry = self.controller.telemetry();
            let x = state.to_array();
            let tick = Tick {
                k,
                t,
                state: x,
                measured,
                reference: &self.reference,
                telemetry,
                errors: tracking_errors(&x, &self.reference, telemetry),
                command: &command,
                applied: u,
                omega: delivered.omega,
                omega_bar: residual_speed(&delivered.omega),
                demand,
                saturated: delivered.saturated,
                nominal_mass: self.scenario.plant.mass,
                mass: plant_now.mass,
                inertia: plant_now.inertia,
                disturbance: self.tv_now.disturbance,
            };
            self.metrics.tick(&tick);
            self.recorder.tick(&tick);
            self.stats.tick(&tick);
            for o in &mut self.observers {
                o.tick(&tick);
            }
        }

        let omega_bar = residual_speed(&delivered.target);
        let substeps = self.scenario.simulation.substeps;
        for j in 0..substeps {
            let t0 = t + j as f64 * h;
            let wind = self.wind.as_mut().map(|w| w.step(t0));
            let tv_next = self.env.time_varying_on_grid(k * u64::from(substeps) + u64::from(j) + 1, t0 + h);
            let z_prev = self.truth.vertical(0).0;
            self.truth.substep(core::slice::from_ref(&Substep {
                t0,
                h,
                a: self.tv_now,
                b: tv_next,
                env: &self.env,
                drive: self.actuators.drive(&delivered, omega_bar),
                wind,
            }));
            if let Some(g) = &self.ground {
                let (mut z, mut vz) = self.truth.vertical(0);
                let contact = g.contact(z_prev, &mut z, &mut vz);
                self.truth.set_vertical(0, z, vz);
                if let Some((fraction, impact_speed)) = contact {
                    self.k = k + 1;
                    return self.end(ExitStatus::Crashed { time: t0 + fraction * h, impact_speed });
                }
            }
            self.actuators.advance(&delivered.target);
            self.tv_now = tv_next;
        }
        self.k = k + 1;
        if self.options.step_done(self.k) {
            return self.end(ExitStatus::Interrupted { time: self.k as f64 * dt });
        }

        let t_next = (k + 1) as f64 * dt;
        self.reference = self.reference_grid.at(k + 1, t_next);
        self.state = self.truth.quad_state();
        if self.wants_body {
            self.body = self.truth.body_attitude();
        }
        self.boundary(t_next);
        if let Some(divergence) = check_divergence(self.scenario, &self.state.to_array(), &self.reference) {
            return self.end(ExitStatus::Diverged { divergence, time: t_next });
        }
        if self.k >= self.steps {
            return self.end(ExitStatus::Completed);
        }
        StepOutcome::Flying
    }

    /// Step to the end and return the outcome.
    pub fn run(mut self) -> RunOutput {
        while self.step() == StepOutcome::Flying {}
        self.finish()
    }

    /// The outcome so far (a flight stopped early reports `Completed` over
    /// the steps flown).
    pub fn finish(self) -> RunOutput {
        let exit = self.exit.unwrap_or(ExitStatus::Completed);
        self.options.flight_done(self.steps, self.k);
        let mut metrics = self.metrics.finish();
        if self.legacy_rotor_metrics {
            metrics.peak_rotor_speed_demand = Some(self.peak_demand);
            metrics.saturation_fraction =
                Some(if self.k > 0 { self.saturated_periods as f64 / self.k as f64 } else { 0.0 });
        }
        RunOutput {
            controller: self.controller.name().to_string(),
            scenario: self.scenario.name.clone(),
            envelope: self.envelope.verdict((!exit.is_completed()).then(|| exit.to_string())),
            exit,
            metrics,
            recording: self.recorder.recording,
            steps: self.k,
            stats: self.stats,
        }
    }
}
