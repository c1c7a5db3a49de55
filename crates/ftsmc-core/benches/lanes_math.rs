//! Speed of the lane kernels of `ftsmc_core::lanes_math` against the
//! scalar `libm` function applied lane by lane (what `Lanes<N>` did
//! before), per element (run on demand:
//! `cargo bench -p ftsmc-core --bench lanes_math`).
//!
//! Each benchmark evaluates one function on the same 64 arguments (in the
//! range the controllers use: `|x| < 3`, positive for `ln`): `scalar` calls `libm` once per argument, `lanes4` /
//! `lanes8` call the kernel on 16 / 8 vectors. Throughput is in elements,
//! so the rates compare per element.
//!
//! The group `avx2/…` (x86-64 CPUs with AVX2 and FMA) runs the same loops
//! inside a `#[target_feature(enable = "avx2,fma")]` function, where the
//! kernels are inlined as they are in the dispatched run loop: `scalar`
//! (libm per element) against `lanes4` (the kernel on 4 lanes). These
//! cells inform `ftsmc_core::lanes::EXP_KERNEL_LANES` (which the Monte
//! Carlo then decides: see its docs).

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
}

/// `scalar` and `lanes4` loops over 64 arguments compiled for AVX2 + FMA.
#[cfg(target_arch = "x86_64")]
macro_rules! avx2_pair {
    ($name:ident, $scalar:expr, $lanes:expr) => {
        mod $name {
            use super::*;
            #[target_feature(enable = "avx2,fma")]
            pub fn scalar(x: &[f64; LEN]) -> [f64; LEN] {
                let mut out = [0.0; LEN];
                for i in 0..LEN {
                    out[i] = $scalar(x[i]);
                }
                out
            }
            #[target_feature(enable = "avx2,fma")]
            pub fn lanes4(x: &[f64; LEN]) -> [f64; LEN] {
                let mut out = [0.0; LEN];
                for k in 0..LEN / 4 {
                    let v: [f64; 4] = core::array::from_fn(|i| x[4 * k + i]);
                    let r = $lanes(v);
                    out[4 * k..4 * k + 4].copy_from_slice(&r);
                }
                out
            }
        }
    };
}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use super::*;
    avx2_pair!(exp, libm::exp, lm::exp::<4>);
    avx2_pair!(ln, libm::log, lm::ln::<4>);

    /// One `avx2/<name>` group: scalar against lanes4.
    fn pair(
        c: &mut Criterion,
        name: &str,
        xs: [f64; LEN],
        scalar: fn(&[f64; LEN]) -> [f64; LEN],
        l4: fn(&[f64; LEN]) -> [f64; LEN],
    ) {
        let mut group = c.benchmark_group(format!("avx2/{name}"));
        group.throughput(Throughput::Elements(LEN as u64));
        group.bench_function("scalar", |b| b.iter(|| black_box(scalar(&black_box(xs)))));
        group.bench_function("lanes4", |b| b.iter(|| black_box(l4(&black_box(xs)))));
        group.finish();
    }

    pub fn kernels(c: &mut Criterion) {
        if !(std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")) {
            eprintln!("avx2/*: this CPU has no AVX2 + FMA; skipped");
            return;
        }
        // SAFETY (each `unsafe` below): AVX2 and FMA were detected just above.
        pair(c, "exp", args(-3.0, 3.0), |x| unsafe { exp::scalar(x) }, |x| unsafe { exp::lanes4(x) });
        pair(c, "ln", args(1e-3, 3.0), |x| unsafe { ln::scalar(x) }, |x| unsafe { ln::lanes4(x) });
    }
}

#[cfg(target_arch = "x86_64")]
criterion_group!(benches, kernels, avx2::kernels);
#[cfg(not(target_arch = "x86_64"))]
criterion_group!(benches, kernels);
criterion_main!(benches);
