//! NanoBench flights: a Crazyflie 2.1 with Vicon ground truth, one CSV file
//! per flight at 100 Hz (Ullah and Baca, "NanoBench: A Multi-Task Benchmark
//! Dataset for Nano-Quadrotor System Identification, Control, and State
//! Estimation", arXiv:2603.09908, 2026; data in the repository
//! syediu/nanobench-iros2026, `datasets/dataset/*.csv`, BSD-3-Clause).
//!
//! The columns used, with the units the dataset's README gives:
//!
//! | FlightLog | columns | unit in the file |
//! | --- | --- | --- |
//! | time | `t` | s, Unix time of the Vicon host (as `f64`: steps of 2.4 × 10⁻⁷ s near 1.8 × 10⁹ s) |
//! | position | `px`, `py`, `pz` | m, Vicon world frame (z up) |
//! | velocity | `vx`, `vy`, `vz` | m/s, Vicon, Savitzky–Golay derivative |
//! | attitude | `qw`, `qx`, `qy`, `qz` | Vicon unit quaternion, scalar last in the file |
//! | body rates | `imu_gyro_x`, `_y`, `_z` | rad/s, onboard gyro, body frame |
//! | accelerometer | `imu_acc_x`, `_y`, `_z` | g (multiplied by 9.80665 m/s²) |
//! | motors | `motor_motor_m1` … `m4` | 16-bit PWM, 0–65535 |
//! | battery | `pwr_pm_vbat` | V (10 Hz, held) |
//! | set-point (when present) | `sp_ctrltarget_x`, `_y`, `_z`, `_yaw` | m, deg (converted to rad) |
//!
//! The other 20 columns (onboard EKF, PID outputs) are left in the file. The body frame is the Crazyflie's: x forward, y left, z up.

use std::path::Path;

use crate::error::LogError;
use crate::flight_log::{FlightLog, Frame, MotorUnit, Motors, Setpoint};
use crate::source::LogLimits;
use crate::table::{read_table, Table};

/// Standard gravity, m/s² (CGPM 1901): the `g` of the accelerometer columns.
pub const STANDARD_GRAVITY_M_S2: f64 = 9.80665;

/// Columns whose presence identifies a NanoBench file.
pub const SIGNATURE: [&str; 3] = ["motor_motor_m1", "pwr_pm_vbat", "imu_acc_x"];

/// Whether a CSV header is NanoBench's.
pub fn is_nanobench(names: &[String]) -> bool {
    SIGNATURE.iter().all(|s| names.iter().any(|n| n == s))
}

/// Reads one NanoBench flight (frame [`Frame::ZUpFlu`]).
pub fn read_nanobench(path: &Path, limits: &LogLimits) -> Result<FlightLog, LogError> {
    let table = read_table(path, limits)?;
    flight_from_nanobench(&table)
}

/// The [`FlightLog`] of a NanoBench table already read.
pub fn flight_from_nanobench(table: &Table) -> Result<FlightLog, LogError> {
    let t = table.require(&["t"], "time")?[0];
    let p = table.require(&["px", "py", "pz"], "Vicon position")?;
    let v = table.require(&["vx", "vy", "vz"], "Vicon velocity")?;
    let q = table.require(&["qw", "qx", "qy", "qz"], "Vicon attitude")?;
    let w = table.require(&["imu_gyro_x", "imu_gyro_y", "imu_gyro_z"], "gyro")?;
    let a = table.require(&["imu_acc_x", "imu_acc_y", "imu_acc_z"], "accelerometer")?;
    let m = table.require(&["motor_motor_m1", "motor_motor_m2", "motor_motor_m3", "motor_motor_m4"], "motors")?;
    let b = table.require(&["pwr_pm_vbat"], "battery")?[0];
    if t.is_empty() {
        return Err(LogError::Missing {
            file: table.file.clone(),
            what: "rows".into(),
            found: "only the header".into(),
        });
    }
    let origin = t[0];
    let n = t.len();
    let row3 = |c: &[&[f64]], i: usize| [c[0][i], c[1][i], c[2][i]];
    let log = FlightLog {
        source: table.file.clone(),
        frame: Frame::ZUpFlu,
        time_origin_s: origin,
        time_s: t.iter().map(|x| x - origin).collect(),
        position_m: Some((0..n).map(|i| row3(&p, i)).collect()),
        velocity_m_s: Some((0..n).map(|i| row3(&v, i)).collect()),
        attitude_wxyz: Some((0..n).map(|i| [q[0][i], q[1][i], q[2][i], q[3][i]]).collect()),
        body_rates_rad_s: Some((0..n).map(|i| row3(&w, i)).collect()),
        accel_m_s2: Some((0..n).map(|i| row3(&a, i).map(|g| g * STANDARD_GRAVITY_M_S2)).collect()),
        motors: Some(Motors {
            unit: MotorUnit::Crazyflie16Bit,
            values: (0..n).map(|i| [m[0][i], m[1][i], m[2][i], m[3][i]]).collect(),
        }),
        battery_v: Some(b.to_vec()),
        setpoint: setpoint(table),
    };
    check_columns(table)?;
    log.validate()?;
    Ok(log)
}

/// The `sp_ctrltarget_*` columns, when all four are there.
fn setpoint(table: &Table) -> Option<Setpoint> {
    let c = table.require(&["sp_ctrltarget_x", "sp_ctrltarget_y", "sp_ctrltarget_z", "sp_ctrltarget_yaw"], "").ok()?;
    Some(Setpoint {
        position_m: (0..c[0].len()).map(|i| [c[0][i], c[1][i], c[2][i]]).collect(),
        yaw_rad: c[3].iter().map(|d| d.to_radians()).collect(),
    })
}

/// Names the CSV column of a non-finite value or of time going back,
/// before [`FlightLog::validate`] would name the channel only.
fn check_columns(table: &Table) -> Result<(), LogError> {
    let t = table.column("t").unwrap_or(&[]);
    for (name, column) in table.names.iter().zip(&table.columns) {
        if let Some(i) = column.iter().position(|x| !x.is_finite()) {
            return Err(LogError::NotFinite {
                file: table.file.clone(),
                field: format!("column {name}"),
                index: i,
                time: t.get(i).copied().unwrap_or(f64::NAN),
                value: column[i],
            });
        }
    }
    if let Some(i) = (1..t.len()).find(|&i| t[i] <= t[i - 1]) {
        return Err(LogError::NonMonotonicTime {
            file: table.file.clone(),
            channel: "column t".into(),
            index: i,
            previous: t[i - 1],
            next: t[i],
        });
    }
    Ok(())
}
