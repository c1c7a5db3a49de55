//! Monte Carlo throughput, one thread (run on demand:
//! `cargo bench -p ftsmc-sim --bench montecarlo`).
//!
//! `montecarlo/<scenario>/<controller>/lanes-<n>`: a batch of [`RUNS`]
//! flights of the built-in scenario (shortened to [`DURATION`] s, its
//! Monte Carlo draws as `ftsmc montecarlo` makes them) flown on one thread,
//! one flight at a time (`lanes-1`, the one-flight path) or
//! [`DEFAULT_LANES`] side by side; throughput in control steps flown
//! (flights that end early count the steps they flew). The ratio of the two
//! lines of a controller, measured in the same run, is what lanes gain on
//! this machine; both give the same rows bit for bit (`tests/lanes.rs`).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use ftsmc_sim::batch::montecarlo::{run_batch, BatchOptions, McRun, DEFAULT_LANES};
use ftsmc_sim::registry::CONTROLLERS;
use ftsmc_sim::scenario::{Scenario, PAPER_SCENARIO_2, REALISTIC_SCENARIO_2};

/// Flights per batch.
const RUNS: u64 = 8;
/// Flight duration, s (shortened from the scenarios' 50 s).
const DURATION: f64 = 10.0;

/// One batch on a one-thread pool.
fn batch(pool: &rayon::ThreadPool, s: &Scenario, controller: &str, lanes: usize) -> Vec<McRun> {
    let spec = s.montecarlo.clone().unwrap_or_default();
    let controllers = [controller.to_string()];
    pool.install(|| run_batch(s, &spec, &controllers, BatchOptions { lanes, ..BatchOptions::new(RUNS, s.seed) }))
        .expect("the built-in scenario flies")
}

fn montecarlo(c: &mut Criterion) {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().expect("a one-thread pool");
    for (name, text) in [("realistic-scenario-2", REALISTIC_SCENARIO_2), ("paper-scenario-2", PAPER_SCENARIO_2)] {
        let mut s = Scenario::from_toml_str(text, &format!("{name}.toml")).expect("built-in scenario");
        s.duration = DURATION;
        let mut group = c.benchmark_group(format!("montecarlo/{name}"));
        group.sample_size(10);
        for (controller, _) in CONTROLLERS {
            // Steps flown: the same for every lane count (same rows).
            let rows = batch(&pool, &s, controller, 1);
            let steps: f64 = rows.iter().map(|r| (r.metrics.duration * s.simulation.control_rate).round()).sum();
            group.throughput(Throughput::Elements(steps as u64));
            for lanes in [1, DEFAULT_LANES] {
                group.bench_function(format!("{controller}/lanes-{lanes}"), |b| {
                    b.iter(|| black_box(batch(&pool, &s, controller, lanes)))
                });
            }
        }
        group.finish();
    }
}

criterion_group!(benches, montecarlo);
criterion_main!(benches);
