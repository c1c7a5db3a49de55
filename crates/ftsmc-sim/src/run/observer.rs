//! Per-tick observers: whatever watches a flight (metrics, the recording,
//! the success envelope, tilt/saturation/rotor statistics) sees the whole
//! control tick through one [`Tick`] and implements [`Observer`].
//!
//! A new per-flight metric is one type implementing [`Observer`] (plus its
//! row in docs/outputs.md); the loop does not change.

use ftsmc_core::cascade::Telemetry;
use ftsmc_core::model::{Command, QuadState, Reference};

use crate::envelope::Tracker;
use crate::metrics::MetricsAccumulator;

/// Everything one control tick of a flight produced, as the loop hands it
/// to every [`Observer`] (before the truth is integrated over the period).
#[derive(Clone, Copy, Debug)]
pub struct Tick<'a> {
    /// Control step index `k` (0-based).
    pub k: u64,
    /// Time `t = k·dt`, s.
    pub t: f64,
    /// True state in Euler form `[x, y, z, φ, θ, ψ, ẋ, ẏ, ż, φ̇, θ̇, ψ̇]` (m, rad, m/s, rad/s).
    pub state: [f64; 12],
    /// What the controller was given (the sensors' output; the truth with perfect sensors).
    pub measured: &'a QuadState,
    /// Reference of this tick.
    pub reference: &'a Reference,
    /// The controller's telemetry after this tick's update (for an
    /// observer whose [`Observer::reads_telemetry`] is true at this tick;
    /// the others must not read it).
    pub telemetry: &'a Telemetry,
    /// Tracking errors `[e_x, e_y, e_z, e_φ, e_θ, e_ψ]` of the truth: the
    /// truth minus the reference, φ and θ against the controller's attitude
    /// reference (`telemetry`), ψ against the reference yaw.
    pub errors: [f64; 6],
    /// Commanded thrust (N) and torques (N·m).
    pub command: &'a Command,
    /// Applied thrust and torques `[U1, u2, u3, u4]` after the actuator stage (N, N·m).
    pub applied: [f64; 4],
    /// Rotor speeds at the tick, rad/s.
    pub omega: [f64; 4],
    /// Residual rotor speed Ω̄ = ω1 − ω2 + ω3 − ω4 of `omega`, rad/s.
    pub omega_bar: f64,
    /// Rotor speeds the command asks for with no limit (paper Eq. 2 inverted), rad/s.
    pub demand: [f64; 4],
    /// The actuator stage could not deliver the command this period.
    pub saturated: bool,
    /// Nominal mass (`plant.mass`), kg.
    pub nominal_mass: f64,
    /// True mass, kg.
    pub mass: f64,
    /// True principal inertia, kg·m².
    pub inertia: [f64; 3],
    /// Disturbances `[D_x … D_ψ]` of this tick (m/s², rad/s²).
    pub disturbance: [f64; 6],
    /// The sensor pipeline's recorded columns (its stages' last readings,
    /// the estimate and its covariance diagonal,
    /// [`crate::sensors::pipeline::Pipeline::column_names`]) at a recorded
    /// tick; empty without a pipeline.
    pub pipeline: &'a [f64],
}

/// Something that watches a flight.
pub trait Observer {
    /// A control tick that produced a finite applied command.
    fn tick(&mut self, tick: &Tick<'_>);
    /// The truth at a period boundary: `t = 0` and after every completed
    /// control period (the state the next tick starts from, or the final one).
    fn boundary(&mut self, t: f64, truth: &QuadState, reference: &Reference) {
        let _ = (t, truth, reference);
    }
    /// True when this observer reads [`Tick::telemetry`] at control step
    /// `k` (the default). A flight gathers a lane's telemetry from the
    /// controller's lanes only at the ticks some observer of it reads it;
    /// an observer that says false here must not read that field.
    fn reads_telemetry(&self, k: u64) -> bool {
        let _ = k;
        true
    }
}

impl Observer for MetricsAccumulator {
    #[inline]
    fn tick(&mut self, tick: &Tick<'_>) {
        self.observe(tick.t, &tick.errors, &tick.applied);
    }
    #[inline]
    fn reads_telemetry(&self, _: u64) -> bool {
        false
    }
}

impl Observer for Tracker {
    #[inline]
    fn tick(&mut self, _: &Tick<'_>) {}
    #[inline]
    fn boundary(&mut self, t: f64, truth: &QuadState, reference: &Reference) {
        self.observe(t, &truth.position, &reference.position, &truth.attitude);
    }
    #[inline]
    fn reads_telemetry(&self, _: u64) -> bool {
        false
    }
}

/// Tilt, saturation and rotor statistics of a flight, without recording.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct FlightStats {
    /// Largest tilt `max(|φ|, |θ|)` of the truth at the period boundaries, rad
    /// (a measurement; the limits on it are `simulation.max_tilt` and `envelope.max_tilt`).
    pub peak_tilt: f64,
    /// Control periods in which the actuator stage saturated.
    pub saturated_periods: u64,
    /// Control periods observed.
    pub periods: u64,
    /// Largest rotor speed the commands asked for with no limit, rad/s (non-finite demands skipped).
    pub peak_rotor_speed_demand: f64,
    /// Largest rotor speed flown at a tick, rad/s.
    pub rotor_speed_max: f64,
    /// Mean over ticks and rotors of the rotor speed flown, rad/s.
    pub rotor_speed_mean: f64,
    sum_speed: f64,
}

impl FlightStats {
    /// The two rotor metrics of [`crate::metrics::Metrics`] of a flight of
    /// `steps` delivered control periods: the peak unlimited rotor-speed
    /// demand (rad/s) and the saturation fraction, the saturated periods
    /// over `steps` (0 with none). `unobserved` is the saturation and
    /// demand of a last period that was delivered but not observed (the
    /// flight diverged at its tick), counted too.
    pub fn rotor_metrics(&self, steps: u64, unobserved: Option<(bool, [f64; 4])>) -> (f64, f64) {
        let (mut peak, mut saturated) = (self.peak_rotor_speed_demand, self.saturated_periods);
        if let Some((last_saturated, demand)) = unobserved {
            peak = demand.iter().fold(peak, |m, &w| if w.is_finite() { m.max(w) } else { m });
            saturated += u64::from(last_saturated);
        }
        (peak, if steps > 0 { saturated as f64 / steps as f64 } else { 0.0 })
    }
}

impl FlightStats {
    /// One observed control period ([`Observer::tick`] reads these fields
    /// of its [`Tick`]): the actuator stage saturated, the unlimited
    /// rotor-speed demand (rad/s; non-finite values skipped) and the rotor
    /// speeds flown (rad/s). The running mean is `Σω / (4 · periods)`.
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn observe_period(&mut self, saturated: bool, demand: &[f64; 4], omega: &[f64; 4]) {
        self.periods += 1;
        self.saturated_periods += u64::from(saturated);
        for &w in demand {
            if w.is_finite() {
                self.peak_rotor_speed_demand = self.peak_rotor_speed_demand.max(w);
            }
        }
        for &w in omega {
            self.rotor_speed_max = self.rotor_speed_max.max(w);
            self.sum_speed += w;
        }
        self.rotor_speed_mean = self.sum_speed / (4 * self.periods) as f64;
    }
}

impl Observer for FlightStats {
    #[inline]
    fn tick(&mut self, tick: &Tick<'_>) {
        self.observe_period(tick.saturated, &tick.demand, &tick.omega);
    }
    #[inline]
    fn boundary(&mut self, _: f64, truth: &QuadState, _: &Reference) {
        let tilt = truth.attitude[0].abs().max(truth.attitude[1].abs());
        if tilt > self.peak_tilt {
            self.peak_tilt = tilt;
        }
    }
    #[inline]
    fn reads_telemetry(&self, _: u64) -> bool {
        false
    }
}
