//! The robustness margin (`ftsmc_sim::margin`): negative exactly when a
//! completed flight fails its envelope, below −1 for a crash or a
//! divergence, and in `runs.csv`.

use ftsmc_sim::batch::montecarlo::{run_batch, BatchOptions};
use ftsmc_sim::batch::runs_table::{runs_table, MARGIN_COLUMNS};
use ftsmc_sim::margin::Binding;
use ftsmc_sim::registry;
use ftsmc_sim::scenario::Scenario;
use ftsmc_sim::RunOptions;

fn scenario(extra: &str) -> Scenario {
    let text = format!("extends = \"paper-scenario-1\"\nname = \"t\"\nduration = 3.0\n{extra}");
    Scenario::from_toml_str(&text, "test.toml").unwrap_or_else(|e| panic!("{e}"))
}

/// Limits on both sides of what the flights reach: every completed flight
/// has `margin < 0` exactly when it fails, and the binding constraint is
/// the one the envelope's verdict names.
#[test]
fn margin_is_negative_exactly_when_a_completed_flight_fails_its_envelope() {
    let mut seen = [0usize; 2];
    for (settle, pos) in [(0.5, 0.05), (0.5, 0.3), (1.5, 0.05), (1.5, 0.3), (2.0, 2.0)] {
        for tilt in [0.02, 0.1, 0.6] {
            let s = scenario(&format!(
                "[envelope]\nsettle_after = {settle}\nmax_position_error = {pos}\nmax_tilt = {tilt}\n"
            ));
            for c in ["ftaftsmc", "pid"] {
                let out = registry::run(c, &s, RunOptions::default()).unwrap();
                assert!(out.exit.is_completed());
                let m = out.margin.expect("an envelope with limits gives a margin");
                assert_eq!(m.value < 0.0, !out.success(), "{c} settle {settle} pos {pos} tilt {tilt}: {m:?}");
                seen[usize::from(out.success())] += 1;
                let why = out.envelope.as_ref().unwrap().violation.clone().unwrap_or_default();
                if m.value < 0.0 {
                    // The most violated constraint (relative to its limit) is one that is broken.
                    let broken = match m.binds {
                        Binding::Position => why.contains("position") || m.position.unwrap() < 0.0,
                        Binding::Tilt => m.tilt.unwrap() < 0.0,
                        _ => false,
                    };
                    assert!(broken, "{m:?} {why}");
                }
                let expect = (m.position.unwrap() / pos).min(m.tilt.unwrap() / tilt);
                assert_eq!(m.value, expect);
            }
        }
    }
    assert!(seen[0] > 0 && seen[1] > 0, "both outcomes exercised: {seen:?}");
}

#[test]
fn a_crash_or_divergence_is_below_minus_one_and_earlier_is_lower() {
    // A tilt bound of the divergence checks the step response breaks.
    let early = scenario("[simulation]\nmax_tilt = 0.05\n[envelope]\nmax_position_error = 5.0\n");
    let out = registry::run("ftaftsmc", &early, RunOptions::default()).unwrap();
    assert!(!out.exit.is_completed(), "{:?}", out.exit);
    let m = out.margin.unwrap();
    assert_eq!(m.binds, Binding::Diverged);
    assert!(m.value <= -1.0 && m.value >= -2.0, "{m:?}");
    assert_eq!(m.at, out.exit.diverged_at().unwrap());
    // Without an envelope a completed flight has no margin, a failed one has.
    let plain = scenario("");
    assert!(registry::run("ftaftsmc", &plain, RunOptions::default()).unwrap().margin.is_none());
    let early_plain = scenario("[simulation]\nmax_tilt = 0.05\n");
    assert!(registry::run("ftaftsmc", &early_plain, RunOptions::default()).unwrap().margin.unwrap().value <= -1.0);
}

#[test]
fn runs_csv_has_the_margin_after_the_existing_columns() {
    let s = scenario("[envelope]\nsettle_after = 1.0\nmax_position_error = 0.1\n[montecarlo]\ninitial_position_offset = { dist = \"uniform\", low = -0.5, high = 0.5 }\n");
    let rows = run_batch(&s, s.montecarlo.as_ref().unwrap(), &["pid".to_string()], BatchOptions::new(4, 7)).unwrap();
    let table = runs_table(&rows);
    let at = table.names.iter().position(|n| n == "crashed").unwrap();
    assert_eq!(&table.names[at + 1..], &MARGIN_COLUMNS.map(String::from));
    for (i, r) in rows.iter().enumerate() {
        let cells = table.record(i);
        let margin: f64 = cells[at + 1].parse().unwrap();
        assert_eq!(margin < 0.0, !r.success);
        assert_eq!(cells[at + 5], "position");
    }
}
