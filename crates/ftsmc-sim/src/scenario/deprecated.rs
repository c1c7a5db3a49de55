//! The old spellings of the true vehicle, `[actual_plant]` and
//! `[vehicle.rigid_body]`, moved into `[vehicle]` at load
//! ([`crate::vehicle::VehicleSettings`]) with a warning per key naming the
//! new key, so an old file flies exactly as before (docs/scenarios.md,
//! "Converting old files").
//!
//! Both old tables were complete: a key missing from them took the paper
//! vehicle's value (`QuadrotorParams::default()`, `RigidBodyParams::default()`),
//! whereas `[vehicle]` takes a missing key from `[plant]`. The conversion
//! therefore writes out every missing key whose paper value differs from
//! `[plant]`'s, and says so. Refused, with how to convert: an old spelling
//! together with a new key, and both old tables in one scenario.

use ftsmc_core::model::QuadrotorParams;

use super::Scenario;
use crate::vehicle::{Inertia, RigidBodyParams, VehicleModel, VehicleSettings};

/// The keys written in the old tables of the resolved (merged) TOML
/// table, before the typed parse reads them.
#[derive(Clone, Debug, Default)]
pub(crate) struct OldKeys {
    /// Keys of `[actual_plant]`, when the table is there.
    actual_plant: Option<Vec<String>>,
    /// Keys of `[vehicle.rigid_body]`, when the table is there.
    rigid_body: Option<Vec<String>>,
}

/// The old tables taken out of `merged` (so the typed parse never sees
/// them): `(actual_plant, vehicle.rigid_body, their key names)`.
pub(crate) fn take_old_tables(merged: &mut toml::Table) -> (Option<toml::Value>, Option<toml::Value>, OldKeys) {
    let keys = |v: Option<&toml::Value>| v.and_then(toml::Value::as_table).map(|t| t.keys().cloned().collect());
    let actual = merged.remove("actual_plant");
    let rigid = match merged.get_mut("vehicle") {
        Some(toml::Value::Table(v)) => v.remove("rigid_body"),
        _ => None,
    };
    let old = OldKeys { actual_plant: keys(actual.as_ref()), rigid_body: keys(rigid.as_ref()) };
    (actual, rigid, old)
}

/// `(dotted key, value, expected)` of a refused mix of spellings.
pub(crate) type Refusal = (String, String, String);

/// `(dotted key, value, message)` of a deprecation warning (the loader
/// adds the file that wrote the key).
pub(crate) type Note = (String, String, String);

/// A value as TOML writes it.
fn shown<T: serde::Serialize>(v: &T) -> String {
    toml::Value::try_from(v).map(|v| v.to_string()).unwrap_or_default()
}

const PAPER_FIELDS: [&str; 9] = [
    "mass",
    "gravity",
    "inertia",
    "rotor_inertia",
    "drag_translational",
    "drag_rotational",
    "lift_coefficient",
    "yaw_drag_coefficient",
    "arm_length",
];

/// Field `f` of `p` as its TOML text and its bits (for an exact comparison).
fn paper_field(p: &QuadrotorParams, f: &str) -> (String, Vec<u64>) {
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    match f {
        "mass" => (shown(&p.mass), bits(&[p.mass])),
        "gravity" => (shown(&p.gravity), bits(&[p.gravity])),
        "inertia" => (shown(&p.inertia), bits(&p.inertia)),
        "rotor_inertia" => (shown(&p.rotor_inertia), bits(&[p.rotor_inertia])),
        "drag_translational" => (shown(&p.drag_translational), bits(&p.drag_translational)),
        "drag_rotational" => (shown(&p.drag_rotational), bits(&p.drag_rotational)),
        "lift_coefficient" => (shown(&p.lift_coefficient), bits(&[p.lift_coefficient])),
        "yaw_drag_coefficient" => (shown(&p.yaw_drag_coefficient), bits(&[p.yaw_drag_coefficient])),
        _ => (shown(&p.arm_length), bits(&[p.arm_length])),
    }
}

/// Set the `[vehicle]` key of paper field `f` to `p`'s value.
fn set_from_paper(v: &mut VehicleSettings, p: &QuadrotorParams, f: &str) {
    match f {
        "mass" => v.mass = Some(p.mass),
        "gravity" => v.gravity = Some(p.gravity),
        "inertia" => v.inertia = Some(Inertia::Diagonal(p.inertia)),
        "rotor_inertia" => v.rotor_inertia = Some(p.rotor_inertia),
        "drag_translational" => v.drag_translational = Some(p.drag_translational),
        "drag_rotational" => v.drag_rotational = Some(p.drag_rotational),
        "lift_coefficient" => v.thrust_coefficient = Some(p.lift_coefficient),
        "yaw_drag_coefficient" => v.moment_coefficient = Some(p.yaw_drag_coefficient),
        _ => v.arm_length = Some(p.arm_length),
    }
}

const RIGID_FIELDS: [&str; 13] = [
    "mass",
    "gravity",
    "inertia",
    "arm_length",
    "configuration",
    "spin",
    "thrust_coefficient",
    "moment_coefficient",
    "rotor_inertia",
    "parasitic_drag",
    "rotor_drag_xy",
    "rotor_drag_z",
    "translational_lift",
];

/// Field `f` of `rb` as its TOML text and its bits (enums by their text).
fn rigid_field(rb: &RigidBodyParams, f: &str) -> (String, Vec<u64>) {
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let text = |s: String| {
        let b = s.bytes().map(u64::from).collect();
        (s, b)
    };
    match f {
        "mass" => (shown(&rb.mass), bits(&[rb.mass])),
        "gravity" => (shown(&rb.gravity), bits(&[rb.gravity])),
        "inertia" => (shown(&rb.inertia), bits(&rb.inertia.concat())),
        "arm_length" => (shown(&rb.arm_length), bits(&[rb.arm_length])),
        "configuration" => text(shown(&rb.configuration)),
        "spin" => text(shown(&rb.spin)),
        "thrust_coefficient" => (shown(&rb.thrust_coefficient), bits(&[rb.thrust_coefficient])),
        "moment_coefficient" => (shown(&rb.moment_coefficient), bits(&[rb.moment_coefficient])),
        "rotor_inertia" => (shown(&rb.rotor_inertia), bits(&[rb.rotor_inertia])),
        "parasitic_drag" => (shown(&rb.parasitic_drag), bits(&rb.parasitic_drag)),
        "rotor_drag_xy" => (shown(&rb.rotor_drag_xy), bits(&[rb.rotor_drag_xy])),
        "rotor_drag_z" => (shown(&rb.rotor_drag_z), bits(&[rb.rotor_drag_z])),
        _ => (shown(&rb.translational_lift), bits(&[rb.translational_lift])),
    }
}

/// Set `[vehicle]` key `f` (a rigid-body field: the same name) to `rb`'s value.
fn set_from_rigid(v: &mut VehicleSettings, rb: &RigidBodyParams, f: &str) {
    match f {
        "mass" => v.mass = Some(rb.mass),
        "gravity" => v.gravity = Some(rb.gravity),
        "inertia" => v.inertia = Some(Inertia::Matrix(rb.inertia)),
        "arm_length" => v.arm_length = Some(rb.arm_length),
        "configuration" => v.configuration = Some(rb.configuration),
        "spin" => v.spin = Some(rb.spin),
        "thrust_coefficient" => v.thrust_coefficient = Some(rb.thrust_coefficient),
        "moment_coefficient" => v.moment_coefficient = Some(rb.moment_coefficient),
        "rotor_inertia" => v.rotor_inertia = Some(rb.rotor_inertia),
        "parasitic_drag" => v.parasitic_drag = Some(rb.parasitic_drag),
        "rotor_drag_xy" => v.rotor_drag_xy = Some(rb.rotor_drag_xy),
        "rotor_drag_z" => v.rotor_drag_z = Some(rb.rotor_drag_z),
        _ => v.translational_lift = Some(rb.translational_lift),
    }
}

fn contains(keys: &Option<Vec<String>>, f: &str) -> bool {
    keys.as_ref().is_some_and(|k| k.iter().any(|k| k == f))
}

const FILLED: &str = "the old table replaced [plant] whole, so its missing keys took the paper vehicle's values; \
                      [vehicle] takes a missing key from [plant] instead, so to keep this meaning write";

/// Move the old tables (as parsed: missing keys the paper vehicle's) into
/// `s.vehicle`; `old` names the keys they were written with.
/// `Ok(warnings)`, one per old key (and one for the missing keys written
/// out); `Err` for a mix of spellings.
pub(crate) fn convert(
    s: &mut Scenario,
    actual: Option<QuadrotorParams>,
    rigid: Option<RigidBodyParams>,
    old: &OldKeys,
) -> Result<Vec<Note>, Refusal> {
    if actual.is_none() && rigid.is_none() {
        return Ok(Vec::new());
    }
    let (old_table, old_list) = match (&actual, &old.actual_plant) {
        (Some(_), keys) => ("actual_plant", keys.clone().unwrap_or_default()),
        (None, _) => ("vehicle.rigid_body", old.rigid_body.clone().unwrap_or_default()),
    };
    let old_key = match old_list.first() {
        Some(k) => format!("{old_table}.{k}"),
        None => old_table.to_string(),
    };
    if let Some(new) = s.vehicle.given_keys().first() {
        let value = toml::Value::try_from(s.vehicle).ok().and_then(|t| t.get(*new).map(ToString::to_string));
        return Err((
            format!("vehicle.{new}"),
            value.unwrap_or_default(),
            format!(
                "not together with the deprecated `{old_key}`: both describe the true vehicle; write every true \
                 parameter in [vehicle] (`{old_table}.<key>` is `vehicle.<key>`, `lift_coefficient` and \
                 `yaw_drag_coefficient` are `thrust_coefficient` and `moment_coefficient`; docs/scenarios.md, \
                 \"Converting old files\")"
            ),
        ));
    }
    if let (Some(_), Some(_)) = (&actual, &rigid) {
        return Err((
            old_key,
            "a table".into(),
            "not together with [vehicle.rigid_body]: the two deprecated tables both describe the true vehicle; \
             write one [vehicle] section with every true parameter (docs/scenarios.md, \"Converting old files\")"
                .into(),
        ));
    }
    // Range errors name the key as written.
    let range = |prefix: &str, e: ftsmc_core::law::GainError| {
        (format!("{prefix}.{}", e.field), crate::text::show(e.value), e.expected.to_string())
    };
    if let Some(a) = &actual {
        a.check().map_err(|e| range("actual_plant", e))?;
    }
    // (On model = "paper" too: an invalid table was refused there before.)
    if let Some(rb) = &rigid {
        rb.check().map_err(|e| range("vehicle.rigid_body", e))?;
    }
    let mut warnings = Vec::new();
    let mut warn = |key: String, value: String, message: String| warnings.push((key, value, message));
    let plant = s.plant;
    let model = s.vehicle.model;
    if let Some(a) = actual {
        let mut filled = Vec::new();
        for f in PAPER_FIELDS {
            let given = contains(&old.actual_plant, f);
            let (value, bits) = paper_field(&a, f);
            let new = crate::vehicle::section::vehicle_key_of_plant_field(f);
            if model == VehicleModel::RigidBody && f.starts_with("drag_") {
                if given {
                    warn(
                        format!("actual_plant.{f}"),
                        value,
                        "deprecated, and it never acted on model = \"rigid-body\" (the rigid body's drag is \
                         vehicle.parasitic_drag, rotor_drag_xy, rotor_drag_z): dropped, delete it"
                            .into(),
                    );
                }
                continue;
            }
            if given {
                set_from_paper(&mut s.vehicle, &a, f);
                warn(
                    format!("actual_plant.{f}"),
                    value.clone(),
                    format!("deprecated: write [vehicle] {new} = {value}"),
                );
            } else if bits != paper_field(&plant, f).1 {
                set_from_paper(&mut s.vehicle, &a, f);
                filled.push(format!("{new} = {value}"));
            }
        }
        if !filled.is_empty() {
            warn("actual_plant".into(), "a table".into(), format!("{FILLED} [vehicle] {}", filled.join(", ")));
        }
    }
    if let Some(rb) = rigid {
        if model == VehicleModel::Paper {
            warn(
                "vehicle.rigid_body".into(),
                "a table".into(),
                "deprecated, and it never acted on model = \"paper\" (only model = \"rigid-body\" flies it): \
                 dropped; to fly it, write model = \"rigid-body\" and its keys in [vehicle]"
                    .into(),
            );
            return Ok(warnings);
        }
        let from_plant = RigidBodyParams::from_paper(&plant);
        let mut filled = Vec::new();
        for f in RIGID_FIELDS {
            let (value, bits) = rigid_field(&rb, f);
            if contains(&old.rigid_body, f) {
                set_from_rigid(&mut s.vehicle, &rb, f);
                warn(
                    format!("vehicle.rigid_body.{f}"),
                    value.clone(),
                    format!("deprecated: write [vehicle] {f} = {value}"),
                );
            } else if bits != rigid_field(&from_plant, f).1 {
                set_from_rigid(&mut s.vehicle, &rb, f);
                if f == "inertia" {
                    // A missing inertia was the paper vehicle's diagonal one.
                    let d = Inertia::Matrix(rb.inertia).diagonal();
                    s.vehicle.inertia = Some(Inertia::Diagonal(d));
                    filled.push(format!("{f} = {}", shown(&d)));
                } else {
                    filled.push(format!("{f} = {value}"));
                }
            }
        }
        if !filled.is_empty() {
            warn("vehicle.rigid_body".into(), "a table".into(), format!("{FILLED} [vehicle] {}", filled.join(", ")));
        }
        // The paper-form view of the true vehicle (recorded true mass and
        // inertia, the payload's base) was [plant]'s; it is now the rigid body's.
        let now = s.vehicle.true_vehicle(&plant);
        if now.mass.to_bits() != plant.mass.to_bits()
            || now.inertia.map(f64::to_bits) != plant.inertia.map(f64::to_bits)
        {
            warn(
                "vehicle.rigid_body".into(),
                "a table".into(),
                "its mass or inertia differs from [plant]'s: the recorded true mass and inertia (mass_true, \
                 inertia_1..3) now show the rigid body's, which is what flies (before: [plant]'s)"
                    .into(),
            );
        }
    }
    Ok(warnings)
}

/// Renamed keys: `(section, old key, new key, what the key means)`. Before,
/// `max_tilt` named both a limit on the flown tilt (`[simulation]`:
/// divergence, `[envelope]`: success) and a limit on the controllers'
/// demand; the demand limits are now `max_demanded_tilt`.
pub(crate) const RENAMED: [(&str, &str, &str, &str); 3] = [
    ("cascade", "max_tilt", "max_demanded_tilt", "the most tilt the paper cascades demand (Eq. 52's asin clamp)"),
    ("pid", "max_tilt", "max_demanded_tilt", "the most tilt PID's thrust direction demands"),
    ("se3", "max_tilt", "max_demanded_tilt", "the most tilt SE(3)'s thrust direction demands"),
];

/// Move each [`RENAMED`] old key of the resolved table to its new name,
/// with a warning; `writer(path)` is the `extends` depth of the file that
/// wrote `path` (0: the scenario itself; `None`: a default). The two names
/// are one key: the file nearer the scenario wins, as for any key (a file
/// extending `paper-scenario-1`, which writes the new name, may still write
/// the old one); both names in one file are refused naming both. `Ok` lists
/// `(old path, new path when the old value moved there, warning)`.
pub(crate) fn rename_keys(
    merged: &mut toml::Table,
    writer: impl Fn(&str) -> Option<usize>,
) -> Result<Vec<(String, Option<String>, Note)>, Refusal> {
    let mut out = Vec::new();
    for (section, old, new, meaning) in RENAMED {
        let Some(toml::Value::Table(table)) = merged.get_mut(section) else { continue };
        let Some(value) = table.remove(old) else { continue };
        let (old_path, new_path) = (format!("{section}.{old}"), format!("{section}.{new}"));
        let shown = value.to_string();
        let moved = match (writer(&old_path), writer(&new_path)) {
            (Some(o), Some(n)) if o == n => {
                return Err((
                    old_path,
                    shown,
                    format!("not together with `{new_path}` (its new name) in one file: keep only `{new_path}`"),
                ));
            }
            // The new name, written nearer the scenario, wins.
            (Some(o), Some(n)) if n < o => None,
            _ => {
                table.insert(new.to_string(), value);
                Some(new_path)
            }
        };
        let message = format!(
            "deprecated: write [{section}] {new} = {shown} ({meaning}; `max_tilt` now names only a limit on the \
             flown tilt, in [simulation] and [envelope])"
        );
        out.push((old_path.clone(), moved, (old_path, shown, message)));
    }
    Ok(out)
}
