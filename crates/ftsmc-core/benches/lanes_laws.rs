//! Speed of one law update per flight, one flight at a time (`f64`) or
//! several side by side (`Lanes<4>`, `Lanes<8>`) (run on demand:
//! `cargo bench -p ftsmc-core --bench lanes_laws`).
//!
//! Each benchmark flies the same 8 flights for 64 control periods of 1 ms
//! through one channel of a law: 8 `f64` laws, 2 laws on `Lanes<4>` or one
//! on `Lanes<8>`, fed the same precomputed errors (a different trajectory
//! per flight, away from the zero-rate special cases, as in flight).
//! Throughput is in flight updates, so the rates compare per flight.
//!
//! - `ranftsmc/*`: RANFTSMC with the published position gains.
//! - `tsm-sta/*`: TSM-STA with the default position gains.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use ftsmc_core::lanes::{Lanes, Real};
use ftsmc_core::law::AxisLaw;
use ftsmc_core::ranftsmc::{RanftsmcAxis, RanftsmcGains};
use ftsmc_core::tsm_sta::{TsmStaAxis, TsmStaGains};

const FLIGHTS: usize = 8;
const STEPS: usize = 64;
const DT: f64 = 1e-3;

/// `(e, ė)` of flight `f` at step `k`: decaying oscillations, a different
/// amplitude and phase per flight.
fn inputs() -> [[(f64, f64); FLIGHTS]; STEPS] {
    core::array::from_fn(|k| {
        core::array::from_fn(|f| {
            let t = k as f64 * DT * 40.0 + f as f64 * 0.7;
            let a = 0.2 + 0.15 * f as f64;
            (a * ftsmc_core::math::cos(t), -0.8 * a * ftsmc_core::math::sin(t) - 0.05)
        })
    })
}

/// 8 flights × 64 periods on `f64`, `Lanes<4>` and `Lanes<8>`.
fn bench_law<L1, L4, L8>(c: &mut Criterion, name: &str, one: L1, four: L4, eight: L8)
where
    L1: AxisLaw<f64> + Copy,
    L4: AxisLaw<Lanes<4>> + Copy,
    L8: AxisLaw<Lanes<8>> + Copy,
{
    let table = inputs();
    let mut group = c.benchmark_group(name);
    group.throughput(Throughput::Elements((FLIGHTS * STEPS) as u64));
    group.bench_function("f64", |b| {
        b.iter(|| {
            let mut laws = [one; FLIGHTS];
            let mut sum = 0.0;
            for row in &table {
                for (law, &(e, e_dot)) in laws.iter_mut().zip(row) {
                    sum += law.update(black_box(e), black_box(e_dot), DT);
                }
            }
            black_box(sum)
        })
    });
    group.bench_function("lanes4", |b| {
        b.iter(|| {
            let mut laws = [four; FLIGHTS / 4];
            let mut sum = Lanes::<4>::splat(0.0);
            for row in &table {
                for (j, law) in laws.iter_mut().enumerate() {
                    let e = Lanes::<4>::from_fn(|i| row[4 * j + i].0);
                    let e_dot = Lanes::<4>::from_fn(|i| row[4 * j + i].1);
                    sum += law.update(black_box(e), black_box(e_dot), DT);
                }
            }
            black_box(sum)
        })
    });
    group.bench_function("lanes8", |b| {
        b.iter(|| {
            let mut law = eight;
            let mut sum = Lanes::<8>::splat(0.0);
            for row in &table {
                let e = Lanes::<8>::from_fn(|i| row[i].0);
                let e_dot = Lanes::<8>::from_fn(|i| row[i].1);
                sum += law.update(black_box(e), black_box(e_dot), DT);
            }
            black_box(sum)
        })
    });
    group.finish();
}

fn laws(c: &mut Criterion) {
    let g = RanftsmcGains::PAPER_POSITION;
    bench_law(c, "ranftsmc", RanftsmcAxis::new(g), RanftsmcAxis::splat(g), RanftsmcAxis::splat(g));
    let g = TsmStaGains::DEFAULT_POSITION;
    bench_law(c, "tsm-sta", TsmStaAxis::new(g), TsmStaAxis::splat(g), TsmStaAxis::splat(g));
}

criterion_group!(benches, laws);
criterion_main!(benches);
