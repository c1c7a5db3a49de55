//! The lane kernels of `ftsmc_core::lanes_math` give, lane by lane, the
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

#[test]
fn atan_is_libm_atan_on_every_lane() {
    let mut rng = Rng(3);
    let mut edges = specials();
    for hw in [0x4410_0000, 0x3fdc_0000, 0x3e40_0000, 0x0010_0000, 0x3fe6_0000, 0x3ff3_0000, 0x4003_8000] {
        around_high(&mut edges, hw);
    }
    let random = randoms(&mut rng);
    let args = arguments(&edges, &random, &mut rng);
    check_both("atan", &args, lm::atan::<4>, lm::atan::<8>, libm::atan);
}

fn asin_acos_edges() -> Vec<f64> {
    let mut edges = specials();
    for hw in [0x3ff0_0000, 0x3fe0_0000, 0x3e50_0000, 0x0010_0000, 0x3fef_3333, 0x3c60_0000] {
        around_high(&mut edges, hw);
    }
    edges
}

#[test]
fn asin_is_libm_asin_on_every_lane() {
    let mut rng = Rng(4);
    let edges = asin_acos_edges();
    let random = randoms(&mut rng);
    let args = arguments(&edges, &random, &mut rng);
    check_both("asin", &args, lm::asin::<4>, lm::asin::<8>, libm::asin);
}

#[test]
fn acos_is_libm_acos_on_every_lane() {
    let mut rng = Rng(5);
    let edges = asin_acos_edges();
    let random = randoms(&mut rng);
    let args = arguments(&edges, &random, &mut rng);
    check_both("acos", &args, lm::acos::<4>, lm::acos::<8>, libm::acos);
}

fn sin_cos_edges() -> Vec<f64> {
    let mut edges = specials();
    for hw in [
        0x3fe9_21fb,
        0x3e50_0000,
        0x3e46_a09e,
        0x0010_0000,
        0x7ff0_0000,
        0x400f_6a7a,
        0x4002_d97c,
        0x401c_463b,
        0x4015_fdbc,
        0x4012_d97c,
        0x4019_21fb,
        0x4139_21fb,
        0x3ff9_21fb,
        0x4009_21fb,
    ] {
        around_high(&mut edges, hw);
    }
    // Multiples of pi/2 (the reduction's cancellations: rounds 2 and 3).
    for k in (1..200).chain([1 << 10, 1 << 15, (1 << 20) - 1, 1 << 20, 1 << 21]) {
        around_value(&mut edges, k as f64 * core::f64::consts::FRAC_PI_2);
    }
    edges
}

fn sin_cos_randoms(rng: &mut Rng) -> Vec<f64> {
    let mut random = randoms(rng);
    for _ in 0..SAMPLES / 4 {
        // Near multiples of pi/2 up to 2^20 pi/2.
        let k = (rng.next() % (1 << 20)) as f64;
        random.push(k * core::f64::consts::FRAC_PI_2 + rng.sym(1e-9));
        random.push(rng.sym(2e6));
    }
    random
}

#[test]
fn sin_is_libm_sin_on_every_lane() {
    let mut rng = Rng(6);
    let edges = sin_cos_edges();
    let random = sin_cos_randoms(&mut rng);
    let args = arguments(&edges, &random, &mut rng);
    check_both("sin", &args, lm::sin::<4>, lm::sin::<8>, libm::sin);
}

#[test]
fn cos_is_libm_cos_on_every_lane() {
    let mut rng = Rng(7);
    let edges = sin_cos_edges();
    let random = sin_cos_randoms(&mut rng);
    let args = arguments(&edges, &random, &mut rng);
    check_both("cos", &args, lm::cos::<4>, lm::cos::<8>, libm::cos);
}

fn sin_cos_parts<const N: usize>(x: [f64; N], part: usize) -> [f64; N] {
    let (s, c) = lm::sin_cos(x);
    if part == 0 {
        s
    } else {
        c
    }
}

#[test]
fn sin_cos_is_libm_sincos_on_every_lane() {
    let mut rng = Rng(8);
    let edges = sin_cos_edges();
    let random = sin_cos_randoms(&mut rng);
    let args = arguments(&edges, &random, &mut rng);
    check_both("sin_cos.0", &args, |x| sin_cos_parts::<4>(x, 0), |x| sin_cos_parts::<8>(x, 0), |x| libm::sincos(x).0);
    check_both("sin_cos.1", &args, |x| sin_cos_parts::<4>(x, 1), |x| sin_cos_parts::<8>(x, 1), |x| libm::sincos(x).1);
}

fn check2<const N: usize>(ys: &[f64], xs: &[f64], lane: fn([f64; N], [f64; N]) -> [f64; N]) -> usize {
    let mut bad = 0;
    for (cy, cx) in ys.chunks_exact(N).zip(xs.chunks_exact(N)) {
        let y: [f64; N] = cy.try_into().unwrap();
        let x: [f64; N] = cx.try_into().unwrap();
        let got = lane(y, x);
        for i in 0..N {
            let want = libm::atan2(y[i], x[i]);
            if !same(got[i], want) {
                if bad < 10 {
                    eprintln!("atan2 N={N} lane {i}: y={:e} x={:e} got {:e} want {:e}", y[i], x[i], got[i], want);
                }
                bad += 1;
            }
        }
    }
    bad
}

#[test]
fn atan2_is_libm_atan2_on_every_lane() {
    let mut rng = Rng(9);
    let mut pts = specials();
    pts.extend([1e-20, 1e20, 3.0, 0.75, f64::MAX / 2.0]);
    let mut ys = Vec::new();
    let mut xs = Vec::new();
    // Every pair of special values, each followed by an ordinary pair so
    // the lanes mix.
    for &y in &pts {
        for &x in &pts {
            ys.push(y);
            xs.push(x);
            ys.push(rng.sym(5.0));
            xs.push(rng.sym(5.0));
        }
    }
    // |y/x| around 2^64 and 2^-64 (the huge and the x < 0 tiny branches).
    for _ in 0..2000 {
        let x = rng.sym(100.0);
        for s in [64.0f64, -64.0, 63.0, 65.0, -65.0] {
            let y = x * libm::exp2(s);
            for yy in [y, next_up(y), next_down(y), -y] {
                for xx in [x, -x] {
                    ys.push(yy);
                    xs.push(xx);
                }
            }
        }
    }
    for _ in 0..SAMPLES {
        ys.push(f64::from_bits(rng.next()));
        xs.push(f64::from_bits(rng.next()));
        ys.push(rng.sym(10.0));
        xs.push(rng.sym(10.0));
        ys.push(rng.sym(1e3));
        xs.push(rng.sym(1e3));
        // x exactly 1 (libm's atan(y) branch) among others.
        ys.push(rng.sym(4.0));
        xs.push(if rng.next() % 4 == 0 { 1.0 } else { rng.sym(4.0) });
    }
    // Shift the y sequence too, so the same pairs land in other lanes.
    let bad = check2::<4>(&ys, &xs, lm::atan2::<4>)
        + check2::<8>(&ys, &xs, lm::atan2::<8>)
        + check2::<4>(&ys[1..], &xs[1..], lm::atan2::<4>)
        + check2::<8>(&ys[3..], &xs[3..], lm::atan2::<8>);
    assert_eq!(bad, 0, "atan2: {bad} lanes differ from libm");
}

/// The `Real` methods of `Lanes<N>` are the kernels: same bits as the
/// `f64` methods (which call `ftsmc_core::math`) lane by lane.
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
