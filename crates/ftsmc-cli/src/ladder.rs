//! The wind ladder in `ftsmc reproduce`'s "Beyond the paper" part: a Monte
//! Carlo of every rung `realistic-<level>-<n>` (`ftsmc_sim::scenario::ladder`)
//! with every controller, and one table, controller × rung: success,
//! completed, crashed, median and p95 RMS position error, saturated time,
//! thrust and torque activity, and why the runs that failed failed.

use std::fmt::Write as _;

use anyhow::{anyhow, Result};
use ftsmc_sim::batch::montecarlo::{run_batch, BatchOptions, McRun};
use ftsmc_sim::registry::label;
use ftsmc_sim::run::{planned_steps, Divergence, ExitStatus};
use ftsmc_sim::scenario::ladder::LADDER;
use ftsmc_sim::scenario::Scenario;
use ftsmc_sim::stats::order::{finite_sorted, interpolated_quantile};
use rayon::prelude::*;
use serde_json::{json, Map, Value};

use crate::console::{steps_bar, Table};
use crate::output::ResultDir;

/// What [`ladder`] produced.
pub struct Ladder {
    /// The section's Markdown.
    pub markdown: String,
    /// `{"runs": N, "rungs": {"<scenario>": {"wind": {…}, "controllers": {"<controller>": {…}}}}}`.
    pub json: Value,
    /// Flights flown.
    pub flights: usize,
}

/// The per-(rung, controller) numbers of the table.
struct Cell {
    runs: usize,
    success: usize,
    completed: usize,
    crashed: usize,
    diverged: usize,
    rms_median: Option<f64>,
    rms_p95: Option<f64>,
    saturated: Option<f64>,
    thrust_activity: Option<f64>,
    torque_activity: Option<f64>,
    why: String,
    success_interval: ftsmc_sim::stats::Interval,
    rms_median_interval: Option<ftsmc_sim::stats::Interval>,
    outcomes: ftsmc_sim::batch::verdicts::Outcomes,
}

fn cell(rows: &[&McRun], conf: f64) -> Cell {
    let done: Vec<&&McRun> = rows.iter().filter(|r| r.exit.is_completed()).collect();
    let rms = finite_sorted(
        done.iter()
            .map(|r| (r.metrics.rms.x.powi(2) + r.metrics.rms.y.powi(2) + r.metrics.rms.z.powi(2)).sqrt())
            .collect(),
    );
    let saturated = finite_sorted(rows.iter().filter_map(|r| r.metrics.saturation_fraction).collect());
    let thrust = finite_sorted(done.iter().map(|r| r.metrics.chattering.thrust).collect());
    let torque = finite_sorted(
        done.iter()
            .map(|r| {
                r.metrics.chattering.roll_torque + r.metrics.chattering.pitch_torque + r.metrics.chattering.yaw_torque
            })
            .collect(),
    );
    let crashed: Vec<f64> = rows
        .iter()
        .filter_map(|r| if let ExitStatus::Crashed { time, .. } = r.exit { Some(time) } else { None })
        .collect();
    let diverged: Vec<(f64, &'static str)> = rows
        .iter()
        .filter_map(|r| match r.exit {
            ExitStatus::Diverged { divergence, time } => Some((
                time,
                match divergence {
                    Divergence::Tilt { .. } => "tilt",
                    Divergence::PositionError { .. } => "position",
                    Divergence::NonFinite => "non-finite",
                    _ => "other",
                },
            )),
            _ => None,
        })
        .collect();
    let success = rows.iter().filter(|r| r.success).count();
    let envelope = done.len() - done.iter().filter(|r| r.success).count();
    let mut why = Vec::new();
    if !diverged.is_empty() {
        let times = finite_sorted(diverged.iter().map(|d| d.0).collect());
        let tilt = diverged.iter().filter(|d| d.1 == "tilt").count();
        let kind = if tilt == diverged.len() {
            "tilt"
        } else if diverged.iter().all(|d| d.1 == "tilt" || d.1 == "position") {
            "tilt/position"
        } else {
            "tilt/position/other"
        };
        why.push(format!(
            "{} diverged ({kind}, median {:.1} s)",
            diverged.len(),
            interpolated_quantile(&times, 0.5).unwrap_or(f64::NAN)
        ));
    }
    if !crashed.is_empty() {
        let times = finite_sorted(crashed.clone());
        why.push(format!(
            "{} crashed (median {:.1} s)",
            crashed.len(),
            interpolated_quantile(&times, 0.5).unwrap_or(f64::NAN)
        ));
    }
    if envelope > 0 {
        why.push(format!("{envelope} left the envelope"));
    }
    let mut outcomes = ftsmc_sim::batch::verdicts::Outcomes::default();
    for r in rows {
        outcomes.push(
            r.success,
            r.exit.is_completed(),
            r.exit.is_crashed(),
            ftsmc_sim::batch::verdicts::rms_position_error(&r.metrics),
        );
    }
    let success_interval =
        ftsmc_sim::stats::rate::wilson(success as u64, rows.len() as u64, conf).expect("counts and level are valid");
    let rms_median_interval = ftsmc_sim::stats::order::quantile_interval(&rms, 0.5, conf).ok().flatten();
    Cell {
        success_interval,
        rms_median_interval,
        outcomes,
        runs: rows.len(),
        success,
        completed: done.len(),
        crashed: crashed.len(),
        diverged: diverged.len(),
        rms_median: interpolated_quantile(&rms, 0.5),
        rms_p95: interpolated_quantile(&rms, 0.95),
        saturated: interpolated_quantile(&saturated, 0.5),
        thrust_activity: interpolated_quantile(&thrust, 0.5),
        torque_activity: interpolated_quantile(&torque, 0.5),
        why: if why.is_empty() { "—".into() } else { why.join("; ") },
    }
}

fn opt(v: Option<f64>, digits: usize) -> String {
    v.map_or_else(|| "—".into(), |x| format!("{x:.digits$}"))
}

/// Fly `runs` Monte Carlo runs of every ladder rung with each of
/// `controllers` and write `beyond/ladder-runs/<scenario>.csv`; return the
/// table (Markdown) and its JSON. With `figures`, one box plot per rung
/// ([`crate::figures::montecarlo`]) under `figures/beyond/`.
pub fn ladder(dir: &ResultDir, runs: u64, controllers: &[&str], figures: bool, confidence: f64) -> Result<Ladder> {
    let names: Vec<String> = controllers.iter().map(|c| (*c).to_string()).collect();
    let scenarios: Vec<Scenario> = LADDER
        .iter()
        .map(|(file, text)| Scenario::from_toml_str(text, file).map_err(|e| anyhow!("{e}")))
        .collect::<Result<_>>()?;
    // Progress totals saturate instead of overflowing (absurd --realistic-runs
    // are refused by the pricing before any flight anyway).
    let per_rung = runs.saturating_mul(names.len() as u64);
    let total = scenarios.iter().fold(0u64, |t, s| t.saturating_add(per_rung.saturating_mul(planned_steps(s))));
    let bar = steps_bar(total, per_rung.saturating_mul(scenarios.len() as u64));
    eprintln!("beyond the paper: the wind ladder, {runs} runs of each of {} rungs per controller …", scenarios.len());
    let mut flights = 0;
    let mut table = Table::new([
        "rung",
        "controller",
        "success",
        "completed",
        "crashed",
        "RMS pos. err. median [interval] / p95 (m)",
        "saturated",
        "thrust activity (N/s)",
        "torque activity (N·m/s)",
        "why not",
    ]);
    let mut wind_table =
        Table::new(["rung", "in words", "mean wind (m/s)", "σ_u, σ_v, σ_w (m/s)", "u variance below 0.1 Hz"]);
    let mut rungs = Map::new();
    let mut verdict_lines: Vec<String> = Vec::new();
    // Each rung's runs, kept for its box plot: the plots are drawn after the
    // flights, in parallel (rasterising one takes about a second).
    let mut flown: Vec<Vec<McRun>> = Vec::new();
    for s in &scenarios {
        let rows = fly_rung(dir, "ladder-runs", s, &names, runs, &bar)?;
        flights += rows.len();
        let wind = s.wind.clone().unwrap_or_default().summary();
        if s.name.ends_with("-1") {
            wind_table.row(vec![
                s.name.trim_start_matches("realistic-").trim_end_matches("-1").to_string(),
                ftsmc_sim::scenario::ladder::rung_words(s).unwrap_or_default(),
                format!("{:.2}", wind.mean_speed),
                format!("{:.2}, {:.2}, {:.2}", wind.sigma[0], wind.sigma[1], wind.sigma[2]),
                wind.u_share_below_0_1_hz.map_or_else(|| "— (no turbulence)".into(), |x| format!("{:.0} %", 100.0 * x)),
            ]);
        }
        let mut per = Map::new();
        let cells: Vec<Cell> = names
            .iter()
            .map(|name| cell(&rows.iter().filter(|r| &r.controller == name).collect::<Vec<_>>(), confidence))
            .collect();
        verdict_lines.push(rung_verdict(&s.name, &names, &cells, confidence));
        for (name, c) in names.iter().zip(&cells) {
            table.row(vec![
                s.name.clone(),
                label(name).to_string(),
                crate::intervals::rate_cell(&c.success_interval),
                format!("{}/{}", c.completed, c.runs),
                c.crashed.to_string(),
                format!("{} / {}", crate::intervals::metre_cell(c.rms_median_interval.as_ref()), opt(c.rms_p95, 3)),
                c.saturated.map_or_else(|| "—".into(), |x| format!("{:.1} %", 100.0 * x)),
                opt(c.thrust_activity, 1),
                opt(c.torque_activity, 2),
                c.why.clone(),
            ]);
            per.insert(
                name.clone(),
                json!({"runs": c.runs, "successes": c.success, "completed": c.completed, "crashed": c.crashed,
                       "diverged": c.diverged, "median_rms_position_error": c.rms_median,
                       "p95_rms_position_error": c.rms_p95, "median_saturation_fraction": c.saturated,
                       "median_thrust_activity": c.thrust_activity, "median_torque_activity": c.torque_activity,
                       "why_not": c.why, "confidence": confidence,
                       "success_rate_interval": c.success_interval,
                       "median_rms_position_error_interval": c.rms_median_interval}),
            );
        }
        rungs.insert(
            s.name.clone(),
            json!({"envelope_max_position_error": s.envelope.and_then(|e| e.max_position_error),
                   "wind": {"in_words": ftsmc_sim::scenario::ladder::rung_words(s), "mean_speed": wind.mean_speed, "sigma": wind.sigma, "airspeed": wind.airspeed,
                            "u_share_below_0_1_hz": wind.u_share_below_0_1_hz},
                   "controllers": per}),
        );
        if figures {
            flown.push(rows);
        }
    }
    if figures {
        let folder = dir.path().join("figures").join("beyond");
        scenarios
            .par_iter()
            .zip(flown.par_iter())
            .try_for_each(|(s, rows)| crate::figures::montecarlo(s, rows, &names, &folder).map(|_| ()))?;
    }
    bar.finish_and_clear();
    let mut md = String::new();
    let _ = writeln!(
        md,
        "\n### The wind ladder: {runs} Monte Carlo runs per rung and controller\n\n\
         One vehicle (AscTec Hummingbird, PX4 mixer, motion capture 200 Hz/6 ms, IMU 1 kHz/1 ms) flies the paper's \
         scenario 1 (steps, `-1`) and 2 (helix, payload, disturbances, `-2`) in still air and in ever stronger wind \
         (`scenarios/realistic-<level>-<n>.toml`, each with its envelope argued in the file). Per run its own seed \
         (turbulence, sensor and motor noise) and its own mass, inertia and drag (and, in scenario 2, payload and \
         disturbances). Wind at 5 m (MIL-F-8785C; the Dryden airspeed is the mean wind):\n\n{}",
        wind_table.render()
    );
    let _ = writeln!(
        md,
        "RMS position error √(rms_x² + rms_y² + rms_z²) and activity (total variation per second, roll + pitch + yaw \
         torque) over the completed runs; saturated: median share of control periods in which the mixer saturated:\n\n{}",
        table.render()
    );
    let _ = writeln!(
        md,
        "Success with its {level} % Wilson interval, the median RMS position error with its distribution-free \
         {level} % interval. Rung by rung, the two controllers with the lowest median RMS position error, paired on the same \
         draws (Wilcoxon signed-rank on RMS position error, McNemar's exact test on success, Holm over both; \
         docs/statistics.md); `no difference shown` is where {runs} runs cannot decide:\n",
        level = crate::intervals::level_percent(confidence)
    );
    for line in &verdict_lines {
        let _ = writeln!(md, "- {line}");
    }
    Ok(Ladder {
        markdown: md,
        json: json!({"runs": runs, "confidence": confidence, "rungs": rungs, "verdicts": verdict_lines}),
        flights,
    })
}

/// The verdict line of one rung: the two controllers with the lowest
/// median RMS position error, paired.
fn rung_verdict(rung: &str, names: &[String], cells: &[Cell], confidence: f64) -> String {
    let contestants: Vec<_> = cells.iter().map(|c| (c.rms_median, &c.outcomes)).collect();
    pair_verdict(rung, names, &contestants, confidence)
}

/// The verdict line of the two contestants `(median RMS error, outcomes)`
/// with the lowest median, paired on the same draws.
fn pair_verdict(
    rung: &str,
    names: &[String],
    contestants: &[(Option<f64>, &ftsmc_sim::batch::verdicts::Outcomes)],
    confidence: f64,
) -> String {
    let mut order: Vec<usize> = (0..names.len()).filter(|&i| contestants[i].0.is_some()).collect();
    order.sort_by(|&a, &b| {
        contestants[a].0.unwrap_or(f64::INFINITY).total_cmp(&contestants[b].0.unwrap_or(f64::INFINITY))
    });
    let (Some(&a), Some(&b)) = (order.first(), order.get(1)) else {
        return format!("{rung}: fewer than two controllers completed a run");
    };
    let pair = [(names[a].clone(), contestants[a].1), (names[b].clone(), contestants[b].1)];
    match ftsmc_sim::batch::verdicts::pairwise(&pair, confidence) {
        Ok(v) => {
            let parts: Vec<String> = v
                .iter()
                .map(|v| {
                    let sentence = match v.verdict {
                        ftsmc_sim::stats::paired::Verdict::NoDifference => "no difference shown".to_string(),
                        _ => format!(
                            "{} better",
                            label(if v.verdict == ftsmc_sim::stats::paired::Verdict::ABetter { &v.a } else { &v.b })
                        ),
                    };
                    format!(
                        "{}: {sentence} (effect {}, Holm p = {})",
                        ftsmc_sim::batch::verdicts::metric_label(v.test.metric),
                        crate::intervals::effect_cell(v),
                        crate::intervals::p_cell(v.p_holm)
                    )
                })
                .collect();
            format!("{rung}, {} against {}: {}", label(&names[a]), label(&names[b]), parts.join("; "))
        }
        Err(e) => format!("{rung}: {e}"),
    }
}

/// The per-mission numbers of one (rung, mission, controller).
struct MissionCell {
    runs: usize,
    completed: usize,
    success_interval: ftsmc_sim::stats::Interval,
    rms_after: Vec<f64>,
    max_after: Vec<f64>,
    settled: Vec<f64>,
    outcomes: ftsmc_sim::batch::verdicts::Outcomes,
}

fn mission_cell(rows: &[&McRun], scenario: &Scenario, window: f64, conf: f64) -> MissionCell {
    use ftsmc_sim::analysis::missions::tracking;
    let limit = scenario.envelope.and_then(|e| e.max_position_error);
    let done: Vec<&&McRun> = rows.iter().filter(|r| r.exit.is_completed()).collect();
    let tracked: Vec<_> = done.iter().filter_map(|r| tracking(&r.metrics, r.margin.as_ref(), limit, window)).collect();
    let mut outcomes = ftsmc_sim::batch::verdicts::Outcomes::default();
    for r in rows {
        let rms = if r.exit.is_completed() {
            tracking(&r.metrics, r.margin.as_ref(), limit, window).map_or(f64::NAN, |t| t.rms_after)
        } else {
            f64::NAN
        };
        outcomes.push(r.success, r.exit.is_completed(), r.exit.is_crashed(), rms);
    }
    let success = rows.iter().filter(|r| r.success).count();
    MissionCell {
        runs: rows.len(),
        completed: done.len(),
        success_interval: ftsmc_sim::stats::rate::wilson(success as u64, rows.len() as u64, conf)
            .expect("counts and level are valid"),
        rms_after: finite_sorted(tracked.iter().map(|t| t.rms_after).collect()),
        max_after: finite_sorted(tracked.iter().filter_map(|t| t.max_after).collect()),
        settled: finite_sorted(tracked.iter().filter_map(|t| t.settle_time).collect()),
        outcomes,
    }
}

/// The median of sorted `values` with its distribution-free interval, as a cell (`—`: none).
fn median_cell(values: &[f64], conf: f64, digits: usize) -> (String, Option<ftsmc_sim::stats::Interval>) {
    let interval = ftsmc_sim::stats::order::quantile_interval(values, 0.5, conf).ok().flatten();
    (interval.as_ref().map_or_else(|| "—".into(), |i| i.display(digits)), interval)
}

/// Fly `runs` Monte Carlo runs of each scenario-1 rung of the ladder for
/// every mission but `steps` (`ftsmc_sim::analysis::missions`) with each of
/// `controllers`, write `beyond/mission-runs/<scenario>.csv`, and return
/// one table, rung × mission × controller: success, RMS position error
/// after the settling window, max deviation after it, time to settle
/// (each median with its interval), and per (rung, mission) the paired
/// verdict of the two lowest medians.
pub fn missions(
    dir: &ResultDir,
    runs: u64,
    controllers: &[&str],
    options: ftsmc_sim::analysis::missions::MissionOptions,
    confidence: f64,
) -> Result<Ladder> {
    use ftsmc_sim::analysis::missions::{mission_scenario, Mission};
    let names: Vec<String> = controllers.iter().map(|c| (*c).to_string()).collect();
    let mut scenarios = Vec::new();
    for (file, text) in LADDER.iter().filter(|(file, _)| file.ends_with("-1.toml")) {
        let rung = Scenario::from_toml_str(text, file).map_err(|e| anyhow!("{e}"))?;
        for mission in [Mission::Hover, Mission::FigureEight, Mission::Waypoints] {
            let s = mission_scenario(&rung, mission, options).map_err(|e| anyhow!("{e}"))?;
            scenarios.push((rung.clone(), mission, s));
        }
    }
    let per = runs.saturating_mul(names.len() as u64);
    let total = scenarios.iter().fold(0u64, |t, s| t.saturating_add(per.saturating_mul(planned_steps(&s.2))));
    let bar = steps_bar(total, per.saturating_mul(scenarios.len() as u64));
    eprintln!(
        "beyond the paper: missions on the ladder, {runs} runs of each of {} (rung, mission) per controller …",
        scenarios.len()
    );
    let mut table = Table::new([
        "rung",
        "mission",
        "controller",
        "success",
        "completed",
        "RMS pos. err. after window, median [interval] (m)",
        "max deviation after window (m)",
        "time to settle (s)",
        "settled",
    ]);
    let mut flights = 0;
    let mut verdict_lines = Vec::new();
    let mut json_rows = Vec::new();
    for (rung, mission, s) in &scenarios {
        let rows = fly_rung(dir, "mission-runs", s, &names, runs, &bar)?;
        flights += rows.len();
        let cells: Vec<MissionCell> = names
            .iter()
            .map(|name| {
                mission_cell(
                    &rows.iter().filter(|r| &r.controller == name).collect::<Vec<_>>(),
                    s,
                    options.window,
                    confidence,
                )
            })
            .collect();
        let words = ftsmc_sim::scenario::ladder::rung_title(rung).unwrap_or_else(|| rung.name.clone());
        let mut medians = Vec::new();
        for (name, c) in names.iter().zip(&cells) {
            let (rms, rms_i) = median_cell(&c.rms_after, confidence, 3);
            let (max, max_i) = median_cell(&c.max_after, confidence, 3);
            let (settle, settle_i) = median_cell(&c.settled, confidence, 2);
            medians.push(rms_i.map(|i| i.estimate));
            table.row(vec![
                words.clone(),
                mission.name().to_string(),
                label(name).to_string(),
                crate::intervals::rate_cell(&c.success_interval),
                format!("{}/{}", c.completed, c.runs),
                rms,
                max,
                settle,
                format!("{}/{}", c.settled.len(), c.completed),
            ]);
            json_rows.push(json!({"rung": rung.name, "rung_in_words": words, "mission": mission.name(),
                "scenario": s.name, "controller": name, "runs": c.runs, "completed": c.completed,
                "success_rate_interval": c.success_interval, "median_rms_after_window_interval": rms_i,
                "median_max_deviation_after_window_interval": max_i,
                "median_time_to_settle_interval": settle_i, "settled": c.settled.len()}));
        }
        let contestants: Vec<(Option<f64>, &ftsmc_sim::batch::verdicts::Outcomes)> =
            medians.iter().zip(&cells).map(|(m, c)| (*m, &c.outcomes)).collect();
        verdict_lines.push(pair_verdict(
            &format!("{} {}", rung.name, mission.name()),
            &names,
            &contestants,
            confidence,
        ));
    }
    bar.finish_and_clear();
    let mut md = String::new();
    let _ = writeln!(
        md,
        "\n### Missions on the ladder: {runs} Monte Carlo runs per rung, mission and controller\n\n\
         Each scenario-1 rung (`realistic-<level>-1`, its vehicle, sensors, wind, Monte Carlo draws and seed) flown \
         for a hover-hold (from rest at the steps' target), a figure-eight about it and a minimum-snap waypoint \
         mission (`ftsmc compare --mission`; docs/scenarios.md \"Missions\"). Tracking is measured after a \
         settling window of {} s: RMS of ‖p − p_d‖ over [{} s, end], the largest ‖p − p_d‖ after it, and the time \
         after which every position axis stays within {} m (`settled`: completed runs that settled). Success: \
         completed and inside the rung's envelope from {} s on. Each median with its distribution-free {level} % \
         interval, success with its Wilson interval:\n\n{}",
        ftsmc_sim::text::show(options.window),
        ftsmc_sim::text::show(options.window),
        ftsmc_sim::text::show(options.band),
        ftsmc_sim::text::show(options.window),
        table.render(),
        level = crate::intervals::level_percent(confidence)
    );
    let _ = writeln!(
        md,
        "Per rung and mission, the two controllers with the lowest median RMS error after the window, paired on the \
         same draws (Wilcoxon signed-rank on that RMS error, McNemar's exact test on success, Holm over both):\n"
    );
    for line in &verdict_lines {
        let _ = writeln!(md, "- {line}");
    }
    Ok(Ladder {
        markdown: md,
        json: json!({"runs": runs, "confidence": confidence, "window": options.window, "band": options.band,
                     "rows": json_rows, "verdicts": verdict_lines}),
        flights,
    })
}

/// Fly `names` through `runs` draws of `s` (its own `[montecarlo]` and
/// seed), ticking `bar`, and write the rows as `beyond/<folder>/<name>.csv`.
fn fly_rung(
    dir: &ResultDir,
    folder: &str,
    s: &Scenario,
    names: &[String],
    runs: u64,
    bar: &indicatif::ProgressBar,
) -> Result<Vec<McRun>> {
    let spec = s.montecarlo.clone().unwrap_or_default();
    let rows =
        run_batch(s, &spec, names, BatchOptions { progress: Some(&|n| bar.inc(n)), ..BatchOptions::new(runs, s.seed) })
            .map_err(|e| anyhow!(e))?;
    dir.write(format!("beyond/{folder}/{}.csv", s.name), &crate::campaign::runs_csv(&rows)?)?;
    Ok(rows)
}
