//! Progress of a long flight batch, reported to a Python callable.
//!
//! The batch flies on its own thread with the GIL released and counts the
//! control steps it has flown; the calling thread wakes every
//! [`INTERVAL`], takes the GIL and calls `progress(done, total)` (steps), a
//! last time with `done == total`. The numbers flown do not depend on it.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use pyo3::prelude::*;

/// Time between two calls of the progress callable.
pub const INTERVAL: Duration = Duration::from_millis(200);

/// Run `work` (given the step counter it must call with each batch of steps
/// flown) with the GIL released; while it runs, call `progress(done, total)`
/// every [`INTERVAL`]. The first exception the callable raises stops further
/// calls and is returned once the batch has finished (its result dropped).
pub fn with_progress<R: Send>(
    py: Python<'_>,
    total: u64,
    progress: Option<&Bound<'_, PyAny>>,
    work: impl FnOnce(&(dyn Fn(u64) + Sync)) -> R + Send,
) -> PyResult<R> {
    let Some(callback) = progress else {
        return Ok(py.detach(|| work(&|_| {})));
    };
    let done = AtomicU64::new(0);
    let mut error: Option<PyErr> = None;
    let result = std::thread::scope(|s| {
        let counter = &done;
        let worker = s.spawn(move || {
            work(&|n| {
                counter.fetch_add(n, Ordering::Relaxed);
            })
        });
        loop {
            let finished = py.detach(|| {
                let start = Instant::now();
                while !worker.is_finished() && start.elapsed() < INTERVAL {
                    std::thread::sleep(Duration::from_millis(5));
                }
                worker.is_finished()
            });
            if error.is_none() {
                let now = if finished { total } else { done.load(Ordering::Relaxed).min(total) };
                if let Err(e) = callback.call1((now, total)) {
                    error = Some(e);
                }
            }
            if finished {
                break;
            }
        }
        worker.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic))
    });
    match error {
        Some(e) => Err(e),
        None => Ok(result),
    }
}
