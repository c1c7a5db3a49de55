//! Cost of recording and writing a flight's time series (run on demand:
//! `cargo bench -p ftsmc-sim --bench recording`).
//!
//! One paper-scenario-2 flight (50 s at 1 kHz, FTAFTSMC, time series at
//! 100 Hz), three ways; throughput in control steps:
//!
//! - `scenario-2/no-recording`: metrics only (`RunOptions { record: false }`);
//! - `scenario-2/recording`: the time series kept in memory;
//! - `scenario-2/recording+csv`: and serialised to CSV bytes, as `ftsmc run`
//!   writes it ([`Recording::to_csv`]: zmij into one byte buffer);
//! - `scenario-2/recording+legacy-csv`: the same rows through the writer
//!   `ftsmc` used before (the `csv` crate, one `format!`ed `String` per number).
//!
//! The CSV overhead is `recording+csv / no-recording − 1` (the aim is
//! at most 20 %).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use ftsmc_sim::registry;
use ftsmc_sim::run::{simulate, Recording, RunOptions};
use ftsmc_sim::scenario::Scenario;

/// The CSV writer of `ftsmc` before it was replaced: the `csv` crate with
/// one `format!`ed `String` per number.
fn legacy_csv(rec: &Recording) -> Vec<u8> {
    let fmt = |v: f64| {
        if v.is_nan() {
            "NaN".to_string()
        } else if v.is_infinite() {
            if v > 0.0 { "inf" } else { "-inf" }.to_string()
        } else {
            format!("{v}")
        }
    };
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(&rec.names).unwrap();
    let mut row = Vec::with_capacity(rec.names.len());
    for i in 0..rec.len() {
        row.clear();
        row.extend(rec.columns.iter().map(|c| fmt(c[i])));
        w.write_record(&row).unwrap();
    }
    w.into_inner().unwrap()
}

fn scenario_2(c: &mut Criterion) {
    let scenario = Scenario::paper_scenarios().remove(1);
    let steps = (scenario.duration * scenario.simulation.control_rate).round() as u64;
    let mut group = c.benchmark_group("scenario-2");
    group.throughput(Throughput::Elements(steps));
    group.sample_size(10);
    let fly = |record: bool| {
        let mut controller = registry::build("ftaftsmc", &scenario).unwrap();
        simulate(&scenario, controller.as_mut(), RunOptions { record, ..Default::default() })
    };
    group.bench_function("no-recording", |b| b.iter(|| black_box(fly(false))));
    group.bench_function("recording", |b| b.iter(|| black_box(fly(true))));
    group.bench_function("recording+csv", |b| b.iter(|| black_box(fly(true).recording.to_csv())));
    group.bench_function("recording+legacy-csv", |b| b.iter(|| black_box(legacy_csv(&fly(true).recording))));
    group.finish();
}

criterion_group!(benches, scenario_2);
criterion_main!(benches);
