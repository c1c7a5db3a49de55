//! `pid`: the PX4 multicopter cascade (`ftsmc_core::pid`); reads `[pid]`.

use ftsmc_core::pid::{PidController, PidGains};

use ftsmc_core::lanes::Real;
use ftsmc_core::law::GainError;
use ftsmc_core::model::QuadrotorParams;

use super::generic::{FullState, FullStateGains};
use super::{GainSection, InvalidGain, NominalVehicle};

/// `[pid]`: PX4's default gains rescaled to the scenario's nominal `[plant]`
/// and rotor limit ([`PidGains::for_vehicle_on`]); keys the
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
    const LIMITS: &'static [&'static str] = &[
        "max_velocity_xy",
        "max_velocity_up",
        "max_velocity_down",
        "max_demanded_tilt",
        "hover_thrust",
        "thrust_min",
        "thrust_max",
        "thrust_xy_margin",
        "max_rate",
        "rate_integral_limit",
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
            ..Self::for_vehicle_on(&vehicle.plant, vehicle.max_thrust, &vehicle.geometry)
        }
    }

    fn check(&self) -> Result<(), InvalidGain> {
        PidGains::check(self).map_err(|e| InvalidGain::at("", e))
    }
}

/// `pid`: P position → PID velocity → thrust and attitude (tilt limit,
/// thrust priority) → P attitude quaternion error → PID body rates.
pub type Pid = FullState<PidGains>;

impl FullStateGains for PidGains {
    const NAME: &'static str = "pid";
    const LABEL: &'static str = "PID (PX4 cascade)";
    const DESCRIPTION: &'static str =
        "PX4-style cascade: P position, PID velocity, P attitude (quaternion), PID body rates; PX4 gains rescaled";
    type On<R: Real> = PidController<R>;

    fn build<R: Real>(plant: QuadrotorParams, gains: Self) -> Result<PidController<R>, GainError> {
        PidController::splat(plant, gains)
    }
}

/// What `ftsmc tune` searches for `pid`: factors on PX4's gains, per loop
/// and per horizontal/vertical (position and velocity loops) or roll-pitch/yaw
/// (attitude and rate loops) group. The limits (velocities, tilt, thrust) are
/// not tuned: they are the vehicle's, not the controller's.
pub fn tune_parameters() -> Vec<super::tune_param::TuneParam> {
    use super::tune_param::{scale, TuneParam, HORIZONTAL, VERTICAL};
    vec![
        TuneParam::factor("position_p_xy", "factor on MPC_XY_P (position_p x, y)", 0.1, 10.0, |t, k| {
            scale(&mut t.gains.pid.position_p, HORIZONTAL, k)
        }),
        TuneParam::factor("position_p_z", "factor on MPC_Z_P (position_p z)", 0.1, 10.0, |t, k| {
            scale(&mut t.gains.pid.position_p, VERTICAL, k)
        }),
        TuneParam::factor("velocity_p_xy", "factor on MPC_XY_VEL_P_ACC", 0.1, 10.0, |t, k| {
            scale(&mut t.gains.pid.velocity_p, HORIZONTAL, k)
        }),
        TuneParam::factor("velocity_p_z", "factor on MPC_Z_VEL_P_ACC", 0.1, 10.0, |t, k| {
            scale(&mut t.gains.pid.velocity_p, VERTICAL, k)
        }),
        TuneParam::factor("velocity_i_xy", "factor on MPC_XY_VEL_I_ACC", 0.01, 100.0, |t, k| {
            scale(&mut t.gains.pid.velocity_i, HORIZONTAL, k)
        }),
        TuneParam::factor("velocity_i_z", "factor on MPC_Z_VEL_I_ACC", 0.01, 100.0, |t, k| {
            scale(&mut t.gains.pid.velocity_i, VERTICAL, k)
        }),
        TuneParam::factor("velocity_d_xy", "factor on MPC_XY_VEL_D_ACC", 0.01, 100.0, |t, k| {
            scale(&mut t.gains.pid.velocity_d, HORIZONTAL, k)
        }),
        TuneParam::factor("attitude_p_roll_pitch", "factor on MC_ROLL_P, MC_PITCH_P", 0.1, 10.0, |t, k| {
            scale(&mut t.gains.pid.attitude_p, HORIZONTAL, k)
        }),
        TuneParam::factor("attitude_p_yaw", "factor on MC_YAW_P", 0.1, 10.0, |t, k| {
            scale(&mut t.gains.pid.attitude_p, VERTICAL, k)
        }),
        TuneParam::factor("rate_p_roll_pitch", "factor on MC_ROLLRATE_P, MC_PITCHRATE_P", 0.1, 10.0, |t, k| {
            scale(&mut t.gains.pid.rate_p, HORIZONTAL, k)
        }),
        TuneParam::factor("rate_p_yaw", "factor on MC_YAWRATE_P", 0.1, 10.0, |t, k| {
            scale(&mut t.gains.pid.rate_p, VERTICAL, k)
        }),
        TuneParam::factor("rate_i_roll_pitch", "factor on MC_ROLLRATE_I, MC_PITCHRATE_I", 0.01, 100.0, |t, k| {
            scale(&mut t.gains.pid.rate_i, HORIZONTAL, k)
        }),
        TuneParam::factor("rate_d_roll_pitch", "factor on MC_ROLLRATE_D, MC_PITCHRATE_D", 0.01, 100.0, |t, k| {
            scale(&mut t.gains.pid.rate_d, HORIZONTAL, k)
        }),
    ]
}
