//! Cost limits: every request is priced before any flight and refused when
//! it is above a documented, generous limit, so a typo (`duration = 1e6`,
//! `--runs 1000000000000`, `substeps = 1e9`) fails in milliseconds with a
//! message instead of hanging, exhausting memory or panicking.
//!
//! Every limit can be raised explicitly, either in the scenario file
//!
//! ```toml
//! [limits]
//! max_steps = 1e10
//! ```
//!
//! or on the command line (`ftsmc run my.toml --limit max_steps=1e10`; the
//! command line wins over the file). The defaults are chosen so that every
//! request under them finishes in minutes to hours on a laptop and fits in a
//! few GB of memory and disk; see `docs/scenarios.md`.
//!
//! All amounts are computed in `f64`, so no request — however large — can
//! overflow while being priced.
//!
//! # Hard bounds
//!
//! A limit set to `inf` switches its check off, not the bounds of the
//! machine: [`hard_bound`] holds whatever the limits say. The steps of one
//! flight stay below [`HARD_MAX_STEPS`]; what a command holds in memory
//! (recorded rows, the rows and CSV text of a batch, the text of a scenario
//! file) stays below the machine's memory ([`memory_bytes`]); worker threads
//! stay below [`hard_max_threads`] (a multiple of the cores); a fixed-time
//! sweep below [`HARD_MAX_SWEEP_POINTS`] magnitudes. A request above a hard
//! bound is refused like one above a limit, with a message saying that no
//! limit raises it (split the work instead: `--shard`, shorter flights).

use ftsmc_core::law::MAX_ESTIMATES;
use serde::{Deserialize, Serialize};

/// Default [`Limits::max_steps`]: 2·10⁸ RK4 steps per flight (about 4 min
/// at ~0.8 M steps/s; 250× paper scenario 2).
pub const DEFAULT_MAX_STEPS: f64 = 2e8;
/// Default [`Limits::max_samples`]: 10⁶ recorded rows per flight
/// (10 000 s at the default 100 Hz; ~0.5 GB in memory).
pub const DEFAULT_MAX_SAMPLES: f64 = 1e6;
/// Default [`Limits::max_output_bytes`]: 2 GB of estimated output per command.
pub const DEFAULT_MAX_OUTPUT_BYTES: f64 = 2e9;
/// Default [`Limits::max_flights`]: 10⁶ flights (runs × controllers) per Monte Carlo batch.
pub const DEFAULT_MAX_FLIGHTS: f64 = 1e6;
/// Default [`Limits::max_sweep_points`]: 1000 initial-error magnitudes per fixed-time sweep.
pub const DEFAULT_MAX_SWEEP_POINTS: f64 = 1000.0;
/// Default [`Limits::max_scenario_bytes`]: 1 MiB (the paper scenarios are ~8 KiB).
pub const DEFAULT_MAX_SCENARIO_BYTES: f64 = 1024.0 * 1024.0;
/// Estimated bytes of one CSV value (digits, sign, exponent, separator).
pub const BYTES_PER_VALUE: f64 = 20.0;
/// Estimated CSV columns of one Monte Carlo row (`runs.csv`: identifiers,
/// sampled values and metrics).
pub const MONTE_CARLO_COLUMNS: f64 = 64.0;

/// Signal term evaluations that cost about as much as one integration step
/// (an RK4 step of the plant with its controller is ~1 µs; a sine term is
/// ~20–30 ns): `max_steps` prices `steps × (1 + terms / TERMS_PER_STEP)`.
pub const TERMS_PER_STEP: f64 = 32.0;

/// Default [`Limits::max_threads`]: 4 × the available cores, at least 256.
pub fn default_max_threads() -> f64 {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    (4 * cores).max(256) as f64
}

/// The cost limits of one command. In a scenario: the optional `[limits]`
/// table (every key optional); on the command line: `--limit KEY=VALUE`.
/// Values are numbers (`1e10` is fine) and must be > 0.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct Limits {
    /// RK4 integration steps per flight, substeps included:
    /// `duration × control_rate × substeps` (default 2e8).
    pub max_steps: f64,
    /// Recorded time-series rows per flight: `duration × record_rate`
    /// (default 1e6). The recording is reserved up front, so this also
    /// bounds memory (rows × ~70 columns × 8 bytes).
    pub max_samples: f64,
    /// Estimated bytes written by one command (CSV time series of every
    /// controller, or `runs.csv` of a batch), at ~20 bytes per value (default 2e9).
    pub max_output_bytes: f64,
    /// Flights in a Monte Carlo batch: `--runs` × controllers (default 1e6).
    pub max_flights: f64,
    /// Initial-error magnitudes of `ftsmc fixed-time`: `5 × --per-decade + 1` (default 1000).
    pub max_sweep_points: f64,
    /// Worker threads of `ftsmc montecarlo --threads` (default 4 × cores, at least 256).
    pub max_threads: f64,
    /// Size of a scenario file, bytes (default 1 MiB). A file is read before
    /// its `[limits]` are known, so only `--limit max_scenario_bytes=…` raises this.
    pub max_scenario_bytes: f64,
}

impl Default for Limits {
    fn default() -> Self {
        Self {
            max_steps: DEFAULT_MAX_STEPS,
            max_samples: DEFAULT_MAX_SAMPLES,
            max_output_bytes: DEFAULT_MAX_OUTPUT_BYTES,
            max_flights: DEFAULT_MAX_FLIGHTS,
            max_sweep_points: DEFAULT_MAX_SWEEP_POINTS,
            max_threads: default_max_threads(),
            max_scenario_bytes: DEFAULT_MAX_SCENARIO_BYTES,
        }
    }
}

/// Most RK4 steps of one flight whatever `max_steps` says (weighted by the
/// signal terms like `max_steps`): 10¹² steps, about two weeks of one core;
/// also keeps every step count far inside `u64`.
pub const HARD_MAX_STEPS: f64 = 1e12;

/// Most magnitudes of one fixed-time sweep whatever `max_sweep_points` says
/// (each is a flight of every channel; 10⁶ is days of work).
pub const HARD_MAX_SWEEP_POINTS: f64 = 1e6;

/// Memory a Monte Carlo batch holds per flight until it is written: the
/// row (sampled values, metrics, statistics) and its `runs.csv` text, bytes.
pub const HELD_BYTES_PER_FLIGHT: f64 = 2048.0;

/// Bytes per recorded value held in memory (`f64`).
const BYTES_PER_HELD_VALUE: f64 = 8.0;

/// Memory assumed when the machine's cannot be read: 8 GiB.
const FALLBACK_MEMORY_BYTES: f64 = 8.0 * 1024.0 * 1024.0 * 1024.0;

/// The machine's physical memory, bytes (`MemTotal` of `/proc/meminfo`;
/// 8 GiB where it cannot be read): the ceiling of everything a command
/// reserves or holds, whatever the limits.
pub fn memory_bytes() -> f64 {
    static MEMORY: std::sync::OnceLock<f64> = std::sync::OnceLock::new();
    *MEMORY.get_or_init(|| {
        let kib = std::fs::read_to_string("/proc/meminfo").ok().and_then(|text| {
            let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
            line.split_whitespace().nth(1)?.parse::<f64>().ok()
        });
        kib.map_or(FALLBACK_MEMORY_BYTES, |k| k * 1024.0)
    })
}

/// Most worker threads whatever `max_threads` says: 64 × the available
/// cores, at least 1024 (above the default limit, far below what makes
/// spawning them hang).
pub fn hard_max_threads() -> f64 {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    (64 * cores).max(1024) as f64
}

/// The hard bound of limit `key` and why it holds: what no `[limits]` or
/// `--limit` raises (see the module docs). `max_flights` is bounded by the
/// memory a batch holds ([`HELD_BYTES_PER_FLIGHT`] per flight),
/// `max_samples` by the memory of a recording (every column an `f64`),
/// `max_output_bytes` and `max_scenario_bytes` by the memory the text is
/// built in.
pub fn hard_bound(key: &str) -> (f64, &'static str) {
    let memory = memory_bytes();
    match key {
        "max_steps" => (HARD_MAX_STEPS, "two weeks of one core"),
        "max_samples" => {
            (memory / (MAX_RECORDING_COLUMNS as f64 * BYTES_PER_HELD_VALUE), "rows held in this machine's memory")
        }
        "max_output_bytes" => (memory, "this machine's memory: results are built in it"),
        "max_flights" => (memory / HELD_BYTES_PER_FLIGHT, "rows held in this machine's memory"),
        "max_sweep_points" => (HARD_MAX_SWEEP_POINTS, "each is a flight per channel"),
        "max_threads" => (hard_max_threads(), "64 × the cores, at least 1024"),
        "max_scenario_bytes" => (memory / 16.0, "read and parsed in memory"),
        _ => (f64::INFINITY, ""),
    }
}

/// A request above a limit.
#[derive(Clone, Debug, PartialEq)]
pub struct LimitError {
    /// The limit's key, e.g. `max_steps`.
    pub key: &'static str,
    /// What was priced, e.g. `integration steps per flight (duration × control_rate × substeps)`.
    pub what: String,
    /// The amount requested.
    pub requested: f64,
    /// The limit in force.
    pub allowed: f64,
    /// Refused by the [`hard_bound`] of the key (which no limit raises),
    /// with its reason; `None` for the limit itself.
    pub hard: Option<&'static str>,
}

impl core::fmt::Display for LimitError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let key = self.key;
        if let Some(why) = self.hard {
            return write!(
                f,
                "refused: {} = {} exceeds the hard bound {} of {key} ({why}), which holds even with {key} = inf; \
                 split the work (--shard K/N, fewer runs, shorter flights)",
                self.what,
                crate::text::show(self.requested),
                crate::text::show(self.allowed),
            );
        }
        write!(
            f,
            "refused before running: {} = {} exceeds the limit {key} = {}; to allow it, raise it with \
             `[limits] {key} = <n>` in the scenario or `--limit {key}=<n>`",
            self.what,
            crate::text::show(self.requested),
            crate::text::show(self.allowed),
        )
    }
}

impl std::error::Error for LimitError {}

/// The names of the limits, in [`Limits`] order.
pub const KEYS: [&str; 7] = [
    "max_steps",
    "max_samples",
    "max_output_bytes",
    "max_flights",
    "max_sweep_points",
    "max_threads",
    "max_scenario_bytes",
];

impl Limits {
    /// The limits with their keys, in [`KEYS`] order.
    pub fn named(&self) -> [(&'static str, f64); 7] {
        [
            ("max_steps", self.max_steps),
            ("max_samples", self.max_samples),
            ("max_output_bytes", self.max_output_bytes),
            ("max_flights", self.max_flights),
            ("max_sweep_points", self.max_sweep_points),
            ("max_threads", self.max_threads),
            ("max_scenario_bytes", self.max_scenario_bytes),
        ]
    }

    fn slot(&mut self, key: &str) -> Option<&mut f64> {
        Some(match key {
            "max_steps" => &mut self.max_steps,
            "max_samples" => &mut self.max_samples,
            "max_output_bytes" => &mut self.max_output_bytes,
            "max_flights" => &mut self.max_flights,
            "max_sweep_points" => &mut self.max_sweep_points,
            "max_threads" => &mut self.max_threads,
            "max_scenario_bytes" => &mut self.max_scenario_bytes,
            _ => return None,
        })
    }

    /// Every limit is a number > 0 (infinity allowed: no limit);
    /// `Err((key, value))` names the first that is not.
    pub fn check(&self) -> Result<(), (&'static str, f64)> {
        for (key, v) in self.named() {
            if v.is_nan() || v <= 0.0 {
                return Err((key, v));
            }
        }
        Ok(())
    }

    /// Apply command-line overrides `KEY=VALUE` (e.g. `max_steps=1e10`).
    pub fn apply_overrides(&mut self, overrides: &[String]) -> Result<(), String> {
        for item in overrides {
            let Some((key, value)) = item.split_once('=') else {
                return Err(format!("--limit {}: expected KEY=VALUE, e.g. max_steps=1e10", abbreviate(item)));
            };
            let key = key.trim();
            let value: f64 = value.trim().parse().map_err(|_| {
                format!("--limit {}: the value is not a number (e.g. max_steps=1e10)", abbreviate(item))
            })?;
            if value.is_nan() || value <= 0.0 {
                return Err(format!("--limit {}: the value must be > 0", abbreviate(item)));
            }
            let slot = self
                .slot(key)
                .ok_or_else(|| format!("--limit {}: unknown limit (known: {})", abbreviate(item), KEYS.join(", ")))?;
            *slot = value;
        }
        Ok(())
    }

    /// `Err` when `requested > limit` (or is NaN).
    pub fn ensure(&self, key: &'static str, what: impl Into<String>, requested: f64) -> Result<(), LimitError> {
        let allowed = self.named().into_iter().find(|(k, _)| *k == key).map_or(0.0, |(_, v)| v);
        // NaN is refused too: it is not `<=` anything.
        if requested.partial_cmp(&allowed).is_none_or(|o| o == core::cmp::Ordering::Greater) {
            return Err(LimitError { key, what: what.into(), requested, allowed, hard: None });
        }
        let (bound, why) = hard_bound(key);
        if requested <= bound {
            Ok(())
        } else {
            Err(LimitError { key, what: what.into(), requested, allowed: bound, hard: Some(why) })
        }
    }
}

fn abbreviate(s: &str) -> String {
    crate::text::show_str(s)
}

/// Widest row of a recording (`run::Recording`): every column of `run::recording_columns`
/// with all estimate slots named and the mass adaptation on.
pub const MAX_RECORDING_COLUMNS: usize = 1 + 12 + 3 + 3 + 2 + 4 + 4 + 4 + 1 + 6 + 6 * MAX_ESTIMATES + 2 + 4 + 6;

/// What a flight's cost depends on: the sizes a scenario declares
/// (built by `Scenario::flight_size`) and the limits it is checked against.
#[derive(Clone, Copy, Debug)]
pub struct FlightSize<'a> {
    /// Flight duration, s.
    pub duration: f64,
    /// Control rate, Hz.
    pub control_rate: f64,
    /// RK4 substeps per control period.
    pub substeps: u32,
    /// Recording rate, Hz (0 = off).
    pub record_rate: f64,
    /// Work of evaluating every signal of the scenario once (references,
    /// disturbances, inertia variation), in term evaluations
    /// ([`crate::signal::Signal::evaluation_cost`]).
    pub signal_cost: f64,
    /// The limits to check against.
    pub limits: &'a Limits,
}

/// The priced cost of flying a scenario once with each of `n` controllers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cost {
    /// Control periods per flight (`round(duration × control_rate)`).
    pub control_steps: f64,
    /// RK4 steps per flight (`control_steps × substeps`).
    pub integration_steps: f64,
    /// Recorded rows per flight (0 when `record_rate = 0`).
    pub samples: f64,
    /// Estimated CSV bytes of all `n` recordings.
    pub output_bytes: f64,
}

/// Price one flight of `scenario` (recording on) with each of `n_controllers`
/// controllers and compare with its [`Limits`]. The same arithmetic as the
/// run loop (`run/mod.rs`), in `f64` so it cannot overflow.
pub fn check_flight(scenario: &FlightSize<'_>, n_controllers: usize) -> Result<Cost, LimitError> {
    let sim = scenario;
    let limits = scenario.limits;
    let control_steps = (scenario.duration * sim.control_rate).round();
    let integration_steps = control_steps * f64::from(sim.substeps);
    limits.ensure(
        "max_steps",
        "integration steps per flight (duration × control_rate × substeps)",
        integration_steps,
    )?;
    // Signal terms are evaluated every step: a file of thousands of terms
    // costs like that many times more steps.
    let weighted = integration_steps * (1.0 + sim.signal_cost / TERMS_PER_STEP);
    limits.ensure(
        "max_steps",
        format!(
            "integration steps per flight weighted by the signal terms (steps × (1 + {} terms / {TERMS_PER_STEP}))",
            crate::text::show(sim.signal_cost)
        ),
        weighted,
    )?;
    let samples = if sim.record_rate > 0.0 {
        let every = (sim.control_rate / sim.record_rate).round().max(1.0);
        (control_steps / every).floor() + 1.0
    } else {
        0.0
    };
    limits.ensure("max_samples", "recorded rows per flight (duration × record_rate)", samples)?;
    let columns = MAX_RECORDING_COLUMNS as f64;
    let output_bytes = samples * columns * BYTES_PER_VALUE * n_controllers.max(1) as f64;
    limits.ensure(
        "max_output_bytes",
        format!(
            "estimated time-series output in bytes (rows × {columns} columns × {BYTES_PER_VALUE} bytes × \
             {n_controllers} controllers)"
        ),
        output_bytes,
    )?;
    Ok(Cost { control_steps, integration_steps, samples, output_bytes })
}

/// Price a Monte Carlo batch of `runs` runs × `n_controllers` controllers
/// (flights are not recorded, so only the step count per flight counts
/// besides the number of flights and the size of `runs.csv`).
pub fn check_batch(scenario: &FlightSize<'_>, runs: u64, n_controllers: usize) -> Result<(), LimitError> {
    let limits = scenario.limits;
    let flights = runs as f64 * n_controllers as f64;
    limits.ensure("max_flights", "flights in the batch (--runs × controllers)", flights)?;
    limits.ensure(
        "max_output_bytes",
        format!("estimated runs.csv size in bytes (flights × {MONTE_CARLO_COLUMNS} columns × {BYTES_PER_VALUE} bytes)"),
        flights * MONTE_CARLO_COLUMNS * BYTES_PER_VALUE,
    )?;
    let sim = scenario;
    let steps = (scenario.duration * sim.control_rate).round() * f64::from(sim.substeps);
    limits.ensure("max_steps", "integration steps per flight (duration × control_rate × substeps)", steps)?;
    limits.ensure(
        "max_steps",
        format!(
            "integration steps per flight weighted by the signal terms (steps × (1 + {} terms / {TERMS_PER_STEP}))",
            crate::text::show(sim.signal_cost)
        ),
        steps * (1.0 + sim.signal_cost / TERMS_PER_STEP),
    )
}

/// Memory one Gymnasium environment holds (its flight lane: vehicle,
/// controller, sensors, wind filters, observation), bytes: an upper estimate.
pub const BYTES_PER_ENV: f64 = 64.0 * 1024.0;

/// Price `num_envs` Gymnasium environments flown side by side: as flights
/// against `max_flights`, and their memory ([`BYTES_PER_ENV`] each) against
/// the machine's ([`memory_bytes`]) whatever the limits.
pub fn check_envs(limits: &Limits, num_envs: f64) -> Result<(), LimitError> {
    let what = "environments flown side by side (num_envs)";
    limits.ensure("max_flights", what, num_envs)?;
    let fits = memory_bytes() / BYTES_PER_ENV;
    if num_envs <= fits {
        Ok(())
    } else {
        Err(LimitError {
            key: "max_flights",
            what: what.to_string(),
            requested: num_envs,
            allowed: fits.floor(),
            hard: Some("64 KiB each in this machine's memory"),
        })
    }
}

/// Number of magnitudes of a fixed-time sweep over `decades` decades with
/// `per_decade` points each (`decades × per_decade + 1`), in `f64`.
pub fn sweep_points(decades: u32, per_decade: u64) -> f64 {
    f64::from(decades) * per_decade as f64 + 1.0
}

/// Refuse a fixed-time sweep of more than `max_sweep_points` magnitudes.
pub fn check_sweep(limits: &Limits, points: f64) -> Result<(), LimitError> {
    limits.ensure("max_sweep_points", "fixed-time sweep magnitudes (5 decades × --per-decade + 1)", points)
}

/// Refuse more than `max_threads` worker threads.
pub fn check_threads(limits: &Limits, threads: usize) -> Result<(), LimitError> {
    limits.ensure("max_threads", "worker threads (--threads)", threads as f64)
}

/// Refuse a scenario file larger than `max_scenario_bytes`.
pub fn check_file_size(limits: &Limits, bytes: u64) -> Result<(), LimitError> {
    limits.ensure("max_scenario_bytes", "scenario file size in bytes", bytes as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overrides_parse_and_reject_nonsense() {
        let mut l = Limits::default();
        l.apply_overrides(&["max_steps=1e10".into(), " max_threads = 8 ".into()]).unwrap();
        assert_eq!((l.max_steps, l.max_threads), (1e10, 8.0));
        assert!(l.apply_overrides(&["max_steps".into()]).is_err());
        assert!(l.apply_overrides(&["max_stepz=1".into()]).is_err());
        assert!(l.apply_overrides(&["max_steps=-1".into()]).is_err());
        assert!(l.apply_overrides(&["max_steps=nan".into()]).is_err());
        assert!(l.apply_overrides(&["max_steps=inf".into()]).is_ok());
    }

    #[test]
    fn errors_name_the_limit_and_how_to_raise_it() {
        let e = Limits::default().ensure("max_steps", "steps", 1e300).unwrap_err().to_string();
        assert!(e.contains("max_steps = 2e8") && e.contains("1e300") && e.contains("--limit max_steps="), "{e}");
        assert!(check_threads(&Limits::default(), 1_000_000).is_err());
        assert!(check_sweep(&Limits::default(), sweep_points(5, u64::MAX)).is_err());
        assert!(check_sweep(&Limits::default(), sweep_points(5, 3)).is_ok());
    }
}
