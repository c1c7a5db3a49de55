//! Controllers by name. Adding a controller: implement
//! [`ftsmc_core::law::AxisLaw`] in the core crate, give it a gain section in
//! [`crate::scenario::Scenario`], and add one arm here.

use ftsmc_core::cascade::{Cascade, CascadeConfig, Controller, MassAdaptation};
use ftsmc_core::ftaftsmc::FtaftsmcAxis;
use ftsmc_core::ranftsmc::RanftsmcAxis;
use ftsmc_core::tsm_sta::TsmStaAxis;

use crate::scenario::Scenario;

pub use crate::names::{CONTROLLERS, PAPER_CONTROLLERS};

/// Human-readable label for figures and tables.
pub fn label(name: &str) -> &str {
    match name {
        "ftaftsmc" => "FTAFTSMC",
        "ftaftsmc-no-mass" => "FTAFTSMC (no mass adaptation)",
        "ftaftsmc-tuned" => "FTAFTSMC (tuned x/y reaching law)",
        "ftaftsmc-zero-derivatives" => "FTAFTSMC (zero attitude-reference derivatives)",
        "ranftsmc" => "RANFTSMC [19]",
        "tsm-sta" => "TSM-STA [2]",
        other => other,
    }
}

/// `Ok(())` for a registered name; otherwise the list of known names.
pub fn check_name(name: &str) -> Result<(), String> {
    crate::names::check_controller(name)
}

/// A boxed controller ready to fly.
pub type BoxedController = Box<dyn Controller + Send>;

/// Build the controller `name` with the gains of `scenario`. Returns the
/// list of known names when `name` is not registered.
pub fn build(name: &str, scenario: &Scenario) -> Result<BoxedController, String> {
    check_name(name)?;
    let config = |mass_adaptation: MassAdaptation| CascadeConfig {
        model: scenario.plant,
        settings: scenario.cascade,
        mass_adaptation,
    };
    Ok(match name {
        "ftaftsmc" | "ftaftsmc-no-mass" => {
            let mut ma = scenario.ftaftsmc.mass_adaptation;
            if name == "ftaftsmc-no-mass" {
                ma.enabled = false;
            }
            let laws = scenario.ftaftsmc.gains().to_array().map(FtaftsmcAxis::new);
            Box::new(Cascade::new(config(ma), laws).map_err(|e| e.to_string())?)
        }
        "ranftsmc" => {
            let laws = scenario.ranftsmc.to_array().map(RanftsmcAxis::new);
            Box::new(Cascade::new(config(MassAdaptation::OFF), laws).map_err(|e| e.to_string())?)
        }
        "tsm-sta" => {
            let laws = scenario.tsm_sta.to_array().map(TsmStaAxis::new);
            Box::new(Cascade::new(config(MassAdaptation::OFF), laws).map_err(|e| e.to_string())?)
        }
        _ => unreachable!("check_name accepted an unhandled name"),
    })
}

/// Build controller `name` for `scenario` and fly it; the output's
/// `controller` field is `name`.
pub fn run(name: &str, scenario: &Scenario, options: crate::run::RunOptions) -> Result<crate::run::RunOutput, String> {
    let mut controller = build(name, scenario)?;
    let mut out = crate::run::simulate(scenario, controller.as_mut(), options);
    out.controller = name.to_string();
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builds_every_listed_name() {
        let scenario = Scenario::paper_scenarios().remove(0);
        for (name, _) in CONTROLLERS {
            assert!(build(name, &scenario).is_ok(), "{name} is listed in names.rs but not built");
        }
        assert!(build("no-such-controller", &scenario).is_err());
    }
}
