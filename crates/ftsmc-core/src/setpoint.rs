//! Setpoint helpers shared by the full-state controllers ([`crate::pid`],
//! [`crate::se3`]): the tilt limit of a thrust direction and the finiteness
//! check of a reference. Their own module, so neither controller imports
//! the other for them.

use crate::math::{cos, finite_probe, sin, sqrt, Vec3};
use crate::model::Reference;

/// The tilt limit of a thrust direction with `cos(max_tilt)` and
/// `sin(max_tilt)` taken once (the limit is a gain, constant over a flight).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct TiltLimit {
    cos: f64,
    sin: f64,
}

impl TiltLimit {
    /// The limit `max_tilt` (rad) from the vertical.
    pub(crate) fn new(max_tilt: f64) -> Self {
        Self { cos: cos(max_tilt), sin: sin(max_tilt) }
    }

    /// Rotate the unit vector `b` towards the vertical so that its angle to
    /// `e₃` is at most `max_tilt` (PX4 `ControlMath::limitTilt`, z up).
    #[inline]
    pub(crate) fn apply(&self, b: Vec3) -> Vec3 {
        let c = b[2];
        let limit_cos = self.cos;
        if c >= limit_cos {
            return b;
        }
        let horizontal = sqrt(b[0] * b[0] + b[1] * b[1]);
        let (hx, hy) = if horizontal > 1e-12 { (b[0] / horizontal, b[1] / horizontal) } else { (1.0, 0.0) };
        let s = self.sin;
        [s * hx, s * hy, limit_cos]
    }
}

/// Every component of the reference is finite.
#[inline]
pub(crate) fn reference_finite(r: &Reference) -> bool {
    finite_probe(&r.position)
        + finite_probe(&r.velocity)
        + finite_probe(&r.acceleration)
        + finite_probe(&[r.yaw, r.yaw_rate, r.yaw_acceleration])
        == 0.0
}
