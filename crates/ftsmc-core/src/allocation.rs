//! Rotor allocation of paper Eq. 2 ("+" configuration, rotors 1..4 on the
//! body axes): thrust and torques ⇄ squared rotor speeds, and the residual
//! rotor speed `Ω̄ = ω1 − ω2 + ω3 − ω4` of the gyroscopic term.
//!
//! Every function is generic over the number type ([`crate::lanes`]): one
//! flight (`f64`) or lanes, lane `i` with the bits of the `f64` call on
//! lane `i`'s values; the parameters are shared.

use crate::lanes::Real;
use crate::model::{Command, QuadrotorParams};

/// Thrust and torques produced by squared rotor speeds `w = ω²` (rad²/s²), Eq. 2:
/// `U1 = bΣw`, `u2 = b l (w4 − w2)`, `u3 = b l (w3 − w1)`, `u4 = d (w1 − w2 + w3 − w4)`.
pub fn forces_from_squared_speeds<R: Real>(p: &QuadrotorParams, w: &[R; 4]) -> Command<R> {
    let b = p.lift_coefficient;
    let bl = b * p.arm_length;
    Command {
        thrust: (w[0] + w[1] + w[2] + w[3]) * b,
        torque: [(w[3] - w[1]) * bl, (w[2] - w[0]) * bl, (w[0] - w[1] + w[2] - w[3]) * p.yaw_drag_coefficient],
    }
}

/// Exact inverse of [`forces_from_squared_speeds`]: the squared rotor speeds
/// (rad²/s², possibly negative when the command is infeasible).
pub fn squared_speeds_from_forces<R: Real>(p: &QuadrotorParams, c: &Command<R>) -> [R; 4] {
    let total = c.thrust / p.lift_coefficient; // Σw
    let roll = c.torque[0] / (p.lift_coefficient * p.arm_length); // w4 − w2
    let pitch = c.torque[1] / (p.lift_coefficient * p.arm_length); // w3 − w1
    let yaw = c.torque[2] / p.yaw_drag_coefficient; // w1 − w2 + w3 − w4
    let odd = (total + yaw) * 0.5; // w1 + w3
    let even = (total - yaw) * 0.5; // w2 + w4
    [(odd - pitch) * 0.5, (even - roll) * 0.5, (odd + pitch) * 0.5, (even + roll) * 0.5]
}

/// Rotor speeds (rad/s) for a command, each squared speed clamped to
/// `[0, max_speed²]` (`max_speed = f64::INFINITY` for no upper limit):
/// the lower bound first, then the upper (the order of `f64::clamp`, whose
/// bits this gives for `max_speed >= 0`; unlike it, never panics: a NaN
/// `max_speed` leaves the upper bound off).
pub fn rotor_speeds<R: Real>(p: &QuadrotorParams, c: &Command<R>, max_speed: f64) -> [R; 4] {
    let w = squared_speeds_from_forces(p, c);
    let zero = R::splat(0.0);
    let w_max = R::splat(max_speed * max_speed);
    w.map(|wi| {
        let lower = R::select(wi.lt(zero), zero, wi);
        R::select(lower.gt(w_max), w_max, lower).sqrt()
    })
}

/// Residual rotor speed `Ω̄ = ω1 − ω2 + ω3 − ω4`, rad/s (gyroscopic term of Eq. 1).
pub fn residual_speed<R: Real>(omega: &[R; 4]) -> R {
    omega[0] - omega[1] + omega[2] - omega[3]
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn round_trip_inside_feasible_set(w in proptest::array::uniform4(0.0f64..2.0e5)) {
            let p = QuadrotorParams::default();
            let c = forces_from_squared_speeds(&p, &w);
            let back = squared_speeds_from_forces(&p, &c);
            for i in 0..4 {
                prop_assert!((back[i] - w[i]).abs() <= 1e-9 * (1.0 + w[i]));
            }
            let omega = rotor_speeds(&p, &c, f64::INFINITY);
            let c2 = forces_from_squared_speeds(&p, &omega.map(|o| o * o));
            prop_assert!((c2.thrust - c.thrust).abs() <= 1e-9 * (1.0 + c.thrust.abs()));
            for i in 0..3 {
                prop_assert!((c2.torque[i] - c.torque[i]).abs() <= 1e-9 * (1.0 + c.torque[i].abs()));
            }
        }
    }

    #[test]
    fn hover_speed_is_about_247_rad_s() {
        let p = QuadrotorParams::default();
        let hover = Command { thrust: p.mass * p.gravity, torque: [0.0; 3] };
        let omega = rotor_speeds(&p, &hover, f64::INFINITY);
        for o in omega {
            assert!((o - p.hover_rotor_speed()).abs() < 1e-9);
            assert!((o - 247.0).abs() < 1.0, "{o}");
        }
        assert!(residual_speed(&omega).abs() < 1e-9);
    }
}
