//! The type of a declared `ftsmc tune` parameter ([`TuneParam`]: a named
//! factor with bounds on some gains) and what it may change
//! ([`TuneTarget`]). The controllers' files declare their parameters with
//! it (`tune_parameters()`), and each controller's line in the list of
//! `controllers/mod.rs` names its function; `tunable.rs` looks them up.
//! Kept apart from `tunable.rs` so that no controller file imports a file
//! that imports it back.

use ftsmc_core::cascade::CascadeSettings;

use super::GainSections;

/// What a parameter may change: every gain section and the shared
/// `[cascade]` settings (command filter) of one scenario.
pub struct TuneTarget<'a> {
    /// The scenario's gain sections.
    pub gains: &'a mut GainSections,
    /// The scenario's `[cascade]` settings.
    pub cascade: &'a mut CascadeSettings,
}

/// One declared parameter: a factor on some gains.
#[derive(Clone, Copy, Debug)]
pub struct TuneParam {
    /// Name (a `[tune]` key and a `history.csv` column).
    pub name: &'static str,
    /// What it multiplies, in one line (docs and `ftsmc tune --list`).
    pub doc: &'static str,
    /// Smallest factor searched (> 0).
    pub low: f64,
    /// Largest factor searched.
    pub high: f64,
    /// Multiply the gains it stands for by `factor`.
    pub apply: fn(&mut TuneTarget<'_>, f64),
}

impl TuneParam {
    /// A log-scale factor parameter searched in `[low, high]`.
    pub const fn factor(
        name: &'static str,
        doc: &'static str,
        low: f64,
        high: f64,
        apply: fn(&mut TuneTarget<'_>, f64),
    ) -> Self {
        Self { name, doc, low, high, apply }
    }
}

/// The declaration of a controller with no tunable parameters (yet): what
/// its line in the list of `controllers/mod.rs` names as `tune`, so that
/// declaring none is written down, not forgotten. `ftsmc tune -c all`
/// leaves such a controller out; `ftsmc tune -c NAME` tunes only its
/// `[[tune.extra]]` keys.
pub fn none() -> Vec<TuneParam> {
    Vec::new()
}

/// Command-filter bandwidth factor on `[cascade] command_filter.natural_frequency`
/// (shared by the cascaded sliding-mode controllers).
pub const COMMAND_FILTER: TuneParam = TuneParam::factor(
    "command_filter",
    "factor on the attitude command filter's natural frequency ω_n ([cascade])",
    0.1,
    4.0,
    |t, a| t.cascade.command_filter.natural_frequency *= a,
);

/// Indices of the horizontal axes x, y (or roll, pitch) in a per-axis
/// `[f64; 3]` gain.
pub const HORIZONTAL: &[usize] = &[0, 1];

/// Index of the vertical axis z (or yaw) in a per-axis `[f64; 3]` gain.
pub const VERTICAL: &[usize] = &[2];

/// Multiply the elements `idx` of a per-axis gain by `factor` (a factor
/// parameter's `apply` on a group of axes).
pub fn scale(gain: &mut [f64; 3], idx: &[usize], factor: f64) {
    for &i in idx {
        gain[i] *= factor;
    }
}
