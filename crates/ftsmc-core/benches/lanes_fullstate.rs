//! Speed of the full-state controllers on one flight (`f64`) and on lanes
//! of flights (`Lanes<4>`, `Lanes<8>`), per flight (run on demand:
//! `cargo bench -p ftsmc-core --bench lanes_fullstate`).
//!
//! Each benchmark calls `update_measured` (quaternion and body rates
//! given, as the rigid-body truth model provides them) for 1000 control
//! periods of 1 ms; every lane flies its own flight near hover (position
//! errors of a few cm, tilts of a few degrees, a slowly turning heading),
//! so the lanes seldom take different branches, as in a Monte Carlo batch.
//! Throughput is in flight-periods: a `Lanes<8>` update counts 8, so the
//! reported rates compare the cost per flight directly.

use std::hint::black_box;

use criterion::measurement::WallTime;
use criterion::{criterion_group, criterion_main, BenchmarkGroup, Criterion, Throughput};
use ftsmc_core::controller::Controller;
use ftsmc_core::kinematics::{body_rates_from_euler_rates, quaternion_from_euler};
use ftsmc_core::lanes::{Lanes, Lanewise, Real};
use ftsmc_core::measured::{BodyAttitude, Measurement};
use ftsmc_core::model::{QuadState, QuadrotorParams, Reference};
use ftsmc_core::{PidController, PidGains, Se3Controller, Se3Gains};

const STEPS: usize = 1000;
const DT: f64 = 1e-3;

/// Flight `flight`'s measurement and reference at period `k`: near hover,
/// smooth, different in every flight.
fn inputs(flight: usize, k: usize) -> (Measurement, Reference) {
    let t = k as f64 * DT;
    let f = flight as f64;
    let phase = 0.7 * f + 3.0 * t;
    let s = |a: f64| ftsmc_core::math::sin(a);
    let attitude = [0.05 * s(phase), -0.04 * s(1.3 * phase), 0.2 + 0.1 * t];
    let angular_rate = [0.15 * s(phase + 1.0), -0.1 * s(1.3 * phase + 1.0), 0.1];
    let euler = QuadState {
        position: [0.03 * s(phase), -0.02 * s(phase + 0.5), 1.0 + 0.01 * f],
        attitude,
        velocity: [0.1 * s(phase + 2.0), 0.05 * s(phase), 0.02],
        angular_rate,
    };
    let body = Some(BodyAttitude {
        quaternion: quaternion_from_euler(&attitude),
        body_rates: body_rates_from_euler_rates(&attitude, &angular_rate),
    });
    let reference = Reference { position: [0.0, 0.0, 1.0], yaw: 0.2 + 0.1 * t, yaw_rate: 0.1, ..Reference::default() };
    (Measurement { euler, body }, reference)
}

/// The inputs of every period, flights side by side in `R`'s lanes.
fn lane_inputs<R: Real>() -> Vec<(Measurement<R>, Reference<R>)> {
    (0..STEPS)
        .map(|k| {
            let mut m = Measurement::<R>::default();
            let mut r = Reference::<R>::default();
            for lane in 0..R::LANES {
                let (mi, ri) = inputs(lane, k);
                m.put_lane(lane, mi);
                r.put_lane(lane, ri);
            }
            (m, r)
        })
        .collect()
}

fn bench_one<R: Real, C: Controller<R>>(group: &mut BenchmarkGroup<'_, WallTime>, name: &str, build: impl Fn() -> C) {
    let data = lane_inputs::<R>();
    group.throughput(Throughput::Elements((STEPS * R::LANES) as u64));
    group.bench_function(name, |b| {
        b.iter(|| {
            let mut c = build();
            let mut last = R::splat(0.0);
            for (m, r) in &data {
                last = c.update_measured(black_box(m), r, DT).thrust;
            }
            black_box(last)
        })
    });
}

fn controllers(c: &mut Criterion) {
    let p = QuadrotorParams::default();
    let pid = PidGains::for_vehicle(&p);
    let se3 = Se3Gains::for_vehicle(&p);
    let mut group = c.benchmark_group("pid-update");
    bench_one::<f64, _>(&mut group, "f64", || PidController::splat(p, pid).unwrap());
    bench_one::<Lanes<4>, _>(&mut group, "lanes4", || PidController::<Lanes<4>>::splat(p, pid).unwrap());
    bench_one::<Lanes<8>, _>(&mut group, "lanes8", || PidController::<Lanes<8>>::splat(p, pid).unwrap());
    group.finish();
    let mut group = c.benchmark_group("se3-update");
    bench_one::<f64, _>(&mut group, "f64", || Se3Controller::splat(p, se3).unwrap());
    bench_one::<Lanes<4>, _>(&mut group, "lanes4", || Se3Controller::<Lanes<4>>::splat(p, se3).unwrap());
    bench_one::<Lanes<8>, _>(&mut group, "lanes8", || Se3Controller::<Lanes<8>>::splat(p, se3).unwrap());
    group.finish();
}

criterion_group!(benches, controllers);
criterion_main!(benches);
