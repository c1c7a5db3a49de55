//! Monte Carlo sampling: [`Dist`], [`MonteCarloSpec`] (the `[montecarlo]`
//! section), the sampled columns and the per-run seed [`run_seed`].

//! Monte Carlo robustness: a scenario's `[montecarlo]` section declares
//! distributions for plant parameters, payload, disturbances and initial
//! state; each run draws its own values from generators derived from the
//! master seed and the run index only (never from thread state), so results
//! are identical whatever the thread count.

use crate::rng::chacha_stream;
use rand::{Rng, RngExt};
use serde::{Deserialize, Serialize};

use crate::gauss::{LogNormal, Normal};
use crate::scenario::Scenario;
use crate::signal::Term;

/// A scalar distribution, optionally truncated to `[low, high]` by
/// clamping (`uniform` uses `low`/`high` as its support).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(tag = "dist", rename_all = "kebab-case", deny_unknown_fields)]
pub enum Dist {
    /// Uniform on `[low, high]`.
    Uniform {
        /// Lower bound.
        low: f64,
        /// Upper bound.
        high: f64,
    },
    /// Normal `N(mean, std²)`, clamped to `[low, high]` when given.
    Normal {
        /// Mean.
        mean: f64,
        /// Standard deviation (≥ 0).
        std: f64,
        /// Optional lower clamp.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        low: Option<f64>,
        /// Optional upper clamp.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        high: Option<f64>,
    },
    /// Log-normal: `exp(N(mu, sigma²))`, clamped to `[low, high]` when given.
    LogNormal {
        /// Mean of the underlying normal.
        mu: f64,
        /// Standard deviation of the underlying normal (≥ 0).
        sigma: f64,
        /// Optional lower clamp.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        low: Option<f64>,
        /// Optional upper clamp.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        high: Option<f64>,
    },
}

impl Dist {
    /// Draw one value.
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        let clamp = |v: f64, low: Option<f64>, high: Option<f64>| {
            let v = low.map_or(v, |l| v.max(l));
            high.map_or(v, |h| v.min(h))
        };
        match *self {
            Dist::Uniform { low, high } => {
                if high > low {
                    rng.random_range(low..=high)
                } else {
                    low
                }
            }
            Dist::Normal { mean, std, low, high } => {
                let v = Normal::new(mean, std).map(|d| d.sample(rng)).unwrap_or(mean);
                clamp(v, low, high)
            }
            Dist::LogNormal { mu, sigma, low, high } => {
                let v = LogNormal::new(mu, sigma).map(|d| d.sample(rng)).unwrap_or(ftsmc_core::math::exp(mu));
                clamp(v, low, high)
            }
        }
    }

    /// Range check: finite parameters (`inf`/`nan` are refused, also as
    /// clamps), `high >= low`, a `uniform` whose width `high - low` is
    /// finite, and draws that are always finite ([`Dist::support`]);
    /// `Err((field, value, expected))`.
    pub fn check(&self) -> Result<(), (&'static str, f64, &'static str)> {
        let finite = |f: &'static str, v: f64| if v.is_finite() { Ok(()) } else { Err((f, v, "a finite number")) };
        let bounds = |low: Option<f64>, high: Option<f64>| {
            if let Some(l) = low {
                finite("low", l)?;
            }
            if let Some(h) = high {
                finite("high", h)?;
            }
            match (low, high) {
                (Some(l), Some(h)) if h < l => Err(("high", h, "high >= low")),
                _ => Ok(()),
            }
        };
        match *self {
            Dist::Uniform { low, high } => {
                finite("low", low)?;
                finite("high", high)?;
                if high < low {
                    return Err(("high", high, "high >= low"));
                }
                if !(high - low).is_finite() {
                    return Err(("high", high, "a range whose width high - low is finite (below ~1.8e308)"));
                }
            }
            Dist::Normal { mean, std, low, high } => {
                finite("mean", mean)?;
                if !(std.is_finite() && std >= 0.0) {
                    return Err(("std", std, "a finite value >= 0"));
                }
                bounds(low, high)?;
                let (lo, hi) = self.support();
                if !(lo.is_finite() && hi.is_finite()) {
                    return Err(("std", std, "a std whose draws stay finite (mean ± 40 std below ~1.8e308)"));
                }
            }
            Dist::LogNormal { mu, sigma, low, high } => {
                finite("mu", mu)?;
                if !(sigma.is_finite() && sigma >= 0.0) {
                    return Err(("sigma", sigma, "a finite value >= 0"));
                }
                bounds(low, high)?;
                let (_, hi) = self.support();
                if !hi.is_finite() {
                    return Err((
                        "mu",
                        mu,
                        "mu + 40 sigma <= 709 (exp of larger values is infinite), or a finite `high` clamp",
                    ));
                }
            }
        }
        Ok(())
    }

    /// The interval `[lo, hi]` every draw lies in, after the optional
    /// clamps: `[low, high]` for `uniform`; mean ± 40 std for `normal` and
    /// exp(mu ± 40 sigma) for `log-normal` (the normal generator never
    /// produces more than ~14 standard deviations), clamped like a draw.
    /// Validation checks this interval against the parameter's physical range.
    pub fn support(&self) -> (f64, f64) {
        const Z: f64 = 40.0;
        let clamp = |v: f64, low: Option<f64>, high: Option<f64>| {
            let v = low.map_or(v, |l| v.max(l));
            high.map_or(v, |h| v.min(h))
        };
        match *self {
            Dist::Uniform { low, high } => (low, high),
            Dist::Normal { mean, std, low, high } => {
                (clamp(mean - Z * std, low, high), clamp(mean + Z * std, low, high))
            }
            Dist::LogNormal { mu, sigma, low, high } => (
                clamp(ftsmc_core::math::exp(mu - Z * sigma), low, high),
                clamp(ftsmc_core::math::exp(mu + Z * sigma), low, high),
            ),
        }
    }
}

/// What a Monte Carlo batch randomises. Every entry is optional; absent
/// entries keep the scenario's value. Factors multiply the scenario value;
/// offsets add to it. The controllers keep the nominal `[plant]` model; the
/// sampled values reach the plant only.
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MonteCarloSpec {
    /// True mass, kg (replaces `plant.mass` in the plant only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mass: Option<Dist>,
    /// Payload mass Δm, kg (replaces `payload.mass`; needs a `[payload]`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub payload_mass: Option<Dist>,
    /// Factor on all three true moments of inertia.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inertia_factor: Option<Dist>,
    /// Factor on every true drag coefficient.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub drag_factor: Option<Dist>,
    /// Factor on every disturbance amplitude / constant.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub disturbance_amplitude: Option<Dist>,
    /// Phase added to every periodic disturbance term, rad (one draw per term).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub disturbance_phase: Option<Dist>,
    /// Offset added to each initial position component, m (one draw per axis).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub initial_position_offset: Option<Dist>,
    /// Offset added to each initial Euler angle, rad (one draw per axis).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub initial_attitude_offset: Option<Dist>,
    /// Factor on the true mass (the vehicle's own, before any payload):
    /// the relative form of `mass`, which follows the vehicle. A file writes
    /// it as `mass = { dist = "uniform", rel = [0.9, 1.1] }` (or directly);
    /// not together with `mass`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mass_factor: Option<Dist>,
    /// Factor on the scenario's `payload.mass`: the relative form of
    /// `payload_mass` (`payload_mass = { dist = "uniform", rel = [a, b] }`);
    /// not together with `payload_mass`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub payload_mass_factor: Option<Dist>,
}

/// `dist` of a factor as the distribution of `value × factor` (`value > 0`):
/// bounds, mean and standard deviation scaled, a log-normal's `mu` shifted
/// by `ln value`.
fn scaled(dist: &Dist, value: f64) -> Dist {
    let opt = |v: Option<f64>| v.map(|v| v * value);
    match *dist {
        Dist::Uniform { low, high } => Dist::Uniform { low: low * value, high: high * value },
        Dist::Normal { mean, std, low, high } => {
            Dist::Normal { mean: mean * value, std: std * value, low: opt(low), high: opt(high) }
        }
        Dist::LogNormal { mu, sigma, low, high } => {
            Dist::LogNormal { mu: mu + ftsmc_core::math::ln(value), sigma, low: opt(low), high: opt(high) }
        }
    }
}

/// A draw whose every value lies within `[value / BAND, value × BAND]` of the
/// vehicle's own value is plausible; one reaching beyond is refused (a
/// draw meant for another vehicle, or a unit slip).
pub const PLAUSIBLE_BAND: f64 = 3.0;
/// A draw reaching beyond `[value / WARN_BAND, value × WARN_BAND]` (but
/// plausible) gets a warning.
pub const WARN_BAND: f64 = 1.5;

/// Names of the sampled columns in `runs.csv`, in order.
pub const SAMPLED_COLUMNS: [&str; 12] = [
    "mass",
    "payload_mass",
    "inertia_factor",
    "drag_factor",
    "disturbance_amplitude",
    "disturbance_phase_0",
    "x0",
    "y0",
    "z0",
    "phi0",
    "theta0",
    "psi0",
];

impl MonteCarloSpec {
    /// Range-check every distribution; `Err((key, value, expected))`.
    pub fn check(&self) -> Result<(), (String, f64, &'static str)> {
        for (name, d) in self.named() {
            if let Some(d) = d {
                d.check().map_err(|(f, v, e)| (format!("montecarlo.{name}.{f}"), v, e))?;
            }
        }
        for (name, d, absolute) in [
            ("mass_factor", &self.mass_factor, &self.mass),
            ("payload_mass_factor", &self.payload_mass_factor, &self.payload_mass),
        ] {
            if let Some(d) = d {
                d.check().map_err(|(f, v, e)| (format!("montecarlo.{name}.{f}"), v, e))?;
                if d.support().0 <= 0.0 {
                    return Err((
                        format!("montecarlo.{name}"),
                        d.support().0,
                        "factors > 0 (give the distribution a `low` > 0)",
                    ));
                }
                if absolute.is_some() {
                    return Err((
                        format!("montecarlo.{name}"),
                        d.support().0,
                        "either the relative draw or the absolute one, not both",
                    ));
                }
            }
        }
        Ok(())
    }

    /// This spec with the relative draws (`mass_factor`,
    /// `payload_mass_factor`) turned into the absolute ones they mean on
    /// `base` (its true mass, its `payload.mass`); the flights and the
    /// range checks use this form.
    pub fn absolute(&self, base: &Scenario) -> MonteCarloSpec {
        let mut out = self.clone();
        if let Some(d) = out.mass_factor.take() {
            out.mass = Some(scaled(&d, base.true_vehicle().mass));
        }
        if let Some(d) = out.payload_mass_factor.take() {
            if let Some(p) = &base.payload {
                out.payload_mass = Some(scaled(&d, p.mass));
            }
        }
        out
    }

    /// The absolute mass and payload draws against the vehicle's own mass
    /// `m` (before payload): `Err` for a draw reaching beyond
    /// `[m / PLAUSIBLE_BAND, m × PLAUSIBLE_BAND]` (payload: above
    /// `m × PLAUSIBLE_BAND`), `Ok(warnings)` for one beyond [`WARN_BAND`];
    /// each `(key, draws, why)`.
    #[allow(clippy::type_complexity)]
    pub fn vehicle_band(&self, base: &Scenario) -> Result<Vec<(String, String, String)>, (String, String, String)> {
        use crate::text::show;
        let m = base.true_vehicle().mass;
        let mut warnings = Vec::new();
        let range = |(lo, hi): (f64, f64)| format!("draws in [{}, {}] kg", show(lo), show(hi));
        let (which, vehicle) = (base.true_mass().1, base.vehicle.preset.map(|p| format!(" (preset {})", p.name())));
        let vehicle = vehicle.unwrap_or_default();
        if let Some(d) = &self.mass {
            let (lo, hi) = d.support();
            if lo < m / PLAUSIBLE_BAND || hi > m * PLAUSIBLE_BAND {
                return Err((
                    "montecarlo.mass".into(),
                    range((lo, hi)),
                    format!(
                        "masses within [{}, {}] kg, a factor {PLAUSIBLE_BAND} of the vehicle's {which} = {} kg{vehicle} (a draw for another vehicle? write it relative: mass = {{ dist = \"uniform\", rel = [0.9, 1.1] }})",
                        show(m / PLAUSIBLE_BAND),
                        show(m * PLAUSIBLE_BAND),
                        show(m)
                    ),
                ));
            }
            if lo < m / WARN_BAND || hi > m * WARN_BAND {
                warnings.push((
                    "montecarlo.mass".into(),
                    range((lo, hi)),
                    format!(
                        "far from the vehicle's {which} = {} kg{vehicle} (more than a factor {WARN_BAND})",
                        show(m)
                    ),
                ));
            }
        }
        if let Some(d) = &self.payload_mass {
            let (_, hi) = d.support();
            if hi > m * PLAUSIBLE_BAND {
                return Err((
                    "montecarlo.payload_mass".into(),
                    range(d.support()),
                    format!(
                        "payloads up to {PLAUSIBLE_BAND} × the vehicle's {which} = {} kg{vehicle} (a draw for another vehicle? write it relative: payload_mass = {{ dist = \"uniform\", rel = [a, b] }})",
                        show(m)
                    ),
                ));
            }
            if hi > m * WARN_BAND {
                warnings.push((
                    "montecarlo.payload_mass".into(),
                    range(d.support()),
                    format!("payloads above {WARN_BAND} × the vehicle's {which} = {} kg{vehicle}", show(m)),
                ));
            }
        }
        Ok(warnings)
    }

    /// [`MonteCarloSpec::check`], then every draw against the physical range
    /// of the value it replaces in `base` — the same ranges as fixed values —
    /// using each distribution's [`Dist::support`]: a true mass > 0 (with the
    /// payload, whose draws need a `[payload]`), inertia factor > 0, drag
    /// factor >= 0, finite scaled inertia / drag / initial position, and an
    /// initial roll and pitch inside `simulation.max_tilt`.
    /// `Err((key, value, expected))`; the key names the distribution.
    pub fn check_against(&self, base: &Scenario) -> Result<(), (String, String, String)> {
        self.check().map_err(|(k, v, e)| (k, crate::text::show(v), e.to_string()))?;
        let absolute = self.absolute(base);
        absolute.check_against_absolute(base)?;
        absolute.vehicle_band(base).map(|_| ())
    }

    /// [`MonteCarloSpec::check_against`] of the absolute form.
    fn check_against_absolute(&self, base: &Scenario) -> Result<(), (String, String, String)> {
        use crate::text::show;
        // After `check`, every support is finite (never NaN), so plain comparisons suffice.
        self.check().map_err(|(k, v, e)| (k, show(v), e.to_string()))?;
        let range = |(lo, hi): (f64, f64)| format!("draws in [{}, {}]", show(lo), show(hi));
        let err =
            |name: &str, d: &Dist, expected: String| Err((format!("montecarlo.{name}"), range(d.support()), expected));
        let truth = base.true_vehicle();
        let mut mass_low = truth.mass;
        if let Some(d) = &self.mass {
            let (lo, _) = d.support();
            if lo <= 0.0 {
                return err("mass", d, "a true mass > 0 (give the distribution a `low` > 0)".into());
            }
            mass_low = lo;
        }
        match (&self.payload_mass, &base.payload) {
            (Some(d), None) => {
                return err("payload_mass", d, "a [payload] section to replace the mass of (there is none)".into())
            }
            (Some(d), Some(_)) => {
                let (lo, _) = d.support();
                if mass_low + lo.min(0.0) <= 0.0 {
                    return err(
                        "payload_mass",
                        d,
                        format!("payload draws > -(smallest true mass {}) so the mass stays > 0", show(mass_low)),
                    );
                }
            }
            (None, Some(p)) => {
                if let Some(d) = &self.mass {
                    if mass_low + p.mass.min(0.0) <= 0.0 {
                        return err(
                            "mass",
                            d,
                            format!("true masses > -payload.mass = {} so the mass stays > 0", show(-p.mass)),
                        );
                    }
                }
            }
            (None, None) => {}
        }
        if let Some(d) = &self.inertia_factor {
            let (lo, hi) = d.support();
            if lo <= 0.0 || truth.inertia.iter().any(|i| !(i * hi).is_finite()) {
                return err("inertia_factor", d, "factors > 0 with finite scaled inertia".into());
            }
        }
        if let Some(d) = &self.drag_factor {
            let (lo, hi) = d.support();
            let drag = truth.drag_translational.iter().chain(&truth.drag_rotational);
            if lo < 0.0 || drag.into_iter().any(|k| !(k * hi).is_finite()) {
                return err("drag_factor", d, "factors >= 0 with finite scaled drag".into());
            }
        }
        // On the rigid body, every draw must also leave its parameters in
        // their valid range (RigidBodyParams::check): mass with the payload,
        // scaled inertia and drag, at both ends of each support.
        if matches!(base.vehicle.model, crate::vehicle::VehicleModel::RigidBody) {
            let ends = |d: Option<&Dist>| d.map_or(Vec::new(), |d| vec![d.support().0, d.support().1]);
            let fails = |rb: crate::vehicle::RigidBodyParams| {
                rb.check().err().map(|e| {
                    format!(
                        "draws keeping the rigid body in its valid range (a draw gives {} = {}; expected {})",
                        e.field,
                        show(e.value),
                        e.expected
                    )
                })
            };
            let masses: Vec<Option<f64>> = match &self.mass {
                Some(d) => ends(Some(d)).into_iter().map(Some).collect(),
                None => vec![None],
            };
            let payloads: Vec<f64> = match (&self.payload_mass, &base.payload) {
                (Some(d), Some(_)) => ends(Some(d)).into_iter().chain([0.0]).collect(),
                (None, Some(p)) => vec![0.0, p.mass],
                _ => vec![0.0],
            };
            for &m in &masses {
                for &added in &payloads {
                    let mut rb = drawn_rigid_body(base, m, 1.0, 1.0);
                    rb.mass += added;
                    if let Some(why) = fails(rb) {
                        let (name, d) = match (&self.payload_mass, &self.mass) {
                            (Some(d), _) if added != 0.0 => ("payload_mass", d),
                            (_, Some(d)) => ("mass", d),
                            (Some(d), None) => ("payload_mass", d),
                            (None, None) => continue, // the fixed values, checked by Scenario::validate
                        };
                        return err(name, d, why);
                    }
                }
            }
            for f in ends(self.inertia_factor.as_ref()) {
                if let (Some(why), Some(d)) = (fails(drawn_rigid_body(base, None, f, 1.0)), &self.inertia_factor) {
                    return err("inertia_factor", d, why);
                }
            }
            for f in ends(self.drag_factor.as_ref()) {
                if let (Some(why), Some(d)) = (fails(drawn_rigid_body(base, None, 1.0, f)), &self.drag_factor) {
                    return err("drag_factor", d, why);
                }
            }
        }
        if let Some(d) = &self.initial_position_offset {
            let (lo, hi) = d.support();
            if base.initial_state.position.iter().any(|p| !((p + lo).is_finite() && (p + hi).is_finite())) {
                return err("initial_position_offset", d, "offsets giving a finite initial position".into());
            }
            // A single file must start at or above the ground; so must every draw.
            if let Some(g) = base.ground.as_ref().filter(|g| g.enabled) {
                let z0 = base.initial_state.position[2];
                if z0 + lo < g.height {
                    return err(
                        "initial_position_offset",
                        d,
                        format!(
                            "offsets keeping the start at or above ground.height = {} (the lowest draw starts at z = {} + {} = {})",
                            show(g.height),
                            show(z0),
                            show(lo),
                            show(z0 + lo)
                        ),
                    );
                }
            }
        }
        // Scaled disturbances are held to a file's range: finite values.
        if let Some(d) = &self.disturbance_amplitude {
            let (lo, hi) = d.support();
            for factor in [lo, hi] {
                let mut scaled = base.disturbance.clone();
                for signal in
                    [&mut scaled.x, &mut scaled.y, &mut scaled.z, &mut scaled.phi, &mut scaled.theta, &mut scaled.psi]
                {
                    signal.for_each_leaf_term_mut(&mut |term| scale_term(term, factor));
                }
                for (axis, signal) in scaled.named() {
                    if let Err((key, value, expected)) = signal.check() {
                        return err(
                            "disturbance_amplitude",
                            d,
                            format!(
                                "factors keeping every disturbance in range (factor {} gives disturbance.{axis}.{key} = {value}; expected {expected})",
                                show(factor)
                            ),
                        );
                    }
                }
            }
        }
        if let Some(d) = &self.initial_attitude_offset {
            let (lo, hi) = d.support();
            let tilt = base.simulation.max_tilt;
            if base.initial_state.attitude[..2].iter().any(|a| !((a + lo).abs() < tilt && (a + hi).abs() < tilt)) {
                return err(
                    "initial_attitude_offset",
                    d,
                    format!("offsets keeping |roll|, |pitch| < simulation.max_tilt = {}", show(tilt)),
                );
            }
            if !(base.initial_state.attitude[2] + lo).is_finite() || !(base.initial_state.attitude[2] + hi).is_finite()
            {
                return err("initial_attitude_offset", d, "offsets giving a finite initial yaw".into());
            }
        }
        Ok(())
    }

    fn named(&self) -> [(&'static str, Option<&Dist>); 8] {
        [
            ("mass", self.mass.as_ref()),
            ("payload_mass", self.payload_mass.as_ref()),
            ("inertia_factor", self.inertia_factor.as_ref()),
            ("drag_factor", self.drag_factor.as_ref()),
            ("disturbance_amplitude", self.disturbance_amplitude.as_ref()),
            ("disturbance_phase", self.disturbance_phase.as_ref()),
            ("initial_position_offset", self.initial_position_offset.as_ref()),
            ("initial_attitude_offset", self.initial_attitude_offset.as_ref()),
        ]
    }

    /// Scenario for run `index` of a batch with master seed `master`, and the
    /// sampled values ([`SAMPLED_COLUMNS`]). Stream `k` of the run's
    /// generator serves parameter `k`, so adding a parameter never changes
    /// the draws of the others.
    pub fn sample(&self, base: &Scenario, master: u64, index: u64) -> (Scenario, u64, [f64; 12]) {
        if self.mass_factor.is_some() || self.payload_mass_factor.is_some() {
            return self.absolute(base).sample(base, master, index);
        }
        let seed = run_seed(master, index);
        let stream = |k: u64| chacha_stream(seed, 100 + k);
        let mut s = base.clone();
        s.seed = seed;
        let mass = self.mass.map(|d| d.sample(&mut stream(0)));
        if let (Some(d), Some(p)) = (&self.payload_mass, s.payload.as_mut()) {
            p.mass = d.sample(&mut stream(1));
        }
        let inertia_factor = self.inertia_factor.map_or(1.0, |d| d.sample(&mut stream(2)));
        let drag_factor = self.drag_factor.map_or(1.0, |d| d.sample(&mut stream(3)));
        draw_true_vehicle(&mut s.vehicle, &base.plant, mass, inertia_factor, drag_factor);
        let truth = s.true_vehicle();
        let amplitude = self.disturbance_amplitude.map_or(1.0, |d| d.sample(&mut stream(4)));
        let mut phase_rng = stream(5);
        let mut first_phase = 0.0;
        let mut n_phase = 0;
        for signal in s.disturbance.signals_mut() {
            signal.for_each_leaf_term_mut(&mut |term| {
                scale_term(term, amplitude);
                match term {
                    Term::Sine { phase, .. } | Term::Cosine { phase, .. } => {
                        if let Some(d) = &self.disturbance_phase {
                            let extra = d.sample(&mut phase_rng);
                            if n_phase == 0 {
                                first_phase = extra;
                            }
                            n_phase += 1;
                            *phase += extra;
                        }
                    }
                    _ => {}
                }
            });
        }
        if let Some(d) = &self.initial_position_offset {
            let mut rng = stream(6);
            for p in &mut s.initial_state.position {
                *p += d.sample(&mut rng);
            }
        }
        if let Some(d) = &self.initial_attitude_offset {
            let mut rng = stream(7);
            for a in &mut s.initial_state.attitude {
                *a += d.sample(&mut rng);
            }
        }
        let init = s.initial_state;
        let sampled = [
            truth.mass,
            s.payload.map_or(0.0, |p| p.mass),
            inertia_factor,
            drag_factor,
            amplitude,
            first_phase,
            init.position[0],
            init.position[1],
            init.position[2],
            init.attitude[0],
            init.attitude[1],
            init.attitude[2],
        ];
        (s, seed, sampled)
    }
}

/// Multiply a disturbance term's size by the drawn `amplitude` factor
/// (`disturbance_amplitude`): constants, step heights, sine and cosine
/// amplitudes, polynomial coefficients and waypoint values.
fn scale_term(term: &mut Term, amplitude: f64) {
    match term {
        Term::Constant { value } => *value *= amplitude,
        Term::Step { height, .. } => *height *= amplitude,
        Term::Sine { amplitude: a, .. } | Term::Cosine { amplitude: a, .. } => *a *= amplitude,
        Term::Polynomial { coefficients } => coefficients.iter_mut().for_each(|c| *c *= amplitude),
        Term::Waypoints(w) => w.scale(amplitude),
        Term::Piecewise { .. } => {} // never a leaf
    }
}

/// Apply one run's draws to the true vehicle `[vehicle]` (over `plant`,
/// the controllers' model its missing keys come from): the true mass
/// (`None`: not drawn), the inertia (diagonal or matrix) scaled by
/// `inertia_factor`, and the drag the model flies scaled by `drag_factor` —
/// Eq. 1's `K_f1`, `K_f2` on the paper model, the parasitic and rotor drag
/// on the rigid body. The controllers' `[plant]` is never touched.
fn draw_true_vehicle(
    v: &mut crate::vehicle::VehicleSettings,
    plant: &ftsmc_core::model::QuadrotorParams,
    mass: Option<f64>,
    inertia_factor: f64,
    drag_factor: f64,
) {
    use crate::vehicle::{Inertia, VehicleModel};
    if let Some(m) = mass {
        v.mass = Some(m);
    }
    v.inertia = Some(match v.inertia {
        Some(Inertia::Matrix(m)) => Inertia::Matrix(m.map(|row| row.map(|j| j * inertia_factor))),
        Some(Inertia::Diagonal(d)) => Inertia::Diagonal(d.map(|j| j * inertia_factor)),
        None => Inertia::Diagonal(plant.inertia.map(|j| j * inertia_factor)),
    });
    let scale = |k: [f64; 3]| k.map(|k| k * drag_factor);
    match v.model {
        VehicleModel::Paper => {
            v.drag_translational = Some(scale(v.drag_translational.unwrap_or(plant.drag_translational)));
            v.drag_rotational = Some(scale(v.drag_rotational.unwrap_or(plant.drag_rotational)));
        }
        VehicleModel::RigidBody => {
            v.parasitic_drag = v.parasitic_drag.map(scale);
            v.rotor_drag_xy = v.rotor_drag_xy.map(|k| k * drag_factor);
            v.rotor_drag_z = v.rotor_drag_z.map(|k| k * drag_factor);
        }
    }
}

/// The rigid-body truth parameters of a run whose true mass is drawn as
/// `mass` (`None`: not drawn) and whose inertia and drag are scaled by
/// `inertia_factor` and `drag_factor`, exactly as [`MonteCarloSpec::sample`]
/// builds them (payload not included).
fn drawn_rigid_body(
    base: &Scenario,
    mass: Option<f64>,
    inertia_factor: f64,
    drag_factor: f64,
) -> crate::vehicle::RigidBodyParams {
    let mut v = base.vehicle;
    draw_true_vehicle(&mut v, &base.plant, mass, inertia_factor, drag_factor);
    v.rigid_body(&base.plant)
}

/// Seed of run `index`: the first word of ChaCha8 stream `index` keyed by
/// the master seed.
pub fn run_seed(master: u64, index: u64) -> u64 {
    chacha_stream(master, index).next_u64()
}
