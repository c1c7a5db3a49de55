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
//! Every sample is two products and a sum away from a `libm` value, so the
//! rotation does not accumulate error from one sample to the next: it
//! agrees with `A·sin(ω t + φ)` to a few units in the last place of the
//! argument `ω t + φ`, the precision to which the direct evaluation itself
//! forms that argument (`tests` below bound it). The bits are not those of
//! [`Signal::value`]; they are a function of `m` alone (not of the order of
//! the calls), so a flight stays deterministic.
//!
//! The other terms (constants, steps, polynomials, waypoints, piecewise)
//! and the window are evaluated at the caller's time `t` exactly as
//! [`Signal::value`] and [`Signal::sample`] do.

use ftsmc_core::math::sin_cos;

use super::{Sample, Signal, Term};

/// Grid points per block: one `sin_cos` per sinusoid term every `BLOCK`
/// samples (a power of two, so the block index and offset are a shift and a mask).
pub const BLOCK: u64 = 64;

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
    /// `(sin θ_a, cos θ_a)` at the block's first point.
    anchor: (f64, f64),
    /// `(sin nωδ, cos nωδ)` for `n = 0 … BLOCK − 1`.
    table: Box<[(f64, f64)]>,
}

impl Phasor {
    fn new(amplitude: f64, omega: f64, phase: f64, cosine: bool, step: f64) -> Self {
        let table = (0..BLOCK).map(|n| sin_cos(omega * (n as f64 * step))).collect();
        Self { amplitude, omega, phase, cosine, block: u64::MAX, anchor: (0.0, 0.0), table }
    }

    /// `(sin θ, cos θ)` of the term's argument `θ = ω t_m + φ` at grid point `m`.
    #[inline]
    fn sin_cos_at(&mut self, m: u64, step: f64) -> (f64, f64) {
        let block = m / BLOCK;
        if block != self.block {
            let t_a = (block * BLOCK) as f64 * step;
            self.anchor = sin_cos(self.omega * t_a + self.phase);
            self.block = block;
        }
        let (s_a, c_a) = self.anchor;
        let (s_n, c_n) = self.table[(m % BLOCK) as usize];
        (s_a * c_n + c_a * s_n, c_a * c_n - s_a * s_n)
    }

    /// The term's value at grid point `m`.
    #[inline]
    fn value(&mut self, m: u64, step: f64) -> f64 {
        let (s, c) = self.sin_cos_at(m, step);
        self.amplitude * if self.cosine { c } else { s }
    }

    /// The term's value and derivatives at grid point `m` (the formulas of
    /// [`Term::sample`]).
    #[inline]
    fn sample(&mut self, m: u64, step: f64) -> Sample {
        let (s, c) = self.sin_cos_at(m, step);
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
    /// `BLOCK` sine/cosine pairs per sinusoid term (1 KiB each).
    pub fn new(signal: &Signal, step: f64) -> Self {
        let terms = signal
            .terms
            .iter()
            .map(|term| match term {
                Term::Sine { amplitude, phase, .. } | Term::Cosine { amplitude, phase, .. } => {
                    let omega = term.angular_frequency().unwrap_or(0.0);
                    let cosine = matches!(term, Term::Cosine { .. });
                    GridTerm::Sinusoid(Phasor::new(*amplitude, omega, *phase, cosine, step))
                }
                other => GridTerm::Other(other.clone()),
            })
            .collect();
        Self { step, window: signal.window, terms }
    }

    /// True when the signal has no terms (identically zero).
    pub fn is_zero(&self) -> bool {
        self.terms.is_empty()
    }

    /// The value at grid point `m`, whose time the caller computed as `t`
    /// (s, `≈ m·step`; the window and the non-sinusoid terms use it).
    #[inline]
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
                GridTerm::Sinusoid(p) => p.value(m, step),
                GridTerm::Other(term) => term.value(t),
            };
        }
        out
    }

    /// Value and derivatives at grid point `m` of time `t` (as [`GridSignal::value`]).
    #[inline]
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
                GridTerm::Sinusoid(p) => p.sample(m, step),
                GridTerm::Other(term) => term.sample(t),
            };
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit in the last place of `x`.
    fn ulp(x: f64) -> f64 {
        let x = x.abs();
        f64::from_bits(x.to_bits() + 1) - x
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

    /// Over a 50 s flight at 1 kHz, every sample agrees with the direct
    /// evaluation to a few units in the last place of the largest argument
    /// `ω t + φ` (times the amplitudes): the direct evaluation's own
    /// rounding of its argument.
    #[test]
    fn grid_samples_agree_with_the_direct_evaluation_to_the_rounding_of_the_argument() {
        let signal = sinusoids();
        let step = 1e-3;
        let mut grid = GridSignal::new(&signal, step);
        let mut worst: f64 = 0.0;
        for m in 0..=50_000u64 {
            let t = m as f64 * step;
            let (direct, on_grid) = (signal.value(t), grid.value(m, t));
            let s = signal.sample(t);
            let g = grid.sample(m, t);
            let largest_argument = 2.0 * core::f64::consts::PI * 2.0 * t + 3.7;
            // Amplitudes 0.9 in all; ω² up to 158 for the acceleration.
            let bound = 4.0 * ulp(largest_argument.max(1.0)) * 0.9;
            let err = (direct - on_grid).abs();
            worst = worst.max(err / bound);
            assert!(err <= bound, "t = {t}: {on_grid} vs {direct}");
            assert!((s.value - g.value).abs() <= bound);
            assert!((s.rate - g.rate).abs() <= 12.6 * bound, "t = {t}: rate {} vs {}", g.rate, s.rate);
            assert!((s.acceleration - g.acceleration).abs() <= 158.0 * bound);
            if !(10.0..=40.0).contains(&t) {
                assert_eq!(on_grid, 0.0);
            }
        }
        assert!(worst > 0.0, "the two evaluations were never compared inside the window");
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
}
