//! Trajectories: a 3-D path with heading whose derivatives up to snap are
//! exact, as `[reference] trajectory = { type = "…", … }` gives it.
//!
//! - [`min_snap`]: minimum-snap polynomials through waypoints with yaw
//!   (Mellinger and Kumar 2011; closed form of Richter, Bry and Roy 2016),
//!   with time allocation from a speed, a total duration or explicit times.
//! - [`library`]: parametric shapes (hover, circle, oval, figure-eight,
//!   lissajous, helix, star, trefoil, ramp) with a C⁴ smooth start.
//! - [`feasibility`]: required thrust, tilt and body rates by differential
//!   flatness (Mellinger and Kumar 2011, §III), against the vehicle's limits.
//!
//! A [`Trajectory`] is sampled as a [`FlatOutput`] at time t. Its time can
//! be stretched by a factor `k ≥ 1` about its start
//! ([`Trajectory::set_stretch`]): `p_k(t) = p(t₀ + (t − t₀)/k)`, every
//! derivative of order m divided by `kᵐ` (what `time_scale = "fit"` sets).

pub mod feasibility;
pub mod library;
pub mod min_snap;

use serde::{Deserialize, Serialize};

use crate::text::show;
use library::{Kind, Shape, ShapeSpec};

/// Most waypoints a minimum-snap trajectory may have. The solve is `O(n)`
/// (banded Cholesky) but each waypoint costs a few hundred bytes and a
/// binary-search step per sample; beyond this, split the mission.
pub const MAX_WAYPOINTS: usize = 10_000;

/// Position and heading with their derivatives at one instant, the flat
/// outputs of a quadrotor (Mellinger and Kumar 2011, §III).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FlatOutput {
    /// Position `[x, y, z]`, m (world frame, z up).
    pub pos: [f64; 3],
    /// Velocity, m/s.
    pub vel: [f64; 3],
    /// Acceleration, m/s².
    pub acc: [f64; 3],
    /// Jerk, m/s³.
    pub jerk: [f64; 3],
    /// Snap, m/s⁴.
    pub snap: [f64; 3],
    /// Heading ψ, rad.
    pub yaw: f64,
    /// ψ̇, rad/s.
    pub yaw_rate: f64,
    /// ψ̈, rad/s².
    pub yaw_acc: f64,
}

/// A minimum-snap trajectory as written in a scenario file: waypoints,
/// optional headings, and one time rule (`speed`, `duration` or `times`).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MinSnapSpec {
    /// Waypoints `[[x, y, z], …]`, m (at least 2; consecutive ones differ).
    pub waypoints: Vec<Vec<f64>>,
    /// Heading at each waypoint, rad (default: 0 at every waypoint).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub yaw: Option<Vec<f64>>,
    /// Mean speed along each segment, m/s: segment `i` lasts
    /// `max(|w_{i+1} − w_i| / speed, min_segment_time)`. Peaks are higher
    /// (about 2.2× on a segment between two stops).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub speed: Option<f64>,
    /// Total duration, s, shared among segments in proportion to their lengths.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub duration: Option<f64>,
    /// Explicit time of every waypoint, s (strictly increasing).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub times: Option<Vec<f64>>,
    /// Time of the first waypoint with `speed` or `duration`, s (default 0).
    #[serde(default)]
    pub start: f64,
    /// Shortest segment with `speed`, s (default 0.5).
    #[serde(default = "default_min_segment_time")]
    pub min_segment_time: f64,
}

fn default_min_segment_time() -> f64 {
    0.5
}

/// A trajectory as written in a scenario file (`type = "…"`).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(tag = "type", rename_all = "kebab-case")]
pub enum TrajectorySpec {
    /// Minimum snap through waypoints ([`min_snap`]).
    MinSnap(MinSnapSpec),
    /// Hold `center` ([`library`]).
    Hover(ShapeSpec),
    /// Circle ([`library`]).
    Circle(ShapeSpec),
    /// Ellipse ([`library`]).
    Oval(ShapeSpec),
    /// Figure-eight ([`library`]).
    FigureEight(ShapeSpec),
    /// Lissajous curve ([`library`]).
    Lissajous(ShapeSpec),
    /// Helix ([`library`]).
    Helix(ShapeSpec),
    /// Smooth star ([`library`]).
    Star(ShapeSpec),
    /// Trefoil knot ([`library`]).
    Trefoil(ShapeSpec),
    /// Slope up and back ([`library`]).
    Ramp(ShapeSpec),
}

/// Why a trajectory cannot be built: the sub-key (e.g. `waypoints[3]`),
/// the value and what is expected.
pub type Refusal = (String, String, String);

#[derive(Clone, Debug, PartialEq)]
enum Built {
    MinSnap(min_snap::Plan),
    Shape(Box<Shape>),
    Refused(Refusal),
}

/// A trajectory with its solved plan. Deserializes from a
/// [`TrajectorySpec`]; an invalid one samples as the origin at rest and
/// [`Trajectory::check`] says why (scenario validation refuses it).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(from = "TrajectorySpec", into = "TrajectorySpec")]
pub struct Trajectory {
    spec: TrajectorySpec,
    built: Built,
    /// Time stretch factor k (1 = as written).
    stretch: f64,
}

impl From<Trajectory> for TrajectorySpec {
    fn from(t: Trajectory) -> Self {
        t.spec
    }
}

impl From<TrajectorySpec> for Trajectory {
    fn from(spec: TrajectorySpec) -> Self {
        let built = build(&spec).unwrap_or_else(Built::Refused);
        Self { spec, built, stretch: 1.0 }
    }
}

fn refuse<T>(key: impl Into<String>, value: String, expected: impl Into<String>) -> Result<T, Refusal> {
    Err((key.into(), value, expected.into()))
}

fn build(spec: &TrajectorySpec) -> Result<Built, Refusal> {
    let shape = |kind: Kind, s: &ShapeSpec| -> Result<Built, Refusal> {
        s.check(kind)?;
        Ok(Built::Shape(Box::new(Shape::new(kind, s.clone()))))
    };
    match spec {
        TrajectorySpec::MinSnap(m) => build_min_snap(m).map(Built::MinSnap),
        TrajectorySpec::Hover(s) => shape(Kind::Hover, s),
        TrajectorySpec::Circle(s) => shape(Kind::Circle, s),
        TrajectorySpec::Oval(s) => shape(Kind::Oval, s),
        TrajectorySpec::FigureEight(s) => shape(Kind::FigureEight, s),
        TrajectorySpec::Lissajous(s) => shape(Kind::Lissajous, s),
        TrajectorySpec::Helix(s) => shape(Kind::Helix, s),
        TrajectorySpec::Star(s) => shape(Kind::Star, s),
        TrajectorySpec::Trefoil(s) => shape(Kind::Trefoil, s),
        TrajectorySpec::Ramp(s) => shape(Kind::Ramp, s),
    }
}

/// Check a minimum-snap spec (cheap checks first, so a huge list is refused
/// before anything is computed), allocate its times and solve.
fn build_min_snap(m: &MinSnapSpec) -> Result<min_snap::Plan, Refusal> {
    let n = m.waypoints.len();
    if n > MAX_WAYPOINTS {
        return refuse(
            "waypoints",
            format!("{n} waypoints"),
            format!("at most {MAX_WAYPOINTS} waypoints (trajectory::MAX_WAYPOINTS); split the mission into shorter trajectories"),
        );
    }
    if n < 2 {
        return refuse(
            "waypoints",
            format!("{n} waypoints"),
            "at least 2 waypoints (a single point is type = \"hover\")",
        );
    }
    for (i, w) in m.waypoints.iter().enumerate() {
        if w.len() != 3 {
            return refuse(format!("waypoints[{i}]"), format!("{} numbers", w.len()), "[x, y, z], m");
        }
        for (j, v) in w.iter().enumerate() {
            if !v.is_finite() {
                return refuse(format!("waypoints[{i}][{j}]"), show(*v), "a finite number, m");
            }
        }
        if i > 0 && *w == m.waypoints[i - 1] {
            let shown = format!("[{}]", w.iter().map(|v| show(*v)).collect::<Vec<_>>().join(", "));
            return refuse(
                format!("waypoints[{i}]"),
                shown,
                format!("a point other than waypoints[{}] (consecutive waypoints must differ)", i - 1),
            );
        }
    }
    let yaw = match &m.yaw {
        Some(y) if y.len() != n => {
            return refuse("yaw", format!("{} headings", y.len()), format!("{n} headings, one per waypoint"))
        }
        Some(y) => {
            for (i, v) in y.iter().enumerate() {
                if !v.is_finite() {
                    return refuse(format!("yaw[{i}]"), show(*v), "a finite heading, rad");
                }
            }
            y.clone()
        }
        None => vec![0.0; n],
    };
    let lengths: Vec<f64> = m
        .waypoints
        .windows(2)
        .map(|w| ftsmc_core::math::sqrt((0..3).map(|j| (w[1][j] - w[0][j]) * (w[1][j] - w[0][j])).sum::<f64>()))
        .collect();
    let rules = [m.speed.is_some(), m.duration.is_some(), m.times.is_some()].iter().filter(|&&b| b).count();
    if rules != 1 {
        return refuse(
            "speed",
            format!("{rules} of speed, duration, times"),
            "exactly one of `speed` (m/s), `duration` (s) or `times` (s)",
        );
    }
    if !m.start.is_finite() {
        return refuse("start", show(m.start), "a finite time, s");
    }
    let times = if let Some(v) = m.speed {
        if !(v.is_finite() && v > 0.0) {
            return refuse("speed", show(v), "a finite speed > 0, m/s");
        }
        if !(m.min_segment_time.is_finite() && m.min_segment_time > 0.0) {
            return refuse("min_segment_time", show(m.min_segment_time), "a finite duration > 0, s");
        }
        let mut t = vec![m.start];
        for l in &lengths {
            let last = t[t.len() - 1];
            t.push(last + (l / v).max(m.min_segment_time));
        }
        t
    } else if let Some(d) = m.duration {
        if !(d.is_finite() && d > 0.0) {
            return refuse("duration", show(d), "a finite duration > 0, s");
        }
        let total: f64 = lengths.iter().sum();
        let mut t = vec![m.start];
        let mut along = 0.0;
        for l in &lengths {
            along += l;
            t.push(m.start + d * along / total);
        }
        t
    } else {
        let t = m.times.clone().unwrap_or_default();
        if t.len() != n {
            return refuse("times", format!("{} times", t.len()), format!("{n} times, one per waypoint"));
        }
        for (i, v) in t.iter().enumerate() {
            if !v.is_finite() {
                return refuse(format!("times[{i}]"), show(*v), "a finite time, s");
            }
            if i > 0 && *v <= t[i - 1] {
                return refuse(
                    format!("times[{i}]"),
                    show(*v),
                    format!("a time after times[{}] = {}", i - 1, show(t[i - 1])),
                );
            }
        }
        t
    };
    for i in 1..n {
        if times[i] <= times[i - 1] {
            return refuse(
                "waypoints",
                format!("segment {} of {} s", i - 1, show(times[i] - times[i - 1])),
                "segments long enough to be represented at this start time",
            );
        }
    }
    let values: Vec<[f64; 4]> =
        (0..n).map(|i| [m.waypoints[i][0], m.waypoints[i][1], m.waypoints[i][2], yaw[i]]).collect();
    min_snap::solve(&times, &values).map_err(|e| {
        (
            "times".to_string(),
            format!("pivot {:.3e} at waypoint {}", e.pivot, e.knot),
            format!(
                "a well-conditioned system (equilibrated Cholesky pivot >= {:e}): segment durations spanning fewer orders of magnitude",
                min_snap::MIN_PIVOT
            ),
        )
    })
}

impl Trajectory {
    /// Build a trajectory from its spec (invalid specs are kept; see [`Trajectory::check`]).
    pub fn new(spec: TrajectorySpec) -> Self {
        spec.into()
    }

    /// The spec as written.
    pub fn spec(&self) -> &TrajectorySpec {
        &self.spec
    }

    /// `Err((sub-key, value, expected))` when the spec is invalid.
    pub fn check(&self) -> Result<(), Refusal> {
        match &self.built {
            Built::Refused(r) => Err(r.clone()),
            _ => Ok(()),
        }
    }

    /// Time the trajectory starts, s (the first waypoint's, or the shape's `start`).
    pub fn start(&self) -> f64 {
        match &self.built {
            Built::MinSnap(p) => p.times[0],
            Built::Shape(s) => s.spec().start,
            Built::Refused(_) => 0.0,
        }
    }

    /// Time it comes to rest for good, s, with the stretch (None: never).
    pub fn end(&self) -> Option<f64> {
        let base = match &self.built {
            Built::MinSnap(p) => Some(p.times[p.times.len() - 1]),
            Built::Shape(s) => s.end_time(),
            Built::Refused(_) => Some(0.0),
        };
        base.map(|e| self.start() + (e - self.start()) * self.stretch)
    }

    /// The time stretch factor k (1 unless [`Trajectory::set_stretch`]).
    pub fn stretch(&self) -> f64 {
        self.stretch
    }

    /// Stretch time by `k` (≥ 1 to slow down) about [`Trajectory::start`].
    pub fn set_stretch(&mut self, k: f64) {
        self.stretch = k;
    }

    /// The flat output at `t` (s).
    pub fn sample(&self, t: f64) -> FlatOutput {
        let k = self.stretch;
        let t0 = self.start();
        let tau = if k == 1.0 { t } else { t0 + (t - t0) / k };
        let mut out = match &self.built {
            Built::MinSnap(p) => p.sample(tau),
            Built::Shape(s) => s.sample(tau),
            Built::Refused(_) => FlatOutput::default(),
        };
        if k != 1.0 {
            let (k2, k3) = (k * k, k * k * k);
            for i in 0..3 {
                out.vel[i] /= k;
                out.acc[i] /= k2;
                out.jerk[i] /= k3;
                out.snap[i] /= k2 * k2;
            }
            out.yaw_rate /= k;
            out.yaw_acc /= k2;
        }
        out
    }

    /// The minimum-snap plan, if this is one.
    pub fn plan(&self) -> Option<&min_snap::Plan> {
        match &self.built {
            Built::MinSnap(p) => Some(p),
            _ => None,
        }
    }

    /// The same trajectory bit for bit: the same spec, every number with
    /// the same bits (compared through the exact TOML text, which writes
    /// every float by its shortest round-trip form and `-0.0` as such), and
    /// the same stretch.
    pub fn same_bits(&self, other: &Trajectory) -> bool {
        self.stretch.to_bits() == other.stretch.to_bits()
            && toml::Value::try_from(&self.spec).ok().map(|v| v.to_string())
                == toml::Value::try_from(&other.spec).ok().map(|v| v.to_string())
    }

    /// Work of one evaluation in signal-term units (for the cost limits):
    /// about `8 + log2(n)` for `n` waypoints, the harmonic count for a shape.
    pub fn evaluation_cost(&self) -> f64 {
        match &self.built {
            Built::MinSnap(p) => 4.0 * (8.0 + ftsmc_core::math::log2(p.times.len().max(1) as f64)),
            Built::Shape(_) => 12.0,
            Built::Refused(_) => 1.0,
        }
    }
}

/// The `[reference] time_scale` rule.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum TimeScale {
    /// Fly as written; refuse an infeasible trajectory (default).
    #[default]
    Fixed,
    /// Stretch time by the smallest factor that makes it feasible.
    Fit,
}
