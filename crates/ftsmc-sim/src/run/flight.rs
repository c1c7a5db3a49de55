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
//!    RK4 substeps (`run/truth.rs`), with the wind sampled once per
//!    substep and the ground checked after each.
//! 7. The next reference; divergence checks.
//!
//! # Lanes
//!
//! A flight's numbers may be `f64` (one flight, [`Flight::new`]) or lanes
//! of `N` flights side by side ([`Flight::new_lanes`], `R = Lanes<N>`,
//! [`ftsmc_core::lanes`]). The controller and the truth model compute on
//! the lanes at once; what is cheap or random (sensors, environment,
//! actuator stage, wind, observers) runs flight by flight on the same
//! one-flight code. Each lane is an independent flight with its own
//! scenario, clock and exit: lane `i` has exactly the bits the same flight
//! has alone, whatever `N` and whatever lane it lands in, and a batch
//! starts the next flight in a lane whose flight ended
//! ([`Flight::start_lane`]).

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
}

impl ReferenceGrid {
    fn new(scenario: &Scenario, dt: f64) -> Self {
        let r = &scenario.reference;
        let g = |s| GridSignal::new(s, dt);
        Self { x: g(&r.x), y: g(&r.y), z: g(&r.z), psi: g(&r.psi) }
    }

    /// The reference at control step `k`, whose time the loop computed as `t` (s).
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn at(&mut self, k: u64, t: f64) -> Reference {
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
        || scenario.sensors.is_some_and(|s| !s.is_perfect())
        || scenario.wind.is_some()
}

/// Everything of one flight that is not in lanes: its scenario, clock,
/// environment, sensors, actuator stage, wind, observers and exit.
struct Lane<'s> {
    scenario: &'s Scenario,
    dt: f64,
    h: f64,
    substeps: u32,
    steps: u64,
    k: u64,
    /// The time of the period boundary `k`, `k as f64 · dt` (s), converted
    /// once per period (every reader takes these bits); set with `k` by
    /// [`Lane::set_step`].
    t: f64,
    env: Environment<'s>,
    actuators: ActuatorStage,
    demand_params: QuadrotorParams,
    base_plant: QuadrotorParams,
    sensors: Option<Sensors>,
    wind: Option<Wind>,
    ground: Option<GroundSettings>,
    /// The flight's ground-contact history (take-off, time on the ground).
    contact: GroundContact,
    tv_now: TimeVarying,
    /// The next substep boundary's plant variation, wind and height (set
    /// before the truth integrates the lanes).
    tv_next: TimeVarying,
    wind_now: Option<[f64; 3]>,
    /// Position at the start of the substep (ground contact only).
    p_prev: [f64; 3],
    reference_grid: ReferenceGrid,
    /// The reference at the lane's current period boundary (the lane's copy
    /// of [`Flight`]'s reference, read by the observers and the checks).
    reference: Reference,
    metrics: MetricsAccumulator,
    recorder: Recorder,
    envelope: Tracker,
    margin: crate::margin::MarginTracker,
    stats: FlightStats,
    legacy_rotor_metrics: bool,
    /// The last delivered period was not observed (the flight ended at its
    /// tick): the two rotor metrics of [`crate::metrics::Metrics`] count it,
    /// the statistics do not.
    unobserved_period: bool,
    /// This period's delivery (the truth reads its drive during the substeps),
    /// its unlimited rotor-speed demand and the true plant of the period
    /// (formed only where it is read: one flight's observers, or an actuator
    /// stage that reads it, [`ActuatorStage::reads_plant`]).
    delivered: Delivered,
    demand: [f64; 4],
    plant_now: QuadrotorParams,
    omega_bar: f64,
    /// The lane completed a period at this step (its boundary is observed).
    at_boundary: bool,
    exit: Option<ExitStatus>,
}

impl<'s> Lane<'s> {
    /// The flight of `scenario` at `t = 0` (its actuator stage built from
    /// the truth model's allocation) and its reference at `t = 0`.
    fn new(scenario: &'s Scenario, recorder: Recorder) -> (Self, Reference) {
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
        let sensors =
            scenario.sensors.filter(|s| !s.is_perfect()).map(|s| Sensors::new(s, sim.control_rate, scenario.seed));
        let metrics = MetricsAccumulator::new(dt, sim.settling_band, sim.settling_floor, sim.steady_state_after)
            .with_window(sim.metrics_window);
        let tv_now = env.time_varying_on_grid(0, 0.0);
        let mut reference_grid = ReferenceGrid::new(scenario, dt);
        let reference = reference_grid.at(0, 0.0);
        let lane = Self {
            scenario,
            dt,
            h,
            substeps: sim.substeps,
            steps,
            k: 0,
            t: 0u64 as f64 * dt,
            env,
            actuators,
            demand_params,
            base_plant: scenario.true_plant(),
            sensors,
            wind,
            ground: scenario.ground.filter(|g| g.enabled),
            contact: GroundContact::default(),
            tv_now,
            tv_next: tv_now,
            wind_now: None,
            p_prev: [0.0; 3],
            reference_grid,
            reference,
            metrics,
            recorder,
            envelope: Tracker::new(scenario.envelope),
            margin: crate::margin::MarginTracker::new(
                scenario.envelope,
                scenario.ground.filter(|g| g.enabled).map(|g| g.height),
            ),
            stats: FlightStats::default(),
            legacy_rotor_metrics: reports_rotor_metrics(scenario),
            unobserved_period: false,
            delivered: Delivered::none(),
            demand: [0.0; 4],
            plant_now: scenario.true_plant(),
            omega_bar: 0.0,
            at_boundary: false,
            exit: None,
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

    /// Substep `j` of the current period as the truth model takes it.
    #[inline]
    fn substep(&self, j: u32) -> Substep<'_> {
        Substep {
            t0: self.t + j as f64 * self.h,
            h: self.h,
            a: &self.tv_now,
            b: &self.tv_next,
            env: &self.env,
            drive: self.actuators.drive(&self.delivered, self.omega_bar),
            wind: self.wind_now,
        }
    }

    /// The sensor stage's reading of `truth` (the truth itself with perfect sensors).
    #[inline]
    fn measure(&mut self, truth: &Measurement) -> Measurement {
        match self.sensors.as_mut() {
            Some(s) => s.measure_full(truth),
            None => *truth,
        }
    }

    /// The outcome of this lane's flight (a flight stopped early reports
    /// `Completed` over the steps flown).
    fn output(self, controller: &str, options: &RunOptions<'_>) -> RunOutput {
        let mut exit = self.exit.unwrap_or(ExitStatus::Completed);
        options.flight_done(self.steps, self.k);
        let mut metrics = self.metrics.finish();
        // A completed flight's metrics are finite: one that overflowed
        // (an error of 1e160 m squared and integrated) is not completed.
        if exit.is_completed() && metrics.first_non_finite().is_some() {
            exit = ExitStatus::Diverged { divergence: Divergence::NonFiniteMetric, time: metrics.duration };
        }
        if self.legacy_rotor_metrics {
            // Every delivered period: the observed ones (the statistics'
            // running maximum and count, the same operations in the same
            // order), then the one the flight ended at, if unobserved.
            let (mut peak_demand, mut saturated_periods) =
                (self.stats.peak_rotor_speed_demand, self.stats.saturated_periods);
            if self.unobserved_period {
                peak_demand = self.demand.iter().fold(peak_demand, |m, &w| if w.is_finite() { m.max(w) } else { m });
                saturated_periods += u64::from(self.delivered.saturated);
            }
            metrics.peak_rotor_speed_demand = Some(peak_demand);
            metrics.saturation_fraction = Some(if self.k > 0 { saturated_periods as f64 / self.k as f64 } else { 0.0 });
        }
        RunOutput {
            controller: controller.to_string(),
            scenario: self.scenario.name.clone(),
            envelope: self.envelope.verdict((!exit.is_completed()).then(|| exit.to_string())),
            margin: self.margin.finish(exit.margin_end(), self.scenario.duration),
            exit,
            metrics,
            recording: self.recorder.recording,
            steps: self.k,
            stats: self.stats,
        }
    }
}

/// An emptied vector of substeps with another lifetime, its allocation
/// kept (the in-place collect of an empty vector of a type of the same
/// layout reuses the buffer).
fn recycle<'a, 'b>(mut v: Vec<Substep<'a>>) -> Vec<Substep<'b>> {
    v.clear();
    v.into_iter().map(|_| unreachable!("emptied")).collect()
}

/// Lane `i` of `x` as its one-flight form: `x` itself when it is already
/// one flight (`R = f64`: no copy), else lane `i` copied into `slot`.
#[cfg_attr(not(debug_assertions), inline(always))]
fn lane_ref<'a, T>(x: &'a T, i: usize, slot: &'a mut Option<T::Scalar>) -> &'a T::Scalar
where
    T: Lanewise + 'static,
    T::Scalar: 'static,
{
    match (x as &dyn core::any::Any).downcast_ref::<T::Scalar>() {
        Some(one) => one,
        None => slot.insert(x.get_lane(i)),
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

/// One flight of a controller through a scenario (or, with lanes, `N`
/// flights side by side), advanced one control period at a time.
pub struct Flight<'s, C: Controller<R> + ?Sized, R: Real = f64> {
    controller: &'s mut C,
    options: RunOptions<'s>,
    truth: Box<dyn TruthModel<R> + Send>,
    /// The truth's Euler state at the current period boundary (converted once per period).
    state: QuadState<R>,
    /// The truth's quaternion and body rates at the same boundary, if it has them.
    body: Option<BodyAttitude<R>>,
    /// The controller flies [`Measurement::body`] (`Controller::uses_body_attitude`).
    wants_body: bool,
    reference: Reference<R>,
    lanes: Vec<Lane<'s>>,
    observers: Vec<&'s mut dyn Observer>,
    /// The measurement of the coming tick when it was taken ahead of
    /// [`Flight::step`] by [`Flight::measurement`] (one flight only).
    measured_ahead: Option<QuadState>,
    /// Its body attitude (full-state controllers only).
    body_ahead: Option<BodyAttitude>,
    /// The allocation the lanes' substeps are gathered in (kept between
    /// substeps; empty in between).
    substeps: Vec<Substep<'static>>,
    /// Per lane, an earlier lane flying the same reference on the same
    /// control grid ([`reference_twins`]): when both reach a boundary at
    /// the same step, its reference is copied, not evaluated again.
    reference_twin: Vec<Option<usize>>,
    /// Per lane, `simulation.max_tilt` (rad) and
    /// `simulation.max_position_error` (m), NaN where not finite (no
    /// comparison with NaN holds: [`Flight::sound_lanes`] then leaves the
    /// lane to the ordered checks).
    limits: [R; 2],
}

/// Per lane, the first earlier lane whose scenario has the same reference
/// signals, bit for bit, on the same control period: [`ReferenceGrid::at`]
/// is a function of the step and its time alone, so both lanes' references
/// at one step are the same bits. `Debug` spells every number of a
/// validated signal (all finite) exactly, `-0.0` included, so equal texts
/// are equal signals.
fn reference_twins(lanes: &[Lane<'_>]) -> Vec<Option<usize>> {
    let keys: Vec<String> = lanes.iter().map(|lane| format!("{:?}", lane.scenario.reference)).collect();
    (0..lanes.len())
        .map(|i| (0..i).find(|&j| lanes[j].dt.to_bits() == lanes[i].dt.to_bits() && keys[j] == keys[i]))
        .collect()
}

impl<'s, C: Controller + ?Sized> Flight<'s, C, f64> {
    /// A flight of `controller` through `scenario` at `t = 0` (the scenario
    /// validated: `Scenario::validate`).
    pub fn new(scenario: &'s Scenario, controller: &'s mut C, options: RunOptions<'s>) -> Self {
        Self::new_lanes(&[scenario], controller, options)
    }

    /// Add an observer of every tick and period boundary from now on; it
    /// first sees the boundary the flight is at (`t = 0` for a new flight).
    pub fn observe_with(&mut self, observer: &'s mut dyn Observer) {
        if self.lanes[0].flying() {
            let t = self.lanes[0].t;
            observer.boundary(t, &self.state, &self.reference);
        }
        self.observers.push(observer);
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
        let truth = Measurement { euler: self.state, body: self.body };
        let m = self.lanes[0].measure(&truth);
        self.measured_ahead = Some(m.euler);
        self.body_ahead = m.body;
        m.euler
    }

    /// The truth's Euler state at the current period boundary.
    pub fn truth_state(&self) -> &QuadState {
        &self.state
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
        let name = self.controller.name();
        let lane = self.lanes.pop().expect("one lane");
        lane.output(name, &self.options)
    }
}

impl<'s, C: Controller<R> + ?Sized, R: Real> Flight<'s, C, R> {
    /// `R::LANES` flights of `controller` side by side, lane `i` flying
    /// `scenarios[i]` from `t = 0` (validated scenarios of one base: the
    /// same vehicle model, control rate and substeps; [`Flight::new`] for
    /// one flight). Recording and observers are for one flight only.
    ///
    /// # Panics
    /// If `scenarios` does not hold `R::LANES` scenarios.
    pub fn new_lanes(scenarios: &[&'s Scenario], controller: &'s mut C, options: RunOptions<'s>) -> Self {
        assert_eq!(scenarios.len(), R::LANES, "one scenario per lane");
        let wants_body = controller.uses_body_attitude();
        let first = scenarios[0];
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
        for (i, &scenario) in scenarios.iter().enumerate() {
            let steps = super::planned_steps(scenario);
            let recorder = Recorder::new(scenario, options.record && R::LANES == 1, steps, &*controller);
            let (mut lane, r) = Lane::new(scenario, recorder);
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
            controller,
            options,
            truth,
            state,
            body,
            wants_body,
            reference,
            lanes,
            observers: Vec::new(),
            measured_ahead: None,
            body_ahead: None,
            substeps: Vec::new(),
            reference_twin: Vec::new(),
            limits: [R::splat(f64::NAN); 2],
        };
        flight.reference_twin = reference_twins(&flight.lanes);
        for i in 0..R::LANES {
            flight.set_limits(i);
            flight.lane_boundary(i, 0.0, false, false);
        }
        flight
    }

    /// Start a new flight of `scenario` in lane `lane` (its flight ended, or
    /// it idles): the lane's truth, controller states, environment, sensors,
    /// actuators and observers start afresh at `t = 0`. `scenario` must be of
    /// the same base as the others ([`Flight::new_lanes`]).
    pub fn start_lane(&mut self, lane: usize, scenario: &'s Scenario) {
        let steps = super::planned_steps(scenario);
        let recorder = Recorder::new(scenario, false, steps, &*self.controller);
        let (mut fresh, r) = Lane::new(scenario, recorder);
        let started = self.truth.start_lane(lane, scenario);
        if let Err(why) = started {
            fresh.exit = Some(ExitStatus::Diverged { divergence: refusal(scenario, why), time: 0.0 });
        }
        self.controller.reset_lane(lane);
        self.reference.put_lane(lane, r);
        self.lanes[lane] = fresh;
        self.reference_twin = reference_twins(&self.lanes);
        self.set_limits(lane);
        self.refresh_lane(lane);
        if started.is_err() {
            // A flight that cannot start is seen at its initial state.
            self.state.put_lane(lane, scenario.initial_state.state());
        }
        self.lane_boundary(lane, 0.0, false, false);
    }

    /// The outcome of lane `lane`'s flight so far, its lane left as it is
    /// (to be restarted with [`Flight::start_lane`] or left idle).
    pub fn lane_output(&mut self, lane: usize) -> RunOutput {
        let scenario = self.lanes[lane].scenario;
        let recorder = Recorder::new(scenario, false, 0, &*self.controller);
        let (mut idle, _) = Lane::new(scenario, recorder);
        idle.exit = Some(ExitStatus::Completed);
        idle.set_step(idle.steps);
        let done = core::mem::replace(&mut self.lanes[lane], idle);
        done.output(self.controller.name(), &self.options)
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
        self.controller
    }

    /// Read lane `lane`'s truth into the boundary state (after its truth changed).
    fn refresh_lane(&mut self, lane: usize) {
        let s = self.truth.quad_state();
        self.state.put_lane(lane, s.get_lane(lane));
        if self.wants_body {
            if let Some(b) = self.truth.body_attitude() {
                let mut body = self.body.unwrap_or_default();
                body.put_lane(lane, b.get_lane(lane));
                self.body = Some(body);
            }
        }
    }

    /// Lanes whose boundary state certainly passes [`check_divergence`]:
    /// `|φ|` and `|θ|` at most `simulation.max_tilt`, every position error
    /// at most `simulation.max_position_error` (both finite:
    /// [`Flight::limits`]; then these five components are finite too) and
    /// the seven other components finite, tested on every lane at once
    /// (comparisons and `x − x` sums only: no number of the flight changes).
    /// Any other lane takes the ordered checks.
    #[allow(clippy::eq_op)] // `x − x` on purpose: the finiteness test below
    fn sound_lanes(&self) -> R::Mask {
        let (s, r) = (&self.state, &self.reference);
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

    /// Lane `lane`'s entries of [`Flight::limits`] for its scenario.
    fn set_limits(&mut self, lane: usize) {
        let sim = &self.lanes[lane].scenario.simulation;
        let finite = |v: f64| if v.is_finite() { v } else { f64::NAN };
        self.limits[0].put_lane(lane, finite(sim.max_tilt));
        self.limits[1].put_lane(lane, finite(sim.max_position_error));
    }

    /// Lane `i`'s envelope, statistics (and, one flight, the observers) see
    /// the truth at the period boundary `t` (s); with `check`, the
    /// divergence checks (skipped when `sound`: [`Flight::sound_lanes`])
    /// and the planned end follow on the same state.
    fn lane_boundary(&mut self, i: usize, t: f64, check: bool, sound: bool) {
        let mut s_slot = None;
        let s = lane_ref(&self.state, i, &mut s_slot);
        let lane = &mut self.lanes[i];
        let r = &lane.reference;
        lane.envelope.boundary(t, s, r);
        lane.margin.update(t, &s.position, &r.position, &s.attitude);
        lane.stats.boundary(t, s, r);
        if R::LANES == 1 {
            for o in &mut self.observers {
                o.boundary(t, s, r);
            }
        }
        if check {
            let divergence = if sound { None } else { check_divergence(lane.scenario, s, r) };
            if let Some(divergence) = divergence {
                lane.exit = Some(ExitStatus::Diverged { divergence, time: t });
            } else if lane.k >= lane.steps {
                lane.exit = Some(ExitStatus::Completed);
            }
        }
    }

    /// Fly one control period of every flying lane (module docs);
    /// [`StepOutcome::Done`] once every lane's flight is over (and on every
    /// later call).
    pub fn step(&mut self) -> StepOutcome {
        let n = R::LANES;
        // Lanes at their planned end complete before anything is computed.
        for lane in &mut self.lanes {
            if lane.flying() && lane.k >= lane.steps {
                lane.exit = Some(ExitStatus::Completed);
            }
        }
        if !self.lanes.iter().any(Lane::flying) {
            return StepOutcome::Done;
        }

        // 1–2. Sensors (lane by lane), controller (on the lanes).
        let mut measured = Measurement::<R>::default();
        let command = if self.wants_body {
            for i in 0..n {
                let reading = match (i, self.measured_ahead.take()) {
                    (0, Some(euler)) => Measurement { euler, body: self.body_ahead.take() },
                    _ => {
                        let truth = Measurement {
                            euler: self.state.get_lane(i),
                            body: self.body.as_ref().map(|b| b.get_lane(i)),
                        };
                        if self.lanes[i].flying() {
                            self.lanes[i].measure(&truth)
                        } else {
                            truth
                        }
                    }
                };
                measured.put_lane(i, reading);
            }
            self.controller.update_measured(&measured, &self.reference, self.lanes[0].dt)
        } else {
            for i in 0..n {
                let reading = match (i, self.measured_ahead.take()) {
                    (0, Some(m)) => m,
                    _ => {
                        let state = self.state.get_lane(i);
                        let lane = &mut self.lanes[i];
                        match lane.sensors.as_mut() {
                            Some(s) if lane.exit.is_none() => s.measure(&state),
                            _ => state,
                        }
                    }
                };
                measured.euler.put_lane(i, reading);
            }
            self.controller.update(&measured.euler, &self.reference, self.lanes[0].dt)
        };

        // 3–4. Environment and actuator stage, lane by lane.
        let mut saturated = R::Mask::splat(false);
        for (i, lane) in self.lanes.iter_mut().enumerate() {
            if !lane.flying() {
                continue;
            }
            let command_i: Command = command.get_lane(i);
            lane.env.next_period();
            // Computed in place (no copies of the plant and the delivery),
            // the plant only where it is read.
            if n == 1 || lane.actuators.reads_plant() {
                lane.plant_now = lane.env.params_with(&lane.tv_now);
            }
            lane.actuators.deliver_into(&command_i, &lane.plant_now, &mut lane.delivered);
            let delivered = &lane.delivered;
            let demand =
                delivered.demand.unwrap_or_else(|| rotor_speeds(&lane.demand_params, &command_i, f64::INFINITY));
            saturated.put_lane(i, delivered.saturated);
            lane.demand = demand;
        }
        self.controller.actuator_feedback(saturated);

        // The truth's plant of the period; a finite applied command; the observers.
        let telemetry = self.controller.telemetry();
        for i in 0..n {
            let lane = &mut self.lanes[i];
            if !lane.flying() {
                continue;
            }
            let t = lane.t;
            if let Err(divergence) = self.truth.begin_period(i, &lane.tv_now, &lane.base_plant) {
                lane.exit = Some(ExitStatus::Diverged { divergence, time: t });
                lane.unobserved_period = true;
                continue;
            }
            let delivered = &lane.delivered;
            let applied = delivered.applied;
            let u = [applied.thrust, applied.torque[0], applied.torque[1], applied.torque[2]];
            if !(u.iter().all(|v| v.is_finite())) {
                lane.exit = Some(ExitStatus::Diverged { divergence: Divergence::NonFinite, time: t });
                lane.unobserved_period = true;
                continue;
            }
            let reference = &lane.reference;
            if n == 1 {
                // One flight: the whole tick (the values themselves, no
                // copies) for the recorder and every observer.
                let (mut s_slot, mut t_slot, mut m_slot, mut c_slot) = (None, None, None, None);
                let x = lane_ref(&self.state, i, &mut s_slot).to_array();
                let telemetry_i: &Telemetry = lane_ref(telemetry, i, &mut t_slot);
                let measured_i = lane_ref(&measured.euler, i, &mut m_slot);
                let command_i: &Command = lane_ref(&command, i, &mut c_slot);
                let tick = Tick {
                    k: lane.k,
                    t,
                    state: x,
                    measured: measured_i,
                    reference,
                    telemetry: telemetry_i,
                    errors: tracking_errors(&x, reference, telemetry_i),
                    command: command_i,
                    applied: u,
                    omega: delivered.omega,
                    omega_bar: residual_speed(&delivered.omega),
                    demand: lane.demand,
                    saturated: delivered.saturated,
                    nominal_mass: lane.scenario.plant.mass,
                    mass: lane.plant_now.mass,
                    inertia: lane.plant_now.inertia,
                    disturbance: lane.tv_now.disturbance,
                };
                lane.metrics.tick(&tick);
                lane.recorder.tick(&tick);
                lane.stats.tick(&tick);
                for o in &mut self.observers {
                    o.tick(&tick);
                }
            } else {
                // Lanes: no recording and no observers (`Flight::new_lanes`);
                // the metrics and the statistics read the tracking errors
                // (`tracking_errors`, the same operations on lane i's numbers),
                // the applied command and the rotor speeds alone.
                let (position, attitude) = (&self.state.position, &self.state.attitude);
                let attitude_reference = &telemetry.attitude_reference;
                let errors = [
                    position[0].get_lane(i) - reference.position[0],
                    position[1].get_lane(i) - reference.position[1],
                    position[2].get_lane(i) - reference.position[2],
                    attitude[0].get_lane(i) - attitude_reference[0].get_lane(i),
                    attitude[1].get_lane(i) - attitude_reference[1].get_lane(i),
                    attitude[2].get_lane(i) - reference.yaw,
                ];
                lane.metrics.observe(t, &errors, &u);
                lane.stats.observe_period(delivered.saturated, &lane.demand, &delivered.omega);
            }
            lane.omega_bar = residual_speed(&delivered.target);
        }

        // 6. The truth over the period: every lane's substep at once.
        let substeps = self.lanes[0].substeps;
        for j in 0..substeps {
            for lane in &mut self.lanes {
                let t0 = lane.t + j as f64 * lane.h;
                if lane.flying() {
                    lane.wind_now = lane.wind.as_mut().map(|w| w.step(t0));
                    lane.tv_next =
                        lane.env.time_varying_on_grid(lane.k * u64::from(substeps) + u64::from(j) + 1, t0 + lane.h);
                }
            }
            for i in 0..n {
                // Only the ground contact reads it.
                if self.lanes[i].ground.is_some() {
                    self.lanes[i].p_prev = self.truth.translation(i).0;
                }
            }
            {
                let lanes = &self.lanes;
                if n == 1 {
                    self.truth.substep(core::slice::from_ref(&lanes[0].substep(j)));
                } else {
                    // The same allocation every substep (recycled: empty in between).
                    let mut gathered: Vec<Substep<'_>> = recycle(core::mem::take(&mut self.substeps));
                    gathered.extend(lanes.iter().map(|lane| lane.substep(j)));
                    self.truth.substep(&gathered);
                    self.substeps = recycle(gathered);
                }
            }
            for (i, lane) in self.lanes.iter_mut().enumerate() {
                if !lane.flying() {
                    continue;
                }
                if let Some(g) = &lane.ground {
                    let (mut p, mut v) = self.truth.translation(i);
                    let t0 = lane.t + j as f64 * lane.h;
                    let contact = g.contact(&mut lane.contact, t0 + lane.h, &lane.p_prev, &mut p, &mut v);
                    self.truth.set_translation(i, &p, &v);
                    if let Some(contact) = contact {
                        lane.set_step(lane.k + 1);
                        lane.exit = Some(match contact {
                            Contact::Crashed { fraction, impact_speed } => {
                                ExitStatus::Crashed { time: t0 + fraction * lane.h, impact_speed }
                            }
                            Contact::Grounded { since } => ExitStatus::Grounded { time: t0 + lane.h, since },
                        });
                        continue;
                    }
                }
                lane.actuators.advance(&lane.delivered.target);
                lane.tv_now = lane.tv_next;
            }
        }

        // 7. The next reference and boundary; divergence checks.
        for i in 0..n {
            let (earlier, rest) = self.lanes.split_at_mut(i);
            let lane = &mut rest[0];
            lane.at_boundary = false;
            if !lane.flying() {
                continue;
            }
            lane.set_step(lane.k + 1);
            let (k, t) = (lane.k, lane.t);
            if self.options.step_done(k) {
                lane.exit = Some(ExitStatus::Interrupted { time: t });
                continue;
            }
            // A twin at the same boundary has this very reference already.
            let twin = self.reference_twin[i].map(|j| &earlier[j]).filter(|twin| twin.at_boundary && twin.k == k);
            lane.reference = match twin {
                Some(twin) => twin.reference,
                None => lane.reference_grid.at(k, t),
            };
            self.reference.put_lane(i, lane.reference);
            lane.at_boundary = true;
        }
        // Written in place: the boundary state is not copied on the way.
        self.truth.quad_state_into(&mut self.state);
        if self.wants_body {
            self.truth.body_attitude_into(&mut self.body);
        }
        let sound = self.sound_lanes();
        for i in 0..n {
            if self.lanes[i].at_boundary {
                let t_next = self.lanes[i].t;
                self.lane_boundary(i, t_next, true, sound.get_lane(i));
            }
        }
        if self.lanes.iter().any(Lane::flying) {
            StepOutcome::Flying
        } else {
            StepOutcome::Done
        }
    }
}
