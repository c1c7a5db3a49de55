//! Geometric tracking control on SE(3): Lee, Leok & McClamroch, *Geometric
//! tracking control of a quadrotor UAV on SE(3)*, CDC 2010, written
//! with world z up and body z along the thrust (the paper has z down).
//!
//! ```text
//! e_x = x − x_d,   e_v = v − v_d
//! F_d = −k_x e_x − k_v e_v + m g e₃ + m ẍ_d                 (desired force, N)
//! b₃d = F_d/‖F_d‖ (tilt-limited),  b₁c = (cos ψ_d, sin ψ_d, 0)
//! b₂d = b₃d × b₁c / ‖b₃d × b₁c‖,  b₁d = b₂d × b₃d,  R_d = [b₁d b₂d b₃d]
//! e_R = ½ (R_dᵀR − RᵀR_d)^∨,   e_Ω = Ω − RᵀR_d Ω_d
//! M = −k_R e_R − k_Ω e_Ω + Ω × JΩ − J(Ω̂ RᵀR_d Ω_d − RᵀR_d Ω̇_d)
//! f = F_d · R e₃   (bounded to [min_thrust, max_thrust])
//! ```
//!
//! Gains are per body axis (`k_x`, `k_v` per world axis), so `k_R e_R` is
//! the diagonal product; Lee et al. use scalars.
//!
//! # What is neglected
//!
//! * **Ω_d and Ω̇_d** are taken from the reference yaw only:
//!   `Ω_d = R_dᵀ e₃ ψ̇_d`, `Ω̇_d = R_dᵀ e₃ ψ̈_d`. The components that come from
//!   the rotation of `b₃d` (they need the jerk and snap of the desired force,
//!   i.e. derivatives of the measured velocity) and the `ψ̇_d Ṙ_d` term of
//!   Ω̇_d are dropped, as RotorPy's `se3_control.py` and most flight code do.
//!   For a step reference (paper scenario 1) Ω_d is then exactly zero after
//!   t = 0.
//! * **Two additions to the paper's law**: the desired thrust direction `b₃d`
//!   is tilt-limited to [`Se3Gains::max_tilt`] from the vertical (as PX4's
//!   `limitTilt`), and the thrust is bounded below by
//!   [`Se3Gains::min_thrust`] and above by [`Se3Gains::max_thrust`] so that the
//!   mixer keeps torque authority both when `F_d · R e₃` is negative (upside
//!   down: rotors cannot push) and when a large error asks for more thrust
//!   than the rotors have (the simulator's mixer gives thrust priority over
//!   torque). Neither acts near hover.
//!
//! # State conversion, and what is approximated on the paper plant
//!
//! The controller receives the Euler state of paper Eq. 1 ([`QuadState`]).
//! It builds `R = R_z(ψ) R_y(θ) R_x(φ)` and the body rates `Ω = W(φ, θ) η̇`
//! exactly ([`crate::kinematics::rotation_from_euler`],
//! [`crate::kinematics::body_rates_from_euler_rates`]). On the rigid-body truth
//! model the simulator reports the Euler angles and rates of its rotation
//! and body rates, so `R` and `Ω` are the true ones and the law is the
//! paper's. The paper plant (Eq. 1) instead drives the Euler-angle
//! accelerations directly with the torques, `I φ̈ = (I₂ − I₃) θ̇ ψ̇ − … + u₂`:
//! the moment computed for `J Ω̇ = M − Ω × JΩ` is applied to `η̈`. The two
//! agree to first order about hover (`W ≈ I`), and the law's `Ω × JΩ` term
//! cancels a coupling the paper plant writes with Euler rates instead
//! of body rates; at large tilt and rates the paper plant sees a different
//! (but still stabilising near hover) moment. The translational part of
//! Eq. 1 uses the same `R e₃`, so it is exact on both plants.

use crate::controller::{Controller, Telemetry};
use crate::kinematics::{
    body_rates_from_euler_rates, euler_from_rotation, rotation_from_euler, rotation_from_quaternion,
};
use crate::lanes::{branch, Blend, Lanewise, Mask, Real};
use crate::law::{check_closed, check_gain, check_left_open, saturate, GainError, INPUT_LIMIT, MAX_ESTIMATES};
use crate::math::{cross, dot, mat_t_mat, mat_t_vec, mat_vec, norm, Mat3, Vec3};
use crate::measured::{BodyAttitude, Measurement};
use crate::model::{Command, QuadState, QuadrotorParams, Reference};
use crate::setpoint::{finite_lanes, nan_command, HeadingSinCos, TiltLimit};

/// Gains of [`Se3Controller`]. `Default` is [`Se3Gains::for_vehicle`] of the
/// paper's quadrotor ([`QuadrotorParams::default`]).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Deserialize, serde::Serialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields, default))]
pub struct Se3Gains {
    /// Position gain `k_x` per world axis, N/m.
    pub position: [f64; 3],
    /// Velocity gain `k_v` per world axis, N·s/m.
    pub velocity: [f64; 3],
    /// Attitude gain `k_R` per body axis, N·m (per unit of `e_R`, ≈ rad for small errors).
    pub attitude: [f64; 3],
    /// Angular-velocity gain `k_Ω` per body axis, N·m·s/rad.
    pub angular_rate: [f64; 3],
    /// Largest angle between the desired thrust direction `b₃d` and the
    /// vertical, rad (not in Lee et al.; default 0.6 rad ≈ 34°, the paper
    /// cascades' default `max_tilt`, so the five controllers share one
    /// demand limit). Scenario key `max_demanded_tilt` (a limit on the
    /// demand, not on the flown tilt).
    #[cfg_attr(feature = "serde", serde(rename = "max_demanded_tilt"))]
    pub max_tilt: f64,
    /// Smallest thrust commanded, N (not in Lee et al., whose `f` may be
    /// negative; default `0.24 m g`, PX4's `MPC_THR_MIN` = 0.12 of a maximum
    /// thrust of `2 m g`, see [`crate::pid`]).
    pub min_thrust: f64,
    /// Largest thrust commanded, N (not in Lee et al.). Core default
    /// `1.6 m g`, 80 % of the `2 m g` maximum that [`crate::pid`] assumes
    /// on unlimited rotors: a cap for thrust-first mixers, where a thrust
    /// command at the rotors' maximum leaves no torque. The simulator's
    /// scenario defaults replace it by the rotors' whole thrust (PX4's
    /// mixer lowers the collective thrust to keep roll/pitch, so no cap is
    /// needed), or 10 m g on unlimited rotors.
    pub max_thrust: f64,
}

impl Default for Se3Gains {
    fn default() -> Self {
        Self::for_vehicle(&QuadrotorParams::default())
    }
}

impl Se3Gains {
    /// Gains by pole placement on the small-error closed loops:
    ///
    /// * attitude, per body axis: `J_i ë + k_Ω,i ė + k_R,i e = 0` with natural
    ///   frequency `ω_R,i` (rad/s) and damping `ζ_R`: `k_R,i = J_i ω_R,i²`,
    ///   `k_Ω,i = 2 ζ_R J_i ω_R,i`;
    /// * position, per world axis: `m ë + k_v ė + k_x e = 0` with `ω_x`, `ζ_x`:
    ///   `k_x = m ω_x²`, `k_v = 2 ζ_x m ω_x`.
    ///
    /// `max_tilt`, `min_thrust` and `max_thrust` take their defaults (0.6 rad,
    /// `0.24 m g`, `1.6 m g`).
    pub fn from_bandwidth(
        params: &QuadrotorParams,
        attitude_frequency: [f64; 3],
        attitude_damping: f64,
        position_frequency: f64,
        position_damping: f64,
    ) -> Self {
        let m = params.mass;
        let j = params.inertia;
        let w = attitude_frequency;
        let wx = position_frequency;
        Self {
            position: [m * wx * wx; 3],
            velocity: [2.0 * position_damping * m * wx; 3],
            attitude: [j[0] * w[0] * w[0], j[1] * w[1] * w[1], j[2] * w[2] * w[2]],
            angular_rate: [
                2.0 * attitude_damping * j[0] * w[0],
                2.0 * attitude_damping * j[1] * w[1],
                2.0 * attitude_damping * j[2] * w[2],
            ],
            max_tilt: 0.6,
            min_thrust: 0.24 * m * params.gravity,
            max_thrust: 1.6 * m * params.gravity,
        }
    }

    /// The default gains (docs/controllers.md, "se3"): RotorPy's
    /// Hummingbird gains (spencerfolk/rotorpy, `rotorpy/controllers/
    /// quadrotor_control.py`, `SE3Control`), which are per unit mass and
    /// inertia (`kp_pos = (6.5, 6.5, 15)`, `kd_pos = (4, 4, 9)` in 1/s² and
    /// 1/s; `kp_att = 544` 1/s², `kd_att = 46.64` 1/s), carried to `params`
    /// by RotorPy's own scaling: `k_x = m kp_pos`, `k_v = m kd_pos`,
    /// `k_R = J kp_att`, `k_Ω = J kd_att`. They place the position loop at
    /// ω_n = 2.55 rad/s (ζ 0.78) horizontally, 3.87 rad/s (ζ 1.16)
    /// vertically, and the attitude loop at ω_n = 23.3 rad/s (ζ 1.0) on
    /// every vehicle. Paper quadrotor: `k_x = (4.81, 4.81, 11.1) N/m`,
    /// `k_v = (2.96, 2.96, 6.66) N·s/m`, `k_R = (2.08, 2.08, 4.17) N·m`,
    /// `k_Ω = (0.178, 0.178, 0.357) N·m·s/rad`. `max_tilt`, `min_thrust`,
    /// `max_thrust` as [`Self::from_bandwidth`].
    pub fn for_vehicle(params: &QuadrotorParams) -> Self {
        let m = params.mass;
        let j = params.inertia;
        Self {
            position: [6.5 * m, 6.5 * m, 15.0 * m],
            velocity: [4.0 * m, 4.0 * m, 9.0 * m],
            attitude: j.map(|ji| 544.0 * ji),
            angular_rate: j.map(|ji| 46.64 * ji),
            ..Self::from_bandwidth(params, [1.0; 3], 1.0, 1.0, 1.0)
        }
    }

    /// Range checks: every gain in `(0, 1e6]`, `0 < max_tilt <= π/2`,
    /// `0 <= min_thrust < max_thrust <= 1e6` N. The error names the field (e.g.
    /// `attitude[2]`) and its value.
    pub fn check(&self) -> Result<(), GainError> {
        const NAMES: [[&str; 3]; 4] = [
            ["position[0]", "position[1]", "position[2]"],
            ["velocity[0]", "velocity[1]", "velocity[2]"],
            ["attitude[0]", "attitude[1]", "attitude[2]"],
            ["angular_rate[0]", "angular_rate[1]", "angular_rate[2]"],
        ];
        for (names, values) in NAMES.iter().zip([self.position, self.velocity, self.attitude, self.angular_rate]) {
            for (name, value) in names.iter().zip(values) {
                check_gain(name, value)?;
            }
        }
        check_left_open(
            "max_demanded_tilt",
            self.max_tilt,
            0.0,
            core::f64::consts::FRAC_PI_2,
            "0 < max_demanded_tilt <= π/2 (rad)",
        )?;
        check_closed("min_thrust", self.min_thrust, 0.0, 1e6, "0 <= min_thrust <= 1e6 (N)")?;
        check_left_open("max_thrust", self.max_thrust, self.min_thrust, 1e6, "min_thrust < max_thrust <= 1e6 (N)")
    }
}

/// `½ (R_dᵀR − RᵀR_d)^∨`, Lee et al. 2010 Eq. 10: zero at `R = R_d`, its
/// norm is `sin` of the rotation angle between them (per lane for lanes).
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn attitude_error<R: Real>(r: &Mat3<R>, r_d: &Mat3<R>) -> Vec3<R> {
    let m = mat_t_mat(r_d, r);
    // (M − Mᵀ)^∨ with M = R_dᵀR (so Mᵀ = RᵀR_d); `x · 0.5` is `0.5 x` with
    // its operands swapped (same bits).
    [(m[2][1] - m[1][2]) * 0.5, (m[0][2] - m[2][0]) * 0.5, (m[1][0] - m[0][1]) * 0.5]
}

/// Lee et al.'s geometric controller ([module docs](self)), of one flight
/// (`R = f64`) or of lanes of flights ([`crate::lanes`]) with the same
/// gains and nominal model. The law has no internal state: only the
/// telemetry and the heading's sine and cosine are per lane.
#[derive(Clone, Debug)]
pub struct Se3Controller<R: Real = f64> {
    model: QuadrotorParams,
    gains: Se3Gains,
    telemetry: Telemetry<R>,
    /// `cos`, `sin` of [`Se3Gains::max_tilt`], taken once.
    tilt_limit: TiltLimit,
    /// `sin`, `cos` of the last reference heading ψ_d.
    yaw_sin_cos: HeadingSinCos<R>,
}

impl Se3Controller {
    /// Build after checking the nominal model ([`QuadrotorParams::check`])
    /// and the gains ([`Se3Gains::check`]): one flight
    /// ([`Se3Controller::splat`] for `f64`).
    pub fn new(model: QuadrotorParams, gains: Se3Gains) -> Result<Self, GainError> {
        Self::splat(model, gains)
    }
}

impl<R: Real> Se3Controller<R> {
    /// Build for the number type `R` (every lane the same gains and nominal
    /// model) after checking the nominal model ([`QuadrotorParams::check`])
    /// and the gains ([`Se3Gains::check`]).
    pub fn splat(model: QuadrotorParams, gains: Se3Gains) -> Result<Self, GainError> {
        model.check()?;
        gains.check()?;
        Ok(Self {
            model,
            gains,
            telemetry: Telemetry::default(),
            tilt_limit: TiltLimit::new(gains.max_tilt),
            yaw_sin_cos: HeadingSinCos::new(),
        })
    }

    /// The gains in use.
    pub fn gains(&self) -> &Se3Gains {
        &self.gains
    }

    /// Desired rotation from the desired force direction and heading ψ_d;
    /// the second value is true (per lane) when the tilt limit changed `b₃d`.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn desired_rotation(&mut self, force: &Vec3<R>, yaw: R) -> (Mat3<R>, R::Mask) {
        let zero = R::splat(0.0);
        let f = norm(force);
        let b3 = branch(
            f.gt(R::splat(1e-9)),
            #[cfg_attr(not(debug_assertions), inline(always))]
            || [force[0] / f, force[1] / f, force[2] / f],
            #[cfg_attr(not(debug_assertions), inline(always))]
            || [zero, zero, R::splat(1.0)],
        );
        let limited = self.tilt_limit.apply(b3);
        let tilt_limited = !(limited[0].eq(b3[0]) & limited[1].eq(b3[1]) & limited[2].eq(b3[2]));
        let b3 = limited;
        let (s, c) = self.yaw_sin_cos.get(yaw);
        let b1c = [c, s, zero];
        let b2 = cross(&b3, &b1c);
        let n2 = norm(&b2);
        // b₃d along b₁c (only with max_tilt = π/2): the heading is undefined;
        // take b₂d horizontal, perpendicular to b₁c.
        let b2 = branch(
            n2.gt(R::splat(1e-9)),
            #[cfg_attr(not(debug_assertions), inline(always))]
            || [b2[0] / n2, b2[1] / n2, b2[2] / n2],
            #[cfg_attr(not(debug_assertions), inline(always))]
            || [-s, c, zero],
        );
        let b1 = cross(&b2, &b3);
        let r_d = [[b1[0], b2[0], b3[0]], [b1[1], b2[1], b3[1]], [b1[2], b2[2], b3[2]]];
        (r_d, tilt_limited)
    }

    /// [`Controller::update`] / [`Controller::update_measured`]: a
    /// non-finite `dt` gives a NaN command everywhere; a lane whose state,
    /// attitude or reference is not finite gets a NaN command and keeps its
    /// telemetry, as a one-flight controller returns early; the other lanes
    /// fly [`Self::law`].
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn update_with(
        &mut self,
        state: &QuadState<R>,
        attitude: Option<&BodyAttitude<R>>,
        reference: &Reference<R>,
        dt: f64,
    ) -> Command<R> {
        let Some(ok) = finite_lanes(dt, state, attitude, reference) else {
            return nan_command();
        };
        if ok.all() {
            return self.law(state, attitude, reference);
        }
        let saved = self.telemetry;
        let command = self.law(state, attitude, reference);
        self.telemetry = Blend::blend(ok, self.telemetry, saved);
        Command::blend(ok, command, nan_command())
    }

    /// The law of the [module docs](self) on finite inputs: `R` and `Ω`
    /// from `attitude` when given, else from the Euler state
    /// (`R = R_z R_y R_x`, `Ω = W η̇`).
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn law(
        &mut self,
        state: &QuadState<R>,
        attitude: Option<&BodyAttitude<R>>,
        reference: &Reference<R>,
    ) -> Command<R> {
        let m = self.model.mass;
        let g = self.model.gravity;
        let j = self.model.inertia;
        let k = self.gains;
        let zero = R::splat(0.0);
        let limit = R::splat(INPUT_LIMIT);

        let (r, omega) = match attitude {
            Some(b) => (rotation_from_quaternion(&b.quaternion), b.body_rates),
            None => (
                rotation_from_euler(&state.attitude),
                body_rates_from_euler_rates(&state.attitude, &state.angular_rate),
            ),
        };
        let omega = omega.map(|w| saturate(w, limit));

        // Translational loop: desired force.
        let mut force = [zero; 3];
        for i in 0..3 {
            let e_x = saturate(state.position[i] - reference.position[i], limit);
            let e_v = saturate(state.velocity[i] - reference.velocity[i], limit);
            let a_d = saturate(reference.acceleration[i], limit);
            // `−k_x e_x − k_v e_v + m a_d`, each product with its operands
            // swapped (same bits; `−k` is exact).
            force[i] = e_x * -k.position[i] - e_v * k.velocity[i] + a_d * m;
        }
        force[2] = force[2] + m * g;
        let (r_d, tilt_limited) = self.desired_rotation(&force, reference.yaw);

        // Attitude loop.
        let e_r = attitude_error(&r, &r_d);
        let rt_rd = mat_t_mat(&r, &r_d);
        let yaw_rate = saturate(reference.yaw_rate, limit);
        let yaw_accel = saturate(reference.yaw_acceleration, limit);
        let omega_d = mat_t_vec(&r_d, &[zero, zero, yaw_rate]);
        let omega_d_dot = mat_t_vec(&r_d, &[zero, zero, yaw_accel]);
        let omega_d_body = mat_vec(&rt_rd, &omega_d);
        let omega_d_dot_body = mat_vec(&rt_rd, &omega_d_dot);
        let j_omega = [omega[0] * j[0], omega[1] * j[1], omega[2] * j[2]];
        let gyro = cross(&omega, &j_omega);
        let hat = cross(&omega, &omega_d_body);
        let mut torque = [zero; 3];
        for i in 0..3 {
            let e_w = omega[i] - omega_d_body[i];
            torque[i] =
                e_r[i] * -k.attitude[i] - e_w * k.angular_rate[i] + gyro[i] - (hat[i] - omega_d_dot_body[i]) * j[i];
        }
        let lee_thrust = dot(&force, &[r[0][2], r[1][2], r[2][2]]);
        let min_thrust = R::splat(k.min_thrust);
        let max_thrust = R::splat(k.max_thrust);
        let thrust = R::select(
            lee_thrust.lt(min_thrust),
            min_thrust,
            R::select(lee_thrust.gt(max_thrust), max_thrust, lee_thrust),
        );

        let desired = euler_from_rotation(&r_d);
        self.telemetry = Telemetry {
            attitude_reference: desired,
            attitude_reference_rate: [zero, zero, yaw_rate],
            attitude_reference_acceleration: [zero, zero, yaw_accel],
            attitude_demand: [desired[0], desired[1]],
            estimates: [[zero; MAX_ESTIMATES]; 6],
            commanded_acceleration: [force[0] / m, force[1] / m, force[2] / m - g],
            nominal_thrust: lee_thrust,
            thrust_limited: !thrust.eq(lee_thrust) | tilt_limited,
            sliding_mode: None,
        };
        Command { thrust, torque }
    }
}

impl<R: Real> Controller<R> for Se3Controller<R> {
    fn name(&self) -> &'static str {
        "se3"
    }

    /// One period of the law of the [module docs](self). A non-finite state,
    /// reference or `dt` gives a NaN command and leaves the telemetry as it
    /// was (per lane; the law has no internal state). Errors, rates and the
    /// reference acceleration are clamped to `±INPUT_LIMIT` (no-op in
    /// flight) so the command is finite for every finite input.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn update(&mut self, state: &QuadState<R>, reference: &Reference<R>, dt: f64) -> Command<R> {
        self.update_with(state, None, reference, dt)
    }

    /// As [`Controller::update`]; with [`Measurement::body`] `R` is the
    /// rotation of its quaternion and `Ω` its body rates (no Euler conversion).
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn update_measured(&mut self, measured: &Measurement<R>, reference: &Reference<R>, dt: f64) -> Command<R> {
        self.update_with(&measured.euler, measured.body.as_ref(), reference, dt)
    }

    fn uses_body_attitude(&self) -> bool {
        true
    }

    fn telemetry(&self) -> &Telemetry<R> {
        &self.telemetry
    }

    fn reset(&mut self) {
        self.telemetry = Telemetry::default();
    }

    /// Lane `lane`'s telemetry back to its initial value (the law has no
    /// other state).
    fn reset_lane(&mut self, lane: usize) {
        self.telemetry.put_lane(lane, Telemetry::default());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn controller() -> Se3Controller {
        Se3Controller::new(QuadrotorParams::default(), Se3Gains::default()).unwrap()
    }

    use crate::lanes::{Lanes, Lanewise};
    use crate::setpoint::lane_tests::{dt_at, flight_inputs, telemetry_bits, Lcg};

    /// `N` flights on `Lanes<N>` against `N` one-flight controllers fed the
    /// same inputs ([`flight_inputs`]: lanes at the reference, beyond the
    /// tilt limit and the thrust cap, on the thrust floor, upside down;
    /// non-finite inputs in single lanes and in all; lanes reset mid-run):
    /// every command and telemetry value (the law's only state), lane by
    /// lane and bit for bit, at every step.
    fn lanes_fly_as_scalars<const N: usize>(with_body: bool) {
        let model = QuadrotorParams::default();
        let gains = Se3Gains::default();
        let mut lanes = Se3Controller::<Lanes<N>>::splat(model, gains).unwrap();
        let mut scalars: [Se3Controller; N] = core::array::from_fn(|_| Se3Controller::new(model, gains).unwrap());
        let mut rng = Lcg(0x5e3_0000 + 2 * N as u64 + u64::from(with_body));
        let (mut floored, mut capped, mut tilted) = (0, 0, 0);
        for step in 0..400 {
            if step == 150 {
                scalars[0].reset();
                lanes.reset_lane(0);
            }
            let dt = dt_at(step);
            let mut m = Measurement::<Lanes<N>>::default();
            let mut r = Reference::<Lanes<N>>::default();
            let mut want = [Command::default(); N];
            for (i, c) in scalars.iter_mut().enumerate() {
                let (mi, ri, _) = flight_inputs(&mut rng, i, step, with_body);
                m.put_lane(i, mi);
                r.put_lane(i, ri);
                want[i] = if step % 2 == 0 { c.update(&mi.euler, &ri, dt) } else { c.update_measured(&mi, &ri, dt) };
            }
            let got = if step % 2 == 0 { lanes.update(&m.euler, &r, dt) } else { lanes.update_measured(&m, &r, dt) };
            for (i, c) in scalars.iter().enumerate() {
                let g = got.get_lane(i);
                assert_eq!(g.thrust.to_bits(), want[i].thrust.to_bits(), "thrust, lane {i}, step {step}");
                for a in 0..3 {
                    assert_eq!(g.torque[a].to_bits(), want[i].torque[a].to_bits(), "torque {a}, lane {i}, step {step}");
                }
                let t = c.telemetry();
                assert_eq!(telemetry_bits(&lanes.telemetry().get_lane(i)), telemetry_bits(t), "lane {i}, step {step}");
                let finite = want[i].thrust.is_finite();
                floored += usize::from(finite && want[i].thrust == gains.min_thrust);
                capped += usize::from(finite && want[i].thrust == gains.max_thrust);
                tilted += usize::from(finite && t.thrust_limited && want[i].thrust != gains.max_thrust);
            }
        }
        // The branches the inputs were built for were taken.
        assert!(floored > 50 && capped > 50 && tilted > 50, "{floored} {capped} {tilted}");
    }

    #[test]
    fn four_lanes_fly_as_four_scalar_controllers() {
        lanes_fly_as_scalars::<4>(false);
        lanes_fly_as_scalars::<4>(true);
    }

    #[test]
    fn eight_lanes_fly_as_eight_scalar_controllers() {
        lanes_fly_as_scalars::<8>(false);
        lanes_fly_as_scalars::<8>(true);
    }

    #[test]
    fn hover_at_the_reference_gives_weight_and_zero_torque() {
        let p = QuadrotorParams::default();
        for yaw in [0.0, 0.5, -2.0] {
            let mut c = controller();
            let state = QuadState { position: [0.3, -1.0, 2.0], attitude: [0.0, 0.0, yaw], ..QuadState::default() };
            let reference = Reference { position: [0.3, -1.0, 2.0], yaw, ..Reference::default() };
            let cmd = c.update(&state, &reference, 1e-3);
            assert!((cmd.thrust - p.mass * p.gravity).abs() < 1e-12, "{}", cmd.thrust);
            assert!(cmd.torque.iter().all(|t| t.abs() < 1e-12), "{:?}", cmd.torque);
            let t = c.telemetry();
            assert!(t.commanded_acceleration.iter().all(|a| a.abs() < 1e-12));
            assert!((t.attitude_reference[2] - yaw).abs() < 1e-12);
        }
    }

    #[test]
    fn attitude_error_is_zero_at_the_desired_rotation_and_antisymmetric() {
        let a = rotation_from_euler(&[0.3, -0.2, 1.1]);
        let b = rotation_from_euler(&[-0.5, 0.4, -0.7]);
        assert!(attitude_error(&a, &a).iter().all(|e| e.abs() < 1e-15));
        // Antisymmetric in its arguments: e_R(R, R_d) = −e_R(R_d, R).
        let ab = attitude_error(&a, &b);
        let ba = attitude_error(&b, &a);
        assert!(ab.iter().any(|e| e.abs() > 0.1));
        for i in 0..3 {
            assert_eq!(ab[i], -ba[i]);
        }
        // A rotation by α about body x: e_R = (sin α, 0, 0).
        let alpha: f64 = 0.7;
        let r = rotation_from_euler(&[alpha, 0.0, 0.0]);
        let e = attitude_error(&r, &rotation_from_euler(&[0.0; 3]));
        assert!((e[0] - crate::math::sin(alpha)).abs() < 1e-15 && e[1].abs() < 1e-15 && e[2].abs() < 1e-15);
    }

    #[test]
    fn a_roll_error_gives_a_restoring_torque_and_the_tilt_limit_holds() {
        let mut c = controller();
        let state = QuadState { attitude: [0.2, 0.0, 0.0], ..QuadState::default() };
        let cmd = c.update(&state, &Reference::default(), 1e-3);
        assert!(cmd.torque[0] < 0.0 && cmd.torque[1].abs() < 1e-12, "{:?}", cmd.torque);
        // A 100 m step asks for a far larger tilt than max_tilt.
        let reference = Reference { position: [100.0, -50.0, 0.0], ..Reference::default() };
        c.update(&QuadState::default(), &reference, 1e-3);
        let [phi, theta, _] = c.telemetry().attitude_reference;
        let tilt = crate::math::acos(crate::math::cos(phi) * crate::math::cos(theta));
        assert!((tilt - Se3Gains::default().max_tilt).abs() < 1e-9, "{tilt}");
        assert!(c.telemetry().thrust_limited);
    }

    #[test]
    fn upside_down_the_thrust_is_floored_and_the_torque_turns_back() {
        let mut c = controller();
        let state = QuadState { position: [0.0, 0.0, 5.0], attitude: [3.0, 0.0, 0.0], ..QuadState::default() };
        let reference = Reference { position: [0.0, 0.0, 5.0], ..Reference::default() };
        let cmd = c.update(&state, &reference, 1e-3);
        assert_eq!(cmd.thrust, Se3Gains::default().min_thrust);
        assert!(c.telemetry().nominal_thrust < 0.0);
        assert!(cmd.torque[0] < 0.0, "{:?}", cmd.torque);
    }

    #[test]
    fn default_gains_follow_the_documented_procedure() {
        // RotorPy's Hummingbird gains per unit mass and inertia, carried to
        // the paper's quadrotor: the same loops on every vehicle.
        let g = Se3Gains::default();
        let p = QuadrotorParams::default();
        for i in 0..3 {
            let wr = (g.attitude[i] / p.inertia[i]).sqrt();
            assert!((wr - 544f64.sqrt()).abs() < 1e-12, "{wr}");
            let zeta = g.angular_rate[i] / (2.0 * p.inertia[i] * wr);
            assert!((zeta - 1.0).abs() < 0.001, "{zeta}");
        }
        let close = |a: [f64; 3], b: [f64; 3]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12);
        assert!(close(g.position.map(|k| k / p.mass), [6.5, 6.5, 15.0]), "{:?}", g.position);
        assert!(close(g.velocity.map(|k| k / p.mass), [4.0, 4.0, 9.0]), "{:?}", g.velocity);
        // Horizontal ω_n 2.55 rad/s, ζ 0.78; vertical 3.87 rad/s, ζ 1.16.
        let wx = (g.position[0] / p.mass).sqrt();
        assert!((wx - 2.55).abs() < 0.01 && (g.velocity[0] / p.mass / (2.0 * wx) - 0.78).abs() < 0.01);
        g.check().unwrap();
    }

    #[test]
    fn bad_gains_are_refused_naming_the_field() {
        let bad = [
            (Se3Gains { position: [1.0, -1.0, 1.0], ..Se3Gains::default() }, "position[1]"),
            (Se3Gains { velocity: [f64::NAN, 1.0, 1.0], ..Se3Gains::default() }, "velocity[0]"),
            (Se3Gains { attitude: [1.0, 1.0, 0.0], ..Se3Gains::default() }, "attitude[2]"),
            (Se3Gains { angular_rate: [1.0, 1e7, 1.0], ..Se3Gains::default() }, "angular_rate[1]"),
            (Se3Gains { max_tilt: 2.0, ..Se3Gains::default() }, "max_demanded_tilt"),
            (Se3Gains { max_tilt: 0.0, ..Se3Gains::default() }, "max_demanded_tilt"),
            (Se3Gains { min_thrust: -1.0, ..Se3Gains::default() }, "min_thrust"),
            (Se3Gains { max_thrust: 1.0, ..Se3Gains::default() }, "max_thrust"),
        ];
        for (gains, field) in bad {
            let err = Se3Controller::new(QuadrotorParams::default(), gains).unwrap_err();
            assert_eq!(err.field, field);
        }
    }

    #[test]
    fn a_non_finite_input_gives_a_nan_command_and_keeps_the_telemetry() {
        let mut c = controller();
        let reference = Reference { position: [1.0, 0.0, 1.0], ..Reference::default() };
        c.update(&QuadState::default(), &reference, 1e-3);
        let before = *c.telemetry();
        let bad = QuadState { angular_rate: [0.0, f64::INFINITY, 0.0], ..QuadState::default() };
        let cmd = c.update(&bad, &reference, 1e-3);
        assert!(cmd.thrust.is_nan() && cmd.torque.iter().all(|t| t.is_nan()));
        assert_eq!(*c.telemetry(), before);
        let cmd = c.update(&QuadState::default(), &Reference { yaw: f64::NAN, ..reference }, 1e-3);
        assert!(cmd.thrust.is_nan());
        c.reset();
        assert_eq!(c.telemetry().sliding_mode, None);
        assert!(!c.adapts_mass());
    }
}
