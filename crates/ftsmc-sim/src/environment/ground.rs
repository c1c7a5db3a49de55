//! An optional ground plane (`[ground]`).
//!
//! Contact model (deliberately simple): after every RK4 substep, if the
//! vehicle's height `z` is at or below `height`,
//!
//! - and it is moving down faster than `max_touchdown_speed`, the run ends
//!   with `ExitStatus::Crashed` (`crate::run`, a floor above, so not linked) (the time is interpolated
//!   linearly to the instant `z` crossed `height` inside the substep; the
//!   impact speed is the downward speed at the end of that substep);
//! - otherwise the vehicle rests: `z` is set to `height` and a downward
//!   vertical velocity is zeroed, so it never accelerates through the
//!   ground (no bounce, no friction: horizontal motion and attitude are left
//!   to the dynamics).
//!
//! A vehicle may start on the ground (`initial_state.position[2] = height`).

use ftsmc_core::law::GainError;
use serde::{Deserialize, Serialize};

/// `[ground]`.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct GroundSettings {
    /// Whether the ground exists (default false).
    pub enabled: bool,
    /// Height of the ground plane, m (world z, default 0).
    pub height: f64,
    /// Largest downward speed at touchdown that is not a crash, m/s (default 1.0).
    pub max_touchdown_speed: f64,
}

impl Default for GroundSettings {
    fn default() -> Self {
        Self { enabled: false, height: 0.0, max_touchdown_speed: 1.0 }
    }
}

impl GroundSettings {
    /// Reject non-finite heights and negative speeds.
    pub fn check(&self) -> Result<(), GainError> {
        if !self.height.is_finite() {
            return Err(GainError { field: "height", value: self.height, expected: "a finite height, m" });
        }
        if !(self.max_touchdown_speed.is_finite() && self.max_touchdown_speed >= 0.0) {
            return Err(GainError {
                field: "max_touchdown_speed",
                value: self.max_touchdown_speed,
                expected: "a finite speed >= 0 m/s",
            });
        }
        Ok(())
    }

    /// Apply the contact model to height `z` and vertical velocity `vz`
    /// after a substep that started at height `z_prev`. Returns
    /// `Some((fraction, impact_speed))` on a crash, `fraction ∈ [0, 1]` being
    /// where in the substep `z` crossed the ground.
    #[inline]
    pub fn contact(&self, z_prev: f64, z: &mut f64, vz: &mut f64) -> Option<(f64, f64)> {
        if !self.enabled || *z > self.height {
            return None;
        }
        if -*vz > self.max_touchdown_speed {
            let drop = z_prev - *z;
            let fraction = if drop > 0.0 { ((z_prev - self.height) / drop).clamp(0.0, 1.0) } else { 0.0 };
            return Some((fraction, -*vz));
        }
        *z = self.height;
        if *vz < 0.0 {
            *vz = 0.0;
        }
        None
    }
}
