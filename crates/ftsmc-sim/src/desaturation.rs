//! PX4's multicopter control allocation with airmode off (`MC_AIRMODE` = 0,
//! PX4's default): `ControlAllocationSequentialDesaturation::mixAirmodeDisabled`
//! and `mixYaw`, with the pseudo-inverse normalisation of
//! `ControlAllocationPseudoInverse::updateControlAllocationMatrixScale` and the
//! final `ControlAllocation::clipActuatorSetpoint` the `ControlAllocator`
//! module applies after every allocation (PX4-Autopilot,
//! `src/modules/control_allocator/ControlAllocation/`). Written from the
//! algorithm's description, in `f64` (PX4 computes in `f32`).
//!
//! Actuator space: PX4's motor setpoints are fractions of full thrust, so
//! rotor `i`'s setpoint is `a_i = ω_i² / ω_max²` within
//! `[ω_min² / ω_max², 1]`.
//!
//! The steps, with the mix `M` (the allocation's inverse in actuator space,
//! each column divided by its axis scale, entries below `1e-3` set to 0;
//! the scales: [`ftsmc_core::rotor_layout::px4_scales`])
//! and the command in normalised units (`c_k = u_k · scale_k`):
//!
//! 1. `a = M_roll c_roll + M_pitch c_pitch + M_thrust c_thrust` (no yaw).
//! 2. Desaturate along the thrust column, only ever **lowering** the thrust.
//! 3. Desaturate along the roll column, then along the pitch column, each
//!    on its own (so the direction of the tilting torque may turn).
//! 4. Add yaw; desaturate along the yaw column against an upper limit raised
//!    by 15 % of the range (`max + 0.15 (max − min)`), then lower the thrust
//!    again (only lowering) against the true limits: the thrust gives up to
//!    0.15 of its range to make room for yaw.
//! 5. Clip every setpoint to `[min, max]`.
//!
//! One desaturation along a vector `d` (`desaturateActuators`): the gain
//! `k = k_min + k_max` of `computeDesaturationGain` (over the saturated
//! actuators with `|d_i| >= 0.2`, `k_i = (limit − a_i)/d_i`; `k_min` the
//! smallest of 0 and the `k_i`, `k_max` the largest) is applied, then half
//! of the gain recomputed at the new point; with "only lowering" a negative
//! first gain applies nothing.

/// Columns of the mix: 0 thrust (upwards), 1 roll, 2 pitch, 3 yaw.
const THRUST: usize = 0;
const ROLL: usize = 1;
const PITCH: usize = 2;
const YAW: usize = 3;

/// PX4's sequential-desaturation allocation for one vehicle (the mix and its
/// normalisation worked out once).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SequentialDesaturation {
    /// `mix[k][i]`: column `k` (thrust, roll, pitch, yaw), actuator `i`, normalised.
    mix: [[f64; 4]; 4],
    /// Per axis, the factor from a command (N, N·m) to PX4's normalised
    /// control setpoint (1 where PX4 applies no scale).
    scale: [f64; 4],
    /// Lowest actuator setpoint `ω_min² / ω_max²`.
    min: f64,
}

/// What [`SequentialDesaturation::allocate`] made of a command.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Allocation {
    /// Actuator setpoints `a_i = ω_i² / ω_max²` after the final clip, in `[min, 1]`.
    pub setpoints: [f64; 4],
    /// `true` when some desaturation gain was nonzero or the clip moved a setpoint.
    pub changed: bool,
}

impl SequentialDesaturation {
    /// The allocation for the inverse `inverse[i][k]` of the vehicle's
    /// allocation matrix (squared rotor speeds, rad²/s², per unit of
    /// thrust N and torques N·m; rows rotors, columns thrust, roll, pitch,
    /// yaw) and the squared speed limits `w_min = ω_min²`, `w_max = ω_max²`
    /// (`w_max` finite and positive; checked by the caller).
    pub fn new(inverse: &[[f64; 4]; 4], w_min: f64, w_max: f64) -> Self {
        // The un-normalised mix in actuator space: a = inverse · u / w_max.
        let mut mix: [[f64; 4]; 4] = core::array::from_fn(|k| core::array::from_fn(|i| inverse[i][k] / w_max));
        let scale = ftsmc_core::rotor_layout::px4_scales(&mix);
        for k in 0..4 {
            for x in mix[k].iter_mut() {
                *x /= scale[k];
                if x.abs() < 1e-3 {
                    *x = 0.0;
                }
            }
        }
        Self { mix, scale, min: w_min / w_max }
    }

    /// `computeDesaturationGain`: the gain along `d` that reduces the
    /// saturation of `a` within `[min, max]` as much as one step can.
    fn gain(&self, d: &[f64; 4], a: &[f64; 4], max: f64) -> f64 {
        let (mut k_min, mut k_max) = (0.0f64, 0.0f64);
        for i in 0..4 {
            // An actuator with a weak effectiveness is not used (no large gains).
            if d[i].abs() < 0.2 {
                continue;
            }
            if a[i] < self.min {
                let k = (self.min - a[i]) / d[i];
                k_min = k_min.min(k);
                k_max = k_max.max(k);
            }
            if a[i] > max {
                let k = (max - a[i]) / d[i];
                k_min = k_min.min(k);
                k_max = k_max.max(k);
            }
        }
        k_min + k_max
    }

    /// `desaturateActuators`: one full and one half gain along `d`; with
    /// `lower_only` nothing when the first gain is negative. Returns whether
    /// a nonzero gain was applied.
    fn desaturate(&self, a: &mut [f64; 4], d: &[f64; 4], lower_only: bool, max: f64) -> bool {
        let gain = self.gain(d, a, max);
        if lower_only && gain < 0.0 {
            return false;
        }
        for i in 0..4 {
            a[i] += gain * d[i];
        }
        let half = 0.5 * self.gain(d, a, max);
        for i in 0..4 {
            a[i] += half * d[i];
        }
        gain != 0.0 || half != 0.0
    }

    /// The actuator setpoints for `u = [U1, u2, u3, u4]` (N, N·m), every
    /// component finite.
    pub fn allocate(&self, u: &[f64; 4]) -> Allocation {
        let c: [f64; 4] = core::array::from_fn(|k| u[k] * self.scale[k]);
        let m = &self.mix;
        let mut a: [f64; 4] =
            core::array::from_fn(|i| m[ROLL][i] * c[ROLL] + m[PITCH][i] * c[PITCH] + m[THRUST][i] * c[THRUST]);
        // PX4's thrust axis points down (NED): a positive gain along it lowers the thrust.
        let down = m[THRUST].map(|x| -x);
        let mut changed = self.desaturate(&mut a, &down, true, 1.0);
        changed |= self.desaturate(&mut a, &m[ROLL], false, 1.0);
        changed |= self.desaturate(&mut a, &m[PITCH], false, 1.0);
        for i in 0..4 {
            a[i] += m[YAW][i] * c[YAW];
        }
        let raised = 1.0 + (1.0 - self.min) * 0.15;
        changed |= self.desaturate(&mut a, &m[YAW], false, raised);
        changed |= self.desaturate(&mut a, &down, true, 1.0);
        let clipped = a.map(|x| x.clamp(self.min, 1.0));
        changed |= clipped != a;
        Allocation { setpoints: clipped, changed }
    }
}
