//! The explicit complementary filter of Mahony, Hamel & Pflimlin 2008,
//! *Nonlinear complementary filters on the special orthogonal group*, IEEE
//! Trans. Automatic Control 53(5), 1203–1218, eq. 32 (the quaternion form
//! of §V), with a proportional and an integral (gyro-bias) gain.
//!
//! With `n` known world directions `v₀ᵢ` and their body-frame
//! measurements `vᵢ` (unit vectors), `v̂ᵢ = R̂ᵀ v₀ᵢ` their predictions:
//!
//! ```text
//! ω_mes = Σᵢ kᵢ vᵢ × v̂ᵢ
//! q̂̇    = ½ q̂ ⊗ (0, ω_m − b̂ + k_P ω_mes)
//! b̂̇    = −k_I ω_mes
//! ```
//!
//! Here `v₀ = e₃` (world up) measured by the normalised specific force
//! `a_m/|a_m|` (at rest or unaccelerated flight the accelerometer reads
//! `Rᵀ g₀ e₃`), weight `k_a`; and `v₀ = m_w/|m_w|`, the world magnetic
//! field, measured by `m_b/|m_b|`, weight `k_m`. Discretised over the IMU
//! period `Δt` by holding the corrected rate:
//! `b̂ ← b̂ − k_I ω_mes Δt`, `q̂ ← q̂ ⊗ Exp((ω_m − b̂_prev + k_P ω_mes) Δt)`.
//! The accelerometer term is skipped when `| |a_m|/g₀ − 1 |` exceeds
//! [`MahonyConfig::accel_tolerance`] (strong manoeuvres violate the
//! assumption that it reads gravity).

use super::{
    check_finite, check_non_negative, check_positive, quaternion, reading_finite, AttitudeEstimate, ConfigError,
    EstimateError, ImuSample, MagReading,
};
use crate::kinematics::{euler_from_quaternion, rotation_from_quaternion};
use crate::math::{cross, mat_t_vec, norm};

/// Gains and constants of the [`Mahony`] filter.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Deserialize, serde::Serialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "kebab-case", deny_unknown_fields, default))]
pub struct MahonyConfig {
    /// Proportional gain `k_P`, rad/s per unit of `ω_mes` (default 1.0; the
    /// attitude error decays with time constant ≈ `1/k_P` s).
    pub kp: f64,
    /// Integral gain `k_I`, 1/s² (default 0.05; 0 disables bias estimation).
    pub ki: f64,
    /// Weight `k_a` of the accelerometer (gravity) direction (default 1).
    pub accel_weight: f64,
    /// Weight `k_m` of the magnetometer direction (default 0.5; 0 ignores it).
    pub mag_weight: f64,
    /// Gravity `g₀`, m/s² (default 9.80665).
    pub gravity: f64,
    /// Skip the accelerometer term when `| |a_m|/g₀ − 1 |` exceeds this (default 0.25).
    pub accel_tolerance: f64,
    /// Earth magnetic field in the world frame (any unit; only its
    /// direction is used) (default `[0.2, 0, −0.45]`).
    pub magnetic_field: [f64; 3],
}

impl Default for MahonyConfig {
    fn default() -> Self {
        Self {
            kp: 1.0,
            ki: 0.05,
            accel_weight: 1.0,
            mag_weight: 0.5,
            gravity: 9.80665,
            accel_tolerance: 0.25,
            magnetic_field: [0.2, 0.0, -0.45],
        }
    }
}

impl MahonyConfig {
    /// Check every field: gains and weights finite and `≥ 0` (`k_P > 0`),
    /// gravity and tolerance `> 0`, a finite non-zero field.
    pub fn check(&self) -> Result<(), ConfigError> {
        check_positive("kp", self.kp)?;
        check_non_negative("ki", self.ki)?;
        check_non_negative("accel-weight", self.accel_weight)?;
        check_non_negative("mag-weight", self.mag_weight)?;
        check_positive("gravity", self.gravity)?;
        check_positive("accel-tolerance", self.accel_tolerance)?;
        check_finite("magnetic-field", &self.magnetic_field)?;
        let n = norm(&self.magnetic_field);
        if n.is_nan() || n <= 0.0 {
            return Err(ConfigError { field: "magnetic-field", value: n, expected: "a non-zero vector" });
        }
        Ok(())
    }
}

/// The Mahony explicit complementary filter (module docs).
#[derive(Clone, Debug)]
pub struct Mahony {
    config: MahonyConfig,
    /// `m_w / |m_w|`.
    field_direction: [f64; 3],
    quaternion: [f64; 4],
    gyro_bias: [f64; 3],
    body_rate: [f64; 3],
    time: Option<f64>,
}

impl Mahony {
    /// A filter at attitude `quaternion` (`[w, x, y, z]`, normalised) with zero bias.
    pub fn new(config: MahonyConfig, quaternion: [f64; 4]) -> Result<Self, ConfigError> {
        config.check()?;
        check_finite("initial.quaternion", &quaternion)?;
        let q = quaternion::normalize(&quaternion);
        if !q.iter().all(|v| v.is_finite()) {
            return Err(ConfigError { field: "initial.quaternion", value: 0.0, expected: "a non-zero quaternion" });
        }
        let n = norm(&config.magnetic_field);
        let m = config.magnetic_field;
        Ok(Self {
            config,
            field_direction: [m[0] / n, m[1] / n, m[2] / n],
            quaternion: q,
            gyro_bias: [0.0; 3],
            body_rate: [0.0; 3],
            time: None,
        })
    }

    /// The current attitude estimate.
    pub fn estimate(&self) -> AttitudeEstimate {
        AttitudeEstimate {
            time: self.time.unwrap_or(f64::NAN),
            quaternion: self.quaternion,
            euler: euler_from_quaternion(&self.quaternion),
            body_rate: self.body_rate,
            gyro_bias: self.gyro_bias,
        }
    }

    /// One step over the interval that ends at `imu.time`, with the
    /// magnetometer reading of that interval if there is one (module docs).
    /// The first sample only sets the time.
    pub fn update(&mut self, imu: &ImuSample, mag: Option<&MagReading>) -> Result<AttitudeEstimate, EstimateError> {
        reading_finite("imu.time", &[imu.time])?;
        reading_finite("imu.gyro", &imu.gyro)?;
        reading_finite("imu.specific-force", &imu.specific_force)?;
        if let Some(m) = mag {
            reading_finite("mag.field", &m.field)?;
        }
        let Some(previous) = self.time else {
            self.time = Some(imu.time);
            self.body_rate = sub3(&imu.gyro, &self.gyro_bias);
            return Ok(self.estimate());
        };
        let dt = imu.time - previous;
        if dt.is_nan() || dt <= 0.0 {
            return Err(EstimateError::TimeNotIncreasing { previous, time: imu.time });
        }
        let r = rotation_from_quaternion(&self.quaternion);
        let mut omega_mes = [0.0; 3];
        let c = &self.config;
        let fa = norm(&imu.specific_force);
        if c.accel_weight > 0.0 && fa > 0.0 && ((fa / c.gravity) - 1.0).abs() <= c.accel_tolerance {
            let v = scale3(&imu.specific_force, 1.0 / fa);
            let v_hat = [r[2][0], r[2][1], r[2][2]]; // Rᵀ e₃
            add_scaled(&mut omega_mes, &cross(&v, &v_hat), c.accel_weight);
        }
        if let Some(m) = mag {
            let fm = norm(&m.field);
            if c.mag_weight > 0.0 && fm > 0.0 {
                let v = scale3(&m.field, 1.0 / fm);
                let v_hat = mat_t_vec(&r, &self.field_direction);
                add_scaled(&mut omega_mes, &cross(&v, &v_hat), c.mag_weight);
            }
        }
        let omega = sub3(&imu.gyro, &self.gyro_bias);
        let corrected =
            [omega[0] + c.kp * omega_mes[0], omega[1] + c.kp * omega_mes[1], omega[2] + c.kp * omega_mes[2]];
        add_scaled(&mut self.gyro_bias, &omega_mes, -c.ki * dt);
        let dq = quaternion::exp(&scale3(&corrected, dt));
        self.quaternion = quaternion::normalize(&quaternion::multiply(&self.quaternion, &dq));
        self.body_rate = omega;
        self.time = Some(imu.time);
        Ok(self.estimate())
    }
}

fn sub3(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn scale3(a: &[f64; 3], k: f64) -> [f64; 3] {
    [a[0] * k, a[1] * k, a[2] * k]
}

fn add_scaled(acc: &mut [f64; 3], v: &[f64; 3], k: f64) {
    for i in 0..3 {
        acc[i] += v[i] * k;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::quaternion_from_euler;

    /// Started 0.5 rad off in roll, pitch and yaw with a gyro bias, a
    /// vehicle at rest: the filter converges to the true attitude and
    /// learns the bias.
    #[test]
    fn converges_from_a_wrong_attitude_and_learns_the_gyro_bias() {
        let truth = [0.1, -0.2, 1.0];
        let r = crate::kinematics::rotation_from_euler(&truth);
        let config = MahonyConfig { ki: 0.2, mag_weight: 4.0, ..MahonyConfig::default() };
        let field = mat_t_vec(&r, &config.magnetic_field);
        let f = [r[2][0] * 9.80665, r[2][1] * 9.80665, r[2][2] * 9.80665];
        let bias = [0.02, -0.01, 0.015];
        let mut m = Mahony::new(config, quaternion_from_euler(&[0.6, 0.3, 1.5])).unwrap();
        let mut last = m.estimate();
        for k in 0..60_000 {
            let t = f64::from(k) * 0.005;
            let imu = ImuSample { time: t, gyro: bias, specific_force: f };
            last = m.update(&imu, Some(&MagReading { time: t, field, std: 0.01 })).unwrap();
        }
        for i in 0..3 {
            assert!((last.euler[i] - truth[i]).abs() < 1e-6, "{:?}", last.euler);
            assert!((last.gyro_bias[i] - bias[i]).abs() < 1e-6, "{:?}", last.gyro_bias);
        }
        let bad = MahonyConfig { kp: 0.0, ..MahonyConfig::default() };
        assert_eq!(Mahony::new(bad, [1.0, 0.0, 0.0, 0.0]).unwrap_err().field, "kp");
    }
}
