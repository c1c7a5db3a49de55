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

/// What `--set KEY=VALUE` accepts as VALUE, for its error messages.
const ONE_VALUE: &str =
    "expected one TOML value (5, true, \"text\", [1, 2], { low = 1, high = 2 }) or a bare word (crazyflie-2)";

/// `KEY=VALUE` of the command line as a dotted key and a TOML value: VALUE
/// is read as exactly one TOML value (`0.5`, `true`, `"text"`, `[1, 2]`,
/// `{ dist = "uniform", low = 1, high = 2 }`), and as a string when it is a
/// bare word that is not one (`vehicle.preset=crazyflie-2`, also an empty
/// VALUE). Refused, naming the key: a VALUE on several lines (a TOML
/// fragment such as `"a"\nseed = 4242` would set a second key), and one
/// that opens a TOML string, array or table (`"`, `'`, `[`, `{`) but is not
/// a valid one (it is not read as a string either).
pub fn parse_set(arg: &str) -> Result<(String, toml::Value), String> {
    let Some((key, value)) = arg.split_once('=') else {
        return Err(format!(
            "--set {}: expected KEY=VALUE (a dotted scenario key, e.g. vehicle.preset=crazyflie-2)",
            crate::text::show_str(arg)
        ));
    };
    let key = key.trim();
    let shown_key = crate::text::show_str(key);
    // Checked before trimming: a line break anywhere, even a trailing one.
    if value.contains(['\n', '\r']) {
        return Err(format!("--set {shown_key}: the value holds a line break; {ONE_VALUE}"));
    }
    let value = value.trim();
    match toml::from_str::<toml::Table>(&format!("v = {value}")) {
        Ok(mut table) => match (table.remove("v"), table.is_empty()) {
            (Some(parsed), true) => Ok((key.to_string(), parsed)),
            _ => {
                Err(format!("--set {shown_key}: `{}` is not one TOML value; {ONE_VALUE}", crate::text::show_str(value)))
            }
        },
        Err(e) if value.starts_with(['"', '\'', '[', '{']) => {
            let why: String = e.message().split_whitespace().collect::<Vec<_>>().join(" ");
            Err(format!(
                "--set {shown_key}: `{}` is not a TOML value ({}); {ONE_VALUE}",
                crate::text::show_str(value),
                crate::text::show_str(&why)
            ))
        }
        Err(_) => Ok((key.to_string(), toml::Value::String(value.to_string()))),
    }
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
        let shown = format!("{} with overrides {}", self.name, shown_keys(&keys));
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
                        // The layout is one thing in two keys: a preset
                        // with either replaces both, unless an override sets one.
                        const LAYOUT: [&str; 2] = ["configuration", "rotor_positions"];
                        let layout_set = LAYOUT.iter().any(|k| keys.contains(&format!("vehicle.{k}").as_str()));
                        let preset_layout = section == "vehicle" && LAYOUT.iter().any(|k| values.contains_key(*k));
                        written.retain(|k, _| {
                            let replaced =
                                values.contains_key(k) || (preset_layout && !layout_set && LAYOUT.contains(&k));
                            !replaced || keys.contains(&format!("{section}.{k}").as_str())
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
        super::resolve::load(super::resolve::Source::Text { text: &text, path: &shown }, &[]).map_err(|e| match e {
            // A line of the text written here means nothing to the user.
            ScenarioError::Parse { path, message } if path == shown => {
                ScenarioError::Parse { message: without_position(&message, &text).to_string(), path }
            }
            other => other,
        })
    }
}

/// Most characters of override keys named in a message's path.
const MAX_SHOWN_KEYS_CHARS: usize = 80;

/// The override keys for a message: `a, b, c`, or as many as fit in
/// [`MAX_SHOWN_KEYS_CHARS`] and `and N more` (each message names its key).
fn shown_keys(keys: &[&str]) -> String {
    let mut out = String::new();
    for (i, key) in keys.iter().enumerate() {
        let next = if i == 0 { crate::text::show_str(key) } else { format!(", {}", crate::text::show_str(key)) };
        if i > 0 && out.chars().count() + next.chars().count() > MAX_SHOWN_KEYS_CHARS {
            out.push_str(&format!(" and {} more", keys.len() - i));
            break;
        }
        out.push_str(&next);
    }
    out
}

/// `message` without the `TOML parse error at line L, column C (`source`): `
/// prefix the loader gives an error in `text` (see `text::parse_message`).
fn without_position<'a>(message: &'a str, text: &str) -> &'a str {
    let strip = || {
        let rest = message.strip_prefix("TOML parse error at line ")?;
        let (line, rest) = rest.split_once(", column ")?;
        let (_column, rest) = rest.split_once(" (`")?;
        let source = text.lines().nth(line.parse::<usize>().ok()?.checked_sub(1)?)?.trim();
        rest.strip_prefix(crate::text::show_str(source).as_str())?.strip_prefix("`): ")
    };
    strip().unwrap_or(message)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_kind_of_toml_value_is_one_value() {
        let v = |arg: &str| parse_set(arg).unwrap_or_else(|e| panic!("{arg}: {e}"));
        assert_eq!(v("seed=4242"), ("seed".into(), toml::Value::Integer(4242)));
        assert_eq!(v("payload.mass = 0.2").1, toml::Value::Float(0.2));
        assert_eq!(v("a=true").1, toml::Value::Boolean(true));
        assert_eq!(v("name=\"a b\"").1, toml::Value::String("a b".into()));
        assert_eq!(v("name='a'").1, toml::Value::String("a".into()));
        assert_eq!(v("seed=42 # a comment").1, toml::Value::Integer(42));
        let array = v("controllers=[\"pid\", \"se3\"]").1;
        assert_eq!(array.as_array().map(Vec::len), Some(2));
        let table = v("mass={ dist = \"uniform\", low = 1, high = 2 }").1;
        assert_eq!(table.as_table().and_then(|t| t.get("high")), Some(&toml::Value::Integer(2)));
    }

    #[test]
    fn a_bare_word_is_a_string_as_before() {
        for (arg, word) in [
            ("vehicle.preset=crazyflie-2", "crazyflie-2"),
            ("wind.preset=breeze", "breeze"),
            ("description=two words", "two words"),
            ("description=", ""),
        ] {
            assert_eq!(parse_set(arg).unwrap().1, toml::Value::String(word.into()), "{arg}");
        }
    }

    #[test]
    fn a_toml_fragment_is_refused_naming_the_key() {
        // Read as `v = VALUE`, this set `seed` beside `name`.
        for arg in
            ["name=\"a\"\nseed = 4242", "name=\"a\"\r\nseed = 4242", "name=a\nseed = 4242", "name=\n", "name=5\n"]
        {
            let err = parse_set(arg).unwrap_err();
            assert!(err.starts_with("--set name: ") && err.contains("one TOML value"), "{arg:?}: {err}");
        }
    }

    #[test]
    fn an_override_error_names_no_line_of_the_generated_text() {
        let (file, text) = super::super::resolve::built_in("paper-scenario-1").unwrap();
        let s = Scenario::from_toml_str(text, file).unwrap();
        let err = s.with_overrides(&[parse_set("durtion=5").unwrap()]).unwrap_err().to_string();
        assert!(
            err.starts_with(
                "paper-scenario-1 with overrides durtion: unknown field `durtion` (did you mean `duration`?)"
            ),
            "{err}"
        );
        let text = "a = 1\n[b]\nc = \"x`): y\"\n";
        let message = "TOML parse error at line 3, column 1 (`c = \\\"x`): y\\\"`): unknown field `c`";
        assert_eq!(without_position(message, text), "unknown field `c`");
        assert_eq!(without_position("unknown field `c`", text), "unknown field `c`");
    }

    #[test]
    fn many_override_keys_are_named_up_to_a_bound() {
        let keys: Vec<String> = (0..40).map(|i| format!("payload.key_{i}")).collect();
        let refs: Vec<&str> = keys.iter().map(String::as_str).collect();
        let shown = shown_keys(&refs);
        assert!(shown.starts_with("payload.key_0, payload.key_1") && shown.ends_with(" more"), "{shown}");
        assert!(shown.chars().count() <= MAX_SHOWN_KEYS_CHARS + 12, "{shown}");
        assert_eq!(shown_keys(&["a", "b"]), "a, b");
    }

    #[test]
    fn a_malformed_toml_value_is_refused_not_read_as_a_string() {
        for arg in ["name=\"a", "controllers=[\"pid\"", "mass={ low = 1", "name='a"] {
            let err = parse_set(arg).unwrap_err();
            assert!(err.starts_with("--set ") && err.contains("not a TOML value"), "{arg:?}: {err}");
            let key = arg.split_once('=').unwrap().0;
            assert!(err.starts_with(&format!("--set {key}: ")), "{arg:?}: {err}");
        }
    }
}
