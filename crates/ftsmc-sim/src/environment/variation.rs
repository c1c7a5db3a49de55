//! Variations of the true plant parameters: multiplicative drag noise per
//! control period (inertia variation is a plain [`crate::signal::Signal`]
//! `ΔI/I`(t), applied in [`super::Environment`]).

use serde::{Deserialize, Serialize};

/// Multiplicative white Gaussian noise on every drag coefficient:
/// `K · max(0, 1 + std · w)`, `w ~ N(0, 1)` drawn once per control period,
/// one independent stream per coefficient.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DragNoise {
    /// Relative standard deviation (0.25 = 25 %).
    pub std: f64,
}
