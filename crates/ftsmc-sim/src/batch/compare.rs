//! `ftsmc compare`: several contestants — a built-in controller, or the
//! controller section (gains and `[cascade]`) of another scenario or tuned
//! file — flown on one scenario's vehicle, wind and draws, with every
//! number's interval and every pair's verdict ([`super::verdicts`]).
//!
//! With a fixed number of runs the verdicts are the Holm-corrected tests
//! at `1 − confidence`. In the sequential mode ([`Plan::UntilDecided`])
//! runs are flown in batches and looked at after each batch; each look
//! spends its share of `α = 1 − confidence` (O'Brien–Fleming-type
//! Lan–DeMets spending over the planned looks,
//! [`crate::stats::sequential`]), so stopping as soon as every pair is
//! decided keeps the chance of any false verdict at most `α`.

use serde::Serialize;

use super::montecarlo::{run_batch, BatchOptions, McRun, MonteCarloSpec};
use super::verdicts::{intervals, pair_tests, pairwise, rms_position_error, Intervals, Outcomes, PairVerdict};
use crate::scenario::Scenario;
use crate::stats::paired::Verdict;
use crate::stats::sequential::Campaign;

/// One contestant: what it is called in the tables, the registered
/// controller it flies and the scenario it flies it in (the compared
/// scenario with the contestant's controller section).
#[derive(Clone, Debug)]
pub struct Contestant {
    /// Name in tables (`pid`, or [`file_label`] for a file: `pid (tuned,
    /// crazyflie-2, calm-1)`).
    pub name: String,
    /// Registered controller.
    pub controller: String,
    /// The compared scenario with this contestant's gains and `[cascade]`.
    pub scenario: Scenario,
}

impl Contestant {
    /// A built-in controller with `base`'s own gains.
    pub fn built_in(base: &Scenario, controller: &str) -> Self {
        Self { name: controller.to_string(), controller: controller.to_string(), scenario: base.clone() }
    }

    /// The controller section of `file` (its first controller, its gain
    /// sections and `[cascade]`) flown on `base`. Refused if `file`'s
    /// vehicle (`[plant]`, `[vehicle]`, `[actuators]`) differs from
    /// `base`'s, unless `allow_other_vehicle`: the error names the keys.
    pub fn from_file(base: &Scenario, name: &str, file: &Scenario, allow_other_vehicle: bool) -> Result<Self, String> {
        let controller = file
            .controllers
            .first()
            .ok_or_else(|| format!("{name}: `controllers` is empty: no controller to take"))?
            .clone();
        let differ = vehicle_differences(base, file);
        if !differ.is_empty() && !allow_other_vehicle {
            // The remedy first: a long list of keys must not push it past
            // the first line's 300 characters.
            let remedy = match file.vehicle.preset {
                Some(p) if base.vehicle.preset != Some(p) => {
                    format!("fly it on its vehicle (`--set vehicle.preset={}`)", p.name())
                }
                _ => "fly it on a scenario with its vehicle".to_string(),
            };
            let shown: Vec<&str> = differ.iter().take(3).map(String::as_str).collect();
            return Err(format!(
                "{name}: its vehicle differs from {}'s: {remedy}, or pass --allow-other-vehicle; differs at {}{}",
                base.name,
                shown.join(", "),
                if differ.len() > 3 { format!(" and {} more", differ.len() - 3) } else { String::new() }
            ));
        }
        let mut scenario = base.clone();
        scenario.gains = file.gains.clone();
        scenario.cascade = file.cascade;
        Ok(Self { name: file_label(name, &controller, file), controller, scenario })
    }
}

/// The table name of a file contestant: its controller, and what the
/// file's gains are (`tuned`), which vehicle preset they were made for and
/// on which scenario: `pid (tuned, crazyflie-2, calm-1)` for a file
/// `ftsmc tune` wrote (named `<scenario>[-<preset>]-<controller>-tuned`);
/// `pid (gains.toml)` (the file name) for any other file.
pub fn file_label(file_name: &str, controller: &str, file: &Scenario) -> String {
    let Some(tuned_on) = file.name.strip_suffix(&format!("-{controller}-tuned")) else {
        return format!("{controller} ({file_name})");
    };
    let mut parts = vec!["tuned".to_string()];
    let mut on = tuned_on;
    if let Some(p) = file.vehicle.preset {
        parts.push(p.name().to_string());
        on = on.strip_suffix(&format!("-{}", p.name())).unwrap_or(on);
    }
    let on = on.strip_prefix("realistic-").unwrap_or(on);
    if !on.is_empty() {
        parts.push(on.to_string());
    }
    format!("{controller} ({})", parts.join(", "))
}

/// The keys (`plant.mass`, `vehicle.inertia`, …) at which the vehicles of
/// two scenarios differ: `[plant]`, `[vehicle]` and `[actuators]`.
pub fn vehicle_differences(a: &Scenario, b: &Scenario) -> Vec<String> {
    let as_json = |s: &Scenario| {
        serde_json::json!({
            "plant": serde_json::to_value(s.plant).unwrap_or_default(),
            "vehicle": serde_json::to_value(s.vehicle).unwrap_or_default(),
            "actuators": serde_json::to_value(s.actuators).unwrap_or_default(),
        })
    };
    let mut out = Vec::new();
    diff("", &as_json(a), &as_json(b), &mut out);
    out
}

fn diff(path: &str, a: &serde_json::Value, b: &serde_json::Value, out: &mut Vec<String>) {
    use serde_json::Value;
    match (a, b) {
        (Value::Object(x), Value::Object(y)) => {
            let mut keys: Vec<&String> = x.keys().chain(y.keys()).collect();
            keys.sort();
            keys.dedup();
            for k in keys {
                let p = if path.is_empty() { k.clone() } else { format!("{path}.{k}") };
                diff(&p, x.get(k).unwrap_or(&Value::Null), y.get(k).unwrap_or(&Value::Null), out);
            }
        }
        _ if a != b => out.push(path.to_string()),
        _ => {}
    }
}

/// How many runs to fly.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Plan {
    /// Exactly this many.
    Fixed {
        /// Runs per contestant.
        runs: u64,
    },
    /// Batches of `batch` runs until every pair is decided, at most
    /// `max_runs`.
    UntilDecided {
        /// Runs per look.
        batch: u64,
        /// Most runs per contestant.
        max_runs: u64,
    },
}

/// One look of a sequential campaign.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Look {
    /// Runs per contestant at this look.
    pub runs: u64,
    /// Share of `α` this look spent.
    pub alpha_spent: f64,
    /// Pairs decided so far.
    pub pairs_decided: usize,
}

/// What [`compare`] found.
#[derive(Clone, Debug)]
pub struct Comparison {
    /// The confidence level of every interval and of the verdicts.
    pub confidence: f64,
    /// The plan flown.
    pub plan: Plan,
    /// Runs per contestant flown.
    pub runs: u64,
    /// Every row, contestant by contestant (controller field: the contestant's name).
    pub rows: Vec<McRun>,
    /// Each contestant's intervals, in the order given.
    pub intervals: Vec<(String, Intervals)>,
    /// Each pair's verdicts (success, then RMS position error).
    pub verdicts: Vec<PairVerdict>,
    /// The looks of a sequential campaign (empty with a fixed plan).
    pub looks: Vec<Look>,
    /// Every pair shows a difference on success or RMS position error.
    pub all_decided: bool,
}

fn outcomes_of(rows: &[McRun]) -> Outcomes {
    let mut o = Outcomes::default();
    for r in rows {
        o.push(r.success, r.exit.is_completed(), r.exit.is_crashed(), rms_position_error(&r.metrics));
    }
    o
}

/// Pairs decided: a pair (tests `2k`, `2k + 1`) counts once either test is.
fn pairs_decided(decided: &[Option<(Verdict, u64)>]) -> usize {
    decided.chunks(2).filter(|c| c.iter().any(Option::is_some)).count()
}

/// Fly `contestants` on `spec`'s draws of master seed `seed` by `plan`,
/// `lanes` flights side by side, and judge them at `confidence`.
/// Run `i` of every contestant flies the same draws.
#[allow(clippy::too_many_arguments)]
pub fn compare(
    contestants: &[Contestant],
    spec: &MonteCarloSpec,
    seed: u64,
    plan: Plan,
    confidence: f64,
    lanes: usize,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Comparison, String> {
    crate::stats::check_confidence(confidence).map_err(|e| e.to_string())?;
    if contestants.len() < 2 {
        return Err(format!("{} contestant(s): a comparison needs at least two", contestants.len()));
    }
    let mut rows: Vec<Vec<McRun>> = vec![Vec::new(); contestants.len()];
    let fly = |rows: &mut Vec<Vec<McRun>>, range: std::ops::Range<u64>| -> Result<(), String> {
        for (c, mine) in contestants.iter().zip(rows.iter_mut()) {
            let options =
                BatchOptions { runs: range.clone(), master_seed: seed, lanes, progress: Some(progress), cancel: None };
            let flown = run_batch(&c.scenario, spec, std::slice::from_ref(&c.controller), options)?;
            mine.extend(flown.into_iter().map(|mut r| {
                r.controller = c.name.clone();
                r
            }));
        }
        Ok(())
    };
    let named = |rows: &[Vec<McRun>]| -> Vec<(String, Outcomes)> {
        contestants.iter().zip(rows).map(|(c, r)| (c.name.clone(), outcomes_of(r))).collect()
    };
    let mut looks = Vec::new();
    let (runs, verdicts) = match plan {
        Plan::Fixed { runs } => {
            fly(&mut rows, 0..runs)?;
            let o = named(&rows);
            let refs: Vec<(String, &Outcomes)> = o.iter().map(|(n, x)| (n.clone(), x)).collect();
            (runs, pairwise(&refs, confidence).map_err(|e| e.to_string())?)
        }
        Plan::UntilDecided { batch, max_runs } => {
            if batch == 0 || max_runs == 0 {
                return Err("--until-decided needs a batch and a maximum of at least one run".into());
            }
            let pairs = contestants.len() * (contestants.len() - 1) / 2;
            let mut campaign = Campaign::new(2 * pairs, max_runs, 1.0 - confidence);
            let mut runs = 0;
            let mut last = Vec::new();
            while runs < max_runs {
                let next = (runs + batch).min(max_runs);
                fly(&mut rows, runs..next)?;
                runs = next;
                let o = named(&rows);
                let refs: Vec<(String, &Outcomes)> = o.iter().map(|(n, x)| (n.clone(), x)).collect();
                let tests = pair_tests(&refs, confidence).map_err(|e| e.to_string())?;
                let plain: Vec<_> = tests.iter().map(|t| t.2.clone()).collect();
                let spent = campaign.look(runs, &plain);
                let decided = pairs_decided(campaign.decided());
                looks.push(Look { runs, alpha_spent: spent, pairs_decided: decided });
                last = pairwise(&refs, confidence).map_err(|e| e.to_string())?;
                if decided == pairs {
                    break;
                }
            }
            // The verdicts are the campaign's: a test counts as decided
            // only if a look rejected it at that look's share of α.
            for (v, d) in last.iter_mut().zip(campaign.decided()) {
                v.verdict = d.map_or(Verdict::NoDifference, |(verdict, _)| verdict);
            }
            (runs, last)
        }
    };
    let all_decided = verdicts.chunks(2).all(|c| c.iter().any(|v| v.verdict != Verdict::NoDifference));
    let mut table = Vec::new();
    for (c, r) in contestants.iter().zip(&rows) {
        table.push((c.name.clone(), intervals(&outcomes_of(r), confidence).map_err(|e| e.to_string())?));
    }
    Ok(Comparison {
        confidence,
        plan,
        runs,
        rows: rows.into_iter().flatten().collect(),
        intervals: table,
        verdicts,
        looks,
        all_decided,
    })
}
