//! Helpers shared by several test binaries.
//!
//! A scratch folder used by one test is a `tempfile::TempDir` owned by the
//! test: it is removed when the test returns or panics. A folder shared by
//! several tests of one binary (one expensive `reproduce` read by many
//! tests) lives in a `static`, and Rust never drops statics: such a folder
//! is handed to [`removed_at_exit`], which removes it when the test binary
//! exits (C `atexit`, run by `exit(3)` after the test harness finishes,
//! whether the tests passed or failed).

// Each test binary compiles this module and uses only part of it.
#![allow(dead_code)]

use std::path::PathBuf;
use std::sync::{Mutex, Once};

use tempfile::TempDir;

/// A fresh scratch folder `<temp dir>/ftsmc-<test binary>-<name>-<random>`,
/// removed when the returned guard drops: when the test ends, passed or
/// failed.
pub fn scratch(name: &str) -> TempDir {
    tempfile::Builder::new().prefix(&format!("ftsmc-{}-{name}-", env!("CARGO_CRATE_NAME"))).tempdir().unwrap()
}

/// Folders to remove when the process exits.
static AT_EXIT: Mutex<Vec<TempDir>> = Mutex::new(Vec::new());

/// Keep `dir` until the process exits, then remove it; returns its path.
/// (On non-Unix targets, without `atexit` here, the folder is left in the
/// temporary folder.)
pub fn removed_at_exit(dir: TempDir) -> PathBuf {
    static REGISTER: Once = Once::new();
    REGISTER.call_once(|| {
        #[cfg(unix)]
        // SAFETY: `atexit` only records the function; `remove_all` takes
        // no arguments, recovers a poisoned lock and ignores removal errors
        // (`TempDir`'s drop), so it does not unwind out of the handler.
        unsafe {
            libc::atexit(remove_all);
        }
    });
    let path = dir.path().to_path_buf();
    AT_EXIT.lock().unwrap_or_else(|e| e.into_inner()).push(dir);
    path
}

/// Drop (remove) every folder registered by [`removed_at_exit`].
#[cfg(unix)]
extern "C" fn remove_all() {
    let dirs = std::mem::take(&mut *AT_EXIT.lock().unwrap_or_else(|e| e.into_inner()));
    drop(dirs);
}
