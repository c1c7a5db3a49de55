//! `ftsmc tune`: CMA-ES gains for one controller on one scenario
//! (`ftsmc_sim::tune`), with a progress bar, `DIR/<scenario>/`:
//! `<controller>.tuned.toml`, `<controller>.history.csv`,
//! `<controller>.summary.json`, `<controller>.scenario.toml` and the
//! convergence figure `<controller>.convergence.{svg,png}`. Every file is
//! named after the controller and owned by the command `tune-<controller>`
//! (its manifest), so tuning a second controller into the same folder
//! keeps the first one's results.

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use ftsmc_sim::scenario::Scenario;
use ftsmc_sim::tune::{tune, tuned_toml, FlightStats, TuneOptions, TuneResult};
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::json;

use crate::console::{num, stats_cells, Table};
use crate::output::{provenance, ResultDir};
use crate::plot::{controller_color, write_figure, Figure, Panel, Rgb, Series};

/// Default training-flight budget of `ftsmc tune`.
pub const DEFAULT_BUDGET: u64 = 2000;

/// The result-folder owner of `ftsmc tune -c <controller>`: one manifest per
/// controller, so tunes of different controllers into one folder each keep
/// their files (see `output.rs`).
pub fn owner(controller: &str) -> String {
    format!("tune-{controller}")
}

/// `<controller>.history.csv`: one row per evaluated candidate (generation 0 is the start).
pub fn history_csv(r: &TuneResult) -> Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    let mut head: Vec<String> = ["generation", "candidate", "flights", "cost"].iter().map(|s| s.to_string()).collect();
    head.extend(r.space.dims.iter().map(|d| d.name.clone()));
    head.extend(
        [
            "runs",
            "success",
            "completed",
            "crashed",
            "diverged",
            "envelope_failures",
            "rms_median",
            "rms_p90",
            "rms_p95",
            "thrust_activity",
            "torque_activity",
            "saturated",
            "divergence_score",
            "error",
        ]
        .iter()
        .map(|s| s.to_string()),
    );
    w.write_record(&head)?;
    for h in &r.history {
        let s = &h.stats;
        let mut row =
            vec![h.generation.to_string(), h.candidate.to_string(), h.flights.to_string(), h.cost.to_string()];
        row.extend(h.values.iter().map(|v| v.to_string()));
        row.extend(
            [s.runs, s.success, s.completed, s.crashed, s.diverged, s.envelope_failures].iter().map(|v| v.to_string()),
        );
        row.extend(
            [s.rms_median, s.rms_p90, s.rms_p95, s.thrust_activity, s.torque_activity, s.saturated, s.divergence_score]
                .iter()
                .map(|v| v.to_string()),
        );
        row.push(h.error.clone().unwrap_or_default());
        w.write_record(&row)?;
    }
    w.into_inner().map_err(|e| anyhow::anyhow!("csv: {e}"))
}

/// The start-vs-tuned table of training and held-out statistics.
pub fn comparison_table(r: &TuneResult) -> String {
    let mut t = Table::new([
        "gains, draws",
        "success",
        "completed",
        "crashed",
        "RMS median (m)",
        "RMS p95 (m)",
        "thrust act. (N/s)",
        "torque act. (N·m/s)",
        "saturated",
    ]);
    let mut row = |name: &str, s: &FlightStats| {
        t.row([name.to_string()].into_iter().chain(stats_cells(s)).collect());
    };
    row("start, training", &r.training.start);
    row("tuned, training", &r.training.tuned);
    if let Some(h) = &r.held_out {
        row("start, held-out", &h.start);
        row("tuned, held-out", &h.tuned);
    }
    t.render()
}

/// Run `ftsmc tune` and write its result folder `out/<scenario name>/`.
#[allow(clippy::too_many_arguments)]
pub fn run(
    scenario: &Scenario,
    scenario_arg: &str,
    controller: &str,
    budget: u64,
    seed: u64,
    threads: Option<usize>,
    out: &Path,
    figures: bool,
) -> Result<()> {
    let folder = out.join(&scenario.name);
    let dir = ResultDir::begin(&folder, &owner(controller))?;
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(t) = threads {
        builder = builder.num_threads(t);
    }
    let pool = builder.build().context("cannot start the thread pool")?;
    let settings = scenario.tune.clone().unwrap_or_default();
    let total = budget.saturating_add(2 * settings.validation_runs);
    let bar = ProgressBar::new(total);
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:30} {human_pos}/{human_len} flights (budget + held-out, {percent} %, eta {eta})",
        )
        .expect("valid template"),
    );
    let options = TuneOptions { controller: controller.to_string(), budget, seed };
    let started = Instant::now();
    let result = pool.install(|| tune(scenario, &options, &|n| bar.inc(n))).map_err(anyhow::Error::msg)?;
    bar.finish_and_clear();
    let elapsed = started.elapsed().as_secs_f64();
    let training_seconds = elapsed; // whole command; training share printed below

    // As shell words: a path with a newline stays one line (and reads back).
    let args: Vec<String> = std::env::args_os().skip(1).map(|a| a.to_string_lossy().into_owned()).collect();
    let command = ftsmc_sim::escape::command_line(&[&["ftsmc".to_string()], args.as_slice()].concat());
    // A file input is extended by its absolute path; a built-in by its name.
    let extends = if Path::new(scenario_arg).exists() {
        std::fs::canonicalize(scenario_arg)
            .map(|p| p.display().to_string())
            .unwrap_or_else(|_| scenario_arg.to_string())
    } else {
        scenario_arg.to_string()
    };
    let text = tuned_toml(&result, &extends, &command).map_err(anyhow::Error::msg)?;
    let tuned_name = format!("{controller}.tuned.toml");
    dir.write(&tuned_name, text.as_bytes())?;
    let history_name = format!("{controller}.history.csv");
    dir.write(&history_name, &history_csv(&result)?)?;
    let scenario_name = format!("{controller}.scenario.toml");
    let file = dir.write_scenario(&scenario_name, &result.start, &scenario_name)?;
    let best = result.best();
    let params: serde_json::Map<String, serde_json::Value> =
        result.space.dims.iter().zip(&best.values).map(|(d, v)| (d.name.clone(), json!(v))).collect();
    let summary = json!({
        "scenario": scenario.name,
        "controller": controller,
        "budget": budget,
        "seed": seed,
        "training_flights": result.training_flights,
        "held_out_flights": result.held_out_flights,
        "seconds": elapsed,
        "flights_per_second": (result.training_flights + result.held_out_flights) as f64 / elapsed.max(1e-9),
        "settings": result.settings,
        "best": { "generation": best.generation, "candidate": best.candidate, "cost": best.cost, "parameters": params },
        "start_cost": result.history[0].cost,
        "training": result.training,
        "held_out": result.held_out,
        "training_run_indices": result.training_indices,
        "held_out_run_indices": [result.held_out_indices.first(), result.held_out_indices.last()],
        "provenance": provenance(&[file]),
    });
    dir.write(format!("{controller}.summary.json"), serde_json::to_string_pretty(&summary)?.as_bytes())?;
    if figures {
        // The stem carries an extension of its own: `write_figure` swaps the
        // last one for svg/png, which must not eat `.convergence`.
        write_convergence(&result, &dir.path().join(format!("{controller}.convergence.svg")))?;
    }
    // One page per tuned controller: the folder is shared by the tunes of
    // every controller of the scenario.
    let md = format!(
        "Tuned {controller} on {} (budget {budget} flights, seed {seed}); the gains: [{tuned_name}]({tuned_name}).\n\n{}\n",
        scenario.name,
        comparison_table(&result)
    );
    let html = crate::html::report(dir.path(), &format!("ftsmc tune {controller} on {}", scenario.name), &md)?;
    dir.write(format!("{controller}.report.html"), html.as_bytes())?;
    dir.commit()?;

    println!(
        "Tuned {controller} on {} ({} parameters, budget {budget} flights, seed {seed})\n",
        scenario.name,
        result.space.dims.len()
    );
    println!("{}", comparison_table(&result));
    println!("\nbest (generation {}, cost {:.4}; start {:.4}):", best.generation, best.cost, result.history[0].cost);
    for (d, v) in result.space.dims.iter().zip(&best.values) {
        println!("  {:<24} {}", d.name, num(*v));
    }
    let flights = result.training_flights + result.held_out_flights;
    println!(
        "\n{flights} flights ({} training, {} held-out) in {training_seconds:.1} s ({:.0} flights/s); wrote {}/ ({tuned_name}, {history_name}, {controller}.summary.json, {scenario_name}, {controller}.report.html{})",
        result.training_flights,
        result.held_out_flights,
        flights as f64 / elapsed.max(1e-9),
        folder.display(),
        if figures { format!(", {controller}.convergence.{{svg,png}}") } else { String::new() }
    );
    Ok(())
}

/// Cost of every candidate and the best so far against training flights.
fn write_convergence(r: &TuneResult, stem: &Path) -> Result<()> {
    let xs: Vec<f64> = r.history.iter().map(|h| h.flights as f64).collect();
    let costs: Vec<f64> = r.history.iter().map(|h| h.cost).collect();
    let mut best = f64::INFINITY;
    let best_so_far: Vec<f64> = costs
        .iter()
        .map(|c| {
            best = best.min(*c);
            best
        })
        .collect();
    let color = controller_color(&r.controller);
    let panel = Panel {
        title: format!("{} on {}", r.controller, r.start.name),
        x_label: "training flights".into(),
        y_label: "cost, log scale".into(),
        series: vec![
            // Each candidate is an independent sample: a point, not a line.
            Series {
                points: true,
                label: "candidate".into(),
                xs: xs.clone(),
                ys: costs,
                color: Rgb(127, 127, 127),
                dashed: false,
                end: None,
            },
            Series { points: false, label: "best so far".into(), xs, ys: best_so_far, color, dashed: false, end: None },
        ],
        log_x: false,
        log_y: true,
    };
    write_figure(&Figure { title: "ftsmc tune: convergence".into(), panels: vec![panel], columns: 1 }, stem)?;
    Ok(())
}
