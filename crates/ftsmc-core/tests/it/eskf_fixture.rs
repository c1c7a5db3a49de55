//! The fixture of the independent cross-check
//! (`python/tests/test_eskf_crosscheck.py`, numpy, written from Sola 2017's
//! equations): a short synthetic run's readings, the configuration, and
//! this crate's ESKF output after every step, in
//! `tests/data/eskf-fixture.json`. The test regenerates the fixture and
//! fails if it differs from the committed file by one byte, so the file
//! cannot go stale silently; `FTSMC_REGEN_FIXTURES=1` rewrites it instead.
//!
//! Layout: one JSON object; `steps` holds one object per line, in order,
//! each a reading (`kind` = `imu`, `gnss`, `baro`, `mag`, `mocap`, with
//! the fields of the reading types in snake case), the update `report`
//! (innovation, NIS, threshold, accepted) for aiding readings, and the
//! `state` after the step: nominal state, gated-out total and the
//! covariance's upper triangle (row major, diagonal included, 120 values).

use crate::eskf_sim::{simulate, Event, Noise, Rates};
use ftsmc_core::estimate::{Eskf, EskfConfig, Estimate, UpdateReport};
use serde_json::{json, Value};

const FIXTURE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/eskf-fixture.json");

fn state(e: &Estimate) -> Value {
    let mut upper = Vec::with_capacity(120);
    for i in 0..15 {
        for j in i..15 {
            upper.push(e.covariance[i][j]);
        }
    }
    let g = e.gated_out;
    json!({
        "time": e.time,
        "position": e.position,
        "velocity": e.velocity,
        "quaternion": e.quaternion,
        "gyro_bias": e.gyro_bias,
        "accel_bias": e.accel_bias,
        "gated_out": g.gnss + g.baro + g.mag + g.mocap,
        "covariance_upper": upper,
    })
}

fn report(r: &UpdateReport) -> Value {
    json!({
        "innovation": &r.innovation[..r.dimension],
        "nis": r.nis,
        "threshold": r.threshold,
        "accepted": r.accepted,
    })
}

/// The fixture text: 2.5 s at 100 Hz (250 IMU samples), GNSS at 5 Hz with
/// its sixth fix moved 50 sigma (gated out), baro and mag at 10 Hz,
/// motion capture at 2 Hz.
fn fixture() -> String {
    let config = EskfConfig::default();
    let rates = Rates { imu_dt: 0.01, steps: 250, gnss_every: 20, baro_every: 10, mag_every: 10, mocap_every: 50 };
    let (initial, events) = simulate(&config, &rates, &Noise::default(), 42);
    let mut filter = Eskf::new(config, initial).unwrap();
    let mut lines = Vec::new();
    let mut fixes = 0;
    for event in &events {
        let mut step = match event {
            Event::Imu(imu, _) => {
                filter.predict(imu).unwrap();
                json!({ "kind": "imu", "time": imu.time, "gyro": imu.gyro, "specific_force": imu.specific_force })
            }
            Event::Gnss(fix) => {
                fixes += 1;
                let mut fix = *fix;
                if fixes == 6 {
                    fix.position[0] += 50.0 * fix.position_std[0];
                }
                let r = filter.update_gnss(&fix).unwrap().unwrap();
                assert_eq!(r.accepted, fixes != 6, "fix {fixes}: {r:?}");
                json!({
                    "kind": "gnss", "time": fix.time, "position": fix.position, "velocity": fix.velocity,
                    "position_std": fix.position_std, "velocity_std": fix.velocity_std, "valid": fix.valid,
                    "report": report(&r),
                })
            }
            Event::Baro(b) => {
                let r = filter.update_baro(b).unwrap();
                json!({ "kind": "baro", "time": b.time, "altitude": b.altitude, "std": b.std, "report": report(&r) })
            }
            Event::Mag(m) => {
                let r = filter.update_mag(m).unwrap();
                json!({ "kind": "mag", "time": m.time, "field": m.field, "std": m.std, "report": report(&r) })
            }
            Event::Mocap(m) => {
                let r = filter.update_mocap(m).unwrap();
                json!({
                    "kind": "mocap", "time": m.time, "position": m.position, "quaternion": m.quaternion,
                    "position_std": m.position_std, "attitude_std": m.attitude_std, "report": report(&r),
                })
            }
        };
        step["state"] = state(&filter.estimate());
        lines.push(serde_json::to_string(&step).unwrap());
    }
    let c = &config;
    let header = json!({
        "description": "ftsmc-core ESKF cross-check fixture (tests/eskf_fixture.rs): readings of a synthetic run, the configuration, and the Rust ESKF state after every step; regenerate with FTSMC_REGEN_FIXTURES=1",
        "config": {
            "gyro_noise": c.gyro_noise, "accel_noise": c.accel_noise,
            "gyro_bias_random_walk": c.gyro_bias_random_walk, "accel_bias_random_walk": c.accel_bias_random_walk,
            "gravity": c.gravity, "magnetic_field": c.magnetic_field,
            "initial_position_std": c.initial_position_std, "initial_velocity_std": c.initial_velocity_std,
            "initial_attitude_std": c.initial_attitude_std, "initial_gyro_bias_std": c.initial_gyro_bias_std,
            "initial_accel_bias_std": c.initial_accel_bias_std, "gate_probability": c.gate_probability,
            "max_variance": c.max_variance,
        },
        "initial": {
            "position": initial.position, "velocity": initial.velocity, "quaternion": initial.quaternion,
            "gyro_bias": initial.gyro_bias, "accel_bias": initial.accel_bias,
        },
    });
    let mut text = serde_json::to_string(&header).unwrap();
    text.pop(); // the closing brace: `steps` follows
    text.push_str(",\"steps\":[\n");
    text.push_str(&lines.join(",\n"));
    text.push_str("\n]}\n");
    text
}

#[test]
fn the_committed_fixture_is_what_the_estimator_gives_today() {
    let text = fixture();
    assert_eq!(text, fixture(), "two generations differ: the estimator is not deterministic");
    if std::env::var("FTSMC_REGEN_FIXTURES").is_ok_and(|v| v == "1") {
        std::fs::write(FIXTURE, &text).unwrap();
        return;
    }
    let committed = std::fs::read_to_string(FIXTURE)
        .unwrap_or_else(|e| panic!("{FIXTURE}: {e} (write it with FTSMC_REGEN_FIXTURES=1)"));
    let steps = text.lines().count();
    assert!(
        committed == text,
        "{FIXTURE} differs from the estimator's output today ({steps} lines): rerun with FTSMC_REGEN_FIXTURES=1, \
         then rerun python/tests/test_eskf_crosscheck.py"
    );
}
