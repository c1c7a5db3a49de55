//! PX4 parameters in and out: the `[pid]` gains ([`PidGains`]) as PX4's
//! own parameters, read from and written to a QGroundControl parameter
//! file (`.params`).
//!
//! # The file format
//!
//! QGroundControl's "Save to file" writes one parameter a line, five
//! tab-separated fields: vehicle id, component id, name, value, MAVLink
//! type (`9` = `MAV_PARAM_TYPE_REAL32`, `6` = `MAV_PARAM_TYPE_INT32`);
//! lines starting with `#` are comments. [`parse_qgc`] reads that (fields
//! separated by any white space); parameters it does not map are ignored
//! (a vehicle's dump holds about a thousand), a mapped one missing takes
//! PX4's published default ([`PX4_DEFAULTS`]), as on a vehicle where it
//! was never set. [`write_qgc`] writes it, values in Rust's shortest
//! round-trip decimal form. The format is six lines of text: hand-written
//! here rather than pulling in a crate for it.
//!
//! # The mapping
//!
//! docs/px4.md has the table. PX4's position, velocity and attitude gains
//! and limits are in SI units and map one to one (angles in degrees,
//! cut-offs in Hz). Its thrusts and torques are normalised: thrust by the
//! vehicle's maximum collective thrust `T_max`, torques by what the control
//! allocation makes of a normalised torque of 1, `τ_max`
//! ([`PidGains::normalisation_thrust`], [`PidGains::max_torques_on`] on the
//! vehicle's rotor layout, the
//! module docs of `ftsmc_core::pid`). So the rate gains are
//! `rate_p = MC_ROLLRATE_K · MC_ROLLRATE_P · τ_max,roll` (and so for `I`,
//! `D`; PX4's `MC_*RATE_K` scales P, I and D, `mc_rate_control_params.c`),
//! `rate_ff = MC_ROLLRATE_FF · τ_max`, `rate_integral_limit = MC_RR_INT_LIM
//! · τ_max`, `thrust_min = MPC_THR_MIN · T_max`. Export writes
//! `MC_*RATE_K = 1`.
//!
//! `hover_thrust` follows PX4's hover-thrust estimator: with
//! `MPC_USE_HTE = 1` (PX4's default) the position controller uses the
//! estimate, which converges to the vehicle's hover thrust; ftsmc takes its
//! converged value `m g` of the nominal vehicle, and `MPC_THR_HOVER` (the
//! estimator's initial value) is not used. With `MPC_USE_HTE = 0` it is
//! `MPC_THR_HOVER · T_max`. Export writes `MPC_THR_HOVER = hover_thrust /
//! T_max` and `MPC_USE_HTE = 1` when `hover_thrust` is `m g` (to 1e-12
//! relative), else `0`.

use std::collections::BTreeMap;
use std::path::Path;

use ftsmc_core::pid::PidGains;

use super::NominalVehicle;

/// MAVLink `MAV_PARAM_TYPE_REAL32`: the type column of a float parameter.
pub const REAL32: u8 = 9;
/// MAVLink `MAV_PARAM_TYPE_INT32`: the type column of an integer parameter.
pub const INT32: u8 = 6;

/// Largest `.params` file read, bytes (a full PX4 dump is about 40 kB).
pub const MAX_PARAMS_BYTES: u64 = 4 << 20;

/// Every PX4 parameter read or written, with PX4's published default and
/// MAVLink type. Sources: `mc_rate_control_params.c`,
/// `mc_att_control_params.yaml`, `multicopter_position_control_gain_params.c`,
/// `multicopter_position_control_limits_params.c`,
/// `multicopter_position_control_params.c` (PX4-Autopilot `main`), and
/// `IMU_DGYRO_CUTOFF` of `sensors/vehicle_angular_velocity`.
pub const PX4_DEFAULTS: &[(&str, f64, u8)] = &[
    ("MPC_XY_P", 0.95, REAL32),
    ("MPC_Z_P", 1.0, REAL32),
    ("MPC_XY_VEL_P_ACC", 1.8, REAL32),
    ("MPC_Z_VEL_P_ACC", 4.0, REAL32),
    ("MPC_XY_VEL_I_ACC", 0.4, REAL32),
    ("MPC_Z_VEL_I_ACC", 2.0, REAL32),
    ("MPC_XY_VEL_D_ACC", 0.2, REAL32),
    ("MPC_Z_VEL_D_ACC", 0.0, REAL32),
    ("MPC_VELD_LP", 5.0, REAL32),
    ("MPC_XY_VEL_MAX", 12.0, REAL32),
    ("MPC_Z_VEL_MAX_UP", 3.0, REAL32),
    ("MPC_Z_VEL_MAX_DN", 1.5, REAL32),
    ("MPC_TILTMAX_AIR", 45.0, REAL32),
    ("MPC_THR_HOVER", 0.5, REAL32),
    ("MPC_USE_HTE", 1.0, INT32),
    ("MPC_THR_MIN", 0.12, REAL32),
    ("MPC_THR_MAX", 1.0, REAL32),
    ("MPC_THR_XY_MARG", 0.3, REAL32),
    ("MC_ROLL_P", 4.0, REAL32),
    ("MC_PITCH_P", 4.0, REAL32),
    ("MC_YAW_P", 2.8, REAL32),
    ("MC_YAW_WEIGHT", 0.4, REAL32),
    ("MC_ROLLRATE_MAX", 220.0, REAL32),
    ("MC_PITCHRATE_MAX", 220.0, REAL32),
    ("MC_YAWRATE_MAX", 200.0, REAL32),
    ("MC_ROLLRATE_P", 0.15, REAL32),
    ("MC_ROLLRATE_I", 0.2, REAL32),
    ("MC_ROLLRATE_D", 0.003, REAL32),
    ("MC_ROLLRATE_FF", 0.0, REAL32),
    ("MC_ROLLRATE_K", 1.0, REAL32),
    ("MC_PITCHRATE_P", 0.15, REAL32),
    ("MC_PITCHRATE_I", 0.2, REAL32),
    ("MC_PITCHRATE_D", 0.003, REAL32),
    ("MC_PITCHRATE_FF", 0.0, REAL32),
    ("MC_PITCHRATE_K", 1.0, REAL32),
    ("MC_YAWRATE_P", 0.2, REAL32),
    ("MC_YAWRATE_I", 0.1, REAL32),
    ("MC_YAWRATE_D", 0.0, REAL32),
    ("MC_YAWRATE_FF", 0.0, REAL32),
    ("MC_YAWRATE_K", 1.0, REAL32),
    ("MC_RR_INT_LIM", 0.3, REAL32),
    ("MC_PR_INT_LIM", 0.3, REAL32),
    ("MC_YR_INT_LIM", 0.3, REAL32),
    ("IMU_DGYRO_CUTOFF", 30.0, REAL32),
];

/// The rate-loop parameter names per body axis: (P, I, D, FF, K, integrator limit, rate limit).
const RATE_NAMES: [[&str; 7]; 3] = [
    [
        "MC_ROLLRATE_P",
        "MC_ROLLRATE_I",
        "MC_ROLLRATE_D",
        "MC_ROLLRATE_FF",
        "MC_ROLLRATE_K",
        "MC_RR_INT_LIM",
        "MC_ROLLRATE_MAX",
    ],
    [
        "MC_PITCHRATE_P",
        "MC_PITCHRATE_I",
        "MC_PITCHRATE_D",
        "MC_PITCHRATE_FF",
        "MC_PITCHRATE_K",
        "MC_PR_INT_LIM",
        "MC_PITCHRATE_MAX",
    ],
    [
        "MC_YAWRATE_P",
        "MC_YAWRATE_I",
        "MC_YAWRATE_D",
        "MC_YAWRATE_FF",
        "MC_YAWRATE_K",
        "MC_YR_INT_LIM",
        "MC_YAWRATE_MAX",
    ],
];

/// The attitude P parameter per body axis.
const ATTITUDE_NAMES: [&str; 3] = ["MC_ROLL_P", "MC_PITCH_P", "MC_YAW_P"];

/// A bad `.params` file, or gains PX4 cannot express.
#[derive(Debug, thiserror::Error)]
pub enum Px4ParamsError {
    /// The file could not be read.
    #[error("cannot read PX4 parameter file {file}: {source}")]
    Io {
        /// File path.
        file: String,
        /// Underlying error.
        source: std::io::Error,
    },
    /// The file is not a regular file or too large.
    #[error("{file}: {message}")]
    File {
        /// File path.
        file: String,
        /// What is wrong.
        message: String,
    },
    /// A line that is not `vehicle component NAME VALUE TYPE`.
    #[error("{file}, line {line}: {message}")]
    Line {
        /// File path.
        file: String,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A parameter whose value ftsmc cannot fly (line 0: PX4's default, not in the file).
    #[error("{file}, line {line}: `{name}` = {value} is invalid (expected {expected})")]
    Value {
        /// File path.
        file: String,
        /// 1-based line number (0: the parameter is not in the file and took PX4's default).
        line: usize,
        /// PX4 parameter name.
        name: String,
        /// The value as written.
        value: String,
        /// What is allowed.
        expected: String,
    },
    /// `[pid]` gains PX4 has no parameter for.
    #[error("`pid.{key}` = {value} cannot be exported to PX4: {reason}")]
    NotExportable {
        /// Key below `[pid]`.
        key: String,
        /// The value, as shown.
        value: String,
        /// Why not.
        reason: String,
    },
}

/// One PX4 parameter: name, value (in PX4's units) and MAVLink type.
#[derive(Clone, Debug, PartialEq)]
pub struct Px4Param {
    /// PX4 parameter name, e.g. `MC_ROLLRATE_P`.
    pub name: &'static str,
    /// Value in PX4's units.
    pub value: f64,
    /// [`REAL32`] or [`INT32`].
    pub kind: u8,
}

/// The mapped parameters of a `.params` file: value and 1-based line, by name.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Px4ParamFile {
    /// File path, as shown in messages.
    pub file: String,
    /// Value and line of every mapped parameter the file sets.
    pub values: BTreeMap<String, (f64, usize)>,
    /// Value and line of every other parameter with a finite value: the
    /// airframe ([`airframe`]) and what ftsmc reads but does not fly
    /// ([`not_flown`]).
    pub others: BTreeMap<String, (f64, usize)>,
}

impl Px4ParamFile {
    /// The value of `name` (the file's, else PX4's default) and its line (0: default).
    fn get(&self, name: &str) -> (f64, usize) {
        self.values.get(name).copied().unwrap_or_else(|| {
            let default = PX4_DEFAULTS.iter().find(|(n, _, _)| *n == name).map_or(f64::NAN, |(_, v, _)| *v);
            (default, 0)
        })
    }

    fn invalid(&self, name: &str, expected: &str) -> Px4ParamsError {
        let (value, line) = self.get(name);
        Px4ParamsError::Value {
            file: self.file.clone(),
            line,
            name: name.to_string(),
            value: crate::text::show(value),
            expected: expected.to_string(),
        }
    }
}

/// Read a QGroundControl `.params` file (a regular file of at most
/// [`MAX_PARAMS_BYTES`]). The type is checked on the metadata before the
/// file is opened (opening a FIFO would block until a writer came, as in
/// [`crate::scenario::read_scenario_text`]) and again on the open file; the
/// read itself is bounded.
pub fn read_qgc(path: &Path) -> Result<Px4ParamFile, Px4ParamsError> {
    use std::io::Read as _;
    let file = path.display().to_string();
    let io = |source| Px4ParamsError::Io { file: file.clone(), source };
    if !std::fs::metadata(path).map_err(io)?.is_file() {
        return Err(Px4ParamsError::File { file, message: "not a regular file".into() });
    }
    let handle = std::fs::File::open(path).map_err(io)?;
    let meta = handle.metadata().map_err(io)?;
    if !meta.is_file() {
        return Err(Px4ParamsError::File { file, message: "not a regular file".into() });
    }
    let mut bytes = Vec::new();
    handle.take(MAX_PARAMS_BYTES + 1).read_to_end(&mut bytes).map_err(io)?;
    if bytes.len() as u64 > MAX_PARAMS_BYTES {
        return Err(Px4ParamsError::File {
            file,
            message: format!("larger than {MAX_PARAMS_BYTES} bytes: not a PX4 parameter file"),
        });
    }
    let text = String::from_utf8(bytes)
        .map_err(|e| Px4ParamsError::File { file: file.clone(), message: format!("not UTF-8 text ({e})") })?;
    parse_qgc(&text, &file)
}

/// Parse the text of a QGroundControl `.params` file named `file` (for
/// messages): the mapped parameters ([`PX4_DEFAULTS`]), each at most once.
pub fn parse_qgc(text: &str, file: &str) -> Result<Px4ParamFile, Px4ParamsError> {
    let mut out = Px4ParamFile { file: file.to_string(), values: BTreeMap::new(), others: BTreeMap::new() };
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let trimmed = raw.trim();
        if trimmed.is_empty() || trimmed.starts_with('#') {
            continue;
        }
        let bad = |message: String| Px4ParamsError::Line { file: file.to_string(), line, message };
        let fields: Vec<&str> = trimmed.split_whitespace().collect();
        if fields.len() != 5 {
            return Err(bad(format!(
                "{} fields; expected 5 (vehicle id, component id, name, value, type), as QGroundControl writes",
                fields.len()
            )));
        }
        let name = fields[2];
        let Some(&(_, _, kind)) = PX4_DEFAULTS.iter().find(|(n, _, _)| *n == name) else {
            // Not a gain: kept for the airframe and the not-flown list; a
            // value that is not a finite number is not one ftsmc reads.
            if let Some(v) = fields[3].parse::<f64>().ok().filter(|v| v.is_finite()) {
                if let Some((_, first)) = out.others.insert(name.to_string(), (v, line)) {
                    return Err(bad(format!("`{name}` is set twice (lines {first} and {line})")));
                }
            }
            continue;
        };
        let shown = crate::text::show_str(fields[3]);
        let value: f64 =
            fields[3].parse().ok().filter(|v: &f64| v.is_finite()).ok_or_else(|| Px4ParamsError::Value {
                file: file.to_string(),
                line,
                name: name.to_string(),
                value: shown.clone(),
                expected: "a finite number".into(),
            })?;
        if kind == INT32 && value.fract() != 0.0 {
            return Err(Px4ParamsError::Value {
                file: file.to_string(),
                line,
                name: name.to_string(),
                value: shown,
                expected: "an integer".into(),
            });
        }
        if let Some((_, first)) = out.values.insert(name.to_string(), (value, line)) {
            return Err(bad(format!("`{name}` is set twice (lines {first} and {line})")));
        }
    }
    Ok(out)
}

/// Write `params` as a QGroundControl `.params` file (vehicle 1, component
/// 1), after the comment lines `header` (each gets a leading `# `).
pub fn write_qgc(params: &[Px4Param], header: &[String]) -> String {
    let mut out = String::new();
    for line in header {
        out.push_str("# ");
        out.push_str(line);
        out.push('\n');
    }
    out.push_str("#\n# Vehicle-Id\tComponent-Id\tName\tValue\tType\n");
    for p in params {
        let value = if p.kind == INT32 { format!("{}", p.value as i64) } else { format!("{}", p.value) };
        out.push_str(&format!("1\t1\t{}\t{value}\t{}\n", p.name, p.kind));
    }
    out
}

/// The normalisation of `vehicle`: (`T_max`, N; `τ_max` per body axis, N·m).
pub fn normalisation(vehicle: &NominalVehicle) -> (f64, [f64; 3]) {
    let t_max = PidGains::normalisation_thrust(&vehicle.plant, vehicle.max_thrust);
    (t_max, PidGains::max_torques_on(&vehicle.plant, t_max, &vehicle.geometry))
}

/// Whether `hover_thrust` is the nominal vehicle's weight (to 1e-12 relative).
fn hovers_at_weight(hover_thrust: f64, vehicle: &NominalVehicle) -> bool {
    let weight = vehicle.plant.mass * vehicle.plant.gravity;
    (hover_thrust - weight).abs() <= 1e-12 * weight
}

/// The PX4 parameters of `gains` on `vehicle` (see the [module docs](self)).
/// Refused: horizontal gains that differ between x and y (PX4 has one
/// `MPC_XY_*` each) and `anti_windup = false` (PX4 always applies it).
pub fn params_from_gains(gains: &PidGains, vehicle: &NominalVehicle) -> Result<Vec<Px4Param>, Px4ParamsError> {
    let (t_max, tau) = normalisation(vehicle);
    let xy = |key: &str, v: [f64; 3]| {
        if v[0] == v[1] {
            Ok(v[0])
        } else {
            Err(Px4ParamsError::NotExportable {
                key: key.to_string(),
                value: format!("[{}, {}, {}]", v[0], v[1], v[2]),
                reason: "x and y differ; PX4 has one horizontal gain (MPC_XY_*)".into(),
            })
        }
    };
    if !gains.anti_windup {
        return Err(Px4ParamsError::NotExportable {
            key: "anti_windup".into(),
            value: "false".into(),
            reason: "PX4's velocity loop always applies its anti-windup".into(),
        });
    }
    let real = |name: &'static str, value: f64| Px4Param { name, value, kind: REAL32 };
    let mut out = vec![
        real("MPC_XY_P", xy("position_p", gains.position_p)?),
        real("MPC_Z_P", gains.position_p[2]),
        real("MPC_XY_VEL_P_ACC", xy("velocity_p", gains.velocity_p)?),
        real("MPC_Z_VEL_P_ACC", gains.velocity_p[2]),
        real("MPC_XY_VEL_I_ACC", xy("velocity_i", gains.velocity_i)?),
        real("MPC_Z_VEL_I_ACC", gains.velocity_i[2]),
        real("MPC_XY_VEL_D_ACC", xy("velocity_d", gains.velocity_d)?),
        real("MPC_Z_VEL_D_ACC", gains.velocity_d[2]),
        real("MPC_VELD_LP", gains.velocity_derivative_cutoff),
        real("MPC_XY_VEL_MAX", gains.max_velocity_xy),
        real("MPC_Z_VEL_MAX_UP", gains.max_velocity_up),
        real("MPC_Z_VEL_MAX_DN", gains.max_velocity_down),
        real("MPC_TILTMAX_AIR", gains.max_tilt.to_degrees()),
        real("MPC_THR_HOVER", gains.hover_thrust / t_max),
        Px4Param {
            name: "MPC_USE_HTE",
            value: if hovers_at_weight(gains.hover_thrust, vehicle) { 1.0 } else { 0.0 },
            kind: INT32,
        },
        real("MPC_THR_MIN", gains.thrust_min / t_max),
        real("MPC_THR_MAX", gains.thrust_max / t_max),
        real("MPC_THR_XY_MARG", gains.thrust_xy_margin / t_max),
        real("MC_YAW_WEIGHT", gains.yaw_weight),
    ];
    for (axis, name) in ATTITUDE_NAMES.iter().enumerate() {
        out.push(real(name, gains.attitude_p[axis]));
    }
    for (axis, [p, i, d, ff, k, lim, max]) in RATE_NAMES.iter().enumerate() {
        out.push(real(p, gains.rate_p[axis] / tau[axis]));
        out.push(real(i, gains.rate_i[axis] / tau[axis]));
        out.push(real(d, gains.rate_d[axis] / tau[axis]));
        out.push(real(ff, gains.rate_ff[axis] / tau[axis]));
        out.push(real(k, 1.0));
        out.push(real(lim, gains.rate_integral_limit[axis] / tau[axis]));
        out.push(real(max, gains.max_rate[axis].to_degrees()));
    }
    out.push(real("IMU_DGYRO_CUTOFF", gains.rate_derivative_cutoff));
    Ok(out)
}

/// The `[pid]` gains of `params` on `vehicle` (see the [module docs](self));
/// checked with [`PidGains::check`], an invalid result naming the PX4
/// parameter it came from, its value and line.
pub fn gains_from_params(params: &Px4ParamFile, vehicle: &NominalVehicle) -> Result<PidGains, Px4ParamsError> {
    let (t_max, tau) = normalisation(vehicle);
    let v = |name: &str| params.get(name).0;
    for (name, expected) in [
        ("MPC_USE_HTE", "0 or 1"),
        ("MC_ROLLRATE_K", "a gain > 0"),
        ("MC_PITCHRATE_K", "a gain > 0"),
        ("MC_YAWRATE_K", "a gain > 0"),
    ] {
        let ok = if name == "MPC_USE_HTE" { v(name) == 0.0 || v(name) == 1.0 } else { v(name) > 0.0 };
        if !ok {
            return Err(params.invalid(name, expected));
        }
    }
    let hover_thrust =
        if v("MPC_USE_HTE") == 1.0 { vehicle.plant.mass * vehicle.plant.gravity } else { v("MPC_THR_HOVER") * t_max };
    let per_axis = |f: &dyn Fn(usize) -> f64| [f(0), f(1), f(2)];
    let rate = |column: usize, with_k: bool| {
        per_axis(&|axis| {
            let k = if with_k { v(RATE_NAMES[axis][4]) } else { 1.0 };
            k * v(RATE_NAMES[axis][column]) * tau[axis]
        })
    };
    let gains = PidGains {
        position_p: [v("MPC_XY_P"), v("MPC_XY_P"), v("MPC_Z_P")],
        velocity_p: [v("MPC_XY_VEL_P_ACC"), v("MPC_XY_VEL_P_ACC"), v("MPC_Z_VEL_P_ACC")],
        velocity_i: [v("MPC_XY_VEL_I_ACC"), v("MPC_XY_VEL_I_ACC"), v("MPC_Z_VEL_I_ACC")],
        velocity_d: [v("MPC_XY_VEL_D_ACC"), v("MPC_XY_VEL_D_ACC"), v("MPC_Z_VEL_D_ACC")],
        velocity_derivative_cutoff: v("MPC_VELD_LP"),
        max_velocity_xy: v("MPC_XY_VEL_MAX"),
        max_velocity_up: v("MPC_Z_VEL_MAX_UP"),
        max_velocity_down: v("MPC_Z_VEL_MAX_DN"),
        max_tilt: v("MPC_TILTMAX_AIR").to_radians(),
        hover_thrust,
        thrust_min: v("MPC_THR_MIN") * t_max,
        thrust_max: v("MPC_THR_MAX") * t_max,
        thrust_xy_margin: v("MPC_THR_XY_MARG") * t_max,
        attitude_p: per_axis(&|axis| v(ATTITUDE_NAMES[axis])),
        yaw_weight: v("MC_YAW_WEIGHT"),
        max_rate: per_axis(&|axis| v(RATE_NAMES[axis][6]).to_radians()),
        rate_p: rate(0, true),
        rate_i: rate(1, true),
        rate_d: rate(2, true),
        rate_ff: rate(3, false),
        rate_integral_limit: rate(5, false),
        rate_derivative_cutoff: v("IMU_DGYRO_CUTOFF"),
        anti_windup: true,
    };
    gains.check().map_err(|e| {
        let name = px4_name_of(e.field, v("MPC_USE_HTE") == 1.0);
        let expected = if name == "MPC_USE_HTE" {
            format!("on this vehicle, {} (`pid.{}` = {})", e.expected, e.field, crate::text::show(e.value))
        } else {
            format!("`pid.{}` {} after the normalisation to this vehicle", e.field, e.expected)
        };
        params.invalid(name, &expected)
    })?;
    Ok(gains)
}

/// The PX4 parameter a [`PidGains`] field (as [`PidGains::check`] names it) comes from.
fn px4_name_of(field: &str, hte: bool) -> &'static str {
    let axis = |f: &str| -> usize {
        f.rsplit('[').next().and_then(|s| s.trim_end_matches(']').parse().ok()).unwrap_or(0).min(2)
    };
    let base = field.split('[').next().unwrap_or(field);
    let a = axis(field);
    let xy_or_z = |xy: &'static str, z: &'static str| if a == 2 { z } else { xy };
    match base {
        "position_p" => xy_or_z("MPC_XY_P", "MPC_Z_P"),
        "velocity_p" => xy_or_z("MPC_XY_VEL_P_ACC", "MPC_Z_VEL_P_ACC"),
        "velocity_i" => xy_or_z("MPC_XY_VEL_I_ACC", "MPC_Z_VEL_I_ACC"),
        "velocity_d" => xy_or_z("MPC_XY_VEL_D_ACC", "MPC_Z_VEL_D_ACC"),
        "velocity_derivative_cutoff" => "MPC_VELD_LP",
        "max_velocity_xy" => "MPC_XY_VEL_MAX",
        "max_velocity_up" => "MPC_Z_VEL_MAX_UP",
        "max_velocity_down" => "MPC_Z_VEL_MAX_DN",
        "max_demanded_tilt" | "max_tilt" => "MPC_TILTMAX_AIR",
        "hover_thrust" if hte => "MPC_USE_HTE",
        "hover_thrust" => "MPC_THR_HOVER",
        "thrust_min" => "MPC_THR_MIN",
        "thrust_max" => "MPC_THR_MAX",
        "thrust_xy_margin" => "MPC_THR_XY_MARG",
        "attitude_p" => ATTITUDE_NAMES[a],
        "yaw_weight" => "MC_YAW_WEIGHT",
        "max_rate" => RATE_NAMES[a][6],
        "rate_p" => RATE_NAMES[a][0],
        "rate_i" => RATE_NAMES[a][1],
        "rate_d" => RATE_NAMES[a][2],
        "rate_ff" => RATE_NAMES[a][3],
        "rate_integral_limit" => RATE_NAMES[a][5],
        _ => "IMU_DGYRO_CUTOFF",
    }
}

/// A PX4 airframe's rotors and motor limits, as its parameters give them
/// (`CA_ROTOR_COUNT`, `CA_ROTOR{n}_PX`, `_PY`, `_KM`; `SIM_GZ_EC_MIN{n}`,
/// `SIM_GZ_EC_MAX{n}` of PX4's Gazebo bridge), in ftsmc's body axes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Px4Airframe {
    /// Hub `(x, y)` of rotors 1..4 = `CA_ROTOR0..3`, m, x forward, y left
    /// (`y = −CA_ROTOR{n}_PY`: PX4's body y points right).
    pub positions: [[f64; 2]; 4],
    /// Spin of rotors 1..4: `CA_ROTOR{n}_KM > 0` counter-clockwise (PX4's
    /// convention: a positive moment ratio is a counter-clockwise rotor).
    pub spin: [crate::vehicle::Spin; 4],
    /// Idle rotor speed ω_min, rad/s (`SIM_GZ_EC_MIN1..4`, all equal), if set.
    pub idle_speed: Option<f64>,
    /// Top rotor speed ω_max, rad/s (`SIM_GZ_EC_MAX1..4`, all equal), if set.
    pub max_speed: Option<f64>,
}

impl Px4Airframe {
    /// The layout as [`ftsmc_core::rotor_layout`] takes it.
    pub fn geometry(&self) -> ftsmc_core::rotor_layout::RotorGeometry {
        ftsmc_core::rotor_layout::RotorGeometry::Custom {
            positions: self.positions,
            spin: self.spin.map(crate::vehicle::Spin::sign),
        }
    }

    /// Whether `geometry` has this airframe's rotors, in any order: the
    /// same hubs (to 1e-6 m) with the same spins.
    pub fn same_layout_as(&self, geometry: &ftsmc_core::rotor_layout::RotorGeometry) -> bool {
        let (theirs, their_spin) = (geometry.positions(), geometry.spin());
        let mut used = [false; 4];
        for (p, s) in self.positions.iter().zip(self.spin) {
            let found = (0..4).find(|&j| {
                !used[j]
                    && (theirs[j][0] - p[0]).abs() <= 1e-6
                    && (theirs[j][1] - p[1]).abs() <= 1e-6
                    && their_spin[j] == s.sign()
            });
            match found {
                Some(j) => used[j] = true,
                None => return false,
            }
        }
        true
    }
}

impl Px4ParamFile {
    /// A non-gain parameter's value and line, if the file sets it.
    fn other(&self, name: &str) -> Option<(f64, usize)> {
        self.others.get(name).copied()
    }

    fn other_invalid(&self, name: &str, value: f64, line: usize, expected: &str) -> Px4ParamsError {
        Px4ParamsError::Value {
            file: self.file.clone(),
            line,
            name: name.to_string(),
            value: crate::text::show(value),
            expected: expected.to_string(),
        }
    }

    /// `SIM_GZ_EC_{kind}1..4`: one speed for all four motors, if any is set.
    fn motor_speed(&self, kind: &str) -> Result<Option<f64>, Px4ParamsError> {
        let names: Vec<String> = (1..=4).map(|n| format!("SIM_GZ_EC_{kind}{n}")).collect();
        let values: Vec<Option<(f64, usize)>> = names.iter().map(|n| self.other(n)).collect();
        if values.iter().all(Option::is_none) {
            return Ok(None);
        }
        let Some((first, _)) = values[0] else {
            return Err(self.other_invalid(
                &names[0],
                f64::NAN,
                0,
                "set with the other three motors (one speed for all four)",
            ));
        };
        for (name, v) in names.iter().zip(&values) {
            match v {
                Some((x, line)) if *x != first => {
                    return Err(self.other_invalid(
                        name,
                        *x,
                        *line,
                        &format!("{first}, as SIM_GZ_EC_{kind}1 (ftsmc flies one rotor limit for all four motors)"),
                    ))
                }
                None => return Err(self.other_invalid(name, f64::NAN, 0, "set with the other three motors")),
                _ => {}
            }
        }
        if first < 0.0 {
            return Err(self.other_invalid(&names[0], first, values[0].map_or(0, |v| v.1), "a rotor speed >= 0 rad/s"));
        }
        Ok(Some(first))
    }
}

/// The airframe of `params`: `None` when it sets no `CA_ROTOR*` geometry
/// (a gains-only file). Refused, naming the parameter: a rotor count other
/// than 4, a rotor without its `_PX`/`_PY`, a zero `_KM` (no spin), motor
/// limits that differ between motors or are inverted.
pub fn airframe(params: &Px4ParamFile) -> Result<Option<Px4Airframe>, Px4ParamsError> {
    let count = params.other("CA_ROTOR_COUNT");
    let any_rotor = params.others.keys().any(|k| k.starts_with("CA_ROTOR") && k != "CA_ROTOR_COUNT");
    let (idle_speed, max_speed) = (params.motor_speed("MIN")?, params.motor_speed("MAX")?);
    if let (Some(lo), Some(hi)) = (idle_speed, max_speed) {
        if lo >= hi {
            let line = params.other("SIM_GZ_EC_MIN1").map_or(0, |v| v.1);
            return Err(params.other_invalid("SIM_GZ_EC_MIN1", lo, line, &format!("below SIM_GZ_EC_MAX1 = {hi}")));
        }
    }
    let Some((n, line)) = count else {
        if any_rotor {
            return Err(params.other_invalid(
                "CA_ROTOR_COUNT",
                f64::NAN,
                0,
                "4, set where CA_ROTOR{n}_* are (the rotor count PX4's allocation reads them with)",
            ));
        }
        return Ok(None);
    };
    if n != 4.0 {
        return Err(params.other_invalid("CA_ROTOR_COUNT", n, line, "4 (ftsmc flies quadrotors)"));
    }
    let mut positions = [[0.0; 2]; 4];
    let mut spin = [crate::vehicle::Spin::Ccw; 4];
    for r in 0..4 {
        let need = |axis: &str| {
            let name = format!("CA_ROTOR{r}_P{axis}");
            params.other(&name).map(|v| v.0).ok_or_else(|| {
                params.other_invalid(
                    &name,
                    f64::NAN,
                    0,
                    "set for every rotor (PX4's default, 0, puts the hub on the centre)",
                )
            })
        };
        positions[r] = [need("X")?, -need("Y")?];
        let km_name = format!("CA_ROTOR{r}_KM");
        // PX4's default moment ratio, 0.05 (a counter-clockwise rotor).
        let (km, km_line) = params.other(&km_name).unwrap_or((0.05, 0));
        spin[r] = if km > 0.0 {
            crate::vehicle::Spin::Ccw
        } else if km < 0.0 {
            crate::vehicle::Spin::Cw
        } else {
            return Err(params.other_invalid(
                &km_name,
                km,
                km_line,
                "nonzero: its sign is the rotor's spin (> 0 counter-clockwise)",
            ));
        };
    }
    let frame = Px4Airframe { positions, spin, idle_speed, max_speed };
    if frame.geometry().px4_torque_scale(1.0, 0.01).is_none() {
        let line = params.other("CA_ROTOR0_PX").map_or(0, |v| v.1);
        return Err(params.other_invalid(
            "CA_ROTOR0_PX",
            positions[0][0],
            line,
            "rotors that can roll, pitch and yaw the vehicle (this layout's allocation is singular)",
        ));
    }
    Ok(Some(frame))
}

/// What `params` sets that ftsmc reads but does not fly, one line each
/// (name, value, line and why): the allocation's own coefficients
/// (`CA_ROTOR{n}_CT`, the magnitude of `_KM`), rotor heights and tilted
/// axes, the Gazebo bridge's command mapping, the thrust curve
/// (`THR_MDL_FAC`), airmode, battery scaling, the attitude reference model
/// and yaw-torque filter, `MPC_THR_HOVER` under the hover-thrust estimator;
/// then a count of the other multicopter parameters (`MC_*`, `MPC_*`,
/// `CA_*`) no mapping uses. Parameters of other modules (estimator,
/// commander, drivers) are not listed.
pub fn not_flown(params: &Px4ParamFile) -> Vec<String> {
    let mut out = Vec::new();
    let at = |name: &str| params.other(name).map(|(v, l)| format!("{name} = {} (line {l})", crate::text::show(v)));
    let mut claimed: std::collections::BTreeSet<String> = std::collections::BTreeSet::new();
    let mut claim = |name: String| {
        claimed.insert(name);
    };
    for r in 0..8 {
        for suffix in ["CT", "KM", "PZ", "AX", "AY", "AZ"] {
            let name = format!("CA_ROTOR{r}_{suffix}");
            let Some(text) = at(&name) else { continue };
            let v = params.other(&name).map_or(0.0, |v| v.0);
            let why = match suffix {
                "CT" => "PX4's allocation thrust coefficient: not flown (the vehicle's thrust_coefficient is)",
                "KM" => "its sign is flown as the spin; its size, PX4's yaw-moment ratio in the allocation, is not (the vehicle's moment_coefficient is)",
                "PZ" if v == 0.0 => continue,
                "PZ" => "rotor height: not flown (ftsmc's hubs lie in the body plane)",
                "AZ" if v == -1.0 => continue,
                "AX" | "AY" if v == 0.0 => continue,
                _ => "a tilted rotor axis: not flown (ftsmc's rotors thrust along the body z axis)",
            };
            out.push(format!("{text}: {why}"));
            claim(name);
        }
        for suffix in ["PX", "PY"] {
            claim(format!("CA_ROTOR{r}_{suffix}"));
        }
    }
    claim("CA_ROTOR_COUNT".into());
    if params.others.keys().any(|k| k.starts_with("SIM_GZ_EC_")) {
        out.push(
            "SIM_GZ_EC_*: PX4's Gazebo bridge maps a motor setpoint linearly to rotor speed between SIM_GZ_EC_MIN and SIM_GZ_EC_MAX; ftsmc flies a setpoint proportional to thrust (ω² / ω_max²) — the command mapping changes the vehicle and is not flown (the limits are)"
                .into(),
        );
        for k in params.others.keys().filter(|k| k.starts_with("SIM_GZ_EC_")) {
            claim(k.clone());
        }
    }
    for (name, why) in [
        ("THR_MDL_FAC", "PX4's thrust-curve factor (setpoint to thrust): not flown, ftsmc's setpoint is thrust"),
        ("MC_AIRMODE", "airmode: flown only with [actuators] mixer = \"px4-exact-airmode\""),
        ("MC_BAT_SCALE_EN", "battery scaling: not flown (no battery model)"),
        ("MC_YAW_TQ_CUTOFF", "yaw-torque low-pass: not flown"),
        ("CA_AIRFRAME", "PX4's airframe type: ftsmc flies the CA_ROTOR geometry"),
    ] {
        if let Some(text) = at(name) {
            out.push(format!("{text}: {why}"));
            claim(name.into());
        }
    }
    if params.values.contains_key("MPC_THR_HOVER") && params.get("MPC_USE_HTE").0 == 1.0 {
        out.push(format!(
            "MPC_THR_HOVER (line {}): read but not used, the hover-thrust estimator (MPC_USE_HTE = 1) takes over",
            params.get("MPC_THR_HOVER").1
        ));
    }
    let refs: Vec<&String> = params.others.keys().filter(|k| k.starts_with("MC_REF_")).collect();
    if !refs.is_empty() {
        out.push(format!(
            "{}: the attitude reference model, not flown",
            refs.iter().map(|s| s.as_str()).collect::<Vec<_>>().join(", ")
        ));
        for k in refs {
            claim(k.clone());
        }
    }
    let rest = params
        .others
        .keys()
        .filter(|k| (k.starts_with("MC_") || k.starts_with("MPC_") || k.starts_with("CA_")) && !claimed.contains(*k))
        .count();
    if rest > 0 {
        out.push(format!("{rest} other multicopter parameters (MC_*, MPC_*, CA_*) that no mapping uses"));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_mapped_name_has_a_default_and_every_default_is_written() {
        let params = params_from_gains(&PidGains::default(), &NominalVehicle::default()).unwrap();
        assert_eq!(params.len(), PX4_DEFAULTS.len());
        for (name, _, kind) in PX4_DEFAULTS {
            let p = params.iter().find(|p| p.name == *name).unwrap_or_else(|| panic!("{name} not written"));
            assert_eq!(p.kind, *kind, "{name}");
        }
    }

    #[test]
    fn the_field_names_map_back_to_their_parameters() {
        assert_eq!(px4_name_of("rate_p[1]", true), "MC_PITCHRATE_P");
        assert_eq!(px4_name_of("velocity_i[2]", true), "MPC_Z_VEL_I_ACC");
        assert_eq!(px4_name_of("rate_integral_limit[2]", true), "MC_YR_INT_LIM");
        assert_eq!(px4_name_of("hover_thrust", false), "MPC_THR_HOVER");
        assert_eq!(px4_name_of("max_demanded_tilt", false), "MPC_TILTMAX_AIR");
    }

    fn frame_file(extra: &str) -> String {
        let mut t = String::from("1\t1\tCA_ROTOR_COUNT\t4\t6\n");
        for (r, (x, y, km)) in
            [(0.13, 0.22, 0.05), (-0.13, -0.2, 0.05), (0.13, -0.22, -0.05), (-0.13, 0.2, -0.05)].iter().enumerate()
        {
            t.push_str(&format!(
                "1\t1\tCA_ROTOR{r}_PX\t{x}\t9\n1\t1\tCA_ROTOR{r}_PY\t{y}\t9\n1\t1\tCA_ROTOR{r}_KM\t{km}\t9\n"
            ));
        }
        t.push_str(extra);
        t
    }

    #[test]
    fn an_airframe_is_read_in_ftsmcs_axes_and_its_mistakes_are_named() {
        let f = airframe(&parse_qgc(&frame_file(""), "f.params").unwrap()).unwrap().unwrap();
        assert_eq!(f.positions[0], [0.13, -0.22]);
        assert_eq!(f.spin.map(|s| s.sign()), [1.0, 1.0, -1.0, -1.0]);
        assert_eq!((f.idle_speed, f.max_speed), (None, None));
        // A gains-only file has no airframe.
        assert_eq!(airframe(&parse_qgc("1\t1\tMC_ROLL_P\t5\t9\n", "g.params").unwrap()).unwrap(), None);
        let refused = |text: &str, wanted: &str| {
            let e = parse_qgc(text, "f.params").and_then(|p| airframe(&p)).unwrap_err().to_string();
            assert!(e.contains(wanted), "{wanted}: {e}");
        };
        refused(&frame_file("").replace("CA_ROTOR_COUNT\t4", "CA_ROTOR_COUNT\t6"), "`CA_ROTOR_COUNT` = 6");
        refused(&frame_file("").replace("1\t1\tCA_ROTOR_COUNT\t4\t6\n", ""), "`CA_ROTOR_COUNT`");
        refused(&frame_file("").replace("1\t1\tCA_ROTOR2_PY\t-0.22\t9\n", ""), "`CA_ROTOR2_PY`");
        refused(&frame_file("").replace("CA_ROTOR1_KM\t0.05", "CA_ROTOR1_KM\t0"), "`CA_ROTOR1_KM` = 0");
        let ec = "1\t1\tSIM_GZ_EC_MIN1\t150\t6\n1\t1\tSIM_GZ_EC_MIN2\t150\t6\n1\t1\tSIM_GZ_EC_MIN3\t150\t6\n1\t1\tSIM_GZ_EC_MIN4\t120\t6\n";
        refused(&frame_file(ec), "`SIM_GZ_EC_MIN4` = 120");
        let f =
            airframe(&parse_qgc(&frame_file(&ec.replace("\t120\t", "\t150\t")), "f.params").unwrap()).unwrap().unwrap();
        assert_eq!(f.idle_speed, Some(150.0));
        // What is read but not flown is listed: here PX4's yaw ratio.
        let listed = not_flown(&parse_qgc(&frame_file(""), "f.params").unwrap());
        assert!(listed.iter().any(|l| l.starts_with("CA_ROTOR0_KM = 0.05 (line 4)")), "{listed:?}");
    }
}
