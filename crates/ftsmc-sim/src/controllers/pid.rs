//! `pid`: the PX4 multicopter cascade (`ftsmc_core::pid`); reads `[pid]`.

use ftsmc_core::pid::{PidController, PidGains};

use super::{BoxedController, BuildContext, Declaration, GainSection, InvalidGain, NominalVehicle};

/// `[pid]`: PX4's default gains rescaled to the scenario's nominal `[plant]`
/// and rotor limit ([`PidGains::for_vehicle_with_max_thrust`]); keys the
/// table gives replace them one by one.
impl GainSection for PidGains {
    const KEY: &'static str = "pid";
    const CORE_ARRAYS: &'static [(&'static str, usize)] = &[
        ("position_p", 3),
        ("velocity_p", 3),
        ("velocity_i", 3),
        ("velocity_d", 3),
        ("attitude_p", 3),
        ("max_rate", 3),
        ("rate_p", 3),
        ("rate_i", 3),
        ("rate_d", 3),
        ("rate_ff", 3),
        ("rate_integral_limit", 3),
    ];

    /// The paper vehicle's: [`GainSection::defaults_for`] the default
    /// `[plant]` with unlimited rotors.
    fn defaults() -> Self {
        Self::defaults_for(&NominalVehicle::default())
    }

    fn defaults_for(vehicle: &NominalVehicle) -> Self {
        // No private thrust cap: on limited rotors PX4's MPC_THR_MAX = 1.0 of
        // the rotors' thrust (the "px4" mixer lowers the collective thrust to
        // keep roll/pitch); on unlimited rotors (the paper plant, where the
        // sliding-mode controllers are not limited either) 10 m g, so it
        // never binds there.
        Self {
            thrust_max: vehicle.thrust_cap(0.0, 10.0),
            ..Self::for_vehicle_with_max_thrust(&vehicle.plant, vehicle.max_thrust)
        }
    }

    fn check(&self) -> Result<(), InvalidGain> {
        PidGains::check(self).map_err(|e| InvalidGain::at("", e))
    }
}

/// `pid`: P position → PID velocity → thrust and attitude (tilt limit,
/// thrust priority) → P attitude quaternion error → PID body rates.
pub struct Pid;

impl Declaration for Pid {
    const NAME: &'static str = "pid";
    const LABEL: &'static str = "PID (PX4 cascade)";
    const DESCRIPTION: &'static str =
        "PX4-style cascade: P position, PID velocity, P attitude (quaternion), PID body rates; PX4 gains rescaled";
    type Section = PidGains;

    fn build(gains: &Self::Section, ctx: &BuildContext) -> Result<BoxedController, String> {
        Ok(Box::new(PidController::new(ctx.plant, *gains).map_err(|e| e.to_string())?))
    }
}
