//! `ftsmc compare SCENARIO -c A,B,…`: built-in controllers and gain files
//! flown on one scenario's vehicle, wind and draws, with every number's
//! interval, every pair's verdict (McNemar on success, Wilcoxon on RMS
//! position error, Holm over all), a verdict matrix and a forest plot.
//! `--until-decided` flies batches until every pair is decided, spending
//! `α` over the looks (`ftsmc_sim::batch::compare`, docs/statistics.md).
//!
//! Writes `OUT/<scenario>/`: `runs.csv`, `summary.json`, `report.md`,
//! `report.html`, `scenario.toml` and `forest.svg` / `forest.png`.

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use anyhow::{anyhow, bail, Context, Result};
use ftsmc_sim::batch::compare::{compare, Comparison, Contestant, Plan};
use ftsmc_sim::batch::montecarlo::MonteCarloSpec;
use ftsmc_sim::run::planned_steps;
use ftsmc_sim::scenario::Scenario;
use serde_json::{json, Map, Value};

use crate::args::{
    check_lanes, controller_names, parse_mission, ConfidenceArgs, OutputArgs, ScenarioArgs, SeedArgs, ThreadsArgs,
};
use crate::console::steps_bar;
use crate::forest::{write_forest, ForestPanel};
use crate::intervals::{interval_table, level_note, verdict_matrix, verdict_table};
use crate::output::{provenance, ResultDir};
use ftsmc_sim::analysis::missions::Mission;
use ftsmc_sim::registry::ControllerList;

/// Arguments of `ftsmc compare`.
#[derive(clap::Args)]
#[command(mut_arg("out", |a| a.default_value("results/compare")))]
#[command(mut_arg("no_figures", |a| a.help("Skip the forest plot")))]
pub struct Args {
    /// The scenario (its vehicle, wind and [montecarlo] draws), `--set`, `--limit`.
    #[command(flatten)]
    scenario: ScenarioArgs,
    /// Contestants (required; comma-separated or repeated): controller names, or files (a `*.tuned.toml`,
    /// any scenario) whose controller section is flown on SCENARIO.
    #[arg(long = "controllers", short = 'c', alias = "contestants", value_name = "CONTESTANTS")]
    #[arg(value_delimiter = ',', value_parser = controller_names)]
    contestants: Vec<String>,
    /// Runs per contestant (not with --until-decided).
    #[arg(long, default_value_t = ftsmc_sim::defaults::COMPARE_RUNS, conflicts_with_all = ["until_decided", "max_runs", "batch"])]
    runs: u64,
    /// Fly batches of --batch runs until every pair is decided (alpha spending keeps the error rate).
    #[arg(long)]
    until_decided: bool,
    /// Most runs per contestant with --until-decided (only with it; default 1000).
    #[arg(long)]
    max_runs: Option<u64>,
    /// Runs per look with --until-decided (only with it; default 50).
    #[arg(long)]
    batch: Option<u64>,
    /// `--confidence`.
    #[command(flatten)]
    confidence: ConfidenceArgs,
    /// A practical-difference margin (repeatable): `rms=0.005` (m), `success=0.02` (a fraction). Each
    /// verdict is then also judged against it: better by more than the margin, equivalent within it
    /// (two one-sided tests), or not decided.
    #[arg(long = "min-effect", value_name = "METRIC=MARGIN")]
    min_effect: Vec<String>,
    /// Fly a file's gains even if it was made for another vehicle.
    #[arg(long)]
    allow_other_vehicle: bool,
    /// What SCENARIO is flown for: `steps` (its own reference, the default), `hover` (hold the steps' target
    /// from rest at it), `figure-eight` or `waypoints` (docs/scenarios.md "Missions").
    #[arg(long, default_value = "steps", value_parser = parse_mission)]
    mission: Mission,
    /// `--seed`.
    #[command(flatten)]
    seed: SeedArgs,
    /// `--threads`.
    #[command(flatten)]
    threads: ThreadsArgs,
    /// Flights each thread flies side by side: 1, 2, 4 or 8. Results do not depend on it.
    #[arg(long, default_value_t = ftsmc_sim::batch::montecarlo::DEFAULT_LANES)]
    lanes: usize,
    /// `--out`, `--no-figures`.
    #[command(flatten)]
    output: OutputArgs,
}

/// The plan of `--runs` or `--until-decided` (with `--max-runs`, `--batch`), refused when
/// the sequential flags come without `--until-decided` or any count is 0.
fn plan(args: &Args) -> Result<Plan> {
    if !args.until_decided {
        // Given without the sequential plan they would be ignored.
        for (flag, value) in [("--max-runs", args.max_runs), ("--batch", args.batch)] {
            anyhow::ensure!(
                value.is_none(),
                "{flag} sets the sequential plan: it needs --until-decided (a fixed number of runs is --runs)"
            );
        }
    }
    let max_runs = args.max_runs.unwrap_or(ftsmc_sim::defaults::COMPARE_MAX_RUNS);
    let batch = args.batch.unwrap_or(ftsmc_sim::defaults::COMPARE_BATCH);
    anyhow::ensure!(args.runs >= 1 && max_runs >= 1 && batch >= 1, "--runs, --max-runs and --batch must be at least 1");
    Ok(if args.until_decided { Plan::UntilDecided { batch, max_runs } } else { Plan::Fixed { runs: args.runs } })
}

/// Runs `ftsmc compare`: every check before any flight, then [`fly_and_write`].
pub fn run(args: Args) -> Result<()> {
    let min_effect = if args.min_effect.is_empty() {
        None
    } else {
        Some(ftsmc_sim::batch::verdicts::MinEffect::parse(&args.min_effect).map_err(anyhow::Error::msg)?)
    };
    anyhow::ensure!(
        !args.contestants.is_empty(),
        "compare needs its contestants, -c/--controllers: controller names or gain files (-c pid,se3 or \
         -c pid.tuned.toml,pid)"
    );
    ControllerList { argument: "-c/--controllers", names: &args.contestants }.check()?;
    let plan_checked = plan(&args);
    let scenario = args.scenario.load()?;
    // `steps` is the scenario itself (its bits unchanged).
    let mut scenario = ftsmc_sim::analysis::missions::mission_scenario(&scenario, args.mission, Default::default())?;
    let confidence = args.confidence.checked()?;
    let plan = plan_checked?;
    let threads = args.threads.checked(&scenario)?;
    let lanes = check_lanes(args.lanes)?;
    scenario.seed = args.seed.or_scenario(&scenario);
    fly_and_write(&Request {
        scenario: &scenario,
        contestants: &args.contestants,
        plan,
        confidence,
        min_effect,
        allow_other_vehicle: args.allow_other_vehicle,
        threads,
        lanes,
        out: &args.output.out,
        figures: args.output.figures(),
        limits: &args.scenario.limits.limit,
    })
}

/// What `ftsmc compare` was asked.
pub struct Request<'a> {
    /// The scenario the contestants fly.
    pub scenario: &'a Scenario,
    /// Contestants as given (`pid`, `tuned/pid.tuned.toml`, …).
    pub contestants: &'a [String],
    /// Runs per contestant, or the sequential plan.
    pub plan: Plan,
    /// Confidence level of every interval and verdict.
    pub confidence: f64,
    /// Practical-difference margins (`--min-effect`).
    pub min_effect: Option<ftsmc_sim::batch::verdicts::MinEffect>,
    /// Fly a file's gains even if it was made for another vehicle.
    pub allow_other_vehicle: bool,
    /// Worker threads (default: all cores).
    pub threads: Option<usize>,
    /// Flights side by side per thread.
    pub lanes: usize,
    /// Parent output folder.
    pub out: &'a Path,
    /// Write the forest plot.
    pub figures: bool,
    /// `--limit` overrides for the files loaded as contestants.
    pub limits: &'a [String],
}

/// Turn each `-c` entry into a [`Contestant`]: a built-in controller, or a
/// file's controller section (refused: unknown names, duplicates, a file
/// for another vehicle without `--allow-other-vehicle`).
pub fn contestants(req: &Request<'_>) -> Result<Vec<Contestant>> {
    let mut out: Vec<Contestant> = Vec::new();
    let mut given: Vec<&String> = Vec::new();
    for c in req.contestants {
        let contestant = if ftsmc_sim::registry::check_name(c).is_ok() {
            Contestant::built_in(req.scenario, c)
        } else {
            let path = Path::new(c);
            if !path.exists() {
                let known = ftsmc_sim::registry::check_name("").err().unwrap_or_default();
                bail!("unknown contestant `{c}`: neither a controller (known: {known}) nor an existing file");
            }
            let loaded = Scenario::load_with_warnings(path, req.limits)?;
            for w in &loaded.warnings {
                eprintln!("warning: {w}");
            }
            let name = path.file_name().map_or_else(|| c.clone(), |f| f.to_string_lossy().into_owned());
            Contestant::from_file(req.scenario, &name, &loaded.scenario, req.allow_other_vehicle)
                .map_err(|e| anyhow!("{e}"))?
        };
        let mut contestant = contestant;
        if let Some(i) = out.iter().position(|o| o.name == contestant.name) {
            if given[i] == c {
                bail!("contestant `{}` is given twice", contestant.name);
            }
            // Two files with the same label (two tunes of one controller):
            // the path tells them apart.
            contestant.name = format!("{} [{c}]", contestant.name);
        }
        given.push(c);
        out.push(contestant);
    }
    if out.len() < 2 {
        bail!("-c {}: a comparison needs at least two contestants", req.contestants.join(","));
    }
    Ok(out)
}

/// Run the comparison and write its folder.
pub fn fly_and_write(req: &Request<'_>) -> Result<()> {
    let scenario = req.scenario;
    let list = contestants(req)?;
    let max_runs = match req.plan {
        Plan::Fixed { runs } => runs,
        Plan::UntilDecided { max_runs, .. } => max_runs,
    };
    ftsmc_sim::limits::check_batch(&scenario.flight_size(), max_runs, list.len())?;
    for c in &list {
        ftsmc_sim::batch::gains_fit::check(&c.scenario, std::slice::from_ref(&c.controller))?;
    }
    let folder = req.out.join(&scenario.name);
    let dir = ResultDir::begin(&folder, "compare")?;
    let spec = scenario.montecarlo.clone().unwrap_or_else(|| {
        eprintln!("note: {} has no [montecarlo] section; runs differ only in their seeds (drag noise)", scenario.name);
        MonteCarloSpec::default()
    });
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(t) = req.threads {
        builder = builder.num_threads(t);
    }
    let pool = builder.build().context("cannot start the thread pool")?;
    let flights = max_runs.saturating_mul(list.len() as u64);
    let bar = steps_bar(flights.saturating_mul(planned_steps(scenario)), flights);
    let started = Instant::now();
    let result = pool
        .install(|| compare(&list, &spec, scenario.seed, req.plan, req.confidence, req.lanes, &|n| bar.inc(n)))
        .map_err(|e| anyhow!("{e}"))?;
    bar.finish_and_clear();
    let elapsed = started.elapsed().as_secs_f64();

    dir.write("runs.csv", &crate::campaign::runs_csv(&result.rows)?)?;
    let file = dir.write_scenario("scenario.toml", scenario, "scenario.toml")?;
    let names: Vec<String> = list.iter().map(|c| c.name.clone()).collect();
    let report = report_md(scenario, &names, &result, req.min_effect.as_ref());
    dir.write("report.md", report.as_bytes())?;
    let summary = summary_json(scenario, &list, &result, req.min_effect.as_ref(), provenance(&[file]));
    dir.write("summary.json", serde_json::to_string_pretty(&summary)?.as_bytes())?;
    if req.figures {
        let panel =
            |label: &str, f: &dyn Fn(&ftsmc_sim::batch::verdicts::Intervals) -> Option<ftsmc_sim::stats::Interval>| {
                ForestPanel {
                    label: label.to_string(),
                    rows: list
                        .iter()
                        .zip(&result.intervals)
                        .map(|(c, (_, i))| (crate::intervals::display_name(&c.name), c.controller.clone(), f(i)))
                        .collect(),
                }
            };
        let panels = [
            panel("success rate (%)", &|i| Some(i.success_rate.scaled(100.0))),
            panel("median RMS position error (m)", &|i| i.rms_median),
            panel("mean RMS position error (m)", &|i| i.rms_mean),
        ];
        let title = format!(
            "{} runs of {} per contestant, {:.0} % intervals",
            result.runs,
            scenario.name,
            100.0 * result.confidence
        );
        write_forest(&title, &panels, &dir.path().join("forest"))?;
    }
    let html = crate::html::report(dir.path(), &format!("ftsmc compare {}", scenario.name), &report)?;
    dir.write("report.html", html.as_bytes())?;
    dir.commit()?;
    println!("{report}");
    println!(
        "{} flights in {elapsed:.1} s; wrote {}/ (runs.csv, summary.json, report.md, report.html, scenario.toml{})",
        result.rows.len(),
        folder.display(),
        if req.figures { ", forest.svg/.png" } else { "" }
    );
    Ok(())
}

/// The Markdown report (also printed).
pub fn report_md(
    scenario: &Scenario,
    names: &[String],
    r: &Comparison,
    min_effect: Option<&ftsmc_sim::batch::verdicts::MinEffect>,
) -> String {
    let mut md = String::new();
    let _ =
        writeln!(md, "# Comparison on {} ({} runs per contestant, seed {})\n", scenario.name, r.runs, scenario.seed);
    let _ = writeln!(
        md,
        "Every contestant flies the same {} draws (vehicle, wind, noise, initial state of run i), so each run is a \
         matched pair. RMS position error √(rms_x² + rms_y² + rms_z²) over the completed runs.\n",
        r.runs
    );
    let _ = writeln!(md, "{}\n\n{}", level_note(r.confidence), interval_table(&r.intervals).render());
    let _ = writeln!(
        md,
        "Paired verdicts: success by McNemar's exact test (effect p_A − p_B, percentage points), RMS position error \
         by the Wilcoxon signed-rank test (effect: the Hodges–Lehmann shift of A − B over the pairs where both completed, with the interval inverting the same test); Holm's \
         correction over all {} tests, family-wise error at most {:.0} %.",
        r.verdicts.len(),
        100.0 * (1.0 - r.confidence)
    );
    if let Plan::UntilDecided { batch, max_runs } = r.plan {
        let looks: Vec<String> = r
            .looks
            .iter()
            .map(|l| format!("{} runs (α spent {:.2e}, {} pairs decided)", l.runs, l.alpha_spent, l.pairs_decided))
            .collect();
        let _ = writeln!(
            md,
            "Sequential (--until-decided, batches of {batch}, at most {max_runs} runs): a verdict counts only if a \
             look rejected it at that look's share of α (O'Brien–Fleming-type Lan–DeMets spending over the planned \
             looks, Holm within each look; p-values below are of the final look, uncorrected for the looks). Looks: {}.",
            looks.join("; ")
        );
    }
    let _ = writeln!(md, "\n{}", verdict_table(&r.verdicts).render());
    if let Some(m) = min_effect {
        let _ = writeln!(
            md,
            "Against the practical margins (--min-effect: success ±{:.1} pp, RMS position error ±{} m): better only when \
             the test says so and the whole effect interval lies beyond the margin; equivalent when the whole interval \
             lies within it (two one-sided tests, each at half the error level).\n\n{}",
            100.0 * m.success,
            m.rms,
            crate::intervals::practical_table(&r.verdicts, m).render()
        );
    }
    let _ = writeln!(
        md,
        "Verdict matrix (row A against column B; `A`: the row is better, `B`: the column, `=`: no difference shown):\n\n{}",
        verdict_matrix(names, &r.verdicts).render()
    );
    if !r.all_decided {
        let _ = writeln!(
            md,
            "Not every pair is decided with {} runs: more runs (`--runs`, or `--until-decided --max-runs M`) may \
             decide them, or their difference is too small to matter.",
            r.runs
        );
    }
    md
}

/// `summary.json`: the plan, the confidence level, each contestant's
/// intervals, every verdict and the looks.
pub fn summary_json(
    scenario: &Scenario,
    list: &[Contestant],
    r: &Comparison,
    min_effect: Option<&ftsmc_sim::batch::verdicts::MinEffect>,
    provenance: Value,
) -> Value {
    let mut contestants = Map::new();
    for (c, (_, i)) in list.iter().zip(&r.intervals) {
        contestants.insert(c.name.clone(), json!({"controller": c.controller, "intervals": i}));
    }
    json!({
        "scenario": scenario.name,
        "master_seed": scenario.seed,
        "confidence": r.confidence,
        "plan": r.plan,
        "runs": r.runs,
        "contestants": Value::Object(contestants),
        "verdicts": r.verdicts,
        "min_effect": min_effect,
        "practical": min_effect.map(|m| r.verdicts.iter().map(|v| ftsmc_sim::batch::verdicts::practical(v, m)).collect::<Vec<_>>()),
        "looks": r.looks,
        "all_decided": r.all_decided,
        "provenance": provenance,
    })
}
