//! The inertial unit: a three-axis accelerometer and a three-axis
//! gyroscope, each with the error model of IEEE Std 952-1997 (Annex C,
//! Allan variance) as summarised by Woodman, "An introduction to inertial
//! navigation", University of Cambridge Tech. Rep. UCAM-CL-TR-696 (2007),
//! §3–4:
//!
//! ```text
//! measured = sat_q( truth + b + σ_w · z ),   σ_w = N / √Δt
//! b_{k+1}  = φ b_k + K √((1 − φ²) τ / 2) · z,  φ = e^{−Δt/τ}
//! ```
//!
//! * `N` — white-noise density (angle / velocity random walk), unit/√Hz:
//!   the Allan deviation's `τ^{-1/2}` branch, `σ_A(τ) = N / √τ`, so
//!   `σ_A(1 s) = N`.
//! * `K` — bias random-walk density, unit/s/√Hz, driving a first-order
//!   Gauss–Markov bias of correlation time `τ` (s): for `Δt ≪ τ` the bias
//!   walks as `K √t` (the Allan `τ^{+1/2}` branch) and settles at a
//!   stationary standard deviation `K √(τ/2)` (the bias-instability
//!   plateau). `τ = ∞` is the pure random walk. This is the bias model of
//!   the Gazebo IMU plugin PX4's SITL flew (`gazebo_imu_plugin.cpp` of
//!   PX4/PX4-SITL_gazebo-classic: `gyroscopeRandomWalk`,
//!   `gyroscopeBiasCorrelationTime`, …).
//! * a turn-on bias drawn once, standard deviation `turn_on_bias` (unit).
//! * `sat_q`: clamp to `±range`, then round to a multiple of `resolution`
//!   (one LSB; 0: no quantisation).
//!
//! The accelerometer measures the specific force in the body frame,
//! `f = Rᵀ (a − g)` with `g = (0, 0, −g)` (world `z` up), so a vehicle at
//! rest reads `+g` along its body `z`; the gyroscope measures body rates
//! `Ω = W(φ, θ) · [φ̇, θ̇, ψ̇]` of the truth's Euler rates.

use ftsmc_core::kinematics::rotation_from_euler;
use ftsmc_core::law::GainError;
use ftsmc_core::math::{exp, mat_t_vec, sqrt};
use serde::{Deserialize, Serialize};

use super::{
    check_non_negative, normals, NoiseStream, Provides, Reading, SensorModel, SensorTruth, StageClock,
    ACCELEROMETER_STREAM, GYROSCOPE_STREAM,
};
use crate::vehicle::rigid_body::euler_rates_to_body_rates;

/// Error model of one three-axis inertial sensor, in its unit `u` (m/s²
/// for the accelerometer, rad/s for the gyroscope). Every value must be
/// finite; densities `> 0` except `bias_random_walk` (`>= 0`).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct AxisModel {
    /// White-noise density `N`, u/√Hz (> 0).
    pub noise_density: f64,
    /// Bias random-walk density `K`, u/s/√Hz (>= 0).
    pub bias_random_walk: f64,
    /// Bias correlation time `τ`, s (> 0; `inf`: pure random walk).
    pub bias_correlation_time: f64,
    /// Standard deviation of the turn-on bias, u (>= 0).
    pub turn_on_bias: f64,
    /// Full-scale range, u (> 0): readings are clamped to `±range`.
    pub range: f64,
    /// Quantisation step (one LSB), u (>= 0; 0: none).
    pub resolution: f64,
}

impl AxisModel {
    fn check(&self, f: [&'static str; 6]) -> Result<(), GainError> {
        check_non_negative(f[0], self.noise_density, true)?;
        check_non_negative(f[1], self.bias_random_walk, false)?;
        if self.bias_correlation_time.is_nan() || self.bias_correlation_time <= 0.0 {
            return Err(GainError {
                field: f[2],
                value: self.bias_correlation_time,
                expected: "a correlation time > 0 s (inf: random walk)",
            });
        }
        check_non_negative(f[3], self.turn_on_bias, false)?;
        check_non_negative(f[4], self.range, true)?;
        check_non_negative(f[5], self.resolution, false)
    }
}

/// Sourced classes of inertial units (`class = "..."`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ImuClass {
    /// The ADIS16448-derived defaults of the Gazebo IMU plugin PX4's SITL
    /// used (`src/gazebo_imu_plugin.h`/`.cpp` of
    /// PX4/PX4-SITL_gazebo-classic, `kDefaultAdis*`): gyroscope
    /// N = 3.39e-4 rad/s/√Hz, K = 3.88e-5 rad/s²/√Hz, τ = 1000 s, turn-on
    /// 8.7e-3 rad/s; accelerometer N = 4e-3 m/s²/√Hz, K = 6e-3 m/s³/√Hz,
    /// τ = 300 s, turn-on 0.196 m/s². Ranges ±2000 °/s and ±16 g, no
    /// quantisation (the plugin has neither). 250 Hz.
    #[default]
    Px4Sitl,
    /// Bosch BMI088 (the Crazyflie 2.1's IMU), datasheet BST-BMI088-DS001
    /// §1 specifications: gyroscope noise density 0.014 °/s/√Hz (2.44e-4
    /// rad/s/√Hz), range ±2000 °/s, 16 bit; accelerometer noise density
    /// 175 µg/√Hz (1.72e-3 m/s²/√Hz) in its ±24 g range, 16 bit. The
    /// datasheet gives no Allan bias parameters: the bias terms are those
    /// of `px4-sitl`, turn-on biases zero (a calibrated unit). 1 kHz.
    Bmi088,
}

/// The `[sensors.inertial]` table: clock and error models of the IMU.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ImuParams {
    /// Sample rate, Hz.
    pub rate_hz: f64,
    /// Latency from sample to estimator, s.
    pub latency_s: f64,
    /// Accelerometer, m/s².
    pub accelerometer: AxisModel,
    /// Gyroscope, rad/s.
    pub gyroscope: AxisModel,
}

const G0: f64 = 9.80665;
const DEG: f64 = core::f64::consts::PI / 180.0;

impl ImuParams {
    /// The parameters of a class ([`ImuClass`]).
    pub fn of_class(class: ImuClass) -> Self {
        let px4_gyro_k = 2.0 * 4.0 / 3600.0 * DEG;
        match class {
            ImuClass::Px4Sitl => Self {
                rate_hz: 250.0,
                latency_s: 0.0,
                gyroscope: AxisModel {
                    noise_density: 2.0 * 35.0 / 3600.0 * DEG,
                    bias_random_walk: px4_gyro_k,
                    bias_correlation_time: 1000.0,
                    turn_on_bias: 0.5 * DEG,
                    range: 2000.0 * DEG,
                    resolution: 0.0,
                },
                accelerometer: AxisModel {
                    noise_density: 2.0 * 2.0e-3,
                    bias_random_walk: 2.0 * 3.0e-3,
                    bias_correlation_time: 300.0,
                    turn_on_bias: 20.0e-3 * 9.8,
                    range: 16.0 * G0,
                    resolution: 0.0,
                },
            },
            ImuClass::Bmi088 => Self {
                rate_hz: 1000.0,
                latency_s: 0.0,
                gyroscope: AxisModel {
                    noise_density: 0.014 * DEG,
                    bias_random_walk: px4_gyro_k,
                    bias_correlation_time: 1000.0,
                    turn_on_bias: 0.0,
                    range: 2000.0 * DEG,
                    resolution: 2.0 * 2000.0 * DEG / 65536.0,
                },
                accelerometer: AxisModel {
                    noise_density: 175e-6 * G0,
                    bias_random_walk: 2.0 * 3.0e-3,
                    bias_correlation_time: 300.0,
                    turn_on_bias: 0.0,
                    range: 24.0 * G0,
                    resolution: 2.0 * 24.0 * G0 / 65536.0,
                },
            },
        }
    }

    /// The stage clock.
    pub fn clock(&self) -> StageClock {
        StageClock { rate_hz: self.rate_hz, latency_s: self.latency_s }
    }

    /// Check every value (the error names the key, `inertial.rate_hz`),
    /// the rate against the physics rate `max_rate_hz` (Hz).
    pub fn check(&self, max_rate_hz: f64) -> Result<(), GainError> {
        self.clock().check("inertial.rate_hz", "inertial.latency_s", max_rate_hz)?;
        self.accelerometer.check([
            "inertial.accelerometer.noise_density",
            "inertial.accelerometer.bias_random_walk",
            "inertial.accelerometer.bias_correlation_time",
            "inertial.accelerometer.turn_on_bias",
            "inertial.accelerometer.range",
            "inertial.accelerometer.resolution",
        ])?;
        self.gyroscope.check([
            "inertial.gyroscope.noise_density",
            "inertial.gyroscope.bias_random_walk",
            "inertial.gyroscope.bias_correlation_time",
            "inertial.gyroscope.turn_on_bias",
            "inertial.gyroscope.range",
            "inertial.gyroscope.resolution",
        ])
    }
}

/// One IMU sample: specific force (m/s²) and body rates (rad/s), body frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ImuReading {
    /// Specific force `Rᵀ (a − g)`, m/s².
    pub specific_force: [f64; 3],
    /// Body rates `[p, q, r]`, rad/s.
    pub body_rates: [f64; 3],
}

/// One three-axis sensor's running error: its model, bias and draws.
#[derive(Clone, Debug)]
pub struct AxisError {
    model: AxisModel,
    bias: [f64; 3],
    rng: NoiseStream,
    stream: u64,
}

impl AxisError {
    /// The error of `model` with draws from `stream` of `key` (the turn-on
    /// bias is the first three draws).
    pub fn new(model: AxisModel, key: u64, stream: u64) -> Self {
        let mut rng = normals(key, stream);
        let bias = [0; 3].map(|_| model.turn_on_bias * rng.normal());
        Self { model, bias, rng, stream }
    }

    /// The current bias, u.
    pub fn bias(&self) -> [f64; 3] {
        self.bias
    }

    /// `truth` read with the error over a sample period `dt` (s): white
    /// noise, then the bias moved on, saturation and quantisation.
    pub fn corrupt(&mut self, truth: [f64; 3], dt: f64) -> [f64; 3] {
        let m = &self.model;
        let sigma_w = m.noise_density / sqrt(dt);
        let tau = m.bias_correlation_time;
        let (phi, drive) = if tau.is_finite() {
            let phi = exp(-dt / tau);
            (phi, m.bias_random_walk * sqrt((1.0 - phi * phi) * tau / 2.0))
        } else {
            (1.0, m.bias_random_walk * sqrt(dt))
        };
        let mut out = [0.0; 3];
        for k in 0..3 {
            let z_w = self.rng.normal();
            let z_b = self.rng.normal();
            let v = truth[k] + self.bias[k] + sigma_w * z_w;
            self.bias[k] = phi * self.bias[k] + drive * z_b;
            let v = v.clamp(-m.range, m.range);
            out[k] = if m.resolution > 0.0 { (v / m.resolution).round() * m.resolution } else { v };
        }
        out
    }

    fn reseed(&mut self, key: u64) {
        self.rng = normals(key, self.stream);
    }
}

/// The IMU model ([`SensorModel`]): accelerometer on [`ACCELEROMETER_STREAM`],
/// gyroscope on [`GYROSCOPE_STREAM`].
#[derive(Clone, Debug)]
pub struct Imu {
    /// Accelerometer error, m/s².
    pub accelerometer: AxisError,
    /// Gyroscope error, rad/s.
    pub gyroscope: AxisError,
}

impl Imu {
    /// The IMU of `params` keyed by `key` (the scenario seed).
    pub fn new(params: &ImuParams, key: u64) -> Self {
        Self {
            accelerometer: AxisError::new(params.accelerometer, key, ACCELEROMETER_STREAM),
            gyroscope: AxisError::new(params.gyroscope, key, GYROSCOPE_STREAM),
        }
    }
}

/// True specific force `Rᵀ (a − g)` in the body frame, m/s², of the world
/// acceleration `a` (m/s²) at Euler attitude `attitude` (rad), gravity
/// `gravity` (m/s², along world `−z`).
pub fn specific_force(attitude: &[f64; 3], acceleration: &[f64; 3], gravity: f64) -> [f64; 3] {
    let r = rotation_from_euler(attitude);
    mat_t_vec(&r, &[acceleration[0], acceleration[1], acceleration[2] + gravity])
}

impl SensorModel for Imu {
    const NAME: &'static str = "imu";
    const COLUMNS: &'static [&'static str] = &["imu_fx", "imu_fy", "imu_fz", "imu_p", "imu_q", "imu_r"];
    const PROVIDES: Provides = Provides { position: false, velocity: false, attitude: false, rate: true };

    fn sample(&mut self, truth: &SensorTruth<'_>, dt: f64) -> Reading {
        let s = truth.state;
        let f = specific_force(&s.attitude, &truth.acceleration, truth.gravity);
        let w = euler_rates_to_body_rates(&s.attitude, &s.angular_rate);
        Reading::Imu(ImuReading {
            specific_force: self.accelerometer.corrupt(f, dt),
            body_rates: self.gyroscope.corrupt(w, dt),
        })
    }

    fn reseed(&mut self, key: u64) {
        self.accelerometer.reseed(key);
        self.gyroscope.reseed(key);
    }

    fn record(reading: &Reading, out: &mut [f64]) {
        if let Reading::Imu(r) = reading {
            out[..3].copy_from_slice(&r.specific_force);
            out[3..6].copy_from_slice(&r.body_rates);
        }
    }
}
