//! Parametric shapes: hover, circle, oval, figure-eight, lissajous, helix,
//! star, trefoil and ramp (the shape names of the NanoBench Crazyflie
//! flights, Ullah and Baca 2026, arXiv:2603.09908; the parameterisations
//! below are this crate's own, documented here, not taken from NanoBench's
//! code).
//!
//! # Shapes in shape time
//!
//! Every shape is `p(s) = center + f(s)` with `f` a sum of sinusoids
//! `A sin(n ω s + φ)` and a linear term per axis, ω = 2π / `period`, so its
//! derivatives of every order are exact. With θ = ω s:
//!
//! | type | f(s) | parameters (defaults) |
//! | --- | --- | --- |
//! | `hover` | 0 | — |
//! | `circle` | r (cos θ, sin θ, 0) | `radius` m (1) |
//! | `oval` | (a cos θ, b sin θ, 0) | `amplitude = [a, b]` m ([1.5, 0.75]) |
//! | `figure-eight` | (a sin θ, b sin 2θ, 0) | `amplitude = [a, b]` m ([1, 0.5]) |
//! | `lissajous` | (A_i sin(n_i θ + φ_i))_i | `amplitude` m ([1, 1, 0]), `frequencies` ([1, 2, 1]), `phases` rad ([π/2, 0, 0]) |
//! | `helix` | (r cos θ, r sin θ, c s / period) | `radius` m (1), `climb` m per lap (0.5) |
//! | `star` | ρ(θ)(cos θ, sin θ, 0), ρ = r (1 − d (1 − cos kθ)/2) | `radius` r m (1), `points` k (5), `depth` d (0.4) |
//! | `trefoil` | (r/3 (sin θ + 2 sin 2θ), r/3 (cos θ − 2 cos 2θ), −h sin 3θ) | `radius` m (1), `height` m (0.25) |
//! | `ramp` | (1 − cos θ)/2 · (Δx, Δy, Δz) | `amplitude = [Δx, Δy, Δz]` m ([1, 0, 0.5]) |
//!
//! The star's ρ cos θ and ρ sin θ are sums of sinusoids of θ, (k − 1)θ and
//! (k + 1)θ (product-to-sum), so it is exact too.
//!
//! # Smooth start and stop (time warp)
//!
//! Flying `p(t − start)` from `t = start` would ask a vehicle at rest for
//! the shape's full speed at once. The shape time instead follows a warp
//! `s(t)` whose rate `ṡ` rises from 0 to 1 over `ramp` seconds as the
//! degree-7 smoothstep `σ(u) = 35u⁴ − 84u⁵ + 70u⁶ − 20u⁷` (`u = (t −
//! start)/ramp`), whose first three derivatives vanish at both ends: `s`
//! is C⁴, so position, velocity, acceleration, jerk and snap are continuous
//! and start from rest. With `laps = L` the rate falls back to 0 the same
//! way over the last `ramp` seconds, the shape covers exactly `L · period`
//! of shape time and the reference rests at its end point from `start + L ·
//! period + ramp` on; without `laps` it goes on until the run ends. The
//! derivatives follow by the chain rule (Faà di Bruno):
//! `ṗ = f′ṡ`, `p̈ = f″ṡ² + f′s̈`, `p⃛ = f‴ṡ³ + 3f″ṡs̈ + f′s⃛`,
//! `p⁽⁴⁾ = f⁗ṡ⁴ + 6f‴ṡ²s̈ + f″(3s̈² + 4ṡs⃛) + f′s⁽⁴⁾`.

use ftsmc_core::math::sin_cos;
use serde::{Deserialize, Serialize};

use super::FlatOutput;
use crate::text::show;

const TAU: f64 = 2.0 * core::f64::consts::PI;

/// The parameters of a library shape as written in a scenario
/// (`[reference] trajectory = { type = "circle", radius = 1.0, … }`).
/// Keys a shape does not use are refused ([`ShapeSpec::check`]).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ShapeSpec {
    /// Centre of the shape `[x, y, z]`, m (default `[0, 0, 1]`).
    #[serde(default = "default_center")]
    pub center: [f64; 3],
    /// Duration of one lap in shape time, s (default 10).
    #[serde(default = "default_period")]
    pub period: f64,
    /// Laps to fly, then rest at the end point (default: until the run ends).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub laps: Option<f64>,
    /// Duration of the smooth start (and stop), s (default 2; 0 = none).
    #[serde(default = "default_ramp")]
    pub ramp: f64,
    /// Time the shape starts, s (default 0); it holds its start point before.
    #[serde(default)]
    pub start: f64,
    /// Heading ψ, rad (default 0), held constant.
    #[serde(default)]
    pub yaw: f64,
    /// Radius, m (circle, helix, star, trefoil).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius: Option<f64>,
    /// Amplitudes, m (oval, figure-eight: `[a, b]`; lissajous, ramp: `[x, y, z]`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub amplitude: Option<Vec<f64>>,
    /// Lissajous frequency multiples `[n_x, n_y, n_z]` of ω.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frequencies: Option<Vec<f64>>,
    /// Lissajous phases `[φ_x, φ_y, φ_z]`, rad.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub phases: Option<Vec<f64>>,
    /// Helix climb per lap, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub climb: Option<f64>,
    /// Star points k (an integer >= 2).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub points: Option<u32>,
    /// Star depth d in [0, 1): the valleys sit at radius r (1 − d).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub depth: Option<f64>,
    /// Trefoil height amplitude, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub height: Option<f64>,
}

fn default_center() -> [f64; 3] {
    [0.0, 0.0, 1.0]
}
fn default_period() -> f64 {
    10.0
}
fn default_ramp() -> f64 {
    2.0
}

/// The kinds of library shape.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Hold `center`.
    Hover,
    /// Circle of `radius`.
    Circle,
    /// Ellipse of semi-axes `amplitude`.
    Oval,
    /// Figure-eight of half-widths `amplitude`.
    FigureEight,
    /// Lissajous curve.
    Lissajous,
    /// Climbing circle.
    Helix,
    /// Smooth k-pointed star.
    Star,
    /// Trefoil knot.
    Trefoil,
    /// Up a straight slope and back.
    Ramp,
}

impl Kind {
    /// The `type` name in a scenario file.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Hover => "hover",
            Kind::Circle => "circle",
            Kind::Oval => "oval",
            Kind::FigureEight => "figure-eight",
            Kind::Lissajous => "lissajous",
            Kind::Helix => "helix",
            Kind::Star => "star",
            Kind::Trefoil => "trefoil",
            Kind::Ramp => "ramp",
        }
    }

    /// The shape-specific keys it takes.
    fn keys(self) -> &'static [&'static str] {
        match self {
            Kind::Hover => &[],
            Kind::Circle => &["radius"],
            Kind::Oval | Kind::FigureEight | Kind::Ramp => &["amplitude"],
            Kind::Lissajous => &["amplitude", "frequencies", "phases"],
            Kind::Helix => &["radius", "climb"],
            Kind::Star => &["radius", "points", "depth"],
            Kind::Trefoil => &["radius", "height"],
        }
    }
}

/// One sinusoid `amplitude · sin(n ω s + phase)` of shape time s.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Harmonic {
    amplitude: f64,
    /// Angular frequency n ω, rad/s of shape time.
    omega: f64,
    phase: f64,
}

/// A library shape ready to sample.
#[derive(Clone, Debug, PartialEq)]
pub struct Shape {
    kind: Kind,
    spec: ShapeSpec,
    /// Per axis: the sinusoids, and the constant rate (m per s of shape time).
    axes: [(Vec<Harmonic>, f64); 3],
}

impl ShapeSpec {
    /// Check every number; `Err((key, value, expected))`.
    pub fn check(&self, kind: Kind) -> Result<(), (String, String, String)> {
        let bad = |k: &str, v: String, e: &str| Err((k.to_string(), v, e.to_string()));
        for (i, c) in self.center.iter().enumerate() {
            if !c.is_finite() {
                return bad(&format!("center[{i}]"), show(*c), "a finite number, m");
            }
        }
        if !(self.period.is_finite() && self.period > 0.0) {
            return bad("period", show(self.period), "a finite period > 0, s");
        }
        if !(self.ramp.is_finite() && self.ramp >= 0.0) {
            return bad("ramp", show(self.ramp), "a finite duration >= 0, s");
        }
        if !self.start.is_finite() {
            return bad("start", show(self.start), "a finite time, s");
        }
        if !self.yaw.is_finite() {
            return bad("yaw", show(self.yaw), "a finite heading, rad");
        }
        if let Some(l) = self.laps {
            if !(l.is_finite() && l > 0.0) {
                return bad("laps", show(l), "a finite number of laps > 0");
            }
            if l * self.period < self.ramp {
                return bad(
                    "laps",
                    show(l),
                    &format!("laps * period >= ramp ({} s): the start and stop ramps must fit", show(self.ramp)),
                );
            }
        }
        let given: [(&str, bool); 7] = [
            ("radius", self.radius.is_some()),
            ("amplitude", self.amplitude.is_some()),
            ("frequencies", self.frequencies.is_some()),
            ("phases", self.phases.is_some()),
            ("climb", self.climb.is_some()),
            ("points", self.points.is_some()),
            ("depth", self.depth.is_some()),
        ];
        for (key, present) in given.into_iter().chain([("height", self.height.is_some())]) {
            if present && !kind.keys().contains(&key) {
                let takes = if kind.keys().is_empty() { "none".to_string() } else { kind.keys().join(", ") };
                return bad(
                    key,
                    "given".into(),
                    &format!("no `{key}` for type \"{}\" (its keys: {takes})", kind.name()),
                );
            }
        }
        let finite = |key: &str, v: f64| if v.is_finite() { Ok(()) } else { bad(key, show(v), "a finite number") };
        if let Some(r) = self.radius {
            if !(r.is_finite() && r > 0.0) {
                return bad("radius", show(r), "a finite radius > 0, m");
            }
        }
        let want = match kind {
            Kind::Oval | Kind::FigureEight => 2,
            _ => 3,
        };
        for (key, v) in [("amplitude", &self.amplitude), ("frequencies", &self.frequencies), ("phases", &self.phases)] {
            if let Some(v) = v {
                if v.len() != want {
                    return bad(key, format!("{} numbers", v.len()), &format!("exactly {want} numbers"));
                }
                for (i, x) in v.iter().enumerate() {
                    finite(&format!("{key}[{i}]"), *x)?;
                }
            }
        }
        if let Some(c) = self.climb {
            finite("climb", c)?;
        }
        if let Some(h) = self.height {
            finite("height", h)?;
        }
        if let Some(k) = self.points {
            if k < 2 {
                return bad("points", k.to_string(), "an integer >= 2");
            }
        }
        if let Some(d) = self.depth {
            if !(0.0..1.0).contains(&d) {
                return bad("depth", show(d), "a depth in [0, 1)");
            }
        }
        Ok(())
    }
}

impl Shape {
    /// The shape of `kind` with `spec` (checked with [`ShapeSpec::check`] first).
    pub fn new(kind: Kind, spec: ShapeSpec) -> Self {
        let w = TAU / spec.period;
        let h = |amplitude: f64, n: f64, phase: f64| Harmonic { amplitude, omega: n * w, phase };
        let cos = core::f64::consts::FRAC_PI_2;
        let amp = |i: usize, default: &[f64]| spec.amplitude.as_ref().map_or(default[i], |a| a[i]);
        let r = spec.radius.unwrap_or(1.0);
        let axes: [(Vec<Harmonic>, f64); 3] = match kind {
            Kind::Hover => Default::default(),
            Kind::Circle => [(vec![h(r, 1.0, cos)], 0.0), (vec![h(r, 1.0, 0.0)], 0.0), (vec![], 0.0)],
            Kind::Oval => {
                let (a, b) = (amp(0, &[1.5, 0.75]), amp(1, &[1.5, 0.75]));
                [(vec![h(a, 1.0, cos)], 0.0), (vec![h(b, 1.0, 0.0)], 0.0), (vec![], 0.0)]
            }
            Kind::FigureEight => {
                let (a, b) = (amp(0, &[1.0, 0.5]), amp(1, &[1.0, 0.5]));
                [(vec![h(a, 1.0, 0.0)], 0.0), (vec![h(b, 2.0, 0.0)], 0.0), (vec![], 0.0)]
            }
            Kind::Lissajous => {
                let n = spec.frequencies.clone().unwrap_or(vec![1.0, 2.0, 1.0]);
                let p = spec.phases.clone().unwrap_or(vec![cos, 0.0, 0.0]);
                let d = [1.0, 1.0, 0.0];
                let a = |i: usize| amp(i, &d);
                [(vec![h(a(0), n[0], p[0])], 0.0), (vec![h(a(1), n[1], p[1])], 0.0), (vec![h(a(2), n[2], p[2])], 0.0)]
            }
            Kind::Helix => {
                let climb = spec.climb.unwrap_or(0.5);
                [(vec![h(r, 1.0, cos)], 0.0), (vec![h(r, 1.0, 0.0)], 0.0), (vec![], climb / spec.period)]
            }
            Kind::Star => {
                let k = spec.points.unwrap_or(5) as f64;
                let d = spec.depth.unwrap_or(0.4);
                let (base, quarter) = (r * (1.0 - d / 2.0), r * d / 4.0);
                // ρ cos θ = base cos θ + quarter (cos (k+1)θ + cos (k−1)θ);
                // ρ sin θ = base sin θ + quarter (sin (k+1)θ − sin (k−1)θ).
                [
                    (vec![h(base, 1.0, cos), h(quarter, k + 1.0, cos), h(quarter, k - 1.0, cos)], 0.0),
                    (vec![h(base, 1.0, 0.0), h(quarter, k + 1.0, 0.0), h(-quarter, k - 1.0, 0.0)], 0.0),
                    (vec![], 0.0),
                ]
            }
            Kind::Trefoil => {
                let (a, z) = (r / 3.0, spec.height.unwrap_or(0.25));
                [
                    (vec![h(a, 1.0, 0.0), h(2.0 * a, 2.0, 0.0)], 0.0),
                    (vec![h(a, 1.0, cos), h(-2.0 * a, 2.0, cos)], 0.0),
                    (vec![h(-z, 3.0, 0.0)], 0.0),
                ]
            }
            Kind::Ramp => {
                // (1 − cos θ)/2 = 1/2 − sin(θ + π/2)/2: the 1/2 goes into the offset.
                let a = |i: usize| amp(i, &[1.0, 0.0, 0.5]);
                [
                    (vec![h(-a(0) / 2.0, 1.0, cos)], 0.0),
                    (vec![h(-a(1) / 2.0, 1.0, cos)], 0.0),
                    (vec![h(-a(2) / 2.0, 1.0, cos)], 0.0),
                ]
            }
        };
        Self { kind, spec, axes }
    }

    /// Its kind.
    pub fn kind(&self) -> Kind {
        self.kind
    }

    /// Its parameters.
    pub fn spec(&self) -> &ShapeSpec {
        &self.spec
    }

    /// Constant offset of axis `i` beyond `center` (the ramp's 1/2).
    fn offset(&self, i: usize) -> f64 {
        match self.kind {
            Kind::Ramp => self.spec.amplitude.as_ref().map_or([1.0, 0.0, 0.5][i], |a| a[i]) / 2.0,
            _ => 0.0,
        }
    }

    /// Derivatives 0–4 of `f_i` at shape time `s`.
    fn f(&self, i: usize, s: f64) -> [f64; 5] {
        let (harmonics, rate) = &self.axes[i];
        let mut out = [self.spec.center[i] + self.offset(i) + rate * s, *rate, 0.0, 0.0, 0.0];
        for h in harmonics {
            let (sn, cs) = sin_cos(h.omega * s + h.phase);
            let w = h.omega;
            // d^m/ds^m sin(x) cycles sin, cos, −sin, −cos.
            let mut wm = h.amplitude;
            for (m, v) in out.iter_mut().enumerate() {
                *v += wm * [sn, cs, -sn, -cs][m % 4];
                wm *= w;
            }
        }
        out
    }

    /// Shape time and its derivatives 1–4 at time `t` (s) ([module docs](self)).
    pub fn warp(&self, t: f64) -> [f64; 5] {
        let spec = &self.spec;
        let r = spec.ramp;
        let total = spec.laps.map(|l| l * spec.period);
        let end = total.map(|s| s + r);
        let u = t - spec.start;
        if u.is_nan() || u <= 0.0 {
            return [0.0; 5];
        }
        if let (Some(total), Some(end)) = (total, end) {
            if u >= end {
                return [total, 0.0, 0.0, 0.0, 0.0];
            }
            if r > 0.0 && u > end - r {
                let [s, s1, s2, s3, s4] = ramp_up(r, end - u);
                return [total - s, s1, -s2, s3, -s4];
            }
        }
        if r > 0.0 && u < r {
            return ramp_up(r, u);
        }
        [r / 2.0 + (u - r), 1.0, 0.0, 0.0, 0.0]
    }

    /// The flat output at `t` (s).
    pub fn sample(&self, t: f64) -> FlatOutput {
        let [s, s1, s2, s3, s4] = self.warp(t);
        let mut out = FlatOutput { yaw: self.spec.yaw, ..FlatOutput::default() };
        for i in 0..3 {
            let [f0, f1, f2, f3, f4] = self.f(i, s);
            out.pos[i] = f0;
            out.vel[i] = f1 * s1;
            out.acc[i] = f2 * s1 * s1 + f1 * s2;
            out.jerk[i] = f3 * s1 * s1 * s1 + 3.0 * f2 * s1 * s2 + f1 * s3;
            out.snap[i] =
                f4 * s1 * s1 * s1 * s1 + 6.0 * f3 * s1 * s1 * s2 + f2 * (3.0 * s2 * s2 + 4.0 * s1 * s3) + f1 * s4;
        }
        out
    }

    /// When the shape ends (rests), s; `None` when it flies until the run ends.
    pub fn end_time(&self) -> Option<f64> {
        self.spec.laps.map(|l| self.spec.start + l * self.spec.period + self.spec.ramp)
    }
}

/// `[s, ṡ, s̈, s⃛, s⁽⁴⁾]` `u` seconds into a ramp of `r` seconds: `ṡ = σ(u/r)`.
fn ramp_up(r: f64, u: f64) -> [f64; 5] {
    let x = u / r;
    let x2 = x * x;
    let x3 = x2 * x;
    let x4 = x3 * x;
    // ∫σ = 7x⁵ − 14x⁶ + 10x⁷ − 2.5x⁸ (= 1/2 at x = 1).
    let s = r * x4 * x * (7.0 + x * (-14.0 + x * (10.0 - 2.5 * x)));
    let s1 = x4 * (35.0 + x * (-84.0 + x * (70.0 - 20.0 * x)));
    let s2 = x3 * (140.0 + x * (-420.0 + x * (420.0 - 140.0 * x))) / r;
    let s3 = x2 * (420.0 + x * (-1680.0 + x * (2100.0 - 840.0 * x))) / (r * r);
    let s4 = x * (840.0 + x * (-5040.0 + x * (8400.0 - 4200.0 * x))) / (r * r * r);
    [s, s1, s2, s3, s4]
}
