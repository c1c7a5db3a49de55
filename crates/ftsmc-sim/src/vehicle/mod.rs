//! Truth models: the vehicle the simulation flies, as opposed to the model
//! a controller was designed on.
//!
//! - [`paper`] — paper Eq. 1 with Euler angles and Euler rates, and the
//!   generic RK4 step every model is integrated with.
//! - [`rigid_body`] — Newton–Euler dynamics with quaternion attitude and body
//!   rates, per-rotor thrust and drag torque, rotor gyroscopic torque and
//!   RotorPy-style air-relative aerodynamics (parasitic and rotor drag),
//!   with conversions to the Euler [`ftsmc_core::model::QuadState`] the
//!   paper's controllers expect.
//!
//! - [`presets`] — named real vehicles with sourced parameters
//!   (`[vehicle] preset`).
//! - [`section`] — `[vehicle]`: which model flies and the true vehicle's
//!   parameters, one key set for both models.
//!
//! Models here depend only on `ftsmc-core` and on the integrator in
//! [`paper`]; nothing here knows about scenarios or the run loop.

mod math;
pub mod paper;
pub mod presets;
pub mod rigid_body;
pub mod section;

pub use rigid_body::{
    body_rates_to_euler_rates, euler_rates_to_body_rates, euler_to_quaternion, from_quad_state, quaternion_to_euler,
    to_quad_state, try_to_quad_state, Configuration, GimbalLock, PreparedInput, RigidBody, RigidBodyInput,
    RigidBodyParams, RigidBodyState, Spin, Wrench,
};

pub use presets::VehiclePreset;
pub use section::{Inertia, VehicleModel, VehicleSettings};
