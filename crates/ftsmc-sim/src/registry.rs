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

/// `Ok(())` for a registered name; otherwise the list of known names.
pub fn check_name(name: &str) -> Result<(), String> {
    crate::controllers::check_name(name)
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
}
