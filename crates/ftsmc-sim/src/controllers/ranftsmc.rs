//! RANFTSMC, the robust adaptive nonsingular fast terminal SMC of Labbadi &
//! Cherkaoui 2020 (the paper's ref. \[19\]); reads `[ranftsmc]`.

use ftsmc_core::cascade::{Cascade, MassAdaptation};
use ftsmc_core::ranftsmc::{RanftsmcAxis, RanftsmcGains};

use super::{check_axes, AxisLawVisitor, BoxedController, BuildContext, Declaration, GainSection, InvalidGain};
use crate::axes::AxisSet;

/// `[ranftsmc.x]` … `[ranftsmc.psi]`: one gain set per channel (default:
/// the published gains, position on x, y, z and attitude on φ, θ, ψ).
impl GainSection for AxisSet<RanftsmcGains> {
    const KEY: &'static str = "ranftsmc";

    fn defaults() -> Self {
        AxisSet::split(RanftsmcGains::PAPER_POSITION, RanftsmcGains::PAPER_ATTITUDE)
    }

    fn check(&self) -> Result<(), InvalidGain> {
        check_axes(self, RanftsmcGains::check)
    }
}

/// `ranftsmc`: six RANFTSMC laws in the cascade, no mass adaptation.
pub struct Ranftsmc;

impl Declaration for Ranftsmc {
    const NAME: &'static str = "ranftsmc";
    const LABEL: &'static str = "RANFTSMC [19]";
    const DESCRIPTION: &'static str =
        "robust adaptive nonsingular fast terminal SMC (Labbadi & Cherkaoui 2020, ref. [19])";
    type Section = AxisSet<RanftsmcGains>;

    fn build(gains: &Self::Section, ctx: &BuildContext) -> Result<BoxedController, String> {
        let laws = gains.to_array().map(RanftsmcAxis::new);
        Ok(Box::new(Cascade::new(ctx.cascade_config(MassAdaptation::OFF), laws).map_err(|e| e.to_string())?))
    }

    fn visit_axis_law<V: AxisLawVisitor>(gains: &Self::Section, axis: usize, visitor: V) -> Option<V::Output> {
        Some(visitor.visit(RanftsmcAxis::new(gains.to_array()[axis])))
    }
}
