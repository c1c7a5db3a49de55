//! PX4 gains in and out (`controllers::px4_params`, docs/px4.md): the
//! export → import round trip, PX4's published defaults importing to the
//! documented `[pid]` values, `[pid] px4_params` in a scenario, and errors
//! that name the file, line, parameter and value.

use ftsmc_core::pid::PidGains;
use ftsmc_sim::controllers::px4_params::{self, gains_from_params, params_from_gains, parse_qgc, write_qgc};
use ftsmc_sim::controllers::{GainSection, NominalVehicle};
use ftsmc_sim::scenario::Scenario;

fn built_in(name: &str) -> Scenario {
    let (file, text) = ftsmc_sim::scenario::resolve::built_in(name).unwrap();
    Scenario::from_toml_str(text, file).unwrap()
}

/// Every field of `a` and `b` within `tol` relative (absolute below 1).
fn assert_close(a: &PidGains, b: &PidGains, tol: f64) {
    let ta = toml::Table::try_from(a).unwrap();
    let tb = toml::Table::try_from(b).unwrap();
    assert_eq!(ta.keys().collect::<Vec<_>>(), tb.keys().collect::<Vec<_>>());
    let num = |v: &toml::Value| -> Vec<f64> {
        match v {
            toml::Value::Float(x) => vec![*x],
            toml::Value::Array(xs) => xs.iter().map(|x| x.as_float().unwrap()).collect(),
            toml::Value::Boolean(b) => vec![f64::from(u8::from(*b))],
            other => panic!("{other:?}"),
        }
    };
    for (key, va) in &ta {
        for (x, y) in num(va).into_iter().zip(num(&tb[key])) {
            assert!((x - y).abs() <= tol * x.abs().max(1.0), "{key}: {x} vs {y}");
        }
    }
}

fn round_trip(gains: &PidGains, vehicle: &NominalVehicle) -> PidGains {
    let params = params_from_gains(gains, vehicle).unwrap();
    let text = write_qgc(&params, &["test".to_string()]);
    let parsed = parse_qgc(&text, "round-trip.params").unwrap();
    assert_eq!(parsed.values.len(), px4_params::PX4_DEFAULTS.len());
    gains_from_params(&parsed, vehicle).unwrap()
}

#[test]
fn export_then_import_gives_the_same_gains_on_every_vehicle() {
    let mut vehicles = vec![built_in("paper-scenario-1").nominal_vehicle()];
    for preset in ftsmc_sim::vehicle::VehiclePreset::ALL {
        let s = built_in("realistic-scenario-1")
            .with_overrides(&[("vehicle.preset".to_string(), toml::Value::String(preset.name().into()))])
            .unwrap()
            .scenario;
        vehicles.push(s.nominal_vehicle());
    }
    for vehicle in &vehicles {
        let defaults = PidGains::defaults_for(vehicle);
        assert_close(&round_trip(&defaults, vehicle), &defaults, 1e-12);
        // Tuned-looking gains, a hover thrust that is not m g (exported with
        // MPC_USE_HTE = 0) and a rate feed-forward.
        let tuned = PidGains {
            position_p: [1.3, 1.3, 0.7],
            velocity_i: [0.9, 0.9, 1.1],
            rate_p: defaults.rate_p.map(|k| 1.7 * k),
            rate_i: defaults.rate_i.map(|k| 0.3 * k),
            rate_d: [0.01, 0.02, 0.003],
            rate_ff: [0.01, 0.01, 0.02],
            hover_thrust: 1.1 * defaults.hover_thrust,
            max_tilt: 0.6,
            ..defaults
        };
        assert_close(&round_trip(&tuned, vehicle), &tuned, 1e-12);
    }
}

#[test]
fn px4_published_defaults_import_to_the_documented_pid_values() {
    // A file with PX4's defaults written out, and one with none of them (a
    // missing parameter takes PX4's default): both give the same gains.
    let listed: String =
        px4_params::PX4_DEFAULTS.iter().map(|(name, value, kind)| format!("1\t1\t{name}\t{value}\t{kind}\n")).collect();
    let full = parse_qgc(&listed, "defaults.params").unwrap();
    let empty = parse_qgc("# nothing\n", "empty.params").unwrap();
    // The Hummingbird (limited rotors, thrust-to-weight 3.42): exactly
    // ftsmc's [pid] defaults (docs/px4.md).
    let hb = built_in("realistic-scenario-1").nominal_vehicle();
    for file in [&full, &empty] {
        let g = gains_from_params(file, &hb).unwrap();
        assert_close(&g, &PidGains::defaults_for(&hb), 1e-12);
    }
    // Unlimited rotors (the paper plant): T_max = 2 m g, so MPC_THR_MAX = 1
    // gives thrust_max = 2 m g where ftsmc's default is 10 m g (docs/px4.md);
    // every other value is ftsmc's default.
    let paper = built_in("paper-scenario-1").nominal_vehicle();
    let g = gains_from_params(&full, &paper).unwrap();
    let weight = paper.plant.mass * paper.plant.gravity;
    let d = PidGains::defaults_for(&paper);
    assert!((d.thrust_max - 10.0 * weight).abs() < 1e-9);
    assert!((g.thrust_max - 2.0 * weight).abs() < 1e-9, "{}", g.thrust_max);
    assert_close(&PidGains { thrust_max: d.thrust_max, ..g }, &d, 1e-12);
    // PX4's MC_*RATE_K scales P, I and D, not the feed-forward or the limit.
    let k2 = parse_qgc("1 1 MC_ROLLRATE_K 2 9\n1 1 MC_ROLLRATE_FF 0.1 9\n", "k.params").unwrap();
    let g = gains_from_params(&k2, &hb).unwrap();
    let h = PidGains::defaults_for(&hb);
    let tau = px4_params::normalisation(&hb).1[0];
    assert!((g.rate_p[0] - 2.0 * h.rate_p[0]).abs() < 1e-12 && (g.rate_i[0] - 2.0 * h.rate_i[0]).abs() < 1e-12);
    assert!((g.rate_d[0] - 2.0 * h.rate_d[0]).abs() < 1e-12);
    assert!((g.rate_ff[0] - 0.1 * tau).abs() < 1e-12 && g.rate_integral_limit == h.rate_integral_limit);
    // The hover thrust: the estimate (m g) unless MPC_USE_HTE = 0.
    let fixed = parse_qgc("1 1 MPC_USE_HTE 0 6\n1 1 MPC_THR_HOVER 0.4 9\n", "h.params").unwrap();
    let (t_max, _) = px4_params::normalisation(&hb);
    assert!((gains_from_params(&fixed, &hb).unwrap().hover_thrust - 0.4 * t_max).abs() < 1e-12);
}

#[test]
fn bad_files_are_refused_naming_file_line_parameter_and_value() {
    let hb = built_in("realistic-scenario-1").nominal_vehicle();
    let cases: [(&str, &[&str]); 6] = [
        ("# c\n1\t1\tMC_ROLLRATE_P\t-0.5\t9\n", &["bad.params, line 2", "MC_ROLLRATE_P", "-0.5"]),
        ("1 1 MPC_XY_P nan 9\n", &["bad.params, line 1", "MPC_XY_P", "nan", "finite"]),
        ("1 1 MPC_XY_P 1 9\n1 1 MPC_Z_P 1 9\n1 1 MPC_XY_P 2 9\n", &["line 3", "MPC_XY_P", "lines 1 and 3"]),
        ("1 1 MPC_XY_P\n", &["bad.params, line 1", "3 fields"]),
        ("1 1 MPC_USE_HTE 0.5 6\n", &["bad.params, line 1", "MPC_USE_HTE", "0.5", "integer"]),
        ("1 1 MPC_THR_MIN 0.9 9\n", &["bad.params, line 1", "MPC_THR_MIN", "0.9"]),
    ];
    for (text, wanted) in cases {
        let err = parse_qgc(text, "bad.params").and_then(|p| gains_from_params(&p, &hb)).unwrap_err().to_string();
        for w in wanted {
            assert!(err.contains(w), "{err:?} lacks {w:?}");
        }
        assert!(err.lines().next().unwrap().len() <= 300, "{err}");
    }
    // Gains PX4 cannot hold are refused on export, naming the key.
    let d = PidGains::defaults_for(&hb);
    let err = params_from_gains(&PidGains { velocity_p: [1.0, 2.0, 3.0], ..d }, &hb).unwrap_err().to_string();
    assert!(err.contains("pid.velocity_p") && err.contains("MPC_XY_"), "{err}");
}

#[test]
fn a_scenario_flies_the_gains_of_its_px4_params_file() {
    let dir = crate::common::scratch("px4");
    let hb = built_in("realistic-scenario-1");
    let vehicle = hb.nominal_vehicle();
    let tuned = PidGains { attitude_p: [6.5, 6.5, 2.8], ..PidGains::defaults_for(&vehicle) };
    let params = params_from_gains(&tuned, &vehicle).unwrap();
    std::fs::create_dir(dir.path().join("gains")).unwrap();
    std::fs::write(dir.path().join("gains/x.params"), write_qgc(&params, &[])).unwrap();
    // Relative to the file that sets the key; a key beside it wins.
    let scenario_text =
        "extends = \"realistic-scenario-1\"\n[pid]\npx4_params = \"gains/x.params\"\nyaw_weight = 0.5\n";
    std::fs::write(dir.path().join("s.toml"), scenario_text).unwrap();
    let s = Scenario::from_file(&dir.path().join("s.toml")).unwrap();
    assert_close(&s.gains.pid, &PidGains { yaw_weight: 0.5, ..tuned }, 1e-12);
    // A bad value: the scenario file and the parameter file's line, name and value.
    std::fs::write(dir.path().join("gains/x.params"), "1\t1\tMC_PITCH_P\t-3\t9\n").unwrap();
    let err = Scenario::from_file(&dir.path().join("s.toml")).unwrap_err().to_string();
    for w in ["s.toml", "px4_params", "x.params, line 1", "MC_PITCH_P", "-3"] {
        assert!(err.contains(w), "{err:?} lacks {w:?}");
    }
    // A missing file is named.
    std::fs::write(dir.path().join("t.toml"), scenario_text.replace("x.params", "missing.params")).unwrap();
    let err = Scenario::from_file(&dir.path().join("t.toml")).unwrap_err().to_string();
    assert!(err.contains("missing.params") && err.contains("t.toml"), "{err}");
}
