//! The magnetometer: the world's field seen in the body frame, with a
//! hard-iron bias and white noise:
//!
//! ```text
//! B_w = S · [cos I cos D, cos I sin D, −sin I],   m̃ = Rᵀ B_w + b_hard + σ ∘ z
//! ```
//!
//! World frame `x` is true north's reference axis, `z` up: the horizontal
//! component points `D` (declination, rad, positive from `x` toward `y`)
//! off `x`, and the field dips `I` (inclination, rad, positive downward)
//! below the horizontal. This is PX4's simulated magnetometer
//! (`src/modules/simulation/sensor_mag_sim/SensorMagSim.cpp`:
//! `Dcmf(Eulerf(0, −inclination, declination)) * Vector3f(strength, 0, 0)`,
//! `noiseGauss3f(0.02f, 0.02f, 0.03f)` gauss, offsets `SIM_MAG_OFFSET_X/Y/Z`,
//! 50 Hz) with a fixed world field instead of the World Magnetic Model
//! look-up. Defaults: 0.5 gauss, 60° inclination, 0° declination.

use ftsmc_core::kinematics::rotation_from_euler;
use ftsmc_core::law::GainError;
use ftsmc_core::math::{mat_t_vec, sin_cos};
use serde::{Deserialize, Serialize};

use super::{
    check_non_negative, normals, NoiseStream, Provides, Reading, SensorModel, SensorTruth, StageClock,
    MAGNETOMETER_STREAM,
};

/// The `[sensors.magnetometer]` table. Units: gauss for fields, rad for angles.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct MagParams {
    /// Sample rate, Hz (PX4 `sensor_mag_sim`: 50 Hz).
    pub rate_hz: f64,
    /// Latency from sample to estimator, s.
    pub latency_s: f64,
    /// Field strength `S`, gauss (> 0).
    pub strength: f64,
    /// Inclination `I` (dip, positive downward), rad, in `[−π/2, π/2]`.
    pub inclination: f64,
    /// Declination `D`, rad, in `[−π, π]`.
    pub declination: f64,
    /// Hard-iron bias in the body frame, gauss.
    pub hard_iron: [f64; 3],
    /// White-noise standard deviation per body axis, gauss (PX4: 0.02, 0.02, 0.03).
    pub noise_std: [f64; 3],
}

impl Default for MagParams {
    fn default() -> Self {
        Self {
            rate_hz: 50.0,
            latency_s: 0.0,
            strength: 0.5,
            inclination: 60.0f64.to_radians(),
            declination: 0.0,
            hard_iron: [0.0; 3],
            noise_std: [0.02, 0.02, 0.03],
        }
    }
}

impl MagParams {
    /// The stage clock.
    pub fn clock(&self) -> StageClock {
        StageClock { rate_hz: self.rate_hz, latency_s: self.latency_s }
    }

    /// The world field `B_w`, gauss.
    pub fn world_field(&self) -> [f64; 3] {
        let (si, ci) = sin_cos(self.inclination);
        let (sd, cd) = sin_cos(self.declination);
        [self.strength * ci * cd, self.strength * ci * sd, -self.strength * si]
    }

    /// Check every value (the error names the key), the rate against the
    /// physics rate `max_rate_hz` (Hz).
    pub fn check(&self, max_rate_hz: f64) -> Result<(), GainError> {
        use core::f64::consts::{FRAC_PI_2, PI};
        self.clock().check("magnetometer.rate_hz", "magnetometer.latency_s", max_rate_hz)?;
        check_non_negative("magnetometer.strength", self.strength, true)?;
        if !(self.inclination.is_finite() && self.inclination.abs() <= FRAC_PI_2) {
            return Err(GainError {
                field: "magnetometer.inclination",
                value: self.inclination,
                expected: "|inclination| <= pi/2 rad",
            });
        }
        if !(self.declination.is_finite() && self.declination.abs() <= PI) {
            return Err(GainError {
                field: "magnetometer.declination",
                value: self.declination,
                expected: "|declination| <= pi rad",
            });
        }
        for b in self.hard_iron {
            if !(b.is_finite() && b.abs() <= 10.0) {
                return Err(GainError {
                    field: "magnetometer.hard_iron",
                    value: b,
                    expected: "|hard_iron| <= 10 gauss per axis",
                });
            }
        }
        for s in self.noise_std {
            check_non_negative("magnetometer.noise_std", s, false)?;
        }
        Ok(())
    }
}

/// One magnetometer reading: the field in the body frame, gauss.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MagReading {
    /// Body-frame field, gauss.
    pub field: [f64; 3],
}

/// The magnetometer model ([`SensorModel`]) on [`MAGNETOMETER_STREAM`].
#[derive(Clone, Debug)]
pub struct Mag {
    params: MagParams,
    world: [f64; 3],
    rng: NoiseStream,
}

impl Mag {
    /// The magnetometer of `params` keyed by `key` (the scenario seed).
    pub fn new(params: MagParams, key: u64) -> Self {
        Self { params, world: params.world_field(), rng: normals(key, MAGNETOMETER_STREAM) }
    }
}

impl SensorModel for Mag {
    const NAME: &'static str = "mag";
    const COLUMNS: &'static [&'static str] = &["mag_x", "mag_y", "mag_z"];
    const PROVIDES: Provides = Provides { position: false, velocity: false, attitude: false, rate: false };

    fn sample(&mut self, truth: &SensorTruth<'_>, _dt: f64) -> Reading {
        let r = rotation_from_euler(&truth.state.attitude);
        let body = mat_t_vec(&r, &self.world);
        let mut field = [0.0; 3];
        for k in 0..3 {
            field[k] = body[k] + self.params.hard_iron[k] + self.params.noise_std[k] * self.rng.normal();
        }
        Reading::Mag(MagReading { field })
    }

    fn reseed(&mut self, key: u64) {
        self.rng = normals(key, MAGNETOMETER_STREAM);
    }

    fn record(reading: &Reading, out: &mut [f64]) {
        if let Reading::Mag(r) = reading {
            out.copy_from_slice(&r.field);
        }
    }
}
