//! The generic flight-log CSV of ftsmc, for any vehicle whose log is
//! neither ULog nor NanoBench: one header line, one row per time stamp,
//! SI units in the column names (docs/logs.md lists them).
//!
//! `time_s` is required; every other group (position, velocity, attitude,
//! body rates, accelerometer, motors, battery, set-point) is optional but all or
//! nothing: `x_m` without `z_m` is an error naming the missing column.
//! Columns of other names are ignored. An optional comment line before the
//! header, `# frame: ned-frd` or `# frame: zup-flu`, states the frames.

use std::path::Path;

use crate::error::LogError;
use crate::flight_log::{FlightLog, Frame, MotorUnit, Motors, Setpoint};
use crate::source::LogLimits;
use crate::table::{read_table, Table};

/// The column groups of the schema, in order, with what each holds.
pub const GROUPS: [(&str, &[&str]); 8] = [
    ("position, m, world frame", &["x_m", "y_m", "z_m"]),
    ("velocity, m/s, world frame", &["vx_m_s", "vy_m_s", "vz_m_s"]),
    ("attitude quaternion body to world, scalar first", &["qw", "qx", "qy", "qz"]),
    ("body rates, rad/s, body frame", &["p_rad_s", "q_rad_s", "r_rad_s"]),
    ("accelerometer specific force, m/s², body frame", &["ax_m_s2", "ay_m_s2", "az_m_s2"]),
    ("motor commands, normalised 0..1", &["motor1", "motor2", "motor3", "motor4"]),
    ("battery voltage, V", &["battery_v"]),
    ("position (m, world frame) and yaw (rad) set-point", &["sp_x_m", "sp_y_m", "sp_z_m", "sp_yaw_rad"]),
];

/// Whether a CSV header is the generic schema's (it has `time_s`).
pub fn is_generic(names: &[String]) -> bool {
    names.iter().any(|n| n == "time_s")
}

/// Reads a generic flight-log CSV.
pub fn read_generic_csv(path: &Path, limits: &LogLimits) -> Result<FlightLog, LogError> {
    let table = read_table(path, limits)?;
    flight_from_generic(&table)
}

/// The [`FlightLog`] of a generic table already read.
pub fn flight_from_generic(table: &Table) -> Result<FlightLog, LogError> {
    let file = || table.file.clone();
    let frame = frame_of(table)?;
    let t = table.require(&["time_s"], "time")?[0];
    if t.is_empty() {
        return Err(LogError::Missing { file: file(), what: "rows".into(), found: "only the header".into() });
    }
    let mut groups: Vec<Option<Vec<&[f64]>>> = Vec::new();
    for (what, names) in GROUPS {
        let present = names.iter().filter(|n| table.column(n).is_some()).count();
        groups.push(if present == 0 { None } else { Some(table.require(names, what)?) });
    }
    for (name, column) in table.names.iter().zip(&table.columns) {
        let used = name == "time_s" || GROUPS.iter().any(|(_, g)| g.contains(&name.as_str()));
        if let (true, Some(i)) = (used, column.iter().position(|x| !x.is_finite())) {
            return Err(LogError::NotFinite {
                file: file(),
                field: format!("column {name}"),
                index: i,
                time: t[i],
                value: column[i],
            });
        }
    }
    if let Some(i) = (1..t.len()).find(|&i| t[i] <= t[i - 1]) {
        return Err(LogError::NonMonotonicTime {
            file: file(),
            channel: "column time_s".into(),
            index: i,
            previous: t[i - 1],
            next: t[i],
        });
    }
    let n = t.len();
    let origin = t[0];
    let vec3 = |g: &Option<Vec<&[f64]>>| g.as_ref().map(|c| (0..n).map(|i| [c[0][i], c[1][i], c[2][i]]).collect());
    let vec4 = |g: &Option<Vec<&[f64]>>| {
        g.as_ref().map(|c| (0..n).map(|i| [c[0][i], c[1][i], c[2][i], c[3][i]]).collect::<Vec<_>>())
    };
    let log = FlightLog {
        source: file(),
        frame,
        time_origin_s: origin,
        time_s: t.iter().map(|x| x - origin).collect(),
        position_m: vec3(&groups[0]),
        velocity_m_s: vec3(&groups[1]),
        attitude_wxyz: vec4(&groups[2]),
        body_rates_rad_s: vec3(&groups[3]),
        accel_m_s2: vec3(&groups[4]),
        motors: vec4(&groups[5]).map(|values| Motors { unit: MotorUnit::Normalised, values }),
        battery_v: groups[6].as_ref().map(|c| c[0].to_vec()),
        setpoint: vec4(&groups[7]).map(|rows| Setpoint {
            position_m: rows.iter().map(|r| [r[0], r[1], r[2]]).collect(),
            yaw_rad: rows.iter().map(|r| r[3]).collect(),
        }),
    };
    log.validate()?;
    Ok(log)
}

fn frame_of(table: &Table) -> Result<Frame, LogError> {
    let mut frame = Frame::Unspecified;
    for comment in &table.comments {
        if let Some(value) = comment.strip_prefix("frame:") {
            frame = match value.trim() {
                "ned-frd" => Frame::NedFrd,
                "zup-flu" => Frame::ZUpFlu,
                other => {
                    return Err(LogError::Malformed {
                        file: table.file.clone(),
                        format: "CSV",
                        offset: 0,
                        detail: format!("`# frame: {other}`: the frame is `ned-frd` or `zup-flu`"),
                    })
                }
            };
        }
    }
    Ok(frame)
}
