//! [`Flight`]: one flight as a steppable object. [`crate::run::simulate`]
//! builds one and steps it to the end; anything that needs to drive a
//! flight tick by tick (an external agent, a batch of lanes) uses it directly.
//!
//! # One control tick ([`Flight::step`]): a short pipeline
//!
//! ```text
//! measure each lane → controller.update (on R) → actuate and observe each lane
//!   → substeps: each lane begins, truth.substep (on R), each lane ends → boundary
//! ```
//!
//! 1. **Measure** ([`LaneFlight::measure`]): the sensors' reading of the truth
//!    (`[sensors]`; the truth itself with perfect sensors), or, when
//!    `[sensors]` names an estimator or a sensor table, the sensor stages
//!    sampled and the estimator's output ([`crate::sensors::pipeline`]; an
//!    estimator that fails ends the flight, [`Divergence::Estimator`]).
//! 2. **Controller** on its own clock: one update per control period
//!    `dt = 1 / simulation.control_rate`, its command held over the period.
//! 3. **Actuate** ([`LaneFlight::actuate`]): the period's drag noise, then the
//!    actuator stage ([`super::actuation`]: ideal, per-rotor clamp, or
//!    mixer + lagged noisy motors); its saturation flag goes back to the
//!    controller (`actuator_feedback`).
//! 4. **Observe** ([`LaneFlight::observe`]): the flight's one observer list
//!    (metrics, recorder, statistics, envelope, the user's observers) sees
//!    the whole tick ([`Tick`]).
//! 5. **Substeps**: the truth model integrates the period by
//!    `simulation.substeps` RK4 substeps (`run/truth.rs`); before each,
//!    every lane samples its wind and plant variation
//!    ([`LaneFlight::begin_substep`]), after each it checks the ground and moves
//!    its motors on ([`LaneFlight::end_substep`]).
//! 6. **Boundary**: the next reference, the observers, the divergence checks.
//!
//! # Lanes
//!
//! A flight's numbers may be `f64` (one flight, [`Flight::new`]) or lanes
//! of `N` flights side by side ([`Flights::new_lanes`], `R = Lanes<N>`,
//! [`ftsmc_core::lanes`]). Only the controller's update and the truth's
//! substep compute on the lanes; every other stage is a method of
//! [`LaneFlight`], one flight's code whatever `N`, fed lane `i`'s numbers. Each
//! lane is an independent flight with its own scenario, clock, observers
//! and exit: lane `i` has exactly the bits the same flight has alone,
//! whatever `N` and whatever lane it lands in, and a batch starts the next
//! flight in a lane whose flight ended ([`Flights::start_lane`]).

use std::sync::Arc;

use ftsmc_core::allocation::{residual_speed, rotor_speeds};
use ftsmc_core::cascade::{Controller, Telemetry};
use ftsmc_core::lanes::{Lanewise, Mask, Real};
use ftsmc_core::measured::{BodyAttitude, Measurement};
use ftsmc_core::model::{Command, QuadState, QuadrotorParams, Reference};

use crate::envelope::Tracker;
use crate::environment::ground::{Contact, GroundContact, GroundSettings};
use crate::environment::wind::Wind;
use crate::environment::{Environment, TimeVarying};
use crate::metrics::MetricsAccumulator;
use crate::scenario::Scenario;
use crate::sensors::pipeline::{self, Pipeline};
use crate::sensors::Sensors;
use crate::signal::grid::GridSignal;

use super::actuation::{ActuatorStage, Delivered};
use super::exit::check_divergence;
use super::observer::{FlightStats, Observer, Tick};
use super::recording::Recorder;
use super::truth::{truth_lanes, truth_of, LaneStart, Substep, TruthModel, TruthSetup};
use super::{tracking_errors, Divergence, ExitStatus, RunOptions, RunOutput};

/// The scenario's reference signals `x, y, z, ψ` on the control grid
/// `t_k = k·dt`: [`super::reference_at`] with the sines and cosines rotated
/// along the grid ([`crate::signal::grid`]), equal to it to rounding.
struct ReferenceGrid {
    x: GridSignal,
    y: GridSignal,
    z: GridSignal,
    psi: GridSignal,
    /// The scenario's trajectory, when it has one (sampled instead of the signals).
    trajectory: Option<crate::trajectory::Trajectory>,
}

impl ReferenceGrid {
    fn new(scenario: &Scenario, dt: f64) -> Self {
        let r = &scenario.reference;
        let g = |s| GridSignal::new(s, dt);
        Self { x: g(&r.x), y: g(&r.y), z: g(&r.z), psi: g(&r.psi), trajectory: r.trajectory.clone() }
    }

    /// The reference at control step `k`, whose time the loop computed as `t` (s).
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn at(&mut self, k: u64, t: f64) -> Reference {
        if let Some(trajectory) = &self.trajectory {
            return super::reference_of_flat(&trajectory.sample(t));
        }
        super::reference_of([self.x.sample(k, t), self.y.sample(k, t), self.z.sample(k, t), self.psi.sample(k, t)])
    }
}

/// What one [`Flight::step`] did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StepOutcome {
    /// The period was flown; the flight goes on (with lanes: some lane's does).
    Flying,
    /// The flight is over (completed, diverged or crashed: [`Flight::exit`];
    /// with lanes: every lane's).
    Done,
}

/// True when the two rotor metrics of [`crate::metrics::Metrics`]
/// (`peak_rotor_speed_demand`, `saturation_fraction`) are reported: any
/// model beyond the paper's (rigid body, `[actuators]`, ground, sensors,
/// wind). [`RunOutput::stats`] has them for every flight.
fn reports_rotor_metrics(scenario: &Scenario) -> bool {
    scenario.vehicle.model != crate::vehicle::VehicleModel::Paper
        || scenario.actuators.is_some_and(|a| a != crate::actuators::ActuatorParams::default())
        || scenario.ground.is_some_and(|g| g.enabled)
        || scenario.sensors.is_some_and(|s| !s.controller_sees_truth())
        || scenario.wind.is_some()
}

/// Every observer of one flight, in the order they see a tick: the
/// metrics, the recorder (recording only when the run asks for it,
/// [`RunOptions::record`]), the statistics, the envelope (at the period
/// boundaries) and the user's observers ([`Flight::observe_with`]).
struct Observers<'o> {
    metrics: MetricsAccumulator,
    recorder: Recorder,
    stats: FlightStats,
    envelope: Tracker,
    /// The robustness margin to the envelope ([`crate::margin`]).
    margin: crate::margin::MarginTracker,
    user: Vec<&'o mut (dyn Observer + Send)>,
}

impl Observers<'_> {
    /// Some observer reads [`Tick::telemetry`] at tick `k`
    /// ([`Observer::reads_telemetry`]): only then is the lane's telemetry
    /// gathered from the controller's lanes.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn read_telemetry(&self, k: u64) -> bool {
        self.recorder.reads_telemetry(k) || self.user.iter().any(|o| o.reads_telemetry(k))
    }

    /// Every observer sees `tick`.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn tick(&mut self, tick: &Tick<'_>) {
        self.metrics.tick(tick);
        self.recorder.tick(tick);
        self.stats.tick(tick);
        for o in &mut self.user {
            o.tick(tick);
        }
    }

    /// Every observer sees the truth at the period boundary `t` (s).
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn boundary(&mut self, t: f64, truth: &QuadState, reference: &Reference) {
        self.envelope.boundary(t, truth, reference);
        self.margin.update(t, &truth.position, &reference.position, &truth.attitude);
        self.stats.boundary(t, truth, reference);
        for o in &mut self.user {
            o.boundary(t, truth, reference);
        }
    }
}

/// One flight of a [`Flight`] (one lane): its scenario, clock,
/// environment, sensors, actuator stage, wind, observers and exit, and the
/// stages of a tick that run flight by flight ([`Flight::step`]).
struct LaneFlight<'o> {
    scenario: Arc<Scenario>,
    dt: f64,
    h: f64,
    substeps: u32,
    steps: u64,
    k: u64,
    /// The time of the period boundary `k`, `k as f64 · dt` (s), converted
    /// once per period (every reader takes these bits); set with `k` by
    /// [`LaneFlight::set_step`].
    t: f64,
    env: Environment,
    actuators: ActuatorStage,
    demand_params: QuadrotorParams,
    base_plant: QuadrotorParams,
    sensors: Option<Sensors>,
    /// The sensor stages and the estimator, when `[sensors]` asks for them
    /// (then `sensors` is `None`).
    pipeline: Option<Pipeline>,
    /// The pipeline's recorded columns at the last recorded tick.
    pipeline_row: Vec<f64>,
    /// The measurement of the coming tick, when it was taken ahead of the
    /// step ([`Flight::measurement`]).
    measured_ahead: Option<Measurement>,
    /// The truth's Euler state at the lane's period boundary (its copy of
    /// lane `i` of [`Flights`]'s boundary state).
    state: QuadState,
    /// What the controller was given this tick when it was not the truth
    /// itself ([`LaneFlight::measure`]; `None`: it was `state`).
    measured: Option<QuadState>,
    /// The controller's telemetry of this lane, gathered from the lanes at
    /// the ticks some observer reads it ([`Observers::read_telemetry`]).
    telemetry: Telemetry,
    wind: Option<Wind>,
    ground: Option<GroundSettings>,
    /// The flight's ground-contact history (take-off, time on the ground).
    contact: GroundContact,
    tv_now: TimeVarying,
    /// The next substep boundary's plant variation (set before the truth
    /// integrates the lanes).
    tv_next: TimeVarying,
    wind_now: Option<[f64; 3]>,
    /// Position at the start of the substep (ground contact only).
    p_prev: [f64; 3],
    reference_grid: ReferenceGrid,
    /// The reference at the lane's current period boundary (the lane's copy
    /// of [`Flight`]'s reference, read by the observers and the checks).
    reference: Reference,
    observers: Observers<'o>,
    /// The scenario reports the two rotor metrics of
    /// [`crate::metrics::Metrics`] ([`reports_rotor_metrics`]).
    rotor_metrics: bool,
    /// The last delivered period was not observed (the flight ended at its
    /// tick): its saturation and demand, which the rotor metrics count.
    unobserved: Option<(bool, [f64; 4])>,
    /// This period's delivery (the truth reads its drive during the
    /// substeps) and its unlimited rotor-speed demand.
    delivered: Delivered,
    /// The lagged motors' command over the coming substep, prepared once
    /// per substep ([`ActuatorStage::held`]).
    held: crate::actuators::HeldCommand,
    demand: [f64; 4],
    /// The true plant of the period (formed only for an actuator stage that
    /// reads it, [`ActuatorStage::reads_plant`]).
    plant_now: QuadrotorParams,
    omega_bar: f64,
    /// The lane completed a period at this step (its boundary is observed).
    at_boundary: bool,
    exit: Option<ExitStatus>,
}

impl<'o> LaneFlight<'o> {
    /// The flight of `scenario` at `t = 0` (its actuator stage built from
    /// the truth model's allocation) and its reference at `t = 0`.
    fn new(owned: Arc<Scenario>, recorder: Recorder) -> (Self, Reference) {
        let scenario = &*owned;
        let sim = &scenario.simulation;
        let dt = scenario.control_period();
        let steps = super::planned_steps(scenario);
        let h = dt / sim.substeps as f64;
        let TruthSetup { allocation, demand: demand_params, hover, .. } = truth_of(scenario);
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
        let base_plant = scenario.true_vehicle();
        let pipeline = scenario.sensors.filter(pipeline::requested).map(|s| {
            Pipeline::new(&s, sim.control_rate, scenario.seed, &scenario.initial_state.state(), base_plant.gravity)
        });
        let sensors = scenario
            .sensors
            .filter(|s| pipeline.is_none() && !s.is_perfect())
            .map(|s| Sensors::new(s, sim.control_rate, scenario.seed));
        let pipeline_row = vec![f64::NAN; pipeline.as_ref().map_or(0, |p| p.column_names().len())];
        let metrics = MetricsAccumulator::new(dt, sim.settling_band, sim.settling_floor, sim.steady_state_after)
            .with_window(sim.metrics_window);
        let tv_now = env.time_varying_on_grid(0, 0.0);
        let mut reference_grid = ReferenceGrid::new(scenario, dt);
        let reference = reference_grid.at(0, 0.0);
        let observers = Observers {
            metrics,
            recorder,
            stats: FlightStats::default(),
            envelope: Tracker::new(scenario.envelope),
            margin: crate::margin::MarginTracker::new(
                scenario.envelope,
                scenario.ground.filter(|g| g.enabled).map(|g| g.height),
            ),
            user: Vec::new(),
        };
        let lane = Self {
            dt,
            h,
            substeps: sim.substeps,
            steps,
            k: 0,
            t: 0u64 as f64 * dt,
            env,
            actuators,
            demand_params,
            base_plant,
            sensors,
            pipeline,
            pipeline_row,
            measured_ahead: None,
            state: QuadState::default(),
            measured: None,
            telemetry: Telemetry::default(),
            wind,
            ground: scenario.ground.filter(|g| g.enabled),
            contact: GroundContact::default(),
            tv_now,
            tv_next: tv_now,
            wind_now: None,
            p_prev: [0.0; 3],
            reference_grid,
            reference,
            observers,
            rotor_metrics: reports_rotor_metrics(scenario),
            unobserved: None,
            delivered: Delivered::none(),
            held: Default::default(),
            demand: [0.0; 4],
            plant_now: base_plant,
            omega_bar: 0.0,
            at_boundary: false,
            exit: None,
            scenario: owned,
        };
        (lane, reference)
    }

    #[inline]
    fn flying(&self) -> bool {
        self.exit.is_none()
    }

    /// Put the lane at period boundary `k` and its time `k·dt`.
    #[inline]
    fn set_step(&mut self, k: u64) {
        self.k = k;
        self.t = k as f64 * self.dt;
    }

    /// Stage 1: the sensors' reading of the truth at the lane's boundary
    /// (its Euler state and, for a full-state controller, lane `i` of
    /// `body`), or the reading taken ahead ([`Flight::measurement`]);
    /// `None` when the controller is given the truth itself (perfect
    /// sensors, or the flight is over): the caller's lanes already hold it.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn measure<R: Real>(&mut self, body: Option<&BodyAttitude<R>>, i: usize) -> Option<Measurement> {
        // (Matched in place: `take()` would copy the empty option out every tick.)
        let m = match (self.measured_ahead, self.sensors.as_mut()) {
            (Some(ahead), _) => {
                self.measured_ahead = None;
                ahead
            }
            (None, Some(s)) if self.exit.is_none() => {
                s.measure_full(&Measurement { euler: self.state, body: body.map(|b| b.get_lane(i)) })
            }
            (None, None) if self.exit.is_none() && self.pipeline.is_some() => {
                let truth = Measurement { euler: self.state, body: body.map(|b| b.get_lane(i)) };
                match self.estimate(&truth) {
                    Some(m) => m,
                    None => {
                        self.measured = None;
                        return None;
                    }
                }
            }
            _ => {
                self.measured = None;
                return None;
            }
        };
        self.measured = Some(m.euler);
        Some(m)
    }

    /// The pipeline's output for `truth` at the lane's boundary (its body
    /// attitude only when the truth has one: the controller flies it); `None`
    /// when the estimator failed, which ends the flight.
    fn estimate(&mut self, truth: &Measurement) -> Option<Measurement> {
        let pipeline = self.pipeline.as_mut()?;
        match pipeline.measure(self.t, truth) {
            Ok(mut m) => {
                if truth.body.is_none() {
                    m.body = None;
                }
                Some(m)
            }
            Err(f) => {
                self.exit =
                    Some(ExitStatus::Diverged { divergence: Divergence::Estimator { cause: f.reason }, time: f.time });
                None
            }
        }
    }

    /// Stage 3: the period's drag noise, then the actuator stage delivers
    /// `command`; true when it saturated.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn actuate(&mut self, command: &Command) -> bool {
        self.env.next_period();
        if self.actuators.reads_plant() {
            // Computed in place (no copies of the plant and the delivery).
            self.plant_now = self.env.params_with(&self.tv_now);
        }
        self.actuators.deliver_into(command, &self.plant_now, &mut self.delivered);
        let delivered = &self.delivered;
        self.demand = delivered.demand.unwrap_or_else(|| rotor_speeds(&self.demand_params, command, f64::INFINITY));
        delivered.saturated
    }

    /// Stage 4: the observers see the tick (lane `i` of the controller's
    /// `telemetry`, gathered only when an observer reads it), unless the
    /// truth could not begin the period (`begun`) or the applied command is
    /// not finite: then the flight diverged at this tick.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn observe<R: Real>(
        &mut self,
        begun: Result<(), Divergence>,
        command: &Command,
        telemetry: &Telemetry<R>,
        i: usize,
    ) {
        let t = self.t;
        let delivered = &self.delivered;
        let applied = delivered.applied;
        let u = [applied.thrust, applied.torque[0], applied.torque[1], applied.torque[2]];
        let divergence = match begun {
            Err(divergence) => Some(divergence),
            Ok(()) if !u.iter().all(|v| v.is_finite()) => Some(Divergence::NonFinite),
            Ok(()) => None,
        };
        if let Some(divergence) = divergence {
            self.exit = Some(ExitStatus::Diverged { divergence, time: t });
            self.unobserved = Some((delivered.saturated, self.demand));
            return;
        }
        if self.observers.read_telemetry(self.k) {
            self.telemetry = telemetry.get_lane(i);
        }
        if let Some(p) = self.pipeline.as_ref().filter(|_| self.observers.recorder.due(self.k)) {
            p.record(&mut self.pipeline_row);
        }
        let attitude_reference =
            [telemetry.attitude_reference[0].get_lane(i), telemetry.attitude_reference[1].get_lane(i)];
        let x = self.state.to_array();
        let reference = &self.reference;
        let tick = Tick {
            k: self.k,
            t,
            state: x,
            measured: self.measured.as_ref().unwrap_or(&self.state),
            reference,
            telemetry: &self.telemetry,
            errors: tracking_errors(&x, reference, attitude_reference),
            command,
            applied: u,
            omega: delivered.omega,
            omega_bar: residual_speed(&delivered.omega),
            demand: self.demand,
            saturated: delivered.saturated,
            nominal_mass: self.scenario.plant.mass,
            // The true plant's mass and inertia of the period (`params_with` copies them).
            mass: self.tv_now.mass,
            inertia: self.tv_now.inertia,
            disturbance: self.tv_now.disturbance,
            pipeline: &self.pipeline_row,
        };
        self.observers.tick(&tick);
        self.omega_bar = residual_speed(&delivered.target);
    }

    /// Stage 5a: before substep `j`, the wind held over it, the plant
    /// variation at its end and (for the ground contact) the position at its
    /// start, lane `i` of `truth`.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn begin_substep<R: Real>(&mut self, i: usize, j: u32, truth: &dyn TruthModel<R>) {
        if self.flying() {
            let t0 = self.t + j as f64 * self.h;
            self.wind_now = self.wind.as_mut().map(|w| w.step(t0));
            let m = self.k * u64::from(self.substeps) + u64::from(j) + 1;
            self.tv_next = self.env.time_varying_on_grid(m, t0 + self.h);
        }
        if self.ground.is_some() {
            self.p_prev = truth.translation(i).0;
        }
        self.actuators.held(&self.delivered, &mut self.held);
    }

    /// Substep `j` of the current period as the truth model takes it (built
    /// in the caller's slot: inlined, or it is built and then copied).
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn substep(&self, j: u32) -> Substep<'_> {
        Substep {
            t0: self.t + j as f64 * self.h,
            h: self.h,
            a: &self.tv_now,
            b: &self.tv_next,
            env: &self.env,
            drive: self.actuators.drive(&self.delivered, self.omega_bar, &self.held),
            wind: self.wind_now,
        }
    }

    /// Stage 5b: after substep `j`, the ground contact of lane `i` of
    /// `truth` (a crash ends the flight), the motors' lag, the plant
    /// variation moved on.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn end_substep<R: Real>(&mut self, i: usize, j: u32, truth: &mut dyn TruthModel<R>) {
        if !self.flying() {
            return;
        }
        if let Some(g) = &self.ground {
            let (mut p, mut v) = truth.translation(i);
            let t0 = self.t + j as f64 * self.h;
            let contact = g.contact(&mut self.contact, t0 + self.h, &self.p_prev, &mut p, &mut v);
            truth.set_translation(i, &p, &v);
            if let Some(contact) = contact {
                self.set_step(self.k + 1);
                self.exit = Some(match contact {
                    Contact::Crashed { fraction, impact_speed } => {
                        ExitStatus::Crashed { time: t0 + fraction * self.h, impact_speed }
                    }
                    Contact::Grounded { since } => ExitStatus::Grounded { time: t0 + self.h, since },
                });
                return;
            }
        }
        self.actuators.advance(&self.delivered.target);
        self.tv_now = self.tv_next;
    }

    /// Stage 6: the flight reaches its next period boundary; false when it
    /// is over (before, or now: interrupted).
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn next_boundary(&mut self, options: &RunOptions<'_>) -> bool {
        self.at_boundary = false;
        if !self.flying() {
            return false;
        }
        self.set_step(self.k + 1);
        if options.step_done(self.k) {
            self.exit = Some(ExitStatus::Interrupted { time: self.t });
            return false;
        }
        true
    }

    /// The observers (and, with `check`, the divergence checks, skipped
    /// when `sound`: [`Flights::sound_lanes`], and the planned end) see the
    /// truth `s` at the lane's period boundary.
    fn boundary(&mut self, s: &QuadState, check: bool, sound: bool) {
        self.state = *s;
        let (t, r) = (self.t, &self.reference);
        self.observers.boundary(t, s, r);
        if check {
            let divergence = if sound { None } else { check_divergence(&self.scenario, s, r) };
            if let Some(divergence) = divergence {
                self.exit = Some(ExitStatus::Diverged { divergence, time: t });
            } else if self.k >= self.steps {
                self.exit = Some(ExitStatus::Completed);
            }
        }
    }

    /// The outcome of this lane's flight (a flight stopped early reports
    /// `Completed` over the steps flown).
    fn output(self, controller: &str, options: &RunOptions<'_>) -> RunOutput {
        let mut exit = self.exit.unwrap_or(ExitStatus::Completed);
        options.flight_done(self.steps, self.k);
        let Observers { metrics, recorder, stats, envelope, margin, .. } = self.observers;
        let mut metrics = metrics.finish();
        // A completed flight's metrics are finite: one that overflowed
        // (an error of 1e160 m squared and integrated) is not completed.
        if exit.is_completed() && metrics.first_non_finite().is_some() {
            exit = ExitStatus::Diverged { divergence: Divergence::NonFiniteMetric, time: metrics.duration };
        }
        if self.rotor_metrics {
            let (peak, fraction) = stats.rotor_metrics(self.k, self.unobserved);
            metrics.peak_rotor_speed_demand = Some(peak);
            metrics.saturation_fraction = Some(fraction);
        }
        RunOutput {
            controller: controller.to_string(),
            scenario: self.scenario.name.clone(),
            envelope: envelope.verdict((!exit.is_completed()).then(|| exit.to_string())),
            margin: margin.finish(exit.margin_end(), self.scenario.duration),
            exit,
            metrics,
            recording: recorder.finish(),
            steps: self.k,
            stats,
        }
    }
}

/// Why a flight of `scenario` cannot start in a lane.
fn refusal(scenario: &Scenario, why: LaneStart) -> Divergence {
    match why {
        LaneStart::Invalid(divergence) => divergence,
        // A batch keeps one truth model per lane set (`registry::lane_compatible`);
        // this is the one-flight path's stand-in for an out-of-range body.
        LaneStart::OtherModel => truth_of(scenario).invalid.unwrap_or(Divergence::NonFinite),
    }
}

/// Most flights a [`Flights`] flies side by side (`Lanes<4>`, the widest
/// lane count a batch flies, `batch::montecarlo::LANE_COUNTS`).
const MAX_LANES: usize = 4;

/// One flight of a controller through a scenario: [`Flights`] of one
/// `f64` lane. [`Flight::new`] builds it; it steps, reads and finishes one
/// flight.
pub type Flight<'o, C> = Flights<'o, C, f64>;

/// `R::LANES` flights of one controller side by side (`R = Lanes<N>`;
/// [`Flight`] for one), advanced one control period at a time. The
/// flights own their scenarios and the controller (`C` may itself be a
/// `&mut` or a `Box` of a controller); `'o` is the lifetime of the
/// progress callback, the cancellation flag and the user's observers.
pub struct Flights<'o, C: Controller<R>, R: Real> {
    controller: C,
    /// The name every output of these flights carries
    /// ([`RunOutput::controller`]): the controller's own
    /// [`Controller::name`] unless [`Flights::named`] gave another.
    name: String,
    options: RunOptions<'o>,
    truth: Box<dyn TruthModel<R> + Send>,
    /// The truth at the current period boundary: its Euler state
    /// (converted once per period) and its quaternion and body rates, if it
    /// has them. What the controller is given with perfect sensors.
    at: Measurement<R>,
    /// The controller flies [`Measurement::body`] (`Controller::uses_body_attitude`).
    wants_body: bool,
    reference: Reference<R>,
    lanes: Vec<LaneFlight<'o>>,
    /// Per lane, an earlier lane flying the same reference on the same
    /// control grid ([`reference_twins`]): when both reach a boundary at
    /// the same step, its reference is copied, not evaluated again.
    reference_twin: Vec<Option<usize>>,
    /// Per lane, `simulation.max_tilt` (rad) and
    /// `simulation.max_position_error` (m), NaN where not finite (no
    /// comparison with NaN holds: [`Flights::sound_lanes`] then leaves the
    /// lane to the ordered checks).
    limits: [R; 2],
}

/// Per lane, the first earlier lane whose scenario has the same reference
/// signals, bit for bit, on the same control period: [`ReferenceGrid::at`]
/// is a function of the step and its time alone, so both lanes' references
/// at one step are the same bits. The signals are compared by
/// [`ReferenceSignals::same_bits`](crate::scenario::ReferenceSignals::same_bits)
/// (`PartialEq` would take `-0.0` for `0.0`).
fn reference_twins(lanes: &[LaneFlight<'_>]) -> Vec<Option<usize>> {
    (0..lanes.len())
        .map(|i| {
            let (lane, reference) = (&lanes[i], &lanes[i].scenario.reference);
            (0..i).find(|&j| {
                lanes[j].dt.to_bits() == lane.dt.to_bits() && lanes[j].scenario.reference.same_bits(reference)
            })
        })
        .collect()
}

impl<'o, C: Controller> Flights<'o, C, f64> {
    /// A flight of `controller` through `scenario` at `t = 0` (the scenario
    /// validated: `Scenario::validate`).
    pub fn new(scenario: impl Into<Arc<Scenario>>, controller: C, options: RunOptions<'o>) -> Self {
        Self::new_lanes(vec![scenario.into()], controller, options)
    }

    /// Add an observer of every tick and period boundary from now on; it
    /// first sees the boundary the flight is at (`t = 0` for a new flight).
    pub fn observe_with(&mut self, observer: &'o mut (dyn Observer + Send)) {
        let lane = &mut self.lanes[0];
        if lane.flying() {
            observer.boundary(lane.t, &self.at.euler, &self.reference);
        }
        lane.observers.user.push(observer);
    }

    /// The measurement the controller will be given at the coming tick
    /// (the sensor stage's output; the truth with perfect sensors), taken
    /// now and handed to the next [`Flight::step`]: an agent outside the
    /// loop sees exactly what the controller stage sees. The sensors are
    /// read once per tick however often this is called.
    pub fn measurement(&mut self) -> QuadState {
        let lane = &mut self.lanes[0];
        if let Some(m) = lane.measured_ahead {
            return m.euler;
        }
        let truth = self.at;
        let m = if let Some(s) = lane.sensors.as_mut() {
            s.measure_full(&truth)
        } else if lane.pipeline.is_some() && lane.flying() {
            match lane.estimate(&truth) {
                Some(m) => m,
                // The estimator failed: the flight is over; the next step ends it.
                None => return truth.euler,
            }
        } else {
            truth
        };
        lane.measured_ahead = Some(m);
        m.euler
    }

    /// From the current period boundary on, every noise source of the
    /// flight — sensors, turbulence, drag noise, motor noise — draws from
    /// the streams of `seed` (each source's own stream number, as the
    /// scenario's seed keys them), each at its first word; every state
    /// (truth, controller, filters, latency lines, motors, observers) is
    /// kept. A flight flown to boundary `k` with its own seed and then
    /// reseeded is a copy of its state at `k` continuing with fresh noise:
    /// the branching of adaptive multilevel splitting
    /// ([`crate::falsify::splitting`]). The same calls at the same steps give
    /// the same bits.
    pub fn reseed_noise(&mut self, seed: u64) {
        let lane = &mut self.lanes[0];
        lane.measured_ahead = None;
        if let Some(s) = &mut lane.sensors {
            s.reseed_noise(seed);
        }
        if let Some(p) = &mut lane.pipeline {
            p.reseed(seed);
        }
        if let Some(w) = &mut lane.wind {
            w.reseed_noise(seed);
        }
        lane.env.reseed_noise(seed);
        lane.actuators.reseed_noise(seed);
    }

    /// The robustness margin of the flight so far ([`crate::margin`]): the
    /// envelope margin over the period boundaries flown (a running minimum,
    /// never increasing while the flight goes on), or the failed flight's
    /// margin once it crashed or diverged; `None` while nothing limits it
    /// (before `settle_after` with no tilt limit).
    pub fn running_margin(&self) -> Option<f64> {
        let lane = &self.lanes[0];
        let end = lane.exit.as_ref().map_or(crate::margin::End::Completed, ExitStatus::margin_end);
        lane.observers.margin.finish(end, lane.scenario.duration).map(|m| m.value)
    }

    /// The truth's Euler state at the current period boundary.
    pub fn truth_state(&self) -> &QuadState {
        &self.at.euler
    }

    /// The reference at the current period boundary.
    pub fn reference(&self) -> &Reference {
        &self.reference
    }

    /// Control steps flown so far.
    pub fn steps_flown(&self) -> u64 {
        self.lanes[0].k
    }

    /// Control steps the flight plans.
    pub fn planned_steps(&self) -> u64 {
        self.lanes[0].steps
    }

    /// How the flight ended (`None` while it is flying).
    pub fn exit(&self) -> Option<&ExitStatus> {
        self.lanes[0].exit.as_ref()
    }

    /// Step to the end and return the outcome.
    pub fn run(mut self) -> RunOutput {
        while self.step() == StepOutcome::Flying {}
        self.finish()
    }

    /// The outcome so far (a flight stopped early reports `Completed` over
    /// the steps flown).
    pub fn finish(mut self) -> RunOutput {
        let lane = self.lanes.pop().expect("one lane");
        lane.output(&self.name, &self.options)
    }
}

impl<'o, C: Controller<R>, R: Real> Flights<'o, C, R> {
    /// `R::LANES` flights of `controller` side by side, lane `i` flying
    /// `scenarios[i]` from `t = 0` (validated scenarios of one base: the
    /// same vehicle model, control rate and substeps; [`Flight::new`] for
    /// one flight). User observers are for one flight only.
    ///
    /// # Panics
    /// If `scenarios` does not hold `R::LANES` scenarios, or more than 8.
    pub fn new_lanes(scenarios: Vec<Arc<Scenario>>, controller: C, options: RunOptions<'o>) -> Self {
        assert_eq!(scenarios.len(), R::LANES, "one scenario per lane");
        assert!(R::LANES <= MAX_LANES, "at most {MAX_LANES} lanes");
        let wants_body = controller.uses_body_attitude();
        let first = &*scenarios[0];
        let mut truth = truth_lanes::<R>(first).unwrap_or_else(|_| {
            // The first flight's rigid body is out of range: the paper plant
            // at the same initial state stands in (that flight stops at t = 0).
            let mut stand_in = first.clone();
            stand_in.vehicle.model = crate::vehicle::VehicleModel::Paper;
            truth_lanes::<R>(&stand_in).expect("the paper plant flies any validated scenario")
        });
        let mut reference = Reference::<R>::default();
        let mut lanes = Vec::with_capacity(R::LANES);
        let mut refused = Vec::new();
        for (i, scenario) in scenarios.iter().enumerate() {
            let steps = super::planned_steps(scenario);
            // A stream carries one flight: only a single lane's first flight uses it.
            let stream = options.stream.filter(|_| R::LANES == 1).cloned();
            let recorder = Recorder::new(scenario, options.record, steps, &controller, stream);
            let (mut lane, r) = LaneFlight::new(scenario.clone(), recorder);
            if let Err(why) = truth.start_lane(i, scenario) {
                lane.exit = Some(ExitStatus::Diverged { divergence: refusal(scenario, why), time: 0.0 });
                refused.push(i);
            }
            reference.put_lane(i, r);
            lanes.push(lane);
        }
        let mut state = truth.quad_state();
        for &i in &refused {
            // A flight that cannot start is seen at its initial state.
            state.put_lane(i, scenarios[i].initial_state.state());
        }
        let body = if wants_body { truth.body_attitude() } else { None };
        let mut flight = Self {
            name: controller.name().to_string(),
            controller,
            options,
            truth,
            at: Measurement { euler: state, body },
            wants_body,
            reference,
            lanes,
            reference_twin: Vec::new(),
            limits: [R::splat(f64::NAN); 2],
        };
        flight.reference_twin = reference_twins(&flight.lanes);
        for i in 0..R::LANES {
            flight.set_limits(i);
            flight.lanes[i].boundary(&flight.at.euler.get_lane(i), false, false);
        }
        flight
    }

    /// The same flights, their outputs named `name` (a registry name, or a
    /// variant's or a contestant's label) instead of the controller's own
    /// [`Controller::name`].
    pub fn named(mut self, name: impl Into<String>) -> Self {
        self.name = name.into();
        self
    }

    /// Start a new flight of `scenario` in lane `lane` (its flight ended, or
    /// it idles): the lane's truth, controller states, environment, sensors,
    /// actuators and observers start afresh at `t = 0`. `scenario` must be of
    /// the same base as the others ([`Flights::new_lanes`]).
    pub fn start_lane(&mut self, lane: usize, scenario: impl Into<Arc<Scenario>>) {
        let scenario: Arc<Scenario> = scenario.into();
        let steps = super::planned_steps(&scenario);
        let recorder = Recorder::new(&scenario, self.options.record, steps, &self.controller, None);
        let (mut fresh, r) = LaneFlight::new(scenario.clone(), recorder);
        let started = self.truth.start_lane(lane, &scenario);
        if let Err(why) = started {
            fresh.exit = Some(ExitStatus::Diverged { divergence: refusal(&scenario, why), time: 0.0 });
        }
        self.controller.reset_lane(lane);
        self.reference.put_lane(lane, r);
        self.lanes[lane] = fresh;
        self.reference_twin = reference_twins(&self.lanes);
        self.set_limits(lane);
        self.refresh_lane(lane);
        if started.is_err() {
            // A flight that cannot start is seen at its initial state.
            self.at.euler.put_lane(lane, scenario.initial_state.state());
        }
        self.lanes[lane].boundary(&self.at.euler.get_lane(lane), false, false);
    }

    /// The outcome of lane `lane`'s flight so far, its lane left as it is
    /// (to be restarted with [`Flights::start_lane`] or left idle).
    pub fn lane_output(&mut self, lane: usize) -> RunOutput {
        let scenario = self.lanes[lane].scenario.clone();
        let recorder = Recorder::new(&scenario, false, 0, &self.controller, None);
        let (mut idle, _) = LaneFlight::new(scenario, recorder);
        idle.exit = Some(ExitStatus::Completed);
        idle.set_step(idle.steps);
        let done = core::mem::replace(&mut self.lanes[lane], idle);
        done.output(&self.name, &self.options)
    }

    /// Stop lane `lane` without an outcome: an idle lane of a batch with
    /// fewer flights than lanes (it reports no progress and no result).
    pub fn stop_lane(&mut self, lane: usize) {
        self.lanes[lane].exit = Some(ExitStatus::Completed);
    }

    /// True while lane `lane`'s flight goes on.
    pub fn lane_flying(&self, lane: usize) -> bool {
        self.lanes[lane].flying()
    }

    /// Number of lanes, `R::LANES`.
    pub fn lane_count(&self) -> usize {
        self.lanes.len()
    }

    /// The controller being flown (e.g. to hand an external agent's
    /// command to it between two steps).
    pub fn controller_mut(&mut self) -> &mut C {
        &mut self.controller
    }

    /// Read lane `lane`'s truth into the boundary state (after its truth changed).
    fn refresh_lane(&mut self, lane: usize) {
        let s = self.truth.quad_state();
        self.at.euler.put_lane(lane, s.get_lane(lane));
        if self.wants_body {
            if let Some(b) = self.truth.body_attitude() {
                let mut body = self.at.body.unwrap_or_default();
                body.put_lane(lane, b.get_lane(lane));
                self.at.body = Some(body);
            }
        }
    }

    /// Lanes whose boundary state certainly passes [`check_divergence`]:
    /// `|φ|` and `|θ|` at most `simulation.max_tilt`, every position error
    /// at most `simulation.max_position_error` (both finite:
    /// [`Flights::limits`]; then these five components are finite too) and
    /// the seven other components finite, tested on every lane at once
    /// (comparisons and `x − x` sums only: no number of the flight changes).
    /// Any other lane takes the ordered checks.
    #[allow(clippy::eq_op)] // `x − x` on purpose: the finiteness test below
    fn sound_lanes(&self) -> R::Mask {
        let (s, r) = (&self.at.euler, &self.reference);
        let zero = R::splat(0.0);
        // `x − x` is +0 for a finite `x` and NaN otherwise: the sum is 0
        // exactly when every component is finite.
        let mut z = s.attitude[2] - s.attitude[2];
        for part in [&s.velocity, &s.angular_rate] {
            for &v in part {
                z += v - v;
            }
        }
        let [max_tilt, max_error] = self.limits;
        let mut sound = z.le(zero) & s.attitude[0].abs().le(max_tilt) & s.attitude[1].abs().le(max_tilt);
        for i in 0..3 {
            sound = sound & (s.position[i] - r.position[i]).abs().le(max_error);
        }
        sound
    }

    /// LaneFlight `lane`'s entries of [`Flights::limits`] for its scenario.
    fn set_limits(&mut self, lane: usize) {
        let sim = &self.lanes[lane].scenario.simulation;
        let finite = |v: f64| if v.is_finite() { v } else { f64::NAN };
        self.limits[0].put_lane(lane, finite(sim.max_tilt));
        self.limits[1].put_lane(lane, finite(sim.max_position_error));
    }

    /// Fly one control period of every flying lane (module docs);
    /// [`StepOutcome::Done`] once every lane's flight is over (and on every
    /// later call). Only the controller's update and the truth's substeps
    /// compute on the lanes; every other stage is a method of [`LaneFlight`],
    /// flight by flight.
    pub fn step(&mut self) -> StepOutcome {
        // Lanes at their planned end complete before anything is computed.
        for lane in self.lanes.iter_mut().filter(|lane| lane.flying() && lane.k >= lane.steps) {
            lane.exit = Some(ExitStatus::Completed);
        }
        if !self.lanes.iter().any(LaneFlight::flying) {
            return StepOutcome::Done;
        }
        // 1. Measure each lane (from the truth's lanes: a lane given the
        // truth itself leaves them as they are); 2. the controller on the lanes.
        let mut sensed: Option<Measurement<R>> = None;
        for (i, lane) in self.lanes.iter_mut().enumerate() {
            if let Some(m) = lane.measure(self.at.body.as_ref(), i) {
                sensed.get_or_insert(self.at).put_lane(i, m);
            }
        }
        let measured = sensed.as_ref().unwrap_or(&self.at);
        let dt = self.lanes[0].dt;
        let command = if self.wants_body {
            self.controller.update_measured(measured, &self.reference, dt)
        } else {
            self.controller.update(&measured.euler, &self.reference, dt)
        };
        // 3. Actuate each lane; the saturation goes back to the controller.
        let mut saturated = R::Mask::splat(false);
        for (i, lane) in self.lanes.iter_mut().enumerate().filter(|(_, lane)| lane.flying()) {
            saturated.put_lane(i, lane.actuate(&command.get_lane(i)));
        }
        self.controller.actuator_feedback(saturated);
        // 4. Each lane's truth begins the period; its observers see the tick.
        let telemetry = self.controller.telemetry();
        for (i, lane) in self.lanes.iter_mut().enumerate().filter(|(_, lane)| lane.flying()) {
            let begun = self.truth.begin_period(i, &lane.tv_now, &lane.base_plant);
            lane.observe(begun, &command.get_lane(i), telemetry, i);
        }
        // 5. The substeps: each lane begins, the truth integrates the lanes, each lane ends.
        let n = self.lanes.len();
        for j in 0..self.lanes[0].substeps {
            for (i, lane) in self.lanes.iter_mut().enumerate() {
                lane.begin_substep(i, j, &*self.truth);
            }
            // Each lane's substep built in its slot (no copies); a slot past
            // the lanes repeats the last lane's and is never read.
            let lanes = &self.lanes;
            let gathered: [Substep<'_>; MAX_LANES] = core::array::from_fn(|i| lanes[i.min(n - 1)].substep(j));
            self.truth.substep(&gathered[..n]);
            for (i, lane) in self.lanes.iter_mut().enumerate() {
                lane.end_substep(i, j, &mut *self.truth);
            }
        }
        // 6. The next period boundary: reference, observers, divergence checks.
        self.boundary()
    }

    /// Stage 6 of [`Flight::step`]: every flying lane at its next period
    /// boundary, its reference (copied from a twin at the same boundary,
    /// [`reference_twins`]), the truth's state, the observers and the checks.
    fn boundary(&mut self) -> StepOutcome {
        for i in 0..self.lanes.len() {
            let (earlier, rest) = self.lanes.split_at_mut(i);
            let lane = &mut rest[0];
            if !lane.next_boundary(&self.options) {
                continue;
            }
            let k = lane.k;
            let twin = self.reference_twin[i].map(|j| &earlier[j]).filter(|twin| twin.at_boundary && twin.k == k);
            lane.reference = match twin {
                Some(twin) => twin.reference,
                None => lane.reference_grid.at(k, lane.t),
            };
            self.reference.put_lane(i, lane.reference);
            lane.at_boundary = true;
        }
        // Written in place: the boundary state is not copied on the way.
        self.truth.quad_state_into(&mut self.at.euler);
        if self.wants_body {
            self.truth.body_attitude_into(&mut self.at.body);
        }
        let sound = self.sound_lanes();
        for (i, lane) in self.lanes.iter_mut().enumerate().filter(|(_, lane)| lane.at_boundary) {
            lane.boundary(&self.at.euler.get_lane(i), true, sound.get_lane(i));
        }
        if self.lanes.iter().any(LaneFlight::flying) {
            StepOutcome::Flying
        } else {
            StepOutcome::Done
        }
    }
}
