//! Time signals with analytic first and second derivatives: the building
//! blocks of references, disturbances and parameter variations in scenario
//! files. A [`Signal`] is a sum of [`Term`]s, optionally active only inside
//! a time window.
//!
//! In a scenario file a signal is written as
//!
//! - a bare number: a constant (`z = 1.0`);
//! - a single term: `{ type = "sine", amplitude = 0.5, omega = 0.4 }`,
//!   including `{ type = "waypoints", … }` and `{ type = "piecewise", … }`;
//! - the full form: `{ terms = [ …terms… ], window = [start, end] }`.
//!
//! All three mean the same thing as the full form with that one term, and
//! serialize as the full form.

pub mod grid;
pub mod waypoints;

use ftsmc_core::math::{cos, sin, sin_cos};
use serde::{Deserialize, Serialize};

use crate::text::show;
use waypoints::Waypoints;

/// One additive term of a [`Signal`]. In TOML: an inline table with a
/// `type` key, e.g. `{ type = "sine", amplitude = 0.5, omega = 0.4 }`.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(tag = "type", rename_all = "kebab-case", deny_unknown_fields)]
pub enum Term {
    /// `value` for all t.
    Constant {
        /// Value (units of the signal).
        value: f64,
    },
    /// 0 before `time`, `height` from `time` on (derivatives 0; the impulse
    /// at the switching instant is not represented).
    Step {
        /// Switching time, s.
        time: f64,
        /// Step height (units of the signal).
        height: f64,
    },
    /// `amplitude · sin(ω t + phase)`, ω given as `omega` (rad/s) or `frequency` (Hz).
    Sine {
        /// Amplitude (units of the signal).
        amplitude: f64,
        /// Angular frequency ω, rad/s (give this or `frequency`).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        omega: Option<f64>,
        /// Frequency f, Hz (ω = 2πf; give this or `omega`).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        frequency: Option<f64>,
        /// Phase, rad (default 0).
        #[serde(default)]
        phase: f64,
    },
    /// `amplitude · cos(ω t + phase)`, ω given as `omega` (rad/s) or `frequency` (Hz).
    Cosine {
        /// Amplitude (units of the signal).
        amplitude: f64,
        /// Angular frequency ω, rad/s (give this or `frequency`).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        omega: Option<f64>,
        /// Frequency f, Hz (ω = 2πf; give this or `omega`).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        frequency: Option<f64>,
        /// Phase, rad (default 0).
        #[serde(default)]
        phase: f64,
    },
    /// `Σ_k coefficients[k] · t^k` (ramps, parabolas, helix climb).
    Polynomial {
        /// Coefficients from degree 0 upward.
        coefficients: Vec<f64>,
    },
    /// Waypoints `t = […]`, `value = […]` joined by C² quintic segments
    /// (see [`crate::signal::waypoints`]); holds the first value before `t[0]` and
    /// the last after `t[N]`.
    Waypoints(Waypoints),
    /// A sequence of time windows, each with its own signal: piece `k` is
    /// active from the previous piece's `until` (inclusive; −∞ for the first)
    /// to its own `until` (exclusive; +∞ for the last, which has none). Each
    /// piece's signal is evaluated at the absolute time t. Nothing is
    /// continuous at the switching times unless the pieces happen to agree.
    Piecewise {
        /// The pieces in time order.
        pieces: Vec<Piece>,
    },
}

/// One time window of a [`Term::Piecewise`].
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Piece {
    /// End of this piece, s (exclusive); absent on the last piece only.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub until: Option<f64>,
    /// The signal during this piece (any signal form, nested pieces included).
    pub signal: Signal,
}

/// Value and two time derivatives of a signal at one instant.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Sample {
    /// Value.
    pub value: f64,
    /// First derivative (per s).
    pub rate: f64,
    /// Second derivative (per s²).
    pub acceleration: f64,
}

impl core::ops::AddAssign for Sample {
    fn add_assign(&mut self, o: Self) {
        self.value += o.value;
        self.rate += o.rate;
        self.acceleration += o.acceleration;
    }
}

impl Term {
    /// Angular frequency of a periodic term, rad/s (None when neither or both
    /// of `omega` and `frequency` are given — rejected by validation).
    pub fn angular_frequency(&self) -> Option<f64> {
        match self {
            Term::Sine { omega, frequency, .. } | Term::Cosine { omega, frequency, .. } => match (omega, frequency) {
                (Some(w), None) => Some(*w),
                (None, Some(f)) => Some(2.0 * core::f64::consts::PI * f),
                _ => None,
            },
            _ => None,
        }
    }

    /// The value of [`Term::sample`] alone, without the derivatives (one
    /// `sin` or `cos` instead of both for the sinusoids; the same bits).
    #[inline]
    pub fn value(&self, t: f64) -> f64 {
        match self {
            Term::Constant { value } => *value,
            Term::Sine { amplitude, phase, .. } => {
                let w = self.angular_frequency().unwrap_or(0.0);
                amplitude * sin(w * t + phase)
            }
            Term::Cosine { amplitude, phase, .. } => {
                let w = self.angular_frequency().unwrap_or(0.0);
                amplitude * cos(w * t + phase)
            }
            _ => self.sample(t).value,
        }
    }

    /// Evaluate at time `t` (s).
    pub fn sample(&self, t: f64) -> Sample {
        match self {
            Term::Constant { value } => Sample { value: *value, ..Sample::default() },
            Term::Step { time, height } => {
                Sample { value: if t >= *time { *height } else { 0.0 }, ..Sample::default() }
            }
            Term::Sine { amplitude, phase, .. } => {
                let w = self.angular_frequency().unwrap_or(0.0);
                let (s, c) = sin_cos(w * t + phase);
                Sample { value: amplitude * s, rate: amplitude * w * c, acceleration: -amplitude * w * w * s }
            }
            Term::Cosine { amplitude, phase, .. } => {
                let w = self.angular_frequency().unwrap_or(0.0);
                let (s, c) = sin_cos(w * t + phase);
                Sample { value: amplitude * c, rate: -amplitude * w * s, acceleration: -amplitude * w * w * c }
            }
            Term::Polynomial { coefficients } => polynomial(coefficients, t),
            Term::Waypoints(w) => w.sample(t),
            Term::Piecewise { pieces } => {
                let active = pieces.iter().find(|p| p.until.is_none_or(|until| t < until));
                active.map_or_else(Sample::default, |p| p.signal.sample(t))
            }
        }
    }
}

// Bit-exact equality of signals: every number compared by its bits
// (`f64::to_bits`), every structural choice (term kind, optional field
// present or not, piece count, waypoint velocity rule) exactly. Unlike
// `PartialEq`, `-0.0` and `0.0` differ (and a NaN equals the same NaN):
// two signals that compare equal here give the same bits at every instant,
// which is what lets the run loop copy one lane's reference to another
// (`Signal::same_bits`, `ReferenceSignals::same_bits`). Allocates nothing.

/// The same bits.
fn same_f64(a: f64, b: f64) -> bool {
    a.to_bits() == b.to_bits()
}

fn same_f64s(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(&x, &y)| same_f64(x, y))
}

fn same_option(a: Option<f64>, b: Option<f64>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(x), Some(y)) => same_f64(x, y),
        _ => false,
    }
}

impl Term {
    /// The same term bit for bit: the same kind, and every number of it
    /// with the same bits (`-0.0` is not `0.0`; a waypoint term by its times,
    /// values and velocity rule, from which its segments follow).
    pub fn same_bits(&self, other: &Term) -> bool {
        use Term::*;
        match (self, other) {
            (Constant { value: a }, Constant { value: b }) => same_f64(*a, *b),
            (Step { time: t1, height: h1 }, Step { time: t2, height: h2 }) => same_f64(*t1, *t2) && same_f64(*h1, *h2),
            (
                Sine { amplitude: a1, omega: w1, frequency: f1, phase: p1 },
                Sine { amplitude: a2, omega: w2, frequency: f2, phase: p2 },
            )
            | (
                Cosine { amplitude: a1, omega: w1, frequency: f1, phase: p1 },
                Cosine { amplitude: a2, omega: w2, frequency: f2, phase: p2 },
            ) => same_f64(*a1, *a2) && same_option(*w1, *w2) && same_option(*f1, *f2) && same_f64(*p1, *p2),
            (Polynomial { coefficients: a }, Polynomial { coefficients: b }) => same_f64s(a, b),
            (Waypoints(a), Waypoints(b)) => {
                a.velocity() == b.velocity() && same_f64s(a.times(), b.times()) && same_f64s(a.values(), b.values())
            }
            (Piecewise { pieces: a }, Piecewise { pieces: b }) => {
                a.len() == b.len()
                    && a.iter().zip(b).all(|(p, q)| same_option(p.until, q.until) && p.signal.same_bits(&q.signal))
            }
            _ => false,
        }
    }
}

/// `Σ_k coefficients[k] · t^k` and its two derivatives at `t` (s), by Horner.
#[inline]
fn polynomial(coefficients: &[f64], t: f64) -> Sample {
    let mut out = Sample::default();
    for &c in coefficients.iter().rev() {
        out.acceleration = out.acceleration * t + 2.0 * out.rate;
        out.rate = out.rate * t + out.value;
        out.value = out.value * t + c;
    }
    out
}

/// A sum of terms, active only inside `window = [start, end]` (s) when given
/// (inclusive at both ends; zero outside). Deserializes from a bare number,
/// a single term or the full table (see the module documentation).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Signal {
    /// Additive terms.
    #[serde(default)]
    pub terms: Vec<Term>,
    /// Active window `[start, end]`, s; always active when absent.
    #[serde(default, skip_serializing_if = "Option::is_none", with = "crate::text::exact_array::option")]
    pub window: Option<[f64; 2]>,
}

/// The full table form of a [`Signal`].
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SignalTable {
    #[serde(default)]
    terms: Vec<Term>,
    #[serde(default, with = "crate::text::exact_array::option")]
    window: Option<[f64; 2]>,
}

impl<'de> Deserialize<'de> for Signal {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        let value = toml::Value::deserialize(d)?;
        let inner = |e: toml::de::Error| D::Error::custom(e.message().trim());
        match value {
            toml::Value::Float(v) => Ok(Signal::constant(v)),
            toml::Value::Integer(v) => Ok(Signal::constant(v as f64)),
            toml::Value::Table(t) if t.contains_key("type") => {
                let term = Term::deserialize(toml::Value::Table(t)).map_err(inner)?;
                Ok(Signal { terms: vec![term], window: None })
            }
            toml::Value::Table(t) => {
                let table = SignalTable::deserialize(toml::Value::Table(t)).map_err(inner)?;
                Ok(Signal { terms: table.terms, window: table.window })
            }
            other => Err(D::Error::custom(format!(
                "invalid signal {}: expected a number (a constant), a term {{ type = \"…\", … }} or a table \
                 {{ terms = […], window = [start, end] }}",
                crate::text::show_str(&other.to_string())
            ))),
        }
    }
}

impl Signal {
    /// Call `f` on every term that is not a [`Term::Piecewise`], in order,
    /// descending into the pieces of piecewise terms.
    pub fn for_each_leaf_term_mut(&mut self, f: &mut dyn FnMut(&mut Term)) {
        for term in &mut self.terms {
            match term {
                Term::Piecewise { pieces } => pieces.iter_mut().for_each(|p| p.signal.for_each_leaf_term_mut(f)),
                other => f(other),
            }
        }
    }

    /// Work of one evaluation, in term evaluations (an upper bound): 1 per
    /// term, a polynomial's coefficient count, `1 + log2(n)` for `n`
    /// waypoints (binary search), and for a piecewise term its piece count
    /// (linear search) plus every piece's own cost. Priced by
    /// [`crate::limits::check_flight`].
    pub fn evaluation_cost(&self) -> f64 {
        self.terms
            .iter()
            .map(|term| match term {
                Term::Polynomial { coefficients } => coefficients.len().max(1) as f64,
                Term::Waypoints(w) => 1.0 + ftsmc_core::math::log2(w.len().max(1) as f64),
                Term::Piecewise { pieces } => {
                    pieces.len() as f64 + pieces.iter().map(|p| p.signal.evaluation_cost()).sum::<f64>()
                }
                _ => 1.0,
            })
            .sum()
    }

    /// The same signal bit for bit: the same terms in the same order
    /// ([`Term::same_bits`]) and the same window, bit for bit. Such signals
    /// evaluate to the same bits at every time.
    pub fn same_bits(&self, other: &Signal) -> bool {
        let window = match (self.window, other.window) {
            (None, None) => true,
            (Some(a), Some(b)) => same_f64s(&a, &b),
            _ => false,
        };
        window
            && self.terms.len() == other.terms.len()
            && self.terms.iter().zip(&other.terms).all(|(a, b)| a.same_bits(b))
    }

    /// A constant signal.
    pub fn constant(value: f64) -> Self {
        Self { terms: vec![Term::Constant { value }], window: None }
    }

    /// True when the signal has no terms (identically zero).
    pub fn is_zero(&self) -> bool {
        self.terms.is_empty()
    }

    /// Evaluate value and derivatives at `t` (s).
    pub fn sample(&self, t: f64) -> Sample {
        if let Some([start, end]) = self.window {
            if t < start || t > end {
                return Sample::default();
            }
        }
        let mut out = Sample::default();
        for term in &self.terms {
            out += term.sample(t);
        }
        out
    }

    /// Value only, at `t` (s): the `value` of [`Signal::sample`], bit for bit.
    pub fn value(&self, t: f64) -> f64 {
        if let Some([start, end]) = self.window {
            if t < start || t > end {
                return 0.0;
            }
        }
        let mut out = 0.0;
        for term in &self.terms {
            out += term.value(t);
        }
        out
    }

    /// Check every term and the window; errors name the sub-key.
    pub fn check(&self) -> Result<(), (String, String, &'static str)> {
        if let Some([start, end]) = self.window {
            if !(start.is_finite() && end.is_finite()) || end < start {
                return Err((
                    "window".into(),
                    format!("[{}, {}]", show(start), show(end)),
                    "a window [start, end] with start <= end",
                ));
            }
        }
        for (k, term) in self.terms.iter().enumerate() {
            let key = |field: &str| format!("terms[{k}].{field}");
            let finite = |field: &str, v: f64| {
                if v.is_finite() {
                    Ok(())
                } else {
                    Err((key(field), show(v), "a finite number"))
                }
            };
            match term {
                Term::Constant { value } => finite("value", *value)?,
                Term::Step { time, height } => {
                    finite("time", *time)?;
                    finite("height", *height)?;
                }
                Term::Sine { amplitude, omega, frequency, phase }
                | Term::Cosine { amplitude, omega, frequency, phase } => {
                    finite("amplitude", *amplitude)?;
                    finite("phase", *phase)?;
                    match (omega, frequency) {
                        (Some(w), None) => finite("omega", *w)?,
                        (None, Some(f)) => finite("frequency", *f)?,
                        (None, None) => {
                            return Err((
                                key("omega"),
                                "missing".into(),
                                "exactly one of `omega` (rad/s) or `frequency` (Hz)",
                            ))
                        }
                        (Some(w), Some(f)) => {
                            return Err((
                                key("frequency"),
                                format!("omega = {w}, frequency = {f}"),
                                "exactly one of `omega` (rad/s) or `frequency` (Hz)",
                            ))
                        }
                    }
                }
                Term::Polynomial { coefficients } => {
                    for (i, c) in coefficients.iter().enumerate() {
                        finite(&format!("coefficients[{i}]"), *c)?;
                    }
                }
                Term::Waypoints(w) => w.check().map_err(|(k, v, e)| (key(&k), v, e))?,
                Term::Piecewise { pieces } => {
                    if pieces.is_empty() {
                        return Err((key("pieces"), "[]".into(), "at least one piece"));
                    }
                    let last = pieces.len() - 1;
                    let mut previous = f64::NEG_INFINITY;
                    for (j, piece) in pieces.iter().enumerate() {
                        let until_key = key(&format!("pieces[{j}].until"));
                        match piece.until {
                            None if j < last => {
                                return Err((until_key, "missing".into(), "an end time on every piece but the last"))
                            }
                            Some(u) if j == last => {
                                return Err((until_key, show(u), "no `until` on the last piece (it lasts to the end)"))
                            }
                            Some(u) if !(u.is_finite() && u > previous) => {
                                return Err((until_key, show(u), "finite, strictly increasing end times"))
                            }
                            Some(u) => previous = u,
                            None => {}
                        }
                        piece.signal.check().map_err(|(k, v, e)| (key(&format!("pieces[{j}].signal.{k}")), v, e))?;
                    }
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use waypoints::WaypointVelocity;

    /// A signal of every term kind (piecewise and waypoints included) with
    /// `x` as one of its numbers.
    fn every_kind(x: f64) -> Signal {
        let inner = Signal {
            terms: vec![
                Term::Constant { value: 0.25 },
                Term::Waypoints(Waypoints::new(vec![0.0, 1.0, 3.0], vec![x, 1.0, -1.0], Default::default())),
            ],
            window: None,
        };
        Signal {
            terms: vec![
                Term::Step { time: 1.0, height: 0.5 },
                Term::Sine { amplitude: 0.5, omega: Some(0.4), frequency: None, phase: x },
                Term::Cosine { amplitude: 1.0, omega: None, frequency: Some(0.2), phase: 0.0 },
                Term::Polynomial { coefficients: vec![1.0, x, 0.3] },
                Term::Piecewise {
                    pieces: vec![
                        Piece { until: Some(2.0), signal: inner },
                        Piece { until: None, signal: Signal::constant(x) },
                    ],
                },
            ],
            window: Some([0.0, 10.0]),
        }
    }

    #[test]
    fn same_bits_holds_for_equal_signals_only() {
        assert!(every_kind(0.0).same_bits(&every_kind(0.0)));
        assert!(every_kind(0.7).same_bits(&every_kind(0.7)));
        assert!(!every_kind(0.7).same_bits(&every_kind(0.7000000000000001)));
        // `PartialEq` takes -0.0 for 0.0; the bits do not.
        assert_eq!(every_kind(-0.0), every_kind(0.0));
        assert!(!every_kind(-0.0).same_bits(&every_kind(0.0)));
        assert!(!Signal::constant(-0.0).same_bits(&Signal::constant(0.0)));
        // Each place `x` sits in, alone, tells the signals apart.
        let base = every_kind(0.0);
        let mut count = 0;
        base.clone().for_each_leaf_term_mut(&mut |_| count += 1);
        for k in 0..count {
            let mut one = base.clone();
            let mut i = 0;
            one.for_each_leaf_term_mut(&mut |term| {
                if i == k {
                    match term {
                        Term::Constant { value } => *value = -*value,
                        Term::Step { height, .. } => *height = -*height,
                        Term::Sine { phase, .. } | Term::Cosine { phase, .. } => *phase = -*phase,
                        Term::Polynomial { coefficients } => coefficients[2] = -coefficients[2],
                        Term::Waypoints(w) => w.scale(-1.0),
                        Term::Piecewise { .. } => unreachable!("leaves only"),
                    }
                }
                i += 1;
            });
            assert!(!one.same_bits(&base), "leaf {k} changed sign");
        }
        // The window, present or not and its bits.
        let mut unwindowed = base.clone();
        unwindowed.window = None;
        assert!(!unwindowed.same_bits(&base));
        let mut windowed = base.clone();
        windowed.window = Some([-0.0, 10.0]);
        assert!(!windowed.same_bits(&base));
    }

    #[test]
    fn same_bits_tells_term_kinds_and_forms_apart() {
        let sine = Term::Sine { amplitude: 0.5, omega: Some(0.4), frequency: None, phase: 0.0 };
        let cosine = Term::Cosine { amplitude: 0.5, omega: Some(0.4), frequency: None, phase: 0.0 };
        assert!(sine.same_bits(&sine.clone()));
        assert!(!sine.same_bits(&cosine));
        // The same number as `omega` or as `frequency`.
        let hz = Term::Sine { amplitude: 0.5, omega: None, frequency: Some(0.4), phase: 0.0 };
        assert!(!sine.same_bits(&hz));
        // The same value from another kind of term, or another coefficient count.
        let constant = Term::Constant { value: 2.0 };
        let polynomial = Term::Polynomial { coefficients: vec![2.0] };
        assert!(!constant.same_bits(&polynomial));
        assert!(!polynomial.same_bits(&Term::Polynomial { coefficients: vec![2.0, 0.0] }));
        // Waypoints: the velocity rule counts.
        let zero = Waypoints::new(vec![0.0, 1.0, 2.0], vec![0.0, 1.0, 0.0], WaypointVelocity::Zero);
        let spline = Waypoints::new(vec![0.0, 1.0, 2.0], vec![0.0, 1.0, 0.0], WaypointVelocity::Spline);
        assert!(Term::Waypoints(zero.clone()).same_bits(&Term::Waypoints(zero.clone())));
        assert!(!Term::Waypoints(zero).same_bits(&Term::Waypoints(spline)));
        // Terms in another order are another signal (their sum may round otherwise).
        let ab = Signal { terms: vec![sine.clone(), constant.clone()], window: None };
        let ba = Signal { terms: vec![constant, sine], window: None };
        assert!(!ab.same_bits(&ba));
    }

    #[test]
    fn terms_evaluate_to_their_formulas() {
        let sine = Term::Sine { amplitude: 0.5, omega: Some(0.4), frequency: None, phase: 0.0 };
        let s = sine.sample(2.0);
        assert_relative_eq!(s.value, 0.5 * ftsmc_core::math::sin(0.8f64), epsilon = 1e-15);
        assert_relative_eq!(s.rate, 0.5 * 0.4 * ftsmc_core::math::cos(0.8f64), epsilon = 1e-15);
        assert_relative_eq!(s.acceleration, -0.5 * 0.16 * ftsmc_core::math::sin(0.8f64), epsilon = 1e-15);

        let hz = Term::Sine { amplitude: 0.15, omega: None, frequency: Some(0.5), phase: 0.0 };
        assert_relative_eq!(
            hz.sample(0.3).value,
            0.15 * ftsmc_core::math::sin(2.0 * std::f64::consts::PI * 0.5 * 0.3),
            epsilon = 1e-15
        );

        let cosine = Term::Cosine { amplitude: 1.0, omega: Some(0.5), frequency: None, phase: 0.0 };
        assert_relative_eq!(cosine.sample(1.0).value, ftsmc_core::math::cos(0.5f64), epsilon = 1e-15);
        assert_relative_eq!(cosine.sample(1.0).rate, -0.5 * ftsmc_core::math::sin(0.5f64), epsilon = 1e-15);

        let poly = Term::Polynomial { coefficients: vec![1.0, 0.1, 0.3] };
        let p = poly.sample(2.0);
        assert_relative_eq!(p.value, 1.0 + 0.2 + 1.2, epsilon = 1e-15);
        assert_relative_eq!(p.rate, 0.1 + 2.0 * 0.3 * 2.0, epsilon = 1e-15);
        assert_relative_eq!(p.acceleration, 0.6, epsilon = 1e-15);

        let step = Term::Step { time: 1.0, height: 2.0 };
        assert_eq!(step.sample(0.999).value, 0.0);
        assert_eq!(step.sample(1.0).value, 2.0);
    }

    #[test]
    fn window_switches_the_sum_on_and_off() {
        let d = Signal {
            terms: vec![
                Term::Constant { value: 0.2 },
                Term::Sine { amplitude: 0.3, omega: Some(1.3), frequency: None, phase: 0.0 },
            ],
            window: Some([10.0, 40.0]),
        };
        assert_eq!(d.value(9.99), 0.0);
        assert_relative_eq!(d.value(20.0), 0.2 + 0.3 * ftsmc_core::math::sin(26.0f64), epsilon = 1e-15);
        assert_eq!(d.value(40.01), 0.0);
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let sig = Signal {
            terms: vec![
                Term::Sine { amplitude: 1.0, omega: Some(0.5), frequency: None, phase: 0.3 },
                Term::Cosine { amplitude: 0.7, omega: None, frequency: Some(0.2), phase: 0.0 },
                Term::Polynomial { coefficients: vec![1.0, 0.1, -0.02, 0.001] },
            ],
            window: None,
        };
        let h = 1e-5;
        for &t in &[0.0, 1.7, 12.0] {
            let s = sig.sample(t);
            let fd1 = (sig.value(t + h) - sig.value(t - h)) / (2.0 * h);
            let fd2 = (sig.sample(t + h).rate - sig.sample(t - h).rate) / (2.0 * h);
            assert!((fd1 - s.rate).abs() < 1e-7);
            assert!((fd2 - s.acceleration).abs() < 1e-7);
        }
    }

    #[test]
    fn check_rejects_inverted_window_and_ambiguous_frequency() {
        let inverted = Signal { terms: vec![], window: Some([40.0, 10.0]) };
        assert_eq!(inverted.check().unwrap_err().0, "window");
        let both = Signal {
            terms: vec![Term::Sine { amplitude: 1.0, omega: Some(1.0), frequency: Some(1.0), phase: 0.0 }],
            window: None,
        };
        assert_eq!(both.check().unwrap_err().0, "terms[0].frequency");
    }
}
