//! The search space of a tune: the controller's declared parameters
//! (`crate::controllers::tunable`) narrowed or extended by `[tune]`, their
//! normalised coordinates for CMA-ES, and how a point becomes a scenario.
//!
//! The search runs in *step coordinates*: dimension d's coordinate is
//! `(t(v) − t(start)) / step_d`, with `t = ln` on a log dimension and the
//! identity on a linear one, so the start is the origin and one unit is the
//! dimension's initial one-standard-deviation step ([`Dim::step`]). Bounds
//! are kept by a transformation, not by clipping: `t(v)` is reflected back
//! into `[t(low), t(high)]` as often as needed ([`reflect`], the mirror
//! boundary handling of Hansen, "The CMA Evolution Strategy: A Tutorial",
//! 2016, Appendix B.3), so every point of the plane maps to a point inside
//! the box, points inside map to themselves, and no two candidates are
//! piled onto a bound.

use crate::controllers::tunable::{parameters, TuneParam, TuneTarget};
use crate::scenario::tune_section::TuneSection;
use crate::scenario::Scenario;

/// What a dimension changes.
#[derive(Clone, Debug)]
pub enum DimKind {
    /// A declared parameter: a factor on the scenario's gains.
    Declared(TuneParam),
    /// `[[tune.extra]]`: an absolute value at a dotted key.
    Key(String),
}

/// One searched dimension.
#[derive(Clone, Debug)]
pub struct Dim {
    /// Name: the declared name, or the dotted key of an extra parameter.
    pub name: String,
    /// Smallest value searched.
    pub low: f64,
    /// Largest value searched.
    pub high: f64,
    /// Searched on `ln(value)`.
    pub log: bool,
    /// Start value: 1 for a factor, the scenario's value for a key.
    pub start: f64,
    /// What it changes.
    pub kind: DimKind,
    /// Initial one-standard-deviation step, in `ln` units on a log
    /// dimension (`ln 1.4`: a factor ×1.4, [`DEFAULT_LOG_STEP`]) and in the
    /// value's units on a linear one (a tenth of the range,
    /// [`DEFAULT_LINEAR_STEP`]); with `[tune] sigma`, that fraction of the
    /// (log) range.
    pub step: f64,
}

/// Default initial step of a log dimension (every declared gain factor, a
/// `[[tune.extra]]` with `log = true`): `ln 1.4`, so one standard deviation
/// multiplies the gain by 1.4 or divides it by 1.4. A step of a fixed
/// fraction of the range instead (0.3 of `ln(20/0.05)`) is a factor ×6,
/// which on a scenario whose defaults sit near a stability limit crashes
/// almost every candidate of the first generations.
pub const DEFAULT_LOG_STEP: f64 = 0.336_472_236_621_212_9; // ln 1.4

/// Default initial step of a linear dimension (`log = false`), as a
/// fraction of its range.
pub const DEFAULT_LINEAR_STEP: f64 = 0.1;

/// `x` reflected into `[lo, hi]` (mirror boundary handling): the identity
/// inside, a triangle wave of period `2 (hi − lo)` outside.
pub fn reflect(x: f64, lo: f64, hi: f64) -> f64 {
    let w = hi - lo;
    if w.is_nan() || w <= 0.0 || !x.is_finite() {
        return x.clamp(lo, hi.max(lo));
    }
    if (lo..=hi).contains(&x) {
        return x;
    }
    let z = (x - lo).rem_euclid(2.0 * w);
    lo + if z > w { 2.0 * w - z } else { z }
}

impl Dim {
    fn to_unit(&self, v: f64) -> f64 {
        let t = |x: f64| if self.log { ftsmc_core::math::ln(x) } else { x };
        (t(v) - t(self.low)) / (t(self.high) - t(self.low))
    }

    fn value_at(&self, u: f64) -> f64 {
        let u = u.clamp(0.0, 1.0);
        if self.log {
            ftsmc_core::math::exp(
                ftsmc_core::math::ln(self.low) + u * (ftsmc_core::math::ln(self.high) - ftsmc_core::math::ln(self.low)),
            )
        } else {
            self.low + u * (self.high - self.low)
        }
    }

    fn t(&self, v: f64) -> f64 {
        if self.log {
            ftsmc_core::math::ln(v)
        } else {
            v
        }
    }

    /// The value at step coordinate `x` (see the module docs).
    pub fn value_at_step(&self, x: f64) -> f64 {
        let y = reflect(self.t(self.start) + x * self.step, self.t(self.low), self.t(self.high));
        let v = if self.log { ftsmc_core::math::exp(y) } else { y };
        v.clamp(self.low, self.high)
    }

    /// The step coordinate of value `v` (inside the bounds).
    pub fn step_of(&self, v: f64) -> f64 {
        (self.t(v) - self.t(self.start)) / self.step
    }
}

/// The search space of one controller on one scenario.
#[derive(Clone, Debug)]
pub struct Space {
    /// The dimensions, declared ones first (declaration order), then extras.
    pub dims: Vec<Dim>,
}

impl Space {
    /// The declared parameters of `controller`, narrowed, re-bounded and
    /// extended by `section`; extra keys must hold a number in `base`.
    pub fn new(controller: &str, base: &Scenario, section: &TuneSection) -> Result<Self, String> {
        let declared =
            parameters(controller).map_err(|known| format!("unknown controller `{controller}` (known: {known})"))?;
        let known = || declared.iter().map(|p| p.name).collect::<Vec<_>>().join(", ");
        let chosen: Vec<TuneParam> = match &section.parameters {
            None => declared.clone(),
            Some(names) => {
                let mut out = Vec::new();
                for n in names {
                    let p = declared.iter().find(|p| p.name == n).ok_or_else(|| {
                        format!("`tune.parameters`: `{n}` is not a parameter of {controller} (known: {})", known())
                    })?;
                    out.push(*p);
                }
                out
            }
        };
        for name in section.bounds.keys() {
            if !declared.iter().any(|p| p.name == name) {
                return Err(format!("`tune.bounds.{name}`: not a parameter of {controller} (known: {})", known()));
            }
        }
        let mut dims: Vec<Dim> = chosen
            .into_iter()
            .map(|p| {
                let [low, high] = section.bounds.get(p.name).copied().unwrap_or([p.low, p.high]);
                let step = step(true, low, high, section.sigma);
                Dim { name: p.name.to_string(), low, high, log: true, start: 1.0, kind: DimKind::Declared(p), step }
            })
            .collect();
        if !section.extra.is_empty() {
            let table = scenario_table(base)?;
            for (i, e) in section.extra.iter().enumerate() {
                let shown = crate::text::show_str(&e.key);
                crate::controllers::tunable::check_extra_key(controller, &e.key)
                    .map_err(|why| format!("{}: `tune.extra[{i}].key` = \"{shown}\": {why}", base.name))?;
                // A gain is a real number: an integer key (a count) is not searched.
                let v = match walk(&table, &e.key) {
                    Some(toml::Value::Float(f)) => *f,
                    _ => {
                        return Err(format!(
                            "{}: `tune.extra[{i}].key` = \"{shown}\": not a real-valued gain of the scenario",
                            base.name
                        ))
                    }
                };
                dims.push(Dim {
                    name: e.key.clone(),
                    low: e.low,
                    high: e.high,
                    log: e.log,
                    start: v.clamp(e.low, e.high),
                    kind: DimKind::Key(e.key.clone()),
                    step: step(e.log, e.low, e.high, section.sigma),
                });
            }
        }
        for d in &dims {
            if !(d.start >= d.low && d.start <= d.high) {
                return Err(format!(
                    "`tune.bounds.{}` = [{}, {}] does not contain the start {}",
                    d.name, d.low, d.high, d.start
                ));
            }
        }
        if dims.is_empty() {
            return Err(format!(
                "nothing to tune for {controller}: `tune.parameters` is empty and there is no `tune.extra`"
            ));
        }
        Ok(Self { dims })
    }

    /// The start point in normalised coordinates (each dimension in [0, 1]).
    pub fn start_unit(&self) -> Vec<f64> {
        self.dims.iter().map(|d| d.to_unit(d.start)).collect()
    }

    /// Parameter values of a normalised point (clamped into the bounds).
    pub fn values(&self, unit: &[f64]) -> Vec<f64> {
        self.dims.iter().zip(unit).map(|(d, u)| d.value_at(*u)).collect()
    }

    /// Parameter values of a point in step coordinates (the module docs).
    pub fn values_at_step(&self, x: &[f64]) -> Vec<f64> {
        self.dims.iter().zip(x).map(|(d, v)| d.value_at_step(*v)).collect()
    }

    /// The start values (1 for factors, the scenario's for keys).
    pub fn start_values(&self) -> Vec<f64> {
        self.dims.iter().map(|d| d.start).collect()
    }

    /// `base` with the parameter `values` applied (factors on `base`'s own
    /// gains, then extra keys), validated; `Err` names the first invalid gain.
    pub fn apply(&self, base: &Scenario, values: &[f64]) -> Result<Scenario, String> {
        let mut s = base.clone();
        {
            let mut target = TuneTarget { gains: &mut s.gains, cascade: &mut s.cascade };
            for (d, v) in self.dims.iter().zip(values) {
                if let DimKind::Declared(p) = &d.kind {
                    (p.apply)(&mut target, *v);
                }
            }
        }
        let keys: Vec<(&str, f64)> = self
            .dims
            .iter()
            .zip(values)
            .filter_map(|(d, v)| match &d.kind {
                DimKind::Key(k) => Some((k.as_str(), *v)),
                DimKind::Declared(_) => None,
            })
            .collect();
        if !keys.is_empty() {
            let mut table = scenario_table(&s)?;
            for (k, v) in keys {
                set_number(&mut table, k, v).ok_or_else(|| format!("`{k}`: not a numeric key of the scenario"))?;
            }
            let text = toml::to_string(&table).map_err(|e| e.to_string())?;
            s = Scenario::from_toml_str(&text, "tune candidate").map_err(|e| e.to_string())?;
        }
        s.gains.check().map_err(|e| format!("`{}` = {} is invalid (expected {})", e.key, e.value, e.expected))?;
        s.cascade
            .check()
            .map_err(|e| format!("`cascade.{}` = {} is invalid (expected {})", e.field, e.value, e.expected))?;
        Ok(s)
    }
}

/// Initial step of a dimension (see [`Dim::step`]).
fn step(log: bool, low: f64, high: f64, sigma: Option<f64>) -> f64 {
    let range = if log { ftsmc_core::math::ln(high / low) } else { high - low };
    match sigma {
        Some(f) => f * range,
        None if log => DEFAULT_LOG_STEP,
        None => DEFAULT_LINEAR_STEP * range,
    }
}

/// The scenario as a TOML table (every default filled in).
pub fn scenario_table(s: &Scenario) -> Result<toml::Table, String> {
    let text = s.to_toml().map_err(|e| e.to_string())?;
    text.parse::<toml::Table>().map_err(|e| e.to_string())
}

fn walk<'a>(table: &'a toml::Table, key: &str) -> Option<&'a toml::Value> {
    let mut parts = key.split('.');
    let mut v = table.get(parts.next()?)?;
    for p in parts {
        v = match v {
            toml::Value::Table(t) => t.get(p)?,
            toml::Value::Array(a) => a.get(p.parse::<usize>().ok()?)?,
            _ => return None,
        };
    }
    Some(v)
}

/// The number at dotted `key` (`a.b.0` indexes an array).
pub fn get_number(table: &toml::Table, key: &str) -> Option<f64> {
    match walk(table, key)? {
        toml::Value::Float(f) => Some(*f),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

/// Set the number at dotted `key`; `None` when it is not a number there.
pub fn set_number(table: &mut toml::Table, key: &str, value: f64) -> Option<()> {
    let parts: Vec<&str> = key.split('.').collect();
    let (first, rest) = parts.split_first()?;
    set_in(table.get_mut(*first)?, rest, value)
}

fn set_in(v: &mut toml::Value, rest: &[&str], value: f64) -> Option<()> {
    match rest.split_first() {
        None => match v {
            toml::Value::Float(_) | toml::Value::Integer(_) => {
                *v = toml::Value::Float(value);
                Some(())
            }
            _ => None,
        },
        Some((p, tail)) => {
            let next = match v {
                toml::Value::Table(t) => t.get_mut(*p)?,
                toml::Value::Array(a) => a.get_mut(p.parse::<usize>().ok()?)?,
                _ => return None,
            };
            set_in(next, tail, value)
        }
    }
}

/// The keys of `tuned` that differ from `base`, as a table of only those
/// (tables recursed; arrays and other values compared whole).
pub fn changed(base: &toml::Table, tuned: &toml::Table) -> toml::Table {
    let mut out = toml::Table::new();
    for (k, v) in tuned {
        match (base.get(k), v) {
            (Some(toml::Value::Table(b)), toml::Value::Table(t)) => {
                let sub = changed(b, t);
                if !sub.is_empty() {
                    out.insert(k.clone(), toml::Value::Table(sub));
                }
            }
            (Some(b), v) if b == v => {}
            (_, v) => {
                out.insert(k.clone(), v.clone());
            }
        }
    }
    out
}
