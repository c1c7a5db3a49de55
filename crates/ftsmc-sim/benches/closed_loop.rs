//! Speed of the closed loop (run on demand: `cargo bench -p ftsmc-sim`).
//!
//! - `flight/<controller>`: one 20 s flight of paper scenario 2's first 20 s
//!   at 1 kHz (controller + RK4 plant, recording off); throughput in control steps.
//! - `control-update/<controller>`: one call of the controller.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use ftsmc_core::model::{QuadState, Reference};
use ftsmc_sim::registry;
use ftsmc_sim::run::{simulate, RunOptions};
use ftsmc_sim::scenario::Scenario;

fn flights(c: &mut Criterion) {
    let mut scenario = Scenario::paper_scenarios().remove(1);
    scenario.duration = 20.0;
    let steps = (scenario.duration * scenario.simulation.control_rate) as u64;
    let mut group = c.benchmark_group("flight");
    group.throughput(Throughput::Elements(steps));
    group.sample_size(20);
    for name in ["ftaftsmc", "ranftsmc", "tsm-sta"] {
        group.bench_function(name, |b| {
            b.iter(|| {
                let mut controller = registry::build(name, &scenario).unwrap();
                black_box(simulate(&scenario, controller.as_mut(), RunOptions { record: false, ..Default::default() }))
            })
        });
    }
    group.finish();
}

fn control_update(c: &mut Criterion) {
    let scenario = Scenario::paper_scenarios().remove(1);
    let state = QuadState {
        position: [0.1, -0.2, 0.9],
        attitude: [0.05, -0.03, 0.25],
        velocity: [0.3, 0.1, -0.1],
        angular_rate: [0.2, -0.1, 0.05],
    };
    let reference = Reference {
        position: [0.0, 0.0, 1.0],
        velocity: [0.5, 0.0, 0.1],
        acceleration: [0.0, -0.25, 0.0],
        yaw: 0.3,
        ..Reference::default()
    };
    let mut group = c.benchmark_group("control-update");
    for name in ["ftaftsmc", "ranftsmc", "tsm-sta"] {
        let mut controller = registry::build(name, &scenario).unwrap();
        group.bench_function(name, |b| {
            b.iter(|| black_box(controller.update(black_box(&state), black_box(&reference), 1e-3)))
        });
    }
    group.finish();
}

criterion_group!(benches, flights, control_update);
criterion_main!(benches);
