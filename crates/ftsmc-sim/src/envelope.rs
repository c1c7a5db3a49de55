//! The success envelope of a scenario (`[envelope]`): what "flying well"
//! means beyond "the run did not diverge".
//!
//! A run succeeds when it completed (no divergence, no crash) and, when the
//! scenario has an `[envelope]`:
//!
//! - its tilt `max(|φ|, |θ|)` stayed within `max_tilt` (rad) over the whole run;
//! - its position error `‖p − p_d‖` (m, Euclidean) stayed within
//!   `max_position_error` from `settle_after` (s) on.
//!
//! Without an `[envelope]` success means "completed", as before. The
//! envelope is evaluated at every control tick (after the plant step), on
//! the true state.

use ftsmc_core::law::GainError;
use serde::{Deserialize, Serialize};

/// `[envelope]`: every key optional; an absent limit is not checked.
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Envelope {
    /// Time from which the position error is checked, s (default 0).
    #[serde(default)]
    pub settle_after: f64,
    /// Largest allowed `‖p − p_d‖` after `settle_after`, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_position_error: Option<f64>,
    /// Largest allowed `max(|φ|, |θ|)` over the whole run, rad.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_tilt: Option<f64>,
}

impl Envelope {
    /// Reject negative or non-finite limits.
    pub fn check(&self) -> Result<(), GainError> {
        if !(self.settle_after.is_finite() && self.settle_after >= 0.0) {
            return Err(GainError {
                field: "settle_after",
                value: self.settle_after,
                expected: "a finite time >= 0 s",
            });
        }
        if let Some(e) = self.max_position_error {
            if !(e.is_finite() && e > 0.0) {
                return Err(GainError { field: "max_position_error", value: e, expected: "a finite distance > 0 m" });
            }
        }
        if let Some(a) = self.max_tilt {
            if !(a.is_finite() && a > 0.0) {
                return Err(GainError { field: "max_tilt", value: a, expected: "a finite angle > 0 rad" });
            }
        }
        Ok(())
    }
}

/// Whether a run met its scenario's envelope.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Verdict {
    /// Completed and inside the envelope.
    pub success: bool,
    /// Why not (`None` on success): the exit status, or the first envelope
    /// limit broken with its worst value and time.
    pub violation: Option<String>,
}

/// Worst values seen during a run, checked against an [`Envelope`].
#[derive(Clone, Copy, Debug)]
pub struct Tracker {
    envelope: Option<Envelope>,
    worst_tilt: (f64, f64),
    worst_position: (f64, f64),
}

impl Tracker {
    /// A tracker for `envelope` (`None`: nothing tracked, no verdict).
    pub fn new(envelope: Option<Envelope>) -> Self {
        Self { envelope, worst_tilt: (0.0, 0.0), worst_position: (0.0, 0.0) }
    }

    /// Observe the true position, its reference and the roll/pitch angles at `t`.
    #[inline]
    pub fn observe(&mut self, t: f64, position: &[f64], reference: &[f64; 3], roll_pitch: &[f64]) {
        let Some(env) = &self.envelope else { return };
        let tilt = roll_pitch[0].abs().max(roll_pitch[1].abs());
        if tilt > self.worst_tilt.0 {
            self.worst_tilt = (tilt, t);
        }
        if t >= env.settle_after {
            let e = (0..3).map(|i| (position[i] - reference[i]).powi(2)).sum::<f64>().sqrt();
            if e > self.worst_position.0 {
                self.worst_position = (e, t);
            }
        }
    }

    /// The verdict for a run (`None` without an envelope); `incomplete` is
    /// the exit status in words when the run did not complete (diverged or
    /// crashed), which fails the envelope by itself.
    pub fn verdict(&self, incomplete: Option<String>) -> Option<Verdict> {
        let env = self.envelope?;
        let fail = |why: String| Some(Verdict { success: false, violation: Some(why) });
        if let Some(why) = incomplete {
            return fail(why);
        }
        if let Some(limit) = env.max_tilt {
            if self.worst_tilt.0 > limit {
                let (a, t) = self.worst_tilt;
                return fail(format!("tilt {a:.3} rad > max_tilt {limit} rad at t = {t:.3} s"));
            }
        }
        if let Some(limit) = env.max_position_error {
            if self.worst_position.0 > limit {
                let (e, t) = self.worst_position;
                return fail(format!("position error {e:.3} m > max_position_error {limit} m at t = {t:.3} s"));
            }
        }
        Some(Verdict { success: true, violation: None })
    }
}
