//! Resolving a scenario file: `extends` chains, the deep merge over the
//! defaults, errors that name the file a key was written in, and warnings
//! for likely unit slips.
//!
//! # Resolution
//!
//! A scenario is the TOML value of the built-in defaults (every key of
//! [`Scenario`] with its default, as serialized), overlaid with the files of
//! its `extends` chain from the deepest base up to the file itself:
//!
//! - tables merge key by key, recursively, so `[ftaftsmc.z]` with only
//!   `lambda = 3.0` changes that one gain and keeps the other seventeen;
//! - arrays and scalars replace;
//! - a **signal** (`reference.*`, `disturbance.*`, `inertia_variation`)
//!   and a Monte Carlo distribution (`montecarlo.*`) are replaced whole: a
//!   partial merge of two signals (the base's `terms` with your `window`, or
//!   a step with your waypoints) would silently add them up.
//!
//! The merged table is then deserialized with every struct's
//! `deny_unknown_fields`, so a misspelt key in any file of the chain is
//! still an error that names it, and `name`/`duration` must be set by some
//! file of the chain. The controllers' gain sections (`[ftaftsmc]`, …; see
//! [`crate::controllers`]) are taken out of the merged table first and each
//! is deserialized with its declared type, its error keys prefixed with the
//! section's.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::controllers::{GainSections, NominalVehicle, SectionParseError};
use crate::limits::Limits;
use crate::scenario::{read_scenario_text, Scenario, ScenarioError, BUILT_IN_SCENARIOS};
use crate::signal::{Signal, Term};
use crate::text::{show, show_str};

/// Longest `extends` chain, files (the file itself included).
pub const MAX_EXTENDS_DEPTH: usize = 16;

/// Where the first file of a chain comes from.
#[derive(Clone, Copy, Debug)]
pub enum Source<'a> {
    /// A file on disk (read with the regular-file and size checks).
    File(&'a Path),
    /// TOML text; `path` names it in messages and, when it has a parent
    /// directory, relative `extends` paths resolve against that directory
    /// (otherwise against the current directory).
    Text {
        /// The TOML text.
        text: &'a str,
        /// Its name in messages.
        path: &'a str,
    },
}

/// A loaded scenario, the files it was resolved from and its warnings.
#[derive(Clone, Debug)]
pub struct Loaded {
    /// The validated scenario.
    pub scenario: Scenario,
    /// The files of the chain, the scenario's own first, its deepest base last.
    pub files: Vec<String>,
    /// Likely unit slips, one line each, naming file, key and value.
    pub warnings: Vec<String>,
    /// The nearest built-in scenario of the `extends` chain
    /// (`realistic-calm-1`), if it has one: what a file written from this
    /// scenario can extend and still load wherever it is moved.
    pub built_in_base: Option<&'static str>,
}

struct Layer {
    shown: String,
    text: String,
    table: toml::Table,
    /// The directory relative paths in the file resolve against (`None`: a
    /// built-in scenario; the working directory).
    dir: Option<PathBuf>,
}

/// The built-in scenario called `name` (`paper-scenario-1`, with or without
/// `.toml`), as `(file name, text)`.
pub fn built_in(name: &str) -> Option<(&'static str, &'static str)> {
    let wanted = name.strip_suffix(".toml").unwrap_or(name);
    BUILT_IN_SCENARIOS.iter().copied().find(|(file, _)| file.strip_suffix(".toml") == Some(wanted))
}

/// The names of every built-in scenario ([`BUILT_IN_SCENARIOS`], file names
/// without `.toml`), in the order `ftsmc list` shows them. The one list that
/// `ftsmc list`, `ftsmc scenario`, the unknown-scenario errors, `extends` and
/// Python's `Scenario.builtin` read.
pub fn built_in_names() -> impl Iterator<Item = &'static str> {
    BUILT_IN_SCENARIOS.iter().map(|(f, _)| f.strip_suffix(".toml").unwrap_or(f))
}

/// [`built_in_names`] for error messages, short enough to survive the CLI's
/// one-line error limit: names that differ only in their last character and
/// follow each other are written once, `realistic-calm-1/2` for
/// `realistic-calm-1, realistic-calm-2`; groups are joined with `", "`.
pub fn built_in_names_joined() -> String {
    let mut groups: Vec<String> = Vec::new();
    let mut last: Option<&str> = None;
    for name in built_in_names() {
        let stem = &name[..name.len() - name.chars().last().map_or(0, char::len_utf8)];
        match (last, groups.last_mut()) {
            (Some(prev), Some(group)) if prev.len() == name.len() && prev.starts_with(stem) && !stem.is_empty() => {
                group.push('/');
                group.push_str(&name[stem.len()..]);
            }
            _ => groups.push(name.to_string()),
        }
        last = Some(name);
    }
    groups.join(", ")
}

/// Dotted keys whose values are replaced whole instead of merged.
fn is_atomic(path: &str) -> bool {
    let mut parts = path.split('.');
    matches!(
        (parts.next(), parts.next(), parts.next()),
        (Some("inertia_variation"), None, _) | (Some("reference" | "disturbance" | "montecarlo"), Some(_), None)
    )
}

/// Record `file` as the writer of `path` and of everything below it.
fn record(value: &toml::Value, path: &str, file: usize, origin: &mut BTreeMap<String, usize>) {
    origin.insert(path.to_string(), file);
    if let toml::Value::Table(t) = value {
        for (k, v) in t {
            record(v, &format!("{path}.{k}"), file, origin);
        }
    }
}

/// Overlay `top` on `base`: tables merge key by key (except [`is_atomic`]
/// ones), everything else replaces.
fn merge(base: &mut toml::Table, top: toml::Table, prefix: &str, file: usize, origin: &mut BTreeMap<String, usize>) {
    for (key, value) in top {
        let path = if prefix.is_empty() { key.clone() } else { format!("{prefix}.{key}") };
        origin.insert(path.clone(), file);
        match (base.get_mut(&key), value) {
            (Some(toml::Value::Table(b)), toml::Value::Table(t)) if !is_atomic(&path) => {
                // A file that writes `reference.trajectory` replaces its
                // base's x, y, z, psi signals, and one that writes a signal
                // replaces its base's trajectory: the two forms exclude
                // each other (docs/scenarios.md, "Trajectories").
                if path == "reference" {
                    let signals = ["x", "y", "z", "psi"];
                    if t.contains_key("trajectory") {
                        signals.iter().for_each(|k| drop(b.remove(*k)));
                    } else if signals.iter().any(|k| t.contains_key(*k)) {
                        b.remove("trajectory");
                        b.remove("time_scale");
                    }
                }
                merge(b, t, &path, file, origin);
            }
            (_, value) => {
                origin.retain(|k, _| !k.starts_with(&format!("{path}.")));
                record(&value, &path, file, origin);
                base.insert(key, value);
            }
        }
    }
}

/// The defaults of every key as a TOML table (without `name`/`duration`,
/// which have none).
fn defaults() -> toml::Table {
    let minimal: Scenario = toml::from_str("name = \"defaults\"\nduration = 1.0").expect("defaults deserialize");
    let mut table = toml::Table::try_from(&minimal).expect("defaults serialize");
    table.remove("name");
    table.remove("duration");
    // Gain sections get their defaults from the scenario's own `[plant]`
    // (`GainSections::take_from`), not the paper vehicle's.
    for key in GainSections::KEYS {
        table.remove(*key);
    }
    table
}

/// Line and column of the deepest key of `path` found in `text`.
fn locate(text: &str, path: &str) -> Option<(usize, usize)> {
    let doc = toml::de::DeTable::parse(text).ok()?;
    let mut table = doc.get_ref();
    let mut span = None;
    for part in path.split('.') {
        let key = part.split('[').next().unwrap_or(part);
        let Some((k, v)) = table.iter().find(|(k, _)| k.get_ref().as_ref() == key) else { break };
        span = Some(k.span());
        match v.get_ref().as_table() {
            Some(t) => table = t,
            None => break,
        }
    }
    let start = span?.start.min(text.len());
    let before = &text.as_bytes()[..start];
    let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
    let column = before.iter().rev().take_while(|&&b| b != b'\n').count() + 1;
    Some((line, column))
}

struct Chain {
    layers: Vec<Layer>,
    origin: BTreeMap<String, usize>,
    /// The nearest built-in scenario of the chain, if any.
    built_in_base: Option<&'static str>,
}

impl Chain {
    /// The layer that wrote `path` (longest written prefix), else the top file.
    fn writer(&self, path: &str) -> usize {
        let clean: String = {
            // `a.b[2].c` -> `a.b.c` for the lookup.
            let mut out = String::new();
            let mut depth = 0;
            for c in path.chars() {
                match c {
                    '[' => depth += 1,
                    ']' => depth -= 1,
                    _ if depth == 0 => out.push(c),
                    _ => {}
                }
            }
            out
        };
        let mut prefix = clean.as_str();
        loop {
            if let Some(&i) = self.origin.get(prefix) {
                return i;
            }
            match prefix.rfind('.') {
                Some(dot) => prefix = &prefix[..dot],
                None => return 0,
            }
        }
    }

    /// How to name layer `i` in a message.
    fn shown(&self, i: usize) -> String {
        if i == 0 {
            self.layers[0].shown.clone()
        } else {
            format!("{} (extended by {})", self.layers[i].shown, self.layers[0].shown)
        }
    }

    /// An error at dotted `path` of layer `i` (before it is merged).
    fn parse_error_in(&self, i: usize, path: &str, message: &str) -> ScenarioError {
        let layer = &self.layers[i];
        let message = match locate(&layer.text, path) {
            Some((line, column)) => {
                let source = layer.text.lines().nth(line - 1).unwrap_or("").trim();
                format!("TOML parse error at line {line}, column {column} (`{}`): {message}", show_str(source))
            }
            None => message.to_string(),
        };
        ScenarioError::Parse { path: self.shown(i), message }
    }

    /// An error at dotted `path`: the file that wrote it, with line and
    /// column when the key is found in its text.
    fn parse_error(&self, path: &str, message: &str) -> ScenarioError {
        let i = self.writer(path);
        let layer = &self.layers[i];
        let message = match (path.is_empty(), locate(&layer.text, path)) {
            (false, Some((line, column))) => {
                let source = layer.text.lines().nth(line - 1).unwrap_or("").trim();
                format!("TOML parse error at line {line}, column {column} (`{}`): {message}", show_str(source))
            }
            _ => message.to_string(),
        };
        ScenarioError::Parse { path: self.shown(i), message }
    }
}

/// Whether the first layer of a chain was read from a file or given as text.
#[derive(Clone, Copy)]
enum SourceKind {
    File,
    Text,
}

/// Load the chain starting at `source`.
fn load_chain(source: Source<'_>, limits: &Limits) -> Result<Chain, ScenarioError> {
    let source_kind = match source {
        Source::File(_) => SourceKind::File,
        Source::Text { .. } => SourceKind::Text,
    };
    let (mut shown, mut text, mut dir, mut id) = match source {
        Source::File(path) => {
            let text = read_scenario_text(path, limits)?;
            let id = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf()).display().to_string();
            (path.display().to_string(), text, path.parent().map(Path::to_path_buf), id)
        }
        Source::Text { text, path } => {
            let dir = Path::new(path).parent().map(Path::to_path_buf);
            (path.to_string(), text.to_string(), dir, format!("text:{path}"))
        }
    };
    let mut layers: Vec<Layer> = Vec::new();
    let mut ids: Vec<String> = Vec::new();
    let mut built_in_base: Option<&'static str> = None;
    loop {
        let mut table: toml::Table = toml::from_str(&text).map_err(|e| ScenarioError::Parse {
            path: shown.clone(),
            // A file reached through `extends` may be anything (a system
            // file): name it and the position, never quote its content.
            message: match layers.last() {
                // A file whose name does not end in `.toml` may be anything
                // (`/etc/passwd`): never quote its content either.
                None if !shown.ends_with(".toml") && matches!(source_kind, SourceKind::File) => format!(
                    "not a scenario file: {} (content not shown: the name does not end in .toml)",
                    crate::text::parse_position(&text, &e)
                ),
                None => crate::text::parse_message(&text, &e),
                Some(by) => format!(
                    "not a scenario file (`extends` target of {}): {} (content not shown)",
                    by.shown,
                    crate::text::parse_position(&text, &e)
                ),
            },
        })?;
        let extends = table.remove("extends");
        ids.push(id);
        layers.push(Layer { shown: shown.clone(), text, table, dir: dir.clone() });
        let Some(extends) = extends else { break };
        let toml::Value::String(target) = extends else {
            return Err(ScenarioError::Parse {
                path: shown,
                message: format!(
                    "`extends` = {} is invalid (expected a string: a built-in scenario name or a path relative to \
                     this file)",
                    show_str(&extends.to_string())
                ),
            });
        };
        let chain_names = |last: &str| {
            let mut names: Vec<String> = layers.iter().map(|l| l.shown.clone()).collect();
            names.push(last.to_string());
            names.join(" → ")
        };
        let (next_shown, next_text, next_dir, next_id) = match built_in(&target) {
            Some((file, text)) if !target.contains(['/', '\\']) => {
                // The nearest built-in (built-ins only extend built-ins).
                built_in_base = built_in_base.or(Some(file.strip_suffix(".toml").unwrap_or(file)));
                (file.to_string(), text.to_string(), None, format!("built-in:{file}"))
            }
            _ => {
                let path: PathBuf = dir.as_deref().unwrap_or(Path::new("")).join(&target);
                let next_shown = path.display().to_string();
                if !path.exists() {
                    return Err(ScenarioError::Parse {
                        path: shown,
                        message: format!(
                            "`extends` = \"{}\": no file {} (relative paths are relative to the extending file) \
                             and not a built-in scenario ({})",
                            show_str(&target),
                            show_str(&next_shown),
                            built_in_names_joined()
                        ),
                    });
                }
                let next_id = std::fs::canonicalize(&path).unwrap_or_else(|_| path.clone()).display().to_string();
                if !ids.contains(&next_id) && layers.len() < MAX_EXTENDS_DEPTH {
                    let text = read_scenario_text(&path, limits)?;
                    (next_shown, text, path.parent().map(Path::to_path_buf), next_id)
                } else {
                    (next_shown, String::new(), None, next_id)
                }
            }
        };
        if ids.contains(&next_id) {
            return Err(ScenarioError::Parse {
                path: layers[0].shown.clone(),
                message: format!("`extends` cycle: {}", chain_names(&next_shown)),
            });
        }
        if layers.len() >= MAX_EXTENDS_DEPTH {
            return Err(ScenarioError::Parse {
                path: layers[0].shown.clone(),
                message: format!("`extends` chain longer than {MAX_EXTENDS_DEPTH} files: {}", chain_names(&next_shown)),
            });
        }
        (shown, text, dir, id) = (next_shown, next_text, next_dir, next_id);
    }
    Ok(Chain { layers, origin: BTreeMap::new(), built_in_base })
}

/// The Monte Carlo draws with a relative form: `(absolute key, relative key)`.
const RELATIVE_DRAWS: [(&str, &str); 2] = [("mass", "mass_factor"), ("payload_mass", "payload_mass_factor")];

/// One file's relative Monte Carlo draws: `mass = { dist = "uniform", rel =
/// [a, b] }` is `mass_factor = { dist = "uniform", low = a, high = b }` (and
/// so for `payload_mass`). Within one file the absolute and the relative
/// key are exclusive; a file that sets either replaces what a base file
/// gave the other (the two are one draw: see the merge).
fn relative_draws(layer: &mut toml::Table) -> Result<(), (String, String)> {
    let Some(toml::Value::Table(mc)) = layer.get_mut("montecarlo") else { return Ok(()) };
    for (absolute, relative) in RELATIVE_DRAWS {
        let Some(toml::Value::Table(d)) = mc.get(absolute) else { continue };
        let Some(rel) = d.get("rel") else { continue };
        let key = format!("montecarlo.{absolute}.rel");
        let pair = rel.as_array().filter(|a| a.len() == 2).and_then(|a| {
            let f = |v: &toml::Value| v.as_float().or_else(|| v.as_integer().map(|i| i as f64));
            Some([f(&a[0])?, f(&a[1])?])
        });
        let Some([low, high]) = pair else {
            return Err((
                key,
                format!(
                    "`rel` = {} is invalid (expected two factors [low, high] of the vehicle's value)",
                    show_str(&rel.to_string())
                ),
            ));
        };
        if d.get("dist").and_then(|v| v.as_str()) != Some("uniform") || d.len() != 2 {
            return Err((key, format!("`rel` goes with dist = \"uniform\" and no other key (write `{absolute} = {{ dist = \"uniform\", rel = [{}, {}] }}`, or `{relative}` for another distribution of the factor)", show(low), show(high))));
        }
        if mc.contains_key(relative) {
            return Err((key, format!("`{absolute}` with `rel` is `{relative}`: not both in one file")));
        }
        let mut factor = toml::Table::new();
        factor.insert("dist".into(), toml::Value::String("uniform".into()));
        factor.insert("low".into(), toml::Value::Float(low));
        factor.insert("high".into(), toml::Value::Float(high));
        mc.remove(absolute);
        mc.insert(relative.into(), toml::Value::Table(factor));
    }
    Ok(())
}

/// Before a file is merged: its absolute or relative draw of a quantity
/// ([`RELATIVE_DRAWS`]) replaces the base files' draw of the other form.
fn release_other_draw_form(merged: &mut toml::Table, layer: &toml::Table, origin: &mut BTreeMap<String, usize>) {
    let Some(toml::Value::Table(mc)) = layer.get("montecarlo") else { return };
    let Some(toml::Value::Table(base)) = merged.get_mut("montecarlo") else { return };
    for (absolute, relative) in RELATIVE_DRAWS {
        for (set, other) in [(absolute, relative), (relative, absolute)] {
            if mc.contains_key(set) && base.remove(other).is_some() {
                let path = format!("montecarlo.{other}");
                origin.retain(|k, _| k != &path && !k.starts_with(&format!("{path}.")));
            }
        }
    }
}

/// A file that sets `[wind] preset` owns the preset's keys
/// ([`crate::environment::wind::PRESET_OWNED_KEYS`]): the values a base
/// file gave them are dropped unless this file sets them too, so a child's
/// `preset = "calm"` is still air whatever the parent's speed or turbulence.
fn release_wind_preset_keys(merged: &mut toml::Table, layer: &toml::Table, origin: &mut BTreeMap<String, usize>) {
    let Some(toml::Value::Table(wind)) = layer.get("wind") else { return };
    if !wind.contains_key("preset") {
        return;
    }
    if let Some(toml::Value::Table(base)) = merged.get_mut("wind") {
        for key in crate::environment::wind::PRESET_OWNED_KEYS {
            if !wind.contains_key(key) && base.remove(key).is_some() {
                let path = format!("wind.{key}");
                origin.retain(|k, _| k != &path && !k.starts_with(&format!("{path}.")));
            }
        }
    }
}

/// The vehicle preset `vehicle.preset` names, if any
/// ([`crate::vehicle::presets`]), as a layer just below the file that names
/// it: it fills every `[plant]`, `[vehicle]` and `[actuators]` key it has,
/// except those written by that file or a file extending it (`origin`
/// index at most the naming file's); the values of its base files are
/// replaced, so a child that names another vehicle gets that vehicle's
/// nominal model, true vehicle and rotors. With `model = "paper"` written
/// at or above the naming file, the rigid-body-only keys are left out. The
/// layout (`configuration`, `rotor_positions`) is filled or kept whole.
/// A filled key is recorded as written by the naming file. `Err(message)`
/// for a name that is not a preset.
fn apply_vehicle_preset(merged: &mut toml::Table, origin: &mut BTreeMap<String, usize>) -> Result<(), String> {
    use crate::vehicle::presets::{VehiclePreset, PRESET_SECTIONS, RIGID_BODY_ONLY_KEYS};
    const LAYOUT_KEYS: [&str; 2] = ["configuration", "rotor_positions"];
    let Some(name) = merged.get("vehicle").and_then(|v| v.get("preset")) else { return Ok(()) };
    let preset = match name.as_str().and_then(VehiclePreset::from_name) {
        Some(p) => p,
        None => {
            return Err(format!(
                "`preset` = {} is not a vehicle preset (known: {})",
                show_str(&name.to_string()),
                VehiclePreset::names_joined()
            ))
        }
    };
    let naming = origin.get("vehicle.preset").copied().unwrap_or(0);
    let kept = |origin: &BTreeMap<String, usize>, path: &str| origin.get(path).is_some_and(|&i| i <= naming);
    let paper = merged.get("vehicle").and_then(|v| v.get("model")).and_then(|m| m.as_str()) == Some("paper")
        && kept(origin, "vehicle.model");
    // The layout is one thing, `configuration` and `rotor_positions` two
    // keys of it: a file at or below the naming one that writes either
    // keeps its layout whole, and otherwise the preset's layout replaces a
    // base file's whole (no "cross" of the preset beside positions of a base).
    let own_layout = LAYOUT_KEYS.iter().any(|k| kept(origin, &format!("vehicle.{k}")));
    if !own_layout && !paper {
        if let Some(v) = merged.get_mut("vehicle").and_then(|v| v.as_table_mut()) {
            for key in LAYOUT_KEYS {
                v.remove(key);
                origin.remove(&format!("vehicle.{key}"));
            }
        }
    }
    let mut table = preset.table();
    for section in PRESET_SECTIONS {
        let Some(toml::Value::Table(values)) = table.remove(section) else { continue };
        let target = merged.entry(section).or_insert_with(|| toml::Value::Table(toml::Table::new()));
        let Some(target) = target.as_table_mut() else { continue };
        for (key, value) in values {
            let path = format!("{section}.{key}");
            let skipped = section == "vehicle"
                && ((paper && (RIGID_BODY_ONLY_KEYS.contains(&key.as_str()) || key == "model"))
                    || (own_layout && LAYOUT_KEYS.contains(&key.as_str())));
            if !kept(origin, &path) && !skipped {
                origin.retain(|k, _| !k.starts_with(&format!("{path}.")));
                origin.insert(path, naming);
                target.insert(key, value);
            }
        }
    }
    Ok(())
}

/// The key path (`in `a.b``) of a deserialization error, plus the unknown
/// field's name when the error is about one.
fn error_path(e: &toml::de::Error) -> String {
    let display = e.to_string();
    let mut path = display
        .lines()
        .rev()
        .find_map(|l| l.strip_prefix("in `").and_then(|l| l.strip_suffix('`')))
        .unwrap_or("")
        .to_string();
    if let Some(rest) = e.message().strip_prefix("unknown field `") {
        if let Some(field) = rest.split('`').next() {
            if !path.is_empty() {
                path.push('.');
            }
            path.push_str(field);
        }
    }
    path
}

/// serde's "unknown field `k`, expected one of `a`, `b`" for the top level
/// of a scenario, with the gain sections (which `Scenario` does not
/// deserialize itself) added to the known keys; `None` for other messages.
fn with_gain_sections(message: &str) -> Option<String> {
    let message: String = message.split_whitespace().collect::<Vec<_>>().join(" ");
    let (head, known) = message.split_once(", expected one of ")?;
    if !head.starts_with("unknown field `") || !known.contains("`name`") {
        return None;
    }
    let sections: Vec<String> = GainSections::KEYS.iter().map(|k| format!("`{k}`")).collect();
    let all = format!("{head}, expected one of {known}, {}", sections.join(", "));
    crate::text::shorten_unknown_field(&all).or(Some(all))
}

/// Resolve, deserialize and validate the scenario at `source`, with
/// command-line limit overrides (see [`Limits::apply_overrides`]).
pub fn load(source: Source<'_>, overrides: &[String]) -> Result<Loaded, ScenarioError> {
    let top_name = match source {
        Source::File(p) => p.display().to_string(),
        Source::Text { path, .. } => path.to_string(),
    };
    let mut limits = Limits::default();
    limits.apply_overrides(overrides).map_err(|message| ScenarioError::Parse { path: top_name.clone(), message })?;
    let mut chain = load_chain(source, &limits)?;

    let mut merged = defaults();
    let layers: Vec<toml::Table> = chain.layers.iter().map(|l| l.table.clone()).collect();
    for (i, mut table) in layers.into_iter().enumerate().rev() {
        relative_draws(&mut table).map_err(|(key, message)| chain.parse_error_in(i, &key, &message))?;
        release_wind_preset_keys(&mut merged, &table, &mut chain.origin);
        release_other_draw_form(&mut merged, &table, &mut chain.origin);
        merge(&mut merged, table, "", i, &mut chain.origin);
    }

    apply_vehicle_preset(&mut merged, &mut chain.origin)
        .map_err(|message| chain.parse_error("vehicle.preset", &message))?;
    crate::scenario::check_core_array_lengths(&merged).map_err(|(path, message)| chain.parse_error(&path, &message))?;
    // Renamed keys (`max_tilt` of the controllers' demand limits) move to
    // their new names before the typed parse, each with a warning.
    let renamed = super::deprecated::rename_keys(&mut merged, |path| chain.origin.get(path).copied()).map_err(
        |(key, value, expected)| ScenarioError::Invalid { path: chain.shown(chain.writer(&key)), key, value, expected },
    )?;
    let mut renamed_warnings = Vec::new();
    for (old, moved_to, warning) in renamed {
        if let Some(new) = moved_to {
            let file = chain.writer(&old);
            chain.origin.insert(new, file);
        }
        let (key, value, message) = warning;
        renamed_warnings.push(Warning { key, value, message });
    }
    let describe = |e: &toml::de::Error, path: &str| {
        let mut message: String = crate::text::shorten_unknown_field(e.message())
            .unwrap_or_else(|| e.message().split_whitespace().collect::<Vec<_>>().join(" "));
        if e.message().starts_with("missing field") {
            let key = if path.is_empty() { String::new() } else { format!(" in `{path}`") };
            message = if chain.layers.len() > 1 {
                format!("{message}{key} (set by no file of the `extends` chain)")
            } else {
                format!("{message}{key}")
            };
        }
        chain.parse_error(path, &message)
    };
    // The gain sections wait for the typed scenario: their vehicle-derived
    // defaults are built for its nominal vehicle (`Scenario::nominal_vehicle`).
    let mut gain_tables = toml::Table::new();
    for key in GainSections::KEYS {
        if let Some(section) = merged.remove(*key) {
            gain_tables.insert(key.to_string(), section);
        }
    }
    let (old_actual, old_rigid, old) = super::deprecated::take_old_tables(&mut merged);
    let prefixed = |prefix: &str, e: &toml::de::Error| {
        let inner = error_path(e);
        describe(e, &if inner.is_empty() { prefix.to_string() } else { format!("{prefix}.{inner}") })
    };
    let old_actual = old_actual
        .map(ftsmc_core::model::QuadrotorParams::deserialize)
        .transpose()
        .map_err(|e| prefixed("actual_plant", &e))?;
    let old_rigid = old_rigid
        .map(crate::vehicle::RigidBodyParams::deserialize)
        .transpose()
        .map_err(|e| prefixed("vehicle.rigid_body", &e))?;
    let mut scenario = Scenario::deserialize(merged).map_err(|e| {
        let path = error_path(&e);
        match with_gain_sections(e.message()) {
            // An unknown top-level key: the known keys include the gain sections.
            Some(message) if !path.contains('.') => chain.parse_error(&path, &message),
            _ => describe(&e, &path),
        }
    })?;
    let deprecations =
        super::deprecated::convert(&mut scenario, old_actual, old_rigid, &old).map_err(|(key, value, expected)| {
            ScenarioError::Invalid { path: chain.shown(chain.writer(&key)), key, value, expected }
        })?;
    import_px4_params(&mut gain_tables, &scenario.nominal_vehicle(), &chain)?;
    scenario.gains = GainSections::take_from(&mut gain_tables, &scenario.nominal_vehicle()).map_err(
        |SectionParseError { section, error }| {
            let inner = error_path(&error);
            let path = if inner.is_empty() { section.to_string() } else { format!("{section}.{inner}") };
            describe(&error, &path)
        },
    )?;
    scenario.limits.apply_overrides(overrides).map_err(|message| ScenarioError::Parse { path: top_name, message })?;
    scenario.validate(&chain.layers[0].shown).map_err(|e| match e {
        ScenarioError::Invalid { key, value, expected, .. } => {
            ScenarioError::Invalid { path: chain.shown(chain.writer(&key)), key, value, expected }
        }
        other => other,
    })?;
    let fitted = fit_trajectory(&mut scenario);
    scenario.check_trajectory_feasibility().map_err(|(key, value, expected)| ScenarioError::Invalid {
        path: chain.shown(chain.writer(&key)),
        key,
        value,
        expected,
    })?;
    let warnings = renamed_warnings
        .into_iter()
        .chain(deprecations.into_iter().map(|(key, value, message)| Warning { key, value, message }))
        .chain(fitted)
        .chain(unit_slip_warnings(&scenario))
        .map(|w| format!("{}: `{}` = {}: {}", chain.shown(chain.writer(&w.key)), w.key, w.value, w.message))
        .collect();
    Ok(Loaded {
        scenario,
        files: chain.layers.iter().map(|l| l.shown.clone()).collect(),
        warnings,
        built_in_base: chain.built_in_base,
    })
}

/// `[reference] time_scale = "fit"`: stretch the trajectory's time by the
/// smallest factor with which the vehicle can fly it
/// ([`crate::trajectory::feasibility::fit`]), and say by how much (a note
/// among the warnings). Runs on a validated scenario; when no factor up to
/// the largest fits, the largest is set and the feasibility check that
/// follows reports what is still exceeded.
fn fit_trajectory(scenario: &mut Scenario) -> Option<Warning> {
    use crate::trajectory::{feasibility, TimeScale};
    if scenario.reference.time_scale != TimeScale::Fit {
        return None;
    }
    let limits = scenario.trajectory_limits();
    let duration = scenario.duration;
    let trajectory = scenario.reference.trajectory.as_mut()?;
    trajectory.check().ok()?;
    let k = feasibility::fit(trajectory, &limits, duration).unwrap_or(feasibility::MAX_STRETCH);
    trajectory.set_stretch(k);
    (k > 1.0).then(|| Warning {
        key: "reference.time_scale".into(),
        value: "\"fit\"".into(),
        message: format!(
            "note: the trajectory's time is stretched by {k:.4} (x{k:.4} slower) to stay within the vehicle's thrust and tilt limits{}",
            trajectory.end().map_or(String::new(), |e| format!("; it now ends at {} s", show(e)))
        ),
    })
}

/// `[pid] px4_params = "FILE.params"`: the PX4 gains of a QGroundControl
/// parameter file (path relative to the file that sets the key), converted
/// for `vehicle` ([`crate::controllers::px4_params`]), become the `[pid]`
/// table; keys the `[pid]` tables of the chain set beside it replace the
/// imported values.
fn import_px4_params(
    gain_tables: &mut toml::Table,
    vehicle: &NominalVehicle,
    chain: &Chain,
) -> Result<(), ScenarioError> {
    use crate::controllers::px4_params;
    const KEY: &str = "pid.px4_params";
    let Some(toml::Value::Table(pid)) = gain_tables.get_mut("pid") else { return Ok(()) };
    let Some(value) = pid.remove("px4_params") else { return Ok(()) };
    let toml::Value::String(file) = value else {
        return Err(chain.parse_error(KEY, "expected a string: the path of a QGroundControl .params file"));
    };
    let dir = chain.layers[chain.writer(KEY)].dir.clone().unwrap_or_default();
    let params = px4_params::read_qgc(&dir.join(&file)).map_err(|e| chain.parse_error(KEY, &e.to_string()))?;
    // The gains are normalised on this scenario's vehicle; a file that
    // describes another airframe would be normalised on the wrong one.
    if let Some(frame) = px4_params::airframe(&params).map_err(|e| chain.parse_error(KEY, &e.to_string()))? {
        if !frame.same_layout_as(&vehicle.geometry) {
            let shown = |p: [[f64; 2]; 4]| {
                p.iter()
                    .map(|[x, y]| format!("({}, {})", show(round4(*x)), show(round4(*y))))
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            return Err(chain.parse_error(
                KEY,
                &format!(
                    "set [vehicle] rotor_positions = the file's layout or remove its CA_ROTOR lines: {file} describes rotors at {} m (x forward, y left), this vehicle has them at {} m, and PX4's torque normalisation depends on the layout (`ftsmc px4 import` writes the file's layout with the gains)",
                    shown(frame.positions),
                    shown(vehicle.geometry.positions())
                ),
            ));
        }
    }
    let gains = px4_params::gains_from_params(&params, vehicle).map_err(|e| chain.parse_error(KEY, &e.to_string()))?;
    let mut table = toml::Table::try_from(gains).map_err(|e| chain.parse_error(KEY, &e.to_string()))?;
    for (key, value) in std::mem::take(pid) {
        table.insert(key, value);
    }
    *pid = table;
    Ok(())
}

/// `x` to 4 significant digits, for messages (positions of a layout).
fn round4(x: f64) -> f64 {
    format!("{x:.4e}").parse().unwrap_or(x)
}

/// A likely unit slip: valid, but probably not what was meant.
#[derive(Clone, Debug, PartialEq)]
pub struct Warning {
    /// Dotted key, e.g. `initial_state.attitude[2]`.
    pub key: String,
    /// The value, as shown.
    pub value: String,
    /// Why it looks wrong.
    pub message: String,
}

const TWO_PI: f64 = 2.0 * core::f64::consts::PI;

/// Angle-valued parts of a yaw reference: constants, step heights,
/// amplitudes, waypoint values and polynomial offsets (not slopes, so a
/// yaw ramp that turns several times does not warn).
fn angle_levels(signal: &Signal, prefix: &str, out: &mut Vec<(String, f64)>) {
    for (k, term) in signal.terms.iter().enumerate() {
        let key = |f: &str| format!("{prefix}.terms[{k}].{f}");
        match term {
            Term::Constant { value } => out.push((key("value"), *value)),
            Term::Step { height, .. } => out.push((key("height"), *height)),
            Term::Sine { amplitude, .. } | Term::Cosine { amplitude, .. } => out.push((key("amplitude"), *amplitude)),
            Term::Polynomial { coefficients } => {
                if let Some(c) = coefficients.first() {
                    out.push((key("coefficients[0]"), *c));
                }
            }
            Term::Waypoints(w) => {
                out.extend(w.values().iter().enumerate().map(|(i, v)| (key(&format!("value[{i}]")), *v)));
            }
            Term::Piecewise { pieces } => {
                for (j, p) in pieces.iter().enumerate() {
                    angle_levels(&p.signal, &key(&format!("pieces[{j}].signal")), out);
                }
            }
        }
    }
}

/// Warnings for deprecated keys (`simulation.max_rotor_speed`, naming the
/// key that replaces it) and for values that are valid but look like unit slips: angles
/// beyond 2π (degrees for radians), a payload above 10× the vehicle's
/// mass (grams, or a typo), Monte Carlo mass or payload draws far from the
/// vehicle's mass, windows that start after the end of the run.
pub fn unit_slip_warnings(s: &Scenario) -> Vec<Warning> {
    let mut out = Vec::new();
    let mut warn = |key: String, value: String, message: String| out.push(Warning { key, value, message });
    let degrees = |v: f64| {
        format!("angles are in radians (|angle| > 2π; if degrees were meant, {}° = {:.4} rad)", show(v), v.to_radians())
    };
    if let (Some(w), None) = (s.simulation.max_rotor_speed, &s.actuators) {
        warn(
            "simulation.max_rotor_speed".into(),
            show(w),
            format!(
                "deprecated: write [actuators] max_rotor_speed = {}, mixer = \"clamp\" (the per-rotor clamp this key means, on every truth model)",
                show(w)
            ),
        );
    }
    for (i, a) in s.initial_state.attitude.iter().enumerate() {
        if a.abs() > TWO_PI {
            warn(format!("initial_state.attitude[{i}]"), show(*a), degrees(*a));
        }
    }
    let mut levels = Vec::new();
    angle_levels(&s.reference.psi, "reference.psi", &mut levels);
    for (key, v) in levels {
        if v.abs() > TWO_PI {
            warn(key, show(v), degrees(v));
        }
    }
    if let Some(p) = &s.payload {
        let (mass, which) = s.true_mass();
        if p.mass > 10.0 * mass {
            warn(
                "payload.mass".into(),
                format!("{} kg", show(p.mass)),
                format!("more than 10 × the vehicle's mass ({which} = {} kg); masses are in kg", show(mass)),
            );
        }
        if p.start > s.duration {
            warn(
                "payload.start".into(),
                format!("{} s", show(p.start)),
                format!("after the end of the run (duration = {} s): the payload never acts", show(s.duration)),
            );
        }
    }
    if let Some(mc) = &s.montecarlo {
        // Refused beyond the plausible band (validation); far draws warn.
        for (key, value, message) in mc.absolute(s).vehicle_band(s).unwrap_or_default() {
            warn(key, value, message);
        }
    }
    let after_end = |start: f64| start > s.duration;
    let mut windows: Vec<(String, &Signal)> =
        s.disturbance.named().into_iter().map(|(n, sig)| (format!("disturbance.{n}"), sig)).collect();
    if let Some(v) = &s.inertia_variation {
        windows.push(("inertia_variation".into(), v));
    }
    for (name, sig) in windows {
        if let Some([start, end]) = sig.window {
            if after_end(start) {
                warn(
                    format!("{name}.window"),
                    format!("[{}, {}]", show(start), show(end)),
                    format!("starts after the end of the run (duration = {} s): it never acts", show(s.duration)),
                );
            }
        }
    }
    if let Some([start, end]) = s.simulation.metrics_window {
        if after_end(start) {
            warn(
                "simulation.metrics_window".into(),
                format!("[{}, {}]", show(start), show(end)),
                format!("starts after the end of the run (duration = {} s): its ISE is 0", show(s.duration)),
            );
        }
    }
    out
}
