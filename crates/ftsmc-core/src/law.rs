//! The per-axis control-law interface shared by every controller of ftsmc.
//!
//! All three controllers of the paper (FTAFTSMC, RANFTSMC [19], TSM-STA [2])
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

/// Check `value > 0` and finite.
pub(crate) fn check_positive(field: &'static str, value: f64) -> Result<(), GainError> {
    check_open(field, value, 0.0, f64::INFINITY, "a finite value > 0")
}

/// Check `value >= 0` and finite.
pub(crate) fn check_non_negative(field: &'static str, value: f64) -> Result<(), GainError> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(GainError { field, value, expected: "a finite value >= 0" })
    }
}

/// Check that `value` is finite.
pub(crate) fn check_finite(field: &'static str, value: f64) -> Result<(), GainError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(GainError { field, value, expected: "a finite number" })
    }
}

/// Maximum number of adaptive / internal states an axis law exposes.
pub const MAX_ESTIMATES: usize = 3;

/// A single-channel sliding-mode law: error in, feedback acceleration out.
///
/// Implementations hold only their gains and their adaptive / integral
/// states; they never allocate and never perform I/O.
pub trait AxisLaw {
    /// Short machine name used in scenario files and outputs (e.g. `"ftaftsmc"`).
    const NAME: &'static str;

    /// Compute the feedback acceleration for error `e` and error rate `e_dot`
    /// (units of the channel: m, m/s → m/s²; rad, rad/s → rad/s²) using the
    /// current adaptive states, then advance those states by one control
    /// period `dt` (s) with explicit Euler (the adaptive laws run on the
    /// control clock).
    fn update(&mut self, e: f64, e_dot: f64, dt: f64) -> f64;

    /// Sliding variable evaluated in the last [`AxisLaw::update`].
    fn sliding_variable(&self) -> f64;

    /// Adaptive / internal states after the last update (unused slots are 0),
    /// e.g. `[δ̂, 0, 0]` for FTAFTSMC, `[â0, â1, â2]` for RANFTSMC, `[ν, 0, 0]`
    /// for TSM-STA.
    fn estimates(&self) -> [f64; MAX_ESTIMATES];

    /// Restore the initial adaptive / internal states.
    fn reset(&mut self);
}
