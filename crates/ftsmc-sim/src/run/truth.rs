//! Truth models as the run loop flies them: the paper plant of Eq. 1 and the
//! Newton–Euler rigid body behind one [`TruthModel`] trait, integrated by
//! RK4 substeps ([`crate::vehicle::paper::rk4_step`]) the loop drives.
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
//! rigid body uses its own aerodynamics (`[vehicle] parasitic_drag`,
//! `rotor_drag_xy`, `rotor_drag_z`, `translational_lift`).
//!
//! With `[wind]` both models see air-relative drag: Eq. 1's `K_f1` drag on
//! `v − w`, the rigid body's parasitic and rotor drag.
//!
//! # Lanes
//!
//! [`TruthModel`] is generic over the number type: `TruthModel<f64>` is one
//! flight ([`truth_of`]), `TruthModel<Lanes<N>>` is `N` flights of one
//! model side by side ([`truth_lanes`]), each lane its own scenario's
//! vehicle, started with [`TruthModel::start_lane`]. A substep takes one
//! [`Substep`] per lane: what each lane's RK4 stage inputs are made of
//! (the period's plant, the endpoints of the disturbance and plant
//! variation, the held or lagged rotors) is gathered into lanes once per
//! substep, each stage's inputs are then lane operations doing, lane by
//! lane, the one-flight code's operations in its order (the paper plant
//! with lagged rotors still makes them with the one-flight code per lane),
//! and one RK4 step runs on the lanes: lane `i` has exactly the bits of the
//! one-flight model fed lane `i`'s substeps. The Euler state of the rigid
//! body ([`TruthModel::quad_state`]) is computed on the lanes too.

use ftsmc_core::allocation::{forces_from_squared_speeds, residual_speed};
use ftsmc_core::lanes::{Lanewise, Real};
use ftsmc_core::measured::BodyAttitude;
use ftsmc_core::model::{Command, QuadState, QuadrotorParams};

use crate::environment::Environment;
use crate::environment::TimeVarying;
use crate::scenario::Scenario;
use crate::vehicle::paper::{derivative_in_wind_of, derivative_of, rk4_step_staged, Eq1Params};
use crate::vehicle::rigid_body::{has_plain_diagonal, normalize_quaternion, RigidBodyState};
use crate::vehicle::{from_quad_state, to_quad_state, RigidBody, RigidBodyInput, RigidBodyParams, VehicleModel};

use super::actuation::Drive;
use super::Divergence;

/// One RK4 substep `[t0, t0 + h]` as the loop hands it to a truth model.
#[derive(Clone, Copy)]
pub(crate) struct Substep<'a> {
    /// Start time, s.
    pub t0: f64,
    /// Length, s.
    pub h: f64,
    /// Time-varying plant inputs at `t0` and `t0 + h` (interpolated
    /// linearly inside), borrowed from the lane: a substep is gathered for
    /// every lane every substep, and copying them was most of its cost.
    pub a: &'a TimeVarying,
    /// See `a`.
    pub b: &'a TimeVarying,
    /// The environment (drag noise of the period).
    pub env: &'a Environment,
    /// The rotors.
    pub drive: Drive<'a>,
    /// Wind held over the substep, world frame, m/s (`None`: still air, no `[wind]`).
    pub wind: Option<[f64; 3]>,
}

/// Why a flight cannot start in a lane ([`TruthModel::start_lane`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum LaneStart {
    /// The scenario's rigid body is out of range (what [`truth_of`] reports
    /// as `invalid`: the flight stops at t = 0).
    Invalid(Divergence),
    /// The scenario flies the other truth model (`[vehicle] model`): lanes
    /// of one model only.
    OtherModel,
}

/// A truth model the loop can fly: one flight (`R = f64`) or `R::LANES`
/// flights side by side ([`ftsmc_core::lanes`]), each lane computing
/// exactly what the one-flight model of its flight computes.
pub(crate) trait TruthModel<R: Real = f64> {
    /// The state in the Euler form every controller takes.
    fn quad_state(&self) -> QuadState<R>;
    /// The attitude as quaternion and body rates, when the model has them
    /// (handed to full-state controllers beside the Euler state). The
    /// default: none (the model's state is the Euler state).
    fn body_attitude(&self) -> Option<BodyAttitude<R>> {
        None
    }
    /// [`TruthModel::quad_state`] written into `out` (the loop's boundary
    /// state, overwritten in place: the same bits, no copy on the way).
    fn quad_state_into(&self, out: &mut QuadState<R>) {
        *out = self.quad_state();
    }
    /// [`TruthModel::body_attitude`] written into `out` (in place, as
    /// [`TruthModel::quad_state_into`]).
    fn body_attitude_into(&self, out: &mut Option<BodyAttitude<R>>) {
        *out = self.body_attitude();
    }
    /// The start of a control period of lane `lane`'s flight with the plant
    /// variation `tv` (the rigid body's payload and inertia scaling); `base`
    /// is that flight's true plant. An error stops that flight: the model
    /// cannot represent this variation (the lane is left as it was).
    fn begin_period(&mut self, lane: usize, tv: &TimeVarying, base: &QuadrotorParams) -> Result<(), Divergence> {
        let _ = (lane, tv, base);
        Ok(())
    }
    /// Integrate one substep: `s[i]` is lane `i`'s (`s.len() >= R::LANES`).
    fn substep(&mut self, s: &[Substep<'_>]);
    /// Position (m) and world-frame velocity (m/s) of lane `lane`, for
    /// ground contact.
    fn translation(&self, lane: usize) -> ([f64; 3], [f64; 3]);
    /// Overwrite lane `lane`'s position (m) and velocity (m/s) (ground contact).
    fn set_translation(&mut self, lane: usize, p: &[f64; 3], v: &[f64; 3]);
    /// Start a new flight of `scenario` in lane `lane`: its vehicle and its
    /// initial state, the other lanes untouched. On error the lane is
    /// unchanged.
    fn start_lane(&mut self, lane: usize, scenario: &Scenario) -> Result<(), LaneStart>;
}

/// Paper Eq. 1 in Euler form: `[x, y, z, φ, θ, ψ, ẋ, ẏ, ż, φ̇, θ̇, ψ̇]` per lane.
pub(crate) struct PaperTruth<R: Real = f64>(pub [R; 12]);

/// The inputs of Eq. 1 at one RK4 stage time: the plant of the period's
/// variation, the rotors' wrench and residual speed, the disturbance and
/// the wind (zero in still air).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct PaperStage<R: Real = f64> {
    plant: Eq1Params<R>,
    command: Command<R>,
    omega_bar: R,
    disturbance: [R; 6],
    wind: [R; 3],
}

ftsmc_core::lanewise_struct!(PaperStage { plant, command, omega_bar, disturbance, wind });

/// The one-flight Eq. 1 inputs of substep `s` at the stage time `tau` (s):
/// the plant of the variation interpolated to `tau`, and the held wrench or
/// the one the lagged rotors deliver at `tau`.
#[cfg_attr(not(debug_assertions), inline(always))]
fn paper_stage(s: &Substep<'_>, tau: f64) -> PaperStage {
    let tv = TimeVarying::lerp(s.a, s.b, (tau - s.t0) / s.h);
    let p = s.env.params_with(&tv);
    let wind = s.wind.unwrap_or([0.0; 3]);
    match s.drive {
        Drive::Held { applied, omega_bar, .. } => {
            PaperStage { plant: Eq1Params::of(&p), command: *applied, omega_bar, disturbance: tv.disturbance, wind }
        }
        drive @ Drive::Lagged { .. } => {
            let w = drive.speeds_after(tau - s.t0);
            let delivered: Command = forces_from_squared_speeds(&p, &w.map(|o| o * o));
            PaperStage {
                plant: Eq1Params::of(&p),
                command: delivered,
                omega_bar: residual_speed(&w),
                disturbance: tv.disturbance,
                wind,
            }
        }
    }
}

/// [`paper_stage`] of every lane at its stage time (lane `i` of `tau`).
#[cfg_attr(not(debug_assertions), inline(always))]
fn paper_stages<R: Real>(s: &[Substep<'_>], tau: R) -> PaperStage<R> {
    let mut stage = PaperStage::<R>::default();
    for (i, s) in s.iter().enumerate() {
        stage.put_lane(i, paper_stage(s, tau.get_lane(i)));
    }
    stage
}

/// Eq. 1's plant over one substep of every lane with held rotors: the
/// period's plant (`Environment::params_with`) and the endpoints of the
/// variation (mass, inertia, disturbance), gathered into lanes once.
struct HeldPlant<R: Real> {
    /// The plant at the substep start (its gravity, drags and rotor
    /// inertia hold over the substep).
    base: Eq1Params<R>,
    /// Mass at the start, kg, and its change over the substep.
    mass: (R, R),
    /// Inertia at the start, kg·m², and its change.
    inertia: ([R; 3], [R; 3]),
    /// Disturbance at the start, m/s² and rad/s², and its change.
    disturbance: ([R; 6], [R; 6]),
}

/// [`HeldPlant`] of every lane's substep.
#[cfg_attr(not(debug_assertions), inline(always))]
fn held_plant<R: Real>(s: &[Substep<'_>]) -> HeldPlant<R> {
    let base = <Eq1Params<R>>::from_lanes(s, |s| Eq1Params::of(&s.env.params_with(s.a)));
    let (m_a, m_b) = (R::from_lanes(s, |s| s.a.mass), R::from_lanes(s, |s| s.b.mass));
    let (i_a, i_b) = (<[R; 3]>::from_lanes(s, |s| s.a.inertia), <[R; 3]>::from_lanes(s, |s| s.b.inertia));
    let (d_a, d_b) = (<[R; 6]>::from_lanes(s, |s| s.a.disturbance), <[R; 6]>::from_lanes(s, |s| s.b.disturbance));
    let (mut i_gap, mut d_gap) = (i_b, d_b);
    for k in 0..3 {
        i_gap[k] = i_b[k] - i_a[k];
    }
    for k in 0..6 {
        d_gap[k] = d_b[k] - d_a[k];
    }
    HeldPlant { base, mass: (m_a, m_b - m_a), inertia: (i_a, i_gap), disturbance: (d_a, d_gap) }
}

impl<R: Real> HeldPlant<R> {
    /// The plant and disturbance at the fraction `w` (lane `i`: lane `i`'s
    /// `(τ − t0)/h`) of the substep: `Environment::params_with` of
    /// `TimeVarying::lerp` (`a + w (b − a)`), lane `i` with the one-flight
    /// operations.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn at(&self, w: R) -> (Eq1Params<R>, [R; 6]) {
        let (i_a, i_gap) = self.inertia;
        let (d_a, d_gap) = self.disturbance;
        let (mut inertia, mut d) = (i_a, d_a);
        for k in 0..3 {
            inertia[k] = i_a[k] + w * i_gap[k];
        }
        for k in 0..6 {
            d[k] = d_a[k] + w * d_gap[k];
        }
        (Eq1Params { mass: self.mass.0 + w * self.mass.1, inertia, ..self.base }, d)
    }
}

impl<R: Real> PaperTruth<R> {
    /// Every lane at `scenario`'s initial state.
    pub(crate) fn new(scenario: &Scenario) -> Self {
        Self(scenario.initial_state.state().to_array().map(R::splat))
    }
}

impl<R: Real> TruthModel<R> for PaperTruth<R> {
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn quad_state(&self) -> QuadState<R> {
        let a = &self.0;
        QuadState {
            position: [a[0], a[1], a[2]],
            attitude: [a[3], a[4], a[5]],
            velocity: [a[6], a[7], a[8]],
            angular_rate: [a[9], a[10], a[11]],
        }
    }

    #[cfg_attr(not(debug_assertions), inline(always))]
    fn substep(&mut self, s: &[Substep<'_>]) {
        let s = &s[..R::LANES];
        let t0 = R::from_fn(|i| s[i].t0);
        let h = R::from_fn(|i| s[i].h);
        // The plant of each RK4 stage time, made once per lane with the
        // one-flight code (the second and third stages share theirs).
        if s.iter().all(|s| matches!(s.drive, Drive::Held { .. })) {
            // Held rotors: the wrench, Ω̄ and the wind are the substep's;
            // only the plant and the disturbance move with the stage time.
            let mut command = Command::<R>::default();
            let mut omega_bar = R::default();
            let mut wind = [R::default(); 3];
            let mut windy = false;
            for (i, s) in s.iter().enumerate() {
                if let Drive::Held { applied, omega_bar: w, .. } = s.drive {
                    command.put_lane(i, *applied);
                    omega_bar.put_lane(i, w);
                }
                wind.put_lane(i, s.wind.unwrap_or([0.0; 3]));
                windy |= s.wind.is_some();
            }
            // Eq. 1 in still air unless some lane has wind; the wind form
            // with a zero wind is Eq. 1 bit for bit (`v − 0 = v`), so a
            // still-air lane flies the same either way. The closures are
            // forced inline so that the step compiles inside the
            // dispatched kernel (`OnIsa`).
            // The plant of the period (all but the mass and inertia, which
            // the variation moves) and the variation's endpoints, gathered
            // once; each stage is then `TimeVarying::lerp` on the lanes.
            let plant = held_plant(s);
            self.0 = if windy {
                rk4_step_staged(
                    #[cfg_attr(not(debug_assertions), inline(always))]
                    |tau: R| plant.at((tau - t0) / h),
                    #[cfg_attr(not(debug_assertions), inline(always))]
                    |(p, d): &(Eq1Params<R>, [R; 6]), x: &[R; 12]| {
                        derivative_in_wind_of(x, &command, omega_bar, p, d, &wind)
                    },
                    t0,
                    &self.0,
                    h,
                )
            } else {
                rk4_step_staged(
                    #[cfg_attr(not(debug_assertions), inline(always))]
                    |tau: R| plant.at((tau - t0) / h),
                    #[cfg_attr(not(debug_assertions), inline(always))]
                    |(p, d): &(Eq1Params<R>, [R; 6]), x: &[R; 12]| derivative_of(x, &command, omega_bar, p, d),
                    t0,
                    &self.0,
                    h,
                )
            };
        } else {
            // Some lane's rotors lag (the one-flight model takes the wind
            // form for them, with a zero wind in still air): every stage
            // input per lane and stage.
            self.0 = rk4_step_staged(
                #[cfg_attr(not(debug_assertions), inline(always))]
                |tau: R| paper_stages(s, tau),
                #[cfg_attr(not(debug_assertions), inline(always))]
                |st: &PaperStage<R>, x: &[R; 12]| {
                    derivative_in_wind_of(x, &st.command, st.omega_bar, &st.plant, &st.disturbance, &st.wind)
                },
                t0,
                &self.0,
                h,
            );
        }
    }

    #[inline]
    fn translation(&self, lane: usize) -> ([f64; 3], [f64; 3]) {
        let x = &self.0;
        (
            [x[0].get_lane(lane), x[1].get_lane(lane), x[2].get_lane(lane)],
            [x[6].get_lane(lane), x[7].get_lane(lane), x[8].get_lane(lane)],
        )
    }

    #[inline]
    fn set_translation(&mut self, lane: usize, p: &[f64; 3], v: &[f64; 3]) {
        for i in 0..3 {
            self.0[i].put_lane(lane, p[i]);
            self.0[6 + i].put_lane(lane, v[i]);
        }
    }

    fn start_lane(&mut self, lane: usize, scenario: &Scenario) -> Result<(), LaneStart> {
        if scenario.vehicle.model != VehicleModel::Paper {
            return Err(LaneStart::OtherModel);
        }
        self.0.put_lane(lane, scenario.initial_state.state().to_array());
        Ok(())
    }
}

/// A value of every lane's substep gathered into lanes (lane `i` of
/// `f(&s[i])`).
trait FromLanes: Lanewise + Default {
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn from_lanes(s: &[Substep<'_>], f: impl Fn(&Substep<'_>) -> Self::Scalar) -> Self {
        let mut v = Self::default();
        for (i, s) in s.iter().enumerate() {
            v.put_lane(i, f(s));
        }
        v
    }
}

impl<T: Lanewise + Default> FromLanes for T {}

/// Every lane's rotor speeds `dt` (lane `i`: lane `i`'s stage time minus
/// its substep start, s) into the substep, rad/s: lane `i` is
/// [`Drive::speeds_after`] of lane `i`'s drive (the one motor-lag code,
/// per lane: a lane kernel of it saved less than the 10 % a lane kernel must
/// earn, docs/results.md).
#[cfg_attr(not(debug_assertions), inline(always))]
fn rotor_speeds_after<R: Real>(s: &[Substep<'_>], dt: R) -> [R; 4] {
    let mut w = [R::default(); 4];
    for (i, s) in s.iter().enumerate() {
        w.put_lane(i, s.drive.speeds_after(dt.get_lane(i)));
    }
    w
}

/// One flight's rigid-body bookkeeping beside its lane of the body.
#[derive(Clone, Copy, Debug)]
struct RigidLane {
    /// The scenario's vehicle.
    base: RigidBodyParams,
    /// The added mass (kg) and inertia scale the lane's body flies: its mass
    /// is `base.mass + key.0`, its inertia `key.1 · base.inertia`.
    key: (f64, f64),
    /// `base.inertia` is diagonal with `+0.0` products of inertia
    /// (`has_plain_diagonal`): its scaled inverse takes the diagonal shortcut.
    plain_diagonal: bool,
}

/// The rigid body of `scenario` at its initial state, one flight.
fn rigid_flight(scenario: &Scenario) -> Result<(RigidBody, RigidLane, RigidBodyState), Divergence> {
    let base = scenario.rigid_body_params();
    let body =
        RigidBody::new(base).map_err(|_| Divergence::RigidBodyOutOfRange { mass: base.mass, inertia_scale: 1.0 })?;
    let lane = RigidLane { base, key: (0.0, 1.0), plain_diagonal: has_plain_diagonal(&base.inertia) };
    Ok((body, lane, from_quad_state(&scenario.initial_state.state())))
}

/// The Newton–Euler rigid body ([`RigidBody`]), one vehicle per lane.
pub(crate) struct RigidTruth<R: Real = f64> {
    body: RigidBody<R>,
    /// One per lane.
    lanes: Vec<RigidLane>,
    x: RigidBodyState<R>,
}

impl<R: Real> RigidTruth<R> {
    /// The rigid body of `scenario` at its initial state in every lane
    /// (`Err`: its parameters are out of range; `Scenario::validate` refuses
    /// them, a caller may skip validation).
    pub(crate) fn new(scenario: &Scenario) -> Result<Self, Divergence> {
        let (body, lane, x) = rigid_flight(scenario)?;
        Ok(Self { body: RigidBody::splat(&body), lanes: vec![lane; R::LANES], x: x.map(R::splat) })
    }
}

impl<R: Real> TruthModel<R> for RigidTruth<R> {
    /// The one-flight Euler conversion written for any [`Real`]: on the
    /// lanes at once (forced inline, so that it compiles inside the
    /// dispatched kernel, `OnIsa`).
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn quad_state(&self) -> QuadState<R> {
        to_quad_state(&self.x)
    }

    #[inline]
    fn body_attitude(&self) -> Option<BodyAttitude<R>> {
        let x = &self.x;
        Some(BodyAttitude { quaternion: [x[6], x[7], x[8], x[9]], body_rates: [x[10], x[11], x[12]] })
    }

    #[inline]
    fn body_attitude_into(&self, out: &mut Option<BodyAttitude<R>>) {
        let x = &self.x;
        let b = out.get_or_insert_with(BodyAttitude::default);
        b.quaternion = [x[6], x[7], x[8], x[9]];
        b.body_rates = [x[10], x[11], x[12]];
    }

    fn begin_period(&mut self, lane: usize, tv: &TimeVarying, base_plant: &QuadrotorParams) -> Result<(), Divergence> {
        let added = tv.mass - base_plant.mass;
        let scale = tv.inertia[0] / base_plant.inertia[0];
        let l = &mut self.lanes[lane];
        if (added, scale) != l.key {
            let mass = l.base.mass + added;
            // The body's inertia is `scale · base` already when the scale
            // has not changed (a payload alone): then only the mass moves.
            let updated = if scale == l.key.1 {
                self.body.set_mass_in_lane(lane, mass)
            } else if l.plain_diagonal {
                self.body.set_mass_and_scaled_diagonal_inertia_in_lane(lane, mass, &l.base.inertia, scale)
            } else {
                self.body.set_mass_and_scaled_inertia_in_lane(lane, mass, &l.base.inertia, scale)
            };
            if updated.is_err() {
                // Never fly a mass or inertia other than the recorded one.
                return Err(Divergence::RigidBodyOutOfRange { mass, inertia_scale: scale });
            }
            l.key = (added, scale);
        }
        Ok(())
    }

    #[cfg_attr(not(debug_assertions), inline(always))]
    fn substep(&mut self, s: &[Substep<'_>]) {
        let s = &s[..R::LANES];
        let t0 = R::from_fn(|i| s[i].t0);
        let h = R::from_fn(|i| s[i].h);
        let mut wind = [R::default(); 3];
        for (i, s) in s.iter().enumerate() {
            wind.put_lane(i, s.wind.unwrap_or([0.0; 3]));
        }
        let body = &self.body;
        let mass = body.mass();
        // The inputs at each RK4 stage time, made once (the second and third
        // stages share theirs) on the lanes from each lane's substep gathered
        // once: the disturbance of `TimeVarying::lerp` (its mass and inertia
        // are not used here: the body's are those of the period) and the
        // rotor speeds of `Drive::speeds_after`, each lane with the
        // one-flight operations in their order.
        let (d_a, d_b) = (<[R; 6]>::from_lanes(s, |s| s.a.disturbance), <[R; 6]>::from_lanes(s, |s| s.b.disturbance));
        let mut d_gap = d_b;
        for k in 0..6 {
            d_gap[k] = d_b[k] - d_a[k];
        }
        // Closures in argument position, forced inline: the whole step then
        // compiles inside the dispatched kernel (`OnIsa`), none of it left
        // behind in a baseline-ISA function.
        self.x = rk4_step_staged(
            #[cfg_attr(not(debug_assertions), inline(always))]
            |tau: R| {
                // (`core::array::from_fn` and `map` are avoided in the
                // kernels: their out-of-line instances compile for the
                // baseline instruction set.)
                let w = (tau - t0) / h;
                let mut d = d_a;
                for k in 0..6 {
                    d[k] = d_a[k] + w * d_gap[k];
                }
                body.prepare(&RigidBodyInput {
                    rotor_speeds: rotor_speeds_after(s, tau - t0),
                    wind,
                    force: [mass * d[0], mass * d[1], mass * d[2]],
                    torque: body.inertia_times([d[3], d[4], d[5]]),
                })
            },
            #[cfg_attr(not(debug_assertions), inline(always))]
            |input, x| body.derivative_prepared(x, input),
            t0,
            &self.x,
            h,
        );
        normalize_quaternion(&mut self.x);
    }

    #[inline]
    fn translation(&self, lane: usize) -> ([f64; 3], [f64; 3]) {
        let x = &self.x;
        (
            [x[0].get_lane(lane), x[1].get_lane(lane), x[2].get_lane(lane)],
            [x[3].get_lane(lane), x[4].get_lane(lane), x[5].get_lane(lane)],
        )
    }

    #[inline]
    fn set_translation(&mut self, lane: usize, p: &[f64; 3], v: &[f64; 3]) {
        for i in 0..3 {
            self.x[i].put_lane(lane, p[i]);
            self.x[3 + i].put_lane(lane, v[i]);
        }
    }

    fn start_lane(&mut self, lane: usize, scenario: &Scenario) -> Result<(), LaneStart> {
        if scenario.vehicle.model != VehicleModel::RigidBody {
            return Err(LaneStart::OtherModel);
        }
        let (body, one, x) = rigid_flight(scenario).map_err(LaneStart::Invalid)?;
        self.body.put_lane(lane, body);
        self.lanes[lane] = one;
        self.x.put_lane(lane, x);
        Ok(())
    }
}

/// A truth model whose substeps run on a chosen instruction set
/// ([`crate::isa`]): the lane kernels compiled for AVX2 + FMA when the CPU
/// has them, the same bits either way.
struct OnIsa<T> {
    inner: T,
    isa: crate::isa::Isa,
}

impl<R: Real, T: TruthModel<R>> TruthModel<R> for OnIsa<T> {
    fn quad_state(&self) -> QuadState<R> {
        let mut state = QuadState::default();
        self.quad_state_into(&mut state);
        state
    }
    fn body_attitude(&self) -> Option<BodyAttitude<R>> {
        self.inner.body_attitude()
    }
    fn quad_state_into(&self, out: &mut QuadState<R>) {
        let inner = &self.inner;
        crate::isa::run_on(
            self.isa,
            #[cfg_attr(not(debug_assertions), inline(always))]
            || inner.quad_state_into(out),
        );
    }
    fn body_attitude_into(&self, out: &mut Option<BodyAttitude<R>>) {
        self.inner.body_attitude_into(out);
    }
    fn begin_period(&mut self, lane: usize, tv: &TimeVarying, base: &QuadrotorParams) -> Result<(), Divergence> {
        self.inner.begin_period(lane, tv, base)
    }
    fn substep(&mut self, s: &[Substep<'_>]) {
        let inner = &mut self.inner;
        crate::isa::run_on(
            self.isa,
            #[cfg_attr(not(debug_assertions), inline(always))]
            || inner.substep(s),
        );
    }
    fn translation(&self, lane: usize) -> ([f64; 3], [f64; 3]) {
        self.inner.translation(lane)
    }
    fn set_translation(&mut self, lane: usize, p: &[f64; 3], v: &[f64; 3]) {
        self.inner.set_translation(lane, p, v);
    }
    fn start_lane(&mut self, lane: usize, scenario: &Scenario) -> Result<(), LaneStart> {
        self.inner.start_lane(lane, scenario)
    }
}

/// What a flight's truth model brings to the loop ([`truth_of`]).
pub(crate) struct TruthSetup {
    /// Its allocation `u = A ω²`.
    pub allocation: [[f64; 4]; 4],
    /// Paper-form parameters of its unsaturated rotor-speed demand.
    pub demand: QuadrotorParams,
    /// Its hover rotor speed, rad/s.
    pub hover: f64,
    /// Why it cannot fly (an out-of-range rigid body: the paper plant
    /// stands in and the run stops at t = 0).
    pub invalid: Option<Divergence>,
}

/// The allocation, demand model, hover speed and validity of the truth
/// model `scenario` flies (`[vehicle] model`; the model itself:
/// [`truth_lanes`]).
pub(crate) fn truth_of(scenario: &Scenario) -> TruthSetup {
    let (allocation, demand) = scenario.truth_allocation();
    let p = scenario.true_vehicle();
    let paper_hover = (p.mass * p.gravity / (4.0 * p.lift_coefficient)).sqrt();
    let (hover, invalid) = match scenario.vehicle.model {
        VehicleModel::Paper => (paper_hover, None),
        VehicleModel::RigidBody => match rigid_flight(scenario) {
            Ok((_, lane, _)) => (lane.base.hover_rotor_speed(), None),
            Err(why) => (paper_hover, Some(why)),
        },
    };
    TruthSetup { allocation, demand, hover, invalid }
}

/// The truth model of `scenario` in every lane of `R` at its initial state
/// (`[vehicle] model`; `Err`: its rigid body is out of range, which
/// [`truth_of`] reports as `invalid`). New flights enter lanes with
/// [`TruthModel::start_lane`].
pub(crate) fn truth_lanes<R: Real>(scenario: &Scenario) -> Result<Box<dyn TruthModel<R> + Send>, Divergence> {
    // One flight keeps the baseline path; lanes run on the detected instruction set.
    let isa = if R::LANES > 1 { crate::isa::Isa::detect() } else { crate::isa::Isa::Baseline };
    Ok(match scenario.vehicle.model {
        VehicleModel::Paper => Box::new(OnIsa { inner: PaperTruth::<R>::new(scenario), isa }),
        VehicleModel::RigidBody => Box::new(OnIsa { inner: RigidTruth::<R>::new(scenario)?, isa }),
    })
}

#[cfg(test)]
mod lane_tests {
    //! Lane equivalence: a truth model on `Lanes<4>` and `Lanes<8>`, each
    //! lane flying its own scenario (vehicle, drive, wind, disturbances,
    //! commands), equals bit for bit the one-flight models fed the same
    //! inputs, substep by substep.

    use super::*;
    use crate::actuators::{MixerKind, NoiseScale};
    use crate::environment::wind::Wind;
    use crate::run::actuation::{ActuatorStage, Delivered};
    use crate::scenario::ladder::{REALISTIC_CALM_2, REALISTIC_MODERATE_2};
    use crate::scenario::{PAPER_SCENARIO_1, PAPER_SCENARIO_2};
    use crate::vehicle::{Configuration, Inertia};
    use ftsmc_core::lanes::Lanes;

    fn parse(text: &str, name: &str) -> Scenario {
        Scenario::from_toml_str(&format!("{text}\n"), name).unwrap()
    }

    /// Scenarios of one model, differing in everything a lane may differ in.
    fn scenarios(rigid: bool) -> Vec<Scenario> {
        let moderate = parse(REALISTIC_MODERATE_2, "realistic-moderate-2.toml");
        let calm = parse(REALISTIC_CALM_2, "realistic-calm-2.toml");
        let paper = parse(PAPER_SCENARIO_2, "paper-scenario-2.toml");
        let mut out = Vec::new();
        if rigid {
            // Lagged rotors in wind; lagged in still air, heavier; held
            // (clamp mixer) with products of inertia in the "×" layout; the
            // paper vehicle (no aerodynamics) on default rotors.
            // The first two with motor noise, relative and absolute (no
            // built-in scenario has any).
            let noisy = |s: &Scenario, std: f64, scale: NoiseScale| {
                let mut s = s.clone();
                s.actuators = s.actuators.map(|a| crate::actuators::ActuatorParams {
                    noise: Some(crate::actuators::MotorNoise { std, scale }),
                    ..a
                });
                s
            };
            out.push(noisy(&moderate, 0.05, NoiseScale::Relative));
            let mut heavy = noisy(&calm, 40.0, NoiseScale::Absolute);
            heavy.vehicle.mass = Some(0.9);
            heavy.seed = 11;
            out.push(heavy);
            let mut held = calm.clone();
            held.actuators = held.actuators.map(|a| crate::actuators::ActuatorParams {
                mixer: MixerKind::Clamp,
                time_constant_up: 0.0,
                time_constant_down: 0.0,
                ..a
            });
            held.vehicle.inertia =
                Some(Inertia::Matrix([[0.007, 2e-4, -1e-4], [2e-4, 0.0072, 5e-5], [-1e-4, 5e-5, 0.012]]));
            held.vehicle.configuration = Some(Configuration::Cross);
            held.wind = moderate.wind.clone();
            out.push(held);
            let mut bare = paper.clone();
            bare.vehicle.model = VehicleModel::RigidBody;
            out.push(bare);
        } else {
            // Ideal (held) in still air; held in wind; lagged rotors; paper 1.
            out.push(paper.clone());
            let mut windy = paper.clone();
            windy.wind = moderate.wind.clone();
            windy.seed = 5;
            out.push(windy);
            let mut lagged = paper.clone();
            lagged.actuators = calm.actuators;
            out.push(lagged);
            out.push(parse(PAPER_SCENARIO_1, "paper-scenario-1.toml"));
        }
        out
    }

    /// A small deterministic generator, uniform in [−1, 1).
    struct Lcg(u64);
    impl Lcg {
        fn next(&mut self) -> f64 {
            self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        }
    }

    /// One flight's surroundings, as `Flight` sets them up, and its
    /// one-flight truth model (apart: the substeps borrow the former while
    /// the latter integrates).
    struct ScalarFlight<'s> {
        scenario: &'s Scenario,
        env: Environment,
        actuators: ActuatorStage,
        wind: Option<Wind>,
        tv_now: TimeVarying,
        base_plant: QuadrotorParams,
        h: f64,
        k: u64,
    }

    impl<'s> ScalarFlight<'s> {
        fn new(scenario: &'s Scenario) -> (Self, Box<dyn TruthModel + Send>) {
            let h = scenario.control_period() / scenario.simulation.substeps as f64;
            let setup = truth_of(scenario);
            assert!(setup.invalid.is_none());
            let actuators = ActuatorStage::of(scenario, setup.allocation, setup.hover, h);
            let mut env_params = scenario.environment();
            if scenario.vehicle.model == VehicleModel::RigidBody {
                env_params.drag_noise = None;
            }
            let mut env = Environment::new(env_params).on_grid(h);
            let wind = scenario.wind.clone().and_then(|w| Wind::new(w, h, scenario.seed).ok());
            let tv_now = env.time_varying_on_grid(0, 0.0);
            let lane = Self { scenario, env, actuators, wind, tv_now, base_plant: scenario.true_vehicle(), h, k: 0 };
            (lane, truth_lanes::<f64>(scenario).expect("valid"))
        }

        fn t0(&self, j: u32) -> f64 {
            self.k as f64 * self.scenario.control_period() + j as f64 * self.h
        }
    }

    /// Bits, any NaN as one: Rust leaves a NaN's sign and payload
    /// unspecified (RFC 3514), and the compiler orders the operands of a
    /// vector and a scalar operation as it likes.
    fn to_bits(v: f64) -> u64 {
        if v.is_nan() {
            f64::NAN.to_bits()
        } else {
            v.to_bits()
        }
    }

    fn assert_lane<R: Real>(lanes: &dyn TruthModel<R>, i: usize, scalar: &dyn TruthModel, at: &str) {
        let bits = |q: QuadState| [q.position, q.attitude, q.velocity, q.angular_rate].map(|v| v.map(to_bits));
        assert_eq!(bits(lanes.quad_state().get_lane(i)), bits(scalar.quad_state()), "lane {i} {at}");
        let body = |b: Option<BodyAttitude>| b.map(|b| (b.quaternion.map(to_bits), b.body_rates.map(to_bits)));
        assert_eq!(body(lanes.body_attitude().map(|b| b.get_lane(i))), body(scalar.body_attitude()), "lane {i} {at}");
        let v = |(p, v): ([f64; 3], [f64; 3])| (p.map(to_bits), v.map(to_bits));
        assert_eq!(v(lanes.translation(i)), v(scalar.translation(0)), "lane {i} {at}");
    }

    /// Fly `periods` control periods of `R::LANES` flights of one model in
    /// lanes and one by one, comparing every lane after every substep.
    /// Lanes cycle through [`scenarios`]; every lane's commands are random,
    /// with saturating ones now and then; the lanes below ground are
    /// clamped (`set_translation`); lane 2 starts a new flight a third of the
    /// way (`start_lane`); lane 3 gets a NaN command and disturbance late; even lanes see
    /// their mass and inertia change (`begin_period`), once out of range.
    /// Returns the number of substeps flown and how many lanes went
    /// non-finite.
    fn fly<R: Real>(rigid: bool, periods: u64) -> (u64, usize) {
        fly_pool::<R>(scenarios(rigid), rigid, periods)
    }

    /// [`fly`] with the lanes cycling through `pool`.
    fn fly_pool<R: Real>(pool: Vec<Scenario>, rigid: bool, periods: u64) -> (u64, usize) {
        let n = R::LANES;
        let (mut lanes, mut scalars): (Vec<ScalarFlight<'_>>, Vec<Box<dyn TruthModel + Send>>) =
            (0..n).map(|i| ScalarFlight::new(&pool[i % pool.len()])).unzip();
        let mut model = truth_lanes::<R>(&pool[0]).unwrap();
        for (i, lane) in lanes.iter().enumerate() {
            model.start_lane(i, lane.scenario).unwrap();
            assert_lane(&*model, i, &*scalars[i], "start");
        }
        // A flight of the other model is refused, the lane unchanged.
        let other = scenarios(!rigid);
        assert_eq!(model.start_lane(0, &other[0]), Err(LaneStart::OtherModel));
        assert_lane(&*model, 0, &*scalars[0], "refused");
        let mut rng = Lcg(42);
        let mut refused = 0;
        let mut substeps = 0;
        for period in 0..periods {
            if period == periods / 3 {
                let (lane, scalar) = ScalarFlight::new(&pool[3 % pool.len()]);
                let r = 2 % n;
                lanes[r] = lane;
                scalars[r] = scalar;
                model.start_lane(r, lanes[r].scenario).unwrap();
                assert_lane(&*model, r, &*scalars[r], "restart");
            }
            let mut delivered: Vec<Delivered> = Vec::with_capacity(n);
            for (i, lane) in lanes.iter_mut().enumerate() {
                let (m, g) = (lane.base_plant.mass, lane.base_plant.gravity);
                let mut command = Command {
                    thrust: m * g * (1.0 + 0.4 * rng.next()),
                    torque: [0.02 * rng.next(), 0.02 * rng.next(), 0.005 * rng.next()],
                };
                if (period + i as u64) % 29 == 0 {
                    // Far past the rotors: saturations.
                    command.thrust *= 4.0;
                    command.torque[0] = 2.0;
                }
                if i == 3 % n && period == periods * 4 / 5 {
                    // A NaN command (which a mixer may clamp) and a NaN
                    // disturbance (which no stage does).
                    command.thrust = f64::NAN;
                    lane.tv_now.disturbance[0] = f64::NAN;
                }
                lane.env.next_period();
                let plant_now = lane.env.params_with(&lane.tv_now);
                let mut d = Delivered::none();
                lane.actuators.deliver_into(&command, &plant_now, &mut d);
                delivered.push(d);
                let mut tv = lane.tv_now;
                if i % 2 == 0 && period % 3 == 0 {
                    tv.mass += 0.1 * rng.next();
                    if period % 9 == 0 {
                        tv.inertia = tv.inertia.map(|v| v * (1.0 + 0.3 * rng.next()));
                    }
                }
                if i % 2 == 0 && period == periods / 2 {
                    tv.mass = -5.0;
                }
                let a = scalars[i].begin_period(0, &tv, &lane.base_plant);
                let b = model.begin_period(i, &tv, &lane.base_plant);
                assert_eq!(a, b, "lane {i} period {period}");
                refused += usize::from(a.is_err());
                assert_lane(&*model, i, &*scalars[i], "begin_period");
            }
            let steps = lanes[0].scenario.simulation.substeps;
            assert!(lanes.iter().all(|l| l.scenario.simulation.substeps == steps));
            for j in 0..steps {
                let mut winds = Vec::with_capacity(n);
                let mut next = Vec::with_capacity(n);
                for lane in lanes.iter_mut() {
                    let t0 = lane.t0(j);
                    winds.push(lane.wind.as_mut().map(|w| w.step(t0)));
                    next.push(lane.env.time_varying_on_grid(lane.k * u64::from(steps) + u64::from(j) + 1, t0 + lane.h));
                }
                let held: Vec<crate::actuators::HeldCommand> = lanes
                    .iter()
                    .enumerate()
                    .map(|(i, lane)| {
                        let mut held = Default::default();
                        lane.actuators.held(&delivered[i], &mut held);
                        held
                    })
                    .collect();
                let subs: Vec<Substep<'_>> = lanes
                    .iter()
                    .enumerate()
                    .map(|(i, lane)| Substep {
                        t0: lane.t0(j),
                        h: lane.h,
                        a: &lane.tv_now,
                        b: &next[i],
                        env: &lane.env,
                        drive: lane.actuators.drive(&delivered[i], residual_speed(&delivered[i].target), &held[i]),
                        wind: winds[i],
                    })
                    .collect();
                model.substep(&subs);
                for (scalar, sub) in scalars.iter_mut().zip(&subs) {
                    scalar.substep(core::slice::from_ref(sub));
                }
                drop(subs);
                for (i, scalar) in scalars.iter_mut().enumerate() {
                    let (mut p, mut v) = scalar.translation(0);
                    if p[2] < 0.0 {
                        // A ground at z = 0 (frictionless here).
                        p[2] = 0.0;
                        v[2] = v[2].max(0.0);
                        scalar.set_translation(0, &p, &v);
                        model.set_translation(i, &p, &v);
                    }
                    assert_lane(&*model, i, &**scalar, &format!("period {period} substep {j}"));
                }
                for (lane, tv) in lanes.iter_mut().zip(next) {
                    lane.tv_now = tv;
                }
                substeps += 1;
            }
            for (lane, d) in lanes.iter_mut().zip(&delivered) {
                lane.actuators.advance(&d.target);
                lane.k += 1;
            }
        }
        let nonfinite = scalars.iter().filter(|s| !s.quad_state().to_array().iter().all(|v| v.is_finite())).count();
        assert_eq!(refused > 0, rigid, "begin_period refuses the rigid body's out-of-range mass only");
        (substeps, nonfinite)
    }

    #[test]
    fn rigid_body_in_4_lanes_is_4_flights_bit_for_bit() {
        let (substeps, nonfinite) = fly::<Lanes<4>>(true, 400);
        assert!(substeps >= 400, "{substeps}");
        assert!(nonfinite >= 1, "the NaN lane");
    }

    #[test]
    fn rigid_body_in_8_lanes_is_8_flights_bit_for_bit() {
        let (substeps, _) = fly::<Lanes<8>>(true, 400);
        assert!(substeps >= 400, "{substeps}");
    }

    #[test]
    fn paper_model_in_4_lanes_is_4_flights_bit_for_bit() {
        let (substeps, nonfinite) = fly::<Lanes<4>>(false, 400);
        assert!(substeps >= 400, "{substeps}");
        assert!(nonfinite >= 1, "the NaN lane");
    }

    #[test]
    fn paper_model_in_8_lanes_is_8_flights_bit_for_bit() {
        let (substeps, _) = fly::<Lanes<8>>(false, 400);
        assert!(substeps >= 400, "{substeps}");
    }

    /// Eq. 1 with held rotors in every lane (the wrench of the substep, with
    /// and without wind): the lanes' other path.
    #[test]
    fn paper_model_with_held_rotors_in_lanes_is_flights_bit_for_bit() {
        let held = || scenarios(false).into_iter().filter(|s| s.actuators.is_none()).collect::<Vec<_>>();
        assert_eq!(held().len(), 3);
        let (substeps, nonfinite) = fly_pool::<Lanes<4>>(held(), false, 400);
        assert!(substeps >= 400 && nonfinite >= 1, "{substeps} {nonfinite}");
        let (substeps, _) = fly_pool::<Lanes<8>>(held(), false, 400);
        assert!(substeps >= 400);
    }

    /// One lane is one flight: the lanes model on `f64` is the model
    /// `truth_of` gives (the same trait object type behind both).
    #[test]
    fn one_lane_is_the_one_flight_model() {
        let (substeps, _) = fly::<f64>(true, 400);
        assert!(substeps >= 150);
        let (substeps, _) = fly::<f64>(false, 400);
        assert!(substeps >= 150);
    }
}
