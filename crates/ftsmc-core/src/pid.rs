//! The PX4 multicopter cascade (`mc_pos_control` `PositionControl.cpp`,
//! `mc_att_control` `AttitudeControl.cpp`, `rate_control.cpp`), in SI units
//! and the z-up world frame of paper Eq. 1. All loops run at the control
//! rate (PX4 runs position at the estimator rate, ~50–100 Hz, and rates at
//! the gyro rate).
//!
//! 1. **Position (P)**: `v_sp = K_p,x ⊙ (x_d − x) + v_d`; the horizontal part
//!    limited to `max_velocity_xy` keeping the position part first (PX4
//!    `constrainXY`), the vertical one to `[−max_velocity_down, max_velocity_up]`.
//! 2. **Velocity (PID → acceleration)**: `e_v = v_sp − v`,
//!    `a_sp = ẍ_d + K_p,v ⊙ e_v + I_v − K_d,v ⊙ v̇`, `v̇` the measured
//!    velocity differenced and low-passed at `velocity_derivative_cutoff` (PX4
//!    `MPC_VELD_LP`); `İ_v = K_i,v ⊙ e_v'` with the anti-windup of 5 below.
//! 3. **Acceleration → thrust vector** (PX4 `_accelerationControl`): thrust
//!    direction `b₃ = (a_x, a_y, g)/‖·‖` tilted at most `max_tilt` towards the
//!    vertical; collective thrust `T = H (a_z + g)/(g b₃·e₃)` (`H` = hover
//!    thrust, N), at least `thrust_min`; thrust vector `T b₃`.
//! 4. **Thrust priority** (PX4 `_velocityControl`): the vertical component is
//!    kept first, up to `sqrt(T_max² − min(‖T_xy‖, margin)²)`; the horizontal
//!    one is scaled to what is left, `sqrt(T_max² − T_z²)`.
//! 5. **Anti-windup**: vertical — `e_v,z` is not integrated while `T_z` sits
//!    at `thrust_min` (error down) or `thrust_max` (error up); horizontal —
//!    tracking anti-windup (Rundqwist 1990, PX4's choice),
//!    `e_v,xy' = e_v,xy − (2/K_p,v,x)(a_sp,xy − a_lim,xy)`, `a_lim` the
//!    acceleration the limited thrust produces, `T_xy g/H`, when it is smaller;
//!    `|I_v,z| <= g`. [`PidGains::anti_windup`] = false switches both off
//!    (PX4 cannot; used to show what they prevent).
//! 6. **Thrust → attitude** (PX4 `thrustToAttitude`/`bodyzToAttitude`):
//!    `R_d = [b₁ b₂ b₃]`, `b₁ = (y_C × b₃)/‖·‖`, `y_C = (−sin ψ_d, cos ψ_d, 0)`,
//!    `b₂ = b₃ × b₁`; commanded thrust `‖T‖` (N).
//! 7. **Attitude (quaternion P, tilt before yaw)** (PX4 `AttitudeControl`):
//!    the reduced desired attitude `q_red` turns the body z axis onto `b₃` by
//!    the shortest arc; the remaining yaw rotation `q_red⁻¹ q_d` is scaled by
//!    `yaw_weight`; `q_e = q⁻¹ q_d'`, `ω_sp = 2 vec(q_e) ⊙ K_att'` with
//!    `K_att' = (K_φ, K_θ, K_ψ / yaw_weight)` (so the small-error yaw gain
//!    is `K_ψ`), plus the yaw-rate feed-forward `Rᵀe₃ ψ̇_d`, each component
//!    limited to `max_rate`. (PX4's newer reference model, `MC_REF_*`, is
//!    not implemented.)
//! 8. **Rates (PID → torque)** (PX4 `RateControl::update`):
//!    `τ = K_p,ω ⊙ e_ω + I_ω − K_d,ω ⊙ Ω̇ + K_ff ⊙ ω_sp`, `e_ω = ω_sp − Ω`,
//!    `Ω̇` differenced and low-passed at `rate_derivative_cutoff`;
//!    `İ_ω = f(e_ω) K_i,ω e_ω`, `f(e) = max(0, 1 − (e/400°/s)²)`,
//!    `|I_ω| <= rate_integral_limit`. While the simulator reports actuator
//!    saturation ([`Controller::actuator_feedback`]), an axis whose last
//!    torque was positive (negative) only integrates negative (positive)
//!    errors: PX4's per-axis saturation flags, with the direction taken from
//!    the sign of the torque because the report is one flag.
//!
//! # Gains: PX4 defaults rescaled to this vehicle
//!
//! [`PidGains::for_vehicle_with_max_thrust`] keeps PX4's position, velocity
//! and attitude gains unchanged (they are in SI units: 1/s, 1/s², m/s² per
//! m/s²) and converts the normalised ones as PX4's control allocation
//! (`ControlAllocationPseudoInverse`, the default for multicopters) would
//! on this vehicle:
//!
//! * **Thrust.** PX4's thrust setpoint is normalised to the vehicle's
//!   maximum collective thrust `T_max`: `4 b ω_max²` when the rotors are
//!   limited (24.0 N on the AscTec Hummingbird), and `m g / MPC_THR_HOVER`
//!   = 2 m g (PX4's default hover thrust 0.5) when they are not (the paper
//!   plant). The hover thrust is `m g` (what PX4's hover-thrust estimator
//!   converges to), `thrust_min = 0.12 T_max` (`MPC_THR_MIN`; at most
//!   `m g / 2`, so a vehicle with thrust-to-weight above 4 can still
//!   descend), margin
//!   `0.3 T_max` (`MPC_THR_XY_MARG`), `thrust_max = T_max` (`MPC_THR_MAX`
//!   1.0): with PX4's mixer (`[actuators] mixer = "px4"`) the allocator
//!   lowers the collective thrust to keep roll/pitch, so the controller
//!   needs no private thrust cap.
//! * **Torque.** PX4 normalises the pseudo-inverse of the effectiveness
//!   matrix so that the roll (pitch) column has squared norm
//!   `n/2`, `n` the number of rotors that roll (pitch) the vehicle, and the
//!   yaw column has largest entry 1 (`updateControlAllocationMatrixScale`),
//!   rotor thrusts in units of one rotor's maximum `T_max/4`. For the "+"
//!   allocation of Eq. 2 two rotors roll the vehicle, each by
//!   `±1/√2 · T_max/4` for a normalised roll torque of 1: roll/pitch
//!   `τ_max = √2 l T_max/4` (1.44 N·m on the Hummingbird); every rotor
//!   yaws by `±T_max/4`: `τ_max = (d/b) T_max`. `MC_*RATE_P/I/D` and
//!   `MC_*R_INT_LIM` are multiplied by these. (An earlier ftsmc took
//!   `l T_max/4` with `T_max = 2 m g`: 2.42× softer on the Hummingbird.)
//!   On any other layout the same normalisation is worked out from the
//!   layout's effectiveness ([`crate::rotor_layout::RotorGeometry::px4_torque_scale`]):
//!   a square "×" has four rotors rolling the vehicle, `τ_max = l T_max/2`
//!   (√2 times the "+" of the same arm); a stretched or irregular layout
//!   has its own ([`PidGains::for_vehicle_on`]).
//! * **Attitude.** `MC_ROLL_P = MC_PITCH_P = 4.0`, `MC_YAW_P = 2.8`: the
//!   values of PX4's current `mc_att_control_params.c` (older releases
//!   shipped 6.5). PX4's rate loop has no reference model by default, so
//!   nothing else shapes the attitude response. On the Hummingbird the
//!   small-error roll loop is `s² + K_p τ_max/J s + K_p τ_max/J · 4`
//!   = `s² + 30.9 s + 124` (ω_n 11.1 rad/s, ζ 1.39).
//!
//! [`PidGains::for_vehicle`] is the same with unlimited rotors.
//!
//! # State conversion, and what is approximated on the paper plant
//!
//! As for [`crate::se3`]: the attitude quaternion is built from the Euler
//! angles and the body rates `Ω = W(φ, θ) η̇` exactly; on the rigid-body
//! truth model these are the true attitude and body rates. On the paper
//! plant (Eq. 1) the torques drive the Euler-angle accelerations instead of
//! `Ω̇`, so the rate loop acts on `η̈` with a gain matrix that equals the
//! intended one only to first order about hover (`W ≈ I`). The PID law
//! has no model terms to cancel, so nothing else differs.

use crate::controller::{Controller, Telemetry};
use crate::kinematics::{
    body_rates_from_euler_rates, roll_pitch_from_rotation, rotation_from_euler, rotation_from_quaternion,
};
use crate::lanes::{branch, Blend, Lanewise, Mask, Real};
use crate::law::{
    check_gain, check_gain_or_zero, check_left_open, check_open, saturate, GainError, INPUT_LIMIT, MAX_ESTIMATES,
    STATE_LIMIT,
};
use crate::math::{cross, dot, exp, mat_t_vec, norm, Mat3, Vec3};
use crate::measured::{BodyAttitude, Measurement};
use crate::model::{Command, QuadState, QuadrotorParams, Reference};
use crate::rotor_layout::RotorGeometry;
use crate::setpoint::{finite_lanes, nan_command, HeadingSinCos, TiltLimit};

/// PX4 `MPC_THR_HOVER` default: hover at half the maximum thrust (T/W = 2).
pub const PX4_HOVER_THRUST: f64 = 0.5;

/// Gains and limits of [`PidController`], in SI units. `Default` is
/// [`PidGains::for_vehicle`] of the paper's quadrotor. The PX4 parameter
/// each field comes from is named in its doc.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Deserialize, serde::Serialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields, default))]
pub struct PidGains {
    /// Position P per world axis, 1/s (`MPC_XY_P` 0.95, `MPC_Z_P` 1.0).
    pub position_p: [f64; 3],
    /// Velocity P, 1/s = m/s² per m/s (`MPC_XY_VEL_P_ACC` 1.8, `MPC_Z_VEL_P_ACC` 4.0).
    pub velocity_p: [f64; 3],
    /// Velocity I, 1/s² (`MPC_XY_VEL_I_ACC` 0.4, `MPC_Z_VEL_I_ACC` 2.0).
    pub velocity_i: [f64; 3],
    /// Velocity D, m/s² per m/s² (`MPC_XY_VEL_D_ACC` 0.2, `MPC_Z_VEL_D_ACC` 0).
    pub velocity_d: [f64; 3],
    /// Cutoff of the velocity-derivative low-pass, Hz (`MPC_VELD_LP` 5).
    pub velocity_derivative_cutoff: f64,
    /// Horizontal velocity limit, m/s (`MPC_XY_VEL_MAX` 12).
    pub max_velocity_xy: f64,
    /// Climb-rate limit, m/s (`MPC_Z_VEL_MAX_UP` 3).
    pub max_velocity_up: f64,
    /// Descent-rate limit, m/s (`MPC_Z_VEL_MAX_DN` 1.5).
    pub max_velocity_down: f64,
    /// Tilt limit of the thrust direction, rad (`MPC_TILTMAX_AIR` 45°).
    /// Scenario key `max_demanded_tilt` (a limit on the demand, not on the flown tilt).
    #[cfg_attr(feature = "serde", serde(rename = "max_demanded_tilt"))]
    pub max_tilt: f64,
    /// Hover thrust `H`, N (`MPC_THR_HOVER` × T_max = m g).
    pub hover_thrust: f64,
    /// Minimum collective thrust, N (`MPC_THR_MIN` 0.12 × T_max, at most m g / 2).
    pub thrust_min: f64,
    /// Maximum collective thrust, N (`MPC_THR_MAX` 1.0 × T_max). A lower
    /// value is a private thrust cap, useful only with a thrust-first mixer.
    pub thrust_max: f64,
    /// Horizontal thrust kept when the vertical one saturates, N (`MPC_THR_XY_MARG` 0.3 × T_max).
    pub thrust_xy_margin: f64,
    /// Attitude P per body axis, 1/s (`MC_ROLL_P` 4.0, `MC_PITCH_P` 4.0, `MC_YAW_P` 2.8).
    pub attitude_p: [f64; 3],
    /// Weight of yaw against tilt in the attitude error, in (0, 1] (`MC_YAW_WEIGHT` 0.4).
    pub yaw_weight: f64,
    /// Body-rate setpoint limits, rad/s (`MC_ROLLRATE_MAX`, `MC_PITCHRATE_MAX` 220°/s, `MC_YAWRATE_MAX` 200°/s).
    pub max_rate: [f64; 3],
    /// Rate P, N·m per rad/s (`MC_ROLLRATE_P` 0.15, `MC_YAWRATE_P` 0.2, × τ_max).
    pub rate_p: [f64; 3],
    /// Rate I, N·m per rad (`MC_ROLLRATE_I` 0.2, `MC_YAWRATE_I` 0.1, × τ_max).
    pub rate_i: [f64; 3],
    /// Rate D, N·m per rad/s² (`MC_ROLLRATE_D` 0.003, `MC_YAWRATE_D` 0, × τ_max).
    pub rate_d: [f64; 3],
    /// Rate feed-forward, N·m per rad/s (`MC_ROLLRATE_FF` 0).
    pub rate_ff: [f64; 3],
    /// Rate integrator limit, N·m (`MC_RR_INT_LIM`, `MC_PR_INT_LIM`, `MC_YR_INT_LIM` 0.3, × τ_max).
    pub rate_integral_limit: [f64; 3],
    /// Cutoff of the angular-acceleration low-pass of the D term, Hz (PX4 `IMU_DGYRO_CUTOFF` 30).
    pub rate_derivative_cutoff: f64,
    /// Velocity-loop anti-windup (step 5 of the module docs: vertical
    /// conditional integration and horizontal tracking). PX4 always applies
    /// it (default true); false integrates the raw velocity error, only to
    /// show what it prevents (`tests/practitioners.rs`).
    pub anti_windup: bool,
}

impl Default for PidGains {
    fn default() -> Self {
        Self::for_vehicle(&QuadrotorParams::default())
    }
}

impl PidGains {
    /// PX4's default gains rescaled to `params` with unlimited rotors
    /// ([`Self::for_vehicle_with_max_thrust`] with `None`).
    pub fn for_vehicle(params: &QuadrotorParams) -> Self {
        Self::for_vehicle_with_max_thrust(params, None)
    }

    /// PX4's default gains rescaled to `params` and the rotors' maximum
    /// collective thrust `max_thrust` (N; `None`: unlimited rotors, then
    /// `T_max = m g / MPC_THR_HOVER`) ([module docs](self), "Gains"):
    /// torque = normalised rate-loop output × [`Self::max_torques`].
    pub fn for_vehicle_with_max_thrust(params: &QuadrotorParams, max_thrust: Option<f64>) -> Self {
        Self::for_vehicle_on(params, max_thrust, &RotorGeometry::Plus { arm_length: params.arm_length })
    }

    /// [`Self::for_vehicle_with_max_thrust`] on the rotor layout `geometry`:
    /// the torque normalisation is PX4's for that layout
    /// ([`Self::max_torques_on`]).
    pub fn for_vehicle_on(params: &QuadrotorParams, max_thrust: Option<f64>, geometry: &RotorGeometry) -> Self {
        let deg = core::f64::consts::PI / 180.0;
        let weight = params.mass * params.gravity;
        let t_max = Self::normalisation_thrust(params, max_thrust);
        let [roll, pitch, yaw] = Self::max_torques_on(params, t_max, geometry);
        let scale = |normalised: [f64; 3]| [normalised[0] * roll, normalised[1] * pitch, normalised[2] * yaw];
        Self {
            position_p: [0.95, 0.95, 1.0],
            velocity_p: [1.8, 1.8, 4.0],
            velocity_i: [0.4, 0.4, 2.0],
            velocity_d: [0.2, 0.2, 0.0],
            velocity_derivative_cutoff: 5.0,
            max_velocity_xy: 12.0,
            max_velocity_up: 3.0,
            max_velocity_down: 1.5,
            max_tilt: 45.0 * deg,
            hover_thrust: weight,
            // MPC_THR_MIN, kept below half the hover thrust: on a vehicle
            // with thrust-to-weight above 4 (0.12 T_max > m g / 2) PX4's
            // fraction would leave no room to descend.
            thrust_min: (0.12 * t_max).min(0.5 * weight),
            thrust_max: t_max,
            thrust_xy_margin: 0.3 * t_max,
            attitude_p: [4.0, 4.0, 2.8],
            yaw_weight: 0.4,
            max_rate: [220.0 * deg, 220.0 * deg, 200.0 * deg],
            rate_p: scale([0.15, 0.15, 0.2]),
            rate_i: scale([0.2, 0.2, 0.1]),
            rate_d: scale([0.003, 0.003, 0.0]),
            rate_ff: [0.0; 3],
            rate_integral_limit: scale([0.3, 0.3, 0.3]),
            rate_derivative_cutoff: 30.0,
            anti_windup: true,
        }
    }

    /// The thrust PX4 normalises to, N: `max_thrust` when given (finite and
    /// above the weight), else `m g / MPC_THR_HOVER`.
    pub fn normalisation_thrust(params: &QuadrotorParams, max_thrust: Option<f64>) -> f64 {
        let weight = params.mass * params.gravity;
        max_thrust.filter(|t| t.is_finite() && *t > weight).unwrap_or(weight / PX4_HOVER_THRUST)
    }

    /// Torque, N·m, that a normalised rate-loop output of 1 stands for on
    /// each body axis with unlimited rotors (`T_max = m g / MPC_THR_HOVER`):
    /// [`Self::max_torques_for`].
    pub fn max_torques(params: &QuadrotorParams) -> [f64; 3] {
        Self::max_torques_for(params, params.mass * params.gravity / PX4_HOVER_THRUST)
    }

    /// Torque, N·m, that a normalised rate-loop output of 1 stands for with
    /// PX4's allocation normalisation on the "+" allocation of Eq. 2 and a
    /// maximum collective thrust `t_max` (N): `[√2 l T_max/4, √2 l T_max/4,
    /// (d/b) T_max]` ([module docs](self), "Gains").
    pub fn max_torques_for(params: &QuadrotorParams, t_max: f64) -> [f64; 3] {
        let tilt = core::f64::consts::SQRT_2 * params.arm_length * t_max / 4.0;
        [tilt, tilt, params.yaw_drag_coefficient / params.lift_coefficient * t_max]
    }

    /// Torque, N·m, that a normalised rate-loop output of 1 stands for with
    /// PX4's allocation normalisation on the layout `geometry`, each rotor
    /// giving `t_max / 4` at full thrust and yawing by `d/b` of its thrust
    /// ([`RotorGeometry::px4_torque_scale`]; on the "+" layout of arm
    /// `params.arm_length`, [`Self::max_torques_for`] bit for bit). A
    /// layout that cannot make every torque (singular) takes the "+"
    /// value, which [`RotorGeometry::px4_torque_scale`]'s callers refuse
    /// before it comes to that.
    pub fn max_torques_on(params: &QuadrotorParams, t_max: f64, geometry: &RotorGeometry) -> [f64; 3] {
        let ratio = params.yaw_drag_coefficient / params.lift_coefficient;
        geometry.px4_torque_scale(t_max / 4.0, ratio).unwrap_or_else(|| Self::max_torques_for(params, t_max))
    }

    /// Range checks (the error names the field and value): P gains, limits,
    /// cutoffs and rates in `(0, 1e6]`; I, D, feed-forward gains, the
    /// margin and the integrator limits in `[0, 1e6]`; `0 < max_tilt < π/2`;
    /// `0 < yaw_weight <= 1`; `0 <= thrust_min < hover_thrust < thrust_max`.
    pub fn check(&self) -> Result<(), GainError> {
        let triples: [(&[&'static str; 3], [f64; 3], bool); 10] = [
            (&["position_p[0]", "position_p[1]", "position_p[2]"], self.position_p, true),
            (&["velocity_p[0]", "velocity_p[1]", "velocity_p[2]"], self.velocity_p, true),
            (&["velocity_i[0]", "velocity_i[1]", "velocity_i[2]"], self.velocity_i, false),
            (&["velocity_d[0]", "velocity_d[1]", "velocity_d[2]"], self.velocity_d, false),
            (&["attitude_p[0]", "attitude_p[1]", "attitude_p[2]"], self.attitude_p, true),
            (&["max_rate[0]", "max_rate[1]", "max_rate[2]"], self.max_rate, true),
            (&["rate_p[0]", "rate_p[1]", "rate_p[2]"], self.rate_p, true),
            (&["rate_i[0]", "rate_i[1]", "rate_i[2]"], self.rate_i, false),
            (&["rate_d[0]", "rate_d[1]", "rate_d[2]"], self.rate_d, false),
            (&["rate_ff[0]", "rate_ff[1]", "rate_ff[2]"], self.rate_ff, false),
        ];
        for (names, values, positive) in triples {
            for (name, value) in names.iter().zip(values) {
                if positive {
                    check_gain(name, value)?;
                } else {
                    check_gain_or_zero(name, value)?;
                }
            }
        }
        for (name, value) in ["rate_integral_limit[0]", "rate_integral_limit[1]", "rate_integral_limit[2]"]
            .iter()
            .zip(self.rate_integral_limit)
        {
            check_gain_or_zero(name, value)?;
        }
        check_gain("velocity_derivative_cutoff", self.velocity_derivative_cutoff)?;
        check_gain("rate_derivative_cutoff", self.rate_derivative_cutoff)?;
        check_gain("max_velocity_xy", self.max_velocity_xy)?;
        check_gain("max_velocity_up", self.max_velocity_up)?;
        check_gain("max_velocity_down", self.max_velocity_down)?;
        check_open(
            "max_demanded_tilt",
            self.max_tilt,
            0.0,
            core::f64::consts::FRAC_PI_2,
            "0 < max_demanded_tilt < π/2 (rad)",
        )?;
        check_left_open("yaw_weight", self.yaw_weight, 0.0, 1.0, "0 < yaw_weight <= 1")?;
        check_gain("hover_thrust", self.hover_thrust)?;
        check_gain("thrust_max", self.thrust_max)?;
        check_gain_or_zero("thrust_xy_margin", self.thrust_xy_margin)?;
        if !(self.thrust_min >= 0.0 && self.thrust_min < self.hover_thrust) {
            return Err(GainError {
                field: "thrust_min",
                value: self.thrust_min,
                expected: "0 <= thrust_min < hover_thrust (N)",
            });
        }
        if self.thrust_max <= self.hover_thrust {
            return Err(GainError {
                field: "thrust_max",
                value: self.thrust_max,
                expected: "hover_thrust < thrust_max <= 1e6 (N)",
            });
        }
        Ok(())
    }
}

/// Unit quaternion `[w, x, y, z]` (Hamilton, body-to-world).
type Quat<R = f64> = [R; 4];

/// Hamilton product `a ⊗ b`.
#[cfg_attr(not(debug_assertions), inline(always))]
fn quat_mul<R: Real>(a: &Quat<R>, b: &Quat<R>) -> Quat<R> {
    [
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    ]
}

/// Conjugate `q*` (the inverse of a unit quaternion).
#[cfg_attr(not(debug_assertions), inline(always))]
fn quat_conj<R: Real>(q: &Quat<R>) -> Quat<R> {
    [q[0], -q[1], -q[2], -q[3]]
}

/// `q / ‖q‖`; the identity where `‖q‖` is 0 (or NaN).
#[cfg_attr(not(debug_assertions), inline(always))]
fn quat_normalise<R: Real>(q: Quat<R>) -> Quat<R> {
    let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    branch(
        n.gt(R::splat(0.0)),
        #[cfg_attr(not(debug_assertions), inline(always))]
        || [q[0] / n, q[1] / n, q[2] / n, q[3] / n],
        #[cfg_attr(not(debug_assertions), inline(always))]
        || unit_quat(),
    )
}

/// The identity rotation `[1, 0, 0, 0]`.
#[cfg_attr(not(debug_assertions), inline(always))]
fn unit_quat<R: Real>() -> Quat<R> {
    let zero = R::splat(0.0);
    [R::splat(1.0), zero, zero, zero]
}

/// `q` or `−q`, whichever has `w >= 0` (the shorter rotation).
#[cfg_attr(not(debug_assertions), inline(always))]
fn canonical<R: Real>(q: Quat<R>) -> Quat<R> {
    branch(
        q[0].lt(R::splat(0.0)),
        #[cfg_attr(not(debug_assertions), inline(always))]
        || [-q[0], -q[1], -q[2], -q[3]],
        #[cfg_attr(not(debug_assertions), inline(always))]
        || q,
    )
}

/// Quaternion of a rotation matrix (Shepperd's method: largest pivot).
#[cfg_attr(not(debug_assertions), inline(always))]
fn quat_from_rotation<R: Real>(r: &Mat3<R>) -> Quat<R> {
    let zero = R::splat(0.0);
    let one = R::splat(1.0);
    let trace = r[0][0] + r[1][1] + r[2][2];
    // `x · 2`, `s · 0.25`, `trace + 1`: the products `2 x`, `0.25 s` and the
    // sum `1 + trace` with their operands swapped (same bits).
    let q = branch(
        trace.gt(zero),
        #[cfg_attr(not(debug_assertions), inline(always))]
        || {
            let s = (trace + 1.0).sqrt() * 2.0;
            [s * 0.25, (r[2][1] - r[1][2]) / s, (r[0][2] - r[2][0]) / s, (r[1][0] - r[0][1]) / s]
        },
        #[cfg_attr(not(debug_assertions), inline(always))]
        || {
            branch(
                r[0][0].gt(r[1][1]) & r[0][0].gt(r[2][2]),
                #[cfg_attr(not(debug_assertions), inline(always))]
                || {
                    let s = (one + r[0][0] - r[1][1] - r[2][2]).max(zero).sqrt() * 2.0;
                    [(r[2][1] - r[1][2]) / s, s * 0.25, (r[0][1] + r[1][0]) / s, (r[0][2] + r[2][0]) / s]
                },
                #[cfg_attr(not(debug_assertions), inline(always))]
                || {
                    branch(
                        r[1][1].gt(r[2][2]),
                        #[cfg_attr(not(debug_assertions), inline(always))]
                        || {
                            let s = (one + r[1][1] - r[0][0] - r[2][2]).max(zero).sqrt() * 2.0;
                            [(r[0][2] - r[2][0]) / s, (r[0][1] + r[1][0]) / s, s * 0.25, (r[1][2] + r[2][1]) / s]
                        },
                        #[cfg_attr(not(debug_assertions), inline(always))]
                        || {
                            let s = (one + r[2][2] - r[0][0] - r[1][1]).max(zero).sqrt() * 2.0;
                            [(r[1][0] - r[0][1]) / s, (r[0][2] + r[2][0]) / s, (r[1][2] + r[2][1]) / s, s * 0.25]
                        },
                    )
                },
            )
        },
    );
    quat_normalise(q)
}

/// Shortest-arc rotation taking the unit vector `u` onto the unit vector
/// `v`; for opposite vectors, a half turn about an axis perpendicular to `u`.
#[cfg_attr(not(debug_assertions), inline(always))]
fn quat_between<R: Real>(u: &Vec3<R>, v: &Vec3<R>) -> Quat<R> {
    let zero = R::splat(0.0);
    let one = R::splat(1.0);
    let c = cross(u, v);
    let d = dot(u, v);
    branch(
        norm(&c).lt(R::splat(1e-9)) & d.lt(zero),
        #[cfg_attr(not(debug_assertions), inline(always))]
        || {
            // Half turn about the axis perpendicular to u with the smallest components.
            let axis = branch(
                u[0].abs().lt(R::splat(0.9)),
                #[cfg_attr(not(debug_assertions), inline(always))]
                || cross(u, &[one, zero, zero]),
                #[cfg_attr(not(debug_assertions), inline(always))]
                || cross(u, &[zero, one, zero]),
            );
            let n = norm(&axis);
            [zero, axis[0] / n, axis[1] / n, axis[2] / n]
        },
        // `d + 1`: the sum `1 + d` with its operands swapped (same bits).
        || quat_normalise([d + 1.0, c[0], c[1], c[2]]),
    )
}

/// PX4 `ControlMath::constrainXY`: `v0 + v1` limited to norm `max` (m/s),
/// keeping `v0` first (the position part before the feed-forward).
#[cfg_attr(not(debug_assertions), inline(always))]
fn constrain_xy<R: Real>(v0: [R; 2], v1: [R; 2], max: f64) -> [R; 2] {
    let sum = [v0[0] + v1[0], v0[1] + v1[1]];
    let n_sum = (sum[0] * sum[0] + sum[1] * sum[1]).sqrt();
    branch(
        n_sum.le(R::splat(max)),
        #[cfg_attr(not(debug_assertions), inline(always))]
        || sum,
        #[cfg_attr(not(debug_assertions), inline(always))]
        || {
            let n0 = (v0[0] * v0[0] + v0[1] * v0[1]).sqrt();
            branch(
                n0.ge(R::splat(max)),
                #[cfg_attr(not(debug_assertions), inline(always))]
                || [v0[0] / n0 * max, v0[1] / n0 * max],
                #[cfg_attr(not(debug_assertions), inline(always))]
                || {
                    // |v0 + s v1| = max, s in [0, 1): a s² + b s + c = 0.
                    let a = v1[0] * v1[0] + v1[1] * v1[1];
                    // `x · 2`, `a · 4`, `a · 2`: `2 x`, `4 a`, `2 a` with their operands swapped.
                    let b = (v0[0] * v1[0] + v0[1] * v1[1]) * 2.0;
                    let c = n0 * n0 - max * max;
                    let s = (-b + (b * b - a * 4.0 * c).max(R::splat(0.0)).sqrt()) / (a * 2.0);
                    [v0[0] + s * v1[0], v0[1] + s * v1[1]]
                },
            )
        },
    )
}

/// PX4's cascade ([module docs](self)), of one flight (`R = f64`) or of
/// lanes of flights ([`crate::lanes`]) with the same gains. The gains, the
/// nominal model and the filter weights are shared; integrators, filter
/// states, previous values, the `initialised` flag, the last torque and
/// the actuator-saturation report are per lane.
#[derive(Clone, Debug)]
pub struct PidController<R: Real = f64> {
    model: QuadrotorParams,
    gains: PidGains,
    velocity_integral: Vec3<R>,
    rate_integral: Vec3<R>,
    previous_velocity: Vec3<R>,
    previous_rates: Vec3<R>,
    velocity_derivative: Vec3<R>,
    rate_derivative: Vec3<R>,
    initialised: R::Mask,
    last_torque: Vec3<R>,
    actuator_saturated: R::Mask,
    telemetry: Telemetry<R>,
    /// The derivative filters' `α = 1 − e^{−2π f_c dt}` (velocity, rates)
    /// for the control period whose bits are `alpha_dt` (constant over a flight).
    alphas: [f64; 2],
    alpha_dt: u64,
    /// `cos`, `sin` of [`PidGains::max_tilt`], taken once.
    tilt_limit: TiltLimit,
    /// `sin`, `cos` of the last reference heading ψ_d.
    yaw_sin_cos: HeadingSinCos<R>,
}

/// Names of the [`Telemetry::estimates`] slots: slot 0 of x, y, z is the
/// velocity integrator (m/s²), of φ, θ, ψ the rate integrator (N·m).
pub const PID_ESTIMATE_NAMES: [&str; MAX_ESTIMATES] = ["integral", "", ""];

impl PidController {
    /// Build after checking the nominal model ([`QuadrotorParams::check`])
    /// and the gains ([`PidGains::check`]): one flight
    /// ([`PidController::splat`] for `f64`).
    pub fn new(model: QuadrotorParams, gains: PidGains) -> Result<Self, GainError> {
        Self::splat(model, gains)
    }
}

impl<R: Real> PidController<R> {
    /// Build for the number type `R` (every lane the same gains and nominal
    /// model, every lane's states initial) after checking the nominal model
    /// ([`QuadrotorParams::check`]) and the gains ([`PidGains::check`]).
    pub fn splat(model: QuadrotorParams, gains: PidGains) -> Result<Self, GainError> {
        model.check()?;
        gains.check()?;
        Ok(Self::initial(model, gains))
    }

    /// Every lane at its initial states, for checked `model` and `gains`.
    fn initial(model: QuadrotorParams, gains: PidGains) -> Self {
        let zero = [R::splat(0.0); 3];
        Self {
            model,
            gains,
            velocity_integral: zero,
            rate_integral: zero,
            previous_velocity: zero,
            previous_rates: zero,
            velocity_derivative: zero,
            rate_derivative: zero,
            initialised: R::Mask::splat(false),
            last_torque: zero,
            actuator_saturated: R::Mask::splat(false),
            telemetry: Telemetry::default(),
            alphas: [0.0; 2],
            alpha_dt: f64::NAN.to_bits(),
            tilt_limit: TiltLimit::new(gains.max_tilt),
            yaw_sin_cos: HeadingSinCos::new(),
        }
    }

    /// The gains in use.
    pub fn gains(&self) -> &PidGains {
        &self.gains
    }

    /// Velocity integrator `I_v`, m/s².
    pub fn velocity_integral(&self) -> Vec3<R> {
        self.velocity_integral
    }

    /// Rate integrator `I_ω`, N·m.
    pub fn rate_integral(&self) -> Vec3<R> {
        self.rate_integral
    }

    /// The low-pass weights `α = 1 − e^{−2π f_c dt}` of the velocity and
    /// rate derivative filters for a period `dt` (s), computed when `dt` changes.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn derivative_alphas(&mut self, dt: f64) -> [f64; 2] {
        if self.alpha_dt != dt.to_bits() {
            let alpha = |hz: f64| 1.0 - exp(-2.0 * core::f64::consts::PI * hz * dt);
            self.alphas = [alpha(self.gains.velocity_derivative_cutoff), alpha(self.gains.rate_derivative_cutoff)];
            self.alpha_dt = dt.to_bits();
        }
        self.alphas
    }

    /// First-order low-pass (weight `alpha`, [`Self::derivative_alphas`]) of
    /// a finite difference over `dt`; `previous` is updated to `value`.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn filtered_derivative(value: &Vec3<R>, previous: &mut Vec3<R>, filtered: &mut Vec3<R>, alpha: f64, dt: f64) {
        if dt > 0.0 {
            let limit = R::splat(INPUT_LIMIT);
            for i in 0..3 {
                let raw = saturate((value[i] - previous[i]) / dt, limit);
                // `(raw − y) · α`: the product `α (raw − y)` with its operands swapped.
                filtered[i] = saturate(filtered[i] + (raw - filtered[i]) * alpha, limit);
            }
        }
        *previous = *value;
    }

    /// Body-rate setpoint of the quaternion P law (step 7), rad/s.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn rate_setpoint(&self, r: &Mat3<R>, q: &Quat<R>, r_d: &Mat3<R>, yaw_rate: R) -> Vec3<R> {
        let k = &self.gains;
        let zero = R::splat(0.0);
        let q_d = quat_from_rotation(r_d);
        let e_z = [r[0][2], r[1][2], r[2][2]];
        let e_z_d = [r_d[0][2], r_d[1][2], r_d[2][2]];
        let tilt = quat_between(&e_z, &e_z_d);
        let reversed = R::splat(1.0 - 1e-5);
        let q_red = branch(
            tilt[1].abs().gt(reversed) | tilt[2].abs().gt(reversed),
            // Thrust axis exactly reversed: full attitude control (PX4's corner case).
            || q_d,
            #[cfg_attr(not(debug_assertions), inline(always))]
            || quat_mul(&tilt, q),
        );
        let mut dyaw = canonical(quat_mul(&quat_conj(&q_red), &q_d));
        dyaw[0] = saturate(dyaw[0], R::splat(1.0));
        dyaw[3] = saturate(dyaw[3], R::splat(1.0));
        let w = k.yaw_weight;
        // `acos(·) · w`: the product `w acos(·)` with its operands swapped.
        let weighted = [(dyaw[0].acos() * w).cos(), zero, zero, (dyaw[3].asin() * w).sin()];
        let q_target = quat_mul(&q_red, &weighted);
        let q_e = canonical(quat_mul(&quat_conj(q), &q_target));
        // A subnormal yaw_weight would make K_ψ / w infinite (and 0 · ∞ = NaN).
        let gain = [k.attitude_p[0], k.attitude_p[1], saturate(k.attitude_p[2] / w, INPUT_LIMIT)];
        let feed_forward = mat_t_vec(r, &[zero, zero, yaw_rate]);
        let mut rate = [zero; 3];
        for i in 0..3 {
            // `q · 2`: the product `2 q` with its operands swapped.
            rate[i] = saturate(q_e[i + 1] * 2.0 * gain[i] + feed_forward[i], R::splat(k.max_rate[i]));
        }
        rate
    }

    /// [`Controller::update`] / [`Controller::update_measured`]: a
    /// non-finite `dt` gives a NaN command everywhere; a lane whose state,
    /// attitude or reference is not finite gets a NaN command and keeps
    /// every internal state (and its telemetry) as it was, as a one-flight
    /// controller returns early; the other lanes fly [`Self::law`].
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
            return self.law(state, attitude, reference, dt);
        }
        let saved = self.clone();
        let command = self.law(state, attitude, reference, dt);
        self.keep_lanes(!ok, &saved);
        Command::blend(ok, command, nan_command())
    }

    /// Restore the per-lane states of `saved` in the lanes of `keep`.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn keep_lanes(&mut self, keep: R::Mask, saved: &Self) {
        self.velocity_integral = Blend::blend(keep, saved.velocity_integral, self.velocity_integral);
        self.rate_integral = Blend::blend(keep, saved.rate_integral, self.rate_integral);
        self.previous_velocity = Blend::blend(keep, saved.previous_velocity, self.previous_velocity);
        self.previous_rates = Blend::blend(keep, saved.previous_rates, self.previous_rates);
        self.velocity_derivative = Blend::blend(keep, saved.velocity_derivative, self.velocity_derivative);
        self.rate_derivative = Blend::blend(keep, saved.rate_derivative, self.rate_derivative);
        self.initialised = Blend::blend(keep, saved.initialised, self.initialised);
        self.last_torque = Blend::blend(keep, saved.last_torque, self.last_torque);
        self.actuator_saturated = Blend::blend(keep, saved.actuator_saturated, self.actuator_saturated);
        self.telemetry = Blend::blend(keep, saved.telemetry, self.telemetry);
    }

    /// The cascade of the [module docs](self) on finite inputs: the
    /// rotation `R`, its quaternion and the body rates come from `attitude`
    /// when given, else from the Euler state (`R = R_z R_y R_x`, Shepperd's
    /// quaternion, `Ω = W η̇`).
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn law(
        &mut self,
        state: &QuadState<R>,
        attitude: Option<&BodyAttitude<R>>,
        reference: &Reference<R>,
        dt: f64,
    ) -> Command<R> {
        let k = self.gains;
        let g = self.model.gravity;
        let zero = R::splat(0.0);
        let limit = R::splat(INPUT_LIMIT);
        let dt = dt.max(0.0);
        let velocity = state.velocity.map(|v| saturate(v, limit));
        let (r, q, omega) = match attitude {
            Some(b) => (rotation_from_quaternion(&b.quaternion), b.quaternion, b.body_rates),
            None => {
                let r = rotation_from_euler(&state.attitude);
                (r, quat_from_rotation(&r), body_rates_from_euler_rates(&state.attitude, &state.angular_rate))
            }
        };
        let omega = omega.map(|w| saturate(w, limit));
        if !self.initialised.all() {
            let started = self.initialised;
            self.previous_velocity = Blend::blend(started, self.previous_velocity, velocity);
            self.previous_rates = Blend::blend(started, self.previous_rates, omega);
            self.initialised = R::Mask::splat(true);
        }
        let alphas = self.derivative_alphas(dt);
        Self::filtered_derivative(&velocity, &mut self.previous_velocity, &mut self.velocity_derivative, alphas[0], dt);
        Self::filtered_derivative(&omega, &mut self.previous_rates, &mut self.rate_derivative, alphas[1], dt);

        // 1. Position P → velocity setpoint.
        let mut from_position = [zero; 3];
        for (i, v) in from_position.iter_mut().enumerate() {
            // `e · K_p`: the product `K_p e` with its operands swapped.
            *v = saturate(reference.position[i] - state.position[i], limit) * k.position_p[i];
        }
        let ff = reference.velocity.map(|v| saturate(v, limit));
        let xy = constrain_xy([from_position[0], from_position[1]], [ff[0], ff[1]], k.max_velocity_xy);
        let vz = from_position[2] + ff[2];
        let up = R::splat(k.max_velocity_up);
        let down = R::splat(-k.max_velocity_down);
        let vz = R::select(vz.gt(up), up, R::select(vz.lt(down), down, vz));
        let velocity_setpoint = [xy[0], xy[1], vz];

        // 2. Velocity PID → acceleration setpoint.
        let mut error = [zero; 3];
        let mut accel = [zero; 3];
        for i in 0..3 {
            error[i] = velocity_setpoint[i] - velocity[i];
            accel[i] = saturate(
                saturate(reference.acceleration[i], limit) + error[i] * k.velocity_p[i] + self.velocity_integral[i]
                    - self.velocity_derivative[i] * k.velocity_d[i],
                limit,
            );
        }

        // 3. Acceleration → thrust vector (N).
        let unlimited = {
            let v = [accel[0], accel[1], R::splat(g)];
            let n = norm(&v);
            [v[0] / n, v[1] / n, v[2] / n]
        };
        let direction = self.tilt_limit.apply(unlimited);
        // `(a + g) · H`: the product `H (a + g)` with its operands swapped.
        let nominal_thrust = (accel[2] + g) * k.hover_thrust / g / direction[2];
        let thrust_min = R::splat(k.thrust_min);
        let thrust_max = R::splat(k.thrust_max);
        let floored = nominal_thrust.lt(thrust_min);
        let collective = R::select(floored, thrust_min, nominal_thrust);
        let mut thrust = direction.map(|d| d * collective);

        // 5a. Vertical anti-windup: stop integrating into a saturated thrust.
        if k.anti_windup {
            let held = (thrust[2].le(thrust_min) & error[2].le(zero)) | (thrust[2].ge(thrust_max) & error[2].ge(zero));
            error[2] = R::select(held, zero, error[2]);
        }

        // 4. Vertical priority with a horizontal margin.
        let horizontal = (thrust[0] * thrust[0] + thrust[1] * thrust[1]).sqrt();
        let max_sq = R::splat(k.thrust_max * k.thrust_max);
        let allocated = horizontal.min(R::splat(k.thrust_xy_margin));
        let z_max = (max_sq - allocated * allocated).max(zero).sqrt();
        let z_capped = thrust[2].gt(z_max);
        thrust[2] = R::select(z_capped, z_max, thrust[2]);
        let xy_max = (max_sq - thrust[2] * thrust[2]).max(zero).sqrt();
        let xy_capped = horizontal.gt(xy_max);
        [thrust[0], thrust[1]] = branch(
            xy_capped,
            #[cfg_attr(not(debug_assertions), inline(always))]
            || [thrust[0] * (xy_max / horizontal), thrust[1] * (xy_max / horizontal)],
            #[cfg_attr(not(debug_assertions), inline(always))]
            || [thrust[0], thrust[1]],
        );

        // 5b. Horizontal tracking anti-windup.
        let produced = [thrust[0] * g / k.hover_thrust, thrust[1] * g / k.hover_thrust];
        let demanded = [accel[0], accel[1]];
        let limited = Blend::blend(
            (demanded[0] * demanded[0] + demanded[1] * demanded[1])
                .gt(produced[0] * produced[0] + produced[1] * produced[1]),
            produced,
            demanded,
        );
        // Bounded: a subnormal velocity_p gives 2 / K_p = ∞ and ∞ · 0 = NaN.
        let arw = if k.anti_windup { saturate(2.0 / k.velocity_p[0], STATE_LIMIT) } else { 0.0 };
        for i in 0..2 {
            // `(d − l) · arw`: the product `arw (d − l)` with its operands swapped.
            error[i] -= (demanded[i] - limited[i]) * arw;
        }
        let state_limit = R::splat(STATE_LIMIT);
        for i in 0..3 {
            // `e · K_i`: the product `K_i e` with its operands swapped.
            self.velocity_integral[i] =
                saturate(self.velocity_integral[i] + error[i] * k.velocity_i[i] * dt, state_limit);
        }
        self.velocity_integral[2] = saturate(self.velocity_integral[2], R::splat(g));

        // 6. Thrust vector → desired attitude and collective thrust.
        let one = R::splat(1.0);
        let magnitude = norm(&thrust);
        let b3 = branch(
            magnitude.gt(zero),
            #[cfg_attr(not(debug_assertions), inline(always))]
            || thrust.map(|t| t / magnitude),
            #[cfg_attr(not(debug_assertions), inline(always))]
            || [zero, zero, one],
        );
        let (s, c) = self.yaw_sin_cos.get(reference.yaw);
        let b1 = cross(&[-s, c, zero], &b3);
        let n1 = norm(&b1);
        let b1 = branch(
            n1.gt(R::splat(1e-9)),
            #[cfg_attr(not(debug_assertions), inline(always))]
            || b1.map(|v| v / n1),
            #[cfg_attr(not(debug_assertions), inline(always))]
            || [one, zero, zero],
        );
        let b2 = cross(&b3, &b1);
        let r_d = [[b1[0], b2[0], b3[0]], [b1[1], b2[1], b3[1]], [b1[2], b2[2], b3[2]]];

        // 7. Attitude P → body-rate setpoint.
        let rate_setpoint = self.rate_setpoint(&r, &q, &r_d, saturate(reference.yaw_rate, limit));

        // 8. Rate PID → torques.
        let mut torque = [zero; 3];
        let max_error = 400.0 * core::f64::consts::PI / 180.0;
        let saturated = self.actuator_saturated;
        for i in 0..3 {
            let mut e = rate_setpoint[i] - omega[i];
            // Each product `K x` as `x · K` (operands swapped, same bits).
            torque[i] = e * k.rate_p[i] + self.rate_integral[i] - self.rate_derivative[i] * k.rate_d[i]
                + rate_setpoint[i] * k.rate_ff[i];
            if saturated.any() {
                let last = self.last_torque[i];
                let one_sided = R::select(last.gt(zero), e.min(zero), R::select(last.lt(zero), e.max(zero), e));
                e = R::select(saturated, one_sided, e);
            }
            let f = e / max_error;
            let factor = (one - f * f).max(zero);
            self.rate_integral[i] =
                saturate(self.rate_integral[i] + factor * k.rate_i[i] * e * dt, R::splat(k.rate_integral_limit[i]));
        }
        self.last_torque = torque;

        // Only the demanded roll and pitch are reported (the heading is ψ_d).
        let desired = roll_pitch_from_rotation(&r_d);
        let mut estimates = [[zero; MAX_ESTIMATES]; 6];
        for i in 0..3 {
            estimates[i][0] = self.velocity_integral[i];
            estimates[3 + i][0] = self.rate_integral[i];
        }
        let redirected =
            !(direction[0].eq(unlimited[0]) & direction[1].eq(unlimited[1]) & direction[2].eq(unlimited[2]));
        self.telemetry = Telemetry {
            attitude_reference: [desired[0], desired[1], reference.yaw],
            attitude_reference_rate: [zero, zero, reference.yaw_rate],
            attitude_reference_acceleration: [zero, zero, reference.yaw_acceleration],
            attitude_demand: [desired[0], desired[1]],
            estimates,
            commanded_acceleration: accel,
            nominal_thrust,
            thrust_limited: floored | z_capped | xy_capped | redirected,
            sliding_mode: None,
        };
        Command { thrust: magnitude, torque }
    }
}

impl<R: Real> Controller<R> for PidController<R> {
    fn name(&self) -> &'static str {
        "pid"
    }

    /// One period of the cascade of the [module docs](self). A non-finite
    /// state, reference or `dt` gives a NaN command and leaves every
    /// internal state unchanged (per lane: the other lanes fly on). Errors
    /// and rates are clamped to `±INPUT_LIMIT` and the integrators to
    /// `±STATE_LIMIT` (no-ops in flight).
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn update(&mut self, state: &QuadState<R>, reference: &Reference<R>, dt: f64) -> Command<R> {
        self.update_with(state, None, reference, dt)
    }

    /// As [`Controller::update`]; with [`Measurement::body`] the rotation is
    /// that of its quaternion and `Ω` its body rates (no Euler conversion).
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

    fn estimate_names(&self) -> [&'static str; MAX_ESTIMATES] {
        PID_ESTIMATE_NAMES
    }

    fn reset(&mut self) {
        // The filter weights of the last `dt` and the heading cache are
        // kept: they hold no flight state.
        *self = Self {
            alphas: self.alphas,
            alpha_dt: self.alpha_dt,
            yaw_sin_cos: self.yaw_sin_cos,
            ..Self::initial(self.model, self.gains)
        };
    }

    /// Lane `lane`'s integrators, filters, previous values, flags and
    /// telemetry back to their initial values (the other lanes untouched).
    fn reset_lane(&mut self, lane: usize) {
        for v in [
            &mut self.velocity_integral,
            &mut self.rate_integral,
            &mut self.previous_velocity,
            &mut self.previous_rates,
            &mut self.velocity_derivative,
            &mut self.rate_derivative,
            &mut self.last_torque,
        ] {
            v.put_lane(lane, [0.0; 3]);
        }
        self.initialised.put_lane(lane, false);
        self.actuator_saturated.put_lane(lane, false);
        self.telemetry.put_lane(lane, Telemetry::default());
    }

    fn actuator_feedback(&mut self, saturated: R::Mask) {
        self.actuator_saturated = saturated;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn controller() -> PidController {
        PidController::new(QuadrotorParams::default(), PidGains::default()).unwrap()
    }

    use crate::lanes::{LaneMask, Lanes, Lanewise};
    use crate::setpoint::lane_tests::{dt_at, flight_inputs, telemetry_bits, Lcg, TELEMETRY_VALUES};

    /// Number of per-lane state values [`state_bits`] returns.
    const STATE_VALUES: usize = 7 * 3 + 2;

    /// The bits of every per-lane state of a one-flight controller (the
    /// heading cache, whose value is always `sin_cos` of its key, aside).
    fn state_bits(c: &PidController) -> ([u64; STATE_VALUES], [u64; TELEMETRY_VALUES]) {
        let mut out = [0u64; STATE_VALUES];
        let vectors = [
            c.velocity_integral,
            c.rate_integral,
            c.previous_velocity,
            c.previous_rates,
            c.velocity_derivative,
            c.rate_derivative,
            c.last_torque,
        ];
        for (slot, v) in out.iter_mut().zip(vectors.iter().flatten()) {
            *slot = v.to_bits();
        }
        out[21] = u64::from(c.initialised);
        out[22] = u64::from(c.actuator_saturated);
        (out, telemetry_bits(&c.telemetry))
    }

    /// Lane `i` of a lanes controller as a one-flight controller.
    fn lane_of<const N: usize>(c: &PidController<Lanes<N>>, i: usize) -> PidController {
        PidController {
            model: c.model,
            gains: c.gains,
            velocity_integral: c.velocity_integral.get_lane(i),
            rate_integral: c.rate_integral.get_lane(i),
            previous_velocity: c.previous_velocity.get_lane(i),
            previous_rates: c.previous_rates.get_lane(i),
            velocity_derivative: c.velocity_derivative.get_lane(i),
            rate_derivative: c.rate_derivative.get_lane(i),
            initialised: c.initialised.get_lane(i),
            last_torque: c.last_torque.get_lane(i),
            actuator_saturated: c.actuator_saturated.get_lane(i),
            telemetry: c.telemetry.get_lane(i),
            alphas: c.alphas,
            alpha_dt: c.alpha_dt,
            tilt_limit: c.tilt_limit,
            yaw_sin_cos: HeadingSinCos::new(),
        }
    }

    /// `N` flights on `Lanes<N>` against `N` one-flight controllers fed the
    /// same inputs ([`flight_inputs`]: lanes at the reference, beyond the
    /// velocity, tilt and thrust limits, on the thrust floor with the
    /// vertical anti-windup holding, upside down with the thrust axis
    /// reversed; non-finite inputs in single lanes and in all; actuator
    /// saturation per lane; lanes reset mid-run): every command, telemetry
    /// value and state, lane by lane and bit for bit, at every step.
    fn lanes_fly_as_scalars<const N: usize>(gains: PidGains, with_body: bool) {
        let model = QuadrotorParams::default();
        let mut lanes = PidController::<Lanes<N>>::splat(model, gains).unwrap();
        let mut scalars: [PidController; N] = core::array::from_fn(|_| PidController::new(model, gains).unwrap());
        let mut rng = Lcg(0x5eed_0000 + 2 * N as u64 + u64::from(with_body));
        let (mut floored, mut limited, mut reversed) = (0, 0, 0);
        for step in 0..400 {
            for lane in [0, N - 1] {
                if (step == 150 && lane == 0) || (step == 151 && lane == N - 1) {
                    scalars[lane].reset();
                    lanes.reset_lane(lane);
                }
            }
            let dt = dt_at(step);
            let mut m = Measurement::<Lanes<N>>::default();
            let mut r = Reference::<Lanes<N>>::default();
            let mut saturated = LaneMask::<N>::default();
            let mut want = [Command::default(); N];
            for (i, c) in scalars.iter_mut().enumerate() {
                let (mi, ri, si) = flight_inputs(&mut rng, i, step, with_body);
                m.put_lane(i, mi);
                r.put_lane(i, ri);
                saturated.put_lane(i, si);
                c.actuator_feedback(si);
                want[i] = if step % 2 == 0 { c.update(&mi.euler, &ri, dt) } else { c.update_measured(&mi, &ri, dt) };
            }
            lanes.actuator_feedback(saturated);
            let got = if step % 2 == 0 { lanes.update(&m.euler, &r, dt) } else { lanes.update_measured(&m, &r, dt) };
            for (i, c) in scalars.iter().enumerate() {
                let g = got.get_lane(i);
                assert_eq!(g.thrust.to_bits(), want[i].thrust.to_bits(), "thrust, lane {i}, step {step}");
                for a in 0..3 {
                    assert_eq!(g.torque[a].to_bits(), want[i].torque[a].to_bits(), "torque {a}, lane {i}, step {step}");
                }
                assert_eq!(state_bits(&lane_of(&lanes, i)), state_bits(c), "states, lane {i}, step {step}");
                let t = c.telemetry();
                floored += usize::from(want[i].thrust.is_finite() && t.nominal_thrust < gains.thrust_min);
                limited += usize::from(want[i].thrust.is_finite() && t.thrust_limited && i % 5 == 1);
                // Lane 3 on even steps: upside down, demanded thrust axis exactly vertical.
                reversed += usize::from(
                    i % 5 == 3 && step % 2 == 0 && want[i].thrust.is_finite() && t.commanded_acceleration[0] == 0.0,
                );
            }
        }
        // The branches the inputs were built for were taken.
        assert!(floored > 100 && limited > 100 && reversed > 100, "{floored} {limited} {reversed}");
        let r = rotation_from_euler(&[core::f64::consts::PI, 0.0, 0.0]);
        let tilt = quat_between(&[r[0][2], r[1][2], r[2][2]], &[0.0, 0.0, 1.0]);
        assert!(tilt[1].abs() > 1.0 - 1e-5 || tilt[2].abs() > 1.0 - 1e-5, "{tilt:?}");
    }

    #[test]
    fn four_lanes_fly_as_four_scalar_controllers() {
        lanes_fly_as_scalars::<4>(PidGains::default(), false);
        lanes_fly_as_scalars::<4>(PidGains::default(), true);
        lanes_fly_as_scalars::<4>(PidGains { anti_windup: false, ..PidGains::default() }, true);
    }

    #[test]
    fn eight_lanes_fly_as_eight_scalar_controllers() {
        lanes_fly_as_scalars::<8>(PidGains::default(), false);
        lanes_fly_as_scalars::<8>(PidGains::default(), true);
    }

    #[test]
    fn hover_at_the_reference_gives_weight_zero_torque_and_no_integration() {
        let p = QuadrotorParams::default();
        for yaw in [0.0, 0.7, -2.5] {
            let mut c = controller();
            let state = QuadState { position: [1.0, 2.0, 3.0], attitude: [0.0, 0.0, yaw], ..QuadState::default() };
            let reference = Reference { position: [1.0, 2.0, 3.0], yaw, ..Reference::default() };
            for _ in 0..100 {
                let cmd = c.update(&state, &reference, 1e-3);
                assert!((cmd.thrust - p.mass * p.gravity).abs() < 1e-12, "{}", cmd.thrust);
                assert!(cmd.torque.iter().all(|t| t.abs() < 1e-12), "{:?}", cmd.torque);
            }
            assert_eq!(c.velocity_integral(), [0.0; 3]);
            assert!(c.rate_integral().iter().all(|i| i.abs() < 1e-15));
        }
    }

    #[test]
    fn rescaled_gains_have_the_documented_values() {
        let p = QuadrotorParams::default();
        let g = PidGains::for_vehicle(&p);
        let [roll, _, yaw] = PidGains::max_torques(&p);
        // √2 l T_max/4 and (d/b) T_max with T_max = 2 m g = 14.52 N.
        assert!((roll - 1.0779).abs() < 1e-4, "{roll}");
        assert!((yaw - 0.157244).abs() < 1e-5, "{yaw}");
        assert!((g.thrust_max - 2.0 * p.mass * p.gravity).abs() < 1e-12);
        assert!((g.hover_thrust - p.mass * p.gravity).abs() < 1e-12);
        // Rate-loop bandwidth K_p τ_max / J.
        assert!((g.rate_p[0] / p.inertia[0] - 42.25).abs() < 0.05, "{}", g.rate_p[0] / p.inertia[0]);
        assert!((g.rate_p[2] / p.inertia[2] - 4.107).abs() < 0.01, "{}", g.rate_p[2] / p.inertia[2]);
        g.check().unwrap();
        // The AscTec Hummingbird of the realistic scenarios (RotorS): 24.0 N
        // of rotor thrust, 2.42× the torque of the old l (2 m g)/4 scaling.
        let hb = QuadrotorParams {
            mass: 0.716,
            inertia: [0.007, 0.007, 0.012],
            lift_coefficient: 8.54858e-6,
            yaw_drag_coefficient: 1.36777e-7,
            arm_length: 0.17,
            ..QuadrotorParams::default()
        };
        let t_max = 4.0 * 8.54858e-6 * 838.0 * 838.0;
        let g = PidGains::for_vehicle_with_max_thrust(&hb, Some(t_max));
        let old = 0.17 * 2.0 * 0.716 * 9.81 / 4.0;
        assert!((g.rate_p[0] / 0.15 / old - 2.42).abs() < 0.01, "{}", g.rate_p[0] / 0.15 / old);
        assert!((g.thrust_max - t_max).abs() < 1e-12);
    }

    #[test]
    fn the_demanded_tilt_never_exceeds_max_tilt() {
        let mut c = controller();
        let reference = Reference { position: [50.0, -80.0, 0.0], ..Reference::default() };
        // Moving fast sideways: the velocity error alone asks for ~60 m/s².
        let state = QuadState { velocity: [-20.0, 15.0, 0.0], ..QuadState::default() };
        c.update(&state, &reference, 1e-3);
        let [phi, theta, _] = c.telemetry().attitude_reference;
        let tilt = crate::math::acos(crate::math::cos(phi) * crate::math::cos(theta));
        assert!(tilt <= PidGains::default().max_tilt + 1e-12, "{tilt}");
        assert!(tilt > PidGains::default().max_tilt - 1e-9, "{tilt}");
        assert!(c.telemetry().commanded_acceleration[0].abs() > 20.0);
    }

    #[test]
    fn thrust_stays_within_its_limits_with_vertical_priority() {
        let k = PidGains::default();
        let mut c = controller();
        // A fast climb demand: thrust capped at thrust_max.
        let state = QuadState { velocity: [0.0, 0.0, -10.0], ..QuadState::default() };
        let cmd = c.update(&state, &Reference { position: [0.0, 0.0, 20.0], ..Reference::default() }, 1e-3);
        assert!((cmd.thrust - k.thrust_max).abs() < 1e-9, "{}", cmd.thrust);
        // A fast descent demand: thrust floored at thrust_min.
        let mut c = controller();
        let state = QuadState { velocity: [0.0, 0.0, 10.0], ..QuadState::default() };
        let cmd = c.update(&state, &Reference { position: [0.0, 0.0, -20.0], ..Reference::default() }, 1e-3);
        assert!((cmd.thrust - k.thrust_min).abs() < 1e-9, "{}", cmd.thrust);
        // The vertical integrator did not wind further into the floor.
        assert_eq!(c.velocity_integral()[2], 0.0);
    }

    #[test]
    fn tilt_is_corrected_before_yaw() {
        // Rolled 0.3 rad and 1 rad off in yaw: the rate setpoint is mostly roll.
        let c = controller();
        let r = rotation_from_euler(&[0.3, 0.0, 1.0]);
        let q = quat_from_rotation(&r);
        let r_d = rotation_from_euler(&[0.0, 0.0, 0.0]);
        let rate = c.rate_setpoint(&r, &q, &r_d, 0.0);
        let k = PidGains::default();
        // Roll error 0.3 rad at gain 4.0 ≈ 1.2 rad/s; yaw 1 rad weighted 0.4 at 2.8/0.4.
        assert!(rate[0] < -1.0, "{rate:?}");
        assert!(rate[2].abs() < k.attitude_p[2] * 1.0 + 0.1, "{rate:?}");
        // Pure yaw error: small-error yaw gain is MC_YAW_P.
        let r = rotation_from_euler(&[0.0, 0.0, 0.01]);
        let rate = c.rate_setpoint(&r, &quat_from_rotation(&r), &r_d, 0.0);
        assert!((rate[2] + 0.01 * k.attitude_p[2]).abs() < 1e-4, "{rate:?}");
    }

    #[test]
    fn quaternion_helpers_agree_with_rotation_matrices() {
        let r = rotation_from_euler(&[0.4, -0.3, 2.9]);
        let q = quat_from_rotation(&r);
        // Rotating e₃ by q gives the third column of R.
        let v = quat_mul(&quat_mul(&q, &[0.0, 0.0, 0.0, 1.0]), &quat_conj(&q));
        for i in 0..3 {
            assert!((v[i + 1] - r[i][2]).abs() < 1e-12);
        }
        let t = quat_between(&[0.0, 0.0, 1.0], &[0.0, 0.0, -1.0]);
        let w = quat_mul(&quat_mul(&t, &[0.0, 0.0, 0.0, 1.0]), &quat_conj(&t));
        assert!((w[3] + 1.0).abs() < 1e-12);
        let v = constrain_xy([3.0, 4.0], [1.0, 0.0], 2.0);
        assert!((v[0] - 1.2).abs() < 1e-12 && (v[1] - 1.6).abs() < 1e-12, "{v:?}");
        let v = constrain_xy([1.0, 0.0], [0.0, 5.0], 2.0);
        assert!(((v[0] * v[0] + v[1] * v[1]).sqrt() - 2.0).abs() < 1e-12 && v[0] == 1.0);
    }

    #[test]
    fn bad_gains_are_refused_naming_the_field() {
        let d = PidGains::default();
        let bad = [
            (PidGains { position_p: [1.0, 0.0, 1.0], ..d }, "position_p[1]"),
            (PidGains { velocity_i: [0.0, 0.0, -1.0], ..d }, "velocity_i[2]"),
            (PidGains { rate_p: [f64::NAN, 1.0, 1.0], ..d }, "rate_p[0]"),
            (PidGains { rate_integral_limit: [0.1, -0.1, 0.1], ..d }, "rate_integral_limit[1]"),
            (PidGains { max_tilt: 1.6, ..d }, "max_demanded_tilt"),
            (PidGains { yaw_weight: 0.0, ..d }, "yaw_weight"),
            (PidGains { thrust_min: d.hover_thrust, ..d }, "thrust_min"),
            (PidGains { thrust_max: d.hover_thrust, ..d }, "thrust_max"),
            (PidGains { rate_derivative_cutoff: 0.0, ..d }, "rate_derivative_cutoff"),
        ];
        for (gains, field) in bad {
            let err = PidController::new(QuadrotorParams::default(), gains).unwrap_err();
            assert_eq!(err.field, field, "{err}");
        }
    }

    #[test]
    fn a_non_finite_input_leaves_every_state_unchanged_and_reset_clears_them() {
        let mut c = controller();
        let reference = Reference { position: [1.0, -1.0, 2.0], ..Reference::default() };
        let state = QuadState { attitude: [0.1, 0.0, 0.0], angular_rate: [0.5, 0.0, 0.0], ..QuadState::default() };
        for _ in 0..50 {
            c.update(&state, &reference, 1e-3);
        }
        let before =
            (c.velocity_integral(), c.rate_integral(), c.velocity_derivative, c.rate_derivative, *c.telemetry());
        assert!(before.0.iter().any(|v| *v != 0.0) && before.1.iter().any(|v| *v != 0.0));
        let bad = QuadState { position: [f64::NAN, 0.0, 0.0], ..state };
        let cmd = c.update(&bad, &reference, 1e-3);
        assert!(cmd.thrust.is_nan() && cmd.torque.iter().all(|t| t.is_nan()));
        assert!(c.update(&state, &reference, f64::INFINITY).thrust.is_nan());
        let after =
            (c.velocity_integral(), c.rate_integral(), c.velocity_derivative, c.rate_derivative, *c.telemetry());
        assert_eq!(before, after);
        c.reset();
        assert_eq!((c.velocity_integral(), c.rate_integral()), ([0.0; 3], [0.0; 3]));
        assert_eq!(c.telemetry().sliding_mode, None);
        assert_eq!(c.estimate_names(), PID_ESTIMATE_NAMES);
    }

    #[test]
    fn saturation_feedback_stops_the_rate_integrator_growing() {
        let mut free = controller();
        let mut held = controller();
        let state = QuadState { attitude: [0.3, 0.0, 0.0], ..QuadState::default() };
        let reference = Reference::default();
        held.actuator_feedback(true);
        free.update(&state, &reference, 1e-3);
        held.update(&state, &reference, 1e-3);
        for _ in 0..100 {
            free.update(&state, &reference, 1e-3);
            held.update(&state, &reference, 1e-3);
        }
        // Negative roll torque demanded; the held integrator does not grow more negative.
        assert!(free.rate_integral()[0] < -1e-3, "{:?}", free.rate_integral());
        assert!(held.rate_integral()[0] >= free.rate_integral()[0]);
        // Only the first step (before any torque sign is known) integrated.
        assert!(held.rate_integral()[0].abs() < 1e-3, "{:?}", held.rate_integral());
    }
}
