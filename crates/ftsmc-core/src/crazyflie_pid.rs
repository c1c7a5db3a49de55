//! The Crazyflie firmware's PID cascade (position → velocity → attitude →
//! rate) with its power distribution, as the firmware flies it.
//!
//! Structure, gains and units are facts read from bitcraze/crazyflie-firmware
//! at tag 2025.12.1 (commit `252b41341a078c29662ff7bd580985befce42a6c`, the
//! firmware NanoBench's flights report): `src/modules/src/controller/
//! controller_pid.c`, `position_controller_pid.c`,
//! `attitude_pid_controller.c`, `src/utils/src/pid.c`,
//! `src/modules/src/power_distribution_quadrotor.c`, `src/drivers/src/motors.c`
//! and the defaults of `src/platform/interface/platform_defaults_cf2.h`.
//! The code here is ftsmc's own, in ftsmc's frames.
//!
//! # The cascade
//!
//! Angles in the firmware's degrees, with its "legacy" pitch sign (pitch
//! positive nose up: `θ_cf = −θ`, `q_cf = −q` for ftsmc's Z-Y-X pitch θ and
//! body rate q; world z up, body forward-left-up):
//!
//! ```text
//! every position period (1/100 s, POSITION_RATE):
//!   in the yaw frame: x_b = x cos ψ + y sin ψ, y_b = −x sin ψ + y cos ψ
//!   v_sp,b = PID_pos(p_sp,b − p_b)          (each |·| ≤ 1.1 v_max; z on world z)
//!   θ_cf,sp = −PID_vx(v_sp,x − v_b,x),  φ_sp = −PID_vy(v_sp,y − v_b,y)   (≤ 20°)
//!   T = 1000 PID_vz(v_sp,z − v_z) + thrust_base, T ≥ thrust_min, T ∈ [0, 65535]
//! every attitude period (1/500 s, ATTITUDE_RATE):
//!   ω_sp = PID_att(η_sp − η)                 (yaw error wrapped to ±180°)
//!   (roll, pitch, yaw) = sat_int16(PID_rate(ω_sp − (p, −q, r)))
//!   yaw ← −yaw
//! power distribution ("legacy", quad ×):
//!   r = trunc(roll/2), s = trunc(pitch/2)
//!   m1 = T − r + s + yaw,  m2 = T − r − s − yaw,
//!   m3 = T + r − s + yaw,  m4 = T + r + s − yaw
//!   cap: all lowered by (max m − 65535) when above; each ≥ idle_thrust
//! ```
//!
//! with the firmware's PID of `pid.c`: `out = kp e + kd (−Δmeasured/dt) + ki
//! ∫e dt + kff desired` (derivative on the measurement, integral clamped to
//! `±integration_limit`, output clamped to `±output_limit` where the loop has
//! one). m1 is front-right, m2 back-right, m3 back-left, m4 front-left
//! (Bitcraze, "Crazyflie 2.x coordinate system"); m1 and m3 turn
//! counter-clockwise seen from above.
//!
//! # Motor commands, and what the rotors make of them
//!
//! [`CrazyfliePid::pwm`] are the four 16-bit motor commands m1…m4 after the
//! cap, before the firmware's battery compensation
//! ([`battery_compensated`], which needs the supply voltage: a caller that
//! has it applies it). Through [`Controller::update`] the command becomes a
//! force and moments for ftsmc's mixer: rotor speed `ω_i = (m_i/65535) ω_max`
//! ([`PwmMap`]), thrust `k_f ω_i²`, moments on the × layout with
//! `arm_length`, yaw moment `k_m ω_i²` with the spins above — the map under
//! which `ftsmc identify` and `ftsmc validate` read a log's PWM.
//!
//! # What is not modelled
//!
//! * The second-order low-pass on the derivative of the position and
//!   velocity PIDs (`lpf2p`, 20 Hz): their default `kd` is 0, so it does not
//!   act; [`CrazyfliePidGains::check`] refuses a non-zero `kd` there rather
//!   than fly it unfiltered. The attitude and rate filters are off by
//!   default (`ATTITUDE_LPF_ENABLE`, `ATTITUDE_RATE_LPF_ENABLE` false).
//! * The firmware computes in `f32`; this is `f64`.
//! * Only position mode (`modeAbs` on x, y, z and yaw), the mode of a
//!   position set-point (the high-level commander, `send_position_setpoint`);
//!   in it the velocity set-point's feed-forward is not used.
//! * The state estimator: the controller is given the state it is given.

use crate::controller::Telemetry;
use crate::kinematics::{body_rates_from_euler_rates, euler_from_quaternion, quaternion_from_euler};
use crate::law::{check_closed, check_gain, check_gain_or_zero, check_left_open, GainError};
use crate::math::{cbrt, sin_cos, sqrt, Vec3};
use crate::measured::BodyAttitude;
use crate::model::{Command, QuadState, QuadrotorParams, Reference};

/// Largest 16-bit motor command, `UINT16_MAX`.
pub const PWM_MAX: f64 = 65535.0;
/// The firmware's attitude and rate loop rate, Hz (`ATTITUDE_RATE`, `stabilizer_types.h`).
pub const ATTITUDE_RATE_HZ: f64 = 500.0;
/// The firmware's position loop rate, Hz (`POSITION_RATE`).
pub const POSITION_RATE_HZ: f64 = 100.0;
/// Thrust units per unit of the vertical-velocity PID output (`thrustScale`).
pub const THRUST_SCALE: f64 = 1000.0;
/// Output limits of the position and velocity PIDs are the limits ×1.10
/// (`velMaxOverhead`, `rpLimitOverhead`).
pub const LIMIT_OVERHEAD: f64 = 1.10;
/// Default top rotor speed of [`PwmMap`], rad/s: the `crazyflie-2.1`
/// preset's (Bitcraze's Gazebo model, 25,000 rpm).
pub const CRAZYFLIE_MAX_ROTOR_SPEED: f64 = 2618.0;

/// The gains of one firmware PID (`PidObject` of `pid.h`), in the units of
/// its loop.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Deserialize, serde::Serialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct FirmwarePidGains {
    /// Proportional gain `kp`.
    pub kp: f64,
    /// Integral gain `ki`, per s.
    pub ki: f64,
    /// Derivative gain `kd` (on the measurement), s.
    pub kd: f64,
    /// Feed-forward gain `kff` on the desired value.
    pub kff: f64,
    /// Bound of the error integral `iLimit`, loop units × s (0: none).
    pub integration_limit: f64,
}

impl FirmwarePidGains {
    /// `kp, ki, kd, kff` with the firmware's default integral bound
    /// (`DEFAULT_PID_INTEGRATION_LIMIT` = 5000).
    pub const fn new(kp: f64, ki: f64, kd: f64, kff: f64) -> Self {
        Self { kp, ki, kd, kff, integration_limit: 5000.0 }
    }

    /// The same gains with integral bound `limit`.
    pub const fn limited(self, limit: f64) -> Self {
        Self { integration_limit: limit, ..self }
    }

    fn check(&self, names: [&'static str; 5]) -> Result<(), GainError> {
        check_gain_or_zero(names[0], self.kp)?;
        check_gain_or_zero(names[1], self.ki)?;
        check_gain_or_zero(names[2], self.kd)?;
        check_closed(names[3], self.kff, -1e6, 1e6, "-1e6 <= kff <= 1e6")?;
        check_gain_or_zero(names[4], self.integration_limit)
    }
}

/// The state of one firmware PID: the error integral and the previous
/// measurement (for the derivative); `None` until the first update, when
/// the firmware's reset (`pidReset(actual)`, done while the motors are off)
/// sets the previous measurement to the current one.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FirmwarePid {
    integral: f64,
    previous: Option<f64>,
}

impl FirmwarePid {
    /// `pidUpdate` of `pid.c`: the output for `desired` and `measured`
    /// over `dt` s, clamped to `±output_limit` when it is positive; `angle`
    /// wraps the error and the measurement's change to ±180 (the yaw angle).
    pub fn update(
        &mut self,
        gains: &FirmwarePidGains,
        desired: f64,
        measured: f64,
        dt: f64,
        output_limit: f64,
        angle: bool,
    ) -> f64 {
        let wrap = |x: f64| {
            if !angle {
                x
            } else if x > 180.0 {
                x - 360.0
            } else if x < -180.0 {
                x + 360.0
            } else {
                x
            }
        };
        let error = wrap(desired - measured);
        let delta = wrap(-(measured - self.previous.unwrap_or(measured)));
        let mut out = gains.kp * error + gains.kd * (delta / dt);
        self.integral += error * dt;
        if gains.integration_limit != 0.0 {
            self.integral = self.integral.clamp(-gains.integration_limit, gains.integration_limit);
        }
        out += gains.ki * self.integral + gains.kff * desired;
        if output_limit > 0.0 {
            out = out.clamp(-output_limit, output_limit);
        }
        self.previous = Some(measured);
        out
    }

    /// The error integral, loop units × s.
    pub fn integral(&self) -> f64 {
        self.integral
    }
}

/// What turns the 16-bit motor commands into rotor speeds:
/// `ω_i = (m_i / 65535) ω_max` (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Deserialize, serde::Serialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct PwmMap {
    /// Rotor speed at a command of 65535, rad/s (default
    /// [`CRAZYFLIE_MAX_ROTOR_SPEED`]).
    pub max_rotor_speed: f64,
    /// Smallest command of a running motor (`powerDist.idleThrust`; default
    /// 0, the Crazyflie 2.1's `CONFIG_MOTORS_DEFAULT_IDLE_THRUST` without
    /// the BigQuad deck).
    pub idle_thrust: f64,
}

impl Default for PwmMap {
    fn default() -> Self {
        Self { max_rotor_speed: CRAZYFLIE_MAX_ROTOR_SPEED, idle_thrust: 0.0 }
    }
}

impl PwmMap {
    /// Range checks: `0 < max_rotor_speed <= 1e6` rad/s, `0 <= idle_thrust <= 65535`.
    pub fn check(&self) -> Result<(), GainError> {
        check_left_open("max_rotor_speed", self.max_rotor_speed, 0.0, 1e6, "0 < max_rotor_speed <= 1e6 (rad/s)")?;
        check_closed("idle_thrust", self.idle_thrust, 0.0, PWM_MAX, "0 <= idle_thrust <= 65535")
    }

    /// The force and moments (body frame: forward-left-up) the commands
    /// `m1…m4` ask of a Crazyflie-numbered × vehicle with `plant`'s thrust
    /// and moment coefficients and arm length (module docs).
    pub fn command(&self, plant: &QuadrotorParams, pwm: &[f64; 4]) -> Command {
        let w2 = pwm.map(|m| {
            let w = m / PWM_MAX * self.max_rotor_speed;
            w * w
        });
        let t = w2.map(|w| plant.lift_coefficient * w);
        let d = plant.arm_length * core::f64::consts::FRAC_1_SQRT_2;
        // m1 front-right (x +d, y −d), m2 back-right, m3 back-left, m4 front-left.
        let x = [d, -d, -d, d];
        let y = [-d, -d, d, d];
        let spin_ccw = [true, false, true, false];
        let mut torque = [0.0; 3];
        for i in 0..4 {
            torque[0] += y[i] * t[i];
            torque[1] -= x[i] * t[i];
            let m = plant.yaw_drag_coefficient * w2[i];
            torque[2] += if spin_ccw[i] { -m } else { m };
        }
        Command { thrust: t.iter().sum(), torque }
    }
}

/// The firmware's "legacy" power distribution (`powerDistributionLegacy`,
/// module docs): the four uncapped motor thrusts m1…m4 of thrust `thrust`
/// and the attitude outputs `roll`, `pitch`, `yaw` (int16 units, already
/// saturated), with the firmware's integer truncations.
pub fn power_distribution_uncapped(thrust: f64, roll: f64, pitch: f64, yaw: f64) -> [f64; 4] {
    let r = libm::trunc(roll / 2.0);
    let p = libm::trunc(pitch / 2.0);
    [thrust - r + p + yaw, thrust - r - p - yaw, thrust + r - p + yaw, thrust + r + p - yaw].map(libm::trunc)
}

/// The firmware's cap (`powerDistributionCap`): every motor lowered by the
/// excess of the highest over 65535, then each at least `idle_thrust`
/// (and, as a 16-bit value, at most 65535).
pub fn power_cap(uncapped: [f64; 4], idle_thrust: f64) -> [f64; 4] {
    let highest = uncapped.iter().copied().fold(0.0, f64::max);
    let reduction = if highest > PWM_MAX { highest - PWM_MAX } else { 0.0 };
    uncapped.map(|m| (m - reduction).max(idle_thrust).min(PWM_MAX))
}

/// [`power_distribution_uncapped`] then [`power_cap`]: every value in
/// `[idle_thrust, 65535]`.
pub fn power_distribution(thrust: f64, roll: f64, pitch: f64, yaw: f64, idle_thrust: f64) -> [f64; 4] {
    power_cap(power_distribution_uncapped(thrust, roll, pitch, yaw), idle_thrust)
}

/// `saturateSignedInt16` of `attitude_pid_controller.c`: clamp to ±32767
/// and truncate towards zero.
pub fn saturate_int16(x: f64) -> f64 {
    libm::trunc(x.clamp(-32767.0, 32767.0))
}

/// The motor-voltage → thrust cubic of the Crazyflie 2.1 with 2.1+
/// propellers (`VMOTOR2THRUST0…3` of `platform_defaults_cf2.h`, thrust in N
/// per motor from volts).
pub const VMOTOR_TO_THRUST: [f64; 4] =
    [-0.02476537915958403, 0.06523793527519485, -0.026792504967750107, 0.006776789303971145];
/// `THRUST_MIN` of the battery compensation (2.1+ propellers), N per motor.
pub const COMPENSATION_THRUST_MIN: f64 = 0.012817578393224994;
/// `THRUST_MAX` of the battery compensation (2.1+ propellers), N per motor.
pub const COMPENSATION_THRUST_MAX: f64 = 0.12;

/// The firmware's battery compensation (`motorsCompensateBatteryVoltage`
/// of `motors.c`, on by default: `CONFIG_ENABLE_THRUST_BAT_COMPENSATED`):
/// command `m` means the thrust `m/65535 · THRUST_MAX`; the motor voltage
/// giving it is the real root of the cubic [`VMOTOR_TO_THRUST`] (Cardano),
/// and the PWM is that voltage over the supply `supply_v` (V), ×65535. 0
/// below `THRUST_MIN` or a supply under 2 V, as the firmware. Not capped:
/// the firmware caps after it (the cap of [`power_distribution`]).
pub fn battery_compensated(m: f64, supply_v: f64) -> f64 {
    if supply_v.is_nan() || supply_v < 2.0 {
        return 0.0;
    }
    let thrust = m / PWM_MAX * COMPENSATION_THRUST_MAX;
    if thrust < COMPENSATION_THRUST_MIN {
        return 0.0;
    }
    let [c0, c1, c2, c3] = VMOTOR_TO_THRUST;
    let p = -c2 / (3.0 * c3);
    let q = p * p * p + (c2 * c1 - 3.0 * c3 * (c0 - thrust)) / (6.0 * c3 * c3);
    let r = c1 / (3.0 * c3);
    let s = r - p * p;
    let qrp = sqrt(q * q + s * s * s);
    let v = cbrt(q + qrp) + cbrt(q - qrp) + p;
    PWM_MAX * v / supply_v
}

/// Gains and limits of [`CrazyfliePid`]. `Default` is the firmware's
/// (`platform_defaults_cf2.h`, 2025.12.1); NanoBench's published code sets
/// none of them.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Deserialize, serde::Serialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields, default))]
pub struct CrazyfliePidGains {
    /// x position → x velocity, 1/s (`PID_POS_X_*`: kp 2).
    pub position_x: FirmwarePidGains,
    /// y position → y velocity (`PID_POS_Y_*`: kp 2).
    pub position_y: FirmwarePidGains,
    /// z position → z velocity (`PID_POS_Z_*`: kp 2, ki 0.5).
    pub position_z: FirmwarePidGains,
    /// x velocity → pitch, deg per m/s (`PID_VEL_X_*`: kp 25, ki 1).
    pub velocity_x: FirmwarePidGains,
    /// y velocity → roll, deg per m/s (`PID_VEL_Y_*`: kp 25, ki 1).
    pub velocity_y: FirmwarePidGains,
    /// z velocity → thrust / 1000, per m/s (`PID_VEL_Z_*`: kp 25, ki 15).
    pub velocity_z: FirmwarePidGains,
    /// Roll → roll rate, 1/s (`PID_ROLL_*`: kp 6, ki 3, integral ≤ 20).
    pub attitude_roll: FirmwarePidGains,
    /// Pitch → pitch rate (`PID_PITCH_*`: kp 6, ki 3, integral ≤ 20).
    pub attitude_pitch: FirmwarePidGains,
    /// Yaw → yaw rate (`PID_YAW_*`: kp 6, ki 1, kd 0.35, integral ≤ 360).
    pub attitude_yaw: FirmwarePidGains,
    /// Roll rate → roll output, int16 units per deg/s (`PID_ROLL_RATE_*`:
    /// kp 250, ki 500, kd 2.5, integral ≤ 33.3).
    pub rate_roll: FirmwarePidGains,
    /// Pitch rate → pitch output (`PID_PITCH_RATE_*`: as roll).
    pub rate_pitch: FirmwarePidGains,
    /// Yaw rate → yaw output (`PID_YAW_RATE_*`: kp 120, ki 16.7, integral ≤ 166.7).
    pub rate_yaw: FirmwarePidGains,
    /// Thrust at zero vertical-velocity PID output, 16-bit units
    /// (`PID_VEL_THRUST_BASE` 36000).
    pub thrust_base: f64,
    /// Smallest thrust of the velocity loop (`PID_VEL_THRUST_MIN` 20000).
    pub thrust_min: f64,
    /// Largest roll set-point, deg (`PID_VEL_ROLL_MAX` 20).
    pub roll_limit: f64,
    /// Largest pitch set-point, deg (`PID_VEL_PITCH_MAX` 20).
    pub pitch_limit: f64,
    /// Largest velocity set-points of the position loop `[x, y, z]`, m/s
    /// (`PID_POS_VEL_*_MAX` 1; z is used as at least 0.5).
    pub velocity_max: [f64; 3],
    /// Position loop period, s (1/`POSITION_RATE` = 0.01); the attitude and
    /// rate loops run at every update (the firmware's 500 Hz).
    pub position_period: f64,
    /// The motor commands' rotor speeds.
    pub motors: PwmMap,
}

impl Default for CrazyfliePidGains {
    fn default() -> Self {
        let p = FirmwarePidGains::new;
        Self {
            position_x: p(2.0, 0.0, 0.0, 0.0),
            position_y: p(2.0, 0.0, 0.0, 0.0),
            position_z: p(2.0, 0.5, 0.0, 0.0),
            velocity_x: p(25.0, 1.0, 0.0, 0.0),
            velocity_y: p(25.0, 1.0, 0.0, 0.0),
            velocity_z: p(25.0, 15.0, 0.0, 0.0),
            attitude_roll: p(6.0, 3.0, 0.0, 0.0).limited(20.0),
            attitude_pitch: p(6.0, 3.0, 0.0, 0.0).limited(20.0),
            attitude_yaw: p(6.0, 1.0, 0.35, 0.0).limited(360.0),
            rate_roll: p(250.0, 500.0, 2.5, 0.0).limited(33.3),
            rate_pitch: p(250.0, 500.0, 2.5, 0.0).limited(33.3),
            rate_yaw: p(120.0, 16.7, 0.0, 0.0).limited(166.7),
            thrust_base: 36000.0,
            thrust_min: 20000.0,
            roll_limit: 20.0,
            pitch_limit: 20.0,
            velocity_max: [1.0; 3],
            position_period: 1.0 / POSITION_RATE_HZ,
            motors: PwmMap::default(),
        }
    }
}

impl CrazyfliePidGains {
    /// Range checks; the error names the field (`rate_roll.kp`, …). A
    /// non-zero `kd` of a position or velocity loop is refused (its
    /// firmware filter is not modelled, module docs).
    pub fn check(&self) -> Result<(), GainError> {
        macro_rules! pid {
            ($f:ident) => {
                self.$f.check([
                    concat!(stringify!($f), ".kp"),
                    concat!(stringify!($f), ".ki"),
                    concat!(stringify!($f), ".kd"),
                    concat!(stringify!($f), ".kff"),
                    concat!(stringify!($f), ".integration_limit"),
                ])?
            };
        }
        pid!(position_x);
        pid!(position_y);
        pid!(position_z);
        pid!(velocity_x);
        pid!(velocity_y);
        pid!(velocity_z);
        pid!(attitude_roll);
        pid!(attitude_pitch);
        pid!(attitude_yaw);
        pid!(rate_roll);
        pid!(rate_pitch);
        pid!(rate_yaw);
        let filtered = [
            ("position_x.kd", self.position_x.kd),
            ("position_y.kd", self.position_y.kd),
            ("position_z.kd", self.position_z.kd),
            ("velocity_x.kd", self.velocity_x.kd),
            ("velocity_y.kd", self.velocity_y.kd),
            ("velocity_z.kd", self.velocity_z.kd),
        ];
        for (field, value) in filtered {
            if value != 0.0 {
                return Err(GainError {
                    field,
                    value,
                    expected: "0 (the firmware low-passes this derivative at 20 Hz, which ftsmc does not model)",
                });
            }
        }
        check_closed("thrust_base", self.thrust_base, 0.0, PWM_MAX, "0 <= thrust_base <= 65535")?;
        check_closed("thrust_min", self.thrust_min, 0.0, PWM_MAX, "0 <= thrust_min <= 65535")?;
        check_left_open("roll_limit", self.roll_limit, 0.0, 90.0, "0 < roll_limit <= 90 (deg)")?;
        check_left_open("pitch_limit", self.pitch_limit, 0.0, 90.0, "0 < pitch_limit <= 90 (deg)")?;
        for (field, v) in ["velocity_max[0]", "velocity_max[1]", "velocity_max[2]"].into_iter().zip(self.velocity_max) {
            check_gain(field, v)?;
        }
        check_left_open("position_period", self.position_period, 0.0, 1.0, "0 < position_period <= 1 (s)")?;
        self.motors.check()
    }
}

/// The state a Crazyflie controller reads at one update.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FirmwareState {
    /// World position, m.
    pub position: Vec3,
    /// World velocity, m/s.
    pub velocity: Vec3,
    /// Attitude `[w, x, y, z]`, body → world.
    pub quaternion: [f64; 4],
    /// Body rates (p, q, r), rad/s (the gyro).
    pub body_rates: Vec3,
}

impl FirmwareState {
    /// From ftsmc's Euler state, or its quaternion and body rates when the
    /// measurement carries them.
    pub fn from_measurement(euler: &QuadState, body: Option<&BodyAttitude>) -> Self {
        let (quaternion, body_rates) = match body {
            Some(b) => (b.quaternion, b.body_rates),
            None => (
                quaternion_from_euler(&euler.attitude),
                body_rates_from_euler_rates(&euler.attitude, &euler.angular_rate),
            ),
        };
        Self { position: euler.position, velocity: euler.velocity, quaternion, body_rates }
    }

    /// Roll, legacy pitch and yaw, deg (module docs).
    pub fn legacy_euler_deg(&self) -> Vec3 {
        let e = euler_from_quaternion(&self.quaternion);
        [e[0].to_degrees(), -e[1].to_degrees(), e[2].to_degrees()]
    }
}

/// `capAngle` of `controller_pid.c`: an angle in deg brought to `[−180, 180]`.
pub fn cap_angle(mut a: f64) -> f64 {
    if !a.is_finite() {
        return a;
    }
    while a > 180.0 {
        a -= 360.0;
    }
    while a < -180.0 {
        a += 360.0;
    }
    a
}

/// The firmware's PID cascade ([module docs](self)), one flight.
#[derive(Clone, Debug)]
pub struct CrazyfliePid {
    model: QuadrotorParams,
    gains: CrazyfliePidGains,
    position: [FirmwarePid; 3],
    velocity: [FirmwarePid; 3],
    attitude: [FirmwarePid; 3],
    rate: [FirmwarePid; 3],
    /// `[roll, legacy pitch, yaw]` set-point, deg.
    attitude_desired: Vec3,
    /// Thrust of the velocity loop, 16-bit units.
    thrust: f64,
    /// Time since the position loop last ran, s (`None`: never).
    since_position: Option<f64>,
    /// `[roll, pitch, yaw]` outputs of the rate loop (int16 units, yaw negated).
    outputs: Vec3,
    uncapped: [f64; 4],
    pwm: [f64; 4],
    telemetry: Telemetry,
}

impl CrazyfliePid {
    /// Build after checking the nominal model (its thrust and moment
    /// coefficients and arm length map the commands to forces) and the gains.
    pub fn new(model: QuadrotorParams, gains: CrazyfliePidGains) -> Result<Self, GainError> {
        model.check()?;
        gains.check()?;
        Ok(Self::fresh(model, gains))
    }

    /// At its initial state (every PID reset, no set-point yet).
    fn fresh(model: QuadrotorParams, gains: CrazyfliePidGains) -> Self {
        Self {
            model,
            gains,
            position: Default::default(),
            velocity: Default::default(),
            attitude: Default::default(),
            rate: Default::default(),
            attitude_desired: [0.0; 3],
            thrust: 0.0,
            since_position: None,
            outputs: [0.0; 3],
            uncapped: [0.0; 4],
            pwm: [0.0; 4],
            telemetry: Telemetry::default(),
        }
    }

    /// The gains in use.
    pub fn gains(&self) -> &CrazyfliePidGains {
        &self.gains
    }

    /// Motor commands m1…m4 of the last update (16-bit units, module docs).
    pub fn pwm(&self) -> [f64; 4] {
        self.pwm
    }

    /// Motor thrusts m1…m4 of the last update before the cap (16-bit
    /// units): what the firmware's battery compensation takes.
    pub fn uncapped(&self) -> [f64; 4] {
        self.uncapped
    }

    /// Thrust of the velocity loop at the last update, 16-bit units (the
    /// firmware's `controller.cmd_thrust`).
    pub fn thrust(&self) -> f64 {
        self.thrust
    }

    /// `[roll, pitch, yaw]` outputs of the rate loop at the last update,
    /// int16 units (the firmware's `controller.cmd_roll`, `cmd_pitch`,
    /// `cmd_yaw`; yaw already negated).
    pub fn outputs(&self) -> Vec3 {
        self.outputs
    }

    /// `[roll, legacy pitch, yaw]` set-point of the attitude loop, deg.
    pub fn attitude_desired(&self) -> Vec3 {
        self.attitude_desired
    }

    /// The position and velocity loops (`positionController`,
    /// `velocityController`) over `dt` s.
    fn position_loop(&mut self, s: &FirmwareState, reference: &Reference, yaw_deg: f64, dt: f64) {
        let g = &self.gains;
        let (sy, cy) = sin_cos(yaw_deg.to_radians());
        let body = |v: &Vec3| [v[0] * cy + v[1] * sy, -v[0] * sy + v[1] * cy];
        let sp = body(&reference.position);
        let p = body(&s.position);
        let vel_sp = [
            self.position[0].update(&g.position_x, sp[0], p[0], dt, g.velocity_max[0] * LIMIT_OVERHEAD, false),
            self.position[1].update(&g.position_y, sp[1], p[1], dt, g.velocity_max[1] * LIMIT_OVERHEAD, false),
            self.position[2].update(
                &g.position_z,
                reference.position[2],
                s.position[2],
                dt,
                g.velocity_max[2].max(0.5) * LIMIT_OVERHEAD,
                false,
            ),
        ];
        let v = body(&s.velocity);
        let pitch = -self.velocity[0].update(&g.velocity_x, vel_sp[0], v[0], dt, g.pitch_limit * LIMIT_OVERHEAD, false);
        let roll = -self.velocity[1].update(&g.velocity_y, vel_sp[1], v[1], dt, g.roll_limit * LIMIT_OVERHEAD, false);
        self.attitude_desired[0] = roll.clamp(-g.roll_limit, g.roll_limit);
        self.attitude_desired[1] = pitch.clamp(-g.pitch_limit, g.pitch_limit);
        let raw =
            self.velocity[2].update(&g.velocity_z, vel_sp[2], s.velocity[2], dt, PWM_MAX / 2.0 / THRUST_SCALE, false);
        self.thrust = (raw * THRUST_SCALE + g.thrust_base).max(g.thrust_min).clamp(0.0, PWM_MAX);
    }

    /// One attitude period of `dt` s from the firmware's state: the
    /// position loop when its period has passed, then the attitude and
    /// rate loops and the power distribution; returns m1…m4.
    pub fn step(&mut self, s: &FirmwareState, reference: &Reference, dt: f64) -> [f64; 4] {
        let g = self.gains;
        let eta = s.legacy_euler_deg();
        self.attitude_desired[2] = cap_angle(reference.yaw.to_degrees());
        let due = match self.since_position {
            None => true,
            // Half an attitude period of slack: the periods are multiples.
            Some(t) => t + dt >= g.position_period - 0.5 * dt,
        };
        if due {
            self.position_loop(s, reference, eta[2], g.position_period);
            self.since_position = Some(0.0);
        } else if let Some(t) = self.since_position.as_mut() {
            *t += dt;
        }
        let d = self.attitude_desired;
        let rate_sp = [
            self.attitude[0].update(&g.attitude_roll, d[0], eta[0], dt, 0.0, false),
            self.attitude[1].update(&g.attitude_pitch, d[1], eta[1], dt, 0.0, false),
            self.attitude[2].update(&g.attitude_yaw, d[2], eta[2], dt, 0.0, true),
        ];
        let w = s.body_rates.map(f64::to_degrees);
        let gyro = [w[0], -w[1], w[2]];
        let roll = saturate_int16(self.rate[0].update(&g.rate_roll, rate_sp[0], gyro[0], dt, 0.0, false));
        let pitch = saturate_int16(self.rate[1].update(&g.rate_pitch, rate_sp[1], gyro[1], dt, 0.0, false));
        let yaw = -saturate_int16(self.rate[2].update(&g.rate_yaw, rate_sp[2], gyro[2], dt, 0.0, false));
        self.outputs = [roll, pitch, yaw];
        self.uncapped = power_distribution_uncapped(self.thrust, roll, pitch, yaw);
        self.pwm = power_cap(self.uncapped, g.motors.idle_thrust);
        self.telemetry.attitude_reference = [d[0].to_radians(), -d[1].to_radians(), d[2].to_radians()];
        self.telemetry.attitude_reference_rate =
            [rate_sp[0].to_radians(), -rate_sp[1].to_radians(), rate_sp[2].to_radians()];
        self.telemetry.attitude_demand = [d[0].to_radians(), -d[1].to_radians()];
        self.pwm
    }
}

/// The [`Controller`] glue of the firmware's controllers (this module's
/// [`CrazyfliePid`] and `crate::mellinger::Mellinger`), one definition for
/// both: the measured state as the firmware's estimator reports it
/// ([`FirmwareState::from_measurement`]), the controller's own `step`
/// (firmware units, PWM m1…m4 after the power distribution and cap), then
/// [`PwmMap::command`]: PWM → rotor speed `ω = (m/65535) ω_max` → rotor
/// thrusts `k_f ω²` → collective thrust and body moments on the nominal
/// model. The type must have the fields `model: QuadrotorParams`,
/// `gains` (with `motors: PwmMap`) and `telemetry: Telemetry`, and the
/// methods `step(&FirmwareState, &Reference, dt) -> [f64; 4]` and
/// `fresh(model, gains) -> Self`.
macro_rules! firmware_controller {
    ($ty:ident, $name:literal) => {
        impl $ty {
            fn update_with(
                &mut self,
                euler: &$crate::model::QuadState,
                body: Option<&$crate::measured::BodyAttitude>,
                reference: &$crate::model::Reference,
                dt: f64,
            ) -> $crate::model::Command {
                let s = $crate::crazyflie_pid::FirmwareState::from_measurement(euler, body);
                let pwm = self.step(&s, reference, dt);
                let command = self.gains.motors.command(&self.model, &pwm);
                self.telemetry.nominal_thrust = command.thrust;
                command
            }
        }

        impl $crate::controller::Controller for $ty {
            fn name(&self) -> &'static str {
                $name
            }

            fn update(
                &mut self,
                state: &$crate::model::QuadState,
                reference: &$crate::model::Reference,
                dt: f64,
            ) -> $crate::model::Command {
                self.update_with(state, None, reference, dt)
            }

            fn update_measured(
                &mut self,
                measured: &$crate::measured::Measurement,
                reference: &$crate::model::Reference,
                dt: f64,
            ) -> $crate::model::Command {
                self.update_with(&measured.euler, measured.body.as_ref(), reference, dt)
            }

            fn uses_body_attitude(&self) -> bool {
                true
            }

            fn telemetry(&self) -> &$crate::controller::Telemetry {
                &self.telemetry
            }

            fn reset(&mut self) {
                *self = Self::fresh(self.model, self.gains);
            }
        }
    };
}
pub(crate) use firmware_controller;

firmware_controller!(CrazyfliePid, "crazyflie-pid");

#[cfg(test)]
mod tests {
    use super::*;

    pub(crate) fn plant() -> QuadrotorParams {
        QuadrotorParams {
            mass: 0.029,
            inertia: [1.6572e-5, 1.6656e-5, 2.9262e-5],
            lift_coefficient: 1.64140e-8,
            yaw_drag_coefficient: 9.7902e-11,
            arm_length: 0.046,
            ..QuadrotorParams::default()
        }
    }

    fn hover_state() -> FirmwareState {
        FirmwareState {
            position: [0.0, 0.0, 1.0],
            velocity: [0.0; 3],
            quaternion: [1.0, 0.0, 0.0, 0.0],
            body_rates: [0.0; 3],
        }
    }

    fn hover_reference() -> Reference {
        Reference { position: [0.0, 0.0, 1.0], ..Reference::default() }
    }

    #[test]
    fn at_the_set_point_every_motor_gets_the_thrust_base() {
        let mut c = CrazyfliePid::new(plant(), CrazyfliePidGains::default()).unwrap();
        for _ in 0..50 {
            assert_eq!(c.step(&hover_state(), &hover_reference(), 0.002), [36000.0; 4]);
        }
        assert_eq!(c.outputs(), [0.0; 3]);
        // Hover equilibrium: the integrators settle where the thrust is the
        // weight (velocity loop integral × ki × 1000 = hover − base).
        let cmd = c.gains.motors.command(&plant(), &c.pwm());
        assert_eq!(cmd.torque, [0.0; 3]);
    }

    #[test]
    fn each_loop_pushes_towards_its_set_point() {
        let g = CrazyfliePidGains::default();
        let pwm = |s: FirmwareState, r: Reference| CrazyfliePid::new(plant(), g).unwrap().step(&s, &r, 0.002);
        let sum = |m: [f64; 4]| m.iter().sum::<f64>();
        // Below the set-point: more thrust on every motor.
        let mut s = hover_state();
        s.position[2] = 0.9;
        assert!(pwm(s, hover_reference()).iter().all(|&m| m > 36000.0));
        // Behind in +x: pitch nose down (θ > 0 in ftsmc): back motors (m2, m3) up.
        let mut r = hover_reference();
        r.position[0] = 0.5;
        let m = pwm(hover_state(), r);
        assert!(m[1] + m[2] > m[0] + m[3], "{m:?}");
        assert!(g.motors.command(&plant(), &m).torque[1] > 0.0, "{m:?}");
        // Behind in +y: roll negative (thrust towards +y).
        let mut r = hover_reference();
        r.position[1] = 0.5;
        assert!(g.motors.command(&plant(), &pwm(hover_state(), r)).torque[0] < 0.0);
        // Rolling at +p, pitching at +q, yawing at +r: the rate loop opposes each.
        for axis in 0..3 {
            let mut s = hover_state();
            s.body_rates[axis] = 1.0;
            let torque = g.motors.command(&plant(), &pwm(s, hover_reference())).torque;
            assert!(torque[axis] < 0.0, "axis {axis}: {torque:?}");
        }
        // Yaw set-point ahead (+ψ): a positive yaw moment, collective thrust kept.
        let mut r = hover_reference();
        r.yaw = 0.3;
        let m = pwm(hover_state(), r);
        assert!(g.motors.command(&plant(), &m).torque[2] > 0.0);
        assert!((sum(m) - 4.0 * 36000.0).abs() <= 4.0, "{m:?}");
    }

    #[test]
    fn outputs_and_motor_commands_saturate_as_the_firmware() {
        assert_eq!(saturate_int16(1e9), 32767.0);
        assert_eq!(saturate_int16(-1e9), -32767.0);
        assert_eq!(saturate_int16(-12.7), -12.0);
        // A command above 65535 lowers every motor by the excess.
        assert_eq!(power_distribution(60000.0, 0.0, 20000.0, 0.0, 0.0), [65535.0, 45535.0, 45535.0, 65535.0]);
        // Idle thrust is a floor.
        assert_eq!(power_distribution(1000.0, 0.0, 0.0, 5000.0, 7000.0), [7000.0; 4]);
        // The velocity loop's thrust stays within [thrust_min, 65535] and
        // the tilt set-point within 20°.
        let mut c = CrazyfliePid::new(plant(), CrazyfliePidGains::default()).unwrap();
        let mut far = hover_reference();
        far.position = [100.0, -100.0, 100.0];
        for _ in 0..100 {
            c.step(&hover_state(), &far, 0.002);
        }
        assert_eq!(c.thrust(), PWM_MAX);
        let d = c.attitude_desired();
        assert!(d[0].abs() <= 20.0 && d[1].abs() <= 20.0 && d[0].abs() == 20.0, "{d:?}");
        far.position[2] = -100.0;
        let mut c = CrazyfliePid::new(plant(), CrazyfliePidGains::default()).unwrap();
        c.step(&hover_state(), &far, 0.002);
        assert_eq!(c.thrust(), 20000.0);
    }

    #[test]
    fn battery_compensation_inverts_the_firmware_cubic() {
        let [c0, c1, c2, c3] = VMOTOR_TO_THRUST;
        for m in [20000.0, 36000.0, 60000.0] {
            let v_supply = 3.7;
            let pwm = battery_compensated(m, v_supply);
            let v = pwm / PWM_MAX * v_supply;
            let thrust = c0 + c1 * v + c2 * v * v + c3 * v * v * v;
            assert!((thrust - m / PWM_MAX * COMPENSATION_THRUST_MAX).abs() < 1e-12, "{m}: {thrust}");
        }
        assert_eq!(battery_compensated(1000.0, 3.7), 0.0);
        assert_eq!(battery_compensated(30000.0, 1.5), 0.0);
    }

    #[test]
    fn the_gain_check_names_the_field() {
        let mut g = CrazyfliePidGains::default();
        g.rate_pitch.kp = -1.0;
        assert_eq!(g.check().unwrap_err().field, "rate_pitch.kp");
        let mut g = CrazyfliePidGains::default();
        g.velocity_z.kd = 0.1;
        assert_eq!(g.check().unwrap_err().field, "velocity_z.kd");
        let mut g = CrazyfliePidGains::default();
        g.motors.max_rotor_speed = f64::NAN;
        assert_eq!(g.check().unwrap_err().field, "max_rotor_speed");
    }
}
