//! Scenario files: the shipped ones load; bad ones fail with errors that
//! name the key and value, never a panic.

use ftsmc_sim::scenario::{Scenario, ScenarioError, PAPER_SCENARIO_1};

fn parse(text: &str) -> Result<Scenario, ScenarioError> {
    Scenario::from_toml_str(text, "bad.toml")
}

fn message(text: &str) -> String {
    let err = parse(text).expect_err("must be rejected");
    let msg = err.to_string();
    assert!(msg.starts_with("bad.toml"), "error must name the file: {msg}");
    msg
}

#[test]
fn shipped_files_match_the_built_in_copies_and_load() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios");
    for (file, text) in ftsmc_sim::scenario::BUILT_IN_SCENARIOS {
        let on_disk = std::fs::read_to_string(root.join(file)).unwrap();
        assert_eq!(on_disk, text, "{file} differs from the built-in copy");
        Scenario::from_toml_str(text, file).unwrap();
    }
    for entry in std::fs::read_dir(&root).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            Scenario::from_file(&path).unwrap_or_else(|e| panic!("{e}"));
        }
    }
}

#[test]
fn empty_file_names_the_missing_key() {
    let msg = message("");
    assert!(msg.contains("missing field `name`") || msg.contains("missing field `duration`"), "{msg}");
}

#[test]
fn unknown_key_is_rejected_with_its_name() {
    let text = PAPER_SCENARIO_1.replace("[plant]", "[plant]\nmas = 0.74");
    let msg = message(&text);
    assert!(msg.contains("unknown field `mas`"), "{msg}");
    let msg = message(&format!("{PAPER_SCENARIO_1}\n[ftaftsmc.mass_adaptation.extra]\n"));
    assert!(msg.contains("extra") || msg.contains("duplicate"), "{msg}");
}

#[test]
fn wrong_type_is_rejected_with_the_key() {
    let text = PAPER_SCENARIO_1.replace("duration = 20.0", "duration = \"long\"");
    let msg = message(&text);
    assert!(msg.contains("duration"), "{msg}");
}

#[test]
fn exponent_out_of_range_names_the_gain() {
    // First `p = 0.1` in the file belongs to [ftaftsmc.x].
    let text = PAPER_SCENARIO_1.replacen("p = 0.1", "p = 1.2", 1);
    match parse(&text).unwrap_err() {
        ScenarioError::Invalid { key, value, expected, .. } => {
            assert_eq!(key, "ftaftsmc.x.p");
            assert_eq!(value, "1.2");
            assert!(expected.contains("0 < p < 1"));
        }
        other => panic!("{other}"),
    }
}

#[test]
fn negative_mass_names_the_key() {
    let text = PAPER_SCENARIO_1.replace("mass = 0.74", "mass = -0.74");
    let msg = message(&text);
    assert!(msg.contains("`plant.mass` = -0.74"), "{msg}");
}

#[test]
fn non_positive_rates_and_unknown_controllers_are_rejected() {
    let msg = message(&PAPER_SCENARIO_1.replace("control_rate = 1000.0", "control_rate = 0.0"));
    assert!(msg.contains("simulation.control_rate"), "{msg}");
    let msg = message(&PAPER_SCENARIO_1.replace("\"tsm-sta\"", "\"pidd\""));
    assert!(msg.contains("unknown controller `pidd`"), "{msg}");
    let msg = message(
        &PAPER_SCENARIO_1.replace("attitude_derivatives = \"command-filter\"", "attitude_derivatives = \"magic\""),
    );
    assert!(msg.contains("magic"), "{msg}");
}
