//! TSM-STA — nonsingular terminal sliding surface with a super-twisting
//! reaching law (the paper's ref. \[2\]; that paper is not available, so this is
//! the standard form, docs/controllers.md) on one channel:
//!
//! ```text
//! s    = e + (1/λ) sig^(p/q)(ė),                 p, q odd, 1 < p/q < 2
//! v_fb = −λ (q/p) sig^(2−p/q)(ė) − k1 |s|^(1/2) sign(s) + ν
//! dν/dt = −k2 sign(s),  ν(0) = 0
//! ```
//!
//! Why this shape: with exact model cancellation `ë = v_fb`, so
//! `ṡ = ė + (1/λ)(p/q)|ė|^(p/q−1) ë`
//! `  = ė + (1/λ)(p/q)|ė|^(p/q−1) (−λ (q/p) |ė|^(2−p/q) sign(ė) + w)`
//! `  = (p/(λq)) |ė|^(p/q−1) w`, with `w = −k1 |s|^½ sign(s) + ν`:
//! the super-twisting algorithm acting on `s` through a positive gain, and no
//! negative power of ė anywhere (the surface is nonsingular).

use crate::lanes::{Lanewise, Mask, Real};
use crate::law::{
    check_closed, check_gain, check_non_negative, saturate, AxisLaw, ContinuousRhs, GainError, INPUT_LIMIT,
    MAX_ESTIMATES, STATE_LIMIT,
};
use crate::math::{pow_abs, sig, sign_of, tanh};

/// Largest `p` and `q` accepted (99): an update computes `|ė|^(p/q)` and
/// `|ė|^(2−p/q)` by `p` and `2q − p` multiplications, so the bound keeps one
/// update O(1) (≤ 2·99 multiplications); two-digit odd integers already
/// approximate any ratio in (1, 2) within 1 %. The paper uses 5/3.
pub const MAX_EXPONENT_INTEGER: f64 = 99.0;

/// Gains of one TSM-STA channel.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Deserialize, serde::Serialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct TsmStaGains {
    /// λ > 0: surface gain (units make `s` an error).
    pub lambda: f64,
    /// p: odd integer in `[1, 99]`, numerator of the exponent p/q. Stored as
    /// f64 (scenario files may write `5.0`), but [`TsmStaGains::check`]
    /// rejects any value that is not exactly such an integer: it is never
    /// rounded or truncated.
    pub p: f64,
    /// q: odd integer in `[1, 99]`, denominator of the exponent p/q
    /// (1 < p/q < 2); validated like `p`.
    pub q: f64,
    /// k1 > 0: proportional super-twisting gain.
    pub k1: f64,
    /// k2 > 0: integral super-twisting gain.
    pub k2: f64,
    /// Boundary layer φ ≥ 0: when > 0, `sign(s)` is replaced by `tanh(s/φ)` in
    /// both terms (default 0: the discontinuous law).
    #[cfg_attr(feature = "serde", serde(default))]
    pub sign_smoothing: f64,
}

/// `v` is an odd integer in `[1, MAX_EXPONENT_INTEGER]` (checked before any
/// conversion, so nothing is truncated).
fn is_odd_integer_in_range(v: f64) -> bool {
    v.is_finite() && (1.0..=MAX_EXPONENT_INTEGER).contains(&v) && v == (v as i64) as f64 && (v as i64) % 2 == 1
}

impl TsmStaGains {
    /// Base position-loop shape (p/q = 5/3) before the time scaling of the
    /// tuning procedure (`ftsmc_sim::tuning`).
    pub const BASE_POSITION: Self = Self { lambda: 1.0, p: 5.0, q: 3.0, k1: 1.5, k2: 1.1, sign_smoothing: 0.0 };
    /// Base attitude-loop shape before time scaling.
    pub const BASE_ATTITUDE: Self = Self { lambda: 1.0, p: 5.0, q: 3.0, k1: 1.5, k2: 1.1, sign_smoothing: 0.0 };
    /// Default position gains: [`Self::BASE_POSITION`] time-scaled by the
    /// factor the tuning procedure finds on paper scenario 1 (same settling
    /// time as RANFTSMC with its published gains; `ftsmc tune-tsm-sta`).
    pub const DEFAULT_POSITION: Self = Self {
        lambda: 0.903647932444618,
        p: 5.0,
        q: 3.0,
        k1: 1.328282253104149,
        k2: 0.9166242693571983,
        sign_smoothing: 0.0,
    };
    /// Default attitude gains (tuned like [`Self::DEFAULT_POSITION`]).
    pub const DEFAULT_ATTITUDE: Self = Self {
        lambda: 3.8138158458545344,
        p: 5.0,
        q: 3.0,
        k1: 7.476923232761458,
        k2: 12.241656218670652,
        sign_smoothing: 0.0,
    };

    /// Reject gains outside the ranges the method requires, tightened to
    /// where the law is finite in f64 and one update is O(1):
    ///
    /// | gain | range |
    /// |---|---|
    /// | λ | `[1e-6, 1e6]` (the surface divides by λ) |
    /// | p, q | odd integers in `[1, 99]` with `1 < p/q < 2` |
    /// | k1, k2 | `(0, 1e6]` |
    /// | sign_smoothing | `[0, ∞)`, finite |
    pub fn check(&self) -> Result<(), GainError> {
        check_closed(
            "lambda",
            self.lambda,
            1e-6,
            1e6,
            "1e-6 <= lambda <= 1e6 (s divides by lambda; outside, it overflows)",
        )?;
        if !is_odd_integer_in_range(self.p) {
            return Err(GainError {
                field: "p",
                value: self.p,
                expected: "an odd integer 1 <= p <= 99 (one update costs p multiplications)",
            });
        }
        if !is_odd_integer_in_range(self.q) {
            return Err(GainError {
                field: "q",
                value: self.q,
                expected: "an odd integer 1 <= q <= 99 (one update costs 2q multiplications)",
            });
        }
        let ratio = self.p / self.q;
        if !(ratio > 1.0 && ratio < 2.0) {
            return Err(GainError { field: "p", value: self.p, expected: "1 < p/q < 2" });
        }
        check_gain("k1", self.k1)?;
        check_gain("k2", self.k2)?;
        check_non_negative("sign_smoothing", self.sign_smoothing)
    }

    /// `(p, 2q − p)` as integers when `p` and `q` are valid (odd integers in
    /// `[1, 99]`, `1 < p/q < 2`), else `None`.
    fn integer_exponents(&self) -> Option<(u32, u32)> {
        let valid = is_odd_integer_in_range(self.p) && is_odd_integer_in_range(self.q) && {
            let ratio = self.p / self.q;
            ratio > 1.0 && ratio < 2.0
        };
        valid.then_some((self.p as u32, (2.0 * self.q - self.p) as u32))
    }
}

/// Nonsingular terminal surface `s = e + (1/λ) sig^(p/q)(ė)` (error units:
/// m or rad), for one flight or per lane.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn sliding_surface<R: Real>(g: &TsmStaGains, e: R, e_dot: R) -> R {
    e + sig(e_dot, g.p / g.q) / g.lambda
}

/// `sign(s)`, or `tanh(s/φ)` with a boundary layer φ > 0 (dimensionless),
/// for one flight or per lane.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn switching_sign<R: Real>(g: &TsmStaGains, s: R) -> R {
    if g.sign_smoothing > 0.0 {
        (s / g.sign_smoothing).map(tanh)
    } else {
        sign_of(s)
    }
}

/// `x^(1/q)` for `x ≥ 0` (cube root when `q = 3`), per lane. `q` is a gain,
/// the same in every lane, so the path is chosen once for all lanes.
#[cfg_attr(not(debug_assertions), inline(always))]
fn qth_root<R: Real>(x: R, q: f64) -> R {
    if q == 3.0 {
        x.map(crate::math::cbrt)
    } else if q == 1.0 {
        x
    } else {
        let inverse = 1.0 / q;
        x.map(|v| crate::math::powf(v, inverse))
    }
}

/// `x^n` for a small non-negative integer `n` by repeated multiplication
/// (`n` is a gain: the same number of multiplications in every lane).
#[cfg_attr(not(debug_assertions), inline(always))]
fn powi<R: Real>(x: R, n: u32) -> R {
    let mut out = R::splat(1.0);
    for _ in 0..n {
        out *= x;
    }
    out
}

/// One TSM-STA channel: gains, the super-twisting integral state ν, last s.
///
/// `R` is the number type ([`crate::lanes`]): `f64` (the default) for one
/// flight, [`crate::lanes::Lanes`] for several flights side by side that
/// share the gains; lane `i` has exactly the bits of an `f64` channel fed
/// lane `i`'s inputs (its own ν, s and freeze flag).
#[derive(Clone, Copy, Debug)]
pub struct TsmStaAxis<R: Real = f64> {
    /// Gains (shared by every lane).
    pub gains: TsmStaGains,
    /// Integral state ν of the super-twisting law, channel units/s², per lane.
    pub nu: R,
    /// s of the last update (channel units: m or rad), per lane.
    pub s: R,
    /// `(p, 2q − p)` as integers when the gains are valid; `None` (general
    /// real powers) otherwise, so that an unchecked `p = 2999999999` is
    /// neither truncated nor looped over. Shared by every lane.
    exponents: Option<(u32, u32)>,
    /// ν held (not integrated) in the lanes where true; see
    /// [`AxisLaw::set_adaptation_frozen`].
    frozen: R::Mask,
}

crate::lanewise_struct!(TsmStaAxis { nu, s, frozen } shared { gains, exponents });

impl TsmStaAxis<f64> {
    /// A channel with ν = 0, after validating the gains ([`TsmStaGains::check`]).
    pub fn try_new(gains: TsmStaGains) -> Result<Self, GainError> {
        gains.check()?;
        Ok(Self::new(gains))
    }

    /// A channel with ν = 0, **without** validating the gains
    /// (`new_unchecked` semantics): the caller must have run
    /// [`TsmStaGains::check`] or use [`TsmStaAxis::try_new`]. Out-of-range
    /// gains never panic and never make an update slow (p, q outside the
    /// checked range use real powers instead of repeated multiplication),
    /// but may give non-finite commands.
    pub fn new(gains: TsmStaGains) -> Self {
        Self::splat(gains)
    }

    /// [`AxisLaw::continuous_rhs`] of one flight: `v` and s exactly as
    /// [`AxisLaw::update`] computes them with `ν = estimates[0]`;
    /// `dν/dt = −k2 sign(s)` (or `tanh(s/φ)`; zero while frozen).
    fn continuous_rhs_one(&self, e: f64, e_dot: f64, estimates: [f64; 3]) -> ContinuousRhs {
        let mut at = Self { nu: estimates[0], ..*self };
        let v = at.update(e, e_dot, 0.0);
        let rate = if self.frozen { 0.0 } else { -self.gains.k2 * switching_sign(&self.gains, at.s) };
        ContinuousRhs { v, s: at.s, estimates_rate: [rate, 0.0, 0.0] }
    }
}

impl<R: Real> TsmStaAxis<R> {
    /// Every lane a fresh channel ([`TsmStaAxis::new`]: ν = 0, s = 0,
    /// released), **without** validating the gains.
    pub fn splat(gains: TsmStaGains) -> Self {
        Self {
            gains,
            nu: R::splat(0.0),
            s: R::splat(0.0),
            exponents: gains.integer_exponents(),
            frozen: R::Mask::splat(false),
        }
    }

    /// Whether ν is currently held, per lane ([`AxisLaw::set_adaptation_frozen`]).
    pub fn adaptation_frozen(&self) -> R::Mask {
        self.frozen
    }
}

impl<R: Real> AxisLaw<R> for TsmStaAxis<R> {
    const NAME: &'static str = "tsm-sta";
    const ESTIMATE_NAMES: [&'static str; MAX_ESTIMATES] = ["nu", "", ""];

    /// Returns `v_fb`; then `ν += dt · (−k2 sign(s))`.
    ///
    /// Guards (no-ops on every meaningful input, see [`AxisLaw::update`]):
    /// NaN and no state change for a non-finite input; `e`, `ė` clamped to
    /// `±INPUT_LIMIT`; ν saturated to `±STATE_LIMIT`.
    ///
    /// While frozen ([`AxisLaw::set_adaptation_frozen`]) the output uses the
    /// held ν and `dν/dt` is not integrated. ν is not an adaptive gain but
    /// the super-twisting integral; holding it while the actuators saturate
    /// is the classic conditional-integration anti-windup, so it is frozen
    /// by the same option as the adaptive gains of the other laws.
    ///
    /// On lanes every guard acts per lane: a lane with a non-finite `e` or
    /// `ė` gets NaN and keeps its states while the other lanes update (a
    /// non-finite `dt`, shared, is every lane's). The exponents are gains,
    /// so every lane takes the same power path and the same number of
    /// multiplications.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn update(&mut self, e: R, e_dot: R, dt: f64) -> R {
        let ok = e.is_finite() & e_dot.is_finite();
        if !(dt.is_finite() && ok.any()) {
            return R::splat(f64::NAN);
        }
        // From here on, lanes with a bad input compute garbage that the
        // selects below throw away (for one flight `ok` is true here).
        let input_limit = R::splat(INPUT_LIMIT);
        let (e, e_dot) = (saturate(e, input_limit), saturate(e_dot, input_limit));
        let g = &self.gains;
        let ratio = g.p / g.q;
        let (ed_ratio, ed_two_minus_ratio) = match self.exponents {
            // Both powers of |ė| (p/q and 2 − p/q) from one q-th root r = |ė|^(1/q):
            // |ė|^(p/q) = r^p, |ė|^(2−p/q) = r^(2q−p) (p, q are small odd integers).
            Some((p, two_q_minus_p)) => {
                let root = qth_root(e_dot.abs(), g.q);
                (powi(root, p), powi(root, two_q_minus_p))
            }
            None => (pow_abs(e_dot, ratio), pow_abs(e_dot, 2.0 - ratio)),
        };
        let sign_ed = sign_of(e_dot);
        let s = e + ed_ratio * sign_ed / g.lambda;
        let sw = switching_sign(g, s);
        let v = ed_two_minus_ratio * (-g.lambda / ratio) * sign_ed - s.abs().sqrt() * g.k1 * sw + self.nu;
        let integrate = ok & !self.frozen;
        if integrate.any() {
            let integrated = saturate(self.nu - sw * (dt * g.k2), R::splat(STATE_LIMIT));
            self.nu = R::select(integrate, integrated, self.nu);
        }
        self.s = R::select(ok, s, self.s);
        R::select(ok, v, R::splat(f64::NAN))
    }

    fn sliding_variable(&self) -> R {
        self.s
    }

    fn estimates(&self) -> [R; 3] {
        [self.nu, R::splat(0.0), R::splat(0.0)]
    }

    fn reset(&mut self) {
        *self = Self::splat(self.gains);
    }

    /// Lane `lane` becomes a fresh channel ([`TsmStaAxis::new`]); the other
    /// lanes are untouched.
    fn reset_lane(&mut self, lane: usize) {
        self.put_lane(lane, TsmStaAxis::new(self.gains));
    }

    fn set_adaptation_frozen(&mut self, frozen: R::Mask) {
        self.frozen = frozen;
    }

    fn check_gains(&self) -> Result<(), GainError> {
        self.gains.check()
    }

    /// `v` and s exactly as [`AxisLaw::update`] computes them with
    /// `ν = estimates[0]`; `dν/dt = −k2 sign(s)` (or `tanh(s/φ)`; zero while
    /// frozen). One flight: on lanes, lane 0's law (its gains and freeze
    /// flag; ν comes from `estimates`).
    fn continuous_rhs(&self, e: f64, e_dot: f64, estimates: [f64; 3]) -> Option<ContinuousRhs> {
        Some(self.get_lane(0).continuous_rhs_one(e, e_dot, estimates))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{pow_abs, sign};
    use approx::assert_relative_eq;

    #[test]
    fn finite_at_zero_and_for_large_errors() {
        for g in [TsmStaGains::DEFAULT_POSITION, TsmStaGains::DEFAULT_ATTITUDE] {
            for &(e, ed) in &[(0.0, 0.0), (0.0, 1.0), (1.0, 0.0), (100.0, -100.0), (-100.0, 0.0), (1e-300, 0.0)] {
                let mut a = TsmStaAxis::new(g);
                let v = a.update(e, ed, 1e-3);
                assert!(v.is_finite() && a.nu.is_finite(), "e={e} ė={ed}: {v}");
            }
        }
    }

    #[test]
    fn one_step_matches_hand_computation() {
        let g = TsmStaGains { lambda: 2.0, p: 5.0, q: 3.0, k1: 3.0, k2: 4.0, sign_smoothing: 0.0 };
        let (e, ed, dt) = (-0.3f64, 0.7f64, 1e-3);
        let mut axis = TsmStaAxis::new(g);
        axis.nu = 0.25;
        let s = e + crate::math::powf(ed.abs(), 5.0 / 3.0) * ed.signum() / 2.0;
        let v_expected = -2.0 * (3.0 / 5.0) * crate::math::powf(ed.abs(), 2.0 - 5.0 / 3.0) * ed.signum()
            - 3.0 * s.abs().sqrt() * s.signum()
            + 0.25;
        let v = axis.update(e, ed, dt);
        assert_relative_eq!(v, v_expected, epsilon = 1e-12);
        assert_relative_eq!(axis.s, s, epsilon = 1e-14);
        assert_relative_eq!(axis.nu, 0.25 - dt * 4.0 * s.signum(), epsilon = 1e-15);
    }

    #[test]
    fn surface_rate_is_the_super_twisting_input_under_exact_cancellation() {
        // ṡ = (p/(λq)) |ė|^(p/q−1) w along ë = v_fb, checked by finite differences.
        let g = TsmStaGains { lambda: 1.7, p: 5.0, q: 3.0, k1: 2.0, k2: 1.0, sign_smoothing: 0.0 };
        let (e, ed) = (0.4, -0.9);
        let mut axis = TsmStaAxis::new(g);
        axis.nu = 0.1;
        let v = axis.update(e, ed, 0.0);
        let w = -g.k1 * axis.s.abs().sqrt() * axis.s.signum() + 0.1;
        let h = 1e-7;
        let s1 = sliding_surface(&g, e + ed * h, ed + v * h);
        let fd = (s1 - axis.s) / h;
        let want = (5.0 / (1.7 * 3.0)) * crate::math::powf(ed.abs(), 5.0 / 3.0 - 1.0) * w;
        assert!((fd - want).abs() < 1e-5, "{fd} vs {want}");
    }

    #[test]
    fn root_based_powers_equal_the_formulas() {
        let g = TsmStaGains::DEFAULT_ATTITUDE;
        for &(e, ed) in &[(0.3, -0.7), (-2.0, 0.01), (1e-4, 30.0), (0.0, -0.5), (0.8, 0.0)] {
            let mut axis = TsmStaAxis::new(g);
            let v = axis.update(e, ed, 1e-3);
            let s = sliding_surface(&g, e, ed);
            let want = -g.lambda * 0.6 * pow_abs(ed, 1.0 / 3.0) * sign(ed) - g.k1 * s.abs().sqrt() * sign(s);
            assert!((v - want).abs() <= 1e-12 * (1.0 + want.abs()), "{v} vs {want}");
            assert!((axis.s - s).abs() <= 1e-12 * (1.0 + s.abs()));
        }
    }

    #[test]
    fn bad_gains_name_the_field() {
        let base = TsmStaGains::BASE_POSITION;
        let bad = |g: TsmStaGains| g.check().unwrap_err().field;
        assert_eq!(bad(TsmStaGains { p: 4.0, ..base }), "p");
        assert_eq!(bad(TsmStaGains { p: 9.0, q: 3.0, ..base }), "p");
        assert_eq!(bad(TsmStaGains { q: 2.0, ..base }), "q");
        assert_eq!(bad(TsmStaGains { k1: -1.0, ..base }), "k1");
        assert_eq!(bad(TsmStaGains { sign_smoothing: -0.1, ..base }), "sign_smoothing");
        base.check().unwrap();
    }

    #[test]
    fn smoothing_makes_the_law_continuous_across_s_zero() {
        let g = TsmStaGains { sign_smoothing: 0.05, ..TsmStaGains::BASE_POSITION };
        let at = |e: f64| TsmStaAxis::new(g).update(e, 0.0, 1e-3);
        assert!((at(1e-6) - at(-1e-6)).abs() < 1e-3);
    }

    #[test]
    fn default_gains_settle_a_double_integrator() {
        for (g, e0, limit) in [(TsmStaGains::DEFAULT_POSITION, 1.0, 8.0), (TsmStaGains::DEFAULT_ATTITUDE, 0.5, 8.0)] {
            let mut axis = TsmStaAxis::new(g);
            let dt = 1e-3;
            let (mut e, mut ed) = (e0, 0.0f64);
            let mut last_outside = 0.0;
            for k in 0..20_000 {
                let v = axis.update(e, ed, dt);
                if e.abs() > 0.02 * e0 {
                    last_outside = k as f64 * dt;
                }
                e += ed * dt + 0.5 * v * dt * dt;
                ed += v * dt;
            }
            assert!(last_outside < limit, "settles at {last_outside}");
        }
    }

    /// Saturation remedy: ν (the super-twisting integral) is held while
    /// frozen, released it integrates again.
    #[test]
    fn freezing_holds_nu_and_keeps_the_output() {
        use crate::law::testing::{check_freeze, warmed};
        for g in [TsmStaGains::DEFAULT_POSITION, TsmStaGains::DEFAULT_ATTITUDE] {
            let axis = warmed(TsmStaAxis::new(g));
            assert!(!axis.adaptation_frozen() && axis.nu != 0.0);
            check_freeze(axis);
        }
    }
}
