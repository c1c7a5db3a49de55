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
//! Models here depend only on `ftsmc-core` and on the integrator in
//! [`paper`]; nothing here knows about scenarios or the run loop.

mod math;
pub mod paper;
pub mod rigid_body;

pub use rigid_body::{
    body_rates_to_euler_rates, euler_rates_to_body_rates, euler_to_quaternion, from_quad_state, quaternion_to_euler,
    to_quad_state, try_to_quad_state, Configuration, GimbalLock, RigidBody, RigidBodyInput, RigidBodyParams,
    RigidBodyState, Spin, Wrench,
};

use serde::{Deserialize, Serialize};

/// Which truth model flies (`[vehicle] model`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum VehicleModel {
    /// Paper Eq. 1 (default).
    #[default]
    Paper,
    /// Newton–Euler rigid body ([`rigid_body`]).
    RigidBody,
}

/// `[vehicle]`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct VehicleSettings {
    /// Truth model (default `paper`).
    #[serde(default)]
    pub model: VehicleModel,
    /// Rigid-body parameters (default: [`RigidBodyParams::from_paper`] of
    /// the true plant, aerodynamics off). A given table is complete: its
    /// missing keys take the [`RigidBodyParams`] defaults (paper vehicle).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rigid_body: Option<RigidBodyParams>,
}

impl VehicleSettings {
    /// True when nothing is set (for `skip_serializing_if`).
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }
}
