//! Scenario ergonomics: `extends` with a deep merge, partial gain tables,
//! bare-number signals, waypoint and piecewise signals, unit-slip warnings.

use std::path::{Path, PathBuf};

use ftsmc_sim::scenario::{Scenario, PAPER_SCENARIO_1, PAPER_SCENARIO_2};
use ftsmc_sim::signal::waypoints::{WaypointVelocity, Waypoints};
use ftsmc_sim::signal::{Signal, Term};

use crate::common::scratch;

fn write(dir: &Path, file: &str, text: &str) -> PathBuf {
    let path = dir.join(file);
    std::fs::write(&path, text).unwrap();
    path
}

fn paper(text: &str, name: &str) -> Scenario {
    Scenario::from_toml_str(text, name).unwrap()
}

#[test]
fn extends_with_one_gain_override_changes_only_that_gain() {
    let tmp = scratch("one-gain");
    let dir = tmp.path();
    let child = write(dir, "child.toml", "extends = \"paper-scenario-1\"\n[ftaftsmc.z]\nlambda = 3.5\n");
    let got = Scenario::from_file(&child).unwrap();
    let mut want = paper(PAPER_SCENARIO_1, "paper-scenario-1.toml");
    assert_ne!(want.gains.ftaftsmc.z.lambda, 3.5);
    want.gains.ftaftsmc.z.lambda = 3.5;
    assert_eq!(got, want);
}

#[test]
fn extends_of_a_built_in_equals_the_built_in_with_or_without_toml() {
    for target in ["paper-scenario-2", "paper-scenario-2.toml"] {
        let got = Scenario::from_toml_str(&format!("extends = \"{target}\"\n"), "x.toml").unwrap();
        assert_eq!(got, paper(PAPER_SCENARIO_2, "paper-scenario-2.toml"));
    }
    let tuned = Scenario::from_toml_str("extends = \"ftaftsmc-tuned-scenario-1\"", "x.toml").unwrap();
    assert_eq!(tuned.name, "ftaftsmc-tuned-scenario-1");
}

#[test]
fn chains_resolve_relative_to_each_file_and_the_nearest_file_wins() {
    let tmp = scratch("chain");
    let dir = tmp.path();
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    write(dir, "base.toml", "extends = \"paper-scenario-2\"\nname = \"base\"\n[payload]\nmass = 0.5\n");
    write(dir, "sub/mid.toml", "extends = \"../base.toml\"\nname = \"mid\"\nduration = 30.0\n");
    let top = write(dir, "sub/top.toml", "extends = \"mid.toml\"\n[payload]\nstart = 12.0\n");
    let loaded = Scenario::load_with_warnings(&top, &[]).unwrap();
    let s = loaded.scenario;
    assert_eq!(loaded.files.len(), 4, "{:?}", loaded.files);
    assert_eq!(s.name, "mid");
    assert_eq!(s.duration, 30.0);
    let p = s.payload.unwrap();
    assert_eq!((p.mass, p.start, p.decay_start, p.tau), (0.5, 12.0, Some(40.0), Some(3.0)));
}

#[test]
fn cycles_and_overlong_chains_are_refused_naming_the_chain() {
    let tmp = scratch("cycle");
    let dir = tmp.path();
    let a = write(dir, "a.toml", "extends = \"b.toml\"\nname = \"a\"\n");
    write(dir, "b.toml", "extends = \"a.toml\"\n");
    let msg = Scenario::from_file(&a).unwrap_err().to_string();
    assert!(msg.contains("cycle") && msg.contains("a.toml → ") && msg.contains("b.toml"), "{msg}");

    let selfish = write(dir, "self.toml", "extends = \"./self.toml\"\n");
    let msg = Scenario::from_file(&selfish).unwrap_err().to_string();
    assert!(msg.contains("cycle"), "{msg}");

    for i in 0..20 {
        write(dir, &format!("l{i}.toml"), &format!("extends = \"l{}.toml\"\n", i + 1));
    }
    write(dir, "l20.toml", "extends = \"paper-scenario-1\"\n");
    let msg = Scenario::from_file(&dir.join("l0.toml")).unwrap_err().to_string();
    assert!(msg.contains("longer than 16"), "{msg}");
    // 16 files in all (l6 … l20 and the built-in) is fine.
    Scenario::from_file(&dir.join("l6.toml")).unwrap();
}

#[test]
fn a_missing_base_or_a_non_string_extends_is_an_error() {
    let msg = Scenario::from_toml_str("extends = \"nope.toml\"\n", "x.toml").unwrap_err().to_string();
    assert!(msg.contains("nope.toml") && msg.contains("paper-scenario-1"), "{msg}");
    let msg = Scenario::from_toml_str("extends = 3\n", "x.toml").unwrap_err().to_string();
    assert!(msg.contains("`extends`"), "{msg}");
}

#[test]
fn every_file_of_a_chain_gets_the_file_checks() {
    let tmp = scratch("file-checks");
    let dir = tmp.path();
    std::fs::create_dir_all(dir.join("adir")).unwrap();
    let child = write(dir, "child.toml", "extends = \"adir\"\nname = \"c\"\n");
    let msg = Scenario::from_file(&child).unwrap_err().to_string();
    assert!(msg.contains("directory"), "{msg}");

    write(dir, "big.toml", &format!("extends = \"paper-scenario-1\"\n{}", "# padding\n".repeat(200)));
    let child = write(dir, "small.toml", "extends = \"big.toml\"\n");
    let msg = Scenario::from_file_with_limits(&child, &["max_scenario_bytes=1000".into()]).unwrap_err().to_string();
    assert!(msg.contains("max_scenario_bytes") && msg.contains("big.toml"), "{msg}");
    Scenario::from_file_with_limits(&child, &["max_scenario_bytes=3000".into()]).unwrap();
}

#[test]
fn unknown_keys_in_an_extending_file_are_errors_naming_key_and_file() {
    let tmp = scratch("unknown");
    let dir = tmp.path();
    let child = write(dir, "child.toml", "extends = \"paper-scenario-1\"\n\n[ftaftsmc.z]\nlambdda = 2.0\n");
    let msg = Scenario::from_file(&child).unwrap_err().to_string();
    assert!(msg.contains("child.toml") && msg.contains("unknown field `lambdda`"), "{msg}");
    assert!(msg.contains("line 4"), "{msg}");

    // A typo in the base is attributed to the base.
    write(dir, "base.toml", "extends = \"paper-scenario-1\"\n[plant]\nmas = 0.8\n");
    let child = write(dir, "child2.toml", "extends = \"base.toml\"\nname = \"c\"\n");
    let msg = Scenario::from_file(&child).unwrap_err().to_string();
    assert!(msg.starts_with(&dir.join("base.toml").display().to_string()), "{msg}");
    assert!(msg.contains("extended by") && msg.contains("unknown field `mas`"), "{msg}");

    // A range error in the base names the base too.
    write(dir, "base3.toml", "extends = \"paper-scenario-1\"\n[ftaftsmc.z]\np = 1.5\n");
    let child = write(dir, "child3.toml", "extends = \"base3.toml\"\nname = \"c\"\n");
    let msg = Scenario::from_file(&child).unwrap_err().to_string();
    assert!(msg.contains("base3.toml") && msg.contains("`ftaftsmc.z.p` = 1.5"), "{msg}");
}

#[test]
fn required_keys_must_come_from_some_file_of_the_chain() {
    let msg = Scenario::from_toml_str("[ftaftsmc.z]\nlambda = 2.0\n", "x.toml").unwrap_err().to_string();
    assert!(msg.contains("missing field `name`"), "{msg}");
    let msg = Scenario::from_toml_str("name = \"x\"\n", "x.toml").unwrap_err().to_string();
    assert!(msg.contains("missing field `duration`"), "{msg}");
}

#[test]
fn partial_gain_tables_keep_the_per_axis_defaults() {
    let s = Scenario::from_toml_str(
        "name = \"p\"\nduration = 1.0\n[ftaftsmc.z]\nlambda = 2.5\n[ftaftsmc.psi]\ngamma = 3.0\n[tsm-sta.x]\nk1 = 4.0\n",
        "p.toml",
    )
    .unwrap();
    let defaults = Scenario::from_toml_str("name = \"p\"\nduration = 1.0\n", "d.toml").unwrap();
    let mut want = defaults.clone();
    want.gains.ftaftsmc.z.lambda = 2.5;
    want.gains.ftaftsmc.psi.gamma = 3.0;
    want.gains.tsm_sta.x.k1 = 4.0;
    assert_eq!(s, want);
    // x/y, z and attitude defaults differ, and each axis kept its own.
    assert_ne!(defaults.gains.ftaftsmc.x, defaults.gains.ftaftsmc.z);
    assert_eq!(s.gains.ftaftsmc.x, defaults.gains.ftaftsmc.x);
    assert_eq!(s.gains.ftaftsmc.z.gamma, defaults.gains.ftaftsmc.z.gamma);
}

#[test]
fn a_bare_number_or_a_single_term_is_a_signal() {
    let s = Scenario::from_toml_str(
        "name = \"b\"\nduration = 1.0\n[reference]\nz = 1.0\npsi = 0\nx = { type = \"sine\", amplitude = 0.5, omega = 2.0 }\n\
         [disturbance]\nx = -0.25\n",
        "b.toml",
    )
    .unwrap();
    assert_eq!(s.reference.z, Signal::constant(1.0));
    assert_eq!(s.reference.psi, Signal::constant(0.0));
    assert_eq!(s.disturbance.x, Signal::constant(-0.25));
    assert_eq!(s.reference.x.terms, vec![Term::Sine { amplitude: 0.5, omega: Some(2.0), frequency: None, phase: 0.0 }]);
    // Readable errors for the other forms.
    let msg = Scenario::from_toml_str("name = \"b\"\nduration = 1.0\n[reference]\nz = \"one\"\n", "b.toml")
        .unwrap_err()
        .to_string();
    assert!(msg.contains("expected a number") && msg.contains("line 4"), "{msg}");
    let msg = Scenario::from_toml_str("name = \"b\"\nduration = 1.0\n[reference]\nz = { trems = [] }\n", "b.toml")
        .unwrap_err()
        .to_string();
    assert!(msg.contains("unknown field `trems`"), "{msg}");
    let msg = Scenario::from_toml_str(
        "name = \"b\"\nduration = 1.0\n[reference]\nz = { type = \"sine\", amplitude = 1 }\n",
        "b.toml",
    )
    .unwrap_err()
    .to_string();
    assert!(msg.contains("reference.z") && msg.contains("omega"), "{msg}");
}

#[test]
fn signals_are_replaced_whole_by_an_extending_file() {
    let s = Scenario::from_toml_str("extends = \"paper-scenario-2\"\n[disturbance.x]\nwindow = [0.0, 5.0]\n", "x.toml")
        .unwrap();
    assert!(s.disturbance.x.terms.is_empty(), "{:?}", s.disturbance.x);
    let s = Scenario::from_toml_str("extends = \"paper-scenario-1\"\n[reference]\nx = 2.0\n", "x.toml").unwrap();
    assert_eq!(s.reference.x, Signal::constant(2.0));
    assert_eq!(s.reference.y, paper(PAPER_SCENARIO_1, "p1").reference.y);
}

fn check_derivatives(w: &Waypoints, times: &[f64]) {
    let h = 1e-6;
    for &t in times {
        let s = w.sample(t);
        let fd1 = (w.sample(t + h).value - w.sample(t - h).value) / (2.0 * h);
        let fd2 = (w.sample(t + h).rate - w.sample(t - h).rate) / (2.0 * h);
        assert!((fd1 - s.rate).abs() < 1e-6 * (1.0 + s.rate.abs()), "rate at {t}: {fd1} vs {}", s.rate);
        assert!(
            (fd2 - s.acceleration).abs() < 1e-5 * (1.0 + s.acceleration.abs()),
            "acc at {t}: {fd2} vs {}",
            s.acceleration
        );
    }
}

fn waypoint_cases() -> Vec<Waypoints> {
    let t = vec![0.0, 2.0, 3.0, 7.5, 10.0, 15.0];
    let v = vec![0.0, 1.0, -0.5, 2.0, 2.0, 0.0];
    vec![
        Waypoints::new(t.clone(), v.clone(), WaypointVelocity::Zero),
        Waypoints::new(t, v, WaypointVelocity::Spline),
        Waypoints::new(vec![1.0, 4.0], vec![3.0, -1.0], WaypointVelocity::Spline),
        Waypoints::new(vec![-1.0, 0.5, 1.0], vec![0.2, 0.2, 1.0], WaypointVelocity::Spline),
    ]
}

#[test]
fn waypoints_pass_through_their_points_and_hold_outside() {
    for w in waypoint_cases() {
        for (t, v) in w.times().iter().zip(w.values()) {
            assert!((w.sample(*t).value - v).abs() < 1e-12, "{t}");
        }
        let (first, last) = (w.times()[0], *w.times().last().unwrap());
        for t in [first - 100.0, first - 1e-3, last + 1e-3, last + 100.0] {
            let s = w.sample(t);
            let hold = if t < first { w.values()[0] } else { *w.values().last().unwrap() };
            assert_eq!((s.value, s.rate, s.acceleration), (hold, 0.0, 0.0));
        }
        assert!(w.check().is_ok());
    }
    let zero = &waypoint_cases()[0];
    // velocity = "zero": rest at every waypoint, no overshoot.
    for &t in zero.times() {
        assert!(zero.sample(t).rate.abs() < 1e-12 && zero.sample(t).acceleration.abs() < 1e-12);
    }
    for k in 0..=1500 {
        let v = zero.sample(k as f64 * 0.01).value;
        assert!((-0.5..=2.0).contains(&v), "{v}");
    }
}

#[test]
fn waypoint_derivatives_match_finite_differences() {
    for w in waypoint_cases() {
        let (first, last) = (w.times()[0] - 1.0, *w.times().last().unwrap() + 1.0);
        let mut times: Vec<f64> = (0..=997).map(|k| first + (last - first) * k as f64 / 997.0).collect();
        for &knot in w.times() {
            times.extend([knot - 1e-4, knot + 1e-4, knot - 1e-3, knot + 1e-3]);
        }
        check_derivatives(&w, &times);
    }
}

#[test]
fn waypoints_are_c2_at_the_knots_and_ends() {
    for w in waypoint_cases() {
        let eps = 1e-9;
        for &t in w.times() {
            let (a, b) = (w.sample(t - eps), w.sample(t + eps));
            assert!((a.value - b.value).abs() < 1e-7, "value jump at {t}");
            assert!((a.rate - b.rate).abs() < 1e-6, "rate jump at {t}: {} vs {}", a.rate, b.rate);
            assert!((a.acceleration - b.acceleration).abs() < 1e-5, "acceleration jump at {t}");
        }
    }
    // "spline" really passes through interior points (non-zero velocity).
    let spline = &waypoint_cases()[1];
    assert!(spline.sample(2.0).rate.abs() > 1e-3);
}

#[test]
fn invalid_waypoints_are_refused_naming_the_index() {
    let base = "name = \"w\"\nduration = 1.0\n[reference]\n";
    for (x, key) in [
        ("x = { type = \"waypoints\", t = [0.0, 2.0, 2.0], value = [0, 1, 2] }", "reference.x.terms[0].t[2]"),
        ("x = { type = \"waypoints\", t = [0.0, 2.0], value = [0, 1, 2] }", "reference.x.terms[0].value"),
        ("x = { type = \"waypoints\", t = [], value = [] }", "reference.x.terms[0].value"),
        ("x = { type = \"waypoints\", t = [0.0, nan], value = [0, 1] }", "reference.x.terms[0].t[1]"),
    ] {
        let msg = Scenario::from_toml_str(&format!("{base}{x}\n"), "w.toml").unwrap_err().to_string();
        assert!(msg.contains(key), "{x}: {msg}");
    }
}

#[test]
fn piecewise_switches_signals_at_until() {
    let s = Scenario::from_toml_str(
        "name = \"pw\"\nduration = 1.0\n[reference]\nz = { type = \"piecewise\", pieces = [\n\
           { until = 5.0, signal = 1.0 },\n\
           { until = 10.0, signal = { type = \"polynomial\", coefficients = [0.0, 0.2] } },\n\
           { signal = { terms = [{ type = \"sine\", amplitude = 0.5, omega = 1.0 }], window = [12.0, 20.0] } },\n\
         ] }\n",
        "pw.toml",
    )
    .unwrap();
    let z = &s.reference.z;
    assert_eq!(z.value(-3.0), 1.0);
    assert_eq!(z.value(4.999), 1.0);
    assert!((z.value(5.0) - 1.0).abs() < 1e-12 && (z.sample(7.0).rate - 0.2).abs() < 1e-12);
    assert_eq!(z.value(11.0), 0.0);
    assert!((z.value(13.0) - 0.5 * ftsmc_core::math::sin(13f64)).abs() < 1e-12);
    assert_eq!(z.value(25.0), 0.0);

    let bad = |pieces: &str| {
        Scenario::from_toml_str(
            &format!(
                "name = \"pw\"\nduration = 1.0\n[reference]\nz = {{ type = \"piecewise\", pieces = [{pieces}] }}\n"
            ),
            "pw.toml",
        )
        .unwrap_err()
        .to_string()
    };
    assert!(bad("{ until = 5.0, signal = 1 }, { until = 4.0, signal = 2 }, { signal = 3 }").contains("pieces[1].until"));
    assert!(bad("{ signal = 1 }, { signal = 2 }").contains("pieces[0].until"));
    assert!(bad("{ until = 5.0, signal = 1 }").contains("pieces[0].until"));
    assert!(bad("").contains("pieces"));
    assert!(bad("{ until = 5.0, signal = { type = \"sine\", amplitude = 1 } }, { signal = 0 }")
        .contains("pieces[0].signal.terms[0].omega"));
}

#[test]
fn unit_slip_warnings_fire_and_name_file_key_and_value() {
    let tmp = scratch("warnings");
    let dir = tmp.path();
    let cases = [
        ("[initial_state]\nattitude = [0.0, 0.0, 45.0]\n", "`initial_state.attitude[2]` = 45"),
        ("[reference]\npsi = 45.0\n", "`reference.psi.terms[0].value` = 45"),
        (
            "[reference]\npsi = { type = \"sine\", amplitude = 90.0, omega = 1.0 }\n",
            "`reference.psi.terms[0].amplitude` = 90",
        ),
        ("[reference]\npsi = { type = \"waypoints\", t = [0, 1], value = [0, 180] }\n", "value[1]` = 180"),
        ("[payload]\nmass = 370.0\nstart = 1.0\n", "`payload.mass` = 370 kg"),
        ("[payload]\nmass = 0.3\nstart = 30.0\n", "`payload.start` = 30 s"),
        (
            "[disturbance.y]\nwindow = [25.0, 30.0]\nterms = [{ type = \"constant\", value = 1.0 }]\n",
            "`disturbance.y.window` = [25, 30]",
        ),
        ("[inertia_variation]\nwindow = [21.0, 30.0]\n", "`inertia_variation.window`"),
    ];
    for (i, (extra, want)) in cases.iter().enumerate() {
        let file = write(dir, &format!("w{i}.toml"), &format!("extends = \"paper-scenario-1\"\nname = \"w\"\n{extra}"));
        let loaded = Scenario::load_with_warnings(&file, &[]).unwrap();
        assert_eq!(loaded.warnings.len(), 1, "{extra}: {:?}", loaded.warnings);
        let w = &loaded.warnings[0];
        assert!(w.contains(want) && w.starts_with(&file.display().to_string()), "{w}");
        assert_eq!(loaded.scenario.warnings().len(), 1);
    }
}

#[test]
fn plausible_scenarios_do_not_warn() {
    for (file, text) in ftsmc_sim::scenario::BUILT_IN_SCENARIOS {
        let loaded = Scenario::from_toml_str_with_warnings(text, file, &[]).unwrap();
        assert!(loaded.warnings.is_empty(), "{file}: {:?}", loaded.warnings);
    }
    let fine = "extends = \"paper-scenario-2\"\nname = \"ok\"\n[initial_state]\nattitude = [0.1, -0.1, 3.0]\n\
                [reference]\npsi = { type = \"polynomial\", coefficients = [0.0, 1.0] }\n\
                [payload]\nmass = 7.0\nstart = 39.0\n[disturbance.x]\nwindow = [45.0, 80.0]\n";
    let loaded = Scenario::from_toml_str_with_warnings(fine, "ok.toml", &[]).unwrap();
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
}

#[test]
fn example_scenarios_load_and_fly_one_second() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/examples");
    let mut seen = 0;
    for entry in std::fs::read_dir(&root).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "toml") {
            continue;
        }
        seen += 1;
        let loaded = Scenario::load_with_warnings(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
        assert!(loaded.warnings.is_empty(), "{}: {:?}", path.display(), loaded.warnings);
        let mut s = loaded.scenario;
        s.duration = 1.0;
        for controller in s.controllers.clone() {
            let out = ftsmc_sim::registry::run(&controller, &s, Default::default()).unwrap();
            assert!(
                matches!(out.exit, ftsmc_sim::ExitStatus::Completed),
                "{} {controller}: {:?}",
                path.display(),
                out.exit
            );
        }
    }
    assert!(seen >= 2);

    let heavier = Scenario::from_file(&root.join("heavier-payload.toml")).unwrap();
    let mut want = paper(PAPER_SCENARIO_2, "paper-scenario-2.toml");
    want.name = "heavier-payload".into();
    want.description = heavier.description.clone();
    want.payload.as_mut().unwrap().mass = 0.74;
    assert_eq!(heavier, want);

    let square = Scenario::from_file(&root.join("square-path.toml")).unwrap();
    // The x-y reference moves along the square's edges.
    for k in 0..=240 {
        let t = k as f64 * 0.1;
        let (x, y) = (square.reference.x.value(t), square.reference.y.value(t));
        let on_edge = [x.abs(), (x - 1.0).abs(), y.abs(), (y - 1.0).abs()].iter().any(|d| *d < 1e-12);
        assert!(on_edge && (-1e-12..=1.0 + 1e-12).contains(&x) && (-1e-12..=1.0 + 1e-12).contains(&y), "{t}: {x}, {y}");
    }
}
