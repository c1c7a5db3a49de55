//! `ftsmc montecarlo`: randomised batches in parallel, `runs.csv`,
//! `summary.json` and box plots.

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use ftsmc_sim::batch::montecarlo::{run_batch, summarize_at, BatchOptions, ControllerSummary, McRun, MonteCarloSpec};
use ftsmc_sim::batch::runs_table::runs_table;
use ftsmc_sim::batch::shard::Shard;
use ftsmc_sim::registry::label;
use ftsmc_sim::run::planned_steps;
use ftsmc_sim::scenario::Scenario;
use serde_json::{json, Map, Value};

use crate::console::{num, steps_bar, Table};
use crate::output::{provenance, ResultDir};
use crate::plot::{controller_color, write_boxplots, BoxGroup, BoxPanel};

/// `runs.csv` text: one row per (run, controller), in run order (the
/// columns of [`runs_table`], shared with the Python package). The integral
/// metrics of a diverged row cover `[0, duration]` (its last column) and
/// the `completed` column says whether that is the whole scenario;
/// `max_error_after_*` is empty when the run ended before
/// `steady_state_after` (`settling_time_*` is `NaN` when not settled).
pub fn runs_csv(rows: &[McRun]) -> Result<Vec<u8>> {
    let table = runs_table(rows);
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(&table.names)?;
    for row in 0..table.rows {
        w.write_record(table.record(row))?;
    }
    w.into_inner().map_err(|e| anyhow::anyhow!("csv: {e}"))
}

/// The printed table: statistics over the completed runs (a diverged run's
/// integrals cover a shorter span and would look better), with the count of
/// diverged runs; `— (all N diverged)` when none completed.
///
/// Two tables, each within 120 columns: success counts with the z and ψ
/// statistics, then the x and y statistics (median [p5, p95]).
pub fn mc_table(summaries: &[(String, ControllerSummary)]) -> String {
    let stat_cell = |s: &ControllerSummary, m: &str| {
        s.metrics.get(m).map_or_else(
            || match (s.diverged, s.crashed) {
                (0, 0) => "—".to_string(),
                (d, 0) => format!("— (all {d} diverged)"),
                (d, c) => format!("— (none completed: {d} diverged, {c} crashed)"),
            },
            |st| format!("{} [{}, {}]", num(st.median), num(st.p5), num(st.p95)),
        )
    };
    let mut a =
        Table::new(["controller", "diverged", "ISE z median [p5, p95]", "worst ISE z", "ISE ψ median [p5, p95]"]);
    let mut b = Table::new(["controller", "ISE x median [p5, p95]", "ISE y median [p5, p95]"]);
    for (name, s) in summaries {
        a.row(vec![
            label(name).to_string(),
            if s.crashed > 0 { format!("{} (+{} crashed)", s.diverged, s.crashed) } else { s.diverged.to_string() },
            stat_cell(s, "ise_z"),
            s.metrics.get("ise_z").map_or_else(|| stat_cell(s, "ise_z"), |st| num(st.worst)),
            stat_cell(s, "ise_psi"),
        ]);
        b.row(vec![label(name).to_string(), stat_cell(s, "ise_x"), stat_cell(s, "ise_y")]);
    }
    let mut md = String::from(
        "ISE ∫e² dt over the completed runs (m²·s; ψ rad²·s): median and the 5th and 95th percentiles of the runs (their spread, not an interval):\n\n",
    );
    md.push_str(&a.render());
    md.push('\n');
    md.push_str(&b.render());
    md
}

/// Every table of a batch, as printed and in report.md: the headline
/// (success and RMS position error with their intervals at `confidence`),
/// then the paper's ISE ([`mc_table`]).
pub fn tables(summaries: &[(String, ControllerSummary)], confidence: f64) -> String {
    let rows: Vec<(String, ftsmc_sim::batch::verdicts::Intervals)> =
        summaries.iter().map(|(n, s)| (n.clone(), s.intervals.clone())).collect();
    format!(
        "Headline: success and RMS position error √(rms_x² + rms_y² + rms_z²). {}\n\n{}\n{}",
        crate::intervals::level_note(confidence),
        crate::intervals::interval_table(&rows).render(),
        mc_table(summaries)
    )
}

/// How `ftsmc montecarlo` flies a batch (its flags).
#[derive(Clone, Copy, Debug)]
pub struct Options {
    /// Runs of the whole batch (each flown by every controller).
    pub runs: u64,
    /// Fly only this shard's block of the runs.
    pub shard: Option<Shard>,
    /// Worker threads (default: all cores).
    pub threads: Option<usize>,
    /// Flights each thread flies side by side.
    pub lanes: usize,
    /// Confidence level of every interval.
    pub confidence: f64,
    /// Write the box-plot figure.
    pub figures: bool,
}

/// Run a batch of `scenario` (its `controllers`, master seed `seed`) and
/// write its outputs to `out/<name>/`; with `shard` = K/N only that shard's
/// block of runs, to `out/<name>-shard-K-of-N/` (see [`crate::merge`]).
pub fn run(scenario: &Scenario, options: &Options, out: &Path) -> Result<()> {
    let Options { runs, shard, threads, lanes, confidence, figures } = *options;
    let controllers = &scenario.controllers;
    let seed = scenario.seed;
    let indices = shard.unwrap_or(Shard::WHOLE).range(runs)?;
    let folder = out.join(shard.map_or_else(|| scenario.name.clone(), |s| s.folder_name(&scenario.name)));
    // Refuse a bad --out before any flight.
    let dir = ResultDir::begin(&folder, "montecarlo")?;
    let spec = scenario.montecarlo.clone().unwrap_or_else(|| {
        eprintln!("note: {} has no [montecarlo] section; runs differ only in their seeds (drag noise)", scenario.name);
        MonteCarloSpec::default()
    });
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(t) = threads {
        builder = builder.num_threads(t);
    }
    let pool = builder.build().context("cannot start the thread pool")?;
    let flights = (indices.end - indices.start).saturating_mul(controllers.len() as u64);
    let bar = steps_bar(flights.saturating_mul(planned_steps(scenario)), flights);
    let started = Instant::now();
    let cpu_started = crate::cpu::process_cpu_seconds();
    let rows = pool
        .install(|| {
            run_batch(
                scenario,
                &spec,
                controllers,
                BatchOptions {
                    runs: indices.clone(),
                    master_seed: seed,
                    lanes,
                    progress: Some(&|n| bar.inc(n)),
                    cancel: None,
                },
            )
        })
        .map_err(|known| anyhow::anyhow!("unknown controller (known: {known})"))?;
    bar.finish_and_clear();
    let elapsed = started.elapsed().as_secs_f64();
    let cpu = crate::cpu::process_cpu_seconds().zip(cpu_started).map(|(end, start)| end - start);
    // Control steps flown: diverged and crashed runs stop early.
    let period = scenario.control_period();
    let steps: u64 = rows.iter().map(|r| (r.metrics.duration / period).round() as u64).sum();

    let csv = runs_csv(&rows)?;
    dir.write("runs.csv", &csv)?;
    // The resolved scenario, with the master seed and the controllers flown:
    // `ftsmc montecarlo <out>/<name>/scenario.toml --runs N` repeats the batch.
    let file = dir.write_scenario("scenario.toml", scenario, "scenario.toml")?;
    let summaries = summarize_at(&rows, controllers, confidence);
    let mut per_controller = Map::new();
    for (name, s) in &summaries {
        per_controller.insert(name.clone(), serde_json::to_value(s)?);
    }
    let mut summary = json!({
        "scenario": scenario.name,
        "runs": runs,
        "master_seed": seed,
        "confidence": confidence,
        "controllers": Value::Object(per_controller),
        "provenance": provenance(&[file]),
    });
    if let Some(shard) = shard {
        summary["shard"] = shard_json(shard, &indices);
        // `ftsmc merge` checks the rows against it.
        summary["shard"]["runs_csv_sha256"] = json!(crate::output::sha256_hex(&csv));
    }
    dir.write("summary.json", serde_json::to_string_pretty(&summary)?.as_bytes())?;

    if figures {
        let title = match shard {
            Some(k) => format!("runs {}–{} (shard {k}) of {}", indices.start, indices.end - 1, scenario.name),
            None => format!("{runs} runs of {}", scenario.name),
        };
        let completed: Vec<(&str, [f64; 4])> = rows
            .iter()
            .filter(|r| r.exit.is_completed())
            .map(|r| (r.controller.as_str(), [r.metrics.ise.x, r.metrics.ise.y, r.metrics.ise.z, r.metrics.ise.psi]))
            .collect();
        write_ise_boxplots(&title, controllers, &summaries, &completed, &dir.path().join("montecarlo-ise"))?;
    }
    let md = format!(
        "Monte Carlo: {} × {runs} runs of {} (master seed {seed}); every run's row is in [runs.csv](runs.csv).\n\n{}\n",
        controllers.len(),
        scenario.name,
        tables(&summaries, confidence)
    );
    let html = crate::html::report(dir.path(), &format!("ftsmc montecarlo {}", scenario.name), &md)?;
    dir.write("report.html", html.as_bytes())?;
    dir.commit()?;

    let what = match shard {
        Some(k) => format!("runs {}..{} (shard {k}) of {runs}", indices.start, indices.end),
        None => format!("{runs} runs"),
    };
    println!("Monte Carlo: {} × {what} of {} (seed {seed})\n", controllers.len(), scenario.name);
    println!("{}", tables(&summaries, confidence));
    println!(
        "\n{} flights, {:.2} M control steps in {elapsed:.2} s ({:.0} flights/s{}; {lanes} lane{} per thread, {}); wrote {}/ (runs.csv, summary.json, scenario.toml, report.html{})",
        rows.len(),
        steps as f64 / 1e6,
        rows.len() as f64 / elapsed.max(1e-9),
        crate::cpu::steps_per_cpu_second(steps, cpu),
        if lanes == 1 { "" } else { "s" },
        ftsmc_sim::isa::Isa::detect().name(),
        folder.display(),
        if figures { ", montecarlo-ise.{svg,png}" } else { "" }
    );
    Ok(())
}

/// The box plots of ISE x, y, z, ψ over the completed runs, one box per
/// controller: `completed` holds `(controller, [ISE x, y, z, ψ])` of every
/// completed row; written to `path.{svg,png}`.
pub fn write_ise_boxplots(
    what: &str,
    controllers: &[String],
    summaries: &[(String, ControllerSummary)],
    completed: &[(&str, [f64; 4])],
    path: &Path,
) -> Result<()> {
    {
        let panels: Vec<BoxPanel> = ["x", "y", "z", "psi"]
            .iter()
            .map(|axis| BoxPanel {
                title: format!("ISE {}", if *axis == "psi" { "ψ" } else { axis }),
                y_label: format!("ISE ({}), log scale", if *axis == "psi" { "rad²·s" } else { "m²·s" }),
                groups: controllers
                    .iter()
                    .map(|c| BoxGroup {
                        // Counts, not a rate: the rate's interval is in the tables.
                        label: summaries.iter().find(|(n, _)| n == c).map_or_else(
                            || label(c).to_string(),
                            |(_, s)| format!("{} ({}/{} ok)", label(c), s.intervals.successes, s.intervals.runs),
                        ),
                        values: completed
                            .iter()
                            .filter(|(name, _)| name == c)
                            .map(|(_, ise)| match *axis {
                                "x" => ise[0],
                                "y" => ise[1],
                                "z" => ise[2],
                                _ => ise[3],
                            })
                            .collect(),
                        color: controller_color(c),
                    })
                    .collect(),
                log_y: true,
            })
            .collect();
        write_boxplots(
            &format!("Monte Carlo — {what} (completed runs; boxes q1–q3, whiskers p5–p95)"),
            &panels,
            2,
            path,
        )?;
    }
    Ok(())
}

/// The `shard` object of a shard's `summary.json`: `index` K and `count` N
/// (`--shard K/N`) and the run indices it holds, `first_run` ..
/// `end_run` (end excluded).
pub fn shard_json(shard: Shard, indices: &std::ops::Range<u64>) -> Value {
    json!({"index": shard.index, "count": shard.count, "first_run": indices.start, "end_run": indices.end})
}
