//! The environment's sinusoid terms on the run loop's grid, side by side.
//!
//! The disturbances and the inertia variation are evaluated at every
//! substep boundary `t_m = m·δ` ([`super::Environment::on_grid`]). When
//! each of these signals is a sum of leading constants and sine or cosine
//! terms (the paper's scenarios and their Monte Carlo draws), every term is
//! the rotation of [`crate::signal::grid`]: at offset `n` of block `a`,
//!
//! ```text
//! θ = ω t + φ,   r = (θ − θ_a) − τ_n,
//! x = U cos τ_n + V sin τ_n,   y = W cos τ_n + Z sin τ_n,
//! term = A (x + y r)
//! ```
//!
//! with `θ_a = ω (a·BLOCK·δ) + φ`, `[U, V, W, Z]` the anchor's rotation
//! (`[sin θ_a, cos θ_a, cos θ_a, −sin θ_a]` for a sine, `[cos θ_a, −sin θ_a,
//! −sin θ_a, −cos θ_a]` for a cosine) and `(τ_n, sin τ_n, cos τ_n)` the
//! term's table. [`PhasorBank`] holds the terms of all the signals in
//! groups of four, field by field, so that one pass computes four terms
//! per operation (in the baseline instruction set: the AVX2 path,
//! [`crate::isa`], saved 2.7 % of a paper flight-step on 4 lanes, under the
//! 10 % a kernel outside the controller and the truth must earn),
//! and then sums each signal's terms in its order from its leading
//! constants' sum. The leading constants, the tables, the anchors and each
//! term's value are the grid signals' own functions
//! ([`crate::signal::grid`]'s `leading_constants`, `table_row`, `anchor`,
//! `term_value`), so every signal has the bits of its
//! [`crate::signal::grid::GridSignal`] (`tests` compare them sample by
//! sample).

use crate::signal::grid::{anchor, leading_constants, table_row, term_value, BLOCK, MAX_PHASORS};
use crate::signal::{Signal, Term};

/// Terms per group.
const WIDTH: usize = 4;

/// Four terms, field by field (unused slots have zero amplitude and are
/// never summed).
#[derive(Clone, Copy, Debug, Default)]
struct Group {
    /// `A` (units of the signal).
    amplitude: [f64; WIDTH],
    /// ω, rad/s.
    omega: [f64; WIDTH],
    /// φ, rad.
    phase: [f64; WIDTH],
    /// `θ_a` of the current block, rad.
    anchor: [f64; WIDTH],
    /// The anchor's rotation `[U, V, W, Z]`.
    rotation: [[f64; WIDTH]; 4],
}

/// One row of the tables: `τ_n`, `sin τ_n`, `cos τ_n` of a group's terms.
type Row = [[f64; WIDTH]; 3];

/// The sinusoid terms of several signals on the grid `t_m = m·step`
/// (module documentation).
#[derive(Clone, Debug)]
pub(super) struct PhasorBank {
    step: f64,
    /// The block whose anchors the groups hold (`u64::MAX`: none yet).
    block: u64,
    groups: Vec<Group>,
    /// Cosine terms (else sines), by term index.
    cosine: Vec<bool>,
    /// `table[n · groups + g]`: row `n` of group `g`.
    table: Vec<Row>,
    /// Per signal: its leading constants' sum `0.0 + c_1 + …`, and the
    /// range of its terms.
    signals: Vec<(f64, core::ops::Range<usize>)>,
    /// The terms' values at the latest sample.
    values: Vec<f64>,
}

impl PhasorBank {
    /// The bank of `signals` on the grid of spacing `step` (s), or `None`
    /// when some signal has a term after its leading constants other than
    /// a sine or cosine, or more than [`MAX_PHASORS`] of them (the grid
    /// signals evaluate those).
    pub(super) fn new(signals: &[&Signal], step: f64) -> Option<Self> {
        let mut terms = Vec::new();
        let mut ranges = Vec::new();
        for signal in signals {
            let (start, leading) = leading_constants(signal);
            let rest = &signal.terms[leading..];
            if rest.len() > MAX_PHASORS {
                return None;
            }
            let first = terms.len();
            for term in rest {
                match term {
                    Term::Sine { amplitude, phase, .. } | Term::Cosine { amplitude, phase, .. } => {
                        let omega = term.angular_frequency().unwrap_or(0.0);
                        terms.push((*amplitude, omega, *phase, matches!(term, Term::Cosine { .. })));
                    }
                    _ => return None,
                }
            }
            ranges.push((start, first..terms.len()));
        }
        let count = terms.len().div_ceil(WIDTH);
        let mut groups = vec![Group::default(); count];
        let mut table = vec![[[0.0; WIDTH]; 3]; count * BLOCK as usize];
        for (p, &(amplitude, omega, phase, _)) in terms.iter().enumerate() {
            let (g, k) = (p / WIDTH, p % WIDTH);
            groups[g].amplitude[k] = amplitude;
            groups[g].omega[k] = omega;
            groups[g].phase[k] = phase;
            for n in 0..BLOCK as usize {
                let (tau, s, c) = table_row(omega, n, step);
                let row = &mut table[n * count + g];
                row[0][k] = tau;
                row[1][k] = s;
                row[2][k] = c;
            }
        }
        Some(Self {
            step,
            block: u64::MAX,
            groups,
            cosine: terms.iter().map(|t| t.3).collect(),
            table,
            signals: ranges,
            values: vec![0.0; count * WIDTH],
        })
    }

    /// Move the anchors to `block`: `θ_a = ω (a·BLOCK·δ) + φ` and its sine
    /// and cosine, as [`crate::signal::grid`] takes them.
    #[cold]
    #[inline(never)]
    fn set_anchors(&mut self, block: u64) {
        for (p, &cosine) in self.cosine.iter().enumerate() {
            let g = &mut self.groups[p / WIDTH];
            let k = p % WIDTH;
            let ((theta_a, _, _), rotation) = anchor(g.omega[k], g.phase[k], cosine, block, self.step);
            g.anchor[k] = theta_a;
            for (field, value) in g.rotation.iter_mut().zip(rotation) {
                field[k] = value;
            }
        }
        self.block = block;
    }

    /// Every signal's value at grid point `m`, whose time the caller
    /// computed as `t` (s), into `out` (in the order the signals were given;
    /// windows are the caller's).
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub(super) fn values(&mut self, m: u64, t: f64, out: &mut [f64]) {
        let block = m / BLOCK;
        if block != self.block {
            self.set_anchors(block);
        }
        let n = (m % BLOCK) as usize;
        let count = self.groups.len();
        let rows = &self.table[n * count..(n + 1) * count];
        terms(&self.groups, rows, t, &mut self.values);
        for ((start, range), o) in self.signals.iter().zip(out.iter_mut()) {
            let mut sum = *start;
            for v in &self.values[range.clone()] {
                sum += v;
            }
            *o = sum;
        }
    }
}

/// Every term's value at time `t` from its group and its table row
/// (module documentation), four at a time.
#[cfg_attr(not(debug_assertions), inline(always))]
fn terms(groups: &[Group], rows: &[Row], t: f64, values: &mut [f64]) {
    for ((g, row), out) in groups.iter().zip(rows).zip(values.chunks_exact_mut(WIDTH)) {
        let [u, v, w, z] = &g.rotation;
        let [tau, s_n, c_n] = row;
        // Into a local first: inlined into its caller, `out` and the
        // inputs are fields of one bank with no `noalias` between them, so
        // a store straight into `out` could alias the next term's inputs
        // and the four terms would not be computed side by side.
        let mut four = [0.0; WIDTH];
        for k in 0..WIDTH {
            let rotation = [u[k], v[k], w[k], z[k]];
            let row = (tau[k], s_n[k], c_n[k]);
            four[k] = term_value(g.amplitude[k], g.omega[k], g.phase[k], g.anchor[k], rotation, row, t);
        }
        out.copy_from_slice(&four);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::signal::grid::GridSignal;

    fn term(cosine: bool, amplitude: f64, omega: Option<f64>, frequency: Option<f64>, phase: f64) -> Term {
        if cosine {
            Term::Cosine { amplitude, omega, frequency, phase }
        } else {
            Term::Sine { amplitude, omega, frequency, phase }
        }
    }

    /// Every signal from the bank has the bits of its own grid signal at
    /// every grid point: one, two and five terms, leading constants, no
    /// terms, frequencies in Hz, phases, and an empty slot in a group.
    #[test]
    fn the_bank_gives_each_signals_grid_bits() {
        let signals = [
            Signal {
                terms: vec![term(false, 0.5, Some(0.4), None, 0.0), term(false, 0.3, Some(1.3), None, 0.2)],
                window: None,
            },
            Signal { terms: vec![term(true, 0.5, Some(0.7), None, 1.1)], window: Some([1.0, 2.0]) },
            Signal { terms: vec![], window: None },
            Signal {
                terms: vec![
                    Term::Constant { value: 0.1 },
                    Term::Constant { value: -0.3 },
                    term(true, 0.2, None, Some(2.0), 0.0),
                ],
                window: None,
            },
            Signal { terms: vec![Term::Constant { value: 0.7 }], window: None },
            Signal {
                terms: (0..5)
                    .map(|i| term(i % 2 == 0, 0.1 * i as f64 - 0.2, None, Some(0.5 + i as f64), -0.4 * i as f64))
                    .collect(),
                window: None,
            },
        ];
        let refs: Vec<&Signal> = signals.iter().collect();
        for step in [1e-3, 2.5e-4] {
            let mut bank = PhasorBank::new(&refs, step).expect("sinusoids only");
            let mut own: Vec<GridSignal> = signals.iter().map(|s| GridSignal::new(s, step)).collect();
            let mut out = [0.0; 6];
            for m in (0..20_000u64).chain(1_000_000..1_000_300) {
                let t = m as f64 * step;
                bank.values(m, t, &mut out);
                for (i, s) in own.iter_mut().enumerate() {
                    assert_eq!(out[i].to_bits(), s.value_inside(m, t).to_bits(), "signal {i}, m = {m}, step {step}");
                }
            }
        }
    }

    /// A term the bank does not hold sends the environment back to the grid signals.
    #[test]
    fn other_terms_are_left_to_the_grid_signals() {
        let poly = Signal { terms: vec![Term::Polynomial { coefficients: vec![0.0, 0.2] }], window: None };
        let sine = Signal { terms: vec![term(false, 1.0, Some(1.0), None, 0.0)], window: None };
        assert!(PhasorBank::new(&[&sine, &poly], 1e-3).is_none());
        let mixed =
            Signal { terms: vec![term(false, 1.0, Some(1.0), None, 0.0), Term::Constant { value: 1.0 }], window: None };
        assert!(PhasorBank::new(&[&mixed], 1e-3).is_none());
        assert!(PhasorBank::new(&[&sine], 1e-3).is_some());
    }
}
