//! What `ftsmc tune` may change in each controller: named parameters with
//! bounds and scale, declared in the controller's own file
//! (`tune_parameters()` in `ftaftsmc.rs`, `pid.rs`, …) and named by the
//! controller's line in the list of `controllers/mod.rs`
//! ([`super::Declared::tune_parameters`]); this module only looks them up,
//! so a new controller cannot be missed here.
//!
//! Every declared parameter is a **factor** on the gains the scenario
//! already has (its start is 1: the controller's defaults, or the gains the
//! scenario file sets), searched on a log scale between `low` and `high`.
//! Applying a parameter multiplies one or more gains; applying the same
//! values to the same scenario always gives the same gains, and the factor
//! 1 leaves them bit for bit as they were.
//!
//! # Adding a parameter
//!
//! Append a [`TuneParam`] to the controller's `tune_parameters()`: a name
//! (unique for the controller; it is a `[tune]` key and a `history.csv`
//! column), one line of documentation, bounds on the factor and the
//! function that applies it (`apply(target, factor)` multiplies the gains
//! it stands for). A user adds a one-off parameter without code through
//! `[[tune.extra]]` (absolute values): any gain of the tuned controller's
//! own section except the section's declared limits
//! ([`super::GainSection::LIMITS`]), and the command filter's
//! `natural_frequency` and `damping` for a controller that declares the
//! `command_filter` parameter ([`check_extra_key`]). Nothing else — the
//! seed, the duration, rates, the vehicle, structural keys — is tunable:
//! the search must not change what it is judged on.

pub use super::tune_param::{TuneParam, TuneTarget, COMMAND_FILTER};

/// The declared parameters of controller `name`; `Err(known names)` for an
/// unknown one.
pub fn parameters(name: &str) -> Result<Vec<TuneParam>, String> {
    parameters_in(super::DECLARED, name)
}

/// [`parameters`] of `name` among the declarations `declared` (a list the
/// `declare_controllers!` macro generated).
pub fn parameters_in(declared: &[super::Declared], name: &str) -> Result<Vec<TuneParam>, String> {
    match declared.iter().find(|d| d.name == name) {
        Some(d) => Ok((d.tune_parameters)()),
        None => Err(declared.iter().map(|d| d.name).collect::<Vec<_>>().join(", ")),
    }
}

/// The names of the controllers among `declared` that declare at least one
/// tunable parameter, in list order (what `ftsmc tune -c all` tunes).
pub fn tunable_in(declared: &[super::Declared]) -> Vec<&'static str> {
    declared.iter().filter(|d| !(d.tune_parameters)().is_empty()).map(|d| d.name).collect()
}

/// The `[cascade]` keys `[[tune.extra]]` may search, for a controller that
/// declares the [`COMMAND_FILTER`] parameter.
pub const CASCADE_GAINS: [&str; 2] = ["cascade.command_filter.natural_frequency", "cascade.command_filter.damping"];

/// Whether `[[tune.extra]]` may search the dotted `key` for controller
/// `name`: a key below the controller's own gain section (`pid.rate_p.0`,
/// `ftaftsmc.x.lambda`) that is not one of the section's limits, or one of
/// [`CASCADE_GAINS`] for a controller that uses the command filter.
/// `Err` says why not (the caller names the key and where it was given).
/// Whether the key holds a number is checked on the scenario.
pub fn check_extra_key(name: &str, key: &str) -> Result<(), String> {
    let declared = super::DECLARED
        .iter()
        .find(|d| d.name == name)
        .ok_or_else(|| format!("unknown controller `{name}` (known: {})", super::known_names()))?;
    let uses_filter = parameters(name)?.iter().any(|p| p.name == COMMAND_FILTER.name);
    if CASCADE_GAINS.contains(&key) {
        return if uses_filter { Ok(()) } else { Err(format!("{name} has no command filter")) };
    }
    let section = declared.section;
    let below = key.strip_prefix(section).and_then(|rest| rest.strip_prefix('.'));
    let Some(below) = below.filter(|b| !b.is_empty()) else {
        let filter = if uses_filter { " and cascade.command_filter.{natural_frequency,damping}" } else { "" };
        return Err(format!("not a gain of {name}: its tunable keys are the numbers of [{section}]{filter}"));
    };
    let limits = super::GainSections::LIMITS.iter().find(|(k, _)| *k == section).map_or(&[][..], |(_, l)| *l);
    if let Some(limit) = limits.iter().find(|l| below == **l || below.starts_with(&format!("{l}."))) {
        return Err(format!("`{section}.{limit}` is a limit of the vehicle, not a gain of {name}"));
    }
    Ok(())
}

/// Whether some declared controller may search `key` with `[[tune.extra]]`
/// ([`check_extra_key`]): how a scenario file's `[tune]` is checked when it
/// is loaded, before the tuned controller is known. `Err` says why not.
pub fn check_extra_key_any(key: &str) -> Result<(), String> {
    if super::DECLARED.iter().any(|d| check_extra_key(d.name, key).is_ok()) {
        return Ok(());
    }
    let first = key.split('.').next().unwrap_or("");
    // A key in a gain section: the reason its controllers give.
    if let Some(d) = super::DECLARED.iter().find(|d| d.section == first) {
        return check_extra_key(d.name, key);
    }
    Err(format!(
        "not a controller gain: the tunable keys are the numbers of [{}] and cascade.command_filter.{{natural_frequency,damping}}",
        super::GainSections::KEYS.join("], [")
    ))
}
