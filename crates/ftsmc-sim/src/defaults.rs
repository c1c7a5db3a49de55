//! The defaults of every campaign a front end starts, written once: the
//! CLI's flags (clap reads these constants), the Python binding's
//! signatures, the Python wrapper (`ftsmc.defaults()` returns them) and the
//! type stubs all take them from here, and `python/tests/test_defaults.py`
//! checks that all four agree.
//!
//! Numbers of flights are per contestant (compare) or per controller
//! (montecarlo); budgets are flights.

/// Randomised runs of `montecarlo`, each flown by every controller.
pub const MONTECARLO_RUNS: u64 = 100;
/// Runs per contestant of `compare` with a fixed number of runs.
pub const COMPARE_RUNS: u64 = 100;
/// Most runs per contestant of `compare` until decided.
pub const COMPARE_MAX_RUNS: u64 = 1000;
/// Runs per look of `compare` until decided.
pub const COMPARE_BATCH: u64 = 50;
/// Training flights of `tune`.
pub const TUNE_BUDGET: u64 = 2000;
/// Flights per method of `falsify` (when the scenario's `[falsify] budget` is not set).
pub const FALSIFY_BUDGET: u64 = 200;
/// Flights of `failure-probability`, cross-entropy levels included.
pub const FAILURE_PROBABILITY_BUDGET: u64 = 2000;
/// Confidence level of every interval and verdict ([`crate::stats::DEFAULT_CONFIDENCE`]).
pub const CONFIDENCE: f64 = crate::stats::DEFAULT_CONFIDENCE;

/// Every default by the name the Python binding gives it (`ftsmc.defaults()`).
pub const ALL: [(&str, f64); 8] = [
    ("montecarlo_runs", MONTECARLO_RUNS as f64),
    ("compare_runs", COMPARE_RUNS as f64),
    ("compare_max_runs", COMPARE_MAX_RUNS as f64),
    ("compare_batch", COMPARE_BATCH as f64),
    ("tune_budget", TUNE_BUDGET as f64),
    ("falsify_budget", FALSIFY_BUDGET as f64),
    ("failure_probability_budget", FAILURE_PROBABILITY_BUDGET as f64),
    ("confidence", CONFIDENCE),
];
