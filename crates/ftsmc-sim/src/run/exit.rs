//! How a run ends: [`ExitStatus`], [`Divergence`] and the divergence checks.

use ftsmc_core::model::{QuadState, Reference};
use serde::{Deserialize, Serialize};

use crate::scenario::Scenario;

/// Why a run stopped early.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case", tag = "reason")]
pub enum Divergence {
    /// A state or command component became NaN or infinite.
    NonFinite,
    /// |φ| or |θ| exceeded `simulation.max_tilt`.
    Tilt {
        /// The angle reached, rad.
        angle: f64,
    },
    /// A position error exceeded `simulation.max_position_error`.
    PositionError {
        /// The error reached, m.
        error: f64,
    },
    /// The rigid body's mass or inertia (with the payload and the inertia
    /// variation of this instant) left its valid range
    /// ([`crate::vehicle::RigidBodyParams::check`]): the run stops rather
    /// than fly parameters it cannot represent.
    RigidBodyOutOfRange {
        /// True mass asked for, kg.
        mass: f64,
        /// Inertia scale asked for (1 + ΔI/I), dimensionless.
        inertia_scale: f64,
    },
    /// The flight reached its end with a finite state, but a metric (an
    /// error or control integral) overflowed to ±∞ or NaN: the flight is
    /// not reported completed ([`crate::metrics::Metrics::first_non_finite`]).
    NonFiniteMetric,
    /// The state estimator stopped giving a state (`[sensors] estimator`,
    /// [`crate::sensors::pipeline`]): its estimate or covariance became
    /// non-finite, a variance passed its bound, or its innovation gate
    /// rejected every aiding reading for longer than
    /// [`crate::sensors::pipeline::MAX_GATED_S`].
    Estimator {
        /// Why.
        cause: crate::sensors::estimator::FailureReason,
    },
}

/// How a run ended.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case", tag = "status")]
pub enum ExitStatus {
    /// Ran for the whole duration.
    Completed,
    /// Stopped at `time` (s) for `divergence`.
    Diverged {
        /// What went wrong.
        divergence: Divergence,
        /// Simulated time at which it was detected, s.
        time: f64,
    },
    /// Hit the ground (`[ground]`) faster than `max_touchdown_speed`.
    Crashed {
        /// Simulated time of the touchdown, s.
        time: f64,
        /// Downward speed at touchdown, m/s.
        impact_speed: f64,
    },
    /// Rested on the ground (`[ground]`) for longer than
    /// `max_ground_time` after take-off: landed where it should fly.
    Grounded {
        /// Simulated time at which the flight was stopped, s.
        time: f64,
        /// When the vehicle came to rest on the ground, s.
        since: f64,
    },
    /// Stopped at `time` (s) on request ([`crate::run::RunOptions::cancel`], e.g. Ctrl-C).
    Interrupted {
        /// Simulated time at which the run stopped, s.
        time: f64,
    },
}

/// The exit categories every table and count of ftsmc uses — `runs.csv`'s
/// `completed` and `crashed` columns, `ftsmc montecarlo`'s and `ftsmc
/// compare`'s counts and rates, the wind ladder's calibration table — one
/// per run, so the four counts of a batch add up to its runs
/// (docs/statistics.md, "Exit categories").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum ExitCategory {
    /// Flew the whole duration ([`ExitStatus::Completed`]).
    Completed,
    /// Stopped by a divergence check ([`ExitStatus::Diverged`]).
    Diverged,
    /// Ended on the ground: hit it too fast ([`ExitStatus::Crashed`]) or
    /// landed and stayed there ([`ExitStatus::Grounded`], "landed").
    Crashed,
    /// Stopped on request ([`ExitStatus::Interrupted`]).
    Interrupted,
}

impl ExitCategory {
    /// Every category, in table order.
    pub const ALL: [ExitCategory; 4] =
        [ExitCategory::Completed, ExitCategory::Diverged, ExitCategory::Crashed, ExitCategory::Interrupted];

    /// The word tables print: `completed`, `diverged`, `crashed`, `interrupted`.
    pub fn word(self) -> &'static str {
        match self {
            ExitCategory::Completed => "completed",
            ExitCategory::Diverged => "diverged",
            ExitCategory::Crashed => "crashed",
            ExitCategory::Interrupted => "interrupted",
        }
    }
}

/// How many runs of a batch ended in each [`ExitCategory`], and how many
/// of the crashed ones landed ([`ExitStatus::Grounded`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ExitCounts {
    /// Runs that completed.
    pub completed: usize,
    /// Runs that diverged.
    pub diverged: usize,
    /// Runs that ended on the ground, landings included.
    pub crashed: usize,
    /// Of `crashed`, the runs that landed and stayed on the ground.
    pub landed: usize,
    /// Runs stopped on request.
    pub interrupted: usize,
}

impl ExitCounts {
    /// Count one run's exit.
    pub fn add(&mut self, exit: &ExitStatus) {
        match exit.category() {
            ExitCategory::Completed => self.completed += 1,
            ExitCategory::Diverged => self.diverged += 1,
            ExitCategory::Crashed => self.crashed += 1,
            ExitCategory::Interrupted => self.interrupted += 1,
        }
        self.landed += usize::from(matches!(exit, ExitStatus::Grounded { .. }));
    }

    /// The counts of `exits`.
    pub fn of<'a>(exits: impl IntoIterator<Item = &'a ExitStatus>) -> Self {
        let mut counts = Self::default();
        for e in exits {
            counts.add(e);
        }
        counts
    }

    /// Runs counted: the four categories add up to it.
    pub fn runs(&self) -> usize {
        self.completed + self.diverged + self.crashed + self.interrupted
    }
}

impl ExitStatus {
    /// The run's [`ExitCategory`].
    pub fn category(&self) -> ExitCategory {
        match self {
            ExitStatus::Completed => ExitCategory::Completed,
            ExitStatus::Diverged { .. } => ExitCategory::Diverged,
            ExitStatus::Crashed { .. } | ExitStatus::Grounded { .. } => ExitCategory::Crashed,
            ExitStatus::Interrupted { .. } => ExitCategory::Interrupted,
        }
    }

    /// True for [`ExitStatus::Completed`].
    pub fn is_completed(&self) -> bool {
        matches!(self, ExitStatus::Completed)
    }

    /// Simulated time at which the run diverged (`None` if it completed).
    pub fn diverged_at(&self) -> Option<f64> {
        match self {
            ExitStatus::Diverged { time, .. } => Some(*time),
            ExitStatus::Completed
            | ExitStatus::Crashed { .. }
            | ExitStatus::Grounded { .. }
            | ExitStatus::Interrupted { .. } => None,
        }
    }

    /// True for a flight that ended on the ground: [`ExitStatus::Crashed`]
    /// (too fast) and [`ExitStatus::Grounded`] (stayed there); the
    /// `crashed` column of `runs.csv`.
    pub fn is_crashed(&self) -> bool {
        self.category() == ExitCategory::Crashed
    }

    /// Short form for table cells: `completed`, `diverged at 0.64 s` or `crashed at 1.23 s`.
    pub fn short(&self) -> String {
        match self {
            ExitStatus::Completed => "completed".into(),
            ExitStatus::Diverged { time, .. } => format!("diverged at {time:.2} s"),
            ExitStatus::Crashed { time, .. } => format!("crashed at {time:.2} s"),
            ExitStatus::Grounded { since, .. } => format!("landed at {since:.2} s"),
            ExitStatus::Interrupted { time } => format!("interrupted at {time:.2} s"),
        }
    }
}

impl core::fmt::Display for ExitStatus {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ExitStatus::Completed => write!(f, "completed"),
            ExitStatus::Diverged { divergence, time } => match divergence {
                Divergence::NonFinite => write!(f, "diverged: non-finite state at t = {time:.3} s"),
                Divergence::Tilt { angle } => write!(f, "diverged: tilt {angle:.3} rad at t = {time:.3} s"),
                Divergence::PositionError { error } => {
                    write!(f, "diverged: position error {error:.3} m at t = {time:.3} s")
                }
                Divergence::NonFiniteMetric => {
                    write!(f, "diverged: a metric (error or control integral) overflowed by t = {time:.3} s")
                }
                Divergence::Estimator { cause } => {
                    write!(f, "diverged: estimator lost ({}) at t = {time:.3} s", cause.word())
                }
                Divergence::RigidBodyOutOfRange { mass, inertia_scale } => write!(
                    f,
                    "stopped: rigid body out of its valid range (mass {mass} kg, inertia x {inertia_scale}) at t = {time:.3} s"
                ),
            },
            ExitStatus::Crashed { time, impact_speed } => {
                write!(f, "crashed: hit the ground at {impact_speed:.1} m/s at t = {time:.3} s")
            }
            ExitStatus::Grounded { time, since } => write!(
                f,
                "landed: on the ground since t = {since:.3} s after take-off, stopped at t = {time:.3} s ([ground] \
                 max_ground_time)"
            ),
            ExitStatus::Interrupted { time } => write!(f, "interrupted at t = {time:.3} s"),
        }
    }
}

/// Why the truth `state` at a period boundary ends the flight of
/// `scenario`, if it does: a non-finite component first, then
/// `|φ|` or `|θ|` above `simulation.max_tilt` (φ first), then a position
/// error `|x_i − x_d,i|` above `simulation.max_position_error` (x, y, z).
#[cfg_attr(not(debug_assertions), inline(always))]
pub(super) fn check_divergence(scenario: &Scenario, state: &QuadState, reference: &Reference) -> Option<Divergence> {
    // Every component tested (no early exit): one verdict for the twelve.
    let mut finite = true;
    for part in [&state.position, &state.attitude, &state.velocity, &state.angular_rate] {
        for v in part {
            finite &= v.is_finite();
        }
    }
    if !finite {
        return Some(Divergence::NonFinite);
    }
    let sim = &scenario.simulation;
    for &angle in &state.attitude[..2] {
        if angle.abs() > sim.max_tilt {
            return Some(Divergence::Tilt { angle });
        }
    }
    for i in 0..3 {
        let error = (state.position[i] - reference.position[i]).abs();
        if error > sim.max_position_error {
            return Some(Divergence::PositionError { error });
        }
    }
    None
}

impl ExitStatus {
    /// How the flight ended, for its robustness margin ([`crate::margin`]):
    /// a stopped flight counts as completed over what it flew.
    pub fn margin_end(&self) -> crate::margin::End {
        use crate::margin::End;
        match *self {
            ExitStatus::Completed | ExitStatus::Interrupted { .. } => End::Completed,
            // Grounded counts as crashed, as in runs.csv's `crashed` column.
            ExitStatus::Crashed { time, .. } | ExitStatus::Grounded { time, .. } => End::Crashed(time),
            ExitStatus::Diverged { time, .. } => End::Diverged(time),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every exit falls in one category; a landing counts as crashed (as in
    /// `runs.csv`'s `crashed` column) and is counted among the landed too.
    #[test]
    fn every_exit_is_counted_once_and_landings_are_crashes() {
        let exits = [
            ExitStatus::Completed,
            ExitStatus::Diverged { divergence: Divergence::Tilt { angle: 1.0 }, time: 1.0 },
            ExitStatus::Crashed { time: 2.0, impact_speed: 3.0 },
            ExitStatus::Grounded { time: 5.0, since: 4.0 },
            ExitStatus::Interrupted { time: 1.0 },
        ];
        let counts = ExitCounts::of(&exits);
        assert_eq!(counts, ExitCounts { completed: 1, diverged: 1, crashed: 2, landed: 1, interrupted: 1 });
        assert_eq!(counts.runs(), exits.len());
        for e in &exits {
            assert_eq!(e.is_crashed(), e.category() == ExitCategory::Crashed);
            assert_eq!(e.is_completed(), e.category() == ExitCategory::Completed);
        }
        assert_eq!(ExitCategory::ALL.map(ExitCategory::word), ["completed", "diverged", "crashed", "interrupted"]);
    }
}
