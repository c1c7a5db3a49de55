//! The Crazyflie firmware's Mellinger controller (Mellinger & Kumar,
//! "Minimum snap trajectory generation and control for quadrotors", ICRA
//! 2011, as the firmware implements it), with the firmware's power
//! distribution ([`crate::crazyflie_pid`]).
//!
//! Structure, gains and units are facts read from bitcraze/crazyflie-firmware
//! at tag 2025.12.1 (commit `252b41341a078c29662ff7bd580985befce42a6c`):
//! `src/modules/src/controller/controller_mellinger.c` (its defaults in
//! `g_self`, mass `CF_MASS` of `platform_defaults_cf2.h`). The code here is
//! ftsmc's own, in ftsmc's frames (world z up, body forward-left-up); the
//! firmware's sign flips of its legacy pitch are applied at the output, so
//! the law below is written in the standard form.
//!
//! ```text
//! e_p = p_sp − p,  e_v = v_sp − v,  i_p += e_p dt  (|i_xy| ≤ i_range_xy, |i_z| ≤ i_range_z)
//! F_des = m (a_sp + g e₃) + K_p e_p + K_d e_v + K_i i_p                (N)
//! T = F_des · z_B                                                       (z_B = R e₃)
//! z_d = F_des/|F_des|,  x_c = (cos ψ_sp, sin ψ_sp, 0)
//! y_d = z_d × x_c /|…|,  x_d = y_d × z_d,  R_d = [x_d y_d z_d]
//! e_R = (R_dᵀR − RᵀR_d)^∨   (no ½: twice Lee et al.'s),   e_ω = ω_sp − ω
//! i_R += −e_R dt  (|i_R,xy| ≤ i_range_m_xy, |i_R,z| ≤ i_range_m_z)
//! M = −K_R e_R + K_ω e_ω + K_iM i_R + kd_omega_rp d(e_ω,x, e_ω,y)/dt
//! thrust = mass_thrust · T;  roll = M_x, pitch = −M_y, yaw = −M_z  (each ±32000, int16)
//! ```
//!
//! then the legacy power distribution and cap of the PID cascade. `ω_sp` is
//! `(0, 0, ψ̇_sp)` (a position set-point carries no roll or pitch rate). A
//! thrust `T ≤ 0` gives zero outputs and resets the integrals, as the
//! firmware.
//!
//! Not modelled: the firmware's `f32` arithmetic; the modes other than
//! position (`modeAbs`).

use crate::controller::Telemetry;
use crate::crazyflie_pid::{
    cap_angle, firmware_controller, power_cap, power_distribution_uncapped, FirmwareState, PwmMap,
};
use crate::kinematics::rotation_from_quaternion;
use crate::law::{check_gain, check_gain_or_zero, check_left_open, GainError};
use crate::math::{cross, dot, mat_t_mat, norm, sin_cos, Vec3};
use crate::model::{QuadrotorParams, Reference};

/// Gains of [`Mellinger`]. `Default` is the firmware's (`g_self` of
/// `controller_mellinger.c`, 2025.12.1); NanoBench's published code sets
/// none of them. Names as the firmware's `ctrlMel` parameters, in snake
/// case (`kR_xy` is `kr_xy`).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Deserialize, serde::Serialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields, default))]
pub struct MellingerGains {
    /// Mass in the force demand, kg (`CF_MASS` 0.029).
    pub mass: f64,
    /// Thrust units per newton (`massThrust` 132000).
    pub mass_thrust: f64,
    /// Position gain, x and y, N/m (0.4).
    pub kp_xy: f64,
    /// Velocity gain, x and y, N·s/m (0.2).
    pub kd_xy: f64,
    /// Position integral gain, x and y, N/(m·s) (0.05).
    pub ki_xy: f64,
    /// Bound of the x, y position integral, m·s (2).
    pub i_range_xy: f64,
    /// Position gain, z, N/m (1.25).
    pub kp_z: f64,
    /// Velocity gain, z, N·s/m (0.4).
    pub kd_z: f64,
    /// Position integral gain, z (0.05).
    pub ki_z: f64,
    /// Bound of the z position integral, m·s (0.4).
    pub i_range_z: f64,
    /// Attitude gain, roll and pitch, thrust units per unit `e_R` (`kR_xy` 70000).
    pub kr_xy: f64,
    /// Rate gain, roll and pitch, per rad/s (`kw_xy` 20000).
    pub kw_xy: f64,
    /// Attitude integral gain, roll and pitch (`ki_m_xy` 0).
    pub ki_m_xy: f64,
    /// Bound of the roll, pitch attitude integral (`i_range_m_xy` 1).
    pub i_range_m_xy: f64,
    /// Attitude gain, yaw (`kR_z` 60000).
    pub kr_z: f64,
    /// Rate gain, yaw (`kw_z` 12000).
    pub kw_z: f64,
    /// Attitude integral gain, yaw (`ki_m_z` 500).
    pub ki_m_z: f64,
    /// Bound of the yaw attitude integral (`i_range_m_z` 1500).
    pub i_range_m_z: f64,
    /// Gain on the derivative of the roll and pitch rate error, per rad/s² (`kd_omega_rp` 200).
    pub kd_omega_rp: f64,
    /// The motor commands' rotor speeds.
    pub motors: PwmMap,
}

impl Default for MellingerGains {
    fn default() -> Self {
        Self {
            mass: 0.029,
            mass_thrust: 132000.0,
            kp_xy: 0.4,
            kd_xy: 0.2,
            ki_xy: 0.05,
            i_range_xy: 2.0,
            kp_z: 1.25,
            kd_z: 0.4,
            ki_z: 0.05,
            i_range_z: 0.4,
            kr_xy: 70000.0,
            kw_xy: 20000.0,
            ki_m_xy: 0.0,
            i_range_m_xy: 1.0,
            kr_z: 60000.0,
            kw_z: 12000.0,
            ki_m_z: 500.0,
            i_range_m_z: 1500.0,
            kd_omega_rp: 200.0,
            motors: PwmMap::default(),
        }
    }
}

impl MellingerGains {
    /// Range checks: `mass` and `mass_thrust` and the P and D gains in
    /// `(0, 1e6]`, integral gains, bounds and `kd_omega_rp` in `[0, 1e6]`;
    /// the error names the field.
    pub fn check(&self) -> Result<(), GainError> {
        check_left_open("mass", self.mass, 0.0, 1e6, "0 < mass <= 1e6 (kg)")?;
        for (f, v) in [
            ("mass_thrust", self.mass_thrust),
            ("kp_xy", self.kp_xy),
            ("kd_xy", self.kd_xy),
            ("kp_z", self.kp_z),
            ("kd_z", self.kd_z),
            ("kr_xy", self.kr_xy),
            ("kw_xy", self.kw_xy),
            ("kr_z", self.kr_z),
            ("kw_z", self.kw_z),
        ] {
            check_gain(f, v)?;
        }
        for (f, v) in [
            ("ki_xy", self.ki_xy),
            ("i_range_xy", self.i_range_xy),
            ("ki_z", self.ki_z),
            ("i_range_z", self.i_range_z),
            ("ki_m_xy", self.ki_m_xy),
            ("i_range_m_xy", self.i_range_m_xy),
            ("ki_m_z", self.ki_m_z),
            ("i_range_m_z", self.i_range_m_z),
            ("kd_omega_rp", self.kd_omega_rp),
        ] {
            check_gain_or_zero(f, v)?;
        }
        self.motors.check()
    }
}

/// The firmware's Mellinger controller ([module docs](self)), one flight.
#[derive(Clone, Debug)]
pub struct Mellinger {
    model: QuadrotorParams,
    gains: MellingerGains,
    /// Position error integral, m·s.
    position_integral: Vec3,
    /// Attitude error integral `∫ −e_R dt`.
    attitude_integral: Vec3,
    /// `(ω_sp − ω)` of roll and pitch at the last update (`None`: first update).
    previous_rate_error: Option<[f64; 2]>,
    /// Thrust of the last update, 16-bit units.
    thrust: f64,
    outputs: Vec3,
    uncapped: [f64; 4],
    pwm: [f64; 4],
    telemetry: Telemetry,
}

/// `x` clamped to `±limit`.
fn clamp_sym(x: f64, limit: f64) -> f64 {
    x.clamp(-limit, limit)
}

impl Mellinger {
    /// Build after checking the nominal model (its thrust and moment
    /// coefficients and arm length map the commands to forces) and the gains.
    pub fn new(model: QuadrotorParams, gains: MellingerGains) -> Result<Self, GainError> {
        model.check()?;
        gains.check()?;
        Ok(Self::fresh(model, gains))
    }

    fn fresh(model: QuadrotorParams, gains: MellingerGains) -> Self {
        Self {
            model,
            gains,
            position_integral: [0.0; 3],
            attitude_integral: [0.0; 3],
            previous_rate_error: None,
            thrust: 0.0,
            outputs: [0.0; 3],
            uncapped: [0.0; 4],
            pwm: [0.0; 4],
            telemetry: Telemetry::default(),
        }
    }

    /// The gains in use.
    pub fn gains(&self) -> &MellingerGains {
        &self.gains
    }

    /// Motor commands m1…m4 of the last update (16-bit units).
    pub fn pwm(&self) -> [f64; 4] {
        self.pwm
    }

    /// Motor thrusts m1…m4 of the last update before the cap (16-bit
    /// units): what the firmware's battery compensation takes.
    pub fn uncapped(&self) -> [f64; 4] {
        self.uncapped
    }

    /// Thrust of the last update, 16-bit units (`ctrlMel.cmd_thrust`).
    pub fn thrust(&self) -> f64 {
        self.thrust
    }

    /// `[roll, pitch, yaw]` outputs of the last update (int16 units, the
    /// firmware's legacy signs).
    pub fn outputs(&self) -> Vec3 {
        self.outputs
    }

    /// One update of `dt` s (the firmware's 1/500 s); returns m1…m4.
    pub fn step(&mut self, s: &FirmwareState, reference: &Reference, dt: f64) -> [f64; 4] {
        let g = self.gains;
        let e_p: Vec3 = core::array::from_fn(|i| reference.position[i] - s.position[i]);
        let e_v: Vec3 = core::array::from_fn(|i| reference.velocity[i] - s.velocity[i]);
        let ranges = [g.i_range_xy, g.i_range_xy, g.i_range_z];
        for i in 0..3 {
            self.position_integral[i] = clamp_sym(self.position_integral[i] + e_p[i] * dt, ranges[i]);
        }
        let (kp, kd, ki) = ([g.kp_xy, g.kp_xy, g.kp_z], [g.kd_xy, g.kd_xy, g.kd_z], [g.ki_xy, g.ki_xy, g.ki_z]);
        let gravity = [0.0, 0.0, self.model.gravity];
        let force: Vec3 = core::array::from_fn(|i| {
            g.mass * (reference.acceleration[i] + gravity[i])
                + kp[i] * e_p[i]
                + kd[i] * e_v[i]
                + ki[i] * self.position_integral[i]
        });
        let r = rotation_from_quaternion(&s.quaternion);
        let z_body = [r[0][2], r[1][2], r[2][2]];
        let thrust_n = dot(&force, &z_body);
        let f = norm(&force);
        let z_d = if f > 0.0 { force.map(|x| x / f) } else { [0.0, 0.0, 1.0] };
        let yaw_deg = cap_angle(reference.yaw.to_degrees());
        let (sy, cy) = sin_cos(yaw_deg.to_radians());
        let y_d = cross(&z_d, &[cy, sy, 0.0]);
        let ny = norm(&y_d);
        let y_d = if ny > 0.0 { y_d.map(|x| x / ny) } else { [-sy, cy, 0.0] };
        let x_d = cross(&y_d, &z_d);
        let r_d = [[x_d[0], y_d[0], z_d[0]], [x_d[1], y_d[1], z_d[1]], [x_d[2], y_d[2], z_d[2]]];
        let a = mat_t_mat(&r_d, &r); // R_dᵀR; (R_dᵀR − RᵀR_d) = A − Aᵀ
        let e_r = [a[2][1] - a[1][2], a[0][2] - a[2][0], a[1][0] - a[0][1]];
        let w_sp = [0.0, 0.0, reference.yaw_rate];
        let e_w: Vec3 = core::array::from_fn(|i| w_sp[i] - s.body_rates[i]);
        let d_rate = match self.previous_rate_error {
            Some(prev) => [(e_w[0] - prev[0]) / dt, (e_w[1] - prev[1]) / dt],
            None => [0.0; 2],
        };
        self.previous_rate_error = Some([e_w[0], e_w[1]]);
        let ranges_m = [g.i_range_m_xy, g.i_range_m_xy, g.i_range_m_z];
        for i in 0..3 {
            self.attitude_integral[i] = clamp_sym(self.attitude_integral[i] - e_r[i] * dt, ranges_m[i]);
        }
        let (kr, kw, kim) = ([g.kr_xy, g.kr_xy, g.kr_z], [g.kw_xy, g.kw_xy, g.kw_z], [g.ki_m_xy, g.ki_m_xy, g.ki_m_z]);
        let kdw = [g.kd_omega_rp, g.kd_omega_rp, 0.0];
        let d3 = [d_rate[0], d_rate[1], 0.0];
        let moment: Vec3 = core::array::from_fn(|i| {
            -kr[i] * e_r[i] + kw[i] * e_w[i] + kim[i] * self.attitude_integral[i] + kdw[i] * d3[i]
        });
        self.thrust = g.mass_thrust * thrust_n;
        if self.thrust > 0.0 {
            let out = |x: f64| libm::trunc(clamp_sym(x, 32000.0));
            self.outputs = [out(moment[0]), out(-moment[1]), out(-moment[2])];
        } else {
            self.outputs = [0.0; 3];
            self.position_integral = [0.0; 3];
            self.attitude_integral = [0.0; 3];
        }
        let [roll, pitch, yaw] = self.outputs;
        self.uncapped = power_distribution_uncapped(self.thrust.max(0.0), roll, pitch, yaw);
        self.pwm = power_cap(self.uncapped, g.motors.idle_thrust);
        self.telemetry.commanded_acceleration = force.map(|x| x / g.mass);
        self.pwm
    }
}

firmware_controller!(Mellinger, "mellinger");

#[cfg(test)]
mod tests {
    use super::*;

    fn plant() -> QuadrotorParams {
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
    fn hover_asks_mass_thrust_times_the_weight_on_every_motor() {
        let mut c = Mellinger::new(plant(), MellingerGains::default()).unwrap();
        let pwm = c.step(&hover_state(), &hover_reference(), 0.002);
        let expected = (132000.0 * 0.029 * 9.81_f64).trunc();
        assert_eq!(pwm, [expected; 4]);
        assert_eq!(c.outputs(), [0.0; 3]);
    }

    #[test]
    fn each_loop_pushes_towards_its_set_point() {
        let g = MellingerGains::default();
        let torque = |s: FirmwareState, r: Reference| {
            let mut c = Mellinger::new(plant(), g).unwrap();
            let pwm = c.step(&s, &r, 0.002);
            g.motors.command(&plant(), &pwm)
        };
        let mut s = hover_state();
        s.position[2] = 0.9;
        let base = torque(hover_state(), hover_reference()).thrust;
        assert!(torque(s, hover_reference()).thrust > base);
        // Set-point ahead in +x: nose down (positive pitch moment); in +y:
        // negative roll moment; yaw ahead: positive yaw moment.
        let mut r = hover_reference();
        r.position[0] = 0.5;
        assert!(torque(hover_state(), r).torque[1] > 0.0);
        let mut r = hover_reference();
        r.position[1] = 0.5;
        assert!(torque(hover_state(), r).torque[0] < 0.0);
        let mut r = hover_reference();
        r.yaw = 0.3;
        assert!(torque(hover_state(), r).torque[2] > 0.0);
        // Body rates are damped.
        for axis in 0..3 {
            let mut s = hover_state();
            s.body_rates[axis] = 1.0;
            let t = torque(s, hover_reference()).torque;
            assert!(t[axis] < 0.0, "axis {axis}: {t:?}");
        }
    }

    #[test]
    fn outputs_saturate_and_a_negative_thrust_zeroes_them() {
        let mut c = Mellinger::new(plant(), MellingerGains::default()).unwrap();
        let mut s = hover_state();
        s.body_rates = [50.0, -50.0, 50.0];
        c.step(&s, &hover_reference(), 0.002);
        assert_eq!(c.outputs(), [-32000.0, -32000.0, 32000.0]);
        // Far above the set-point: the force points down, no thrust, no outputs.
        let mut s = hover_state();
        s.position[2] = 100.0;
        let mut c = Mellinger::new(plant(), MellingerGains::default()).unwrap();
        assert_eq!(c.step(&s, &hover_reference(), 0.002), [0.0; 4]);
        assert_eq!(c.outputs(), [0.0; 3]);
    }

    #[test]
    fn the_gain_check_names_the_field() {
        let g = MellingerGains { kw_xy: 0.0, ..Default::default() };
        assert_eq!(g.check().unwrap_err().field, "kw_xy");
        let g = MellingerGains { i_range_m_z: -1.0, ..Default::default() };
        assert_eq!(g.check().unwrap_err().field, "i_range_m_z");
    }
}
