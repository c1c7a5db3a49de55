//! `[falsify]`: the search space of `ftsmc falsify` and
//! `ftsmc failure-probability` — bounded parameters of the flight's
//! conditions, each with a nominal distribution (docs/falsification.md).
//!
//! Every parameter is a table `{ low, high, nominal }`: the search stays in
//! `[low, high]`; `nominal` is the distribution the parameter has on an
//! ordinary day (`"uniform"` on the bounds, the default, or
//! `{ mean, std }`, a normal truncated to the bounds), which the
//! failure-probability estimate integrates over.
//!
//! | key | unit | what it sets |
//! |---|---|---|
//! | `wind_speed` | m/s | `[wind] speed` (the mean wind along `direction`; replaces a `mean` vector) |
//! | `wind_direction` | degrees | `[wind] direction` |
//! | `gust_onset` | s | start `t₀` of each searched 1−cosine gust (MIL-F-8785C §3.7.3) |
//! | `gust_length` | s | its duration `d` |
//! | `gust_amplitude` | m/s | its peak `A` |
//! | `gust_direction` | degrees | the horizontal direction it blows towards (from world x towards y) |
//! | `disturbance_amplitude` | 1 | factor on every `[disturbance]` term's size |
//! | `disturbance_frequency` | 1 | factor on every sine and cosine term's frequency |
//! | `disturbance_phase` | rad | added to every sine and cosine term's phase |
//! | `payload_mass` | kg | `[payload] mass` (a payload picked up at `payload_time`, else at its own `start`, else at 0) |
//! | `payload_time` | s | `[payload] start`, when the payload is picked up |
//! | `sensor_latency` | control periods | `[sensors] latency`, rounded to the nearest integer |
//! | `sensor_bias` | m | bias of the measured position along world x (`[sensors] position.bias[0]`) |
//! | `initial_offset` | m | added to each of x, y, z of the initial position |
//!
//! `gusts` (default 1 when a `gust_*` key is given, at most
//! [`MAX_GUSTS`]) independent gusts, each with its own four values from the
//! same bounds, are added to the scenario's own gusts.

use serde::{Deserialize, Serialize};

use crate::environment::wind::Gust;
use crate::scenario::Scenario;

/// Most gusts a search may add.
pub const MAX_GUSTS: usize = 8;

/// Most flights a `budget` may ask for (a search past that is refused
/// before it starts; split it into several seeds).
pub const MAX_BUDGET: u64 = 10_000_000;

/// A parameter's distribution on an ordinary day.
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(untagged)]
pub enum Nominal {
    /// `"uniform"`: uniform on `[low, high]`.
    #[default]
    #[serde(with = "uniform_word")]
    Uniform,
    /// `{ mean, std }`: normal `N(mean, std²)` truncated to `[low, high]`.
    Normal {
        /// Mean, in the parameter's unit.
        mean: f64,
        /// Standard deviation (> 0), in the parameter's unit.
        std: f64,
    },
}

mod uniform_word {
    use serde::{Deserialize, Deserializer, Serializer};
    pub fn serialize<S: Serializer>(s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str("uniform")
    }
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<(), D::Error> {
        let word = String::deserialize(d)?;
        if word == "uniform" {
            Ok(())
        } else {
            Err(serde::de::Error::custom(format!("nominal = \"{word}\": expected \"uniform\" or {{ mean, std }}")))
        }
    }
}

/// One searched parameter: its bounds and nominal distribution.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Bounds {
    /// Lower bound, in the parameter's unit.
    pub low: f64,
    /// Upper bound (> `low`).
    pub high: f64,
    /// Distribution on an ordinary day (default: uniform on the bounds).
    #[serde(default)]
    pub nominal: Nominal,
}

/// The `[falsify]` section (module documentation).
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct FalsifySection {
    /// Default flights of a search (`--budget` overrides). Default 200.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub budget: Option<u64>,
    /// Searched gusts (default 1 with any `gust_*` key, else 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gusts: Option<usize>,
    #[allow(missing_docs)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wind_speed: Option<Bounds>,
    #[allow(missing_docs)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wind_direction: Option<Bounds>,
    #[allow(missing_docs)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gust_onset: Option<Bounds>,
    #[allow(missing_docs)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gust_length: Option<Bounds>,
    #[allow(missing_docs)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gust_amplitude: Option<Bounds>,
    #[allow(missing_docs)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gust_direction: Option<Bounds>,
    #[allow(missing_docs)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub disturbance_amplitude: Option<Bounds>,
    #[allow(missing_docs)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub disturbance_frequency: Option<Bounds>,
    #[allow(missing_docs)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub disturbance_phase: Option<Bounds>,
    #[allow(missing_docs)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub payload_mass: Option<Bounds>,
    #[allow(missing_docs)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub payload_time: Option<Bounds>,
    #[allow(missing_docs)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sensor_latency: Option<Bounds>,
    #[allow(missing_docs)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sensor_bias: Option<Bounds>,
    #[allow(missing_docs)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub initial_offset: Option<Bounds>,
}

/// What a searched value sets (module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// `[wind] speed`, m/s.
    WindSpeed,
    /// `[wind] direction`, degrees.
    WindDirection,
    /// Gust `i`'s onset, s.
    GustOnset(usize),
    /// Gust `i`'s length, s.
    GustLength(usize),
    /// Gust `i`'s peak, m/s.
    GustAmplitude(usize),
    /// Gust `i`'s horizontal direction, degrees.
    GustDirection(usize),
    /// Factor on the disturbances' sizes.
    DisturbanceAmplitude,
    /// Factor on the disturbances' frequencies.
    DisturbanceFrequency,
    /// Added to the disturbances' phases, rad.
    DisturbancePhase,
    /// Payload mass, kg.
    PayloadMass,
    /// Payload pick-up time, s.
    PayloadTime,
    /// Sensor latency, control periods (rounded).
    SensorLatency,
    /// Position bias along x, m.
    SensorBias,
    /// Initial position offset on each axis, m.
    InitialOffset,
}

/// One coordinate of the search space.
#[derive(Clone, Debug, PartialEq)]
pub struct Param {
    /// Name in history.csv and summary.json (`gust_onset[0]`, `wind_speed`, …).
    pub name: String,
    /// The `[falsify]` key it comes from.
    pub key: &'static str,
    /// What it sets.
    pub target: Target,
    /// Bounds and nominal distribution.
    pub bounds: Bounds,
}

impl FalsifySection {
    fn keyed(&self) -> [(&'static str, Option<Bounds>); 14] {
        [
            ("wind_speed", self.wind_speed),
            ("wind_direction", self.wind_direction),
            ("gust_onset", self.gust_onset),
            ("gust_length", self.gust_length),
            ("gust_amplitude", self.gust_amplitude),
            ("gust_direction", self.gust_direction),
            ("disturbance_amplitude", self.disturbance_amplitude),
            ("disturbance_frequency", self.disturbance_frequency),
            ("disturbance_phase", self.disturbance_phase),
            ("payload_mass", self.payload_mass),
            ("payload_time", self.payload_time),
            ("sensor_latency", self.sensor_latency),
            ("sensor_bias", self.sensor_bias),
            ("initial_offset", self.initial_offset),
        ]
    }

    /// Number of searched gusts.
    pub fn gust_count(&self) -> usize {
        let any =
            [self.gust_onset, self.gust_length, self.gust_amplitude, self.gust_direction].iter().any(Option::is_some);
        self.gusts.unwrap_or(usize::from(any))
    }

    /// The coordinates of the search space, in a fixed order.
    pub fn params(&self) -> Vec<Param> {
        let mut out = Vec::new();
        for (key, bounds) in self.keyed() {
            let Some(bounds) = bounds else { continue };
            let one = |target| Param { name: key.to_string(), key, target, bounds };
            match key {
                "wind_speed" => out.push(one(Target::WindSpeed)),
                "wind_direction" => out.push(one(Target::WindDirection)),
                "gust_onset" | "gust_length" | "gust_amplitude" | "gust_direction" => {
                    for i in 0..self.gust_count() {
                        let target = match key {
                            "gust_onset" => Target::GustOnset(i),
                            "gust_length" => Target::GustLength(i),
                            "gust_amplitude" => Target::GustAmplitude(i),
                            _ => Target::GustDirection(i),
                        };
                        out.push(Param { name: format!("{key}[{i}]"), key, target, bounds });
                    }
                }
                "disturbance_amplitude" => out.push(one(Target::DisturbanceAmplitude)),
                "disturbance_frequency" => out.push(one(Target::DisturbanceFrequency)),
                "disturbance_phase" => out.push(one(Target::DisturbancePhase)),
                "payload_mass" => out.push(one(Target::PayloadMass)),
                "payload_time" => out.push(one(Target::PayloadTime)),
                "sensor_latency" => out.push(one(Target::SensorLatency)),
                "sensor_bias" => out.push(one(Target::SensorBias)),
                _ => out.push(one(Target::InitialOffset)),
            }
        }
        out
    }

    /// Range checks of the section alone: `Err((key, message))` naming the
    /// key and its value — a search space without parameters, bounds that
    /// are non-finite, inverted or empty (`low = high`), a nominal
    /// distribution with a non-finite or non-positive spread, a budget of
    /// 0 or above [`MAX_BUDGET`], more than [`MAX_GUSTS`] gusts or gusts
    /// without all four `gust_*` bounds.
    pub fn check(&self) -> Result<(), (String, String)> {
        if let Some(b) = self.budget {
            if b == 0 || b > MAX_BUDGET {
                return Err(("falsify.budget".into(), format!("budget = {b}: expected 1 to {MAX_BUDGET} flights")));
            }
        }
        for (key, bounds) in self.keyed() {
            let Some(b) = bounds else { continue };
            let k = format!("falsify.{key}");
            if !(b.low.is_finite() && b.high.is_finite()) {
                return Err((k, format!("low = {}, high = {}: bounds must be finite", b.low, b.high)));
            }
            if b.low > b.high {
                return Err((k, format!("low = {} > high = {}: inverted bounds", b.low, b.high)));
            }
            if b.low == b.high {
                return Err((
                    k,
                    format!("low = high = {}: an empty interval (fix the value in the scenario instead)", b.low),
                ));
            }
            if let Nominal::Normal { mean, std } = b.nominal {
                if !(mean.is_finite() && std.is_finite() && std > 0.0) {
                    return Err((
                        format!("{k}.nominal"),
                        format!("mean = {mean}, std = {std}: expected a finite mean and a finite std > 0"),
                    ));
                }
            }
        }
        let n = self.gust_count();
        if n > MAX_GUSTS {
            return Err(("falsify.gusts".into(), format!("gusts = {n}: at most {MAX_GUSTS}")));
        }
        if n > 0 {
            for (key, b) in [
                ("gust_onset", self.gust_onset),
                ("gust_length", self.gust_length),
                ("gust_amplitude", self.gust_amplitude),
                ("gust_direction", self.gust_direction),
            ] {
                if b.is_none() {
                    return Err((
                        format!("falsify.{key}"),
                        format!(
                            "missing: gusts = {n} needs gust_onset, gust_length, gust_amplitude and gust_direction"
                        ),
                    ));
                }
            }
        }
        if self.params().is_empty() {
            return Err(("falsify".into(), "an empty search space: give at least one parameter's bounds".into()));
        }
        Ok(())
    }

    /// Refuse bounds that take `base` out of its valid range: every
    /// parameter alone at its `low` and at its `high` (the others at the
    /// scenario's own values) must give a scenario that passes
    /// [`Scenario::validate`]. `Err((key, message))`.
    pub fn check_against(&self, base: &Scenario, path: &str) -> Result<(), (String, String)> {
        let params = self.params();
        for (i, p) in params.iter().enumerate() {
            for v in [p.bounds.low, p.bounds.high] {
                let mut values: Vec<Option<f64>> = vec![None; params.len()];
                values[i] = Some(v);
                let s = apply_partial(base, &params, &values);
                if let Err(e) = s.validate(path) {
                    let first = e.to_string();
                    let first = first.lines().next().unwrap_or("").chars().take(160).collect::<String>();
                    return Err((
                        format!("falsify.{}", p.key),
                        format!("{} = {v} leaves the scenario's valid range: {first}", p.name),
                    ));
                }
            }
        }
        Ok(())
    }
}

/// `base` with the searched values `x` (one per [`FalsifySection::params`]
/// entry, in order) set: the flight of one point of the search space. Its
/// `[falsify]` section is dropped (every searched value is now fixed), the
/// seed and everything else kept.
pub fn apply(base: &Scenario, params: &[Param], x: &[f64]) -> Scenario {
    let values: Vec<Option<f64>> = x.iter().map(|&v| Some(v)).collect();
    apply_partial(base, params, &values)
}

fn apply_partial(base: &Scenario, params: &[Param], x: &[Option<f64>]) -> Scenario {
    let mut s = base.clone();
    s.falsify = None;
    let get = |t: Target| params.iter().zip(x).find(|(p, _)| p.target == t).and_then(|(_, v)| *v);
    if params.iter().any(|p| matches!(p.target, Target::WindSpeed | Target::WindDirection))
        && (get(Target::WindSpeed).is_some() || get(Target::WindDirection).is_some())
    {
        let w = s.wind.get_or_insert_with(Default::default);
        if let Some(v) = get(Target::WindSpeed) {
            if w.mean != [0.0; 3] {
                // The vector's direction, as degrees, unless searched.
                w.direction = ftsmc_core::math::atan2(w.mean[1], w.mean[0]).to_degrees();
                w.mean = [0.0; 3];
            }
            w.speed = Some(v);
        }
        if let Some(d) = get(Target::WindDirection) {
            w.direction = d;
        }
    }
    let gusts =
        params.iter().filter_map(|p| if let Target::GustOnset(i) = p.target { Some(i + 1) } else { None }).max();
    if let Some(n) = gusts {
        let mut added = Vec::new();
        for i in 0..n {
            let onset = get(Target::GustOnset(i));
            let length = get(Target::GustLength(i));
            let amp = get(Target::GustAmplitude(i));
            let dir = get(Target::GustDirection(i));
            if onset.is_none() && length.is_none() && amp.is_none() && dir.is_none() {
                continue;
            }
            let mid = |b: Option<&Param>| b.map_or(0.0, |p| 0.5 * (p.bounds.low + p.bounds.high));
            let find = |f: fn(usize) -> Target| params.iter().find(|p| p.target == f(i));
            let onset = onset.unwrap_or(mid(find(Target::GustOnset)));
            let length = length.unwrap_or(mid(find(Target::GustLength)));
            let amp = amp.unwrap_or(0.0);
            let dir = dir.unwrap_or(0.0).to_radians();
            let (sin, cos) = (ftsmc_core::math::sin(dir), ftsmc_core::math::cos(dir));
            added.push(Gust { start: onset, duration: length, amplitude: [amp * cos, amp * sin, 0.0] });
        }
        if !added.is_empty() {
            s.wind.get_or_insert_with(Default::default).gusts.extend(added);
        }
    }
    let amp = get(Target::DisturbanceAmplitude);
    let freq = get(Target::DisturbanceFrequency);
    let phase = get(Target::DisturbancePhase);
    if amp.is_some() || freq.is_some() || phase.is_some() {
        for signal in s.disturbance.signals_mut() {
            signal.for_each_leaf_term_mut(&mut |term| {
                use crate::signal::Term;
                if let Some(a) = amp {
                    match term {
                        Term::Constant { value } => *value *= a,
                        Term::Step { height, .. } => *height *= a,
                        Term::Sine { amplitude, .. } | Term::Cosine { amplitude, .. } => *amplitude *= a,
                        Term::Polynomial { coefficients } => coefficients.iter_mut().for_each(|c| *c *= a),
                        Term::Waypoints(w) => w.scale(a),
                        Term::Piecewise { .. } => {}
                    }
                }
                if let Term::Sine { omega, frequency, phase: p, .. } | Term::Cosine { omega, frequency, phase: p, .. } =
                    term
                {
                    if let Some(f) = freq {
                        if let Some(w) = omega.as_mut() {
                            *w *= f;
                        }
                        if let Some(w) = frequency.as_mut() {
                            *w *= f;
                        }
                    }
                    if let Some(dp) = phase {
                        *p += dp;
                    }
                }
            });
        }
    }
    let pm = get(Target::PayloadMass);
    let pt = get(Target::PayloadTime);
    if pm.is_some() || pt.is_some() {
        let p = s.payload.get_or_insert(crate::environment::Payload {
            mass: 0.0,
            start: 0.0,
            decay_start: None,
            tau: None,
        });
        if let Some(m) = pm {
            p.mass = m;
        }
        if let Some(t) = pt {
            p.start = t;
        }
    }
    let lat = get(Target::SensorLatency);
    let bias = get(Target::SensorBias);
    if lat.is_some() || bias.is_some() {
        let sensors = s.sensors.get_or_insert_with(Default::default);
        if let Some(l) = lat {
            sensors.latency = l.round().clamp(0.0, u32::MAX as f64) as u32;
        }
        if let Some(b) = bias {
            sensors.position.bias[0] = b;
        }
    }
    if let Some(o) = get(Target::InitialOffset) {
        for p in &mut s.initial_state.position {
            *p += o;
        }
    }
    s
}
