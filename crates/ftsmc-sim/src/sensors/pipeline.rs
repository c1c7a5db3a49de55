//! The sensor pipeline the run loop flies when `[sensors]` names an
//! estimator or a sensor table: a list of sensor stages ([`SensorStage`])
//! and one estimator stage ([`EstimatorStage`]) between the truth and the
//! controller.
//!
//! ```text
//! truth at boundary k ─► stage₁ … stageₙ (each on its clock, with its latency)
//!                         │ readings, in order of availability
//!                         ▼
//!                   estimator.accept(…) ─► estimator.output(t_k) ─► controller
//! ```
//!
//! The stages are sampled at the control period boundaries (every rate at
//! most `simulation.control_rate`). The accelerometer's truth is the mean
//! world acceleration over the last control period, `(v_k − v_{k−1}) / dt`
//! (what an integrating IMU's delta-velocity measures), zero at `t = 0`.
//!
//! Without any of the keys below the pipeline is not built and the loop
//! flies [`super::Sensors`] exactly as before (every committed scenario's
//! bits).
//!
//! # Keys (in `[sensors]`)
//!
//! * `estimator = "passthrough" | "mahony" | "eskf"` ([`EstimatorKind`]).
//! * `motion_capture = true | false`: the motion-capture/attitude reading
//!   of the other `[sensors]` keys is a stage (default: true for
//!   `passthrough`, false otherwise).
//! * `[sensors.inertial]` ([`InertialSection`]), `[sensors.gnss]`
//!   ([`GnssParams`]), `[sensors.barometer]` ([`BaroParams`]),
//!   `[sensors.magnetometer]` ([`MagParams`]): each table present turns
//!   its sensor on.
//!
//! Stage order (and so the order readings of one instant reach the
//! estimator): inertial, motion capture, GNSS, barometer, magnetometer.

use ftsmc_core::estimate::{
    self, AttitudeEstimate, Eskf, EskfConfig, EstimateError, ImuSample, InitialState, Mahony, MahonyConfig,
};
use ftsmc_core::kinematics::{euler_rates_from_body_rates, quaternion_from_euler};
use ftsmc_core::law::GainError;
use ftsmc_core::measured::{BodyAttitude, Measurement};
use ftsmc_core::model::QuadState;
use serde::{Deserialize, Serialize};

use super::baro::{isa_pressure, Baro, BaroParams};
use super::estimator::{EstimatorFailure, EstimatorStage, FailureReason, MotionCapture, Passthrough};
use super::gnss::{Gnss, GnssParams};
use super::imu::{AxisModel, Imu, ImuClass, ImuParams};
use super::mag::Mag;
use super::{Provides, Reading, SensorParams, SensorStage, SensorTruth, Stage, Stamped};

/// Which estimator turns the readings into the controller's state
/// (`[sensors] estimator`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum EstimatorKind {
    /// The motion-capture reading straight to the controller (today's behaviour).
    #[default]
    Passthrough,
    /// Mahony, Hamel & Pflimlin 2008 complementary attitude filter on the
    /// IMU (and magnetometer); position and velocity from the last GNSS
    /// or motion-capture reading.
    Mahony,
    /// The 15-state error-state Kalman filter of Solà 2017 (IMU
    /// propagation; GNSS, barometer, magnetometer, motion-capture updates).
    Eskf,
}

impl EstimatorKind {
    /// The key's spelling.
    pub fn name(self) -> &'static str {
        match self {
            Self::Passthrough => "passthrough",
            Self::Mahony => "mahony",
            Self::Eskf => "eskf",
        }
    }
}

/// Optional overrides of one axis model of an IMU class (every key of
/// [`AxisModel`], in its unit; absent: the class's value).
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct AxisOverride {
    /// White-noise density `N`, u/√Hz (> 0).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub noise_density: Option<f64>,
    /// Bias random-walk density `K`, u/s/√Hz (>= 0).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bias_random_walk: Option<f64>,
    /// Bias correlation time `τ`, s (> 0; `inf`: random walk). The bias
    /// instability (the Allan plateau) is `K √(τ/2)`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bias_correlation_time: Option<f64>,
    /// Turn-on bias standard deviation, u (>= 0).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub turn_on_bias: Option<f64>,
    /// Full-scale range, u (> 0).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub range: Option<f64>,
    /// Quantisation step (one LSB), u (>= 0).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub resolution: Option<f64>,
}

impl AxisOverride {
    fn apply(&self, m: &mut AxisModel) {
        let set = |v: &mut f64, o: Option<f64>| {
            if let Some(o) = o {
                *v = o;
            }
        };
        set(&mut m.noise_density, self.noise_density);
        set(&mut m.bias_random_walk, self.bias_random_walk);
        set(&mut m.bias_correlation_time, self.bias_correlation_time);
        set(&mut m.turn_on_bias, self.turn_on_bias);
        set(&mut m.range, self.range);
        set(&mut m.resolution, self.resolution);
    }
}

/// The `[sensors.inertial]` table: a sourced class ([`ImuClass`]:
/// `"px4-sitl"`, the default, or `"bmi088"`) and any of its values
/// overridden.
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct InertialSection {
    /// The class the values start from.
    pub class: ImuClass,
    /// Sample rate, Hz (class: 250 or 1000).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rate_hz: Option<f64>,
    /// Latency, s (class: 0).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub latency_s: Option<f64>,
    /// Accelerometer overrides, m/s².
    pub accelerometer: AxisOverride,
    /// Gyroscope overrides, rad/s.
    pub gyroscope: AxisOverride,
}

impl InertialSection {
    /// The IMU parameters: the class's with the overrides applied.
    pub fn params(&self) -> ImuParams {
        let mut p = ImuParams::of_class(self.class);
        if let Some(r) = self.rate_hz {
            p.rate_hz = r;
        }
        if let Some(l) = self.latency_s {
            p.latency_s = l;
        }
        self.accelerometer.apply(&mut p.accelerometer);
        self.gyroscope.apply(&mut p.gyroscope);
        p
    }
}

/// The `[sensors.eskf]` table: the filter's gate and when it counts as
/// lost. Its noise model is not here: it is the sensors' own.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct EskfSection {
    /// Probability `p` of the chi-square innovation gate, `0 < p < 1`
    /// (default 0.999: a reading is rejected when its NIS exceeds
    /// `χ²_m(0.999)`).
    pub gate_probability: f64,
    /// Largest variance of any error-state component before the filter is
    /// lost, in that component's unit squared (default 1e6).
    pub max_variance: f64,
    /// Longest time every aiding reading may be gated out, s (default 5).
    pub max_gated_s: f64,
}

impl Default for EskfSection {
    fn default() -> Self {
        let c = EskfConfig::default();
        Self { gate_probability: c.gate_probability, max_variance: c.max_variance, max_gated_s: MAX_GATED_S }
    }
}

/// A refused `[sensors]` pipeline: the key (under `sensors.`), the value
/// as written and what was expected.
#[derive(Clone, Debug, PartialEq)]
pub struct PipelineError {
    /// Dotted key under `sensors.` (`"gnss.rate_hz"`, `"estimator"`).
    pub key: String,
    /// The offending value.
    pub value: String,
    /// What is allowed.
    pub expected: String,
}

impl From<GainError> for PipelineError {
    fn from(e: GainError) -> Self {
        Self { key: e.field.to_string(), value: crate::text::show(e.value), expected: e.expected.to_string() }
    }
}

/// True when `params` asks for the pipeline (an estimator or any sensor table).
pub fn requested(params: &SensorParams) -> bool {
    params.estimator.is_some()
        || params.motion_capture.is_some()
        || params.inertial.is_some()
        || params.gnss.is_some()
        || params.barometer.is_some()
        || params.magnetometer.is_some()
        || params.eskf.is_some()
}

/// The recorded columns of the pipeline of `params` (in stage order, then
/// the estimator's; [`Pipeline::column_names`] of the pipeline it builds).
pub fn column_names(params: &SensorParams) -> Vec<&'static str> {
    use super::SensorModel;
    let mut names: Vec<&'static str> = Vec::new();
    if params.inertial.is_some() {
        names.extend(Imu::COLUMNS);
    }
    if params.gnss.is_some() {
        names.extend(Gnss::COLUMNS);
    }
    if params.barometer.is_some() {
        names.extend(Baro::COLUMNS);
    }
    if params.magnetometer.is_some() {
        names.extend(Mag::COLUMNS);
    }
    names.extend(match params.estimator.unwrap_or_default() {
        EstimatorKind::Passthrough => &[][..],
        EstimatorKind::Mahony => MAHONY_COLUMNS,
        EstimatorKind::Eskf => ESKF_COLUMNS,
    });
    names
}

/// Whether the motion-capture stage is flown (`motion_capture`, default:
/// only with `passthrough`).
fn has_motion_capture(params: &SensorParams) -> bool {
    params.motion_capture.unwrap_or(params.estimator.unwrap_or_default() == EstimatorKind::Passthrough)
}

/// Check a pipeline `[sensors]` against the control rate `control_rate`
/// (Hz): every sensor's own values (rates `0 < rate <= control_rate`,
/// noise densities and standard deviations the estimator divides by
/// `> 0`), rates consistent with the estimator (no aiding sensor faster
/// than the IMU it propagates on), and the sources the estimator needs.
/// Nothing to check (Ok) when the pipeline is not requested.
pub fn check(params: &SensorParams, control_rate: f64) -> Result<(), PipelineError> {
    if !requested(params) {
        return Ok(());
    }
    let kind = params.estimator.unwrap_or_default();
    let imu = params.inertial.map(|s| s.params());
    if let Some(imu) = &imu {
        imu.check(control_rate)?;
    }
    if let Some(g) = &params.gnss {
        g.check(control_rate)?;
    }
    if let Some(b) = &params.barometer {
        b.check(control_rate)?;
    }
    if let Some(m) = &params.magnetometer {
        m.check(control_rate)?;
    }
    let mocap = has_motion_capture(params);
    let error = |key: &str, value: String, expected: String| PipelineError { key: key.into(), value, expected };
    let needs =
        |what: &str| error("estimator", format!("\"{}\"", kind.name()), format!("{what} (add the table to [sensors])"));
    match kind {
        EstimatorKind::Passthrough => {
            if !mocap {
                return Err(error(
                    "motion_capture",
                    "false".into(),
                    "true with estimator = \"passthrough\" (it hands the motion-capture reading on)".into(),
                ));
            }
        }
        EstimatorKind::Mahony | EstimatorKind::Eskf => {
            if imu.is_none() {
                return Err(needs("an inertial unit: [sensors.inertial]"));
            }
            if params.gnss.is_none() && !mocap {
                return Err(needs("a position source: [sensors.gnss] or motion_capture = true"));
            }
        }
    }
    if let (Some(imu), EstimatorKind::Mahony | EstimatorKind::Eskf) = (&imu, kind) {
        // The estimator propagates on the IMU: an aiding sensor faster than
        // it would be fused several times between two propagations.
        let aiding = [
            ("gnss.rate_hz", params.gnss.map(|g| g.rate_hz)),
            ("barometer.rate_hz", params.barometer.map(|b| b.rate_hz)),
            ("magnetometer.rate_hz", params.magnetometer.map(|m| m.rate_hz)),
        ];
        for (key, rate) in aiding {
            if let Some(rate) = rate.filter(|r| *r > imu.rate_hz) {
                return Err(error(
                    key,
                    crate::text::show(rate),
                    format!(
                        "at most inertial.rate_hz = {} Hz (the {} estimator propagates on the IMU)",
                        crate::text::show(imu.rate_hz),
                        kind.name()
                    ),
                ));
            }
        }
    }
    if let Some(e) = &params.eskf {
        let p = e.gate_probability;
        if !(p > 0.0 && p < 1.0) {
            return Err(error("eskf.gate_probability", crate::text::show(p), "0 < gate_probability < 1".into()));
        }
        super::check_non_negative("eskf.max_variance", e.max_variance, true)?;
        super::check_non_negative("eskf.max_gated_s", e.max_gated_s, true)?;
        if kind != EstimatorKind::Eskf {
            return Err(error("eskf", "a table".into(), "[sensors.eskf] only with estimator = \"eskf\"".into()));
        }
    }
    if kind == EstimatorKind::Eskf {
        // Standard deviations the filter's measurement covariance is built of.
        let strict = |key: &'static str, v: f64| super::check_non_negative(key, v, true).map_err(PipelineError::from);
        if let Some(g) = &params.gnss {
            strict("gnss.position_std", g.position_std)?;
            strict("gnss.vertical_std", g.vertical_std)?;
            strict("gnss.velocity_std", g.velocity_std)?;
            strict("gnss.vertical_velocity_std", g.vertical_velocity_std)?;
        }
        if let Some(b) = &params.barometer {
            strict("barometer.noise_std", b.noise_std)?;
        }
        if let Some(m) = &params.magnetometer {
            for s in m.noise_std {
                strict("magnetometer.noise_std", s)?;
            }
        }
    }
    Ok(())
}

/// Default longest time (s) the ESKF may go with every aiding reading
/// rejected by its innovation gate while readings keep arriving, before
/// the flight ends with [`FailureReason::InnovationGate`]
/// (`[sensors.eskf] max_gated_s`).
pub const MAX_GATED_S: f64 = 5.0;

/// Smallest standard deviations the ESKF assumes for a motion-capture
/// reading: 1 mm in position, 1 mrad in attitude (a perfect `[sensors]`
/// reading has none, and a Kalman update needs `R > 0`).
pub const MOCAP_STD_FLOOR: [f64; 2] = [1e-3, 1e-3];

/// The sensor stages and the estimator of one flight.
pub struct Pipeline {
    stages: Vec<Box<dyn SensorStage>>,
    estimator: Box<dyn EstimatorStage>,
    /// Velocity and time of the previous boundary (the accelerometer's truth).
    previous: Option<([f64; 3], f64)>,
    gravity: f64,
    /// Column names: each stage's, then the estimator's.
    names: Vec<&'static str>,
    /// The failure, once the estimator failed (every later call repeats it).
    failed: Option<EstimatorFailure>,
}

impl Pipeline {
    /// The pipeline of `params` (checked by [`check`]) at `control_rate`
    /// (Hz), its noise keyed by `seed`, for a flight starting at `initial`
    /// (the estimator's prior: aligned with the truth at `t = 0`) under
    /// gravity `gravity` (m/s²).
    pub fn new(params: &SensorParams, control_rate: f64, seed: u64, initial: &QuadState, gravity: f64) -> Self {
        let mut stages: Vec<Box<dyn SensorStage>> = Vec::new();
        let imu = params.inertial.map(|s| s.params());
        if let Some(imu) = &imu {
            stages.push(Box::new(Stage::new(Imu::new(imu, seed), imu.clock())));
        }
        let mocap = has_motion_capture(params);
        if mocap {
            stages.push(Box::new(MotionCapture::new(params.motion_capture_part(), control_rate, seed)));
        }
        if let Some(g) = params.gnss {
            stages.push(Box::new(Stage::new(Gnss::new(g, seed), g.clock())));
        }
        if let Some(b) = params.barometer {
            stages.push(Box::new(Stage::new(Baro::new(b, seed), b.clock())));
        }
        if let Some(m) = params.magnetometer {
            stages.push(Box::new(Stage::new(Mag::new(m, seed), m.clock())));
        }
        let estimator: Box<dyn EstimatorStage> = match params.estimator.unwrap_or_default() {
            EstimatorKind::Passthrough => Box::new(Passthrough::default()),
            EstimatorKind::Mahony => Box::new(MahonyStage::new(params, initial, gravity)),
            EstimatorKind::Eskf => Box::new(EskfStage::new(params, initial, gravity)),
        };
        let mut names: Vec<&'static str> = stages.iter().flat_map(|s| s.columns().iter().copied()).collect();
        names.extend(estimator.columns().iter().copied());
        debug_assert_eq!(names, column_names(params), "the recorder's header is the pipeline's columns");
        Self { stages, estimator, previous: None, gravity, names, failed: None }
    }

    /// The recorded column names (each stage's, then the estimator's).
    pub fn column_names(&self) -> &[&'static str] {
        &self.names
    }

    /// The values of [`Pipeline::column_names`] now.
    pub fn record(&self, out: &mut [f64]) {
        let mut at = 0;
        for s in &self.stages {
            let n = s.columns().len();
            s.record(&mut out[at..at + n]);
            at += n;
        }
        let n = self.estimator.columns().len();
        self.estimator.record(&mut out[at..at + n]);
    }

    /// What the estimator gives the controller at the boundary of `truth`
    /// (its Euler state and, if any, body attitude) at time `t` (s): every
    /// stage sampled, every reading available by `t` accepted, then the
    /// output; or the failure that ends the flight.
    pub fn measure(&mut self, t: f64, truth: &Measurement) -> Result<Measurement, EstimatorFailure> {
        if let Some(f) = self.failed {
            return Err(f);
        }
        let v = truth.euler.velocity;
        let acceleration = match self.previous {
            Some((v0, t0)) if t > t0 => core::array::from_fn(|i| (v[i] - v0[i]) / (t - t0)),
            _ => [0.0; 3],
        };
        self.previous = Some((v, t));
        let sensor_truth =
            SensorTruth { t, state: &truth.euler, body: truth.body, acceleration, gravity: self.gravity };
        let estimator = &mut self.estimator;
        for stage in &mut self.stages {
            stage.step(&sensor_truth, &mut |s: &Stamped| estimator.accept(s));
        }
        let out = self.estimator.output(t);
        if let Err(f) = out {
            self.failed = Some(f);
        }
        out
    }

    /// Re-derive every stage's noise streams from `key`
    /// ([`SensorStage::reseed`]); the estimator's state is kept.
    pub fn reseed(&mut self, key: u64) {
        for s in &mut self.stages {
            s.reseed(key);
        }
    }

    /// What the stages provide together.
    pub fn provides(&self) -> Provides {
        self.stages.iter().fold(Provides::default(), |acc, s| acc.union(s.provides()))
    }
}

/// A core estimator error as a flight's failure.
fn failure_of(e: EstimateError, t: f64) -> EstimatorFailure {
    use estimate::DivergenceReason as D;
    let reason = match e {
        EstimateError::Diverged { reason: D::NonFiniteState | D::NonFiniteCovariance, .. } => FailureReason::NonFinite,
        EstimateError::Diverged { reason: D::NegativeVariance { .. }, .. } => FailureReason::CovarianceNotPositive,
        EstimateError::Diverged { reason: D::VarianceBound { .. }, .. } => FailureReason::CovarianceBound,
        EstimateError::BadReading { .. } | EstimateError::TimeNotIncreasing { .. } | EstimateError::NotStarted => {
            FailureReason::NonFinite
        }
    };
    let time = match e {
        EstimateError::Diverged { time, .. } => time,
        _ => t,
    };
    EstimatorFailure { reason, time }
}

/// The Euler state and body attitude of an attitude `quaternion`, body
/// rates `body_rates` (rad/s), position and velocity.
fn measurement_of(position: [f64; 3], velocity: [f64; 3], quaternion: [f64; 4], body_rates: [f64; 3]) -> Measurement {
    let attitude = ftsmc_core::kinematics::euler_from_quaternion(&quaternion);
    let angular_rate = euler_rates_from_body_rates(&attitude, &body_rates);
    Measurement {
        euler: QuadState { position, attitude, velocity, angular_rate },
        body: Some(BodyAttitude { quaternion, body_rates }),
    }
}

/// Tracks whether the gate rejects every aiding reading (see [`MAX_GATED_S`]).
#[derive(Clone, Copy, Debug)]
struct GateWatch {
    /// Time of the first rejection since the last accepted reading, s.
    rejecting_since: Option<f64>,
    /// The longest rejection allowed, s.
    max_s: f64,
}

impl GateWatch {
    fn saw(&mut self, accepted: bool, t: f64) {
        if accepted {
            self.rejecting_since = None;
        } else if self.rejecting_since.is_none() {
            self.rejecting_since = Some(t);
        }
    }
    fn failed(&self, t: f64) -> bool {
        self.rejecting_since.is_some_and(|t0| t - t0 > self.max_s)
    }
}

/// The [`Eskf`] as an estimator stage. Its configuration is the sensors'
/// own (a matched filter): process noise from the IMU's densities and
/// bias random walks, measurement noise from each sensor's standard
/// deviations, the magnetic reference from `[sensors.magnetometer]`.
/// A late reading (GNSS) is moved forward to the filter's time by the
/// motion the filter propagated since it was sampled, `z + Δ(t) − Δ(t_sample)`
/// with `Δ` the running sum of the position (velocity) increments of the
/// IMU propagations alone — not of the updates, which correct the
/// estimate and are no motion — kept as a short history (the
/// measurement-extrapolation approach to delayed measurements; Larsen,
/// Andersen, Ravn & Poulsen, "Incorporation of time delayed measurements
/// in a discrete-time Kalman filter", IEEE CDC 1998, with the
/// cross-covariance of the shift neglected).
pub struct EskfStage {
    filter: Eskf,
    /// `(time, Δp, Δv)` after each propagation, oldest first, covering
    /// the longest latency (allocated once).
    history: std::collections::VecDeque<(f64, [f64; 3], [f64; 3])>,
    history_len: usize,
    /// The running sums `Δp` (m) and `Δv` (m/s) of the propagations.
    propagated: ([f64; 3], [f64; 3]),
    gnss: Option<GnssParams>,
    baro_std_m: f64,
    mag_std: f64,
    mocap_std: [f64; 2],
    gate: GateWatch,
    failed: Option<EstimatorFailure>,
    /// NIS of the last update and its dimension.
    last_nis: (f64, f64),
}

/// Recorded columns of the ESKF stage: the estimate (position, velocity,
/// Euler attitude, gyro and accelerometer biases), the covariance diagonal
/// of the error state `[δp, δv, δθ, δb_g, δb_a]`, the last update's NIS
/// and its dimension.
pub const ESKF_COLUMNS: &[&str] = &[
    "est_x",
    "est_y",
    "est_z",
    "est_vx",
    "est_vy",
    "est_vz",
    "est_phi",
    "est_theta",
    "est_psi",
    "est_bgx",
    "est_bgy",
    "est_bgz",
    "est_bax",
    "est_bay",
    "est_baz",
    "var_px",
    "var_py",
    "var_pz",
    "var_vx",
    "var_vy",
    "var_vz",
    "var_thx",
    "var_thy",
    "var_thz",
    "var_bgx",
    "var_bgy",
    "var_bgz",
    "var_bax",
    "var_bay",
    "var_baz",
    "est_nis",
    "est_nis_dim",
];

/// Altitude standard deviation (m) of a barometer with pressure noise
/// `noise_std` (Pa) at `origin_altitude` (m): `σ_h = σ_p / |dp/dh|`, the
/// slope of the ISA troposphere by a central difference over ±0.5 m.
fn baro_altitude_std(b: &BaroParams) -> f64 {
    let h = b.origin_altitude;
    let slope = isa_pressure(h - 0.5) - isa_pressure(h + 0.5);
    b.noise_std / slope
}

impl EskfStage {
    /// The filter of `params` at the truth `initial` (its initial
    /// covariance: the sensors' own uncertainty, see docs/estimators.md).
    pub fn new(params: &SensorParams, initial: &QuadState, gravity: f64) -> Self {
        let imu = params.inertial.map(|s| s.params()).unwrap_or_else(|| ImuParams::of_class(ImuClass::Px4Sitl));
        let field = params.magnetometer.map_or(EskfConfig::default().magnetic_field, |m| m.world_field());
        let gnss = params.gnss;
        let section = params.eskf.unwrap_or_default();
        let position_std = gnss.map_or(MOCAP_STD_FLOOR[0].max(params.position.std[0]), |g| g.position_std);
        let config = EskfConfig {
            gyro_noise: imu.gyroscope.noise_density,
            accel_noise: imu.accelerometer.noise_density,
            gyro_bias_random_walk: imu.gyroscope.bias_random_walk,
            accel_bias_random_walk: imu.accelerometer.bias_random_walk,
            gravity,
            magnetic_field: field,
            initial_position_std: position_std.max(1e-3),
            initial_velocity_std: gnss.map_or(0.05, |g| g.velocity_std.max(0.05)),
            initial_attitude_std: 0.02,
            initial_gyro_bias_std: imu.gyroscope.turn_on_bias.max(1e-3),
            initial_accel_bias_std: imu.accelerometer.turn_on_bias.max(1e-2),
            gate_probability: section.gate_probability,
            max_variance: section.max_variance,
        };
        let start = InitialState {
            position: initial.position,
            velocity: initial.velocity,
            quaternion: quaternion_from_euler(&initial.attitude),
            gyro_bias: [0.0; 3],
            accel_bias: [0.0; 3],
        };
        // `check` refused every value this could fail on.
        let filter = Eskf::new(config, start).expect("a checked [sensors] gives a valid ESKF configuration");
        // The history covers the GNSS latency at the IMU rate, plus margin.
        let latency = gnss.map_or(0.0, |g| g.latency_s);
        let history_len = (latency * imu.rate_hz).ceil() as usize + 4;
        Self {
            filter,
            history: std::collections::VecDeque::with_capacity(history_len),
            history_len,
            propagated: ([0.0; 3], [0.0; 3]),
            gnss,
            baro_std_m: params.barometer.map_or(1.0, |b| baro_altitude_std(&b)),
            mag_std: params.magnetometer.map_or(0.03, |m| m.noise_std.iter().fold(0.0f64, |a, b| a.max(*b))),
            mocap_std: [
                MOCAP_STD_FLOOR[0].max(params.position.std.iter().fold(0.0f64, |a, b| a.max(*b))),
                MOCAP_STD_FLOOR[1].max(params.attitude.std.iter().fold(0.0f64, |a, b| a.max(*b))),
            ],
            gate: GateWatch { rejecting_since: None, max_s: section.max_gated_s },
            failed: None,
            last_nis: (f64::NAN, 0.0),
        }
    }

    /// The filter's current estimate.
    pub fn estimate(&self) -> estimate::Estimate {
        self.filter.estimate()
    }

    /// The propagated sums `(Δp, Δv)` at `t` (s): the last history entry
    /// at or before it (the oldest one if none is).
    fn state_at(&self, t: f64) -> Option<([f64; 3], [f64; 3])> {
        let mut found = self.history.front()?;
        for h in &self.history {
            if h.0 <= t + 1e-9 {
                found = h;
            } else {
                break;
            }
        }
        Some((found.1, found.2))
    }

    fn fuse(&mut self, s: &Stamped) -> Result<(), EstimateError> {
        let report = match s.reading {
            Reading::Imu(r) => {
                let imu = ImuSample { time: s.t_sample, gyro: r.body_rates, specific_force: r.specific_force };
                let before = self.filter.estimate();
                self.filter.predict(&imu)?;
                let after = self.filter.estimate();
                let (dp, dv) = &mut self.propagated;
                for i in 0..3 {
                    dp[i] += after.position[i] - before.position[i];
                    dv[i] += after.velocity[i] - before.velocity[i];
                }
                if self.history.len() == self.history_len {
                    self.history.pop_front();
                }
                self.history.push_back((s.t_sample, *dp, *dv));
                return Ok(());
            }
            Reading::Gnss(r) => {
                let Some(g) = self.gnss else { return Ok(()) };
                if !r.fix {
                    return Ok(());
                }
                let (p_now, v_now) = self.propagated;
                let (p_then, v_then) = self.state_at(s.t_sample).unwrap_or(self.propagated);
                let fix = estimate::GnssFix {
                    time: s.t_available,
                    position: core::array::from_fn(|i| r.position[i] + p_now[i] - p_then[i]),
                    velocity: core::array::from_fn(|i| r.velocity[i] + v_now[i] - v_then[i]),
                    position_std: [g.position_std, g.position_std, g.vertical_std],
                    velocity_std: [g.velocity_std, g.velocity_std, g.vertical_velocity_std],
                    valid: true,
                };
                self.filter.update_gnss(&fix)?
            }
            Reading::Baro(r) => Some(self.filter.update_baro(&estimate::BaroReading {
                time: s.t_available,
                altitude: r.altitude,
                std: self.baro_std_m,
            })?),
            Reading::Mag(r) => Some(self.filter.update_mag(&estimate::MagReading {
                time: s.t_available,
                field: r.field,
                std: self.mag_std,
            })?),
            Reading::Motion(m) => {
                let quaternion = m.body.map_or_else(|| quaternion_from_euler(&m.euler.attitude), |b| b.quaternion);
                Some(self.filter.update_mocap(&estimate::MocapReading {
                    time: s.t_available,
                    position: m.euler.position,
                    quaternion,
                    position_std: self.mocap_std[0],
                    attitude_std: self.mocap_std[1],
                })?)
            }
        };
        if let Some(report) = report {
            self.gate.saw(report.accepted, s.t_available);
            self.last_nis = (report.nis, report.dimension as f64);
        }
        Ok(())
    }
}

impl EstimatorStage for EskfStage {
    fn name(&self) -> &'static str {
        "eskf"
    }
    fn needs(&self) -> Provides {
        Provides { position: true, velocity: false, attitude: false, rate: true }
    }
    fn accept(&mut self, reading: &Stamped) {
        if self.failed.is_some() {
            return;
        }
        match self.fuse(reading) {
            Ok(()) => {}
            // An update before the first IMU sample cannot happen in stage
            // order (the IMU is sampled first); it is skipped, not fatal.
            Err(EstimateError::NotStarted) => {}
            Err(e) => self.failed = Some(failure_of(e, reading.t_available)),
        }
    }
    fn output(&mut self, t: f64) -> Result<Measurement, EstimatorFailure> {
        if let Some(f) = self.failed {
            return Err(f);
        }
        if self.gate.failed(t) {
            let f = EstimatorFailure { reason: FailureReason::InnovationGate, time: t };
            self.failed = Some(f);
            return Err(f);
        }
        let e = self.filter.estimate();
        Ok(measurement_of(e.position, e.velocity, e.quaternion, e.body_rate))
    }
    fn columns(&self) -> &'static [&'static str] {
        ESKF_COLUMNS
    }
    fn record(&self, out: &mut [f64]) {
        let e = self.filter.estimate();
        let parts = [e.position, e.velocity, e.euler, e.gyro_bias, e.accel_bias];
        for (k, p) in parts.iter().enumerate() {
            out[3 * k..3 * k + 3].copy_from_slice(p);
        }
        for i in 0..15 {
            out[15 + i] = e.covariance[i][i];
        }
        out[30] = self.last_nis.0;
        out[31] = self.last_nis.1;
    }
}

/// The [`Mahony`] filter as an estimator stage: attitude and body rates
/// from the IMU (and magnetometer, the last reading held); position and
/// velocity dead-reckoned on the IMU between fixes and reset to each GNSS
/// fix or motion-capture reading, moved forward by the motion propagated
/// since it was sampled (as [`EskfStage`] does with late readings).
///
/// Between fixes, with `R̂` the filter's attitude, `f` the specific force
/// and `g` gravity (world `z` up): `a = R̂ f − g e₃`, `p ← p + v Δt + ½ a Δt²`,
/// `v ← v + a Δt` (strapdown navigation, Titterton & Weston, *Strapdown
/// Inertial Navigation Technology*, 2nd ed., 2004, §3.5). At a fix sampled
/// at `t_s`: `p ← z_p + Δp(t) − Δp(t_s)`, `v ← z_v + Δv(t) − Δv(t_s)`. Holding
/// the last fix instead (what this stage did first) handed the controller a
/// position up to latency + one GNSS period old (150 + 125 ms) and the
/// scenario's initial state until the first fix: a stiff position loop
/// (FTAFTSMC on the paper's steps) wound its thrust up against a frozen
/// altitude and crashed within 0.3 s.
pub struct MahonyStage {
    filter: Mahony,
    mag: Option<estimate::MagReading>,
    position: [f64; 3],
    velocity: [f64; 3],
    gravity: f64,
    /// Time of the last IMU sample, s.
    last_imu: Option<f64>,
    /// `(time, Δp, Δv)` after each propagation, oldest first (allocated once).
    history: std::collections::VecDeque<(f64, [f64; 3], [f64; 3])>,
    history_len: usize,
    /// Running sums `Δp` (m), `Δv` (m/s) of the propagations.
    propagated: ([f64; 3], [f64; 3]),
    failed: Option<EstimatorFailure>,
}

/// Recorded columns of the Mahony stage: the attitude estimate and the gyro bias.
pub const MAHONY_COLUMNS: &[&str] = &["est_phi", "est_theta", "est_psi", "est_bgx", "est_bgy", "est_bgz"];

impl MahonyStage {
    /// The filter of `params` aligned with the truth `initial`.
    pub fn new(params: &SensorParams, initial: &QuadState, gravity: f64) -> Self {
        let mut config = MahonyConfig { gravity, ..MahonyConfig::default() };
        match params.magnetometer {
            Some(m) => config.magnetic_field = m.world_field(),
            None => config.mag_weight = 0.0,
        }
        let filter = Mahony::new(config, quaternion_from_euler(&initial.attitude))
            .expect("a checked [sensors] gives a valid Mahony configuration");
        let imu = params.inertial.map(|s| s.params()).unwrap_or_else(|| ImuParams::of_class(ImuClass::Px4Sitl));
        // The history covers the GNSS latency, and at least 0.5 s (a
        // motion-capture reading's latency is whole control periods).
        let latency = params.gnss.map_or(0.0, |g| g.latency_s).max(0.5);
        let history_len = (latency * imu.rate_hz).ceil() as usize + 4;
        Self {
            filter,
            mag: None,
            position: initial.position,
            velocity: initial.velocity,
            gravity,
            last_imu: None,
            history: std::collections::VecDeque::with_capacity(history_len),
            history_len,
            propagated: ([0.0; 3], [0.0; 3]),
            failed: None,
        }
    }

    /// Dead-reckon position and velocity over the IMU interval ending at
    /// `t` (s) with specific force `f` (m/s², body) and the filter's attitude.
    fn propagate(&mut self, t: f64, f: &[f64; 3]) {
        if let Some(t0) = self.last_imu.filter(|t0| t > *t0) {
            let dt = t - t0;
            let r = ftsmc_core::kinematics::rotation_from_quaternion(&self.filter.estimate().quaternion);
            let rf = ftsmc_core::math::mat_vec(&r, f);
            let a = [rf[0], rf[1], rf[2] - self.gravity];
            let (dp, dv) = &mut self.propagated;
            for i in 0..3 {
                let step_p = self.velocity[i] * dt + 0.5 * a[i] * dt * dt;
                let step_v = a[i] * dt;
                self.position[i] += step_p;
                self.velocity[i] += step_v;
                dp[i] += step_p;
                dv[i] += step_v;
            }
        }
        self.last_imu = Some(t);
        if self.history.len() == self.history_len {
            self.history.pop_front();
        }
        self.history.push_back((t, self.propagated.0, self.propagated.1));
    }

    /// Reset position and velocity to a fix sampled at `t_sample` (s),
    /// moved forward by the motion propagated since.
    fn reset_to(&mut self, t_sample: f64, position: &[f64; 3], velocity: &[f64; 3]) {
        let mut then = self.history.front().map_or(self.propagated, |h| (h.1, h.2));
        for h in &self.history {
            if h.0 <= t_sample + 1e-9 {
                then = (h.1, h.2);
            } else {
                break;
            }
        }
        let (p_now, v_now) = self.propagated;
        for i in 0..3 {
            self.position[i] = position[i] + p_now[i] - then.0[i];
            self.velocity[i] = velocity[i] + v_now[i] - then.1[i];
        }
    }

    /// The filter's current attitude estimate.
    pub fn estimate(&self) -> AttitudeEstimate {
        self.filter.estimate()
    }
}

impl EstimatorStage for MahonyStage {
    fn name(&self) -> &'static str {
        "mahony"
    }
    fn needs(&self) -> Provides {
        Provides { position: true, velocity: true, attitude: false, rate: true }
    }
    fn accept(&mut self, s: &Stamped) {
        if self.failed.is_some() {
            return;
        }
        match s.reading {
            Reading::Imu(r) => {
                let imu = ImuSample { time: s.t_sample, gyro: r.body_rates, specific_force: r.specific_force };
                if let Err(e) = self.filter.update(&imu, self.mag.take().as_ref()) {
                    self.failed = Some(failure_of(e, s.t_available));
                    return;
                }
                self.propagate(s.t_sample, &r.specific_force);
            }
            Reading::Mag(r) => self.mag = Some(estimate::MagReading { time: s.t_available, field: r.field, std: 1.0 }),
            Reading::Gnss(r) if r.fix => self.reset_to(s.t_sample, &r.position, &r.velocity),
            Reading::Motion(m) => self.reset_to(s.t_sample, &m.euler.position, &m.euler.velocity),
            Reading::Gnss(_) | Reading::Baro(_) => {}
        }
    }
    fn output(&mut self, _t: f64) -> Result<Measurement, EstimatorFailure> {
        if let Some(f) = self.failed {
            return Err(f);
        }
        let e = self.filter.estimate();
        Ok(measurement_of(self.position, self.velocity, e.quaternion, e.body_rate))
    }
    fn columns(&self) -> &'static [&'static str] {
        MAHONY_COLUMNS
    }
    fn record(&self, out: &mut [f64]) {
        let e = self.filter.estimate();
        out[..3].copy_from_slice(&e.euler);
        out[3..6].copy_from_slice(&e.gyro_bias);
    }
}
