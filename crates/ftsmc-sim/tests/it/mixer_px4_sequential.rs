//! `[actuators] mixer = "px4"` against a separate, plain transcription of
//! PX4's `ControlAllocationSequentialDesaturation` with airmode off
//! (PX4-Autopilot `src/modules/control_allocator/ControlAllocation/`):
//! PX4's axis order (roll, pitch, yaw, thrust x, y, z), its effectiveness
//! matrix in actuator units (fractions of full thrust, thrust along −z), the
//! pseudo-inverse (here the inverse: four rotors, four axes), the
//! normalisation of `updateControlAllocationMatrixScale`, the steps of
//! `mixAirmodeDisabled` / `mixYaw` and the final clip. On 10,000 random
//! saturated commands per vehicle the rotor setpoints agree to 1e-12,
//! including the commands where the roll-then-pitch desaturation turns the
//! direction of the tilting torque.

use ftsmc_core::model::{Command, QuadrotorParams};
use ftsmc_sim::actuators::{paper_allocation_matrix, ActuatorParams, Mixer, MixerKind};
use ftsmc_sim::vehicle::{Configuration, RigidBodyParams, VehiclePreset};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

const ROLL: usize = 0;
const PITCH: usize = 1;
const YAW: usize = 2;
const THRUST_Z: usize = 5;

/// Solve `m x = b` by Gaussian elimination with partial pivoting.
fn solve(m: [[f64; 4]; 4], b: [f64; 4]) -> [f64; 4] {
    let mut a = m;
    let mut y = b;
    for c in 0..4 {
        let p = (c..4).max_by(|&r, &s| a[r][c].abs().partial_cmp(&a[s][c].abs()).unwrap()).unwrap();
        a.swap(c, p);
        y.swap(c, p);
        for r in c + 1..4 {
            let f = a[r][c] / a[c][c];
            for k in c..4 {
                a[r][k] -= f * a[c][k];
            }
            y[r] -= f * y[c];
        }
    }
    let mut x = [0.0; 4];
    for c in (0..4).rev() {
        let s: f64 = (c + 1..4).map(|k| a[c][k] * x[k]).sum();
        x[c] = (y[c] - s) / a[c][c];
    }
    x
}

struct Px4 {
    /// `mix[i][axis]`, 4 actuators × 6 axes, normalised.
    mix: [[f64; 6]; 4],
    scale: [f64; 6],
    min: f64,
    max: f64,
}

impl Px4 {
    /// From ftsmc's allocation `[U1, τx, τy, τz] = A w` and the speed limits.
    fn new(a: [[f64; 4]; 4], w_min: f64, w_max: f64) -> Self {
        // Effectiveness in actuator units x = w / w_max, PX4's rows:
        // roll, pitch, yaw torque, then thrust x, y, z (z down).
        let mut b = [[0.0f64; 4]; 6];
        for i in 0..4 {
            b[ROLL][i] = a[1][i] * w_max;
            b[PITCH][i] = a[2][i] * w_max;
            b[YAW][i] = a[3][i] * w_max;
            b[THRUST_Z][i] = -a[0][i] * w_max;
        }
        // The square part [roll, pitch, yaw, thrust_z] is invertible: its
        // inverse is the pseudo-inverse's nonzero columns.
        let rows = [ROLL, PITCH, YAW, THRUST_Z];
        let sq: [[f64; 4]; 4] = core::array::from_fn(|r| b[rows[r]]);
        let mut mix = [[0.0f64; 6]; 4];
        for (c, &axis) in rows.iter().enumerate() {
            let e: [f64; 4] = core::array::from_fn(|k| if k == c { 1.0 } else { 0.0 });
            let col = solve(sq, e);
            for i in 0..4 {
                mix[i][axis] = col[i];
            }
        }
        // updateControlAllocationMatrixScale, normalize_rpy on.
        let mut scale = [1.0f64; 6];
        let count = |axis: usize| (0..4).filter(|&i| mix[i][axis].abs() > 1e-3).count();
        let norm_sq = |axis: usize| (0..4).map(|i| mix[i][axis] * mix[i][axis]).sum::<f64>();
        let (nr, np) = (count(ROLL), count(PITCH));
        let roll_scale = if nr > 0 { (norm_sq(ROLL) / (nr as f64 / 2.0)).sqrt() } else { 1.0 };
        let pitch_scale = if np > 0 { (norm_sq(PITCH) / (np as f64 / 2.0)).sqrt() } else { 1.0 };
        scale[ROLL] = roll_scale.max(pitch_scale);
        scale[PITCH] = scale[ROLL];
        scale[YAW] = (0..4).map(|i| mix[i][YAW]).fold(f64::NEG_INFINITY, f64::max);
        let mut norm_sum = 0.0;
        let mut nonzero = 0;
        for row in &mix {
            let n = (row[3] * row[3] + row[4] * row[4] + row[5] * row[5]).sqrt();
            norm_sum += n;
            if n > f32::EPSILON as f64 {
                nonzero += 1;
            }
        }
        for axis in 3..6 {
            scale[axis] = if nonzero > 0 { norm_sum / nonzero as f64 } else { 1.0 };
        }
        // normalizeControlAllocationMatrix.
        let eps = f32::EPSILON as f64;
        for row in mix.iter_mut() {
            if scale[0] > eps {
                row[0] /= scale[0];
                row[1] /= scale[1];
            }
            if scale[2] > eps {
                row[2] /= scale[2];
            }
            if scale[3] > eps {
                row[3] /= scale[3];
                row[4] /= scale[4];
                row[5] /= scale[5];
            }
            for x in row.iter_mut() {
                if x.abs() < 1e-3 {
                    *x = 0.0;
                }
            }
        }
        // A scale PX4 does not apply converts nothing.
        for s in scale.iter_mut() {
            if *s <= eps {
                *s = 1.0;
            }
        }
        Px4 { mix, scale, min: w_min / w_max, max: 1.0 }
    }

    fn gain(&self, d: &[f64; 4], sp: &[f64; 4], max: f64) -> f64 {
        let mut k_min = 0.0f64;
        let mut k_max = 0.0f64;
        for i in 0..4 {
            if d[i].abs() < 0.2 {
                continue;
            }
            if sp[i] < self.min {
                let k = (self.min - sp[i]) / d[i];
                if k < k_min {
                    k_min = k;
                }
                if k > k_max {
                    k_max = k;
                }
            }
            if sp[i] > max {
                let k = (max - sp[i]) / d[i];
                if k < k_min {
                    k_min = k;
                }
                if k > k_max {
                    k_max = k;
                }
            }
        }
        k_min + k_max
    }

    fn desaturate(&self, sp: &mut [f64; 4], d: &[f64; 4], increase_only: bool, max: f64) {
        let g = self.gain(d, sp, max);
        if increase_only && g < 0.0 {
            return;
        }
        for i in 0..4 {
            sp[i] += g * d[i];
        }
        let g = 0.5 * self.gain(d, sp, max);
        for i in 0..4 {
            sp[i] += g * d[i];
        }
    }

    /// Actuator setpoints (fractions of ω_max²) for a command.
    fn allocate(&self, c: &Command) -> [f64; 4] {
        let mut control = [0.0f64; 6];
        control[ROLL] = c.torque[0] * self.scale[ROLL];
        control[PITCH] = c.torque[1] * self.scale[PITCH];
        control[YAW] = c.torque[2] * self.scale[YAW];
        control[THRUST_Z] = -c.thrust * self.scale[THRUST_Z];
        let col = |axis: usize| -> [f64; 4] { core::array::from_fn(|i| self.mix[i][axis]) };
        // mixAirmodeDisabled.
        let mut sp = [0.0f64; 4];
        for i in 0..4 {
            sp[i] = self.mix[i][ROLL] * control[ROLL]
                + self.mix[i][PITCH] * control[PITCH]
                + self.mix[i][THRUST_Z] * control[THRUST_Z];
        }
        self.desaturate(&mut sp, &col(THRUST_Z), true, self.max);
        self.desaturate(&mut sp, &col(ROLL), false, self.max);
        self.desaturate(&mut sp, &col(PITCH), false, self.max);
        // mixYaw.
        for i in 0..4 {
            sp[i] += self.mix[i][YAW] * control[YAW];
        }
        let raised = self.max + (self.max - self.min) * 0.15;
        self.desaturate(&mut sp, &col(YAW), false, raised);
        self.desaturate(&mut sp, &col(THRUST_Z), true, self.max);
        // clipActuatorSetpoint.
        sp.map(|x| {
            if x < self.min {
                self.min
            } else if x > self.max {
                self.max
            } else {
                x
            }
        })
    }
}

fn vehicles() -> Vec<(&'static str, [[f64; 4]; 4], ActuatorParams)> {
    let paper = QuadrotorParams::default();
    let hb = RigidBodyParams::hummingbird();
    let plus = RigidBodyParams { configuration: Configuration::Plus, ..RigidBodyParams::crazyflie() };
    let act = |w_min: f64, w_max: f64| ActuatorParams {
        min_rotor_speed: w_min,
        max_rotor_speed: w_max,
        mixer: MixerKind::Px4,
        ..ActuatorParams::default()
    };
    vec![
        ("paper +", paper_allocation_matrix(&paper), act(0.0, 400.0)),
        ("hummingbird ×", hb.allocation_matrix(), act(100.0, 838.0)),
        ("crazyflie +", plus.allocation_matrix(), act(0.0, 2500.0)),
    ]
}

#[test]
fn the_px4_mixer_is_px4s_sequential_desaturation_on_10000_saturated_commands() {
    let mut rng = ChaCha8Rng::seed_from_u64(38);
    for (name, a, act) in vehicles() {
        let mixer = Mixer::new(a, &act).unwrap();
        let w_min = act.min_rotor_speed * act.min_rotor_speed;
        let w_max = act.max_rotor_speed * act.max_rotor_speed;
        let reference = Px4::new(a, w_min, w_max);
        let exact = Mixer::new(a, &ActuatorParams { mixer: MixerKind::Px4Exact, ..act }).unwrap();
        let t_max = mixer.thrust_range()[1];
        // Torque scales: what one rotor pair gives at full speed.
        let tau_rp = (a[1].iter().map(|x| x.abs()).fold(0.0, f64::max)) * w_max;
        let tau_y = a[3][0].abs() * w_max;
        let (mut saturated, mut turned, mut yaw_cut_thrust) = (0, 0, 0);
        while saturated < 10_000 {
            let c = Command {
                thrust: rng.random_range(0.0..1.1) * t_max,
                torque: [
                    rng.random_range(-1.5..1.5) * tau_rp,
                    rng.random_range(-1.5..1.5) * tau_rp,
                    rng.random_range(-1.5..1.5) * tau_y,
                ],
            };
            let out = mixer.mix(&c);
            if !exact.mix(&c).saturated {
                continue; // feasible: not one of the saturated commands
            }
            saturated += 1;
            let expected = reference.allocate(&c);
            let got = out.rotor_speeds.map(|w| w * w / w_max);
            for i in 0..4 {
                assert!((got[i] - expected[i]).abs() <= 1e-12, "{name}: {c:?}: rotor {i}: {got:?} vs {expected:?}");
            }
            // The delivered command is what the rotors make.
            let delivered = mixer.forces(&out.rotor_speeds.map(|w| w * w));
            assert!((delivered.thrust - out.applied.thrust).abs() <= 1e-9 * t_max, "{name}");
            let angle = |t: &[f64; 3]| ftsmc_core::math::atan2(t[1], t[0]);
            let applied_rp = ftsmc_core::math::hypot(out.applied.torque[0], out.applied.torque[1]);
            if applied_rp > 1e-6 * tau_rp {
                let mut d = (angle(&out.applied.torque) - angle(&c.torque)).abs();
                if d > std::f64::consts::PI {
                    d = 2.0 * std::f64::consts::PI - d;
                }
                if d > 1f64.to_radians() {
                    turned += 1;
                }
            }
            let exact_out = exact.mix(&c);
            if out.applied.thrust < exact_out.applied.thrust - 1e-9 * t_max && c.torque[2].abs() > 0.5 * tau_y {
                yaw_cut_thrust += 1;
            }
        }
        eprintln!("{name}: {saturated} saturated, {turned} turned > 1°, {yaw_cut_thrust} thrust lowered for yaw");
        // The cases the issue asks for are among them.
        assert!(turned > 500, "{name}: only {turned} commands turned the tilting torque");
        assert!(
            yaw_cut_thrust > 100,
            "{name}: only {yaw_cut_thrust} commands lowered the thrust further than px4-exact"
        );
    }
}

#[test]
fn a_feasible_command_keeps_its_forces_with_the_px4_mixer() {
    for (name, a, act) in vehicles() {
        let mixer = Mixer::new(a, &act).unwrap();
        let t = 0.5 * mixer.thrust_range()[1];
        let c = Command { thrust: t, torque: [0.0, 0.0, 0.0] };
        let out = mixer.mix(&c);
        assert!(!out.saturated, "{name}");
        assert_eq!(out.applied, c, "{name}");
    }
}

/// PX4 takes the yaw scale as the largest entry of the yaw column in
/// its own (z-down) frame, the negated smallest in ftsmc's. On the "+"
/// and square "×" layouts of every preset the column is symmetric bit
/// for bit, so this is the largest entry of ftsmc's column, as before
/// the scales moved to `ftsmc_core::rotor_layout` (the flights of the
/// square layouts keep their bits).
#[test]
fn square_layouts_have_symmetric_yaw_columns() {
    let mut bodies = vec![RigidBodyParams::default(), RigidBodyParams::crazyflie(), RigidBodyParams::hummingbird()];
    for preset in VehiclePreset::ALL {
        let s = ftsmc_sim::scenario::Scenario::from_toml_str(
            &format!("extends = \"realistic-calm-1\"\nname = \"p\"\n[vehicle]\npreset = \"{}\"\n", preset.name()),
            "test",
        )
        .unwrap();
        bodies.push(s.rigid_body_params());
    }
    let mut squares = 0;
    for rb in bodies {
        if rb.configuration == Configuration::Custom {
            continue;
        }
        squares += 1;
        let inverse = ftsmc_core::rotor_layout::invert4(&rb.allocation_matrix()).unwrap();
        let yaw: [f64; 4] = core::array::from_fn(|i| inverse[i][3]);
        let max = yaw.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let min = yaw.iter().copied().fold(f64::INFINITY, f64::min);
        assert_eq!(max.to_bits(), (-min).to_bits(), "{:?}: {yaw:?}", rb.configuration);
    }
    assert!(squares >= 6, "{squares}");
}
