//! `ftsmc px4 export` and `ftsmc px4 import`: a scenario's `[pid]` gains as
//! a QGroundControl parameter file, and a PX4 vehicle's parameter file as a
//! `[pid]` section (the mapping: `ftsmc_sim::controllers::px4_params`,
//! docs/px4.md).

use std::io::Write as _;
use std::path::Path;

use anyhow::{bail, Context, Result};
use ftsmc_sim::controllers::px4_params;
use ftsmc_sim::scenario::Scenario;

/// The comment lines naming the vehicle and its normalisation.
fn vehicle_lines(scenario: &Scenario) -> Vec<String> {
    let vehicle = scenario.nominal_vehicle();
    let (t_max, tau) = px4_params::normalisation(&vehicle);
    vec![
        format!(
            "vehicle: {} (scenario {}), nominal mass {} kg, rotors {}",
            scenario.vehicle.preset.map_or("no preset", |p| p.name()),
            scenario.name,
            vehicle.plant.mass,
            if vehicle.max_thrust.is_some() { "limited" } else { "unlimited (T_max = m g / MPC_THR_HOVER 0.5)" }
        ),
        format!(
            "normalisation: T_max = {t_max:.6} N; tau_max roll, pitch, yaw = {:.6}, {:.6}, {:.6} N m",
            tau[0], tau[1], tau[2]
        ),
    ]
}

/// Write `text` to `out` (never over an existing file), or to stdout.
fn emit(text: &str, out: Option<&Path>) -> Result<()> {
    match out {
        Some(path) => {
            let mut file =
                std::fs::OpenOptions::new().write(true).create_new(true).open(path).with_context(|| {
                    format!("cannot create {} (an existing file is never overwritten)", path.display())
                })?;
            file.write_all(text.as_bytes()).with_context(|| format!("cannot write {}", path.display()))?;
            eprintln!("wrote {}", path.display());
        }
        None => print!("{text}"),
    }
    Ok(())
}

/// `ftsmc px4 export`: the `[pid]` gains of `scenario` (named `source`) as a
/// QGroundControl `.params` file.
pub fn export(scenario: &Scenario, source: &str, out: Option<&Path>) -> Result<()> {
    let vehicle = scenario.nominal_vehicle();
    let params = px4_params::params_from_gains(&scenario.gains.pid, &vehicle)
        .with_context(|| format!("exporting the [pid] gains of {source}"))?;
    if vehicle.max_thrust.is_none() {
        eprintln!(
            "warning: {source} has unlimited rotors: thrusts and torques are normalised to T_max = 2 m g, not to a real \
             vehicle's rotors"
        );
    }
    let mut header = vec![
        format!("PX4 parameters of the [pid] gains of {source}, written by ftsmc {}", env!("CARGO_PKG_VERSION")),
        "(mapping and normalisation: docs/px4.md)".to_string(),
    ];
    header.extend(vehicle_lines(scenario));
    emit(&px4_params::write_qgc(&params, &header), out)
}

/// `ftsmc px4 import`: the `.params` file `params` as a `[pid]` section for
/// the vehicle of `scenario` (named `source`).
pub fn import(params: &Path, scenario: &Scenario, source: &str, out: Option<&Path>) -> Result<()> {
    // The bounded reader of every file ftsmc did not write: a FIFO or a
    // device is refused without blocking, the size without reading past it.
    let bytes = crate::bounded_read::read_limited(params, px4_params::MAX_PARAMS_BYTES, "PX4 parameter file")?;
    let shown = params.display().to_string();
    let text = String::from_utf8(bytes).map_err(|e| {
        anyhow::anyhow!("{shown}: not UTF-8 text (invalid byte at offset {})", e.utf8_error().valid_up_to())
    })?;
    let file = px4_params::parse_qgc(&text, &shown)?;
    if file.values.is_empty() {
        bail!(
            "{}: no PX4 parameter ftsmc maps (MC_ROLLRATE_P, MPC_XY_P, …; docs/px4.md): not a PX4 multicopter parameter \
             file",
            params.display()
        );
    }
    let gains = px4_params::gains_from_params(&file, &scenario.nominal_vehicle())?;
    let mut text = format!(
        "# [pid] gains of the PX4 parameter file {} on the vehicle of {source}, written by ftsmc {}\n",
        params.display(),
        env!("CARGO_PKG_VERSION")
    );
    for line in vehicle_lines(scenario) {
        text.push_str(&format!("# {line}\n"));
    }
    let missing = px4_params::PX4_DEFAULTS.iter().filter(|(n, _, _)| !file.values.contains_key(*n)).count();
    if missing > 0 {
        text.push_str(&format!("# {missing} mapped parameters not in the file took PX4's defaults\n"));
    }
    let body = toml::to_string(&gains).context("serialising the [pid] gains")?;
    text.push_str("[pid]\n");
    text.push_str(&body);
    emit(&text, out)
}
