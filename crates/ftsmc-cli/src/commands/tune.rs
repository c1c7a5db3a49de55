//! `ftsmc tune`: CMA-ES gains for one controller on one scenario
//! (`ftsmc_sim::tune`), with a progress bar, `DIR/<scenario>/`:
//! `<controller>.tuned.toml`, `<controller>.history.csv`,
//! `<controller>.summary.json`, `<controller>.scenario.toml` and the
//! convergence figure `<controller>.convergence.{svg,png}`. Every file is
//! named after the controller and owned by the command `tune-<controller>`
//! (its manifest), so tuning a second controller into the same folder
//! keeps the first one's results. With several controllers (`-c a,b` or
//! `-c all`) each is tuned on the same budget and seed, then all tuned
//! gain sets are compared on the same held-out draws (paired: run `i` is
//! one draw for all of them) with the intervals and Holm-corrected paired
//! verdicts of `ftsmc compare` (`ftsmc_sim::batch::verdicts`), written to
//! `comparison.md` and `comparison.json` (owner `tune-comparison`).

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use ftsmc_sim::batch::verdicts::{intervals, pairwise, Intervals, Outcomes};
use ftsmc_sim::scenario::Scenario;
use ftsmc_sim::stats::rate::wilson;
use ftsmc_sim::tune::{tune, tuned_toml, OutcomeStats, TuneOptions, TuneResult};
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::json;

use crate::args::{controller_names, parse_mission, ConfidenceArgs, OutputArgs, ScenarioArgs, SeedArgs, ThreadsArgs};
use crate::console::{num, Table};
use crate::intervals::{interval_table, level_note, metre_cell, rate_cell, verdict_table};
use crate::intervals::{outcomes, stats_cells};
use crate::output::{provenance, ResultDir};
use crate::plot::{controller_color, write_figure, Figure, Panel, Rgb, Series};
use ftsmc_sim::analysis::missions::Mission;
use ftsmc_sim::registry::ControllerList;

/// Arguments of `ftsmc tune`.
#[derive(clap::Args)]
#[command(mut_arg("out", |a| a.default_value("results/tune")))]
#[command(mut_arg("no_figures", |a| a.help("Skip the convergence figure")))]
#[command(mut_arg("seed", |a| a.help("Seed of the search and of the Monte Carlo draws (default: the scenario's `seed`)")))]
pub struct Args {
    /// The scenario (its [tune] section, optional, narrows the parameters and sets the cost), `--set`, `--limit`.
    #[command(flatten)]
    scenario: ScenarioArgs,
    /// Controller to tune; a comma-separated list or `all` tunes each on an equal budget, then compares them on
    /// the same held-out draws.
    #[arg(long, short = 'c', value_parser = controller_names)]
    controller: String,
    /// The mission to tune for: `steps` (the scenario's own reference), `hover`, `figure-eight` or `waypoints`, as
    /// `compare --mission` flies it; the tuned file states it (`[tune] mission`).
    #[arg(long, default_value = "steps", value_parser = parse_mission)]
    mission: Mission,
    /// `--confidence`.
    #[command(flatten)]
    confidence: ConfidenceArgs,
    /// Training flights the search may fly per controller (the start's and the race's included).
    #[arg(long, allow_negative_numbers = true, default_value_t = ftsmc_sim::defaults::TUNE_BUDGET)]
    budget: u64,
    /// `--seed`.
    #[command(flatten)]
    seed: SeedArgs,
    /// `--threads`.
    #[command(flatten)]
    threads: ThreadsArgs,
    /// `--out`, `--no-figures`.
    #[command(flatten)]
    output: OutputArgs,
}

/// Runs `ftsmc tune`: every check before any flight, then each controller's tune.
pub fn run(args: Args) -> Result<()> {
    let scenario = ftsmc_sim::tune::mission_base(&args.scenario.load()?, args.mission)?;
    let controllers = controller_list(&args.controller)?;
    let confidence = args.confidence.checked()?;
    anyhow::ensure!(args.threads.threads != Some(0), "--threads must be at least 1");
    let settings = scenario.tune.clone().unwrap_or_default();
    ftsmc_sim::limits::check_batch(
        &scenario.flight_size(),
        args.budget.saturating_add(2 * settings.validation_runs),
        controllers.len(),
    )?;
    let threads = args.threads.checked(&scenario)?;
    let seed = args.seed.or_scenario(&scenario);
    let figures = args.output.figures();
    let request =
        Request { budget: args.budget, seed: Some(seed), threads, out: &args.output.out, figures, confidence };
    tune_all(&scenario, &args.scenario.scenario, &controllers, &request)
}

/// `-c`'s controllers: `all` (every registered controller that declares
/// tunable parameters — the Crazyflie firmware's `crazyflie-pid` and
/// `mellinger` declare none yet, so `all` leaves them out), or a
/// comma-separated list (duplicates dropped, order kept), refused by the
/// library's [`ControllerList::check_known`] when empty, when an entry is
/// empty (`-c pid,`) or names no controller.
pub fn controller_list(arg: &str) -> Result<Vec<String>> {
    let given: Vec<String> = if arg.trim() == "all" {
        ftsmc_sim::registry::CONTROLLERS
            .iter()
            .filter(|(n, _)| ftsmc_sim::controllers::tunable::parameters(n).is_ok_and(|p| !p.is_empty()))
            .map(|(n, _)| n.to_string())
            .collect()
    } else {
        arg.split(',').map(|c| c.trim().to_string()).collect()
    };
    ControllerList { argument: "-c/--controller", names: &given }.check_known()?;
    let mut out: Vec<String> = Vec::new();
    for c in given {
        if !out.contains(&c) {
            out.push(c);
        }
    }
    Ok(out)
}

/// What every tune of one `ftsmc tune` command shares.
pub struct Request<'a> {
    /// Training-flight budget per controller.
    pub budget: u64,
    /// Seed (`None`: the scenario's).
    pub seed: Option<u64>,
    /// Worker threads (`None`: all cores).
    pub threads: Option<usize>,
    /// Parent folder of the results.
    pub out: &'a Path,
    /// Write the convergence figures.
    pub figures: bool,
    /// Confidence level of every interval and verdict.
    pub confidence: f64,
}

/// The result-folder owner of `ftsmc tune -c <controller>`: one manifest per
/// controller, so tunes of different controllers into one folder each keep
/// their files (see `output.rs`).
pub fn owner(controller: &str) -> String {
    format!("tune-{controller}")
}

/// `<controller>.history.csv`: one row per evaluated candidate (generation 0 is the start).
pub fn history_csv(r: &TuneResult) -> Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    let mut head: Vec<String> =
        ["generation", "restart", "candidate", "role", "flights", "cost"].iter().map(|s| s.to_string()).collect();
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
            "margin_shortfall",
            "error",
        ]
        .iter()
        .map(|s| s.to_string()),
    );
    w.write_record(&head)?;
    for h in &r.history {
        let s = &h.stats;
        let mut row = vec![
            h.generation.to_string(),
            h.restart.to_string(),
            h.candidate.to_string(),
            h.role.name().to_string(),
            h.flights.to_string(),
            h.cost.to_string(),
        ];
        row.extend(h.values.iter().map(|v| v.to_string()));
        row.extend(
            [s.runs, s.success, s.completed, s.crashed, s.diverged, s.envelope_failures].iter().map(|v| v.to_string()),
        );
        row.extend(
            [
                s.rms_median,
                s.rms_p90,
                s.rms_p95,
                s.thrust_activity,
                s.torque_activity,
                s.saturated,
                s.divergence_score,
                s.margin_shortfall,
            ]
            .iter()
            .map(|v| v.to_string()),
        );
        row.push(h.error.clone().unwrap_or_default());
        w.write_record(&row)?;
    }
    w.into_inner().map_err(|e| anyhow::anyhow!("csv: {e}"))
}

/// The start-vs-tuned table of training, race and held-out statistics:
/// success with its Wilson interval, the RMS position error median with
/// its order-statistic interval (held-out; the training and race rows keep
/// no per-run values, and the 95 % interval of a median of 8 runs spans
/// all 8 anyway), at `confidence`.
pub fn comparison_table(r: &TuneResult, confidence: f64) -> String {
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
    let mut row = |name: &str, s: &OutcomeStats, held: Option<&Intervals>| {
        let success = wilson(s.success as u64, s.runs as u64, confidence)
            .map_or_else(|_| "—".to_string(), |i| format!("{}/{} {}", s.success, s.runs, rate_cell(&i)));
        let median = match held {
            Some(i) => metre_cell(i.rms_median.as_ref()),
            None => num(s.rms_median),
        };
        t.row(std::iter::once(name.to_string()).chain(stats_cells(s, success, median)).collect());
    };
    row("start, training", &r.training.start, None);
    row("tuned, training", &r.training.tuned, None);
    if let (Some(s0), Some(w)) = (r.race.first().and_then(|x| x.stats), r.best_raced().and_then(|x| x.stats)) {
        row("start, re-flown", &s0, None);
        row("tuned, re-flown", &w, None);
    }
    if let Some(h) = &r.held_out {
        let iv = held_intervals(r, confidence);
        row("start, held-out", &h.start, iv.as_ref().map(|i| &i[0]));
        row("tuned, held-out", &h.tuned, iv.as_ref().map(|i| &i[1]));
    }
    format!(
        "{}
{}
(training: {} draws per candidate, each generation its own; re-flown: the race's final, {} fresh training draws; held-out: {} draws the search never saw)",
        level_note(confidence),
        t.render(),
        r.settings.runs,
        r.race.first().and_then(|x| x.stats).map_or(0, |st| st.runs),
        r.held_out_indices.len()
    )
}

/// Intervals of the start's and the tuned gains' held-out flights.
pub fn held_intervals(r: &TuneResult, confidence: f64) -> Option<[Intervals; 2]> {
    let [a, b] = r.held_out_runs.as_ref()?;
    Some([intervals(&outcomes(a), confidence).ok()?, intervals(&outcomes(b), confidence).ok()?])
}

/// Each generation's share of failed candidates (invalid gains, or a
/// diverged or crashed training flight), in percent, and where the search
/// restarted (`|` after a generation).
pub fn failure_line(r: &TuneResult) -> String {
    let mut out = String::new();
    for g in &r.generations {
        out.push_str(&format!("{:.0}", 100.0 * g.failed as f64 / g.population.max(1) as f64));
        out.push_str(if g.restarted.is_some() { " | " } else { " " });
    }
    out.trim_end().to_string()
}

/// Run `ftsmc tune` for each of `controllers` (equal budgets, one seed)
/// and write `out/<scenario name>/`; with more than one, compare the tuned
/// gain sets on their common held-out draws.
fn tune_all(scenario: &Scenario, scenario_arg: &str, controllers: &[String], req: &Request<'_>) -> Result<()> {
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(t) = req.threads {
        builder = builder.num_threads(t);
    }
    let pool = builder.build().context("cannot start the thread pool")?;
    let seed = req.seed.unwrap_or(scenario.seed);
    let started = Instant::now();
    let mut results = Vec::new();
    let mut skipped = Vec::new();
    for controller in controllers {
        match tune_one(scenario, scenario_arg, controller, seed, req, &pool) {
            Ok(r) => results.push(r),
            // With several controllers one that cannot fly the vehicle is
            // skipped (no file written for it), the others tuned.
            Err(e) if controllers.len() > 1 && format!("{e:#}").contains(ftsmc_sim::tune::UNFIT_START) => {
                eprintln!("skipped: {e:#}");
                skipped.push(format!("{e:#}"));
            }
            Err(e) => return Err(e),
        }
        if controllers.len() > 1 {
            println!();
        }
    }
    if results.len() < 2 && !skipped.is_empty() {
        println!(
            "Bottom line: {} of {} controllers could fly {} from their start gains ({}); nothing to compare.",
            results.len(),
            controllers.len(),
            scenario.name,
            if results.is_empty() { "none".to_string() } else { results[0].controller.clone() }
        );
    }
    if results.len() > 1 {
        let folder = req.out.join(&scenario.name);
        let dir = ResultDir::begin(&folder, "tune-comparison")?;
        let (md, json) = comparison(scenario, &results, &skipped, req.budget, seed, req.confidence)?;
        dir.write("comparison.md", md.as_bytes())?;
        dir.write("comparison.json", serde_json::to_string_pretty(&json)?.as_bytes())?;
        dir.commit()?;
        println!("{md}");
        println!(
            "{} controllers tuned{} on {} in {:.1} s wall; wrote {}/comparison.{{md,json}}",
            results.len(),
            if skipped.is_empty() {
                String::new()
            } else {
                format!(" ({} skipped: start gains that do not fly)", skipped.len())
            },
            scenario.name,
            started.elapsed().as_secs_f64(),
            folder.display()
        );
    }
    Ok(())
}

/// The equal-budget comparison of the tuned gain sets on their common
/// held-out draws: intervals per controller and the paired verdicts of
/// every pair (Markdown, and the same as JSON).
pub fn comparison(
    scenario: &Scenario,
    results: &[TuneResult],
    skipped: &[String],
    budget: u64,
    seed: u64,
    confidence: f64,
) -> Result<(String, serde_json::Value)> {
    let mut named = Vec::new();
    for r in results {
        let Some([_, tuned]) = &r.held_out_runs else {
            anyhow::bail!("`tune.validation_runs` = 0: no held-out draws to compare the tuned controllers on");
        };
        named.push((r.controller.clone(), outcomes(tuned)));
    }
    let rows: Vec<(String, Intervals)> = named
        .iter()
        .map(|(n, o)| Ok((n.clone(), intervals(o, confidence)?)))
        .collect::<Result<_, ftsmc_sim::stats::StatsError>>()?;
    let refs: Vec<(String, &Outcomes)> = named.iter().map(|(n, o)| (n.clone(), o)).collect();
    let verdicts = pairwise(&refs, confidence)?;
    let runs = named.first().map_or(0, |(_, o)| o.runs());
    let bottom = bottom_line(&rows, &verdicts, results);
    let mut md = format!(
        "Tuned on {} with a budget of {budget} training flights each (seed {seed}), judged on the same {runs} held-out draws (paired).\n\n{}\n\n{}\n\nPaired verdicts (McNemar on success, Wilcoxon signed-rank on RMS position error; Holm over all {} tests):\n\n{}\n\n{bottom}\n",
        scenario.name,
        level_note(confidence),
        interval_table(&rows).render(),
        verdicts.len(),
        verdict_table(&verdicts).render()
    );
    for s in skipped {
        md.push_str(&format!("\nSkipped (no file written): {s}\n"));
    }
    let json = json!({
        "scenario": scenario.name,
        "budget": budget,
        "seed": seed,
        "confidence": confidence,
        "held_out_runs": runs,
        "controllers": rows.iter().map(|(n, i)| json!({"controller": n, "improved": results.iter().find(|r| &r.controller == n).map(|r| r.improved), "held_out": i})).collect::<Vec<_>>(),
        "verdicts": verdicts,
        "bottom_line": bottom,
        "skipped": skipped,
    });
    Ok((md, json))
}

/// The one conclusion of a multi-controller tune: the controller whose
/// tuned gains did best on the held-out draws (most successes, then the
/// lowest RMS median), its paired verdicts against the runner-up (the
/// tests named, Holm-adjusted over the whole table), and a flag for every
/// tuned file that is not better than its start on the headline.
pub fn bottom_line(
    rows: &[(String, Intervals)],
    verdicts: &[ftsmc_sim::batch::verdicts::PairVerdict],
    results: &[TuneResult],
) -> String {
    let rms = |i: &Intervals| i.rms_median.as_ref().map_or(f64::INFINITY, |m| m.estimate);
    let mut order: Vec<usize> = (0..rows.len()).collect();
    order.sort_by(|&a, &b| {
        rows[b].1.successes.cmp(&rows[a].1.successes).then(rms(&rows[a].1).total_cmp(&rms(&rows[b].1)))
    });
    let mut out = String::new();
    if let [best, second, ..] = order[..] {
        let (b, r) = (&rows[best], &rows[second]);
        let tests: Vec<String> = verdicts
            .iter()
            .filter(|v| (v.a == b.0 && v.b == r.0) || (v.a == r.0 && v.b == b.0))
            .map(|v| {
                let test = match v.test.metric {
                    ftsmc_sim::stats::paired::PairedMetric::Success => "McNemar on success",
                    _ => "Wilcoxon on RMS position error",
                };
                format!("{test}: {}, Holm p = {}", v.sentence(), crate::intervals::p_cell(v.p_holm))
            })
            .collect();
        let decided = verdicts.iter().any(|v| {
            ((v.a == b.0 && v.b == r.0) || (v.a == r.0 && v.b == b.0))
                && v.verdict != ftsmc_sim::stats::paired::Verdict::NoDifference
        });
        out.push_str(&format!(
            "Bottom line: {} did best on the held-out draws ({}/{} successes, RMS median {}); against the runner-up {} ({}/{}, {}): {}{}.",
            b.0,
            b.1.successes,
            b.1.runs,
            metre_cell(b.1.rms_median.as_ref()),
            r.0,
            r.1.successes,
            r.1.runs,
            metre_cell(r.1.rms_median.as_ref()),
            tests.join("; "),
            if decided { "" } else { " — no difference shown: the runs do not separate the two" }
        ));
    }
    for r in results {
        if let Some(h) = &r.held_out {
            if h.tuned.success < h.start.success {
                out.push_str(&format!(
                    "\nFlag: {}'s tuned gains succeed on fewer held-out draws ({}/{}) than its start ({}/{}).",
                    r.controller, h.tuned.success, h.tuned.runs, h.start.success, h.start.runs
                ));
            } else if !r.improved && r.best != 0 {
                out.push_str(&format!(
                    "\nFlag: {}'s tuned gains are not better than its start on the headline ({}).",
                    r.controller, r.improved_reason
                ));
            }
        }
    }
    out
}

/// Tune one controller and write its files into `out/<scenario name>/`.
fn tune_one(
    scenario: &Scenario,
    scenario_arg: &str,
    controller: &str,
    seed: u64,
    req: &Request<'_>,
    pool: &rayon::ThreadPool,
) -> Result<TuneResult> {
    let (budget, confidence, figures) = (req.budget, req.confidence, req.figures);
    let folder = req.out.join(&scenario.name);
    let dir = ResultDir::begin(&folder, &owner(controller))?;
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
    let cpu_before = crate::cpu::process_cpu_seconds();
    let result = pool.install(|| tune(scenario, &options, &|n| bar.inc(n))).map_err(anyhow::Error::msg)?;
    bar.finish_and_clear();
    let elapsed = started.elapsed().as_secs_f64();
    let cpu = match (cpu_before, crate::cpu::process_cpu_seconds()) {
        (Some(a), Some(b)) => Some(b - a),
        _ => None,
    };

    // As shell words: a path with a newline stays one line (and reads back).
    let args: Vec<String> = std::env::args_os().skip(1).map(|a| a.to_string_lossy().into_owned()).collect();
    let command = ftsmc_sim::escape::command_line(&[&["ftsmc".to_string()], args.as_slice()].concat());
    let text = tuned_toml(&result, built_in_base(scenario_arg).as_deref(), &command).map_err(anyhow::Error::msg)?;
    let tuned_name = format!("{controller}.tuned.toml");
    dir.write(&tuned_name, text.as_bytes())?;
    let history_name = format!("{controller}.history.csv");
    dir.write(&history_name, &history_csv(&result)?)?;
    let scenario_name = format!("{controller}.scenario.toml");
    let file = dir.write_scenario(&scenario_name, &result.start, &scenario_name)?;
    let best = result.best();
    let params: serde_json::Map<String, serde_json::Value> =
        result.space.dims.iter().zip(&best.values).map(|(d, v)| (d.name.clone(), json!(v))).collect();
    let flights = result.training_flights + result.race_flights + result.held_out_flights;
    let rate = |s: &OutcomeStats| wilson(s.success as u64, s.runs as u64, confidence).ok();
    let held = held_intervals(&result, confidence);
    let summary = json!({
        "scenario": scenario.name,
        "controller": controller,
        "budget": budget,
        "seed": seed,
        "confidence": confidence,
        "improved": result.improved,
        "improved_reason": result.improved_reason,
        "training_flights": result.training_flights,
        "race_flights": result.race_flights,
        "held_out_flights": result.held_out_flights,
        "seconds": elapsed,
        "cpu_seconds": cpu,
        "flights_per_second": flights as f64 / elapsed.max(1e-9),
        "flights_per_cpu_second": cpu.map(|c| flights as f64 / c.max(1e-9)),
        "settings": result.settings,
        "best": { "generation": best.generation, "candidate": best.candidate, "restart": best.restart, "cost": best.cost, "parameters": params },
        "start_cost": result.history[0].cost,
        "generations": result.generations,
        "race": result.race,
        "training": result.training,
        "training_success": { "start": rate(&result.training.start), "tuned": rate(&result.training.tuned) },
        "race_success": {
            "start": result.race.first().and_then(|r| r.stats.as_ref()).and_then(rate),
            "tuned": result.best_raced().and_then(|r| r.stats.as_ref()).and_then(rate),
        },
        "held_out": result.held_out,
        "held_out_intervals": held.as_ref().map(|[a, b]| json!({ "start": a, "tuned": b })),
        "training_run_indices": [result.training_indices.first(), result.training_indices.last()],
        "race_run_indices": [result.race_indices.first(), result.race_indices.last()],
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
        comparison_table(&result, confidence)
    );
    let html = crate::html::report(dir.path(), &format!("ftsmc tune {controller} on {}", scenario.name), &md)?;
    dir.write(format!("{controller}.report.html"), html.as_bytes())?;
    dir.commit()?;

    println!(
        "Tuned {controller} on {} ({} parameters, budget {budget} flights, seed {seed})\n",
        scenario.name,
        result.space.dims.len()
    );
    println!("{}", comparison_table(&result, confidence));
    println!(
        "\nfailed candidates per generation (%, `|` = restart): {}",
        if result.generations.is_empty() { "no generation flown".to_string() } else { failure_line(&result) }
    );
    println!(
        "\nchosen (generation {}, {}, training cost {:.4} on its generation's draws; start {:.4}{}):",
        best.generation,
        best.role.name(),
        best.cost,
        result.history[0].cost,
        match (result.best_raced().and_then(|w| w.cost), result.race.first().and_then(|s0| s0.cost)) {
            (Some(w), Some(s0)) => format!("; race final cost {w:.4}, start {s0:.4}"),
            _ => String::new(),
        }
    );
    for (d, v) in result.space.dims.iter().zip(&best.values) {
        println!("  {:<24} {}", d.name, num(*v));
    }
    println!(
        "\n{flights} flights ({} training, {} re-flown in the race, {} held-out) in {elapsed:.1} s ({:.0} flights/s{}); wrote {}/ ({tuned_name}, {history_name}, {controller}.summary.json, {scenario_name}, {controller}.report.html{})",
        result.training_flights,
        result.race_flights,
        result.held_out_flights,
        flights as f64 / elapsed.max(1e-9),
        cpu.map_or(String::new(), |c| format!(", {:.0} per CPU-second", flights as f64 / c.max(1e-9))),
        folder.display(),
        if figures { format!(", {controller}.convergence.{{svg,png}}") } else { String::new() }
    );
    if result.best == 0 {
        eprintln!(
            "warning: {controller} on {}: the search found nothing better than the start (the scenario's own gains, written back unchanged; `improved: false`). Try a larger --budget (now {budget}) or a smaller `[tune] sigma`.",
            scenario.name
        );
    } else if !result.improved {
        eprintln!(
            "warning: {controller} on {}: the chosen gains won on the cost but are not better than the start on the headline ({}); `improved: false` in {tuned_name}",
            scenario.name, result.improved_reason
        );
    }
    Ok(result)
}

/// The built-in scenario `arg` is, or the one its `extends` chain ends at:
/// what a tuned file extends (never a path, so the file can be moved).
pub fn built_in_base(arg: &str) -> Option<String> {
    let path = Path::new(arg);
    if !path.exists() {
        return ftsmc_sim::scenario::resolve::built_in(arg)
            .map(|_| arg.strip_suffix(".toml").unwrap_or(arg).to_string());
    }
    Scenario::load_with_warnings(path, &[]).ok()?.built_in_base.map(str::to_string)
}

/// Cost of every candidate and of the search distribution's mean (each on
/// its own generation's draws) against training flights.
fn write_convergence(r: &TuneResult, stem: &Path) -> Result<()> {
    use ftsmc_sim::tune::Role;
    let xs: Vec<f64> = r.history.iter().map(|h| h.flights as f64).collect();
    let costs: Vec<f64> = r.history.iter().map(|h| h.cost).collect();
    let means: Vec<&ftsmc_sim::tune::Evaluated> =
        r.history.iter().filter(|h| matches!(h.role, Role::Start | Role::Mean)).collect();
    let mean_xs: Vec<f64> = means.iter().map(|h| h.flights as f64).collect();
    let mean_costs: Vec<f64> = means.iter().map(|h| h.cost).collect();
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
                xs,
                ys: costs,
                color: Rgb(127, 127, 127),
                dashed: false,
                end: None,
            },
            Series {
                points: false,
                label: "mean of the search".into(),
                xs: mean_xs,
                ys: mean_costs,
                color,
                dashed: false,
                end: None,
            },
        ],
        log_x: false,
        log_y: true,
    };
    write_figure(&Figure { title: "ftsmc tune: convergence".into(), panels: vec![panel], columns: 1 }, stem)?;
    Ok(())
}
