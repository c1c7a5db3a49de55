//! Statistics of a set of flights and the tuning cost built from them.

use serde::Serialize;

use crate::batch::montecarlo::stats;
use crate::run::RunOutput;
use crate::scenario::tune_section::TuneSection;

/// What the cost and the comparison table need from one flight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlightOutcome {
    /// Completed the scenario (no divergence, no crash).
    pub completed: bool,
    /// Hit the ground too fast (`[ground]`).
    pub crashed: bool,
    /// Completed and inside the `[envelope]` (without one: completed).
    pub success: bool,
    /// Simulated time flown, s (the divergence time of a diverged flight).
    pub time: f64,
    /// RMS position error `sqrt(rms_x² + rms_y² + rms_z²)`, m.
    pub rms: f64,
    /// Thrust activity: chattering index of U1, N/s.
    pub thrust_activity: f64,
    /// Torque activity: sum of the chattering indices of u2, u3, u4, N·m/s.
    pub torque_activity: f64,
    /// Fraction of control periods with a saturated mixer (0 without rotor limits).
    pub saturated: f64,
    /// The robustness margin to the `[envelope]` (`crate::margin`: a
    /// fraction of the binding limit, `< 0` outside; at most −1 for a
    /// crashed or diverged flight); `None` without one.
    pub margin: Option<f64>,
}

/// The margin the cost asks of every flight ([`OutcomeStats::margin_shortfall`]):
/// a quarter of the binding limit, e.g. a position error at most 0.375 m
/// against a 0.5 m `max_position_error`.
pub const MARGIN_TARGET: f64 = 0.25;

impl FlightOutcome {
    /// From a run's output.
    pub fn of(run: &RunOutput) -> Self {
        let m = &run.metrics;
        let c = &m.chattering;
        Self {
            completed: run.exit.is_completed(),
            crashed: run.exit.is_crashed(),
            success: run.success(),
            time: m.duration,
            rms: (m.rms.x * m.rms.x + m.rms.y * m.rms.y + m.rms.z * m.rms.z).sqrt(),
            thrust_activity: c.thrust,
            torque_activity: c.roll_torque + c.pitch_torque + c.yaw_torque,
            saturated: m.saturation_fraction.unwrap_or(0.0),
            margin: run.margin.as_ref().map(|m| m.value),
        }
    }
}

/// Statistics of a set of flights (one candidate's training runs, or a
/// held-out Monte Carlo). Error and activity statistics are over the
/// completed flights (`NaN` when none completed).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct OutcomeStats {
    /// Flights.
    pub runs: usize,
    /// Completed and inside the envelope.
    pub success: usize,
    /// Completed (no divergence, no crash).
    pub completed: usize,
    /// Crashed into the ground.
    pub crashed: usize,
    /// Diverged (tilt or position error beyond the scenario's limits).
    pub diverged: usize,
    /// Completed but outside the envelope.
    pub envelope_failures: usize,
    /// Median RMS position error, m.
    pub rms_median: f64,
    /// 90th percentile (nearest rank) of the RMS position error, m.
    pub rms_p90: f64,
    /// 95th percentile (nearest rank) of the RMS position error, m.
    pub rms_p95: f64,
    /// Median thrust activity, N/s.
    pub thrust_activity: f64,
    /// Median torque activity, N·m/s.
    pub torque_activity: f64,
    /// Median saturated fraction of the control periods.
    pub saturated: f64,
    /// Mean over all flights of `2 − t/T` for each diverged or crashed
    /// flight (0 for a completed one): the divergence term of the cost.
    pub divergence_score: f64,
    /// Mean over all flights of `min(max(0, MARGIN_TARGET − margin), 1 +
    /// MARGIN_TARGET)` ([`MARGIN_TARGET`], `crate::margin`; 0 for a flight
    /// without a margin): how far the flights fell short of a safe margin,
    /// a continuous signal of the envelope's failures and near-misses,
    /// seen on far fewer draws than the failures themselves.
    pub margin_shortfall: f64,
}

impl OutcomeStats {
    /// Number of values of [`OutcomeStats::to_values`].
    pub const VALUES: usize = 14;

    /// The statistics as numbers in field order (counts exact as `f64`):
    /// how a Dask task of `ftsmc.tune(..., client=...)` sends them back.
    pub fn to_values(&self) -> [f64; Self::VALUES] {
        [
            self.runs as f64,
            self.success as f64,
            self.completed as f64,
            self.crashed as f64,
            self.diverged as f64,
            self.envelope_failures as f64,
            self.rms_median,
            self.rms_p90,
            self.rms_p95,
            self.thrust_activity,
            self.torque_activity,
            self.saturated,
            self.divergence_score,
            self.margin_shortfall,
        ]
    }

    /// The inverse of [`OutcomeStats::to_values`]; `None` when `v` is not
    /// [`OutcomeStats::VALUES`] numbers with non-negative integer counts.
    pub fn from_values(v: &[f64]) -> Option<Self> {
        if v.len() != Self::VALUES {
            return None;
        }
        let count = |x: f64| (x >= 0.0 && x.fract() == 0.0 && x < 9.0e15).then_some(x as usize);
        Some(Self {
            runs: count(v[0])?,
            success: count(v[1])?,
            completed: count(v[2])?,
            crashed: count(v[3])?,
            diverged: count(v[4])?,
            envelope_failures: count(v[5])?,
            rms_median: v[6],
            rms_p90: v[7],
            rms_p95: v[8],
            thrust_activity: v[9],
            torque_activity: v[10],
            saturated: v[11],
            divergence_score: v[12],
            margin_shortfall: v[13],
        })
    }
}

/// Nearest-rank percentile `q` of the finite values (`NaN` if none).
fn percentile(values: &[f64], q: f64) -> f64 {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[((q * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1]
}

impl OutcomeStats {
    /// Statistics of `flights` of a scenario lasting `duration` s.
    pub fn of(flights: &[FlightOutcome], duration: f64) -> Self {
        let done: Vec<&FlightOutcome> = flights.iter().filter(|f| f.completed).collect();
        let median = |g: fn(&FlightOutcome) -> f64| {
            stats(&done.iter().map(|f| g(f)).collect::<Vec<_>>()).map_or(f64::NAN, |s| s.median)
        };
        let rms: Vec<f64> = done.iter().map(|f| f.rms).collect();
        let runs = flights.len();
        let crashed = flights.iter().filter(|f| f.crashed).count();
        let success = flights.iter().filter(|f| f.success).count();
        // Summed from +0.0 (`Iterator::sum` of floats starts at −0.0, which
        // an empty sum would keep and the CSV would print as `-0`).
        let score = flights
            .iter()
            .filter(|f| !f.completed)
            .map(|f| 2.0 - (f.time / duration).clamp(0.0, 1.0))
            .fold(0.0, |a, x| a + x);
        let shortfall = flights
            .iter()
            .filter_map(|f| f.margin)
            .map(|m| (MARGIN_TARGET - m).clamp(0.0, 1.0 + MARGIN_TARGET))
            .fold(0.0, |a, x| a + x);
        Self {
            runs,
            success,
            completed: done.len(),
            crashed,
            diverged: runs - done.len() - crashed,
            envelope_failures: done.len() - success.min(done.len()),
            rms_median: median(|f| f.rms),
            rms_p90: percentile(&rms, 0.9),
            rms_p95: percentile(&rms, 0.95),
            thrust_activity: median(|f| f.thrust_activity),
            torque_activity: median(|f| f.torque_activity),
            saturated: median(|f| f.saturated),
            divergence_score: if runs > 0 { score / runs as f64 } else { 0.0 },
            margin_shortfall: if runs > 0 { shortfall / runs as f64 } else { 0.0 },
        }
    }

    /// The tuning cost (lower is better), with the weights `w` of `[tune]`:
    ///
    /// `divergence × mean(2 − t/T over diverged or crashed runs, 0 otherwise)
    ///  + envelope × (envelope failures / runs) + margin × margin shortfall
    ///  + rms × p90(RMS position error) + thrust_activity × median(thrust activity)
    ///  + torque_activity × median(torque activity) + saturated × median(saturated fraction)`,
    ///
    /// the error and activity terms over the completed runs (0 when none
    /// completed: the divergence term then dominates anyway).
    pub fn cost(&self, w: &TuneSection) -> f64 {
        let or0 = |v: f64| if v.is_finite() { v } else { 0.0 };
        let runs = self.runs.max(1) as f64;
        w.divergence * self.divergence_score
            + w.envelope * self.envelope_failures as f64 / runs
            + w.margin * self.margin_shortfall
            + w.rms * or0(self.rms_p90)
            + w.thrust_activity * or0(self.thrust_activity)
            + w.torque_activity * or0(self.torque_activity)
            + w.saturated * or0(self.saturated)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn completed(margin: Option<f64>) -> FlightOutcome {
        FlightOutcome {
            completed: true,
            crashed: false,
            success: true,
            time: 20.0,
            rms: 0.3,
            thrust_activity: 40.0,
            torque_activity: 20.0,
            saturated: 0.0,
            margin,
        }
    }

    #[test]
    fn flights_that_neither_fail_nor_fall_short_score_plus_zero() {
        // No failed flight, no margin: both sums are empty.
        let s = OutcomeStats::of(&[completed(None), completed(None)], 20.0);
        assert_eq!(s.divergence_score.to_bits(), 0.0f64.to_bits(), "{}", s.divergence_score);
        assert_eq!(s.margin_shortfall.to_bits(), 0.0f64.to_bits(), "{}", s.margin_shortfall);
        // Margins at or above the target fall short by nothing.
        let s = OutcomeStats::of(&[completed(Some(0.5)), completed(Some(MARGIN_TARGET))], 20.0);
        assert_eq!(s.margin_shortfall.to_bits(), 0.0f64.to_bits());
        // And the terms still count what they should.
        let mut failed = completed(Some(-1.0));
        failed.completed = false;
        failed.success = false;
        failed.time = 5.0;
        let s = OutcomeStats::of(&[failed, completed(Some(0.0))], 20.0);
        assert_eq!(s.divergence_score, (2.0 - 0.25) / 2.0);
        assert_eq!(s.margin_shortfall, ((1.0 + MARGIN_TARGET) + MARGIN_TARGET) / 2.0);
    }
}
