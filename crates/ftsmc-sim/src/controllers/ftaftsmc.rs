//! FTAFTSMC, the paper's controller (§3, Eq. 9–17 and 44), and its variant
//! with the mass adaptation switched off; both read `[ftaftsmc]`.

use ftsmc_core::cascade::{Cascade, MassAdaptation};
use ftsmc_core::ftaftsmc::{FtaftsmcAxis, FtaftsmcGains};
use serde::{Deserialize, Serialize};

use super::{check_axes, AxisLawVisitor, BoxedController, BuildContext, Declaration, GainSection, InvalidGain};
use crate::axes::AxisSet;

/// FTAFTSMC configuration, `[ftaftsmc]`: mass adaptation and per-channel
/// gains (Tables 4–5).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct FtaftsmcConfig {
    /// Mass adaptation of §3.2 (β1, β2 of Table 5).
    pub mass_adaptation: MassAdaptation,
    /// x channel (Table 5).
    pub x: FtaftsmcGains,
    /// y channel (Table 5).
    pub y: FtaftsmcGains,
    /// z channel (Table 5).
    pub z: FtaftsmcGains,
    /// Roll channel (Table 4).
    pub phi: FtaftsmcGains,
    /// Pitch channel (Table 4).
    pub theta: FtaftsmcGains,
    /// Yaw channel (Table 4).
    pub psi: FtaftsmcGains,
}

impl FtaftsmcConfig {
    /// The six channel gain sets.
    pub fn gains(&self) -> AxisSet<FtaftsmcGains> {
        AxisSet { x: self.x, y: self.y, z: self.z, phi: self.phi, theta: self.theta, psi: self.psi }
    }
}

impl Default for FtaftsmcConfig {
    /// Tables 4–5 with the mass adaptation on.
    fn default() -> Self {
        Self {
            mass_adaptation: MassAdaptation::PAPER,
            x: FtaftsmcGains::PAPER_XY,
            y: FtaftsmcGains::PAPER_XY,
            z: FtaftsmcGains::PAPER_Z,
            phi: FtaftsmcGains::PAPER_ROLL_PITCH,
            theta: FtaftsmcGains::PAPER_ROLL_PITCH,
            psi: FtaftsmcGains::PAPER_YAW,
        }
    }
}

impl GainSection for FtaftsmcConfig {
    const KEY: &'static str = "ftaftsmc";
    const CORE_ARRAYS: &'static [(&'static str, usize)] = &[("mass_adaptation.alpha_hat_bounds", 2)];

    fn defaults() -> Self {
        Self::default()
    }

    fn check(&self) -> Result<(), InvalidGain> {
        self.mass_adaptation.check().map_err(|e| InvalidGain::at("mass_adaptation", e))?;
        check_axes(&self.gains(), FtaftsmcGains::check)
    }
}

/// The cascade of six FTAFTSMC laws with mass adaptation `mass_adaptation`.
fn cascade(
    config: &FtaftsmcConfig,
    mass_adaptation: MassAdaptation,
    ctx: &BuildContext,
) -> Result<BoxedController, String> {
    let laws = config.gains().to_array().map(FtaftsmcAxis::new);
    Ok(Box::new(Cascade::new(ctx.cascade_config(mass_adaptation), laws).map_err(|e| e.to_string())?))
}

/// `ftaftsmc`: the paper's controller.
pub struct Ftaftsmc;

impl Declaration for Ftaftsmc {
    const NAME: &'static str = "ftaftsmc";
    const LABEL: &'static str = "FTAFTSMC";
    const DESCRIPTION: &'static str =
        "fixed-time adaptive fast terminal SMC with mass adaptation (the paper's controller)";
    type Section = FtaftsmcConfig;

    fn build(config: &FtaftsmcConfig, ctx: &BuildContext) -> Result<BoxedController, String> {
        cascade(config, config.mass_adaptation, ctx)
    }

    fn visit_axis_law<V: AxisLawVisitor>(config: &FtaftsmcConfig, axis: usize, visitor: V) -> Option<V::Output> {
        Some(visitor.visit(FtaftsmcAxis::new(config.gains().to_array()[axis])))
    }

    /// Eq. 38: `1/(λ2 (q2 − 1)) + 1/(γ2 (1 − p2))`.
    fn reaching_time_bound(config: &FtaftsmcConfig, axis: usize) -> Option<f64> {
        Some(config.gains().to_array()[axis].reaching_time_bound())
    }
}

/// `ftaftsmc-no-mass`: FTAFTSMC with the mass adaptation of §3.2 switched
/// off (`U1 = u1`), the same `[ftaftsmc]` gains otherwise.
pub struct FtaftsmcNoMass;

impl Declaration for FtaftsmcNoMass {
    const NAME: &'static str = "ftaftsmc-no-mass";
    const LABEL: &'static str = "FTAFTSMC (no mass adaptation)";
    const DESCRIPTION: &'static str = "FTAFTSMC with the mass adaptation of §3.2 switched off (U1 = u1)";
    type Section = FtaftsmcConfig;

    fn build(config: &FtaftsmcConfig, ctx: &BuildContext) -> Result<BoxedController, String> {
        cascade(config, MassAdaptation { enabled: false, ..config.mass_adaptation }, ctx)
    }

    fn visit_axis_law<V: AxisLawVisitor>(config: &FtaftsmcConfig, axis: usize, visitor: V) -> Option<V::Output> {
        Ftaftsmc::visit_axis_law(config, axis, visitor)
    }

    fn reaching_time_bound(config: &FtaftsmcConfig, axis: usize) -> Option<f64> {
        Ftaftsmc::reaching_time_bound(config, axis)
    }
}
