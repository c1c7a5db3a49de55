//! The vehicle a log is identified against or validated on: a preset name
//! (`crazyflie-2.1`, …) or a scenario/vehicle file, read by ftsmc's own
//! scenario loader and flown as its rigid body with its actuators.
//!
//! A log's motor commands `u ∈ [0, 1]` drive the rotors as speed commands
//! `ω_cmd = u ω_max` (`[actuators] max_rotor_speed`) through the motor lag:
//! ftsmc's motors take speeds, and a speed proportional to the command is
//! the map under which its `T = k_f ω²` is a thrust quadratic in the
//! command, the form Förster (2015) measured on the Crazyflie's PWM.

use std::path::Path;

use ftsmc_sim::actuators::ActuatorParams;
use ftsmc_sim::scenario::Scenario;
use ftsmc_sim::vehicle::{RigidBodyParams, VehicleModel, VehiclePreset};

use crate::error::IdentError;

/// A vehicle ready to fly logged commands.
#[derive(Clone, Debug, PartialEq)]
pub struct Vehicle {
    /// The preset name or the file, as given.
    pub name: String,
    /// The preset, when `name` is one.
    pub preset: Option<VehiclePreset>,
    /// The file, when `name` is one.
    pub file: Option<String>,
    /// The rigid body (mass, inertia, rotor layout, coefficients, drag).
    pub body: RigidBodyParams,
    /// Rotor limits and lag.
    pub actuators: ActuatorParams,
}

impl Vehicle {
    /// A preset by name, or a scenario file (its `[vehicle]`, `[plant]` and
    /// `[actuators]`, `extends` and presets resolved). The truth model must
    /// be the rigid body and `max_rotor_speed` finite (the command map).
    pub fn load(spec: &str) -> Result<Self, IdentError> {
        let err = |message: String| IdentError::Vehicle { vehicle: spec.to_string(), message };
        let (scenario, preset, file) = if let Some(preset) = VehiclePreset::from_name(spec) {
            let text = format!("name = \"{spec}\"\nduration = 1.0\n[vehicle]\npreset = \"{spec}\"\n");
            (Scenario::from_toml_str(&text, spec).map_err(|e| err(e.to_string()))?, Some(preset), None)
        } else if Path::new(spec).is_file() {
            let s = Scenario::from_file(Path::new(spec)).map_err(|e| err(e.to_string()))?;
            (s, None, Some(spec.to_string()))
        } else {
            return Err(err(format!("neither a vehicle preset (known: {}) nor a file", VehiclePreset::names_joined())));
        };
        if scenario.vehicle.model != VehicleModel::RigidBody {
            return Err(err(
                "its `[vehicle] model` is not \"rigid-body\" (identification and validation fly the rigid body)".into(),
            ));
        }
        let actuators = scenario.actuators.unwrap_or_default();
        if !actuators.max_rotor_speed.is_finite() {
            return Err(err(
                "`[actuators] max_rotor_speed` is not finite: a log's 0–1 commands map to rotor speeds through it"
                    .into(),
            ));
        }
        let preset = preset.or(scenario.vehicle.preset);
        Ok(Vehicle { name: spec.to_string(), preset, file, body: scenario.rigid_body_params(), actuators })
    }

    /// `ω_max`, rad/s.
    pub fn max_rotor_speed(&self) -> f64 {
        self.actuators.max_rotor_speed
    }

    /// The motor time constant (spin-up), s.
    pub fn time_constant(&self) -> f64 {
        self.actuators.time_constant_up
    }
}
