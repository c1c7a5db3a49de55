//! Vehicle presets (`[vehicle] preset = "…"`): named real vehicles whose
//! nominal model (`[plant]`), true vehicle (`[vehicle]`) and rotors and
//! motors (`[actuators]`) come from a sourced file in `vehicles/` (every
//! value cites its source there; docs/vehicles.md has the table).
//!
//! A preset acts as a layer just below the file that names it: it sets
//! every key it has in those three sections unless that file (or a file
//! extending it) sets the key too. A base file's values are replaced, so a
//! file that extends a Hummingbird scenario and names `crazyflie-2` flies a
//! Crazyflie, controllers' model included (the resolver applies it,
//! [`crate::scenario::resolve`]; `--set vehicle.preset=…` is such a file).

use serde::{Deserialize, Serialize};

/// A named vehicle (`[vehicle] preset`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
pub enum VehiclePreset {
    /// AscTec Hummingbird, RotorS's identified set (`vehicles/hummingbird.toml`).
    #[serde(rename = "hummingbird")]
    Hummingbird,
    /// Crazyflie 2.0, RotorPy's set (Förster 2015; `vehicles/crazyflie-2.toml`).
    #[serde(rename = "crazyflie-2")]
    Crazyflie2,
    /// Crazyflie 2.1 with the 2.1+ propellers, Bitcraze's firmware constants
    /// and Gazebo model (`vehicles/crazyflie-2.1.toml`).
    #[serde(rename = "crazyflie-2.1")]
    Crazyflie21,
    /// PX4's reference X500, PX4's Gazebo model (`vehicles/px4-x500.toml`).
    #[serde(rename = "px4-x500")]
    Px4X500,
    /// UZH RPG's Agilicious 5-inch racer, Flightmare's identified set
    /// (Foehn et al. 2022; `vehicles/agilicious.toml`).
    #[serde(rename = "agilicious")]
    Agilicious,
}

/// The sections a preset fills.
pub const PRESET_SECTIONS: [&str; 3] = ["plant", "vehicle", "actuators"];

/// The `[vehicle]` keys only the rigid body flies: a preset leaves them out
/// when a file sets `model = "paper"`.
pub const RIGID_BODY_ONLY_KEYS: [&str; 7] = [
    "configuration",
    "rotor_positions",
    "spin",
    "parasitic_drag",
    "rotor_drag_xy",
    "rotor_drag_z",
    "translational_lift",
];

impl VehiclePreset {
    /// Every preset, in the order `ftsmc list` shows them.
    pub const ALL: [VehiclePreset; 5] = [
        VehiclePreset::Hummingbird,
        VehiclePreset::Crazyflie2,
        VehiclePreset::Crazyflie21,
        VehiclePreset::Px4X500,
        VehiclePreset::Agilicious,
    ];

    /// The name a scenario file writes.
    pub fn name(self) -> &'static str {
        match self {
            VehiclePreset::Hummingbird => "hummingbird",
            VehiclePreset::Crazyflie2 => "crazyflie-2",
            VehiclePreset::Crazyflie21 => "crazyflie-2.1",
            VehiclePreset::Px4X500 => "px4-x500",
            VehiclePreset::Agilicious => "agilicious",
        }
    }

    /// The preset by its name.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|p| p.name() == name)
    }

    /// Every preset's name, comma-separated (for messages).
    pub fn names_joined() -> String {
        Self::ALL.map(Self::name).join(", ")
    }

    /// The preset's file, as shipped in `vehicles/`.
    pub fn text(self) -> &'static str {
        match self {
            VehiclePreset::Hummingbird => include_str!("../../../../vehicles/hummingbird.toml"),
            VehiclePreset::Crazyflie2 => include_str!("../../../../vehicles/crazyflie-2.toml"),
            VehiclePreset::Crazyflie21 => include_str!("../../../../vehicles/crazyflie-2.1.toml"),
            VehiclePreset::Px4X500 => include_str!("../../../../vehicles/px4-x500.toml"),
            VehiclePreset::Agilicious => include_str!("../../../../vehicles/agilicious.toml"),
        }
    }

    /// The preset's file as a table: `description` and the
    /// [`PRESET_SECTIONS`] (the built-in files parse; a test checks it).
    pub fn table(self) -> toml::Table {
        toml::from_str(self.text()).expect("built-in vehicle preset parses")
    }

    /// One line about the vehicle (its file's `description`).
    pub fn description(self) -> String {
        self.table().get("description").and_then(|d| d.as_str()).unwrap_or_default().to_string()
    }
}
