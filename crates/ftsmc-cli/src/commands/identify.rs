//! `ftsmc identify LOG… [--mass M] [--vehicle FILE|preset] --out DIR`:
//! the vehicle parameters the logs identify (ftsmc_ident::identify), with
//! bootstrap intervals, as a vehicle file the simulator flies and as tables.
//!
//! Writes DIR/vehicle.toml (a scenario layer: `[vehicle]`, `[plant]`,
//! `[actuators]` over the base vehicle, intervals in its header),
//! DIR/parameters.csv and DIR/identification.json.

use anyhow::{Context, Result};
use ftsmc_ident::identify::{identify, IdentifyOptions};
use ftsmc_ident::report;
use ftsmc_ident::vehicle::Vehicle;

use crate::log_args::LogArgs;
use crate::output::write_atomic;

/// Arguments of `ftsmc identify`.
#[derive(clap::Args)]
pub struct Args {
    /// Logs, output folder, bootstrap and seed.
    #[command(flatten)]
    pub common: LogArgs,
    /// Vehicle mass, kg (default: the base vehicle's); forces, inertias and drags need it.
    #[arg(long)]
    pub mass: Option<f64>,
    /// Base vehicle: a preset name or a scenario/vehicle file (its layout, max rotor speed, J_z).
    #[arg(long, default_value = "crazyflie-2.1")]
    pub vehicle: String,
    /// Bootstrap segment length, s.
    #[arg(long, default_value_t = 2.0)]
    pub segment: f64,
    /// Largest command delay tried, log steps (the log's timing; `ftsmc validate --command-delay` applies it).
    #[arg(long, default_value_t = 5)]
    pub max_delay: usize,
}

/// Runs `ftsmc identify`.
pub fn run(a: Args) -> Result<()> {
    let base = Vehicle::load(&a.vehicle)?;
    let series = a.common.read_series("identification")?;
    let options = IdentifyOptions {
        mass_kg: a.mass,
        segment_s: a.segment,
        bootstrap: a.common.bootstrap,
        seed: a.common.seed,
        max_delay_steps: a.max_delay,
        ..Default::default()
    };
    let id = identify(&series, &base, &options)?;
    std::fs::create_dir_all(&a.common.out).with_context(|| format!("cannot create {}", a.common.out.display()))?;
    let base_path = match &base.file {
        Some(f) => Some(std::fs::canonicalize(f).with_context(|| format!("cannot resolve {f}"))?.display().to_string()),
        None => None,
    };
    write_atomic(&a.common.out.join("vehicle.toml"), id.vehicle_toml(base_path.as_deref()).as_bytes())?;
    write_atomic(&a.common.out.join("parameters.csv"), report::parameters_csv(&id).as_bytes())?;
    let report = report::identification_json(&id);
    write_atomic(&a.common.out.join("identification.json"), serde_json::to_string_pretty(&report)?.as_bytes())?;
    println!(
        "identified from {} log(s): {} sample steps in {} segments, {} bootstrap replicates",
        id.flights.len(),
        id.rows,
        id.segments,
        id.replicates
    );
    println!("{:<34} {:>13} {:>13} {:>13} {:>13}", "parameter", "value", "2.5 %", "97.5 %", "base");
    for e in &id.estimates {
        println!("{:<34} {:>13.5e} {:>13.5e} {:>13.5e} {:>13.5e}", e.name, e.value, e.lo, e.hi, e.base);
    }
    for (n, v) in &id.r2 {
        println!("R² {n}: {v:.4}");
    }
    println!("wrote {}", a.common.out.join("vehicle.toml").display());
    Ok(())
}
