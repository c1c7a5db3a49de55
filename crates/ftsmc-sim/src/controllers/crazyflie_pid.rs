//! `crazyflie-pid`: the Crazyflie firmware's PID cascade with its power
//! distribution (`ftsmc_core::crazyflie_pid`); reads `[crazyflie-pid]`.

use ftsmc_core::crazyflie_pid::{CrazyfliePid as Law, CrazyfliePidGains, PwmMap, PWM_MAX};

use super::{BoxedController, BuildContext, Declaration, GainSection, InvalidGain, NominalVehicle};

/// The map of the 16-bit motor commands to the rotor speeds of `vehicle`:
/// command 65535 is the rotors' top speed (`4 k_f ω_max²` = the vehicle's
/// largest thrust); on unlimited rotors, the top speed at which the
/// command `hover_command` hovers the nominal vehicle.
pub fn pwm_map_for(vehicle: &NominalVehicle, hover_command: f64) -> PwmMap {
    let b = vehicle.plant.lift_coefficient;
    let max_rotor_speed = match vehicle.max_thrust {
        Some(t) => (t / (4.0 * b)).sqrt(),
        None => (vehicle.plant.mass * vehicle.plant.gravity / (4.0 * b)).sqrt() * PWM_MAX / hover_command,
    };
    PwmMap { max_rotor_speed, ..PwmMap::default() }
}

/// `[crazyflie-pid]`: the firmware's default gains (2025.12.1,
/// `platform_defaults_cf2.h`), with the motor map of the scenario's
/// vehicle ([`pwm_map_for`], hover at the firmware's `thrust_base` on
/// unlimited rotors).
impl GainSection for CrazyfliePidGains {
    const KEY: &'static str = "crazyflie-pid";
    const CORE_ARRAYS: &'static [(&'static str, usize)] = &[("velocity_max", 3)];
    const LIMITS: &'static [&'static str] =
        &["thrust_min", "roll_limit", "pitch_limit", "velocity_max", "position_period", "motors"];

    /// The paper vehicle's: [`GainSection::defaults_for`] the default
    /// `[plant]` with unlimited rotors.
    fn defaults() -> Self {
        Self::defaults_for(&NominalVehicle::default())
    }

    fn defaults_for(vehicle: &NominalVehicle) -> Self {
        let base = CrazyfliePidGains::default();
        Self { motors: pwm_map_for(vehicle, base.thrust_base), ..base }
    }

    fn check(&self) -> Result<(), InvalidGain> {
        CrazyfliePidGains::check(self).map_err(|e| InvalidGain::at("", e))
    }
}

/// `crazyflie-pid`: one flight per controller (no lane form: lanes fly
/// side-by-side copies).
pub struct CrazyfliePid;

impl Declaration for CrazyfliePid {
    const NAME: &'static str = "crazyflie-pid";
    const LABEL: &'static str = "Crazyflie PID (firmware)";
    const DESCRIPTION: &'static str =
        "the Crazyflie firmware's PID cascade (position, velocity, attitude, rate) and legacy power distribution, firmware gains";
    type Section = CrazyfliePidGains;

    fn build(gains: &CrazyfliePidGains, ctx: &BuildContext) -> Result<BoxedController, String> {
        Ok(Box::new(Law::new(ctx.plant, *gains).map_err(|e| e.to_string())?))
    }
}
