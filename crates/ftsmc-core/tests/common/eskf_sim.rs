//! A self-contained synthetic flight for the estimator tests: a smooth 3-D
//! motion driven by known body rates `ω(t)` and world acceleration `a(t)`,
//! the truth propagated by the same zero-order-hold kinematics the ESKF
//! assumes (so the filter's only model error is linearisation), biases
//! drifting as random walks, and IMU, GNSS, barometer, magnetometer and
//! motion-capture readings drawn with known noise from seeded ChaCha8
//! streams (one stream per source).

#![allow(dead_code)]

use ftsmc_core::estimate::eskf::{EskfConfig, InitialState};
use ftsmc_core::estimate::quaternion;
use ftsmc_core::estimate::{BaroReading, GnssFix, ImuSample, MagReading, MocapReading};
use ftsmc_core::kinematics::{quaternion_from_euler, rotation_from_quaternion};
use ftsmc_core::math::{cos, ln, mat_t_vec, mat_vec, sin, sqrt};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The true state at an IMU sample time.
#[derive(Clone, Copy, Debug)]
pub struct Truth {
    pub position: [f64; 3],
    pub velocity: [f64; 3],
    pub quaternion: [f64; 4],
    pub gyro_bias: [f64; 3],
    pub accel_bias: [f64; 3],
}

/// One reading, in time order; an IMU sample carries the truth at its time.
#[derive(Clone, Copy, Debug)]
pub enum Event {
    Imu(ImuSample, Truth),
    Gnss(GnssFix),
    Baro(BaroReading),
    Mag(MagReading),
    Mocap(MocapReading),
}

/// Sampling: IMU period and run length, and every how many IMU samples
/// each aiding sensor reads (0: never).
#[derive(Clone, Copy, Debug)]
pub struct Rates {
    pub imu_dt: f64,
    pub steps: usize,
    pub gnss_every: usize,
    pub baro_every: usize,
    pub mag_every: usize,
    pub mocap_every: usize,
}

/// Standard deviations of the aiding readings (units of the reading types).
#[derive(Clone, Copy, Debug)]
pub struct Noise {
    pub gnss_position: [f64; 3],
    pub gnss_velocity: [f64; 3],
    pub baro: f64,
    pub mag: f64,
    pub mocap_position: f64,
    pub mocap_attitude: f64,
}

impl Default for Noise {
    fn default() -> Self {
        Self {
            gnss_position: [0.3, 0.3, 0.5],
            gnss_velocity: [0.1, 0.1, 0.15],
            baro: 0.3,
            mag: 0.01,
            mocap_position: 0.01,
            mocap_attitude: 0.01,
        }
    }
}

/// A standard normal draw by Box–Muller from two 53-bit uniforms in (0, 1).
pub fn normal(rng: &mut ChaCha8Rng) -> f64 {
    let u = |x: u64| ((x >> 11) as f64 + 0.5) * (1.0 / 9007199254740992.0);
    let u1 = u(rng.next_u64());
    let u2 = u(rng.next_u64());
    sqrt(-2.0 * ln(u1)) * cos(2.0 * core::f64::consts::PI * u2)
}

fn normal3(rng: &mut ChaCha8Rng, std: f64) -> [f64; 3] {
    [normal(rng) * std, normal(rng) * std, normal(rng) * std]
}

fn stream(seed: u64, stream: u64) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream);
    rng
}

/// True body rate, rad/s, body frame.
fn omega(t: f64) -> [f64; 3] {
    [0.3 * sin(0.7 * t), 0.25 * cos(0.5 * t), 0.2 * sin(0.3 * t) + 0.1]
}

/// True acceleration, m/s², world frame.
fn accel(t: f64) -> [f64; 3] {
    [0.8 * sin(0.4 * t), 0.6 * cos(0.3 * t), 0.3 * sin(0.5 * t)]
}

fn add(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// The filter's starting state (the truth perturbed by a draw from `P₀`)
/// and the events of one run of seed `seed`.
pub fn simulate(config: &EskfConfig, rates: &Rates, noise: &Noise, seed: u64) -> (InitialState, Vec<Event>) {
    let mut init_rng = stream(seed, 0);
    let mut gyro_rng = stream(seed, 1);
    let mut accel_rng = stream(seed, 2);
    let mut bias_rng = stream(seed, 3);
    let mut gnss_rng = stream(seed, 4);
    let mut baro_rng = stream(seed, 5);
    let mut mag_rng = stream(seed, 6);
    let mut mocap_rng = stream(seed, 7);

    let mut truth = Truth {
        position: [0.0, 0.0, 1.0],
        velocity: [0.2, -0.1, 0.0],
        quaternion: quaternion_from_euler(&[0.05, -0.03, 0.4]),
        gyro_bias: normal3(&mut bias_rng, config.initial_gyro_bias_std),
        accel_bias: normal3(&mut bias_rng, config.initial_accel_bias_std),
    };
    // x̂₀ = x₀ ⊖ δx₀ with δx₀ ~ N(0, P₀).
    let dp = normal3(&mut init_rng, config.initial_position_std);
    let dv = normal3(&mut init_rng, config.initial_velocity_std);
    let dth = normal3(&mut init_rng, config.initial_attitude_std);
    let dbg = normal3(&mut init_rng, config.initial_gyro_bias_std);
    let dba = normal3(&mut init_rng, config.initial_accel_bias_std);
    let sub = |a: &[f64; 3], b: &[f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let initial = InitialState {
        position: sub(&truth.position, &dp),
        velocity: sub(&truth.velocity, &dv),
        quaternion: quaternion::multiply(&truth.quaternion, &quaternion::conjugate(&quaternion::exp(&dth))),
        gyro_bias: sub(&truth.gyro_bias, &dbg),
        accel_bias: sub(&truth.accel_bias, &dba),
    };

    let dt = rates.imu_dt;
    let g = config.gravity;
    let sg = config.gyro_noise / sqrt(dt);
    let sa = config.accel_noise / sqrt(dt);
    let mut events = Vec::new();
    let first = ImuSample {
        time: 0.0,
        gyro: add(&omega(0.0), &truth.gyro_bias),
        specific_force: add(
            &mat_t_vec(&rotation_from_quaternion(&truth.quaternion), &add(&accel(0.0), &[0.0, 0.0, g])),
            &truth.accel_bias,
        ),
    };
    events.push(Event::Imu(first, truth));
    for k in 1..=rates.steps {
        let t0 = (k - 1) as f64 * dt;
        let t = k as f64 * dt;
        let w = omega(t0);
        let a = accel(t0);
        let r = rotation_from_quaternion(&truth.quaternion);
        let f = mat_t_vec(&r, &add(&a, &[0.0, 0.0, g]));
        let imu = ImuSample {
            time: t,
            gyro: add(&add(&w, &truth.gyro_bias), &normal3(&mut gyro_rng, sg)),
            specific_force: add(&add(&f, &truth.accel_bias), &normal3(&mut accel_rng, sa)),
        };
        // Truth over [t0, t] with the inputs held (the filter's kinematics).
        let ra = mat_vec(&r, &f);
        let aw = [ra[0], ra[1], ra[2] - g];
        for i in 0..3 {
            truth.position[i] += truth.velocity[i] * dt + 0.5 * aw[i] * dt * dt;
            truth.velocity[i] += aw[i] * dt;
        }
        let wdt = [w[0] * dt, w[1] * dt, w[2] * dt];
        truth.quaternion = quaternion::normalize(&quaternion::multiply(&truth.quaternion, &quaternion::exp(&wdt)));
        truth.gyro_bias = add(&truth.gyro_bias, &normal3(&mut bias_rng, config.gyro_bias_random_walk * sqrt(dt)));
        truth.accel_bias = add(&truth.accel_bias, &normal3(&mut bias_rng, config.accel_bias_random_walk * sqrt(dt)));
        events.push(Event::Imu(imu, truth));

        if rates.gnss_every > 0 && k % rates.gnss_every == 0 {
            let mut fix = GnssFix {
                time: t,
                position: truth.position,
                velocity: truth.velocity,
                position_std: noise.gnss_position,
                velocity_std: noise.gnss_velocity,
                valid: true,
            };
            for i in 0..3 {
                fix.position[i] += normal(&mut gnss_rng) * noise.gnss_position[i];
                fix.velocity[i] += normal(&mut gnss_rng) * noise.gnss_velocity[i];
            }
            events.push(Event::Gnss(fix));
        }
        if rates.baro_every > 0 && k % rates.baro_every == 0 {
            let altitude = truth.position[2] + normal(&mut baro_rng) * noise.baro;
            events.push(Event::Baro(BaroReading { time: t, altitude, std: noise.baro }));
        }
        if rates.mag_every > 0 && k % rates.mag_every == 0 {
            let rt = rotation_from_quaternion(&truth.quaternion);
            let field = add(&mat_t_vec(&rt, &config.magnetic_field), &normal3(&mut mag_rng, noise.mag));
            events.push(Event::Mag(MagReading { time: t, field, std: noise.mag }));
        }
        if rates.mocap_every > 0 && k % rates.mocap_every == 0 {
            let position = add(&truth.position, &normal3(&mut mocap_rng, noise.mocap_position));
            let dq = quaternion::exp(&normal3(&mut mocap_rng, noise.mocap_attitude));
            events.push(Event::Mocap(MocapReading {
                time: t,
                position,
                quaternion: quaternion::multiply(&truth.quaternion, &dq),
                position_std: noise.mocap_position,
                attitude_std: noise.mocap_attitude,
            }));
        }
    }
    (initial, events)
}

/// The 15-state error `x_t ⊖ x̂` (layout of `ftsmc_core::estimate::index`).
pub fn error_state(truth: &Truth, est: &ftsmc_core::estimate::Estimate) -> [f64; 15] {
    let dth = quaternion::difference(&est.quaternion, &truth.quaternion);
    let mut e = [0.0; 15];
    for i in 0..3 {
        e[i] = truth.position[i] - est.position[i];
        e[3 + i] = truth.velocity[i] - est.velocity[i];
        e[6 + i] = dth[i];
        e[9 + i] = truth.gyro_bias[i] - est.gyro_bias[i];
        e[12 + i] = truth.accel_bias[i] - est.accel_bias[i];
    }
    e
}

/// `eᵀ P⁻¹ e` by Cholesky.
pub fn nees(e: &[f64; 15], p: &[[f64; 15]; 15]) -> f64 {
    use ftsmc_core::estimate::matrix::{cholesky, forward_substitute};
    let l = cholesky(p).expect("covariance positive definite");
    forward_substitute(&l, e).iter().map(|v| v * v).sum()
}
