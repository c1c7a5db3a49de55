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

use ftsmc_core::allocation::{forces_from_squared_speeds, residual_speed};
use ftsmc_core::lanes::{Lanewise, Real};
use ftsmc_core::measured::BodyAttitude;
use ftsmc_core::model::{Command, QuadState, QuadrotorParams};

use crate::environment::Environment;
use crate::environment::TimeVarying;
use crate::scenario::Scenario;
use crate::vehicle::paper::{derivative_in_wind_of, derivative_of, rk4_step_staged, Eq1Params};
use crate::vehicle::rigid_body::{normalize_quaternion, RigidBodyState};
use crate::vehicle::{from_quad_state, to_quad_state, RigidBody, RigidBodyInput, RigidBodyParams, VehicleModel};

use super::actuation::Drive;
use super::Divergence;

/// One RK4 substep `[t0, t0 + h]` as the loop hands it to a truth model.
pub(crate) struct Substep<'a> {
    /// Start time, s.
    pub t0: f64,
    /// Length, s.
    pub h: f64,
    /// Time-varying plant inputs at `t0` and `t0 + h` (interpolated linearly inside).
    pub a: TimeVarying,
    /// See `a`.
    pub b: TimeVarying,
    /// The environment (drag noise of the period).
    pub env: &'a Environment<'a>,
    /// The rotors.
    pub drive: Drive<'a>,
    /// Wind held over the substep, world frame, m/s (`None`: still air, no `[wind]`).
    pub wind: Option<[f64; 3]>,
}

/// Why a flight cannot start in a lane ([`TruthModel::start_lane`]).
#[derive(Clone, Copy, Debug, PartialEq)]
#[allow(dead_code)] // the batched run loop is built on it next
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
    /// Height `z` (m) and vertical velocity `ż` (m/s) of lane `lane`, for
    /// ground contact.
    fn vertical(&self, lane: usize) -> (f64, f64);
    /// Overwrite lane `lane`'s `z` (m) and `ż` (m/s) (ground contact).
    fn set_vertical(&mut self, lane: usize, z: f64, vz: f64);
    /// Start a new flight of `scenario` in lane `lane`: its vehicle and its
    /// initial state, the other lanes untouched. On error the lane is
    /// unchanged.
    #[allow(dead_code)] // the batched run loop is built on it next
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
#[inline]
fn paper_stage(s: &Substep<'_>, tau: f64) -> PaperStage {
    let tv = TimeVarying::lerp(&s.a, &s.b, (tau - s.t0) / s.h);
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

impl<R: Real> PaperTruth<R> {
    /// Every lane at `scenario`'s initial state.
    pub(crate) fn new(scenario: &Scenario) -> Self {
        Self(scenario.initial_state.state().to_array().map(R::splat))
    }
}

impl<R: Real> TruthModel<R> for PaperTruth<R> {
    #[inline]
    fn quad_state(&self) -> QuadState<R> {
        let a = &self.0;
        QuadState {
            position: [a[0], a[1], a[2]],
            attitude: [a[3], a[4], a[5]],
            velocity: [a[6], a[7], a[8]],
            angular_rate: [a[9], a[10], a[11]],
        }
    }

    #[inline]
    fn substep(&mut self, s: &[Substep<'_>]) {
        let s = &s[..R::LANES];
        let t0 = R::from_fn(|i| s[i].t0);
        let h = R::from_fn(|i| s[i].h);
        // The plant of each RK4 stage time, made once per lane with the
        // one-flight code (the second and third stages share theirs).
        let inputs = |tau: R| {
            let mut stage = PaperStage::<R>::default();
            for (i, s) in s.iter().enumerate() {
                stage.put_lane(i, paper_stage(s, tau.get_lane(i)));
            }
            stage
        };
        // Eq. 1 in still air unless some lane has wind or lagged rotors
        // (which always took the wind form); the wind form with a zero wind
        // is Eq. 1 bit for bit (`v − 0 = v`), so a still-air lane flies the
        // same either way.
        let in_wind = s.iter().any(|s| s.wind.is_some() || matches!(s.drive, Drive::Lagged { .. }));
        self.0 = if in_wind {
            let f = |st: &PaperStage<R>, x: &[R; 12]| {
                derivative_in_wind_of(x, &st.command, st.omega_bar, &st.plant, &st.disturbance, &st.wind)
            };
            rk4_step_staged(inputs, f, t0, &self.0, h)
        } else {
            let f = |st: &PaperStage<R>, x: &[R; 12]| {
                derivative_of(x, &st.command, st.omega_bar, &st.plant, &st.disturbance)
            };
            rk4_step_staged(inputs, f, t0, &self.0, h)
        };
    }

    #[inline]
    fn vertical(&self, lane: usize) -> (f64, f64) {
        (self.0[2].get_lane(lane), self.0[8].get_lane(lane))
    }

    #[inline]
    fn set_vertical(&mut self, lane: usize, z: f64, vz: f64) {
        self.0[2].put_lane(lane, z);
        self.0[8].put_lane(lane, vz);
    }

    fn start_lane(&mut self, lane: usize, scenario: &Scenario) -> Result<(), LaneStart> {
        if scenario.vehicle.model != VehicleModel::Paper {
            return Err(LaneStart::OtherModel);
        }
        self.0.put_lane(lane, scenario.initial_state.state().to_array());
        Ok(())
    }
}

/// One flight's rigid-body bookkeeping beside its lane of the body.
#[derive(Clone, Copy, Debug)]
struct RigidLane {
    /// The scenario's vehicle.
    base: RigidBodyParams,
    /// The added mass (kg) and inertia scale the lane's body flies: its mass
    /// is `base.mass + key.0`, its inertia `key.1 · base.inertia`.
    key: (f64, f64),
}

/// The rigid body of `scenario` at its initial state, one flight.
fn rigid_flight(scenario: &Scenario) -> Result<(RigidBody, RigidLane, RigidBodyState), Divergence> {
    let base = scenario.rigid_body_params();
    let body =
        RigidBody::new(base).map_err(|_| Divergence::RigidBodyOutOfRange { mass: base.mass, inertia_scale: 1.0 })?;
    Ok((body, RigidLane { base, key: (0.0, 1.0) }, from_quad_state(&scenario.initial_state.state())))
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
    #[inline]
    fn quad_state(&self) -> QuadState<R> {
        // The Euler conversion is the one-flight one, lane by lane.
        let mut q = QuadState::<R>::default();
        for i in 0..R::LANES {
            q.put_lane(i, to_quad_state(&self.x.get_lane(i)));
        }
        q
    }

    #[inline]
    fn body_attitude(&self) -> Option<BodyAttitude<R>> {
        let x = &self.x;
        Some(BodyAttitude { quaternion: [x[6], x[7], x[8], x[9]], body_rates: [x[10], x[11], x[12]] })
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

    #[inline]
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
        // stages share theirs): each lane's rotor speeds and disturbance by
        // the one-flight code, then the body's terms on the lanes.
        let inputs = |tau: R| {
            let mut rotor_speeds = [R::default(); 4];
            let mut d = [R::default(); 6];
            for (i, s) in s.iter().enumerate() {
                let tau = tau.get_lane(i);
                // The disturbance of `TimeVarying::lerp` (its mass and
                // inertia are not used here: the body's are those of the period).
                let w = (tau - s.t0) / s.h;
                let (a, b) = (&s.a.disturbance, &s.b.disturbance);
                d.put_lane(i, core::array::from_fn(|k| a[k] + w * (b[k] - a[k])));
                rotor_speeds.put_lane(i, s.drive.speeds_after(tau - s.t0));
            }
            body.prepare(&RigidBodyInput {
                rotor_speeds,
                wind,
                force: [mass * d[0], mass * d[1], mass * d[2]],
                torque: body.inertia_times([d[3], d[4], d[5]]),
            })
        };
        self.x = rk4_step_staged(inputs, |input, x| body.derivative_prepared(x, input), t0, &self.x, h);
        normalize_quaternion(&mut self.x);
    }

    #[inline]
    fn vertical(&self, lane: usize) -> (f64, f64) {
        (self.x[2].get_lane(lane), self.x[5].get_lane(lane))
    }

    #[inline]
    fn set_vertical(&mut self, lane: usize, z: f64, vz: f64) {
        self.x[2].put_lane(lane, z);
        self.x[5].put_lane(lane, vz);
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

/// What a flight's truth model brings to the loop ([`truth_of`]).
pub(crate) struct TruthSetup {
    /// The model at the scenario's initial state.
    pub truth: Box<dyn TruthModel + Send>,
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

/// The truth model `scenario` flies (`[vehicle] model`).
pub(crate) fn truth_of(scenario: &Scenario) -> TruthSetup {
    let (allocation, demand) = scenario.truth_allocation();
    let p = scenario.true_plant();
    let paper_hover = (p.mass * p.gravity / (4.0 * p.lift_coefficient)).sqrt();
    let paper = || Box::new(PaperTruth::<f64>::new(scenario));
    let (truth, hover, invalid): (Box<dyn TruthModel + Send>, f64, Option<Divergence>) = match scenario.vehicle.model {
        VehicleModel::Paper => (paper(), paper_hover, None),
        VehicleModel::RigidBody => match RigidTruth::new(scenario) {
            Ok(truth) => {
                let hover = truth.lanes[0].base.hover_rotor_speed();
                (Box::new(truth), hover, None)
            }
            Err(why) => (paper(), paper_hover, Some(why)),
        },
    };
    TruthSetup { truth, allocation, demand, hover, invalid }
}

/// The truth model of `scenario` in every lane of `R` at its initial state
/// (`[vehicle] model`; `Err`: its rigid body is out of range, which
/// [`truth_of`] reports as `invalid`). New flights enter lanes with
/// [`TruthModel::start_lane`].
#[allow(dead_code)] // the batched run loop is built on it next
pub(crate) fn truth_lanes<R: Real>(scenario: &Scenario) -> Result<Box<dyn TruthModel<R> + Send>, Divergence> {
    Ok(match scenario.vehicle.model {
        VehicleModel::Paper => Box::new(PaperTruth::<R>::new(scenario)),
        VehicleModel::RigidBody => Box::new(RigidTruth::<R>::new(scenario)?),
    })
}
