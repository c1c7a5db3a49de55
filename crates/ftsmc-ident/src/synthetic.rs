//! A flight made by ftsmc's own plant and motors, as a log: the known truth
//! that identification must recover and validation must reproduce.
//!
//! ftsmc's rigid body and motor lag ([`crate::validate::step`]: RK4
//! substeps, rotor speeds held over each) fly a Lissajous figure
//! (`x = 1.0 sin 0.7t`, `y = 0.8 sin 1.1t`, `z = 1 + 0.3 sin 0.5t`, m)
//! under a geometric controller (Lee, Leok and McClamroch 2010: position
//! PD, attitude error `e_R = ½ (R_dᵀR − RᵀR_d)^∨`), its rotor speeds
//! allocated by the vehicle's allocation matrix, plus a dither on every
//! rotor command (uniform in `±dither`, a new value every 0.1 s) so that
//! every parameter is excited. Each sample logs the state, the
//! accelerometer's specific force of the plant, and the command `u = ω/ω_max`
//! held until the next sample; noise (Gaussian, one ChaCha stream per
//! channel of `seed`) is added to the logged velocity, body rates and
//! specific force only.

use ftsmc_logs::{FlightLog, Frame, MotorUnit, Motors as LogMotors};
use ftsmc_sim::actuators::Motors;
use ftsmc_sim::gauss::standard_normal;
use ftsmc_sim::vehicle::rigid_body::{rotation_matrix, RigidBody};
use rand::Rng;

use crate::error::IdentError;
use crate::validate::{specific_force, step};
use crate::vehicle::Vehicle;

/// Settings of [`fly`].
#[derive(Clone, Debug, PartialEq)]
pub struct SyntheticOptions {
    /// Flight time, s (default 30).
    pub duration_s: f64,
    /// Log rate, Hz (default 200).
    pub rate_hz: f64,
    /// RK4 steps per log step (default 4, as validation's).
    pub substeps: usize,
    /// Amplitude of the command dither, 0–1 (default 0.04).
    pub dither: f64,
    /// σ of the accelerometer noise, m/s² (default 0).
    pub accel_noise_m_s2: f64,
    /// σ of the gyro noise, rad/s (default 0).
    pub gyro_noise_rad_s: f64,
    /// σ of the velocity noise, m/s (default 0).
    pub velocity_noise_m_s: f64,
    /// Seed of the dither and noise.
    pub seed: u64,
}

impl Default for SyntheticOptions {
    fn default() -> Self {
        Self {
            duration_s: 30.0,
            rate_hz: 200.0,
            substeps: 4,
            dither: 0.04,
            accel_noise_m_s2: 0.0,
            gyro_noise_rad_s: 0.0,
            velocity_noise_m_s: 0.0,
            seed: 0,
        }
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}
fn unit(a: [f64; 3]) -> [f64; 3] {
    let n = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    a.map(|x| x / n)
}

/// Solves the 4×4 system `a x = b` (Gaussian elimination, partial pivoting).
fn solve4(mut a: [[f64; 4]; 4], mut b: [f64; 4]) -> [f64; 4] {
    for c in 0..4 {
        let p = (c..4).max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs())).unwrap_or(c);
        a.swap(c, p);
        b.swap(c, p);
        for r in c + 1..4 {
            let f = a[r][c] / a[c][c];
            for k in c..4 {
                a[r][k] -= f * a[c][k];
            }
            b[r] -= f * b[c];
        }
    }
    let mut x = [0.0; 4];
    for r in (0..4).rev() {
        let mut s = b[r];
        for k in r + 1..4 {
            s -= a[r][k] * x[k];
        }
        x[r] = s / a[r][r];
    }
    x
}

/// The reference and its first two derivatives at `t`.
fn reference(t: f64) -> [[f64; 3]; 3] {
    use ftsmc_core::math::{cos, sin};
    let (a, b, c) = ([1.0, 0.8, 0.3], [0.7, 1.1, 0.5], [0.0, 0.0, 1.0]);
    let mut out = [[0.0; 3]; 3];
    for i in 0..3 {
        out[0][i] = c[i] + a[i] * sin(b[i] * t);
        out[1][i] = a[i] * b[i] * cos(b[i] * t);
        out[2][i] = -a[i] * b[i] * b[i] * sin(b[i] * t);
    }
    out
}

/// Flies `vehicle` (module docs) and returns the flight as a log in
/// ftsmc's frames (`ZUpFlu`) and numbering, commands normalised.
pub fn fly(vehicle: &Vehicle, o: &SyntheticOptions) -> Result<FlightLog, IdentError> {
    let body = RigidBody::new(vehicle.body)
        .map_err(|e| IdentError::Vehicle { vehicle: vehicle.name.clone(), message: e.to_string() })?;
    let p = vehicle.body;
    let w_max = vehicle.max_rotor_speed();
    let dt = 1.0 / o.rate_hz;
    let n = (o.duration_s * o.rate_hz).round() as usize + 1;
    let alloc = p.allocation_matrix();
    let j = [p.inertia[0][0], p.inertia[1][1], p.inertia[2][2]];
    let stream = |s| ftsmc_sim::rng::chacha_stream(o.seed, s);
    let (mut dither_rng, mut acc_rng, mut gyro_rng, mut vel_rng) = (stream(1), stream(2), stream(3), stream(4));
    let r0 = reference(0.0);
    let mut x = [0.0; 13];
    x[0..3].copy_from_slice(&r0[0]);
    x[3..6].copy_from_slice(&r0[1]);
    x[6] = 1.0;
    let hover = p.hover_rotor_speed() / w_max;
    let mut motors = Motors::new(&vehicle.actuators, [hover * w_max; 4]);
    let mut dither = [0.0; 4];
    let mut log = FlightLog {
        source: format!("synthetic {} seed {}", vehicle.name, o.seed),
        frame: Frame::ZUpFlu,
        time_origin_s: 0.0,
        time_s: Vec::with_capacity(n),
        position_m: Some(Vec::with_capacity(n)),
        velocity_m_s: Some(Vec::with_capacity(n)),
        attitude_wxyz: Some(Vec::with_capacity(n)),
        body_rates_rad_s: Some(Vec::with_capacity(n)),
        accel_m_s2: Some(Vec::with_capacity(n)),
        motors: Some(LogMotors { unit: MotorUnit::Normalised, values: Vec::with_capacity(n) }),
        battery_v: None,
        setpoint: None,
    };
    let every = ((0.1 * o.rate_hz).round() as usize).max(1);
    for k in 0..n {
        let t = k as f64 * dt;
        let [pr, vr, ar] = reference(t);
        let pos = [x[0], x[1], x[2]];
        let vel = [x[3], x[4], x[5]];
        let q = [x[6], x[7], x[8], x[9]];
        let w = [x[10], x[11], x[12]];
        let r = rotation_matrix(&q);
        let ep = sub(pr, pos);
        let ev = sub(vr, vel);
        let ad: [f64; 3] =
            core::array::from_fn(|i| 2.0 * ep[i] + 2.5 * ev[i] + ar[i] + if i == 2 { p.gravity } else { 0.0 });
        let b3 = [r[0][2], r[1][2], r[2][2]];
        let thrust = p.mass * (ad[0] * b3[0] + ad[1] * b3[1] + ad[2] * b3[2]);
        let b3d = unit(ad);
        let b2d = unit(cross(b3d, [1.0, 0.0, 0.0]));
        let b1d = cross(b2d, b3d);
        let rd = [[b1d[0], b2d[0], b3d[0]], [b1d[1], b2d[1], b3d[1]], [b1d[2], b2d[2], b3d[2]]];
        // M = R_dᵀ R − Rᵀ R_d; e_R = ½ M^∨.
        let mut m = [[0.0; 3]; 3];
        for a in 0..3 {
            for b in 0..3 {
                for c in 0..3 {
                    m[a][b] += rd[c][a] * r[c][b] - r[c][a] * rd[c][b];
                }
            }
        }
        let er = [0.5 * m[2][1], 0.5 * m[0][2], 0.5 * m[1][0]];
        let jw = [j[0] * w[0], j[1] * w[1], j[2] * w[2]];
        let gyro = cross(w, jw);
        let tau: [f64; 3] = core::array::from_fn(|a| j[a] * (-36.0 * er[a] - 10.0 * w[a]) + gyro[a]);
        let w2 = solve4(alloc, [thrust, tau[0], tau[1], tau[2]]);
        if k % every == 0 {
            dither = core::array::from_fn(|_| o.dither * (2.0 * uniform(&mut dither_rng) - 1.0));
        }
        let u: [f64; 4] = core::array::from_fn(|i| (w2[i].max(0.0).sqrt() / w_max + dither[i]).clamp(0.0, 1.0));
        if k == 0 {
            motors = Motors::new(&vehicle.actuators, u.map(|c| c * w_max));
        }
        let f = specific_force(&body, &x, &motors.speeds());
        let noisy = |v: [f64; 3], s: f64, rng: &mut rand_chacha::ChaCha8Rng| {
            if s > 0.0 {
                v.map(|c| c + s * standard_normal(rng))
            } else {
                v
            }
        };
        log.time_s.push(t);
        log.position_m.as_mut().unwrap().push(pos);
        log.velocity_m_s.as_mut().unwrap().push(noisy(vel, o.velocity_noise_m_s, &mut vel_rng));
        log.attitude_wxyz.as_mut().unwrap().push(q);
        log.body_rates_rad_s.as_mut().unwrap().push(noisy(w, o.gyro_noise_rad_s, &mut gyro_rng));
        log.accel_m_s2.as_mut().unwrap().push(noisy(f, o.accel_noise_m_s2, &mut acc_rng));
        log.motors.as_mut().unwrap().values.push(u);
        x = step(&body, &mut motors, &x, &u, w_max, dt, o.substeps);
        if !x.iter().all(|v| v.is_finite()) {
            return Err(IdentError::Vehicle {
                vehicle: vehicle.name.clone(),
                message: format!("the synthetic flight diverged at {t} s"),
            });
        }
    }
    Ok(log)
}

fn uniform(rng: &mut rand_chacha::ChaCha8Rng) -> f64 {
    (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// `log` in the generic CSV schema (docs/logs.md), `# frame:` line
/// included; numbers in Rust's shortest round-trip form, so reading it
/// back gives the same bits.
pub fn to_generic_csv(log: &FlightLog) -> String {
    let frame = match log.frame {
        Frame::ZUpFlu => "# frame: zup-flu\n",
        Frame::NedFrd => "# frame: ned-frd\n",
        Frame::Unspecified => "",
    };
    let mut out = String::from(frame);
    let mut header = vec!["time_s"];
    let groups: [(bool, &[&str]); 8] = [
        (log.position_m.is_some(), &["x_m", "y_m", "z_m"]),
        (log.velocity_m_s.is_some(), &["vx_m_s", "vy_m_s", "vz_m_s"]),
        (log.attitude_wxyz.is_some(), &["qw", "qx", "qy", "qz"]),
        (log.body_rates_rad_s.is_some(), &["p_rad_s", "q_rad_s", "r_rad_s"]),
        (log.accel_m_s2.is_some(), &["ax_m_s2", "ay_m_s2", "az_m_s2"]),
        (log.motors.is_some(), &["motor1", "motor2", "motor3", "motor4"]),
        (log.battery_v.is_some(), &["battery_v"]),
        (log.setpoint.is_some(), &["sp_x_m", "sp_y_m", "sp_z_m", "sp_yaw_rad"]),
    ];
    for (on, names) in groups {
        if on {
            header.extend_from_slice(names);
        }
    }
    out.push_str(&header.join(","));
    out.push('\n');
    for k in 0..log.len() {
        let mut row: Vec<f64> = vec![log.time_s[k]];
        if let Some(v) = &log.position_m {
            row.extend_from_slice(&v[k]);
        }
        if let Some(v) = &log.velocity_m_s {
            row.extend_from_slice(&v[k]);
        }
        if let Some(v) = &log.attitude_wxyz {
            row.extend_from_slice(&v[k]);
        }
        if let Some(v) = &log.body_rates_rad_s {
            row.extend_from_slice(&v[k]);
        }
        if let Some(v) = &log.accel_m_s2 {
            row.extend_from_slice(&v[k]);
        }
        if let Some(m) = &log.motors {
            row.extend_from_slice(&m.values[k]);
        }
        if let Some(v) = &log.battery_v {
            row.push(v[k]);
        }
        if let Some(sp) = &log.setpoint {
            row.extend_from_slice(&sp.position_m[k]);
            row.push(sp.yaw_rad[k]);
        }
        let cells: Vec<String> = row.iter().map(|v| format!("{v:?}")).collect();
        out.push_str(&cells.join(","));
        out.push('\n');
    }
    out
}
