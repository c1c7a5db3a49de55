//! A controller whose updates run on a chosen instruction set
//! ([`crate::isa::run_on`], the one dispatch): the lane kernels of the
//! built-in controllers compiled for AVX2 + FMA when the CPU has them, the
//! same bits either way.

use ftsmc_core::cascade::{Controller, Telemetry};
use ftsmc_core::lanes::Real;
use ftsmc_core::law::MAX_ESTIMATES;
use ftsmc_core::measured::Measurement;
use ftsmc_core::model::{Command, QuadState, Reference};

use crate::isa::{run_on, Isa};

/// `inner` with its [`Controller::update`] and
/// [`Controller::update_measured`] run on `isa`.
pub struct OnIsa<C> {
    inner: C,
    isa: Isa,
}

impl<C> OnIsa<C> {
    /// `inner` on the instruction set this process uses ([`Isa::detect`]).
    pub fn detected(inner: C) -> Self {
        Self { inner, isa: Isa::detect() }
    }
}

impl<R: Real, C: Controller<R>> Controller<R> for OnIsa<C> {
    fn name(&self) -> &'static str {
        self.inner.name()
    }

    fn update(&mut self, state: &QuadState<R>, reference: &Reference<R>, dt: f64) -> Command<R> {
        let inner = &mut self.inner;
        run_on(
            self.isa,
            #[cfg_attr(not(debug_assertions), inline(always))]
            || inner.update(state, reference, dt),
        )
    }

    fn update_measured(&mut self, measured: &Measurement<R>, reference: &Reference<R>, dt: f64) -> Command<R> {
        let inner = &mut self.inner;
        run_on(
            self.isa,
            #[cfg_attr(not(debug_assertions), inline(always))]
            || inner.update_measured(measured, reference, dt),
        )
    }

    fn uses_body_attitude(&self) -> bool {
        self.inner.uses_body_attitude()
    }

    fn telemetry(&self) -> &Telemetry<R> {
        self.inner.telemetry()
    }

    fn estimate_names(&self) -> [&'static str; MAX_ESTIMATES] {
        self.inner.estimate_names()
    }

    fn adapts_mass(&self) -> bool {
        self.inner.adapts_mass()
    }

    fn reset(&mut self) {
        self.inner.reset();
    }

    fn reset_lane(&mut self, lane: usize) {
        self.inner.reset_lane(lane);
    }

    fn actuator_feedback(&mut self, saturated: R::Mask) {
        self.inner.actuator_feedback(saturated);
    }
}
