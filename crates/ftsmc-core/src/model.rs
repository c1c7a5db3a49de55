//! Quadrotor physical parameters (paper Table 2, corrected) and the plain
//! data types that cross the controller boundary: state, reference, command.

use crate::lanes::Real;
use crate::law::{check_closed, check_gain, check_gain_or_zero, GainError};

/// Physical parameters of the quadrotor (paper Table 2 with the errata of
/// `docs/paper-errata.md`). The controller holds a nominal copy; the plant
/// may see a varied one.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Deserialize, serde::Serialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields, default))]
pub struct QuadrotorParams {
    /// Mass m, kg (default 0.74).
    pub mass: f64,
    /// Gravitational acceleration g, m/s² (default 9.81).
    pub gravity: f64,
    /// Principal moments of inertia `[I1, I2, I3]`, kg·m² (default
    /// `[3.827e-3, 3.827e-3, 7.6566e-3]`).
    pub inertia: [f64; 3],
    /// Rotor inertia J_r, kg·m² (default 2.8385e-5).
    pub rotor_inertia: f64,
    /// Translational drag `[K_f1x, K_f1y, K_f1z]`, N·s/m (default 5.567e-4 each).
    pub drag_translational: [f64; 3],
    /// Rotational drag `[K_f2x, K_f2y, K_f2z]`, N·m·s²/rad² (default 5.567e-4 each).
    pub drag_rotational: [f64; 3],
    /// Lift coefficient b, N·s²/rad² (Table 2 prints 2.9842e-3; 2.9842e-5 is meant).
    pub lift_coefficient: f64,
    /// Yaw drag coefficient d, N·m·s²/rad² (Table 2 prints K = 3.2320e-2; 3.2320e-7 is meant).
    pub yaw_drag_coefficient: f64,
    /// Arm length l, m (not given in the paper; default 0.21).
    pub arm_length: f64,
}

impl Default for QuadrotorParams {
    fn default() -> Self {
        Self {
            mass: 0.74,
            gravity: 9.81,
            inertia: [3.827e-3, 3.827e-3, 7.6566e-3],
            rotor_inertia: 2.8385e-5,
            drag_translational: [5.567e-4; 3],
            drag_rotational: [5.567e-4; 3],
            lift_coefficient: 2.9842e-5,
            yaw_drag_coefficient: 3.2320e-7,
            arm_length: 0.21,
        }
    }
}

impl QuadrotorParams {
    /// Reject non-physical values, with ranges bounded to where the
    /// cascade's cancellation terms are finite in f64 (mass, inertia and
    /// coefficients multiply accelerations up to 1e12 and rates up to 1e12;
    /// the rotor allocation divides by `b`, `b l` and `d`):
    ///
    /// | parameter | range |
    /// |---|---|
    /// | mass (kg) | `[1e-6, 1e6]` |
    /// | gravity (m/s²) | `[1e-3, 1e3]` (the cascade divides by `1e-3 m g`) |
    /// | inertia (kg·m²) | `(0, 1e6]` |
    /// | rotor inertia, drag coefficients | `[0, 1e6]` |
    /// | lift coefficient b, yaw drag coefficient d | `[1e-12, 1e6]` |
    /// | arm length l (m) | `[1e-6, 1e6]` |
    pub fn check(&self) -> Result<(), GainError> {
        check_closed(
            "mass",
            self.mass,
            1e-6,
            1e6,
            "1e-6 <= mass <= 1e6 kg (outside, the cascade's products overflow)",
        )?;
        check_closed(
            "gravity",
            self.gravity,
            1e-3,
            1e3,
            "1e-3 <= gravity <= 1e3 m/s^2 (the cascade divides by 1e-3 m g)",
        )?;
        const INERTIA: [&str; 3] = ["inertia[0]", "inertia[1]", "inertia[2]"];
        for (name, &value) in INERTIA.iter().zip(&self.inertia) {
            check_gain(name, value)?;
        }
        check_gain_or_zero("rotor_inertia", self.rotor_inertia)?;
        const DT: [&str; 3] = ["drag_translational[0]", "drag_translational[1]", "drag_translational[2]"];
        const DR: [&str; 3] = ["drag_rotational[0]", "drag_rotational[1]", "drag_rotational[2]"];
        for i in 0..3 {
            check_gain_or_zero(DT[i], self.drag_translational[i])?;
            check_gain_or_zero(DR[i], self.drag_rotational[i])?;
        }
        const COEFFICIENT: &str = "1e-12 <= value <= 1e6 (the rotor allocation divides by it)";
        check_closed("lift_coefficient", self.lift_coefficient, 1e-12, 1e6, COEFFICIENT)?;
        check_closed("yaw_drag_coefficient", self.yaw_drag_coefficient, 1e-12, 1e6, COEFFICIENT)?;
        check_closed(
            "arm_length",
            self.arm_length,
            1e-6,
            1e6,
            "1e-6 <= arm_length <= 1e6 m (the allocation divides by b l)",
        )
    }

    /// Hover rotor speed `sqrt(m g / (4 b))`, rad/s (≈ 247 rad/s by default).
    pub fn hover_rotor_speed(&self) -> f64 {
        crate::math::sqrt(self.mass * self.gravity / (4.0 * self.lift_coefficient))
    }
}

/// The 12-dimensional state of paper Eq. 1 (world frame, z up, Z-Y-X Euler),
/// of one flight (`R = f64`) or of several side by side ([`crate::lanes`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct QuadState<R = f64> {
    /// Position `[x, y, z]`, m.
    pub position: [R; 3],
    /// Euler angles `[φ, θ, ψ]` (roll, pitch, yaw), rad.
    pub attitude: [R; 3],
    /// Velocity `[ẋ, ẏ, ż]`, m/s.
    pub velocity: [R; 3],
    /// Euler-angle rates `[φ̇, θ̇, ψ̇]`, rad/s.
    pub angular_rate: [R; 3],
}
crate::lanewise_struct!(QuadState { position, attitude, velocity, angular_rate });

impl<R: Real> QuadState<R> {
    /// True (per lane) when all twelve components are finite (branch-free,
    /// [`crate::math::finite_probe`]).
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn is_finite(&self) -> R::Mask {
        use crate::math::finite_probe;
        (finite_probe(&self.position)
            + finite_probe(&self.attitude)
            + finite_probe(&self.velocity)
            + finite_probe(&self.angular_rate))
        .eq(R::splat(0.0))
    }
}

impl QuadState {
    /// Flatten to `[x, y, z, φ, θ, ψ, ẋ, ẏ, ż, φ̇, θ̇, ψ̇]`.
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn to_array(&self) -> [f64; 12] {
        let mut a = [0.0; 12];
        a[0..3].copy_from_slice(&self.position);
        a[3..6].copy_from_slice(&self.attitude);
        a[6..9].copy_from_slice(&self.velocity);
        a[9..12].copy_from_slice(&self.angular_rate);
        a
    }

    /// Inverse of [`QuadState::to_array`].
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn from_array(a: &[f64; 12]) -> Self {
        Self {
            position: [a[0], a[1], a[2]],
            attitude: [a[3], a[4], a[5]],
            velocity: [a[6], a[7], a[8]],
            angular_rate: [a[9], a[10], a[11]],
        }
    }
}

/// Desired trajectory at one instant (position with two derivatives, yaw
/// with two derivatives); roll and pitch references are produced by the
/// cascade (Eq. 52).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Reference<R = f64> {
    /// `[x_d, y_d, z_d]`, m.
    pub position: [R; 3],
    /// `[ẋ_d, ẏ_d, ż_d]`, m/s.
    pub velocity: [R; 3],
    /// `[ẍ_d, ÿ_d, z̈_d]`, m/s².
    pub acceleration: [R; 3],
    /// ψ_d, rad.
    pub yaw: R,
    /// ψ̇_d, rad/s.
    pub yaw_rate: R,
    /// ψ̈_d, rad/s².
    pub yaw_acceleration: R,
}
crate::lanewise_struct!(Reference { position, velocity, acceleration, yaw, yaw_rate, yaw_acceleration });

/// Control command: total thrust and body torques (paper Eq. 2).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Command<R = f64> {
    /// Total thrust U1, N.
    pub thrust: R,
    /// Torques `[u2, u3, u4]` about the roll, pitch, yaw axes, N·m.
    pub torque: [R; 3],
}
crate::lanewise_struct!(Command { thrust, torque });
