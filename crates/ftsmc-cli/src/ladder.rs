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

/// `q`-quantile (0..1) of sorted values by linear interpolation; `None` if empty.
fn quantile(sorted: &[f64], q: f64) -> Option<f64> {
    match sorted.len() {
        0 => None,
        1 => Some(sorted[0]),
        n => {
            let x = q * (n - 1) as f64;
            let i = x.floor() as usize;
            let j = (i + 1).min(n - 1);
            Some(sorted[i] + (x - i as f64) * (sorted[j] - sorted[i]))
        }
    }
}

fn sorted(mut v: Vec<f64>) -> Vec<f64> {
    v.retain(|x| x.is_finite());
    v.sort_by(f64::total_cmp);
    v
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
    let rms = sorted(
        done.iter()
            .map(|r| (r.metrics.rms.x.powi(2) + r.metrics.rms.y.powi(2) + r.metrics.rms.z.powi(2)).sqrt())
            .collect(),
    );
    let saturated = sorted(rows.iter().filter_map(|r| r.metrics.saturation_fraction).collect());
    let thrust = sorted(done.iter().map(|r| r.metrics.chattering.thrust).collect());
    let torque = sorted(
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
        let times = sorted(diverged.iter().map(|d| d.0).collect());
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
            quantile(&times, 0.5).unwrap_or(f64::NAN)
        ));
    }
    if !crashed.is_empty() {
        let times = sorted(crashed.clone());
        why.push(format!("{} crashed (median {:.1} s)", crashed.len(), quantile(&times, 0.5).unwrap_or(f64::NAN)));
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
        rms_median: quantile(&rms, 0.5),
        rms_p95: quantile(&rms, 0.95),
        saturated: quantile(&saturated, 0.5),
        thrust_activity: quantile(&thrust, 0.5),
        torque_activity: quantile(&torque, 0.5),
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
        let spec = s.montecarlo.clone().unwrap_or_default();
        let rows = run_batch(
            s,
            &spec,
            &names,
            BatchOptions { progress: Some(&|n| bar.inc(n)), ..BatchOptions::new(runs, s.seed) },
        )
        .map_err(|e| anyhow!(e))?;
        flights += rows.len();
        dir.write(format!("beyond/ladder-runs/{}.csv", s.name), &crate::montecarlo::runs_csv(&rows)?)?;
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
    let mut order: Vec<usize> = (0..names.len()).filter(|&i| cells[i].rms_median.is_some()).collect();
    order.sort_by(|&a, &b| {
        cells[a].rms_median.unwrap_or(f64::INFINITY).total_cmp(&cells[b].rms_median.unwrap_or(f64::INFINITY))
    });
    let (Some(&a), Some(&b)) = (order.first(), order.get(1)) else {
        return format!("{rung}: fewer than two controllers completed a run");
    };
    let pair = [(names[a].clone(), &cells[a].outcomes), (names[b].clone(), &cells[b].outcomes)];
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
