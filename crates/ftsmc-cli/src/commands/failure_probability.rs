//! `ftsmc failure-probability`: `P(margin < 0)` under the scenario's own
//! draws (adaptive multilevel splitting, cross-entropy importance sampling
//! or plain Monte Carlo; `ftsmc_sim::falsify`, docs/falsification.md),
//! with its interval. Writes `DIR/<scenario>/<controller>.failure-probability.{json,csv}`,
//! owned by `failure-probability-<controller>`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Result;
use ftsmc_sim::falsify::rare::{cross_entropy, plain, Estimate};
use ftsmc_sim::falsify::{Problem, RareProblem};
use ftsmc_sim::registry::check_controllers;
use ftsmc_sim::scenario::Scenario;
use serde_json::json;

use crate::args::{check_budget, controller_names, pool, ConfidenceArgs, ScenarioArgs, SeedArgs, ThreadsArgs};
use crate::output::{provenance, ResultDir};

/// Arguments of `ftsmc failure-probability`.
#[derive(clap::Args)]
#[command(mut_arg("scenario", |a| a.help("Scenario file (TOML) or built-in name with a [falsify] section and an [envelope]")))]
#[command(mut_arg("seed", |a| a.help("Seed of the proposal draws (default: the scenario's `seed`, also the master seed of the draws)")))]
pub struct Args {
    /// The scenario, `--set`, `--limit`.
    #[command(flatten)]
    scenario: ScenarioArgs,
    /// Controller.
    #[arg(long, short = 'c', value_parser = controller_names)]
    controller: String,
    /// Estimator (default: plain Monte Carlo when the flights draw sensor, turbulence, drag or motor noise, which cross-entropy cannot move and splitting does not yet estimate reliably on real rungs; else cross-entropy).
    #[arg(long, value_enum)]
    method: Option<Method>,
    /// Flights of cross-entropy (its levels included) or plain Monte Carlo.
    #[arg(long, allow_negative_numbers = true, default_value_t = ftsmc_sim::defaults::FAILURE_PROBABILITY_BUDGET)]
    budget: u64,
    /// Splitting: particles per repetition.
    #[arg(long, allow_negative_numbers = true, default_value_t = SPLITTING_PARTICLES)]
    particles: usize,
    /// Splitting: independent repetitions (their spread gives the interval).
    #[arg(long, allow_negative_numbers = true, default_value_t = SPLITTING_REPETITIONS)]
    repetitions: usize,
    /// Most flights of the whole run (splitting's branches and --plain included); work that needs more is refused before it starts.
    #[arg(long, allow_negative_numbers = true, default_value_t = SPLITTING_MAX_FLIGHTS)]
    max_flights: u64,
    /// `--confidence` of the interval.
    #[command(flatten)]
    confidence: ConfidenceArgs,
    /// Also fly N plain Monte Carlo flights and print their estimate beside it (0: none).
    #[arg(long, allow_negative_numbers = true, default_value_t = 0)]
    plain: u64,
    /// `--seed`.
    #[command(flatten)]
    seed: SeedArgs,
    /// `--threads`.
    #[command(flatten)]
    threads: ThreadsArgs,
    /// Parent folder: the results go to `OUT/<scenario name>/`.
    #[arg(long, default_value = "results/failure-probability")]
    out: PathBuf,
}

/// Runs `ftsmc failure-probability`: every check before any flight, then the estimate.
pub fn run(args: Args) -> Result<()> {
    let scenario = args.scenario.load()?;
    let controller = args.controller;
    check_controllers("-c/--controller", std::slice::from_ref(&controller))?;
    anyhow::ensure!(args.threads.threads != Some(0), "--threads must be at least 1");
    let method = args.method.unwrap_or_else(|| Method::default_for(&scenario));
    let (budget, plain, max_flights) = (args.budget, args.plain, args.max_flights);
    let flights = check_max_flights(method, budget, args.particles, args.repetitions, plain, max_flights)?;
    check_budget(flights)?;
    ftsmc_sim::limits::check_batch(&scenario.flight_size(), flights.saturating_add(plain), 1)?;
    let threads = args.threads.checked(&scenario)?;
    let seed = args.seed.or_scenario(&scenario);
    let confidence = args.confidence.confidence;
    let splitting =
        ftsmc_sim::falsify::splitting::Settings::new(args.particles, args.repetitions, max_flights - plain, confidence);
    let request = FailureRequest { method, budget, splitting, seed, confidence, plain_runs: plain, threads };
    estimate_and_write(&scenario, &controller, &request, &args.out)
}

/// The flights `ftsmc failure-probability` may fly within `max_flights`
/// (for splitting: `max_flights − plain`, its budget; otherwise `budget`),
/// or the refusal of work that cannot finish within it: cross-entropy and
/// plain Monte Carlo fly `budget + plain` flights; splitting at least its
/// `particles · repetitions` first flights plus `plain` (its branches then
/// stop at `max_flights`, which flags the estimate unreliable).
fn check_max_flights(
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
fn estimate_and_write(scenario: &Scenario, controller: &str, request: &FailureRequest, out: &Path) -> Result<()> {
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
