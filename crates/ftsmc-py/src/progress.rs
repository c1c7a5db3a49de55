//! Progress of a long flight batch, reported to a Python callable, with
//! Ctrl-C handling.
//!
//! The batch flies on its own thread with the GIL released and counts the
//! control steps it has flown. The calling thread wakes every
//! [`SIGNAL_POLL`] to check for signals (Ctrl-C sets the
//! cancellation flag, the batch stops and `KeyboardInterrupt` is raised, as
//! in the flight module's `with_ctrl_c`) and every [`INTERVAL`] takes the GIL to call
//! `progress(done, total)` (steps), a last time with `done == total`. The
//! numbers flown do not depend on it.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

use pyo3::prelude::*;

/// How often the watcher checks for a signal (Ctrl-C), s (shared by
/// `flight.rs`'s `with_ctrl_c` and [`with_progress`]).
pub(crate) const SIGNAL_POLL: std::time::Duration = std::time::Duration::from_millis(50);

/// Time between two calls of the progress callable.
pub const INTERVAL: Duration = Duration::from_millis(200);

/// Run `work` (given the cancellation flag and the step counter it must call
/// with each batch of steps flown) on a worker thread with the GIL released;
/// while it runs, check for signals and call `progress(done, total)` every
/// [`INTERVAL`]. The first exception the callable raises stops further
/// calls and is returned once the batch has finished (its result dropped).
pub fn with_progress<R: Send>(
    py: Python<'_>,
    total: u64,
    progress: Option<&Bound<'_, PyAny>>,
    work: impl FnOnce(&AtomicBool, &(dyn Fn(u64) + Sync)) -> R + Send,
) -> PyResult<R> {
    let cancel = AtomicBool::new(false);
    let done = AtomicU64::new(0);
    let mut error: Option<PyErr> = None;
    let mut interrupted: Option<PyErr> = None;
    let result = std::thread::scope(|s| {
        let (counter, flag) = (&done, &cancel);
        let worker = s.spawn(move || {
            work(flag, &|n| {
                counter.fetch_add(n, Ordering::Relaxed);
            })
        });
        let mut last_call = Instant::now();
        loop {
            let finished = py.detach(|| {
                std::thread::sleep(SIGNAL_POLL.min(INTERVAL));
                worker.is_finished()
            });
            if let Err(e) = py.check_signals() {
                cancel.store(true, Ordering::Relaxed);
                interrupted = Some(e);
                break;
            }
            if let Some(callback) = progress {
                if error.is_none() && (finished || last_call.elapsed() >= INTERVAL) {
                    last_call = Instant::now();
                    let now = if finished { total } else { done.load(Ordering::Relaxed).min(total) };
                    if let Err(e) = callback.call1((now, total)) {
                        error = Some(e);
                    }
                }
            }
            if finished {
                break;
            }
        }
        py.detach(|| worker.join())
    });
    if let Some(e) = interrupted.or(error) {
        return Err(e);
    }
    result.map_err(|_| pyo3::exceptions::PyRuntimeError::new_err("the flight thread panicked"))
}
