//! Helpers shared by several test binaries.

// Each test binary compiles this module and uses only part of it.
#![allow(dead_code)]

pub mod counting_alloc;

/// A fresh scratch folder `<temp dir>/ftsmc-<test binary>-<name>-<random>`,
/// removed when the returned guard drops: when the test ends, passed or
/// failed.
pub fn scratch(name: &str) -> tempfile::TempDir {
    tempfile::Builder::new().prefix(&format!("ftsmc-{}-{name}-", env!("CARGO_CRATE_NAME"))).tempdir().unwrap()
}
