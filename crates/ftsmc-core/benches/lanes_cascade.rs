//! Speed of the FTAFTSMC cascade on lanes (run on demand:
//! `cargo bench -p ftsmc-core --bench lanes_cascade`).
//!
//! `cascade-update/<f64|lanes4|lanes8>`: one [`Controller::update`] of the
//! paper's FTAFTSMC cascade (Tables 4–5 gains, mass adaptation, command
//! filter) on one flight (`f64`) and on 4 and 8 flights side by side
//! (`Lanes<4>`, `Lanes<8>`). The throughput is in flights, so criterion's
//! `elem/s` compares the cost per flight directly. Each lane flies its own
//! state (slightly different errors, so the lanes do not take identical
//! values), towards the same reference.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use ftsmc_core::cascade::{Cascade, CascadeConfig, CascadeSettings, MassAdaptation};
use ftsmc_core::controller::Controller;
use ftsmc_core::ftaftsmc::{FtaftsmcAxis, FtaftsmcGains};
use ftsmc_core::lanes::{Lanes, Lanewise, Real};
use ftsmc_core::law::AxisLaw;
use ftsmc_core::model::{QuadState, QuadrotorParams, Reference};

const GAINS: [FtaftsmcGains; 6] = [
    FtaftsmcGains::PAPER_XY,
    FtaftsmcGains::PAPER_XY,
    FtaftsmcGains::PAPER_Z,
    FtaftsmcGains::PAPER_ROLL_PITCH,
    FtaftsmcGains::PAPER_ROLL_PITCH,
    FtaftsmcGains::PAPER_YAW,
];

fn config() -> CascadeConfig {
    CascadeConfig {
        model: QuadrotorParams::default(),
        settings: CascadeSettings::default(),
        mass_adaptation: MassAdaptation::PAPER,
    }
}

/// Flight `i`'s measured state: near the reference, errors that differ by flight.
fn state(i: usize) -> QuadState {
    let d = 0.01 * i as f64;
    QuadState {
        position: [0.1 + d, -0.2 + d, 0.9 - d],
        attitude: [0.05 - d, -0.03 + 0.5 * d, 0.25],
        velocity: [0.3, 0.1 - d, -0.1],
        angular_rate: [0.2, -0.1 + d, 0.05],
    }
}

fn reference() -> Reference {
    Reference {
        position: [0.0, 0.0, 1.0],
        velocity: [0.5, 0.0, 0.1],
        acceleration: [0.0, -0.25, 0.0],
        yaw: 0.3,
        ..Reference::default()
    }
}

/// One update of a cascade on `R` (`R::LANES` flights per call).
fn bench_lanes<R: Real>(group: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>, name: &str)
where
    FtaftsmcAxis<R>: AxisLaw<R>,
{
    let mut cascade =
        Cascade::<FtaftsmcAxis<R>, R>::with_laws(config(), GAINS.map(FtaftsmcAxis::with_gains)).expect("paper gains");
    let mut s = QuadState::<R>::default();
    let mut r = Reference::<R>::default();
    for i in 0..R::LANES {
        s.put_lane(i, state(i));
        r.put_lane(i, reference());
    }
    group.throughput(Throughput::Elements(R::LANES as u64));
    group.bench_function(name, |b| b.iter(|| black_box(cascade.update(black_box(&s), black_box(&r), 1e-3))));
}

fn cascade_update(c: &mut Criterion) {
    let mut group = c.benchmark_group("cascade-update");
    bench_lanes::<f64>(&mut group, "f64");
    bench_lanes::<Lanes<4>>(&mut group, "lanes4");
    bench_lanes::<Lanes<8>>(&mut group, "lanes8");
    group.finish();
}

criterion_group!(benches, cascade_update);
criterion_main!(benches);
