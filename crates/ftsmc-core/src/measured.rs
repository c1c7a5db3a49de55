//! What the simulator hands a controller each control period: the Euler
//! state of paper Eq. 1 ([`QuadState`]) and, when the truth model or the
//! sensors have them, the attitude quaternion and body rates that state came
//! from ([`BodyAttitude`]).
//!
//! The paper's cascade works on Euler angles and rates and reads
//! [`Measurement::euler`] only. Full-state controllers (PID, SE(3)) work on
//! the rotation and the body rates; given [`Measurement::body`] they take
//! them as they are instead of rebuilding them from the Euler angles
//! (`R = R_z(ψ) R_y(θ) R_x(φ)` and `Ω = W(φ, θ) η̇`, five `sin`/`cos` pairs and
//! a matrix-to-quaternion conversion per update).

use crate::lanes::Real;
use crate::model::QuadState;

/// Attitude as a unit quaternion and body rates, the rigid body's own
/// variables (Newton–Euler with `q̇ = ½ q ⊗ (0, Ω)`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BodyAttitude<R = f64> {
    /// Unit quaternion `[w, x, y, z]` (scalar first, Hamilton product),
    /// body → world: `v_w = R(q) v_b`, with `R(q) = R_z(ψ) R_y(θ) R_x(φ)` of
    /// the Euler angles of the same measurement
    /// ([`crate::kinematics::quaternion_from_euler`]).
    pub quaternion: [R; 4],
    /// Body rates `Ω = [p, q, r]` in the body frame, rad/s.
    pub body_rates: [R; 3],
}
crate::lanewise_struct!(BodyAttitude { quaternion, body_rates });

impl<R: Real> BodyAttitude<R> {
    /// True (per lane) when every component is finite.
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn is_finite(&self) -> R::Mask {
        (crate::math::finite_probe(&self.quaternion) + crate::math::finite_probe(&self.body_rates)).eq(R::splat(0.0))
    }
}

/// One measurement of the vehicle as the controller stage receives it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Measurement<R = f64> {
    /// The Euler state of paper Eq. 1 (position, Z-Y-X angles, velocity,
    /// Euler rates), always present.
    pub euler: QuadState<R>,
    /// The same attitude as quaternion and body rates, when the source has
    /// them (the rigid-body truth, or sensors reading it); `None` for the
    /// paper plant, whose state is the Euler state.
    pub body: Option<BodyAttitude<R>>,
}
crate::lanewise_struct!(Measurement { euler, body });

impl Measurement {
    /// A measurement of an Euler state alone.
    pub fn euler(state: QuadState) -> Self {
        Self { euler: state, body: None }
    }
}
