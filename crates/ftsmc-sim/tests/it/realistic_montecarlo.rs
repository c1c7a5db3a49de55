//! The Monte Carlo of realistic scenario 2 (its `[montecarlo]`
//! section: per-run turbulence, sensor and motor noise, payload,
//! disturbance amplitude and phase, initial attitude) completes, and every
//! run is counted as exactly one of success, envelope failure, divergence
//! or crash.
//!
//! Runtime (test profile, 2 shared cores): FTAFTSMC flies 300 runs (with
//! its printed gains it tips over within about 3 s, so each run is short);
//! RANFTSMC and TSM-STA, which fly much longer, 100 each. (It flew 1000
//! and 200 each, the slowest test of CI at 59 s; the counts it checks add
//! up or not whatever the number of runs.)

use ftsmc_sim::batch::montecarlo::{run_batch, summarize, BatchOptions, ControllerSummary, McRun};
use ftsmc_sim::scenario::{Scenario, REALISTIC_SCENARIO_2};

fn scenario() -> Scenario {
    Scenario::from_toml_str(REALISTIC_SCENARIO_2, "realistic-scenario-2.toml").unwrap()
}

fn batch(s: &Scenario, controller: &str, runs: u64) -> Vec<McRun> {
    let spec = s.montecarlo.clone().expect("realistic scenario 2 has a [montecarlo] section");
    run_batch(s, &spec, &[controller.to_string()], BatchOptions::new(runs, s.seed)).unwrap()
}

/// The summary's counts add up to the runs, and agree with the rows.
fn check_counts(rows: &[McRun], sm: &ControllerSummary, runs: u64) {
    let successes = rows.iter().filter(|r| r.success).count();
    let crashed = rows.iter().filter(|r| r.exit.is_crashed()).count();
    let diverged = rows.iter().filter(|r| r.exit.diverged_at().is_some()).count();
    let envelope = rows.iter().filter(|r| r.exit.is_completed() && !r.success).count();
    assert_eq!(rows.len() as u64, runs);
    assert_eq!(sm.runs as u64, runs);
    assert_eq!((sm.crashed, sm.diverged, sm.envelope_failures), (crashed, diverged, envelope));
    assert_eq!(successes + sm.envelope_failures + sm.diverged + sm.crashed, sm.runs, "{sm:?}");
    assert_eq!(sm.success_rate, successes as f64 / runs as f64);
    // A success is a completed run inside the envelope: never a crashed or diverged one.
    assert!(rows.iter().filter(|r| r.success).all(|r| r.exit.is_completed()));
    // The runs differ (own seeds): not every row has the same exit.
    let first = rows[0].exit.to_string();
    assert!(rows.iter().any(|r| r.exit.to_string() != first), "all {runs} runs ended alike: {first}");
}

#[test]
fn monte_carlo_of_realistic_scenario_2_counts_every_run() {
    let s = scenario();
    for (controller, runs) in [("ftaftsmc", 300), ("ranftsmc", 100), ("tsm-sta", 100)] {
        let rows = batch(&s, controller, runs);
        let summary = summarize(&rows, &[controller.to_string()]);
        let (_, sm) = &summary[0];
        check_counts(&rows, sm, runs);
        println!(
            "{controller}: {runs} runs, success {} ({:.1} %), envelope failures {}, diverged {}, crashed {}",
            (sm.success_rate * runs as f64).round(),
            100.0 * sm.success_rate,
            sm.envelope_failures,
            sm.diverged,
            sm.crashed
        );
    }
}

#[test]
fn realistic_monte_carlo_rates_do_not_depend_on_the_thread_count() {
    let s = scenario();
    let spec = s.montecarlo.clone().unwrap();
    let controllers: Vec<String> = ["ranftsmc", "tsm-sta", "ftaftsmc"].map(String::from).to_vec();
    let fly = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        let rows = pool.install(|| run_batch(&s, &spec, &controllers, BatchOptions::new(6, s.seed))).unwrap();
        let lines: Vec<String> = rows
            .iter()
            .map(|r| format!("{} {} {} {} {:?}", r.index, r.controller, r.exit, r.success, r.metrics.flat()))
            .collect();
        (lines, summarize(&rows, &controllers))
    };
    let (one, one_summary) = fly(1);
    let (two, two_summary) = fly(2);
    assert_eq!(one.len(), 18);
    assert_eq!(one, two);
    assert_eq!(one_summary, two_summary);
}

/// The draws of true mass, inertia and drag reach the rigid body the
/// scenario's `[vehicle]` describes (the truth model).
#[test]
fn mass_inertia_and_drag_draws_reach_the_rigid_body() {
    let s = scenario();
    assert!(s.vehicle.parasitic_drag.is_some(), "realistic scenario 2 names its rigid body's aerodynamics");
    let base = s.rigid_body_params();
    let spec = s.montecarlo.clone().unwrap();
    let (flown, _, sampled) = spec.sample(&s, s.seed, 3);
    let rb = flown.rigid_body_params();
    let (mass, inertia_factor, drag_factor) = (sampled[0], sampled[2], sampled[3]);
    assert_ne!(mass, base.mass, "the draw must differ from the nominal mass");
    assert_eq!(rb.mass, mass);
    assert_ne!(inertia_factor, 1.0);
    for (row, base_row) in rb.inertia.iter().zip(&base.inertia) {
        for (j, b) in row.iter().zip(base_row) {
            assert_eq!(*j, b * inertia_factor);
        }
    }
    assert_ne!(drag_factor, 1.0);
    assert_eq!(rb.rotor_drag_z, base.rotor_drag_z * drag_factor);
    assert_eq!(rb.parasitic_drag[0], base.parasitic_drag[0] * drag_factor);
    // The controllers keep their nominal model.
    assert_eq!(flown.plant, s.plant);
}
