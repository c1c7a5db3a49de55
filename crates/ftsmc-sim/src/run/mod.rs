//! The run loop, one for every flight: a controller on its own clock
//! (zero-order hold at the control period) behind a sensor stage, an
//! actuator stage ([`actuation`]), a truth model (`run/truth.rs`: paper Eq. 1 or
//! the rigid body) integrated by RK4 substeps between control ticks
//! (restarting at each tick, where the input jumps), the environment
//! (plant variations, wind, ground), and per-tick observers ([`observer`]:
//! metrics, recording, envelope, flight statistics). [`Flight`] is one
//! flight as a steppable object; [`simulate`] steps it to the end.
//!
//! A run that diverges is an outcome ([`ExitStatus::Diverged`] with the
//! reason and time), never a panic.

use ftsmc_core::cascade::Controller;
use ftsmc_core::model::Reference;

use crate::metrics::Metrics;
use crate::scenario::Scenario;

pub mod actuation;
mod exit;
pub mod flight;
pub mod observer;
mod recording;
mod stream;
pub mod summary;
mod truth;

pub use actuation::actuators;
pub use exit::{Divergence, ExitCategory, ExitCounts, ExitStatus};
pub use flight::{Flight, Flights, StepOutcome};
pub use observer::{FlightStats, Observer, Tick};
pub use recording::{push_number, recording_columns, Recording, RowStream, CSV_CHUNK_BYTES, MAX_RECORDING_COLUMNS};
use std::sync::atomic::{AtomicBool, Ordering};
pub use stream::{stream_csv, STREAM_CHUNK_ROWS};

/// Result of one flight.
#[derive(Clone, Debug)]
pub struct RunOutput {
    /// Controller name.
    pub controller: String,
    /// Scenario name.
    pub scenario: String,
    /// How the run ended.
    pub exit: ExitStatus,
    /// Metrics up to the end (or divergence).
    pub metrics: Metrics,
    /// Time series (empty when recording is off).
    pub recording: Recording,
    /// Control steps executed.
    pub steps: u64,
    /// The success envelope's verdict (`None`: the scenario has no `[envelope]`).
    pub envelope: Option<crate::envelope::Verdict>,
    /// The robustness margin to the envelope ([`crate::margin`]; `None`:
    /// a completed flight of a scenario whose envelope limits neither
    /// position nor tilt).
    pub margin: Option<crate::margin::Margin>,
    /// Tilt, saturation and rotor statistics ([`FlightStats`]).
    pub stats: FlightStats,
}

impl RunOutput {
    /// Completed and inside the scenario's envelope (just completed without one).
    pub fn success(&self) -> bool {
        self.envelope.as_ref().map_or(self.exit.is_completed(), |v| v.success)
    }
}

/// The reference of `scenario` at time `t`.
#[inline]
pub fn reference_at(scenario: &Scenario, t: f64) -> Reference {
    let r = &scenario.reference;
    match &r.trajectory {
        Some(trajectory) => reference_of_flat(&trajectory.sample(t)),
        None => reference_of([r.x.sample(t), r.y.sample(t), r.z.sample(t), r.psi.sample(t)]),
    }
}

/// The [`Reference`] of a trajectory's flat output (jerk and snap are not
/// part of a controller's reference).
#[inline]
pub(crate) fn reference_of_flat(f: &crate::trajectory::FlatOutput) -> Reference {
    Reference {
        position: f.pos,
        velocity: f.vel,
        acceleration: f.acc,
        yaw: f.yaw,
        yaw_rate: f.yaw_rate,
        yaw_acceleration: f.yaw_acc,
    }
}

/// The [`Reference`] of the samples of its x, y, z and ψ signals.
#[inline]
pub(crate) fn reference_of([x, y, z, psi]: [crate::signal::Sample; 4]) -> Reference {
    Reference {
        position: [x.value, y.value, z.value],
        velocity: [x.rate, y.rate, z.rate],
        acceleration: [x.acceleration, y.acceleration, z.acceleration],
        yaw: psi.value,
        yaw_rate: psi.rate,
        yaw_acceleration: psi.acceleration,
    }
}

/// Options of one run (construct with `RunOptions { record: false, ..Default::default() }`).
#[derive(Clone, Copy)]
pub struct RunOptions<'a> {
    /// Record the time series at `simulation.record_rate`.
    pub record: bool,
    /// Called with the number of control steps flown since the last call,
    /// every [`PROGRESS_EVERY`] steps and once at the end (the remainder of
    /// the planned steps, so a diverged run still adds its planned total).
    pub progress: Option<&'a (dyn Fn(u64) + Sync)>,
    /// Cancellation: when set to `true` (by another thread, e.g. on Ctrl-C),
    /// the run stops within [`PROGRESS_EVERY`] control steps with
    /// [`ExitStatus::Interrupted`].
    pub cancel: Option<&'a AtomicBool>,
    /// Hand the recording's rows to this stream while flying, to be
    /// written as CSV by another thread ([`stream_csv`]); for one flight
    /// (a flight of lanes, or a lane started afresh, does not use it).
    pub stream: Option<&'a RowStream>,
}

/// Control steps between two [`RunOptions::progress`] calls.
pub const PROGRESS_EVERY: u64 = 1000;

impl Default for RunOptions<'_> {
    fn default() -> Self {
        Self { record: true, progress: None, cancel: None, stream: None }
    }
}

impl RunOptions<'_> {
    /// After control step `executed` (1-based): report [`PROGRESS_EVERY`]
    /// steps when `executed` is a multiple of it, and then also check the
    /// cancellation flag. True when the run must stop (cancelled).
    pub(crate) fn step_done(&self, executed: u64) -> bool {
        if executed % PROGRESS_EVERY != 0 {
            return false;
        }
        if let Some(progress) = self.progress {
            progress(PROGRESS_EVERY);
        }
        self.cancelled()
    }

    /// True when [`RunOptions::cancel`] is set.
    pub fn cancelled(&self) -> bool {
        self.cancel.is_some_and(|c| c.load(Ordering::Relaxed))
    }

    /// At the end of a flight of `planned` steps that stopped after
    /// `executed`: report the rest of the planned total.
    pub(crate) fn flight_done(&self, planned: u64, executed: u64) {
        if let Some(progress) = self.progress {
            progress(planned - executed / PROGRESS_EVERY * PROGRESS_EVERY);
        }
    }
}

impl core::fmt::Debug for RunOptions<'_> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("RunOptions")
            .field("record", &self.record)
            .field("progress", &self.progress.is_some())
            .field("cancel", &self.cancel.is_some())
            .field("stream", &self.stream.is_some())
            .finish()
    }
}

/// Control steps a flight of `scenario` plans (its progress total).
pub fn planned_steps(scenario: &Scenario) -> u64 {
    (scenario.duration / scenario.control_period()).round() as u64
}

/// Tracking errors `[e_x, e_y, e_z, e_φ, e_θ, e_ψ]` the metrics integrate:
/// position against the reference, roll and pitch against the attitude
/// reference the controller tracks (`attitude_reference`: its telemetry's
/// `[φ_d, θ_d]`), yaw against ψ_d. `state` is `[x, y, z, φ, θ, ψ, …]`.
pub(crate) fn tracking_errors(state: &[f64; 12], reference: &Reference, attitude_reference: [f64; 2]) -> [f64; 6] {
    [
        state[0] - reference.position[0],
        state[1] - reference.position[1],
        state[2] - reference.position[2],
        state[3] - attitude_reference[0],
        state[4] - attitude_reference[1],
        state[5] - reference.yaw,
    ]
}

/// Fly `controller` through `scenario` ([`Flight`] stepped to the end).
pub fn simulate(scenario: &Scenario, controller: &mut dyn Controller, options: RunOptions<'_>) -> RunOutput {
    Flight::new(scenario.clone(), controller, options).run()
}
