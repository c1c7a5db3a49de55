//! Monte Carlo robustness: a scenario's `[montecarlo]` section declares
//! distributions for plant parameters, payload, disturbances and initial
//! state; each run draws its own values from generators derived from the
//! master seed and the run index only (never from thread state), so results
//! are identical whatever the thread count.

use rand::{Rng, RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution as _, LogNormal, Normal};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::metrics::Metrics;
use crate::scenario::Scenario;
use crate::signal::Term;
use crate::simulate::{ExitStatus, RunOptions};

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
                let v = LogNormal::new(mu, sigma).map(|d| d.sample(rng)).unwrap_or(mu.exp());
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
            Dist::LogNormal { mu, sigma, low, high } => {
                (clamp((mu - Z * sigma).exp(), low, high), clamp((mu + Z * sigma).exp(), low, high))
            }
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
}

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
        Ok(())
    }

    /// [`MonteCarloSpec::check`], then every draw against the physical range
    /// of the value it replaces in `base` — the same ranges as fixed values —
    /// using each distribution's [`Dist::support`]: a true mass > 0 (with the
    /// payload, whose draws need a `[payload]`), inertia factor > 0, drag
    /// factor >= 0, finite scaled inertia / drag / initial position, and an
    /// initial roll and pitch inside `simulation.max_tilt`.
    /// `Err((key, value, expected))`; the key names the distribution.
    pub fn check_against(&self, base: &Scenario) -> Result<(), (String, String, String)> {
        use crate::scenario::show;
        // After `check`, every support is finite (never NaN), so plain comparisons suffice.
        self.check().map_err(|(k, v, e)| (k, show(v), e.to_string()))?;
        let range = |(lo, hi): (f64, f64)| format!("draws in [{}, {}]", show(lo), show(hi));
        let err =
            |name: &str, d: &Dist, expected: String| Err((format!("montecarlo.{name}"), range(d.support()), expected));
        let truth = base.actual_plant.unwrap_or(base.plant);
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
        if let Some(d) = &self.initial_position_offset {
            let (lo, hi) = d.support();
            if base.initial_state.position.iter().any(|p| !((p + lo).is_finite() && (p + hi).is_finite())) {
                return err("initial_position_offset", d, "offsets giving a finite initial position".into());
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
        let seed = run_seed(master, index);
        let stream = |k: u64| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            rng.set_stream(100 + k);
            rng
        };
        let mut s = base.clone();
        s.seed = seed;
        let mut truth = s.actual_plant.unwrap_or(s.plant);
        if let Some(d) = &self.mass {
            truth.mass = d.sample(&mut stream(0));
        }
        if let (Some(d), Some(p)) = (&self.payload_mass, s.payload.as_mut()) {
            p.mass = d.sample(&mut stream(1));
        }
        let inertia_factor = self.inertia_factor.map_or(1.0, |d| d.sample(&mut stream(2)));
        for i in &mut truth.inertia {
            *i *= inertia_factor;
        }
        let drag_factor = self.drag_factor.map_or(1.0, |d| d.sample(&mut stream(3)));
        for k in truth.drag_translational.iter_mut().chain(truth.drag_rotational.iter_mut()) {
            *k *= drag_factor;
        }
        s.actual_plant = Some(truth);
        let amplitude = self.disturbance_amplitude.map_or(1.0, |d| d.sample(&mut stream(4)));
        let mut phase_rng = stream(5);
        let mut first_phase = 0.0;
        let mut n_phase = 0;
        for signal in [
            &mut s.disturbance.x,
            &mut s.disturbance.y,
            &mut s.disturbance.z,
            &mut s.disturbance.phi,
            &mut s.disturbance.theta,
            &mut s.disturbance.psi,
        ] {
            signal.for_each_leaf_term_mut(&mut |term| {
                match term {
                    Term::Constant { value } => *value *= amplitude,
                    Term::Step { height, .. } => *height *= amplitude,
                    Term::Sine { amplitude: a, phase, .. } | Term::Cosine { amplitude: a, phase, .. } => {
                        *a *= amplitude;
                        if let Some(d) = &self.disturbance_phase {
                            let extra = d.sample(&mut phase_rng);
                            if n_phase == 0 {
                                first_phase = extra;
                            }
                            n_phase += 1;
                            *phase += extra;
                        }
                    }
                    Term::Polynomial { coefficients } => coefficients.iter_mut().for_each(|c| *c *= amplitude),
                    Term::Waypoints(w) => w.scale(amplitude),
                    Term::Piecewise { .. } => {} // never a leaf
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

/// Seed of run `index`: the first word of ChaCha8 stream `index` keyed by
/// the master seed.
pub fn run_seed(master: u64, index: u64) -> u64 {
    let mut rng = ChaCha8Rng::seed_from_u64(master);
    rng.set_stream(index);
    rng.next_u64()
}

/// One row of a batch.
#[derive(Clone, Debug)]
pub struct McRun {
    /// Run index in the batch.
    pub index: u64,
    /// Seed of this run (drag noise and sampling).
    pub seed: u64,
    /// Sampled values ([`SAMPLED_COLUMNS`]).
    pub sampled: [f64; 12],
    /// Controller name.
    pub controller: String,
    /// Exit status.
    pub exit: ExitStatus,
    /// Metrics.
    pub metrics: Metrics,
    /// Completed and inside the scenario's `[envelope]` ([`RunOutput::success`](crate::RunOutput::success)).
    pub success: bool,
}

/// Fly `runs` randomised copies of `base` with each controller, in parallel
/// on the current rayon pool. `progress` receives control steps flown, from
/// inside each flight ([`RunOptions::progress`]); a batch adds up to
/// `runs × controllers × planned_steps(base)`.
/// The output order is (run index, controller) whatever the thread count.
pub fn run_batch(
    base: &Scenario,
    spec: &MonteCarloSpec,
    controllers: &[String],
    runs: u64,
    master_seed: u64,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Vec<McRun>, String> {
    for name in controllers {
        crate::registry::check_name(name)?;
    }
    let rows: Vec<Vec<McRun>> = (0..runs)
        .into_par_iter()
        .map(|index| {
            let (scenario, seed, sampled) = spec.sample(base, master_seed, index);
            controllers
                .iter()
                .map(|name| {
                    let options = RunOptions { record: false, progress: Some(progress) };
                    let out = crate::registry::run(name, &scenario, options).expect("controller names checked above");
                    McRun {
                        index,
                        seed,
                        sampled,
                        controller: name.clone(),
                        exit: out.exit,
                        success: out.success(),
                        metrics: out.metrics,
                    }
                })
                .collect()
        })
        .collect();
    Ok(rows.into_iter().flatten().collect())
}

/// Order statistics of one metric over the completed runs of a controller.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Stats {
    /// Median (nearest rank).
    pub median: f64,
    /// 5th percentile (nearest rank).
    pub p5: f64,
    /// 95th percentile (nearest rank).
    pub p95: f64,
    /// Largest value (worst for an error metric).
    pub worst: f64,
    /// Number of finite values the statistics are over.
    pub count: usize,
}

/// Nearest-rank statistics of the finite values (`None` if there are none).
pub fn stats(values: &[f64]) -> Option<Stats> {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let rank = |q: f64| v[((q * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1];
    Some(Stats { median: rank(0.5), p5: rank(0.05), p95: rank(0.95), worst: v[v.len() - 1], count: v.len() })
}

/// Per-controller summary of a batch.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ControllerSummary {
    /// Runs flown.
    pub runs: usize,
    /// Runs that diverged.
    pub diverged: usize,
    /// Runs that hit the ground too fast (`[ground]`).
    pub crashed: usize,
    /// Runs that completed but left the scenario's `[envelope]`.
    pub envelope_failures: usize,
    /// Fraction of runs that succeeded: completed and inside the
    /// `[envelope]` (without one: the fraction that completed).
    pub success_rate: f64,
    /// Fraction of runs that completed (no divergence, no crash).
    pub completed_rate: f64,
    /// Statistics of every metric over the completed runs (settling times:
    /// over the runs that settled).
    pub metrics: std::collections::BTreeMap<String, Stats>,
}

/// Summaries per controller, in the order the controllers were given.
pub fn summarize(rows: &[McRun], controllers: &[String]) -> Vec<(String, ControllerSummary)> {
    controllers
        .iter()
        .map(|name| {
            let mine: Vec<&McRun> = rows.iter().filter(|r| &r.controller == name).collect();
            let completed: Vec<&McRun> = mine.iter().copied().filter(|r| r.exit.is_completed()).collect();
            let mut metrics = std::collections::BTreeMap::new();
            if let Some(first) = completed.first() {
                let names: Vec<String> = first.metrics.flat().into_iter().map(|(n, _)| n).collect();
                let flats: Vec<Vec<(String, f64)>> = completed.iter().map(|r| r.metrics.flat()).collect();
                for (k, n) in names.iter().enumerate() {
                    let values: Vec<f64> = flats.iter().map(|f| f[k].1).collect();
                    if let Some(st) = stats(&values) {
                        metrics.insert(n.clone(), st);
                    }
                }
            }
            let runs = mine.len();
            let crashed = mine.iter().filter(|r| r.exit.is_crashed()).count();
            let diverged = runs - completed.len() - crashed;
            let successes = mine.iter().filter(|r| r.success).count();
            let envelope_failures = completed.iter().filter(|r| !r.success).count();
            let rate = |n: usize| if runs > 0 { n as f64 / runs as f64 } else { 0.0 };
            let (success_rate, completed_rate) = (rate(successes), rate(completed.len()));
            let summary =
                ControllerSummary { runs, diverged, crashed, envelope_failures, success_rate, completed_rate, metrics };
            (name.clone(), summary)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_rank_statistics() {
        let v: Vec<f64> = (1..=100).map(f64::from).chain([f64::NAN]).collect();
        let s = stats(&v).unwrap();
        assert_eq!((s.median, s.p5, s.p95, s.worst, s.count), (50.0, 5.0, 95.0, 100.0, 100));
        assert!(stats(&[f64::NAN]).is_none());
    }

    #[test]
    fn distributions_respect_their_bounds_and_are_seeded() {
        let d = Dist::Normal { mean: 1.0, std: 5.0, low: Some(0.5), high: Some(1.5) };
        let mut a = ChaCha8Rng::seed_from_u64(7);
        let mut b = ChaCha8Rng::seed_from_u64(7);
        for _ in 0..1000 {
            let x = d.sample(&mut a);
            assert!((0.5..=1.5).contains(&x));
            assert_eq!(x, d.sample(&mut b));
        }
        let u = Dist::Uniform { low: -2.0, high: 3.0 };
        let xs: Vec<f64> = (0..2000).map(|_| u.sample(&mut a)).collect();
        assert!(xs.iter().all(|x| (-2.0..=3.0).contains(x)));
        let mean = xs.iter().sum::<f64>() / xs.len() as f64;
        assert!((mean - 0.5).abs() < 0.1, "{mean}");
        assert!(Dist::Uniform { low: 1.0, high: 0.0 }.check().is_err());
        assert!(Dist::LogNormal { mu: 0.0, sigma: -1.0, low: None, high: None }.check().is_err());
    }

    #[test]
    fn run_seeds_depend_only_on_master_and_index() {
        assert_eq!(run_seed(1, 5), run_seed(1, 5));
        assert_ne!(run_seed(1, 5), run_seed(1, 6));
        assert_ne!(run_seed(1, 5), run_seed(2, 5));
    }
}
