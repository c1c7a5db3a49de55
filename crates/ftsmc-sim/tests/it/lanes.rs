//! Flights in lanes: a Monte Carlo batch gives the same rows, bit for bit,
//! whatever number of flights it flies side by side, whatever lane a run
//! lands in, and whatever the thread count — for every built-in controller
//! on both truth models, and when lanes start new runs as flights end early.

use ftsmc_sim::batch::montecarlo::{run_batch, BatchOptions, MonteCarloSpec, LANE_COUNTS};
use ftsmc_sim::registry::CONTROLLERS;
use ftsmc_sim::scenario::{Scenario, PAPER_SCENARIO_1, PAPER_SCENARIO_2, REALISTIC_SCENARIO_2};

fn builtin(name: &str, duration: f64) -> Scenario {
    let text = match name {
        "paper-scenario-1" => PAPER_SCENARIO_1,
        "paper-scenario-2" => PAPER_SCENARIO_2,
        _ => REALISTIC_SCENARIO_2,
    };
    let mut s = Scenario::from_toml_str(text, &format!("{name}.toml")).expect("built-in scenario");
    s.duration = duration;
    s
}

/// The rows of a batch as text: `{:?}` of an `f64` is its shortest
/// round-trip form, so equal text is equal bits.
fn rows(
    s: &Scenario,
    spec: &MonteCarloSpec,
    controllers: &[String],
    runs: u64,
    lanes: usize,
    threads: usize,
) -> Vec<String> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    let rows = pool
        .install(|| run_batch(s, spec, controllers, BatchOptions { lanes, ..BatchOptions::new(runs, s.seed) }))
        .expect("batch flies");
    rows.iter()
        .map(|r| {
            format!(
                "{} {} {} {:?} {:?} {} {:?}",
                if r.exit.is_completed() { "completed" } else { "ended-early" },
                r.index,
                r.controller,
                r.sampled,
                r.metrics.flat(),
                r.exit,
                (r.stats.peak_tilt, r.stats.rotor_speed_max, r.stats.saturated_periods)
            )
        })
        .collect()
}

#[test]
fn every_controller_gives_the_same_rows_on_any_number_of_lanes() {
    let controllers: Vec<String> = CONTROLLERS.iter().map(|(n, _)| n.to_string()).collect();
    for name in ["paper-scenario-2", "realistic-scenario-2"] {
        let s = builtin(name, 2.0);
        let spec = s.montecarlo.clone().unwrap_or_default();
        let alone = rows(&s, &spec, &controllers, 5, 1, 1);
        assert_eq!(alone.len(), 5 * controllers.len());
        for lanes in LANE_COUNTS.into_iter().filter(|&l| l > 1) {
            assert_eq!(rows(&s, &spec, &controllers, 5, lanes, 2), alone, "{name}, {lanes} lanes");
        }
    }
}

#[test]
fn lanes_start_new_runs_as_flights_end_early() {
    // FTAFTSMC with the paper's gains on the realistic rotors diverges, each
    // run at its own time, while PID completes: lanes empty at different
    // times and start the next runs.
    let s = builtin("realistic-scenario-2", 26.0);
    let spec = s.montecarlo.clone().unwrap_or_default();
    let controllers = vec!["ftaftsmc".to_string(), "pid".to_string()];
    let alone = rows(&s, &spec, &controllers, 7, 1, 1);
    let ended_early = alone.iter().filter(|r| r.starts_with("ended-early")).count();
    assert!(ended_early > 1 && ended_early < alone.len(), "{ended_early} of {} ended early", alone.len());
    for lanes in LANE_COUNTS.into_iter().filter(|&l| l > 1) {
        assert_eq!(rows(&s, &spec, &controllers, 7, lanes, 1), alone, "{lanes} lanes");
    }
}

#[test]
fn an_unknown_lane_count_is_refused() {
    let s = builtin("paper-scenario-1", 1.0);
    let err = run_batch(
        &s,
        &MonteCarloSpec::default(),
        &["pid".into()],
        BatchOptions { lanes: 3, ..BatchOptions::new(1, 1) },
    )
    .expect_err("3 lanes");
    assert!(err.contains("lanes = 3") && err.contains("[1, 4]"), "{err}");
}

#[test]
fn flights_stopped_at_a_tick_the_observers_do_not_see_give_the_same_rows_on_any_number_of_lanes() {
    // From 0.5 s the inertia variation takes the rigid body out of its
    // range: each flight stops at a tick the statistics do not observe,
    // which the rotor metrics (peak demand, saturation fraction) still count.
    let text = format!(
        "{REALISTIC_SCENARIO_2}\n[inertia_variation]\nwindow = [0.5, 1.0]\nterms = [{{ type = \"constant\", value = -2.0 }}]\n"
    );
    let mut s = Scenario::from_toml_str(&text, "stopped.toml").expect("scenario");
    s.duration = 2.0;
    let spec = s.montecarlo.clone().unwrap_or_default();
    let controllers = vec!["pid".to_string()];
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let batch = pool
        .install(|| run_batch(&s, &spec, &controllers, BatchOptions { lanes: 4, ..BatchOptions::new(5, s.seed) }))
        .expect("batch flies");
    for r in &batch {
        assert!(r.exit.to_string().contains("rigid body out of its valid range"), "{}", r.exit);
        let peak = r.metrics.peak_rotor_speed_demand.expect("realistic flights report it");
        assert!(peak >= r.stats.peak_rotor_speed_demand && peak > 0.0, "{peak} {:?}", r.stats);
    }
    let alone = rows(&s, &spec, &controllers, 5, 1, 1);
    for lanes in LANE_COUNTS.into_iter().filter(|&l| l > 1) {
        assert_eq!(rows(&s, &spec, &controllers, 5, lanes, 1), alone, "{lanes} lanes");
    }
}
