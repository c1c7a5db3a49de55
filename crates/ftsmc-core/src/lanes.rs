//! Lanes: the same arithmetic on one flight or on `N` flights side by side.
//!
//! The laws, the truth models and the actuators are written once, generic
//! over a [`Real`]: `f64` flies one flight, [`Lanes<N>`] flies `N` flights
//! in structure-of-arrays form (one `f64` per lane, each operation applied
//! lane by lane), which the compiler turns into vector instructions. Every
//! operation of [`Lanes`] is the IEEE 754 operation of `f64` on each lane,
//! and Rust never fuses a multiply and an add on its own, so **lane `i` of
//! a computation on `Lanes<N>` has exactly the bits of the same computation
//! on `f64` with lane `i`'s inputs** — whatever `N`, whatever the lane and
//! whatever vector width the CPU offers. Transcendental functions are the
//! one maths library's ([`crate::elementary`]), never a vector
//! approximation: called lane by lane, or, where that is faster, the lane
//! ports of the same algorithms ([`crate::lanes_math`]), which perform
//! `libm`'s operations in `libm`'s order on every lane and so give its bits.
//!
//! # Branches
//!
//! A comparison gives a [`Real::Mask`] (`bool` for `f64`). Where a scalar
//! law branches, lane code either computes both sides and picks with
//! [`Real::select`], or calls [`branch`]: for `f64` that is the plain `if`
//! (only the taken side is computed), for lanes it computes a side only if
//! some lane takes it and blends the two ([`Blend`]). Either way each lane
//! gets the value its own branch would have produced. Side effects (random
//! draws, state updates) never go inside a branch closure: update states
//! with `select` after computing the candidate.
//!
//! # Moving flights in and out of lanes
//!
//! [`Lanewise`] reads lane `i` of a value as its one-flight (`f64`) form and
//! writes a one-flight value into lane `i`: a batch starts a new flight in
//! a lane by writing the freshly built scalar state into it, and reads a
//! lane out to report it. [`lanewise_struct!`](crate::lanewise_struct)
//! implements it for a struct generic over `R: Real` field by field.

use core::fmt::Debug;
use core::ops::{Add, AddAssign, BitAnd, BitOr, Div, DivAssign, Mul, MulAssign, Neg, Not, Sub, SubAssign};

/// Reading and writing one lane of a value as its one-flight form.
pub trait Lanewise {
    /// The one-flight form (`f64` for a number, `bool` for a mask, the
    /// `f64` instance of a generic struct).
    type Scalar;
    /// Lane `i` (`i < LANES`; lane 0 of a one-flight value is itself).
    fn get_lane(&self, i: usize) -> Self::Scalar;
    /// Overwrite lane `i` with `v`.
    fn put_lane(&mut self, i: usize, v: Self::Scalar);
}

/// Per-lane choice between two values of a type: `blend(m, a, b)` is `a`
/// in the lanes where `m` is true and `b` elsewhere.
pub trait Blend<M>: Sized {
    /// `a` where `m`, else `b`, lane by lane.
    fn blend(m: M, a: Self, b: Self) -> Self;
}

/// A per-lane truth value: `bool` for one flight, [`LaneMask`] for lanes.
pub trait Mask:
    Copy
    + Debug
    + PartialEq
    + Send
    + Sync
    + 'static
    + BitAnd<Output = Self>
    + BitOr<Output = Self>
    + Not<Output = Self>
    + Default
    + Lanewise<Scalar = bool>
    + Blend<Self>
{
    /// Every lane `b`.
    fn splat(b: bool) -> Self;
    /// True in every lane.
    fn all(self) -> bool;
    /// True in some lane.
    fn any(self) -> bool;
}

/// A number of one flight (`f64`) or of `LANES` flights ([`Lanes`]): the
/// IEEE 754 operations of `f64`, lane by lane (module docs).
pub trait Real:
    Copy
    + Debug
    + Default
    + Send
    + Sync
    + 'static
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
    + DivAssign
    + Add<f64, Output = Self>
    + Sub<f64, Output = Self>
    + Mul<f64, Output = Self>
    + Div<f64, Output = Self>
    + Lanewise<Scalar = f64>
    + Blend<<Self as Real>::Mask>
{
    /// The result of a comparison.
    type Mask: Mask;
    /// Number of flights side by side (1 for `f64`).
    const LANES: usize;
    /// Every lane `v`.
    fn splat(v: f64) -> Self;
    /// Lane `i` is `f(i)`.
    fn from_fn(f: impl FnMut(usize) -> f64) -> Self;
    /// Correctly rounded square root ([`crate::elementary::sqrt`]).
    fn sqrt(self) -> Self;
    /// `|x|`.
    fn abs(self) -> Self;
    /// `f64::min` lane by lane (the other operand where one is NaN).
    fn min(self, other: Self) -> Self;
    /// `f64::max` lane by lane (the other operand where one is NaN).
    fn max(self, other: Self) -> Self;
    /// `self < other`.
    fn lt(self, other: Self) -> Self::Mask;
    /// `self <= other`.
    fn le(self, other: Self) -> Self::Mask;
    /// `self > other`.
    fn gt(self, other: Self) -> Self::Mask;
    /// `self >= other`.
    fn ge(self, other: Self) -> Self::Mask;
    /// `self == other` (IEEE: NaN equals nothing, `-0 == +0`).
    fn eq(self, other: Self) -> Self::Mask;
    /// Neither infinite nor NaN.
    fn is_finite(self) -> Self::Mask;
    /// NaN.
    fn is_nan(self) -> Self::Mask;
    /// `a` where `m`, else `b`.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn select(m: Self::Mask, a: Self, b: Self) -> Self {
        Self::blend(m, a, b)
    }
    /// `f` applied to every lane (a scalar function of [`crate::elementary`]).
    fn map(self, f: impl Fn(f64) -> f64) -> Self;
    /// `f` applied to the pairs of lanes of `self` and `other`.
    fn map2(self, other: Self, f: impl Fn(f64, f64) -> f64) -> Self;

    /// `sin x` (rad), [`crate::elementary::sin`] per lane.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn sin(self) -> Self {
        self.map(crate::elementary::sin)
    }
    /// `cos x` (rad), [`crate::elementary::cos`] per lane.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn cos(self) -> Self {
        self.map(crate::elementary::cos)
    }
    /// `(sin x, cos x)` (rad), [`crate::elementary::sin_cos`] per lane.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn sin_cos(self) -> (Self, Self) {
        let mut s = self;
        let mut c = self;
        for i in 0..Self::LANES {
            let (si, ci) = crate::elementary::sin_cos(self.get_lane(i));
            s.put_lane(i, si);
            c.put_lane(i, ci);
        }
        (s, c)
    }
    /// `eˣ`, [`crate::elementary::exp`] per lane.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn exp(self) -> Self {
        self.map(crate::elementary::exp)
    }
    /// `ln x`, [`crate::elementary::ln`] per lane.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn ln(self) -> Self {
        self.map(crate::elementary::ln)
    }
    /// `asin x` (rad), [`crate::elementary::asin`] per lane.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn asin(self) -> Self {
        self.map(crate::elementary::asin)
    }
    /// `acos x` (rad), [`crate::elementary::acos`] per lane.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn acos(self) -> Self {
        self.map(crate::elementary::acos)
    }
    /// `atan x` (rad), [`crate::elementary::atan`] per lane.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn atan(self) -> Self {
        self.map(crate::elementary::atan)
    }
    /// `atan2(self, x)` (rad), [`crate::elementary::atan2`] per lane.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn atan2(self, x: Self) -> Self {
        self.map2(x, crate::elementary::atan2)
    }
    /// `self^y`, [`crate::elementary::powf`] per lane.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn powf(self, y: Self) -> Self {
        self.map2(y, crate::elementary::powf)
    }
}

/// `a()` where `m`, else `b()`, computing only the sides some lane takes:
/// for one flight the plain `if`; for lanes both sides when the lanes
/// disagree, blended per lane. The closures must not have side effects
/// (module docs).
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn branch<M: Mask, T: Blend<M>>(m: M, a: impl FnOnce() -> T, b: impl FnOnce() -> T) -> T {
    if m.all() {
        a()
    } else if !m.any() {
        b()
    } else {
        T::blend(m, a(), b())
    }
}

// ---------------------------------------------------------------- one flight

impl Lanewise for f64 {
    type Scalar = f64;
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn get_lane(&self, _i: usize) -> f64 {
        *self
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn put_lane(&mut self, _i: usize, v: f64) {
        *self = v;
    }
}

impl Lanewise for bool {
    type Scalar = bool;
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn get_lane(&self, _i: usize) -> bool {
        *self
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn put_lane(&mut self, _i: usize, v: bool) {
        *self = v;
    }
}

impl Blend<bool> for f64 {
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn blend(m: bool, a: f64, b: f64) -> f64 {
        if m {
            a
        } else {
            b
        }
    }
}

impl Blend<bool> for bool {
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn blend(m: bool, a: bool, b: bool) -> bool {
        if m {
            a
        } else {
            b
        }
    }
}

impl Mask for bool {
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn splat(b: bool) -> Self {
        b
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn all(self) -> bool {
        self
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn any(self) -> bool {
        self
    }
}

impl Real for f64 {
    type Mask = bool;
    const LANES: usize = 1;
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn splat(v: f64) -> Self {
        v
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn from_fn(mut f: impl FnMut(usize) -> f64) -> Self {
        f(0)
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn sqrt(self) -> Self {
        crate::elementary::sqrt(self)
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn abs(self) -> Self {
        f64::abs(self)
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn min(self, other: Self) -> Self {
        f64::min(self, other)
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn max(self, other: Self) -> Self {
        f64::max(self, other)
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn lt(self, other: Self) -> bool {
        self < other
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn le(self, other: Self) -> bool {
        self <= other
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn gt(self, other: Self) -> bool {
        self > other
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn ge(self, other: Self) -> bool {
        self >= other
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn eq(self, other: Self) -> bool {
        self == other
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn is_finite(self) -> bool {
        f64::is_finite(self)
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn is_nan(self) -> bool {
        f64::is_nan(self)
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn map(self, f: impl Fn(f64) -> f64) -> Self {
        f(self)
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn map2(self, other: Self, f: impl Fn(f64, f64) -> f64) -> Self {
        f(self, other)
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn sin_cos(self) -> (Self, Self) {
        crate::elementary::sin_cos(self)
    }
}

// ---------------------------------------------------------------- N flights

/// `N` flights' numbers side by side, one `f64` per lane. Every operation
/// is `f64`'s on each lane (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(transparent)]
pub struct Lanes<const N: usize>(pub [f64; N]);

/// `N` flights' truth values: all bits set (true) or clear (false) per
/// lane, the form vector comparisons produce.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(transparent)]
pub struct LaneMask<const N: usize>(pub [u64; N]);

impl<const N: usize> Default for LaneMask<N> {
    /// False in every lane.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn default() -> Self {
        Self([0; N])
    }
}

impl<const N: usize> Default for Lanes<N> {
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn default() -> Self {
        Self([0.0; N])
    }
}

/// `[f(0), …, f(N − 1)]` by a plain loop (always inlined, unlike
/// `core::array::from_fn`, whose out-of-line instances would leave lane
/// arithmetic outside the dispatched kernels).
#[cfg_attr(not(debug_assertions), inline(always))]
fn lanes_of<const N: usize>(mut f: impl FnMut(usize) -> f64) -> [f64; N] {
    let mut out = [0.0; N];
    for (i, v) in out.iter_mut().enumerate() {
        *v = f(i);
    }
    out
}

#[cfg_attr(not(debug_assertions), inline(always))]
fn mask_bits(b: bool) -> u64 {
    (b as u64).wrapping_neg()
}

impl<const N: usize> LaneMask<N> {
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn from_fn(mut f: impl FnMut(usize) -> bool) -> Self {
        let mut m = [0u64; N];
        for (i, v) in m.iter_mut().enumerate() {
            *v = mask_bits(f(i));
        }
        Self(m)
    }
}

impl<const N: usize> Lanewise for Lanes<N> {
    type Scalar = f64;
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn get_lane(&self, i: usize) -> f64 {
        self.0[i]
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn put_lane(&mut self, i: usize, v: f64) {
        self.0[i] = v;
    }
}

impl<const N: usize> Lanewise for LaneMask<N> {
    type Scalar = bool;
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn get_lane(&self, i: usize) -> bool {
        self.0[i] != 0
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn put_lane(&mut self, i: usize, v: bool) {
        self.0[i] = mask_bits(v);
    }
}

impl<const N: usize> BitAnd for LaneMask<N> {
    type Output = Self;
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn bitand(self, o: Self) -> Self {
        let mut m = self.0;
        for i in 0..N {
            m[i] &= o.0[i];
        }
        Self(m)
    }
}

impl<const N: usize> BitOr for LaneMask<N> {
    type Output = Self;
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn bitor(self, o: Self) -> Self {
        let mut m = self.0;
        for i in 0..N {
            m[i] |= o.0[i];
        }
        Self(m)
    }
}

impl<const N: usize> Not for LaneMask<N> {
    type Output = Self;
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn not(self) -> Self {
        Self(self.0.map(|v| !v))
    }
}

impl<const N: usize> Blend<LaneMask<N>> for LaneMask<N> {
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn blend(m: LaneMask<N>, a: Self, b: Self) -> Self {
        let mut out = [0u64; N];
        for i in 0..N {
            out[i] = (a.0[i] & m.0[i]) | (b.0[i] & !m.0[i]);
        }
        Self(out)
    }
}

impl<const N: usize> Mask for LaneMask<N> {
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn splat(b: bool) -> Self {
        Self([mask_bits(b); N])
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn all(self) -> bool {
        self.0.iter().fold(u64::MAX, |acc, &v| acc & v) != 0
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn any(self) -> bool {
        self.0.iter().fold(0, |acc, &v| acc | v) != 0
    }
}

impl<const N: usize> Blend<LaneMask<N>> for Lanes<N> {
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn blend(m: LaneMask<N>, a: Self, b: Self) -> Self {
        let mut out = [0.0; N];
        for i in 0..N {
            out[i] = f64::from_bits((a.0[i].to_bits() & m.0[i]) | (b.0[i].to_bits() & !m.0[i]));
        }
        Self(out)
    }
}

macro_rules! lane_binary {
    ($tr:ident, $f:ident, $atr:ident, $af:ident, $op:tt) => {
        impl<const N: usize> $tr for Lanes<N> {
            type Output = Self;
            #[cfg_attr(not(debug_assertions), inline(always))]
            fn $f(self, o: Self) -> Self {
                let mut out = self.0;
                for i in 0..N {
                    out[i] = self.0[i] $op o.0[i];
                }
                Self(out)
            }
        }
        impl<const N: usize> $tr<f64> for Lanes<N> {
            type Output = Self;
            #[cfg_attr(not(debug_assertions), inline(always))]
            fn $f(self, o: f64) -> Self {
                let mut out = self.0;
                for i in 0..N {
                    out[i] = self.0[i] $op o;
                }
                Self(out)
            }
        }
        impl<const N: usize> $atr for Lanes<N> {
            #[cfg_attr(not(debug_assertions), inline(always))]
            fn $af(&mut self, o: Self) {
                *self = *self $op o;
            }
        }
    };
}

lane_binary!(Add, add, AddAssign, add_assign, +);
lane_binary!(Sub, sub, SubAssign, sub_assign, -);
lane_binary!(Mul, mul, MulAssign, mul_assign, *);
lane_binary!(Div, div, DivAssign, div_assign, /);

impl<const N: usize> Neg for Lanes<N> {
    type Output = Self;
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn neg(self) -> Self {
        Self(lanes_of(|i| -self.0[i]))
    }
}

impl<const N: usize> Real for Lanes<N> {
    type Mask = LaneMask<N>;
    const LANES: usize = N;
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn splat(v: f64) -> Self {
        Self([v; N])
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn from_fn(f: impl FnMut(usize) -> f64) -> Self {
        Self(lanes_of(f))
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn sqrt(self) -> Self {
        Self(lanes_of(|i| crate::elementary::sqrt(self.0[i])))
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn abs(self) -> Self {
        Self(lanes_of(|i| self.0[i].abs()))
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn min(self, o: Self) -> Self {
        let mut out = self.0;
        for i in 0..N {
            out[i] = f64::min(self.0[i], o.0[i]);
        }
        Self(out)
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn max(self, o: Self) -> Self {
        let mut out = self.0;
        for i in 0..N {
            out[i] = f64::max(self.0[i], o.0[i]);
        }
        Self(out)
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn lt(self, o: Self) -> LaneMask<N> {
        LaneMask::from_fn(|i| self.0[i] < o.0[i])
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn le(self, o: Self) -> LaneMask<N> {
        LaneMask::from_fn(|i| self.0[i] <= o.0[i])
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn gt(self, o: Self) -> LaneMask<N> {
        LaneMask::from_fn(|i| self.0[i] > o.0[i])
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn ge(self, o: Self) -> LaneMask<N> {
        LaneMask::from_fn(|i| self.0[i] >= o.0[i])
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn eq(self, o: Self) -> LaneMask<N> {
        LaneMask::from_fn(|i| self.0[i] == o.0[i])
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn is_finite(self) -> LaneMask<N> {
        LaneMask::from_fn(|i| self.0[i].is_finite())
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn is_nan(self) -> LaneMask<N> {
        LaneMask::from_fn(|i| self.0[i].is_nan())
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn map(self, f: impl Fn(f64) -> f64) -> Self {
        Self(lanes_of(|i| f(self.0[i])))
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn map2(self, o: Self, f: impl Fn(f64, f64) -> f64) -> Self {
        Self(lanes_of(|i| f(self.0[i], o.0[i])))
    }
    // `exp` and `ln` have lane kernels (`lanes_math`, the same bits as
    // the scalar functions); the others are the scalar function per lane.
    /// [`crate::elementary::sin`] per lane.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn sin(self) -> Self {
        self.map(crate::elementary::sin)
    }
    /// [`crate::elementary::cos`] per lane.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn cos(self) -> Self {
        self.map(crate::elementary::cos)
    }
    /// [`crate::elementary::sin_cos`] per lane.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn sin_cos(self) -> (Self, Self) {
        let mut s = self;
        let mut c = self;
        for i in 0..N {
            (s.0[i], c.0[i]) = crate::elementary::sin_cos(self.0[i]);
        }
        (s, c)
    }
    /// [`crate::lanes_math::exp`] (4 lanes and more) or
    /// [`crate::elementary::exp`] per lane: the same bits.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn exp(self) -> Self {
        if N >= EXP_KERNEL_LANES {
            Self(crate::lanes_math::exp(self.0))
        } else {
            self.map(crate::elementary::exp)
        }
    }
    /// [`crate::lanes_math::ln`]: [`crate::elementary::ln`]'s bits per lane.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn ln(self) -> Self {
        Self(crate::lanes_math::ln(self.0))
    }
    /// [`crate::elementary::asin`] per lane.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn asin(self) -> Self {
        self.map(crate::elementary::asin)
    }
    /// [`crate::elementary::acos`] per lane.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn acos(self) -> Self {
        self.map(crate::elementary::acos)
    }
    /// [`crate::elementary::atan`] per lane.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn atan(self) -> Self {
        self.map(crate::elementary::atan)
    }
    /// [`crate::elementary::atan2`] per lane.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn atan2(self, x: Self) -> Self {
        self.map2(x, crate::elementary::atan2)
    }
}

/// Lane count from which `Lanes::exp` uses [`crate::lanes_math::exp`]:
/// 0.57 × the time of four scalar calls (`cargo bench -p ftsmc-core --bench
/// lanes_math`), and the
/// controllers whose fractional powers are `exp(a ln|x|)` fly faster with
/// it (paper-scenario-2 FTAFTSMC on 4 lanes: 2.86–2.89 M steps per
/// CPU-second against 2.76–2.79 M with the other kernels as well).
pub const EXP_KERNEL_LANES: usize = 4;

// ---------------------------------------------------------------- composites

impl<T: Lanewise, const K: usize> Lanewise for [T; K] {
    type Scalar = [T::Scalar; K];
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn get_lane(&self, i: usize) -> Self::Scalar {
        core::array::from_fn(|k| self[k].get_lane(i))
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn put_lane(&mut self, i: usize, v: Self::Scalar) {
        for (slot, x) in self.iter_mut().zip(v) {
            slot.put_lane(i, x);
        }
    }
}

impl<M: Copy, T: Blend<M> + Copy, const K: usize> Blend<M> for [T; K] {
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn blend(m: M, a: Self, b: Self) -> Self {
        let mut out = a;
        for k in 0..K {
            out[k] = T::blend(m, a[k], b[k]);
        }
        out
    }
}

impl<M: Copy, A: Blend<M>, B: Blend<M>> Blend<M> for (A, B) {
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn blend(m: M, a: Self, b: Self) -> Self {
        (A::blend(m, a.0, b.0), B::blend(m, a.1, b.1))
    }
}

impl<M: Copy, A: Blend<M>, B: Blend<M>, C: Blend<M>> Blend<M> for (A, B, C) {
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn blend(m: M, a: Self, b: Self) -> Self {
        (A::blend(m, a.0, b.0), B::blend(m, a.1, b.1), C::blend(m, a.2, b.2))
    }
}

impl<A: Lanewise, B: Lanewise> Lanewise for (A, B) {
    type Scalar = (A::Scalar, B::Scalar);
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn get_lane(&self, i: usize) -> Self::Scalar {
        (self.0.get_lane(i), self.1.get_lane(i))
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn put_lane(&mut self, i: usize, v: Self::Scalar) {
        self.0.put_lane(i, v.0);
        self.1.put_lane(i, v.1);
    }
}

/// An optional part, present in every lane or in none: lane `i` of
/// `Some(x)` is `Some(lane i of x)`. Writing `Some` into `None` starts the
/// other lanes from `T::default()`; writing `None` makes the whole value
/// `None`.
impl<T: Lanewise + Default> Lanewise for Option<T> {
    type Scalar = Option<T::Scalar>;
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn get_lane(&self, i: usize) -> Self::Scalar {
        self.as_ref().map(|x| x.get_lane(i))
    }
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn put_lane(&mut self, i: usize, v: Self::Scalar) {
        match v {
            Some(v) => self.get_or_insert_with(T::default).put_lane(i, v),
            None => *self = None,
        }
    }
}

impl<M: Copy, T: Blend<M>> Blend<M> for Option<T> {
    /// Both present: blended; otherwise `a` (the presence is the same in
    /// every lane).
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn blend(m: M, a: Self, b: Self) -> Self {
        match (a, b) {
            (Some(a), Some(b)) => Some(T::blend(m, a, b)),
            (a, _) => a,
        }
    }
}

/// Implement [`Lanewise`] and [`Blend`] for a struct generic over one
/// `R: Real` parameter, field by field: lane `i` of `S<R>` is the `S<f64>`
/// whose fields are lane `i` of each field. Every per-lane field's type
/// must be [`Lanewise`] with the `S<f64>` field's type as its scalar
/// (numbers, masks, arrays of them, or such structs). Fields listed after
/// `shared` are the same in every lane (gains, settings: any `Clone` type):
/// read as themselves, overwritten when a lane is written, and taken from
/// the first operand of a blend.
///
/// ```ignore
/// lanewise_struct!(State { position, velocity, armed } shared { gains });
/// ```
#[macro_export]
macro_rules! lanewise_struct {
    ($name:ident { $($field:ident),* $(,)? } $(shared { $($shared:ident),* $(,)? })?) => {
        impl<R: $crate::lanes::Real> $crate::lanes::Lanewise for $name<R> {
            type Scalar = $name<f64>;
            #[cfg_attr(not(debug_assertions), inline(always))]
            fn get_lane(&self, i: usize) -> $name<f64> {
                $name {
                    $($field: $crate::lanes::Lanewise::get_lane(&self.$field, i),)*
                    $($($shared: ::core::clone::Clone::clone(&self.$shared),)*)?
                }
            }
            #[cfg_attr(not(debug_assertions), inline(always))]
            fn put_lane(&mut self, i: usize, v: $name<f64>) {
                $($crate::lanes::Lanewise::put_lane(&mut self.$field, i, v.$field);)*
                $($(self.$shared = v.$shared;)*)?
            }
        }
        impl<R: $crate::lanes::Real> $crate::lanes::Blend<R::Mask> for $name<R> {
            #[cfg_attr(not(debug_assertions), inline(always))]
            fn blend(m: R::Mask, a: Self, b: Self) -> Self {
                $name {
                    $($field: $crate::lanes::Blend::blend(m, a.$field, b.$field),)*
                    $($($shared: a.$shared,)*)?
                }
            }
        }
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    const SAMPLES: [f64; 12] =
        [0.0, -0.0, 1.5, -2.25, 1e-310, -3e300, f64::INFINITY, f64::NEG_INFINITY, f64::NAN, 0.1, 7.0, -1e-3];

    fn bits4(x: Lanes<4>) -> [u64; 4] {
        x.0.map(f64::to_bits)
    }

    /// Every operation on lanes gives, in each lane, the bits of the `f64`
    /// operation on that lane's operands — including NaN, ±0, ±∞ and
    /// subnormals, and `min`/`max` with a NaN operand.
    #[test]
    fn every_lane_operation_is_the_scalar_operation() {
        for (ia, &a0) in SAMPLES.iter().enumerate() {
            let a = Lanes::<4>::from_fn(|i| SAMPLES[(ia + i) % SAMPLES.len()]);
            let b = Lanes::<4>::from_fn(|i| SAMPLES[(ia * 5 + 3 * i + 1) % SAMPLES.len()]);
            let scalar =
                |f: &dyn Fn(f64, f64) -> f64| -> [u64; 4] { core::array::from_fn(|i| f(a.0[i], b.0[i]).to_bits()) };
            assert_eq!(bits4(a + b), scalar(&|x, y| x + y));
            assert_eq!(bits4(a - b), scalar(&|x, y| x - y));
            assert_eq!(bits4(a * b), scalar(&|x, y| x * y));
            assert_eq!(bits4(a / b), scalar(&|x, y| x / y));
            assert_eq!(bits4(a * a0), scalar(&|x, _| x * a0));
            assert_eq!(bits4(-a), scalar(&|x, _| -x));
            assert_eq!(bits4(Real::min(a, b)), scalar(&|x, y| Real::min(x, y)));
            assert_eq!(bits4(Real::max(a, b)), scalar(&|x, y| Real::max(x, y)));
            assert_eq!(bits4(Real::sqrt(a)), scalar(&|x, _| Real::sqrt(x)));
            assert_eq!(bits4(Real::abs(a)), scalar(&|x, _| Real::abs(x)));
            assert_eq!(bits4(a.atan2(b)), scalar(&|x, y| Real::atan2(x, y)));
            assert_eq!(bits4(a.exp()), scalar(&|x, _| Real::exp(x)));
            let (s, c) = Real::sin_cos(a);
            assert_eq!(bits4(s), scalar(&|x, _| Real::sin_cos(x).0));
            assert_eq!(bits4(c), scalar(&|x, _| Real::sin_cos(x).1));
            for i in 0..4 {
                let (x, y) = (a.0[i], b.0[i]);
                assert_eq!(Real::lt(a, b).get_lane(i), x < y);
                assert_eq!(Real::le(a, b).get_lane(i), x <= y);
                assert_eq!(Real::gt(a, b).get_lane(i), x > y);
                assert_eq!(Real::ge(a, b).get_lane(i), x >= y);
                assert_eq!(Real::eq(a, b).get_lane(i), x == y);
                assert_eq!(Real::is_finite(a).get_lane(i), x.is_finite());
                assert_eq!(Real::is_nan(a).get_lane(i), x.is_nan());
                let picked = Real::select(Real::lt(a, b), a, b).get_lane(i);
                assert_eq!(picked.to_bits(), if x < y { x } else { y }.to_bits());
            }
        }
    }

    #[test]
    fn masks_combine_lane_by_lane() {
        let a = LaneMask::<4>::from_fn(|i| i % 2 == 0);
        let b = LaneMask::<4>::from_fn(|i| i < 2);
        for i in 0..4 {
            assert_eq!((a & b).get_lane(i), i == 0);
            assert_eq!((a | b).get_lane(i), i != 3);
            assert_eq!((!a).get_lane(i), i % 2 == 1);
        }
        assert!(LaneMask::<4>::splat(true).all());
        assert!(!a.all() && a.any());
        assert!(!LaneMask::<4>::splat(false).any());
    }

    /// `branch` evaluates a side only when some lane takes it, and each lane
    /// gets its own side's value.
    #[test]
    fn branch_computes_only_the_sides_taken() {
        use core::cell::Cell;
        let calls = Cell::new((0, 0));
        let x = Lanes::<4>([1.0, -2.0, 3.0, -4.0]);
        let count = |left: bool| {
            let (l, r) = calls.get();
            calls.set(if left { (l + 1, r) } else { (l, r + 1) });
        };
        let y = branch(
            Real::gt(x, Lanes::splat(0.0)),
            #[cfg_attr(not(debug_assertions), inline(always))]
            || {
                count(true);
                Real::sqrt(x)
            },
            #[cfg_attr(not(debug_assertions), inline(always))]
            || {
                count(false);
                -x
            },
        );
        assert_eq!(y.0, [1.0, 2.0, crate::elementary::sqrt(3.0), 4.0]);
        assert_eq!(calls.get(), (1, 1));
        calls.set((0, 0));
        let _ = branch(
            Real::gt(x, Lanes::splat(-10.0)),
            #[cfg_attr(not(debug_assertions), inline(always))]
            || {
                count(true);
                x
            },
            #[cfg_attr(not(debug_assertions), inline(always))]
            || {
                count(false);
                x
            },
        );
        assert_eq!(calls.get(), (1, 0));
        let s = branch(
            2.0 > 1.0,
            #[cfg_attr(not(debug_assertions), inline(always))]
            || 1.0,
            #[cfg_attr(not(debug_assertions), inline(always))]
            || f64::NAN,
        );
        assert_eq!(s, 1.0);
    }

    #[derive(Clone, Copy, Debug, Default, PartialEq)]
    struct Demo<R: Real> {
        v: [R; 2],
        armed: R::Mask,
        gain: f64,
    }
    crate::lanewise_struct!(Demo { v, armed } shared { gain });

    #[test]
    fn a_struct_moves_in_and_out_of_a_lane() {
        let mut d = Demo::<Lanes<4>> { v: [Lanes::splat(0.0); 2], armed: LaneMask::splat(false), gain: 2.0 };
        d.put_lane(2, Demo { v: [1.0, 2.0], armed: true, gain: 2.0 });
        assert_eq!(d.get_lane(2), Demo { v: [1.0, 2.0], armed: true, gain: 2.0 });
        assert_eq!(d.get_lane(1), Demo { v: [0.0, 0.0], armed: false, gain: 2.0 });
        let picked = Demo::blend(LaneMask::from_fn(|i| i == 2), d, Demo { v: [Lanes::splat(9.0); 2], ..d });
        assert_eq!(picked.get_lane(2).v, [1.0, 2.0]);
        assert_eq!(picked.get_lane(0).v, [9.0, 9.0]);
    }
}
