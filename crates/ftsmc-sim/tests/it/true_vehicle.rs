//! One section for the true vehicle (`[vehicle]`, docs/scenarios.md "The
//! true vehicle"): the old spellings `[actual_plant]` and
//! `[vehicle.rigid_body]` load with a warning naming the new key and fly
//! bit for bit like the new spelling, which keeps the old meaning (the old
//! tables were complete: missing keys the paper vehicle's); mixing the
//! spellings is refused naming both keys; a key only the other truth model
//! flies is refused naming file, key, value and model.

use ftsmc_core::model::QuadrotorParams;
use ftsmc_sim::registry;
use ftsmc_sim::scenario::resolve::Loaded;
use ftsmc_sim::scenario::Scenario;
use ftsmc_sim::vehicle::{RigidBodyParams, VehicleModel};
use ftsmc_sim::RunOptions;

/// A `[plant]` that differs from the paper vehicle in every key, so a key
/// that falls back to `[plant]` cannot pass for one that took the paper's value.
const PLANT: &str = "[plant]\nmass = 0.7\ngravity = 9.7\ninertia = [4e-3, 4.1e-3, 8e-3]\nrotor_inertia = 3e-5\n\
                     drag_translational = [1e-3, 1e-3, 2e-3]\ndrag_rotational = [6e-4, 6e-4, 7e-4]\n\
                     lift_coefficient = 3e-5\nyaw_drag_coefficient = 3.3e-7\narm_length = 0.2\n";

/// The paper vehicle, key by key, as `[vehicle]` spells it.
const PAPER: [(&str, &str); 9] = [
    ("mass", "0.74"),
    ("gravity", "9.81"),
    ("inertia", "[3.827e-3, 3.827e-3, 7.6566e-3]"),
    ("rotor_inertia", "2.8385e-5"),
    ("drag_translational", "[5.567e-4, 5.567e-4, 5.567e-4]"),
    ("drag_rotational", "[5.567e-4, 5.567e-4, 5.567e-4]"),
    ("thrust_coefficient", "2.9842e-5"),
    ("moment_coefficient", "3.2320e-7"),
    ("arm_length", "0.21"),
];

fn load(body: &str) -> Result<Loaded, String> {
    let text = format!("extends = \"paper-scenario-1\"\nname = \"t\"\nduration = 1.0\n{PLANT}{body}");
    Scenario::from_toml_str_with_warnings(&text, "t.toml", &[]).map_err(|e| e.to_string())
}

fn loaded(body: &str) -> Loaded {
    load(body).unwrap_or_else(|e| panic!("{e}\n{body}"))
}

/// Every recorded number of a flight, as bits, and how it ended.
fn flight_bits(s: &Scenario) -> (Vec<u64>, String) {
    let out = registry::run("ftaftsmc", s, RunOptions { record: true, ..Default::default() }).unwrap();
    let bits = out.recording.columns.iter().flatten().map(|v| v.to_bits()).collect();
    (bits, out.exit.to_string())
}

fn deprecations(l: &Loaded) -> Vec<&String> {
    l.warnings.iter().filter(|w| w.contains("deprecated") || w.contains("paper vehicle's values")).collect()
}

/// `[actual_plant] <key>` (every key): the warning names the new key, the
/// true vehicle is the old table's (missing keys the paper's, not
/// `[plant]`'s), the new spelling the docs give loads to the same scenario
/// and both fly the same bits.
#[test]
fn every_actual_plant_key_loads_with_a_warning_and_flies_like_the_new_spelling() {
    let values = [
        ("mass", "mass", "0.8"),
        ("gravity", "gravity", "9.75"),
        ("inertia", "inertia", "[4.2e-3, 4.3e-3, 8.1e-3]"),
        ("rotor_inertia", "rotor_inertia", "2e-5"),
        ("drag_translational", "drag_translational", "[2e-3, 2e-3, 3e-3]"),
        ("drag_rotational", "drag_rotational", "[7e-4, 7e-4, 8e-4]"),
        ("lift_coefficient", "thrust_coefficient", "3.1e-5"),
        ("yaw_drag_coefficient", "moment_coefficient", "3.4e-7"),
        ("arm_length", "arm_length", "0.22"),
    ];
    for (old_key, new_key, value) in values {
        let old = loaded(&format!("[actual_plant]\n{old_key} = {value}\n"));
        let w = deprecations(&old);
        assert!(
            w.iter()
                .any(|w| w.contains(&format!("`actual_plant.{old_key}`"))
                    && w.contains(&format!("[vehicle] {new_key} ="))),
            "{old_key}: {w:?}"
        );
        assert!(
            w.iter().any(|w| w.contains("t.toml") && w.contains("[plant]")),
            "{old_key}: missing keys explained: {w:?}"
        );
        // The old meaning: the table replaced [plant] whole.
        let table: QuadrotorParams = toml::from_str(&format!("{old_key} = {value}")).unwrap();
        assert_eq!(old.scenario.true_vehicle(), table, "{old_key}");
        assert_eq!(old.scenario.plant.mass, 0.7, "the controllers' model stays [plant]");
        // The new spelling: the key, and the paper's value of every other key.
        let mut new_text = format!("[vehicle]\n{new_key} = {value}\n");
        for (k, v) in PAPER.iter().filter(|(k, _)| *k != new_key) {
            new_text.push_str(&format!("{k} = {v}\n"));
        }
        let new = loaded(&new_text);
        assert!(deprecations(&new).is_empty(), "{:?}", new.warnings);
        assert_eq!(old.scenario, new.scenario, "{old_key}");
        assert_eq!(flight_bits(&old.scenario), flight_bits(&new.scenario), "{old_key}");
    }
}

/// `[vehicle.rigid_body] <key>` (every key), with `model = "rigid-body"`.
#[test]
fn every_rigid_body_key_loads_with_a_warning_and_flies_like_the_new_spelling() {
    let values = [
        ("mass", "0.8"),
        ("gravity", "9.75"),
        ("inertia", "[[4e-3, 1e-5, 0.0], [1e-5, 4e-3, 0.0], [0.0, 0.0, 8e-3]]"),
        ("arm_length", "0.22"),
        ("configuration", "\"cross\""),
        ("spin", "[\"ccw\", \"cw\", \"ccw\", \"cw\"]"),
        ("thrust_coefficient", "3.1e-5"),
        ("moment_coefficient", "3.4e-7"),
        ("rotor_inertia", "2e-5"),
        ("parasitic_drag", "[0.01, 0.01, 0.02]"),
        ("rotor_drag_xy", "1e-4"),
        ("rotor_drag_z", "2e-4"),
        ("translational_lift", "3e-3"),
    ];
    let shared =
        ["mass", "gravity", "inertia", "arm_length", "thrust_coefficient", "moment_coefficient", "rotor_inertia"];
    for (key, value) in values {
        let old = loaded(&format!("[vehicle]\nmodel = \"rigid-body\"\n[vehicle.rigid_body]\n{key} = {value}\n"));
        let w = deprecations(&old);
        assert!(
            w.iter().any(
                |w| w.contains(&format!("`vehicle.rigid_body.{key}`")) && w.contains(&format!("[vehicle] {key} ="))
            ),
            "{key}: {w:?}"
        );
        // The old meaning: the table was complete, its missing keys the paper vehicle's.
        let table: RigidBodyParams = toml::from_str(&format!("{key} = {value}")).unwrap();
        assert_eq!(old.scenario.rigid_body_params(), table, "{key}");
        let mut new_text = format!("[vehicle]\nmodel = \"rigid-body\"\n{key} = {value}\n");
        for (k, v) in PAPER.iter().filter(|(k, _)| *k != key && shared.contains(k)) {
            new_text.push_str(&format!("{k} = {v}\n"));
        }
        let new = loaded(&new_text);
        assert!(deprecations(&new).is_empty(), "{:?}", new.warnings);
        assert_eq!(old.scenario, new.scenario, "{key}");
        assert_eq!(flight_bits(&old.scenario), flight_bits(&new.scenario), "{key}");
    }
}

/// An old table with every key written (as the committed realistic
/// scenarios had it) needs nothing filled in: one warning per key.
#[test]
fn a_complete_old_table_converts_key_for_key() {
    let old = loaded("[actual_plant]\nmass = 0.8\ngravity = 9.7\ninertia = [4e-3, 4.1e-3, 8e-3]\n");
    assert_eq!(old.scenario.vehicle.mass, Some(0.8));
    assert_eq!(old.scenario.true_vehicle().gravity, 9.7);
    // rotor_inertia etc. were missing: the paper's, written out.
    assert_eq!(old.scenario.vehicle.rotor_inertia, Some(2.8385e-5));
    assert_eq!(old.scenario.vehicle.model, VehicleModel::Paper);
}

/// The deprecated tables that never acted on the model flown are dropped
/// with a warning saying so, and the flight is the one without them.
#[test]
fn old_keys_the_model_never_flew_are_dropped_with_a_warning() {
    let base = loaded("");
    let paper = loaded("[vehicle.rigid_body]\nparasitic_drag = [0.5, 0.5, 0.5]\n");
    assert!(paper.warnings.iter().any(|w| w.contains("never acted on model = \"paper\"")), "{:?}", paper.warnings);
    assert_eq!(paper.scenario, base.scenario);
    let rigid = loaded("[vehicle]\nmodel = \"rigid-body\"\n[actual_plant]\ndrag_translational = [0.1, 0.1, 0.1]\n");
    assert!(
        rigid.warnings.iter().any(|w| w.contains("actual_plant.drag_translational") && w.contains("never acted")),
        "{:?}",
        rigid.warnings
    );
    assert_eq!(rigid.scenario.vehicle.drag_translational, None);
}

#[test]
fn old_and_new_spellings_together_are_refused_naming_both_keys() {
    let e = load("[actual_plant]\nmass = 0.8\n[vehicle]\ngravity = 9.8\n").unwrap_err();
    assert!(e.contains("t.toml") && e.contains("vehicle.gravity") && e.contains("actual_plant.mass"), "{e}");
    let e =
        load("[vehicle]\nmodel = \"rigid-body\"\nmass = 0.8\n[vehicle.rigid_body]\nparasitic_drag = [0.1, 0.1, 0.1]\n")
            .unwrap_err();
    assert!(e.contains("vehicle.mass") && e.contains("vehicle.rigid_body.parasitic_drag"), "{e}");
    let e = load("[vehicle]\nmodel = \"rigid-body\"\n[vehicle.rigid_body]\nmass = 0.8\n[actual_plant]\nmass = 0.8\n")
        .unwrap_err();
    assert!(e.contains("actual_plant.mass") && e.contains("[vehicle.rigid_body]"), "{e}");
}

/// An old key in a file that extends a converted built-in is refused, and
/// the error names the file that wrote each key.
#[test]
fn an_old_key_over_a_converted_built_in_is_refused_naming_the_files() {
    let dir = tempfile::Builder::new().prefix("ftsmc-true-vehicle-").tempdir().unwrap();
    let path = dir.path().join("mine.toml");
    std::fs::write(&path, "extends = \"realistic-calm-1\"\nname = \"mine\"\n[vehicle.rigid_body]\nmass = 0.8\n")
        .unwrap();
    let e = Scenario::from_file(&path).unwrap_err().to_string();
    assert!(e.contains("vehicle.rigid_body.mass") && e.contains("`vehicle.mass`"), "{e}");
    assert!(e.contains("realistic-calm-1.toml"), "the new key's file: {e}");
}

#[test]
fn a_key_only_the_other_model_flies_is_refused_naming_file_key_value_and_model() {
    for (body, key, value, model) in [
        ("[vehicle]\nparasitic_drag = [0.01, 0.01, 0.02]\n", "vehicle.parasitic_drag", "[0.01, 0.01, 0.02]", "paper"),
        ("[vehicle]\nrotor_drag_z = 2e-4\n", "vehicle.rotor_drag_z", "0.0002", "paper"),
        ("[vehicle]\nconfiguration = \"cross\"\n", "vehicle.configuration", "cross", "paper"),
        (
            "[vehicle]\nmodel = \"rigid-body\"\ndrag_translational = [1e-3, 1e-3, 1e-3]\n",
            "vehicle.drag_translational",
            "[0.001, 0.001, 0.001]",
            "rigid-body",
        ),
        (
            "[vehicle]\ninertia = [[4e-3, 1e-5, 0.0], [1e-5, 4e-3, 0.0], [0.0, 0.0, 8e-3]]\n",
            "vehicle.inertia[0][1]",
            "1e-5",
            "paper",
        ),
    ] {
        let e = load(body).unwrap_err();
        assert!(
            e.contains("t.toml") && e.contains(key) && e.contains(value) && e.contains(&format!("model = \"{model}\"")),
            "{body}: {e}"
        );
    }
    // The same keys on the model that flies them load.
    loaded("[vehicle]\nmodel = \"rigid-body\"\nparasitic_drag = [0.01, 0.01, 0.02]\ninertia = [[4e-3, 1e-5, 0.0], [1e-5, 4e-3, 0.0], [0.0, 0.0, 8e-3]]\n");
    loaded("[vehicle]\ndrag_translational = [1e-3, 1e-3, 1e-3]\ninertia = [[4e-3, 0.0, 0.0], [0.0, 4e-3, 0.0], [0.0, 0.0, 8e-3]]\n");
}

/// `[vehicle]` keys not given are `[plant]`'s, on both models.
#[test]
fn missing_vehicle_keys_are_the_plants() {
    let s = loaded("[vehicle]\nmass = 0.8\n").scenario;
    let plant = s.plant;
    assert_eq!(s.true_vehicle(), QuadrotorParams { mass: 0.8, ..plant });
    let s = loaded("[vehicle]\nmodel = \"rigid-body\"\nmass = 0.8\nrotor_drag_z = 2e-4\n").scenario;
    let mut rb = RigidBodyParams::from_paper(&QuadrotorParams { mass: 0.8, ..plant });
    rb.rotor_drag_z = 2e-4;
    assert_eq!(s.rigid_body_params(), rb);
    // No [vehicle] key: the true vehicle is [plant].
    let s = loaded("").scenario;
    assert_eq!(s.true_vehicle(), s.plant);
}

#[test]
fn bad_true_values_are_refused_naming_the_key_written() {
    for (body, key) in [
        ("[vehicle]\nmass = -1.0\n", "vehicle.mass"),
        ("[vehicle]\nmodel = \"rigid-body\"\nparasitic_drag = [-1.0, 0.0, 0.0]\n", "vehicle.parasitic_drag[0]"),
        // (an untagged value: the error quotes the line, `inertia = …`)
        ("[vehicle]\ninertia = [1.0, 2.0]\n", "inertia = [1.0, 2.0]"),
        ("[vehicle]\nmodel = \"rigid-body\"\nparasitic_drag = [0.1, 0.1, 0.1, 0.1]\n", "vehicle.parasitic_drag"),
        ("[actual_plant]\nmass = -1.0\n", "actual_plant.mass"),
        ("[vehicle]\nmodel = \"rigid-body\"\n[vehicle.rigid_body]\nmass = -1.0\n", "vehicle.rigid_body.mass"),
    ] {
        let e = load(body).unwrap_err();
        assert!(e.contains("t.toml") && e.contains(key), "{body}: {e}");
    }
}

/// Every committed scenario (built-ins, `scenarios/**`) is written in the
/// new spelling: none loads with a deprecation warning.
#[test]
fn no_committed_scenario_uses_an_old_spelling() {
    for name in ftsmc_sim::scenario::resolve::built_in_names() {
        let (file, text) = ftsmc_sim::scenario::resolve::built_in(name).unwrap();
        let l = Scenario::from_toml_str_with_warnings(text, file, &[]).unwrap();
        assert!(deprecations(&l).is_empty(), "{file}: {:?}", l.warnings);
    }
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios");
    let mut stack = vec![root];
    let mut n = 0;
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "toml") {
                let l = Scenario::load_with_warnings(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
                assert!(deprecations(&l).is_empty(), "{}: {:?}", path.display(), l.warnings);
                n += 1;
            }
        }
    }
    assert!(n >= 30, "found only {n} scenario files");
}

/// The written scenario (`scenario.toml` of every result folder) uses the
/// new spelling and loads back to the same scenario.
#[test]
fn a_converted_scenario_is_written_in_the_new_spelling_and_reloads_identically() {
    let old = loaded(
        "[vehicle]\nmodel = \"rigid-body\"\n[vehicle.rigid_body]\nmass = 0.8\nparasitic_drag = [0.01, 0.01, 0.02]\n",
    );
    let text = old.scenario.to_toml().unwrap();
    assert!(!text.contains("rigid_body") && !text.contains("actual_plant"), "{text}");
    let back = Scenario::from_toml_str_with_warnings(&text, "written.toml", &[]).unwrap();
    assert!(deprecations(&back).is_empty(), "{:?}", back.warnings);
    assert_eq!(back.scenario, old.scenario);
}

/// `[actual_plant]` on the rigid body: the rigid body was built from the
/// table (missing keys the paper's); the conversion keeps it.
#[test]
fn actual_plant_on_the_rigid_body_keeps_the_rigid_body_it_built() {
    let old =
        loaded("[vehicle]\nmodel = \"rigid-body\"\n[actual_plant]\nmass = 0.8\ninertia = [4.2e-3, 4.3e-3, 8.1e-3]\n");
    let table: QuadrotorParams = toml::from_str("mass = 0.8\ninertia = [4.2e-3, 4.3e-3, 8.1e-3]").unwrap();
    assert_eq!(old.scenario.rigid_body_params(), RigidBodyParams::from_paper(&table));
    assert_eq!(old.scenario.vehicle.drag_translational, None, "no Eq. 1 drag on the rigid body");
}

/// Monte Carlo draws act on the true vehicle exactly as they acted on the
/// old `actual_plant` (paper model: mass drawn, inertia and both linear
/// drags scaled), and never on the controllers' `[plant]`.
#[test]
fn monte_carlo_draws_act_on_the_true_vehicle_as_before() {
    let s = loaded(
        "[vehicle]\nmass = 0.8\n[montecarlo]\nmass = { dist = \"uniform\", low = 0.7, high = 0.9 }\n\
         inertia_factor = { dist = \"uniform\", low = 0.8, high = 1.2 }\ndrag_factor = { dist = \"uniform\", low = 0.5, high = 2.0 }\n",
    )
    .scenario;
    let spec = s.montecarlo.clone().unwrap();
    let base = s.true_vehicle();
    for index in 0..4 {
        let (flown, _, sampled) = spec.sample(&s, s.seed, index);
        let (mass, fi, fd) = (sampled[0], sampled[2], sampled[3]);
        let expected = QuadrotorParams {
            mass,
            inertia: base.inertia.map(|j| j * fi),
            drag_translational: base.drag_translational.map(|k| k * fd),
            drag_rotational: base.drag_rotational.map(|k| k * fd),
            ..base
        };
        assert_eq!(flown.true_vehicle(), expected, "run {index}");
        assert_eq!(flown.plant, s.plant, "the controllers' model is never drawn");
        assert!(flown.validate("mc.toml").is_ok());
    }
}
