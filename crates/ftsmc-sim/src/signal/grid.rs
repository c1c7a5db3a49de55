//! A [`Signal`] evaluated on a uniform time grid `t_m = m·δ` (`m` = 0, 1,
//! 2, …), as the run loop samples its disturbances, parameter variations
//! and reference: the same sum of terms, with every sine and cosine term
//! turned into a rotation instead of a call of `sin`/`cos` per sample.
//!
//! For a term `A·sin(ω t + φ)` the grid is cut into blocks of
//! [`BLOCK`] points. At the first point `a` of a block the term takes
//! `(sin θ_a, cos θ_a) = sin_cos(ω·(a·δ) + φ)` once; the `n`-th point after
//! it uses the angle-addition formulas
//!
//! ```text
//! sin(θ_a + nωδ) = sin θ_a · cos(nωδ) + cos θ_a · sin(nωδ)
//! cos(θ_a + nωδ) = cos θ_a · cos(nωδ) − sin θ_a · sin(nωδ)
//! ```
//!
//! with `(sin nωδ, cos nωδ)` tabulated once per term when the grid is built.
//! The sample's own argument `θ = ω t + φ`, formed from the caller's `t` as
//! [`Term::sample`] forms it, differs from `θ_a + nωδ` by a residual `r` of
//! a few units in its last place (the rounding of `t` and of `θ`); one more
//! first-order rotation by `r` (`sin(x + r) = sin x + r cos x`, the `r²/2`
//! left out is below 1e-25) lands on `θ` itself. Every sample is a few
//! products and sums away from `libm` values, so nothing accumulates from
//! one sample to the next: it agrees with [`Signal::value`] to a few units
//! in the last place of the amplitude (`tests` below bound it), as two
//! correctly rounded `sin` implementations would. The bits are not those of
//! [`Signal::value`]; they are a function of `(m, t)` alone (not of the
//! order of the calls), so a flight stays deterministic.
//!
//! The other terms (constants, steps, polynomials, waypoints, piecewise)
//! and the window are evaluated at the caller's time `t` exactly (bit for
//! bit) as
//! [`Signal::value`] and [`Signal::sample`] do.

use ftsmc_core::math::sin_cos;

use super::{Sample, Signal, Term};

/// Grid points per block: one `sin_cos` per sinusoid term every `BLOCK`
/// samples (a power of two, so the block index and offset are a shift and a mask).
pub const BLOCK: u64 = 64;

/// Sine and cosine terms of one signal that get a table (1.5 KiB each); any
/// beyond are evaluated directly, as [`Term::sample`] does, so a signal of
/// thousands of terms does not hold megabytes per flight.
pub const MAX_PHASORS: usize = 256;

/// `(τ_n, sin τ_n, cos τ_n)` with `τ_n = ω·(n·δ)` for `n = 0 … BLOCK − 1`
/// (fixed length: the offset `m mod BLOCK` indexes it without a bounds check).
type Table = [(f64, f64, f64); BLOCK as usize];

/// The sum `0.0 + c_1 + … + c_j` of `signal`'s leading constant terms and
/// their count `j` (the sum [`Signal::value`] has after them).
pub(crate) fn leading_constants(signal: &Signal) -> (f64, usize) {
    let leading = signal.terms.iter().take_while(|term| matches!(term, Term::Constant { .. })).count();
    let mut start = 0.0;
    for term in &signal.terms[..leading] {
        start += term.value(0.0);
    }
    (start, leading)
}

/// Row `n` of a sinusoid term's table: `(τ_n, sin τ_n, cos τ_n)` with
/// `τ_n = ω·(n·δ)` (ω in rad/s, δ = `step` in s).
pub(crate) fn table_row(omega: f64, n: usize, step: f64) -> (f64, f64, f64) {
    let tau = omega * (n as f64 * step);
    let (s, c) = sin_cos(tau);
    (tau, s, c)
}

/// The anchor of `block` for a term of angular frequency `omega` (rad/s)
/// and phase `phase` (rad): `(θ_a, sin θ_a, cos θ_a)` with
/// `θ_a = ω·(a·δ) + φ`, `a = block·BLOCK`, and the rotation `[U, V, W, Z]`
/// the term's value reads ([`term_value`]): `[sin θ_a, cos θ_a, cos θ_a,
/// −sin θ_a]` for a sine, `[cos θ_a, −sin θ_a, −sin θ_a, −cos θ_a]` for a
/// cosine.
pub(crate) fn anchor(omega: f64, phase: f64, cosine: bool, block: u64, step: f64) -> ((f64, f64, f64), [f64; 4]) {
    let theta_a = omega * ((block * BLOCK) as f64 * step) + phase;
    let (s, c) = sin_cos(theta_a);
    ((theta_a, s, c), if cosine { [c, -s, -s, -c] } else { [s, c, c, -s] })
}

/// A term's value at time `t` (s) from its anchor's `θ_a` and rotation
/// ([`anchor`]) and its table row `(τ_n, sin τ_n, cos τ_n)`
/// ([`table_row`]): `A·(X + Y·r)` with `X = U cos τ_n + V sin τ_n`,
/// `Y = W cos τ_n + Z sin τ_n` and the residual `r = (θ − θ_a) − τ_n` of
/// `θ = ω t + φ` ([`Phasor::value`] explains why these are the bits of
/// the rotated `A·sin` or `A·cos`).
#[allow(clippy::too_many_arguments)]
#[cfg_attr(not(debug_assertions), inline(always))]
pub(crate) fn term_value(
    amplitude: f64,
    omega: f64,
    phase: f64,
    theta_a: f64,
    [u, v, w, z]: [f64; 4],
    (tau, s_n, c_n): (f64, f64, f64),
    t: f64,
) -> f64 {
    let theta = omega * t + phase;
    let r = (theta - theta_a) - tau;
    let (x, y) = (u * c_n + v * s_n, w * c_n + z * s_n);
    amplitude * (x + y * r)
}

/// One `A·sin(ω t + φ)` or `A·cos(ω t + φ)` term on the grid.
#[derive(Clone, Debug)]
struct Phasor {
    /// Amplitude `A` (units of the signal).
    amplitude: f64,
    /// ω, rad/s.
    omega: f64,
    /// φ, rad.
    phase: f64,
    /// A cosine term (else a sine).
    cosine: bool,
    /// The anchor's argument `θ_a = ω·(a·δ) + φ` (rad) and `(sin θ_a, cos θ_a)`
    /// for the block its [`GridSignal`] holds.
    anchor: (f64, f64, f64),
    /// The anchor as the value's two rotations read it, `[U, V, W, Z]`
    /// ([`Phasor::value`]): `[sin θ_a, cos θ_a, cos θ_a, −sin θ_a]` for a
    /// sine, `[cos θ_a, −sin θ_a, −sin θ_a, −cos θ_a]` for a cosine.
    rotation: [f64; 4],
    /// The term's table.
    table: Box<Table>,
}

impl Phasor {
    fn new(amplitude: f64, omega: f64, phase: f64, cosine: bool, step: f64) -> Self {
        let table = Box::new(core::array::from_fn(|n| table_row(omega, n, step)));
        Self { amplitude, omega, phase, cosine, anchor: (0.0, 0.0, 1.0), rotation: [0.0; 4], table }
    }

    /// Take the anchor of `block`.
    fn set_anchor(&mut self, block: u64, step: f64) {
        (self.anchor, self.rotation) = anchor(self.omega, self.phase, self.cosine, block, step);
    }

    /// The residual `r = θ − θ_a − τ_n` of the term's argument `θ = ω t + φ`
    /// (formed as [`Term::sample`] forms it) at offset `n` of the anchor's
    /// block, and the table's `(sin τ_n, cos τ_n)`.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn residual(&self, n: usize, t: f64) -> (f64, f64, f64) {
        let (tau, s_n, c_n) = self.table[n];
        let theta = self.omega * t + self.phase;
        let r = (theta - self.anchor.0) - tau;
        (r, s_n, c_n)
    }

    /// `(sin θ, cos θ)` at offset `n` of the anchor's block, time `t ≈ m·δ`:
    /// the anchor rotated by the table's `τ_n`, then by the residual `r` to
    /// first order (`r²/2` is below 1e-25).
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn sin_cos_at(&self, n: usize, t: f64) -> (f64, f64) {
        let (_, s_a, c_a) = self.anchor;
        let (r, s_n, c_n) = self.residual(n, t);
        let (s, c) = (s_a * c_n + c_a * s_n, c_a * c_n - s_a * s_n);
        (s + c * r, c - s * r)
    }

    /// The term's value at offset `n` of the anchor's block, time `t`:
    /// `A·(X + Y·r)` with `X = U cos τ_n + V sin τ_n`, `Y = W cos τ_n +
    /// Z sin τ_n` ([`Phasor::rotation`]), one formula for both kinds and the
    /// bits of [`Phasor::sin_cos_at`]'s `A·sin` (sine) or `A·cos` (cosine):
    /// `a + (−b)·c` is `a − b·c` in IEEE arithmetic, and for a cosine
    /// `Y = (−sin θ_a) cos τ_n + (−cos θ_a) sin τ_n` is `−sin(θ_a + τ_n)`
    /// but for the sign of an exact zero, which `X + Y·r` absorbs (`X`, the
    /// cosine, is then ±1 to rounding).
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn value(&self, n: usize, t: f64) -> f64 {
        term_value(self.amplitude, self.omega, self.phase, self.anchor.0, self.rotation, self.table[n], t)
    }

    /// The term's value and derivatives at offset `n` of the anchor's block,
    /// time `t` (the formulas of [`Term::sample`]).
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn sample(&self, n: usize, t: f64) -> Sample {
        let (s, c) = self.sin_cos_at(n, t);
        let (a, w) = (self.amplitude, self.omega);
        if self.cosine {
            Sample { value: a * c, rate: -a * w * s, acceleration: -a * w * w * c }
        } else {
            Sample { value: a * s, rate: a * w * c, acceleration: -a * w * w * s }
        }
    }
}

/// One term of a [`GridSignal`] after its leading constants.
#[derive(Clone, Debug)]
enum GridTerm {
    /// A sine or cosine, rotated along the grid: its index among the phasors.
    Sinusoid(usize),
    /// [`Term::Constant`].
    Constant(f64),
    /// [`Term::Polynomial`]: its coefficients from degree 0 upward.
    Polynomial(Vec<f64>),
    /// Any other term, evaluated at `t` as [`Term::sample`] does.
    Other(Term),
}

/// How a [`GridSignal`]'s terms after the leading constants are summed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Shape {
    /// None: the signal is its leading constants' sum.
    Constant,
    /// One tabulated sinusoid (the first phasor).
    Sinusoid,
    /// One polynomial ([`GridSignal::polynomial`]).
    Polynomial,
    /// Only tabulated sinusoids, in the order of the phasors.
    Sinusoids,
    /// Anything else: the terms in order.
    General,
}

/// A [`Signal`] prepared for sampling on the grid `t_m = m·step` (module
/// documentation).
///
/// Every sample is the sum [`Signal::value`] forms, in its order from
/// `0.0`; what can be is formed once: the sum of the leading constant terms
/// (`0.0 + c_1 + c_2 …`, the same bits the sum has after them), and a
/// signal of those alone is that constant inside its window.
#[derive(Clone, Debug)]
pub struct GridSignal {
    step: f64,
    /// The window `[start, end]`, s, if any.
    window: Option<[f64; 2]>,
    /// `0.0 + c_1 + … + c_j`: the sum of the leading constant terms.
    start: f64,
    shape: Shape,
    /// The signal has no terms.
    empty: bool,
    /// The block whose anchors the phasors hold (`u64::MAX`: none yet).
    block: u64,
    /// The tabulated sine and cosine terms, in order.
    phasors: Vec<Phasor>,
    /// The terms after the leading constants ([`Shape::General`] only).
    terms: Vec<GridTerm>,
    /// The coefficients of the one polynomial of a [`Shape::Polynomial`]
    /// signal, from degree 0 upward.
    polynomial: Vec<f64>,
}

impl GridSignal {
    /// `signal` on the grid of spacing `step` (s, > 0). Tabulates
    /// `BLOCK` angles with their sines and cosines for each of the first
    /// [`MAX_PHASORS`] sinusoid terms (1.5 KiB each).
    pub fn new(signal: &Signal, step: f64) -> Self {
        let (start, leading) = leading_constants(signal);
        let mut phasors = Vec::new();
        let terms: Vec<GridTerm> = signal.terms[leading..]
            .iter()
            .map(|term| match term {
                Term::Sine { amplitude, phase, .. } | Term::Cosine { amplitude, phase, .. }
                    if phasors.len() < MAX_PHASORS =>
                {
                    let omega = term.angular_frequency().unwrap_or(0.0);
                    let cosine = matches!(term, Term::Cosine { .. });
                    phasors.push(Phasor::new(*amplitude, omega, *phase, cosine, step));
                    GridTerm::Sinusoid(phasors.len() - 1)
                }
                Term::Constant { value } => GridTerm::Constant(*value),
                Term::Polynomial { coefficients } => GridTerm::Polynomial(coefficients.clone()),
                other => GridTerm::Other(other.clone()),
            })
            .collect();
        let (shape, polynomial) = match terms.as_slice() {
            [] => (Shape::Constant, Vec::new()),
            [GridTerm::Sinusoid(_)] => (Shape::Sinusoid, Vec::new()),
            [GridTerm::Polynomial(coefficients)] => (Shape::Polynomial, coefficients.clone()),
            _ if terms.iter().all(|term| matches!(term, GridTerm::Sinusoid(_))) => (Shape::Sinusoids, Vec::new()),
            _ => (Shape::General, Vec::new()),
        };
        let terms = if shape == Shape::General { terms } else { Vec::new() };
        let window = signal.window;
        let empty = signal.terms.is_empty();
        Self { step, window, start, shape, empty, block: u64::MAX, phasors, terms, polynomial }
    }

    /// True when the signal has no terms (identically zero).
    pub fn is_zero(&self) -> bool {
        self.empty
    }

    /// The offset of grid point `m` in its block, the phasors' anchors
    /// moved to that block first (once every `BLOCK` samples).
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn offset(&mut self, m: u64) -> usize {
        let block = m / BLOCK;
        if block != self.block {
            self.set_anchors(block);
        }
        (m % BLOCK) as usize
    }

    #[cold]
    #[inline(never)]
    fn set_anchors(&mut self, block: u64) {
        for p in &mut self.phasors {
            p.set_anchor(block, self.step);
        }
        self.block = block;
    }

    /// The signal's window `[start, end]`, s, if any.
    pub fn window(&self) -> Option<[f64; 2]> {
        self.window
    }

    /// True when `t` (s) is outside the window (as [`Signal::value`] tests it).
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub(crate) fn outside(&self, t: f64) -> bool {
        match self.window {
            Some([start, end]) => t < start || t > end,
            None => false,
        }
    }

    /// The value at grid point `m`, whose time the caller computed as `t`
    /// (s, `≈ m·step`; the window and the non-sinusoid terms use it).
    #[cfg_attr(not(debug_assertions), inline(always))] // the loop calls it for every signal at every substep
    pub fn value(&mut self, m: u64, t: f64) -> f64 {
        if self.outside(t) {
            return 0.0;
        }
        self.value_inside(m, t)
    }

    /// [`GridSignal::value`] at a time `t` the caller found inside the
    /// window ([`GridSignal::window`]; any `t` without one): the sum
    /// without the window's test.
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn value_inside(&mut self, m: u64, t: f64) -> f64 {
        match self.shape {
            Shape::Constant => self.start,
            Shape::Sinusoid => {
                let n = self.offset(m);
                self.start + self.phasors[0].value(n, t)
            }
            Shape::Polynomial => self.start + super::polynomial(&self.polynomial, t).value,
            Shape::Sinusoids => {
                let n = self.offset(m);
                let mut out = self.start;
                for p in &self.phasors {
                    out += p.value(n, t);
                }
                out
            }
            Shape::General => self.general_value(m, t),
        }
    }

    /// [`GridSignal::value`] of a [`Shape::General`] signal inside its window.
    #[inline(never)]
    fn general_value(&mut self, m: u64, t: f64) -> f64 {
        let n = self.offset(m);
        let mut out = self.start;
        for term in &self.terms {
            out += match term {
                GridTerm::Sinusoid(p) => self.phasors[*p].value(n, t),
                GridTerm::Constant(value) => *value,
                GridTerm::Polynomial(coefficients) => super::polynomial(coefficients, t).value,
                GridTerm::Other(term) => term.value(t),
            };
        }
        out
    }

    /// Value and derivatives at grid point `m` of time `t` (as [`GridSignal::value`]).
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn sample(&mut self, m: u64, t: f64) -> Sample {
        if self.outside(t) {
            return Sample::default();
        }
        let mut out = Sample { value: self.start, ..Sample::default() };
        match self.shape {
            Shape::Constant => {}
            Shape::Sinusoid => {
                let n = self.offset(m);
                out += self.phasors[0].sample(n, t);
            }
            Shape::Polynomial => out += super::polynomial(&self.polynomial, t),
            Shape::Sinusoids => {
                let n = self.offset(m);
                for p in &self.phasors {
                    out += p.sample(n, t);
                }
            }
            Shape::General => {
                let n = self.offset(m);
                for term in &self.terms {
                    out += match term {
                        GridTerm::Sinusoid(p) => self.phasors[*p].sample(n, t),
                        GridTerm::Constant(value) => Sample { value: *value, ..Sample::default() },
                        GridTerm::Polynomial(coefficients) => super::polynomial(coefficients, t),
                        GridTerm::Other(term) => term.sample(t),
                    };
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The implementation before the leading constants were folded, the
    /// phasors shared one anchor block and the value took one formula for
    /// both kinds: the bits every sample must keep.
    mod previous {
        use ftsmc_core::math::sin_cos;

        use super::super::{BLOCK, MAX_PHASORS};
        use crate::signal::{polynomial, Sample, Signal, Term};

        /// One `A·sin(ω t + φ)` or `A·cos(ω t + φ)` term on the grid.
        #[derive(Clone, Debug)]
        struct Phasor {
            /// Amplitude `A` (units of the signal).
            amplitude: f64,
            /// ω, rad/s.
            omega: f64,
            /// φ, rad.
            phase: f64,
            /// A cosine term (else a sine).
            cosine: bool,
            /// Block whose anchor `anchor` holds (`u64::MAX`: none yet).
            block: u64,
            /// The anchor's argument `θ_a = ω·(a·δ) + φ` (rad) and `(sin θ_a, cos θ_a)`.
            anchor: (f64, f64, f64),
            /// `(τ_n, sin τ_n, cos τ_n)` with `τ_n = ω·(n·δ)` for `n = 0 … BLOCK − 1`.
            table: Box<[(f64, f64, f64)]>,
        }

        impl Phasor {
            fn new(amplitude: f64, omega: f64, phase: f64, cosine: bool, step: f64) -> Self {
                let table = (0..BLOCK)
                    .map(|n| {
                        let tau = omega * (n as f64 * step);
                        let (s, c) = sin_cos(tau);
                        (tau, s, c)
                    })
                    .collect();
                Self { amplitude, omega, phase, cosine, block: u64::MAX, anchor: (0.0, 0.0, 1.0), table }
            }

            /// Take the anchor of `block` (once every `BLOCK` samples).
            #[cold]
            #[inline(never)]
            fn set_anchor(&mut self, block: u64, step: f64) {
                let theta_a = self.omega * ((block * BLOCK) as f64 * step) + self.phase;
                let (s, c) = sin_cos(theta_a);
                self.anchor = (theta_a, s, c);
                self.block = block;
            }

            /// `(sin θ, cos θ)` of the term's argument `θ = ω t + φ` (formed as
            /// [`Term::sample`] forms it) at grid point `m` of time `t ≈ m·δ`: the
            /// anchor rotated by the table's `τ_n`, then by the residual
            /// `r = θ − θ_a − τ_n` (a few units in the last place of `θ`) to first
            /// order (`r²/2` is below 1e-25).
            #[cfg_attr(not(debug_assertions), inline(always))]
            fn sin_cos_at(&mut self, m: u64, t: f64, step: f64) -> (f64, f64) {
                let block = m / BLOCK;
                if block != self.block {
                    self.set_anchor(block, step);
                }
                let (theta_a, s_a, c_a) = self.anchor;
                let (tau, s_n, c_n) = self.table[(m % BLOCK) as usize];
                let theta = self.omega * t + self.phase;
                let r = (theta - theta_a) - tau;
                let (s, c) = (s_a * c_n + c_a * s_n, c_a * c_n - s_a * s_n);
                (s + c * r, c - s * r)
            }

            /// The term's value at grid point `m` of time `t`.
            #[inline]
            fn value(&mut self, m: u64, t: f64, step: f64) -> f64 {
                let (s, c) = self.sin_cos_at(m, t, step);
                self.amplitude * if self.cosine { c } else { s }
            }

            /// The term's value and derivatives at grid point `m` of time `t` (the
            /// formulas of [`Term::sample`]).
            #[inline]
            fn sample(&mut self, m: u64, t: f64, step: f64) -> Sample {
                let (s, c) = self.sin_cos_at(m, t, step);
                let (a, w) = (self.amplitude, self.omega);
                if self.cosine {
                    Sample { value: a * c, rate: -a * w * s, acceleration: -a * w * w * c }
                } else {
                    Sample { value: a * s, rate: a * w * c, acceleration: -a * w * w * s }
                }
            }
        }

        /// One term of a [`GridSignal`].
        #[derive(Clone, Debug)]
        enum GridTerm {
            /// A sine or cosine, rotated along the grid.
            Sinusoid(Phasor),
            /// [`Term::Constant`].
            Constant(f64),
            /// [`Term::Polynomial`]: its coefficients from degree 0 upward.
            Polynomial(Vec<f64>),
            /// Any other term, evaluated at `t` as [`Term::sample`] does.
            Other(Term),
        }

        /// A [`Signal`] prepared for sampling on the grid `t_m = m·step` (module
        /// documentation).
        #[derive(Clone, Debug)]
        pub struct GridSignal {
            step: f64,
            window: Option<[f64; 2]>,
            terms: Vec<GridTerm>,
        }

        impl GridSignal {
            /// `signal` on the grid of spacing `step` (s, > 0). Tabulates
            /// `BLOCK` angles with their sines and cosines for each of the first
            /// [`MAX_PHASORS`] sinusoid terms (1.5 KiB each).
            pub fn new(signal: &Signal, step: f64) -> Self {
                let mut phasors = 0;
                let terms = signal
                    .terms
                    .iter()
                    .map(|term| match term {
                        Term::Sine { amplitude, phase, .. } | Term::Cosine { amplitude, phase, .. }
                            if phasors < MAX_PHASORS =>
                        {
                            phasors += 1;
                            let omega = term.angular_frequency().unwrap_or(0.0);
                            let cosine = matches!(term, Term::Cosine { .. });
                            GridTerm::Sinusoid(Phasor::new(*amplitude, omega, *phase, cosine, step))
                        }
                        Term::Constant { value } => GridTerm::Constant(*value),
                        Term::Polynomial { coefficients } => GridTerm::Polynomial(coefficients.clone()),
                        other => GridTerm::Other(other.clone()),
                    })
                    .collect();
                Self { step, window: signal.window, terms }
            }

            /// The value at grid point `m`, whose time the caller computed as `t`
            /// (s, `≈ m·step`; the window and the non-sinusoid terms use it).
            #[cfg_attr(not(debug_assertions), inline(always))] // the loop calls it for every signal at every substep
            pub fn value(&mut self, m: u64, t: f64) -> f64 {
                if let Some([start, end]) = self.window {
                    if t < start || t > end {
                        return 0.0;
                    }
                }
                let step = self.step;
                let mut out = 0.0;
                for term in &mut self.terms {
                    out += match term {
                        GridTerm::Sinusoid(p) => p.value(m, t, step),
                        GridTerm::Constant(value) => *value,
                        GridTerm::Polynomial(coefficients) => polynomial(coefficients, t).value,
                        GridTerm::Other(term) => term.value(t),
                    };
                }
                out
            }

            /// Value and derivatives at grid point `m` of time `t` (as [`GridSignal::value`]).
            #[cfg_attr(not(debug_assertions), inline(always))]
            pub fn sample(&mut self, m: u64, t: f64) -> Sample {
                if let Some([start, end]) = self.window {
                    if t < start || t > end {
                        return Sample::default();
                    }
                }
                let step = self.step;
                let mut out = Sample::default();
                for term in &mut self.terms {
                    out += match term {
                        GridTerm::Sinusoid(p) => p.sample(m, t, step),
                        GridTerm::Constant(value) => Sample { value: *value, ..Sample::default() },
                        GridTerm::Polynomial(coefficients) => polynomial(coefficients, t),
                        GridTerm::Other(term) => term.sample(t),
                    };
                }
                out
            }
        }
    }

    /// A family of signals of every shape the grid distinguishes (leading
    /// constants, sinusoids only, mixed terms, windows, zero and negative
    /// amplitudes, large phases), from a fixed pseudo-random sequence.
    fn shapes() -> Vec<Signal> {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut uniform = move |low: f64, high: f64| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            low + (high - low) * ((state >> 11) as f64 / (1u64 << 53) as f64)
        };
        let mut signals = Vec::new();
        for case in 0..48 {
            let mut terms = Vec::new();
            for _ in 0..case % 3 {
                terms.push(Term::Constant { value: uniform(-1.0, 1.0) });
            }
            let sinusoids = 1 + case % 4;
            for i in 0..sinusoids {
                let amplitude = if case % 7 == 3 && i == 0 { 0.0 } else { uniform(-1.5, 1.5) };
                let phase = uniform(-7.0, 7.0);
                let (omega, frequency) =
                    if i % 2 == 0 { (Some(uniform(0.0, 20.0)), None) } else { (None, Some(uniform(0.0, 3.0))) };
                terms.push(if (case + i) % 2 == 0 {
                    Term::Sine { amplitude, omega, frequency, phase }
                } else {
                    Term::Cosine { amplitude, omega, frequency, phase }
                });
                if case % 5 == 4 && i == 0 {
                    terms.push(Term::Polynomial { coefficients: vec![uniform(-1.0, 1.0), uniform(-0.1, 0.1)] });
                    terms.push(Term::Constant { value: uniform(-1.0, 1.0) });
                    terms.push(Term::Step { time: uniform(0.0, 3.0), height: uniform(-1.0, 1.0) });
                }
            }
            let window = (case % 2 == 1).then(|| [uniform(0.0, 1.0), uniform(1.5, 3.0)]);
            signals.push(Signal { terms, window });
        }
        signals.push(Signal { terms: vec![Term::Constant { value: 0.3 }], window: None });
        signals.push(Signal { terms: vec![Term::Constant { value: -0.0 }], window: Some([0.5, 1.0]) });
        signals.push(Signal { terms: vec![Term::Polynomial { coefficients: vec![1.0, 0.1] }], window: None });
        signals.push(Signal::default());
        signals
    }

    /// Every shape, on grids of the loop's substep times (`k·dt + j·h + h`)
    /// with 1 and 4 substeps: values and samples have the previous
    /// implementation's bits, whatever order the points are taken in.
    #[test]
    fn samples_have_the_bits_of_the_previous_implementation() {
        let mut seen = Vec::new();
        for signal in shapes() {
            let shape = GridSignal::new(&signal, 1e-3).shape;
            if !seen.contains(&shape) {
                seen.push(shape);
            }
            for substeps in [1u64, 4] {
                let (dt, h) = (1e-3, 1e-3 / substeps as f64);
                let mut grid = GridSignal::new(&signal, h);
                let mut old = previous::GridSignal::new(&signal, h);
                let bits = |s: Sample| [s.value.to_bits(), s.rate.to_bits(), s.acceleration.to_bits()];
                for k in (0..3_000u64).chain([7_777, 40_000, 123, 39_999]) {
                    for j in 0..substeps {
                        let t = k as f64 * dt + j as f64 * h + h;
                        let m = k * substeps + j + 1;
                        let (new, before) = (grid.value(m, t), old.value(m, t));
                        assert_eq!(new.to_bits(), before.to_bits(), "{signal:?} at t = {t}: {new} vs {before}");
                        assert_eq!(bits(grid.sample(m, t)), bits(old.sample(m, t)), "{signal:?} at t = {t}");
                    }
                }
                assert_eq!(grid.is_zero(), signal.terms.is_empty());
            }
        }
        assert_eq!(seen.len(), 5, "every shape was compared: {seen:?}");
    }

    fn sinusoids() -> Signal {
        Signal {
            terms: vec![
                Term::Sine { amplitude: 0.5, omega: Some(0.4), frequency: None, phase: 5.1 },
                Term::Cosine { amplitude: 0.3, omega: Some(1.3), frequency: None, phase: 0.2 },
                Term::Sine { amplitude: 0.1, omega: None, frequency: Some(2.0), phase: 3.7 },
                Term::Constant { value: 0.25 },
                Term::Polynomial { coefficients: vec![0.0, 0.01] },
            ],
            window: Some([10.0, 40.0]),
        }
    }

    /// Over a 50 s flight at 1 kHz (arguments up to 632 rad), every sample
    /// agrees with the direct evaluation to a few units in the last place
    /// of the amplitudes, its derivatives likewise (times ω and ω²).
    #[test]
    fn grid_samples_agree_with_the_direct_evaluation_to_rounding() {
        let signal = sinusoids();
        let step = 1e-3;
        let mut grid = GridSignal::new(&signal, step);
        // Amplitudes 0.9 in all, ω up to 12.6 rad/s.
        let bound = 4.0 * f64::EPSILON * 0.9;
        let mut inside = 0;
        for m in 0..=50_000u64 {
            let t = m as f64 * step;
            let (direct, on_grid) = (signal.value(t), grid.value(m, t));
            let s = signal.sample(t);
            let g = grid.sample(m, t);
            assert!((direct - on_grid).abs() <= bound, "t = {t}: {on_grid} vs {direct}");
            assert!((s.value - g.value).abs() <= bound, "t = {t}: {} vs {}", g.value, s.value);
            assert!((s.rate - g.rate).abs() <= 12.6 * bound, "t = {t}: rate {} vs {}", g.rate, s.rate);
            assert!((s.acceleration - g.acceleration).abs() <= 158.0 * bound, "t = {t}");
            if (10.0..=40.0).contains(&t) {
                inside += 1;
            } else {
                assert_eq!(on_grid, 0.0);
            }
        }
        assert!(inside > 29_000, "the two evaluations were compared inside the window");
    }

    /// The same at the substeps of a 1 kHz loop with 4 substeps, with times
    /// formed as the run loop forms them (`k·dt + j·h + h`, not `m·h`).
    #[test]
    fn grid_samples_at_the_loops_substep_times_agree_to_rounding() {
        let signal = sinusoids();
        let (dt, substeps) = (1e-3, 4u64);
        let h = dt / substeps as f64;
        let mut grid = GridSignal::new(&signal, h);
        for k in 0..50_000u64 {
            for j in 0..substeps {
                let t = k as f64 * dt + j as f64 * h + h;
                let m = k * substeps + j + 1;
                let (direct, on_grid) = (signal.value(t), grid.value(m, t));
                assert!((direct - on_grid).abs() <= 4.0 * f64::EPSILON * 0.9, "t = {t}: {on_grid} vs {direct}");
            }
        }
    }

    /// The value at a grid point does not depend on which points were
    /// evaluated before it (a flight stays deterministic however it is stepped).
    #[test]
    fn grid_values_depend_on_the_point_alone() {
        let signal = sinusoids();
        let mut stepped = GridSignal::new(&signal, 1e-3);
        let mut jumping = GridSignal::new(&signal, 1e-3);
        let at = |m: u64| m as f64 * 1e-3;
        let seq: Vec<f64> = (0..40_000u64).map(|m| stepped.value(m, at(m))).collect();
        for m in [39_999u64, 12_345, 20_000, 12_346, 30_063, 30_064, 10_000] {
            assert_eq!(jumping.value(m, at(m)).to_bits(), seq[m as usize].to_bits(), "m = {m}");
        }
    }

    #[test]
    fn the_other_terms_and_the_window_are_those_of_the_signal() {
        let signal = Signal {
            terms: vec![Term::Step { time: 1.0, height: 2.0 }, Term::Polynomial { coefficients: vec![1.0, 0.1, 0.3] }],
            window: Some([0.5, 3.0]),
        };
        let mut grid = GridSignal::new(&signal, 0.01);
        for m in 0..400u64 {
            let t = m as f64 * 0.01;
            assert_eq!(grid.value(m, t).to_bits(), signal.value(t).to_bits());
            assert_eq!(grid.sample(m, t), signal.sample(t));
        }
        assert!(GridSignal::new(&Signal::default(), 0.01).is_zero());
    }

    /// Sinusoids beyond [`MAX_PHASORS`] are evaluated directly (their bits
    /// are those of the signal); the sum still agrees to rounding.
    #[test]
    fn sinusoids_beyond_the_table_budget_are_evaluated_directly() {
        let n = MAX_PHASORS + 3;
        let terms: Vec<Term> = (0..n)
            .map(|i| Term::Sine { amplitude: 1e-3, omega: Some(0.1 * i as f64), frequency: None, phase: 0.0 })
            .collect();
        let mut grid = GridSignal::new(&Signal { terms: terms.clone(), window: None }, 1e-3);
        let tabulated = grid.terms.iter().filter(|t| matches!(t, GridTerm::Sinusoid(_))).count();
        assert_eq!(tabulated, MAX_PHASORS);
        assert!(matches!(grid.terms[n - 1], GridTerm::Other(_)));
        let signal = Signal { terms, window: None };
        for m in [0u64, 1, 777, 12_345] {
            let t = m as f64 * 1e-3;
            assert!((grid.value(m, t) - signal.value(t)).abs() <= 1e-15, "t = {t}");
        }
    }
}
