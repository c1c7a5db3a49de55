//! Waypoint references: a list of times and values joined by quintic
//! polynomials, so the value and its first **and second** derivatives are
//! continuous everywhere (C²), including where the signal starts and ends.
//!
//! # Construction
//!
//! On each segment `[t_i, t_{i+1}]` the signal is the unique quintic that
//! takes the prescribed value, velocity and acceleration at both ends
//! (quintic Hermite interpolation). Neighbouring segments share the knot's
//! value, velocity and acceleration, so the whole curve is C²; the third
//! derivative (jerk) jumps at the knots.
//!
//! The knot velocities and accelerations are chosen by `velocity`:
//!
//! - `"zero"` (default): the reference comes to rest at every waypoint
//!   (velocity and acceleration 0). Each segment is then the minimum-jerk
//!   rest-to-rest profile `p_i + (p_{i+1} − p_i)(10τ³ − 15τ⁴ + 6τ⁵)`: it
//!   never overshoots, and x and y references on the same time grid move
//!   exactly along the straight edges of the polygon they describe (the
//!   square paths of quadrotor papers), stopping at each corner.
//! - `"spline"`: the reference passes through the interior waypoints
//!   without stopping; their velocities and accelerations are those of the
//!   C² cubic spline through the waypoints with zero end slopes (clamped
//!   spline). Smoother and faster, but it rounds polygon corners and may
//!   overshoot between waypoints.
//!
//! In both cases the first and last waypoints have velocity and
//! acceleration 0, and the signal holds the first value before `t_0` and the
//! last value after `t_N` with zero derivatives, so the hold is C² as well.
//!
//! # Validity
//!
//! `t` and `value` must have the same length (at least one point), be
//! finite, and `t` must be strictly increasing; [`Waypoints::check`] reports
//! the offending index. Evaluation never panics, even on invalid data.

use serde::{Deserialize, Serialize};

use super::Sample;

/// How the velocities and accelerations at interior waypoints are chosen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum WaypointVelocity {
    /// Stop at every waypoint (velocity and acceleration 0).
    #[default]
    Zero,
    /// Pass through: velocities and accelerations of the clamped C² cubic spline.
    Spline,
}

/// The waypoint term as written in a scenario file.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct WaypointsSpec {
    /// Times, s (strictly increasing).
    pub t: Vec<f64>,
    /// Values at those times (units of the signal).
    pub value: Vec<f64>,
    /// Velocities at interior waypoints (default `"zero"`).
    #[serde(default)]
    pub velocity: WaypointVelocity,
}

/// A waypoint signal with its precomputed quintic segments.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(from = "WaypointsSpec", into = "WaypointsSpec")]
pub struct Waypoints {
    spec: WaypointsSpec,
    /// Per segment: coefficients of `p(τ) = Σ c_k τ^k`, τ = (t − t_i)/h_i.
    coefficients: Vec<[f64; 6]>,
}

impl From<WaypointsSpec> for Waypoints {
    fn from(spec: WaypointsSpec) -> Self {
        let coefficients = segments(&spec);
        Self { spec, coefficients }
    }
}

impl From<Waypoints> for WaypointsSpec {
    fn from(w: Waypoints) -> Self {
        w.spec
    }
}

/// Knot velocities and accelerations of the clamped (zero end slopes) C²
/// cubic spline through `(t, y)`; the end knots are then set to 0, 0.
fn spline_knots(t: &[f64], y: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let n = t.len();
    let mut v = vec![0.0; n];
    let mut a = vec![0.0; n];
    if n < 3 {
        return (v, a);
    }
    let h: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    let slope: Vec<f64> = (0..n - 1).map(|i| (y[i + 1] - y[i]) / h[i]).collect();
    // Tridiagonal system for the second derivatives M (clamped ends).
    let mut diag = vec![0.0; n];
    let mut upper = vec![0.0; n];
    let mut lower = vec![0.0; n];
    let mut rhs = vec![0.0; n];
    diag[0] = 2.0 * h[0];
    upper[0] = h[0];
    rhs[0] = 6.0 * slope[0];
    for i in 1..n - 1 {
        lower[i] = h[i - 1];
        diag[i] = 2.0 * (h[i - 1] + h[i]);
        upper[i] = h[i];
        rhs[i] = 6.0 * (slope[i] - slope[i - 1]);
    }
    lower[n - 1] = h[n - 2];
    diag[n - 1] = 2.0 * h[n - 2];
    rhs[n - 1] = -6.0 * slope[n - 2];
    // Thomas algorithm (diagonally dominant for increasing t).
    for i in 1..n {
        let m = lower[i] / diag[i - 1];
        diag[i] -= m * upper[i - 1];
        rhs[i] -= m * rhs[i - 1];
    }
    let mut second = vec![0.0; n];
    second[n - 1] = rhs[n - 1] / diag[n - 1];
    for i in (0..n - 1).rev() {
        second[i] = (rhs[i] - upper[i] * second[i + 1]) / diag[i];
    }
    for i in 1..n - 1 {
        v[i] = slope[i] - h[i] * (2.0 * second[i] + second[i + 1]) / 6.0;
        a[i] = second[i];
    }
    (v, a)
}

fn segments(spec: &WaypointsSpec) -> Vec<[f64; 6]> {
    let n = spec.t.len().min(spec.value.len());
    let (t, y) = (&spec.t[..n], &spec.value[..n]);
    let (v, a) = match spec.velocity {
        WaypointVelocity::Zero => (vec![0.0; n], vec![0.0; n]),
        WaypointVelocity::Spline => spline_knots(t, y),
    };
    (0..n.saturating_sub(1))
        .map(|i| {
            let h = t[i + 1] - t[i];
            let (p0, p1) = (y[i], y[i + 1]);
            let (v0, v1) = (v[i] * h, v[i + 1] * h);
            let (a0, a1) = (a[i] * h * h, a[i + 1] * h * h);
            let dp = p1 - p0;
            [
                p0,
                v0,
                a0 / 2.0,
                10.0 * dp - 6.0 * v0 - 4.0 * v1 - (3.0 * a0 - a1) / 2.0,
                -15.0 * dp + 8.0 * v0 + 7.0 * v1 + (3.0 * a0 - 2.0 * a1) / 2.0,
                6.0 * dp - 3.0 * v0 - 3.0 * v1 - (a0 - a1) / 2.0,
            ]
        })
        .collect()
}

impl Waypoints {
    /// Waypoints through `(t[i], value[i])`.
    pub fn new(t: Vec<f64>, value: Vec<f64>, velocity: WaypointVelocity) -> Self {
        WaypointsSpec { t, value, velocity }.into()
    }

    /// The times, s.
    pub fn times(&self) -> &[f64] {
        &self.spec.t
    }

    /// The values.
    pub fn values(&self) -> &[f64] {
        &self.spec.value
    }

    /// How interior velocities are chosen.
    pub fn velocity(&self) -> WaypointVelocity {
        self.spec.velocity
    }

    /// Multiply every value by `factor` (Monte Carlo disturbance amplitude).
    pub fn scale(&mut self, factor: f64) {
        self.spec.value.iter_mut().for_each(|v| *v *= factor);
        self.coefficients = segments(&self.spec);
    }

    /// Number of waypoints.
    pub fn len(&self) -> usize {
        self.spec.t.len().min(self.spec.value.len())
    }

    /// True when there is no waypoint.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Value, rate and acceleration at `t` (s).
    pub fn sample(&self, t: f64) -> Sample {
        let n = self.spec.t.len().min(self.spec.value.len());
        if n == 0 {
            return Sample::default();
        }
        let times = &self.spec.t[..n];
        if t.is_nan() || t <= times[0] {
            return Sample { value: self.spec.value[0], ..Sample::default() };
        }
        if t >= times[n - 1] {
            return Sample { value: self.spec.value[n - 1], ..Sample::default() };
        }
        // Segment i with times[i] < t < times[i + 1] (also safe on unsorted t).
        let i = times.partition_point(|&k| k < t).saturating_sub(1).min(n - 2);
        let h = times[i + 1] - times[i];
        let tau = (t - times[i]) / h;
        let c = &self.coefficients[i];
        let value = c[0] + tau * (c[1] + tau * (c[2] + tau * (c[3] + tau * (c[4] + tau * c[5]))));
        let d1 = c[1] + tau * (2.0 * c[2] + tau * (3.0 * c[3] + tau * (4.0 * c[4] + tau * 5.0 * c[5])));
        let d2 = 2.0 * c[2] + tau * (6.0 * c[3] + tau * (12.0 * c[4] + tau * 20.0 * c[5]));
        Sample { value, rate: d1 / h, acceleration: d2 / (h * h) }
    }

    /// Check lengths, finiteness and ordering: `(sub-key, value, expected)`.
    pub fn check(&self) -> Result<(), (String, String, &'static str)> {
        use crate::text::show;
        let (t, v) = (&self.spec.t, &self.spec.value);
        if t.is_empty() || t.len() != v.len() {
            return Err((
                "value".into(),
                format!("{} values for {} times", v.len(), t.len()),
                "as many values as times, at least one",
            ));
        }
        for (i, x) in t.iter().enumerate() {
            if !x.is_finite() {
                return Err((format!("t[{i}]"), show(*x), "a finite number"));
            }
            if i > 0 && *x <= t[i - 1] {
                return Err((format!("t[{i}]"), show(*x), "strictly increasing times"));
            }
        }
        for (i, x) in v.iter().enumerate() {
            if !x.is_finite() {
                return Err((format!("value[{i}]"), show(*x), "a finite number"));
            }
        }
        Ok(())
    }
}
