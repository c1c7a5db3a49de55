//! `ftsmc run SCENARIO [-c …]`: fly one scenario with its controllers (or
//! those given) and write `OUT/<name>/`: a CSV per controller (written
//! while it flies), scenario.toml, summary.json, report.html and the
//! comparison figures.

use std::path::{Path, PathBuf};

use anyhow::Result;
use ftsmc_sim::run::{Recording, RunOutput};
use ftsmc_sim::scenario::Scenario;
use serde_json::Map;

use crate::args::{ControllersArgs, OutputArgs, ScenarioArgs};
use crate::flights::{fly_into, metrics_table, Flown, Job};
use crate::output::{provenance, summary_json, ResultDir};

/// Arguments of `ftsmc run`.
#[derive(clap::Args)]
pub struct Args {
    /// The scenario, `--set`, `--limit`.
    #[command(flatten)]
    scenario: ScenarioArgs,
    /// `-c`.
    #[command(flatten)]
    controllers: ControllersArgs,
    /// `--out`, `--no-figures`.
    #[command(flatten)]
    output: OutputArgs,
}

/// Runs `ftsmc run`.
pub fn run(args: Args) -> Result<()> {
    let mut scenario = args.scenario.load()?;
    let names = args.controllers.or_scenario(&scenario)?;
    scenario.check_cost(names.len())?;
    ftsmc_sim::batch::gains_fit::check(&scenario, &names)?;
    // The resolved scenario (written as scenario.toml) lists what was flown.
    scenario.controllers = names;
    run_scenario(&scenario, &args.output.out, args.output.figures())
}

/// `ftsmc run`: fly `scenario.controllers` and write `out/<name>/`.
pub fn run_scenario(scenario: &Scenario, out: &Path, figures: bool) -> Result<()> {
    // `out/<name>/` is the result folder: checked before any flight,
    // written in staging, swapped into place whole.
    let dir = ResultDir::begin(&out.join(&scenario.name), "run")?;
    let jobs: Vec<Job> = scenario
        .controllers
        .iter()
        .map(|n| Job { scenario: scenario.clone(), controller: n.clone(), key: n.clone() })
        .collect();
    let started = std::time::Instant::now();
    // Each CSV is written while its flight flies.
    let csv = |job: &Job| PathBuf::from(format!("{}.csv", job.key));
    let runs = fly_into(&jobs, &dir, csv)?;
    let flight_seconds = started.elapsed().as_secs_f64();
    let file = dir.write_scenario("scenario.toml", scenario, "scenario.toml")?;
    let refs: Vec<&RunOutput> = runs.iter().collect();
    let flown: Vec<Flown> = runs.iter().map(|r| (r, scenario)).collect();
    let table = metrics_table(&flown, &format!("{} — metrics", scenario.name));
    let mut extra = Map::new();
    extra.insert("provenance".into(), provenance(&[file]));
    let summary = summary_json(&refs, extra);
    dir.write("summary.json", serde_json::to_string_pretty(&summary)?.as_bytes())?;
    if figures {
        crate::figures::generic(&refs, &dir.path().join("figures"))?;
    }
    // The replay's rows from the recordings in memory, not the files just written.
    let recorded: Vec<(PathBuf, &Recording)> =
        jobs.iter().zip(&runs).map(|(job, r)| (csv(job), &r.recording)).collect();
    let html = crate::html::report_with(dir.path(), &format!("ftsmc run {}", scenario.name), &table, &recorded)?;
    dir.write("report.html", html.as_bytes())?;
    dir.commit()?;
    println!("{table}");
    println!(
        "wrote {}/ (CSV per controller, scenario.toml, summary.json, report.html{}); {} flight{} in {flight_seconds:.3} s",
        out.join(&scenario.name).display(),
        if figures { ", figures/" } else { "" },
        runs.len(),
        if runs.len() == 1 { "" } else { "s" }
    );
    Ok(())
}
