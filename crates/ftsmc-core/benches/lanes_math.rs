//! Speed of the lane kernels of `ftsmc_core::lanes_math` against the
//! scalar `libm` function applied lane by lane (what `Lanes<N>` did
//! before), per element (run on demand:
//! `cargo bench -p ftsmc-core --bench lanes_math`).
//!
//! Each benchmark evaluates one function on the same 64 arguments (in the
//! range the controllers use: `|x| < 3`, positive for `ln`, `|x| < 1` for
//! `asin`/`acos`): `scalar` calls `libm` once per argument, `lanes4` /
//! `lanes8` call the kernel on 16 / 8 vectors. Throughput is in elements,
//! so the rates compare per element.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use ftsmc_core::lanes_math as lm;

const LEN: usize = 64;

/// 64 arguments spread over `(lo, hi)` (a fixed irrational stride).
fn args(lo: f64, hi: f64) -> [f64; LEN] {
    core::array::from_fn(|i| lo + (hi - lo) * ((i as f64 * 0.618_033_988_749_895) % 1.0))
}

fn bench1(
    c: &mut Criterion,
    name: &str,
    xs: [f64; LEN],
    scalar: fn(f64) -> f64,
    l4: fn([f64; 4]) -> [f64; 4],
    l8: fn([f64; 8]) -> [f64; 8],
) {
    let mut group = c.benchmark_group(name);
    group.throughput(Throughput::Elements(LEN as u64));
    group.bench_function("scalar", |b| {
        b.iter(|| {
            let x = black_box(xs);
            let mut out = [0.0; LEN];
            for i in 0..LEN {
                out[i] = scalar(x[i]);
            }
            black_box(out)
        })
    });
    group.bench_function("lanes4", |b| {
        b.iter(|| {
            let x = black_box(xs);
            let mut out = [0.0; LEN];
            for (o, v) in out.chunks_exact_mut(4).zip(x.chunks_exact(4)) {
                o.copy_from_slice(&l4(v.try_into().unwrap()));
            }
            black_box(out)
        })
    });
    group.bench_function("lanes8", |b| {
        b.iter(|| {
            let x = black_box(xs);
            let mut out = [0.0; LEN];
            for (o, v) in out.chunks_exact_mut(8).zip(x.chunks_exact(8)) {
                o.copy_from_slice(&l8(v.try_into().unwrap()));
            }
            black_box(out)
        })
    });
    group.finish();
}

fn kernels(c: &mut Criterion) {
    bench1(c, "exp", args(-3.0, 3.0), libm::exp, lm::exp::<4>, lm::exp::<8>);
    bench1(c, "ln", args(1e-3, 3.0), libm::log, lm::ln::<4>, lm::ln::<8>);
    bench1(c, "atan", args(-3.0, 3.0), libm::atan, lm::atan::<4>, lm::atan::<8>);
    bench1(
        c,
        "atan2",
        args(-2.0, 3.0),
        |x| libm::atan2(x * 0.7 - 0.4, x),
        |x| lm::atan2(x.map(|v| v * 0.7 - 0.4), x),
        |x| lm::atan2(x.map(|v| v * 0.7 - 0.4), x),
    );
    bench1(c, "asin", args(-0.999, 0.999), libm::asin, lm::asin::<4>, lm::asin::<8>);
    bench1(c, "acos", args(-0.999, 0.999), libm::acos, lm::acos::<4>, lm::acos::<8>);
    bench1(c, "sin", args(-3.0, 3.0), libm::sin, lm::sin::<4>, lm::sin::<8>);
    bench1(c, "cos", args(-3.0, 3.0), libm::cos, lm::cos::<4>, lm::cos::<8>);
    bench1(
        c,
        "sin_cos",
        args(-3.0, 3.0),
        |x| {
            let (s, c) = libm::sincos(x);
            s + c
        },
        |x| {
            let (s, c) = lm::sin_cos::<4>(x);
            core::array::from_fn(|i| s[i] + c[i])
        },
        |x| {
            let (s, c) = lm::sin_cos::<8>(x);
            core::array::from_fn(|i| s[i] + c[i])
        },
    );
}

criterion_group!(benches, kernels);
criterion_main!(benches);
