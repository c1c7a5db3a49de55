//! The lane kernels of `ftsmc_core::lanes_math` (`exp`, `ln`) give, lane by lane, the
//! bits of the scalar `libm` functions (NaN: both NaN), on `[f64; 4]` and
//! `[f64; 8]`, and so do the `Real` methods of `Lanes<N>` that call them.
//!
//! Arguments: random bit patterns over the whole exponent range, random
//! values in the ranges the controllers use (`|x| < 10`, `|x| < 1e3`,
//! `exp` over `[−745, 710]`), every special value (±0, ±∞, NaN, subnormals,
//! extremes) and the range boundaries of each branch of the scalar code
//! with their neighbours (`next_up` / `next_down`). Specials are
//! interleaved with ordinary values and fed at every lane position, so a
//! vector mixes lanes that take different branches. Fewer samples in
//! debug builds, more in release.

// The exp thresholds below are written as in the libm sources.
#![allow(clippy::excessive_precision)]

use ftsmc_core::lanes::{Lanes, Real};
use ftsmc_core::lanes_math as lm;

/// Random samples per family (debug / release).
const SAMPLES: usize = if cfg!(debug_assertions) { 100_000 } else { 2_000_000 };

/// splitmix64: a small deterministic generator.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    /// Uniform in `[0, 1)`.
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
    /// Uniform in `(−a, a)`.
    fn sym(&mut self, a: f64) -> f64 {
        (2.0 * self.unit() - 1.0) * a
    }
}

fn same(a: f64, b: f64) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

/// Values every function sees: zeros, infinities, NaNs, subnormals,
/// extremes, small integers.
fn specials() -> Vec<f64> {
    let mut v = vec![
        0.0,
        -0.0,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NAN,
        -f64::NAN,
        f64::from_bits(0x7ff0_0000_0000_0001),
        f64::from_bits(0xfff4_0000_dead_beef),
        f64::from_bits(1),
        f64::from_bits(0x000f_ffff_ffff_ffff),
        f64::from_bits(0x0008_0000_0000_0000),
        f64::MIN_POSITIVE,
        f64::MAX,
        f64::EPSILON,
        1e-300,
        1e300,
    ];
    for k in -4..=4 {
        v.push(k as f64);
        v.push(k as f64 * 0.5);
    }
    let neg: Vec<f64> = v.iter().map(|x| -x).collect();
    v.extend(neg);
    v
}

/// The next representable value above `x` (`f64::next_up`, stable after
/// this crate's minimum Rust version).
fn next_up(x: f64) -> f64 {
    if x.is_nan() || x == f64::INFINITY {
        x
    } else if x == 0.0 {
        f64::from_bits(1)
    } else if x > 0.0 {
        f64::from_bits(x.to_bits() + 1)
    } else {
        f64::from_bits(x.to_bits() - 1)
    }
}

/// The next representable value below `x`.
fn next_down(x: f64) -> f64 {
    -next_up(-x)
}

/// `x`, `next_down(x)`, `next_up(x)` for `±x`.
fn around_value(out: &mut Vec<f64>, x: f64) {
    for s in [x, -x] {
        out.extend([s, next_down(s), next_up(s)]);
    }
}

/// The values around a high-word threshold `hw` of the scalar code: the
/// first and last values with that high word and their neighbours, both
/// signs.
fn around_high(out: &mut Vec<f64>, hw: u32) {
    let lo = f64::from_bits((hw as u64) << 32);
    let hi = f64::from_bits(((hw as u64) << 32) | 0xffff_ffff);
    around_value(out, lo);
    around_value(out, hi);
}

/// Random arguments of the shared families: bit patterns, `|x| < 10`,
/// `|x| < 1e3`, `|x| < 1`.
fn randoms(rng: &mut Rng) -> Vec<f64> {
    let mut v = Vec::with_capacity(4 * SAMPLES);
    for _ in 0..SAMPLES {
        v.push(f64::from_bits(rng.next()));
        v.push(rng.sym(10.0));
        v.push(rng.sym(1e3));
        v.push(rng.sym(1.0));
    }
    v
}

/// Every special/boundary value interleaved with ordinary values, once per
/// lane position, followed by `random`.
fn arguments(edges: &[f64], random: &[f64], rng: &mut Rng) -> Vec<f64> {
    let mut v = Vec::new();
    for _pos in 0..8 {
        for &e in edges {
            v.push(e);
            // 0..3 ordinary values after it, so the next edge lands in
            // another lane.
            for _ in 0..(rng.next() % 4) {
                v.push(rng.sym(3.0));
            }
        }
        v.push(rng.sym(3.0));
    }
    // Runs of edges side by side too.
    v.extend_from_slice(edges);
    v.extend_from_slice(random);
    v
}

fn check1<const N: usize>(name: &str, args: &[f64], lane: fn([f64; N]) -> [f64; N], scalar: fn(f64) -> f64) -> usize {
    let mut bad = 0;
    for chunk in args.chunks_exact(N) {
        let x: [f64; N] = chunk.try_into().unwrap();
        let got = lane(x);
        for i in 0..N {
            let want = scalar(x[i]);
            if !same(got[i], want) {
                if bad < 10 {
                    eprintln!(
                        "{name} N={N} lane {i}: x={:e} ({:#018x}) got {:e} ({:#018x}) want {:e} ({:#018x})",
                        x[i],
                        x[i].to_bits(),
                        got[i],
                        got[i].to_bits(),
                        want,
                        want.to_bits()
                    );
                }
                bad += 1;
            }
        }
    }
    bad
}

fn check_both(
    name: &str,
    args: &[f64],
    l4: fn([f64; 4]) -> [f64; 4],
    l8: fn([f64; 8]) -> [f64; 8],
    scalar: fn(f64) -> f64,
) {
    let bad = check1(name, args, l4, scalar) + check1(name, args, l8, scalar);
    assert_eq!(bad, 0, "{name}: {bad} lanes differ from libm");
}

#[test]
fn exp_is_libm_exp_on_every_lane() {
    let mut rng = Rng(1);
    let mut edges = specials();
    for hw in [0x4086_232b, 0x3fd6_2e42, 0x3ff0_a2b2, 0x3e30_0000] {
        around_high(&mut edges, hw);
    }
    for x in
        [709.782712893383973096, 708.39641853226410622, 745.13321910194110842, 700.0, 1022.0 * core::f64::consts::LN_2]
    {
        around_value(&mut edges, x);
    }
    // Where k changes: (k + 1/2) ln 2.
    for k in -1100..1100 {
        around_value(&mut edges, (k as f64 + 0.5) * core::f64::consts::LN_2);
    }
    let mut random = randoms(&mut rng);
    for _ in 0..SAMPLES {
        random.push(-745.0 + 1455.0 * rng.unit());
        random.push(rng.sym(40.0));
    }
    let args = arguments(&edges, &random, &mut rng);
    check_both("exp", &args, lm::exp::<4>, lm::exp::<8>, libm::exp);
}

#[test]
fn ln_is_libm_log_on_every_lane() {
    let mut rng = Rng(2);
    let mut edges = specials();
    for hw in [0x0010_0000, 0x7ff0_0000, 0x3ff0_0000, 0x3fe6_a09e, 0x3ff6_a09e, 0x7fef_ffff] {
        around_high(&mut edges, hw);
    }
    let mut random = randoms(&mut rng);
    for _ in 0..SAMPLES {
        // Magnitudes (the power laws' |x|) and positive bit patterns.
        random.push(libm::fabs(rng.sym(10.0)));
        random.push(f64::from_bits(rng.next() >> 1));
        random.push(1.0 + rng.sym(1e-6));
    }
    let args = arguments(&edges, &random, &mut rng);
    check_both("ln", &args, lm::ln::<4>, lm::ln::<8>, libm::log);
}

/// The `Real` methods of `Lanes<N>` (the kernels for `exp` and `ln`, the
/// scalar function per lane for the others): same bits as the `f64`
/// methods (which call `ftsmc_core::math`) lane by lane.
#[test]
fn real_methods_on_lanes_are_the_scalar_methods_per_lane() {
    fn run<const N: usize>(rng: &mut Rng) {
        for _ in 0..2000 {
            let x = Lanes::<N>::from_fn(|_| match rng.next() % 8 {
                0 => f64::from_bits(rng.next()),
                1 => 0.0,
                2 => f64::NAN,
                _ => rng.sym(4.0),
            });
            let y = Lanes::<N>::from_fn(|_| rng.sym(4.0));
            let (s, c) = x.sin_cos();
            for i in 0..N {
                let xi = x.0[i];
                let yi = y.0[i];
                let (ss, cs) = Real::sin_cos(xi);
                for (got, want) in [
                    (x.exp().0[i], Real::exp(xi)),
                    (x.ln().0[i], Real::ln(xi)),
                    (x.sin().0[i], Real::sin(xi)),
                    (x.cos().0[i], Real::cos(xi)),
                    (s.0[i], ss),
                    (c.0[i], cs),
                    (x.asin().0[i], Real::asin(xi)),
                    (x.acos().0[i], Real::acos(xi)),
                    (x.atan().0[i], Real::atan(xi)),
                    (x.atan2(y).0[i], Real::atan2(xi, yi)),
                    (y.atan2(x).0[i], Real::atan2(yi, xi)),
                ] {
                    assert!(same(got, want), "x={xi:e} y={yi:e}: {got:e} vs {want:e}");
                }
            }
        }
    }
    let mut rng = Rng(10);
    run::<4>(&mut rng);
    run::<8>(&mut rng);
}
