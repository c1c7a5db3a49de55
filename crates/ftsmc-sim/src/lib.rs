//! # ftsmc-sim
//!
//! Everything around the control laws of `ftsmc-core`: the quadrotor plant of
//! paper Eq. 1 ([`plant`]), time signals for references and disturbances
//! ([`signal`]), scenario files ([`scenario`]), the zero-order-hold RK4 run
//! loop ([`simulate`]), metrics ([`metrics`]) and the controller registry
//! ([`registry`]), and the cost limits every request is checked against
//! before any flight ([`limits`]).
#![warn(missing_docs)]

pub mod actuators;
pub mod envelope;
pub mod fixed_time;
pub mod ground;
pub mod limits;
pub mod metrics;
pub mod montecarlo;
pub mod plant;
pub mod registry;
pub mod resolve;
pub mod scenario;
pub mod signal;
pub mod simulate;
pub mod truth;
pub mod tuning;
pub mod vehicle;
pub mod waypoints;

pub use scenario::{Scenario, ScenarioError};
pub use simulate::{simulate, ExitStatus, RunOptions, RunOutput};
