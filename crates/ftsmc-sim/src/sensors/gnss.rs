//! GNSS: position and velocity at a few hertz, late, with a correlated
//! error and fix loss.
//!
//! Each axis's position and velocity error is a first-order Gauss–Markov
//! process sampled every `Δt = 1 / rate_hz`:
//!
//! ```text
//! e_{k+1} = φ e_k + σ √(1 − φ²) · z,   φ = e^{−Δt/τ}
//! ```
//!
//! with stationary standard deviation `σ` and correlation time `τ`, so
//! its autocorrelation is `σ² e^{−|lag|/τ}`. This is the form of PX4's
//! simulated receiver (`src/modules/simulation/sensor_gps_sim/SensorGpsSim.cpp`
//! of PX4/PX4-Autopilot: `_gps_pos_noise_n = _pos_markov_time *
//! _gps_pos_noise_n + _pos_random_walk * wgn * _pos_noise_amplitude`,
//! vertical × 1.5, at 8 Hz), written with `σ, τ` instead of the per-step
//! constants. The `px4-sim` defaults are PX4's constants turned into
//! `σ, τ`: φ = 0.76 per 0.125 s gives τ = 0.456 s, drive 0.016 m gives
//! σ = 0.025 m horizontal (0.037 m vertical); velocity φ = 0.54, drive
//! 0.02 m/s: τ = 0.203 s, σ = 0.024 m/s (×1.2 vertical).
//!
//! Fix loss: a two-state Markov chain (fix / no fix) with mean durations
//! `mean_fix_s` and `mean_outage_s` (0: the fix is never lost), stepped
//! on its own stream ([`GNSS_FIX_STREAM`]), and an optional scheduled
//! outage window. Without a fix the reading has `fix = false` and NaN
//! position and velocity (PX4 publishes `fix_type = 0` with eph = 100 m).

use ftsmc_core::law::GainError;
use ftsmc_core::math::{exp, sqrt};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::{
    check_non_negative, normals, sensor_noise_rng, NoiseStream, Provides, Reading, SensorModel, SensorTruth,
    StageClock, GNSS_FIX_STREAM, GNSS_STREAM,
};

/// The `[sensors.gnss]` table. Defaults ([`GnssParams::default`]): PX4's
/// simulated receiver, 8 Hz, 150 ms latency, never loses the fix.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct GnssParams {
    /// Sample rate, Hz (PX4 `sensor_gps_sim`: 8 Hz).
    pub rate_hz: f64,
    /// Latency from sample to estimator, s (typical receivers 0.1–0.2 s).
    pub latency_s: f64,
    /// Stationary standard deviation of the horizontal position error
    /// (each axis), m; also spelled `eph` (PX4's horizontal accuracy,
    /// which its EKF2 fuses as a per-axis standard deviation).
    #[serde(alias = "eph")]
    pub position_std: f64,
    /// Stationary standard deviation of the vertical position error, m;
    /// also spelled `epv`.
    #[serde(alias = "epv")]
    pub vertical_std: f64,
    /// Correlation time of the position error, s (> 0).
    pub position_correlation_time: f64,
    /// Stationary standard deviation of the velocity error (each horizontal axis), m/s.
    pub velocity_std: f64,
    /// Stationary standard deviation of the vertical velocity error, m/s.
    pub vertical_velocity_std: f64,
    /// Correlation time of the velocity error, s (> 0).
    pub velocity_correlation_time: f64,
    /// Mean time with a fix between random outages, s (0: never lost).
    pub mean_fix_s: f64,
    /// Mean duration of a random outage, s.
    pub mean_outage_s: f64,
    /// A scheduled outage `[start, end]`, s (optional).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub outage: Option<[f64; 2]>,
    /// A position jump: from `onset` (s) on, every position reads
    /// `offset` (m, world frame) further (a wrong fix, e.g. multipath or
    /// a false RTK ambiguity resolution). Optional.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub jump: Option<GnssJump>,
}

/// A step in the GNSS position solution (`gnss.jump`).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct GnssJump {
    /// When the jump starts, s (>= 0).
    pub onset: f64,
    /// The offset added to every position from then on, m, world frame.
    pub offset: [f64; 3],
}

impl Default for GnssParams {
    fn default() -> Self {
        let dt = 0.125;
        // PX4's per-step constants (SensorGpsSim.hpp) as σ and τ.
        let (phi_p, drive_p) = (0.76f64, 0.02 * 0.8);
        let (phi_v, drive_v) = (0.54f64, 0.4 * 0.05);
        let sigma = |phi: f64, drive: f64| drive / sqrt(1.0 - phi * phi);
        let tau = |phi: f64| -dt / ftsmc_core::math::ln(phi);
        Self {
            rate_hz: 8.0,
            latency_s: 0.15,
            position_std: sigma(phi_p, drive_p),
            vertical_std: 1.5 * sigma(phi_p, drive_p),
            position_correlation_time: tau(phi_p),
            velocity_std: sigma(phi_v, drive_v),
            vertical_velocity_std: 1.2 * sigma(phi_v, drive_v),
            velocity_correlation_time: tau(phi_v),
            mean_fix_s: 0.0,
            mean_outage_s: 0.0,
            outage: None,
            jump: None,
        }
    }
}

impl GnssParams {
    /// The stage clock.
    pub fn clock(&self) -> StageClock {
        StageClock { rate_hz: self.rate_hz, latency_s: self.latency_s }
    }

    /// Check every value (the error names the key, `gnss.rate_hz`), the
    /// rate against the physics rate `max_rate_hz` (Hz).
    pub fn check(&self, max_rate_hz: f64) -> Result<(), GainError> {
        self.clock().check("gnss.rate_hz", "gnss.latency_s", max_rate_hz)?;
        check_non_negative("gnss.position_std", self.position_std, false)?;
        check_non_negative("gnss.vertical_std", self.vertical_std, false)?;
        check_non_negative("gnss.position_correlation_time", self.position_correlation_time, true)?;
        check_non_negative("gnss.velocity_std", self.velocity_std, false)?;
        check_non_negative("gnss.vertical_velocity_std", self.vertical_velocity_std, false)?;
        check_non_negative("gnss.velocity_correlation_time", self.velocity_correlation_time, true)?;
        check_non_negative("gnss.mean_fix_s", self.mean_fix_s, false)?;
        check_non_negative("gnss.mean_outage_s", self.mean_outage_s, false)?;
        if self.mean_fix_s > 0.0 && self.mean_outage_s <= 0.0 {
            return Err(GainError {
                field: "gnss.mean_outage_s",
                value: self.mean_outage_s,
                expected: "a mean outage > 0 s when gnss.mean_fix_s > 0",
            });
        }
        if let Some([a, b]) = self.outage {
            if !(a.is_finite() && b.is_finite() && 0.0 <= a && a <= b) {
                return Err(GainError {
                    field: "gnss.outage",
                    value: a,
                    expected: "[start, end] with 0 <= start <= end",
                });
            }
        }
        if let Some(j) = self.jump {
            if !(j.onset.is_finite() && j.onset >= 0.0) {
                return Err(GainError { field: "gnss.jump.onset", value: j.onset, expected: "a finite onset >= 0 s" });
            }
            for o in j.offset {
                if !(o.is_finite() && o.abs() <= 1e4) {
                    return Err(GainError {
                        field: "gnss.jump.offset",
                        value: o,
                        expected: "|offset| <= 1e4 m per axis",
                    });
                }
            }
        }
        Ok(())
    }
}

/// One GNSS reading (world frame, `z` up).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GnssReading {
    /// Position, m (NaN without a fix).
    pub position: [f64; 3],
    /// Velocity, m/s (NaN without a fix).
    pub velocity: [f64; 3],
    /// The receiver has a fix.
    pub fix: bool,
}

/// The GNSS model ([`SensorModel`]): errors on [`GNSS_STREAM`], fix loss on
/// [`GNSS_FIX_STREAM`].
#[derive(Clone, Debug)]
pub struct Gnss {
    params: GnssParams,
    /// Position and velocity errors, m and m/s.
    error: [[f64; 3]; 2],
    rng: NoiseStream,
    fix_rng: ChaCha8Rng,
    /// The chain's state: a fix (true) or a random outage.
    chain_fix: bool,
    started: bool,
}

impl Gnss {
    /// The receiver of `params` keyed by `key` (the scenario seed).
    pub fn new(params: GnssParams, key: u64) -> Self {
        Self {
            params,
            error: [[0.0; 3]; 2],
            rng: normals(key, GNSS_STREAM),
            fix_rng: sensor_noise_rng(key, GNSS_FIX_STREAM),
            chain_fix: true,
            started: false,
        }
    }

    /// The current position and velocity errors.
    pub fn error(&self) -> [[f64; 3]; 2] {
        self.error
    }

    fn stds(&self) -> [[f64; 3]; 2] {
        let p = &self.params;
        [[p.position_std, p.position_std, p.vertical_std], [p.velocity_std, p.velocity_std, p.vertical_velocity_std]]
    }
}

impl SensorModel for Gnss {
    const NAME: &'static str = "gnss";
    const COLUMNS: &'static [&'static str] =
        &["gnss_x", "gnss_y", "gnss_z", "gnss_vx", "gnss_vy", "gnss_vz", "gnss_fix"];
    const PROVIDES: Provides = Provides { position: true, velocity: true, attitude: false, rate: false };

    fn sample(&mut self, truth: &SensorTruth<'_>, dt: f64) -> Reading {
        let stds = self.stds();
        let taus = [self.params.position_correlation_time, self.params.velocity_correlation_time];
        for q in 0..2 {
            let phi = exp(-dt / taus[q]);
            let drive = sqrt(1.0 - phi * phi);
            for k in 0..3 {
                let z = self.rng.normal();
                // The first sample starts in the stationary distribution.
                self.error[q][k] =
                    if self.started { phi * self.error[q][k] + stds[q][k] * drive * z } else { stds[q][k] * z };
            }
        }
        self.started = true;
        // The fix chain: leave the state with probability dt / mean.
        if self.params.mean_fix_s > 0.0 {
            let u = (self.fix_rng.next_u64() >> 11) as f64 * (1.0 / 9_007_199_254_740_992.0);
            let mean = if self.chain_fix { self.params.mean_fix_s } else { self.params.mean_outage_s };
            if u < 1.0 - exp(-dt / mean) {
                self.chain_fix = !self.chain_fix;
            }
        }
        let scheduled_out = self.params.outage.is_some_and(|[a, b]| truth.t >= a && truth.t < b);
        let fix = self.chain_fix && !scheduled_out;
        let s = truth.state;
        let read = |v: [f64; 3], e: [f64; 3]| if fix { [v[0] + e[0], v[1] + e[1], v[2] + e[2]] } else { [f64::NAN; 3] };
        let mut position_error = self.error[0];
        if let Some(j) = self.params.jump.filter(|j| truth.t >= j.onset) {
            for k in 0..3 {
                position_error[k] += j.offset[k];
            }
        }
        Reading::Gnss(GnssReading {
            position: read(s.position, position_error),
            velocity: read(s.velocity, self.error[1]),
            fix,
        })
    }

    fn reseed(&mut self, key: u64) {
        self.rng = normals(key, GNSS_STREAM);
        self.fix_rng = sensor_noise_rng(key, GNSS_FIX_STREAM);
    }

    fn record(reading: &Reading, out: &mut [f64]) {
        if let Reading::Gnss(r) = reading {
            out[..3].copy_from_slice(&r.position);
            out[3..6].copy_from_slice(&r.velocity);
            out[6] = if r.fix { 1.0 } else { 0.0 };
        }
    }
}
