//! What `ftsmc tune` may change in each controller: named parameters with
//! bounds and scale, declared in the controller's own file
//! (`tune_parameters()` in `ftaftsmc.rs`, `pid.rs`, …) and listed here by
//! controller name.
//!
//! Every declared parameter is a **factor** on the gains the scenario
//! already has (its start is 1: the controller's defaults, or the gains the
//! scenario file sets), searched on a log scale between `low` and `high`.
//! Applying a parameter multiplies one or more gains; applying the same
//! values to the same scenario always gives the same gains, and the factor
//! 1 leaves them bit for bit as they were.
//!
//! # Adding a parameter
//!
//! Append a [`TuneParam`] to the controller's `tune_parameters()`: a name
//! (unique for the controller; it is a `[tune]` key and a `history.csv`
//! column), one line of documentation, bounds on the factor and the
//! function that applies it (`apply(target, factor)` multiplies the gains
//! it stands for). A user adds a one-off parameter without code through
//! `[[tune.extra]]` (any numeric key, absolute values).

pub use super::tune_param::{TuneParam, TuneTarget, COMMAND_FILTER};

/// The declared parameters of controller `name`; `Err(known names)` for an
/// unknown one.
pub fn parameters(name: &str) -> Result<Vec<TuneParam>, String> {
    super::check_name(name)?;
    Ok(match name {
        "ftaftsmc" => super::ftaftsmc::tune_parameters(true),
        "ftaftsmc-no-mass" => super::ftaftsmc::tune_parameters(false),
        "ranftsmc" => super::ranftsmc::tune_parameters(),
        "tsm-sta" => super::tsm_sta::tune_parameters(),
        "pid" => super::pid::tune_parameters(),
        "se3" => super::se3::tune_parameters(),
        _ => Vec::new(),
    })
}
