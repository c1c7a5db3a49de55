//! Setpoint helpers shared by the full-state controllers ([`crate::pid`],
//! [`crate::se3`]): the tilt limit of a thrust direction and the finiteness
//! check of a reference. Their own module, so neither controller imports
//! the other for them.

use crate::math::{cos, sin, sqrt, Vec3};
use crate::model::Reference;

/// Rotate the unit vector `b` towards the vertical so that its angle to
/// `e₃` is at most `max_tilt` (PX4 `ControlMath::limitTilt`, z up).
pub(crate) fn limit_tilt(b: Vec3, max_tilt: f64) -> Vec3 {
    let c = b[2];
    let limit_cos = cos(max_tilt);
    if c >= limit_cos {
        return b;
    }
    let horizontal = sqrt(b[0] * b[0] + b[1] * b[1]);
    let (hx, hy) = if horizontal > 1e-12 { (b[0] / horizontal, b[1] / horizontal) } else { (1.0, 0.0) };
    let s = sin(max_tilt);
    [s * hx, s * hy, limit_cos]
}

/// Every component of the reference is finite.
pub(crate) fn reference_finite(r: &Reference) -> bool {
    r.position.iter().chain(&r.velocity).chain(&r.acceleration).all(|v| v.is_finite())
        && r.yaw.is_finite()
        && r.yaw_rate.is_finite()
        && r.yaw_acceleration.is_finite()
}
