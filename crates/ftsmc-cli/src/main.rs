//! `ftsmc` — reproduce the FTAFTSMC quadrotor paper and go beyond it.
//!
//! Run `ftsmc --help` for the commands. This file only declares the
//! command line and dispatches: each subcommand is a module of
//! [`commands`], the argument groups they share are in [`args`].

mod args;
mod bounded_read;
mod campaign;
mod commands;
mod console;
mod cpu;
mod figures;
mod flights;
mod forest;
mod html;
mod intervals;
mod ladder;
mod log_args;
mod output;
mod plot;
mod raster;
mod result_dir;
mod svg;
mod ticks;
mod tuned;
mod worst_case;
#[cfg(test)]
mod writers_fuzz;

use anyhow::Result;
use clap::{Parser, Subcommand};

use commands::{
    compare, failure_probability, falsify, fixed_time, identify, list, merge, montecarlo, px4, reproduce, run,
    scenario, tune, tune_tsm_sta, validate,
};

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
    Identify(identify::Args),
    /// Open-loop validation of a vehicle against flight logs (docs/validation.md).
    Validate(validate::Args),
    /// Run both paper scenarios with every controller; print Table 3 beside the paper's; write CSV, JSON, figures.
    Reproduce(reproduce::Args),
    /// Run one scenario file with its controllers (or those given); write CSV, summary.json and comparison figures.
    Run(run::Args),
    /// Measure reaching and settling times against the initial error (1e-3 … 1e2) beside the paper's fixed-time bound.
    FixedTime(fixed_time::Args),
    /// Fly N randomised copies of a scenario (its [montecarlo] section) with each controller, in parallel.
    Montecarlo(montecarlo::Args),
    /// Search the scenario's [falsify] space for the flight with the lowest robustness margin (CMA-ES with restarts), beside uniform random search at the same budget.
    Falsify(falsify::Args),
    /// Estimate P(margin < 0) under the scenario's own draws (adaptive multilevel splitting, cross-entropy importance sampling or plain Monte Carlo), with its interval.
    FailureProbability(failure_probability::Args),
    /// Fly controllers or gain files on one scenario's draws; intervals, paired verdicts, a forest plot.
    Compare(compare::Args),
    /// Join the shard folders of `ftsmc montecarlo --shard K/N` into the unsharded result (runs.csv, summary.json).
    Merge(merge::Args),
    /// Tune controllers' declared gains on a scenario by CMA-ES over Monte Carlo flights; judge on held-out seeds.
    Tune(tune::Args),
    /// Rerun the documented TSM-STA gain procedure (match RANFTSMC's scenario-1 settling times) and print the gains as TOML.
    TuneTsmSta(tune_tsm_sta::Args),
    /// Print a built-in scenario as TOML (a starting point for your own; `ftsmc list` describes them).
    Scenario(scenario::Args),
    /// List controllers and built-in scenarios.
    List,
    /// PX4 gains in and out: the PID's gains as a QGroundControl parameter file, and back (docs/px4.md).
    Px4(px4::Args),
}

fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    if let Some(style) = cli.style {
        plot::set_style(style);
    }
    match run(cli.command) {
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

/// Dispatch: each command's module parses nothing further and runs.
fn run(command: Command) -> Result<()> {
    match command {
        Command::Identify(args) => identify::run(args),
        Command::Validate(args) => validate::run(args),
        Command::Reproduce(args) => reproduce::run(args),
        Command::Run(args) => run::run(args),
        Command::FixedTime(args) => fixed_time::run(args),
        Command::Montecarlo(args) => montecarlo::run(args),
        Command::Falsify(args) => falsify::run(args),
        Command::FailureProbability(args) => failure_probability::run(args),
        Command::Compare(args) => compare::run(args),
        Command::Merge(args) => merge::run(args),
        Command::Tune(args) => tune::run(args),
        Command::TuneTsmSta(args) => tune_tsm_sta::run(args),
        Command::Scenario(args) => scenario::run(args),
        Command::List => list::run(),
        Command::Px4(args) => px4::run(args),
    }
}
