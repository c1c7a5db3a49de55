//! System identification of a quadrotor from flight logs, and open-loop
//! validation of ftsmc's rigid-body plant against them (docs/validation.md).
//!
//! - [`series`]: a [`ftsmc_logs::FlightLog`] in ftsmc's frames (world z up,
//!   body forward-left-up) and rotor numbering, commands normalised to 0–1.
//! - [`vehicle`]: the vehicle a log is identified against or validated on
//!   (a preset name or a scenario/vehicle file, flown as ftsmc's rigid body).
//! - [`identify`]: physics-based linear least squares on the Newton–Euler
//!   equations, the motor lag by a grid over τ, intervals by a bootstrap over
//!   flight segments; [`identify::Identification::vehicle_toml`] writes a
//!   vehicle file the simulator accepts.
//! - [`validate`]: the plant's predicted specific force and angular
//!   acceleration from logged states and commands (one step, 0.1 s, 0.5 s)
//!   against the measured ones, beside a constant-acceleration baseline.
//! - [`closed_loop`]: the log's set-point flown in ftsmc by the log's
//!   controller (the Crazyflie firmware's PID or Mellinger), the simulated
//!   tracking error beside the real one, flight by flight.
//! - [`report`]: the identification's and the validation's tables (CSV,
//!   JSON), shared by the CLI and the Python binding.
//! - [`synthetic`]: a flight made by ftsmc's own plant and motor models, as a
//!   [`ftsmc_logs::FlightLog`] and in the generic CSV schema (the tests'
//!   known truth).

pub mod closed_loop;
pub mod error;
pub mod identify;
pub mod lsq;
pub mod report;
pub mod series;
pub mod synthetic;
pub mod validate;
pub mod vehicle;

pub use error::IdentError;
