//! `ftsmc validate LOG… --vehicle FILE|preset --out DIR`: open-loop
//! validation of the vehicle on the logs (ftsmc_ident::validate): predicted
//! against measured specific force and angular acceleration, one step,
//! 0.1 s and 0.5 s, per axis, beside the constant-acceleration baseline.
//!
//! Writes DIR/validation.csv and DIR/validation.json. With `--closed-loop`:
//! the logs' set-points flown in ftsmc by the log's controller
//! (ftsmc_ident::closed_loop), DIR/closed_loop.csv (the sim-to-real table)
//! and DIR/closed_loop_overlay.csv (the flights, sample by sample), and
//! per flight DIR/closed_loop_STEM.svg/.png (set-point, real and simulated
//! x, y, z against time).

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
    /// Closed loop instead: fly each log's set-point with the log's controller and compare tracking errors.
    #[arg(long)]
    pub closed_loop: bool,
    /// The log's controller for `--closed-loop`: crazyflie-pid or mellinger.
    #[arg(long, default_value = "crazyflie-pid")]
    pub controller: String,
}

/// Runs `ftsmc validate`.
pub fn run(a: Args) -> Result<()> {
    let vehicle = Vehicle::load(&a.vehicle)?;
    let series = a.common.read_series("validation")?;
    if a.closed_loop {
        return closed_loop(&a, &vehicle, &series);
    }
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

/// `--closed-loop`: the sim-to-real table and the overlay data.
fn closed_loop(a: &Args, vehicle: &Vehicle, series: &[ftsmc_ident::series::Series]) -> Result<()> {
    use ftsmc_ident::closed_loop::{fly_log, overlay_csv, table, table_csv, ClosedLoopOptions, LogController};
    let options = ClosedLoopOptions { controller: LogController::from_name(&a.controller)?, ..Default::default() };
    let flights = series.iter().map(|s| fly_log(s, vehicle, &options)).collect::<Result<Vec<_>, _>>()?;
    let rows = table(&flights);
    std::fs::create_dir_all(&a.common.out).with_context(|| format!("cannot create {}", a.common.out.display()))?;
    write_atomic(&a.common.out.join("closed_loop.csv"), table_csv(&rows).as_bytes())?;
    write_atomic(&a.common.out.join("closed_loop_overlay.csv"), overlay_csv(&flights).as_bytes())?;
    println!(
        "{:<40} {:>3} {:>10} {:>10} {:>10} {:>22}",
        "flight", "n", "real RMS", "sim RMS", "sim−real", "95 % interval"
    );
    for r in &rows {
        println!(
            "{:<40} {:>3} {:>10.4} {:>10.4} {:>10.4} [{:>9.4}, {:>9.4}]",
            r.flight, r.flights, r.real_rms_m, r.sim_rms_m, r.difference_m, r.difference_lo_m, r.difference_hi_m
        );
    }
    for f in &flights {
        overlay_figure(f, &a.common.out)?;
    }
    for f in flights.iter().filter(|f| f.diverged_at_s.is_some()) {
        println!("{}: the simulation diverged at {:.2} s", f.source, f.diverged_at_s.unwrap_or(f64::NAN));
    }
    println!("wrote {}", a.common.out.join("closed_loop.csv").display());
    Ok(())
}

/// x, y, z of one flight against time: set-point (dashed), real, simulated.
fn overlay_figure(f: &ftsmc_ident::closed_loop::ClosedLoopFlight, out: &std::path::Path) -> Result<()> {
    use crate::plot::{controller_color, write_figure, Figure, Panel, Rgb, Series};
    let line = |label: &str, ys: Vec<f64>, color: Rgb, dashed: bool| Series {
        label: label.into(),
        xs: f.time_s.clone(),
        ys,
        color,
        dashed,
        end: None,
        points: false,
    };
    let panels = ["x", "y", "z"]
        .iter()
        .enumerate()
        .map(|(i, axis)| Panel {
            title: axis.to_string(),
            x_label: "t (s)".into(),
            y_label: format!("{axis} (m)"),
            series: vec![
                line("set-point", f.setpoint_m.iter().map(|p| p[i]).collect(), controller_color("reference"), true),
                line(
                    &format!("real (RMS {:.3} m)", f.real_rms_m),
                    f.real_m.iter().map(|p| p[i]).collect(),
                    Rgb(0, 0, 0),
                    false,
                ),
                line(
                    &format!("ftsmc (RMS {:.3} m)", f.sim_rms_m),
                    f.sim_m.iter().map(|p| p[i]).collect(),
                    Rgb(213, 94, 0),
                    false,
                ),
            ],
            log_x: false,
            log_y: false,
        })
        .collect();
    let stem = std::path::Path::new(&f.source).file_stem().and_then(|s| s.to_str()).unwrap_or("flight");
    let fig = Figure { title: format!("{stem}: closed loop, real and ftsmc"), panels, columns: 1 };
    write_figure(&fig, &out.join(format!("closed_loop_{stem}")))?;
    Ok(())
}
