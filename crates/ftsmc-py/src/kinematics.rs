//! `ftsmc._ftsmc.kinematics_*`: the core's Z-Y-X Euler / quaternion
//! conversions (`ftsmc_core::kinematics`, `libm` trigonometry) for Python,
//! so `ftsmc.rotorpy` converts states with the very functions the
//! controllers and the simulator use. Inputs are sequences or numpy arrays
//! of floats; outputs are numpy arrays. Quaternions are `[w, x, y, z]`
//! (scalar first, body → world).

use ftsmc_core::kinematics;
use numpy::PyArray1;
use pyo3::prelude::*;

use crate::value_error;

/// `values` as `[f64; N]`, or a `ValueError` naming the argument.
fn fixed<const N: usize>(name: &str, values: Vec<f64>) -> PyResult<[f64; N]> {
    let n = values.len();
    values.try_into().map_err(|_| value_error(format!("{name}: expected {N} numbers, got {n}")))
}

/// Z-Y-X Euler angles `[φ, θ, ψ]` (rad) of a unit quaternion `[w, x, y, z]`.
#[pyfunction]
pub(crate) fn kinematics_euler_from_quaternion(py: Python<'_>, q: Vec<f64>) -> PyResult<Bound<'_, PyArray1<f64>>> {
    let q = fixed::<4>("q", q)?;
    Ok(PyArray1::from_slice(py, &kinematics::euler_from_quaternion(&q)))
}

/// Unit quaternion `[w, x, y, z]` of Z-Y-X Euler angles `[φ, θ, ψ]` (rad).
#[pyfunction]
pub(crate) fn kinematics_quaternion_from_euler(py: Python<'_>, euler: Vec<f64>) -> PyResult<Bound<'_, PyArray1<f64>>> {
    let e = fixed::<3>("euler", euler)?;
    Ok(PyArray1::from_slice(py, &kinematics::quaternion_from_euler(&e)))
}

/// Euler rates `[φ̇, θ̇, ψ̇]` (rad/s) of body rates `[p, q, r]` (rad/s) at
/// `euler` (rad); `cos θ` clamped to ±1e-6 at gimbal lock.
#[pyfunction]
pub(crate) fn kinematics_euler_rates(
    py: Python<'_>,
    euler: Vec<f64>,
    body_rates: Vec<f64>,
) -> PyResult<Bound<'_, PyArray1<f64>>> {
    let e = fixed::<3>("euler", euler)?;
    let w = fixed::<3>("body_rates", body_rates)?;
    Ok(PyArray1::from_slice(py, &kinematics::euler_rates_from_body_rates(&e, &w)))
}

/// Body rates `[p, q, r]` (rad/s) of Euler rates `[φ̇, θ̇, ψ̇]` (rad/s) at
/// `euler` (rad).
#[pyfunction]
pub(crate) fn kinematics_body_rates(
    py: Python<'_>,
    euler: Vec<f64>,
    euler_rates: Vec<f64>,
) -> PyResult<Bound<'_, PyArray1<f64>>> {
    let e = fixed::<3>("euler", euler)?;
    let r = fixed::<3>("euler_rates", euler_rates)?;
    Ok(PyArray1::from_slice(py, &kinematics::body_rates_from_euler_rates(&e, &r)))
}
