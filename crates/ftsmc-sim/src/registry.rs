//! Controllers by name, for the rest of the crate and its users: build one
//! with the gains of a scenario, fly it, label it. The controllers
//! themselves are declared in [`crate::controllers`] (one file each, one
//! line in its list); this module only adds the scenario around them.

use crate::scenario::Scenario;

pub use crate::controllers::{BoxedController, CONTROLLERS, DECLARED, PAPER_CONTROLLERS};

/// Labels of result variants that are not controllers of their own
/// (`ftsmc reproduce` flies `ftaftsmc` on modified scenarios under these keys).
const VARIANT_LABELS: [(&str, &str); 2] = [
    ("ftaftsmc-tuned", "FTAFTSMC (tuned x/y reaching law)"),
    ("ftaftsmc-zero-derivatives", "FTAFTSMC (zero attitude-reference derivatives)"),
];

/// Human-readable label for figures and tables: the declared
/// [`crate::controllers::Declaration::LABEL`], a result variant's label, or
/// `name` itself.
pub fn label(name: &str) -> &str {
    crate::controllers::label(name)
        .or_else(|| VARIANT_LABELS.iter().find(|(n, _)| *n == name).map(|(_, l)| *l))
        .unwrap_or(name)
}

/// The registered controllers that declare tunable parameters (their
/// list line's `tune`, see [`crate::controllers::tunable`]), in list
/// order: what `ftsmc tune -c all` tunes. A controller declared with
/// `tune_param::none` is left out.
pub fn tunable_controllers() -> Vec<&'static str> {
    crate::controllers::tunable::tunable_in(DECLARED)
}

/// `Ok(())` for a registered name; otherwise the list of known names.
pub fn check_name(name: &str) -> Result<(), String> {
    crate::controllers::check_name(name)
}

/// A list of controller names as a front end received it (`-c` of the CLI,
/// `controllers=` of the Python functions), checked here once for every
/// front end: [`ControllerList::check`] refuses an empty list and an empty
/// name (`-c ''`, `-c ,`, `-c pid,`), [`ControllerList::check_known`] also
/// an unregistered one.
#[derive(Clone, Copy, Debug)]
pub struct ControllerList<'a> {
    /// The argument the names came from, as the user wrote it (`-c/--controllers`, `controllers`).
    pub argument: &'a str,
    /// The names, one per entry (a comma-separated value split at its commas, empty entries kept).
    pub names: &'a [String],
}

/// Why a [`ControllerList`] is refused; each names the argument and the value.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ControllerListError {
    /// No name at all.
    #[error(
        "{argument}: no controller named (an empty list): expected a name such as `pid`, or a comma-separated \
         list such as `pid,se3` (`ftsmc list` lists them)"
    )]
    Empty {
        /// The argument.
        argument: String,
    },
    /// An entry that is empty or only spaces.
    #[error(
        "{argument} `{value}`: no controller named in entry {entry} of {entries}: expected a name such as `pid`, \
         or a comma-separated list such as `pid,se3` (`ftsmc list` lists them)"
    )]
    EmptyName {
        /// The argument.
        argument: String,
        /// The whole value, entries joined by commas.
        value: String,
        /// The empty entry, counted from 1.
        entry: usize,
        /// Entries in the value.
        entries: usize,
    },
    /// A name no controller is registered under.
    #[error("unknown controller `{name}` (known: {known})")]
    Unknown {
        /// The name.
        name: String,
        /// The registered names, comma-separated.
        known: String,
    },
}

impl ControllerList<'_> {
    /// Refuses an empty list and an empty (or blank) name.
    pub fn check(&self) -> Result<(), ControllerListError> {
        if self.names.is_empty() {
            return Err(ControllerListError::Empty { argument: self.argument.to_string() });
        }
        if let Some(i) = self.names.iter().position(|n| n.trim().is_empty()) {
            return Err(ControllerListError::EmptyName {
                argument: self.argument.to_string(),
                value: self.names.join(","),
                entry: i + 1,
                entries: self.names.len(),
            });
        }
        Ok(())
    }

    /// [`check`](Self::check), then every name registered ([`check_name`]).
    pub fn check_known(&self) -> Result<(), ControllerListError> {
        self.check()?;
        for name in self.names {
            check_name(name).map_err(|known| ControllerListError::Unknown { name: name.clone(), known })?;
        }
        Ok(())
    }
}

/// [`ControllerList::check_known`] of `names` given as `argument`.
pub fn check_controllers(argument: &str, names: &[String]) -> Result<(), ControllerListError> {
    ControllerList { argument, names }.check_known()
}

/// Build the controller `name` with the gains of `scenario`. Returns the
/// list of known names when `name` is not registered.
pub fn build(name: &str, scenario: &Scenario) -> Result<BoxedController, String> {
    crate::controllers::build(name, &scenario.gains, &scenario.build_context())
}

/// The declared controller `name` with the gains of `scenario` on `N`
/// lanes ([`ftsmc_core::lanes`]): every lane a flight of that controller.
pub fn build_lanes<const N: usize>(
    name: &str,
    scenario: &Scenario,
) -> Result<crate::controllers::LaneController<N>, String> {
    crate::controllers::build_lanes::<N>(name, &scenario.gains, &scenario.build_context())
}

/// True when flights of `a` and `b` may share one batch of lanes: the same
/// controller gains, nominal plant, cascade settings and simulation
/// settings (a Monte Carlo run's sampled true vehicle, payload,
/// disturbances and initial state may differ).
pub fn lane_compatible(a: &Scenario, b: &Scenario) -> bool {
    a.gains == b.gains
        && a.build_context() == b.build_context()
        && a.simulation == b.simulation
        && a.vehicle.model == b.vehicle.model
        && a.sensors.is_some() == b.sensors.is_some()
        && a.wind.is_some() == b.wind.is_some()
        && a.duration == b.duration
}

/// Build controller `name` for `scenario` and fly it; the output's
/// `controller` field is `name`.
pub fn run(name: &str, scenario: &Scenario, options: crate::run::RunOptions) -> Result<crate::run::RunOutput, String> {
    run_as(name, name, scenario, options)
}

/// [`run`], the output's `controller` field `label` (a variant's name).
pub fn run_as(
    name: &str,
    label: &str,
    scenario: &Scenario,
    options: crate::run::RunOptions,
) -> Result<crate::run::RunOutput, String> {
    let controller = build(name, scenario)?;
    Ok(crate::run::Flight::new(scenario.clone(), controller, options).named(label).run())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builds_every_listed_name() {
        let scenario = Scenario::paper_scenarios().remove(0);
        for (name, _) in CONTROLLERS {
            assert!(build(name, &scenario).is_ok(), "{name} is declared but not built");
        }
        let err = build("no-such-controller", &scenario).err().expect("unknown name rejected");
        assert!(err.contains("ftaftsmc") && err.contains("tsm-sta"), "{err}");
    }

    #[test]
    fn labels_come_from_the_declarations_and_the_variants() {
        assert_eq!(label("ranftsmc"), "RANFTSMC [19]");
        assert_eq!(label("ftaftsmc-tuned"), "FTAFTSMC (tuned x/y reaching law)");
        assert_eq!(label("unknown"), "unknown");
    }

    #[test]
    fn an_empty_controller_list_or_name_is_refused_naming_the_argument_and_value() {
        let list = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let e = ControllerList { argument: "-c", names: &[] }.check().unwrap_err();
        assert!(e.to_string().starts_with("-c: no controller named"), "{e}");
        let names = list(&["pid", " "]);
        let e = ControllerList { argument: "controllers", names: &names }.check().unwrap_err();
        assert!(e.to_string().starts_with("controllers `pid, `: no controller named in entry 2 of 2"), "{e}");
        let e = check_controllers("-c", &list(&["pid", "nope"])).unwrap_err();
        assert!(matches!(e, ControllerListError::Unknown { ref name, .. } if name == "nope"), "{e}");
        assert_eq!(check_controllers("-c", &list(&["pid", "se3"])), Ok(()));
        // check() alone accepts a name it does not know (compare's gain files).
        assert_eq!(ControllerList { argument: "-c", names: &list(&["x.tuned.toml"]) }.check(), Ok(()));
    }
}
