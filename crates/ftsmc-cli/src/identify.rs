//! `ftsmc identify LOG… [--mass M] [--vehicle FILE|preset] --out DIR`:
//! the vehicle parameters the logs identify (ftsmc_ident::identify), with
//! bootstrap intervals, as a vehicle file the simulator flies and as tables.
//!
//! Writes DIR/vehicle.toml (a scenario layer: `[vehicle]`, `[plant]`,
//! `[actuators]` over the base vehicle, intervals in its header),
//! DIR/parameters.csv and DIR/identification.json.

use std::path::PathBuf;

use anyhow::{Context, Result};
use ftsmc_ident::identify::{identify, IdentifyOptions};
use ftsmc_ident::series::Series;
use ftsmc_ident::vehicle::Vehicle;
use serde_json::json;

use crate::output::write_atomic;

/// Arguments of `ftsmc identify`.
#[derive(clap::Args)]
pub struct IdentifyArgs {
    /// Flight logs: PX4 ULog, NanoBench CSV or the generic CSV (docs/logs.md).
    #[arg(required = true)]
    pub logs: Vec<PathBuf>,
    /// Vehicle mass, kg (default: the base vehicle's); forces, inertias and drags need it.
    #[arg(long)]
    pub mass: Option<f64>,
    /// Base vehicle: a preset name or a scenario/vehicle file (its layout, max rotor speed, J_z).
    #[arg(long, default_value = "crazyflie-2.1")]
    pub vehicle: String,
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
    /// Bootstrap replicates over flight segments.
    #[arg(long, default_value_t = 200)]
    pub bootstrap: usize,
    /// Seed of the bootstrap.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Bootstrap segment length, s.
    #[arg(long, default_value_t = 2.0)]
    pub segment: f64,
    /// Largest command delay tried, log steps (the log's timing; `ftsmc validate --command-delay` applies it).
    #[arg(long, default_value_t = 5)]
    pub max_delay: usize,
}

/// Reads every log as a [`Series`] for `purpose`.
pub fn read_series(logs: &[PathBuf], purpose: &'static str) -> Result<Vec<Series>> {
    let limits = ftsmc_logs::LogLimits::default();
    logs.iter()
        .map(|p| {
            let log = ftsmc_logs::read_log(p, &limits)?;
            Ok(Series::from_log(&log, purpose)?)
        })
        .collect()
}

/// Runs `ftsmc identify`.
pub fn run(a: IdentifyArgs) -> Result<()> {
    let base = Vehicle::load(&a.vehicle)?;
    let series = read_series(&a.logs, "identification")?;
    let options = IdentifyOptions {
        mass_kg: a.mass,
        segment_s: a.segment,
        bootstrap: a.bootstrap,
        seed: a.seed,
        ..Default::default()
    };
    let id = identify(&series, &base, &options)?;
    std::fs::create_dir_all(&a.out).with_context(|| format!("cannot create {}", a.out.display()))?;
    let base_path = match &base.file {
        Some(f) => Some(std::fs::canonicalize(f).with_context(|| format!("cannot resolve {f}"))?.display().to_string()),
        None => None,
    };
    write_atomic(&a.out.join("vehicle.toml"), id.vehicle_toml(base_path.as_deref()).as_bytes())?;
    let mut csv = String::from("name,unit,value,lo,hi,basis,base\n");
    for e in &id.estimates {
        csv.push_str(&format!("{},{},{:e},{:e},{:e},{},{:e}\n", e.name, e.unit, e.value, e.lo, e.hi, e.basis, e.base));
    }
    write_atomic(&a.out.join("parameters.csv"), csv.as_bytes())?;
    let num = |v: f64| if v.is_finite() { json!(v) } else { json!(null) };
    let report = json!({
        "flights": id.flights,
        "base_vehicle": id.base.name,
        "mass_kg": id.mass_kg,
        "mass_source": id.mass_source,
        "rows": id.rows,
        "segments": id.segments,
        "bootstrap_replicates": id.replicates,
        "seed": id.seed,
        "battery_ref_v": num(id.battery_ref_v),
        "r2": id.r2.iter().map(|(n, v)| (n.to_string(), num(*v))).collect::<serde_json::Map<_, _>>(),
        "thrust_maps": id.thrust_maps.iter().map(|m| json!({
            "name": m.name, "linear_n": m.linear_n, "quadratic_n": m.quadratic_n, "r2": num(m.r2)
        })).collect::<Vec<_>>(),
        "estimates": id.estimates.iter().map(|e| json!({
            "name": e.name, "unit": e.unit, "value": num(e.value), "lo": num(e.lo), "hi": num(e.hi),
            "basis": e.basis, "base": num(e.base)
        })).collect::<Vec<_>>(),
    });
    write_atomic(&a.out.join("identification.json"), serde_json::to_string_pretty(&report)?.as_bytes())?;
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
    println!("wrote {}", a.out.join("vehicle.toml").display());
    Ok(())
}
