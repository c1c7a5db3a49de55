//! The `[tune]` section: what `ftsmc tune` searches and how it scores a
//! candidate (ignored by `run`, `montecarlo` and `reproduce`).
//!
//! The parameters themselves are declared with each controller
//! (`crate::controllers::tunable`); this section narrows that set
//! (`parameters`), moves bounds (`bounds`), adds gains of the controller's
//! own section (`[[tune.extra]]`, checked by
//! `crate::controllers::tunable::check_extra_key`) and holds the cost weights. docs/tuning.md explains
//! the cost; docs/scenarios.md lists every key.

use std::collections::BTreeMap;

use ftsmc_core::law::GainError;
use serde::{Deserialize, Serialize};

/// One extra tuned value: a gain of the tuned controller, by its dotted
/// path (`ftaftsmc.x.lambda`, `pid.rate_p.0` for element 0 of an array,
/// `cascade.command_filter.damping`), searched between `low` and `high`
/// starting from the value the scenario gives it.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ExtraParameter {
    /// Dotted key from the scenario root.
    pub key: String,
    /// Smallest value searched (units of the key).
    pub low: f64,
    /// Largest value searched (units of the key).
    pub high: f64,
    /// Search on `ln(value)` (default true; needs `low > 0`).
    #[serde(default = "yes")]
    pub log: bool,
}

fn yes() -> bool {
    true
}

/// The names `[tune] mission` takes: those of
/// `crate::analysis::missions::Mission` (which sits on a higher floor; a
/// test in `crate::tune` keeps the two lists equal).
pub const MISSIONS: [&str; 4] = ["steps", "hover", "figure-eight", "waypoints"];

/// `[tune] mission`: a name of [`MISSIONS`], refused otherwise with the value and the names.
fn mission_name<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<String>, D::Error> {
    let name = String::deserialize(d)?;
    if MISSIONS.contains(&name.as_str()) {
        Ok(Some(name))
    } else {
        Err(serde::de::Error::custom(format!("mission `{name}`: expected one of {}", MISSIONS.join(", "))))
    }
}

/// `[tune]`: parameter set, search settings and cost weights. Every key is
/// optional; the defaults are [`TuneSection::default`].
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct TuneSection {
    /// Names of the controller's declared parameters to tune (default: all
    /// of them); `[]` tunes only `extra`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub parameters: Option<Vec<String>>,
    /// `name = [low, high]`: new bounds for a declared parameter (factors
    /// on the scenario's own gains, like the declared ones).
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub bounds: BTreeMap<String, [f64; 2]>,
    /// Extra parameters: gains of the controller's own section, absolute values.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub extra: Vec<ExtraParameter>,
    /// Training flights per candidate and generation: fresh Monte Carlo
    /// draws each generation, the same for every entry of it (common random
    /// numbers). Default 8.
    pub runs: u64,
    /// Held-out flights that judge the start and the result (seeds the
    /// search never used). Default 200.
    pub validation_runs: u64,
    /// Initial CMA-ES step, as a fraction of each parameter's search range
    /// (log range for log parameters). Default (absent): one standard
    /// deviation is a factor of ×1.4 on a log parameter (every declared
    /// gain factor, `[[tune.extra]]` with `log = true`) and a tenth of the
    /// range on a linear one (`log = false`); see
    /// `crate::tune::space::DEFAULT_LOG_STEP`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sigma: Option<f64>,
    /// Candidates of the search re-flown on fresh training draws before the
    /// winner is chosen (racing; the start is always re-flown beside them):
    /// the runs' final means and the generations' best samples. Default 8;
    /// 0 takes the last generation's mean when it cost less on its draws
    /// than the start on its own.
    pub race: u64,
    /// Fresh training draws each raced candidate flies in the race's
    /// screening. Default 8.
    pub race_runs: u64,
    /// Further fresh training draws on which the start and the two best
    /// screened candidates are judged: the lowest cost on these alone
    /// wins. Default 32.
    pub race_final_runs: u64,
    /// CMA-ES population λ (default `4 + ⌊3 ln n⌋` for n parameters).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub population: Option<u64>,
    /// The mission the gains were tuned for (`ftsmc tune --mission`, and
    /// `mission=` of Python's `ftsmc.tune`): one of [`MISSIONS`], stated in
    /// the tuned file; absent means `steps`, the scenario's own reference
    /// (a file tuned without `--mission` has no such key). Informative:
    /// loading the file flies the reference the file holds.
    #[serde(skip_serializing_if = "Option::is_none", deserialize_with = "mission_name")]
    pub mission: Option<String>,
    /// Cost of a flight that diverged or crashed at time t of a flight of
    /// duration T: `divergence × (2 − t/T)`, averaged over the runs
    /// (default 1000).
    pub divergence: f64,
    /// Cost per run that completed outside the `[envelope]`, averaged over
    /// the runs (default 10).
    pub envelope: f64,
    /// Weight of the margin shortfall: the mean over the runs of how far
    /// each fell short of a robustness margin of a quarter of its binding
    /// `[envelope]` limit (`crate::tune::cost::MARGIN_TARGET`), per unit of
    /// that fraction (default 4).
    pub margin: f64,
    /// Weight of the 90th percentile of the completed runs' RMS position
    /// error `sqrt(rms_x² + rms_y² + rms_z²)`, per m (default 1).
    pub rms: f64,
    /// Weight of the median thrust activity (chattering index of U1, N/s),
    /// per N/s (default 0.002).
    pub thrust_activity: f64,
    /// Weight of the median torque activity (sum of the chattering indices
    /// of u2, u3, u4, N·m/s), per N·m/s (default 0.005).
    pub torque_activity: f64,
    /// Weight of the median fraction of control periods with a saturated
    /// mixer (0–1; default 1).
    pub saturated: f64,
}

impl Default for TuneSection {
    fn default() -> Self {
        Self {
            parameters: None,
            bounds: BTreeMap::new(),
            extra: Vec::new(),
            runs: 8,
            validation_runs: 200,
            sigma: None,
            race: 8,
            race_runs: 8,
            race_final_runs: 32,
            population: None,
            mission: None,
            divergence: 1000.0,
            envelope: 10.0,
            margin: 4.0,
            rms: 1.0,
            thrust_activity: 0.002,
            torque_activity: 0.005,
            saturated: 1.0,
        }
    }
}

impl TuneSection {
    /// Range checks: weights finite and ≥ 0, `1 <= runs <= 1e6`,
    /// `validation_runs <= 1e6`, `0 < sigma <= 1`, `race <= 100`,
    /// `1 <= race_runs, race_final_runs <= 1e6` when racing, `2 <= population <= 1000`,
    /// bounds and extra ranges finite with `low < high` (and `low > 0` on a
    /// log scale). `Err((dotted key below [tune], error))`.
    pub fn check(&self) -> Result<(), (String, GainError)> {
        let err = |key: &str, value: f64, expected: &'static str| {
            Err((key.to_string(), GainError { field: "", value, expected }))
        };
        for (key, w) in [
            ("divergence", self.divergence),
            ("envelope", self.envelope),
            ("margin", self.margin),
            ("rms", self.rms),
            ("thrust_activity", self.thrust_activity),
            ("torque_activity", self.torque_activity),
            ("saturated", self.saturated),
        ] {
            if !(w.is_finite() && w >= 0.0) {
                return err(key, w, "a finite weight >= 0");
            }
        }
        if !(1..=1_000_000).contains(&self.runs) {
            return err("runs", self.runs as f64, "1 <= runs <= 1e6");
        }
        if self.validation_runs > 1_000_000 {
            return err("validation_runs", self.validation_runs as f64, "0 <= validation_runs <= 1e6");
        }
        if let Some(sigma) = self.sigma {
            if !(sigma > 0.0 && sigma <= 1.0) {
                return err("sigma", sigma, "0 < sigma <= 1 (a fraction of each parameter's range)");
            }
        }
        if self.race > 100 {
            return err("race", self.race as f64, "0 <= race <= 100");
        }
        if self.race > 0 && !(1..=1_000_000).contains(&self.race_runs) {
            return err("race_runs", self.race_runs as f64, "1 <= race_runs <= 1e6");
        }
        if self.race > 0 && !(1..=1_000_000).contains(&self.race_final_runs) {
            return err("race_final_runs", self.race_final_runs as f64, "1 <= race_final_runs <= 1e6");
        }
        if let Some(p) = self.population {
            if !(2..=1000).contains(&p) {
                return err("population", p as f64, "2 <= population <= 1000");
            }
        }
        for (name, [lo, hi]) in &self.bounds {
            let key = format!("bounds.{name}");
            if !(lo.is_finite() && *lo > 0.0) {
                return err(&key, *lo, "a finite factor > 0 as low");
            }
            if !(hi.is_finite() && hi > lo) {
                return err(&key, *hi, "a finite high > low");
            }
        }
        for (i, e) in self.extra.iter().enumerate() {
            if !e.low.is_finite() || (e.log && e.low <= 0.0) {
                return err(&format!("extra[{i}].low"), e.low, "a finite value (> 0 when log = true)");
            }
            if !(e.high.is_finite() && e.high > e.low) {
                return err(&format!("extra[{i}].high"), e.high, "a finite high > low");
            }
        }
        Ok(())
    }
}
