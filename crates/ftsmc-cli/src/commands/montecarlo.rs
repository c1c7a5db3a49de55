//! `ftsmc montecarlo`: randomised batches in parallel, `runs.csv`,
//! `summary.json` and box plots.

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use ftsmc_sim::batch::montecarlo::{run_batch, summarize_at, BatchOptions, MonteCarloSpec};
use ftsmc_sim::batch::shard::Shard;
use ftsmc_sim::run::planned_steps;
use ftsmc_sim::scenario::Scenario;
use serde_json::{json, Map, Value};

use crate::args::{check_lanes, ConfidenceArgs, ControllersArgs, OutputArgs, ScenarioArgs, SeedArgs, ThreadsArgs};
use crate::campaign::{runs_csv, shard_json, tables, write_ise_boxplots};
use crate::console::steps_bar;
use crate::output::{provenance, ResultDir};

/// Arguments of `ftsmc montecarlo`.
#[derive(clap::Args)]
#[command(mut_arg("out", |a| a.default_value("results/montecarlo")))]
#[command(mut_arg("no_figures", |a| a.help("Skip the box-plot figure")))]
pub struct Args {
    /// The scenario, `--set`, `--limit`.
    #[command(flatten)]
    scenario: ScenarioArgs,
    /// Number of randomised runs (each flown by every controller).
    #[arg(long, allow_negative_numbers = true, default_value_t = ftsmc_sim::defaults::MONTECARLO_RUNS)]
    runs: u64,
    /// `--seed`.
    #[command(flatten)]
    seed: SeedArgs,
    /// `--threads`.
    #[command(flatten)]
    threads: ThreadsArgs,
    /// Flights each thread flies side by side in vector lanes: 1 or 4. Results do not depend on it.
    #[arg(long, allow_negative_numbers = true, default_value_t = ftsmc_sim::batch::montecarlo::DEFAULT_LANES)]
    lanes: usize,
    /// `-c`.
    #[command(flatten)]
    controllers: ControllersArgs,
    /// `--out`, `--no-figures`.
    #[command(flatten)]
    output: OutputArgs,
    /// Fly only shard K of N (a contiguous block of the runs) into `OUT/<name>-shard-K-of-N/`;
    /// `ftsmc merge` joins the N shards into the unsharded result (docs/campaigns.md).
    #[arg(long, value_name = "K/N")]
    shard: Option<Shard>,
    /// `--confidence` of every interval in the tables and summary.json (recorded there).
    #[command(flatten)]
    confidence: ConfidenceArgs,
}

/// Runs `ftsmc montecarlo`: every check before any flight, then [`fly_and_write`].
pub fn run(args: Args) -> Result<()> {
    let confidence = args.confidence.checked()?;
    let mut scenario = args.scenario.load()?;
    let names = args.controllers.or_scenario(&scenario)?;
    let runs = args.runs;
    anyhow::ensure!(runs >= 1, "--runs must be at least 1");
    anyhow::ensure!(args.threads.threads != Some(0), "--threads must be at least 1");
    // A shard is priced by the runs it flies.
    let own = args.shard.map_or(Ok(0..runs), |k| k.range(runs))?;
    ftsmc_sim::limits::check_batch(&scenario.flight_size(), own.end - own.start, names.len())?;
    ftsmc_sim::batch::gains_fit::check(&scenario, &names)?;
    let threads = args.threads.checked(&scenario)?;
    // The resolved scenario (scenario.toml) carries the master seed and
    // the controllers flown, so re-running it gives the same batch.
    scenario.seed = args.seed.or_scenario(&scenario);
    scenario.controllers = names;
    let lanes = check_lanes(args.lanes)?;
    let figures = args.output.figures();
    let options = Options { runs, shard: args.shard, threads, lanes, confidence, figures };
    fly_and_write(&scenario, &options, &args.output.out)
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
/// block of runs, to `out/<name>-shard-K-of-N/` (`ftsmc merge` joins them).
pub fn fly_and_write(scenario: &Scenario, options: &Options, out: &Path) -> Result<()> {
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
