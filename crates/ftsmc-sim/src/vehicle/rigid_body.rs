//! Rigid-body truth model: Newton–Euler dynamics with quaternion attitude,
//! body rates, per-rotor forces and RotorPy-style aerodynamics.
//!
//! # Conventions
//!
//! - World frame: x, y horizontal, **z up** (gravity `−g ẑ`), as the paper
//!   plant ([`crate::vehicle::paper`]).
//! - Body frame: x forward, y left, z up (thrust along `+z_b`).
//! - Attitude: unit quaternion `q = [w, x, y, z]` (scalar first, Hamilton
//!   product) rotating body vectors into the world: `v_w = R(q) v_b`.
//!   Kinematics `q̇ = ½ q ⊗ (0, Ω)`.
//! - Ω: body rates (rad/s) expressed in the body frame.
//! - Euler angles: Z-Y-X (yaw ψ, then pitch θ, then roll φ),
//!   `R = R_z(ψ) R_y(θ) R_x(φ)`, the convention of the paper's Eq. 1 (its
//!   thrust direction is the third column of this `R`).
//! - Rotors: numbering, positions and spin directions of paper Eq. 2
//!   ([`ftsmc_core::allocation`]), see [`Configuration`] and [`Spin`].
//!
//! # Trigonometry
//!
//! The conversions below are those of `ftsmc_core::kinematics` (the one
//! Euler/quaternion module of the controllers, the simulator and Python),
//! on the one maths library of `ftsmc_core::math`: the same bits on every
//! CPU. One exception, for speed: the Euler rates of [`to_quad_state`] and
//! [`try_to_quad_state`] evaluate the core's formula
//! ([`kinematics::euler_rates_from_body_rates_with`]) with the sines and cosines of
//! roll and pitch read off the quaternion instead of `sin_cos` of the
//! angles (the same values to rounding; the core's formula near gimbal lock).
//!
//! # State
//!
//! `[p (3), v (3), q (4), Ω (3)]` = 13 numbers, world position (m), world
//! velocity (m/s), quaternion, body rates (rad/s); see [`index`]. The array
//! goes through the generic [`crate::vehicle::paper::rk4_step`].
//!
//! # Lanes
//!
//! [`RigidBody`], its inputs, the derivative and [`normalize_quaternion`]
//! are generic over the number type ([`ftsmc_core::lanes::Real`], `f64` by
//! default): on `Lanes<N>` they fly `N` vehicles side by side, every
//! parameter (mass, inertia and its inverse, arm length and layout, spin
//! directions, rotor and aerodynamic coefficients) one lane per vehicle.
//! Where the one-flight body skips a term it does not have (diagonal
//! inertia, rotor aerodynamics, translational lift, parasitic drag), lanes
//! skip it per lane, so lane `i` computes the one-flight body's operations
//! in the same order: the same bits. So is [`to_quad_state`]; the other
//! Euler conversions below are one-flight (`f64`).
//!
//! # Equations (body wrench in the body frame)
//!
//! ```text
//! ṗ = v
//! v̇ = (R F_b + F_ext)/m − g ẑ
//! q̇ = ½ q ⊗ (0, Ω)
//! Ω̇ = J⁻¹ (M_b + τ_ext − Ω × (J Ω) − Ω × h_r)
//!
//! v_a = Rᵀ(v − w)                       air-relative velocity, body frame
//! v_i = v_a + Ω × r_i                    local air velocity at rotor i
//! T_i = k_f ω_i² ẑ                       thrust
//! H_i = −ω_i diag(k_d, k_d, k_z) v_i     rotor drag (H force)
//! D   = −‖v_a‖ diag(c_D) v_a             parasitic drag
//! F_b = Σ (T_i + H_i) + D
//! M_b = Σ r_i × (T_i + H_i) − Σ s_i k_m ω_i² ẑ
//! h_r = J_r Σ s_i ω_i ẑ                  rotor angular momentum
//! ```
//!
//! `s_i = +1` for a rotor spinning counter-clockwise seen from above (spin
//! vector `+z_b`), −1 clockwise. The reaction (drag) torque a rotor puts on
//! the body opposes its spin, hence `−s_i k_m ω_i²`. The aerodynamic terms
//! are those of RotorPy `multirotor.py` (`compute_body_wrench`; translational
//! lift and flapping moments are not modelled). The torque `J_r Σ s_i ω̇_i ẑ`
//! from rotor acceleration is neglected (the rotor speeds are an input).
//!
//! # The gyroscopic sign against the paper plant
//!
//! The paper's yaw allocation `u4 = d(ω1² − ω2² + ω3² − ω4²)` makes rotors 1
//! and 3 put a `+z` reaction torque on the body, so they spin clockwise
//! (`s = [−1, +1, −1, +1]`) and `h_r = −J_r Ω̄ ẑ` with `Ω̄ = ω1 − ω2 + ω3 − ω4`.
//! The paper plant (errata E5) uses `h_r = +J_r Ω̄ ẑ`; its gyroscopic torques
//! therefore have the opposite sign to this model's. The test
//! `gyroscopic_torque_is_opposite_to_the_paper_plant` pins this down.

use ftsmc_core::kinematics;
use ftsmc_core::lanes::{branch, Lanewise, Mask, Real};
use ftsmc_core::law::GainError;
use ftsmc_core::model::{QuadState, QuadrotorParams};
use ftsmc_core::rotor_layout::RotorGeometry;
use serde::{Deserialize, Serialize};

use super::math::{
    add, cross, det3, inverse3, inverse3_positive, mat_t_vec, mat_vec, norm, quat_derivative, rotation, sub, Mat3,
    Quat, Vec3,
};
use crate::vehicle::paper::rk4_step;

/// Length of the rigid-body state array.
pub const STATE_LEN: usize = 13;

/// The rigid-body state `[p, v, q, Ω]` (see [`index`]): of one flight
/// (`f64`, the default) or of flights in lanes.
pub type RigidBodyState<R = f64> = [R; STATE_LEN];

/// Index of the first component of each block of [`RigidBodyState`].
pub mod index {
    /// World position `[x, y, z]`, m.
    pub const POSITION: usize = 0;
    /// World velocity `[ẋ, ẏ, ż]`, m/s.
    pub const VELOCITY: usize = 3;
    /// Attitude quaternion `[w, x, y, z]` (body → world).
    pub const QUATERNION: usize = 6;
    /// Body rates `[p, q, r]`, rad/s.
    pub const BODY_RATES: usize = 10;
}

/// Rotor layout. Both keep the numbering and spin pattern of paper Eq. 2
/// (rotors 1 and 3 on one diagonal, 2 and 4 on the other).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Configuration {
    /// "+" layout of paper Eq. 2: rotor 1 at `(l, 0)`, 2 at `(0, −l)`,
    /// 3 at `(−l, 0)`, 4 at `(0, l)` (body x, y), so that
    /// `u2 = b l (ω4² − ω2²)` and `u3 = b l (ω3² − ω1²)`.
    Plus,
    /// "×" layout: the "+" layout turned by +45° about z: rotor 1 at
    /// `l(1, 1)/√2`, 2 at `l(1, −1)/√2`, 3 at `l(−1, −1)/√2`, 4 at
    /// `l(−1, 1)/√2` — RotorPy's `crazyflie_params.py` / `hummingbird_params.py` layout.
    Cross,
    /// Any planar layout: rotor `i` at [`RigidBodyParams::rotor_positions`]'s
    /// entry `i` (`[vehicle] rotor_positions`; the arm length is not used).
    Custom,
}

/// Spin direction of a rotor, seen from above (from `+z_b`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Spin {
    /// Counter-clockwise: spin vector `+z_b`, reaction torque on the body `−z_b`.
    Ccw,
    /// Clockwise: spin vector `−z_b`, reaction torque on the body `+z_b`.
    Cw,
}

impl Spin {
    /// `s_i`: +1 counter-clockwise, −1 clockwise.
    pub fn sign(self) -> f64 {
        match self {
            Spin::Ccw => 1.0,
            Spin::Cw => -1.0,
        }
    }
}

/// Spin directions implied by paper Eq. 2's yaw row `u4 = d(ω1² − ω2² + ω3² − ω4²)`:
/// rotors 1 and 3 turn the body counter-clockwise, so they spin clockwise.
pub const PAPER_SPIN: [Spin; 4] = [Spin::Cw, Spin::Ccw, Spin::Cw, Spin::Ccw];

/// Physical parameters of the rigid-body model. Defaults: the paper vehicle
/// ([`RigidBodyParams::from_paper`] of `QuadrotorParams::default()`, aerodynamics off).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct RigidBodyParams {
    /// Mass m, kg (default 0.74, paper Table 2).
    pub mass: f64,
    /// Gravitational acceleration g, m/s² (default 9.81).
    pub gravity: f64,
    /// Inertia matrix J about the centre of mass in body axes, kg·m²;
    /// symmetric positive definite (default `diag(3.827e-3, 3.827e-3, 7.6566e-3)`, paper Table 2).
    pub inertia: [[f64; 3]; 3],
    /// Distance l from the centre of mass to each rotor hub, m (default 0.21, ftsmc's paper choice).
    pub arm_length: f64,
    /// Rotor layout (default `plus`, paper Eq. 2).
    pub configuration: Configuration,
    /// Hub `(x, y)` of rotors 1..4 in body axes, m: given exactly when
    /// `configuration` is [`Configuration::Custom`] (default none). A
    /// scenario sets it as `[vehicle] rotor_positions`
    /// ([`crate::vehicle::VehicleSettings`]); the deprecated `[rigid_body]`
    /// section has no such key.
    #[serde(skip)]
    pub custom_positions: Option<[[f64; 2]; 4]>,
    /// Spin direction of rotors 1..4 (default `["cw", "ccw", "cw", "ccw"]`, [`PAPER_SPIN`]).
    pub spin: [Spin; 4],
    /// Thrust coefficient k_f (per rotor `T = k_f ω²`), N·s²/rad²
    /// (default 2.9842e-5, paper b).
    pub thrust_coefficient: f64,
    /// Drag-torque coefficient k_m (per rotor `|Q| = k_m ω²`), N·m·s²/rad²
    /// (default 3.2320e-7, paper d).
    pub moment_coefficient: f64,
    /// Rotor (plus motor rotor) inertia J_r about its spin axis, kg·m² (default 2.8385e-5, paper Table 2).
    pub rotor_inertia: f64,
    /// Parasitic drag coefficients `[c_Dx, c_Dy, c_Dz]` in body axes, N·s²/m²
    /// (default 0; RotorPy Hummingbird: `[0.5e-2, 0.5e-2, 1e-2]`).
    pub parasitic_drag: [f64; 3],
    /// In-plane rotor drag coefficient k_d, N·s²/(m·rad) (default 0; RotorPy
    /// Crazyflie 1.02506e-6, Hummingbird 1.19e-4).
    pub rotor_drag_xy: f64,
    /// Axial rotor drag (induced inflow) coefficient k_z, N·s²/(m·rad)
    /// (default 0; RotorPy Crazyflie 7.553e-7, Hummingbird 2.32e-4).
    pub rotor_drag_z: f64,
    /// Translational lift coefficient k_h, N·s²/m² (= kg/m): each rotor's
    /// thrust grows by `k_h (v_x² + v_y²)` with the in-plane components of its
    /// local airspeed in body axes (body airspeed plus `Ω × r_i`), as RotorPy's
    /// `compute_body_wrench` models translational lift (default 0, off; RotorPy
    /// Hummingbird 3.39e-3, Crazyflie 0).
    pub translational_lift: f64,
}

impl Default for RigidBodyParams {
    fn default() -> Self {
        Self::from_paper(&QuadrotorParams::default())
    }
}

fn diag(d: [f64; 3]) -> Mat3 {
    [[d[0], 0.0, 0.0], [0.0, d[1], 0.0], [0.0, 0.0, d[2]]]
}

fn closed(field: &'static str, value: f64, lo: f64, hi: f64, expected: &'static str) -> Result<(), GainError> {
    if (lo..=hi).contains(&value) {
        Ok(())
    } else {
        Err(GainError { field, value, expected })
    }
}

impl RigidBodyParams {
    /// The paper vehicle: `k_f = b`, `k_m = d`, J_r, l, mass, gravity and the
    /// diagonal inertia of `p`, "+" layout with [`PAPER_SPIN`]; aerodynamics
    /// off (the paper's linear drags `K_f1`, `K_f2` have no counterpart here).
    /// With these, small angles and `J_r = 0`, the model agrees with
    /// [`crate::vehicle::paper::derivative`] (see the module docs for the gyroscopic sign).
    pub fn from_paper(p: &QuadrotorParams) -> Self {
        Self {
            mass: p.mass,
            gravity: p.gravity,
            inertia: diag(p.inertia),
            arm_length: p.arm_length,
            configuration: Configuration::Plus,
            custom_positions: None,
            spin: PAPER_SPIN,
            thrust_coefficient: p.lift_coefficient,
            moment_coefficient: p.yaw_drag_coefficient,
            rotor_inertia: p.rotor_inertia,
            parasitic_drag: [0.0; 3],
            rotor_drag_xy: 0.0,
            rotor_drag_z: 0.0,
            translational_lift: 0.0,
        }
    }

    /// Crazyflie 2.0 as RotorPy `rotorpy/vehicles/crazyflie_params.py` gives
    /// it (Forster 2015 system identification): m 0.03 kg, J diag(1.43e-5,
    /// 1.43e-5, 2.89e-5) kg·m², l 0.043 m "×", k_f 2.3e-8, k_m 7.8e-10,
    /// k_d 1.02506e-6, k_z 7.553e-7, c_D 0. RotorPy has no rotor inertia;
    /// J_r is 0 here.
    pub fn crazyflie() -> Self {
        Self {
            mass: 0.03,
            gravity: 9.81,
            inertia: diag([1.43e-5, 1.43e-5, 2.89e-5]),
            arm_length: 0.043,
            configuration: Configuration::Cross,
            custom_positions: None,
            spin: PAPER_SPIN,
            thrust_coefficient: 2.3e-8,
            moment_coefficient: 7.8e-10,
            rotor_inertia: 0.0,
            parasitic_drag: [0.0; 3],
            rotor_drag_xy: 1.02506e-6,
            rotor_drag_z: 7.553e-7,
            translational_lift: 0.0,
        }
    }

    /// AscTec Hummingbird as RotorPy `rotorpy/vehicles/hummingbird_params.py`
    /// gives it: m 0.5 kg, J diag(3.65e-3, 3.68e-3, 7.03e-3) kg·m², l 0.17 m
    /// "×", k_f 5.57e-6, k_m 1.36e-7, k_d 1.19e-4, k_z 2.32e-4, k_h 3.39e-3,
    /// c_D (0.5e-2, 0.5e-2, 1e-2). J_r is 0 (not in RotorPy).
    pub fn hummingbird() -> Self {
        Self {
            mass: 0.5,
            gravity: 9.81,
            inertia: diag([3.65e-3, 3.68e-3, 7.03e-3]),
            arm_length: 0.17,
            configuration: Configuration::Cross,
            custom_positions: None,
            spin: PAPER_SPIN,
            thrust_coefficient: 5.57e-6,
            moment_coefficient: 1.36e-7,
            rotor_inertia: 0.0,
            parasitic_drag: [0.5e-2, 0.5e-2, 1e-2],
            rotor_drag_xy: 1.19e-4,
            rotor_drag_z: 2.32e-4,
            translational_lift: 3.39e-3,
        }
    }

    /// Reject non-physical values:
    ///
    /// | parameter | range |
    /// |---|---|
    /// | mass (kg) | `[1e-6, 1e6]` |
    /// | gravity (m/s²) | `[0, 1e3]` |
    /// | inertia (kg·m²) | finite, symmetric (to 1e-12 relative), positive definite |
    /// | arm length (m) | `[1e-6, 1e6]` |
    /// | thrust, moment coefficients | `[1e-12, 1e6]` (the mixer divides by them) |
    /// | rotor inertia, drag and translational-lift coefficients | `[0, 1e6]` |
    pub fn check(&self) -> Result<(), GainError> {
        self.check_mass_inertia()?;
        self.check_rest()
    }

    /// The mass, gravity and inertia rows of [`RigidBodyParams::check`], in
    /// its order; on success the inertia inverse.
    fn check_mass_inertia(&self) -> Result<Mat3, GainError> {
        closed("mass", self.mass, 1e-6, 1e6, "1e-6 <= mass <= 1e6 kg")?;
        closed("gravity", self.gravity, 0.0, 1e3, "0 <= gravity <= 1e3 m/s^2")?;
        const NAMES: [[&str; 3]; 3] = [
            ["inertia[0][0]", "inertia[0][1]", "inertia[0][2]"],
            ["inertia[1][0]", "inertia[1][1]", "inertia[1][2]"],
            ["inertia[2][0]", "inertia[2][1]", "inertia[2][2]"],
        ];
        let j = &self.inertia;
        let scale = j[0][0].abs().max(j[1][1].abs()).max(j[2][2].abs());
        for r in 0..3 {
            for c in 0..3 {
                closed(NAMES[r][c], j[r][c], -1e6, 1e6, "a finite inertia entry, |J_ij| <= 1e6 kg m^2")?;
                if c > r && (j[r][c] - j[c][r]).abs() > 1e-12 * scale {
                    return Err(GainError {
                        field: NAMES[r][c],
                        value: j[r][c],
                        expected: "a symmetric inertia matrix (J_ij = J_ji)",
                    });
                }
            }
        }
        const PD: &str = "a positive definite inertia matrix (leading minors > 0)";
        let minor2 = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        if j[0][0] <= 0.0 {
            return Err(GainError { field: "inertia[0][0]", value: j[0][0], expected: PD });
        }
        if minor2 <= 0.0 {
            return Err(GainError { field: "inertia[1][1]", value: j[1][1], expected: PD });
        }
        match inverse3(j) {
            Some(inv) if det3(j) > 0.0 => Ok(inv),
            _ => Err(GainError { field: "inertia[2][2]", value: j[2][2], expected: PD }),
        }
    }

    /// The rows of [`RigidBodyParams::check`] after the inertia.
    fn check_rest(&self) -> Result<(), GainError> {
        closed("arm_length", self.arm_length, 1e-6, 1e6, "1e-6 <= arm_length <= 1e6 m")?;
        match (self.configuration, self.custom_positions) {
            (Configuration::Custom, None) => {
                return Err(GainError {
                    field: "rotor_positions",
                    value: f64::NAN,
                    expected: "four rotor positions [[x, y], ..] (m) with configuration = \"custom\"",
                })
            }
            (Configuration::Custom, Some(p)) => {
                const NAMES: [[&str; 2]; 4] = [
                    ["rotor_positions[0][0]", "rotor_positions[0][1]"],
                    ["rotor_positions[1][0]", "rotor_positions[1][1]"],
                    ["rotor_positions[2][0]", "rotor_positions[2][1]"],
                    ["rotor_positions[3][0]", "rotor_positions[3][1]"],
                ];
                for (names, xy) in NAMES.iter().zip(&p) {
                    for (name, &v) in names.iter().zip(xy) {
                        closed(name, v, -1e6, 1e6, "a finite position, |x|, |y| <= 1e6 m")?;
                    }
                }
                if self.geometry().px4_torque_scale(1.0, 1.0).is_none() {
                    return Err(GainError {
                        field: "rotor_positions",
                        value: p[0][0],
                        expected: "rotors that can roll, pitch and yaw the vehicle (an invertible allocation: not all on one line, spins not all alike)",
                    });
                }
            }
            (_, Some(p)) => {
                return Err(GainError {
                    field: "rotor_positions",
                    value: p[0][0],
                    expected: "rotor positions only with configuration = \"custom\"",
                })
            }
            (_, None) => {}
        }
        const COEF: &str = "1e-12 <= value <= 1e6 (the mixer divides by it)";
        closed("thrust_coefficient", self.thrust_coefficient, 1e-12, 1e6, COEF)?;
        closed("moment_coefficient", self.moment_coefficient, 1e-12, 1e6, COEF)?;
        const NONNEG: &str = "0 <= value <= 1e6";
        closed("rotor_inertia", self.rotor_inertia, 0.0, 1e6, NONNEG)?;
        const CD: [&str; 3] = ["parasitic_drag[0]", "parasitic_drag[1]", "parasitic_drag[2]"];
        for (name, &v) in CD.iter().zip(&self.parasitic_drag) {
            closed(name, v, 0.0, 1e6, NONNEG)?;
        }
        closed("rotor_drag_xy", self.rotor_drag_xy, 0.0, 1e6, NONNEG)?;
        closed("rotor_drag_z", self.rotor_drag_z, 0.0, 1e6, NONNEG)?;
        closed("translational_lift", self.translational_lift, 0.0, 1e6, NONNEG)
    }

    /// Rotor hub positions `r_i` in body axes, m (all in the plane z_b = 0).
    pub fn rotor_positions(&self) -> [[f64; 3]; 4] {
        let l = self.arm_length;
        match self.configuration {
            Configuration::Plus => [[l, 0.0, 0.0], [0.0, -l, 0.0], [-l, 0.0, 0.0], [0.0, l, 0.0]],
            Configuration::Cross => {
                let a = l * core::f64::consts::FRAC_1_SQRT_2;
                [[a, a, 0.0], [a, -a, 0.0], [-a, -a, 0.0], [-a, a, 0.0]]
            }
            Configuration::Custom => self.custom_positions.unwrap_or_default().map(|[x, y]| [x, y, 0.0]),
        }
    }

    /// The layout as [`ftsmc_core::rotor_layout`] takes it (the positions of
    /// [`RigidBodyParams::rotor_positions`], the spins of [`RigidBodyParams::spin`]):
    /// "+" and "×" with the paper's spins keep their closed forms.
    pub fn geometry(&self) -> RotorGeometry {
        let arm_length = self.arm_length;
        match self.configuration {
            Configuration::Plus if self.spin == PAPER_SPIN => RotorGeometry::Plus { arm_length },
            Configuration::Cross if self.spin == PAPER_SPIN => RotorGeometry::Cross { arm_length },
            _ => RotorGeometry::Custom {
                positions: self.rotor_positions().map(|[x, y, _]| [x, y]),
                spin: self.spin.map(Spin::sign),
            },
        }
    }

    /// Static allocation matrix `A` (aerodynamics off): `[U1, u2, u3, u4]ᵀ = A [ω1², ω2², ω3², ω4²]ᵀ`
    /// with U1 in N and torques in N·m. For the paper vehicle it is paper Eq. 2
    /// ([`ftsmc_core::allocation::forces_from_squared_speeds`]).
    pub fn allocation_matrix(&self) -> [[f64; 4]; 4] {
        let r = self.rotor_positions();
        let kf = self.thrust_coefficient;
        let km = self.moment_coefficient;
        let mut a = [[0.0; 4]; 4];
        for i in 0..4 {
            a[0][i] = kf;
            a[1][i] = kf * r[i][1]; // (r × k_f ẑ)_x = r_y k_f
            a[2][i] = -kf * r[i][0]; // (r × k_f ẑ)_y = −r_x k_f
            a[3][i] = -self.spin[i].sign() * km;
        }
        a
    }

    /// Rotor speed at which the four rotors together carry the weight, rad/s:
    /// `sqrt(m g / (4 k_f))`.
    pub fn hover_rotor_speed(&self) -> f64 {
        (self.mass * self.gravity / (4.0 * self.thrust_coefficient)).sqrt()
    }
}

/// Inputs held constant over an integration step, for one flight (`f64`) or
/// for flights in lanes (each number one lane per flight).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RigidBodyInput<R: Real = f64> {
    /// Rotor speeds `ω_i ≥ 0`, rad/s (magnitudes; the direction is [`RigidBodyParams::spin`]).
    pub rotor_speeds: [R; 4],
    /// Wind velocity w in the world frame, m/s.
    pub wind: [R; 3],
    /// External force in the world frame (disturbance, payload), N.
    pub force: [R; 3],
    /// External torque in the body frame, N·m.
    pub torque: [R; 3],
}

ftsmc_core::lanewise_struct!(RigidBodyInput { rotor_speeds, wind, force, torque });

/// [`RigidBodyInput`] with the terms of the body wrench that depend on the
/// rotor speeds alone worked out ([`RigidBody::prepare`]): once per RK4
/// stage time instead of once per derivative.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PreparedInput<R: Real = f64> {
    /// The inputs.
    pub input: RigidBodyInput<R>,
    /// Thrust per rotor `k_f ω_i²`, N.
    thrust: [R; 4],
    /// Reaction torque per rotor `s_i k_m ω_i²`, N·m.
    reaction: [R; 4],
    /// In-plane rotor drag per unit airspeed `ω_i k_d`, N·s/m.
    drag_xy: [R; 4],
    /// Axial rotor drag per unit airspeed `ω_i k_z`, N·s/m.
    drag_z: [R; 4],
    /// Rotor angular momentum `h_r` ([`RigidBody::rotor_momentum`]), kg·m²/s.
    momentum: [R; 3],
}

/// Force and moment in the body frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Wrench<R: Real = f64> {
    /// Force, N (body frame).
    pub force: [R; 3],
    /// Moment about the centre of mass, N·m (body frame).
    pub torque: [R; 3],
}

/// The rigid-body model: checked parameters with the inertia inverse and the
/// rotor geometry precomputed, for one flight (`RigidBody<f64>`, the
/// default) or for flights in lanes (`RigidBody<Lanes<N>>`: every number,
/// and every yes/no derived from one, one lane per flight, so each lane may
/// fly its own vehicle). Lane `i` of a lanes body computes exactly what the
/// one-flight body of lane `i`'s parameters computes, bit for bit
/// ([`ftsmc_core::lanes`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigidBody<R: Real = f64> {
    /// Mass m, kg.
    mass: R,
    /// Gravitational acceleration g, m/s².
    gravity: R,
    /// Inertia J, kg·m².
    inertia: Mat3<R>,
    /// J⁻¹, 1/(kg·m²).
    inertia_inv: Mat3<R>,
    /// The inertia (and so its inverse) has zero products of inertia: the
    /// products `J Ω` and `J⁻¹ M` skip the zero entries.
    diagonal: R::Mask,
    /// Arm length l, m.
    arm_length: R,
    /// The "×" layout ([`Configuration::Cross`]).
    cross_layout: R::Mask,
    /// A custom layout ([`Configuration::Custom`]); "+" when neither mask is set.
    custom_layout: R::Mask,
    /// Rotor hub positions, all with `z = 0` ([`RigidBodyParams::rotor_positions`]), m.
    rotors: [Vec3<R>; 4],
    /// Spin signs `s_i` ([`Spin::sign`]).
    spin: [R; 4],
    /// k_f, N·s²/rad².
    thrust_coefficient: R,
    /// k_m, N·m·s²/rad².
    moment_coefficient: R,
    /// J_r, kg·m².
    rotor_inertia: R,
    /// c_D, N·s²/m².
    parasitic_drag: [R; 3],
    /// k_d, N·s²/(m·rad).
    rotor_drag_xy: R,
    /// k_z, N·s²/(m·rad).
    rotor_drag_z: R,
    /// k_h, N·s²/m².
    translational_lift: R,
    /// Some rotor aerodynamics: `k_d`, `k_z` or `k_h` nonzero.
    rotor_aero: R::Mask,
    /// `k_h` nonzero.
    lift: R::Mask,
    /// Some `c_D` nonzero.
    parasitic: R::Mask,
}

ftsmc_core::lanewise_struct!(RigidBody {
    mass,
    gravity,
    inertia,
    inertia_inv,
    diagonal,
    arm_length,
    cross_layout,
    custom_layout,
    rotors,
    spin,
    thrust_coefficient,
    moment_coefficient,
    rotor_inertia,
    parasitic_drag,
    rotor_drag_xy,
    rotor_drag_z,
    translational_lift,
    rotor_aero,
    lift,
    parasitic,
});

/// No products of inertia, each one `+0.0` bit for bit (not `−0.0`): what
/// [`RigidBody::set_mass_and_scaled_diagonal_inertia_in_lane`] takes.
pub(crate) fn has_plain_diagonal(j: &Mat3) -> bool {
    (0..3).all(|r| (0..3).all(|c| r == c || j[r][c].to_bits() == 0))
}

/// The range in which the per-lane mass and inertia setters take their
/// fast path: a positive finite `scale`, `mass` in [1e-6, 1e6] kg and every
/// given inertia entry in [−1e6, 1e6] kg·m². Anything else goes to the full
/// check, which accepts or refuses it with its reason.
fn in_fast_range(mass: f64, scale: f64, mut inertia: impl Iterator<Item = f64>) -> bool {
    scale > 0.0 && scale.is_finite() && (1e-6..=1e6).contains(&mass) && inertia.all(|v| (-1e6..=1e6).contains(&v))
}

/// No products of inertia: every off-diagonal entry is zero.
fn is_diagonal(j: &Mat3) -> bool {
    j[0][1] == 0.0 && j[0][2] == 0.0 && j[1][0] == 0.0 && j[1][2] == 0.0 && j[2][0] == 0.0 && j[2][1] == 0.0
}

/// `m v`, or where `diagonal` only the diagonal of `m` times `v`: the same
/// values (the skipped products are zeros added to a sum). Per lane for
/// lanes ([`branch`]: each product only if some lane needs it).
#[cfg_attr(not(debug_assertions), inline(always))]
fn mat_vec_or_diagonal<R: Real>(m: &Mat3<R>, diagonal: R::Mask, v: Vec3<R>) -> Vec3<R> {
    branch(
        diagonal,
        #[cfg_attr(not(debug_assertions), inline(always))]
        || [m[0][0] * v[0], m[1][1] * v[1], m[2][2] * v[2]],
        #[cfg_attr(not(debug_assertions), inline(always))]
        || mat_vec(m, v),
    )
}

/// `a × r` for a rotor position `r` with `r_z = 0` (the terms with `r_z`
/// are zeros).
#[cfg_attr(not(debug_assertions), inline(always))]
fn cross_rotor<R: Real>(a: Vec3<R>, r: Vec3<R>) -> Vec3<R> {
    [-(a[2] * r[1]), a[2] * r[0], a[0] * r[1] - a[1] * r[0]]
}

/// `r × f` for a rotor position `r` with `r_z = 0`.
#[cfg_attr(not(debug_assertions), inline(always))]
fn rotor_cross<R: Real>(r: Vec3<R>, f: Vec3<R>) -> Vec3<R> {
    [r[1] * f[2], -(r[0] * f[2]), r[0] * f[1] - r[1] * f[0]]
}

impl RigidBody<f64> {
    /// Check the parameters and precompute.
    pub fn new(params: RigidBodyParams) -> Result<Self, GainError> {
        params.check()?;
        let inertia_inv = inverse3(&params.inertia).expect("checked positive definite");
        let p = &params;
        Ok(Self {
            mass: p.mass,
            gravity: p.gravity,
            inertia: p.inertia,
            inertia_inv,
            diagonal: is_diagonal(&p.inertia),
            arm_length: p.arm_length,
            cross_layout: p.configuration == Configuration::Cross,
            custom_layout: p.configuration == Configuration::Custom,
            rotors: p.rotor_positions(),
            spin: p.spin.map(Spin::sign),
            thrust_coefficient: p.thrust_coefficient,
            moment_coefficient: p.moment_coefficient,
            rotor_inertia: p.rotor_inertia,
            parasitic_drag: p.parasitic_drag,
            rotor_drag_xy: p.rotor_drag_xy,
            rotor_drag_z: p.rotor_drag_z,
            translational_lift: p.translational_lift,
            rotor_aero: p.rotor_drag_xy != 0.0 || p.rotor_drag_z != 0.0 || p.translational_lift != 0.0,
            lift: p.translational_lift != 0.0,
            parasitic: p.parasitic_drag != [0.0; 3],
        })
    }

    /// This body with another mass (kg) and inertia (kg·m²): the same
    /// result as [`RigidBody::new`] of the changed parameters (only the mass
    /// and inertia checks run again; the rotor geometry is kept), for a
    /// payload or an inertia variation changing them during a flight.
    pub fn with_mass_and_inertia(&self, mass: f64, inertia: Mat3) -> Result<Self, GainError> {
        let params = RigidBodyParams { mass, inertia, ..self.params() };
        let inertia_inv = params.check_mass_inertia()?;
        Ok(Self { mass, inertia, inertia_inv, diagonal: is_diagonal(&inertia), ..*self })
    }

    /// In place, the result of [`RigidBody::with_mass_and_inertia`] of
    /// `mass` and the inertia `scale · base_inertia` (each entry times
    /// `scale`, the same bits), where `base_inertia` is an inertia that
    /// passed [`RigidBodyParams::check`]: for a finite `scale > 0` the scaled
    /// matrix keeps its symmetry and positive definiteness, so only the
    /// mass, the entry bound and the inverse are checked (a payload or an
    /// inertia variation changing them every control period). Otherwise, or
    /// when any of those fails, the full check answers (the same error as
    /// [`RigidBody::with_mass_and_inertia`]); on error `self` is unchanged.
    pub fn set_mass_and_scaled_inertia(&mut self, mass: f64, base_inertia: &Mat3, scale: f64) -> Result<(), GainError> {
        self.set_mass_and_scaled_inertia_in_lane(0, mass, base_inertia, scale)
    }

    /// In place, the result of [`RigidBody::with_mass_and_inertia`] of `mass`
    /// (kg) and this body's inertia: only the mass check runs (the inertia
    /// and its inverse are kept); on error `self` is unchanged.
    pub fn set_mass(&mut self, mass: f64) -> Result<(), GainError> {
        self.set_mass_in_lane(0, mass)
    }

    /// The parameters (the ones [`RigidBody::new`] was given, with the mass
    /// and inertia of the latest change).
    pub fn params(&self) -> RigidBodyParams {
        self.lane_params(0)
    }

    /// One RK4 step of `h` seconds with the inputs held, without renormalising
    /// the quaternion (for tests of the integrator's own norm drift).
    pub fn step_unnormalized(&self, x: &RigidBodyState, input: &RigidBodyInput, h: f64) -> RigidBodyState {
        rk4_step(|_, s| self.derivative(s, input), 0.0, x, h)
    }

    /// One RK4 step of `h` seconds with the inputs held, then the quaternion
    /// renormalised to unit length. RK4 does not preserve `‖q‖` exactly (its
    /// drift per step is of order `(h‖Ω‖)⁵`, below 1e-12 over thousands of
    /// steps at 1 kHz); renormalising keeps the rotation matrix orthonormal to
    /// rounding over any horizon, and changes the attitude by no more than the
    /// drift it removes.
    pub fn step(&self, x: &RigidBodyState, input: &RigidBodyInput, h: f64) -> RigidBodyState {
        let mut next = self.step_unnormalized(x, input, h);
        normalize_quaternion(&mut next);
        next
    }

    /// World-frame angular momentum of the body (rotors included):
    /// `R (J Ω + h_r)`, kg·m²/s.
    pub fn angular_momentum_world(&self, x: &RigidBodyState, rotor_speeds: &[f64; 4]) -> [f64; 3] {
        let omega = block(x, index::BODY_RATES);
        let body = add(mat_vec(&self.inertia, omega), self.rotor_momentum(rotor_speeds));
        mat_vec(&rotation(quaternion(x)), body)
    }

    /// Rotational kinetic energy of the body `½ Ωᵀ J Ω`, J.
    pub fn rotational_energy(&self, x: &RigidBodyState) -> f64 {
        let omega = block(x, index::BODY_RATES);
        0.5 * super::math::dot(omega, mat_vec(&self.inertia, omega))
    }
}

impl<R: Real> RigidBody<R> {
    /// Every lane `body` (for `f64`, `body` itself).
    pub fn splat(body: &RigidBody<f64>) -> Self {
        let s = |v: f64| R::splat(v);
        let m = |b: bool| <R::Mask as Mask>::splat(b);
        Self {
            mass: s(body.mass),
            gravity: s(body.gravity),
            inertia: body.inertia.map(|r| r.map(s)),
            inertia_inv: body.inertia_inv.map(|r| r.map(s)),
            diagonal: m(body.diagonal),
            arm_length: s(body.arm_length),
            cross_layout: m(body.cross_layout),
            custom_layout: m(body.custom_layout),
            rotors: body.rotors.map(|r| r.map(s)),
            spin: body.spin.map(s),
            thrust_coefficient: s(body.thrust_coefficient),
            moment_coefficient: s(body.moment_coefficient),
            rotor_inertia: s(body.rotor_inertia),
            parasitic_drag: body.parasitic_drag.map(s),
            rotor_drag_xy: s(body.rotor_drag_xy),
            rotor_drag_z: s(body.rotor_drag_z),
            translational_lift: s(body.translational_lift),
            rotor_aero: m(body.rotor_aero),
            lift: m(body.lift),
            parasitic: m(body.parasitic),
        }
    }

    /// The parameters of lane `lane`'s vehicle (`lane < R::LANES`).
    pub fn lane_params(&self, lane: usize) -> RigidBodyParams {
        let spin = self.spin.get_lane(lane).map(|s| if s > 0.0 { Spin::Ccw } else { Spin::Cw });
        RigidBodyParams {
            mass: self.mass.get_lane(lane),
            gravity: self.gravity.get_lane(lane),
            inertia: self.inertia.get_lane(lane),
            arm_length: self.arm_length.get_lane(lane),
            configuration: if self.custom_layout.get_lane(lane) {
                Configuration::Custom
            } else if self.cross_layout.get_lane(lane) {
                Configuration::Cross
            } else {
                Configuration::Plus
            },
            custom_positions: self
                .custom_layout
                .get_lane(lane)
                .then(|| self.rotors.map(|r| [r[0].get_lane(lane), r[1].get_lane(lane)])),
            spin,
            thrust_coefficient: self.thrust_coefficient.get_lane(lane),
            moment_coefficient: self.moment_coefficient.get_lane(lane),
            rotor_inertia: self.rotor_inertia.get_lane(lane),
            parasitic_drag: self.parasitic_drag.get_lane(lane),
            rotor_drag_xy: self.rotor_drag_xy.get_lane(lane),
            rotor_drag_z: self.rotor_drag_z.get_lane(lane),
            translational_lift: self.translational_lift.get_lane(lane),
        }
    }

    /// Mass m of every lane, kg.
    #[inline]
    pub fn mass(&self) -> R {
        self.mass
    }

    /// [`RigidBody::set_mass_and_scaled_inertia`] on lane `lane` alone
    /// (`lane < R::LANES`; the other lanes are untouched, and so is this
    /// one on error).
    pub fn set_mass_and_scaled_inertia_in_lane(
        &mut self,
        lane: usize,
        mass: f64,
        base_inertia: &Mat3,
        scale: f64,
    ) -> Result<(), GainError> {
        let inertia = base_inertia.map(|r| r.map(|v| v * scale));
        let inverse = if in_fast_range(mass, scale, inertia.iter().flatten().copied()) {
            inverse3_positive(&inertia)
        } else {
            None
        };
        let inverse = match inverse {
            Some(inv) => inv,
            None => RigidBodyParams { mass, inertia, ..self.lane_params(lane) }.check_mass_inertia()?,
        };
        self.mass.put_lane(lane, mass);
        self.inertia.put_lane(lane, inertia);
        self.inertia_inv.put_lane(lane, inverse);
        self.diagonal.put_lane(lane, is_diagonal(&inertia));
        Ok(())
    }

    /// [`RigidBody::set_mass_and_scaled_inertia_in_lane`] for a base inertia
    /// `diag(base)` whose products of inertia are `+0.0` (bit for bit, as
    /// [`has_plain_diagonal`] tells): the same result and the same bits with
    /// the zero products worked out once. With `J = diag(d)`,
    /// `d = scale · base`, and `+0.0` elsewhere, the adjugate formula of
    /// `inverse3` reduces exactly to `det = d₀ (d₁ d₂)` (the terms it drops
    /// are `x − (+0)` and `x + (+0)` of a finite `x ≥ 0`, which are `x`),
    /// the diagonal `(d₁ d₂)/det`, `(d₀ d₂)/det`, `(d₀ d₁)/det`, and the
    /// products of inertia `±0/det` with the adjugate's signs (`det > 0`
    /// keeps them). Anything the shortcut does not cover (a scale or mass
    /// out of range, a determinant that is not a positive normal number)
    /// goes to the full method, which answers as before.
    pub(crate) fn set_mass_and_scaled_diagonal_inertia_in_lane(
        &mut self,
        lane: usize,
        mass: f64,
        base: &Mat3,
        scale: f64,
    ) -> Result<(), GainError> {
        let d = [base[0][0] * scale, base[1][1] * scale, base[2][2] * scale];
        if in_fast_range(mass, scale, d.into_iter()) {
            let p = d[1] * d[2];
            let det = d[0] * p;
            if det > 0.0 && det.is_normal() {
                let (z, n) = (0.0, -0.0);
                let inertia = [[d[0], z, z], [z, d[1], z], [z, z, d[2]]];
                let inverse = [[p / det, n, z], [n, (d[0] * d[2]) / det, n], [z, n, (d[0] * d[1]) / det]];
                self.mass.put_lane(lane, mass);
                self.inertia.put_lane(lane, inertia);
                self.inertia_inv.put_lane(lane, inverse);
                self.diagonal.put_lane(lane, true);
                return Ok(());
            }
        }
        self.set_mass_and_scaled_inertia_in_lane(lane, mass, base, scale)
    }

    /// [`RigidBody::set_mass`] on lane `lane` alone (`lane < R::LANES`; the
    /// other lanes are untouched, and so is this one on error).
    pub fn set_mass_in_lane(&mut self, lane: usize, mass: f64) -> Result<(), GainError> {
        if !(1e-6..=1e6).contains(&mass) {
            RigidBodyParams { mass, ..self.lane_params(lane) }.check_mass_inertia()?;
        }
        self.mass.put_lane(lane, mass);
        Ok(())
    }

    /// `J v` for a body-frame vector `v` (the inertia times an angular
    /// acceleration, rad/s² → N·m): the same values as the full product,
    /// the zero products of a diagonal inertia skipped.
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn inertia_times(&self, v: [R; 3]) -> [R; 3] {
        mat_vec_or_diagonal(&self.inertia, self.diagonal, v)
    }

    /// Rotor and aerodynamic wrench in the body frame at a state (without
    /// gravity, external inputs or the gyroscopic terms).
    pub fn body_wrench(&self, x: &RigidBodyState<R>, input: &RigidBodyInput<R>) -> Wrench<R> {
        self.body_wrench_in(x, &self.prepare(input), &rotation(quaternion(x)))
    }

    /// The rotor terms of `input` ([`PreparedInput`]) for
    /// [`RigidBody::derivative_prepared`].
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn prepare(&self, input: &RigidBodyInput<R>) -> PreparedInput<R> {
        let input = *input;
        let w = input.rotor_speeds;
        // Loops rather than `map`: its out-of-line instances would compile
        // for the baseline instruction set, outside a dispatched kernel.
        let (mut thrust, mut reaction, mut drag_xy, mut drag_z) = (w, w, w, w);
        for i in 0..4 {
            thrust[i] = self.thrust_coefficient * w[i] * w[i];
            reaction[i] = self.spin[i] * self.moment_coefficient * w[i] * w[i];
            drag_xy[i] = w[i] * self.rotor_drag_xy;
            drag_z[i] = w[i] * self.rotor_drag_z;
        }
        PreparedInput { input, thrust, reaction, drag_xy, drag_z, momentum: self.rotor_momentum(&w) }
    }

    /// [`RigidBody::body_wrench`] with the body-to-world rotation `r` of `x`
    /// given. The terms a vehicle does not have (rotor aerodynamics,
    /// translational lift, parasitic drag) are skipped per lane
    /// ([`branch`]), so each lane adds exactly the terms its one-flight body
    /// adds.
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn body_wrench_in(&self, x: &RigidBodyState<R>, prepared: &PreparedInput<R>, r: &Mat3<R>) -> Wrench<R> {
        let input = &prepared.input;
        let v = block(x, index::VELOCITY);
        let omega = block(x, index::BODY_RATES);
        let v_air = mat_t_vec(r, sub(v, input.wind));
        let zero = R::splat(0.0);
        // Two loops of the same arithmetic, so neither carries the other's
        // branch: rotor aerodynamics on (the realistic vehicles) or off.
        let (mut force, torque) = branch(
            self.rotor_aero,
            #[cfg_attr(not(debug_assertions), inline(always))]
            || {
                let mut force = [zero; 3];
                let mut torque = [zero; 3];
                for i in 0..4 {
                    let mut f = [zero, zero, prepared.thrust[i]];
                    let vi = add(v_air, cross_rotor(omega, self.rotors[i]));
                    f[0] -= prepared.drag_xy[i] * vi[0];
                    f[1] -= prepared.drag_xy[i] * vi[1];
                    f[2] -= prepared.drag_z[i] * vi[2];
                    // Off (k_h = 0) it would add a zero.
                    f[2] = branch(
                        self.lift,
                        #[cfg_attr(not(debug_assertions), inline(always))]
                        || f[2] + self.translational_lift * (vi[0] * vi[0] + vi[1] * vi[1]),
                        #[cfg_attr(not(debug_assertions), inline(always))]
                        || f[2],
                    );
                    force = add(force, f);
                    torque = add(torque, rotor_cross(self.rotors[i], f));
                    torque[2] -= prepared.reaction[i];
                }
                (force, torque)
            },
            #[cfg_attr(not(debug_assertions), inline(always))]
            || {
                // The thrust alone: `f = [0, 0, T]`, `r × f = [r_y T, −r_x T, 0]`.
                let mut force = [zero; 3];
                let mut torque = [zero; 3];
                for i in 0..4 {
                    let (r, t) = (self.rotors[i], prepared.thrust[i]);
                    force[2] += t;
                    torque[0] += r[1] * t;
                    torque[1] += -(r[0] * t);
                    torque[2] -= prepared.reaction[i];
                }
                (force, torque)
            },
        );
        let cd = self.parasitic_drag;
        force = branch(
            self.parasitic,
            #[cfg_attr(not(debug_assertions), inline(always))]
            || {
                let speed = norm(v_air);
                let mut f = force;
                f[0] -= speed * cd[0] * v_air[0];
                f[1] -= speed * cd[1] * v_air[1];
                f[2] -= speed * cd[2] * v_air[2];
                f
            },
            #[cfg_attr(not(debug_assertions), inline(always))]
            || force,
        );
        Wrench { force, torque }
    }

    /// Rotor angular momentum `h_r = J_r Σ s_i ω_i ẑ` (body frame), kg·m²/s.
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn rotor_momentum(&self, rotor_speeds: &[R; 4]) -> [R; 3] {
        // The sum of `Iterator::sum` for f64: from −0 (which leaves any
        // first term's bits as they are), term by term.
        let mut s = R::splat(-0.0);
        for i in 0..4 {
            s += self.spin[i] * rotor_speeds[i];
        }
        let zero = R::splat(0.0);
        [zero, zero, self.rotor_inertia * s]
    }

    /// Time derivative of the state (module docs for the equations).
    pub fn derivative(&self, x: &RigidBodyState<R>, input: &RigidBodyInput<R>) -> RigidBodyState<R> {
        self.derivative_prepared(x, &self.prepare(input))
    }

    /// [`RigidBody::derivative`] of the inputs [`RigidBody::prepare`] made,
    /// bit for bit: the form for several states with the same inputs (the
    /// second and third RK4 stages).
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn derivative_prepared(&self, x: &RigidBodyState<R>, prepared: &PreparedInput<R>) -> RigidBodyState<R> {
        let input = &prepared.input;
        let q = quaternion(x);
        let omega = block(x, index::BODY_RATES);
        let r = rotation(q);
        let wrench = self.body_wrench_in(x, prepared, &r);
        let f_world = add(mat_vec(&r, wrench.force), input.force);
        let acc = [f_world[0] / self.mass, f_world[1] / self.mass, f_world[2] / self.mass - self.gravity];
        let j_omega = mat_vec_or_diagonal(&self.inertia, self.diagonal, omega);
        let m = sub(add(wrench.torque, input.torque), cross(omega, add(j_omega, prepared.momentum)));
        let omega_dot = mat_vec_or_diagonal(&self.inertia_inv, self.diagonal, m);
        let q_dot = quat_derivative(q, omega);
        let mut d = [R::default(); STATE_LEN];
        d[0..3].copy_from_slice(&x[3..6]);
        d[3..6].copy_from_slice(&acc);
        d[6..10].copy_from_slice(&q_dot);
        d[10..13].copy_from_slice(&omega_dot);
        d
    }
}

#[cfg_attr(not(debug_assertions), inline(always))]
fn block<R: Real>(x: &RigidBodyState<R>, start: usize) -> Vec3<R> {
    [x[start], x[start + 1], x[start + 2]]
}

#[cfg_attr(not(debug_assertions), inline(always))]
fn quaternion<R: Real>(x: &RigidBodyState<R>) -> Quat<R> {
    let i = index::QUATERNION;
    [x[i], x[i + 1], x[i + 2], x[i + 3]]
}

/// Scale the quaternion block of `x` to unit length (left unchanged if its
/// norm is zero, subnormal or not finite), lane by lane for lanes.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn normalize_quaternion<R: Real>(x: &mut RigidBodyState<R>) {
    let i = index::QUATERNION;
    let n = (x[i] * x[i] + x[i + 1] * x[i + 1] + x[i + 2] * x[i + 2] + x[i + 3] * x[i + 3]).sqrt();
    // `n.is_normal()` for the `n ≥ 0` (or NaN) of a square root.
    let normal = n.ge(R::splat(f64::MIN_POSITIVE)) & n.is_finite();
    for k in i..i + 4 {
        x[k] = R::select(normal, x[k] / n, x[k]);
    }
}

/// Rotation matrix (body → world) of a unit quaternion `[w, x, y, z]`.
pub fn rotation_matrix(q: &[f64; 4]) -> [[f64; 3]; 3] {
    rotation(*q)
}

/// Unit quaternion `[w, x, y, z]` of Z-Y-X Euler angles `[φ, θ, ψ]` (rad):
/// `q = q_z(ψ) ⊗ q_y(θ) ⊗ q_x(φ)`, so `R(q) = R_z(ψ) R_y(θ) R_x(φ)`.
///
/// The core's [`kinematics::quaternion_from_euler`].
pub fn euler_to_quaternion(euler: &[f64; 3]) -> [f64; 4] {
    kinematics::quaternion_from_euler(euler)
}

/// Z-Y-X Euler angles `[φ, θ, ψ]` (rad) of a unit quaternion: φ, ψ in
/// `(−π, π]`, θ in `[−π/2, π/2]`. At θ = ±π/2 (gimbal lock) only φ ∓ ψ is
/// defined; the split returned there is whatever `atan2` gives and is not
/// continuous. `q` and `−q` give the same angles.
///
/// The core's [`kinematics::euler_from_quaternion`].
pub fn quaternion_to_euler(q: &[f64; 4]) -> [f64; 3] {
    kinematics::euler_from_quaternion(q)
}

/// Body rates `Ω = [p, q, r]` (rad/s) from Z-Y-X Euler rates at `euler`:
///
/// ```text
/// p = φ̇ − ψ̇ sθ
/// q = θ̇ cφ + ψ̇ cθ sφ
/// r = −θ̇ sφ + ψ̇ cθ cφ
/// ```
///
/// Defined everywhere. The core's
/// [`kinematics::body_rates_from_euler_rates`].
pub fn euler_rates_to_body_rates(euler: &[f64; 3], euler_rates: &[f64; 3]) -> [f64; 3] {
    kinematics::body_rates_from_euler_rates(euler, euler_rates)
}

/// Smallest `|cos θ|` at which [`body_rates_to_euler_rates`] answers
/// (|θ| within about 1e-6 rad of π/2 is refused); the core's
/// [`kinematics::GIMBAL_LOCK_COS`].
pub const GIMBAL_LOCK_COS: f64 = kinematics::GIMBAL_LOCK_COS;

/// The Euler-rate map is singular at θ = ±π/2.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error("gimbal lock: pitch θ = {theta} rad has |cos θ| < {GIMBAL_LOCK_COS}; Euler rates are undefined")]
pub struct GimbalLock {
    /// The pitch angle θ, rad.
    pub theta: f64,
}

/// Z-Y-X Euler rates `[φ̇, θ̇, ψ̇]` (rad/s) from body rates Ω at `euler`:
///
/// ```text
/// φ̇ = p + (q sφ + r cφ) tθ
/// θ̇ = q cφ − r sφ
/// ψ̇ = (q sφ + r cφ) / cθ
/// ```
///
/// Errors with [`GimbalLock`] when `|cos θ| < GIMBAL_LOCK_COS`.
pub fn body_rates_to_euler_rates(euler: &[f64; 3], body_rates: &[f64; 3]) -> Result<[f64; 3], GimbalLock> {
    if ftsmc_core::math::cos(euler[1]).abs() < GIMBAL_LOCK_COS {
        return Err(GimbalLock { theta: euler[1] });
    }
    // Away from the singularity the clamp of `cos θ` is a no-op.
    Ok(euler_rates_clamped(euler, body_rates))
}

/// Z-Y-X Euler rates from body rates with `cos θ` clamped to
/// `±`[`GIMBAL_LOCK_COS`] near the singularity (finite everywhere): the
/// core's [`kinematics::euler_rates_from_body_rates`].
pub fn euler_rates_clamped(euler: &[f64; 3], body_rates: &[f64; 3]) -> [f64; 3] {
    kinematics::euler_rates_from_body_rates(euler, body_rates)
}

/// The Z-Y-X angles of the unit quaternion `q` and the sines and cosines
/// their Euler rates take, in one pass (every lane for lanes).
///
/// The angles are the core's [`kinematics::euler_from_quaternion`], the same
/// operations in the same order: `φ = atan2(a, b)`, `θ = asin(s)`,
/// `ψ = atan2(2(wz + xy), 1 − 2(y² + z²))` with `a = 2(wx + yz) = cθ sφ`,
/// `b = 1 − 2(x² + y²) = cθ cφ` and `s = sat(2(wy − xz), ±1) = sθ`.
///
/// The Euler rates ([`euler_rates_clamped`]) take the sines and cosines of φ
/// and θ read off `q` instead of evaluated: `cθ = √(a² + b²)`,
/// `sφ = a/cθ`, `cφ = b/cθ`, `sθ = s` (the same values to rounding, without
/// two `sin_cos`). Within `cθ < 1e-3` of gimbal lock, where `a` and `b` lose
/// their relative precision, the core's formula on the angles answers
/// (per lane for lanes, [`branch`]).
#[cfg_attr(not(debug_assertions), inline(always))]
fn euler_of_quaternion<R: Real>(q: &Quat<R>, body_rates: &Vec3<R>) -> (Vec3<R>, Vec3<R>) {
    let [w, x, y, z] = *q;
    let one = R::splat(1.0);
    let a = (w * x + y * z) * 2.0;
    let b = one - (x * x + y * y) * 2.0;
    let s = ftsmc_core::law::saturate((w * y - x * z) * 2.0, one);
    let attitude = [a.atan2(b), s.asin(), ((w * z + x * y) * 2.0).atan2(one - (y * y + z * z) * 2.0)];
    let ct = (a * a + b * b).sqrt();
    let rates = branch(
        ct.ge(R::splat(1e-3)),
        #[cfg_attr(not(debug_assertions), inline(always))]
        || kinematics::euler_rates_from_body_rates_with([a / ct, b / ct], [s, ct], body_rates),
        // Near gimbal lock, or a non-finite quaternion.
        #[cfg_attr(not(debug_assertions), inline(always))]
        || kinematics::euler_rates_from_body_rates(&attitude, body_rates),
    );
    (attitude, rates)
}

/// The Euler state the paper's controllers were designed for: position,
/// velocity, Z-Y-X angles ([`quaternion_to_euler`]) and Euler rates
/// ([`body_rates_to_euler_rates`]). Errors with [`GimbalLock`] at θ = ±π/2.
pub fn try_to_quad_state(x: &RigidBodyState) -> Result<QuadState, GimbalLock> {
    let (attitude, angular_rate) = euler_of_quaternion(&quaternion(x), &block(x, index::BODY_RATES));
    if ftsmc_core::math::cos(attitude[1]).abs() < GIMBAL_LOCK_COS {
        return Err(GimbalLock { theta: attitude[1] });
    }
    Ok(QuadState { position: block(x, index::POSITION), attitude, velocity: block(x, index::VELOCITY), angular_rate })
}

/// As [`try_to_quad_state`], but never fails: within [`GIMBAL_LOCK_COS`] of
/// the singularity `cos θ` is clamped to `±GIMBAL_LOCK_COS` (the sign of
/// cos θ; positive at exactly 0), so the Euler rates stay finite (large, up to ~1e6 × ‖Ω‖)
/// rather than infinite. A controller flying there has already lost its
/// Euler-angle model; use [`try_to_quad_state`] to detect it.
///
/// Generic over the number type: on lanes ([`ftsmc_core::lanes`]) lane `i`
/// is the one-flight conversion of lane `i`'s state, bit for bit (the
/// arithmetic lane by lane, `atan2` and `asin` from the one maths library
/// per lane).
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn to_quad_state<R: Real>(x: &RigidBodyState<R>) -> QuadState<R> {
    let (attitude, angular_rate) = euler_of_quaternion(&quaternion(x), &block(x, index::BODY_RATES));
    QuadState { position: block(x, index::POSITION), attitude, velocity: block(x, index::VELOCITY), angular_rate }
}

/// Rigid-body state of an Euler state (quaternion from the angles, body
/// rates from the Euler rates).
pub fn from_quad_state(s: &QuadState) -> RigidBodyState {
    let q = euler_to_quaternion(&s.attitude);
    let omega = euler_rates_to_body_rates(&s.attitude, &s.angular_rate);
    let mut x = [0.0; STATE_LEN];
    x[0..3].copy_from_slice(&s.position);
    x[3..6].copy_from_slice(&s.velocity);
    x[6..10].copy_from_slice(&q);
    x[10..13].copy_from_slice(&omega);
    x
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The module's equations written out with full 3×3 products and cross
    /// products, in the order of the sums of [`RigidBody::derivative`].
    fn reference_derivative(body: &RigidBody, x: &RigidBodyState, input: &RigidBodyInput) -> RigidBodyState {
        let p = body.params();
        let rotors = p.rotor_positions();
        let spin = p.spin.map(Spin::sign);
        let q = quaternion(x);
        let r = rotation(q);
        let (v, omega) = (block(x, index::VELOCITY), block(x, index::BODY_RATES));
        let v_air = mat_t_vec(&r, sub(v, input.wind));
        let (mut force, mut torque) = ([0.0; 3], [0.0; 3]);
        for i in 0..4 {
            let w = input.rotor_speeds[i];
            let vi = add(v_air, cross(omega, rotors[i]));
            let mut f = [0.0, 0.0, p.thrust_coefficient * w * w];
            f[0] -= w * p.rotor_drag_xy * vi[0];
            f[1] -= w * p.rotor_drag_xy * vi[1];
            f[2] -= w * p.rotor_drag_z * vi[2];
            f[2] += p.translational_lift * (vi[0] * vi[0] + vi[1] * vi[1]);
            force = add(force, f);
            torque = add(torque, cross(rotors[i], f));
            torque[2] -= spin[i] * p.moment_coefficient * w * w;
        }
        let speed = norm(v_air);
        for k in 0..3 {
            force[k] -= speed * p.parasitic_drag[k] * v_air[k];
        }
        let f_world = add(mat_vec(&r, force), input.force);
        let h_r = body.rotor_momentum(&input.rotor_speeds);
        let m = sub(add(torque, input.torque), cross(omega, add(mat_vec(&p.inertia, omega), h_r)));
        let omega_dot = mat_vec(&inverse3(&p.inertia).unwrap(), m);
        let mut d = [0.0; STATE_LEN];
        d[0..3].copy_from_slice(&x[3..6]);
        d[3..6].copy_from_slice(&[f_world[0] / p.mass, f_world[1] / p.mass, f_world[2] / p.mass - p.gravity]);
        d[6..10].copy_from_slice(&quat_derivative(q, omega));
        d[10..13].copy_from_slice(&omega_dot);
        d
    }

    /// The Euler rates with sines and cosines read off the quaternion equal
    /// the core's formula on the angles to rounding, at any attitude,
    /// including near and at gimbal lock (where the core's formula answers).
    /// "To rounding" near gimbal lock is the angle path's: its
    /// `cos θ = cos(asin s)` has an absolute error of about `ε/cθ`, so the
    /// rates (∝ 1/cθ) differ by up to about `ε ‖Ω‖/cθ³`; the quaternion's
    /// `cθ = √(a² + b²)` keeps its relative precision there.
    #[test]
    fn euler_rates_from_the_quaternion_agree_with_the_angles() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let mut worst: f64 = 0.0;
        for k in 0..20_000 {
            let mut u = || -> f64 { rng.random_range(-1.0..1.0) };
            // Every third sample close to θ = ±π/2 (down to exactly there).
            let theta = if k % 3 == 0 {
                (core::f64::consts::FRAC_PI_2 - 10f64.powi(-(k % 17))) * u().signum()
            } else {
                1.5 * u()
            };
            let euler = [3.1 * u(), theta, 3.1 * u()];
            let q = kinematics::quaternion_from_euler(&euler);
            let angles = kinematics::euler_from_quaternion(&q);
            let rates = [2.0 * u(), 2.0 * u(), 2.0 * u()];
            let want = euler_rates_clamped(&angles, &rates);
            let (got_angles, got) = euler_of_quaternion(&q, &rates);
            assert_eq!(got_angles.map(f64::to_bits), angles.map(f64::to_bits));
            let ct = ftsmc_core::math::cos(angles[1]).abs();
            for i in 0..3 {
                // Relative to the angle path's precision ‖Ω‖/cθ³ (‖Ω‖ ≤ 2√3).
                let err = (got[i] - want[i]).abs() * ct.max(GIMBAL_LOCK_COS).powi(3) / 4.0;
                worst = worst.max(err);
                assert!(err <= 1e-14, "{euler:?} {rates:?}: {got:?} vs {want:?}");
            }
        }
        assert!(worst > 0.0, "the two forms are not the same bits everywhere");
    }

    /// The Euler state of rigid-body states in lanes is, lane by lane, the
    /// one-flight [`to_quad_state`] bit for bit, with lanes near and at
    /// gimbal lock (where the angle formula answers) and non-finite lanes
    /// beside ordinary ones.
    #[test]
    fn euler_state_in_lanes_is_the_one_flight_state_bit_for_bit() {
        use ftsmc_core::lanes::Lanes;
        fn check<R: Real>(rng: &mut ChaCha8Rng) {
            let bits = |q: QuadState| q.to_array().map(|v| if v.is_nan() { f64::NAN.to_bits() } else { v.to_bits() });
            let mut near_lock = 0;
            for k in 0..3000 {
                let xs: Vec<RigidBodyState> = (0..R::LANES)
                    .map(|i| {
                        let mut u = || -> f64 { rng.random_range(-1.0..1.0) };
                        let theta = match (k + i) % 4 {
                            0 => (core::f64::consts::FRAC_PI_2 - 10f64.powi(-((k / 4) as i32 % 12))) * u().signum(),
                            _ => 1.5 * u(),
                        };
                        let q = kinematics::quaternion_from_euler(&[3.1 * u(), theta, 3.1 * u()]);
                        let mut x: RigidBodyState = core::array::from_fn(|_| 5.0 * u());
                        x[6..10].copy_from_slice(&q);
                        if (k + 3 * i) % 97 == 0 {
                            x[7 + i % 3] = f64::NAN;
                        }
                        x
                    })
                    .collect();
                let mut lanes = [R::splat(0.0); STATE_LEN];
                for (i, x) in xs.iter().enumerate() {
                    lanes.put_lane(i, *x);
                }
                let q = to_quad_state(&lanes);
                for (i, x) in xs.iter().enumerate() {
                    let one = to_quad_state(x);
                    near_lock += usize::from(ftsmc_core::math::cos(one.attitude[1]).abs() < 1e-3);
                    assert_eq!(bits(q.get_lane(i)), bits(one), "lane {i} of {x:?}");
                }
            }
            assert!(near_lock > 100, "{near_lock}");
        }
        let mut rng = ChaCha8Rng::seed_from_u64(21);
        check::<Lanes<4>>(&mut rng);
        check::<Lanes<8>>(&mut rng);
    }

    /// The derivative skips the zero terms of the rotor positions (`r_z = 0`),
    /// of a thrust without aerodynamics and of a diagonal inertia: the same
    /// values as the full products, for both layouts, aerodynamics on and
    /// off, diagonal and full inertia.
    #[test]
    fn derivative_equals_the_full_products() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let full = RigidBodyParams {
            inertia: [[3.8e-3, 1e-4, -2e-4], [1e-4, 3.9e-3, 5e-5], [-2e-4, 5e-5, 7.6e-3]],
            ..RigidBodyParams::hummingbird()
        };
        let bodies = [RigidBodyParams::default(), RigidBodyParams::hummingbird(), RigidBodyParams::crazyflie(), full];
        for params in bodies {
            let body = RigidBody::new(params).unwrap();
            assert_eq!(body.diagonal, is_diagonal(&params.inertia));
            for _ in 0..200 {
                let mut u = || -> f64 { rng.random_range(-3.0..3.0) };
                let q = [1.0 + u().abs(), u(), u(), u()];
                let n = q.iter().map(|c| c * c).sum::<f64>().sqrt();
                let mut x: RigidBodyState = core::array::from_fn(|_| u());
                x[6..10].copy_from_slice(&q.map(|c| c / n));
                let input = RigidBodyInput {
                    rotor_speeds: core::array::from_fn(|_| 300.0 * (2.0 + u())),
                    wind: [u(), u(), u()],
                    force: [u(), u(), u()],
                    torque: [0.01 * u(), 0.01 * u(), 0.01 * u()],
                };
                let got = body.derivative(&x, &input);
                let want = reference_derivative(&body, &x, &input);
                assert_eq!(got, want, "{params:?}");
            }
        }
    }

    /// The diagonal shortcut of the scaled inertia's inverse gives the bits
    /// (and the errors) of the full method: masses, inertias and scales in
    /// range, at and past its edges, non-finite ones, and a determinant
    /// that underflows.
    #[test]
    fn the_diagonal_shortcut_is_the_full_inverse_bit_for_bit() {
        let bits = |b: &RigidBody| {
            let mut v = vec![b.mass.to_bits(), u64::from(b.diagonal)];
            v.extend(b.inertia.iter().chain(&b.inertia_inv).flatten().map(|x| x.to_bits()));
            v
        };
        let mut rng = ChaCha8Rng::seed_from_u64(17);
        let bases = [
            RigidBodyParams::hummingbird().inertia,
            RigidBodyParams::crazyflie().inertia,
            diag([1e-100, 1e-100, 1e-100]),
            diag([5e5, 2e5, 9e5]),
        ];
        let mut checked = (0, 0);
        for base in bases {
            assert!(has_plain_diagonal(&base));
            let body = RigidBody::new(RigidBodyParams { inertia: base, ..RigidBodyParams::hummingbird() }).ok();
            let Some(body) = body else { continue };
            let edges =
                [1.0, 0.0, -0.0, -1.0, 2.0, 1e6, 1e300, f64::INFINITY, f64::NAN, 1e-300, 1e-3, f64::MIN_POSITIVE];
            for k in 0..4000 {
                let scale = if k < edges.len() { edges[k] } else { rng.random_range(0.5..1.5) };
                let mass = match k % 7 {
                    0 => 1e-7,
                    1 => 2e6,
                    2 => f64::NAN,
                    _ => rng.random_range(0.1..2.0),
                };
                let (mut full, mut short) = (body, body);
                let a = full.set_mass_and_scaled_inertia_in_lane(0, mass, &base, scale);
                let b = short.set_mass_and_scaled_diagonal_inertia_in_lane(0, mass, &base, scale);
                // (Debug text: an error may carry a NaN, which `==` never equals.)
                assert_eq!(format!("{a:?}"), format!("{b:?}"), "scale {scale}, mass {mass}");
                assert_eq!(bits(&full), bits(&short), "scale {scale}, mass {mass}");
                if a.is_ok() {
                    checked.0 += 1;
                } else {
                    checked.1 += 1;
                }
            }
        }
        assert!(checked.0 > 1000 && checked.1 > 100, "{checked:?}");
        // A `−0.0` product of inertia is not plain (the shortcut's signs would differ).
        assert!(!has_plain_diagonal(&[[1.0, -0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]));
    }

    /// Four different vehicles in `Lanes<4>` (and the same four, twice, in
    /// `Lanes<8>`): every lane reads back its parameters, and 300 staged RK4
    /// steps with per-lane states, rotor speeds, winds and external wrenches
    /// (one lane's rotor speed NaN midway, masses and inertias changed in
    /// some lanes) give each lane the one-flight body's bits.
    #[test]
    fn vehicles_in_lanes_are_the_one_flight_vehicles_bit_for_bit() {
        use crate::vehicle::paper::rk4_step_staged;
        use ftsmc_core::lanes::Lanes;
        fn check<R: Real>() {
            let full = RigidBodyParams {
                inertia: [[3.8e-3, 1e-4, -2e-4], [1e-4, 3.9e-3, 5e-5], [-2e-4, 5e-5, 7.6e-3]],
                ..RigidBodyParams::hummingbird()
            };
            let params =
                [RigidBodyParams::default(), RigidBodyParams::hummingbird(), RigidBodyParams::crazyflie(), full];
            let mut ones: Vec<RigidBody> = (0..R::LANES).map(|i| RigidBody::new(params[i % 4]).unwrap()).collect();
            let mut lanes = RigidBody::<R>::splat(&ones[1]);
            for (i, one) in ones.iter().enumerate() {
                lanes.put_lane(i, *one);
                assert_eq!(lanes.lane_params(i), params[i % 4]);
            }
            let mut rng = ChaCha8Rng::seed_from_u64(9);
            let mut xs: Vec<RigidBodyState> = (0..R::LANES)
                .map(|i| {
                    let mut x: RigidBodyState = core::array::from_fn(|_| rng.random_range(-1.0..1.0));
                    x[6] += 2.0 + i as f64;
                    normalize_quaternion(&mut x);
                    x
                })
                .collect();
            let mut x = [R::splat(0.0); STATE_LEN];
            for (i, xi) in xs.iter().enumerate() {
                x.put_lane(i, *xi);
            }
            let h = 1e-3;
            for k in 0..300 {
                let inputs: Vec<RigidBodyInput> = ones
                    .iter()
                    .map(|one| {
                        let hover = one.params().hover_rotor_speed();
                        let mut u = || -> f64 { rng.random_range(-1.0..1.0) };
                        RigidBodyInput {
                            rotor_speeds: core::array::from_fn(|_| hover * (1.0 + 0.1 * u())),
                            wind: [3.0 * u(), 3.0 * u(), u()],
                            force: [0.01 * u(), 0.01 * u(), 0.01 * u()],
                            torque: [1e-5 * u(), 1e-5 * u(), 1e-5 * u()],
                        }
                    })
                    .map(|mut input| {
                        if k == 150 {
                            input.rotor_speeds[2] = f64::NAN;
                        }
                        input
                    })
                    .collect();
                // Only lane 1 gets the NaN (the others keep flying).
                let inputs: Vec<RigidBodyInput> = inputs
                    .into_iter()
                    .enumerate()
                    .map(|(i, mut input)| {
                        if input.rotor_speeds[2].is_nan() && i != 1 {
                            input.rotor_speeds[2] = 0.0;
                        }
                        input
                    })
                    .collect();
                if k % 50 == 25 {
                    for (i, one) in ones.iter_mut().enumerate().filter(|(i, _)| i % 2 == 0) {
                        let p = one.params();
                        let (mass, scale) = (p.mass * 1.1, 1.0 + 0.01 * k as f64);
                        let a = one.set_mass_and_scaled_inertia(mass, &params[i % 4].inertia, scale);
                        let b = lanes.set_mass_and_scaled_inertia_in_lane(i, mass, &params[i % 4].inertia, scale);
                        assert_eq!(a, b);
                        assert_eq!(one.set_mass(mass * 0.95), lanes.set_mass_in_lane(i, mass * 0.95));
                    }
                }
                let mut lane_input = RigidBodyInput::<R>::default();
                for (i, input) in inputs.iter().enumerate() {
                    lane_input.put_lane(i, *input);
                }
                for (i, xi) in xs.iter_mut().enumerate() {
                    let one = &ones[i];
                    *xi = rk4_step_staged(
                        |_| one.prepare(&inputs[i]),
                        |input, s| one.derivative_prepared(s, input),
                        k as f64 * h,
                        xi,
                        h,
                    );
                    normalize_quaternion(xi);
                }
                x = rk4_step_staged(
                    |_| lanes.prepare(&lane_input),
                    |input, s| lanes.derivative_prepared(s, input),
                    R::splat(k as f64 * h),
                    &x,
                    R::splat(h),
                );
                normalize_quaternion(&mut x);
                // Bits, any NaN as one: Rust leaves a NaN's sign and payload
                // unspecified (RFC 3514), and the compiler orders the
                // operands of a vector and a scalar operation as it likes.
                let bits = |v: f64| if v.is_nan() { f64::NAN.to_bits() } else { v.to_bits() };
                for (i, xi) in xs.iter().enumerate() {
                    assert_eq!(x.get_lane(i).map(bits), xi.map(bits), "lane {i} step {k}");
                    assert_eq!(lanes.get_lane(i), ones[i], "lane {i} step {k}");
                }
            }
            assert!(xs[1].iter().any(|v| v.is_nan()) && xs[0].iter().all(|v| v.is_finite()));
        }
        check::<Lanes<4>>();
        check::<Lanes<8>>();
    }
}
