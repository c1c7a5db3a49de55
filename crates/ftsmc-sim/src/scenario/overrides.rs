//! Dotted-key overrides of a loaded scenario: the CLI's `--set KEY=VALUE`
//! and Python's `Scenario.with_overrides`, one implementation.
//!
//! The resolved scenario is written as TOML ([`Scenario::to_toml`]), each
//! key set (missing tables created) and the text loaded again, so an
//! override is validated exactly as the same key in a file would be. Two
//! kinds of keys follow an override instead of keeping their written value:
//!
//! - gain sections still at their vehicle-derived defaults (`[pid]`,
//!   `[se3]`) are dropped first, so they follow an overridden `[plant]` or
//!   rotor limit;
//! - when `vehicle.preset` is overridden, every `[plant]`, `[vehicle]` and
//!   `[actuators]` key the new preset has is dropped unless also
//!   overridden, so those keys follow the new preset, as in a file that
//!   extends the scenario and names it ([`crate::vehicle::presets`]);
//! - when `wind.preset` is overridden, the wind keys a preset owns are
//!   dropped unless also overridden ([`crate::environment::wind::PRESET_OWNED_KEYS`]).
//!
//! An override of `vehicle.preset` to another vehicle than the scenario's
//! (and no override of `name`) appends the preset to the name
//! (`realistic-calm-1-crazyflie-2`): result folders, report and figure
//! titles and tuned files then name the vehicle that flew.

use super::resolve::Loaded;
use super::{Scenario, ScenarioError};
use crate::vehicle::presets::PRESET_SECTIONS;

/// Longest dotted override key, characters.
pub const MAX_KEY_CHARS: usize = 256;
/// Most parts of a dotted override key.
pub const MAX_KEY_PARTS: usize = 16;

/// Set `table[a][b][c] = value` for `key = "a.b.c"`, creating missing
/// tables; an existing non-table on the way is an error naming it.
pub fn set_dotted(table: &mut toml::Table, key: &str, value: toml::Value) -> Result<(), String> {
    if key.chars().count() > MAX_KEY_CHARS || key.split('.').count() > MAX_KEY_PARTS {
        return Err(format!("a dotted key is at most {MAX_KEY_CHARS} characters and {MAX_KEY_PARTS} parts"));
    }
    let parts: Vec<&str> = key.split('.').collect();
    if parts.iter().any(|p| p.is_empty()) {
        return Err("empty key part (expected dotted keys such as `payload.mass`)".into());
    }
    let (last, path) = parts.split_last().expect("split gives at least one part");
    let mut here = table;
    for (i, part) in path.iter().enumerate() {
        let entry = here.entry(part.to_string()).or_insert_with(|| toml::Value::Table(toml::Table::new()));
        here = match entry {
            toml::Value::Table(t) => t,
            other => {
                return Err(format!("`{}` is a {}, not a table", parts[..=i].join("."), other.type_str()));
            }
        };
    }
    here.insert(last.to_string(), value);
    Ok(())
}

/// `KEY=VALUE` of the command line as a dotted key and a TOML value: VALUE
/// is read as a TOML value (`0.5`, `true`, `"text"`, `[1, 2]`,
/// `{ dist = "uniform", low = 1, high = 2 }`), and as a string when it is
/// not one (`vehicle.preset=crazyflie-2`).
pub fn parse_set(arg: &str) -> Result<(String, toml::Value), String> {
    let Some((key, value)) = arg.split_once('=') else {
        return Err(format!(
            "--set {}: expected KEY=VALUE (a dotted scenario key, e.g. vehicle.preset=crazyflie-2)",
            crate::text::show_str(arg)
        ));
    };
    let key = key.trim();
    let value = value.trim();
    let parsed = toml::from_str::<toml::Table>(&format!("v = {value}")).ok().and_then(|mut t| t.remove("v"));
    Ok((key.to_string(), parsed.unwrap_or_else(|| toml::Value::String(value.to_string()))))
}

/// The preset `overrides` switch the vehicle to, when it is not `s`'s own
/// and the overrides leave `name` alone: the suffix of the new name.
fn renamed_for(s: &Scenario, overrides: &[(String, toml::Value)]) -> Option<&'static str> {
    if overrides.iter().any(|(k, _)| k == "name") {
        return None;
    }
    let (_, toml::Value::String(name)) = overrides.iter().rev().find(|(k, _)| k == "vehicle.preset")? else {
        return None;
    };
    let preset = crate::vehicle::presets::VehiclePreset::from_name(name)?;
    (s.vehicle.preset != Some(preset)).then_some(preset.name())
}

impl Scenario {
    /// A new scenario with dotted keys set (module docs), validated as a
    /// file would be; messages name the scenario and the keys.
    pub fn with_overrides(&self, overrides: &[(String, toml::Value)]) -> Result<Loaded, ScenarioError> {
        for (key, _) in overrides {
            if key.chars().count() > MAX_KEY_CHARS || key.split('.').count() > MAX_KEY_PARTS {
                return Err(ScenarioError::Parse {
                    path: self.name.clone(),
                    message: format!(
                        "override `{}…`: a dotted key is at most {MAX_KEY_CHARS} characters and {MAX_KEY_PARTS} parts",
                        key.chars().take(40).collect::<String>()
                    ),
                });
            }
        }
        let keys: Vec<&str> = overrides.iter().map(|(k, _)| k.as_str()).collect();
        let shown = format!("{} with overrides {}", self.name, keys.join(", "));
        let fail = |message: String| ScenarioError::Parse { path: shown.clone(), message };
        let text = self.to_toml().map_err(|e| fail(e.to_string()))?;
        let mut table: toml::Table = toml::from_str(&text).map_err(|e| fail(e.to_string()))?;
        for key in self.gains.keys_at_defaults(&self.nominal_vehicle()) {
            table.remove(key);
        }
        if keys.contains(&"vehicle.preset") {
            // The overrides are a file above the scenario: the preset they
            // name replaces every key it has that they do not set.
            if let Some(toml::Value::String(name)) =
                overrides.iter().find(|(k, _)| k == "vehicle.preset").map(|(_, v)| v)
            {
                if let Some(preset) = crate::vehicle::presets::VehiclePreset::from_name(name) {
                    let preset = preset.table();
                    for section in PRESET_SECTIONS {
                        let (Some(toml::Value::Table(values)), Some(toml::Value::Table(written))) =
                            (preset.get(section), table.get_mut(section))
                        else {
                            continue;
                        };
                        written.retain(|k, _| {
                            !values.contains_key(k) || keys.contains(&format!("{section}.{k}").as_str())
                        });
                    }
                }
            }
        }
        if keys.contains(&"wind.preset") {
            if let Some(toml::Value::Table(wind)) = table.get_mut("wind") {
                for owned in crate::environment::wind::PRESET_OWNED_KEYS {
                    if !keys.contains(&format!("wind.{owned}").as_str()) {
                        wind.remove(owned);
                    }
                }
            }
        }
        for (key, value) in overrides {
            set_dotted(&mut table, key, value.clone()).map_err(|m| fail(format!("override `{key}`: {m}")))?;
        }
        // A scenario flown on another vehicle is named after it, so its
        // result folders, reports and tuned files say which vehicle flew.
        if let Some(preset) = renamed_for(self, overrides) {
            table.insert("name".into(), toml::Value::String(format!("{}-{preset}", self.name)));
        }
        let text = toml::to_string(&table).map_err(|e| fail(e.to_string()))?;
        super::resolve::load(super::resolve::Source::Text { text: &text, path: &shown }, &[])
    }
}
