//! Controllers by name. Adding a controller: implement
//! [`ftsmc_core::law::AxisLaw`] in the core crate, give it a gain section in
//! [`crate::scenario::Scenario`], and add one arm here.

use ftsmc_core::cascade::{Cascade, CascadeConfig, Controller, MassAdaptation};
use ftsmc_core::ftaftsmc::FtaftsmcAxis;
use ftsmc_core::ranftsmc::RanftsmcAxis;
use ftsmc_core::tsm_sta::TsmStaAxis;

use crate::scenario::Scenario;

/// The three controllers compared in the paper, in table order.
pub const PAPER_CONTROLLERS: [&str; 3] = ["ranftsmc", "tsm-sta", "ftaftsmc"];

/// Every registered name (with a one-line description).
pub const CONTROLLERS: [(&str, &str); 4] = [
    ("ftaftsmc", "fixed-time adaptive fast terminal SMC with mass adaptation (the paper's controller)"),
    ("ftaftsmc-no-mass", "FTAFTSMC with the mass adaptation of §3.2 switched off (U1 = u1)"),
    ("ranftsmc", "robust adaptive nonsingular fast terminal SMC (Labbadi & Cherkaoui 2020, ref. [19])"),
    ("tsm-sta", "nonsingular terminal sliding surface with super-twisting reaching law (ref. [2])"),
];

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
    if CONTROLLERS.iter().any(|(n, _)| *n == name) {
        Ok(())
    } else {
        Err(CONTROLLERS.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", "))
    }
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
pub fn run(
    name: &str,
    scenario: &Scenario,
    options: crate::simulate::RunOptions,
) -> Result<crate::simulate::RunOutput, String> {
    let mut controller = build(name, scenario)?;
    let mut out = crate::simulate::simulate(scenario, controller.as_mut(), options);
    out.controller = name.to_string();
    Ok(out)
}

/// Sweep the decoupled channel `axis` (0..6 = x, y, z, φ, θ, ψ) of
/// controller `name` with the gains of `scenario` (see [`crate::fixed_time`]).
pub fn sweep_channel(
    name: &str,
    scenario: &Scenario,
    axis: usize,
    settings: &crate::fixed_time::SweepSettings,
    sampling: crate::fixed_time::Sampling,
) -> Result<Vec<crate::fixed_time::ChannelTimes>, String> {
    use crate::fixed_time::sweep;
    check_name(name)?;
    Ok(match name {
        "ftaftsmc" | "ftaftsmc-no-mass" => {
            sweep(&FtaftsmcAxis::new(scenario.ftaftsmc.gains().to_array()[axis]), settings, sampling)
        }
        "ranftsmc" => sweep(&RanftsmcAxis::new(scenario.ranftsmc.to_array()[axis]), settings, sampling),
        "tsm-sta" => sweep(&TsmStaAxis::new(scenario.tsm_sta.to_array()[axis]), settings, sampling),
        _ => unreachable!("check_name accepted an unhandled name"),
    })
}

/// The paper's reaching-time bound (Eq. 38) for `axis` of controller `name`,
/// when the controller has one (FTAFTSMC only; the baselines are finite-time
/// with initial-condition-dependent bounds, Eq. 36–37).
pub fn reaching_time_bound(name: &str, scenario: &Scenario, axis: usize) -> Option<f64> {
    match name {
        "ftaftsmc" | "ftaftsmc-no-mass" => Some(scenario.ftaftsmc.gains().to_array()[axis].reaching_time_bound()),
        _ => None,
    }
}
