//! The telemetry split: PID and SE(3) report no sliding-mode part, so their
//! recordings carry no `s_<axis>` (nor `alpha_hat`) columns, while the
//! paper's cascade reports its sliding variables as before; the columns of
//! the two kinds differ by exactly the six `s_<axis>` (and the mass
//! adaptation's two), the rest being the same names in the same order.

use ftsmc_sim::registry;
use ftsmc_sim::run::RunOptions;
use ftsmc_sim::scenario::Scenario;

fn short_scenario_2() -> Scenario {
    let mut s = Scenario::paper_scenarios().remove(1);
    s.duration = 0.5;
    s
}

#[test]
fn pid_and_se3_record_no_sliding_columns_and_the_cascade_does() {
    let s = short_scenario_2();
    let names = |c: &str| registry::run(c, &s, RunOptions::default()).unwrap().recording.names;
    let sliding = |n: &String| n.starts_with("s_");
    let cascade = names("tsm-sta");
    assert_eq!(cascade.iter().filter(|n| sliding(n)).count(), 6);
    for c in ["pid", "se3"] {
        let full = names(c);
        assert!(!full.iter().any(|n| sliding(n) || n == "alpha_hat"), "{c}: {full:?}");
        // The same columns as the cascade's apart from the sliding variables
        // and the channel laws' own estimates.
        let common = |v: &Vec<String>| -> Vec<String> {
            v.iter().filter(|n| !sliding(n) && !n.starts_with("nu_") && !n.starts_with("integral_")).cloned().collect()
        };
        assert_eq!(common(&full), common(&cascade), "{c}");
    }
}

#[test]
fn the_cascade_reports_its_sliding_part_and_pid_none() {
    let s = short_scenario_2();
    let ft = registry::run("ftaftsmc", &s, RunOptions::default()).unwrap().recording;
    // α̂ is recorded from the sliding-mode part and moves under payload.
    assert!(ft.column("s_z").iter().any(|v| *v != 0.0));
    assert!(ft.column("alpha_hat").iter().all(|a| a.is_finite()));
    assert_eq!(registry::build("pid", &s).unwrap().telemetry().sliding_mode, None);
    assert_eq!(registry::build("se3", &s).unwrap().telemetry().sliding_mode, None);
    assert!(registry::build("ftaftsmc", &s).unwrap().telemetry().sliding_mode.is_some());
}
