//! An optional ground plane (`[ground]`).
//!
//! Contact model: after every RK4 substep, if the vehicle's height `z` is
//! at or below `height`,
//!
//! - and it is moving down faster than `max_touchdown_speed`, the run ends
//!   with `ExitStatus::Crashed` (`crate::run`, a floor above, so not linked) (the time is interpolated
//!   linearly to the instant `z` crossed `height` inside the substep; the
//!   impact speed is the downward speed at the end of that substep);
//! - otherwise the vehicle rests: `z` is set to `height` and a downward
//!   vertical velocity `v_z` is zeroed (no bounce). That change of velocity
//!   is the normal impulse per unit mass, `Δv_n = −v_z`, and Coulomb
//!   friction takes at most `μ Δv_n` off the horizontal speed, never
//!   reversing it: `v_xy ← v_xy · max(0, 1 − μ Δv_n / |v_xy|)`. When
//!   friction holds the vehicle (the speed reaches zero) its horizontal
//!   position is also held at where the substep started, so a vehicle
//!   pushed sideways by less than `μ` times its weight on the ground does
//!   not creep. This is the velocity-level (impulse) contact with a Coulomb
//!   friction cone that Bullet's sequential-impulse solver uses (Catto,
//!   "Iterative Dynamics with Temporal Coherence", GDC 2005), the physics
//!   PyBullet runs for gym-pybullet-drones; `friction` defaults to Bullet's
//!   default coefficient 0.5 (`btCollisionObject`). Attitude and body rates
//!   are left to the dynamics.
//!
//! A flight that has been above the ground (taken off) and then rests on
//! it for longer than `max_ground_time` ends as landed
//! (`ExitStatus::Grounded`, with the time it touched down): a flight that
//! sits on the ground is not a completed flight, whatever its errors.
//!
//! A vehicle may start on the ground (`initial_state.position[2] = height`);
//! it has taken off once it is above the ground at the end of a substep.
//! A flight that never touches the ground is not changed in any bit.

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
    /// Coulomb friction coefficient μ between the vehicle and the ground
    /// (default 0.5, Bullet's default; 0: a frictionless ground).
    pub friction: f64,
    /// Longest time, s, a flight may rest on the ground after take-off
    /// before it ends as landed (default 1.0).
    pub max_ground_time: f64,
}

impl Default for GroundSettings {
    fn default() -> Self {
        Self { enabled: false, height: 0.0, max_touchdown_speed: 1.0, friction: 0.5, max_ground_time: 1.0 }
    }
}

/// What the ground did to a flight in one substep.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Contact {
    /// Hit the ground too fast: where in the substep `z` crossed the
    /// ground (`fraction ∈ [0, 1]`) and the downward speed, m/s.
    Crashed {
        /// Fraction of the substep at which `z` crossed the ground.
        fraction: f64,
        /// Downward speed at the end of the substep, m/s.
        impact_speed: f64,
    },
    /// Rested on the ground longer than `max_ground_time` after take-off.
    Grounded {
        /// When this stay on the ground began, s.
        since: f64,
    },
}

/// One flight's contact history: whether it has taken off, and since when
/// it rests on the ground.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GroundContact {
    took_off: bool,
    resting_since: Option<f64>,
}

impl GroundSettings {
    /// Reject non-finite heights, negative speeds, friction and times.
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
        if !(self.friction.is_finite() && (0.0..=10.0).contains(&self.friction)) {
            return Err(GainError { field: "friction", value: self.friction, expected: "0 <= μ <= 10" });
        }
        if !(self.max_ground_time.is_finite() && self.max_ground_time >= 0.0) {
            return Err(GainError {
                field: "max_ground_time",
                value: self.max_ground_time,
                expected: "a finite time >= 0 s",
            });
        }
        Ok(())
    }

    /// Apply the contact model ([module docs](self)) to the position `p`
    /// (m) and velocity `v` (m/s, world frame) at time `t_end` (s), the end
    /// of a substep that started at position `p_prev`. `state` is the
    /// flight's contact history. Leaves `p` and `v` untouched while the
    /// vehicle is above the ground.
    #[inline]
    pub fn contact(
        &self,
        state: &mut GroundContact,
        t_end: f64,
        p_prev: &[f64; 3],
        p: &mut [f64; 3],
        v: &mut [f64; 3],
    ) -> Option<Contact> {
        if !self.enabled {
            return None;
        }
        if p[2] > self.height {
            state.took_off = true;
            state.resting_since = None;
            return None;
        }
        if -v[2] > self.max_touchdown_speed {
            let drop = p_prev[2] - p[2];
            let fraction = if drop > 0.0 { ((p_prev[2] - self.height) / drop).clamp(0.0, 1.0) } else { 0.0 };
            return Some(Contact::Crashed { fraction, impact_speed: -v[2] });
        }
        p[2] = self.height;
        let normal = if v[2] < 0.0 { -v[2] } else { 0.0 };
        if v[2] < 0.0 {
            v[2] = 0.0;
        }
        let speed = (v[0] * v[0] + v[1] * v[1]).sqrt();
        if speed > 0.0 {
            let removed = self.friction * normal;
            if removed >= speed {
                // Held: no sliding, not even within the substep.
                v[0] = 0.0;
                v[1] = 0.0;
                p[0] = p_prev[0];
                p[1] = p_prev[1];
            } else {
                let keep = 1.0 - removed / speed;
                v[0] *= keep;
                v[1] *= keep;
            }
        }
        if state.took_off {
            let since = *state.resting_since.get_or_insert(t_end);
            if t_end - since > self.max_ground_time {
                return Some(Contact::Grounded { since });
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ground() -> GroundSettings {
        GroundSettings { enabled: true, ..GroundSettings::default() }
    }

    #[test]
    fn friction_holds_a_push_below_mu_times_the_normal_impulse_and_slows_a_larger_one() {
        let g = ground();
        let mut state = GroundContact::default();
        // Pushed 0.004 m/s sideways while the ground took 0.01 m/s downward: held.
        let (mut p, mut v) = ([1.0, 2.0, -1e-6], [0.004, 0.0, -0.01]);
        assert_eq!(g.contact(&mut state, 0.1, &[0.9999, 2.0, 0.0], &mut p, &mut v), None);
        assert_eq!((p, v), ([0.9999, 2.0, 0.0], [0.0, 0.0, 0.0]));
        // Sliding at 1 m/s: loses μ · 0.01 = 0.005 m/s of it, direction kept.
        let (mut p, mut v) = ([1.0, 2.0, 0.0], [0.6, 0.8, -0.01]);
        g.contact(&mut state, 0.2, &[1.0, 2.0, 0.0], &mut p, &mut v);
        assert!((v[0] - 0.6 * 0.995).abs() < 1e-15 && (v[1] - 0.8 * 0.995).abs() < 1e-15, "{v:?}");
        // In the air: nothing changes.
        let (mut p, mut v) = ([1.0, 2.0, 0.5], [3.0, 0.0, -0.5]);
        assert_eq!(g.contact(&mut state, 0.3, &[1.0, 2.0, 0.6], &mut p, &mut v), None);
        assert_eq!((p, v), ([1.0, 2.0, 0.5], [3.0, 0.0, -0.5]));
    }

    #[test]
    fn resting_longer_than_max_ground_time_after_take_off_ends_the_flight() {
        let g = ground();
        let mut state = GroundContact::default();
        let rest = |state: &mut GroundContact, t: f64| {
            let (mut p, mut v) = ([0.0; 3], [0.0; 3]);
            g.contact(state, t, &[0.0; 3], &mut p, &mut v)
        };
        // On the ground before take-off: never grounded.
        assert_eq!(rest(&mut state, 5.0), None);
        let (mut p, mut v) = ([0.0, 0.0, 0.1], [0.0; 3]);
        g.contact(&mut state, 6.0, &[0.0; 3], &mut p, &mut v);
        assert_eq!(rest(&mut state, 7.0), None);
        assert_eq!(rest(&mut state, 8.0), None);
        assert_eq!(rest(&mut state, 8.01), Some(Contact::Grounded { since: 7.0 }));
    }
}
