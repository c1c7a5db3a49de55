//! `ftsmc` — reproduce the FTAFTSMC quadrotor paper and go beyond it.
//!
//! Run `ftsmc --help` for the commands.

mod bounded_read;
mod compare;
mod console;
mod cpu;
mod falsify;
mod figures;
mod fixed_time;
mod forest;
mod html;
mod identify;
mod intervals;
mod ladder;
mod log_args;
mod merge;
mod montecarlo;
mod output;
mod plot;
mod px4;
mod raster;
mod reproduce;
mod result_dir;
mod svg;
mod ticks;
mod tune;
mod tuned;
mod validate;
mod worst_case;
#[cfg(test)]
mod writers_fuzz;

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::{Parser, Subcommand};
use ftsmc_sim::registry;
use ftsmc_sim::scenario::{Scenario, BUILT_IN_SCENARIOS};

#[derive(Parser)]
#[command(
    name = "ftsmc",
    version,
    about = "Fixed-time adaptive terminal sliding-mode control of a quadrotor: reproduce the paper, run scenarios",
    long_about = "ftsmc simulates a quadrotor (paper Eq. 1-2, corrected) under the fixed-time adaptive fast terminal \
sliding-mode controller FTAFTSMC, the two earlier sliding-mode controllers the paper compares it with \
(RANFTSMC, TSM-STA) and two practitioners' baselines (PID, the PX4 cascade; SE(3), Lee et al. 2010): five \
controllers.\n\n\
Start with `ftsmc reproduce`: it runs the paper's two scenarios with the paper's three controllers, prints the \
paper's Table 3 beside ours with a verdict on each claim, flies all five controllers beyond the paper, and writes \
CSV time series, summary.json, the figures (SVG + PNG), report.md and report.html (one self-contained page with \
every table and figure) under results/.\n\n\
Write your own scenario as a TOML file (start from `ftsmc scenario paper-scenario-1 > my.toml`) and run it with \
`ftsmc run my.toml`.\n\n\
Every command takes `--out DIR`, the parent folder of its results: `run`, `montecarlo` and `fixed-time` write \
DIR/<scenario name>/ (defaults results, results/montecarlo, results/fixed-time); `reproduce` writes \
DIR/<scenario name>/ for each paper scenario and its report beside them in DIR (default results). Each result \
folder holds scenario.toml, the resolved scenario as flown: `ftsmc run DIR/<name>/scenario.toml` flies it again."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Figure style: `screen` (readable at 100 %) or `paper` (3.5/7 in wide, 8 pt text, 300 dpi PNG, SVG in pt).
    /// Default: $FTSMC_FIGURE_STYLE, else screen.
    #[arg(long, global = true, value_enum)]
    style: Option<plot::Style>,
}

#[derive(Subcommand)]
enum Command {
    /// Identify a vehicle's parameters from flight logs, with bootstrap intervals (docs/validation.md).
    Identify(identify::IdentifyArgs),
    /// Open-loop validation of a vehicle against flight logs (docs/validation.md).
    Validate(validate::ValidateArgs),
    /// Run both paper scenarios with every controller; print Table 3 beside the paper's; write CSV, JSON, figures.
    Reproduce {
        /// Parent folder: writes `OUT/<scenario>/` per paper scenario, and summary.json, report.md, figures/ in OUT.
        #[arg(long, default_value = "results")]
        out: PathBuf,
        /// Skip figure rendering (tables, CSV and JSON only).
        #[arg(long, conflicts_with = "style")]
        no_figures: bool,
        /// Monte Carlo runs of each wind-ladder rung (`realistic-<level>-<n>`) per controller in the "Beyond the paper" section (0: none).
        #[arg(long, allow_negative_numbers = true, default_value_t = reproduce::DEFAULT_REALISTIC_RUNS)]
        realistic_runs: u64,
        /// Raise a cost limit of the realistic Monte Carlo, e.g. `--limit max_flights=1e7` (repeatable; see docs/scenarios.md).
        #[arg(long = "limit", value_name = "KEY=VALUE")]
        limit: Vec<String>,
        /// Confidence level of the ladder's and tuned table's intervals and verdicts (family-wise error 1 − confidence).
        #[arg(long, default_value_t = ftsmc_sim::defaults::CONFIDENCE)]
        confidence: f64,
        /// Held-out draws per gain set in the table of the committed tuned gains against the defaults
        /// (`scenarios/tuned/`; 0: no table; docs/tuning.md's table uses 200).
        #[arg(long, default_value_t = 0)]
        tuned_runs: u64,
        /// Flights per falsification and per failure-probability estimate in the worst-case table
        /// (two rungs × every controller × default and tuned gains; 0: no table; docs/falsification.md).
        #[arg(long, default_value_t = 0)]
        worst_case_budget: u64,
        /// Monte Carlo runs per scenario-1 rung, mission (hover, figure-eight, waypoints) and controller
        /// in the missions table of "Beyond the paper" (0: none; docs/scenarios.md "Missions").
        #[arg(long, default_value_t = reproduce::DEFAULT_MISSION_RUNS)]
        mission_runs: u64,
        /// Settling window of the missions' tracking metrics, s (they cover [window, end]).
        #[arg(long, default_value_t = ftsmc_sim::analysis::missions::DEFAULT_SETTLING_WINDOW)]
        mission_window: f64,
        /// Settling band of the missions' time to settle, m.
        #[arg(long, default_value_t = ftsmc_sim::analysis::missions::DEFAULT_SETTLING_BAND)]
        mission_band: f64,
    },
    /// Run one scenario file with its controllers (or those given); write CSV, summary.json and comparison figures.
    Run {
        /// Scenario file (TOML), or the name of a built-in paper scenario.
        scenario: String,
        /// Controller(s) to run (repeat or comma-separate); default: the scenario's `controllers` list.
        #[arg(long, short = 'c', alias = "controller", value_delimiter = ',', value_parser = controller_names)]
        controllers: Vec<String>,
        /// Parent folder: the results go to `OUT/<scenario name>/`.
        #[arg(long, default_value = "results")]
        out: PathBuf,
        /// Skip figure rendering.
        #[arg(long, conflicts_with = "style")]
        no_figures: bool,
        /// Raise a cost limit, e.g. `--limit max_steps=1e10` (repeatable; keys: max_steps, max_samples,
        /// max_output_bytes, max_flights, max_sweep_points, max_threads, max_scenario_bytes; see docs/scenarios.md).
        #[arg(long = "limit", value_name = "KEY=VALUE")]
        limit: Vec<String>,
        /// Set a scenario key, e.g. `--set vehicle.preset=crazyflie-2` or `--set wind.preset=breeze` (repeatable;
        /// the dotted keys of Python's `Scenario.with_overrides`; recorded in the written scenario.toml).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
    /// Measure reaching and settling times against the initial error (1e-3 … 1e2) beside the paper's fixed-time bound.
    FixedTime {
        /// Scenario whose gains are used (file or built-in name).
        #[arg(long, default_value = "paper-scenario-1")]
        scenario: String,
        /// Controller(s) to sweep (repeat or comma-separate); default: the scenario's `controllers` list.
        #[arg(long, short = 'c', value_delimiter = ',', value_parser = controller_names)]
        controllers: Vec<String>,
        /// Log-spaced magnitudes per decade.
        #[arg(long, allow_negative_numbers = true, default_value_t = 3)]
        per_decade: usize,
        /// Parent folder: the results go to `OUT/<scenario name>/`.
        #[arg(long, default_value = "results/fixed-time")]
        out: PathBuf,
        /// Raise a cost limit, e.g. `--limit max_steps=1e10` (repeatable; keys: max_steps, max_samples,
        /// max_output_bytes, max_flights, max_sweep_points, max_threads, max_scenario_bytes; see docs/scenarios.md).
        #[arg(long = "limit", value_name = "KEY=VALUE")]
        limit: Vec<String>,
        /// Set a scenario key, e.g. `--set vehicle.preset=crazyflie-2` or `--set wind.preset=breeze` (repeatable;
        /// the dotted keys of Python's `Scenario.with_overrides`; recorded in the written scenario.toml).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
    /// Fly N randomised copies of a scenario (its [montecarlo] section) with each controller, in parallel.
    Montecarlo {
        /// Scenario file (TOML) or built-in name.
        scenario: String,
        /// Number of randomised runs (each flown by every controller).
        #[arg(long, allow_negative_numbers = true, default_value_t = ftsmc_sim::defaults::MONTECARLO_RUNS)]
        runs: u64,
        /// Master seed (default: the scenario's `seed`).
        #[arg(long, allow_negative_numbers = true)]
        seed: Option<u64>,
        /// Worker threads (default: all cores). Results do not depend on it.
        #[arg(long, allow_negative_numbers = true)]
        threads: Option<usize>,
        /// Flights each thread flies side by side in vector lanes: 1 or 4. Results do not depend on it.
        #[arg(long, allow_negative_numbers = true, default_value_t = ftsmc_sim::batch::montecarlo::DEFAULT_LANES)]
        lanes: usize,
        /// Controller(s) to fly (repeat or comma-separate); default: the scenario's `controllers` list.
        #[arg(long, short = 'c', value_delimiter = ',', value_parser = controller_names)]
        controllers: Vec<String>,
        /// Parent folder: the results go to `OUT/<scenario name>/`.
        #[arg(long, default_value = "results/montecarlo")]
        out: PathBuf,
        /// Skip the box-plot figure.
        #[arg(long, conflicts_with = "style")]
        no_figures: bool,
        /// Raise a cost limit, e.g. `--limit max_steps=1e10` (repeatable; keys: max_steps, max_samples,
        /// max_output_bytes, max_flights, max_sweep_points, max_threads, max_scenario_bytes; see docs/scenarios.md).
        #[arg(long = "limit", value_name = "KEY=VALUE")]
        limit: Vec<String>,
        /// Set a scenario key, e.g. `--set vehicle.preset=crazyflie-2` or `--set wind.preset=breeze` (repeatable;
        /// the dotted keys of Python's `Scenario.with_overrides`; recorded in the written scenario.toml).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// Fly only shard K of N (a contiguous block of the runs) into `OUT/<name>-shard-K-of-N/`;
        /// `ftsmc merge` joins the N shards into the unsharded result (docs/campaigns.md).
        #[arg(long, value_name = "K/N")]
        shard: Option<ftsmc_sim::batch::shard::Shard>,
        /// Confidence level of every interval in the tables and summary.json (recorded there).
        #[arg(long, default_value_t = ftsmc_sim::defaults::CONFIDENCE)]
        confidence: f64,
    },
    /// Search the scenario's [falsify] space for the flight with the lowest robustness margin (CMA-ES with restarts), beside uniform random search at the same budget.
    Falsify {
        /// Scenario file (TOML) or built-in name with a [falsify] section and an [envelope].
        scenario: String,
        /// Controller to falsify.
        #[arg(long, short = 'c', value_parser = controller_names)]
        controller: String,
        /// Flights per method (default: `[falsify] budget`, else 200).
        #[arg(long, allow_negative_numbers = true)]
        budget: Option<u64>,
        /// Seed of the search (default: the scenario's `seed`); the turbulence seed is the scenario's, held fixed.
        #[arg(long, allow_negative_numbers = true)]
        seed: Option<u64>,
        /// Worker threads (default: all cores). Results do not depend on it.
        #[arg(long, allow_negative_numbers = true)]
        threads: Option<usize>,
        /// Parent folder: the results go to `OUT/<scenario name>/`.
        #[arg(long, default_value = "results/falsify")]
        out: PathBuf,
        /// Skip the worst-vs-nominal figure.
        #[arg(long, conflicts_with = "style")]
        no_figures: bool,
        /// Raise a cost limit (repeatable; see docs/scenarios.md).
        #[arg(long = "limit", value_name = "KEY=VALUE")]
        limit: Vec<String>,
        /// Set a scenario key (repeatable; dotted keys as `Scenario.with_overrides`).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
    /// Estimate P(margin < 0) under the scenario's own draws (adaptive multilevel splitting, cross-entropy importance sampling or plain Monte Carlo), with its interval.
    FailureProbability {
        /// Scenario file (TOML) or built-in name with a [falsify] section and an [envelope].
        scenario: String,
        /// Controller.
        #[arg(long, short = 'c', value_parser = controller_names)]
        controller: String,
        /// Estimator (default: plain Monte Carlo when the flights draw sensor, turbulence, drag or motor noise, which cross-entropy cannot move and splitting does not yet estimate reliably on real rungs; else cross-entropy).
        #[arg(long, value_enum)]
        method: Option<falsify::Method>,
        /// Flights of cross-entropy (its levels included) or plain Monte Carlo.
        #[arg(long, allow_negative_numbers = true, default_value_t = ftsmc_sim::defaults::FAILURE_PROBABILITY_BUDGET)]
        budget: u64,
        /// Splitting: particles per repetition.
        #[arg(long, allow_negative_numbers = true, default_value_t = falsify::SPLITTING_PARTICLES)]
        particles: usize,
        /// Splitting: independent repetitions (their spread gives the interval).
        #[arg(long, allow_negative_numbers = true, default_value_t = falsify::SPLITTING_REPETITIONS)]
        repetitions: usize,
        /// Most flights of the whole run (splitting's branches and --plain included); work that needs more is refused before it starts.
        #[arg(long, allow_negative_numbers = true, default_value_t = falsify::SPLITTING_MAX_FLIGHTS)]
        max_flights: u64,
        /// Confidence level of the interval.
        #[arg(long, allow_negative_numbers = true, default_value_t = ftsmc_sim::defaults::CONFIDENCE)]
        confidence: f64,
        /// Also fly N plain Monte Carlo flights and print their estimate beside it (0: none).
        #[arg(long, allow_negative_numbers = true, default_value_t = 0)]
        plain: u64,
        /// Seed of the proposal draws (default: the scenario's `seed`, also the master seed of the draws).
        #[arg(long, allow_negative_numbers = true)]
        seed: Option<u64>,
        /// Worker threads (default: all cores). Results do not depend on it.
        #[arg(long, allow_negative_numbers = true)]
        threads: Option<usize>,
        /// Parent folder: the results go to `OUT/<scenario name>/`.
        #[arg(long, default_value = "results/failure-probability")]
        out: PathBuf,
        /// Raise a cost limit (repeatable).
        #[arg(long = "limit", value_name = "KEY=VALUE")]
        limit: Vec<String>,
        /// Set a scenario key (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
    /// Fly controllers or gain files on one scenario's draws; intervals, paired verdicts, a forest plot.
    Compare {
        /// Scenario file (TOML) or built-in name: its vehicle, wind and [montecarlo] draws.
        scenario: String,
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
        /// Confidence level of every interval and verdict (family-wise error 1 − confidence).
        #[arg(long, default_value_t = ftsmc_sim::defaults::CONFIDENCE)]
        confidence: f64,
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
        mission: ftsmc_sim::analysis::missions::Mission,
        /// Master seed (default: the scenario's `seed`).
        #[arg(long)]
        seed: Option<u64>,
        /// Worker threads (default: all cores). Results do not depend on it.
        #[arg(long)]
        threads: Option<usize>,
        /// Flights each thread flies side by side: 1, 2, 4 or 8. Results do not depend on it.
        #[arg(long, default_value_t = ftsmc_sim::batch::montecarlo::DEFAULT_LANES)]
        lanes: usize,
        /// Parent folder: the results go to `OUT/<scenario name>/`.
        #[arg(long, default_value = "results/compare")]
        out: PathBuf,
        /// Skip the forest plot.
        #[arg(long, conflicts_with = "style")]
        no_figures: bool,
        /// Raise a cost limit (repeatable; see docs/scenarios.md).
        #[arg(long = "limit", value_name = "KEY=VALUE")]
        limit: Vec<String>,
        /// Set a scenario key, e.g. `--set vehicle.preset=crazyflie-2` (repeatable; the dotted keys of Python's
        /// `Scenario.with_overrides`).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
    /// Join the shard folders of `ftsmc montecarlo --shard K/N` into the unsharded result (runs.csv, summary.json).
    Merge {
        /// Shard folders (all N of one campaign, any order).
        #[arg(required = true, value_name = "DIR")]
        shards: Vec<PathBuf>,
        /// Parent folder: the merged result goes to `OUT/<scenario name>/`.
        #[arg(long, default_value = "results/montecarlo")]
        out: PathBuf,
        /// Skip the box-plot figure.
        #[arg(long, conflicts_with = "style")]
        no_figures: bool,
        /// Confidence level of every interval in the tables and summary.json (recorded there).
        #[arg(long, default_value_t = ftsmc_sim::defaults::CONFIDENCE)]
        confidence: f64,
    },
    /// Tune controllers' declared gains on a scenario by CMA-ES over Monte Carlo flights; judge on held-out seeds.
    Tune {
        /// Scenario file (TOML) or built-in name; its [tune] section (optional) narrows the parameters and sets the cost.
        scenario: String,
        /// Controller to tune; a comma-separated list or `all` tunes each on an equal budget, then compares them on
        /// the same held-out draws.
        #[arg(long, short = 'c', value_parser = controller_names)]
        controller: String,
        /// Confidence level of every interval and verdict (family-wise error 1 − confidence).
        #[arg(long, default_value_t = ftsmc_sim::defaults::CONFIDENCE)]
        confidence: f64,
        /// Training flights the search may fly per controller (the start's and the race's included).
        #[arg(long, allow_negative_numbers = true, default_value_t = ftsmc_sim::defaults::TUNE_BUDGET)]
        budget: u64,
        /// Seed of the search and of the Monte Carlo draws (default: the scenario's `seed`).
        #[arg(long, allow_negative_numbers = true)]
        seed: Option<u64>,
        /// Worker threads (default: all cores). Results do not depend on it.
        #[arg(long, allow_negative_numbers = true)]
        threads: Option<usize>,
        /// Parent folder: the results go to `OUT/<scenario name>/`.
        #[arg(long, default_value = "results/tune")]
        out: PathBuf,
        /// Skip the convergence figure.
        #[arg(long, conflicts_with = "style")]
        no_figures: bool,
        /// Raise a cost limit, e.g. `--limit max_flights=1e6` (repeatable; see docs/scenarios.md).
        #[arg(long = "limit", value_name = "KEY=VALUE")]
        limit: Vec<String>,
        /// Set a scenario key, e.g. `--set vehicle.preset=crazyflie-2` or `--set wind.preset=breeze` (repeatable;
        /// the dotted keys of Python's `Scenario.with_overrides`; recorded in the written scenario.toml).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
    /// Rerun the documented TSM-STA gain procedure (match RANFTSMC's scenario-1 settling times) and print the gains as TOML.
    TuneTsmSta {
        /// Scenario to tune on (file or built-in name).
        #[arg(long, default_value = "paper-scenario-1")]
        scenario: String,
        /// Set a scenario key, e.g. `--set vehicle.preset=crazyflie-2` or `--set wind.preset=breeze` (repeatable;
        /// the dotted keys of Python's `Scenario.with_overrides`; recorded in the written scenario.toml).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
    /// Print a built-in scenario as TOML (a starting point for your own; `ftsmc list` describes them).
    Scenario {
        /// Built-in scenario name.
        #[arg(value_parser = built_in_names())]
        name: String,
    },
    /// List controllers and built-in scenarios.
    List,
    /// PX4 gains in and out: the PID's gains as a QGroundControl parameter file, and back (docs/px4.md).
    Px4 {
        #[command(subcommand)]
        action: Px4Action,
    },
}

#[derive(Subcommand)]
enum Px4Action {
    /// Write the scenario's [pid] gains as a QGroundControl .params file under PX4's names and units.
    Export {
        /// Scenario file (TOML) or built-in name: its [pid] gains and its vehicle (the normalisation).
        scenario: String,
        /// Output file (never overwritten); default: standard output.
        #[arg(long, short = 'o')]
        out: Option<PathBuf>,
        /// Set a scenario key, e.g. `--set vehicle.preset=px4-x500` (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
    /// Convert a QGroundControl .params file into a [pid] section for a scenario's vehicle.
    Import {
        /// QGroundControl parameter file (.params).
        params: PathBuf,
        /// Scenario file or built-in name whose vehicle the gains are normalised to (the rotors' thrust, arm, inertia).
        #[arg(long)]
        scenario: String,
        /// Output file (never overwritten); default: standard output.
        #[arg(long, short = 'o')]
        out: Option<PathBuf>,
        /// Set a scenario key, e.g. `--set vehicle.preset=px4-x500` (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
}

/// `ftsmc compare --until-decided`: most runs per contestant without `--max-runs`.
const COMPARE_MAX_RUNS: u64 = ftsmc_sim::defaults::COMPARE_MAX_RUNS;
/// `ftsmc compare --until-decided`: runs per look without `--batch`.
const COMPARE_BATCH: u64 = ftsmc_sim::defaults::COMPARE_BATCH;

/// Load a scenario from a file path or a built-in name.
pub fn load_scenario(arg: &str) -> Result<Scenario> {
    load_scenario_with_limits(arg, &[], &[])
}

/// [`load_scenario`] with `--limit KEY=VALUE` overrides applied before the
/// scenario is priced (they win over its `[limits]`), then the `--set
/// KEY=VALUE` keys (`Scenario::with_overrides`, as Python's).
pub fn load_scenario_with_limits(arg: &str, limits: &[String], sets: &[String]) -> Result<Scenario> {
    let path = PathBuf::from(arg);
    let loaded = if path.exists() {
        Some(Scenario::load_with_warnings(&path, limits)?)
    } else {
        match ftsmc_sim::scenario::resolve::built_in(arg) {
            Some((file, text)) => Some(Scenario::from_toml_str_with_warnings(text, file, limits)?),
            None => None,
        }
    };
    if let Some(mut loaded) = loaded {
        if !sets.is_empty() {
            let sets = sets
                .iter()
                .map(|a| ftsmc_sim::scenario::overrides::parse_set(a))
                .collect::<Result<Vec<_>, _>>()
                .map_err(anyhow::Error::msg)?;
            let warnings = std::mem::take(&mut loaded.warnings);
            loaded = loaded.scenario.with_overrides(&sets)?;
            // The file's own warnings, then those of the overridden scenario not already given.
            let extra: Vec<String> = std::mem::take(&mut loaded.warnings);
            loaded.warnings = warnings;
            loaded.warnings.extend(extra);
        }
        for warning in &loaded.warnings {
            eprintln!("warning: {warning}");
        }
        return Ok(loaded.scenario);
    }
    bail!(
        "no scenario file `{}` (and it is not a built-in scenario: {})",
        ftsmc_sim::scenario::show_str(arg),
        ftsmc_sim::scenario::resolve::built_in_names_joined()
    )
}

/// The built-in scenario names (file names without `.toml`), for `ftsmc scenario`.
fn built_in_names() -> clap::builder::PossibleValuesParser {
    clap::builder::PossibleValuesParser::new(ftsmc_sim::scenario::resolve::built_in_names())
}

/// The value parser of every `-c`: a value naming no controller (`-c ''`,
/// `-c ','`, an empty entry of a comma-separated list) is refused, naming
/// the flag, instead of meaning "no controllers" or an unknown name ``.
fn controller_names(value: &str) -> Result<String, String> {
    if value.split(',').all(|name| name.trim().is_empty()) {
        return Err("no controller named: expected a name such as `pid`, or a comma-separated list such as \
                    `pid,se3` (`ftsmc list` lists them)"
            .into());
    }
    Ok(value.to_string())
}

fn check_names(names: &[String]) -> Result<()> {
    for name in names {
        registry::check_name(name).map_err(|known| anyhow::anyhow!("unknown controller `{name}` (known: {known})"))?;
    }
    Ok(())
}

fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    if let Some(style) = cli.style {
        plot::set_style(style);
    }
    match run(cli) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(err) => {
            // `{:#}` prints the whole context chain and, unlike returning
            // the error from main, never a stack backtrace; `one_line` keeps
            // it one bounded line (a parser's multi-line source snippet of
            // a huge line would otherwise print hundreds of KiB).
            eprintln!("error: {}", output::one_line(&format!("{err:#}"), output::MAX_ERROR_CHARS));
            std::process::ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Reproduce {
            out,
            no_figures,
            realistic_runs,
            limit,
            confidence,
            tuned_runs,
            worst_case_budget,
            mission_runs,
            mission_window,
            mission_band,
        } => {
            ftsmc_sim::stats::check_confidence(confidence).map_err(|e| anyhow::anyhow!("--confidence: {e}"))?;
            reproduce::price_realistic_runs(realistic_runs, &limit)?;
            // Two gain sets per tuned file, on the ladder's vehicles: priced as twice the runs per rung.
            reproduce::price_realistic_runs(tuned_runs.saturating_mul(2), &limit)
                .map_err(|e| anyhow::anyhow!("--tuned-runs {tuned_runs}: {e:#}"))?;
            if worst_case_budget > 0 {
                anyhow::ensure!(
                    worst_case_budget >= 20,
                    "--worst-case-budget {worst_case_budget}: cross-entropy sampling needs at least 20 flights (0: no table)"
                );
                falsify::check_budget(worst_case_budget).map_err(|e| anyhow::anyhow!("--worst-case-budget: {e}"))?;
            }
            // Three missions on four rungs: priced like the ladder's runs per rung.
            reproduce::price_realistic_runs(mission_runs, &limit)
                .map_err(|e| anyhow::anyhow!("--mission-runs {mission_runs}: {e:#}"))?;
            let missions = ftsmc_sim::analysis::missions::MissionOptions { window: mission_window, band: mission_band };
            let options = reproduce::Options {
                figures: !no_figures,
                realistic_runs,
                tuned_runs,
                confidence,
                worst_case_budget,
                mission_runs,
                missions,
            };
            reproduce::reproduce(&out, &options)
        }
        Command::Run { scenario, controllers, out, no_figures, limit, set } => {
            let mut scenario = load_scenario_with_limits(&scenario, &limit, &set)?;
            let names = if controllers.is_empty() { scenario.controllers.clone() } else { controllers };
            check_names(&names)?;
            scenario.check_cost(names.len())?;
            ftsmc_sim::batch::gains_fit::check(&scenario, &names)?;
            // The resolved scenario (written as scenario.toml) lists what was flown.
            scenario.controllers = names;
            reproduce::run_scenario(&scenario, &out, !no_figures)
        }
        Command::FixedTime { scenario, controllers, per_decade, out, limit, set } => {
            let mut scenario = load_scenario_with_limits(&scenario, &limit, &set)?;
            let controllers = if controllers.is_empty() { scenario.controllers.clone() } else { controllers };
            check_names(&controllers)?;
            scenario.controllers = controllers.clone();
            anyhow::ensure!(per_decade >= 1, "--per-decade must be at least 1");
            ftsmc_sim::limits::check_sweep(&scenario.limits, ftsmc_sim::limits::sweep_points(5, per_decade as u64))?;
            // With `max_sweep_points = inf` the check is off: refuse what
            // cannot be counted or held in memory instead of overflowing.
            let points = per_decade.checked_mul(5).and_then(|n| n.checked_add(1));
            let fits = points.is_some_and(|n| Vec::<f64>::new().try_reserve_exact(n).is_ok());
            anyhow::ensure!(fits, "--per-decade {per_decade}: 5 × {per_decade} + 1 magnitudes do not fit in memory");
            let sim = &scenario.simulation;
            let t_max = ftsmc_sim::analysis::fixed_time::SweepSettings::default().t_max;
            scenario.limits.ensure(
                "max_steps",
                "integration steps per sweep flight (60 s × control_rate × substeps)",
                t_max * sim.control_rate * f64::from(sim.substeps),
            )?;
            let settings = ftsmc_sim::analysis::fixed_time::SweepSettings {
                magnitudes: ftsmc_sim::analysis::fixed_time::SweepSettings::log_magnitudes(-3, 2, per_decade),
                dt: scenario.control_period(),
                ..Default::default()
            };
            fixed_time::run(&scenario, &controllers, &settings, &out)
        }
        Command::Montecarlo {
            scenario,
            runs,
            seed,
            threads,
            lanes,
            controllers,
            out,
            no_figures,
            limit,
            set,
            shard,
            confidence,
        } => {
            ftsmc_sim::stats::check_confidence(confidence).map_err(|e| anyhow::anyhow!("--confidence: {e}"))?;
            let mut scenario = load_scenario_with_limits(&scenario, &limit, &set)?;
            let names = if controllers.is_empty() { scenario.controllers.clone() } else { controllers };
            check_names(&names)?;
            anyhow::ensure!(runs >= 1, "--runs must be at least 1");
            anyhow::ensure!(threads != Some(0), "--threads must be at least 1");
            // A shard is priced by the runs it flies.
            let own = shard.map_or(Ok(0..runs), |k| k.range(runs))?;
            ftsmc_sim::limits::check_batch(&scenario.flight_size(), own.end - own.start, names.len())?;
            ftsmc_sim::batch::gains_fit::check(&scenario, &names)?;
            if let Some(n) = threads {
                ftsmc_sim::limits::check_threads(&scenario.limits, n)?;
            }
            // The resolved scenario (scenario.toml) carries the master seed and
            // the controllers flown, so re-running it gives the same batch.
            scenario.seed = seed.unwrap_or(scenario.seed);
            scenario.controllers = names;
            anyhow::ensure!(
                ftsmc_sim::batch::montecarlo::LANE_COUNTS.contains(&lanes),
                "--lanes {lanes}: expected one of {:?}",
                ftsmc_sim::batch::montecarlo::LANE_COUNTS
            );
            let options = montecarlo::Options { runs, shard, threads, lanes, confidence, figures: !no_figures };
            montecarlo::run(&scenario, &options, &out)
        }
        Command::Tune { scenario: arg, controller, confidence, budget, seed, threads, out, no_figures, limit, set } => {
            let scenario = load_scenario_with_limits(&arg, &limit, &set)?;
            let controllers = tune::controller_list(&controller);
            check_names(&controllers)?;
            ftsmc_sim::stats::check_confidence(confidence).map_err(|e| anyhow::anyhow!("--confidence: {e}"))?;
            anyhow::ensure!(threads != Some(0), "--threads must be at least 1");
            let settings = scenario.tune.clone().unwrap_or_default();
            ftsmc_sim::limits::check_batch(
                &scenario.flight_size(),
                budget.saturating_add(2 * settings.validation_runs),
                controllers.len(),
            )?;
            if let Some(n) = threads {
                ftsmc_sim::limits::check_threads(&scenario.limits, n)?;
            }
            let seed = seed.unwrap_or(scenario.seed);
            let request =
                tune::Request { budget, seed: Some(seed), threads, out: &out, figures: !no_figures, confidence };
            tune::run(&scenario, &arg, &controllers, &request)
        }
        Command::Falsify { scenario: arg, controller, budget, seed, threads, out, no_figures, limit, set } => {
            let scenario = load_scenario_with_limits(&arg, &limit, &set)?;
            check_names(std::slice::from_ref(&controller))?;
            anyhow::ensure!(threads != Some(0), "--threads must be at least 1");
            let budget = falsify::budget_of(&scenario, budget);
            falsify::check_budget(budget)?;
            ftsmc_sim::limits::check_batch(&scenario.flight_size(), budget.saturating_mul(2).saturating_add(3), 1)?;
            if let Some(n) = threads {
                ftsmc_sim::limits::check_threads(&scenario.limits, n)?;
            }
            let seed = seed.unwrap_or(scenario.seed);
            falsify::run(&scenario, &controller, budget, seed, threads, &out, !no_figures)
        }
        Command::FailureProbability {
            scenario: arg,
            controller,
            method,
            budget,
            particles,
            repetitions,
            max_flights,
            confidence,
            plain,
            seed,
            threads,
            out,
            limit,
            set,
        } => {
            let scenario = load_scenario_with_limits(&arg, &limit, &set)?;
            check_names(std::slice::from_ref(&controller))?;
            anyhow::ensure!(threads != Some(0), "--threads must be at least 1");
            let method = method.unwrap_or_else(|| falsify::Method::default_for(&scenario));
            let flights = falsify::check_max_flights(method, budget, particles, repetitions, plain, max_flights)?;
            falsify::check_budget(flights)?;
            ftsmc_sim::limits::check_batch(&scenario.flight_size(), flights.saturating_add(plain), 1)?;
            if let Some(n) = threads {
                ftsmc_sim::limits::check_threads(&scenario.limits, n)?;
            }
            let seed = seed.unwrap_or(scenario.seed);
            let request = falsify::FailureRequest {
                method,
                budget,
                splitting: ftsmc_sim::falsify::splitting::Settings::new(
                    particles,
                    repetitions,
                    max_flights - plain,
                    confidence,
                ),
                seed,
                confidence,
                plain_runs: plain,
                threads,
            };
            falsify::run_failure_probability(&scenario, &controller, &request, &out)
        }
        Command::Compare {
            scenario,
            contestants,
            mission,
            runs,
            until_decided,
            max_runs,
            batch,
            confidence,
            min_effect,
            allow_other_vehicle,
            seed,
            threads,
            lanes,
            out,
            no_figures,
            limit,
            set,
        } => {
            let min_effect = if min_effect.is_empty() {
                None
            } else {
                Some(ftsmc_sim::batch::verdicts::MinEffect::parse(&min_effect).map_err(anyhow::Error::msg)?)
            };
            anyhow::ensure!(
                !contestants.is_empty(),
                "compare needs its contestants, -c/--controllers: controller names or gain files (-c pid,se3 or \
                 -c pid.tuned.toml,pid)"
            );
            if !until_decided {
                // Given without the sequential plan they would be ignored.
                for (flag, value) in [("--max-runs", max_runs), ("--batch", batch)] {
                    anyhow::ensure!(
                        value.is_none(),
                        "{flag} sets the sequential plan: it needs --until-decided (a fixed number of runs is --runs)"
                    );
                }
            }
            let (max_runs, batch) = (max_runs.unwrap_or(COMPARE_MAX_RUNS), batch.unwrap_or(COMPARE_BATCH));
            let scenario = load_scenario_with_limits(&scenario, &limit, &set)?;
            // `steps` is the scenario itself (its bits unchanged).
            let mut scenario = ftsmc_sim::analysis::missions::mission_scenario(&scenario, mission, Default::default())?;
            ftsmc_sim::stats::check_confidence(confidence).map_err(|e| anyhow::anyhow!("--confidence: {e}"))?;
            anyhow::ensure!(
                runs >= 1 && max_runs >= 1 && batch >= 1,
                "--runs, --max-runs and --batch must be at least 1"
            );
            anyhow::ensure!(threads != Some(0), "--threads must be at least 1");
            anyhow::ensure!(
                ftsmc_sim::batch::montecarlo::LANE_COUNTS.contains(&lanes),
                "--lanes {lanes}: expected one of {:?}",
                ftsmc_sim::batch::montecarlo::LANE_COUNTS
            );
            if let Some(n) = threads {
                ftsmc_sim::limits::check_threads(&scenario.limits, n)?;
            }
            scenario.seed = seed.unwrap_or(scenario.seed);
            let plan = if until_decided {
                ftsmc_sim::batch::compare::Plan::UntilDecided { batch, max_runs }
            } else {
                ftsmc_sim::batch::compare::Plan::Fixed { runs }
            };
            compare::run(&compare::Request {
                scenario: &scenario,
                contestants: &contestants,
                plan,
                confidence,
                min_effect,
                allow_other_vehicle,
                threads,
                lanes,
                out: &out,
                figures: !no_figures,
                limits: &limit,
            })
        }
        Command::Merge { shards, out, no_figures, confidence } => {
            ftsmc_sim::stats::check_confidence(confidence).map_err(|e| anyhow::anyhow!("--confidence: {e}"))?;
            merge::merge(&shards, &out, !no_figures, confidence)
        }
        Command::Px4 { action: Px4Action::Export { scenario: arg, out, set } } => {
            let scenario = load_scenario_with_limits(&arg, &[], &set)?;
            px4::export(&scenario, &arg, out.as_deref())
        }
        Command::Px4 { action: Px4Action::Import { params, scenario: arg, out, set } } => {
            let scenario = load_scenario_with_limits(&arg, &[], &set)?;
            px4::import(&params, &scenario, &arg, out.as_deref())
        }
        Command::TuneTsmSta { scenario, set } => {
            let scenario = load_scenario_with_limits(&scenario, &[], &set)?;
            let r = ftsmc_sim::analysis::tuning::tune_tsm_sta(
                &scenario,
                &ftsmc_core::tsm_sta::TsmStaGains::BASE_POSITION,
                &ftsmc_core::tsm_sta::TsmStaGains::BASE_ATTITUDE,
            )
            .map_err(anyhow::Error::msg)?;
            println!("# TSM-STA gains from the procedure of docs/results.md (ftsmc tune-tsm-sta)");
            println!("# time-scale factors: position {:.6}, attitude {:.6}", r.position_scale, r.attitude_scale);
            println!(
                "# RANFTSMC settling (slowest of x,y,z; psi): {:.3} s, {:.3} s; TSM-STA achieves {:.3} s, {:.3} s",
                r.target[0], r.target[1], r.achieved[0], r.achieved[1]
            );
            for (axis, g) in r.gains.named() {
                println!("\n[tsm-sta.{axis}]");
                print!("{}", toml::to_string(g)?);
            }
            Ok(())
        }
        Command::Scenario { name } => {
            let (_, text) = ftsmc_sim::scenario::resolve::built_in(&name).with_context(|| {
                format!(
                    "no built-in scenario `{name}` (built-in: {})",
                    ftsmc_sim::scenario::resolve::built_in_names_joined()
                )
            })?;
            print!("{text}");
            Ok(())
        }
        Command::List => {
            print!("{}", list_text()?);
            Ok(())
        }
        Command::Identify(args) => identify::run(args),
        Command::Validate(args) => validate::run(args),
    }
}

/// `--mission NAME`: one of `ftsmc_sim::analysis::missions::Mission`.
fn parse_mission(name: &str) -> Result<ftsmc_sim::analysis::missions::Mission, String> {
    ftsmc_sim::analysis::missions::Mission::from_name(name)
        .ok_or_else(|| format!("`{name}`: expected one of {}", ftsmc_sim::analysis::missions::Mission::names_joined()))
}

/// `ftsmc list`: every controller of the registry and every built-in
/// scenario (`BUILT_IN_SCENARIOS`), names in one aligned column.
fn list_text() -> Result<String> {
    let scenarios = BUILT_IN_SCENARIOS
        .iter()
        .map(|(file, text)| {
            let s = Scenario::from_toml_str(text, file)?;
            // A scenario with wind says it in a user's words, computed from its [wind].
            let description = match ftsmc_sim::scenario::ladder::rung_words(&s) {
                Some(words) => format!("{} — {words}", s.description),
                None => s.description,
            };
            Ok((file.trim_end_matches(".toml").to_string(), description))
        })
        .collect::<Result<Vec<_>>>()?;
    let width = registry::CONTROLLERS
        .iter()
        .map(|(name, _)| name.chars().count())
        .chain(scenarios.iter().map(|(name, _)| name.chars().count()))
        .max()
        .unwrap_or(0);
    let mut text = String::from("controllers (-c/--controllers):\n");
    for (name, what) in registry::CONTROLLERS {
        text.push_str(&format!("  {name:<width$}  {what}\n"));
    }
    text.push_str("built-in scenarios (ftsmc run NAME, ftsmc scenario NAME):\n");
    for (name, what) in &scenarios {
        text.push_str(&format!("  {name:<width$}  {what}\n"));
    }
    text.push_str("vehicle presets ([vehicle] preset = NAME, --set vehicle.preset=NAME; docs/vehicles.md):\n");
    for preset in ftsmc_sim::vehicle::VehiclePreset::ALL {
        text.push_str(&format!("  {:<width$}  {}\n", preset.name(), preset.description()));
    }
    Ok(text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_unknown_scenario_error_lists_every_built_in_scenario() {
        // As `main` prints it: one line of at most MAX_ERROR_CHARS, even for a long name.
        let arg = "no-such-scenario-anywhere-with-a-rather-long-name-indeed.toml";
        let err = load_scenario(arg).expect_err("unknown");
        let line = output::one_line(&format!("{err:#}"), output::MAX_ERROR_CHARS);
        assert!(line.starts_with("no scenario file `no-such-scenario") && line.ends_with(')'), "cut: {line}");
        let list = line.rsplit_once(": ").unwrap().1.trim_end_matches(')');
        let mut listed = Vec::new();
        for group in list.split(", ") {
            let mut parts = group.split('/');
            let first = parts.next().unwrap();
            listed.push(first.to_string());
            listed.extend(parts.map(|last| format!("{}{last}", &first[..first.len() - 1])));
        }
        let names: Vec<String> = ftsmc_sim::scenario::resolve::built_in_names().map(String::from).collect();
        assert_eq!(listed, names, "{line}");
    }

    #[test]
    fn mission_names_round_trip_and_a_wrong_one_lists_them() {
        for m in ftsmc_sim::analysis::missions::Mission::ALL {
            assert_eq!(parse_mission(m.name()), Ok(m));
        }
        let e = parse_mission("eight").unwrap_err();
        assert_eq!(e, "`eight`: expected one of steps, hover, figure-eight, waypoints");
    }

    #[test]
    fn list_names_every_built_in_scenario_and_vehicle_preset_in_one_aligned_column() {
        let text = list_text().unwrap();
        for (file, _) in BUILT_IN_SCENARIOS {
            assert!(text.contains(file.trim_end_matches(".toml")), "{file} missing:\n{text}");
        }
        let starts: Vec<usize> = text
            .lines()
            .filter(|l| l.starts_with("  "))
            .map(|l| {
                let name_end = 2 + l[2..].find(' ').unwrap();
                name_end + l[name_end..].chars().take_while(|c| *c == ' ').count()
            })
            .collect();
        let presets = ftsmc_sim::vehicle::VehiclePreset::ALL;
        assert_eq!(starts.len(), registry::CONTROLLERS.len() + BUILT_IN_SCENARIOS.len() + presets.len());
        for p in presets {
            assert!(
                text.lines().any(|l| l.trim_start().starts_with(p.name()) && l.ends_with(&p.description())),
                "{text}"
            );
        }
        for (name, what) in registry::CONTROLLERS {
            assert!(text.lines().any(|l| l.trim_start().starts_with(name) && l.ends_with(what)), "{name}:\n{text}");
        }
        assert!(starts.windows(2).all(|w| w[0] == w[1]), "descriptions not aligned:\n{text}");
    }
}
