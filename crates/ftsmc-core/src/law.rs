//! The per-axis control-law interface shared by every controller of ftsmc.
//!
//! All three controllers of the paper (FTAFTSMC, RANFTSMC \[19\], TSM-STA \[2\])
//! have the same structure on each of the six channels x, y, z, φ, θ, ψ: from
//! the tracking error `e = q − q_d` and its rate `ė` they compute a feedback
//! acceleration `v_fb` so that the commanded acceleration is
//! `q̈_cmd = q̈_d + v_fb` (Eq. 18–20 and 56–58 with the model terms cancelled
//! by the [`crate::cascade::Cascade`]). A new controller implements
//! [`AxisLaw`] and is wrapped in the same cascade; nothing else changes.

/// Why a gain set was rejected: the field, its value and the range the
/// paper requires. `no_std`-friendly (static strings only).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GainError {
    /// Field name as it appears in scenario files (e.g. `"p"`, `"lambda2"`).
    pub field: &'static str,
    /// The offending value.
    pub value: f64,
    /// The range required, in words (e.g. `"0 < p < 1"`).
    pub expected: &'static str,
}

impl core::fmt::Display for GainError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{} = {} is out of range (expected {})", self.field, self.value, self.expected)
    }
}

/// Check `lo < value < hi` (either bound may be infinite).
pub(crate) fn check_open(
    field: &'static str,
    value: f64,
    lo: f64,
    hi: f64,
    expected: &'static str,
) -> Result<(), GainError> {
    if value.is_finite() && value > lo && value < hi {
        Ok(())
    } else {
        Err(GainError { field, value, expected })
    }
}

/// Check `lo <= value <= hi` (both bounds finite).
pub(crate) fn check_closed(
    field: &'static str,
    value: f64,
    lo: f64,
    hi: f64,
    expected: &'static str,
) -> Result<(), GainError> {
    if (lo..=hi).contains(&value) {
        Ok(())
    } else {
        Err(GainError { field, value, expected })
    }
}

/// Check `lo < value <= hi`.
pub(crate) fn check_left_open(
    field: &'static str,
    value: f64,
    lo: f64,
    hi: f64,
    expected: &'static str,
) -> Result<(), GainError> {
    if value > lo && value <= hi {
        Ok(())
    } else {
        Err(GainError { field, value, expected })
    }
}

/// Check `0 < value <= GAIN_MAX` for a gain that multiplies other terms.
pub(crate) fn check_gain(field: &'static str, value: f64) -> Result<(), GainError> {
    if value > 0.0 && value <= GAIN_MAX {
        Ok(())
    } else {
        Err(GainError { field, value, expected: "0 < value <= 1e6 (larger overflows the law's products in f64)" })
    }
}

/// Check `0 <= value <= GAIN_MAX` for a gain that may be switched off.
pub(crate) fn check_gain_or_zero(field: &'static str, value: f64) -> Result<(), GainError> {
    if (0.0..=GAIN_MAX).contains(&value) {
        Ok(())
    } else {
        Err(GainError { field, value, expected: "0 <= value <= 1e6 (larger overflows the law's products in f64)" })
    }
}

/// Check `0 <= value <= STATE_LIMIT` for the initial value of an adaptive state.
pub(crate) fn check_initial_state(field: &'static str, value: f64) -> Result<(), GainError> {
    check_closed(field, value, 0.0, STATE_LIMIT, "0 <= value <= 1e100 (adaptive states are saturated at 1e100)")
}

/// Largest gain accepted by the `check()` functions (1e6). With every gain
/// at most this, the inputs clamped to [`INPUT_LIMIT`] and the states to
/// [`STATE_LIMIT`], every product the laws form stays below ~1e290, so the
/// commands are finite. The paper's gains are all below 20.
pub const GAIN_MAX: f64 = 1e6;

/// Smallest value accepted for a gain the laws divide by (`b2` of RANFTSMC,
/// `lambda` of TSM-STA, `xi` of FTAFTSMC, `aleph1`): 1e-6.
pub const GAIN_MIN_DIVISOR: f64 = 1e-6;

/// Errors and error rates (`e`, `ė`, channel units: m, m/s, rad, rad/s) and
/// the commanded accelerations of the cascade are clamped to `±INPUT_LIMIT`
/// = ±1e12 before use. No physical flight gets near (the simulator declares
/// divergence at a 100 m error by default), so this is a no-op on every
/// meaningful input; it keeps every power of the laws finite in f64 for
/// inputs up to ±f64::MAX.
pub const INPUT_LIMIT: f64 = 1e12;

/// Adaptive and internal states (δ̂ of FTAFTSMC, `â` of RANFTSMC, ν of
/// TSM-STA, α̂ and the command filter of the cascade) are saturated to
/// `±STATE_LIMIT` = ±1e100 after each update, so they stay finite and bounded
/// whatever the (finite) inputs. The paper's runs stay below 10.
pub const STATE_LIMIT: f64 = 1e100;

/// Largest control period `dt` (s) for which finiteness is guaranteed
/// (legal range `0 <= dt <= DT_MAX`; `dt = 0` evaluates without advancing
/// the states).
pub const DT_MAX: f64 = 1e3;

/// Saturating powers (see [`crate::math::pow_abs_sat`]) never return more
/// than this (1e100).
pub const POWER_LIMIT: f64 = 1e100;

/// `x` clamped to `[-limit, limit]` for `limit >= 0`, propagating NaN, never
/// panicking (unlike `f64::clamp`, which panics on a NaN bound).
/// Bit-identical to `x` inside the range (signed zeros included) and to `x`
/// for a NaN `limit`. (A negative `limit`, which no caller passes, gives
/// `-limit` for every non-NaN `x`.)
///
/// Written as the two selects `limit < x ? limit : x` and
/// `-limit > t ? -limit : t`, which compile to one `minsd` and one `maxsd`
/// (NaN in `x` passes through both) instead of two compare-and-branch
/// pairs: the laws call it dozens of times per period.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn saturate<R: crate::lanes::Real>(x: R, limit: R) -> R {
    let upper = R::select(limit.lt(x), limit, x);
    R::select((-limit).gt(upper), -limit, upper)
}

/// True when `e`, `ė` and `dt` are all finite. Every law returns NaN and
/// leaves its states untouched when this is false, so one bad measurement
/// is reported as divergence by the caller and does not poison the
/// adaptive states.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn inputs_finite(e: f64, e_dot: f64, dt: f64) -> bool {
    e.is_finite() && e_dot.is_finite() && dt.is_finite()
}

/// Check `value >= 0` and finite.
pub(crate) fn check_non_negative(field: &'static str, value: f64) -> Result<(), GainError> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(GainError { field, value, expected: "a finite value >= 0" })
    }
}

/// Maximum number of adaptive / internal states an axis law exposes.
pub const MAX_ESTIMATES: usize = 3;

/// The continuous-time form of a law at one point (see
/// [`AxisLaw::continuous_rhs`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ContinuousRhs {
    /// Feedback acceleration `v_fb` (as returned by [`AxisLaw::update`]).
    pub v: f64,
    /// Sliding variable (as returned by [`AxisLaw::sliding_variable`]).
    pub s: f64,
    /// Time derivatives of the adaptive / internal states, in the order of
    /// [`AxisLaw::estimates`] (unused slots 0), per second.
    pub estimates_rate: [f64; MAX_ESTIMATES],
}

/// A single-channel sliding-mode law: error in, feedback acceleration out.
///
/// Implementations hold only their gains and their adaptive / integral
/// states; they never allocate and never perform I/O.
///
/// `R` is the number type ([`crate::lanes`]): `f64` (the default) for one
/// flight, a lane type for several flights side by side sharing the gains,
/// each lane with the bits of the one-flight law.
pub trait AxisLaw<R: crate::lanes::Real = f64> {
    /// Short machine name used in scenario files and outputs (e.g. `"ftaftsmc"`).
    const NAME: &'static str;

    /// Output names of the [`AxisLaw::estimates`] slots, `""` for an unused
    /// slot: time-series columns are `<name>_<axis>` (e.g. `delta_hat_z`),
    /// written only for the named slots (docs/outputs.md).
    const ESTIMATE_NAMES: [&'static str; MAX_ESTIMATES];

    /// Compute the feedback acceleration for error `e` and error rate `e_dot`
    /// (units of the channel: m, m/s → m/s²; rad, rad/s → rad/s²) using the
    /// current adaptive states, then advance those states by one control
    /// period `dt` (s) with explicit Euler (the adaptive laws run on the
    /// control clock).
    ///
    /// Contract, for gains that pass `check()`: for every finite `e`,
    /// `e_dot` and `0 <= dt <= DT_MAX` the result and the states are
    /// finite (inputs are clamped to [`INPUT_LIMIT`], states saturated to
    /// [`STATE_LIMIT`]). If `e`, `e_dot` or `dt` is not finite the result is
    /// NaN and the law is left exactly as it was before the call.
    fn update(&mut self, e: R, e_dot: R, dt: f64) -> R;

    /// Sliding variable evaluated in the last [`AxisLaw::update`].
    fn sliding_variable(&self) -> R;

    /// Adaptive / internal states after the last update (unused slots are 0),
    /// e.g. `[δ̂, 0, 0]` for FTAFTSMC, `[â0, â1, â2]` for RANFTSMC, `[ν, 0, 0]`
    /// for TSM-STA.
    fn estimates(&self) -> [R; MAX_ESTIMATES];

    /// Restore the initial adaptive / internal states (every lane).
    fn reset(&mut self);

    /// Restore lane `lane`'s initial states, leaving the other lanes as
    /// they are (a new flight starts in that lane). The default,
    /// [`AxisLaw::reset`], is right for one flight only; a law that flies
    /// lanes overrides it.
    fn reset_lane(&mut self, lane: usize) {
        let _ = lane;
        self.reset();
    }

    /// Freeze (`true`) or release (`false`) the law's adaptive / integral
    /// states (δ̂ of FTAFTSMC, `â` of RANFTSMC, ν of TSM-STA).
    ///
    /// While frozen, [`AxisLaw::update`] still computes its output from the
    /// error and the *current* states, exactly as when released, but skips
    /// the state increments, so the states hold their values; the finiteness
    /// contract of [`AxisLaw::update`] is unchanged. Released (the initial
    /// condition, and the state after [`AxisLaw::reset`]), `update` is
    /// bit-identical to a law that was never frozen.
    /// [`AxisLaw::continuous_rhs`] reports zero state rates while frozen.
    ///
    /// This is the anti-windup remedy of
    /// [`crate::cascade::CascadeSettings::freeze_adaptation_on_saturation`]:
    /// the cascade sets it on all six laws before each update. The default
    /// does nothing (a law without adaptive states has nothing to freeze).
    fn set_adaptation_frozen(&mut self, frozen: R::Mask) {
        let _ = frozen;
    }

    /// Validate the law's gains (the gain struct's `check()`); used by
    /// [`crate::cascade::Cascade::new`].
    fn check_gains(&self) -> Result<(), GainError>;

    /// The law as an ODE, for high-order integrators of the closed loop
    /// (the fixed-time analysis): `v_fb`, `S` and `d/dt` of the adaptive
    /// states at `(e, ė)` with the adaptive states set to `estimates`,
    /// leaving `self` unchanged. [`AxisLaw::update`] is explicit Euler on
    /// exactly these rates (plus its saturation guards).
    ///
    /// The default returns `None` (the law does not expose its rates); the
    /// caller then has to hold the adaptive states over a step and advance
    /// them with [`AxisLaw::update`].
    fn continuous_rhs(&self, e: f64, e_dot: f64, estimates: [f64; MAX_ESTIMATES]) -> Option<ContinuousRhs> {
        let _ = (e, e_dot, estimates);
        None
    }
}

/// Shared checks of the law implementations.
#[cfg(test)]
pub(crate) mod testing {
    use super::AxisLaw;

    const INPUTS: [(f64, f64); 5] = [(0.4, -0.3), (-0.2, 0.5), (0.05, 0.0), (1.2, -0.8), (-0.7, 0.9)];
    const DT: f64 = 1e-3;

    fn bits<const N: usize>(x: [f64; N]) -> [u64; N] {
        x.map(f64::to_bits)
    }

    /// [`AxisLaw::set_adaptation_frozen`] on `warm` (a law with non-trivial
    /// states): frozen, the states hold bit for bit while the output is the
    /// one computed with the held states and still follows the error;
    /// released again, the law is bit-identical to one never frozen, and
    /// its states move (so the first part is not vacuous);
    /// [`AxisLaw::continuous_rhs`] gives zero rates while frozen.
    pub(crate) fn check_freeze<L: AxisLaw + Clone>(warm: L) {
        let held = warm.estimates();
        let mut frozen = warm.clone();
        frozen.set_adaptation_frozen(true);
        let mut outputs = [0.0; INPUTS.len()];
        for (k, &(e, e_dot)) in INPUTS.iter().enumerate() {
            outputs[k] = frozen.update(e, e_dot, DT);
            assert_eq!(bits(frozen.estimates()), bits(held), "state moved while frozen at step {k}");
            // The output of a law at the held states, which `dt = 0` does not advance.
            let want = warm.clone().update(e, e_dot, 0.0);
            assert_eq!(outputs[k].to_bits(), want.to_bits(), "step {k}: {} vs {want}", outputs[k]);
            if let (Some(f), Some(free)) = (frozen.continuous_rhs(e, e_dot, held), warm.continuous_rhs(e, e_dot, held))
            {
                assert_eq!(f.estimates_rate, [0.0; super::MAX_ESTIMATES]);
                assert_eq!((f.v.to_bits(), f.s.to_bits()), (free.v.to_bits(), free.s.to_bits()));
            }
        }
        assert!(outputs.windows(2).all(|w| w[0] != w[1]), "frozen output ignores the error: {outputs:?}");

        let mut released = warm.clone();
        released.set_adaptation_frozen(true);
        released.set_adaptation_frozen(false);
        let mut never = warm.clone();
        for &(e, e_dot) in &INPUTS {
            let (a, b) = (released.update(e, e_dot, DT), never.update(e, e_dot, DT));
            assert_eq!(a.to_bits(), b.to_bits());
            assert_eq!(bits(released.estimates()), bits(never.estimates()));
            assert_eq!(released.sliding_variable().to_bits(), never.sliding_variable().to_bits());
        }
        assert_ne!(bits(never.estimates()), bits(held), "the states never move: the test is vacuous");

        // `reset` releases.
        frozen.reset();
        let mut fresh = frozen.clone();
        frozen.update(0.4, -0.3, DT);
        fresh.set_adaptation_frozen(false);
        fresh.update(0.4, -0.3, DT);
        assert_eq!(bits(frozen.estimates()), bits(fresh.estimates()));
    }

    /// `law` after a few updates, so its states are not the initial ones.
    pub(crate) fn warmed<L: AxisLaw>(mut law: L) -> L {
        for &(e, e_dot) in INPUTS.iter().rev() {
            law.update(e, e_dot, 10.0 * DT);
        }
        law
    }
}

#[cfg(test)]
mod tests {
    use super::saturate;

    /// The branch-free `saturate` gives the bits of the plain
    /// compare-and-branch clamp for every non-negative or NaN limit,
    /// signed zeros, infinities, subnormals and NaN included.
    #[test]
    fn saturate_is_the_plain_clamp_bit_for_bit() {
        fn plain(x: f64, limit: f64) -> f64 {
            if x > limit {
                limit
            } else if x < -limit {
                -limit
            } else {
                x
            }
        }
        let values = [
            0.0,
            -0.0,
            1e-310,
            -1e-310,
            0.5,
            -0.5,
            1.0,
            -1.0,
            1.0 + f64::EPSILON,
            -1.0 - f64::EPSILON,
            1e12,
            -1e12,
            1e300,
            -1e300,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ];
        let limits = [0.0, -0.0, 1e-310, 0.5, 1.0, 1e12, 1e100, f64::INFINITY, f64::NAN];
        for &x in &values {
            for &limit in &limits {
                assert_eq!(saturate(x, limit).to_bits(), plain(x, limit).to_bits(), "x = {x:e}, limit = {limit:e}");
            }
        }
    }
}
