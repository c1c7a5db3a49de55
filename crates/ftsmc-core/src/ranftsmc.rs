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

use crate::lanes::{branch, Blend, Lanewise, Mask, Real};
use crate::law::{
    check_closed, check_gain, check_gain_or_zero, check_initial_state, check_left_open, check_non_negative, check_open,
    saturate, AxisLaw, ContinuousRhs, GainError, INPUT_LIMIT, MAX_ESTIMATES, STATE_LIMIT,
};
use crate::math::{pow_abs, pow_abs_minus_one, sig, sign_of, tanh};

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

/// Nonsingular fast terminal surface `σ = e + b1 sig^α(e) + b2 sig^β(ė)`
/// (error units: m or rad), for one flight or per lane.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn sliding_surface<R: Real>(g: &RanftsmcGains, e: R, e_dot: R) -> R {
    e + sig(e, g.alpha) * g.b1 + sig(e_dot, g.beta) * g.b2
}

/// Equivalent part `−(1/(β b2)) |ė|^(2−β) (1 + α b1 |e|^(α−1)) sign(ė)`,
/// channel units/s², for one flight or per lane.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn equivalent_law<R: Real>(g: &RanftsmcGains, e: R, e_dot: R) -> R {
    pow_abs(e_dot, 2.0 - g.beta)
        * (-(1.0 / (g.beta * g.b2)))
        * (pow_abs_minus_one(e, g.alpha) * (g.alpha * g.b1) + 1.0)
        * sign_of(e_dot)
}

/// `sign(σ)`, or `tanh(σ/φ)` with a boundary layer φ > 0 (dimensionless),
/// for one flight or per lane.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn switching_sign<R: Real>(g: &RanftsmcGains, sigma: R) -> R {
    if g.sign_smoothing > 0.0 {
        (sigma / g.sign_smoothing).map(tanh)
    } else {
        sign_of(sigma)
    }
}

/// One RANFTSMC channel: gains and the adaptive gains `[â0, â1, â2]`.
///
/// `R` is the number type ([`crate::lanes`]): `f64` (the default) for one
/// flight, [`crate::lanes::Lanes`] for several flights side by side that
/// share the gains; lane `i` has exactly the bits of an `f64` channel fed
/// lane `i`'s inputs (its own `â`, σ and freeze flag).
#[derive(Clone, Copy, Debug)]
pub struct RanftsmcAxis<R: Real = f64> {
    /// Gains (shared by every lane).
    pub gains: RanftsmcGains,
    /// `[â0, â1, â2]` (â0 channel units/s², â1 1/s², â2 1/s), per lane.
    pub a_hat: [R; 3],
    /// σ of the last update (channel units: m or rad), per lane.
    pub sigma: R,
    /// `â` held (not integrated) in the lanes where true; see
    /// [`AxisLaw::set_adaptation_frozen`].
    frozen: R::Mask,
}

crate::lanewise_struct!(RanftsmcAxis { a_hat, sigma, frozen } shared { gains });

/// Below this `|ė|` the update computes `|ė|^(2−β)` with its own power
/// instead of `|ė|² / |ė|^β`: for `|ė| ≤ 6.8e-195` (β = 5/3) both `|ė|²`
/// and `|ė|^β` underflow to 0 and the quotient is `0/0 = NaN`. At and above
/// 1e-100 both are normal numbers, so the shared-power shortcut is exact to
/// rounding there.
const SHARED_POWER_MIN: f64 = 1e-100;

impl RanftsmcAxis<f64> {
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
        Self::splat(gains)
    }

    /// [`AxisLaw::continuous_rhs`] of one flight: `v` and σ exactly as
    /// [`AxisLaw::update`] computes them with `â = estimates`;
    /// `dâ/dt = [μ0 |σ| |ė|^(β−1), μ1 |σ| |e| |ė|^(β−1), μ2 |σ| |ė|^β]`
    /// (zero while frozen).
    fn continuous_rhs_one(&self, e: f64, e_dot: f64, estimates: [f64; 3]) -> ContinuousRhs {
        let mut at = Self { a_hat: estimates, ..*self };
        let v = at.update(e, e_dot, 0.0);
        if self.frozen {
            return ContinuousRhs { v, s: at.sigma, estimates_rate: [0.0; 3] };
        }
        let (e, e_dot) = (saturate(e, INPUT_LIMIT), saturate(e_dot, INPUT_LIMIT));
        let g = &self.gains;
        let abs_sigma = at.sigma.abs();
        let ed_beta_minus_one = pow_abs_minus_one(e_dot, g.beta);
        ContinuousRhs {
            v,
            s: at.sigma,
            estimates_rate: [
                g.mu0 * abs_sigma * ed_beta_minus_one,
                g.mu1 * abs_sigma * e.abs() * ed_beta_minus_one,
                g.mu2 * abs_sigma * e_dot.abs() * ed_beta_minus_one,
            ],
        }
    }
}

impl<R: Real> RanftsmcAxis<R> {
    /// Every lane a fresh channel ([`RanftsmcAxis::new`]: `â` at its
    /// initial values, σ = 0, released), **without** validating the gains.
    pub fn splat(gains: RanftsmcGains) -> Self {
        Self {
            gains,
            a_hat: [R::splat(gains.a0_hat0), R::splat(gains.a1_hat0), R::splat(gains.a2_hat0)],
            sigma: R::splat(0.0),
            frozen: R::Mask::splat(false),
        }
    }

    /// Whether `â` is currently held, per lane ([`AxisLaw::set_adaptation_frozen`]).
    pub fn adaptation_frozen(&self) -> R::Mask {
        self.frozen
    }
}

impl<R: Real> AxisLaw<R> for RanftsmcAxis<R> {
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
    ///
    /// On lanes every guard acts per lane: a lane with a non-finite `e` or
    /// `ė` gets NaN and keeps its states while the other lanes update (a
    /// non-finite `dt`, shared, is every lane's); the direct `|ė|^(2−β)` is
    /// computed only when some lane needs it ([`crate::lanes::branch`]).
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
        let (ae, aed) = (e.abs(), e_dot.abs());
        let e_alpha_minus_one = pow_abs_minus_one(e, g.alpha);
        let ed_beta_minus_one = pow_abs_minus_one(e_dot, g.beta);
        let ed_beta = aed * ed_beta_minus_one;
        let sign_ed = sign_of(e_dot);
        // σ = e + b1 sig^α(e) + b2 sig^β(ė)
        let sigma = e + e * g.b1 * e_alpha_minus_one + ed_beta * g.b2 * sign_ed;
        // |ė|^(2−β) = |ė|² / |ė|^β (0 at ė = 0 since β < 2); for tiny |ė|
        // the quotient would be 0/0, so take the power directly.
        let zero = R::splat(0.0);
        let ed_two_minus_beta = branch(
            aed.ge(R::splat(SHARED_POWER_MIN)),
            #[cfg_attr(not(debug_assertions), inline(always))]
            || aed * aed / ed_beta,
            #[cfg_attr(not(debug_assertions), inline(always))]
            || {
                branch(
                    aed.gt(zero),
                    #[cfg_attr(not(debug_assertions), inline(always))]
                    || pow_abs(e_dot, 2.0 - g.beta),
                    #[cfg_attr(not(debug_assertions), inline(always))]
                    || zero,
                )
            },
        );
        let v_eq =
            ed_two_minus_beta * (-(1.0 / (g.beta * g.b2))) * (e_alpha_minus_one * (g.alpha * g.b1) + 1.0) * sign_ed;
        let [a0, a1, a2] = self.a_hat;
        let v = v_eq - sigma * g.c - (a0 + a1 * ae + a2 * aed + g.h) * switching_sign(g, sigma);
        let adapt = ok & !self.frozen;
        if adapt.any() {
            let abs_sigma = sigma.abs();
            let state_limit = R::splat(STATE_LIMIT);
            let adapted = [
                saturate(a0 + abs_sigma * (dt * g.mu0) * ed_beta_minus_one, state_limit),
                saturate(a1 + abs_sigma * (dt * g.mu1) * ae * ed_beta_minus_one, state_limit),
                saturate(a2 + abs_sigma * (dt * g.mu2) * ed_beta, state_limit),
            ];
            self.a_hat = Blend::blend(adapt, adapted, self.a_hat);
        }
        self.sigma = R::select(ok, sigma, self.sigma);
        R::select(ok, v, R::splat(f64::NAN))
    }

    fn sliding_variable(&self) -> R {
        self.sigma
    }

    fn estimates(&self) -> [R; 3] {
        self.a_hat
    }

    fn reset(&mut self) {
        *self = Self::splat(self.gains);
    }

    /// Lane `lane` becomes a fresh channel ([`RanftsmcAxis::new`]); the
    /// other lanes are untouched.
    fn reset_lane(&mut self, lane: usize) {
        self.put_lane(lane, RanftsmcAxis::new(self.gains));
    }

    fn set_adaptation_frozen(&mut self, frozen: R::Mask) {
        self.frozen = frozen;
    }

    fn check_gains(&self) -> Result<(), GainError> {
        self.gains.check()
    }

    /// `v` and σ exactly as [`AxisLaw::update`] computes them with
    /// `â = estimates`; `dâ/dt = [μ0 |σ| |ė|^(β−1), μ1 |σ| |e| |ė|^(β−1), μ2 |σ| |ė|^β]`
    /// (zero while frozen). One flight: on lanes, lane 0's law (its gains
    /// and freeze flag; `â` comes from `estimates`).
    fn continuous_rhs(&self, e: f64, e_dot: f64, estimates: [f64; 3]) -> Option<ContinuousRhs> {
        Some(self.get_lane(0).continuous_rhs_one(e, e_dot, estimates))
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

    /// Saturation remedy: `â` is held while frozen, released it adapts again.
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
