//! The control loop allocates nothing: the number of heap allocations of a
//! flight does not grow with its length (recording off).

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use ftsmc_core::model::{QuadState, Reference};
use ftsmc_sim::registry;
use ftsmc_sim::scenario::Scenario;
use ftsmc_sim::simulate::{simulate, RunOptions};

struct Counting;
static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn allocations_of(f: impl FnOnce()) -> usize {
    let before = ALLOCATIONS.load(Ordering::SeqCst);
    f();
    ALLOCATIONS.load(Ordering::SeqCst) - before
}

#[test]
fn control_update_and_simulation_loop_do_not_allocate() {
    // One test (not several) so that no other test thread allocates meanwhile.
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
                std::hint::black_box(simulate(&s, c.as_mut(), RunOptions { record: false }));
            })
        };
        let (short, long) = (flight(1.0), flight(12.0));
        assert_eq!(short, long, "{name}: allocations grow with flight length ({short} → {long})");
    }
}
