//! The elementary functions of the one maths library (square root, powers,
//! exponentials, logarithms, trigonometry), each the pure-Rust [`libm`]
//! crate's with or without `std` (the square root: the correctly rounded
//! instruction). [`crate::math`] re-exports them; the lanes
//! ([`crate::lanes`]) call them lane by lane. Their own module, below both,
//! so that neither imports the other.

/// Define a scalar function of the one maths library: the pure-Rust
/// [`libm`] crate, with or without `std`.
macro_rules! one_libm {
    ($(#[$m:meta])* $name:ident ( $($arg:ident),* ) => $libm:ident) => {
        $(#[$m])*
        #[inline]
        pub fn $name($($arg: f64),*) -> f64 {
            libm::$libm($($arg),*)
        }
    };
}

one_libm!(/// `x^y` (real power).
    powf(x, y) => pow);
/// Square root (correctly rounded, as IEEE 754 requires, so every
/// implementation gives the same bits).
///
/// On x86 this is the `sqrtsd` instruction through its intrinsic rather
/// than `libm::sqrt`, whose inline assembly always emits the legacy SSE
/// encoding: inside code built for AVX (a `target-cpu` build or a
/// runtime-dispatched kernel) that encoding pays an SSE/AVX transition on
/// every call — measured 2.1× slower flights — and hides the operation from
/// the optimiser. The intrinsic follows the enclosing code's encoding.
#[inline]
pub fn sqrt(x: f64) -> f64 {
    #[cfg(all(target_arch = "x86_64", target_feature = "sse2"))]
    {
        use core::arch::x86_64::{_mm_cvtsd_f64, _mm_set_sd, _mm_sqrt_pd};
        // SAFETY: SSE2 is enabled for this build (the cfg above), which is
        // all these three intrinsics require; they touch no memory.
        unsafe { _mm_cvtsd_f64(_mm_sqrt_pd(_mm_set_sd(x))) }
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "sse2")))]
    {
        libm::sqrt(x)
    }
}
one_libm!(/// Cube root.
    cbrt(x) => cbrt);
one_libm!(/// Natural exponential `eˣ`.
    exp(x) => exp);
one_libm!(/// `eˣ − 1`, accurate for small `x`.
    exp_m1(x) => expm1);
one_libm!(/// Sine (rad).
    sin(x) => sin);
one_libm!(/// Cosine (rad).
    cos(x) => cos);
one_libm!(/// Arcsine (rad), in `[−π/2, π/2]`.
    asin(x) => asin);
one_libm!(/// Arccosine (rad), in `[0, π]`.
    acos(x) => acos);
one_libm!(/// Arctangent (rad), in `(−π/2, π/2)`.
    atan(x) => atan);
one_libm!(/// Four-quadrant arctangent of `y / x` (rad), in `[−π, π]`.
    atan2(y, x) => atan2);
one_libm!(/// Hyperbolic tangent.
    tanh(x) => tanh);
one_libm!(/// Natural logarithm.
    ln(x) => log);
one_libm!(/// Base-2 logarithm.
    log2(x) => log2);
one_libm!(/// Base-10 logarithm.
    log10(x) => log10);
one_libm!(/// `√(x² + y²)` without undue overflow.
    hypot(x, y) => hypot);

/// `(sin x, cos x)` in one call (rad).
#[inline]
pub fn sin_cos(x: f64) -> (f64, f64) {
    libm::sincos(x)
}
