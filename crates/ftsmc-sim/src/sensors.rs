//! Sensors: what the controller sees instead of the true state.
//!
//! Each control period the run loop hands the true [`QuadState`] to
//! [`Sensors::measure`] and gives the controller the answer. The pipeline,
//! in order:
//!
//! 1. **Sampling** at [`SensorParams::sample_rate`] (zero-order hold): on a
//!    sample period the sensor reads the truth, otherwise it repeats its last
//!    reading.
//! 2. **Error** on each reading, per quantity and axis: `measured = truth +
//!    bias + std · z`, `z ~ N(0, 1)` drawn from that quantity's own generator
//!    ([`POSITION_NOISE_STREAM`] … [`ANGULAR_RATE_NOISE_STREAM`]), so turning
//!    one source on or off leaves every other source's draws unchanged.
//!    Rates are corrupted in the frame [`SensorParams::rates`] says is
//!    measured; body rates are turned back into the Euler rates the
//!    controllers use with the *measured* attitude, as an estimator would.
//! 3. **Latency** of [`SensorParams::latency`] whole control periods: the
//!    controller sees the reading of `latency` periods ago. Before `latency`
//!    periods have elapsed it sees the first reading (the sensor's start-up
//!    value), so a delayed sensor never invents a state.
//!
//! [`SensorParams::default`] is the perfect sensor: every period, no error,
//! no latency; [`Sensors::measure`] then returns the truth bit-exactly.
//!
//! With [`SensorParams::imu`] attitude and rates have their own sample
//! rate and latency (an IMU), position and velocity keep `sample_rate` and
//! `latency` (a motion-capture or GNSS source); each quantity keeps its own
//! random stream either way.
//!
//! No allocation per call: the latency line is a ring buffer of
//! `latency + 1` states allocated once in [`Sensors::new`]; `measure` only
//! writes into it. A run loop calling `measure` every step does not touch the
//! heap (asserted by `tests/sensors_alloc.rs` with a counting allocator).

use ftsmc_core::kinematics::{
    euler_rates_from_body_rates_with, full_angle, gimbal_clamped_cos, half_angle, quaternion_from_half_angles,
};
use ftsmc_core::law::GainError;
use ftsmc_core::measured::{BodyAttitude, Measurement};
use ftsmc_core::model::QuadState;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

use crate::vehicle::rigid_body::{euler_rates_clamped, euler_rates_to_body_rates};

/// ChaCha stream of the position-noise generator (scenario seed). Streams in
/// use elsewhere: 1–6 drag noise (`environment`), 16 motor noise
/// ([`crate::actuators::MOTOR_NOISE_STREAM`]), 100 + k Monte Carlo sampling
/// (`scenario::distributions`). The sensors take 20–23.
pub const POSITION_NOISE_STREAM: u64 = 20;
/// ChaCha stream of the velocity-noise generator.
pub const VELOCITY_NOISE_STREAM: u64 = 21;
/// ChaCha stream of the attitude-noise generator.
pub const ATTITUDE_NOISE_STREAM: u64 = 22;
/// ChaCha stream of the angular-rate-noise generator (body or Euler rates,
/// whichever [`SensorParams::rates`] measures).
pub const ANGULAR_RATE_NOISE_STREAM: u64 = 23;

/// Largest accepted noise standard deviation or |bias|, in the quantity's
/// unit (m, m/s, rad or rad/s): far beyond any real sensor, it only catches
/// unit slips and overflow.
pub const MAX_ERROR: f64 = 1e3;

/// Largest accepted latency, control periods (bounds the ring buffer).
pub const MAX_LATENCY: u32 = 100_000;

/// Error model of one measured quantity, per axis `[x, y, z]` or
/// `[φ, θ, ψ]` (or `[p, q, r]` for body rates). Default: no error.
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct QuantityError {
    /// Standard deviation of the white Gaussian noise added to each reading,
    /// in the quantity's unit (default 0: no noise). A fresh draw is taken
    /// at every sample, not every control period.
    pub std: [f64; 3],
    /// Constant bias added to each reading, in the quantity's unit
    /// (default 0).
    pub bias: [f64; 3],
}

impl QuantityError {
    fn has_noise(&self) -> bool {
        self.std.iter().any(|s| *s != 0.0)
    }

    fn check(&self, std_field: &'static str, bias_field: &'static str) -> Result<(), GainError> {
        for s in self.std {
            if !(0.0..=MAX_ERROR).contains(&s) {
                return Err(GainError { field: std_field, value: s, expected: "0 <= std <= 1e3 (per axis)" });
            }
        }
        for b in self.bias {
            if !(-MAX_ERROR..=MAX_ERROR).contains(&b) {
                return Err(GainError { field: bias_field, value: b, expected: "-1e3 <= bias <= 1e3 (per axis)" });
            }
        }
        Ok(())
    }
}

/// Which angular rates the sensor measures (`rates = "euler" | "body"`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum RateFrame {
    /// Euler-angle rates `[φ̇, θ̇, ψ̇]`, rad/s, corrupted directly (default:
    /// the paper's idealisation).
    #[default]
    Euler,
    /// Body rates `Ω = [p, q, r]`, rad/s, as a gyroscope measures them:
    /// the true Euler rates are mapped to Ω at the true attitude, corrupted,
    /// and mapped back to Euler rates at the *measured* attitude.
    Body,
}

/// Sensor parameters. Defaults: the perfect sensor — no noise, no bias,
/// Euler rates, a sample every control period, no latency.
///
/// Orders of magnitude, as examples only: an optical motion-capture system
/// (Vicon) shows static position errors around 0.15 mm with a spread below
/// 0.025 mm and dynamic errors under 2 mm (Merriaux et al., "A Study of
/// Vicon System Positioning Performance", *Sensors* 17(7):1591, 2017); a
/// consumer MEMS gyroscope (InvenSense MPU-6000 datasheet, PS-MPU-6000A-00
/// rev. 3.4, §6.1) has a rate noise spectral density of 0.005 °/s/√Hz and a
/// total RMS noise of 0.05 °/s at a 100 Hz filter bandwidth (≈ 8.7e-4 rad/s).
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct SensorParams {
    /// Position error, m.
    pub position: QuantityError,
    /// Velocity error, m/s.
    pub velocity: QuantityError,
    /// Attitude (Z-Y-X Euler angles) error, rad.
    pub attitude: QuantityError,
    /// Angular-rate error, rad/s, in the frame [`SensorParams::rates`] names.
    pub angular_rate: QuantityError,
    /// Which rates are measured (default Euler).
    pub rates: RateFrame,
    /// Sample rate, Hz (default: absent, a sample every control period).
    /// Below the control rate the last sample is held (zero-order hold); at
    /// or above it the controller still sees one sample per period.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sample_rate: Option<f64>,
    /// Latency, whole control periods (default 0).
    pub latency: u32,
    /// The IMU's own clock for attitude and angular rates (default: absent,
    /// they share `sample_rate` and `latency` with position and velocity).
    /// An IMU runs far faster than a motion-capture system (≥ 500 Hz,
    /// about 1 ms against 100–200 Hz and about 6 ms).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub imu: Option<SensorClock>,
}

/// Sample rate and latency of one group of measured quantities.
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct SensorClock {
    /// Sample rate, Hz (absent: a sample every control period).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sample_rate: Option<f64>,
    /// Latency, whole control periods (default 0).
    pub latency: u32,
}

impl SensorClock {
    fn check(&self, rate_field: &'static str, latency_field: &'static str) -> Result<(), GainError> {
        if let Some(rate) = self.sample_rate {
            if !(rate > 0.0 && rate <= 1e6) {
                return Err(GainError { field: rate_field, value: rate, expected: "0 < sample_rate <= 1e6 Hz" });
            }
        }
        if self.latency > MAX_LATENCY {
            return Err(GainError {
                field: latency_field,
                value: f64::from(self.latency),
                expected: "0 <= latency <= 100000 control periods",
            });
        }
        Ok(())
    }
}

impl SensorParams {
    /// Whether these parameters are the perfect sensor (truth bit-exactly).
    pub fn is_perfect(&self) -> bool {
        *self == Self::default()
    }

    /// Check every value: `0 <= std <= 1e3`, `|bias| <= 1e3` (per axis, in
    /// the quantity's unit), `0 < sample_rate <= 1e6` Hz, `latency <= 1e5`
    /// periods. The error names the offending field.
    pub fn check(&self) -> Result<(), GainError> {
        self.position.check("position.std", "position.bias")?;
        self.velocity.check("velocity.std", "velocity.bias")?;
        self.attitude.check("attitude.std", "attitude.bias")?;
        self.angular_rate.check("angular_rate.std", "angular_rate.bias")?;
        SensorClock { sample_rate: self.sample_rate, latency: self.latency }.check("sample_rate", "latency")?;
        if let Some(imu) = &self.imu {
            imu.check("imu.sample_rate", "imu.latency")?;
        }
        Ok(())
    }
}

/// The generator of one noise source: `ChaCha8Rng` seeded with the run's
/// seed, on `stream`.
pub fn sensor_noise_rng(seed: u64, stream: u64) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream);
    rng
}

/// One noise source: its error model and its own generator.
#[derive(Clone, Debug)]
struct Source {
    error: QuantityError,
    rng: ChaCha8Rng,
    /// [`QuantityError::has_noise`], decided once.
    noisy: bool,
    /// Any axis has a bias.
    biased: bool,
}

impl Source {
    fn new(error: QuantityError, seed: u64, stream: u64) -> Self {
        let biased = error.bias.iter().any(|b| *b != 0.0);
        Self { error, rng: sensor_noise_rng(seed, stream), noisy: error.has_noise(), biased }
    }

    /// `truth + bias + std · z` per axis. Three draws per reading whenever
    /// any axis is noisy (so an axis's draws do not depend on the others'
    /// std); none otherwise. Zero terms are skipped, not added, so a
    /// perfect quantity is returned bit-exactly (`-0.0 + 0.0` would not be).
    fn corrupt(&mut self, truth: [f64; 3]) -> [f64; 3] {
        let mut out = truth;
        if self.noisy {
            for k in 0..3 {
                let z: f64 = StandardNormal.sample(&mut self.rng);
                if self.error.std[k] != 0.0 {
                    out[k] += self.error.std[k] * z;
                }
            }
        }
        if self.biased {
            for k in 0..3 {
                if self.error.bias[k] != 0.0 {
                    out[k] += self.error.bias[k];
                }
            }
        }
        out
    }
}

/// The sample clock, held sample and latency line of one group of
/// quantities (the whole state is carried; the caller picks its fields).
#[derive(Clone, Debug)]
struct Line {
    /// Samples per control period, clamped to at most 1.
    samples_per_period: f64,
    /// `samples_per_period == 1`: a sample is due every period.
    every_period: bool,
    /// Index of the last sample taken (`⌊period · samples_per_period⌋`).
    last_sample: u64,
    /// The reading held between samples.
    held: QuadState,
    /// Ring of the last `latency + 1` readings.
    ring: Vec<QuadState>,
    /// The held reading's attitude as a quaternion with its measured body
    /// rates (rad/s), `None` when the rates were not measured as such (see
    /// [`Sensors::measure_full`]).
    held_body: Option<BodyAttitude>,
    /// Their ring, beside `ring`.
    body_ring: Vec<Option<BodyAttitude>>,
    /// Slot the next reading goes into.
    head: usize,
}

impl Line {
    fn new(clock: SensorClock, control_rate_hz: f64) -> Self {
        let samples_per_period = match clock.sample_rate {
            Some(rate) if control_rate_hz > 0.0 => (rate / control_rate_hz).min(1.0),
            _ => 1.0,
        };
        Self {
            samples_per_period,
            every_period: samples_per_period == 1.0,
            last_sample: 0,
            held: QuadState::default(),
            ring: vec![QuadState::default(); clock.latency as usize + 1],
            held_body: None,
            body_ring: vec![None; clock.latency as usize + 1],
            head: 0,
        }
    }

    /// Whether a sample is due in control period `period`: when the sample
    /// index ⌊k · f_s / f_c⌋ moves on (the 1e-9 guards exact ratios, 100 Hz
    /// at 1 kHz: every 10th period, against rounding down).
    fn due(&mut self, period: u64) -> bool {
        if self.every_period {
            // ⌊k · 1 + 1e-9⌋ = k moves on every period.
            self.last_sample = period;
            return true;
        }
        let index = (period as f64 * self.samples_per_period + 1e-9).floor() as u64;
        if period == 0 || index != self.last_sample {
            self.last_sample = index;
            true
        } else {
            false
        }
    }

    /// Push this period's held reading and return the one of `latency`
    /// periods ago (the first reading until then).
    fn delayed(&mut self, period: u64) -> QuadState {
        if period == 0 {
            self.ring.fill(self.held);
            self.body_ring.fill(self.held_body);
        }
        let n = self.ring.len();
        self.ring[self.head] = self.held;
        self.body_ring[self.head] = self.held_body;
        self.head = if self.head + 1 == n { 0 } else { self.head + 1 };
        self.ring[self.head]
    }

    /// The body rates of the reading [`Line::delayed`] returned last.
    fn delayed_body(&self) -> Option<BodyAttitude> {
        self.body_ring[self.head]
    }
}

/// A running sensor: four noise sources, the sample clocks, the held
/// samples and the latency lines (one for position and velocity, one for
/// attitude and rates when [`SensorParams::imu`] gives the IMU its own
/// clock). Build one per flight with [`Sensors::new`]; call
/// [`Sensors::measure`] once per control period.
#[derive(Clone, Debug)]
pub struct Sensors {
    params: SensorParams,
    position: Source,
    velocity: Source,
    attitude: Source,
    angular_rate: Source,
    /// Control periods seen so far.
    period: u64,
    /// Position and velocity (and attitude/rates without an IMU clock).
    main: Line,
    /// Attitude and rates on their own clock, if any.
    imu: Option<Line>,
}

impl Sensors {
    /// A sensor for a run at `control_rate_hz` (Hz, > 0) whose noise streams
    /// are keyed by `seed` (streams [`POSITION_NOISE_STREAM`]…
    /// [`ANGULAR_RATE_NOISE_STREAM`]). `params` should have passed
    /// [`SensorParams::check`]. Allocates the latency lines (`latency + 1`
    /// states each) here, once.
    pub fn new(params: SensorParams, control_rate_hz: f64, seed: u64) -> Self {
        let main = SensorClock { sample_rate: params.sample_rate, latency: params.latency };
        Self {
            params,
            position: Source::new(params.position, seed, POSITION_NOISE_STREAM),
            velocity: Source::new(params.velocity, seed, VELOCITY_NOISE_STREAM),
            attitude: Source::new(params.attitude, seed, ATTITUDE_NOISE_STREAM),
            angular_rate: Source::new(params.angular_rate, seed, ANGULAR_RATE_NOISE_STREAM),
            period: 0,
            main: Line::new(main, control_rate_hz),
            imu: params.imu.map(|c| Line::new(c, control_rate_hz)),
        }
    }

    /// The parameters this sensor was built with.
    pub fn params(&self) -> &SensorParams {
        &self.params
    }

    /// What the controller sees this control period, given the true state
    /// (Euler rates in `truth.angular_rate`, rad/s). Call exactly once per
    /// control period: the sample clocks and the latency lines advance by
    /// one period per call. Never allocates.
    pub fn measure(&mut self, truth: &QuadState) -> QuadState {
        self.measure_full(&Measurement::euler(*truth)).euler
    }

    /// [`Sensors::measure`] of a truth that may carry its quaternion and
    /// body rates ([`Measurement::body`]). With them and `rates = "body"`,
    /// the reading carries the measured attitude as a quaternion
    /// ([`quaternion_from_euler`] of the measured angles) with the measured
    /// body rates, so a full-state controller needs no Euler conversion;
    /// the gyroscope then reads the truth's own body rates. Otherwise the
    /// reading has no body attitude. The clocks, latency and random draws
    /// are those of [`Sensors::measure`], and so are the readings of
    /// position, velocity and angles, bit for bit; the Euler rates agree to
    /// rounding (with body rates the sines and cosines of the measured
    /// angles come from the quaternion's half angles).
    pub fn measure_full(&mut self, truth: &Measurement) -> Measurement {
        let k = self.period;
        self.period += 1;
        match &mut self.imu {
            None => {
                if self.main.due(k) {
                    let (held, body) = self.read(truth);
                    self.main.held = held;
                    self.main.held_body = body;
                }
                let euler = self.main.delayed(k);
                Measurement { euler, body: self.main.delayed_body() }
            }
            Some(_) => {
                if self.main.due(k) {
                    let position = self.position.corrupt(truth.euler.position);
                    let velocity = self.velocity.corrupt(truth.euler.velocity);
                    self.main.held = QuadState { position, velocity, ..self.main.held };
                }
                let imu_due = self.imu.as_mut().is_some_and(|l| l.due(k));
                if imu_due {
                    let (attitude, angular_rate, body) = self.read_rotation(truth);
                    if let Some(l) = &mut self.imu {
                        l.held = QuadState { attitude, angular_rate, ..l.held };
                        l.held_body = body;
                    }
                }
                let translation = self.main.delayed(k);
                let (rotation, body) = match self.imu.as_mut() {
                    Some(l) => (l.delayed(k), l.delayed_body()),
                    None => (translation, self.main.delayed_body()),
                };
                let euler = QuadState {
                    position: translation.position,
                    velocity: translation.velocity,
                    attitude: rotation.attitude,
                    angular_rate: rotation.angular_rate,
                };
                Measurement { euler, body }
            }
        }
    }

    /// One reading of attitude and angular rate with their errors: Euler
    /// angles, Euler rates, and, when the rates are measured in the body
    /// frame of a truth that has them, the body attitude (the quaternion of
    /// the measured angles with the measured body rates).
    fn read_rotation(&mut self, truth: &Measurement) -> ([f64; 3], [f64; 3], Option<BodyAttitude>) {
        let euler = &truth.euler;
        let attitude = self.attitude.corrupt(euler.attitude);
        match (self.params.rates, truth.body) {
            (RateFrame::Euler, _) => (attitude, self.angular_rate.corrupt(euler.angular_rate), None),
            (RateFrame::Body, None) => {
                // A truth without body rates (the paper's plant): the body
                // rates of its Euler state.
                let body_rates =
                    self.angular_rate.corrupt(euler_rates_to_body_rates(&euler.attitude, &euler.angular_rate));
                (attitude, euler_rates_clamped(&attitude, &body_rates), None)
            }
            (RateFrame::Body, Some(truth_body)) => {
                // The gyroscope reads the truth's body rates. The half
                // angles of the measured attitude give its quaternion, and
                // by the double-angle formulas the sines and cosines of φ
                // and θ for its Euler rates (equal to `sin_cos` within a few
                // units in the last place).
                let body_rates = self.angular_rate.corrupt(truth_body.body_rates);
                let halves = attitude.map(half_angle);
                let quaternion = quaternion_from_half_angles(halves[0], halves[1], halves[2]);
                let [st, ct] = full_angle(halves[1]);
                let rates =
                    euler_rates_from_body_rates_with(full_angle(halves[0]), [st, gimbal_clamped_cos(ct)], &body_rates);
                (attitude, rates, Some(BodyAttitude { quaternion, body_rates }))
            }
        }
    }

    /// One reading of the truth with every error applied.
    fn read(&mut self, truth: &Measurement) -> (QuadState, Option<BodyAttitude>) {
        let position = self.position.corrupt(truth.euler.position);
        let velocity = self.velocity.corrupt(truth.euler.velocity);
        let (attitude, angular_rate, body) = self.read_rotation(truth);
        (QuadState { position, attitude, velocity, angular_rate }, body)
    }
}
