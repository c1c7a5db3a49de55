//! TSM-STA, a nonsingular terminal sliding surface with a super-twisting
//! reaching law (the paper's ref. \[2\]); reads `[tsm-sta]`.

use ftsmc_core::cascade::{Cascade, MassAdaptation};
use ftsmc_core::tsm_sta::{TsmStaAxis, TsmStaGains};

use super::{check_axes, AxisLawVisitor, BoxedController, BuildContext, Declaration, GainSection, InvalidGain};
use crate::axes::AxisSet;

/// `[tsm-sta.x]` … `[tsm-sta.psi]`: one gain set per channel (default: the
/// gains of the tuning procedure in `analysis::tuning`, position on x, y, z
/// and attitude on φ, θ, ψ).
impl GainSection for AxisSet<TsmStaGains> {
    const KEY: &'static str = "tsm-sta";

    fn defaults() -> Self {
        AxisSet::split(TsmStaGains::DEFAULT_POSITION, TsmStaGains::DEFAULT_ATTITUDE)
    }

    fn check(&self) -> Result<(), InvalidGain> {
        check_axes(self, TsmStaGains::check)
    }
}

/// `tsm-sta`: six TSM-STA laws in the cascade, no mass adaptation.
pub struct TsmSta;

impl Declaration for TsmSta {
    const NAME: &'static str = "tsm-sta";
    const LABEL: &'static str = "TSM-STA [2]";
    const DESCRIPTION: &'static str =
        "nonsingular terminal sliding surface with super-twisting reaching law (ref. [2])";
    type Section = AxisSet<TsmStaGains>;

    fn build(gains: &Self::Section, ctx: &BuildContext) -> Result<BoxedController, String> {
        let laws = gains.to_array().map(TsmStaAxis::new);
        Ok(Box::new(Cascade::new(ctx.cascade_config(MassAdaptation::OFF), laws).map_err(|e| e.to_string())?))
    }

    fn visit_axis_law<V: AxisLawVisitor>(gains: &Self::Section, axis: usize, visitor: V) -> Option<V::Output> {
        Some(visitor.visit(TsmStaAxis::new(gains.to_array()[axis])))
    }
}
