//! Helpers shared by several test binaries.
pub mod counting_alloc;
