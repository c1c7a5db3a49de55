//! `max_tilt` names one thing: a limit on the flown tilt (`[simulation]`:
//! the flight stops as diverged; `[envelope]`: the flight fails). The
//! controllers' limits on the tilt they demand are `max_demanded_tilt`
//! (`[cascade]`, `[pid]`, `[se3]`); their old `max_tilt` loads with a
//! warning naming the new key and flies the same bits. The measured peak is
//! `peak_tilt` (`FlightStats`, runs.csv).

use ftsmc_sim::registry;
use ftsmc_sim::scenario::resolve::Loaded;
use ftsmc_sim::scenario::Scenario;
use ftsmc_sim::RunOptions;

fn load(body: &str) -> Result<Loaded, String> {
    let text = format!("extends = \"paper-scenario-1\"\nname = \"t\"\nduration = 2.0\n{body}");
    Scenario::from_toml_str_with_warnings(&text, "t.toml", &[]).map_err(|e| e.to_string())
}

fn bits(s: &Scenario, controller: &str) -> (Vec<u64>, String, u64) {
    let out = registry::run(controller, s, RunOptions { record: true, ..Default::default() }).unwrap();
    let bits = out.recording.columns.iter().flatten().map(|v| v.to_bits()).collect();
    (bits, out.exit.to_string(), out.stats.peak_tilt.to_bits())
}

#[test]
fn the_controllers_old_max_tilt_loads_with_a_warning_and_flies_like_max_demanded_tilt() {
    for (section, controller) in [("cascade", "ftaftsmc"), ("pid", "pid"), ("se3", "se3")] {
        let old = load(&format!("[{section}]\nmax_tilt = 0.3\n")).unwrap_or_else(|e| panic!("{e}"));
        let w: Vec<_> = old.warnings.iter().filter(|w| w.contains("deprecated")).collect();
        assert!(
            w.len() == 1
                && w[0].contains("t.toml")
                && w[0].contains(&format!("`{section}.max_tilt`"))
                && w[0].contains(&format!("[{section}] max_demanded_tilt = 0.3")),
            "{section}: {w:?}"
        );
        let new = load(&format!("[{section}]\nmax_demanded_tilt = 0.3\n")).unwrap();
        assert!(new.warnings.iter().all(|w| !w.contains("deprecated")), "{:?}", new.warnings);
        assert_eq!(old.scenario, new.scenario, "{section}");
        // The key acts: a different demand limit flies differently.
        let default = load("").unwrap();
        assert_ne!(default.scenario, new.scenario, "{section}");
        assert_eq!(bits(&old.scenario, controller), bits(&new.scenario, controller), "{section}");
        // Written back in the new spelling only.
        let text = new.scenario.to_toml().unwrap();
        assert!(text.contains("max_demanded_tilt = 0.3"), "{section}");
    }
}

#[test]
fn old_and_new_tilt_names_together_are_refused_naming_both() {
    for section in ["cascade", "pid", "se3"] {
        let e = load(&format!("[{section}]\nmax_tilt = 0.3\nmax_demanded_tilt = 0.4\n")).unwrap_err();
        assert!(
            e.contains("t.toml")
                && e.contains(&format!("{section}.max_tilt"))
                && e.contains(&format!("{section}.max_demanded_tilt")),
            "{e}"
        );
    }
}

#[test]
fn the_limits_on_the_flown_tilt_keep_their_name_without_a_warning() {
    let l = load("[simulation]\nmax_tilt = 1.2\n[envelope]\nmax_tilt = 0.5\n").unwrap();
    assert!(l.warnings.is_empty(), "{:?}", l.warnings);
    assert_eq!(l.scenario.simulation.max_tilt, 1.2);
    assert_eq!(l.scenario.envelope.unwrap().max_tilt, Some(0.5));
    // The measured peak is below the divergence limit of a completed flight.
    let out = registry::run("ftaftsmc", &l.scenario, RunOptions::default()).unwrap();
    assert!(out.exit.is_completed() && out.stats.peak_tilt > 0.0 && out.stats.peak_tilt < 1.2);
}

/// The old and the new name are one key across an `extends` chain: the
/// file nearer the scenario wins, as for any key.
#[test]
fn across_an_extends_chain_the_nearer_file_wins() {
    let tmp = tempfile::Builder::new().prefix("ftsmc-tilt-names-").tempdir().unwrap();
    let dir = tmp.path();
    std::fs::write(dir.join("base.toml"), "extends = \"paper-scenario-1\"\nname = \"b\"\n[cascade]\nmax_tilt = 0.3\n")
        .unwrap();
    std::fs::write(dir.join("top.toml"), "extends = \"base.toml\"\nname = \"t\"\n[cascade]\nmax_demanded_tilt = 0.4\n")
        .unwrap();
    let top = Scenario::load_with_warnings(&dir.join("top.toml"), &[]).unwrap();
    let base = Scenario::load_with_warnings(&dir.join("base.toml"), &[]).unwrap();
    assert_eq!(top.scenario.cascade.max_tilt, 0.4);
    assert!(
        top.warnings.iter().any(|w| w.contains("base.toml") && w.contains("cascade.max_tilt")),
        "{:?}",
        top.warnings
    );
    // The old name over a base that writes the new one (paper-scenario-1 does).
    assert_eq!(base.scenario.cascade.max_tilt, 0.3);
}
