//! Monte Carlo batches: deterministic across thread counts; divergence is a row.

use ftsmc_sim::batch::montecarlo::{run_batch, BatchOptions, Dist, MonteCarloSpec};
use ftsmc_sim::scenario::{Scenario, PAPER_SCENARIO_2};

fn short_scenario() -> Scenario {
    let mut s = Scenario::from_toml_str(PAPER_SCENARIO_2, "paper-scenario-2.toml").unwrap();
    s.duration = 12.0;
    s
}

fn batch(threads: usize, spec: &MonteCarloSpec, s: &Scenario) -> Vec<String> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    let controllers = vec!["ftaftsmc".to_string(), "ranftsmc".to_string()];
    let rows = pool.install(|| run_batch(s, spec, &controllers, BatchOptions::new(6, 42))).unwrap();
    rows.iter()
        .map(|r| format!("{} {} {} {:?} {:?} {}", r.index, r.seed, r.controller, r.sampled, r.metrics.flat(), r.exit))
        .collect()
}

#[test]
fn batch_is_identical_with_one_and_two_threads() {
    let s = short_scenario();
    let spec = s.montecarlo.clone().expect("paper scenario 2 ships a [montecarlo] section");
    let one = batch(1, &spec, &s);
    let two = batch(2, &spec, &s);
    assert_eq!(one.len(), 12);
    assert_eq!(one, two);
    // Runs really are randomised.
    assert_ne!(one[0].split(' ').nth(3), one[2].split(' ').nth(3));
}

#[test]
fn a_diverging_run_is_reported_not_fatal() {
    let s = short_scenario();
    // Disturbance amplitudes from ×1 up to ×400: the large ones cannot be flown.
    let spec = MonteCarloSpec {
        disturbance_amplitude: Some(Dist::Uniform { low: 1.0, high: 400.0 }),
        ..MonteCarloSpec::default()
    };
    let controllers = vec!["ftaftsmc".to_string()];
    let rows = run_batch(&s, &spec, &controllers, BatchOptions::new(8, 3)).unwrap();
    assert_eq!(rows.len(), 8, "every run is a row");
    let diverged = rows.iter().filter(|r| !r.exit.is_completed()).count();
    assert!(diverged >= 1, "the batch must contain a diverged run");
    for r in rows.iter().filter(|r| !r.exit.is_completed()) {
        assert!(r.exit.to_string().starts_with("diverged"), "{}", r.exit);
        assert!(r.metrics.duration < s.duration);
    }
}
