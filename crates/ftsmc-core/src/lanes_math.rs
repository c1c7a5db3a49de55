//! The one maths library on lanes: `exp`, `ln`, `atan`, `atan2`, `asin`,
//! `acos`, `sin`, `cos` and `sin_cos` over `[f64; N]`, with exactly the
//! bits of the scalar functions of [`crate::math`] on every lane.
//!
//! Each kernel is a port of the `libm` crate's function (itself a port of
//! musl's libm, from FreeBSD's msun / Sun's fdlibm; MIT licence for the
//! `libm` crate, the Sun notice permitting use with the notice kept):
//! `exp` (`e_exp.c`), `log` (`e_log.c`), `atan` (`s_atan.c`), `atan2`
//! (`e_atan2.c`), `asin` (`e_asin.c`), `acos` (`e_acos.c`), `sin`, `cos`,
//! `sincos` with the kernels `__sin`, `__cos` and the reduction
//! `__rem_pio2` (`k_sin.c`, `k_cos.c`, `e_rem_pio2.c`). The kernels
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
//! underflows, zero, negative and subnormal arguments of `ln`, `|x| > 1` of
//! `asin`/`acos`, arguments of `sin`/`cos` that need the multi-precision
//! reduction `__rem_pio2_large`, `|x| ≥ 2⁶⁶` of `atan`, infinite
//! arguments of `atan2`) are flagged per lane, and only when some lane is
//! flagged are those lanes recomputed by the scalar function itself: the
//! same bits by construction, at the scalar cost, for those lanes only.
//!
//! The tests (`tests/lanes_math.rs`) compare every kernel on `[f64; 4]` and
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

/// High 32 bits of `x`'s representation (fdlibm's `GET_HIGH_WORD`).
#[cfg_attr(not(debug_assertions), inline(always))]
fn high(x: f64) -> u32 {
    (x.to_bits() >> 32) as u32
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

// --------------------------------------------------------------------- atan

const ATANHI: [f64; 4] = [
    4.63647609000806093515e-01, /* atan(0.5)hi 0x3FDDAC67, 0x0561BB4F */
    7.85398163397448278999e-01, /* atan(1.0)hi 0x3FE921FB, 0x54442D18 */
    9.82793723247329054082e-01, /* atan(1.5)hi 0x3FEF730B, 0xD281F69B */
    1.57079632679489655800e+00, /* atan(inf)hi 0x3FF921FB, 0x54442D18 */
];
const ATANLO: [f64; 4] = [
    2.26987774529616870924e-17, /* atan(0.5)lo 0x3C7A2B7F, 0x222F65E2 */
    3.06161699786838301793e-17, /* atan(1.0)lo 0x3C81A626, 0x33145C07 */
    1.39033110312309984516e-17, /* atan(1.5)lo 0x3C700788, 0x7AF0CBBD */
    6.12323399573676603587e-17, /* atan(inf)lo 0x3C91A626, 0x33145C07 */
];
const AT: [f64; 11] = [
    3.33333333333329318027e-01,  /* 0x3FD55555, 0x5555550D */
    -1.99999999998764832476e-01, /* 0xBFC99999, 0x9998EBC4 */
    1.42857142725034663711e-01,  /* 0x3FC24924, 0x920083FF */
    -1.11111104054623557880e-01, /* 0xBFBC71C6, 0xFE231671 */
    9.09088713343650656196e-02,  /* 0x3FB745CD, 0xC54C206E */
    -7.69187620504482999495e-02, /* 0xBFB3B0F2, 0xAF749A6D */
    6.66107313738753120669e-02,  /* 0x3FB10D66, 0xA0D03D51 */
    -5.83357013379057348645e-02, /* 0xBFADDE2D, 0x52DEFD9A */
    4.97687799461593236017e-02,  /* 0x3FA97B4B, 0x24760DEB */
    -3.65315727442169155270e-02, /* 0xBFA2B444, 0x2C6A6C2F */
    1.62858201153657823623e-02,  /* 0x3F90AD3A, 0xE322DA11 */
];

/// One lane of `atan` (`s_atan.c`) without its `|x| ≥ 2⁶⁶`/NaN branch:
/// `(value, rare)`, `rare` where that branch applies.
#[cfg_attr(not(debug_assertions), inline(always))]
fn atan_lane(x: f64) -> (f64, bool) {
    let hfull = high(x);
    let sign = hfull >> 31;
    let ix = hfull & 0x7fff_ffff;
    let rare = ix >= 0x4410_0000;
    let ax = f64::from_bits(x.to_bits() & 0x7fff_ffff_ffff_ffff);
    // id: -1 for |x| < 0.4375, else the table entry; the reduced argument
    // is num / den of that entry's branch (one division per lane).
    let small = ix < 0x3fdc_0000;
    let b0 = ix < 0x3fe6_0000; // 7/16 <= |x| < 11/16
    let b1 = ix < 0x3ff3_0000; // 11/16 <= |x| < 19/16
    let b2 = ix < 0x4003_8000; // 19/16 <= |x| < 2.4375
    let num = if b0 {
        2. * ax - 1.
    } else if b1 {
        ax - 1.
    } else if b2 {
        ax - 1.5
    } else {
        -1.
    };
    let den = if b0 {
        2. + ax
    } else if b1 {
        ax + 1.
    } else if b2 {
        1. + 1.5 * ax
    } else {
        ax
    };
    let xr = sel(small, x, num / den);
    let z = xr * xr;
    let w = z * z;
    let s1 = z * (AT[0] + w * (AT[2] + w * (AT[4] + w * (AT[6] + w * (AT[8] + w * AT[10])))));
    let s2 = w * (AT[1] + w * (AT[3] + w * (AT[5] + w * (AT[7] + w * AT[9]))));
    let v_small = xr - xr * (s1 + s2);
    let hi = if b0 {
        ATANHI[0]
    } else if b1 {
        ATANHI[1]
    } else if b2 {
        ATANHI[2]
    } else {
        ATANHI[3]
    };
    let lo = if b0 {
        ATANLO[0]
    } else if b1 {
        ATANLO[1]
    } else if b2 {
        ATANLO[2]
    } else {
        ATANLO[3]
    };
    let zt = hi - (xr * (s1 + s2) - lo - xr);
    let v_table = sel(sign != 0, -zt, zt);
    // |x| < 2^-27: x itself.
    let v = sel(small, sel(ix < 0x3e40_0000, x, v_small), v_table);
    (v, rare)
}

/// `atan x` (rad) on each lane: [`crate::math::atan`] (`libm::atan`,
/// fdlibm's `s_atan.c`: reduction to `|t| ≤ 7/16` about 0, ½, 1, 3⁄2 or ∞
/// and an odd degree-23 polynomial), bit for bit. Vectorised for
/// `|x| < 2⁶⁶`; larger, infinite and NaN lanes go through the scalar
/// function.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn atan<const N: usize>(x: [f64; N]) -> [f64; N] {
    let mut out = [0.0; N];
    let mut rare = [0u64; N];
    for i in 0..N {
        let (v, r) = atan_lane(x[i]);
        out[i] = v;
        rare[i] = bits(r);
    }
    if any(&rare) {
        patch(&mut out, &rare, &x, math::atan);
    }
    out
}

// -------------------------------------------------------------------- atan2

const PI: f64 = 3.1415926535897931160E+00; /* 0x400921FB, 0x54442D18 */
const PI_LO: f64 = 1.2246467991473531772E-16; /* 0x3CA1A626, 0x33145C07 */

/// `atan2(y, x)` (rad) on each lane: [`crate::math::atan2`]
/// (`libm::atan2`, fdlibm's `e_atan2.c`: `atan(|y/x|)` placed in its
/// quadrant with `π` split in two parts), bit for bit. Vectorised for
/// finite arguments with `x ≠ 1`, including `y = 0`, `x = 0` and
/// `|y/x| > 2⁶⁴`; NaN, infinite and `x = 1` lanes go through the scalar
/// function.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn atan2<const N: usize>(y: [f64; N], x: [f64; N]) -> [f64; N] {
    let mut out = [0.0; N];
    let mut rare = [0u64; N];
    for i in 0..N {
        let (yi, xi) = (y[i], x[i]);
        let hx = high(xi);
        let lx = xi.to_bits() as u32;
        let hy = high(yi);
        let ly = yi.to_bits() as u32;
        let ix = hx & 0x7fff_ffff;
        let iy = hy & 0x7fff_ffff;
        // NaN or infinite operands, x == 1 (atan(y)): scalar.
        let x_one = (hx.wrapping_sub(0x3ff0_0000) | lx) == 0;
        let r0 = ix >= 0x7ff0_0000 || iy >= 0x7ff0_0000 || x_one;
        let m = ((hy >> 31) & 1) | ((hx >> 30) & 2); /* 2*sign(x)+sign(y) */
        let y_neg = m & 1 != 0;
        let x_neg = m & 2 != 0;
        let y_zero = (iy | ly) == 0;
        let x_zero = (ix | lx) == 0;
        let half_pi = sel(y_neg, -PI / 2.0, PI / 2.0);
        let v_y_zero = sel(x_neg, sel(y_neg, -PI, PI), yi);
        let huge = ix.wrapping_add(64 << 20) < iy;
        let tiny_neg = x_neg && iy.wrapping_add(64 << 20) < ix;
        let (a, ra) = atan_lane(f64::from_bits((yi / xi).to_bits() & 0x7fff_ffff_ffff_ffff));
        let z = sel(tiny_neg, 0.0, a);
        let v = if x_neg {
            if y_neg {
                (z - PI_LO) - PI
            } else {
                PI - (z - PI_LO)
            }
        } else if y_neg {
            -z
        } else {
            z
        };
        let v = sel(huge, half_pi, v);
        let v = sel(x_zero, half_pi, v);
        out[i] = sel(y_zero, v_y_zero, v);
        // The atan branch for |y/x| >= 2^66 cannot be reached past `huge`
        // (|y/x| < 2^65); flagged anyway rather than assumed.
        rare[i] = bits(r0 || (ra && !(tiny_neg || huge || x_zero || y_zero)));
    }
    if any(&rare) {
        for i in 0..N {
            if rare[i] != 0 {
                out[i] = math::atan2(y[i], x[i]);
            }
        }
    }
    out
}

// ---------------------------------------------------------------- asin/acos

const PIO2_HI: f64 = 1.57079632679489655800e+00; /* 0x3FF921FB, 0x54442D18 */
const PIO2_LO: f64 = 6.12323399573676603587e-17; /* 0x3C91A626, 0x33145C07 */
const PS0: f64 = 1.66666666666666657415e-01; /* 0x3FC55555, 0x55555555 */
const PS1: f64 = -3.25565818622400915405e-01; /* 0xBFD4D612, 0x03EB6F7D */
const PS2: f64 = 2.01212532134862925881e-01; /* 0x3FC9C155, 0x0E884455 */
const PS3: f64 = -4.00555345006794114027e-02; /* 0xBFA48228, 0xB5688F3B */
const PS4: f64 = 7.91534994289814532176e-04; /* 0x3F49EFE0, 0x7501B288 */
const PS5: f64 = 3.47933107596021167570e-05; /* 0x3F023DE1, 0x0DFDF709 */
const QS1: f64 = -2.40339491173441421878e+00; /* 0xC0033A27, 0x1C8A2D4B */
const QS2: f64 = 2.02094576023350569471e+00; /* 0x40002AE5, 0x9C598AC8 */
const QS3: f64 = -6.88283971605453293030e-01; /* 0xBFE6066C, 0x1B8D0159 */
const QS4: f64 = 7.70381505559019352791e-02; /* 0x3FB3B8C5, 0xB12E9282 */

/// The rational approximation shared by `asin` and `acos` (`R(z)`).
#[cfg_attr(not(debug_assertions), inline(always))]
fn comp_r(z: f64) -> f64 {
    let p = z * (PS0 + z * (PS1 + z * (PS2 + z * (PS3 + z * (PS4 + z * PS5)))));
    let q = 1.0 + z * (QS1 + z * (QS2 + z * (QS3 + z * QS4)));
    p / q
}

/// `2⁻¹²⁰`, added to results that are rounded to make them inexact.
const X1P_120: f64 = f64::from_bits(0x3870_0000_0000_0000);

/// `asin x` (rad) on each lane: [`crate::math::asin`] (`libm::asin`,
/// fdlibm's `e_asin.c`: `x + x R(x²)` for `|x| < ½`, else through
/// `√((1 − |x|)/2)`), bit for bit. Vectorised for `|x| ≤ 1`; `|x| > 1`
/// and NaN lanes go through the scalar function.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn asin<const N: usize>(x: [f64; N]) -> [f64; N] {
    let mut out = [0.0; N];
    let mut rare = [0u64; N];
    for i in 0..N {
        let xi = x[i];
        let hx = high(xi);
        let ix = hx & 0x7fff_ffff;
        let lx = xi.to_bits() as u32;
        let ge1 = ix >= 0x3ff0_0000;
        let one = ge1 && ((ix.wrapping_sub(0x3ff0_0000)) | lx) == 0;
        rare[i] = bits(ge1 && !one);
        let small = ix < 0x3fe0_0000;
        let ax = f64::from_bits(xi.to_bits() & 0x7fff_ffff_ffff_ffff);
        let zb = (1.0 - ax) * 0.5;
        let zz = sel(small, xi * xi, zb);
        let r = comp_r(zz);
        // |x| < 0.5
        let v_small = sel((0x0010_0000..0x3e50_0000).contains(&ix), xi, xi + xi * r);
        // 1 > |x| >= 0.5
        let s = math::sqrt(zb);
        let v_975 = PIO2_HI - (2. * (s + s * r) - PIO2_LO);
        let f = f64::from_bits(s.to_bits() & 0xffff_ffff_0000_0000);
        let c = (zb - f * f) / (s + f);
        let v_mid = 0.5 * PIO2_HI - (2.0 * s * r - (PIO2_LO - 2.0 * c) - (0.5 * PIO2_HI - 2.0 * f));
        let v_big = sel(ix >= 0x3fef_3333, v_975, v_mid);
        let v_big = sel(hx >> 31 != 0, -v_big, v_big);
        let v = sel(small, v_small, v_big);
        // asin(+-1) = +-pi/2 with inexact.
        out[i] = sel(one, xi * PIO2_HI + X1P_120, v);
    }
    if any(&rare) {
        patch(&mut out, &rare, &x, math::asin);
    }
    out
}

/// `acos x` (rad) on each lane: [`crate::math::acos`] (`libm::acos`,
/// fdlibm's `e_acos.c`: `π/2 − (x + x R(x²))` for `|x| < ½`, else through
/// `√((1 ∓ x)/2)`), bit for bit. Vectorised for `|x| ≤ 1`; `|x| > 1` and
/// NaN lanes go through the scalar function.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn acos<const N: usize>(x: [f64; N]) -> [f64; N] {
    let mut out = [0.0; N];
    let mut rare = [0u64; N];
    for i in 0..N {
        let xi = x[i];
        let hx = high(xi);
        let ix = hx & 0x7fff_ffff;
        let lx = xi.to_bits() as u32;
        let neg = (hx >> 31) != 0;
        let ge1 = ix >= 0x3ff0_0000;
        let one = ge1 && ((ix.wrapping_sub(0x3ff0_0000)) | lx) == 0;
        rare[i] = bits(ge1 && !one);
        let v_one = sel(neg, 2. * PIO2_HI + X1P_120, 0.);
        let small = ix < 0x3fe0_0000;
        let zb = sel(neg, (1.0 + xi) * 0.5, (1.0 - xi) * 0.5);
        let zz = sel(small, xi * xi, zb);
        let r = comp_r(zz);
        // |x| < 0.5
        let v_small = sel(ix <= 0x3c60_0000, PIO2_HI + X1P_120, PIO2_HI - (xi - (PIO2_LO - xi * r)));
        let s = math::sqrt(zb);
        // x < -0.5
        let w_neg = r * s - PIO2_LO;
        let v_neg = 2. * (PIO2_HI - (s + w_neg));
        // x > 0.5
        let df = f64::from_bits(s.to_bits() & 0xffff_ffff_0000_0000);
        let c = (zb - df * df) / (s + df);
        let w_pos = r * s + c;
        let v_pos = 2. * (df + w_pos);
        let v = sel(small, v_small, sel(neg, v_neg, v_pos));
        out[i] = sel(one, v_one, v);
    }
    if any(&rare) {
        patch(&mut out, &rare, &x, math::acos);
    }
    out
}

// ------------------------------------------------------------ sin/cos/sincos

const S1: f64 = -1.66666666666666324348e-01; /* 0xBFC55555, 0x55555549 */
const S2: f64 = 8.33333333332248946124e-03; /* 0x3F811111, 0x1110F8A6 */
const S3: f64 = -1.98412698298579493134e-04; /* 0xBF2A01A0, 0x19C161D5 */
const S4: f64 = 2.75573137070700676789e-06; /* 0x3EC71DE3, 0x57B1FE7D */
const S5: f64 = -2.50507602534068634195e-08; /* 0xBE5AE5E6, 0x8A2B9CEB */
const S6: f64 = 1.58969099521155010221e-10; /* 0x3DE5D93A, 0x5ACFD57C */

const C1: f64 = 4.16666666666666019037e-02; /* 0x3FA55555, 0x5555554C */
const C2: f64 = -1.38888888888741095749e-03; /* 0xBF56C16C, 0x16C15177 */
const C3: f64 = 2.48015872894767294178e-05; /* 0x3EFA01A0, 0x19CB1590 */
const C4: f64 = -2.75573143513906633035e-07; /* 0xBE927E4F, 0x809C52AD */
const C5: f64 = 2.08757232129817482790e-09; /* 0x3E21EE9E, 0xBDB4B1C4 */
const C6: f64 = -1.13596475577881948265e-11; /* 0xBDA8FAE9, 0xBE8838D4 */

const INV_PIO2: f64 = 6.36619772367581382433e-01; /* 0x3FE45F30, 0x6DC9C883 */
const PIO2_1: f64 = 1.57079632673412561417e+00; /* 0x3FF921FB, 0x54400000 */
const PIO2_1T: f64 = 6.07710050650619224932e-11; /* 0x3DD0B461, 0x1A626331 */
const PIO2_2: f64 = 6.07710050630396597660e-11; /* 0x3DD0B461, 0x1A600000 */
const PIO2_2T: f64 = 2.02226624879595063154e-21; /* 0x3BA3198A, 0x2E037073 */
const PIO2_3: f64 = 2.02226624871116645580e-21; /* 0x3BA3198A, 0x2E000000 */
const PIO2_3T: f64 = 8.47842766036889956997e-32; /* 0x397B839A, 0x252049C1 */

/// `__sin(x, y, iy)` (`k_sin.c`) with the `iy` branch as a select.
#[cfg_attr(not(debug_assertions), inline(always))]
fn k_sin(x: f64, y: f64, iy: bool) -> f64 {
    let z = x * x;
    let w = z * z;
    let r = S2 + z * (S3 + z * S4) + z * w * (S5 + z * S6);
    let v = z * x;
    sel(iy, x - ((z * (0.5 * y - v * r) - y) - v * S1), x + v * (S1 + z * r))
}

/// `__cos(x, y)` (`k_cos.c`).
#[cfg_attr(not(debug_assertions), inline(always))]
fn k_cos(x: f64, y: f64) -> f64 {
    let z = x * x;
    let w = z * z;
    let r = z * (C1 + z * (C2 + z * C3)) + w * w * (C4 + z * (C5 + z * C6));
    let hz = 0.5 * z;
    let w = 1.0 - hz;
    w + (((1.0 - w) - hz) + (z * r - x * y))
}

/// The Cody-Waite reduction of `__rem_pio2`'s medium case
/// (`|x| < 2²⁰ π/2`): `(q, y0, y1)` with `q = n mod 4`, up to three rounds
/// as the scalar code takes them (computed all, then selected). The
/// exponent tests `ex − ey > 16` (`> 49`) are made on the biased exponents
/// as `u64`s, and `n mod 4` is read from the bits of `x · 2/π + 1.5·2⁵²`
/// (`n` itself is `f_n`), so a lane never leaves the 64-bit registers.
#[cfg_attr(not(debug_assertions), inline(always))]
fn medium_lane(x: f64) -> (u64, f64, f64) {
    let tmp = x * INV_PIO2 + TO_INT;
    let f_n = tmp - TO_INT;
    let q = tmp.to_bits() & 3;
    let r1 = x - f_n * PIO2_1;
    let w1 = f_n * PIO2_1T;
    let y01 = r1 - w1;
    let exponent = |v: f64| (v.to_bits() >> 52) & 0x7ff;
    let ex = exponent(x);
    let ey1 = exponent(y01);
    let t = r1;
    let w2a = f_n * PIO2_2;
    let r2 = t - w2a;
    let w2 = f_n * PIO2_2T - ((t - r2) - w2a);
    let y02 = r2 - w2;
    let ey2 = exponent(y02);
    let t = r2;
    let w3a = f_n * PIO2_3;
    let r3 = t - w3a;
    let w3 = f_n * PIO2_3T - ((t - r3) - w3a);
    let y03 = r3 - w3;
    let round2 = bits(ex > ey1 + 16);
    let round3 = round2 & bits(ex > ey2 + 49);
    let r = selb(round3, r3, selb(round2, r2, r1));
    let w = selb(round3, w3, selb(round2, w2, w1));
    let y0 = selb(round3, y03, selb(round2, y02, y01));
    (q, y0, (r - y0) - w)
}

/// `sin`/`cos`/`sincos` up to the quadrant, on all lanes: `(s, c, q, ax,
/// rare)` with `s = __sin`, `c = __cos` of the reduced argument (of `x`
/// itself for `|x| ≤ π/4`, with `iy = 0` for `__sin`), `q = n mod 4` the
/// quadrant (0 when not reduced), `ax = |x|`, `rare` for ±∞, NaN and
/// `|x| ≥ 2²⁰ π/2` (`__rem_pio2_large`). The medium reduction is computed
/// only when some lane needs it. Written for the vectoriser like [`exp`]:
/// the high-word range tests are comparisons of `|x|` with `at_high`
/// bounds, the small multiple `n` of π/2 is a double, and the quadrant is
/// read from the bits of `n + 1.5·2⁵²`.
#[allow(clippy::type_complexity)]
#[cfg_attr(not(debug_assertions), inline(always))]
fn sin_cos_core<const N: usize>(x: &[f64; N]) -> ([f64; N], [f64; N], [u64; N], [f64; N], [u64; N]) {
    let mut y0 = [0.0; N];
    let mut y1 = [0.0; N];
    let mut q = [0u64; N];
    let mut axs = [0.0; N];
    let mut rare = [0u64; N];
    let mut med = [0u64; N];
    let mut reduced = [0u64; N];
    for i in 0..N {
        let xi = x[i];
        let sign = xi.to_bits() & SIGN;
        let ax = f64::from_bits(xi.to_bits() & !SIGN);
        let ix = ax.to_bits() >> 32;
        axs[i] = ax;
        // ix >= 0x413921fb, or NaN.
        rare[i] = !bits(ax < at_high(0x4139_21fb));
        // ix > 0x3fe921fb: |x| > pi/4.
        let reduce = bits(ax >= at_high(0x3fe9_21fc));
        reduced[i] = reduce;
        // __rem_pio2, small multiples of pi/2 (|x| ~<= 9pi/4): n = +-1..4
        // and x - n pio2_1 - n pio2_1t, unless close to a multiple (medium).
        let le_5pio4 = bits(ax < at_high(0x400f_6a7b));
        let le_9pio4 = bits(ax < at_high(0x401c_463c));
        let le_7pio4 = bits(ax < at_high(0x4015_fdbd));
        let cancel = (le_5pio4 & bits((ix & 0xfffff) == 0x921fb))
            | (!le_5pio4 & le_7pio4 & bits(ix == 0x4012_d97c))
            | (!le_7pio4 & bits(ix == 0x4019_21fb));
        // 1 + [> 3pi/4] + [> 5pi/4] + [> 7pi/4] (each range test 0 or 1).
        let step = |m: u64| f64::from_bits(1f64.to_bits() & m);
        let k_small = 1.0 + step(bits(ax >= at_high(0x4002_d97d))) + step(!le_5pio4) + step(!le_7pio4);
        let nf_small = f64::from_bits(k_small.to_bits() | sign);
        let zs = xi - nf_small * PIO2_1;
        let y0s = zs - nf_small * PIO2_1T;
        let y1s = (zs - y0s) - nf_small * PIO2_1T;
        med[i] = reduce & (!le_9pio4 | cancel);
        y0[i] = selb(reduce, y0s, xi);
        y1[i] = selb(reduce, y1s, 0.0);
        q[i] = (nf_small + TO_INT).to_bits() & 3 & reduce;
    }
    if any(&med) {
        for i in 0..N {
            let (qm, a, b) = medium_lane(x[i]);
            let m = med[i];
            y0[i] = selb(m, a, y0[i]);
            y1[i] = selb(m, b, y1[i]);
            q[i] = (qm & m) | (q[i] & !m);
        }
    }
    let mut s = [0.0; N];
    let mut c = [0.0; N];
    for i in 0..N {
        s[i] = k_sin(y0[i], y1[i], reduced[i] != 0);
        c[i] = k_cos(y0[i], y1[i]);
    }
    (s, c, q, axs, rare)
}

/// `sin x` (rad) on each lane: [`crate::math::sin`] (`libm::sin`, fdlibm's
/// `s_sin.c`: `__rem_pio2` reduction to `[−π/4, π/4]` and the `__sin` /
/// `__cos` polynomials), bit for bit. Vectorised for `|x| < 2²⁰ π/2`;
/// larger, infinite and NaN lanes go through the scalar function.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn sin<const N: usize>(x: [f64; N]) -> [f64; N] {
    let mut out = [0.0; N];
    let (s, c, q, ax, rare) = sin_cos_core(&x);
    for i in 0..N {
        let (s, c, q, ax) = (s[i], c[i], q[i], ax[i]);
        // q: 0 => s, 1 => c, 2 => -s, 3 => -c (selects, not a jump table).
        let v = selb(bits(q & 1 != 0), c, s);
        let v = selb(bits(q & 2 != 0), -v, v);
        // |x| < 2^-26 (ix < 0x3e500000): x itself.
        out[i] = selb(bits(ax < at_high(0x3e50_0000)), x[i], v);
    }
    if any(&rare) {
        patch(&mut out, &rare, &x, math::sin);
    }
    out
}

/// `cos x` (rad) on each lane: [`crate::math::cos`] (`libm::cos`, fdlibm's
/// `s_cos.c`), bit for bit. Vectorised for `|x| < 2²⁰ π/2`; larger,
/// infinite and NaN lanes go through the scalar function.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn cos<const N: usize>(x: [f64; N]) -> [f64; N] {
    let mut out = [0.0; N];
    let (s, c, q, ax, rare) = sin_cos_core(&x);
    for i in 0..N {
        let (s, c, q, ax) = (s[i], c[i], q[i], ax[i]);
        // q: 0 => c, 1 => -s, 2 => -c, 3 => s (selects, not a jump table).
        let v = selb(bits(q & 1 != 0), s, c);
        let v = selb(bits((q + 1) & 2 != 0), -v, v);
        // |x| < 2^-27 sqrt(2) (ix < 0x3e46a09e): 1.
        out[i] = selb(bits(ax < at_high(0x3e46_a09e)), 1.0, v);
    }
    if any(&rare) {
        patch(&mut out, &rare, &x, math::cos);
    }
    out
}

/// `(sin x, cos x)` (rad) on each lane: [`crate::math::sin_cos`]
/// (`libm::sincos`), bit for bit. Vectorised for `|x| < 2²⁰ π/2`; larger,
/// infinite and NaN lanes go through the scalar function.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn sin_cos<const N: usize>(x: [f64; N]) -> ([f64; N], [f64; N]) {
    let mut so = [0.0; N];
    let mut co = [0.0; N];
    let (s, c, q, ax, rare) = sin_cos_core(&x);
    for i in 0..N {
        let (s, c, q, ax) = (s[i], c[i], q[i], ax[i]);
        // q: 0 => (s, c), 1 => (c, -s), 2 => (-s, -c), 3 => (-c, s).
        let odd = bits(q & 1 != 0);
        let vs = selb(odd, c, s);
        let vs = selb(bits(q & 2 != 0), -vs, vs);
        let vc = selb(odd, s, c);
        let vc = selb(bits((q + 1) & 2 != 0), -vc, vc);
        // |x| < 2^-27 sqrt(2) (ix < 0x3e46a09e): (x, 1).
        let tiny = bits(ax < at_high(0x3e46_a09e));
        so[i] = selb(tiny, x[i], vs);
        co[i] = selb(tiny, 1.0, vc);
    }
    if any(&rare) {
        for i in 0..N {
            if rare[i] != 0 {
                (so[i], co[i]) = math::sin_cos(x[i]);
            }
        }
    }
    (so, co)
}
