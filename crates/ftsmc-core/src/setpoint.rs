//! Setpoint helpers shared by the full-state controllers ([`crate::pid`],
//! [`crate::se3`]): the tilt limit of a thrust direction, the finiteness
//! check of a reference and the sine and cosine of the reference heading
//! kept from one period to the next. Their own module, so neither
//! controller imports the other for them. Generic over the number type
//! ([`crate::lanes`]): the same bits per lane as on `f64`.

use crate::lanes::{branch, Real};
use crate::math::{cos, finite_probe, sin, Vec3};
use crate::model::Reference;

/// The tilt limit of a thrust direction with `cos(max_tilt)` and
/// `sin(max_tilt)` taken once (the limit is a gain, constant over a flight
/// and the same in every lane).
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
    /// `e₃` is at most `max_tilt` (PX4 `ControlMath::limitTilt`, z up); per
    /// lane for lanes.
    #[inline]
    pub(crate) fn apply<R: Real>(&self, b: Vec3<R>) -> Vec3<R> {
        let limit_cos = R::splat(self.cos);
        branch(
            b[2].ge(limit_cos),
            || b,
            || {
                let horizontal = (b[0] * b[0] + b[1] * b[1]).sqrt();
                let (hx, hy) = branch(
                    horizontal.gt(R::splat(1e-12)),
                    || (b[0] / horizontal, b[1] / horizontal),
                    || (R::splat(1.0), R::splat(0.0)),
                );
                // `hx · s`: the product `s hx` with its operands swapped (same bits).
                [hx * self.sin, hy * self.sin, limit_cos]
            },
        )
    }
}

/// Every component of the reference is finite (per lane).
#[inline]
pub(crate) fn reference_finite<R: Real>(r: &Reference<R>) -> R::Mask {
    (finite_probe(&r.position)
        + finite_probe(&r.velocity)
        + finite_probe(&r.acceleration)
        + finite_probe(&[r.yaw, r.yaw_rate, r.yaw_acceleration]))
    .eq(R::splat(0.0))
}

/// `(sin ψ, cos ψ)` of the last heading ψ (rad), per lane: recomputed
/// ([`Real::sin_cos`]) only when the bits of ψ change in some lane, so a
/// constant heading reference is not reduced and expanded again every
/// period. Always the bits of `sin_cos(ψ)` (as [`crate::math::SinCosCache`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct HeadingSinCos<R: Real> {
    heading: R,
    value: (R, R),
}

impl<R: Real> HeadingSinCos<R> {
    /// A cache holding `sin_cos(0)` in every lane.
    pub(crate) fn new() -> Self {
        let heading = R::splat(0.0);
        Self { heading, value: heading.sin_cos() }
    }

    /// `(sin ψ, cos ψ)`, the bits of [`Real::sin_cos`]`(ψ)`.
    #[inline]
    pub(crate) fn get(&mut self, heading: R) -> (R, R) {
        if (0..R::LANES).any(|i| heading.get_lane(i).to_bits() != self.heading.get_lane(i).to_bits()) {
            self.value = heading.sin_cos();
            self.heading = heading;
        }
        self.value
    }
}
