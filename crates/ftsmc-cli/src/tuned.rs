//! The committed tuned gain files (`scenarios/tuned/`, made by `ftsmc tune`
//! with the command recorded in each) flown by `reproduce` beside the
//! controllers' default gains, on held-out Monte Carlo draws: the
//! equal-budget comparison table of docs/tuning.md. Nothing is re-tuned.

use anyhow::{Context, Result};
use ftsmc_sim::batch::verdicts::{intervals, metric_label, pairwise, Outcomes};
use ftsmc_sim::registry::label;
use ftsmc_sim::scenario::Scenario;
use ftsmc_sim::stats::paired::PairedMetric;
use ftsmc_sim::tune::{judge_flights, FlightOutcome, OutcomeStats};
use rayon::prelude::*;

use crate::console::{num, Table};
use crate::intervals::{effect_cell, level_note, metre_cell, p_cell, rate_cell};
use crate::intervals::{outcomes, stats_cells};

/// Held-out flights per gain set of docs/tuning.md's table (`reproduce --tuned-runs 200`; the default run flies none).
pub const DEFAULT_TUNED_RUNS: u64 = 200;

/// The training flights per candidate of the start the committed files were
/// tuned with (`[tune] runs` default): the held-out indices skip their seeds.
fn training_runs() -> u64 {
    ftsmc_sim::scenario::tune_section::TuneSection::default().runs
}

/// `(scenario, controller, tuned file text)` of every committed tuned file.
pub const TUNED_FILES: &[(&str, &str, &str)] = &[
    ("paper-scenario-1", "ftaftsmc", include_str!("../../../scenarios/tuned/paper-scenario-1-ftaftsmc.toml")),
    ("paper-scenario-1", "ranftsmc", include_str!("../../../scenarios/tuned/paper-scenario-1-ranftsmc.toml")),
    ("paper-scenario-1", "tsm-sta", include_str!("../../../scenarios/tuned/paper-scenario-1-tsm-sta.toml")),
    ("paper-scenario-1", "pid", include_str!("../../../scenarios/tuned/paper-scenario-1-pid.toml")),
    ("paper-scenario-1", "se3", include_str!("../../../scenarios/tuned/paper-scenario-1-se3.toml")),
    ("paper-scenario-2", "ftaftsmc", include_str!("../../../scenarios/tuned/paper-scenario-2-ftaftsmc.toml")),
    ("paper-scenario-2", "ranftsmc", include_str!("../../../scenarios/tuned/paper-scenario-2-ranftsmc.toml")),
    ("paper-scenario-2", "tsm-sta", include_str!("../../../scenarios/tuned/paper-scenario-2-tsm-sta.toml")),
    ("paper-scenario-2", "pid", include_str!("../../../scenarios/tuned/paper-scenario-2-pid.toml")),
    ("paper-scenario-2", "se3", include_str!("../../../scenarios/tuned/paper-scenario-2-se3.toml")),
    ("realistic-calm-1", "ftaftsmc", include_str!("../../../scenarios/tuned/realistic-calm-1-ftaftsmc.toml")),
    ("realistic-calm-1", "ranftsmc", include_str!("../../../scenarios/tuned/realistic-calm-1-ranftsmc.toml")),
    ("realistic-calm-1", "tsm-sta", include_str!("../../../scenarios/tuned/realistic-calm-1-tsm-sta.toml")),
    ("realistic-calm-1", "pid", include_str!("../../../scenarios/tuned/realistic-calm-1-pid.toml")),
    ("realistic-calm-1", "se3", include_str!("../../../scenarios/tuned/realistic-calm-1-se3.toml")),
    ("realistic-calm-2", "ftaftsmc", include_str!("../../../scenarios/tuned/realistic-calm-2-ftaftsmc.toml")),
    ("realistic-calm-2", "ranftsmc", include_str!("../../../scenarios/tuned/realistic-calm-2-ranftsmc.toml")),
    ("realistic-calm-2", "tsm-sta", include_str!("../../../scenarios/tuned/realistic-calm-2-tsm-sta.toml")),
    ("realistic-calm-2", "pid", include_str!("../../../scenarios/tuned/realistic-calm-2-pid.toml")),
    ("realistic-calm-2", "se3", include_str!("../../../scenarios/tuned/realistic-calm-2-se3.toml")),
    ("realistic-breeze-1", "ftaftsmc", include_str!("../../../scenarios/tuned/realistic-breeze-1-ftaftsmc.toml")),
    ("realistic-breeze-1", "ranftsmc", include_str!("../../../scenarios/tuned/realistic-breeze-1-ranftsmc.toml")),
    ("realistic-breeze-1", "tsm-sta", include_str!("../../../scenarios/tuned/realistic-breeze-1-tsm-sta.toml")),
    ("realistic-breeze-1", "pid", include_str!("../../../scenarios/tuned/realistic-breeze-1-pid.toml")),
    ("realistic-breeze-1", "se3", include_str!("../../../scenarios/tuned/realistic-breeze-1-se3.toml")),
    ("realistic-breeze-2", "ftaftsmc", include_str!("../../../scenarios/tuned/realistic-breeze-2-ftaftsmc.toml")),
    ("realistic-breeze-2", "ranftsmc", include_str!("../../../scenarios/tuned/realistic-breeze-2-ranftsmc.toml")),
    ("realistic-breeze-2", "tsm-sta", include_str!("../../../scenarios/tuned/realistic-breeze-2-tsm-sta.toml")),
    ("realistic-breeze-2", "pid", include_str!("../../../scenarios/tuned/realistic-breeze-2-pid.toml")),
    ("realistic-breeze-2", "se3", include_str!("../../../scenarios/tuned/realistic-breeze-2-se3.toml")),
    ("realistic-light-1", "ftaftsmc", include_str!("../../../scenarios/tuned/realistic-light-1-ftaftsmc.toml")),
    ("realistic-light-1", "ranftsmc", include_str!("../../../scenarios/tuned/realistic-light-1-ranftsmc.toml")),
    ("realistic-light-1", "tsm-sta", include_str!("../../../scenarios/tuned/realistic-light-1-tsm-sta.toml")),
    ("realistic-light-1", "pid", include_str!("../../../scenarios/tuned/realistic-light-1-pid.toml")),
    ("realistic-light-1", "se3", include_str!("../../../scenarios/tuned/realistic-light-1-se3.toml")),
    ("realistic-light-2", "ftaftsmc", include_str!("../../../scenarios/tuned/realistic-light-2-ftaftsmc.toml")),
    ("realistic-light-2", "ranftsmc", include_str!("../../../scenarios/tuned/realistic-light-2-ranftsmc.toml")),
    ("realistic-light-2", "tsm-sta", include_str!("../../../scenarios/tuned/realistic-light-2-tsm-sta.toml")),
    ("realistic-light-2", "pid", include_str!("../../../scenarios/tuned/realistic-light-2-pid.toml")),
    ("realistic-light-2", "se3", include_str!("../../../scenarios/tuned/realistic-light-2-se3.toml")),
    ("realistic-moderate-1", "ftaftsmc", include_str!("../../../scenarios/tuned/realistic-moderate-1-ftaftsmc.toml")),
    ("realistic-moderate-1", "ranftsmc", include_str!("../../../scenarios/tuned/realistic-moderate-1-ranftsmc.toml")),
    ("realistic-moderate-1", "tsm-sta", include_str!("../../../scenarios/tuned/realistic-moderate-1-tsm-sta.toml")),
    ("realistic-moderate-1", "pid", include_str!("../../../scenarios/tuned/realistic-moderate-1-pid.toml")),
    ("realistic-moderate-1", "se3", include_str!("../../../scenarios/tuned/realistic-moderate-1-se3.toml")),
    ("realistic-moderate-2", "ftaftsmc", include_str!("../../../scenarios/tuned/realistic-moderate-2-ftaftsmc.toml")),
    ("realistic-moderate-2", "ranftsmc", include_str!("../../../scenarios/tuned/realistic-moderate-2-ranftsmc.toml")),
    ("realistic-moderate-2", "tsm-sta", include_str!("../../../scenarios/tuned/realistic-moderate-2-tsm-sta.toml")),
    ("realistic-moderate-2", "pid", include_str!("../../../scenarios/tuned/realistic-moderate-2-pid.toml")),
    ("realistic-moderate-2", "se3", include_str!("../../../scenarios/tuned/realistic-moderate-2-se3.toml")),
];

/// One row of the table.
pub struct Row {
    /// Scenario name.
    pub scenario: String,
    /// Controller name.
    pub controller: String,
    /// Default gains on the held-out draws.
    pub default: OutcomeStats,
    /// Tuned gains on the same draws.
    pub tuned: OutcomeStats,
    /// The default gains' held-out flights, in run order (the pairing).
    pub default_runs: Vec<FlightOutcome>,
    /// The tuned gains' held-out flights, in run order.
    pub tuned_runs: Vec<FlightOutcome>,
    /// The tuned file holds the default gains (its search kept the start).
    pub kept_defaults: bool,
}

/// Fly every committed tuned file and its controller's default gains on
/// `runs` held-out draws each (seed: the scenario's); in file order.
pub fn fly(runs: u64) -> Result<Vec<Row>> {
    TUNED_FILES
        .par_iter()
        .map(|(scenario, controller, text)| {
            let (file, base_text) = ftsmc_sim::scenario::resolve::built_in(scenario)
                .with_context(|| format!("no built-in scenario `{scenario}`"))?;
            let mut base = Scenario::from_toml_str(base_text, file)?;
            base.controllers = vec![controller.to_string()];
            let path = format!("scenarios/tuned/{scenario}-{controller}.toml");
            let tuned = Scenario::from_toml_str(text, &path)?;
            let seed = base.seed;
            let fly = |s: &Scenario| {
                judge_flights(s, controller, seed, training_runs(), runs, &|_| {}).map_err(anyhow::Error::msg)
            };
            let (default_runs, tuned_runs) = (fly(&base)?, fly(&tuned)?);
            Ok(Row {
                scenario: scenario.to_string(),
                controller: controller.to_string(),
                default: OutcomeStats::of(&default_runs, base.duration),
                tuned: OutcomeStats::of(&tuned_runs, tuned.duration),
                default_runs,
                tuned_runs,
                kept_defaults: holds_defaults(text),
            })
        })
        .collect()
}

/// The cells of one gain set: success with its Wilson interval, completed,
/// crashed, RMS position error median with its order-statistic interval,
/// p95, activities, saturated fraction.
fn cells(s: &OutcomeStats, runs: &[FlightOutcome], confidence: f64) -> Vec<String> {
    let iv = intervals(&outcomes(runs), confidence).ok();
    let success = iv.as_ref().map_or_else(
        || format!("{}/{}", s.success, s.runs),
        |i| format!("{}/{} {}", s.success, s.runs, rate_cell(&i.success_rate)),
    );
    let median = iv.as_ref().map_or_else(|| num(s.rms_median), |i| metre_cell(i.rms_median.as_ref()));
    stats_cells(s, success, median)
}

/// Tuned FTAFTSMC against the best other tuned controller of `scenario`
/// (most held-out successes, then lowest median RMS position error):
/// McNemar on success and Wilcoxon on RMS position error over the paired
/// held-out draws, Holm over the two tests. `None` without FTAFTSMC or
/// another controller.
pub fn ftaftsmc_verdict(rows: &[Row], scenario: &str, confidence: f64) -> Option<String> {
    let of = |c: &str| rows.iter().find(|r| r.scenario == scenario && r.controller == c);
    let ours = of("ftaftsmc")?;
    let key = |r: &&Row| (r.tuned.success, std::cmp::Reverse(ordered(r.tuned.rms_median)));
    let best = rows.iter().filter(|r| r.scenario == scenario && r.controller != "ftaftsmc").max_by_key(key)?;
    // A scenario without random draws flies one flight `runs` times: a
    // paired test would count one comparison as many; its values instead.
    let one_flight = |r: &[FlightOutcome]| {
        r.windows(2).all(|w| w[0].rms.to_bits() == w[1].rms.to_bits() && w[0].success == w[1].success)
    };
    if one_flight(&ours.tuned_runs) && one_flight(&best.tuned_runs) {
        let (x, y) = (ours.tuned_runs.first()?, best.tuned_runs.first()?);
        let ok = |o: &FlightOutcome| if o.success { "succeeds" } else { "fails" };
        return Some(format!(
            "Tuned FTAFTSMC against the best other tuned controller ({}): no paired test, the held-out draws are one \
             deterministic flight flown {} times; on it tuned FTAFTSMC {} with an RMS position error of {} m, tuned {} {} \
             with {} m.",
            label(&best.controller),
            ours.tuned_runs.len(),
            ok(x),
            num(x.rms),
            label(&best.controller),
            ok(y),
            num(y.rms)
        ));
    }
    let (a, b) = (outcomes(&ours.tuned_runs), outcomes(&best.tuned_runs));
    let names = [("tuned ".to_string() + label("ftaftsmc"), &a), ("tuned ".to_string() + label(&best.controller), &b)];
    let refs: Vec<(String, &Outcomes)> = names.iter().map(|(n, o)| (n.clone(), *o)).collect();
    let v = pairwise(&refs, confidence).ok()?;
    let part = |m: PairedMetric| {
        v.iter().find(|p| p.test.metric == m).map(|p| {
            format!(
                "{} {} (p = {}, Holm {}): {}",
                metric_label(m),
                effect_cell(p),
                p_cell(p.test.p),
                p_cell(p.p_holm),
                p.sentence()
            )
        })
    };
    Some(format!(
        "Tuned FTAFTSMC against the best other tuned controller ({}), paired on the {} held-out draws, effect FTAFTSMC − {}: {}; {}.",
        label(&best.controller),
        a.runs(),
        label(&best.controller),
        part(PairedMetric::Success)?,
        part(PairedMetric::Error)?
    ))
}

/// A total order key for a median (NaN last).
fn ordered(x: f64) -> u64 {
    if x.is_finite() {
        x.max(0.0).to_bits()
    } else {
        u64::MAX
    }
}

/// The comparison table (Markdown), one per scenario, with intervals at
/// `confidence` and the verdict of tuned FTAFTSMC against the best other.
pub fn table(rows: &[Row], confidence: f64) -> String {
    let mut out = String::from(
        "Default and tuned gains on held-out draws (RMS position error in m, over the completed runs; U1 act. = thrust \
         activity, N/s; τ act. = torque activity, N·m/s; sat. = median saturated fraction of control periods). ",
    );
    out.push_str(&level_note(confidence));
    out.push('\n');
    let mut scenarios: Vec<&str> = rows.iter().map(|r| r.scenario.as_str()).collect();
    scenarios.dedup();
    for scenario in scenarios {
        let mut t = Table::new([
            "controller",
            "gains",
            "success",
            "completed",
            "crashed",
            "RMS med",
            "RMS p95",
            "U1 act.",
            "τ act.",
            "sat.",
        ]);
        let mut kept = false;
        for r in rows.iter().filter(|r| r.scenario == scenario) {
            let same = r.kept_defaults;
            kept |= same;
            let tuned = if same { "tuned (= default)" } else { "tuned" };
            for (gains, s, runs) in [("default", &r.default, &r.default_runs), (tuned, &r.tuned, &r.tuned_runs)] {
                t.row(
                    [r.controller.clone(), gains.to_string()].into_iter().chain(cells(s, runs, confidence)).collect(),
                );
            }
        }
        out.push_str(&format!("\n{scenario} ({}):\n\n", label_list(rows, scenario)));
        out.push_str(&t.render());
        if kept {
            out.push_str(
                "\n(= default): the search found nothing better than the default gains, so the tuned file holds \
                 them and its row repeats the default row. `—`: no run completed, so no RMS error.\n",
            );
        }
        if let Some(v) = ftaftsmc_verdict(rows, scenario, confidence) {
            out.push_str(&format!("\n{v}\n"));
        }
    }
    out
}

/// True when a tuned file's header says its search kept the start (`# The
/// search found nothing better than the start`; older files: a bare
/// `# Improved: false`, and those of the first tuner `# Best: generation
/// 0, candidate 0,`). A file whose chosen gains merely lost on the headline
/// (`# Improved: false (…)`) holds tuned gains.
fn holds_defaults(text: &str) -> bool {
    text.contains("# The search found nothing better than the start")
        || text.lines().any(|l| l.trim_end() == "# Improved: false")
        || text.contains("# Best: generation 0, candidate 0,")
}

/// The controllers' labels of `scenario`'s rows, comma-separated.
fn label_list(rows: &[Row], scenario: &str) -> String {
    rows.iter().filter(|r| r.scenario == scenario).map(|r| label(&r.controller)).collect::<Vec<_>>().join(", ")
}

/// `reproduce`'s tuned-gains section: fly the table with `runs` held-out
/// draws per gain set and write `beyond/tuned.md`; `None` (nothing flown)
/// when `runs` is 0 (`--realistic-runs 0`).
pub fn write(dir: &crate::output::ResultDir, runs: u64, confidence: f64) -> Result<Option<String>> {
    if runs == 0 {
        return Ok(None);
    }
    let rows = fly(runs)?;
    let mut md = String::from("# Tuned gains against default gains (held-out draws)\n\n");
    md.push_str("The files are `scenarios/tuned/<scenario>-<controller>.toml` (each records the `ftsmc tune` command that made it; nothing is re-tuned here). docs/tuning.md explains the method.\n\n");
    md.push_str(&table(&rows, confidence));
    dir.write("beyond/tuned.md", md.as_bytes())?;
    Ok(Some(table(&rows, confidence)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_tuned_row_equal_to_its_default_says_so_and_nan_reads_as_a_dash() {
        let stats = |rms: f64| OutcomeStats {
            runs: 4,
            success: 4,
            completed: 4,
            crashed: 0,
            diverged: 0,
            envelope_failures: 0,
            rms_median: rms,
            rms_p90: rms,
            rms_p95: rms,
            thrust_activity: 1.0,
            torque_activity: 0.1,
            saturated: 0.0,
            divergence_score: 0.0,
            margin_shortfall: 0.0,
        };
        let rows = vec![
            Row {
                scenario: "realistic-light-2".into(),
                controller: "tsm-sta".into(),
                default: stats(1.0),
                tuned: stats(1.0),
                default_runs: Vec::new(),
                tuned_runs: Vec::new(),
                kept_defaults: true,
            },
            Row {
                scenario: "realistic-light-2".into(),
                controller: "pid".into(),
                default: stats(f64::NAN),
                tuned: stats(0.5),
                default_runs: Vec::new(),
                tuned_runs: Vec::new(),
                kept_defaults: false,
            },
        ];
        let md = table(&rows, 0.95);
        assert!(
            md.contains("tuned (= default)") && md.contains("(= default): the search found nothing better"),
            "{md}"
        );
        assert_eq!(md.matches("tuned (= default)").count(), 1, "{md}");
        assert!(!md.contains("NaN") && md.contains("| —"), "{md}");
    }

    #[test]
    fn one_deterministic_flight_gets_its_values_and_random_draws_a_paired_test() {
        let flight = |rms: f64, success: bool| FlightOutcome {
            completed: true,
            crashed: false,
            success,
            time: 10.0,
            rms,
            thrust_activity: 1.0,
            torque_activity: 0.1,
            saturated: 0.0,
            margin: None,
        };
        let row = |controller: &str, runs: Vec<FlightOutcome>| {
            let stats = OutcomeStats::of(&runs, 10.0);
            Row {
                scenario: "s".into(),
                controller: controller.into(),
                default: stats,
                tuned: stats,
                default_runs: runs.clone(),
                tuned_runs: runs,
                kept_defaults: false,
            }
        };
        // The same flight 12 times each: values, no p-value.
        let rows = vec![row("ftaftsmc", vec![flight(0.258, true); 12]), row("pid", vec![flight(0.202, true); 12])];
        let v = ftaftsmc_verdict(&rows, "s", 0.95).unwrap();
        assert!(v.contains("no paired test") && v.contains("0.258") && v.contains("0.202"), "{v}");
        assert!(!v.contains("Holm"), "{v}");
        // Draws that differ: McNemar and Wilcoxon with Holm.
        let spread = |base: f64| (0..12).map(|i| flight(base + 0.01 * i as f64, i % 5 != 0)).collect();
        let rows = vec![row("ftaftsmc", spread(0.4)), row("pid", spread(0.2))];
        let v = ftaftsmc_verdict(&rows, "s", 0.95).unwrap();
        assert!(v.contains("Holm") && !v.contains("no paired test"), "{v}");
    }

    #[test]
    fn every_committed_tuned_file_loads_and_changes_only_its_controller() {
        for (scenario, controller, text) in TUNED_FILES {
            let tuned =
                Scenario::from_toml_str(text, "tuned.toml").unwrap_or_else(|e| panic!("{scenario}/{controller}: {e}"));
            assert_eq!(tuned.controllers, vec![controller.to_string()]);
            assert!(text.contains("# Made by: ftsmc tune"), "{scenario}/{controller}: no command recorded");
            let (file, base) = ftsmc_sim::scenario::resolve::built_in(scenario).unwrap();
            let base = Scenario::from_toml_str(base, file).unwrap();
            // A search that found nothing better than the defaults writes
            // them back (and says so); every other file changes the gains.
            if holds_defaults(text) {
                assert_eq!(tuned.gains, base.gains, "{scenario}/{controller}: the start is the best, yet gains differ");
            } else {
                assert_ne!(tuned.gains, base.gains, "{scenario}/{controller}: nothing tuned");
            }
            assert_eq!(tuned.plant, base.plant);
            assert_eq!(tuned.duration, base.duration);
        }
    }
}
