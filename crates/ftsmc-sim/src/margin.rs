//! The robustness margin of a flight: how far it stayed inside its
//! scenario's `[envelope]`, signed, as the robustness of a signal temporal
//! logic (STL) formula (Donzé & Maler 2010, "Robust satisfaction of
//! temporal logic over real-valued signals", FORMATS).
//!
//! The envelope ([`crate::envelope`]) is the STL formula
//!
//! ```text
//! □_[settle_after, T] (‖p − p_d‖ ≤ E)   ∧   □_[0, T] (max(|φ|, |θ|) ≤ Θ)
//! ```
//!
//! whose robustness is the minimum over time of each inequality's slack,
//! and over the conjunction the minimum of the two. Metres and radians do
//! not compare, so each slack is divided by its limit before the minimum:
//!
//! ```text
//! ρ_p = min_t (E − ‖p(t) − p_d(t)‖)          m   (t ≥ settle_after)
//! ρ_θ = min_t (Θ − max(|φ(t)|, |θ(t)|))     rad  (every t)
//! margin = min(ρ_p / E, ρ_θ / Θ)              1   (a fraction of the limit)
//! ```
//!
//! over the truth at the control-period boundaries, the samples the
//! envelope's verdict reads. `margin < 0` exactly when a limit was broken
//! (`E − e < 0 ⇔ e > E` in floating point, and dividing by a positive limit
//! keeps the sign), so for a completed flight `margin < 0 ⇔ success = false`.
//!
//! A flight that **crashed** or **diverged** at `t_end` of a planned `T` has
//! failed whatever its slack; its margin is
//!
//! ```text
//! margin = min(ρ, 0) − 1 − (T − t_end)/T      ∈ (−∞, −1]
//! ```
//!
//! (`ρ` the envelope margin up to `t_end`, 0 without an envelope): at most
//! −1, below the envelope margin it had reached, and lower the earlier it
//! ended, so a search that minimises the margin is still led towards
//! earlier failures. (A completed flight far outside the envelope can have
//! a margin below −1 too: an error of 10 m against a 0.5 m limit is −19.)
//!
//! The ground clearance `min_t (z − h_ground)` (m) is reported beside the
//! margin when the scenario has a `[ground]`; it is not part of the
//! margin, since touching the ground is a failure only when the ground
//! model calls it a crash (faster than `max_touchdown_speed`), and that is
//! the crash branch above.

use crate::envelope::Envelope;
use serde::Serialize;

/// Which constraint sets the margin.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Binding {
    /// The position error `‖p − p_d‖` against `max_position_error`.
    Position,
    /// The tilt `max(|φ|, |θ|)` against `max_tilt`.
    Tilt,
    /// The flight crashed into the ground.
    Crashed,
    /// The flight diverged.
    Diverged,
}

impl Binding {
    /// The name written in `runs.csv` and summary.json.
    pub fn as_str(self) -> &'static str {
        match self {
            Binding::Position => "position",
            Binding::Tilt => "tilt",
            Binding::Crashed => "crashed",
            Binding::Diverged => "diverged",
        }
    }
}

/// How a flight ended, as far as the margin cares.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum End {
    /// Flew the whole scenario (or was stopped on request).
    Completed,
    /// Crashed into the ground at `t` (s).
    Crashed(f64),
    /// Diverged at `t` (s).
    Diverged(f64),
}

/// The robustness margin of one flight (module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Margin {
    /// The margin, 1 (a fraction of the binding limit; `< 0`: failed).
    pub value: f64,
    /// `ρ_p`, m: the smallest slack `max_position_error − ‖p − p_d‖` after
    /// `settle_after` (`None`: no position limit, or the flight ended before `settle_after`).
    pub position: Option<f64>,
    /// `ρ_θ`, rad: the smallest slack `max_tilt − max(|φ|, |θ|)` (`None`: no tilt limit).
    pub tilt: Option<f64>,
    /// Smallest height above the ground plane, m (`None`: no `[ground]`).
    pub ground_clearance: Option<f64>,
    /// Which constraint sets [`Margin::value`].
    pub binds: Binding,
    /// When: the time of the binding constraint's smallest slack, or of the crash or divergence, s.
    pub at: f64,
}

/// Collects a flight's margin, one period boundary at a time.
#[derive(Clone, Copy, Debug)]
pub struct MarginTracker {
    envelope: Option<Envelope>,
    ground_height: Option<f64>,
    /// Largest position error after `settle_after` and its time (`None`: none seen yet).
    worst_position: Option<(f64, f64)>,
    /// Largest tilt and its time.
    worst_tilt: Option<(f64, f64)>,
    clearance: Option<f64>,
}

impl MarginTracker {
    /// A tracker for `envelope` (`None`: no envelope) over a ground plane at
    /// `ground_height` (m; `None`: no ground).
    pub fn new(envelope: Option<Envelope>, ground_height: Option<f64>) -> Self {
        Self { envelope, ground_height, worst_position: None, worst_tilt: None, clearance: None }
    }

    /// The truth at a period boundary `t` (s): position and its reference
    /// (m), roll and pitch (rad). The error is formed exactly as the
    /// envelope forms it, so the two agree to the bit.
    #[inline]
    pub fn update(&mut self, t: f64, position: &[f64], reference: &[f64; 3], roll_pitch: &[f64]) {
        if let Some(h) = self.ground_height {
            let c = position[2] - h;
            self.clearance = Some(self.clearance.map_or(c, |m: f64| m.min(c)));
        }
        let Some(env) = &self.envelope else { return };
        let tilt = roll_pitch[0].abs().max(roll_pitch[1].abs());
        if self.worst_tilt.is_none_or(|(w, _)| tilt > w) {
            self.worst_tilt = Some((tilt, t));
        }
        if t >= env.settle_after {
            let e = (0..3).map(|i| (position[i] - reference[i]).powi(2)).sum::<f64>().sqrt();
            if self.worst_position.is_none_or(|(w, _)| e > w) {
                self.worst_position = Some((e, t));
            }
        }
    }

    /// The margin of the flight that ended as `end` after a planned
    /// `duration` (s). `None` for a completed flight without a position or
    /// tilt limit (nothing to be robust against).
    pub fn finish(&self, end: End, duration: f64) -> Option<Margin> {
        let env = self.envelope.unwrap_or_default();
        // NaN worst values (a state gone non-finite) count as no slack at all.
        let slack = |limit: Option<f64>, worst: Option<(f64, f64)>| match (limit, worst) {
            (Some(l), Some((w, t))) => Some((if w.is_nan() { -l } else { l - w }, l, t)),
            _ => None,
        };
        let position = slack(env.max_position_error, self.worst_position);
        let tilt = slack(env.max_tilt, self.worst_tilt);
        let mut envelope: Option<(f64, Binding, f64)> = None;
        for (s, b) in [(position, Binding::Position), (tilt, Binding::Tilt)] {
            if let Some((rho, limit, t)) = s {
                let v = rho / limit;
                if envelope.is_none_or(|(m, _, _)| v < m) {
                    envelope = Some((v, b, t));
                }
            }
        }
        let failed = |binds: Binding, t: f64| {
            let rest = if duration > 0.0 { ((duration - t) / duration).clamp(0.0, 1.0) } else { 0.0 };
            let rho = envelope.map_or(0.0, |(m, _, _)| m.min(0.0));
            (rho - 1.0 - rest, binds, t)
        };
        let (value, binds, at) = match end {
            End::Completed => envelope?,
            End::Crashed(t) => failed(Binding::Crashed, t),
            End::Diverged(t) => failed(Binding::Diverged, t),
        };
        Some(Margin {
            value,
            position: position.map(|p| p.0),
            tilt: tilt.map(|p| p.0),
            ground_clearance: self.clearance,
            binds,
            at,
        })
    }
}
