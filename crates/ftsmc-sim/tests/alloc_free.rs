//! The control loop allocates nothing: the number of heap allocations of a
//! flight does not grow with its length (recording off).
//!
//! Allocations are counted per thread: the test harness's main thread (and
//! any other test thread) allocates at times of its own choosing, and a
//! process-global counter picked those up (the test failed 4 times in 20).
//! Only the allocations made by the thread that runs the measured closure
//! are counted here.

use ftsmc_core::model::{QuadState, Reference};
use ftsmc_sim::registry;
use ftsmc_sim::run::{simulate, RunOptions};
use ftsmc_sim::scenario::Scenario;

mod common;

use common::counting_alloc::{allocations_of, Counting};

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn the_counter_sees_this_threads_allocations_and_no_other_threads() {
    // The counter must be able to fail: an allocation on this thread counts…
    let n = allocations_of(|| {
        std::hint::black_box(vec![1u8; 64]);
    });
    assert!(n >= 1, "an allocation on the measuring thread was not counted");
    // …and a busy allocating thread elsewhere does not.
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let noisy = {
        let stop = stop.clone();
        std::thread::spawn(move || {
            while !stop.load(std::sync::atomic::Ordering::Relaxed) {
                std::hint::black_box(vec![0u8; 128]);
            }
        })
    };
    let n = allocations_of(|| {
        for _ in 0..100_000 {
            std::hint::black_box(1 + 1);
        }
    });
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    noisy.join().unwrap();
    assert_eq!(n, 0, "allocations of another thread were counted");
}

#[test]
fn control_update_and_simulation_loop_do_not_allocate() {
    let scenario = Scenario::paper_scenarios().remove(1);
    for name in ["ftaftsmc", "ranftsmc", "tsm-sta"] {
        let mut c = registry::build(name, &scenario).unwrap();
        let state = QuadState { attitude: [0.1, -0.05, 0.2], ..QuadState::default() };
        let reference = Reference { position: [1.0, 0.5, 1.0], yaw: 0.3, ..Reference::default() };
        let n = allocations_of(|| {
            for _ in 0..10_000 {
                std::hint::black_box(c.update(&state, &reference, 1e-3));
            }
        });
        assert_eq!(n, 0, "{name}: {n} allocations in 10 000 control updates");

        let flight = |duration: f64| {
            let mut s = scenario.clone();
            s.duration = duration;
            let mut c = registry::build(name, &s).unwrap();
            allocations_of(|| {
                std::hint::black_box(simulate(&s, c.as_mut(), RunOptions { record: false, ..Default::default() }));
            })
        };
        let (short, long) = (flight(1.0), flight(12.0));
        assert_eq!(short, long, "{name}: allocations grow with flight length ({short} → {long})");
    }
}
