//! `ftsmc scenario NAME`: print a built-in scenario as TOML.

use anyhow::{Context, Result};

/// Arguments of `ftsmc scenario`.
#[derive(clap::Args)]
pub struct Args {
    /// Built-in scenario name.
    #[arg(value_parser = built_in_names())]
    name: String,
}

/// The built-in scenario names (file names without `.toml`).
fn built_in_names() -> clap::builder::PossibleValuesParser {
    clap::builder::PossibleValuesParser::new(ftsmc_sim::scenario::resolve::built_in_names())
}

/// Runs `ftsmc scenario`.
pub fn run(args: Args) -> Result<()> {
    let name = args.name;
    let (_, text) = ftsmc_sim::scenario::resolve::built_in(&name).with_context(|| {
        format!("no built-in scenario `{name}` (built-in: {})", ftsmc_sim::scenario::resolve::built_in_names_joined())
    })?;
    print!("{text}");
    Ok(())
}
