//! TSM-STA — nonsingular terminal sliding surface with a super-twisting
//! reaching law (the paper's ref. [2]; that paper is not available, so this is
//! the standard form fixed by SPEC §3) on one channel:
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

use crate::law::{check_non_negative, check_positive, AxisLaw, GainError};
use crate::math::{sig, sign, sqrt, tanh};

/// Gains of one TSM-STA channel.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Deserialize, serde::Serialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct TsmStaGains {
    /// λ > 0: surface gain (units make `s` an error).
    pub lambda: f64,
    /// p: odd positive integer, numerator of the exponent p/q.
    pub p: f64,
    /// q: odd positive integer, denominator of the exponent p/q (1 < p/q < 2).
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

fn is_odd_positive_integer(v: f64) -> bool {
    v.is_finite() && v >= 1.0 && v == (v as i64) as f64 && (v as i64) % 2 == 1
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

    /// Reject gains outside the ranges the method requires.
    pub fn check(&self) -> Result<(), GainError> {
        check_positive("lambda", self.lambda)?;
        if !is_odd_positive_integer(self.p) {
            return Err(GainError { field: "p", value: self.p, expected: "an odd positive integer" });
        }
        if !is_odd_positive_integer(self.q) {
            return Err(GainError { field: "q", value: self.q, expected: "an odd positive integer" });
        }
        let ratio = self.p / self.q;
        if !(ratio > 1.0 && ratio < 2.0) {
            return Err(GainError { field: "p", value: self.p, expected: "1 < p/q < 2" });
        }
        check_positive("k1", self.k1)?;
        check_positive("k2", self.k2)?;
        check_non_negative("sign_smoothing", self.sign_smoothing)
    }
}

/// Nonsingular terminal surface `s = e + (1/λ) sig^(p/q)(ė)`.
#[inline]
pub fn sliding_surface(g: &TsmStaGains, e: f64, e_dot: f64) -> f64 {
    e + sig(e_dot, g.p / g.q) / g.lambda
}

/// `sign(s)`, or `tanh(s/φ)` with a boundary layer φ > 0.
#[inline]
pub fn switching_sign(g: &TsmStaGains, s: f64) -> f64 {
    if g.sign_smoothing > 0.0 {
        tanh(s / g.sign_smoothing)
    } else {
        sign(s)
    }
}

/// `x^(1/q)` for `x ≥ 0` (cube root when `q = 3`).
#[inline]
fn qth_root(x: f64, q: f64) -> f64 {
    if q == 3.0 {
        crate::math::cbrt(x)
    } else if q == 1.0 {
        x
    } else {
        crate::math::powf(x, 1.0 / q)
    }
}

/// `x^n` for a small non-negative integer `n` by repeated multiplication.
#[inline]
fn powi(x: f64, n: i32) -> f64 {
    let mut out = 1.0;
    for _ in 0..n {
        out *= x;
    }
    out
}

/// One TSM-STA channel: gains, the super-twisting integral state ν, last s.
#[derive(Clone, Copy, Debug)]
pub struct TsmStaAxis {
    /// Gains.
    pub gains: TsmStaGains,
    /// Integral state ν of the super-twisting law, channel units/s².
    pub nu: f64,
    /// s of the last update.
    pub s: f64,
}

impl TsmStaAxis {
    /// A channel with ν = 0.
    pub fn new(gains: TsmStaGains) -> Self {
        Self { gains, nu: 0.0, s: 0.0 }
    }
}

impl AxisLaw for TsmStaAxis {
    const NAME: &'static str = "tsm-sta";

    /// Returns `v_fb`; then `ν += dt · (−k2 sign(s))`.
    #[inline]
    fn update(&mut self, e: f64, e_dot: f64, dt: f64) -> f64 {
        let g = &self.gains;
        let ratio = g.p / g.q;
        // Both powers of |ė| (p/q and 2 − p/q) from one q-th root r = |ė|^(1/q):
        // |ė|^(p/q) = r^p, |ė|^(2−p/q) = r^(2q−p) (p, q are small odd integers).
        let root = qth_root(e_dot.abs(), g.q);
        let ed_ratio = powi(root, g.p as i32);
        let ed_two_minus_ratio = powi(root, (2.0 * g.q - g.p) as i32);
        let s = e + ed_ratio * sign(e_dot) / g.lambda;
        let sw = switching_sign(g, s);
        let v = -g.lambda / ratio * ed_two_minus_ratio * sign(e_dot) - g.k1 * sqrt(s.abs()) * sw + self.nu;
        self.nu -= dt * g.k2 * sw;
        self.s = s;
        v
    }

    fn sliding_variable(&self) -> f64 {
        self.s
    }

    fn estimates(&self) -> [f64; 3] {
        [self.nu, 0.0, 0.0]
    }

    fn reset(&mut self) {
        *self = Self::new(self.gains);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::pow_abs;
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
        let s = e + ed.abs().powf(5.0 / 3.0) * ed.signum() / 2.0;
        let v_expected = -2.0 * (3.0 / 5.0) * ed.abs().powf(2.0 - 5.0 / 3.0) * ed.signum()
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
        let want = (5.0 / (1.7 * 3.0)) * ed.abs().powf(5.0 / 3.0 - 1.0) * w;
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
}
