//! `ftsmc._ftsmc.log_*`: flight logs, identification and validation for
//! Python (`ftsmc.read_log`, `ftsmc.identify`, `ftsmc.validate`). The
//! computations are `ftsmc-logs` and `ftsmc-ident`'s; the tables are
//! `ftsmc_ident::report`'s, the same text the CLI writes.

use std::path::Path;

use ftsmc_ident::identify::{identify, IdentifyOptions};
use ftsmc_ident::series::Series;
use ftsmc_ident::validate::{validate, ValidateOptions};
use ftsmc_ident::vehicle::Vehicle;
use ftsmc_logs::{Frame, MotorUnit};
use numpy::PyArray1;
use pyo3::prelude::*;

use crate::value_error;

fn frame_name(f: Frame) -> &'static str {
    match f {
        Frame::NedFrd => "ned-frd",
        Frame::ZUpFlu => "zup-flu",
        Frame::Unspecified => "unspecified",
    }
}

fn unit_name(u: MotorUnit) -> &'static str {
    match u {
        MotorUnit::Normalised => "normalised",
        MotorUnit::PwmMicroseconds => "pwm-us",
        MotorUnit::Crazyflie16Bit => "crazyflie-16bit",
    }
}

/// The log at `path` (PX4 ULog, NanoBench CSV or the generic CSV; docs/logs.md)
/// as columns in the generic CSV schema's names (`time_s`, `x_m`…, `qw`…,
/// `p_rad_s`…, `ax_m_s2`…, `motor1`…, `battery_v`; only the channels the
/// log has), each a float64 array, in the log's own frame and units;
/// and `(source, frame, time_origin_s, motor_unit)`.
#[pyfunction]
#[allow(clippy::type_complexity)]
pub fn log_columns<'py>(
    py: Python<'py>,
    path: &str,
) -> PyResult<(Vec<String>, Vec<Bound<'py, PyArray1<f64>>>, (String, String, f64, Option<String>))> {
    let log =
        py.detach(|| ftsmc_logs::read_log(Path::new(path), &ftsmc_logs::LogLimits::default())).map_err(value_error)?;
    let mut names: Vec<String> = vec!["time_s".into()];
    let mut cols: Vec<Vec<f64>> = vec![log.time_s.clone()];
    push(&mut names, &mut cols, ["x_m", "y_m", "z_m"], &log.position_m);
    push(&mut names, &mut cols, ["vx_m_s", "vy_m_s", "vz_m_s"], &log.velocity_m_s);
    push(&mut names, &mut cols, ["qw", "qx", "qy", "qz"], &log.attitude_wxyz);
    push(&mut names, &mut cols, ["p_rad_s", "q_rad_s", "r_rad_s"], &log.body_rates_rad_s);
    push(&mut names, &mut cols, ["ax_m_s2", "ay_m_s2", "az_m_s2"], &log.accel_m_s2);
    let motors = log.motors.as_ref().map(|m| m.values.clone());
    push(&mut names, &mut cols, ["motor1", "motor2", "motor3", "motor4"], &motors);
    if let Some(b) = &log.battery_v {
        names.push("battery_v".into());
        cols.push(b.clone());
    }
    let arrays = cols.into_iter().map(|c| PyArray1::from_vec(py, c)).collect();
    let meta = (
        log.source.clone(),
        frame_name(log.frame).to_string(),
        log.time_origin_s,
        log.motors.as_ref().map(|m| unit_name(m.unit).to_string()),
    );
    Ok((names, arrays, meta))
}

/// Appends the `N` columns of `v` (when the log has it) named `prefix`.
fn push<const N: usize>(
    names: &mut Vec<String>,
    cols: &mut Vec<Vec<f64>>,
    prefix: [&str; N],
    v: &Option<Vec<[f64; N]>>,
) {
    if let Some(v) = v {
        for (i, p) in prefix.iter().enumerate() {
            names.push(p.to_string());
            cols.push(v.iter().map(|r| r[i]).collect());
        }
    }
}

fn read_series(logs: &[String], purpose: &'static str) -> PyResult<Vec<Series>> {
    if logs.is_empty() {
        return Err(value_error("logs = [] is invalid (expected at least one flight log)"));
    }
    Series::read_all(logs, purpose).map_err(value_error)
}

/// `ftsmc identify` (docs/validation.md): the vehicle file (TOML), the
/// parameters table (CSV) and the whole identification (JSON).
#[pyfunction]
#[pyo3(signature = (logs, vehicle, mass=None, bootstrap=200, seed=0, segment=2.0, max_delay=5))]
#[allow(clippy::too_many_arguments)]
pub fn log_identify(
    py: Python<'_>,
    logs: Vec<String>,
    vehicle: &str,
    mass: Option<f64>,
    bootstrap: usize,
    seed: u64,
    segment: f64,
    max_delay: usize,
) -> PyResult<(String, String, String)> {
    let base = Vehicle::load(vehicle).map_err(value_error)?;
    let series = read_series(&logs, "identification")?;
    let options = IdentifyOptions {
        mass_kg: mass,
        segment_s: segment,
        bootstrap,
        seed,
        max_delay_steps: max_delay,
        ..Default::default()
    };
    let id = py.detach(|| identify(&series, &base, &options)).map_err(value_error)?;
    let base_path = match &base.file {
        Some(f) => Some(
            std::fs::canonicalize(f)
                .map_err(|e| value_error(format!("cannot resolve {f}: {e}")))?
                .display()
                .to_string(),
        ),
        None => None,
    };
    let json = serde_json::to_string_pretty(&ftsmc_ident::report::identification_json(&id)).map_err(value_error)?;
    Ok((id.vehicle_toml(base_path.as_deref()), ftsmc_ident::report::parameters_csv(&id), json))
}

/// `ftsmc validate` (docs/validation.md): the validation table (CSV).
#[pyfunction]
#[pyo3(signature = (logs, vehicle, bootstrap=200, seed=0, command_delay=0))]
pub fn log_validate(
    py: Python<'_>,
    logs: Vec<String>,
    vehicle: &str,
    bootstrap: usize,
    seed: u64,
    command_delay: usize,
) -> PyResult<String> {
    let vehicle = Vehicle::load(vehicle).map_err(value_error)?;
    let series = read_series(&logs, "validation")?;
    let options = ValidateOptions { bootstrap, seed, command_delay_steps: command_delay, ..Default::default() };
    let rows = py.detach(|| validate(&series, &vehicle, &options)).map_err(value_error)?;
    Ok(ftsmc_ident::report::validation_csv(&rows))
}

/// A flight made by ftsmc's own plant for the tests and examples
/// (`ftsmc_ident::synthetic`): `duration_s` s of dithered hover of
/// `vehicle`, with optional accelerometer and gyro noise (m/s², rad/s),
/// as generic CSV text.
#[pyfunction]
#[pyo3(signature = (vehicle, duration_s=12.0, accel_noise=0.0, gyro_noise=0.0, seed=0))]
pub fn log_synthetic(vehicle: &str, duration_s: f64, accel_noise: f64, gyro_noise: f64, seed: u64) -> PyResult<String> {
    if !(duration_s > 0.0 && duration_s <= 3600.0) {
        return Err(value_error(format!("duration_s = {duration_s}: expected 0 < duration_s <= 3600")));
    }
    for (name, v) in [("accel_noise", accel_noise), ("gyro_noise", gyro_noise)] {
        if !(v >= 0.0 && v.is_finite()) {
            return Err(value_error(format!("{name} = {v}: expected a finite value >= 0")));
        }
    }
    let v = Vehicle::load(vehicle).map_err(value_error)?;
    let o = ftsmc_ident::synthetic::SyntheticOptions {
        duration_s,
        accel_noise_m_s2: accel_noise,
        gyro_noise_rad_s: gyro_noise,
        seed,
        ..Default::default()
    };
    let log = ftsmc_ident::synthetic::fly(&v, &o).map_err(value_error)?;
    Ok(ftsmc_ident::synthetic::to_generic_csv(&log))
}
