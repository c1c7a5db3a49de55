//! The barometer: static pressure of the International Standard
//! Atmosphere's troposphere (ISO 2533:1975; U.S. Standard Atmosphere 1976,
//! Table 4), with white noise, a constant offset and a drift, and the
//! altitude the pressure implies:
//!
//! ```text
//! p(h) = p₀ (1 − L h / T₀)^(g₀ M / (R* L)),   h(p) = (T₀ / L) (1 − (p / p₀)^(R* L / (g₀ M)))
//! p̃_k = p(h_k) + offset + d_k + σ · z,   d_{k+1} = d_k + rate · Δt + D √Δt · z'
//! ```
//!
//! `p₀ = 101325 Pa`, `T₀ = 288.15 K`, `L = 0.0065 K/m`, exponent
//! `g₀ M / (R* L) = 5.255877`. PX4's simulated barometer
//! (`src/modules/simulation/sensor_baro_sim/SensorBaroSim.cpp`) uses the
//! same troposphere (with 288 K and 5.256), 1 Pa RMS noise, a drift
//! `_baro_drift_pa_per_sec` and the offset parameter `SIM_BARO_OFF_P`;
//! the defaults here are its 1 Pa noise at its 20 Hz, no offset, no drift.

use ftsmc_core::law::GainError;
use ftsmc_core::math::{powf, sqrt};
use serde::{Deserialize, Serialize};

use super::{
    check_non_negative, normals, NoiseStream, Provides, Reading, SensorModel, SensorTruth, StageClock, BAROMETER_STREAM,
};

/// Sea-level pressure of the ISA, Pa.
pub const ISA_P0: f64 = 101_325.0;
/// Sea-level temperature of the ISA, K.
pub const ISA_T0: f64 = 288.15;
/// Temperature lapse rate of the ISA troposphere, K/m.
pub const ISA_LAPSE: f64 = 0.0065;
/// Exponent `g₀ M / (R* L)` of the ISA troposphere (dimensionless).
pub const ISA_EXPONENT: f64 = 5.255_877;

/// Static pressure at geopotential altitude `h` (m above mean sea level,
/// troposphere: `h < 11 km`), Pa.
pub fn isa_pressure(h: f64) -> f64 {
    ISA_P0 * powf(1.0 - ISA_LAPSE * h / ISA_T0, ISA_EXPONENT)
}

/// Altitude (m above mean sea level) of static pressure `p` (Pa): the
/// inverse of [`isa_pressure`].
pub fn isa_altitude(p: f64) -> f64 {
    ISA_T0 / ISA_LAPSE * (1.0 - powf(p / ISA_P0, 1.0 / ISA_EXPONENT))
}

/// The `[sensors.barometer]` table. Defaults: PX4's simulated barometer.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct BaroParams {
    /// Sample rate, Hz (PX4 `sensor_baro_sim`: 20 Hz).
    pub rate_hz: f64,
    /// Latency from sample to estimator, s.
    pub latency_s: f64,
    /// Altitude of the world origin above mean sea level, m.
    pub origin_altitude: f64,
    /// Standard deviation of the white pressure noise, Pa (PX4: 1 Pa).
    pub noise_std: f64,
    /// Constant pressure offset, Pa (PX4 `SIM_BARO_OFF_P`).
    pub offset: f64,
    /// Deterministic drift rate, Pa/s.
    pub drift_rate: f64,
    /// Random-walk density of the drift, Pa/√s (>= 0).
    pub drift_random_walk: f64,
}

impl Default for BaroParams {
    fn default() -> Self {
        Self {
            rate_hz: 20.0,
            latency_s: 0.0,
            origin_altitude: 0.0,
            noise_std: 1.0,
            offset: 0.0,
            drift_rate: 0.0,
            drift_random_walk: 0.0,
        }
    }
}

impl BaroParams {
    /// The stage clock.
    pub fn clock(&self) -> StageClock {
        StageClock { rate_hz: self.rate_hz, latency_s: self.latency_s }
    }

    /// Check every value (the error names the key), the rate against the
    /// physics rate `max_rate_hz` (Hz).
    pub fn check(&self, max_rate_hz: f64) -> Result<(), GainError> {
        self.clock().check("barometer.rate_hz", "barometer.latency_s", max_rate_hz)?;
        if !(self.origin_altitude.is_finite() && (-500.0..=10_000.0).contains(&self.origin_altitude)) {
            return Err(GainError {
                field: "barometer.origin_altitude",
                value: self.origin_altitude,
                expected: "-500 <= origin_altitude <= 10000 m (the ISA troposphere)",
            });
        }
        check_non_negative("barometer.noise_std", self.noise_std, false)?;
        if !self.offset.is_finite() {
            return Err(GainError { field: "barometer.offset", value: self.offset, expected: "a finite offset, Pa" });
        }
        if !self.drift_rate.is_finite() {
            return Err(GainError {
                field: "barometer.drift_rate",
                value: self.drift_rate,
                expected: "a finite rate, Pa/s",
            });
        }
        check_non_negative("barometer.drift_random_walk", self.drift_random_walk, false)
    }
}

/// One barometer reading.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BaroReading {
    /// Static pressure, Pa.
    pub pressure: f64,
    /// Altitude of that pressure above the world origin, m ([`isa_altitude`]
    /// minus `origin_altitude`).
    pub altitude: f64,
}

/// The barometer model ([`SensorModel`]) on [`BAROMETER_STREAM`].
#[derive(Clone, Debug)]
pub struct Baro {
    params: BaroParams,
    drift: f64,
    rng: NoiseStream,
}

impl Baro {
    /// The barometer of `params` keyed by `key` (the scenario seed).
    pub fn new(params: BaroParams, key: u64) -> Self {
        Self { params, drift: 0.0, rng: normals(key, BAROMETER_STREAM) }
    }

    /// The drift so far, Pa.
    pub fn drift(&self) -> f64 {
        self.drift
    }
}

impl SensorModel for Baro {
    const NAME: &'static str = "baro";
    const COLUMNS: &'static [&'static str] = &["baro_pressure", "baro_altitude"];
    const PROVIDES: Provides = Provides { position: false, velocity: false, attitude: false, rate: false };

    fn sample(&mut self, truth: &SensorTruth<'_>, dt: f64) -> Reading {
        let p = &self.params;
        let (z, z_drift) = (self.rng.normal(), self.rng.normal());
        let pressure =
            isa_pressure(p.origin_altitude + truth.state.position[2]) + p.offset + self.drift + p.noise_std * z;
        self.drift += p.drift_rate * dt + p.drift_random_walk * sqrt(dt) * z_drift;
        Reading::Baro(BaroReading { pressure, altitude: isa_altitude(pressure) - p.origin_altitude })
    }

    fn reseed(&mut self, key: u64) {
        self.rng = normals(key, BAROMETER_STREAM);
    }

    fn record(reading: &Reading, out: &mut [f64]) {
        if let Reading::Baro(r) = reading {
            out[0] = r.pressure;
            out[1] = r.altitude;
        }
    }
}
