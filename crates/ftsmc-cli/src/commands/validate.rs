//! `ftsmc validate LOG… --vehicle FILE|preset --out DIR`: open-loop
//! validation of the vehicle on the logs (ftsmc_ident::validate): predicted
//! against measured specific force and angular acceleration, one step,
//! 0.1 s and 0.5 s, per axis, beside the constant-acceleration baseline.
//!
//! Writes DIR/validation.csv and DIR/validation.json.

use anyhow::{Context, Result};
use ftsmc_ident::report;
use ftsmc_ident::validate::{validate, ValidateOptions};
use ftsmc_ident::vehicle::Vehicle;

use crate::log_args::LogArgs;
use crate::output::write_atomic;

/// Arguments of `ftsmc validate`.
#[derive(clap::Args)]
pub struct Args {
    /// Logs, output folder, bootstrap and seed.
    #[command(flatten)]
    pub common: LogArgs,
    /// The vehicle: a preset name or a vehicle file (e.g. `ftsmc identify`'s vehicle.toml).
    #[arg(long)]
    pub vehicle: String,
    /// The logged commands act this many log steps later (`ftsmc identify`'s command_delay_steps).
    #[arg(long, default_value_t = 0)]
    pub command_delay: usize,
}

/// Runs `ftsmc validate`.
pub fn run(a: Args) -> Result<()> {
    let vehicle = Vehicle::load(&a.vehicle)?;
    let series = a.common.read_series("validation")?;
    let rows = validate(
        &series,
        &vehicle,
        &ValidateOptions {
            bootstrap: a.common.bootstrap,
            seed: a.common.seed,
            command_delay_steps: a.command_delay,
            ..Default::default()
        },
    )?;
    std::fs::create_dir_all(&a.common.out).with_context(|| format!("cannot create {}", a.common.out.display()))?;
    write_atomic(&a.common.out.join("validation.csv"), report::validation_csv(&rows).as_bytes())?;
    let flights: Vec<String> = series.iter().map(|s| s.source.clone()).collect();
    let report = report::validation_json(&vehicle.name, &flights, &rows);
    write_atomic(&a.common.out.join("validation.json"), serde_json::to_string_pretty(&report)?.as_bytes())?;
    println!(
        "{:<8} {:<21} {:<4} {:>8} {:>19} {:>10} {:>10} {:>10}",
        "horizon", "quantity", "axis", "R²", "R² interval", "RMS", "base R²", "base RMS"
    );
    for r in rows.iter().filter(|r| r.flight == "all") {
        println!(
            "{:<8.3} {:<21} {:<4} {:>8.4} [{:>8.4}, {:>8.4}] {:>10.4} {:>10.4} {:>10.4}",
            r.horizon_s, r.quantity, r.axis, r.r2, r.r2_lo, r.r2_hi, r.rms, r.baseline_r2, r.baseline_rms
        );
    }
    println!("wrote {}", a.common.out.join("validation.csv").display());
    Ok(())
}
