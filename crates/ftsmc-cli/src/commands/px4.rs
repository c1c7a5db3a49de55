//! `ftsmc px4 export` and `ftsmc px4 import`: a scenario's `[pid]` gains as
//! a QGroundControl parameter file, and a PX4 vehicle's parameter file as a
//! `[pid]` section (the mapping: `ftsmc_sim::controllers::px4_params`,
//! docs/px4.md).

use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use ftsmc_sim::controllers::{px4_params, NominalVehicle};
use ftsmc_sim::scenario::Scenario;

use crate::args::{load_scenario_with_limits, SetArgs};

/// Arguments of `ftsmc px4`.
#[derive(clap::Args)]
pub struct Args {
    /// Export or import.
    #[command(subcommand)]
    action: Action,
}

#[derive(clap::Subcommand)]
enum Action {
    /// Write the scenario's [pid] gains as a QGroundControl .params file under PX4's names and units.
    Export {
        /// Scenario file (TOML) or built-in name: its [pid] gains and its vehicle (the normalisation).
        scenario: String,
        /// Output file (never overwritten); default: standard output.
        #[arg(long, short = 'o')]
        out: Option<PathBuf>,
        /// `--set`, e.g. `--set vehicle.preset=px4-x500`.
        #[command(flatten)]
        set: SetArgs,
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
        /// `--set`, e.g. `--set vehicle.preset=px4-x500`.
        #[command(flatten)]
        set: SetArgs,
    },
}

/// Runs `ftsmc px4 export|import`.
pub fn run(args: Args) -> Result<()> {
    match args.action {
        Action::Export { scenario: arg, out, set } => {
            let scenario = load_scenario_with_limits(&arg, &[], &set.set)?;
            export(&scenario, &arg, out.as_deref())
        }
        Action::Import { params, scenario: arg, out, set } => {
            let scenario = load_scenario_with_limits(&arg, &[], &set.set)?;
            import(&params, &scenario, &arg, out.as_deref())
        }
    }
}

/// Rotor positions as `[[x, y], ..]` (m), as a scenario file writes them.
fn positions_text(p: &[[f64; 2]; 4]) -> String {
    let each: Vec<String> = p.iter().map(|[x, y]| format!("[{x:?}, {y:?}]")).collect();
    format!("[{}]", each.join(", "))
}

/// The comment lines naming the vehicle and its normalisation.
fn vehicle_lines(scenario: &Scenario, vehicle: &NominalVehicle) -> Vec<String> {
    let (t_max, tau) = px4_params::normalisation(vehicle);
    vec![
        format!(
            "vehicle: {} (scenario {}), nominal mass {} kg, rotors {}",
            scenario.vehicle.preset.map_or("no preset", |p| p.name()),
            scenario.name,
            vehicle.plant.mass,
            if vehicle.max_thrust.is_some() { "limited" } else { "unlimited (T_max = m g / MPC_THR_HOVER 0.5)" }
        ),
        format!(
            "normalisation: T_max = {t_max:.6} N; tau_max roll, pitch, yaw = {:.6}, {:.6}, {:.6} N m on rotors at {} m \
             (x forward, y left)",
            tau[0],
            tau[1],
            tau[2],
            positions_text(&vehicle.geometry.positions())
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
    header.extend(vehicle_lines(scenario, &vehicle));
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
    // The airframe the file describes (CA_ROTOR*, SIM_GZ_EC_*) is the one the
    // gains are normalised on and the one the written sections fly.
    let frame = px4_params::airframe(&file)?;
    let base = scenario.nominal_vehicle();
    let vehicle = match &frame {
        Some(f) => {
            let limit = f.max_speed.or_else(|| scenario.actuators.map(|a| a.max_rotor_speed));
            NominalVehicle::new(base.plant, limit).on(f.geometry())
        }
        None => base,
    };
    let gains = px4_params::gains_from_params(&file, &vehicle)?;
    let mut text = format!(
        "# [pid] gains of the PX4 parameter file {} on the vehicle of {source}, written by ftsmc {}\n",
        params.display(),
        env!("CARGO_PKG_VERSION")
    );
    for line in vehicle_lines(scenario, &vehicle) {
        text.push_str(&format!("# {line}\n"));
    }
    let mut notes = Vec::new();
    if let Some(f) = &frame {
        if !f.same_layout_as(&base.geometry) {
            notes.push(format!(
                "the file's CA_ROTOR layout is not {source}'s vehicle (rotors at {} m): the [vehicle] section below flies \
                 the file's",
                positions_text(&base.geometry.positions())
            ));
        }
        if scenario.vehicle.model == ftsmc_sim::vehicle::VehicleModel::Paper {
            notes.push(format!(
                "{source} flies paper Eq. 1 (the \"+\" of Eq. 2): the [vehicle] section below switches to model = \
                 \"rigid-body\" to fly the file's layout"
            ));
        }
    }
    for line in px4_params::not_flown(&file) {
        notes.push(format!("not flown: {line}"));
    }
    for note in &notes {
        eprintln!("note: {note}");
        text.push_str(&format!("# {note}\n"));
    }
    let missing = px4_params::PX4_DEFAULTS.iter().filter(|(n, _, _)| !file.values.contains_key(*n)).count();
    if missing > 0 {
        text.push_str(&format!("# {missing} mapped parameters not in the file took PX4's defaults\n"));
    }
    let body = toml::to_string(&gains).context("serialising the [pid] gains")?;
    text.push_str("[pid]\n");
    text.push_str(&body);
    if let Some(f) = &frame {
        text.push_str("\n# The airframe of the parameter file (CA_ROTOR*: PX4's order, y = -PY; KM > 0 counter-clockwise)\n[vehicle]\n");
        if scenario.vehicle.model == ftsmc_sim::vehicle::VehicleModel::Paper {
            text.push_str("model = \"rigid-body\"\n");
        }
        let spins: Vec<String> =
            f.spin.iter().map(|s| format!("\"{}\"", if s.sign() > 0.0 { "ccw" } else { "cw" })).collect();
        text.push_str(&format!("rotor_positions = {}\nspin = [{}]\n", positions_text(&f.positions), spins.join(", ")));
        if f.idle_speed.is_some() || f.max_speed.is_some() {
            text.push_str("\n[actuators]\n");
            if let Some(w) = f.idle_speed {
                text.push_str(&format!("min_rotor_speed = {w:?}                 # rad/s: SIM_GZ_EC_MIN\n"));
            }
            if let Some(w) = f.max_speed {
                text.push_str(&format!("max_rotor_speed = {w:?}                # rad/s: SIM_GZ_EC_MAX\n"));
            }
        }
    }
    emit(&text, out)
}
