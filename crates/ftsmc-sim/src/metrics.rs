//! Performance metrics (docs/outputs.md), accumulated online at the control rate:
//! ISE, IAE, ITAE, RMS, maximum error after the transient, 2 % settling time
//! per channel; control energy and chattering index per control signal.
//!
//! Integrals use the left rectangle rule on the control-rate samples (the
//! command is a zero-order hold, so this is exact for it; for the errors the
//! difference to the trapezoid rule is O(dt)).

use serde::{Deserialize, Serialize};

use crate::axes::AxisSet;

/// One value per control signal `U1, u2, u3, u4`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize, Serialize)]
pub struct SignalSet<T> {
    /// Total thrust U1.
    pub thrust: T,
    /// Roll torque u2.
    pub roll_torque: T,
    /// Pitch torque u3.
    pub pitch_torque: T,
    /// Yaw torque u4.
    pub yaw_torque: T,
}

impl<T: Copy> SignalSet<T> {
    /// From `[U1, u2, u3, u4]`.
    pub fn from_array(a: [T; 4]) -> Self {
        Self { thrust: a[0], roll_torque: a[1], pitch_torque: a[2], yaw_torque: a[3] }
    }
    /// As `[U1, u2, u3, u4]`.
    pub fn to_array(&self) -> [T; 4] {
        [self.thrust, self.roll_torque, self.pitch_torque, self.yaw_torque]
    }
    /// Names as used in outputs.
    pub const NAMES: [&'static str; 4] = ["thrust", "roll_torque", "pitch_torque", "yaw_torque"];
}

/// All metrics of one run. Channel errors are `x − x_d`, …, `φ − φ_ref`,
/// `θ − θ_ref` (the cascade's attitude reference), `ψ − ψ_d`.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
pub struct Metrics {
    /// ∫ e² dt (Table 3), units² · s.
    pub ise: AxisSet<f64>,
    /// ∫ |e| dt, units · s.
    pub iae: AxisSet<f64>,
    /// ∫ t |e| dt, units · s².
    pub itae: AxisSet<f64>,
    /// sqrt(ISE / duration), units.
    pub rms: AxisSet<f64>,
    /// max |e| for t ≥ `simulation.steady_state_after`, units; `None`
    /// (JSON `null`) when the run ended before `steady_state_after`.
    pub max_error_after: AxisSet<Option<f64>>,
    /// Time after which |e| stays within the band (2 % of |e(0)|, at least
    /// `settling_floor`), s; `None` if still outside at the end.
    pub settling_time: AxisSet<Option<f64>>,
    /// ∫ u² dt per control signal (N²·s, (N·m)²·s).
    pub control_energy: SignalSet<f64>,
    /// Chattering index: total variation Σ|u_k − u_{k−1}| per second of run
    /// (N/s, N·m/s).
    pub chattering: SignalSet<f64>,
    /// ∫ e² dt restricted to `simulation.metrics_window` (when set).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ise_window: Option<AxisSet<f64>>,
    /// Simulated time covered, s: every integral above is over
    /// `[0, duration]`, which is shorter than the scenario for a run that
    /// diverged.
    pub duration: f64,
    /// Flights with any model beyond the paper's (rigid body, `[actuators]`,
    /// ground, sensors, wind) only: the largest rotor speed the
    /// controller's commands asked for, without limits, rad/s.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub peak_rotor_speed_demand: Option<f64>,
    /// Realistic flights only: fraction of control periods in which the mixer saturated.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub saturation_fraction: Option<f64>,
}

impl Metrics {
    /// The first metric that is not finite (`"ise_z"`, `"chattering_thrust"`,
    /// …), if any: a completed flight never reports one — its exit becomes
    /// [`crate::run::Divergence::NonFiniteMetric`] instead.
    pub fn first_non_finite(&self) -> Option<String> {
        let axes = [("ise", &self.ise), ("iae", &self.iae), ("itae", &self.itae), ("rms", &self.rms)];
        for (metric, set) in axes.into_iter().chain(self.ise_window.as_ref().map(|w| ("ise_window", w))) {
            if let Some((axis, _)) = set.named().into_iter().find(|(_, v)| !v.is_finite()) {
                return Some(format!("{metric}_{axis}"));
            }
        }
        for (axis, v) in self.max_error_after.named() {
            if v.is_some_and(|v| !v.is_finite()) {
                return Some(format!("max_error_after_{axis}"));
            }
        }
        for (metric, set) in [("control_energy", &self.control_energy), ("chattering", &self.chattering)] {
            if let Some((k, _)) = set.to_array().into_iter().enumerate().find(|(_, v)| !v.is_finite()) {
                return Some(format!("{metric}_{}", SignalSet::<f64>::NAMES[k]));
            }
        }
        None
    }

    /// The time span `[0, t_end]` (s) the integral metrics cover.
    pub fn covered(&self) -> [f64; 2] {
        [0.0, self.duration]
    }

    /// Every metric as a named scalar (`ise_x`, …, `max_error_after_psi`
    /// (NaN when the run ended before `steady_state_after`),
    /// `settling_time_psi` (NaN when not settled), `control_energy_thrust`,
    /// …), in a fixed order: the columns of Monte Carlo tables.
    pub fn flat(&self) -> Vec<(String, f64)> {
        let mut out = Vec::with_capacity(64);
        let names = ["x", "y", "z", "phi", "theta", "psi"];
        let mut axes = |prefix: &str, a: &AxisSet<f64>| {
            for (n, v) in names.iter().zip(a.to_array()) {
                out.push((format!("{prefix}_{n}"), v));
            }
        };
        axes("ise", &self.ise);
        axes("iae", &self.iae);
        axes("itae", &self.itae);
        axes("rms", &self.rms);
        let after = self.max_error_after.to_array().map(|v| v.unwrap_or(f64::NAN));
        for (n, v) in names.iter().zip(after) {
            out.push((format!("max_error_after_{n}"), v));
        }
        let settling = self.settling_time.to_array().map(|v| v.unwrap_or(f64::NAN));
        for (n, v) in names.iter().zip(settling) {
            out.push((format!("settling_time_{n}"), v));
        }
        if let Some(w) = &self.ise_window {
            for (n, v) in names.iter().zip(w.to_array()) {
                out.push((format!("ise_window_{n}"), v));
            }
        }
        for (n, v) in SignalSet::<f64>::NAMES.iter().zip(self.control_energy.to_array()) {
            out.push((format!("control_energy_{n}"), v));
        }
        for (n, v) in SignalSet::<f64>::NAMES.iter().zip(self.chattering.to_array()) {
            out.push((format!("chattering_{n}"), v));
        }
        // Realistic flights only.
        if let Some(v) = self.peak_rotor_speed_demand {
            out.push(("peak_rotor_speed_demand".into(), v));
        }
        if let Some(v) = self.saturation_fraction {
            out.push(("saturation_fraction".into(), v));
        }
        out.push(("duration".into(), self.duration));
        out
    }
}

/// Online accumulator of [`Metrics`].
#[derive(Clone, Debug)]
pub struct MetricsAccumulator {
    dt: f64,
    band_fraction: f64,
    band_floor: f64,
    steady_after: f64,
    window: Option<[f64; 2]>,
    /// The sums below are of the samples alone (`Σ e²`, `Σ |e|`, `Σ t |e|`,
    /// `Σ u²`); [`MetricsAccumulator::finish`] multiplies them by `dt` once.
    ise_window: [f64; 6],
    started: bool,
    band: [f64; 6],
    ise: [f64; 6],
    iae: [f64; 6],
    itae: [f64; 6],
    max_after: [f64; 6],
    /// A sample at or after `steady_after` was observed.
    reached_after: bool,
    /// The last sample time with `|e| >` the band, s (meaningful where
    /// [`MetricsAccumulator::outside`] is set).
    last_outside: [f64; 6],
    /// Some sample had `|e|` above the band.
    outside: [bool; 6],
    energy: [f64; 4],
    variation: [f64; 4],
    last_u: [f64; 4],
    time: f64,
}

impl MetricsAccumulator {
    /// New accumulator for samples every `dt` s.
    pub fn new(dt: f64, band_fraction: f64, band_floor: f64, steady_after: f64) -> Self {
        Self {
            dt,
            band_fraction,
            band_floor,
            steady_after,
            window: None,
            ise_window: [0.0; 6],
            started: false,
            band: [0.0; 6],
            ise: [0.0; 6],
            iae: [0.0; 6],
            itae: [0.0; 6],
            max_after: [0.0; 6],
            reached_after: false,
            last_outside: [0.0; 6],
            outside: [false; 6],
            energy: [0.0; 4],
            variation: [0.0; 4],
            last_u: [0.0; 4],
            time: 0.0,
        }
    }

    /// Also accumulate ISE over `[start, end]` (s).
    pub fn with_window(mut self, window: Option<[f64; 2]>) -> Self {
        self.window = window;
        self
    }

    /// Add the sample at time `t` (s): channel errors and the command
    /// `[U1, u2, u3, u4]` held over the following period.
    ///
    /// Each sum takes the sample in time order (`Σ ← Σ + e²`, …); the
    /// maximum and the last time outside the band are selections,
    /// branch-free per channel.
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn observe(&mut self, t: f64, errors: &[f64; 6], u: &[f64; 4]) {
        if !self.started {
            self.start(errors, u);
        }
        let after = t >= self.steady_after;
        self.reached_after |= after;
        // One statement per loop, channel by channel: the loops compile to
        // vector instructions (each channel's operations unchanged).
        let a: [f64; 6] = core::array::from_fn(|i| errors[i].abs());
        for i in 0..6 {
            self.ise[i] += errors[i] * errors[i];
        }
        for i in 0..6 {
            self.iae[i] += a[i];
        }
        for i in 0..6 {
            self.itae[i] += t * a[i];
        }
        if after {
            for i in 0..6 {
                self.max_after[i] = if a[i] > self.max_after[i] { a[i] } else { self.max_after[i] };
            }
        }
        for i in 0..6 {
            let outside = a[i] > self.band[i];
            self.last_outside[i] = if outside { t } else { self.last_outside[i] };
            self.outside[i] |= outside;
        }
        if let Some([start, end]) = self.window {
            if t >= start && t <= end {
                for i in 0..6 {
                    self.ise_window[i] += errors[i] * errors[i];
                }
            }
        }
        for j in 0..4 {
            self.energy[j] += u[j] * u[j];
        }
        for j in 0..4 {
            self.variation[j] += (u[j] - self.last_u[j]).abs();
        }
        self.last_u = *u;
        self.time = t + self.dt;
    }

    /// The settling bands `max(band_fraction · |e(0)|, band_floor)` from
    /// the first sample, which also starts the command's variation.
    #[cold]
    fn start(&mut self, errors: &[f64; 6], u: &[f64; 4]) {
        for i in 0..6 {
            self.band[i] = (self.band_fraction * errors[i].abs()).max(self.band_floor);
        }
        self.last_u = *u;
        self.started = true;
    }

    /// Final metrics over the observed time.
    pub fn finish(&self) -> Metrics {
        let duration = self.time;
        let axes = |a: [f64; 6]| AxisSet { x: a[0], y: a[1], z: a[2], phi: a[3], theta: a[4], psi: a[5] };
        let settled: [Option<f64>; 6] =
            core::array::from_fn(|i| match self.outside[i].then_some(self.last_outside[i]) {
                None => Some(0.0),
                Some(t) if t + self.dt < duration - 0.5 * self.dt => Some(t + self.dt),
                Some(_) => None,
            });
        let dt = self.dt;
        let ise = self.ise.map(|v| v * dt);
        let rms = ise.map(|v| if duration > 0.0 { (v / duration).sqrt() } else { 0.0 });
        let per_second = self.variation.map(|v| if duration > 0.0 { v / duration } else { 0.0 });
        Metrics {
            ise: axes(ise),
            iae: axes(self.iae.map(|v| v * dt)),
            itae: axes(self.itae.map(|v| v * dt)),
            rms: axes(rms),
            max_error_after: {
                let after = self.max_after.map(|v| self.reached_after.then_some(v));
                AxisSet { x: after[0], y: after[1], z: after[2], phi: after[3], theta: after[4], psi: after[5] }
            },
            settling_time: AxisSet {
                x: settled[0],
                y: settled[1],
                z: settled[2],
                phi: settled[3],
                theta: settled[4],
                psi: settled[5],
            },
            control_energy: SignalSet::from_array(self.energy.map(|v| v * dt)),
            chattering: SignalSet::from_array(per_second),
            ise_window: self.window.map(|_| axes(self.ise_window.map(|v| v * dt))),
            duration,
            peak_rotor_speed_demand: None,
            saturation_fraction: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn exponential_decay_metrics_match_closed_forms() {
        // e(t) = e^{−t} on every axis for 20 s at 1 kHz.
        let dt = 1e-3;
        let mut acc = MetricsAccumulator::new(dt, 0.02, 1e-3, 5.0);
        let n = 20_000;
        for k in 0..n {
            let t = k as f64 * dt;
            let e = ftsmc_core::math::exp(-t);
            acc.observe(t, &[e; 6], &[1.0, 0.0, (k % 2) as f64, 0.0]);
        }
        let m = acc.finish();
        assert_relative_eq!(m.ise.x, 0.5, epsilon = 1e-3);
        assert_relative_eq!(m.iae.y, 1.0, epsilon = 1e-3);
        assert_relative_eq!(m.itae.z, 1.0, epsilon = 2e-3);
        assert_relative_eq!(m.max_error_after.psi.unwrap(), ftsmc_core::math::exp(-5.0f64), epsilon = 1e-6);
        assert_eq!(m.covered(), [0.0, 20.0]);
        // |e| < 0.02 from t = ln 50 ≈ 3.912 s on.
        let ts = m.settling_time.x.unwrap();
        assert!((ts - ftsmc_core::math::ln(50f64)).abs() < 2e-3, "{ts}");
        assert_relative_eq!(m.control_energy.thrust, 20.0, epsilon = 1e-9);
        // Pitch torque alternates 0/1 every sample: variation 1 per sample.
        assert_relative_eq!(m.chattering.pitch_torque, (n - 1) as f64 / 20.0, epsilon = 1e-9);
        assert_eq!(m.chattering.thrust, 0.0);
    }

    /// The accumulator as it was before its loops were split for vector
    /// instructions (one loop with branches, the last time outside the band
    /// an `Option`): the bits every metric must keep.
    fn previous(dt: f64, steady_after: f64, window: [f64; 2], samples: &[(f64, [f64; 6], [f64; 4])]) -> Metrics {
        let (band_fraction, band_floor) = (0.02, 1e-3);
        let (mut band, mut ise, mut iae, mut itae, mut max_after, mut ise_window) =
            ([0.0f64; 6], [0.0f64; 6], [0.0f64; 6], [0.0f64; 6], [0.0f64; 6], [0.0f64; 6]);
        let mut last_outside = [None::<f64>; 6];
        let (mut energy, mut variation, mut last_u) = ([0.0f64; 4], [0.0f64; 4], [0.0f64; 4]);
        let (mut started, mut reached_after, mut time) = (false, false, 0.0);
        for (t, errors, u) in samples {
            let t = *t;
            if !started {
                for i in 0..6 {
                    band[i] = (band_fraction * errors[i].abs()).max(band_floor);
                }
                last_u = *u;
                started = true;
            }
            let after = t >= steady_after;
            reached_after |= after;
            let in_window = t >= window[0] && t <= window[1];
            for i in 0..6 {
                let e = errors[i];
                let a = e.abs();
                ise[i] += e * e;
                iae[i] += a;
                itae[i] += t * a;
                if in_window {
                    ise_window[i] += e * e;
                }
                if after && a > max_after[i] {
                    max_after[i] = a;
                }
                if a > band[i] {
                    last_outside[i] = Some(t);
                }
            }
            for j in 0..4 {
                energy[j] += u[j] * u[j];
                variation[j] += (u[j] - last_u[j]).abs();
            }
            last_u = *u;
            time = t + dt;
        }
        let mut acc = MetricsAccumulator::new(dt, band_fraction, band_floor, steady_after).with_window(Some(window));
        // The state the sums above reached, finished by the current code.
        acc.started = started;
        acc.band = band;
        acc.ise = ise;
        acc.iae = iae;
        acc.itae = itae;
        acc.ise_window = ise_window;
        acc.max_after = max_after;
        acc.reached_after = reached_after;
        acc.outside = last_outside.map(|v| v.is_some());
        acc.last_outside = last_outside.map(|v| v.unwrap_or(0.0));
        acc.energy = energy;
        acc.variation = variation;
        acc.last_u = last_u;
        acc.time = time;
        acc.finish()
    }

    #[test]
    fn split_loops_keep_the_bits_of_the_branching_loop() {
        // Errors that cross the band, ties, signed zeros, a NaN and
        // infinities: every selection and sum must take the same path.
        let dt = 0.01;
        let specials = [0.0, -0.0, 1e-3, -1e-3, 0.25, -0.25, f64::NAN, f64::INFINITY, -f64::INFINITY, 3.0];
        let mut samples = Vec::new();
        let mut x = 0.123_456_789_f64;
        for k in 0..400u32 {
            let t = f64::from(k) * dt;
            let errors: [f64; 6] = core::array::from_fn(|i| {
                x = (x * 3.9 * (1.0 - x)).clamp(1e-9, 1.0 - 1e-9);
                if (k as usize + i) % 37 == 0 {
                    specials[(k as usize / 37 + i) % specials.len()]
                } else {
                    (x - 0.5) * ftsmc_core::math::exp(-t)
                }
            });
            let u: [f64; 4] =
                core::array::from_fn(|j| if (k as usize + j) % 53 == 0 { -0.0 } else { x * (j as f64 + 1.0) });
            samples.push((t, errors, u));
        }
        let (steady_after, window) = (1.5, [0.5, 2.5]);
        let mut acc = MetricsAccumulator::new(dt, 0.02, 1e-3, steady_after).with_window(Some(window));
        for (t, errors, u) in &samples {
            acc.observe(*t, errors, u);
        }
        let (now, before) = (acc.finish(), previous(dt, steady_after, window, &samples));
        let bits = |m: &Metrics| m.flat().into_iter().map(|(n, v)| (n, v.to_bits())).collect::<Vec<_>>();
        assert_eq!(bits(&now), bits(&before));
        assert!(now.ise.x.is_nan(), "a NaN error reaches the ISE");
    }

    #[test]
    fn not_settled_when_outside_at_the_end() {
        let dt = 0.01;
        let mut acc = MetricsAccumulator::new(dt, 0.02, 1e-3, 0.0);
        for k in 0..100 {
            acc.observe(k as f64 * dt, &[1.0; 6], &[0.0; 4]);
        }
        assert_eq!(acc.finish().settling_time.x, None);
    }

    #[test]
    fn max_error_after_is_none_when_the_run_ended_before_it() {
        let dt = 0.01;
        // Steady state from 5 s, but only 0.64 s observed (a diverged run).
        let mut acc = MetricsAccumulator::new(dt, 0.02, 1e-3, 5.0);
        for k in 0..64 {
            acc.observe(k as f64 * dt, &[0.5; 6], &[0.0; 4]);
        }
        let m = acc.finish();
        assert_eq!(m.max_error_after.z, None);
        assert!((m.covered()[1] - 0.64).abs() < 1e-12);
        let flat = m.flat();
        let z = flat.iter().find(|(n, _)| n == "max_error_after_z").unwrap().1;
        assert!(z.is_nan());
    }
}
