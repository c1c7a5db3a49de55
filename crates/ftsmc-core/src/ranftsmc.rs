//! RANFTSMC — robust adaptive nonsingular fast terminal sliding-mode control
//! (Labbadi & Cherkaoui, ISA Trans. 2020; the paper's ref. \[19\]) on one
//! channel, in the form of its published equations:
//!
//! ```text
//! σ    = e + b1 sig^α(e) + b2 sig^β(ė),                      1 < β < 2, α > β
//! v_eq = −(1/(β b2)) |ė|^(2−β) (1 + α b1 |e|^(α−1)) sign(ė)
//! v_sw = −c σ − (â0 + â1|e| + â2|ė| + h) sign(σ)
//! dâ0/dt = μ0 |σ| |ė|^(β−1),  dâ1/dt = μ1 |σ| |e| |ė|^(β−1),  dâ2/dt = μ2 |σ| |ė|^β
//! ```
//!
//! The commanded acceleration is `q̈_d + v_eq + v_sw` (model terms cancelled
//! by the cascade). Since `α, β > 1`, the powers `|e|^(α−1)` and `|ė|^(β−1)`
//! vanish at zero and every term stays finite.

use crate::law::{
    check_closed, check_gain, check_gain_or_zero, check_initial_state, check_left_open, check_non_negative, check_open,
    inputs_finite, saturate, AxisLaw, ContinuousRhs, GainError, INPUT_LIMIT, MAX_ESTIMATES, STATE_LIMIT,
};
use crate::math::{pow_abs, pow_abs_minus_one, sig, sign, tanh};

/// Gains of one RANFTSMC channel (the published gain table of ref. \[19\]).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Deserialize, serde::Serialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct RanftsmcGains {
    /// b1 > 0: weight of `sig^α(e)` in σ.
    pub b1: f64,
    /// b2 > 0: weight of `sig^β(ė)` in σ.
    pub b2: f64,
    /// c > 0: linear reaching gain.
    pub c: f64,
    /// β in (1, 2): exponent of ė in σ.
    pub beta: f64,
    /// α > β: exponent of e in σ.
    pub alpha: f64,
    /// h ≥ 0: constant switching gain.
    pub h: f64,
    /// μ0 ≥ 0: adaptation rate of â0.
    pub mu0: f64,
    /// μ1 ≥ 0: adaptation rate of â1.
    pub mu1: f64,
    /// μ2 ≥ 0: adaptation rate of â2.
    pub mu2: f64,
    /// â0(0) ≥ 0 (default 0).
    #[cfg_attr(feature = "serde", serde(default))]
    pub a0_hat0: f64,
    /// â1(0) ≥ 0 (default 0).
    #[cfg_attr(feature = "serde", serde(default))]
    pub a1_hat0: f64,
    /// â2(0) ≥ 0 (default 0).
    #[cfg_attr(feature = "serde", serde(default))]
    pub a2_hat0: f64,
    /// Boundary layer φ ≥ 0 of the switching term: when > 0, `sign(σ)` is
    /// replaced by `tanh(σ/φ)` (default 0: the discontinuous law).
    #[cfg_attr(feature = "serde", serde(default))]
    pub sign_smoothing: f64,
}

impl RanftsmcGains {
    /// Published position-loop gains.
    pub const PAPER_POSITION: Self = Self {
        b1: 0.03,
        b2: 0.8,
        c: 1.21,
        beta: 5.0 / 3.0,
        alpha: 2.0,
        h: 0.5,
        mu0: 0.5,
        mu1: 0.001,
        mu2: 0.01,
        a0_hat0: 0.0,
        a1_hat0: 0.0,
        a2_hat0: 0.0,
        sign_smoothing: 0.0,
    };

    /// Published attitude-loop gains.
    pub const PAPER_ATTITUDE: Self = Self {
        b1: 8.7406,
        b2: 0.4838,
        c: 11.7180,
        beta: 1.0885,
        alpha: 1.2,
        h: 0.5,
        mu0: 0.0118,
        mu1: 6.2942e-4,
        mu2: 0.01,
        a0_hat0: 0.0,
        a1_hat0: 0.0,
        a2_hat0: 0.0,
        sign_smoothing: 0.0,
    };

    /// Reject gains outside the ranges the method requires, tightened to
    /// where every term is finite in f64 (each error's `expected` says why):
    ///
    /// | gain | range |
    /// |---|---|
    /// | b1, c | `(0, 1e6]` |
    /// | b2 | `[1e-6, 1e6]` (v_eq divides by β b2) |
    /// | β | `(1, 2)` |
    /// | α | `(β, 10]` |
    /// | h, μ0, μ1, μ2 | `[0, 1e6]` |
    /// | â0(0), â1(0), â2(0) | `[0, 1e100]` |
    /// | sign_smoothing | `[0, ∞)`, finite |
    pub fn check(&self) -> Result<(), GainError> {
        check_gain("b1", self.b1)?;
        check_closed("b2", self.b2, 1e-6, 1e6, "1e-6 <= b2 <= 1e6 (v_eq divides by beta b2; outside, it overflows)")?;
        check_gain("c", self.c)?;
        check_open("beta", self.beta, 1.0, 2.0, "1 < beta < 2")?;
        check_left_open(
            "alpha",
            self.alpha,
            self.beta,
            10.0,
            "beta < alpha <= 10 (|e|^alpha must stay finite for |e| <= 1e12)",
        )?;
        check_gain_or_zero("h", self.h)?;
        check_gain_or_zero("mu0", self.mu0)?;
        check_gain_or_zero("mu1", self.mu1)?;
        check_gain_or_zero("mu2", self.mu2)?;
        check_initial_state("a0_hat0", self.a0_hat0)?;
        check_initial_state("a1_hat0", self.a1_hat0)?;
        check_initial_state("a2_hat0", self.a2_hat0)?;
        check_non_negative("sign_smoothing", self.sign_smoothing)
    }
}

/// Nonsingular fast terminal surface `σ = e + b1 sig^α(e) + b2 sig^β(ė)`.
#[inline]
pub fn sliding_surface(g: &RanftsmcGains, e: f64, e_dot: f64) -> f64 {
    e + g.b1 * sig(e, g.alpha) + g.b2 * sig(e_dot, g.beta)
}

/// Equivalent part `−(1/(β b2)) |ė|^(2−β) (1 + α b1 |e|^(α−1)) sign(ė)`, channel units/s².
#[inline]
pub fn equivalent_law(g: &RanftsmcGains, e: f64, e_dot: f64) -> f64 {
    -(1.0 / (g.beta * g.b2))
        * pow_abs(e_dot, 2.0 - g.beta)
        * (1.0 + g.alpha * g.b1 * pow_abs_minus_one(e, g.alpha))
        * sign(e_dot)
}

/// `sign(σ)`, or `tanh(σ/φ)` with a boundary layer φ > 0.
#[inline]
pub fn switching_sign(g: &RanftsmcGains, sigma: f64) -> f64 {
    if g.sign_smoothing > 0.0 {
        tanh(sigma / g.sign_smoothing)
    } else {
        sign(sigma)
    }
}

/// One RANFTSMC channel: gains and the adaptive gains `[â0, â1, â2]`.
#[derive(Clone, Copy, Debug)]
pub struct RanftsmcAxis {
    /// Gains.
    pub gains: RanftsmcGains,
    /// `[â0, â1, â2]`.
    pub a_hat: [f64; 3],
    /// σ of the last update.
    pub sigma: f64,
    /// `â` held (not integrated) while true; see
    /// [`AxisLaw::set_adaptation_frozen`].
    frozen: bool,
}

/// Below this `|ė|` the update computes `|ė|^(2−β)` with its own power
/// instead of `|ė|² / |ė|^β`: for `|ė| ≤ 6.8e-195` (β = 5/3) both `|ė|²`
/// and `|ė|^β` underflow to 0 and the quotient is `0/0 = NaN`. At and above
/// 1e-100 both are normal numbers, so the shared-power shortcut is exact to
/// rounding there.
const SHARED_POWER_MIN: f64 = 1e-100;

impl RanftsmcAxis {
    /// A channel with `â = [a0_hat0, a1_hat0, a2_hat0]`, after validating the
    /// gains ([`RanftsmcGains::check`]).
    pub fn try_new(gains: RanftsmcGains) -> Result<Self, GainError> {
        gains.check()?;
        Ok(Self::new(gains))
    }

    /// A channel with `â = [a0_hat0, a1_hat0, a2_hat0]`, **without**
    /// validating the gains (`new_unchecked` semantics): the caller must have
    /// run [`RanftsmcGains::check`] or use [`RanftsmcAxis::try_new`].
    /// Out-of-range gains never panic but may give non-finite commands.
    pub fn new(gains: RanftsmcGains) -> Self {
        Self { gains, a_hat: [gains.a0_hat0, gains.a1_hat0, gains.a2_hat0], sigma: 0.0, frozen: false }
    }

    /// Whether `â` is currently held ([`AxisLaw::set_adaptation_frozen`]).
    pub fn adaptation_frozen(&self) -> bool {
        self.frozen
    }
}

impl AxisLaw for RanftsmcAxis {
    const NAME: &'static str = "ranftsmc";
    const ESTIMATE_NAMES: [&'static str; MAX_ESTIMATES] = ["a_hat0", "a_hat1", "a_hat2"];

    /// Returns `v_eq + v_sw`; then `â += dt · dâ/dt`.
    ///
    /// All five fractional powers come from two: `|e|^(α−1)` and `|ė|^(β−1)`
    /// (`sig^α(e) = e |e|^(α−1)`, `|ė|^β = |ė| |ė|^(β−1)`,
    /// `|ė|^(2−β) = |ė|² / |ė|^β`), which halves the cost of the law.
    ///
    /// Guards (no-ops on every meaningful input, see [`AxisLaw::update`]):
    /// NaN and no state change for a non-finite input; `e`, `ė` clamped to
    /// `±INPUT_LIMIT`; `|ė|^(2−β)` computed directly for `|ė| < 1e-100`;
    /// `â` saturated at `STATE_LIMIT` (the adaptation has no leakage).
    ///
    /// While frozen ([`AxisLaw::set_adaptation_frozen`]) the output uses the
    /// held `â` and the three adaptation laws are not integrated.
    #[inline]
    fn update(&mut self, e: f64, e_dot: f64, dt: f64) -> f64 {
        if !inputs_finite(e, e_dot, dt) {
            return f64::NAN;
        }
        let (e, e_dot) = (saturate(e, INPUT_LIMIT), saturate(e_dot, INPUT_LIMIT));
        let g = &self.gains;
        let (ae, aed) = (e.abs(), e_dot.abs());
        let e_alpha_minus_one = pow_abs_minus_one(e, g.alpha);
        let ed_beta_minus_one = pow_abs_minus_one(e_dot, g.beta);
        let ed_beta = aed * ed_beta_minus_one;
        // σ = e + b1 sig^α(e) + b2 sig^β(ė)
        let sigma = e + g.b1 * e * e_alpha_minus_one + g.b2 * ed_beta * sign(e_dot);
        // |ė|^(2−β) = |ė|² / |ė|^β (0 at ė = 0 since β < 2); for tiny |ė|
        // the quotient would be 0/0, so take the power directly.
        let ed_two_minus_beta = if aed >= SHARED_POWER_MIN {
            aed * aed / ed_beta
        } else if aed > 0.0 {
            pow_abs(e_dot, 2.0 - g.beta)
        } else {
            0.0
        };
        let v_eq =
            -(1.0 / (g.beta * g.b2)) * ed_two_minus_beta * (1.0 + g.alpha * g.b1 * e_alpha_minus_one) * sign(e_dot);
        let [a0, a1, a2] = self.a_hat;
        let v = v_eq - g.c * sigma - (a0 + a1 * ae + a2 * aed + g.h) * switching_sign(g, sigma);
        if !self.frozen {
            let abs_sigma = sigma.abs();
            self.a_hat[0] = saturate(self.a_hat[0] + dt * g.mu0 * abs_sigma * ed_beta_minus_one, STATE_LIMIT);
            self.a_hat[1] = saturate(self.a_hat[1] + dt * g.mu1 * abs_sigma * ae * ed_beta_minus_one, STATE_LIMIT);
            self.a_hat[2] = saturate(self.a_hat[2] + dt * g.mu2 * abs_sigma * ed_beta, STATE_LIMIT);
        }
        self.sigma = sigma;
        v
    }

    fn sliding_variable(&self) -> f64 {
        self.sigma
    }

    fn estimates(&self) -> [f64; 3] {
        self.a_hat
    }

    fn reset(&mut self) {
        *self = Self::new(self.gains);
    }

    fn set_adaptation_frozen(&mut self, frozen: bool) {
        self.frozen = frozen;
    }

    fn check_gains(&self) -> Result<(), GainError> {
        self.gains.check()
    }

    /// `v` and σ exactly as [`AxisLaw::update`] computes them with
    /// `â = estimates`; `dâ/dt = [μ0 |σ| |ė|^(β−1), μ1 |σ| |e| |ė|^(β−1), μ2 |σ| |ė|^β]`
    /// (zero while frozen).
    fn continuous_rhs(&self, e: f64, e_dot: f64, estimates: [f64; 3]) -> Option<ContinuousRhs> {
        let mut at = Self { a_hat: estimates, ..*self };
        let v = at.update(e, e_dot, 0.0);
        if self.frozen {
            return Some(ContinuousRhs { v, s: at.sigma, estimates_rate: [0.0; 3] });
        }
        let (e, e_dot) = (saturate(e, INPUT_LIMIT), saturate(e_dot, INPUT_LIMIT));
        let g = &self.gains;
        let abs_sigma = at.sigma.abs();
        let ed_beta_minus_one = pow_abs_minus_one(e_dot, g.beta);
        Some(ContinuousRhs {
            v,
            s: at.sigma,
            estimates_rate: [
                g.mu0 * abs_sigma * ed_beta_minus_one,
                g.mu1 * abs_sigma * e.abs() * ed_beta_minus_one,
                g.mu2 * abs_sigma * e_dot.abs() * ed_beta_minus_one,
            ],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn finite_at_zero_and_for_large_errors() {
        for g in [RanftsmcGains::PAPER_POSITION, RanftsmcGains::PAPER_ATTITUDE] {
            for &(e, ed) in &[(0.0, 0.0), (0.0, 1.0), (1.0, 0.0), (100.0, -100.0), (-100.0, 0.0), (1e-300, 0.0)] {
                let mut a = RanftsmcAxis::new(g);
                let v = a.update(e, ed, 1e-3);
                assert!(v.is_finite() && a.a_hat.iter().all(|x| x.is_finite()), "e={e} ė={ed}: {v}");
            }
        }
    }

    #[test]
    fn one_step_matches_hand_computation() {
        let g = RanftsmcGains { a0_hat0: 0.2, a1_hat0: 0.1, a2_hat0: 0.05, ..RanftsmcGains::PAPER_POSITION };
        let (e, ed, dt) = (0.4f64, -0.3f64, 1e-3);
        let (b1, b2, c, beta, alpha, h) = (0.03, 0.8, 1.21, 5.0 / 3.0, 2.0, 0.5);
        let sigma = e
            + b1 * crate::math::powf(e.abs(), alpha) * e.signum()
            + b2 * crate::math::powf(ed.abs(), beta) * ed.signum();
        let v_eq = -(1.0 / (beta * b2))
            * crate::math::powf(ed.abs(), 2.0 - beta)
            * (1.0 + alpha * b1 * crate::math::powf(e.abs(), alpha - 1.0))
            * ed.signum();
        let v_sw = -c * sigma - (0.2 + 0.1 * e.abs() + 0.05 * ed.abs() + h) * sigma.signum();
        let mut axis = RanftsmcAxis::new(g);
        let v = axis.update(e, ed, dt);
        assert_relative_eq!(v, v_eq + v_sw, epsilon = 1e-12);
        assert_relative_eq!(axis.sigma, sigma, epsilon = 1e-14);
        assert_relative_eq!(
            axis.a_hat[0],
            0.2 + dt * 0.5 * sigma.abs() * crate::math::powf(ed.abs(), beta - 1.0),
            epsilon = 1e-14
        );
        assert_relative_eq!(
            axis.a_hat[1],
            0.1 + dt * 0.001 * sigma.abs() * e.abs() * crate::math::powf(ed.abs(), beta - 1.0),
            epsilon = 1e-14
        );
        assert_relative_eq!(
            axis.a_hat[2],
            0.05 + dt * 0.01 * sigma.abs() * crate::math::powf(ed.abs(), beta),
            epsilon = 1e-14
        );
    }

    fn double_integrator_settling(g: RanftsmcGains, e0: f64, t_max: f64) -> Option<f64> {
        let mut axis = RanftsmcAxis::new(g);
        let dt = 1e-3;
        let (mut e, mut ed) = (e0, 0.0);
        let mut last_outside = 0.0;
        let n = (t_max / dt) as usize;
        for k in 0..n {
            let v = axis.update(e, ed, dt);
            if e.abs() > 0.02 * e0.abs() {
                last_outside = k as f64 * dt;
            }
            e += ed * dt + 0.5 * v * dt * dt;
            ed += v * dt;
        }
        (last_outside < t_max - 1.0).then_some(last_outside)
    }

    #[test]
    fn published_gains_settle_a_double_integrator() {
        let pos = double_integrator_settling(RanftsmcGains::PAPER_POSITION, 1.0, 15.0).expect("position settles");
        assert!(pos < 8.0, "{pos}");
        let att = double_integrator_settling(RanftsmcGains::PAPER_ATTITUDE, 0.5, 5.0).expect("attitude settles");
        assert!(att < 2.0, "{att}");
    }

    #[test]
    fn fast_update_equals_the_textbook_formulas() {
        // The update shares powers between terms; it must equal the
        // formula-by-formula evaluation (sliding_surface, equivalent_law).
        for g in [RanftsmcGains::PAPER_POSITION, RanftsmcGains::PAPER_ATTITUDE] {
            for &(e, ed) in &[(0.3, -0.7), (-2.0, 0.01), (1e-4, 3.0), (0.0, -0.5), (0.8, 0.0)] {
                let mut axis = RanftsmcAxis::new(g);
                let v = axis.update(e, ed, 1e-3);
                let sigma = sliding_surface(&g, e, ed);
                let want = equivalent_law(&g, e, ed) - g.c * sigma - g.h * switching_sign(&g, sigma);
                assert!((v - want).abs() <= 1e-12 * (1.0 + want.abs()), "{v} vs {want}");
                assert!((axis.sigma - sigma).abs() <= 1e-14 * (1.0 + sigma.abs()));
                let rate2 = g.mu2 * sigma.abs() * pow_abs(ed, g.beta);
                assert!((axis.a_hat[2] - 1e-3 * rate2).abs() <= 1e-15 * (1.0 + rate2));
            }
        }
    }

    #[test]
    fn bad_gains_name_the_field() {
        let bad = |g: RanftsmcGains| g.check().unwrap_err().field;
        let p = RanftsmcGains::PAPER_POSITION;
        assert_eq!(bad(RanftsmcGains { beta: 2.5, ..p }), "beta");
        assert_eq!(bad(RanftsmcGains { alpha: 1.5, ..p }), "alpha");
        assert_eq!(bad(RanftsmcGains { c: -1.0, ..p }), "c");
        assert_eq!(bad(RanftsmcGains { sign_smoothing: -0.1, ..p }), "sign_smoothing");
        p.check().unwrap();
        RanftsmcGains::PAPER_ATTITUDE.check().unwrap();
    }

    #[test]
    fn smoothing_makes_the_law_continuous_across_sigma_zero() {
        let g = RanftsmcGains { sign_smoothing: 0.05, ..RanftsmcGains::PAPER_POSITION };
        let at = |e: f64| RanftsmcAxis::new(g).update(e, 0.0, 1e-3);
        assert!((at(1e-6) - at(-1e-6)).abs() < 1e-3);
        let hard = |e: f64| RanftsmcAxis::new(RanftsmcGains::PAPER_POSITION).update(e, 0.0, 1e-3);
        assert!((hard(1e-6) - hard(-1e-6)).abs() > 0.9, "the default law switches");
    }

    /// Issue 11 item 6: `â` is held while frozen, released it adapts again.
    #[test]
    fn freezing_holds_a_hat_and_keeps_the_output() {
        use crate::law::testing::{check_freeze, warmed};
        for g in [RanftsmcGains::PAPER_POSITION, RanftsmcGains::PAPER_ATTITUDE] {
            let g = RanftsmcGains { a0_hat0: 0.2, a1_hat0: 0.1, a2_hat0: 0.05, ..g };
            let axis = warmed(RanftsmcAxis::new(g));
            assert!(!axis.adaptation_frozen());
            check_freeze(axis);
        }
    }
}
