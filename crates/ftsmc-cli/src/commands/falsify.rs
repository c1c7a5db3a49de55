//! `ftsmc falsify` and `ftsmc failure-probability`
//! (`ftsmc_sim::falsify`, docs/falsification.md).
//!
//! `falsify` writes `DIR/<scenario>/`: `<controller>.worst.toml` (the
//! worst case found, every searched value fixed: `ftsmc run` of it gives
//! the reported margin bit for bit), `<controller>.worst-random.toml` (the
//! worst of the uniform random draws), `<controller>.history.csv`,
//! `<controller>.summary.json` and the figure
//! `<controller>.worst.{svg,png}` (position error and tilt of the worst
//! flight beside the nominal one). `failure-probability` writes
//! `<controller>.failure-probability.json`. Every file is named after the
//! controller and owned by `falsify-<controller>` or
//! `failure-probability-<controller>`, so several controllers share a folder.

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use ftsmc_sim::falsify::search::{cmaes, random, History};
use ftsmc_sim::falsify::{margin_of, Problem};
use ftsmc_sim::run::RunOutput;
use ftsmc_sim::scenario::Scenario;
use ftsmc_sim::RunOptions;
use serde_json::json;

use crate::args::{check_budget, controller_names, pool, OutputArgs, ScenarioArgs, SeedArgs, ThreadsArgs};
use crate::console::num;
use crate::output::{provenance, ResultDir};
use crate::plot::{controller_color, write_figure, Figure, Panel, Rgb, Series};
use ftsmc_sim::registry::check_controllers;

/// Arguments of `ftsmc falsify`.
#[derive(clap::Args)]
#[command(mut_arg("out", |a| a.default_value("results/falsify")))]
#[command(mut_arg("no_figures", |a| a.help("Skip the worst-vs-nominal figure")))]
#[command(mut_arg("scenario", |a| a.help("Scenario file (TOML) or built-in name with a [falsify] section and an [envelope]")))]
#[command(mut_arg("seed", |a| a.help("Seed of the search (default: the scenario's `seed`); the turbulence seed is the scenario's, held fixed")))]
pub struct Args {
    /// The scenario, `--set`, `--limit`.
    #[command(flatten)]
    scenario: ScenarioArgs,
    /// Controller to falsify.
    #[arg(long, short = 'c', value_parser = controller_names)]
    controller: String,
    /// Flights per method (default: `[falsify] budget`, else 200).
    #[arg(long, allow_negative_numbers = true)]
    budget: Option<u64>,
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

/// Runs `ftsmc falsify`: every check before any flight, then both searches.
pub fn run(args: Args) -> Result<()> {
    let scenario = args.scenario.load()?;
    let controller = args.controller;
    check_controllers("-c/--controller", std::slice::from_ref(&controller))?;
    anyhow::ensure!(args.threads.threads != Some(0), "--threads must be at least 1");
    let budget = budget_of(&scenario, args.budget);
    check_budget(budget)?;
    ftsmc_sim::limits::check_batch(&scenario.flight_size(), budget.saturating_mul(2).saturating_add(3), 1)?;
    let threads = args.threads.checked(&scenario)?;
    let seed = args.seed.or_scenario(&scenario);
    search_and_write(&scenario, &controller, budget, seed, threads, &args.output.out, args.output.figures())
}

/// Flights of a search when neither `--budget` nor `[falsify] budget` says.
pub const DEFAULT_BUDGET: u64 = ftsmc_sim::defaults::FALSIFY_BUDGET;

/// The flights of a search: `--budget`, else `[falsify] budget`, else [`DEFAULT_BUDGET`].
pub fn budget_of(scenario: &Scenario, budget: Option<u64>) -> u64 {
    budget.or_else(|| scenario.falsify.as_ref().and_then(|f| f.budget)).unwrap_or(DEFAULT_BUDGET)
}

/// `<controller>.history.csv`: one row per flight of either search.
fn history_csv(problem: &Problem, searches: &[(&str, &History)]) -> Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    let mut head: Vec<String> = ["method", "flight", "restart", "margin"].iter().map(|s| s.to_string()).collect();
    head.extend(problem.params.iter().map(|p| p.name.clone()));
    w.write_record(&head)?;
    for (method, h) in searches {
        for e in &h.evaluations {
            let mut row = vec![method.to_string(), e.flight.to_string(), e.restart.to_string(), fmt(e.margin)];
            row.extend(problem.values(&e.point).iter().map(|v| fmt(*v)));
            w.write_record(&row)?;
        }
    }
    w.into_inner().map_err(|e| anyhow::anyhow!("csv: {e}"))
}

fn fmt(v: f64) -> String {
    crate::output::format_number(v)
}

/// What a search found, as summary.json has it.
fn search_json(problem: &Problem, h: &History) -> serde_json::Value {
    let point = |e: &ftsmc_sim::falsify::search::Evaluation| {
        let values: serde_json::Map<String, serde_json::Value> =
            problem.params.iter().zip(problem.values(&e.point)).map(|(p, v)| (p.name.clone(), json!(v))).collect();
        json!({ "flight": e.flight, "margin": e.margin, "parameters": values })
    };
    json!({
        "flights": h.evaluations.len(),
        "lowest": h.best().map(point),
        "first_violation": h.first_violation().map(point),
        "violations": h.violations(),
        "restarts": h.evaluations.last().map_or(0, |e| e.restart + 1),
    })
}

/// Run `ftsmc falsify` and write its result folder `out/<scenario name>/`.
#[allow(clippy::too_many_arguments)]
fn search_and_write(
    scenario: &Scenario,
    controller: &str,
    budget: u64,
    seed: u64,
    threads: Option<usize>,
    out: &Path,
    figures: bool,
) -> Result<()> {
    let problem = Problem::new(scenario, controller)?;
    let folder = out.join(&scenario.name);
    let dir = ResultDir::begin(&folder, &format!("falsify-{controller}"))?;
    let pool = pool(threads)?;
    let cpu0 = crate::cpu::process_cpu_seconds();
    let started = Instant::now();
    let search = pool.install(|| cmaes(&problem, budget, seed, Some(problem.nominal_point())));
    let search_seconds = started.elapsed().as_secs_f64();
    let search_cpu = crate::cpu::process_cpu_seconds().zip(cpu0).map(|(a, b)| a - b);
    let uniform = pool.install(|| random(&problem, budget, seed));
    let best = search.best().context("no flight of the search has a margin")?;
    let worst_values = problem.values(&best.point);
    let mut worst = problem.scenario(&worst_values);
    worst.name = format!("{}-{controller}-worst", scenario.name);
    let nominal_values = problem.values(&problem.nominal_point());
    let nominal = problem.scenario(&nominal_values);
    let record = RunOptions { record: true, ..Default::default() };
    let fly = |s: &Scenario| ftsmc_sim::registry::run(controller, s, record).map_err(anyhow::Error::msg);
    let (worst_flight, nominal_flight) = pool.install(|| (fly(&worst), fly(&nominal)));
    let (worst_flight, nominal_flight) = (worst_flight?, nominal_flight?);
    // The written file, read back and flown alone, must give the search's margin.
    let worst_text = crate::output::scenario_toml(&worst)?;
    let replay = Scenario::from_toml_str(&worst_text, "worst.toml")?;
    let replayed = margin_of(&pool.install(|| fly(&replay))?);
    anyhow::ensure!(
        replayed.to_bits() == best.margin.to_bits(),
        "internal error: the worst case replays to margin {replayed}, not {}",
        best.margin
    );
    let worst_name = format!("{controller}.worst.toml");
    let file = dir.write_scenario(&worst_name, &worst, &worst_name)?;
    if let Some(rb) = uniform.best() {
        let mut s = problem.scenario(&problem.values(&rb.point));
        s.name = format!("{}-{controller}-worst-random", scenario.name);
        dir.write_scenario(&format!("{controller}.worst-random.toml"), &s, "worst-random.toml")?;
    }
    dir.write(
        format!("{controller}.history.csv"),
        &history_csv(&problem, &[("cma-es", &search), ("random", &uniform)])?,
    )?;
    let summary = json!({
        "scenario": scenario.name,
        "controller": controller,
        "budget": budget,
        "search_seed": seed,
        "turbulence_seed": scenario.seed,
        "parameters": problem.params.iter().map(|p| json!({"name": p.name, "low": p.bounds.low, "high": p.bounds.high})).collect::<Vec<_>>(),
        "nominal": { "margin": margin_of(&nominal_flight), "margin_detail": nominal_flight.margin },
        "falsify": search_json(&problem, &search),
        "random": search_json(&problem, &uniform),
        "worst": { "file": worst_name, "margin": best.margin, "margin_detail": worst_flight.margin, "exit": worst_flight.exit.to_string() },
        "search_seconds": search_seconds,
        "search_cpu_seconds": search_cpu,
        "flights_per_cpu_second": search_cpu.map(|c| budget as f64 / c.max(1e-9)),
        "provenance": provenance(&[file]),
    });
    dir.write(format!("{controller}.summary.json"), serde_json::to_string_pretty(&summary)?.as_bytes())?;
    if figures {
        write_worst_figure(
            &problem,
            &nominal_flight,
            &worst_flight,
            &dir.path().join(format!("{controller}.worst.svg")),
        )?;
    }
    dir.commit()?;

    println!(
        "Falsified {controller} on {} ({} parameters, {budget} flights per method, search seed {seed}, turbulence seed {} held fixed)\n",
        scenario.name,
        problem.params.len(),
        scenario.seed
    );
    let line = |name: &str, h: &History| {
        let lowest = h.best().map_or("-".into(), |e| format!("{} (flight {})", num(e.margin), e.flight));
        let first =
            h.first_violation().map_or("none".into(), |e| format!("flight {} (margin {})", e.flight, num(e.margin)));
        println!(
            "  {name:<8} lowest margin {lowest:<28} first violation {first:<30} {} violating flights",
            h.violations()
        );
    };
    line("CMA-ES", &search);
    line("random", &uniform);
    println!("  nominal  margin {}", num(margin_of(&nominal_flight)));
    println!(
        "\nworst case ({}):",
        worst_flight.margin.map_or("-".into(), |m| format!("binds {} at {:.2} s", m.binds.as_str(), m.at))
    );
    for (p, v) in problem.params.iter().zip(&worst_values) {
        println!("  {:<24} {}", p.name, num(*v));
    }
    let rate =
        search_cpu.map_or(String::new(), |c| format!(", {:.1} flights per CPU-second", budget as f64 / c.max(1e-9)));
    println!(
        "\nsearch: {budget} flights in {search_seconds:.1} s{rate}; wrote {}/ ({worst_name}: `ftsmc run` of it reproduces margin {} bit for bit)",
        folder.display(),
        num(best.margin)
    );
    Ok(())
}

/// Position error and tilt of the nominal and the worst flight.
fn write_worst_figure(problem: &Problem, nominal: &RunOutput, worst: &RunOutput, stem: &Path) -> Result<()> {
    let env = problem.base.envelope.unwrap_or_default();
    let series = |o: &RunOutput, label: &str, color: Rgb| -> (Series, Series) {
        let r = &o.recording;
        let t = r.column("t").to_vec();
        let err: Vec<f64> = (0..r.len())
            .map(|k| {
                ["x", "y", "z"]
                    .iter()
                    .map(|a| (r.column(a)[k] - r.column(&format!("{a}_ref"))[k]).powi(2))
                    .sum::<f64>()
                    .sqrt()
            })
            .collect();
        let tilt: Vec<f64> = (0..r.len()).map(|k| r.column("phi")[k].abs().max(r.column("theta")[k].abs())).collect();
        let end = (!o.exit.is_completed()).then(|| o.exit.to_string());
        let s = |ys: Vec<f64>| Series {
            label: format!("{label} (margin {})", num(margin_of(o))),
            xs: t.clone(),
            ys,
            color,
            dashed: false,
            end: end.clone(),
            points: false,
        };
        (s(err), s(tilt))
    };
    let (ne, nt) = series(nominal, "nominal", Rgb(127, 127, 127));
    let (we, wt) = series(worst, "worst found", controller_color(&problem.controller));
    let t_end = problem.base.duration;
    let limit = |v: Option<f64>, from: f64, label: &str| {
        v.map(|v| Series {
            label: label.to_string(),
            xs: vec![from, t_end],
            ys: vec![v, v],
            color: Rgb(200, 0, 0),
            dashed: true,
            end: None,
            points: false,
        })
    };
    let mut p1 = vec![ne, we];
    p1.extend(limit(env.max_position_error, env.settle_after, "max_position_error"));
    let mut p2 = vec![nt, wt];
    p2.extend(limit(env.max_tilt, 0.0, "max_tilt"));
    let panel = |title: &str, y: &str, series| Panel {
        title: title.into(),
        x_label: "t (s)".into(),
        y_label: y.into(),
        series,
        log_x: false,
        log_y: false,
    };
    write_figure(
        &Figure {
            title: format!("ftsmc falsify: {} on {}", problem.controller, problem.base.name),
            panels: vec![panel("position error ‖p − p_d‖", "m", p1), panel("tilt max(|φ|, |θ|)", "rad", p2)],
            columns: 1,
        },
        stem,
    )?;
    Ok(())
}
