//! Vehicle presets (`[vehicle] preset`): each sourced vehicle loads, fills
//! the controllers' model, the true vehicle and the rotors; hovers with the
//! default PID and SE(3) in still air; and flies the wind ladder's calm
//! rung. Settings follow the vehicle: relative Monte Carlo draws, a refused
//! inherited absolute draw, a wind preset that owns its keys, and `--set`
//! (`Scenario::with_overrides`).

use ftsmc_sim::batch::montecarlo::{run_batch, summarize, BatchOptions};
use ftsmc_sim::registry;
use ftsmc_sim::run::RunOptions;
use ftsmc_sim::scenario::Scenario;
use ftsmc_sim::vehicle::VehiclePreset;

fn load(text: &str) -> Result<Scenario, String> {
    Scenario::from_toml_str(text, "t.toml").map_err(|e| e.to_string())
}

fn set(s: &Scenario, pairs: &[(&str, toml::Value)]) -> Result<Scenario, String> {
    let pairs: Vec<(String, toml::Value)> = pairs.iter().map(|(k, v)| (k.to_string(), v.clone())).collect();
    s.with_overrides(&pairs).map(|l| l.scenario).map_err(|e| e.to_string())
}

fn built_in(name: &str) -> Scenario {
    let (file, text) = ftsmc_sim::scenario::resolve::built_in(name).unwrap();
    Scenario::from_toml_str(text, file).unwrap()
}

#[test]
fn each_preset_sets_the_plant_the_true_vehicle_and_the_rotors_from_its_file() {
    for preset in VehiclePreset::ALL {
        let table = preset.table();
        let s = load(&format!("name = \"p\"\nduration = 1.0\n[vehicle]\npreset = \"{}\"\n", preset.name())).unwrap();
        let plant = table["plant"].as_table().unwrap();
        let vehicle = table["vehicle"].as_table().unwrap();
        let act = table["actuators"].as_table().unwrap();
        let f = |t: &toml::Table, k: &str| t[k].as_float().unwrap();
        assert_eq!(s.plant.mass, f(plant, "mass"), "{preset:?}");
        assert_eq!(s.plant.lift_coefficient, f(plant, "lift_coefficient"), "{preset:?}");
        assert_eq!(s.vehicle.mass, Some(f(vehicle, "mass")), "{preset:?}");
        assert_eq!(s.vehicle.thrust_coefficient, Some(f(vehicle, "thrust_coefficient")), "{preset:?}");
        let a = s.actuators.unwrap();
        assert_eq!(a.max_rotor_speed, f(act, "max_rotor_speed"), "{preset:?}");
        assert_eq!(a.time_constant_up, f(act, "time_constant_up"), "{preset:?}");
        assert!(!preset.description().is_empty());
        // The nominal model and the truth agree key by key.
        assert_eq!(s.plant.mass, s.rigid_body_params().mass);
        assert_eq!(s.plant.inertia, s.true_vehicle().inertia);
    }
    let e = load("name = \"p\"\nduration = 1.0\n[vehicle]\npreset = \"bebop\"\n").unwrap_err();
    assert!(e.contains("t.toml") && e.contains("bebop") && e.contains("crazyflie-2"), "{e}");
}

#[test]
fn a_key_written_beside_the_preset_wins_a_base_files_key_does_not() {
    let s = load("name = \"p\"\nduration = 1.0\n[vehicle]\npreset = \"crazyflie-2\"\nmass = 0.035\n").unwrap();
    assert_eq!(s.vehicle.mass, Some(0.035));
    assert_eq!(s.plant.mass, 0.03, "the nominal model stays the preset's");
    // realistic-calm-1 names the Hummingbird over paper-scenario-1's [plant].
    let calm = built_in("realistic-calm-1");
    assert_eq!(calm.vehicle.preset, Some(VehiclePreset::Hummingbird));
    assert_eq!((calm.plant.mass, calm.plant.arm_length), (0.716, 0.17));
    assert_eq!(calm.actuators.unwrap().max_rotor_speed, 838.0);
}

/// Hover from the ground to 1 m and hold it: the default PID and SE(3)
/// gains of each preset (built for its nominal model) fly it in still air.
#[test]
fn each_preset_hovers_with_the_default_pid_and_se3_in_still_air() {
    for preset in VehiclePreset::ALL {
        let text = format!(
            "name = \"hover\"\nduration = 8.0\ncontrollers = [\"pid\", \"se3\"]\n\
             [vehicle]\npreset = \"{}\"\n[actuators]\nmixer = \"px4\"\n\
             [ground]\nenabled = true\n\
             [reference]\nz = {{ terms = [{{ type = \"constant\", value = 1.0 }}] }}\n",
            preset.name()
        );
        let s = load(&text).unwrap();
        for c in ["pid", "se3"] {
            let out = registry::run(c, &s, RunOptions::default()).unwrap();
            assert!(out.exit.is_completed(), "{preset:?} {c}: {}", out.exit);
            // After 5 s (simulation.steady_state_after), within 5 cm on every axis.
            let m = &out.metrics.max_error_after;
            for (axis, e) in [("x", m.x), ("y", m.y), ("z", m.z)] {
                let e = e.unwrap();
                assert!(e < 0.05, "{preset:?} {c}: {axis} error {e} m after 5 s");
            }
        }
    }
}

/// The calm rung of scenario 1 flown by each preset (`--set
/// vehicle.preset=…`): the default PID and SE(3) each succeed in at least
/// 95 % of 40 Monte Carlo runs (relative mass draws, sampled inertia and
/// drag) — except SE(3) on the Crazyflie 2.1, whose Bitcraze yaw moment
/// (k_m/k_f = 0.006 m, a sixth of the 2.0 set's) leaves SE(3)'s default yaw
/// loop saturated on about half the draws (docs/vehicles.md); there only
/// the PID is held to it.
#[test]
fn each_preset_flies_its_calm_rung() {
    let calm = built_in("realistic-calm-1");
    for preset in VehiclePreset::ALL {
        let s = set(&calm, &[("vehicle.preset", toml::Value::String(preset.name().into()))]).unwrap();
        assert_eq!(s.vehicle.preset, Some(preset));
        let spec = s.montecarlo.clone().unwrap();
        let controllers = vec!["se3".to_string(), "pid".to_string()];
        let rows = run_batch(&s, &spec, &controllers, BatchOptions::new(40, s.seed)).unwrap();
        let summary = summarize(&rows, &controllers);
        for (name, stats) in &summary {
            let rate = stats.success_rate;
            eprintln!("{}: {name} success {:.1} % of 40", preset.name(), 100.0 * rate);
            if preset == VehiclePreset::Crazyflie21 && name == "se3" {
                continue;
            }
            assert!(rate >= 0.95, "{preset:?}: {name} success {rate} on realistic-calm-1");
        }
        // The relative mass draw follows the vehicle.
        let m = s.true_vehicle().mass;
        assert!(rows.iter().all(|r| (r.sampled[0] - m).abs() <= 0.1 * m * (1.0 + 1e-12)), "{preset:?}");
    }
    // Scenario 2's absolute payload (up to 0.2 kg) is refused on a 30 g vehicle.
    let e = set(&built_in("realistic-calm-2"), &[("vehicle.preset", "crazyflie-2".into())]).unwrap_err();
    assert!(e.contains("montecarlo.payload_mass"), "{e}");
}

/// The file of the report that started this: a Crazyflie described by
/// extending the Hummingbird's calm rung and setting its mass. The ladder's
/// relative draw follows it; an absolute Hummingbird draw inherited from a
/// base file is refused naming the key and that file.
#[test]
fn a_crazyflie_from_the_hummingbird_file_draws_relative_masses_or_is_refused() {
    let dir = tempfile::Builder::new().prefix("ftsmc-presets-").tempdir().unwrap();
    let child = dir.path().join("cf.toml");
    std::fs::write(&child, "extends = \"realistic-calm-1\"\nname = \"cf\"\n[vehicle]\nmass = 0.027\n").unwrap();
    let s = Scenario::from_file(&child).unwrap();
    let spec = s.montecarlo.clone().unwrap().absolute(&s);
    let (lo, hi) = spec.mass.unwrap().support();
    assert!((lo - 0.9 * 0.027).abs() < 1e-15 && (hi - 1.1 * 0.027).abs() < 1e-15, "[{lo}, {hi}]");
    // A base with the old absolute draw.
    let base = dir.path().join("hb.toml");
    std::fs::write(
        &base,
        "extends = \"realistic-calm-1\"\nname = \"hb\"\n[montecarlo]\nmass = { dist = \"uniform\", low = 0.6444, high = 0.7876 }\n",
    )
    .unwrap();
    std::fs::write(&child, "extends = \"hb.toml\"\nname = \"cf\"\n[vehicle]\npreset = \"crazyflie-2\"\n").unwrap();
    let e = Scenario::from_file(&child).unwrap_err().to_string();
    assert!(e.contains("montecarlo.mass") && e.contains("hb.toml") && e.contains("0.03 kg"), "{e}");
    assert!(e.lines().next().unwrap().chars().count() <= 300 + 200, "{e}");
    // The child replaces the draw: accepted.
    std::fs::write(
        &child,
        "extends = \"hb.toml\"\nname = \"cf\"\n[vehicle]\npreset = \"crazyflie-2\"\n[montecarlo]\nmass = { dist = \"uniform\", rel = [0.8, 1.2] }\n",
    )
    .unwrap();
    let s = Scenario::from_file(&child).unwrap();
    assert!(s.montecarlo.as_ref().unwrap().mass.is_none(), "the relative draw replaced the absolute one");
}

#[test]
fn a_draw_far_from_the_vehicle_warns() {
    let text = "extends = \"realistic-calm-1\"\nname = \"w\"\n[montecarlo]\nmass = { dist = \"uniform\", low = 0.3, high = 0.8 }\n";
    let loaded = Scenario::from_toml_str_with_warnings(text, "w.toml", &[]).unwrap();
    assert!(
        loaded.warnings.iter().any(|w| w.contains("montecarlo.mass") && w.contains("far from")),
        "{:?}",
        loaded.warnings
    );
}

/// A child's wind preset replaces the parent's wind: speed and turbulence
/// go unless the child sets them; the written scenario says so.
#[test]
fn a_wind_preset_in_a_child_replaces_the_parents_wind() {
    let dir = tempfile::Builder::new().prefix("ftsmc-presets-").tempdir().unwrap();
    let windy = dir.path().join("windy.toml");
    std::fs::write(
        &windy,
        "extends = \"realistic-calm-1\"\nname = \"windy\"\n[wind]\npreset = \"light\"\nspeed = 3.0\n\
         turbulence = { intensity = { w20 = 7.7 }, altitude = 5.0 }\n",
    )
    .unwrap();
    let calm = dir.path().join("calm.toml");
    std::fs::write(&calm, "extends = \"windy.toml\"\nname = \"calm\"\n[wind]\npreset = \"calm\"\n").unwrap();
    let s = Scenario::from_file(&calm).unwrap();
    let w = s.wind.clone().unwrap();
    assert_eq!(w.speed, None);
    assert!(w.turbulence.is_none());
    assert_eq!(w.resolved().mean, [0.0; 3]);
    let text = s.to_toml().unwrap();
    let wind = text.split("\n[wind]\n").nth(1).unwrap().split("\n[").next().unwrap();
    assert!(wind.contains("preset = \"calm\"") && !wind.contains("speed") && !wind.contains("turbulence"), "{wind}");
    // A child that keeps a key sets it too.
    std::fs::write(&calm, "extends = \"windy.toml\"\nname = \"calm\"\n[wind]\npreset = \"calm\"\nspeed = 1.0\n")
        .unwrap();
    assert_eq!(Scenario::from_file(&calm).unwrap().wind.unwrap().speed, Some(1.0));
    // And through the overrides.
    let windy = Scenario::from_file(&windy).unwrap();
    let s = set(&windy, &[("wind.preset", toml::Value::String("calm".into()))]).unwrap();
    assert_eq!(s.wind.as_ref().unwrap().speed, None);
}

/// `--set` is `with_overrides`: the same keys and values give the same
/// scenario, and the CLI's KEY=VALUE reads as the TOML value.
#[test]
fn set_arguments_are_with_overrides() {
    use ftsmc_sim::scenario::overrides::parse_set;
    let calm = built_in("realistic-calm-1");
    let args = ["vehicle.preset=px4-x500", "wind.preset=breeze", "payload.mass=0.2", "seed=9", "controllers=[\"se3\"]"];
    let parsed: Vec<(String, toml::Value)> = args.iter().map(|a| parse_set(a).unwrap()).collect();
    assert_eq!(parsed[0].1, toml::Value::String("px4-x500".into()));
    assert_eq!(parsed[2].1, toml::Value::Float(0.2));
    assert_eq!(parsed[3].1, toml::Value::Integer(9));
    let a = calm.with_overrides(&parsed[..2]).unwrap().scenario;
    let b = set(&calm, &[("vehicle.preset", "px4-x500".into()), ("wind.preset", "breeze".into())]).unwrap();
    assert_eq!(a, b);
    assert_eq!(a.to_toml().unwrap(), b.to_toml().unwrap());
    assert_eq!(a.plant.mass, 2.0643);
    assert!(parse_set("no-equals-sign").is_err());
}

/// A preset's nominal model has no Eq. 1 drag: its true vehicle is the rigid
/// body, which has none (its drag is rotor and body drag). The paper's
/// `drag_rotational` 5.567e-4, left in the controllers' model of a 30 g
/// Crazyflie (J = 1.43e-5 kg·m², 260× less than the paper vehicle's
/// 3.8e-3), made the sliding-mode controllers "compensate" a drag the
/// vehicle does not have — positive feedback on the body rates — and every
/// one of them diverged within 0.3 s. With the drag gone, the paper's
/// RANFTSMC and TSM-STA gains fly the Crazyflie's calm rung. The Hummingbird
/// keeps the paper's drags in its nominal model (K_f2/J = 0.15: the ladder's
/// model error, documented in docs/vehicles.md).
#[test]
fn presets_model_no_drag_the_vehicle_does_not_have() {
    let calm = built_in("realistic-calm-1");
    for preset in VehiclePreset::ALL {
        let s = set(&calm, &[("vehicle.preset", toml::Value::String(preset.name().into()))]).unwrap();
        if preset == VehiclePreset::Hummingbird {
            assert_eq!(s.plant.drag_rotational, [5.567e-4; 3]);
            continue;
        }
        assert_eq!((s.plant.drag_translational, s.plant.drag_rotational), ([0.0; 3], [0.0; 3]), "{preset:?}");
    }
    let cf = set(&calm, &[("vehicle.preset", "crazyflie-2".into())]).unwrap();
    for c in ["ranftsmc", "tsm-sta"] {
        let out = registry::run(c, &cf, RunOptions::default()).unwrap();
        assert!(out.exit.is_completed(), "{c} on the Crazyflie: {}", out.exit);
    }
    // The same flight with the paper's drag put back diverges (what it did).
    let phantom = set(&cf, &[("plant.drag_rotational", toml::Value::try_from([5.567e-4; 3]).unwrap())]).unwrap();
    let out = registry::run("tsm-sta", &phantom, RunOptions::default()).unwrap();
    assert!(!out.exit.is_completed(), "{}", out.exit);
}

/// The published sliding-mode gains on a vehicle of another size
/// (`batch::gains_fit`): the size factor places the presets; a campaign is
/// refused when the nominal flight fails with them, names the remedies, and
/// is let through by a gain table, by `unfit_gains = "fly"`, by the
/// vehicle-derived PID defaults, or when the nominal flight succeeds.
#[test]
fn published_gains_on_another_size_are_refused_when_their_nominal_flight_fails() {
    use ftsmc_sim::batch::gains_fit::{check, size_factor, SIZE_FACTOR};
    let calm = built_in("realistic-calm-1");
    let on = |preset: &str| set(&calm, &[("vehicle.preset", toml::Value::String(preset.into()))]).unwrap();
    let names = |n: &str| vec![n.to_string()];
    assert_eq!(size_factor(&ftsmc_sim::controllers::NominalVehicle::default()), 1.0);
    assert!(size_factor(&on("hummingbird").nominal_vehicle()) <= SIZE_FACTOR);
    assert!(size_factor(&on("agilicious").nominal_vehicle()) <= SIZE_FACTOR);
    assert!(size_factor(&on("crazyflie-2").nominal_vehicle()) > SIZE_FACTOR);
    let x500 = on("px4-x500");
    assert!(size_factor(&x500.nominal_vehicle()) > SIZE_FACTOR);

    // Of the paper's size: no check, whatever the gains do.
    assert!(check(&calm, &names("ftaftsmc")).is_ok());
    // RANFTSMC's published gains leave the x500's envelope in its nominal flight.
    let e = check(&x500, &names("ranftsmc")).unwrap_err();
    let text = e.to_string();
    assert!(e.controller == "ranftsmc" && e.vehicle == "px4-x500", "{e:?}");
    for remedy in ["ftsmc tune <scenario> -c ranftsmc", "[ranftsmc]", "simulation.unfit_gains=fly"] {
        assert!(text.contains(remedy), "{text}");
    }
    // The remedies let it through.
    let fly = set(&x500, &[("simulation.unfit_gains", toml::Value::String("fly".into()))]).unwrap();
    assert!(check(&fly, &names("ranftsmc")).is_ok());
    let table = set(&x500, &[("ranftsmc.x.b1", toml::Value::Float(2.5))]).unwrap();
    assert!(check(&table, &names("ranftsmc")).is_ok());
    assert!(check(&x500, &names("pid")).is_ok(), "PID's defaults are derived from the vehicle");
    // A nominal flight that succeeds is not refused (RANFTSMC on the Crazyflie 2).
    assert!(check(&on("crazyflie-2"), &names("ranftsmc")).is_ok());
    // A bad policy is refused with its key.
    let bad = set(&x500, &[("simulation.unfit_gains", toml::Value::String("maybe".into()))]).unwrap_err();
    assert!(bad.contains("unfit_gains"), "{bad}");
}
