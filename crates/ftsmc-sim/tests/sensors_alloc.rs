//! `Sensors::measure` never allocates: the latency line is allocated once in
//! `Sensors::new`. A separate test binary because it installs a counting
//! global allocator (per thread, as in `alloc_free.rs`).

use ftsmc_core::model::QuadState;
use ftsmc_sim::sensors::{QuantityError, RateFrame, SensorClock, SensorParams, Sensors};

mod common;

use common::counting_alloc::{allocations_of, Counting};

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn measure_does_not_allocate() {
    let noisy = QuantityError { std: [1e-3; 3], bias: [1e-3; 3] };
    let params = SensorParams {
        position: noisy,
        velocity: noisy,
        attitude: noisy,
        angular_rate: noisy,
        rates: RateFrame::Body,
        sample_rate: Some(250.0),
        latency: 7,
        // The IMU on its own clock: a second latency line, allocated once too.
        imu: Some(SensorClock { sample_rate: Some(1000.0), latency: 1 }),
        ..SensorParams::default()
    };
    let mut sensors = Sensors::new(params, 1000.0, 3);
    let mut sink = 0.0;
    let n = allocations_of(|| {
        for n in 0..10_000 {
            let truth = QuadState { position: [f64::from(n) * 1e-3; 3], ..QuadState::default() };
            sink += sensors.measure(&truth).position[0];
        }
    });
    assert!(sink.is_finite());
    assert_eq!(n, 0, "measure allocated {n} times in 10 000 calls");
}
