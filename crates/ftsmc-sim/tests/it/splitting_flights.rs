//! Adaptive multilevel splitting of real flights against plain Monte Carlo
//! of the same flights ([`SCENARIO`]: realistic-breeze-1 cut to 2 s, the
//! tilt limit 0.24 rad checked from 1 s, flown by PID; every random input
//! of the rung — Dryden turbulence, sensor noise, motor noise, the
//! `[montecarlo]` draws and the `[falsify]` parameters at their nominal law).
//!
//! The plain campaign's counts are committed in
//! `tests/data/splitting-breeze-1-short-plain.toml` with the command that
//! made them; [`the_committed_counts_are_these_flights`] (a default test)
//! flies the first [`CHECKED`] of its flights again and checks their count.
//! The slow measurements are `#[ignore]`d. `splitting_covers_plain` does
//! not pass today: its first seed gave 3.1e-4 (unreliable) against the
//! plain 5.5e-3 (docs/falsification.md says why).
//!
//! ```text
//! FTSMC_PLAIN_FLIGHTS=10000 nice -n 19 cargo test -p ftsmc-sim --test splitting_flights -- --ignored --nocapture plain_campaign
//! nice -n 19 cargo test -p ftsmc-sim --test splitting_flights -- --ignored --nocapture splitting_covers_plain
//! ```

use ftsmc_sim::falsify::splitting::{estimate, Settings, Splitting};
use ftsmc_sim::falsify::{FlightSplitting, Problem};
use rand::Rng;
use rayon::prelude::*;

/// The short breeze rung (its `[falsify]` box and `[montecarlo]` draws kept).
const SCENARIO: &str = "extends = \"realistic-breeze-1\"\nname = \"breeze-1-short\"\nduration = 2.0\n\
                        [envelope]\nsettle_after = 1.0\nmax_position_error = 10.0\nmax_tilt = 0.24\n";
/// Controller flown.
const CONTROLLER: &str = "pid";
/// Seed of the plain campaign's particle keys (stream 0).
const PLAIN_SEED: u64 = 2026;
/// Flights of the committed campaign the default test flies again.
const CHECKED: usize = 200;

fn problem() -> FlightSplitting {
    let base =
        ftsmc_sim::scenario::Scenario::from_toml_str(SCENARIO, "breeze-1-short.toml").unwrap_or_else(|e| panic!("{e}"));
    assert!(ftsmc_sim::falsify::noise_driven(&base));
    FlightSplitting { problem: Problem::new(&base, CONTROLLER).unwrap() }
}

/// The keys of the plain campaign's first `n` flights (each a fresh particle, [`Splitting::start`]).
fn plain_keys(n: usize) -> Vec<u64> {
    let mut rng = ftsmc_sim::rng::chacha_stream(PLAIN_SEED, 0);
    (0..n).map(|_| rng.next_u64()).collect()
}

/// Failing flights among the first `n` of the plain campaign.
fn plain_failures(problem: &FlightSplitting, n: usize) -> u64 {
    plain_keys(n).par_iter().filter(|&&k| problem.margin(&problem.start(k)) < 0.0).count() as u64
}

/// The committed counts: `(flights, failures, failures among the first CHECKED)`.
fn committed() -> (u64, u64, u64) {
    let text = include_str!("../data/splitting-breeze-1-short-plain.toml");
    let table: toml::Table = text.parse().unwrap();
    let get = |k: &str| table[k].as_integer().unwrap_or_else(|| panic!("{k}")) as u64;
    (get("flights"), get("failures"), get("failures_first_200"))
}

/// The committed campaign is these flights: its first [`CHECKED`] flights
/// flown again give the committed count, and the counts are consistent.
#[test]
fn the_committed_counts_are_these_flights() {
    let (flights, failures, first) = committed();
    assert!(flights >= 10_000 && failures <= flights && first <= failures);
    assert_eq!(plain_failures(&problem(), CHECKED), first, "the first {CHECKED} flights of the committed campaign");
}

/// The plain campaign (prints the data file's lines).
#[test]
#[ignore]
fn plain_campaign() {
    let n: usize = std::env::var("FTSMC_PLAIN_FLIGHTS").map_or(10_000, |v| v.parse().unwrap());
    let problem = problem();
    let started = std::time::Instant::now();
    let failures = plain_failures(&problem, n);
    let first = plain_failures(&problem, CHECKED);
    let i = ftsmc_sim::stats::rate::wilson(failures, n as u64, 0.95).unwrap();
    println!("flights = {n}\nfailures = {failures}\nfailures_first_200 = {first}");
    println!(
        "# p = {:.4e}, 95 % Wilson [{:.4e}, {:.4e}], {:.0} s",
        failures as f64 / n as f64,
        i.lo,
        i.hi,
        started.elapsed().as_secs_f64()
    );
}

/// Splitting over [`SEEDS`] seeds against the committed plain estimate:
/// the share of 95 % intervals holding it (at least 0.95 less three
/// binomial standard errors of 20 seeds, 0.80: the plain estimate has its
/// own error, so the coverage of it is somewhat below the nominal), and the
/// flights each needs for a 30 % relative error against plain Monte Carlo's
/// `(1 − p)/(p · 0.09)`.
#[test]
#[ignore]
fn splitting_covers_plain() {
    const SEEDS: u64 = 20;
    let (flights, failures, _) = committed();
    let p_plain = failures as f64 / flights as f64;
    let problem = problem();
    let settings = Settings::new(50, 10, 20_000, 0.95);
    let mut covered = 0;
    let mut spent = Vec::new();
    let mut needed = Vec::new();
    let mut means = Vec::new();
    for seed in 0..SEEDS {
        let started = std::time::Instant::now();
        let e = estimate(&problem, settings, 100 + seed).unwrap();
        let holds = e.lo <= p_plain && p_plain <= e.hi;
        covered += holds as u64;
        println!(
            "seed {}: p = {:.3e} [{:.3e}, {:.3e}] {} reliable {}, {} flights, {:.1} levels, {:.0} flights for 30 % ({:.0} s)",
            100 + seed, e.p, e.lo, e.hi, if holds { "holds" } else { "MISSES" }, e.reliable, e.flights, e.mean_levels,
            e.flights_for_cov(0.3), started.elapsed().as_secs_f64()
        );
        spent.push(e.flights as f64);
        needed.push(e.flights_for_cov(0.3));
        means.push(e.p);
    }
    let avg = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let mean = avg(&means);
    let sd = ftsmc_core::math::sqrt(means.iter().map(|p| (p - mean) * (p - mean)).sum::<f64>() / (SEEDS - 1) as f64);
    let plain_se = ftsmc_core::math::sqrt(p_plain * (1.0 - p_plain) / flights as f64);
    let z = (mean - p_plain) / ftsmc_core::math::sqrt(sd * sd / SEEDS as f64 + plain_se * plain_se);
    println!(
        "plain {failures}/{flights} = {p_plain:.4e}; splitting: coverage {covered}/{SEEDS}, mean of estimates {mean:.4e} (z = {z:.2} against plain), \
         mean flights {:.0}, flights for 30 % relative error {:.0}; plain Monte Carlo needs {:.0}",
        avg(&spent), avg(&needed), (1.0 - p_plain) / (p_plain * 0.09)
    );
    assert!(
        covered as f64 >= 0.95 * SEEDS as f64 - 3.0 * ftsmc_core::math::sqrt(0.95 * 0.05 * SEEDS as f64),
        "coverage {covered}/{SEEDS}"
    );
    assert!(z.abs() < 3.0, "mean of the splitting estimates {z:.2} standard errors from plain");
}
