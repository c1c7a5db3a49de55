//! `ftsmc identify` and `ftsmc validate` on a flight made by ftsmc itself
//! (generic CSV), and their errors for bad inputs.

use std::path::Path;
use std::process::Command;

use ftsmc_ident::synthetic::{fly, to_generic_csv, SyntheticOptions};
use ftsmc_ident::vehicle::Vehicle;

fn ftsmc(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_ftsmc")).args(args).output().unwrap()
}

fn synthetic_log(dir: &Path, noise: bool) -> String {
    let v = Vehicle::load("crazyflie-2.1").unwrap();
    let o = if noise {
        SyntheticOptions {
            duration_s: 20.0,
            accel_noise_m_s2: 0.1,
            gyro_noise_rad_s: 0.01,
            seed: 3,
            ..Default::default()
        }
    } else {
        SyntheticOptions { duration_s: 12.0, ..Default::default() }
    };
    let path = dir.join(if noise { "noisy.csv" } else { "clean.csv" });
    std::fs::write(&path, to_generic_csv(&fly(&v, &o).unwrap())).unwrap();
    path.display().to_string()
}

#[test]
fn identify_writes_a_vehicle_that_validate_flies_and_validate_reproduces_a_clean_flight() {
    let dir = tempfile::tempdir().unwrap();
    let noisy = synthetic_log(dir.path(), true);
    let id_out = dir.path().join("id");
    let out = ftsmc(&[
        "identify",
        &noisy,
        "--vehicle",
        "crazyflie-2.1",
        "--bootstrap",
        "50",
        "--out",
        id_out.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let params = std::fs::read_to_string(id_out.join("parameters.csv")).unwrap();
    let tau: Vec<f64> = params
        .lines()
        .find(|l| l.starts_with("tau,"))
        .unwrap()
        .split(',')
        .skip(2)
        .take(3)
        .map(|x| x.parse().unwrap())
        .collect();
    assert!(tau[1] <= 0.072 && 0.072 <= tau[2], "tau {tau:?}");
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(id_out.join("identification.json")).unwrap()).unwrap();
    assert_eq!(json["bootstrap_replicates"], 50);
    // The vehicle file loads as a vehicle and carries the identified τ.
    let vehicle = id_out.join("vehicle.toml");
    let loaded = Vehicle::load(vehicle.to_str().unwrap()).unwrap();
    assert!((loaded.time_constant() - tau[0]).abs() < 1e-12);
    assert_eq!(loaded.body.configuration, ftsmc_sim::vehicle::Configuration::Cross, "the preset's layout is kept");

    let clean = synthetic_log(dir.path(), false);
    let val_out = dir.path().join("val");
    let out = ftsmc(&[
        "validate",
        &clean,
        "--vehicle",
        "crazyflie-2.1",
        "--bootstrap",
        "20",
        "--out",
        val_out.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let table = std::fs::read_to_string(val_out.join("validation.csv")).unwrap();
    let mut rows = 0;
    for line in table.lines().skip(1) {
        let cells: Vec<&str> = line.split(',').collect();
        let r2: f64 = cells[6].parse().unwrap();
        assert!((1.0 - r2).abs() < 1e-9, "{line}");
        rows += 1;
    }
    assert_eq!(rows, 36);
    // The identified vehicle validates on the noisy flight it came from.
    let out = ftsmc(&[
        "validate",
        &noisy,
        "--vehicle",
        vehicle.to_str().unwrap(),
        "--out",
        dir.path().join("v2").to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
}

#[test]
fn bad_inputs_get_one_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let clean = synthetic_log(dir.path(), false);
    let o = dir.path().join("o");
    let o = o.to_str().unwrap();
    let err = |args: &[&str]| {
        let out = ftsmc(args);
        assert!(!out.status.success(), "{args:?} succeeded");
        String::from_utf8_lossy(&out.stderr).to_string()
    };
    let e = err(&["validate", &clean, "--vehicle", "crazyflie-9", "--out", o]);
    assert!(e.contains("crazyflie-9") && e.contains("crazyflie-2.1"), "{e}");
    let poses = dir.path().join("poses.csv");
    std::fs::write(&poses, "# frame: zup-flu\ntime_s,x_m,y_m,z_m\n0,0,0,1\n0.01,0,0,1\n0.02,0,0,1\n").unwrap();
    let e = err(&["identify", poses.to_str().unwrap(), "--out", o]);
    assert!(e.contains("poses.csv") && e.contains("velocity") && e.contains("identification"), "{e}");
    let short = dir.path().join("short.csv");
    let text = std::fs::read_to_string(&clean).unwrap();
    std::fs::write(&short, text.lines().take(300).collect::<Vec<_>>().join("\n") + "\n").unwrap();
    let e = err(&["identify", short.to_str().unwrap(), "--out", o]);
    assert!(e.contains("short.csv") && e.contains("segment"), "{e}");
    let unstated = dir.path().join("unstated.csv");
    std::fs::write(&unstated, text.lines().skip(1).collect::<Vec<_>>().join("\n") + "\n").unwrap();
    let e = err(&["validate", unstated.to_str().unwrap(), "--vehicle", "crazyflie-2.1", "--out", o]);
    assert!(e.contains("frame"), "{e}");
    let e = err(&["identify", &clean, "--mass=-1", "--out", o]);
    assert!(e.contains("mass") && e.contains("-1"), "{e}");
}

/// `--max-delay` is flown: a synthetic flight whose logged motor commands
/// lead the ones that act by 2 log steps (a log-timing offset) identifies a
/// delay of 2 with `--max-delay 4`, and 0 with `--max-delay 0`; the τ
/// interval never goes below 0.
#[test]
fn identify_finds_a_command_delay_within_max_delay() {
    let dir = tempfile::tempdir().unwrap();
    let v = Vehicle::load("crazyflie-2.1").unwrap();
    let mut log = fly(&v, &SyntheticOptions { duration_s: 12.0, ..Default::default() }).unwrap();
    let motors = log.motors.as_mut().unwrap();
    let n = motors.values.len();
    for k in 0..n - 2 {
        motors.values[k] = motors.values[k + 2];
    }
    let path = dir.path().join("early.csv");
    std::fs::write(&path, to_generic_csv(&log)).unwrap();
    let delay_of = |max: &str| -> (f64, f64) {
        let out_dir = dir.path().join(format!("d{max}"));
        let out = ftsmc(&[
            "identify",
            path.to_str().unwrap(),
            "--vehicle",
            "crazyflie-2.1",
            "--bootstrap",
            "20",
            "--max-delay",
            max,
            "--out",
            out_dir.to_str().unwrap(),
        ]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let params = std::fs::read_to_string(out_dir.join("parameters.csv")).unwrap();
        let field = |name: &str, i: usize| -> f64 {
            let line = params.lines().find(|l| l.starts_with(name)).unwrap();
            line.split(',').nth(i).unwrap().parse().unwrap()
        };
        assert!(field("tau,", 3) >= 0.0, "{params}");
        (field("command_delay_steps,", 2), field("tau,", 2))
    };
    assert_eq!(delay_of("4").0, 2.0);
    assert_eq!(delay_of("0").0, 0.0);
}
