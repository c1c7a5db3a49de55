//! FTAFTSMC on one channel: the fixed-time fast terminal sliding surface
//! (paper Eq. 5–13), the switching law (Eq. 15–16) and the δ̂ adaptation
//! (Eq. 17). The same law serves the position (§3.1) and attitude (§3.3,
//! Eq. 53–55) channels; the mass adaptation of §3.2 lives in the cascade.
//!
//! Notation: `sig^a(v) = |v|^a sign(v)`; `e = q − q_d`, `ė = q̇ − q̇_d`.
//!
//! The surface, the reaching law and [`FtaftsmcAxis`] are generic over the
//! number type ([`crate::lanes`]): `f64` for one flight (the default), a
//! lane type for several flights sharing the gains, each lane with the bits
//! of the one-flight law (the freeze flag is a per-lane mask, the
//! non-finite-input guard acts per lane).

use crate::lanes::{branch, Blend, Lanewise, Mask, Real};
use crate::law::{
    check_closed, check_gain, check_initial_state, check_left_open, check_open, saturate, AxisLaw, ContinuousRhs,
    GainError, INPUT_LIMIT, MAX_ESTIMATES, STATE_LIMIT,
};
use crate::math::{pow_abs, pow_abs_minus_one, saturate_power, sign, sign_of, Power};

/// Gains of one FTAFTSMC channel (paper Tables 4 and 5).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Deserialize, serde::Serialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct FtaftsmcGains {
    /// λ > 0: gain of the `sig^q(e)` term of the surface (Eq. 5).
    pub lambda: f64,
    /// γ > 0: gain of the `S_Δ` term of the surface (Eq. 5).
    pub gamma: f64,
    /// η > 0: gain of the linear term of the surface (Eq. 5).
    pub eta: f64,
    /// q > 1: fast exponent of the surface (Eq. 5).
    pub q: f64,
    /// 0 < p < 1: terminal exponent of the surface (Eq. 5, 7).
    pub p: f64,
    /// ℵ1 in (0, 1]: `Y(∞) = 1/ℵ1` (Eq. 6; Table 4 uses ℵ1 = 1, i.e. Y ≡ 1).
    pub aleph1: f64,
    /// ℵ2 > 0: rate of the exponential in `Y(e)` (Eq. 6).
    pub aleph2: f64,
    /// ℵ3 > 0: exponent of `|e|` in `Y(e)` (Eq. 6).
    pub aleph3: f64,
    /// ε > 0: width of the nonsingular switch of `S_Δ` (Eq. 7, 9), channel units.
    pub epsilon: f64,
    /// λ2 > 0: gain of `sig^q2(S)` in the reaching law (Eq. 15).
    pub lambda2: f64,
    /// γ2 > 0: gain of `sig^p2(S)` in the reaching law (Eq. 15).
    pub gamma2: f64,
    /// η2 > 0: linear gain of the reaching law (Eq. 15).
    pub eta2: f64,
    /// q2 > 1: fast exponent of the reaching law (Eq. 15).
    pub q2: f64,
    /// 0 < p2 < 1: terminal exponent of the reaching law (Eq. 15).
    pub p2: f64,
    /// ξ > 0: scaling of the adaptive term `δ̂/(2ξ²) S` (Eq. 15, 17).
    pub xi: f64,
    /// α1 > 0: adaptation rate (Eq. 17).
    pub alpha1: f64,
    /// α2 > 0: leakage of the adaptation (Eq. 17).
    pub alpha2: f64,
    /// δ̂(0) ≥ 0: initial estimate of δ = Λ² (not given in the paper; default 0).
    #[cfg_attr(feature = "serde", serde(default))]
    pub delta_hat0: f64,
}

impl FtaftsmcGains {
    /// Reject gains outside the ranges stated under Eq. 9 and Eq. 16–17,
    /// tightened to where every term of the law is finite in f64 (each
    /// error's `expected` says why):
    ///
    /// | gain | range |
    /// |---|---|
    /// | λ, γ, η, ℵ2, λ2, γ2, η2, α1, α2 | `(0, 1e6]` |
    /// | q, q2 | `(1, 10]` |
    /// | p, p2 | `(0, 1)` |
    /// | ℵ1 | `[1e-6, 1]` |
    /// | ℵ3 | `[1, 100]` |
    /// | ε | `[1e-9, 1e6]` |
    /// | ξ | `[1e-6, 1e6]` |
    /// | δ̂(0) | `[0, 1e100]` |
    pub fn check(&self) -> Result<(), GainError> {
        check_gain("lambda", self.lambda)?;
        check_gain("gamma", self.gamma)?;
        check_gain("eta", self.eta)?;
        check_left_open("q", self.q, 1.0, 10.0, "1 < q <= 10 (|e|^q must stay finite for |e| <= 1e12)")?;
        check_open("p", self.p, 0.0, 1.0, "0 < p < 1")?;
        check_closed(
            "aleph1",
            self.aleph1,
            1e-6,
            1.0,
            "1e-6 <= aleph1 <= 1 (Y <= 1/aleph1 multiplies every surface term; smaller overflows them)",
        )?;
        check_gain("aleph2", self.aleph2)?;
        check_closed(
            "aleph3",
            self.aleph3,
            1.0,
            100.0,
            "1 <= aleph3 <= 100 (smaller makes |e|^(aleph3-1) in Eq. 11 singular at e = 0; \
             larger only saturates Y)",
        )?;
        check_closed(
            "epsilon",
            self.epsilon,
            1e-9,
            1e6,
            "1e-9 <= epsilon <= 1e6 (kappa2 = (p-1) epsilon^(p-2) of Eq. 9 overflows for smaller epsilon)",
        )?;
        check_gain("lambda2", self.lambda2)?;
        check_gain("gamma2", self.gamma2)?;
        check_gain("eta2", self.eta2)?;
        check_left_open("q2", self.q2, 1.0, 10.0, "1 < q2 <= 10 (|S|^q2 must stay finite)")?;
        check_open("p2", self.p2, 0.0, 1.0, "0 < p2 < 1")?;
        check_closed(
            "xi",
            self.xi,
            1e-6,
            1e6,
            "1e-6 <= xi <= 1e6 (Eq. 15, 17 divide by 2 xi^2, which underflows to 0 for smaller xi)",
        )?;
        check_gain("alpha1", self.alpha1)?;
        check_gain("alpha2", self.alpha2)?;
        check_initial_state("delta_hat0", self.delta_hat0)
    }

    /// Table 5, x and y channels (ε = 0.05).
    pub const PAPER_XY: Self = Self {
        lambda: 0.4,
        gamma: 0.4,
        eta: 0.4,
        q: 1.5,
        p: 0.1,
        aleph1: 0.8,
        aleph2: 30.0,
        aleph3: 2.0,
        epsilon: 0.05,
        lambda2: 0.2,
        gamma2: 2.0,
        eta2: 0.2,
        q2: 4.0,
        p2: 0.2,
        xi: 0.08,
        alpha1: 0.001,
        alpha2: 0.005,
        delta_hat0: 0.0,
    };

    /// Table 5, z channel (ε = 0.05).
    pub const PAPER_Z: Self = Self {
        lambda: 0.3,
        gamma: 1.0,
        eta: 0.3,
        q: 1.5,
        p: 0.1,
        aleph1: 0.8,
        aleph2: 30.0,
        aleph3: 2.0,
        epsilon: 0.05,
        lambda2: 0.5,
        gamma2: 1.0,
        eta2: 0.5,
        q2: 1.1,
        p2: 0.4,
        xi: 0.08,
        alpha1: 0.01,
        alpha2: 0.001,
        delta_hat0: 0.0,
    };

    /// Table 4, φ and θ channels (ℵ1 = 1 as printed, ε = 0.05).
    pub const PAPER_ROLL_PITCH: Self = Self {
        lambda: 2.0,
        gamma: 2.0,
        eta: 2.0,
        q: 4.0,
        p: 0.1,
        aleph1: 1.0,
        aleph2: 30.0,
        aleph3: 2.0,
        epsilon: 0.05,
        lambda2: 1.0,
        gamma2: 2.0,
        eta2: 1.0,
        q2: 2.0,
        p2: 0.6,
        xi: 0.08,
        alpha1: 0.01,
        alpha2: 0.02,
        delta_hat0: 0.0,
    };

    /// Table 4, ψ channel (the printed λ_φ, α_1φ, λ_2φ, q_2φ of the ψ block
    /// read as λ_ψ, α_1ψ, λ_2ψ, q_2ψ).
    pub const PAPER_YAW: Self = Self {
        lambda: 2.0,
        gamma: 2.0,
        eta: 4.0,
        q: 2.0,
        p: 0.1,
        aleph1: 1.0,
        aleph2: 30.0,
        aleph3: 2.0,
        epsilon: 0.05,
        lambda2: 4.0,
        gamma2: 4.0,
        eta2: 1.0,
        q2: 2.0,
        p2: 0.4,
        xi: 0.08,
        alpha1: 0.001,
        alpha2: 0.005,
        delta_hat0: 0.0,
    };

    /// The paper's reaching-time bound of Eq. 38 (s):
    /// `T ≤ 1/(λ2 (q2 − 1)) + 1/(γ2 (1 − p2))`.
    pub fn reaching_time_bound(&self) -> f64 {
        1.0 / (self.lambda2 * (self.q2 - 1.0)) + 1.0 / (self.gamma2 * (1.0 - self.p2))
    }
}

/// Every intermediate quantity of the surface at one instant, for tests,
/// telemetry and the fixed-time analysis, of one flight (`R = f64`) or of
/// lanes ([`crate::lanes`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SurfaceTerms<R: Real = f64> {
    /// `Y(e)` (Eq. 6, with the `(1 − ℵ1)` of Eq. 11).
    pub y: R,
    /// `Ẏ(e)` (Eq. 11), 1/s.
    pub y_dot: R,
    /// `S_Δ(e)` (Eq. 7).
    pub s_delta: R,
    /// `Ṡ_Δ` (Eq. 12).
    pub s_delta_dot: R,
    /// Sliding variable `S` (Eq. 5), channel units per second.
    pub s: R,
    /// `ϖ` (Eq. 13): the part of the equivalent control that cancels `d/dt`
    /// of the surface's error terms, channel units per s².
    pub varpi: R,
}
crate::lanewise_struct!(SurfaceTerms { y, y_dot, s_delta, s_delta_dot, s, varpi });

/// What the gains fix for a whole flight, computed once per channel: `κ1`,
/// `κ2` (Eq. 9), `2ξ²` (Eq. 15, 17) and the evaluation path of each
/// exponent ([`Power`]). Every function below that takes it gives the same
/// bits as its public counterpart, which builds it from the gains per call.
/// Shared by every lane (the gains are).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Constants {
    /// `[κ1, κ2]` of Eq. 9.
    kappa: [f64; 2],
    /// `2 ξ²`, computed as `2.0 * ξ * ξ` (the order of Eq. 15 and 17).
    two_xi_sq: f64,
    /// p (Eq. 5, 7).
    p: Power,
    /// q (Eq. 5).
    q: Power,
    /// q2 (Eq. 15).
    q2: Power,
    /// p2 (Eq. 15).
    p2: Power,
    /// ℵ3 (Eq. 6).
    aleph3: Power,
    /// ℵ3 − 1 (Eq. 11).
    aleph3_minus_one: Power,
}

impl Constants {
    fn new(g: &FtaftsmcGains, kappa: [f64; 2]) -> Self {
        Self {
            kappa,
            two_xi_sq: 2.0 * g.xi * g.xi,
            p: Power::new(g.p),
            q: Power::new(g.q),
            q2: Power::new(g.q2),
            p2: Power::new(g.p2),
            aleph3: Power::new(g.aleph3),
            aleph3_minus_one: Power::new(g.aleph3 - 1.0),
        }
    }
}

// Lane code note: the formulas below are the scalar ones with the operands
// of single products and sums written in the order `R op f64` that `Real`
// offers (IEEE `+` and `*` are commutative, so the bits are unchanged);
// no sum or product is re-associated. Value-dependent `if`s are
// `branch` (expensive sides) so each lane takes its own side.

/// `sign(x)` per lane ([`sign_of`]); for one flight the branch-free
/// integer form of [`crate::math::sign`] (the same bits: −1, 0 or +1), which
/// the scalar law has always used and which costs fewer instructions than
/// two selects.
#[cfg_attr(not(debug_assertions), inline(always))]
fn sgn<R: Real>(x: R) -> R {
    if R::LANES == 1 {
        R::splat(sign(x.get_lane(0)))
    } else {
        sign_of(x)
    }
}

/// `sig²(x) = |x|² sign(x)`, the bits of [`crate::math::sig`]`(x, 2.0)`.
#[cfg_attr(not(debug_assertions), inline(always))]
fn sig2<R: Real>(x: R) -> R {
    Power::Two.pow_abs(x) * sgn(x)
}

/// `Y(e) = 1 / (ℵ1 + (1 − ℵ1) exp(−ℵ2 |e|^ℵ3))` and its time derivative
/// (Eq. 6 with the erratum, Eq. 11), per lane for lanes.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn gain_shaping<R: Real>(g: &FtaftsmcGains, e: R, e_dot: R) -> (R, R) {
    gain_shaping_c(g, &Constants::new(g, [0.0; 2]), e, e_dot)
}

#[cfg_attr(not(debug_assertions), inline(always))]
fn gain_shaping_c<R: Real>(g: &FtaftsmcGains, c: &Constants, e: R, e_dot: R) -> (R, R) {
    if g.aleph1 == 1.0 {
        return (R::splat(1.0), R::splat(0.0));
    }
    let decay = (c.aleph3.pow_abs(e) * -g.aleph2).exp();
    let den = decay * (1.0 - g.aleph1) + g.aleph1;
    let y = R::splat(1.0) / den;
    // When |e|^ℵ3 overflows, decay is 0 and |e|^(ℵ3−1) may be ∞: the limit
    // of their product is 0 (the exponential wins), not 0·∞ = NaN.
    // |e|^(ℵ3−1) as `pow_abs_minus_one` (0 at e = 0 for ℵ3 > 1, 1 for ℵ3 = 1).
    let zero = R::splat(0.0);
    let pow = branch(
        decay.eq(zero),
        #[cfg_attr(not(debug_assertions), inline(always))]
        || zero,
        #[cfg_attr(not(debug_assertions), inline(always))]
        || {
            branch(
                e.eq(zero),
                #[cfg_attr(not(debug_assertions), inline(always))]
                || pow_abs_minus_one(e, g.aleph3),
                #[cfg_attr(not(debug_assertions), inline(always))]
                || c.aleph3_minus_one.pow_abs(e),
            )
        },
    );
    let y_dot = decay * (1.0 - g.aleph1) * g.aleph2 * g.aleph3 * pow * e_dot * sgn(e) / (den * den);
    (y, y_dot)
}

/// `κ1 = (2 − p) ε^(p−1)`, `κ2 = (p − 1) ε^(p−2)` (Eq. 9).
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn kappa(g: &FtaftsmcGains) -> [f64; 2] {
    [(2.0 - g.p) * pow_abs(g.epsilon, g.p - 1.0), (g.p - 1.0) * pow_abs(g.epsilon, g.p - 2.0)]
}

/// `S_Δ(e)` and `Ṡ_Δ` (Eq. 7, 9, 12): `sig^p(e)` outside `|e| ≤ ε`, the
/// quadratic `κ1 e + κ2 sig²(e)` inside, matching value and slope at `|e| = ε`.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn nonsingular_term<R: Real>(g: &FtaftsmcGains, e: R, e_dot: R) -> (R, R) {
    nonsingular_term_with(g, kappa(g), e, e_dot)
}

/// [`nonsingular_term`] with precomputed `[κ1, κ2]`.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn nonsingular_term_with<R: Real>(g: &FtaftsmcGains, kappa: [f64; 2], e: R, e_dot: R) -> (R, R) {
    nonsingular_term_c(g, &Constants::new(g, kappa), e, e_dot)
}

#[cfg_attr(not(debug_assertions), inline(always))]
fn nonsingular_term_c<R: Real>(g: &FtaftsmcGains, c: &Constants, e: R, e_dot: R) -> (R, R) {
    let [kappa1, kappa2] = c.kappa;
    let ae = e.abs();
    branch(
        ae.gt(R::splat(g.epsilon)),
        #[cfg_attr(not(debug_assertions), inline(always))]
        || {
            let pow_p = c.p.pow_abs(e);
            (pow_p * sgn(e), e_dot * g.p * pow_p / ae)
        },
        #[cfg_attr(not(debug_assertions), inline(always))]
        || (e * kappa1 + sig2(e) * kappa2, e_dot * kappa1 + ae * (2.0 * kappa2) * e_dot),
    )
}

/// Evaluate the fixed-time sliding surface (Eq. 5) and `ϖ` (Eq. 13).
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn sliding_surface<R: Real>(g: &FtaftsmcGains, e: R, e_dot: R) -> SurfaceTerms<R> {
    sliding_surface_with(g, kappa(g), e, e_dot)
}

/// [`sliding_surface`] with precomputed `[κ1, κ2]` (see [`kappa`]).
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn sliding_surface_with<R: Real>(g: &FtaftsmcGains, kappa: [f64; 2], e: R, e_dot: R) -> SurfaceTerms<R> {
    sliding_surface_c(g, &Constants::new(g, kappa), e, e_dot)
}

#[cfg_attr(not(debug_assertions), inline(always))]
fn sliding_surface_c<R: Real>(g: &FtaftsmcGains, c: &Constants, e: R, e_dot: R) -> SurfaceTerms<R> {
    let (y, y_dot) = gain_shaping_c(g, c, e, e_dot);
    let (s_delta, s_delta_dot) = nonsingular_term_c(g, c, e, e_dot);
    let pow_q = c.q.pow_abs(e);
    // λ sig^q(e) + γ S_Δ + η e
    let shape = pow_q * g.lambda * sgn(e) + s_delta * g.gamma + e * g.eta;
    // d/dt of the same bracket: λ q |e|^(q−1) ė + γ Ṡ_Δ + η ė
    let pow_q_minus_one = branch(
        e.eq(R::splat(0.0)),
        #[cfg_attr(not(debug_assertions), inline(always))]
        || pow_abs_minus_one(e, g.q),
        #[cfg_attr(not(debug_assertions), inline(always))]
        || pow_q / e.abs(),
    );
    let shape_dot = pow_q_minus_one * (g.lambda * g.q) * e_dot + s_delta_dot * g.gamma + e_dot * g.eta;
    SurfaceTerms { y, y_dot, s_delta, s_delta_dot, s: e_dot + y * shape, varpi: -y_dot * shape - y * shape_dot }
}

/// `ϖ2` (Eq. 15): `−[λ2 sig^q2(S) + γ2 sig^p2(S) + η2 S + δ̂/(2ξ²) S]`,
/// channel units per s². `|S|^q2` is saturated at
/// [`crate::law::POWER_LIMIT`] so that it never overflows.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn reaching_law<R: Real>(g: &FtaftsmcGains, s: R, delta_hat: R) -> R {
    reaching_law_c(g, &Constants::new(g, [0.0; 2]), s, delta_hat)
}

#[cfg_attr(not(debug_assertions), inline(always))]
fn reaching_law_c<R: Real>(g: &FtaftsmcGains, c: &Constants, s: R, delta_hat: R) -> R {
    // |S|^q2 and |S|^p2 share ln|S| when both are general powers.
    let (pow_q2, pow_p2) = Power::pow_abs_pair(c.q2, c.p2, s);
    let sign_s = sgn(s);
    -(saturate_power(pow_q2) * g.lambda2 * sign_s
        + (pow_p2 * sign_s) * g.gamma2
        + s * g.eta2
        + delta_hat / c.two_xi_sq * s)
}

/// `dδ̂/dt = α1 (S²/(2ξ²) − α2 δ̂)` (Eq. 17).
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn delta_hat_rate<R: Real>(g: &FtaftsmcGains, s: R, delta_hat: R) -> R {
    delta_hat_rate_c(g, &Constants::new(g, [0.0; 2]), s, delta_hat)
}

#[cfg_attr(not(debug_assertions), inline(always))]
fn delta_hat_rate_c<R: Real>(g: &FtaftsmcGains, c: &Constants, s: R, delta_hat: R) -> R {
    (s * s / c.two_xi_sq - delta_hat * g.alpha2) * g.alpha1
}

/// One FTAFTSMC channel: gains, the estimate δ̂ and the last surface terms,
/// of one flight (`R = f64`, the default) or of several flights side by
/// side sharing the gains (`R` a lane type, [`crate::lanes`]): lane `i`
/// has the bits of a one-flight channel fed lane `i`'s inputs.
#[derive(Clone, Copy, Debug)]
pub struct FtaftsmcAxis<R: Real = f64> {
    /// Gains (Tables 4–5), shared by every lane.
    pub gains: FtaftsmcGains,
    /// Current estimate δ̂ of δ = Λ² (Eq. 17).
    pub delta_hat: R,
    /// Surface terms of the last update.
    pub last: SurfaceTerms<R>,
    /// `ϖ2` of the last update (Eq. 15).
    pub last_reaching: R,
    /// `κ1`, `κ2` of Eq. 9, `2ξ²` and the exponents' paths, computed once
    /// from the gains.
    constants: Constants,
    /// δ̂ held (Eq. 17 not integrated) in the lanes where true; see
    /// [`AxisLaw::set_adaptation_frozen`].
    frozen: R::Mask,
}
crate::lanewise_struct!(FtaftsmcAxis { delta_hat, last, last_reaching, frozen } shared { gains, constants });

impl FtaftsmcAxis {
    /// A channel with δ̂ = `gains.delta_hat0`, after validating the gains
    /// ([`FtaftsmcGains::check`]).
    pub fn try_new(gains: FtaftsmcGains) -> Result<Self, GainError> {
        Self::try_with_gains(gains)
    }

    /// A channel with δ̂ = `gains.delta_hat0`, **without** validating the
    /// gains (`new_unchecked` semantics, kept infallible for `const`-like
    /// use and hot loops): the caller must have run
    /// [`FtaftsmcGains::check`] (scenario files do) or use
    /// [`FtaftsmcAxis::try_new`]. Out-of-range gains never panic but may
    /// give non-finite commands. [`crate::cascade::Cascade::new`] checks
    /// the gains of the laws it is given.
    pub fn new(gains: FtaftsmcGains) -> Self {
        Self::with_gains(gains)
    }
}

impl<R: Real> FtaftsmcAxis<R> {
    /// [`FtaftsmcAxis::try_new`] for any number type: every lane starts
    /// at δ̂ = `gains.delta_hat0`, released.
    pub fn try_with_gains(gains: FtaftsmcGains) -> Result<Self, GainError> {
        gains.check()?;
        Ok(Self::with_gains(gains))
    }

    /// [`FtaftsmcAxis::new`] (no validation) for any number type: every
    /// lane starts at δ̂ = `gains.delta_hat0`, released.
    pub fn with_gains(gains: FtaftsmcGains) -> Self {
        Self {
            gains,
            delta_hat: R::splat(gains.delta_hat0),
            last: SurfaceTerms::default(),
            last_reaching: R::splat(0.0),
            constants: Constants::new(&gains, kappa(&gains)),
            frozen: R::Mask::splat(false),
        }
    }

    /// Whether δ̂ is currently held ([`AxisLaw::set_adaptation_frozen`]),
    /// per lane.
    pub fn adaptation_frozen(&self) -> R::Mask {
        self.frozen
    }
}

impl<R: Real> AxisLaw<R> for FtaftsmcAxis<R> {
    const NAME: &'static str = "ftaftsmc";
    const ESTIMATE_NAMES: [&'static str; MAX_ESTIMATES] = ["delta_hat", "", ""];

    /// Returns `ϖ + ϖ2` (Eq. 13 + Eq. 15), so that `q̈_cmd = q̈_d + ϖ + ϖ2`
    /// (Eq. 18–20, 56–58 before model cancellation).
    ///
    /// Guards (no-ops on every meaningful input, see [`AxisLaw::update`]):
    /// NaN and no state change for a non-finite input; `e`, `ė` clamped to
    /// `±INPUT_LIMIT`; δ̂ projected onto `[0, STATE_LIMIT]` (δ̂ estimates
    /// Λ² ≥ 0, and Euler keeps it ≥ 0 anyway while `dt α1 α2 ≤ 1`).
    ///
    /// While frozen ([`AxisLaw::set_adaptation_frozen`]) the output uses the
    /// held δ̂ and Eq. 17 is not integrated.
    ///
    /// Lanes: the guards act per lane — a lane with a non-finite `e` or `ė`
    /// gets NaN and keeps all its states, the others advance (a non-finite
    /// `dt`, shared, gives NaN in every lane).
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn update(&mut self, e: R, e_dot: R, dt: f64) -> R {
        let ok = e.is_finite() & e_dot.is_finite();
        if !(dt.is_finite() && ok.any()) {
            return R::splat(f64::NAN);
        }
        // Lanes: the bad lanes compute on 0 (their results are dropped
        // below), so they take no path a finite input would not. A no-op
        // for one flight (`ok` is true here), removed at compile time.
        let (e, e_dot) = if R::LANES > 1 {
            (R::select(ok, e, R::splat(0.0)), R::select(ok, e_dot, R::splat(0.0)))
        } else {
            (e, e_dot)
        };
        let limit = R::splat(INPUT_LIMIT);
        let (e, e_dot) = (saturate(e, limit), saturate(e_dot, limit));
        let terms = sliding_surface_c(&self.gains, &self.constants, e, e_dot);
        let reaching = reaching_law_c(&self.gains, &self.constants, terms.s, self.delta_hat);
        // δ̂ + dt dδ̂/dt projected onto [0, STATE_LIMIT] (`f64::clamp`'s
        // order: the lower bound first), kept where frozen or the input bad.
        let advanced = self.delta_hat + delta_hat_rate_c(&self.gains, &self.constants, terms.s, self.delta_hat) * dt;
        let zero = R::splat(0.0);
        let limit = R::splat(STATE_LIMIT);
        let advanced = R::select(advanced.lt(zero), zero, advanced);
        let advanced = R::select(advanced.gt(limit), limit, advanced);
        self.delta_hat = R::select(ok & !self.frozen, advanced, self.delta_hat);
        self.last = SurfaceTerms::blend(ok, terms, self.last);
        self.last_reaching = R::select(ok, reaching, self.last_reaching);
        R::select(ok, terms.varpi + reaching, R::splat(f64::NAN))
    }

    fn sliding_variable(&self) -> R {
        self.last.s
    }

    fn estimates(&self) -> [R; 3] {
        [self.delta_hat, R::splat(0.0), R::splat(0.0)]
    }

    fn reset(&mut self) {
        *self = Self::with_gains(self.gains);
    }

    /// Lane `lane` back to δ̂ = `gains.delta_hat0`, released, zero surface
    /// terms; the other lanes untouched.
    fn reset_lane(&mut self, lane: usize) {
        self.put_lane(lane, FtaftsmcAxis::new(self.gains));
    }

    fn set_adaptation_frozen(&mut self, frozen: R::Mask) {
        self.frozen = frozen;
    }

    fn check_gains(&self) -> Result<(), GainError> {
        self.gains.check()
    }

    /// `v = ϖ + ϖ2(S, δ̂)`, `dδ̂/dt` of Eq. 17 (the `[0, STATE_LIMIT]`
    /// projection of [`AxisLaw::update`] is not applied: Eq. 17 keeps δ̂ ≥ 0
    /// from δ̂ ≥ 0 by itself); `dδ̂/dt = 0` while frozen.
    ///
    /// One flight (the analysis flies one): the gains are shared, and for
    /// lanes the freeze flag is lane 0's.
    fn continuous_rhs(&self, e: f64, e_dot: f64, estimates: [f64; 3]) -> Option<ContinuousRhs> {
        let (e, e_dot) = (saturate(e, INPUT_LIMIT), saturate(e_dot, INPUT_LIMIT));
        let c = &self.constants;
        let terms = sliding_surface_c(&self.gains, c, e, e_dot);
        let delta_hat = estimates[0];
        Some(ContinuousRhs {
            v: terms.varpi + reaching_law_c(&self.gains, c, terms.s, delta_hat),
            s: terms.s,
            estimates_rate: [
                if self.frozen.get_lane(0) { 0.0 } else { delta_hat_rate_c(&self.gains, c, terms.s, delta_hat) },
                0.0,
                0.0,
            ],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{exp, sig};
    use approx::assert_relative_eq;

    fn gains_xy() -> FtaftsmcGains {
        FtaftsmcGains::PAPER_XY
    }

    #[test]
    fn y_is_one_at_zero_and_tends_to_inverse_aleph1() {
        let g = gains_xy();
        assert_eq!(gain_shaping(&g, 0.0, 1.0).0, 1.0);
        let far = gain_shaping(&g, 50.0, 0.0).0;
        assert_relative_eq!(far, 1.0 / g.aleph1, epsilon = 1e-12);
        // Monotone in |e| between the two limits.
        let mid = gain_shaping(&g, 0.2, 0.0).0;
        assert!(mid > 1.0 && mid < 1.0 / g.aleph1);
    }

    #[test]
    fn s_delta_value_and_slope_continuous_at_epsilon() {
        for g in [FtaftsmcGains::PAPER_XY, FtaftsmcGains::PAPER_Z, FtaftsmcGains::PAPER_ROLL_PITCH] {
            for side in [1.0, -1.0] {
                let at = side * g.epsilon;
                let outside = side * g.epsilon * (1.0 + 1e-15);
                let (v_in, d_in) = nonsingular_term(&g, at, 1.0);
                // Evaluate the outer branch exactly at ε by its formula.
                let v_out = sig(at, g.p);
                let d_out = g.p * pow_abs(at, g.p - 1.0);
                assert!((v_in - v_out).abs() < 1e-12, "value jump {v_in} vs {v_out}");
                assert!((d_in - d_out).abs() < 1e-12, "slope jump {d_in} vs {d_out}");
                let (v_next, _) = nonsingular_term(&g, outside, 1.0);
                assert!((v_next - v_in).abs() < 1e-12);
            }
        }
    }

    fn finite_difference_check(g: &FtaftsmcGains, e: f64, e_dot: f64) {
        let h = 1e-7;
        let (y0, y_dot) = gain_shaping(g, e, e_dot);
        let (y1, _) = gain_shaping(g, e + h * e_dot, e_dot);
        let fd = (y1 - y0) / h;
        assert!((fd - y_dot).abs() < 1e-5 * (1.0 + y_dot.abs()), "Ẏ at e={e}: fd {fd} vs {y_dot}");
        let (s0, s_dot) = nonsingular_term(g, e, e_dot);
        let (s1, _) = nonsingular_term(g, e + h * e_dot, e_dot);
        let fd = (s1 - s0) / h;
        assert!((fd - s_dot).abs() < 1e-4 * (1.0 + s_dot.abs()), "Ṡ_Δ at e={e}: fd {fd} vs {s_dot}");
    }

    #[test]
    fn derivatives_match_finite_differences() {
        for g in [FtaftsmcGains::PAPER_XY, FtaftsmcGains::PAPER_Z] {
            for &e in &[-2.0, -0.3, -0.06, -0.03, 0.01, 0.04, 0.07, 0.5, 3.0] {
                for &e_dot in &[-1.3, 0.7] {
                    finite_difference_check(&g, e, e_dot);
                }
            }
        }
    }

    #[test]
    fn varpi_is_minus_time_derivative_of_surface_error_terms() {
        // Along a smooth trajectory e(t), S − ė = Y·shape(e); its time
        // derivative must equal −ϖ.
        let g = FtaftsmcGains::PAPER_Z;
        let e = |t: f64| 0.8 * crate::math::sin(1.3 * t) - 0.1;
        let e_dot = |t: f64| 0.8 * 1.3 * crate::math::cos(1.3 * t);
        let h = 1e-6;
        for &t in &[0.1, 0.5, 1.0, 2.2, 3.0] {
            let part = |t: f64| {
                let terms = sliding_surface(&g, e(t), e_dot(t));
                terms.s - e_dot(t)
            };
            let fd = (part(t + h) - part(t - h)) / (2.0 * h);
            let varpi = sliding_surface(&g, e(t), e_dot(t)).varpi;
            assert!((fd + varpi).abs() < 1e-5 * (1.0 + fd.abs()), "t={t}: fd {fd} vs −ϖ {}", -varpi);
        }
    }

    #[test]
    fn surface_is_finite_at_zero_and_huge_errors() {
        for g in
            [FtaftsmcGains::PAPER_XY, FtaftsmcGains::PAPER_Z, FtaftsmcGains::PAPER_ROLL_PITCH, FtaftsmcGains::PAPER_YAW]
        {
            for &(e, ed) in &[(0.0, 0.0), (0.0, 1.0), (100.0, -100.0), (-100.0, 0.0), (1e-300, 0.0)] {
                let mut axis = FtaftsmcAxis::new(g);
                let u = axis.update(e, ed, 1e-3);
                assert!(u.is_finite() && axis.delta_hat.is_finite(), "e={e} ė={ed} → {u}");
            }
        }
    }

    /// The channel's update with the exponents' paths, κ and 2ξ² chosen at
    /// construction (and ln|S| shared by the two reaching powers) gives the
    /// same bits as Eq. 5–17 written term by term with the free powers,
    /// as the law was before the hoisting.
    #[test]
    fn update_matches_the_term_by_term_formulas_bit_for_bit() {
        use crate::math::pow_abs_sat;
        fn reference(g: &FtaftsmcGains, delta_hat: f64, e: f64, e_dot: f64, dt: f64) -> (f64, f64) {
            let (y, y_dot) = if g.aleph1 == 1.0 {
                (1.0, 0.0)
            } else {
                let decay = exp(-g.aleph2 * pow_abs(e, g.aleph3));
                let den = g.aleph1 + (1.0 - g.aleph1) * decay;
                let pow = if decay == 0.0 { 0.0 } else { pow_abs_minus_one(e, g.aleph3) };
                (1.0 / den, (1.0 - g.aleph1) * decay * g.aleph2 * g.aleph3 * pow * e_dot * sign(e) / (den * den))
            };
            let [k1, k2] = kappa(g);
            let (sd, sd_dot) = if e.abs() > g.epsilon {
                let pp = pow_abs(e, g.p);
                (pp * sign(e), g.p * e_dot * pp / e.abs())
            } else {
                (k1 * e + k2 * sig(e, 2.0), k1 * e_dot + 2.0 * k2 * e.abs() * e_dot)
            };
            let pq = pow_abs(e, g.q);
            let shape = g.lambda * pq * sign(e) + g.gamma * sd + g.eta * e;
            let pq1 = if e == 0.0 { pow_abs_minus_one(e, g.q) } else { pq / e.abs() };
            let shape_dot = g.lambda * g.q * pq1 * e_dot + g.gamma * sd_dot + g.eta * e_dot;
            let s = e_dot + y * shape;
            let varpi = -y_dot * shape - y * shape_dot;
            let reaching = -(g.lambda2 * pow_abs_sat(s, g.q2) * sign(s)
                + g.gamma2 * sig(s, g.p2)
                + g.eta2 * s
                + delta_hat / (2.0 * g.xi * g.xi) * s);
            let rate = g.alpha1 * (s * s / (2.0 * g.xi * g.xi) - g.alpha2 * delta_hat);
            (varpi + reaching, (delta_hat + dt * rate).clamp(0.0, STATE_LIMIT))
        }
        let general_q = FtaftsmcGains { q: 1.3, aleph3: 2.5, q2: 1.7, ..FtaftsmcGains::PAPER_Z };
        for g in [
            FtaftsmcGains::PAPER_XY,
            FtaftsmcGains::PAPER_Z,
            FtaftsmcGains::PAPER_ROLL_PITCH,
            FtaftsmcGains::PAPER_YAW,
            general_q,
        ] {
            for &e in &[-3.0, -0.4, -0.05, -0.01, 0.0, 1e-7, 0.02, 0.05, 0.3, 2.5] {
                for &e_dot in &[-2.0, -0.1, 0.0, 0.03, 1.5] {
                    for &delta_hat in &[0.0, 0.7] {
                        let mut axis = FtaftsmcAxis::new(FtaftsmcGains { delta_hat0: delta_hat, ..g });
                        let u = axis.update(e, e_dot, 1e-3);
                        let (want_u, want_delta_hat) = reference(&g, delta_hat, e, e_dot, 1e-3);
                        assert_eq!(u.to_bits(), want_u.to_bits(), "{g:?} e={e} ė={e_dot}");
                        assert_eq!(axis.delta_hat.to_bits(), want_delta_hat.to_bits(), "{g:?} e={e} ė={e_dot}");
                    }
                }
            }
        }
    }

    #[test]
    fn delta_hat_follows_eq17_one_step() {
        let g = FtaftsmcGains::PAPER_Z;
        let mut axis = FtaftsmcAxis::new(FtaftsmcGains { delta_hat0: 0.3, ..g });
        let (e, ed, dt) = (0.2, -0.1, 1e-3);
        let s = sliding_surface(&g, e, ed).s;
        axis.update(e, ed, dt);
        let want = 0.3 + dt * g.alpha1 * (s * s / (2.0 * 0.08 * 0.08) - g.alpha2 * 0.3);
        assert_relative_eq!(axis.delta_hat, want, epsilon = 1e-15);
    }

    #[test]
    fn paper_gains_pass_and_bad_gains_name_the_field() {
        for g in
            [FtaftsmcGains::PAPER_XY, FtaftsmcGains::PAPER_Z, FtaftsmcGains::PAPER_ROLL_PITCH, FtaftsmcGains::PAPER_YAW]
        {
            g.check().unwrap();
        }
        let err = FtaftsmcGains { p: 1.2, ..FtaftsmcGains::PAPER_Z }.check().unwrap_err();
        assert_eq!(err.field, "p");
        assert_eq!(err.value, 1.2);
        let err = FtaftsmcGains { q2: 0.9, ..FtaftsmcGains::PAPER_Z }.check().unwrap_err();
        assert_eq!(err.field, "q2");
        let err = FtaftsmcGains { aleph1: 1.5, ..FtaftsmcGains::PAPER_Z }.check().unwrap_err();
        assert_eq!(err.field, "aleph1");
    }

    #[test]
    fn reaching_time_bound_matches_hand_computation() {
        // z: 1/(0.5·0.1) + 1/(1·0.6) = 20 + 1.6667
        assert_relative_eq!(FtaftsmcGains::PAPER_Z.reaching_time_bound(), 20.0 + 1.0 / 0.6, epsilon = 1e-12);
        // x, y: 1/(0.2·3) + 1/(2·0.8) = 1.6667 + 0.625
        assert_relative_eq!(FtaftsmcGains::PAPER_XY.reaching_time_bound(), 1.0 / 0.6 + 0.625, epsilon = 1e-12);
    }

    /// Saturation remedy: δ̂ is held while frozen, released it is Eq. 17 again.
    #[test]
    fn freezing_holds_delta_hat_and_keeps_the_output() {
        use crate::law::testing::{check_freeze, warmed};
        for g in
            [FtaftsmcGains::PAPER_XY, FtaftsmcGains::PAPER_Z, FtaftsmcGains::PAPER_ROLL_PITCH, FtaftsmcGains::PAPER_YAW]
        {
            let axis = warmed(FtaftsmcAxis::new(FtaftsmcGains { delta_hat0: 0.3, ..g }));
            assert!(!axis.adaptation_frozen());
            check_freeze(axis);
        }
    }

    /// A small deterministic generator for the lane tests (Knuth's MMIX LCG).
    struct Lcg(u64);

    impl Lcg {
        /// Uniform in `[-1, 1)`.
        fn next(&mut self) -> f64 {
            self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        }
    }

    /// The mask whose lane `i` is `f(i)`.
    fn mask<const N: usize>(f: impl Fn(usize) -> bool) -> crate::lanes::LaneMask<N> {
        let mut m = crate::lanes::LaneMask::<N>::splat(false);
        for i in 0..N {
            m.put_lane(i, f(i));
        }
        m
    }

    /// Every state of a one-flight channel, as bits.
    fn axis_bits(a: &FtaftsmcAxis) -> [u64; 10] {
        let t = a.last;
        [
            a.delta_hat.to_bits(),
            t.y.to_bits(),
            t.y_dot.to_bits(),
            t.s_delta.to_bits(),
            t.s_delta_dot.to_bits(),
            t.s.to_bits(),
            t.varpi.to_bits(),
            a.last_reaching.to_bits(),
            u64::from(a.frozen),
            a.gains.delta_hat0.to_bits(),
        ]
    }

    /// The channel on `Lanes<N>` against `N` one-flight channels fed each
    /// lane's inputs: per lane and bit for bit, outputs, `S`, estimates and
    /// every state, over 400 steps whose inputs make the lanes take
    /// different sides of every branch (|e| inside and outside ε, e = 0
    /// exactly, e and ė near zero, huge errors clamped at INPUT_LIMIT), with
    /// a NaN and an ∞ input in one lane, per-lane freezing switched on and
    /// off, a `dt = 0` step and a lane reset mid-run. Returns how many
    /// lane-steps were refused, frozen, inside ε and clamped, so the caller
    /// can check that each case happened.
    fn law_lanes_match_scalar<const N: usize>(gains: FtaftsmcGains, seed: u64) -> [usize; 4] {
        use crate::lanes::Lanes;
        let mut lanes = FtaftsmcAxis::<Lanes<N>>::with_gains(gains);
        let mut scalar = [FtaftsmcAxis::new(gains); N];
        let mut rng = Lcg(seed);
        let mut seen = [0usize; 4];
        for k in 0..400 {
            let dt = if k == 57 { 0.0 } else { 1e-3 * (1.0 + 9.0 * (k % 3) as f64) };
            let mut e = [0.0; N];
            let mut e_dot = [0.0; N];
            for i in 0..N {
                let (a, b) = (rng.next(), rng.next());
                (e[i], e_dot[i]) = match (i + k / 50) % 5 {
                    0 => (1e-4 * a, 1e-3 * b),
                    1 => (0.06 * a, 0.5 * b),
                    2 => (3.0 * a, 4.0 * b),
                    3 if k % 7 == 0 => (0.0, b),
                    3 => (1e13 * a, -1e13 * b),
                    _ => (0.5 * a + 0.2, 2.0 * b),
                };
            }
            if k == 120 {
                e[1 % N] = f64::NAN;
            }
            if k == 121 {
                e_dot[2 % N] = f64::INFINITY;
            }
            if k == 200 {
                lanes.reset_lane(3 % N);
                scalar[3 % N].reset();
            }
            let frozen: [bool; N] = core::array::from_fn(|i| (k / 30 + i) % 4 == 1);
            lanes.set_adaptation_frozen(mask(|i| frozen[i]));
            let out = lanes.update(Lanes(e), Lanes(e_dot), dt);
            for i in 0..N {
                scalar[i].set_adaptation_frozen(frozen[i]);
                let want = scalar[i].update(e[i], e_dot[i], dt);
                assert_eq!(out.0[i].to_bits(), want.to_bits(), "N={N} step {k} lane {i}: {} vs {want}", out.0[i]);
                assert_eq!(lanes.sliding_variable().0[i].to_bits(), scalar[i].sliding_variable().to_bits());
                assert_eq!(
                    lanes.estimates().map(|x| x.0[i].to_bits()),
                    scalar[i].estimates().map(f64::to_bits),
                    "N={N} step {k} lane {i}"
                );
                assert_eq!(axis_bits(&lanes.get_lane(i)), axis_bits(&scalar[i]), "N={N} step {k} lane {i}");
                seen[0] += usize::from(want.is_nan());
                seen[1] += usize::from(frozen[i]);
                seen[2] += usize::from(e[i].abs() <= gains.epsilon);
                seen[3] += usize::from(e[i].abs() > INPUT_LIMIT);
            }
        }
        seen
    }

    #[test]
    fn lanes_give_each_flight_the_bits_of_the_scalar_law() {
        let general = FtaftsmcGains { q: 1.3, aleph3: 2.5, q2: 1.7, delta_hat0: 0.4, ..FtaftsmcGains::PAPER_Z };
        // dt α1 α2 > 1: Euler drives δ̂ below 0 and the projection acts.
        let leaky = FtaftsmcGains { alpha1: 50.0, alpha2: 100.0, delta_hat0: 2.0, ..FtaftsmcGains::PAPER_XY };
        for (j, g) in [
            FtaftsmcGains::PAPER_XY,
            FtaftsmcGains::PAPER_Z,
            FtaftsmcGains::PAPER_ROLL_PITCH,
            FtaftsmcGains::PAPER_YAW,
            general,
            leaky,
        ]
        .into_iter()
        .enumerate()
        {
            for seen in [law_lanes_match_scalar::<4>(g, 11 + j as u64), law_lanes_match_scalar::<8>(g, 97 + j as u64)] {
                assert!(seen.iter().all(|&n| n > 0), "a case never happened: {seen:?}");
            }
        }
        // The leaky gains do hit the lower bound of the projection.
        let mut axis = FtaftsmcAxis::new(FtaftsmcGains {
            alpha1: 50.0,
            alpha2: 100.0,
            delta_hat0: 2.0,
            ..FtaftsmcGains::PAPER_XY
        });
        axis.update(0.01, 0.0, 1e-3);
        assert_eq!(axis.delta_hat.to_bits(), 0.0f64.to_bits());
    }

    /// `continuous_rhs` of a channel on lanes is the one-flight channel's
    /// with lane 0's freeze flag.
    #[test]
    fn continuous_rhs_on_lanes_uses_lane_zero() {
        use crate::lanes::Lanes;
        let g = FtaftsmcGains::PAPER_Z;
        let mut lanes = FtaftsmcAxis::<Lanes<4>>::with_gains(g);
        for frozen in [false, true] {
            lanes.set_adaptation_frozen(mask::<4>(|i| (i == 0) == frozen));
            let mut one = FtaftsmcAxis::new(g);
            one.set_adaptation_frozen(frozen);
            let (a, b) =
                (lanes.continuous_rhs(0.3, -0.2, [0.5, 0.0, 0.0]), one.continuous_rhs(0.3, -0.2, [0.5, 0.0, 0.0]));
            assert_eq!(a, b);
            assert_eq!(a.unwrap().estimates_rate[0] == 0.0, frozen);
        }
    }
}
