//! Can the vehicle fly it? By differential flatness (Mellinger and Kumar
//! 2011, §III) the flat output fixes the thrust, attitude and body rates:
//!
//! ```text
//! f = m (a + g e₃),  T = |f|,  z_B = f / T,  tilt = acos(z_B · e₃)
//! x_C = (cos ψ, sin ψ, 0),  y_B = z_B × x_C / |z_B × x_C|,  x_B = y_B × z_B
//! h_ω = (m / T) (j − (z_B · j) z_B),  p = −h_ω · y_B,  q = h_ω · x_B,  r = ψ̇ z_B · e₃
//! ```
//!
//! (drag and the rotors' inertia are left out: a necessary condition, not a
//! sufficient one — the controller needs headroom beyond it.) The check
//! samples the trajectory every [`STEP`] seconds from its start to its end
//! or the end of the run, whichever comes first, and reports the first
//! sample where thrust, tilt or body rate exceeds its limit.

use ftsmc_core::math::{acos, cos, cross, dot, norm, sin, sqrt};

use super::Trajectory;
use crate::text::show;

/// Grid step of the check, s.
pub const STEP: f64 = 0.01;
/// Largest time stretch `time_scale = "fit"` tries.
pub const MAX_STRETCH: f64 = 1000.0;

/// The vehicle's limits the check compares against.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VehicleLimits {
    /// Mass, kg.
    pub mass: f64,
    /// Gravity, m/s².
    pub gravity: f64,
    /// Largest collective thrust, N (`4 k_f ω_max²`; None: unlimited rotors).
    pub max_thrust: Option<f64>,
    /// Largest tilt, rad.
    pub max_tilt: f64,
    /// Largest roll/pitch body rate `√(p² + q²)`, rad/s (None: not checked).
    pub max_body_rate: Option<f64>,
}

/// Thrust, tilt and body rates the trajectory needs at one instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Required {
    /// Collective thrust T, N.
    pub thrust: f64,
    /// Tilt of the thrust axis from vertical, rad.
    pub tilt: f64,
    /// Body rates `[p, q, r]`, rad/s.
    pub body_rates: [f64; 3],
}

/// Thrust, tilt and body rates at `t` (s) for a vehicle of `mass` (kg) under `gravity` (m/s²).
pub fn required(trajectory: &Trajectory, t: f64, mass: f64, gravity: f64) -> Required {
    let s = trajectory.sample(t);
    let f = [mass * s.acc[0], mass * s.acc[1], mass * (s.acc[2] + gravity)];
    let thrust = norm(&f);
    if thrust.is_nan() || thrust <= 0.0 {
        return Required { thrust, tilt: core::f64::consts::PI, body_rates: [f64::INFINITY; 3] };
    }
    let z_b = f.map(|v| v / thrust);
    let tilt = acos(z_b[2].clamp(-1.0, 1.0));
    let x_c = [cos(s.yaw), sin(s.yaw), 0.0];
    let y = cross(&z_b, &x_c);
    let ny = norm(&y);
    let y_b = if ny > 1e-12 { y.map(|v| v / ny) } else { [0.0, 1.0, 0.0] };
    let x_b = cross(&y_b, &z_b);
    let zj = dot(&z_b, &s.jerk);
    let h = [0, 1, 2].map(|i| mass / thrust * (s.jerk[i] - zj * z_b[i]));
    let body_rates = [-dot(&h, &y_b), dot(&h, &x_b), s.yaw_rate * z_b[2]];
    Required { thrust, tilt, body_rates }
}

/// The first violation: time (s), quantity, value and limit.
#[derive(Clone, Debug, PartialEq)]
pub struct Violation {
    /// Time, s.
    pub time: f64,
    /// `"thrust"` (N), `"tilt"` (rad) or `"body rate"` (rad/s).
    pub quantity: &'static str,
    /// The required value.
    pub value: f64,
    /// The limit.
    pub limit: f64,
}

impl std::fmt::Display for Violation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let unit = match self.quantity {
            "thrust" => "N",
            "tilt" => "rad",
            _ => "rad/s",
        };
        write!(
            f,
            "needs {} {} {unit} at t = {} s (limit {} {unit})",
            self.quantity,
            show(self.value),
            show(self.time),
            show(self.limit)
        )
    }
}

/// Check `trajectory` against `limits` until `horizon` (s, the run's end).
pub fn check(trajectory: &Trajectory, limits: &VehicleLimits, horizon: f64) -> Result<(), Violation> {
    let start = trajectory.start().max(0.0);
    let end = trajectory.end().map_or(horizon, |e| e.min(horizon));
    let steps = ((end - start) / STEP).ceil().max(0.0) as u64;
    for k in 0..=steps {
        let t = (start + k as f64 * STEP).min(end);
        let r = required(trajectory, t, limits.mass, limits.gravity);
        if let Some(max) = limits.max_thrust {
            if r.thrust.is_nan() || r.thrust > max {
                return Err(Violation { time: t, quantity: "thrust", value: r.thrust, limit: max });
            }
        }
        if r.tilt.is_nan() || r.tilt > limits.max_tilt {
            return Err(Violation { time: t, quantity: "tilt", value: r.tilt, limit: limits.max_tilt });
        }
        if let Some(max) = limits.max_body_rate {
            let pq = sqrt(r.body_rates[0] * r.body_rates[0] + r.body_rates[1] * r.body_rates[1]);
            if pq.is_nan() || pq > max {
                return Err(Violation { time: t, quantity: "body rate", value: pq, limit: max });
            }
        }
    }
    Ok(())
}

/// The smallest stretch `k ∈ [1, MAX_STRETCH]` (to 1e-4 relative, by
/// bisection after doubling) with which `trajectory` passes [`check`];
/// `Err` with the violation at [`MAX_STRETCH`] when none does.
pub fn fit(trajectory: &Trajectory, limits: &VehicleLimits, horizon: f64) -> Result<f64, Violation> {
    let mut t = trajectory.clone();
    let mut at = |k: f64| {
        t.set_stretch(k);
        check(&t, limits, horizon)
    };
    if at(1.0).is_ok() {
        return Ok(1.0);
    }
    let (mut lo, mut hi) = (1.0, 2.0);
    loop {
        match at(hi) {
            Ok(()) => break,
            Err(v) if hi >= MAX_STRETCH => return Err(v),
            Err(_) => {
                lo = hi;
                hi = (hi * 2.0).min(MAX_STRETCH);
            }
        }
    }
    while hi - lo > 1e-4 * lo {
        let mid = 0.5 * (lo + hi);
        if at(mid).is_ok() {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Ok(hi)
}
