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
use ftsmc_sim::falsify::rare::{cross_entropy, plain, Estimate};
use ftsmc_sim::falsify::search::{cmaes, random, History};
use ftsmc_sim::falsify::{margin_of, Problem, RareProblem};
use ftsmc_sim::run::RunOutput;
use ftsmc_sim::scenario::Scenario;
use ftsmc_sim::RunOptions;
use serde_json::json;

use crate::console::num;
use crate::output::{provenance, ResultDir};
use crate::plot::{controller_color, write_figure, Figure, Panel, Rgb, Series};

/// Flights of a search when neither `--budget` nor `[falsify] budget` says.
pub const DEFAULT_BUDGET: u64 = ftsmc_sim::defaults::FALSIFY_BUDGET;

/// The flights of a search: `--budget`, else `[falsify] budget`, else [`DEFAULT_BUDGET`].
pub fn budget_of(scenario: &Scenario, budget: Option<u64>) -> u64 {
    budget.or_else(|| scenario.falsify.as_ref().and_then(|f| f.budget)).unwrap_or(DEFAULT_BUDGET)
}

/// Refuse a budget of 0 or above the limit before anything flies.
pub fn check_budget(budget: u64) -> Result<()> {
    use ftsmc_sim::scenario::falsify_section::MAX_BUDGET;
    anyhow::ensure!(
        (1..=MAX_BUDGET).contains(&budget),
        "--budget {budget}: expected 1 to {MAX_BUDGET} flights (a search needs at least one flight)"
    );
    Ok(())
}

/// The flights `ftsmc failure-probability` may fly within `max_flights`
/// (for splitting: `max_flights − plain`, its budget; otherwise `budget`),
/// or the refusal of work that cannot finish within it: cross-entropy and
/// plain Monte Carlo fly `budget + plain` flights; splitting at least its
/// `particles · repetitions` first flights plus `plain` (its branches then
/// stop at `max_flights`, which flags the estimate unreliable).
pub fn check_max_flights(
    method: Method,
    budget: u64,
    particles: usize,
    repetitions: usize,
    plain: u64,
    max_flights: u64,
) -> Result<u64> {
    let (needed, what) = match method {
        Method::Splitting => (
            (particles as u64).saturating_mul(repetitions as u64).saturating_add(plain),
            format!(
                "{repetitions} repetitions of {particles} particles start with {} flights",
                particles * repetitions
            ),
        ),
        Method::CrossEntropy | Method::Plain => (budget.saturating_add(plain), format!("--budget {budget}")),
    };
    let plain_note = if plain > 0 { format!(" and --plain {plain}") } else { String::new() };
    anyhow::ensure!(
        needed <= max_flights,
        "--max-flights {max_flights}: {what}{plain_note}, {needed} flights in all, more than the limit; \
         raise it with --max-flights {needed} (or more) or ask for less work"
    );
    Ok(if method == Method::Splitting { max_flights - plain } else { budget })
}

fn pool(threads: Option<usize>) -> Result<rayon::ThreadPool> {
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(t) = threads {
        builder = builder.num_threads(t);
    }
    builder.build().context("cannot start the thread pool")
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
pub fn run(
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

fn estimate_json(e: &Estimate) -> serde_json::Value {
    json!({
        "p": e.p, "lo": e.lo, "hi": e.hi, "confidence": e.confidence,
        "relative_half_width": e.relative_half_width(),
        "flights": e.flights, "final_flights": e.final_flights, "failures": e.failures,
        "effective_sample_size": e.ess, "plain_mc_equivalent": e.plain_mc_equivalent,
        "one_sided": e.one_sided, "reliable": e.reliable, "suggested_budget": e.suggested_budget(),
        "levels": e.levels,
    })
}

/// Plain Monte Carlo flights for the relative half-width `h` at `p`:
/// `z²(1 − p)/(p h²)` (normal approximation of the binomial).
pub fn plain_flights_for(p: f64, h: f64, confidence: f64) -> f64 {
    let z = ftsmc_sim::stats::normal_quantile(0.5 + 0.5 * confidence);
    z * z * (1.0 - p) / (p * h * h)
}

/// The estimator of `ftsmc failure-probability --method`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Method {
    /// Cross-entropy importance sampling of the `[falsify]` parameters (`ftsmc_sim::falsify::rare`).
    CrossEntropy,
    /// Adaptive multilevel splitting on the running margin, over the flight's whole random input.
    Splitting,
    /// Plain Monte Carlo at the nominal law (Wilson interval).
    Plain,
}

impl Method {
    /// The default for `scenario`, the estimator the validation favours
    /// (docs/falsification.md): plain Monte Carlo when its flights draw
    /// noise period by period (`ftsmc_sim::falsify::noise_driven`) —
    /// cross-entropy cannot move that noise, and splitting, which can,
    /// came out an order of magnitude low on a real rung against a 10,000
    /// flight plain campaign; cross-entropy otherwise (its failures then
    /// depend only on the per-flight draws, which the proposal moves).
    pub fn default_for(scenario: &Scenario) -> Self {
        if ftsmc_sim::falsify::noise_driven(scenario) {
            Method::Plain
        } else {
            Method::CrossEntropy
        }
    }

    /// The name printed and written (`--method`'s spelling).
    pub fn name(self) -> &'static str {
        match self {
            Method::CrossEntropy => "cross-entropy",
            Method::Splitting => "splitting",
            Method::Plain => "plain",
        }
    }
}

/// Particles per splitting repetition by default.
pub const SPLITTING_PARTICLES: usize = 100;
/// Splitting repetitions by default (at least `MIN_REPETITIONS` for a reliable interval).
pub const SPLITTING_REPETITIONS: usize = 10;
/// `--max-flights` by default: most flights of a `failure-probability` run (a splitting repetition stops at its share).
pub const SPLITTING_MAX_FLIGHTS: u64 = 200_000;

/// What `ftsmc failure-probability` estimates and how.
#[derive(Clone, Copy, Debug)]
pub struct FailureRequest {
    /// The estimator.
    pub method: Method,
    /// Flights of cross-entropy or plain Monte Carlo.
    pub budget: u64,
    /// Splitting's settings (its `budget` is `--max-flights`).
    pub splitting: ftsmc_sim::falsify::splitting::Settings,
    /// Seed of the estimator's draws.
    pub seed: u64,
    /// Confidence level of the intervals.
    pub confidence: f64,
    /// Plain Monte Carlo flights flown beside it (0: none).
    pub plain_runs: u64,
    /// Worker threads (`None`: all cores).
    pub threads: Option<usize>,
}

/// The fields every method's result carries (JSON top level and the CSV row).
struct Row {
    /// The estimate of `P(margin < 0)`.
    p: f64,
    /// Lower bound of its interval.
    lo: f64,
    /// Upper bound.
    hi: f64,
    /// Flights flown (splitting: branches included).
    flights: u64,
    /// Effective sample size of the final level (cross-entropy, plain); `None` for splitting.
    ess: Option<f64>,
    /// Levels: cross-entropy's, or splitting's mean per repetition (0 for plain).
    levels: f64,
    /// The interval can be trusted (the estimator's own reliability rule).
    reliable: bool,
}

fn splitting_json(e: &ftsmc_sim::falsify::splitting::Estimate) -> serde_json::Value {
    json!({
        "p": e.p, "lo": e.lo, "hi": e.hi, "confidence": e.confidence,
        "std_error": e.std_error, "flights": e.flights, "mean_levels": e.mean_levels,
        "settings": e.settings, "reliable": e.reliable, "suggested": e.suggested(),
        "plain_mc_equivalent": e.plain_mc_equivalent(),
        "flights_for_30_percent_cov": e.flights_for_cov(0.3),
        "repetitions": e.repetitions,
    })
}

/// Run `ftsmc failure-probability` and write `out/<scenario>/<controller>.failure-probability.json` and `.csv`.
pub fn run_failure_probability(
    scenario: &Scenario,
    controller: &str,
    request: &FailureRequest,
    out: &Path,
) -> Result<()> {
    let FailureRequest { method, budget, seed, confidence, plain_runs, threads, .. } = *request;
    anyhow::ensure!(
        confidence > 0.0 && confidence < 1.0,
        "--confidence {confidence}: expected a level strictly between 0 and 1"
    );
    if method == Method::CrossEntropy {
        anyhow::ensure!(budget >= 20, "--budget {budget}: cross-entropy sampling needs at least 20 flights");
    }
    let mut settings = request.splitting;
    settings.confidence = confidence;
    if method == Method::Splitting {
        settings.check().map_err(|e| anyhow::anyhow!("--particles/--repetitions/--max-flights: {e}"))?;
    }
    let problem = Problem::new(scenario, controller)?;
    let rare = RareProblem { problem: problem.clone(), master: scenario.seed };
    let folder = out.join(&scenario.name);
    let dir = ResultDir::begin(&folder, &format!("failure-probability-{controller}"))?;
    let pool = pool(threads)?;
    let started = Instant::now();
    let pct = confidence * 100.0;
    let name = method.name();
    let mut summary = json!({
        "scenario": scenario.name,
        "controller": controller,
        "method": name,
        "master_seed": scenario.seed,
        "seed": seed,
    });
    let mut lines = Vec::new();
    let row: Row;
    match method {
        Method::CrossEntropy | Method::Plain => {
            let e = if method == Method::Plain {
                pool.install(|| plain(&rare, budget, seed, confidence))
            } else {
                pool.install(|| cross_entropy(&rare, budget, seed, confidence))
            };
            let h = e.relative_half_width();
            // A speed-up only where the estimate's variance holds.
            let needed = if e.p > 0.0 && e.reliable { plain_flights_for(e.p, h, confidence) } else { f64::NAN };
            summary[name.replace('-', "_")] = estimate_json(&e);
            row = Row {
                p: e.p,
                lo: e.lo,
                hi: e.hi,
                flights: e.flights,
                ess: Some(e.ess),
                levels: e.levels.len() as f64,
                reliable: e.reliable,
            };
            summary["plain_mc_flights_for_same_relative_half_width"] = json!(needed);
            summary["flights_saved_factor"] = json!(needed / e.flights as f64);
            let how = if method == Method::Plain {
                format!("plain Monte Carlo at the nominal law, {} flights", e.flights)
            } else if e.levels.is_empty() {
                format!("cross-entropy: not rare, plain Monte Carlo at the nominal law, {} flights", e.flights)
            } else {
                format!("cross-entropy importance sampling, {} flights, {} levels", e.flights, e.levels.len())
            };
            lines.push(format!("P(margin < 0) of {controller} on {} ({how}):", scenario.name));
            lines.push(format!(
                "  p = {:.3e}  [{:.3e}, {:.3e}] ({pct:.0} %{}), {} failing of {} final flights, effective sample size {:.0}, {}",
                e.p,
                e.lo,
                e.hi,
                if e.one_sided { ", one-sided: no failing flight" } else { "" },
                e.failures,
                e.final_flights,
                e.ess,
                if e.reliable { "reliable" } else { "UNRELIABLE" }
            ));
            if let Some(b) = e.suggested_budget() {
                lines.push(format!(
                    "  unreliable: {:.1} effective failing flights (at least {:.0} needed for the interval to hold); no speed-up is claimed. Try --budget {b}.",
                    e.ess,
                    ftsmc_sim::falsify::rare::MIN_ESS
                ));
            }
            if e.p > 0.0 && e.reliable && method == Method::CrossEntropy {
                lines.push(format!(
                    "  plain Monte Carlo needs ≈ {needed:.0} flights for the same relative half-width ({:.1} %): {:.1}× the flights",
                    100.0 * h,
                    needed / e.flights as f64
                ));
            }
        }
        Method::Splitting => {
            let splitting = ftsmc_sim::falsify::FlightSplitting { problem };
            let e = pool
                .install(|| ftsmc_sim::falsify::splitting::estimate(&splitting, settings, seed))
                .map_err(|e| anyhow::anyhow!("{e}"))?;
            summary["splitting"] = splitting_json(&e);
            row = Row {
                p: e.p,
                lo: e.lo,
                hi: e.hi,
                flights: e.flights,
                ess: None,
                levels: e.mean_levels,
                reliable: e.reliable,
            };
            lines.push(format!(
                "P(margin < 0) of {controller} on {} (adaptive multilevel splitting on the running margin, {} repetitions of {} particles, {} flights, {:.1} levels per repetition):",
                scenario.name,
                settings.repetitions,
                settings.particles,
                e.flights,
                e.mean_levels
            ));
            lines.push(format!(
                "  p = {:.3e}  [{:.3e}, {:.3e}] ({pct:.0} %, Student's t over the repetitions), standard error {:.2e}, {}",
                e.p,
                e.lo,
                e.hi,
                e.std_error,
                if e.reliable { "reliable" } else { "UNRELIABLE" }
            ));
            if let Some(s) = e.suggested() {
                let stopped = e.repetitions.iter().filter(|r| !r.finished).count();
                let extinct = e.repetitions.iter().filter(|r| r.extinct).count();
                lines.push(format!(
                    "  unreliable ({} repetitions, {stopped} stopped by --max-flights, {extinct} extinct); no speed-up is claimed. Try --particles {} --repetitions {} --max-flights {}.",
                    e.repetitions.len(),
                    s.particles,
                    s.repetitions,
                    s.budget
                ));
            } else {
                let equivalent = e.plain_mc_equivalent();
                lines.push(format!(
                    "  plain Monte Carlo needs ≈ {equivalent:.0} flights for the same variance: {:.1}× the flights",
                    equivalent / e.flights as f64
                ));
            }
        }
    }
    let seconds = started.elapsed().as_secs_f64();
    let mc = (plain_runs > 0).then(|| pool.install(|| plain(&rare, plain_runs, seed, confidence)));
    if let Some(m) = &mc {
        lines.push(format!(
            "  plain Monte Carlo, {} flights: p = {:.3e}  [{:.3e}, {:.3e}] (Wilson, {pct:.0} %), {} failing",
            m.flights, m.p, m.lo, m.hi, m.failures
        ));
    }
    for (key, value) in [
        ("p", json!(row.p)),
        ("lo", json!(row.lo)),
        ("hi", json!(row.hi)),
        ("confidence", json!(confidence)),
        ("flights", json!(row.flights)),
        ("effective_sample_size", json!(row.ess)),
        ("levels", json!(row.levels)),
        ("reliable", json!(row.reliable)),
    ] {
        summary[key] = value;
    }
    let csv = format!(
        "method,p,lo,hi,confidence,flights,effective_sample_size,levels,reliable\n{name},{:e},{:e},{:e},{confidence},{},{},{},{}\n",
        row.p,
        row.lo,
        row.hi,
        row.flights,
        row.ess.map_or(String::new(), |v| format!("{v}")),
        row.levels,
        row.reliable
    );
    dir.write(format!("{controller}.failure-probability.csv"), csv.as_bytes())?;
    let file = dir.write_scenario(&format!("{controller}.scenario.toml"), scenario, "scenario.toml")?;
    summary["plain_monte_carlo"] = json!(mc.as_ref().map(estimate_json));
    summary["seconds"] = json!(seconds);
    summary["provenance"] = provenance(&[file]);
    dir.write(format!("{controller}.failure-probability.json"), serde_json::to_string_pretty(&summary)?.as_bytes())?;
    dir.commit()?;
    for line in lines {
        println!("{line}");
    }
    println!("wrote {}/{controller}.failure-probability.json ({seconds:.1} s)", folder.display());
    Ok(())
}
