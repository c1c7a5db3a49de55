//! One module per subcommand: each parses its clap arguments (the shared
//! groups of [`crate::args`]), checks them, calls the library and presents
//! the result. A command never imports another command; what two commands
//! share lives in a module outside `commands/` (the layout test
//! `tests/it/layout.rs` of this crate enforces both).

pub mod compare;
pub mod failure_probability;
pub mod falsify;
pub mod fixed_time;
pub mod identify;
pub mod list;
pub mod merge;
pub mod montecarlo;
pub mod px4;
pub mod reproduce;
pub mod run;
pub mod scenario;
pub mod tune;
pub mod tune_tsm_sta;
pub mod validate;
