//! `Sensors::measure` never allocates: the latency line is allocated once in
//! `Sensors::new`. A separate test binary because it installs a counting
//! global allocator (per thread, as in `alloc_free.rs`).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use ftsmc_core::model::QuadState;
use ftsmc_sim::sensors::{QuantityError, RateFrame, SensorParams, Sensors};

struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

fn count_one() {
    let _ = ALLOCATIONS.try_with(|n| n.set(n.get() + 1));
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count_one();
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        count_one();
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count_one();
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

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
    };
    let mut sensors = Sensors::new(params, 1000.0, 3);
    let before = ALLOCATIONS.with(Cell::get);
    let mut sink = 0.0;
    for n in 0..10_000 {
        let truth = QuadState { position: [f64::from(n) * 1e-3; 3], ..QuadState::default() };
        sink += sensors.measure(&truth).position[0];
    }
    let after = ALLOCATIONS.with(Cell::get);
    assert!(sink.is_finite());
    assert_eq!(after - before, 0, "measure allocated {} times in 10 000 calls", after - before);
}
