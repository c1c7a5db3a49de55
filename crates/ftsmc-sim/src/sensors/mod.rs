//! Sensors: what the vehicle measures instead of the true state.
//!
//! Two layers:
//!
//! * [`Sensors`] (`mocap.rs`): the motion-capture and attitude/rate
//!   reading the run loop hands the controller today (`[sensors]`, streams
//!   [`POSITION_NOISE_STREAM`]…[`ANGULAR_RATE_NOISE_STREAM`]). Its bits are
//!   those of every committed scenario.
//! * **Sensor stages**: one file per physical sensor, each a [`SensorModel`]
//!   (what one sample reads: its noise, bias and state) wrapped in a
//!   [`Stage`] (its clock and its latency line), seen by the rest of the
//!   program through the one trait [`SensorStage`]: the inertial unit
//!   ([`imu`]), GNSS ([`gnss`]), the barometer ([`baro`]) and the
//!   magnetometer ([`mag`]). An estimator stage ([`estimator`]) turns the
//!   timestamped readings into the state the controller sees; the only one
//!   here is [`estimator::Passthrough`] (the motion-capture reading
//!   straight to the controller, today's behaviour).
//!
//! The run loop flies the stages when `[sensors]` names an estimator or
//! a sensor table ([`pipeline`]: the list of stages and the estimator,
//! Mahony and the ESKF of `ftsmc_core::estimate` among them); otherwise it
//! flies [`Sensors`] as before.
//!
//! # Random streams
//!
//! Every noise source has its own ChaCha8 stream of a key (the scenario
//! seed, or the key of [`SensorStage::reseed`]), so turning one sensor on
//! or off leaves every other source's draws unchanged. Streams in use: 1–6
//! drag noise (`environment`), 16 motor noise, 20–23 the motion-capture
//! and attitude/rate noise ([`Sensors`]), 100 + k Monte Carlo sampling
//! (`scenario::distributions`). The stages take 24–31
//! ([`ACCELEROMETER_STREAM`] … [`MAGNETOMETER_STREAM`]).

mod mocap;
pub use mocap::*;

pub mod baro;
pub mod estimator;
pub mod gnss;
pub mod imu;
pub mod mag;
pub mod pipeline;

use ftsmc_core::law::GainError;
use ftsmc_core::measured::Measurement;
use ftsmc_core::model::QuadState;

/// ChaCha stream of the accelerometer's white noise and bias ([`imu`]).
pub const ACCELEROMETER_STREAM: u64 = 24;
/// ChaCha stream of the gyroscope's white noise and bias ([`imu`]).
pub const GYROSCOPE_STREAM: u64 = 25;
/// ChaCha stream of the GNSS position and velocity errors ([`gnss`]).
pub const GNSS_STREAM: u64 = 26;
/// ChaCha stream of the GNSS fix-loss process ([`gnss`]).
pub const GNSS_FIX_STREAM: u64 = 27;
/// ChaCha stream of the barometer's noise and drift ([`baro`]).
pub const BAROMETER_STREAM: u64 = 28;
/// ChaCha stream of the magnetometer's noise ([`mag`]).
pub const MAGNETOMETER_STREAM: u64 = 29;
/// Streams 30–31 are kept free for the next sensors.
pub const LAST_SENSOR_STREAM: u64 = 31;

/// The truth one sensor stage samples at time `t`.
#[derive(Clone, Copy, Debug)]
pub struct SensorTruth<'a> {
    /// Time of the sample, s.
    pub t: f64,
    /// True state in Euler form (position m, Z-Y-X angles rad, velocity
    /// m/s, Euler rates rad/s), world frame with `z` up.
    pub state: &'a QuadState,
    /// The same attitude as quaternion and body rates, when the truth
    /// model has them (the rigid body); `None` for the paper plant.
    pub body: Option<ftsmc_core::measured::BodyAttitude>,
    /// True acceleration of the centre of mass in the world frame, m/s²
    /// (the accelerometer measures `R^T (a − g)`).
    pub acceleration: [f64; 3],
    /// Gravitational acceleration magnitude, m/s² (acting along world `−z`).
    pub gravity: f64,
}

/// One reading of one sensor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Reading {
    /// A motion-capture/attitude reading: the whole state as [`Sensors`]
    /// gives it.
    Motion(Measurement),
    /// An inertial reading ([`imu::ImuReading`]).
    Imu(imu::ImuReading),
    /// A GNSS reading ([`gnss::GnssReading`]).
    Gnss(gnss::GnssReading),
    /// A barometer reading ([`baro::BaroReading`]).
    Baro(baro::BaroReading),
    /// A magnetometer reading ([`mag::MagReading`]).
    Mag(mag::MagReading),
}

/// A reading with its times: sampled at `t_sample` (s), available to an
/// estimator from `t_available = t_sample + latency` (s).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stamped {
    /// When the truth was sampled, s.
    pub t_sample: f64,
    /// When the reading reaches the estimator, s.
    pub t_available: f64,
    /// What was read.
    pub reading: Reading,
}

/// What a sensor stage provides to an estimator (a set of flags).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Provides {
    /// Position, m.
    pub position: bool,
    /// Velocity, m/s.
    pub velocity: bool,
    /// Attitude, rad.
    pub attitude: bool,
    /// Angular rate, rad/s.
    pub rate: bool,
}

impl Provides {
    /// Every quantity of both.
    pub fn union(self, other: Self) -> Self {
        Self {
            position: self.position || other.position,
            velocity: self.velocity || other.velocity,
            attitude: self.attitude || other.attitude,
            rate: self.rate || other.rate,
        }
    }

    /// True when `self` has every quantity `needed` has.
    pub fn covers(self, needed: Self) -> bool {
        (self.position || !needed.position)
            && (self.velocity || !needed.velocity)
            && (self.attitude || !needed.attitude)
            && (self.rate || !needed.rate)
    }
}

/// One sensor as the run loop sees it: a clock, a latency, its own noise
/// streams and state. [`Stage`] implements it for any [`SensorModel`].
pub trait SensorStage: Send {
    /// Short name (`"imu"`, `"gnss"`, …), the prefix of its recorded columns.
    fn name(&self) -> &'static str;
    /// What it gives an estimator.
    fn provides(&self) -> Provides;
    /// Sample the truth if a sample is due at `truth.t`, then hand `sink`
    /// every reading that has become available by `truth.t` (oldest
    /// first). Call with non-decreasing times. Never allocates.
    fn step(&mut self, truth: &SensorTruth<'_>, sink: &mut dyn FnMut(&Stamped));
    /// Re-derive every noise stream from `key` (the draws from now on are
    /// those of a stage built with seed `key`; the state — biases, held
    /// readings, the latency line — is kept).
    fn reseed(&mut self, key: u64);
    /// Names of the recorded columns (`<name>_<quantity>`).
    fn columns(&self) -> &'static [&'static str];
    /// The last reading made available, one value per column (NaN before
    /// the first).
    fn record(&self, out: &mut [f64]);
}

/// What one physical sensor reads: its error model and state, sampled on
/// the clock of a [`Stage`]. A new sensor is one file implementing this.
pub trait SensorModel: Send {
    /// Short name ([`SensorStage::name`]).
    const NAME: &'static str;
    /// Recorded column names ([`SensorStage::columns`]).
    const COLUMNS: &'static [&'static str];
    /// What it gives an estimator.
    const PROVIDES: Provides;
    /// One sample of the truth (called once per sample period `dt`, s).
    fn sample(&mut self, truth: &SensorTruth<'_>, dt: f64) -> Reading;
    /// Re-derive the noise streams from `key`.
    fn reseed(&mut self, key: u64);
    /// The columns of `reading` ([`SensorModel::COLUMNS`]).
    fn record(reading: &Reading, out: &mut [f64]);
}

/// Sample rate (Hz) and latency (s) of one sensor stage.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StageClock {
    /// Sample rate, Hz (> 0).
    pub rate_hz: f64,
    /// Latency from sampling to availability, s (≥ 0).
    pub latency_s: f64,
}

impl StageClock {
    /// Check the clock against the fastest rate the loop can sample,
    /// `max_rate_hz` (its control rate: stages are sampled at the control
    /// period boundaries): `0 < rate_hz <=
    /// max_rate_hz`, `0 <= latency_s <= 10` s, both finite. `rate_field`
    /// and `latency_field` name the keys (`"gnss.rate_hz"`).
    pub fn check(
        &self,
        rate_field: &'static str,
        latency_field: &'static str,
        max_rate_hz: f64,
    ) -> Result<(), GainError> {
        if !(self.rate_hz > 0.0 && self.rate_hz.is_finite()) {
            return Err(GainError { field: rate_field, value: self.rate_hz, expected: "a finite rate > 0 Hz" });
        }
        if self.rate_hz > max_rate_hz * (1.0 + 1e-12) {
            return Err(GainError {
                field: rate_field,
                value: self.rate_hz,
                expected:
                    "a rate at most simulation.control_rate (sensors are sampled at the control period boundaries)",
            });
        }
        if !(0.0..=MAX_STAGE_LATENCY_S).contains(&self.latency_s) {
            return Err(GainError { field: latency_field, value: self.latency_s, expected: "0 <= latency_s <= 10 s" });
        }
        Ok(())
    }

    /// Readings in flight at once: `⌈latency · rate⌉ + 1` (the latency
    /// line's capacity).
    fn in_flight(&self) -> usize {
        (self.latency_s * self.rate_hz).ceil() as usize + 1
    }
}

/// Longest accepted stage latency, s.
pub const MAX_STAGE_LATENCY_S: f64 = 10.0;

/// Check that `value` is finite and `>= 0` (`> 0` with `strict`), naming
/// `field` on refusal.
pub(crate) fn check_non_negative(field: &'static str, value: f64, strict: bool) -> Result<(), GainError> {
    let ok = value.is_finite() && if strict { value > 0.0 } else { value >= 0.0 };
    if ok {
        Ok(())
    } else {
        Err(GainError { field, value, expected: if strict { "a finite value > 0" } else { "a finite value >= 0" } })
    }
}

/// A [`SensorModel`] on its clock, with its latency line: sample `k` is
/// taken at the first step with `t >= k / rate_hz` and handed on at the
/// first step with `t >= t_sample + latency_s`.
pub struct Stage<M: SensorModel> {
    model: M,
    clock: StageClock,
    /// Index of the next sample.
    next: u64,
    /// Readings sampled and not yet available (a ring of fixed capacity).
    line: std::collections::VecDeque<Stamped>,
    capacity: usize,
    last: Option<Reading>,
}

impl<M: SensorModel> Stage<M> {
    /// `model` on `clock` (checked with [`StageClock::check`]); the
    /// latency line is allocated here, once.
    pub fn new(model: M, clock: StageClock) -> Self {
        let capacity = clock.in_flight();
        Self { model, clock, next: 0, line: std::collections::VecDeque::with_capacity(capacity), capacity, last: None }
    }

    /// The model.
    pub fn model(&self) -> &M {
        &self.model
    }
}

impl<M: SensorModel> SensorStage for Stage<M> {
    fn name(&self) -> &'static str {
        M::NAME
    }
    fn provides(&self) -> Provides {
        M::PROVIDES
    }
    fn step(&mut self, truth: &SensorTruth<'_>, sink: &mut dyn FnMut(&Stamped)) {
        let period = 1.0 / self.clock.rate_hz;
        // A sample is due once t reaches its time (1e-9 s guards exact
        // ratios against rounding); at most one per step.
        if truth.t + 1e-9 >= self.next as f64 * period {
            self.next += 1;
            let reading = self.model.sample(truth, period);
            if self.line.len() == self.capacity {
                // Cannot happen with steps at or above the sample rate; the
                // oldest reading is then due anyway.
                if let Some(old) = self.line.pop_front() {
                    self.last = Some(old.reading);
                    sink(&old);
                }
            }
            self.line.push_back(Stamped { t_sample: truth.t, t_available: truth.t + self.clock.latency_s, reading });
        }
        while self.line.front().is_some_and(|s| s.t_available <= truth.t + 1e-9) {
            if let Some(s) = self.line.pop_front() {
                self.last = Some(s.reading);
                sink(&s);
            }
        }
    }
    fn reseed(&mut self, key: u64) {
        self.model.reseed(key);
    }
    fn columns(&self) -> &'static [&'static str] {
        M::COLUMNS
    }
    fn record(&self, out: &mut [f64]) {
        match &self.last {
            Some(r) => M::record(r, out),
            None => out.iter_mut().for_each(|v| *v = f64::NAN),
        }
    }
}

/// Standard normal draws of one noise source (a [`crate::noise::NoiseStream`]
/// on `stream` of `key`).
pub(crate) fn normals(key: u64, stream: u64) -> NoiseStream {
    NoiseStream::new(sensor_noise_rng(key, stream))
}
