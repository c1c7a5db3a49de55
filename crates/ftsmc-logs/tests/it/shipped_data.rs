//! The flight-log samples of data/ (data/README.md): their records agree
//! with each other (always), and, once data/fetch.sh has brought the files,
//! their SHA-256 match data/SHA256SUMS and every one reads into a plausible
//! flight (the `#[ignore]`d tests: `cargo test -p ftsmc-logs --
//! --include-ignored`).

use std::collections::{BTreeMap, BTreeSet};

use crate::common::data_dir;
use ftsmc_logs::{read_log, Frame, LogLimits, MotorUnit};
use sha2::{Digest, Sha256};

/// `SHA256SUMS`: path → digest, each line checked for form.
fn sums() -> BTreeMap<String, String> {
    let text = std::fs::read_to_string(data_dir().join("SHA256SUMS")).unwrap();
    let mut sums = BTreeMap::new();
    for line in text.lines() {
        let (digest, path) =
            line.split_once("  ").unwrap_or_else(|| panic!("SHA256SUMS: `{line}` is not `<sha256>  <path>`"));
        assert!(
            digest.len() == 64 && digest.bytes().all(|b| b.is_ascii_hexdigit()),
            "SHA256SUMS: bad digest in `{line}`"
        );
        assert!(!path.starts_with('/') && !path.split('/').any(|p| p == ".."), "SHA256SUMS: `{path}` leaves data/");
        assert!(sums.insert(path.to_string(), digest.to_string()).is_none(), "SHA256SUMS lists {path} twice");
    }
    sums
}

/// `flights.csv`: path → role.
fn roles() -> BTreeMap<String, String> {
    let text = std::fs::read_to_string(data_dir().join("flights.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next().unwrap(), "path,role,repository,commit,source_path,licence,what");
    lines
        .map(|l| {
            let cells: Vec<&str> = l.split(',').collect();
            assert!(cells.len() >= 7, "flights.csv: `{l}`");
            assert_eq!(cells[5], "BSD-3-Clause", "{l}");
            assert_eq!(cells[3].len(), 40, "{l}: commit");
            (cells[0].to_string(), cells[1].to_string())
        })
        .collect()
}

#[test]
fn the_records_of_the_samples_agree_and_the_roles_are_disjoint() {
    let sums = sums();
    let roles = roles();
    let readme = std::fs::read_to_string(data_dir().join("README.md")).unwrap();
    let fetch = std::fs::read_to_string(data_dir().join("fetch.sh")).unwrap();
    for (path, role) in &roles {
        assert!(sums.contains_key(path), "{path} is in flights.csv but not in SHA256SUMS");
        assert!(readme.contains(&format!("`{path}`")), "data/README.md does not name {path}");
        let stem = path.rsplit('/').next().unwrap().trim_end_matches(".csv");
        assert!(fetch.contains(stem), "fetch.sh does not bring {path}");
        assert!(["identification", "validation", "reader-test"].contains(&role.as_str()), "{path}: role {role}");
        if path.ends_with(".csv") {
            let meta = path.replace(".csv", "_metadata.yaml");
            assert!(sums.contains_key(&meta), "SHA256SUMS lacks {meta}");
        }
    }
    for path in sums.keys().filter(|p| p.ends_with(".ulg") || p.ends_with(".csv")) {
        assert!(roles.contains_key(path), "{path} is in SHA256SUMS but not in flights.csv");
    }
    let set = |r: &str| roles.iter().filter(|(_, v)| *v == r).map(|(k, _)| k.clone()).collect::<BTreeSet<_>>();
    let (ident, valid) = (set("identification"), set("validation"));
    assert!(!ident.is_empty() && !valid.is_empty());
    assert!(ident.is_disjoint(&valid));
    assert!(sums.contains_key("ulog/LICENSE.md") && sums.contains_key("nanobench/LICENSE"));
}

#[test]
#[ignore = "needs the samples: run data/fetch.sh (data/README.md)"]
fn the_samples_match_sha256sums() {
    for (path, digest) in sums() {
        let file = data_dir().join(&path);
        let bytes = std::fs::read(&file).unwrap_or_else(|e| panic!("{}: {e} (run data/fetch.sh)", file.display()));
        let got: String = Sha256::digest(&bytes).iter().map(|b| format!("{b:02x}")).collect();
        assert_eq!(got, digest, "{path}: SHA-256 differs from data/SHA256SUMS");
    }
}

fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

#[test]
#[ignore = "needs the samples: run data/fetch.sh (data/README.md)"]
fn every_sample_reads_into_a_plausible_flight() {
    for (path, role) in roles() {
        let file = data_dir().join(&path);
        let log = read_log(&file, &LogLimits::default()).unwrap_or_else(|e| panic!("{e}"));
        let n = log.len();
        let q = log.attitude_wxyz.as_ref().unwrap();
        for row in q {
            let len = (row.iter().map(|x| x * x).sum::<f64>()).sqrt();
            assert!((len - 1.0).abs() < 1e-3, "{path}: |q| = {len}");
        }
        let accel = log.accel_m_s2.as_ref().unwrap();
        // On the ground before take-off the accelerometer reads about g.
        assert!((norm(accel[0]) - 9.81).abs() < 0.5, "{path}: |a| at start {}", norm(accel[0]));
        let motors = log.motors.as_ref().unwrap();
        if role == "reader-test" {
            assert_eq!(log.frame, Frame::NedFrd);
            assert!(n > 300 && log.duration_s() > 5.0, "{path}: {n} samples, {} s", log.duration_s());
            assert_eq!(motors.unit, MotorUnit::PwmMicroseconds);
            // PWM µs while armed, or the disarmed value (0 or about 900).
            assert!(motors.values.iter().flatten().all(|&m| (0.0..=2200.0).contains(&m)), "{path}");
            // sample_appended_multiple.ulg logged no battery_status.
            if let Some(battery) = &log.battery_v {
                assert!(battery.iter().all(|&v| (0.0..60.0).contains(&v)), "{path}");
            }
        } else {
            assert_eq!(log.frame, Frame::ZUpFlu);
            // 100 Hz, 15 s of trajectory plus take-off and landing.
            assert!((20.0..30.0).contains(&log.duration_s()), "{path}: {} s", log.duration_s());
            let dt = log.duration_s() / (n - 1) as f64;
            assert!((dt - 0.01).abs() < 1e-4, "{path}: mean step {dt} s");
            assert_eq!(motors.unit, MotorUnit::Crazyflie16Bit);
            assert!(motors.values.iter().flatten().all(|&m| (0.0..=65535.0).contains(&m)), "{path}");
            // A one-cell LiPo.
            let battery = log.battery_v.as_ref().unwrap();
            assert!(battery.iter().all(|&v| (3.0..4.3).contains(&v)), "{path}");
            // It flies at about 1 m (metadata altitude_m: 1.0).
            let top = log.position_m.as_ref().unwrap().iter().map(|p| p[2]).fold(f64::MIN, f64::max);
            assert!((0.8..1.3).contains(&top), "{path}: highest z {top} m");
        }
    }
}
