//! The arguments several commands take, each declared once as a flattened
//! clap group (`#[command(flatten)]`): the scenario with its `--set` and
//! `--limit` overrides, worker threads, the seed, the confidence level, the
//! controllers, and the output folder with `--no-figures`. A command file
//! holds only what is its own; loading the scenario and checking these
//! values happens here, so two commands cannot drift apart.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use ftsmc_sim::registry::{self, ControllerList};
use ftsmc_sim::scenario::Scenario;

/// `--set KEY=VALUE` (repeatable): scenario keys changed after loading.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct SetArgs {
    /// Set a scenario key, e.g. `--set vehicle.preset=crazyflie-2` or `--set wind.preset=breeze` (repeatable;
    /// the dotted keys of Python's `Scenario.with_overrides`; recorded in the written scenario.toml).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
}

/// `--limit KEY=VALUE` (repeatable): cost limits raised over the scenario's `[limits]`.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct LimitArgs {
    /// Raise a cost limit, e.g. `--limit max_steps=1e10` (repeatable; keys: max_steps, max_samples,
    /// max_output_bytes, max_flights, max_sweep_points, max_threads, max_scenario_bytes; see docs/scenarios.md).
    #[arg(long = "limit", value_name = "KEY=VALUE")]
    pub limit: Vec<String>,
}

/// A scenario given as the first positional argument, with its overrides.
#[derive(clap::Args, Clone, Debug)]
pub struct ScenarioArgs {
    /// Scenario file (TOML) or built-in name.
    pub scenario: String,
    /// `--set` keys.
    #[command(flatten)]
    pub set: SetArgs,
    /// `--limit` overrides.
    #[command(flatten)]
    pub limits: LimitArgs,
}

impl ScenarioArgs {
    /// The scenario with its `--limit` and `--set` overrides applied ([`load_scenario_with_limits`]).
    pub fn load(&self) -> Result<Scenario> {
        load_scenario_with_limits(&self.scenario, &self.limits.limit, &self.set.set)
    }
}

/// `--threads N`: worker threads.
#[derive(clap::Args, Clone, Copy, Debug, Default)]
pub struct ThreadsArgs {
    /// Worker threads (default: all cores). Results do not depend on it.
    #[arg(long, allow_negative_numbers = true)]
    pub threads: Option<usize>,
}

impl ThreadsArgs {
    /// `--threads`, refused when 0 or above the scenario's `max_threads`.
    pub fn checked(self, scenario: &Scenario) -> Result<Option<usize>> {
        anyhow::ensure!(self.threads != Some(0), "--threads must be at least 1");
        if let Some(n) = self.threads {
            ftsmc_sim::limits::check_threads(&scenario.limits, n)?;
        }
        Ok(self.threads)
    }
}

/// `--seed N`: the master seed.
#[derive(clap::Args, Clone, Copy, Debug, Default)]
pub struct SeedArgs {
    /// Master seed of the command's draws (default: the scenario's `seed`).
    #[arg(long, allow_negative_numbers = true)]
    pub seed: Option<u64>,
}

impl SeedArgs {
    /// `--seed`, else the scenario's `seed`.
    pub fn or_scenario(self, scenario: &Scenario) -> u64 {
        self.seed.unwrap_or(scenario.seed)
    }
}

/// `--confidence C`: the level of every interval and verdict.
#[derive(clap::Args, Clone, Copy, Debug)]
pub struct ConfidenceArgs {
    /// Confidence level of every interval and verdict (family-wise error 1 − confidence).
    #[arg(long, allow_negative_numbers = true, default_value_t = ftsmc_sim::defaults::CONFIDENCE)]
    pub confidence: f64,
}

impl ConfidenceArgs {
    /// `--confidence`, refused outside (0, 1) naming the flag.
    pub fn checked(self) -> Result<f64> {
        ftsmc_sim::stats::check_confidence(self.confidence).map_err(|e| anyhow::anyhow!("--confidence: {e}"))
    }
}

/// `-c NAME[,NAME…]` (repeatable): the controllers to fly.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct ControllersArgs {
    /// Controller(s) to fly (repeat or comma-separate); default: the scenario's `controllers` list.
    #[arg(long, short = 'c', alias = "controller", value_delimiter = ',', value_parser = controller_names)]
    pub controllers: Vec<String>,
}

impl ControllersArgs {
    /// The controllers given, else the scenario's list, each a known name.
    pub fn or_scenario(&self, scenario: &Scenario) -> Result<Vec<String>> {
        let names = if self.controllers.is_empty() { scenario.controllers.clone() } else { self.controllers.clone() };
        registry::check_controllers("-c/--controllers", &names)?;
        Ok(names)
    }
}

/// `--out DIR` and `--no-figures`. Each command sets the default of `--out`
/// with `#[command(mut_arg("out", …))]`.
#[derive(clap::Args, Clone, Debug)]
pub struct OutputArgs {
    /// Parent folder: the results go to `OUT/<scenario name>/`.
    #[arg(long, default_value = "results")]
    pub out: PathBuf,
    /// Skip figure rendering (tables, CSV and JSON only).
    #[arg(long, conflicts_with = "style")]
    pub no_figures: bool,
}

impl OutputArgs {
    /// Whether figures are drawn.
    pub fn figures(&self) -> bool {
        !self.no_figures
    }
}

/// `--lanes`, refused unless one of the lane counts the batch flies.
pub fn check_lanes(lanes: usize) -> Result<usize> {
    anyhow::ensure!(
        ftsmc_sim::batch::montecarlo::LANE_COUNTS.contains(&lanes),
        "--lanes {lanes}: expected one of {:?}",
        ftsmc_sim::batch::montecarlo::LANE_COUNTS
    );
    Ok(lanes)
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

/// A pool of `threads` workers (`None`: all cores).
pub fn pool(threads: Option<usize>) -> Result<rayon::ThreadPool> {
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(t) = threads {
        builder = builder.num_threads(t);
    }
    builder.build().context("cannot start the thread pool")
}

/// Load a scenario from a file path or a built-in name, with `--limit KEY=VALUE` overrides applied before the
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
    let Some(mut loaded) = loaded else {
        bail!(
            "no scenario file `{}` (and it is not a built-in scenario: {})",
            ftsmc_sim::scenario::show_str(arg),
            ftsmc_sim::scenario::resolve::built_in_names_joined()
        )
    };
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
    Ok(loaded.scenario)
}

/// The value parser of every `-c`: a value naming no controller (`-c ''`,
/// `-c ','`, an empty entry of a comma-separated list) is refused by the
/// library's [`ControllerList::check`] at parse time (a usage error naming
/// the flag), instead of meaning "no controllers" or an unknown name ``.
pub fn controller_names(value: &str) -> Result<String, String> {
    let names: Vec<String> = value.split(',').map(str::to_string).collect();
    ControllerList { argument: "-c", names: &names }.check().map_err(|e| e.to_string())?;
    Ok(value.to_string())
}

/// `--mission NAME`: one of `ftsmc_sim::analysis::missions::Mission`.
pub fn parse_mission(name: &str) -> Result<ftsmc_sim::analysis::missions::Mission, String> {
    ftsmc_sim::analysis::missions::Mission::from_name(name)
        .ok_or_else(|| format!("`{name}`: expected one of {}", ftsmc_sim::analysis::missions::Mission::names_joined()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_unknown_scenario_error_lists_every_built_in_scenario() {
        // As `main` prints it: one line of at most MAX_ERROR_CHARS, even for a long name.
        let arg = "no-such-scenario-anywhere-with-a-rather-long-name-indeed.toml";
        let err = load_scenario_with_limits(arg, &[], &[]).expect_err("unknown");
        let line = crate::output::one_line(&format!("{err:#}"), crate::output::MAX_ERROR_CHARS);
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
}
