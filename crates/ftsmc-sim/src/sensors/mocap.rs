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
//! No allocation per call: each latency line is a ring buffer of
//! `latency + 1` readings (only the quantities its clock reads) allocated
//! once in [`Sensors::new`]; `measure` only
//! writes into them. A run loop calling `measure` every step does not touch the
//! heap (asserted by `tests/sensors_alloc.rs` with a counting allocator).

use ftsmc_core::kinematics::{
    euler_rates_from_body_rates_with, full_angle, gimbal_clamped_cos, half_angle, quaternion_from_half_angles,
};
use ftsmc_core::law::GainError;
use ftsmc_core::measured::{BodyAttitude, Measurement};
use ftsmc_core::model::QuadState;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

pub use crate::noise::NoiseStream;
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
    /// The estimator between the sensor stages and the controller
    /// ([`super::pipeline`]; absent with no sensor table: the reading
    /// above straight to the controller, the loop of every committed
    /// scenario).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub estimator: Option<super::pipeline::EstimatorKind>,
    /// The reading above is a stage of the pipeline (default: true with
    /// `estimator = "passthrough"`, false otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub motion_capture: Option<bool>,
    /// The inertial unit (`[sensors.inertial]`, [`super::pipeline::InertialSection`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub inertial: Option<super::pipeline::InertialSection>,
    /// GNSS (`[sensors.gnss]`, [`super::gnss::GnssParams`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gnss: Option<super::gnss::GnssParams>,
    /// The barometer (`[sensors.barometer]`, [`super::baro::BaroParams`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub barometer: Option<super::baro::BaroParams>,
    /// The magnetometer (`[sensors.magnetometer]`, [`super::mag::MagParams`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub magnetometer: Option<super::mag::MagParams>,
    /// The ESKF's gate and divergence settings (`[sensors.eskf]`,
    /// [`super::pipeline::EskfSection`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub eskf: Option<super::pipeline::EskfSection>,
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
    /// Whether these parameters are the perfect sensor (truth bit-exactly)
    /// with no sensor pipeline.
    pub fn is_perfect(&self) -> bool {
        *self == Self::default()
    }

    /// Whether the controller is given the truth bit-exactly: the perfect
    /// motion-capture reading handed on by the passthrough estimator (the
    /// other sensor stages, if any, only recorded).
    pub fn controller_sees_truth(&self) -> bool {
        self.motion_capture_part().is_perfect()
            && self.estimator.unwrap_or_default() == super::pipeline::EstimatorKind::Passthrough
    }

    /// The motion-capture/attitude part alone (the pipeline's keys cleared):
    /// what [`Sensors`] reads.
    pub fn motion_capture_part(&self) -> Self {
        Self {
            estimator: None,
            motion_capture: None,
            inertial: None,
            gnss: None,
            barometer: None,
            magnetometer: None,
            eskf: None,
            ..*self
        }
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
    crate::rng::chacha_stream(seed, stream)
}

/// Which axes of a quantity carry an error term (noise or bias), decided
/// once from its parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Axes {
    /// No axis: nothing to add.
    None,
    /// Every axis: the term is added without a per-axis test.
    Every,
    /// Some axes: each axis is tested.
    Some,
}

impl Axes {
    /// The axes whose value is not zero.
    fn of(values: &[f64; 3]) -> Self {
        match values.iter().filter(|v| **v != 0.0).count() {
            0 => Axes::None,
            3 => Axes::Every,
            _ => Axes::Some,
        }
    }
}

/// One noise source: its error model and its own generator.
#[derive(Clone, Debug)]
struct Source {
    error: QuantityError,
    rng: NoiseStream,
    /// The axes with a noise std ([`QuantityError::has_noise`] unless `None`).
    noise: Axes,
    /// The axes with a bias.
    bias: Axes,
}

impl Source {
    fn new(error: QuantityError, seed: u64, stream: u64) -> Self {
        debug_assert_eq!(error.has_noise(), Axes::of(&error.std) != Axes::None);
        Self {
            error,
            rng: NoiseStream::new(sensor_noise_rng(seed, stream)),
            noise: Axes::of(&error.std),
            bias: Axes::of(&error.bias),
        }
    }

    /// `truth + bias + std · z` per axis. Three draws per reading whenever
    /// any axis is noisy (so an axis's draws do not depend on the others'
    /// std); none otherwise. Zero terms are skipped, not added, so a
    /// perfect quantity is returned bit-exactly (`-0.0 + 0.0` would not be).
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn corrupt(&mut self, truth: [f64; 3]) -> [f64; 3] {
        let mut out = truth;
        match self.noise {
            Axes::None => {}
            Axes::Every => {
                // The three draws in axis order, then the same sums as below
                // without the tests (every std is non-zero).
                let z = [self.rng.normal(), self.rng.normal(), self.rng.normal()];
                for k in 0..3 {
                    out[k] += self.error.std[k] * z[k];
                }
            }
            Axes::Some => {
                for k in 0..3 {
                    let z = self.rng.normal();
                    if self.error.std[k] != 0.0 {
                        out[k] += self.error.std[k] * z;
                    }
                }
            }
        }
        match self.bias {
            Axes::None => {}
            Axes::Every => {
                for k in 0..3 {
                    out[k] += self.error.bias[k];
                }
            }
            Axes::Some => {
                for k in 0..3 {
                    if self.error.bias[k] != 0.0 {
                        out[k] += self.error.bias[k];
                    }
                }
            }
        }
        out
    }
}

/// Position and velocity as read, `[position (m), velocity (m/s)]`.
type Translation = [[f64; 3]; 2];

/// Attitude and rates as read: Z-Y-X angles (rad), Euler rates (rad/s)
/// and, when the rates are measured as body rates of a truth that has
/// them, the body attitude (see [`Sensors::measure_full`]).
#[derive(Clone, Copy, Debug, Default)]
struct Rotation {
    attitude: [f64; 3],
    angular_rate: [f64; 3],
    body: Option<BodyAttitude>,
}

/// A whole reading, for a sensor whose quantities share one clock.
#[derive(Clone, Copy, Debug, Default)]
struct Reading {
    translation: Translation,
    rotation: Rotation,
}

/// The sample clock, held sample and latency line of one group of
/// quantities; `T` is what the group reads (only that is held and delayed).
#[derive(Clone, Debug)]
struct Line<T> {
    /// Samples per control period, clamped to at most 1.
    samples_per_period: f64,
    /// `samples_per_period == 1`: a sample is due every period.
    every_period: bool,
    /// Index of the last sample taken (`⌊period · samples_per_period⌋`).
    last_sample: u64,
    /// The reading held between samples.
    held: T,
    /// Ring of the last `latency + 1` readings.
    ring: Vec<T>,
    /// Slot the next reading goes into.
    head: usize,
}

impl<T: Copy + Default> Line<T> {
    fn new(clock: SensorClock, control_rate_hz: f64) -> Self {
        let samples_per_period = match clock.sample_rate {
            Some(rate) if control_rate_hz > 0.0 => (rate / control_rate_hz).min(1.0),
            _ => 1.0,
        };
        Self {
            samples_per_period,
            every_period: samples_per_period == 1.0,
            last_sample: 0,
            held: T::default(),
            ring: vec![T::default(); clock.latency as usize + 1],
            head: 0,
        }
    }

    /// Whether a sample is due in control period `period`: when the sample
    /// index ⌊k · f_s / f_c⌋ moves on (the 1e-9 guards exact ratios, 100 Hz
    /// at 1 kHz: every 10th period, against rounding down).
    #[inline]
    fn due(&mut self, period: u64) -> bool {
        if self.every_period {
            // ⌊k · 1 + 1e-9⌋ = k moves on every period.
            self.last_sample = period;
            return true;
        }
        let index = sample_index(period, self.samples_per_period);
        if period == 0 || index != self.last_sample {
            self.last_sample = index;
            true
        } else {
            false
        }
    }

    /// Advance by control period `period`: take a sample with `read` when
    /// one is due ([`Line::due`]), push the held reading into the ring and
    /// return the one of `latency` periods ago (the first reading until
    /// then). A line sampled every period writes `read`'s reading straight
    /// into the ring (holding it as well would only copy it).
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn advance(&mut self, period: u64, read: impl FnOnce() -> T) -> &T {
        let slot = self.head;
        if self.every_period {
            self.ring[slot] = read();
        } else {
            if self.due(period) {
                self.held = read();
            }
            self.ring[slot] = self.held;
        }
        if period == 0 {
            let first = self.ring[slot];
            self.ring.fill(first);
        }
        self.head = if slot + 1 == self.ring.len() { 0 } else { slot + 1 };
        &self.ring[self.head]
    }
}

/// The sample index `⌊k · s + 1e-9⌋` of control period `k` at `s` samples
/// per period. For `x = k · s + 1e-9`, `x as u64` is `⌊x⌋ as u64` for
/// every `x` (truncation is the floor of a non-negative number; a negative
/// `x` gives 0 both ways, NaN 0 and `+∞` `u64::MAX` both ways), without a
/// call to `floor` (baseline x86-64 has no rounding instruction).
#[cfg_attr(not(debug_assertions), inline(always))]
fn sample_index(period: u64, samples_per_period: f64) -> u64 {
    (period as f64 * samples_per_period + 1e-9) as u64
}

/// The four noise sources and the frame the rates are measured in.
#[derive(Clone, Debug)]
struct Sources {
    position: Source,
    velocity: Source,
    attitude: Source,
    angular_rate: Source,
    rates: RateFrame,
}

/// The latency lines: one clock for every quantity, or (with
/// [`SensorParams::imu`]) one for position and velocity and the IMU's for
/// attitude and rates.
#[derive(Clone, Debug)]
enum Lines {
    Shared(Line<Reading>),
    Split { translation: Line<Translation>, rotation: Line<Rotation> },
}

/// A running sensor: four noise sources, the sample clocks, the held
/// samples and the latency lines (one for position and velocity, one for
/// attitude and rates when [`SensorParams::imu`] gives the IMU its own
/// clock). Build one per flight with [`Sensors::new`]; call
/// [`Sensors::measure`] once per control period.
#[derive(Clone, Debug)]
pub struct Sensors {
    params: SensorParams,
    sources: Sources,
    /// Control periods seen so far.
    period: u64,
    lines: Lines,
}

impl Sensors {
    /// A sensor for a run at `control_rate_hz` (Hz, > 0) whose noise streams
    /// are keyed by `seed` (streams [`POSITION_NOISE_STREAM`]…
    /// [`ANGULAR_RATE_NOISE_STREAM`]). `params` should have passed
    /// [`SensorParams::check`]. Allocates the latency lines (`latency + 1`
    /// readings each) here, once.
    pub fn new(params: SensorParams, control_rate_hz: f64, seed: u64) -> Self {
        let main = SensorClock { sample_rate: params.sample_rate, latency: params.latency };
        let lines = match params.imu {
            None => Lines::Shared(Line::new(main, control_rate_hz)),
            Some(imu) => Lines::Split {
                translation: Line::new(main, control_rate_hz),
                rotation: Line::new(imu, control_rate_hz),
            },
        };
        Self {
            params,
            sources: Sources {
                position: Source::new(params.position, seed, POSITION_NOISE_STREAM),
                velocity: Source::new(params.velocity, seed, VELOCITY_NOISE_STREAM),
                attitude: Source::new(params.attitude, seed, ATTITUDE_NOISE_STREAM),
                angular_rate: Source::new(params.angular_rate, seed, ANGULAR_RATE_NOISE_STREAM),
                rates: params.rates,
            },
            period: 0,
            lines,
        }
    }

    /// From now on every noise source draws from the streams of `seed`
    /// (the same stream numbers as [`Sensors::new`]), each at its first
    /// word; the sample clocks, held samples and latency lines are kept. A
    /// flight branched at a control period boundary continues with fresh
    /// noise this way (`falsify::splitting`).
    pub fn reseed_noise(&mut self, seed: u64) {
        let s = &mut self.sources;
        for (source, stream) in [
            (&mut s.position, POSITION_NOISE_STREAM),
            (&mut s.velocity, VELOCITY_NOISE_STREAM),
            (&mut s.attitude, ATTITUDE_NOISE_STREAM),
            (&mut s.angular_rate, ANGULAR_RATE_NOISE_STREAM),
        ] {
            source.rng = NoiseStream::new(sensor_noise_rng(seed, stream));
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
    /// ([`quaternion_from_euler`](ftsmc_core::kinematics::quaternion_from_euler)
    /// of the measured angles) with the measured body rates, so a
    /// full-state controller needs no Euler conversion;
    /// the gyroscope then reads the truth's own body rates. Otherwise the
    /// reading has no body attitude. The clocks, latency and random draws
    /// are those of [`Sensors::measure`], and so are the readings of
    /// position, velocity and angles, bit for bit; the Euler rates agree to
    /// rounding (with body rates the sines and cosines of the measured
    /// angles come from the quaternion's half angles).
    pub fn measure_full(&mut self, truth: &Measurement) -> Measurement {
        let k = self.period;
        self.period += 1;
        let sources = &mut self.sources;
        let (translation, rotation) = match &mut self.lines {
            Lines::Shared(line) => {
                let reading = line.advance(k, || {
                    let translation = sources.read_translation(&truth.euler);
                    Reading { translation, rotation: sources.read_rotation(truth) }
                });
                (&reading.translation, &reading.rotation)
            }
            Lines::Split { translation, rotation } => (
                translation.advance(k, || sources.read_translation(&truth.euler)),
                rotation.advance(k, || sources.read_rotation(truth)),
            ),
        };
        Measurement {
            euler: QuadState {
                position: translation[0],
                attitude: rotation.attitude,
                velocity: translation[1],
                angular_rate: rotation.angular_rate,
            },
            body: rotation.body,
        }
    }
}

impl Sources {
    /// One reading of position and velocity with their errors (position's
    /// draws first).
    #[inline]
    fn read_translation(&mut self, truth: &QuadState) -> Translation {
        let position = self.position.corrupt(truth.position);
        let velocity = self.velocity.corrupt(truth.velocity);
        [position, velocity]
    }

    /// One reading of attitude and angular rate with their errors: Euler
    /// angles, Euler rates, and, when the rates are measured in the body
    /// frame of a truth that has them, the body attitude (the quaternion of
    /// the measured angles with the measured body rates).
    #[inline]
    fn read_rotation(&mut self, truth: &Measurement) -> Rotation {
        let euler = &truth.euler;
        let attitude = self.attitude.corrupt(euler.attitude);
        match (self.rates, &truth.body) {
            (RateFrame::Euler, _) => {
                Rotation { attitude, angular_rate: self.angular_rate.corrupt(euler.angular_rate), body: None }
            }
            (RateFrame::Body, None) => {
                // A truth without body rates (the paper's plant): the body
                // rates of its Euler state.
                let body_rates =
                    self.angular_rate.corrupt(euler_rates_to_body_rates(&euler.attitude, &euler.angular_rate));
                Rotation { attitude, angular_rate: euler_rates_clamped(&attitude, &body_rates), body: None }
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
                let angular_rate =
                    euler_rates_from_body_rates_with(full_angle(halves[0]), [st, gimbal_clamped_cos(ct)], &body_rates);
                Rotation { attitude, angular_rate, body: Some(BodyAttitude { quaternion, body_rates }) }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `sample_index` (truncation) is the floor of the same product for
    /// every sample rate the sensors accept and for the values they should
    /// never see (negative, zero, NaN, infinite ratios).
    #[test]
    fn sample_index_is_the_floor() {
        let floor_index = |k: u64, s: f64| (k as f64 * s + 1e-9).floor() as u64;
        let mut ratios: Vec<f64> = vec![1.0, 0.5, 0.2, 0.1, 1.0 / 3.0, 0.3, 0.7, 1e-6, 0.0, -0.0, -0.3, -2.0];
        ratios.extend([f64::NAN, f64::INFINITY, f64::NEG_INFINITY, f64::MIN_POSITIVE, f64::MAX]);
        ratios.extend((1..200).map(|r| f64::from(r) * 5.0 / 1000.0));
        ratios.extend((1..50).map(|r| 1000.0 / (f64::from(r) * 333.0 + 1.0)).filter(|r| *r <= 1.0));
        for s in ratios {
            for k in (0..3000u64).chain([1 << 40, (1 << 53) - 1, u64::MAX]) {
                assert_eq!(sample_index(k, s), floor_index(k, s), "k = {k}, s = {s}");
            }
        }
    }

    /// `Source::corrupt` with its per-axis plan gives the bits of the plain
    /// per-axis tests (three draws whenever any axis is noisy, zero terms
    /// skipped), for every mix of zero and non-zero std and bias.
    #[test]
    fn corrupt_plan_gives_the_bits_of_the_per_axis_tests() {
        let values = [0.0, 0.02, -0.5];
        let truth = [1.25, -0.0, 3.5e-3];
        for code in 0..(3usize.pow(6)) {
            let pick = |axis: usize| values[(code / 3usize.pow(axis as u32)) % 3];
            let error =
                QuantityError { std: [pick(0), pick(1), pick(2)].map(f64::abs), bias: [pick(3), pick(4), pick(5)] };
            let mut source = Source::new(error, 5, ATTITUDE_NOISE_STREAM);
            let mut rng = NoiseStream::new(sensor_noise_rng(5, ATTITUDE_NOISE_STREAM));
            for reading in 0..40 {
                let mut want = truth;
                if error.std.iter().any(|s| *s != 0.0) {
                    for k in 0..3 {
                        let z = rng.normal();
                        if error.std[k] != 0.0 {
                            want[k] += error.std[k] * z;
                        }
                    }
                }
                for k in 0..3 {
                    if error.bias[k] != 0.0 {
                        want[k] += error.bias[k];
                    }
                }
                let got = source.corrupt(truth);
                assert_eq!(got.map(f64::to_bits), want.map(f64::to_bits), "{error:?}, reading {reading}");
            }
        }
    }

    /// `Line::advance` returns what holding every sample, pushing the held
    /// reading into a ring of `latency + 1` and reading it `latency` periods
    /// later gives, at every sample rate and latency (the first reading
    /// until then).
    #[test]
    fn line_advance_is_hold_then_delay() {
        let control_rate = 1000.0;
        let rates = [
            None,
            Some(1000.0),
            Some(2000.0),
            Some(200.0),
            Some(300.0),
            Some(7.0),
            Some(999.0),
            Some(1000.0 / 3.0),
            Some(0.5),
            Some(1e-300),
            Some(-5.0),
            Some(f64::NAN),
            Some(f64::INFINITY),
        ];
        for sample_rate in rates {
            for latency in [0u32, 1, 2, 6, 13] {
                let mut line = Line::<u64>::new(SensorClock { sample_rate, latency }, control_rate);
                let every = sample_rate.map_or(1.0, |r| (r / control_rate).min(1.0));
                let (mut held, mut last, mut history) = (0u64, 0u64, Vec::new());
                for k in 0..2500u64 {
                    // The reading of period k is 1000 + k; a sample is taken
                    // when the index moves on.
                    let index = (k as f64 * every + 1e-9).floor() as u64;
                    if k == 0 || index != last {
                        last = index;
                        held = 1000 + k;
                    }
                    history.push(held);
                    let want = history[(k as usize).saturating_sub(latency as usize)];
                    let mut reads = 0;
                    let got = *line.advance(k, || {
                        reads += 1;
                        1000 + k
                    });
                    assert_eq!(got, want, "rate {sample_rate:?}, latency {latency}, period {k}");
                    assert!(reads <= 1);
                }
            }
        }
    }
}
