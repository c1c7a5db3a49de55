//! The two shapes most controllers share, declared once.
//!
//! - [`CascadeOf`]: six per-axis sliding laws in the cascade of
//!   `ftsmc_core::cascade` (position on x, y, z → desired roll and pitch →
//!   attitude on φ, θ, ψ), no mass adaptation, read from one `[KEY]` table
//!   with a gain set per channel (`[KEY.x]` … `[KEY.psi]`). RANFTSMC and
//!   TSM-STA are this; a new per-axis law is one [`ChannelGains`] impl.
//! - [`FullState`]: a full-state controller of `ftsmc-core` built from the
//!   nominal plant and one gain section. PID and SE(3) are this; a new one
//!   is one [`FullStateGains`] impl (with its [`GainSection`]).
//!
//! Both fly one flight on `f64` and `N` flights on `Lanes<N>` from the same
//! generic constructor, the lane form on the detected instruction set
//! ([`on_isa::OnIsa`]).

use core::marker::PhantomData;

use ftsmc_core::cascade::{Cascade, Controller, MassAdaptation};
use ftsmc_core::lanes::{Lanes, Real};
use ftsmc_core::law::{AxisLaw, GainError};
use ftsmc_core::model::QuadrotorParams;
use serde::de::DeserializeOwned;
use serde::Serialize;

use super::{
    check_axes, on_isa, AxisLawVisitor, BoxedController, BuildContext, Declaration, GainSection, InvalidGain,
    LaneController,
};
use crate::axes::AxisSet;

/// `built` boxed as a lane controller whose updates run on the detected
/// instruction set, or the build error as text.
pub fn on_lanes<C, const N: usize>(built: Result<C, GainError>) -> Option<Result<LaneController<N>, String>>
where
    C: Controller<Lanes<N>> + Send + 'static,
{
    Some(built.map(|c| Box::new(on_isa::OnIsa::detected(c)) as LaneController<N>).map_err(|e| e.to_string()))
}

/// The gains of one channel of a per-axis sliding law, with what declares
/// the controller that flies six of them in the cascade ([`CascadeOf`]).
pub trait ChannelGains:
    Copy + core::fmt::Debug + PartialEq + Serialize + DeserializeOwned + Send + Sync + 'static
{
    /// TOML key of the `[KEY]` table (`[KEY.x]` … `[KEY.psi]`).
    const KEY: &'static str;
    /// Registry name ([`Declaration::NAME`]).
    const NAME: &'static str;
    /// Label for figures and tables ([`Declaration::LABEL`]).
    const LABEL: &'static str;
    /// One line for `ftsmc list` ([`Declaration::DESCRIPTION`]).
    const DESCRIPTION: &'static str;
    /// The channel law on the number type `R` (`f64`: one flight).
    type Law<R: Real>: AxisLaw<R> + Clone + Send + 'static;
    /// The built-in gains of the six channels.
    fn defaults() -> AxisSet<Self>;
    /// Range-check one channel's gains.
    fn check(&self) -> Result<(), GainError>;
    /// A fresh channel law with these gains on every lane (not validated:
    /// the cascade's constructor checks them).
    fn law<R: Real>(self) -> Self::Law<R>;
}

/// `[KEY.x]` … `[KEY.psi]` of a per-axis law: one gain set per channel.
impl<G: ChannelGains> GainSection for AxisSet<G> {
    const KEY: &'static str = G::KEY;

    fn defaults() -> Self {
        G::defaults()
    }

    fn check(&self) -> Result<(), InvalidGain> {
        check_axes(self, G::check)
    }
}

/// Six channel laws of gains `G` in the cascade, no mass adaptation.
pub struct CascadeOf<G>(PhantomData<G>);

impl<G: ChannelGains> CascadeOf<G> {
    /// The cascade on the number type `R`, after validating the gains, the
    /// nominal model and the cascade settings.
    fn cascade<R: Real>(gains: &AxisSet<G>, ctx: &BuildContext) -> Result<Cascade<G::Law<R>, R>, GainError> {
        Cascade::with_laws(ctx.cascade_config(MassAdaptation::OFF), gains.to_array().map(G::law::<R>))
    }
}

impl<G: ChannelGains> Declaration for CascadeOf<G> {
    const NAME: &'static str = G::NAME;
    const LABEL: &'static str = G::LABEL;
    const DESCRIPTION: &'static str = G::DESCRIPTION;
    type Section = AxisSet<G>;

    fn build(gains: &Self::Section, ctx: &BuildContext) -> Result<BoxedController, String> {
        Ok(Box::new(Self::cascade::<f64>(gains, ctx).map_err(|e| e.to_string())?))
    }

    fn build_lanes<const N: usize>(
        gains: &Self::Section,
        ctx: &BuildContext,
    ) -> Option<Result<LaneController<N>, String>> {
        on_lanes(Self::cascade::<Lanes<N>>(gains, ctx))
    }

    fn visit_axis_law<V: AxisLawVisitor>(gains: &Self::Section, axis: usize, visitor: V) -> Option<V::Output> {
        Some(visitor.visit(gains.to_array()[axis].law::<f64>()))
    }
}

/// The gain section of a full-state controller of `ftsmc-core`, with what
/// declares the controller ([`FullState`]).
pub trait FullStateGains: GainSection + Copy {
    /// Registry name ([`Declaration::NAME`]).
    const NAME: &'static str;
    /// Label for figures and tables ([`Declaration::LABEL`]).
    const LABEL: &'static str;
    /// One line for `ftsmc list` ([`Declaration::DESCRIPTION`]).
    const DESCRIPTION: &'static str;
    /// The controller on the number type `R` (`f64`: one flight).
    type On<R: Real>: Controller<R> + Send + 'static;
    /// Build it for the nominal `plant`, after checking the plant and the gains.
    fn build<R: Real>(plant: QuadrotorParams, gains: Self) -> Result<Self::On<R>, GainError>;
}

/// The full-state controller of gain section `G`.
pub struct FullState<G>(PhantomData<G>);

impl<G: FullStateGains> Declaration for FullState<G> {
    const NAME: &'static str = G::NAME;
    const LABEL: &'static str = G::LABEL;
    const DESCRIPTION: &'static str = G::DESCRIPTION;
    type Section = G;

    fn build(gains: &G, ctx: &BuildContext) -> Result<BoxedController, String> {
        Ok(Box::new(G::build::<f64>(ctx.plant, *gains).map_err(|e| e.to_string())?))
    }

    fn build_lanes<const N: usize>(gains: &G, ctx: &BuildContext) -> Option<Result<LaneController<N>, String>> {
        on_lanes(G::build::<Lanes<N>>(ctx.plant, *gains))
    }
}
