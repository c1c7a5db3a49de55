//! `[vehicle]`: which truth model flies and every parameter of the true
//! vehicle, one key set for both truth models (docs/scenarios.md, "The true
//! vehicle").
//!
//! The controllers' model is `[plant]`; the true vehicle is `[plant]` unless
//! a key of `[vehicle]` says otherwise. Every true-parameter key is optional
//! and means one thing on both models:
//!
//! | key | unit | paper Eq. 1 | rigid body |
//! |---|---|---|---|
//! | `mass`, `gravity` | kg, m/s² | m, g | m, g |
//! | `inertia` | kg·m² | `diag(I1, I2, I3)` (a matrix must be diagonal) | J (diagonal `[Jxx, Jyy, Jzz]` or 3×3) |
//! | `rotor_inertia` | kg·m² | J_r | J_r |
//! | `thrust_coefficient` | N·s²/rad² | b | k_f |
//! | `moment_coefficient` | N·m·s²/rad² | d | k_m |
//! | `arm_length` | m | l | l |
//! | `drag_translational`, `drag_rotational` | N·s/m, N·m·s²/rad² | K_f1, K_f2 | — (an error) |
//! | `configuration`, `rotor_positions`, `spin` | see [`RigidBodyParams`] | — (an error) | the rotor layout (`rotor_positions`: any planar one) |
//! | `parasitic_drag`, `rotor_drag_xy`, `rotor_drag_z`, `translational_lift` | see [`RigidBodyParams`] | — (an error) | RotorPy-style aerodynamics |
//!
//! A key not given takes `[plant]`'s value (`thrust_coefficient` ← `plant.lift_coefficient`,
//! `moment_coefficient` ← `plant.yaw_drag_coefficient`); the rigid-body-only
//! keys default to the paper vehicle's layout (`plus`, [`super::rigid_body::PAPER_SPIN`])
//! and no aerodynamics. A key that only the other model can fly is refused
//! ([`VehicleSettings::check_model_keys`]), never ignored.

use ftsmc_core::law::GainError;
use ftsmc_core::model::QuadrotorParams;
use serde::{Deserialize, Serialize};

use super::rigid_body::{Configuration, RigidBodyParams, Spin};
use crate::text::{exact_array, show};

/// Which truth model flies (`[vehicle] model`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum VehicleModel {
    /// Paper Eq. 1 (default).
    #[default]
    Paper,
    /// Newton–Euler rigid body ([`super::rigid_body`]).
    RigidBody,
}

impl VehicleModel {
    /// The name a scenario file writes (`paper`, `rigid-body`).
    pub fn name(self) -> &'static str {
        match self {
            VehicleModel::Paper => "paper",
            VehicleModel::RigidBody => "rigid-body",
        }
    }
}

/// The true inertia (`[vehicle] inertia`), kg·m²: the principal moments
/// `[Jxx, Jyy, Jzz]` (a diagonal matrix) or the full matrix J about the
/// centre of mass in body axes.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(untagged, expecting = "a diagonal `[Jxx, Jyy, Jzz]` or a 3x3 matrix `[[..], [..], [..]]` of numbers, kg m^2")]
pub enum Inertia {
    /// `[Jxx, Jyy, Jzz]`: `J = diag(Jxx, Jyy, Jzz)` (paper Eq. 1's `I1, I2, I3`).
    Diagonal([f64; 3]),
    /// The full matrix J (the rigid body's; on paper Eq. 1 it must be diagonal).
    Matrix([[f64; 3]; 3]),
}

impl Inertia {
    /// The diagonal `[J00, J11, J22]`, kg·m².
    pub fn diagonal(&self) -> [f64; 3] {
        match self {
            Inertia::Diagonal(d) => *d,
            Inertia::Matrix(m) => [m[0][0], m[1][1], m[2][2]],
        }
    }

    /// The matrix J, kg·m².
    pub fn matrix(&self) -> [[f64; 3]; 3] {
        match self {
            Inertia::Diagonal(d) => [[d[0], 0.0, 0.0], [0.0, d[1], 0.0], [0.0, 0.0, d[2]]],
            Inertia::Matrix(m) => *m,
        }
    }

    /// The first non-zero product of inertia `(row, column, value)`, if any.
    fn off_diagonal(&self) -> Option<(usize, usize, f64)> {
        let m = self.matrix();
        (0..3)
            .flat_map(|r| (0..3).map(move |c| (r, c)))
            .find(|&(r, c)| r != c && m[r][c] != 0.0)
            .map(|(r, c)| (r, c, m[r][c]))
    }
}

/// `[vehicle]`: the truth model and the true vehicle's parameters (module
/// docs). Every parameter is optional: `None` takes `[plant]`'s value (or,
/// for the rigid-body-only keys, the paper vehicle's layout and no
/// aerodynamics).
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct VehicleSettings {
    /// The named vehicle whose sourced parameters fill every `[plant]`,
    /// `[vehicle]` and `[actuators]` key no file sets
    /// ([`super::presets::VehiclePreset`]; default none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub preset: Option<super::presets::VehiclePreset>,
    /// Truth model (default `paper`).
    #[serde(default)]
    pub model: VehicleModel,
    /// True mass m, kg.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mass: Option<f64>,
    /// Gravitational acceleration g, m/s².
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gravity: Option<f64>,
    /// True inertia, kg·m² ([`Inertia`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inertia: Option<Inertia>,
    /// Rotor (plus motor rotor) inertia J_r about its spin axis, kg·m².
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rotor_inertia: Option<f64>,
    /// Thrust coefficient (per rotor `T = k_f ω²`; paper Eq. 2's b), N·s²/rad².
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thrust_coefficient: Option<f64>,
    /// Drag-torque coefficient (per rotor `|Q| = k_m ω²`; paper Eq. 2's d), N·m·s²/rad².
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub moment_coefficient: Option<f64>,
    /// Distance l from the centre of mass to each rotor hub, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub arm_length: Option<f64>,
    /// Paper Eq. 1 only: translational drag `[K_f1x, K_f1y, K_f1z]`, N·s/m.
    #[serde(default, with = "exact_array::option", skip_serializing_if = "Option::is_none")]
    pub drag_translational: Option<[f64; 3]>,
    /// Paper Eq. 1 only: rotational drag `[K_f2x, K_f2y, K_f2z]`, N·m·s²/rad².
    #[serde(default, with = "exact_array::option", skip_serializing_if = "Option::is_none")]
    pub drag_rotational: Option<[f64; 3]>,
    /// Rigid body only: rotor layout ([`Configuration`], default `plus`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub configuration: Option<Configuration>,
    /// Rigid body only: hub `(x, y)` of rotors 1..4 in body axes (x
    /// forward, y left), m, for any planar layout; implies (and needs)
    /// `configuration = "custom"`.
    #[serde(default, deserialize_with = "four_positions", skip_serializing_if = "Option::is_none")]
    pub rotor_positions: Option<[[f64; 2]; 4]>,
    /// Rigid body only: spin of rotors 1..4 (default `["cw", "ccw", "cw", "ccw"]`).
    #[serde(default, with = "exact_array::option", skip_serializing_if = "Option::is_none")]
    pub spin: Option<[Spin; 4]>,
    /// Rigid body only: parasitic drag `[c_Dx, c_Dy, c_Dz]`, N·s²/m² (default 0).
    #[serde(default, with = "exact_array::option", skip_serializing_if = "Option::is_none")]
    pub parasitic_drag: Option<[f64; 3]>,
    /// Rigid body only: in-plane rotor drag k_d, N·s²/(m·rad) (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rotor_drag_xy: Option<f64>,
    /// Rigid body only: axial rotor drag (induced inflow) k_z, N·s²/(m·rad) (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rotor_drag_z: Option<f64>,
    /// Rigid body only: translational lift k_h, N·s²/m² (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub translational_lift: Option<f64>,
}

/// The keys of `[vehicle]` that describe the true vehicle (all but `model`).
pub const TRUE_VEHICLE_KEYS: [&str; 16] = [
    "mass",
    "gravity",
    "inertia",
    "rotor_inertia",
    "thrust_coefficient",
    "moment_coefficient",
    "arm_length",
    "drag_translational",
    "drag_rotational",
    "configuration",
    "rotor_positions",
    "spin",
    "parasitic_drag",
    "rotor_drag_xy",
    "rotor_drag_z",
    "translational_lift",
];

/// The `[vehicle]` key of a [`QuadrotorParams`] field (`lift_coefficient` →
/// `thrust_coefficient`, `yaw_drag_coefficient` → `moment_coefficient`; the
/// others keep their names). `field` may carry an index (`inertia[0]`).
pub fn vehicle_key_of_plant_field(field: &str) -> String {
    let (head, tail) = field.split_at(field.find('[').unwrap_or(field.len()));
    let head = match head {
        "lift_coefficient" => "thrust_coefficient",
        "yaw_drag_coefficient" => "moment_coefficient",
        other => other,
    };
    format!("{head}{tail}")
}

/// The `[plant]` field a `[vehicle]` key falls back to (the inverse of
/// [`vehicle_key_of_plant_field`]); `None` for the rigid-body-only keys.
pub fn plant_field_of_vehicle_key(key: &str) -> Option<String> {
    let (head, tail) = key.split_at(key.find('[').unwrap_or(key.len()));
    let head = match head {
        "thrust_coefficient" => "lift_coefficient",
        "moment_coefficient" => "yaw_drag_coefficient",
        "mass" | "gravity" | "inertia" | "rotor_inertia" | "arm_length" | "drag_translational" | "drag_rotational" => {
            head
        }
        _ => return None,
    };
    Some(format!("{head}{tail}"))
}

impl VehicleSettings {
    /// True when nothing is set (for `skip_serializing_if`).
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }

    /// The true-vehicle keys given (in [`TRUE_VEHICLE_KEYS`] order).
    pub fn given_keys(&self) -> Vec<&'static str> {
        let given = [
            self.mass.is_some(),
            self.gravity.is_some(),
            self.inertia.is_some(),
            self.rotor_inertia.is_some(),
            self.thrust_coefficient.is_some(),
            self.moment_coefficient.is_some(),
            self.arm_length.is_some(),
            self.drag_translational.is_some(),
            self.drag_rotational.is_some(),
            self.configuration.is_some(),
            self.rotor_positions.is_some(),
            self.spin.is_some(),
            self.parasitic_drag.is_some(),
            self.rotor_drag_xy.is_some(),
            self.rotor_drag_z.is_some(),
            self.translational_lift.is_some(),
        ];
        TRUE_VEHICLE_KEYS.iter().zip(given).filter(|(_, g)| *g).map(|(k, _)| *k).collect()
    }

    /// The true vehicle in paper form (Eq. 1's parameters): `plant` with
    /// every given key of `[vehicle]` in place (the inertia's diagonal). On
    /// the rigid body this is the paper-form view of the same vehicle (mass,
    /// inertia diagonal, coefficients), its linear drags `plant`'s (unused).
    pub fn true_vehicle(&self, plant: &QuadrotorParams) -> QuadrotorParams {
        QuadrotorParams {
            mass: self.mass.unwrap_or(plant.mass),
            gravity: self.gravity.unwrap_or(plant.gravity),
            inertia: self.inertia.map_or(plant.inertia, |i| i.diagonal()),
            rotor_inertia: self.rotor_inertia.unwrap_or(plant.rotor_inertia),
            drag_translational: self.drag_translational.unwrap_or(plant.drag_translational),
            drag_rotational: self.drag_rotational.unwrap_or(plant.drag_rotational),
            lift_coefficient: self.thrust_coefficient.unwrap_or(plant.lift_coefficient),
            yaw_drag_coefficient: self.moment_coefficient.unwrap_or(plant.yaw_drag_coefficient),
            arm_length: self.arm_length.unwrap_or(plant.arm_length),
        }
    }

    /// The rigid-body parameters of the true vehicle:
    /// [`RigidBodyParams::from_paper`] of [`VehicleSettings::true_vehicle`],
    /// with the full inertia matrix and the rigid-body-only keys given.
    pub fn rigid_body(&self, plant: &QuadrotorParams) -> RigidBodyParams {
        let mut rb = RigidBodyParams::from_paper(&self.true_vehicle(plant));
        if let Some(i) = self.inertia {
            rb.inertia = i.matrix();
        }
        rb.configuration = self.configuration.unwrap_or(rb.configuration);
        if let Some(p) = self.rotor_positions {
            // Positions imply the custom layout; a conflicting `configuration`
            // is refused by `check_model_keys`, never ignored.
            rb.configuration = self.configuration.unwrap_or(Configuration::Custom);
            rb.custom_positions = Some(p);
        }
        rb.spin = self.spin.unwrap_or(rb.spin);
        rb.parasitic_drag = self.parasitic_drag.unwrap_or(rb.parasitic_drag);
        rb.rotor_drag_xy = self.rotor_drag_xy.unwrap_or(rb.rotor_drag_xy);
        rb.rotor_drag_z = self.rotor_drag_z.unwrap_or(rb.rotor_drag_z);
        rb.translational_lift = self.translational_lift.unwrap_or(rb.translational_lift);
        rb
    }

    /// Refuse a key the chosen model cannot fly: the linear drags of Eq. 1
    /// on the rigid body, the rigid body's layout and aerodynamics (and a
    /// non-diagonal inertia) on Eq. 1. `Err((dotted key, value, expected))`.
    pub fn check_model_keys(&self) -> Result<(), (String, String, String)> {
        let arr = |v: &[f64]| format!("[{}]", v.iter().map(|x| show(*x)).collect::<Vec<_>>().join(", "));
        let refuse = |key: &str, value: String, why: &str| {
            Err((format!("vehicle.{key}"), value, format!("no `{key}` with model = \"{}\": {why}", self.model.name())))
        };
        match self.model {
            VehicleModel::Paper => {
                const ONLY_RB: &str = "only model = \"rigid-body\" flies the rotor layout and aerodynamics (Eq. 1's drags are `drag_translational`, `drag_rotational`)";
                if let Some(c) = self.configuration {
                    return refuse("configuration", format!("{c:?}").to_lowercase(), ONLY_RB);
                }
                if let Some(p) = self.rotor_positions {
                    return refuse("rotor_positions", positions_text(&p), ONLY_RB);
                }
                if let Some(s) = self.spin {
                    return refuse("spin", format!("{s:?}").to_lowercase(), ONLY_RB);
                }
                if let Some(v) = self.parasitic_drag {
                    return refuse("parasitic_drag", arr(&v), ONLY_RB);
                }
                for (key, v) in [
                    ("rotor_drag_xy", self.rotor_drag_xy),
                    ("rotor_drag_z", self.rotor_drag_z),
                    ("translational_lift", self.translational_lift),
                ] {
                    if let Some(v) = v {
                        return refuse(key, show(v), ONLY_RB);
                    }
                }
                if let Some((r, c, v)) = self.inertia.as_ref().and_then(Inertia::off_diagonal) {
                    return Err((
                        format!("vehicle.inertia[{r}][{c}]"),
                        show(v),
                        "a diagonal inertia with model = \"paper\" (Eq. 1 takes J = diag(I1, I2, I3); only model = \"rigid-body\" flies products of inertia)".into(),
                    ));
                }
            }
            VehicleModel::RigidBody => {
                const ONLY_PAPER: &str = "Eq. 1's linear drags K_f1, K_f2 have no counterpart on the rigid body (its drag is `parasitic_drag`, `rotor_drag_xy`, `rotor_drag_z`)";
                if let Some(v) = self.drag_translational {
                    return refuse("drag_translational", arr(&v), ONLY_PAPER);
                }
                if let Some(v) = self.drag_rotational {
                    return refuse("drag_rotational", arr(&v), ONLY_PAPER);
                }
                match (self.configuration, self.rotor_positions) {
                    (Some(c), Some(_)) if c != Configuration::Custom => {
                        return Err((
                            "vehicle.configuration".into(),
                            format!("{c:?}").to_lowercase(),
                            "remove `configuration` (or set it to \"custom\") where `rotor_positions` is set (here or by the preset): the positions are the layout".into(),
                        ))
                    }
                    (Some(Configuration::Custom), None) => {
                        return Err((
                            "vehicle.rotor_positions".into(),
                            "none".into(),
                            "four hub positions [[x, y], ..] (m) with configuration = \"custom\"".into(),
                        ))
                    }
                    _ => {}
                }
            }
        }
        Ok(())
    }

    /// Range-check the true vehicle the model flies (after
    /// [`VehicleSettings::check_model_keys`]): [`QuadrotorParams::check`] of
    /// [`VehicleSettings::true_vehicle`] on Eq. 1, [`RigidBodyParams::check`] of
    /// [`VehicleSettings::rigid_body`] on the rigid body. `Err((dotted key,
    /// error))`: `vehicle.<key>` when the key is given, else the `plant.<field>`
    /// the value came from (the rigid body's range can be narrower than
    /// `[plant]`'s), else `vehicle.<key>` for a rigid-body default.
    pub fn check(&self, plant: &QuadrotorParams) -> Result<(), (String, GainError)> {
        let given = self.given_keys();
        let name = |field: &str| {
            let key = vehicle_key_of_plant_field(field);
            let head = key.split('[').next().unwrap_or(&key);
            match plant_field_of_vehicle_key(&key) {
                Some(p) if !given.contains(&head) => format!("plant.{p}"),
                _ => format!("vehicle.{key}"),
            }
        };
        let split = |full: String| match full.split_once('.') {
            Some((prefix, field)) => (prefix.to_string(), field.to_string()),
            None => (full, String::new()),
        };
        let err = |field: &'static str, e: GainError| {
            let (prefix, _) = split(name(field));
            // Keep the field as the struct names it, under the section the value came from.
            let field_name: &'static str = match prefix.as_str() {
                "plant" => plant_field_static(field),
                _ => vehicle_field_static(field),
            };
            (prefix, GainError { field: field_name, ..e })
        };
        match self.model {
            VehicleModel::Paper => self.true_vehicle(plant).check().map_err(|e| err(e.field, e)),
            VehicleModel::RigidBody => self.rigid_body(plant).check().map_err(|e| err(e.field, e)),
        }
    }
}

/// `field` (a [`QuadrotorParams`] or [`RigidBodyParams`] field, maybe
/// indexed) as the [`QuadrotorParams`] field name: a `'static` string.
fn plant_field_static(field: &'static str) -> &'static str {
    match field.split('[').next() {
        Some("thrust_coefficient") => "lift_coefficient",
        Some("moment_coefficient") => "yaw_drag_coefficient",
        // An entry of the rigid body's inertia matrix falls back to the plant's diagonal.
        Some("inertia") => match field {
            "inertia[0][0]" => "inertia[0]",
            "inertia[1][1]" => "inertia[1]",
            "inertia[2][2]" => "inertia[2]",
            other => other,
        },
        _ => field,
    }
}

/// `rotor_positions`: exactly four `[x, y]` pairs (serde's own arrays
/// would ignore extra elements silently).
fn four_positions<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<[[f64; 2]; 4]>, D::Error> {
    use serde::de::Error;
    let rows: Vec<Vec<f64>> = Deserialize::deserialize(d)?;
    if rows.len() != 4 {
        return Err(D::Error::custom(format!(
            "{} rotor positions where a quadrotor has 4 ([[x, y], ..], m)",
            rows.len()
        )));
    }
    let mut out = [[0.0; 2]; 4];
    for (i, row) in rows.iter().enumerate() {
        match row.as_slice() {
            [x, y] => out[i] = [*x, *y],
            _ => {
                return Err(D::Error::custom(format!(
                    "rotor position {i} has {} numbers where [x, y] has 2 (m, body x forward, y left; the hubs lie in the body plane)",
                    row.len()
                )))
            }
        }
    }
    Ok(Some(out))
}

/// Rotor positions as TOML shows them.
fn positions_text(p: &[[f64; 2]; 4]) -> String {
    let each: Vec<String> = p.iter().map(|[x, y]| format!("[{}, {}]", show(*x), show(*y))).collect();
    format!("[{}]", each.join(", "))
}

/// `field` as the `[vehicle]` key name: a `'static` string.
fn vehicle_field_static(field: &'static str) -> &'static str {
    match field {
        "lift_coefficient" => "thrust_coefficient",
        "yaw_drag_coefficient" => "moment_coefficient",
        other => other,
    }
}
