//! All integration tests of this crate in one test binary: one link of the
//! crate (built at opt-level 2 by `[profile.test]`) instead of one per file.
//!
//! A new test file goes here as a module: put it in tests/it/ (with its
//! `.proptest-regressions` file, if any, beside it) and add `mod name;` below;
//! shared helpers are `crate::common` (tests/common/). Keep a test in its own
//! tests/<name>.rs binary only when it needs its process alone (a
//! `#[global_allocator]`, `std::env::set_var`, rayon's global pool).

#[path = "../common/mod.rs"]
mod common;

mod cli;
mod compare;
mod cpu_levels;
mod falsify;
mod figures;
mod identify_validate;
mod layout;
mod outputs_doc;
mod provenance;
mod refusals;
mod report_html;
mod result_folders;
mod shards;
mod tune;
