//! Estimator stages: what turns the sensors' timestamped readings
//! ([`Stamped`]) into the state the controller sees ([`Measurement`]).
//!
//! An estimator is fed every reading as it becomes available (IMU samples
//! at the IMU's rate, GNSS, barometer, magnetometer and motion capture at
//! theirs, each after its latency) through [`EstimatorStage::accept`], and
//! asked once per control period for its output
//! ([`EstimatorStage::output`]). It may fail (diverge) with a reason and a
//! time ([`EstimatorFailure`]); the run loop is to end the flight with that
//! outcome, never panic. It may record extra columns (its estimate and
//! covariance diagonal).
//!
//! [`Passthrough`] is the motion-capture reading straight to the
//! controller; [`MotionCapture`] is the stage that gives it [`Sensors`]'
//! reading every control period. The Mahony and ESKF stages are in
//! [`super::pipeline`].

use ftsmc_core::measured::Measurement;
use serde::{Deserialize, Serialize};

use super::{Provides, Reading, SensorParams, SensorStage, SensorTruth, Sensors, Stamped};

/// Why an estimator stopped giving a state.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum FailureReason {
    /// It was asked for a state before any reading it needs arrived.
    NoReading,
    /// Its state or covariance became NaN or infinite.
    NonFinite,
    /// Its covariance lost positive definiteness.
    CovarianceNotPositive,
    /// A variance grew beyond the filter's bound (the estimate is lost).
    CovarianceBound,
    /// Its innovations stayed beyond their gate (the filter diverged).
    InnovationGate,
}

impl FailureReason {
    /// The reason as one word (its serde spelling), for exit texts.
    pub fn word(self) -> &'static str {
        match self {
            Self::NoReading => "no-reading",
            Self::NonFinite => "non-finite",
            Self::CovarianceNotPositive => "covariance-not-positive",
            Self::CovarianceBound => "covariance-bound",
            Self::InnovationGate => "innovation-gate",
        }
    }
}

/// An estimator's failure: why, and when (s).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
pub struct EstimatorFailure {
    /// Why.
    pub reason: FailureReason,
    /// Simulated time of the failure, s.
    pub time: f64,
}

/// An estimator as the run loop sees it.
pub trait EstimatorStage: Send {
    /// Its name (`"passthrough"`).
    fn name(&self) -> &'static str;
    /// The quantities it needs among its sensors ([`SensorStage::provides`]).
    fn needs(&self) -> Provides;
    /// One reading, as it becomes available (in order of availability).
    fn accept(&mut self, reading: &Stamped);
    /// The state the controller sees at time `t` (s), or why there is none.
    fn output(&mut self, t: f64) -> Result<Measurement, EstimatorFailure>;
    /// Names of its extra recorded columns (estimate, covariance diagonal).
    fn columns(&self) -> &'static [&'static str] {
        &[]
    }
    /// Its extra columns' values now, one per [`EstimatorStage::columns`].
    fn record(&self, out: &mut [f64]) {
        let _ = out;
    }
}

/// The motion-capture/attitude reading straight to the controller: the
/// last [`Reading::Motion`] accepted. Needs position, velocity, attitude
/// and rate.
#[derive(Clone, Debug, Default)]
pub struct Passthrough {
    last: Option<Measurement>,
}

impl EstimatorStage for Passthrough {
    fn name(&self) -> &'static str {
        "passthrough"
    }
    fn needs(&self) -> Provides {
        Provides { position: true, velocity: true, attitude: true, rate: true }
    }
    fn accept(&mut self, reading: &Stamped) {
        if let Reading::Motion(m) = reading.reading {
            self.last = Some(m);
        }
    }
    fn output(&mut self, t: f64) -> Result<Measurement, EstimatorFailure> {
        self.last.ok_or(EstimatorFailure { reason: super::estimator::FailureReason::NoReading, time: t })
    }
}

/// [`Sensors`] as a stage: one reading every control period (its own
/// sample clock and latency in control periods, as today), available at
/// once. With perfect parameters the reading is the truth itself, body
/// attitude included.
pub struct MotionCapture {
    sensors: Sensors,
    perfect: bool,
    control_rate_hz: f64,
    last: Option<Measurement>,
}

impl MotionCapture {
    /// The stage of `params` at `control_rate_hz` (Hz), keyed by `seed`.
    pub fn new(params: SensorParams, control_rate_hz: f64, seed: u64) -> Self {
        Self {
            sensors: Sensors::new(params, control_rate_hz, seed),
            perfect: params.is_perfect(),
            control_rate_hz,
            last: None,
        }
    }

    /// The reading of `truth` (Euler state and, if any, body attitude):
    /// [`Sensors::measure_full`] bit for bit. Call once per control period.
    pub fn measure(&mut self, truth: &Measurement) -> Measurement {
        let m = if self.perfect { *truth } else { self.sensors.measure_full(truth) };
        self.last = Some(m);
        m
    }
}

impl SensorStage for MotionCapture {
    fn name(&self) -> &'static str {
        "mocap"
    }
    fn provides(&self) -> Provides {
        Provides { position: true, velocity: true, attitude: true, rate: true }
    }
    fn step(&mut self, truth: &SensorTruth<'_>, sink: &mut dyn FnMut(&Stamped)) {
        let m = self.measure(&Measurement { euler: *truth.state, body: truth.body });
        sink(&Stamped { t_sample: truth.t, t_available: truth.t, reading: Reading::Motion(m) });
    }
    fn reseed(&mut self, key: u64) {
        // Rebuilt from `key`: the draws are those of a sensor seeded with
        // `key`; its held samples and latency line start afresh.
        self.sensors = Sensors::new(*self.sensors.params(), self.control_rate_hz, key);
    }
    fn columns(&self) -> &'static [&'static str] {
        &[]
    }
    fn record(&self, out: &mut [f64]) {
        let _ = out;
    }
}

/// Check that `estimator` has every source it needs among `stages`;
/// the error names the estimator and the missing quantity.
pub fn check_sources(estimator: &dyn EstimatorStage, stages: &[&dyn SensorStage]) -> Result<(), String> {
    let have = stages.iter().fold(Provides::default(), |acc, s| acc.union(s.provides()));
    let need = estimator.needs();
    if have.covers(need) {
        return Ok(());
    }
    let missing: Vec<&str> = [
        (need.position && !have.position, "position"),
        (need.velocity && !have.velocity, "velocity"),
        (need.attitude && !have.attitude, "attitude"),
        (need.rate && !have.rate, "angular rate"),
    ]
    .iter()
    .filter(|(m, _)| *m)
    .map(|(_, n)| *n)
    .collect();
    Err(format!(
        "sensors.estimator = \"{}\" needs a source of {} (sensors: {})",
        estimator.name(),
        missing.join(", "),
        stages.iter().map(|s| s.name()).collect::<Vec<_>>().join(", ")
    ))
}
