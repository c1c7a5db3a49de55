//! A payload picked up (and optionally shed) during the flight.

use serde::{Deserialize, Serialize};

/// Payload profile: nominal mass until `start`, `+mass` held until
/// `decay_start`, then `mass · exp(−(t − decay_start)/tau)`.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Payload {
    /// Added mass Δm, kg.
    pub mass: f64,
    /// Time the payload is picked up, s.
    pub start: f64,
    /// Time the exponential decay starts, s (default: never).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub decay_start: Option<f64>,
    /// Decay time constant τ, s (required with `decay_start`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tau: Option<f64>,
}

impl Payload {
    /// Added mass at `t`, kg.
    pub fn added_mass(&self, t: f64) -> f64 {
        if t < self.start {
            return 0.0;
        }
        match (self.decay_start, self.tau) {
            (Some(t2), Some(tau)) if t >= t2 => self.mass * ftsmc_core::math::exp(-(t - t2) / tau),
            _ => self.mass,
        }
    }
}
