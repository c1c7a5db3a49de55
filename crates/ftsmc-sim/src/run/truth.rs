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

use crate::environment::{Environment, TimeVarying};
use crate::scenario::Scenario;
use crate::vehicle::paper::{derivative, derivative_in_wind, rk4_step_staged};
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

/// A truth model the loop can fly.
pub(crate) trait OneTruth {
    /// The state in the Euler form every controller takes.
    fn quad_state(&self) -> QuadState;
    /// The attitude as quaternion and body rates, when the model has them
    /// (handed to full-state controllers beside the Euler state). The
    /// default: none (the model's state is the Euler state).
    fn body_attitude(&self) -> Option<BodyAttitude> {
        None
    }
    /// The start of a control period with the plant variation `tv` (the
    /// rigid body's payload and inertia scaling); `base` is the true plant.
    /// An error stops the run: the model cannot represent this variation.
    fn begin_period(&mut self, tv: &TimeVarying, base: &QuadrotorParams) -> Result<(), Divergence> {
        let _ = (tv, base);
        Ok(())
    }
    /// Integrate one substep.
    fn substep(&mut self, s: &Substep<'_>);
    /// Height `z` (m) and vertical velocity `ż` (m/s), for ground contact.
    fn vertical(&mut self) -> (&mut f64, &mut f64);
    /// Height `z` (m) and vertical velocity `ż` (m/s), read.
    fn height(&self) -> (f64, f64);
}

/// Paper Eq. 1 in Euler form.
pub(crate) struct PaperTruth(pub [f64; 12]);

impl OneTruth for PaperTruth {
    #[inline]
    fn quad_state(&self) -> QuadState {
        QuadState::from_array(&self.0)
    }

    #[inline]
    fn substep(&mut self, s: &Substep<'_>) {
        let (t0, h, a, b, env, wind) = (s.t0, s.h, &s.a, &s.b, s.env, s.wind);
        // The plant of each RK4 stage time, made once (the second and third
        // stages share theirs).
        self.0 = match s.drive {
            Drive::Held { applied, omega_bar, .. } => {
                let inputs = |tau: f64| {
                    let tv = TimeVarying::lerp(a, b, (tau - t0) / h);
                    (env.params_with(&tv), tv.disturbance)
                };
                match wind {
                    None => {
                        rk4_step_staged(inputs, |(p, d), x| derivative(x, applied, omega_bar, p, d), t0, &self.0, h)
                    }
                    Some(wind) => rk4_step_staged(
                        inputs,
                        |(p, d), x| derivative_in_wind(x, applied, omega_bar, p, d, &wind),
                        t0,
                        &self.0,
                        h,
                    ),
                }
            }
            drive @ Drive::Lagged { .. } => {
                let wind = wind.unwrap_or([0.0; 3]);
                let inputs = |tau: f64| {
                    let tv = TimeVarying::lerp(a, b, (tau - t0) / h);
                    let p = env.params_with(&tv);
                    let w = drive.speeds_after(tau - t0);
                    let delivered: Command = forces_from_squared_speeds(&p, &w.map(|o| o * o));
                    (p, delivered, residual_speed(&w), tv.disturbance)
                };
                let f = |(p, delivered, omega_bar, d): &(QuadrotorParams, Command, f64, [f64; 6]), x: &[f64; 12]| {
                    derivative_in_wind(x, delivered, *omega_bar, p, d, &wind)
                };
                rk4_step_staged(inputs, f, t0, &self.0, h)
            }
        };
    }

    #[inline]
    fn vertical(&mut self) -> (&mut f64, &mut f64) {
        let (head, tail) = self.0.split_at_mut(8);
        (&mut head[2], &mut tail[0])
    }

    #[inline]
    fn height(&self) -> (f64, f64) {
        (self.0[2], self.0[8])
    }
}

/// The Newton–Euler rigid body ([`RigidBody`]).
pub(crate) struct RigidTruth {
    body: RigidBody,
    base: RigidBodyParams,
    /// The added mass (kg) and inertia scale the body flies: its mass is
    /// `base.mass + key.0`, its inertia `key.1 · base.inertia`.
    key: (f64, f64),
    x: RigidBodyState,
}

impl RigidTruth {
    /// The rigid body of `scenario` at its initial state (`Err`: its
    /// parameters are out of range; `Scenario::validate` refuses them, a
    /// caller may skip validation).
    pub(crate) fn new(scenario: &Scenario) -> Result<Self, Divergence> {
        let base = scenario.rigid_body_params();
        let body = RigidBody::new(base)
            .map_err(|_| Divergence::RigidBodyOutOfRange { mass: base.mass, inertia_scale: 1.0 })?;
        Ok(Self { body, base, key: (0.0, 1.0), x: from_quad_state(&scenario.initial_state.state()) })
    }
}

impl OneTruth for RigidTruth {
    #[inline]
    fn quad_state(&self) -> QuadState {
        to_quad_state(&self.x)
    }

    #[inline]
    fn body_attitude(&self) -> Option<BodyAttitude> {
        let x = &self.x;
        Some(BodyAttitude { quaternion: [x[6], x[7], x[8], x[9]], body_rates: [x[10], x[11], x[12]] })
    }

    fn begin_period(&mut self, tv: &TimeVarying, base_plant: &QuadrotorParams) -> Result<(), Divergence> {
        let added = tv.mass - base_plant.mass;
        let scale = tv.inertia[0] / base_plant.inertia[0];
        if (added, scale) != self.key {
            let mass = self.base.mass + added;
            // The body's inertia is `scale · base` already when the scale
            // has not changed (a payload alone): then only the mass moves.
            let updated = if scale == self.key.1 {
                self.body.set_mass(mass)
            } else {
                self.body.set_mass_and_scaled_inertia(mass, &self.base.inertia, scale)
            };
            if updated.is_err() {
                // Never fly a mass or inertia other than the recorded one.
                return Err(Divergence::RigidBodyOutOfRange { mass, inertia_scale: scale });
            }
            self.key = (added, scale);
        }
        Ok(())
    }

    #[inline]
    fn substep(&mut self, s: &Substep<'_>) {
        let (t0, h, a, b, drive) = (s.t0, s.h, &s.a, &s.b, &s.drive);
        let wind = s.wind.unwrap_or([0.0; 3]);
        let body = &self.body;
        let mass = body.params().mass;
        // The inputs at each RK4 stage time, made once (the second and third
        // stages share theirs).
        let inputs = |tau: f64| {
            // The disturbance of `TimeVarying::lerp` (its mass and inertia
            // are not used here: the body's are those of the period).
            let w = (tau - t0) / h;
            let d: [f64; 6] = core::array::from_fn(|i| a.disturbance[i] + w * (b.disturbance[i] - a.disturbance[i]));
            body.prepare(&RigidBodyInput {
                rotor_speeds: drive.speeds_after(tau - t0),
                wind,
                force: [mass * d[0], mass * d[1], mass * d[2]],
                torque: body.inertia_times([d[3], d[4], d[5]]),
            })
        };
        self.x = rk4_step_staged(inputs, |input, x| body.derivative_prepared(x, input), t0, &self.x, h);
        normalize_quaternion(&mut self.x);
    }

    #[inline]
    fn vertical(&mut self) -> (&mut f64, &mut f64) {
        let (head, tail) = self.x.split_at_mut(5);
        (&mut head[2], &mut tail[0])
    }

    #[inline]
    fn height(&self) -> (f64, f64) {
        (self.x[2], self.x[5])
    }
}

/// What a flight's truth model brings to the loop ([`truth_of`]).
pub(crate) struct TruthSetup {
    /// The model at the scenario's initial state.
    pub truth: Box<dyn OneTruth + Send>,
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
    let paper = || Box::new(PaperTruth(scenario.initial_state.state().to_array()));
    let (truth, hover, invalid): (Box<dyn OneTruth + Send>, f64, Option<Divergence>) = match scenario.vehicle.model {
        VehicleModel::Paper => (paper(), paper_hover, None),
        VehicleModel::RigidBody => match RigidTruth::new(scenario) {
            Ok(truth) => {
                let hover = truth.base.hover_rotor_speed();
                (Box::new(truth), hover, None)
            }
            Err(why) => (paper(), paper_hover, Some(why)),
        },
    };
    TruthSetup { truth, allocation, demand, hover, invalid }
}

/// A truth model the loop flies on lanes ([`ftsmc_core::lanes`]): lane `i`
/// is one flight's truth.
pub(crate) trait TruthModel<R: Real = f64> {
    /// The Euler states of the lanes.
    fn quad_state(&self) -> QuadState<R>;
    /// The lanes' quaternions and body rates, if the model has them.
    fn body_attitude(&self) -> Option<BodyAttitude<R>>;
    /// The start of a control period of lane `lane` with its plant variation.
    fn begin_period(&mut self, lane: usize, tv: &TimeVarying, base: &QuadrotorParams) -> Result<(), Divergence>;
    /// One RK4 substep of every lane; `s(i)` is lane `i`'s substep.
    fn substep<'a>(&mut self, s: &dyn Fn(usize) -> Substep<'a>);
    /// Height `z` (m) and vertical velocity `ż` (m/s) of lane `lane`.
    fn vertical(&self, lane: usize) -> (f64, f64);
    /// Set lane `lane`'s height and vertical velocity (ground contact).
    fn set_vertical(&mut self, lane: usize, z: f64, vz: f64);
    /// A new flight of `scenario` in lane `lane` at its initial state.
    fn start_lane(&mut self, lane: usize, scenario: &Scenario) -> Result<(), Divergence>;
}

/// Lanes of one-flight truth models, each flown on its own.
struct PerLane<R> {
    lanes: Vec<Box<dyn OneTruth + Send>>,
    _r: core::marker::PhantomData<R>,
}

impl<R: Real> TruthModel<R> for PerLane<R> {
    fn quad_state(&self) -> QuadState<R> {
        let mut q = QuadState::<R>::default();
        for (i, t) in self.lanes.iter().enumerate() {
            q.put_lane(i, t.quad_state());
        }
        q
    }
    fn body_attitude(&self) -> Option<BodyAttitude<R>> {
        let mut b = BodyAttitude::<R>::default();
        for (i, t) in self.lanes.iter().enumerate() {
            b.put_lane(i, t.body_attitude()?);
        }
        Some(b)
    }
    fn begin_period(&mut self, lane: usize, tv: &TimeVarying, base: &QuadrotorParams) -> Result<(), Divergence> {
        self.lanes[lane].begin_period(tv, base)
    }
    fn substep<'a>(&mut self, s: &dyn Fn(usize) -> Substep<'a>) {
        for (i, t) in self.lanes.iter_mut().enumerate() {
            t.substep(&s(i));
        }
    }
    fn vertical(&self, lane: usize) -> (f64, f64) {
        self.lanes[lane].height()
    }
    fn set_vertical(&mut self, lane: usize, z: f64, vz: f64) {
        let (zz, vv) = self.lanes[lane].vertical();
        *zz = z;
        *vv = vz;
    }
    fn start_lane(&mut self, lane: usize, scenario: &Scenario) -> Result<(), Divergence> {
        let setup = truth_of(scenario);
        self.lanes[lane] = setup.truth;
        setup.invalid.map_or(Ok(()), Err)
    }
}

/// The truth model of `scenario` on lanes, every lane at its initial state.
pub(crate) fn truth_lanes<R: Real>(scenario: &Scenario) -> Box<dyn TruthModel<R> + Send> {
    Box::new(PerLane::<R> {
        lanes: (0..R::LANES).map(|_| truth_of(scenario).truth).collect(),
        _r: core::marker::PhantomData,
    })
}
