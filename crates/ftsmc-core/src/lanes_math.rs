//! The one maths library on lanes where it pays: `exp` and `ln` over
//! `[f64; N]`, with exactly the bits of the scalar functions of
//! [`crate::math`] on every lane. (The ports of `atan`, `atan2`, `asin`,
//! `acos`, `sin`, `cos` and `sin_cos` ran only from 8 lanes, a width the
//! simulator no longer flies: 8 lanes flew fewer steps per CPU-second than 4
//! on every Monte Carlo cell measured; those functions run per lane.)
//!
//! Each kernel is a port of the `libm` crate's function (itself a port of
//! musl's libm, from FreeBSD's msun / Sun's fdlibm; MIT licence for the
//! `libm` crate, the Sun notice permitting use with the notice kept):
//! `exp` (`e_exp.c`) and `log` (`e_log.c`). The kernels
//! perform **the same IEEE 754 operations in the same order** on each lane
//! as the scalar code does on that lane's argument: only the control flow
//! changes. Where the scalar code branches on the argument's range, a
//! kernel computes the candidate of every branch some lane may take with
//! plain per-lane loops (which the compiler turns into vector
//! instructions) and picks each lane's own branch with a select; a table
//! look-up becomes a select among the table's entries. Rust never
//! contracts `a * b + c` into a fused multiply-add, so every lane rounds as
//! the scalar code does, and lane `i` of a result has exactly the bits of
//! the scalar function of lane `i`'s argument.
//!
//! The rare ranges (NaN, ±∞, arguments where `exp` overflows or
//! underflows, zero, negative and subnormal arguments of `ln`) are flagged
//! per lane, and only when some lane is
//! flagged are those lanes recomputed by the scalar function itself: the
//! same bits by construction, at the scalar cost, for those lanes only.
//!
//! The tests (`tests/lanes_math.rs`) compare both kernels on `[f64; 4]` and
//! `[f64; 8]` with the scalar `libm` function bit for bit, over random bit
//! patterns, the ranges the controllers use, and every branch boundary of
//! the scalar code with its neighbours.

// The constants are written exactly as in the `libm` sources (fdlibm's
// decimal literals, their bits in the comments), so that a reader can
// compare them line by line; the tests check every kernel's bits.
#![allow(clippy::excessive_precision, clippy::approx_constant)]

use crate::elementary as math;

// ------------------------------------------------------------------ helpers

/// All bits set where `b`, clear elsewhere.
#[cfg_attr(not(debug_assertions), inline(always))]
fn bits(b: bool) -> u64 {
    (b as u64).wrapping_neg()
}

/// Some lane flagged.
#[cfg_attr(not(debug_assertions), inline(always))]
fn any<const N: usize>(m: &[u64; N]) -> bool {
    m.iter().fold(0, |acc, &v| acc | v) != 0
}

/// `a` where `m`, else `b` (a select, not a branch, once vectorised).
#[cfg_attr(not(debug_assertions), inline(always))]
fn sel(m: bool, a: f64, b: f64) -> f64 {
    selb(bits(m), a, b)
}

/// The sign bit of an `f64`.
const SIGN: u64 = 0x8000_0000_0000_0000;

/// `1.5 · 2⁵²` (`__rem_pio2`'s `toint`, `1.5/EPSILON`): `(t + TO_INT) −
/// TO_INT` is `t` rounded to the nearest integer (ties to even) for
/// `|t| < 2⁵¹`, and for an integer `n` there the low bits of `n + TO_INT`
/// are those of `n` (two's complement).
const TO_INT: f64 = 6_755_399_441_055_744.0;

/// `2⁵²`: for an integer `0 ≤ v < 2⁵²`, the bits of `2⁵² + v` are
/// `0x4330_0000_0000_0000 | v`, so `v` can be read from them.
const TWO52: f64 = 4_503_599_627_370_496.0;

/// The smallest non-negative double whose high 32 bits are `h`: for `|x|`
/// (not NaN), `high(|x|) ≥ h` exactly when `|x| ≥ at_high(h)`, so the
/// scalar code's high-word range tests become comparisons of doubles.
const fn at_high(h: u32) -> f64 {
    f64::from_bits((h as u64) << 32)
}

/// `a` where the mask `m` is all ones, `b` where it is zero.
#[cfg_attr(not(debug_assertions), inline(always))]
fn selb(m: u64, a: f64, b: f64) -> f64 {
    f64::from_bits((a.to_bits() & m) | (b.to_bits() & !m))
}

/// `t` truncated towards zero, as `t as i32 as f64` for `|t| < 2³¹`
/// (exact: the nearest integer, moved one towards zero when it is
/// farther from zero than `t`).
#[cfg_attr(not(debug_assertions), inline(always))]
fn trunc_small(t: f64) -> f64 {
    let r = (t + TO_INT) - TO_INT;
    let away = bits(f64::from_bits(r.to_bits() & !SIGN) > f64::from_bits(t.to_bits() & !SIGN));
    let one = f64::from_bits(1f64.to_bits() | (t.to_bits() & SIGN));
    selb(away, r - one, r)
}

/// Overwrite the flagged lanes of `out` with the scalar function of `x`.
/// Inlined: an out-of-line helper taking `&mut out` makes `out` live in
/// memory, and the vectoriser then splits the kernel into 2-lane halves
/// (measured on `exp`: 2 × slower at 4 lanes with AVX2).
#[cfg_attr(not(debug_assertions), inline(always))]
fn patch<const N: usize>(out: &mut [f64; N], rare: &[u64; N], x: &[f64; N], f: fn(f64) -> f64) {
    for i in 0..N {
        if rare[i] != 0 {
            out[i] = f(x[i]);
        }
    }
}

// ---------------------------------------------------------------------- exp

const HALF_EXP: f64 = 0.5;
const LN2HI: f64 = 6.93147180369123816490e-01; /* 0x3fe62e42, 0xfee00000 */
const LN2LO: f64 = 1.90821492927058770002e-10; /* 0x3dea39ef, 0x35793c76 */
const INVLN2: f64 = 1.44269504088896338700e+00; /* 0x3ff71547, 0x652b82fe */
const P1: f64 = 1.66666666666666019037e-01; /* 0x3FC55555, 0x5555553E */
const P2: f64 = -2.77777777770155933842e-03; /* 0xBF66C16C, 0x16BEBD93 */
const P3: f64 = 6.61375632143793436117e-05; /* 0x3F11566A, 0xAF25DE2C */
const P4: f64 = -1.65339022054652515390e-06; /* 0xBEBBBD41, 0xC5D26BF1 */
const P5: f64 = 4.13813679705723846039e-08; /* 0x3E663769, 0x72BEA4D0 */

/// `eˣ` on each lane: [`crate::math::exp`] (`libm::exp`, fdlibm's
/// `e_exp.c`: `x = k ln2 + r`, `|r| ≤ ln2/2`, a degree-5 rational
/// approximation of `eʳ`, scaled by `2ᵏ`), bit for bit. Vectorised for
/// `|x| < 708.39…` (where `2ᵏ` is a normal number) and `x < −745.13…`
/// (`+0`, down to `−∞`); NaN, `+∞`, overflow and the subnormal results go
/// through the scalar function.
///
/// Written for the vectoriser: every range test compares `|x|` with the
/// smallest double of the scalar code's high-word bound,
/// `k` stays a double (the truncation `(x/ln2 ± ½) as i32` is a rounding
/// by `1.5 · 2⁵²` corrected towards zero), and `2ᵏ` is built from the bits
/// of `k + 1023 + 2⁵²`, so no lane leaves the `f64`/`u64` registers.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn exp<const N: usize>(x: [f64; N]) -> [f64; N] {
    let mut out = [0.0; N];
    let mut rare = [0u64; N];
    for i in 0..N {
        let xi = x[i];
        let sign = xi.to_bits() & SIGN;
        let ax = f64::from_bits(xi.to_bits() & !SIGN);
        // x < -745.13...: +0 (down to -inf).
        let zero = bits(xi < -745.133_219_101_941_108_42);
        // |x| >= 708.39... (hx >= 0x4086232b) or NaN: scalar, except zero.
        rare[i] = !bits(ax < at_high(0x4086_232b)) & !zero;
        // Argument reduction for |x| > 0.5 ln2 (hx > 0x3fd62e42); k from
        // the quotient for |x| >= 1.5 ln2 (hx >= 0x3ff0a2b2), else ±1.
        let reduce = bits(ax >= at_high(0x3fd6_2e43));
        let big = bits(ax >= at_high(0x3ff0_a2b2));
        let t = INVLN2 * xi + f64::from_bits(HALF_EXP.to_bits() | sign);
        let k_big = trunc_small(t);
        let k_mid = f64::from_bits(1f64.to_bits() | sign);
        let kf = f64::from_bits(selb(big, k_big, k_mid).to_bits() & reduce);
        let hi_r = xi - kf * LN2HI;
        let lo_r = kf * LN2LO;
        let hi = selb(reduce, hi_r, xi);
        let lo = selb(reduce, lo_r, 0.0);
        let r = selb(reduce, hi_r - lo_r, xi);
        // x is now in the primary range.
        let xx = r * r;
        let c = r - xx * (P1 + xx * (P2 + xx * (P3 + xx * (P4 + xx * P5))));
        let y = 1. + (r * c / (2. - c) - lo + hi);
        // scalbn(y, k) for -1022 <= k <= 1023 is one product by 2^k.
        let scale = f64::from_bits((kf + (1023.0 + TWO52)).to_bits() << 52);
        let scaled = selb(bits(kf == 0.0), y, y * scale);
        // |x| <= 2^-28 (hx <= 0x3e300000): 1 + x.
        let v = selb(bits(ax >= at_high(0x3e30_0001)), scaled, 1. + xi);
        out[i] = selb(zero, 0.0, v);
    }
    if any(&rare) {
        patch(&mut out, &rare, &x, math::exp);
    }
    out
}

// ----------------------------------------------------------------------- ln

const LN2_HI: f64 = 6.93147180369123816490e-01; /* 3fe62e42 fee00000 */
const LN2_LO: f64 = 1.90821492927058770002e-10; /* 3dea39ef 35793c76 */
const LG1: f64 = 6.666666666666735130e-01; /* 3FE55555 55555593 */
const LG2: f64 = 3.999999999940941908e-01; /* 3FD99999 9997FA04 */
const LG3: f64 = 2.857142874366239149e-01; /* 3FD24924 94229359 */
const LG4: f64 = 2.222219843214978396e-01; /* 3FCC71C5 1D8E78AF */
const LG5: f64 = 1.818357216161805012e-01; /* 3FC74664 96CB03DE */
const LG6: f64 = 1.531383769920937332e-01; /* 3FC39A09 D078C69F */
const LG7: f64 = 1.479819860511658591e-01; /* 3FC2F112 DF3E5244 */

/// `ln x` on each lane: [`crate::math::ln`] (`libm::log`, fdlibm's
/// `e_log.c`: `x = 2ᵏ(1 + f)`, `√2/2 < 1 + f < √2`, `ln(1 + f)` by a
/// degree-14 polynomial in `s = f/(2 + f)`), bit for bit. Vectorised for
/// positive normal finite `x` and `±0` (`−∞`); negative, subnormal, `+∞`
/// and NaN lanes go through the scalar function.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn ln<const N: usize>(x: [f64; N]) -> [f64; N] {
    let mut out = [0.0; N];
    let mut rare = [0u64; N];
    for i in 0..N {
        let ui = x[i].to_bits();
        let hx = (ui >> 32) as u32;
        // Subnormal, negative (sign bit), +inf, NaN: scalar. ±0: libm's
        // -1/(x*x) is -inf.
        let zero = (ui << 1) == 0;
        rare[i] = bits((hx < 0x0010_0000 || (hx >> 31) != 0 || hx >= 0x7ff0_0000) && !zero);
        // Reduce x into [sqrt(2)/2, sqrt(2)].
        let hx = hx.wrapping_add(0x3ff0_0000 - 0x3fe6_a09e);
        let k = ((hx >> 20) as i32) - 0x3ff;
        let hx = (hx & 0x000f_ffff) + 0x3fe6_a09e;
        let xr = f64::from_bits(((hx as u64) << 32) | (ui & 0xffff_ffff));
        let f = xr - 1.0;
        let hfsq = 0.5 * f * f;
        let s = f / (2.0 + f);
        let z = s * s;
        let w = z * z;
        let t1 = w * (LG2 + w * (LG4 + w * LG6));
        let t2 = z * (LG1 + w * (LG3 + w * (LG5 + w * LG7)));
        let r = t2 + t1;
        let dk = k as f64;
        let v = s * (hfsq + r) + dk * LN2_LO - hfsq + f + dk * LN2_HI;
        // x == 1: exactly 0.
        let v = sel(ui == 0x3ff0_0000_0000_0000, 0.0, v);
        out[i] = sel(zero, f64::NEG_INFINITY, v);
    }
    if any(&rare) {
        patch(&mut out, &rare, &x, math::ln);
    }
    out
}
