//! `ftsmc tune --mission`: the tuned file states the mission it was tuned
//! for (`[tune] mission`, read back), a tune for `steps` writes the file a
//! tune without a mission writes, and a wrong mission name is refused.

use ftsmc_sim::analysis::missions::Mission;
use ftsmc_sim::scenario::tune_section::{TuneSection, MISSIONS};
use ftsmc_sim::tune::{mission_base, tune, tuned_toml, TuneOptions};
use ftsmc_sim::Scenario;

/// Two training flights per candidate, three held-out, a population of 4:
/// the start and two generations (a few seconds in a debug build).
const TINY_BUDGET: u64 = 2 * (1 + 4 + 4);

/// A short realistic scenario with the tiny `[tune]` settings.
fn base() -> Scenario {
    let mut s =
        Scenario::from_toml_str(ftsmc_sim::scenario::REALISTIC_SCENARIO_2, "realistic-scenario-2.toml").unwrap();
    s.duration = 6.0;
    s.tune = Some(TuneSection { runs: 2, validation_runs: 3, population: Some(4), race: 0, ..TuneSection::default() });
    s
}

fn tuned_text(s: &Scenario) -> String {
    let options = TuneOptions { controller: "pid".into(), budget: TINY_BUDGET, seed: 7 };
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
    let r = pool.install(|| tune(s, &options, &|_| {})).unwrap();
    tuned_toml(&r, Some("realistic-scenario-2"), "test").unwrap()
}

#[test]
fn the_mission_names_of_tune_section_are_the_missions() {
    assert_eq!(MISSIONS, Mission::ALL.map(Mission::name));
}

#[test]
fn a_tune_for_steps_writes_the_file_of_a_tune_without_a_mission() {
    let s = base();
    let steps = mission_base(&s, Mission::Steps).unwrap();
    assert_eq!(steps, s, "steps is the scenario itself");
    let plain = tuned_text(&s);
    assert_eq!(tuned_text(&steps), plain);
    assert!(!plain.contains("mission"), "no mission key without a mission:\n{plain}");
}

#[test]
fn the_tuned_file_states_its_mission_and_reads_it_back() {
    let s = base();
    let hover = mission_base(&s, Mission::Hover).unwrap();
    assert_eq!(hover.name, "realistic-scenario-2-hover");
    assert_eq!(hover.tune.as_ref().and_then(|t| t.mission.as_deref()), Some("hover"));
    let text = tuned_text(&hover);
    assert!(text.contains("mission = \"hover\""), "{text}");
    let tmp = tempfile::Builder::new().prefix("ftsmc-tune-mission-").tempdir().unwrap();
    std::fs::write(tmp.path().join("tuned.toml"), &text).unwrap();
    let back = Scenario::from_file(&tmp.path().join("tuned.toml")).unwrap_or_else(|e| panic!("{e}\n{text}"));
    assert_eq!(back.tune.as_ref().and_then(|t| t.mission.as_deref()), Some("hover"), "{text}");
    // It flies the mission it was tuned for: the hover's reference, not the steps.
    assert_eq!(back.reference, hover.reference, "{text}");
    assert_ne!(back.reference, s.reference);
}

#[test]
fn a_wrong_mission_in_a_file_is_refused_with_its_name_and_the_names() {
    let text = format!("{}\n[tune]\nmission = \"eight\"\n", ftsmc_sim::scenario::REALISTIC_SCENARIO_2);
    let e = Scenario::from_toml_str(&text, "bad.toml").unwrap_err();
    let m = format!("{e:#}");
    let chain = {
        let mut out = m.clone();
        let mut src = std::error::Error::source(&e);
        while let Some(s) = src {
            out.push_str(&format!(": {s}"));
            src = s.source();
        }
        out
    };
    assert!(chain.contains("mission `eight`") && chain.contains("steps, hover, figure-eight, waypoints"), "{chain}");
}
