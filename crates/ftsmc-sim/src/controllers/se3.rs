//! `se3`: the geometric controller of Lee, Leok & McClamroch 2010
//! (`ftsmc_core::se3`); reads `[se3]`.

use ftsmc_core::se3::{Se3Controller, Se3Gains};

use ftsmc_core::lanes::Real;
use ftsmc_core::law::GainError;
use ftsmc_core::model::QuadrotorParams;

use super::generic::{FullState, FullStateGains};
use super::{GainSection, InvalidGain, NominalVehicle};

/// `[se3]`: gains placed on the scenario's nominal `[plant]`
/// ([`Se3Gains::for_vehicle`]); keys the table gives replace them one by one.
impl GainSection for Se3Gains {
    const KEY: &'static str = "se3";
    const CORE_ARRAYS: &'static [(&'static str, usize)] =
        &[("position", 3), ("velocity", 3), ("attitude", 3), ("angular_rate", 3)];
    const LIMITS: &'static [&'static str] = &["max_demanded_tilt", "min_thrust", "max_thrust"];

    /// The paper vehicle's: [`GainSection::defaults_for`] the default
    /// `[plant]` with unlimited rotors.
    fn defaults() -> Self {
        Self::defaults_for(&NominalVehicle::default())
    }

    fn defaults_for(vehicle: &NominalVehicle) -> Self {
        // No private thrust cap: the rotors' whole thrust when they are
        // limited (the "px4" mixer keeps roll/pitch by lowering the
        // collective thrust); 10 m g on unlimited rotors (never binds).
        Self { max_thrust: vehicle.thrust_cap(0.0, 10.0), ..Self::for_vehicle(&vehicle.plant) }
    }

    fn check(&self) -> Result<(), InvalidGain> {
        Se3Gains::check(self).map_err(|e| InvalidGain::at("", e))
    }
}

/// `se3`: force from position/velocity errors, rotation from the force
/// direction and heading, moment from `e_R`, `e_Ω` and `Ω × JΩ`.
pub type Se3 = FullState<Se3Gains>;

impl FullStateGains for Se3Gains {
    const NAME: &'static str = "se3";
    const LABEL: &'static str = "SE(3) (Lee et al. 2010)";
    const DESCRIPTION: &'static str =
        "geometric tracking control on SE(3) (Lee, Leok & McClamroch 2010), gains by pole placement on the vehicle";
    type On<R: Real> = Se3Controller<R>;

    fn build<R: Real>(plant: QuadrotorParams, gains: Self) -> Result<Se3Controller<R>, GainError> {
        Se3Controller::splat(plant, gains)
    }
}

/// What `ftsmc tune` searches for `se3`: factors on k_x, k_v (horizontal and
/// vertical) and k_R, k_Ω (roll-pitch and yaw). The thrust and tilt limits
/// are not tuned.
pub fn tune_parameters() -> Vec<super::tune_param::TuneParam> {
    use super::tune_param::{scale, TuneParam, HORIZONTAL, VERTICAL};
    vec![
        TuneParam::factor("kx_xy", "factor on k_x of x, y", 0.1, 10.0, |t, k| {
            scale(&mut t.gains.se3.position, HORIZONTAL, k)
        }),
        TuneParam::factor("kx_z", "factor on k_x of z", 0.1, 10.0, |t, k| {
            scale(&mut t.gains.se3.position, VERTICAL, k)
        }),
        TuneParam::factor("kv_xy", "factor on k_v of x, y", 0.1, 10.0, |t, k| {
            scale(&mut t.gains.se3.velocity, HORIZONTAL, k)
        }),
        TuneParam::factor("kv_z", "factor on k_v of z", 0.1, 10.0, |t, k| {
            scale(&mut t.gains.se3.velocity, VERTICAL, k)
        }),
        TuneParam::factor("kr_roll_pitch", "factor on k_R of roll, pitch", 0.1, 10.0, |t, k| {
            scale(&mut t.gains.se3.attitude, HORIZONTAL, k)
        }),
        TuneParam::factor("kr_yaw", "factor on k_R of yaw", 0.1, 10.0, |t, k| {
            scale(&mut t.gains.se3.attitude, VERTICAL, k)
        }),
        TuneParam::factor("komega_roll_pitch", "factor on k_Ω of roll, pitch", 0.1, 10.0, |t, k| {
            scale(&mut t.gains.se3.angular_rate, HORIZONTAL, k)
        }),
        TuneParam::factor("komega_yaw", "factor on k_Ω of yaw", 0.1, 10.0, |t, k| {
            scale(&mut t.gains.se3.angular_rate, VERTICAL, k)
        }),
    ]
}
