//! Scalar maths of the whole toolkit: the control laws, the simulator, the
//! tuner and Python all take their transcendental functions from here.
//!
//! # One maths library
//!
//! Every function below is the pure-Rust [`libm`] crate (a port of musl's
//! libm), with or without `std`. The platform's libm is never called:
//! glibc picks an FMA or a non-FMA build of `sin`, `atan2`, `exp`, `pow` …
//! by the CPU at run time, and the two differ in the last bit for some
//! arguments, so the same seed gave different numbers on different
//! machines (measured: the runs.csv of `ftsmc montecarlo` of the paper's
//! scenarios and of realistic-scenario-2 differ from their second row on
//! when glibc is told to ignore AVX2 and FMA with
//! `GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2,-FMA`). `libm` is plain Rust
//! arithmetic, and Rust never fuses a multiply and an add on its own, so
//! its results are the same bits on every CPU and every feature level.
//! `clippy.toml` forbids the `f64` methods these functions replace.
//!
//! Powers with small integer exponents (2, 3, 4 appear in the paper's gains)
//! take the exact multiplication path; this is both faster and bit-for-bit
//! reproducible across platforms.

/// `|x|^a` for `x` of either sign. Returns 0 for `x = 0`, `a > 0`.
///
/// Exponents 1, 2, 3, 4 are exact multiplications, ½ and 3/2 go through the
/// correctly rounded `sqrt`, 0 gives 1; any other exponent is
/// `exp(a ln|x|)`, which agrees with the real power `|x|^a` to a relative
/// `(|a ln|x|| + 2) · 2⁻⁵²` (the rounding of `ln|x|` and of the product
/// `a ln|x|`, times the unit slope of `exp`, plus `exp`'s own rounding):
/// a few units in the last place for the arguments of the sliding laws,
/// at about 120 instructions (`ln` 63, `exp` 54) instead of the 270 of the full `pow`
/// ([`powf`]), whose extra-precise logarithm buys the last bit only. The
/// limits are those of `pow`: `0^a = 0` and `∞^a = ∞` for `a > 0`
/// (`exp(−∞) = 0`, `exp(∞) = ∞`), `0^a = ∞` and `∞^a = 0` for `a < 0`.
///
/// A law that raises to the same exponent every period chooses the path
/// once with [`Power::new`]; this function is `Power::new(a).pow_abs(x)`.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn pow_abs<R: Real>(x: R, a: f64) -> R {
    Power::new(a).pow_abs(x)
}

/// An exponent `a` with the evaluation path of [`pow_abs`] chosen once
/// (at construction), so that a law raising to its gains' exponents every
/// period does not compare `a` with 0, ½, 1, 3/2, 2, 3, 4 each time. Every
/// method gives the same bits as the free function it names.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Power {
    /// `a = 0`: `|x|⁰ = 1`.
    Zero,
    /// `a = ½`: `sqrt|x|`.
    Half,
    /// `a = 1`: `|x|`.
    One,
    /// `a = 3/2`: `|x| sqrt|x|`.
    ThreeHalves,
    /// `a = 2`: `|x| |x|`.
    Two,
    /// `a = 3`: `|x| |x| |x|`.
    Three,
    /// `a = 4`: `(|x| |x|)²`.
    Four,
    /// Any other `a`: `exp(a ln|x|)`.
    General(f64),
}

impl Power {
    /// The path of [`pow_abs`] for the exponent `a` (dimensionless).
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn new(a: f64) -> Self {
        if a == 1.0 {
            Self::One
        } else if a == 2.0 {
            Self::Two
        } else if a == 3.0 {
            Self::Three
        } else if a == 4.0 {
            Self::Four
        } else if a == 0.5 {
            Self::Half
        } else if a == 1.5 {
            Self::ThreeHalves
        } else if a == 0.0 {
            Self::Zero
        } else {
            Self::General(a)
        }
    }

    /// `|x|^a` (same bits as [`pow_abs`]), per lane for lanes.
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn pow_abs<R: Real>(self, x: R) -> R {
        let ax = x.abs();
        match self {
            Self::One => ax,
            Self::Two => ax * ax,
            Self::Three => ax * ax * ax,
            Self::Four => {
                let s = ax * ax;
                s * s
            }
            Self::Half => ax.sqrt(),
            Self::ThreeHalves => ax * ax.sqrt(),
            Self::Zero => R::splat(1.0),
            Self::General(a) => (ax.ln() * a).exp(),
        }
    }

    /// `(|x|^a, |x|^b)` for two exponents of the same base: for two
    /// [`Power::General`] exponents `ln|x|` is taken once (the same bits
    /// as two [`Power::pow_abs`] calls, one logarithm fewer).
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn pow_abs_pair<R: Real>(a: Self, b: Self, x: R) -> (R, R) {
        match (a, b) {
            (Self::General(ea), Self::General(eb)) => {
                let l = x.abs().ln();
                ((l * ea).exp(), (l * eb).exp())
            }
            _ => (a.pow_abs(x), b.pow_abs(x)),
        }
    }
}

/// `min(v, POWER_LIMIT)`: `v` saturated at [`crate::law::POWER_LIMIT`]
/// (1e100), the bound of [`pow_abs_sat`].
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn saturate_power<R: Real>(v: R) -> R {
    let limit = R::splat(crate::law::POWER_LIMIT);
    R::select(v.gt(limit), limit, v)
}

/// `min(|x|^a, POWER_LIMIT)`: [`pow_abs`] saturated at
/// [`crate::law::POWER_LIMIT`] (1e100), so that it never overflows to
/// infinity; identical to [`pow_abs`] below the limit.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn pow_abs_sat<R: Real>(x: R, a: f64) -> R {
    saturate_power(pow_abs(x, a))
}

/// `sign(x)`: −1, 0 or +1 (0 at exactly ±0 and for NaN, unlike
/// `f64::signum`). Computed as `(x > 0) − (x < 0)` in integers and
/// converted (exact), which compiles without branches.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn sign(x: f64) -> f64 {
    f64::from(i32::from(x > 0.0) - i32::from(x < 0.0))
}

/// [`sign`] of one flight or of lanes: −1, 0 or +1 per lane (0 at ±0 and
/// NaN), the same bits as [`sign`] in every lane.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn sign_of<R: Real>(x: R) -> R {
    let zero = R::splat(0.0);
    R::select(x.gt(zero), R::splat(1.0), R::select(x.lt(zero), R::splat(-1.0), zero))
}

/// `sig^a(x) = |x|^a sign(x)` (paper notation after Eq. 5).
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn sig<R: Real>(x: R, a: f64) -> R {
    pow_abs(x, a) * sign_of(x)
}

/// `|x|^(a−1)` used in derivatives of `sig^a`; returns 0 at `x = 0` when the
/// power would be singular (`a < 1`) so that callers stay finite.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn pow_abs_minus_one<R: Real>(x: R, a: f64) -> R {
    let at_zero = R::splat(if a == 1.0 { 1.0 } else { 0.0 });
    crate::lanes::branch(
        x.eq(R::splat(0.0)),
        #[cfg_attr(not(debug_assertions), inline(always))]
        || at_zero,
        #[cfg_attr(not(debug_assertions), inline(always))]
        || pow_abs(x, a - 1.0),
    )
}

use crate::lanes::Real;

pub use crate::elementary::{
    acos, asin, atan, atan2, cbrt, cos, exp, exp_m1, hypot, ln, log10, log2, powf, sin, sin_cos, sqrt, tanh,
};

/// `(sin x, cos x)` of the last argument, kept so that an angle that stays
/// the same from one control period to the next (a constant heading
/// reference) is not reduced and expanded again: [`SinCosCache::get`]
/// returns exactly [`sin_cos`]`(x)`, computed only when the bits of `x`
/// change.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SinCosCache {
    bits: u64,
    value: (f64, f64),
}

impl Default for SinCosCache {
    fn default() -> Self {
        Self::new()
    }
}

impl SinCosCache {
    /// A cache holding `sin_cos(0)`.
    pub fn new() -> Self {
        Self { bits: 0.0f64.to_bits(), value: sin_cos(0.0) }
    }

    /// `(sin x, cos x)` (rad), the same bits as [`sin_cos`]`(x)`.
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn get(&mut self, x: f64) -> (f64, f64) {
        if x.to_bits() != self.bits {
            self.value = sin_cos(x);
            self.bits = x.to_bits();
        }
        self.value
    }
}

/// `Σ (vᵢ − vᵢ)`: 0 when every element is finite, NaN when one is infinite
/// or NaN (`∞ − ∞` and `NaN − NaN` are NaN, and NaN survives the sum).
/// `finite_probe(a) + finite_probe(b) == 0.0` checks many values with
/// neither a branch per value nor a copy; the compiler may not fold
/// `v − v` to 0 (IEEE 754).
#[cfg_attr(not(debug_assertions), inline(always))]
#[allow(clippy::eq_op)] // v − v is the point: NaN for a non-finite v.
pub fn finite_probe<R: Real>(values: &[R]) -> R {
    let mut sum = R::splat(0.0);
    for &v in values {
        sum += v - v;
    }
    sum
}

/// A 3-vector (of one flight, or of lanes: [`crate::lanes`]).
pub type Vec3<R = f64> = [R; 3];
/// A 3×3 matrix, row-major: `m[row][column]`.
pub type Mat3<R = f64> = [[R; 3]; 3];

/// `a · b`.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn dot<R: Real>(a: &Vec3<R>, b: &Vec3<R>) -> R {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// `a × b`.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn cross<R: Real>(a: &Vec3<R>, b: &Vec3<R>) -> Vec3<R> {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// Euclidean norm `‖a‖`.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn norm<R: Real>(a: &Vec3<R>) -> R {
    dot(a, a).sqrt()
}

/// `m a`.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn mat_vec<R: Real>(m: &Mat3<R>, a: &Vec3<R>) -> Vec3<R> {
    [dot(&m[0], a), dot(&m[1], a), dot(&m[2], a)]
}

/// `mᵀ a`.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn mat_t_vec<R: Real>(m: &Mat3<R>, a: &Vec3<R>) -> Vec3<R> {
    core::array::from_fn(|i| m[0][i] * a[0] + m[1][i] * a[1] + m[2][i] * a[2])
}

/// `aᵀ b` of two 3×3 matrices.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn mat_t_mat<R: Real>(a: &Mat3<R>, b: &Mat3<R>) -> Mat3<R> {
    core::array::from_fn(|i| core::array::from_fn(|j| a[0][i] * b[0][j] + a[1][i] * b[1][j] + a[2][i] * b[2][j]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pow_abs_fast_paths_agree_with_powf() {
        for &x in &[-3.7, -0.2, 0.0, 1e-9, 0.5, 2.0, 41.0] {
            for &a in &[0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 0.1, 1.1] {
                let want = libm::pow(libm::fabs(x), a);
                let got = pow_abs(x, a);
                assert!((got - want).abs() <= 1e-12 * want.abs().max(1.0), "x={x} a={a}");
            }
        }
    }

    /// The general path `exp(a ln|x|)` stays within its documented bound of
    /// the full `pow` over the ranges the laws meet (errors from 1e-12 to
    /// 1e12, the exponents of the paper's tables and of the scenario
    /// ranges), and keeps `pow`'s limits at 0, ∞ and NaN.
    #[test]
    fn pow_abs_general_path_is_within_its_bound_of_pow() {
        let mut x = 1e-12;
        while x < 1e12 {
            for &a in &[0.1, 0.2, 0.4, 0.6, 1.1, 0.9, -0.9, -1.9, 1.0 / 3.0, 5.0 / 3.0, 2.5, 9.7] {
                let want = libm::pow(x, a);
                let bound = (libm::fabs(a * libm::log(x)) + 2.0) * f64::EPSILON;
                for sx in [x, -x] {
                    let got = pow_abs(sx, a);
                    assert!(libm::fabs(got - want) <= bound * want, "x={sx} a={a}: {got} vs pow {want}");
                }
            }
            x *= 1.37;
        }
        for &a in &[0.1, 1.1, 2.5] {
            assert_eq!(pow_abs(0.0, a), 0.0);
            assert_eq!(pow_abs(-0.0, a), 0.0);
            assert_eq!(pow_abs(f64::INFINITY, a), f64::INFINITY);
            assert_eq!(pow_abs(1.0, a), 1.0);
            assert!(pow_abs(f64::NAN, a).is_nan());
            assert_eq!(pow_abs(0.0, -a), f64::INFINITY);
            assert_eq!(pow_abs(f64::NEG_INFINITY, -a), 0.0);
        }
        assert_eq!(pow_abs(0.0, 0.0), 1.0);
        assert_eq!(pow_abs(1e300, 9.7), f64::INFINITY);
    }

    #[test]
    fn sin_cos_cache_gives_the_bits_of_sin_cos() {
        let mut cache = SinCosCache::new();
        for &x in &[0.0, -0.0, 0.3, 0.3, 1e6, f64::NAN, 0.0, -2.5, -2.5, f64::INFINITY] {
            let (s, c) = cache.get(x);
            let (ws, wc) = sin_cos(x);
            assert_eq!((s.to_bits(), c.to_bits()), (ws.to_bits(), wc.to_bits()), "x = {x}");
        }
    }

    #[test]
    fn sign_is_minus_one_zero_or_one() {
        for (x, want) in [
            (0.0, 0.0),
            (-0.0, 0.0),
            (f64::NAN, 0.0),
            (1e-310, 1.0),
            (-1e-310, -1.0),
            (3.5, 1.0),
            (-3.5, -1.0),
            (f64::INFINITY, 1.0),
            (f64::NEG_INFINITY, -1.0),
        ] {
            assert_eq!(sign(x).to_bits(), f64::to_bits(want), "sign({x})");
        }
    }

    #[test]
    fn finite_probe_is_zero_exactly_when_every_value_is_finite() {
        assert_eq!(finite_probe::<f64>(&[]), 0.0);
        assert_eq!(finite_probe(&[0.0, -0.0, 1e308, -1e308, 1e-310, f64::MAX]), 0.0);
        for bad in [f64::INFINITY, f64::NEG_INFINITY, f64::NAN] {
            for at in 0..3 {
                let mut v = [1.0, -2e300, 3.0];
                v[at] = bad;
                assert!(finite_probe(&v).is_nan(), "{v:?}");
            }
        }
    }

    #[test]
    fn sig_is_odd_and_zero_at_zero() {
        assert_eq!(sig(0.0, 0.1), 0.0);
        assert_eq!(sig(-2.0, 2.0), -4.0);
        assert_eq!(sig(2.0, 2.0), 4.0);
    }
}
