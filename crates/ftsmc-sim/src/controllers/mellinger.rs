//! `mellinger`: the Crazyflie firmware's Mellinger controller with its
//! power distribution (`ftsmc_core::mellinger`); reads `[mellinger]`.

use ftsmc_core::mellinger::{Mellinger as Law, MellingerGains};

use super::crazyflie_pid::pwm_map_for;
use super::{BoxedController, BuildContext, Declaration, GainSection, InvalidGain, NominalVehicle};

/// `[mellinger]`: the firmware's default gains (2025.12.1,
/// `controller_mellinger.c`), with the motor map of the scenario's vehicle
/// (hover at the firmware's own hover command `mass_thrust · mass · g` on
/// unlimited rotors).
impl GainSection for MellingerGains {
    const KEY: &'static str = "mellinger";
    const LIMITS: &'static [&'static str] = &["motors"];

    /// The paper vehicle's: [`GainSection::defaults_for`] the default
    /// `[plant]` with unlimited rotors.
    fn defaults() -> Self {
        Self::defaults_for(&NominalVehicle::default())
    }

    fn defaults_for(vehicle: &NominalVehicle) -> Self {
        let base = MellingerGains::default();
        let hover = base.mass_thrust * base.mass * vehicle.plant.gravity;
        Self { motors: pwm_map_for(vehicle, hover), ..base }
    }

    fn check(&self) -> Result<(), InvalidGain> {
        MellingerGains::check(self).map_err(|e| InvalidGain::at("", e))
    }
}

/// `mellinger`: one flight per controller (no lane form).
pub struct Mellinger;

impl Declaration for Mellinger {
    const NAME: &'static str = "mellinger";
    const LABEL: &'static str = "Mellinger (Crazyflie firmware)";
    const DESCRIPTION: &'static str =
        "the Crazyflie firmware's Mellinger controller (Mellinger & Kumar 2011) and legacy power distribution, firmware gains";
    type Section = MellingerGains;

    fn build(gains: &MellingerGains, ctx: &BuildContext) -> Result<BoxedController, String> {
        Ok(Box::new(Law::new(ctx.plant, *gains).map_err(|e| e.to_string())?))
    }
}
