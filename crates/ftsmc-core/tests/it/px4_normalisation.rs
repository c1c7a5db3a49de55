//! `ftsmc_core::rotor_layout` against a transcription of PX4's own code
//! (PX4-Autopilot `src/modules/control_allocator/`):
//! `ActuatorEffectivenessRotors::computeEffectivenessMatrix` builds the
//! six-axis effectiveness in PX4's forward-right-down body frame from
//! `CA_ROTOR{n}_P{X,Y,Z}`, `_CT`, `_KM`; `matrix::geninv` pseudo-inverts it;
//! `ControlAllocationPseudoInverse::updateControlAllocationMatrixScale` and
//! `normalizeControlAllocationMatrix` scale the mix. The transcription keeps
//! PX4's frame, its six axes and its own thrust coefficient `CT` (PX4's
//! default 6.5); only `f32` becomes `f64`. The physical torque of a
//! normalised command of 1 is then `(T_r / CT) / scale` (PX4's effectiveness
//! is the physical one divided by `T_r / CT`), which ftsmc's
//! [`RotorGeometry::px4_torque_scale`] must give to 1e-12, and the
//! normalised mixes must agree entry by entry (with the frame's signs).

use ftsmc_core::rotor_layout::{invert4, px4_scales, RotorGeometry, PAPER_SPIN_SIGNS};

const FLT_EPSILON: f64 = f32::EPSILON as f64;

/// One PX4 rotor: position in FRD (m), `CA_ROTOR{n}_KM`, `CA_ROTOR{n}_CT`.
struct Px4Rotor {
    position: [f64; 3],
    km: f64,
    ct: f64,
}

/// `computeEffectivenessMatrix` for upward rotors (axis (0, 0, −1)):
/// `moment = ct·(position × axis) − ct·km·axis`, `thrust = ct·axis`;
/// rows roll, pitch, yaw, Tx, Ty, Tz.
fn px4_effectiveness(rotors: &[Px4Rotor; 4]) -> [[f64; 4]; 6] {
    let mut e = [[0.0; 4]; 6];
    for (i, r) in rotors.iter().enumerate() {
        let axis = [0.0, 0.0, -1.0];
        let p = r.position;
        let cross = [p[1] * axis[2] - p[2] * axis[1], p[2] * axis[0] - p[0] * axis[2], p[0] * axis[1] - p[1] * axis[0]];
        for j in 0..3 {
            e[j][i] = r.ct * cross[j] - r.ct * r.km * axis[j];
            e[j + 3][i] = r.ct * axis[j];
        }
    }
    e
}

/// `geninv` of a 6×4 matrix of rank 4: `(EᵀE)⁻¹ Eᵀ`, 4×6 (actuator × axis).
fn pinv(e: &[[f64; 4]; 6]) -> [[f64; 6]; 4] {
    let mut ete = [[0.0; 4]; 4];
    for a in 0..4 {
        for b in 0..4 {
            ete[a][b] = (0..6).map(|k| e[k][a] * e[k][b]).sum();
        }
    }
    let inv = invert4(&ete).expect("full rank");
    let mut out = [[0.0; 6]; 4];
    for i in 0..4 {
        for k in 0..6 {
            out[i][k] = (0..4).map(|j| inv[i][j] * e[k][j]).sum();
        }
    }
    out
}

/// `updateControlAllocationMatrixScale` with `_normalize_rpy` (multicopter):
/// the six scales, then `normalizeControlAllocationMatrix`.
fn px4_normalise(mix: &mut [[f64; 6]; 4]) -> [f64; 6] {
    let col = |m: &[[f64; 6]; 4], k: usize| -> [f64; 4] { core::array::from_fn(|i| m[i][k]) };
    let norm_scale = |c: [f64; 4]| {
        let n = c.iter().filter(|x| x.abs() > 1e-3).count();
        if n > 0 {
            (c.iter().map(|x| x * x).sum::<f64>() / (n as f64 / 2.0)).sqrt()
        } else {
            1.0
        }
    };
    let mut s = [1.0; 6];
    s[0] = norm_scale(col(mix, 0)).max(norm_scale(col(mix, 1)));
    s[1] = s[0];
    s[2] = col(mix, 2).iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mut n = 0;
    let mut sum = 0.0;
    for row in mix.iter() {
        let norm = (row[3] * row[3] + row[4] * row[4] + row[5] * row[5]).sqrt();
        sum += norm;
        if norm > FLT_EPSILON {
            n += 1;
        }
    }
    if n > 0 {
        s[3] = sum / n as f64;
        s[4] = s[3];
        s[5] = s[3];
    }
    for row in mix.iter_mut() {
        if s[0] > FLT_EPSILON {
            row[0] /= s[0];
            row[1] /= s[1];
        }
        if s[2] > FLT_EPSILON {
            row[2] /= s[2];
        }
        if s[3] > FLT_EPSILON {
            row[3] /= s[3];
            row[4] /= s[4];
            row[5] /= s[5];
        }
        for x in row.iter_mut() {
            if x.abs() < 1e-3 {
                *x = 0.0;
            }
        }
    }
    s
}

/// PX4's rotors of an ftsmc geometry: FRD positions `(x, −y, 0)`, `KM =
/// s_i k` (positive counter-clockwise), PX4's default `CT` 6.5.
fn px4_rotors(g: &RotorGeometry, k: f64) -> [Px4Rotor; 4] {
    let (p, s) = (g.positions(), g.spin());
    core::array::from_fn(|i| Px4Rotor { position: [p[i][0], -p[i][1], 0.0], km: s[i] * k, ct: 6.5 })
}

fn check(name: &str, g: RotorGeometry, rotor_thrust: f64, k: f64) {
    let rotors = px4_rotors(&g, k);
    let mut mix = pinv(&px4_effectiveness(&rotors));
    let s = px4_normalise(&mut mix);
    let to_physical = rotor_thrust / 6.5;
    let px4 = [to_physical / s[0], to_physical / s[1], to_physical / s[2]];
    let ours = g.px4_torque_scale(rotor_thrust, k).expect("full rank");
    for a in 0..3 {
        assert!((ours[a] - px4[a]).abs() <= 1e-12 * px4[a], "{name} axis {a}: ftsmc {} PX4 {}", ours[a], px4[a]);
    }
    // The normalised mixes: ftsmc's (thrust up, roll, pitch, yaw in FLU)
    // against PX4's (Tz down, roll, pitch, yaw in FRD).
    let inverse = invert4(&g.effectiveness(rotor_thrust, k)).unwrap();
    let raw: [[f64; 4]; 4] = core::array::from_fn(|c| core::array::from_fn(|i| inverse[i][c]));
    let scale = px4_scales(&raw);
    for i in 0..4 {
        let ours = [raw[0][i] / scale[0], raw[1][i] / scale[1], raw[2][i] / scale[2], raw[3][i] / scale[3]];
        let theirs = [-mix[i][5], mix[i][0], -mix[i][1], -mix[i][2]];
        for c in 0..4 {
            let (o, t) = (if ours[c].abs() < 1e-3 { 0.0 } else { ours[c] }, theirs[c]);
            assert!((o - t).abs() <= 1e-12 * (1.0 + t.abs()), "{name} rotor {i} column {c}: ftsmc {o} PX4 {t}");
        }
    }
    println!("{name}: tau_max = {ours:?} N m");
}

#[test]
fn plus_layout() {
    check("plus 0.21 m", RotorGeometry::Plus { arm_length: 0.21 }, 7.375, 0.0108);
}

#[test]
fn square_cross() {
    check("cross 0.24607 m", RotorGeometry::Cross { arm_length: 0.24607 }, 8.54858, 0.016);
}

/// PX4's `4001_gz_x500` airframe: `CA_ROTOR0..3_PX/PY` = (0.13, 0.22),
/// (−0.13, −0.20), (0.13, −0.22), (−0.13, 0.20) in FRD, `KM` = 0.05, 0.05,
/// −0.05, −0.05; here in ftsmc's frame (y = −PY) and PX4's rotor order.
#[test]
fn gz_x500_airframe() {
    let positions = [[0.13, -0.22], [-0.13, 0.20], [0.13, 0.22], [-0.13, -0.20]];
    let g = RotorGeometry::Custom { positions, spin: [1.0, 1.0, -1.0, -1.0] };
    check("gz x500", g, 8.54858, 0.05);
}

/// The Agilicious racer's stretched ×: rotors at x = ±0.075 m, y = ±0.10 m.
#[test]
fn agilicious_stretched_cross() {
    let positions = [[0.075, 0.10], [0.075, -0.10], [-0.075, -0.10], [-0.075, 0.10]];
    check("agilicious", RotorGeometry::Custom { positions, spin: PAPER_SPIN_SIGNS }, 8.505, 0.022);
}

/// An asymmetric layout (no two arms alike) still matches entry by entry.
#[test]
fn an_irregular_layout() {
    let positions = [[0.2, 0.11], [0.05, -0.17], [-0.18, -0.09], [-0.07, 0.21]];
    check("irregular", RotorGeometry::Custom { positions, spin: PAPER_SPIN_SIGNS }, 3.0, 0.013);
}
