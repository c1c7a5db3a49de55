//! Four-rotor layouts in the body plane and PX4's normalisation of them:
//! the actuator effectiveness of a layout, its inverse (the mix) and the
//! scale PX4's control allocator applies to each axis, so that a normalised
//! torque of 1 stands for a known torque in N·m on any geometry.
//!
//! Body axes are ftsmc's (x forward, y left, z up; `ftsmc_core::kinematics`).
//! Actuator `i`'s setpoint is PX4's motor setpoint, a fraction of full
//! thrust (`a_i = T_i / T_max,i`), so the effectiveness of rotor `i` with
//! full thrust `T_r` (N), hub `(x_i, y_i)` (m), spin sign `s_i` (+1
//! counter-clockwise seen from above) and moment ratio `k = k_m / k_f` (m) is
//! the column `T_r [1, y_i, −x_i, −s_i k]` of thrust (N, up), roll, pitch and
//! yaw torque (N·m). This is PX4's `ActuatorEffectivenessRotors::
//! computeEffectivenessMatrix` (`ct·(r × axis) − ct·km·axis`, thrust `ct·axis`
//! with the axis `(0, 0, −1)` of its forward-right-down body frame) in
//! ftsmc's frame: roll is the same, pitch and yaw change sign, and PX4's
//! `CA_ROTOR{n}_KM > 0` is a counter-clockwise rotor.
//!
//! PX4's `ControlAllocationPseudoInverse::updateControlAllocationMatrixScale`
//! then scales the mix `M` (the pseudo-inverse of the effectiveness; the
//! inverse for four rotors of full rank): roll and pitch share
//! `max(√(|M_roll|² / (n_roll/2)), √(|M_pitch|² / (n_pitch/2)))` (`n` the
//! entries above 1e-3), yaw takes the largest entry of its column in PX4's
//! frame (`−min` of ftsmc's), thrust the mean magnitude of the nonzero thrust
//! entries. A normalised command `c` on an axis is the physical command
//! `c / scale` ([`px4_scales`]). Written from that algorithm; the test
//! `tests/px4_normalisation.rs` checks it against a transcription of PX4's
//! six-axis code on four geometries.
//!
//! The 4×4 inverse is written here (Gauss–Jordan with partial pivoting, a
//! dozen lines): the crate is `no_std` and depends on no linear-algebra
//! library; the mixer of the simulator uses the same function.

use crate::lanes::Real;

/// A four-rotor layout: where the hubs are and which way each rotor turns.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RotorGeometry {
    /// Paper Eq. 2's "+": rotor 1 at `(l, 0)`, 2 at `(0, −l)`, 3 at `(−l, 0)`,
    /// 4 at `(0, l)`, spins cw, ccw, cw, ccw.
    Plus {
        /// Centre-to-hub distance l, m.
        arm_length: f64,
    },
    /// The "+" turned by +45°: rotor 1 at `l(1, 1)/√2`, 2 at `l(1, −1)/√2`,
    /// 3 at `l(−1, −1)/√2`, 4 at `l(−1, 1)/√2`, spins cw, ccw, cw, ccw.
    Cross {
        /// Centre-to-hub distance l, m.
        arm_length: f64,
    },
    /// Any planar layout.
    Custom {
        /// Hub `(x, y)` of rotors 1..4 in body axes, m.
        positions: [[f64; 2]; 4],
        /// Spin signs of rotors 1..4: +1 counter-clockwise, −1 clockwise (seen from above).
        spin: [f64; 4],
    },
}

/// Spin signs of paper Eq. 2 (rotors 1 and 3 clockwise): `[−1, 1, −1, 1]`.
pub const PAPER_SPIN_SIGNS: [f64; 4] = [-1.0, 1.0, -1.0, 1.0];

impl RotorGeometry {
    /// Hub `(x, y)` of rotors 1..4, m.
    pub fn positions(&self) -> [[f64; 2]; 4] {
        match *self {
            RotorGeometry::Plus { arm_length: l } => [[l, 0.0], [0.0, -l], [-l, 0.0], [0.0, l]],
            RotorGeometry::Cross { arm_length: l } => {
                let a = l * core::f64::consts::FRAC_1_SQRT_2;
                [[a, a], [a, -a], [-a, -a], [-a, a]]
            }
            RotorGeometry::Custom { positions, .. } => positions,
        }
    }

    /// Spin signs of rotors 1..4 (+1 counter-clockwise).
    pub fn spin(&self) -> [f64; 4] {
        match *self {
            RotorGeometry::Custom { spin, .. } => spin,
            _ => PAPER_SPIN_SIGNS,
        }
    }

    /// The actuator effectiveness `B[k][i]` (module docs): rows thrust (N),
    /// roll, pitch, yaw torque (N·m) per unit setpoint of rotor `i`, with
    /// full thrust `rotor_thrust` (N) per rotor and moment ratio
    /// `moment_ratio = k_m / k_f` (m).
    pub fn effectiveness(&self, rotor_thrust: f64, moment_ratio: f64) -> [[f64; 4]; 4] {
        let r = self.positions();
        let s = self.spin();
        core::array::from_fn(|k| {
            core::array::from_fn(|i| match k {
                0 => rotor_thrust,
                1 => rotor_thrust * r[i][1],
                2 => -rotor_thrust * r[i][0],
                _ => -s[i] * moment_ratio * rotor_thrust,
            })
        })
    }

    /// Torque, N·m, that PX4's normalised roll, pitch and yaw command of 1
    /// stands for on this layout ([`px4_scales`] of the inverse of
    /// [`RotorGeometry::effectiveness`]); `None` if the layout cannot make
    /// every torque (a singular effectiveness).
    ///
    /// The "+" and "×" layouts take their closed forms, `[√2 l T/4, √2 l T/4,
    /// k T]` and `[l T/2, l T/2, k T]` with `T = 4 rotor_thrust` (what the
    /// general path gives to rounding; a test checks it to 1e-12).
    pub fn px4_torque_scale(&self, rotor_thrust: f64, moment_ratio: f64) -> Option<[f64; 3]> {
        let t_max = 4.0 * rotor_thrust;
        let yaw = moment_ratio * t_max;
        match *self {
            RotorGeometry::Plus { arm_length } => {
                let tilt = core::f64::consts::SQRT_2 * arm_length * t_max / 4.0;
                Some([tilt, tilt, yaw])
            }
            RotorGeometry::Cross { arm_length } => {
                let tilt = arm_length * t_max / 2.0;
                Some([tilt, tilt, yaw])
            }
            RotorGeometry::Custom { .. } => self.px4_torque_scale_general(rotor_thrust, moment_ratio),
        }
    }

    /// [`RotorGeometry::px4_torque_scale`] through the effectiveness and its
    /// inverse for every layout (the closed forms' check).
    pub fn px4_torque_scale_general(&self, rotor_thrust: f64, moment_ratio: f64) -> Option<[f64; 3]> {
        let inverse = invert4(&self.effectiveness(rotor_thrust, moment_ratio))?;
        let mix: [[f64; 4]; 4] = core::array::from_fn(|k| core::array::from_fn(|i| inverse[i][k]));
        let scale = px4_scales(&mix);
        Some([1.0 / scale[1], 1.0 / scale[2], 1.0 / scale[3]])
    }
}

/// PX4's `FLT_EPSILON` (the `f32` machine epsilon), below which a scale is
/// not applied.
pub const FLT_EPSILON: f64 = f32::EPSILON as f64;

/// The scale PX4 divides each column of the mix by
/// (`updateControlAllocationMatrixScale`; module docs): `mix[k][i]` is
/// column `k` (0 thrust up, 1 roll, 2 pitch, 3 yaw, ftsmc's axes) of the
/// mix in actuator space, entry of actuator `i`. Returns the factor from a
/// physical command (N, N·m) to PX4's normalised one, 1 where PX4 applies
/// no scale (a scale at or below [`FLT_EPSILON`]).
pub fn px4_scales(mix: &[[f64; 4]; 4]) -> [f64; 4] {
    // Roll and pitch share one scale: sqrt(|col|² / (n / 2)) over the
    // actuators with a nonzero entry (|x| > 1e-3), the larger of the two.
    let rp_scale = |col: &[f64; 4]| {
        let n = col.iter().filter(|x| x.abs() > 1e-3).count();
        if n > 0 {
            Real::sqrt(col.iter().map(|x| x * x).sum::<f64>() / (n as f64 / 2.0))
        } else {
            1.0
        }
    };
    let rp = rp_scale(&mix[1]).max(rp_scale(&mix[2]));
    // Yaw: the largest entry of its column in PX4's frame (z down), so the
    // negated smallest of ftsmc's (z up).
    let yaw = -mix[3].iter().copied().fold(f64::INFINITY, f64::min);
    // Thrust: the mean magnitude of the actuators' thrust entries over those
    // with a nonzero one.
    let nonzero = mix[0].iter().filter(|x| x.abs() > FLT_EPSILON).count();
    let thrust = if nonzero > 0 { mix[0].iter().map(|x| x.abs()).sum::<f64>() / nonzero as f64 } else { 1.0 };
    let mut scale = [1.0; 4];
    if rp > FLT_EPSILON {
        scale[1] = rp;
        scale[2] = rp;
    }
    if yaw > FLT_EPSILON {
        scale[3] = yaw;
    }
    if thrust > FLT_EPSILON {
        scale[0] = thrust;
    }
    scale
}

/// Inverse of a 4×4 matrix by Gauss–Jordan elimination with partial
/// pivoting; `None` if a pivot is below `1e-12` of the largest entry (or the
/// matrix has no finite nonzero entry).
pub fn invert4(a: &[[f64; 4]; 4]) -> Option<[[f64; 4]; 4]> {
    let scale = a.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    if !scale.is_normal() {
        return None;
    }
    let mut m = *a;
    let mut inv = [[0.0; 4]; 4];
    for (i, row) in inv.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    for col in 0..4 {
        let pivot = (col..4).max_by(|&r, &s| m[r][col].abs().total_cmp(&m[s][col].abs()))?;
        if m[pivot][col].abs() < 1e-12 * scale {
            return None;
        }
        m.swap(col, pivot);
        inv.swap(col, pivot);
        let d = m[col][col];
        for k in 0..4 {
            m[col][k] /= d;
            inv[col][k] /= d;
        }
        for r in 0..4 {
            if r != col {
                let f = m[r][col];
                for k in 0..4 {
                    m[r][k] -= f * m[col][k];
                    inv[r][k] -= f * inv[col][k];
                }
            }
        }
    }
    Some(inv)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closed_forms_are_the_general_path() {
        for l in [0.043, 0.17, 0.21, 0.24607] {
            for g in [RotorGeometry::Plus { arm_length: l }, RotorGeometry::Cross { arm_length: l }] {
                let closed = g.px4_torque_scale(2.5, 0.016).unwrap();
                let general = g.px4_torque_scale_general(2.5, 0.016).unwrap();
                for k in 0..3 {
                    assert!(
                        (closed[k] - general[k]).abs() <= 1e-12 * closed[k],
                        "{g:?} axis {k}: {closed:?} {general:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn a_square_cross_has_root_two_the_torque_of_a_plus() {
        let plus = RotorGeometry::Plus { arm_length: 0.2 }.px4_torque_scale(1.0, 0.02).unwrap();
        let cross = RotorGeometry::Cross { arm_length: 0.2 }.px4_torque_scale(1.0, 0.02).unwrap();
        assert!((cross[0] / plus[0] - core::f64::consts::SQRT_2).abs() < 1e-15);
        assert_eq!(cross[2], plus[2]);
    }

    #[test]
    fn a_degenerate_layout_is_refused() {
        let line = RotorGeometry::Custom {
            positions: [[0.1, 0.0], [0.2, 0.0], [-0.1, 0.0], [-0.2, 0.0]],
            spin: PAPER_SPIN_SIGNS,
        };
        assert_eq!(line.px4_torque_scale(1.0, 0.02), None);
    }
}
