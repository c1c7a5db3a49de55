//! Any planar rotor layout (`[vehicle] rotor_positions`): a custom layout
//! at the square "×" positions flies the "×" bit for bit (truth, mixer,
//! PX4's desaturation; the PID's normalisation agrees to 1e-12), lanes give
//! back the layout they were built from, the stretched racer's PX4 scale
//! follows its geometry, and every way to get the layout wrong is refused
//! naming the key.

use ftsmc_core::rotor_layout::RotorGeometry;
use ftsmc_sim::batch::montecarlo::{run_batch, BatchOptions};
use ftsmc_sim::controllers::px4_params;
use ftsmc_sim::scenario::Scenario;
use ftsmc_sim::vehicle::{Configuration, RigidBody, RigidBodyParams};

fn load(text: &str) -> Result<Scenario, String> {
    Scenario::from_toml_str(text, "layout.toml").map_err(|e| e.to_string())
}

/// The "×" positions of arm `l` exactly as the rigid body computes them.
fn cross_positions(l: f64) -> [[f64; 2]; 4] {
    let a = l * core::f64::consts::FRAC_1_SQRT_2;
    [[a, a], [a, -a], [-a, -a], [-a, a]]
}

fn toml_positions(p: &[[f64; 2]; 4]) -> String {
    let rows: Vec<String> = p.iter().map(|[x, y]| format!("[{x:?}, {y:?}]")).collect();
    format!("[{}]", rows.join(", "))
}

#[test]
fn custom_positions_of_the_cross_fly_the_cross_bit_for_bit() {
    // The Crazyflie 2.0 preset is a square ×; PX4's mixer so that its
    // desaturation (built from the layout's allocation) is flown too.
    let base = "extends = \"realistic-calm-1\"\nname = \"cf\"\n[vehicle]\npreset = \"crazyflie-2\"\n";
    let cross = load(&format!("{base}[actuators]\nmixer = \"px4\"\n")).unwrap();
    let l = cross.rigid_body_params().arm_length;
    let custom = load(&format!(
        "{base}rotor_positions = {}\n[actuators]\nmixer = \"px4\"\n",
        toml_positions(&cross_positions(l))
    ))
    .unwrap();
    assert_eq!(cross.rigid_body_params().configuration, Configuration::Cross);
    assert_eq!(custom.rigid_body_params().configuration, Configuration::Custom);
    assert_eq!(cross.rigid_body_params().allocation_matrix(), custom.rigid_body_params().allocation_matrix());
    let controllers = vec!["se3".to_string(), "ftaftsmc".to_string()];
    let spec = cross.montecarlo.clone().unwrap();
    let a = run_batch(&cross, &spec, &controllers, BatchOptions::new(6, 7)).unwrap();
    let b = run_batch(&custom, &spec, &controllers, BatchOptions::new(6, 7)).unwrap();
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(format!("{x:?}"), format!("{y:?}"), "a custom × flies differently from the ×");
    }
    // The PID's normalisation: the closed form of the × and the general
    // path of the same positions agree to 1e-12.
    let (_, t_cross) = px4_params::normalisation(&cross.nominal_vehicle());
    let (_, t_custom) = px4_params::normalisation(&custom.nominal_vehicle());
    for k in 0..3 {
        assert!((t_cross[k] - t_custom[k]).abs() <= 1e-12 * t_cross[k], "{t_cross:?} {t_custom:?}");
    }
}

#[test]
fn lanes_give_back_the_layout_they_fly() {
    let positions = [[0.075, 0.10], [0.075, -0.10], [-0.075, -0.10], [-0.075, 0.10]];
    let p = RigidBodyParams {
        configuration: Configuration::Custom,
        custom_positions: Some(positions),
        ..RigidBodyParams::default()
    };
    let body = RigidBody::new(p).unwrap();
    assert_eq!(body.params(), p);
    let lanes = RigidBody::<ftsmc_core::lanes::Lanes<4>>::splat(&body);
    for lane in 0..4 {
        assert_eq!(lanes.lane_params(lane), p);
    }
    assert_eq!(p.rotor_positions()[1], [0.075, -0.10, 0.0]);
}

#[test]
fn the_stretched_racer_normalises_on_its_own_geometry() {
    let s = load("extends = \"realistic-calm-1\"\nname = \"ag\"\n[vehicle]\npreset = \"agilicious\"\n").unwrap();
    let rb = s.rigid_body_params();
    assert_eq!(rb.configuration, Configuration::Custom);
    let vehicle = s.nominal_vehicle();
    assert!(matches!(vehicle.geometry, RotorGeometry::Custom { .. }));
    let (t_max, tau) = px4_params::normalisation(&vehicle);
    // Rotors at x = ±a, y = ±b: the mix's roll column is ±1/(4 T_r b), its
    // pitch column ±1/(4 T_r a); PX4 takes the larger scale for both,
    // 1/(2√2 T_r a) with the shorter arm a = 0.075 m, so a normalised
    // torque of 1 is 2√2 T_r a = √2 a T_max / 2 on roll and pitch — less
    // than the l T_max/2 of a square × of the same reach (0.125 m).
    let expected = core::f64::consts::SQRT_2 * 0.075 * t_max / 2.0;
    assert!((tau[0] - expected).abs() <= 1e-12 * expected, "{tau:?} against {expected}");
    assert!(tau[0] < 0.125 * t_max / 2.0);
    assert_eq!(tau[0], tau[1]);
}

#[test]
fn a_wrong_layout_is_refused_naming_the_key() {
    let rb = "extends = \"realistic-calm-1\"\nname = \"x\"\n[vehicle]\n";
    let cases: [(&str, &str); 6] = [
        ("rotor_positions = [[0.1, 0.1], [0.1, -0.1], [-0.1, -0.1]]\n", "3 rotor positions"),
        (
            "rotor_positions = [[0.1, 0.1, 0.0], [0.1, -0.1], [-0.1, -0.1], [-0.1, 0.1]]\n",
            "rotor position 0 has 3 numbers",
        ),
        (
            "configuration = \"plus\"\nrotor_positions = [[0.1, 0.1], [0.1, -0.1], [-0.1, -0.1], [-0.1, 0.1]]\n",
            "vehicle.configuration",
        ),
        ("configuration = \"custom\"\n", "vehicle.rotor_positions"),
        ("rotor_positions = [[0.1, 0.0], [0.2, 0.0], [-0.1, 0.0], [-0.2, 0.0]]\n", "rotor_positions"),
        ("rotor_positions = [[1e9, 0.1], [0.1, -0.1], [-0.1, -0.1], [-0.1, 0.1]]\n", "rotor_positions[0][0]"),
    ];
    for (keys, wanted) in cases {
        let e = load(&format!("{rb}{keys}")).unwrap_err();
        assert!(e.contains(wanted), "{keys}: {e}");
    }
    // On paper Eq. 1 the layout is the "+" of Eq. 2: positions are refused.
    let paper = "extends = \"paper-scenario-1\"\nname = \"p\"\n[vehicle]\nrotor_positions = [[0.1, 0.1], [0.1, -0.1], [-0.1, -0.1], [-0.1, 0.1]]\n";
    let e = load(paper).unwrap_err();
    assert!(e.contains("vehicle.rotor_positions") && e.contains("rigid-body"), "{e}");
}

#[test]
fn a_file_that_sets_the_layout_keeps_it_whole_over_a_preset() {
    // The racer's preset sets rotor_positions; a file naming it and writing
    // `configuration = "cross"` flies its own × (the preset's positions are
    // not left beside it), and one that names the square Crazyflie over a
    // base file with positions gets the Crazyflie's × whole.
    let own = load(
        "extends = \"realistic-calm-1\"\nname = \"a\"\n[vehicle]\npreset = \"agilicious\"\nconfiguration = \"cross\"\n",
    )
    .unwrap();
    assert_eq!(own.rigid_body_params().configuration, Configuration::Cross);
    assert_eq!(own.rigid_body_params().custom_positions, None);
    let dir = tempfile::tempdir().unwrap();
    let base = dir.path().join("base.toml");
    std::fs::write(&base, "extends = \"realistic-calm-1\"\nname = \"b\"\n[vehicle]\npreset = \"agilicious\"\n")
        .unwrap();
    let child = dir.path().join("child.toml");
    std::fs::write(&child, "extends = \"base.toml\"\nname = \"c\"\n[vehicle]\npreset = \"crazyflie-2\"\n").unwrap();
    let s = Scenario::from_file(&child).unwrap();
    assert_eq!(s.rigid_body_params().configuration, Configuration::Cross);
    assert_eq!(s.rigid_body_params().custom_positions, None);
}

/// `--set vehicle.preset=…` (`Scenario::with_overrides`) on the Hummingbird's
/// "+" rung flies each preset's own layout, as a file naming the preset does
/// (the "+" of the base is not left beside the racer's positions).
#[test]
fn a_preset_set_on_the_command_line_flies_its_own_layout() {
    let (file, text) = ftsmc_sim::scenario::resolve::built_in("realistic-calm-1").unwrap();
    let calm = Scenario::from_toml_str(text, file).unwrap();
    for preset in ftsmc_sim::vehicle::VehiclePreset::ALL {
        let set = calm
            .with_overrides(&[("vehicle.preset".to_string(), toml::Value::String(preset.name().into()))])
            .unwrap()
            .scenario;
        let named =
            load(&format!("extends = \"realistic-calm-1\"\nname = \"n\"\n[vehicle]\npreset = \"{}\"\n", preset.name()))
                .unwrap();
        assert_eq!(set.rigid_body_params(), named.rigid_body_params(), "{preset:?}");
        assert_eq!(set.nominal_vehicle(), named.nominal_vehicle(), "{preset:?}");
    }
}
