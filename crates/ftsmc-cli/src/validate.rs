//! `ftsmc validate LOG… --vehicle FILE|preset --out DIR`: open-loop
//! validation of the vehicle on the logs (ftsmc_ident::validate): predicted
//! against measured specific force and angular acceleration, one step,
//! 0.1 s and 0.5 s, per axis, beside the constant-acceleration baseline.
//!
//! Writes DIR/validation.csv and DIR/validation.json.

use std::path::PathBuf;

use anyhow::{Context, Result};
use ftsmc_ident::validate::{validate, ValidateOptions};
use ftsmc_ident::vehicle::Vehicle;
use serde_json::json;

use crate::identify::read_series;
use crate::output::write_atomic;

/// Arguments of `ftsmc validate`.
#[derive(clap::Args)]
pub struct ValidateArgs {
    /// Flight logs: PX4 ULog, NanoBench CSV or the generic CSV (docs/logs.md).
    #[arg(required = true)]
    pub logs: Vec<PathBuf>,
    /// The vehicle: a preset name or a vehicle file (e.g. `ftsmc identify`'s vehicle.toml).
    #[arg(long)]
    pub vehicle: String,
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
    /// Bootstrap replicates over segments for the pooled intervals.
    #[arg(long, default_value_t = 200)]
    pub bootstrap: usize,
    /// Seed of the bootstrap.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// The logged commands act this many log steps later (`ftsmc identify`'s command_delay_steps).
    #[arg(long, default_value_t = 0)]
    pub command_delay: usize,
}

/// Runs `ftsmc validate`.
pub fn run(a: ValidateArgs) -> Result<()> {
    let vehicle = Vehicle::load(&a.vehicle)?;
    let series = read_series(&a.logs, "validation")?;
    let rows = validate(
        &series,
        &vehicle,
        &ValidateOptions {
            bootstrap: a.bootstrap,
            seed: a.seed,
            command_delay_steps: a.command_delay,
            ..Default::default()
        },
    )?;
    std::fs::create_dir_all(&a.out).with_context(|| format!("cannot create {}", a.out.display()))?;
    let mut csv = String::from(
        "flight,horizon_s,steps,quantity,axis,n,r2,r2_lo,r2_hi,rms,rms_lo,rms_hi,baseline_r2,baseline_rms\n",
    );
    for r in &rows {
        csv.push_str(&format!(
            "{},{},{},{},{},{},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e}\n",
            r.flight.replace(',', ";"),
            r.horizon_s,
            r.steps,
            r.quantity,
            r.axis,
            r.n,
            r.r2,
            r.r2_lo,
            r.r2_hi,
            r.rms,
            r.rms_lo,
            r.rms_hi,
            r.baseline_r2,
            r.baseline_rms
        ));
    }
    write_atomic(&a.out.join("validation.csv"), csv.as_bytes())?;
    let num = |v: f64| if v.is_finite() { json!(v) } else { json!(null) };
    let report = json!({
        "vehicle": vehicle.name,
        "flights": series.iter().map(|s| s.source.clone()).collect::<Vec<_>>(),
        "rows": rows.iter().map(|r| json!({
            "flight": r.flight, "horizon_s": r.horizon_s, "steps": r.steps, "quantity": r.quantity, "axis": r.axis,
            "n": r.n, "r2": num(r.r2), "r2_lo": num(r.r2_lo), "r2_hi": num(r.r2_hi), "rms": num(r.rms),
            "rms_lo": num(r.rms_lo), "rms_hi": num(r.rms_hi), "baseline_r2": num(r.baseline_r2),
            "baseline_rms": num(r.baseline_rms)
        })).collect::<Vec<_>>(),
    });
    write_atomic(&a.out.join("validation.json"), serde_json::to_string_pretty(&report)?.as_bytes())?;
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
    println!("wrote {}", a.out.join("validation.csv").display());
    Ok(())
}
