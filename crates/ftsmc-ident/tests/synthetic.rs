//! Identification and validation on flights made by ftsmc itself
//! (`ftsmc_ident::synthetic`): the truth is known.

use ftsmc_ident::identify::{identify, IdentifyOptions};
use ftsmc_ident::series::Series;
use ftsmc_ident::synthetic::{fly, to_generic_csv, SyntheticOptions};
use ftsmc_ident::validate::{validate, ValidateOptions};
use ftsmc_ident::vehicle::Vehicle;

fn crazyflie() -> Vehicle {
    Vehicle::load("crazyflie-2.1").unwrap()
}

/// Through the generic CSV and its reader, as a user's log would come.
fn through_csv(log: &ftsmc_logs::FlightLog) -> Series {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("flight.csv");
    std::fs::write(&path, to_generic_csv(log)).unwrap();
    let read = ftsmc_logs::read_log(&path, &ftsmc_logs::LogLimits::default()).unwrap();
    Series::from_log(&read, "the test").unwrap()
}

/// The mass-free parameters' truth for `v` (module docs of `identify`).
fn truth(v: &Vehicle) -> Vec<(&'static str, f64)> {
    let b = v.body;
    let w2 = v.max_rotor_speed() * v.max_rotor_speed();
    vec![
        ("tau", v.time_constant()),
        ("thrust_per_mass_full_command", b.thrust_coefficient * w2 / b.mass),
        ("axial_drag_per_mass", b.rotor_drag_z * v.max_rotor_speed() / b.mass),
        ("rotor_drag_per_mass", b.rotor_drag_xy * v.max_rotor_speed() / b.mass),
        ("roll_moment_over_inertia", b.thrust_coefficient * w2 / b.inertia[0][0]),
        ("pitch_moment_over_inertia", b.thrust_coefficient * w2 / b.inertia[1][1]),
        ("yaw_moment_over_inertia", b.moment_coefficient * w2 / b.inertia[2][2]),
    ]
}

#[test]
fn validation_of_a_noiseless_synthetic_flight_gives_r2_one_to_round_off() {
    let v = crazyflie();
    let log = fly(&v, &SyntheticOptions { duration_s: 12.0, ..Default::default() }).unwrap();
    let s = through_csv(&log);
    let rows = validate(&[s], &v, &ValidateOptions { bootstrap: 0, ..Default::default() }).unwrap();
    assert_eq!(rows.len(), 3 * 2 * 3 * 2, "3 horizons x 2 quantities x 3 axes, flight and pooled");
    for r in &rows {
        assert!(r.n > 1000, "{r:?}");
        assert!((1.0 - r.r2).abs() < 1e-9, "{} {} {} at {} s: R² {}", r.flight, r.quantity, r.axis, r.horizon_s, r.r2);
        assert!(r.baseline_r2 < 1.0 - 1e-6, "the baseline is not the model: {r:?}");
    }
}

#[test]
fn a_wrong_vehicle_does_not_validate_to_r2_one() {
    let v = crazyflie();
    let log = fly(&v, &SyntheticOptions { duration_s: 12.0, ..Default::default() }).unwrap();
    let mut heavier = v.clone();
    heavier.body.mass *= 1.2;
    let rows =
        validate(&[through_csv(&log)], &heavier, &ValidateOptions { bootstrap: 0, ..Default::default() }).unwrap();
    let fz = rows
        .iter()
        .find(|r| r.flight == "all" && r.steps == 1 && r.quantity == "specific_force" && r.axis == "z")
        .unwrap();
    assert!(fz.r2 < 0.99, "{fz:?}");
}

/// For each mass-free parameter, the seeds whose interval holds its truth.
/// The flights are logged like NanoBench's (100 Hz) with noise of the
/// order of a Crazyflie's IMU and a motion-capture velocity; the plant is
/// integrated finely (40 substeps, 0.25 ms) so that it stands for a continuous vehicle.
fn coverage(seeds: std::ops::Range<u64>) -> (Vec<(&'static str, usize)>, Vec<String>) {
    let v = crazyflie();
    let names = truth(&v);
    let mut hits: Vec<(&'static str, usize)> = names.iter().map(|(n, _)| (*n, 0)).collect();
    let mut misses = Vec::new();
    for seed in seeds {
        let o = SyntheticOptions {
            duration_s: 30.0,
            rate_hz: 100.0,
            substeps: 40,
            accel_noise_m_s2: 0.2,
            gyro_noise_rad_s: 0.02,
            velocity_noise_m_s: 0.02,
            seed,
            ..Default::default()
        };
        let log = fly(&v, &o).unwrap();
        let s = Series::from_log(&log, "the test").unwrap();
        let id = identify(&[s], &v, &IdentifyOptions { bootstrap: 100, seed, ..Default::default() }).unwrap();
        for (j, (name, t)) in names.iter().enumerate() {
            let e = id.get(name).unwrap();
            if e.lo <= *t && *t <= e.hi {
                hits[j].1 += 1;
            } else {
                misses.push(format!(
                    "seed {seed}: {name} truth {t:.6e} outside [{:.6e}, {:.6e}] (fit {:.6e})",
                    e.lo, e.hi, e.value
                ));
            }
        }
    }
    (hits, misses)
}

fn assert_coverage(n: u64) {
    let (hits, misses) = coverage(0..n);
    for (name, h) in &hits {
        assert!(*h as u64 * 10 >= 9 * n, "{name}: truth in its interval in {h} of {n} seeds:\n{}", misses.join("\n"));
    }
}

#[test]
fn identification_recovers_the_parameters_of_a_noisy_synthetic_flight_within_its_intervals() {
    assert_coverage(50);
}

#[test]
#[ignore = "the 200-seed sweep (about a minute): cargo test -p ftsmc-ident --test synthetic -- --ignored"]
fn identification_covers_the_truth_in_90_percent_of_200_seeds() {
    assert_coverage(200);
}

/// A flight made by ftsmc's closed loop (`closed_loop::fly`, the firmware
/// PID on the `crazyflie-2.1` preset with battery compensation at 3.7 V):
/// take-off from rest, climb to 1 m, a 0.5 m circle; written as a generic
/// CSV with its set-point.
fn closed_loop_log(v: &Vehicle) -> ftsmc_logs::FlightLog {
    use ftsmc_ident::closed_loop::{fly, ClosedLoopOptions, LogController, SetpointTrack};
    let n = 1201; // 12 s at 100 Hz
    let time: Vec<f64> = (0..n).map(|k| k as f64 * 0.01).collect();
    let sp: Vec<[f64; 3]> = time
        .iter()
        .map(|&t| {
            let z = 0.05 + 0.95 * (t / 2.0).min(1.0);
            let a = if t > 3.0 { 0.8 * (t - 3.0) } else { 0.0 };
            [0.5 * ftsmc_core::math::sin(a), 0.5 - 0.5 * ftsmc_core::math::cos(a), z]
        })
        .collect();
    let yaw = vec![0.0; n];
    let battery = vec![3.7; n];
    let mut initial = [0.0; 13];
    initial[2] = 0.05;
    initial[6] = 1.0;
    let track = SetpointTrack { time_s: &time, position_m: &sp, yaw_rad: &yaw, battery_v: Some(&battery) };
    let traj = fly(v, LogController::CrazyfliePid, &initial, &track, &ClosedLoopOptions::default()).unwrap();
    assert_eq!(traj.diverged_at_s, None);
    let at = |k: usize| (k as f64 * 0.01 / 0.002).round() as usize;
    let x = |k: usize| traj.state[at(k)];
    ftsmc_logs::FlightLog {
        source: "closed-loop synthetic".into(),
        frame: ftsmc_logs::Frame::ZUpFlu,
        time_origin_s: 0.0,
        time_s: time.clone(),
        position_m: Some((0..n).map(|k| [x(k)[0], x(k)[1], x(k)[2]]).collect()),
        velocity_m_s: Some((0..n).map(|k| [x(k)[3], x(k)[4], x(k)[5]]).collect()),
        attitude_wxyz: Some((0..n).map(|k| [x(k)[6], x(k)[7], x(k)[8], x(k)[9]]).collect()),
        body_rates_rad_s: Some((0..n).map(|k| [x(k)[10], x(k)[11], x(k)[12]]).collect()),
        accel_m_s2: Some((0..n).map(|k| traj.specific_force[at(k)]).collect()),
        motors: Some(ftsmc_logs::Motors {
            unit: ftsmc_logs::MotorUnit::Normalised,
            values: (0..n).map(|k| traj.commands[at(k)]).collect(),
        }),
        battery_v: Some(battery),
        setpoint: Some(ftsmc_logs::Setpoint { position_m: sp, yaw_rad: yaw }),
    }
}

#[test]
fn closed_loop_validation_of_a_flight_flown_by_ftsmc_gives_the_real_rms_to_round_off() {
    use ftsmc_ident::closed_loop::{fly_log, table, ClosedLoopOptions, LogController};
    let v = crazyflie();
    let s = through_csv(&closed_loop_log(&v));
    let f = fly_log(&s, &v, &ClosedLoopOptions::default()).unwrap();
    assert_eq!(f.diverged_at_s, None);
    // The window is the flight at ≥ 90 % of the top set-point height: from 1.79 s on.
    assert!(f.time_s[0] > 1.7 && f.time_s[0] < 1.9, "{}", f.time_s[0]);
    assert!(f.real_rms_m > 0.01, "the flight tracks with an error: {}", f.real_rms_m);
    assert!((f.sim_rms_m - f.real_rms_m).abs() <= 1e-12, "{} vs {}", f.sim_rms_m, f.real_rms_m);
    for (a, b) in f.sim_m.iter().zip(&f.real_m) {
        for i in 0..3 {
            assert!((a[i] - b[i]).abs() <= 1e-12, "{a:?} vs {b:?}");
        }
    }
    let rows = table(&[f.clone(), f.clone()]);
    let all = rows.iter().find(|r| r.flight == "all").unwrap();
    assert_eq!((all.flights, all.difference_m), (2, 0.0));
    // Another controller, or no battery compensation, flies another flight.
    let mellinger = ClosedLoopOptions { controller: LogController::Mellinger, ..Default::default() };
    assert!((fly_log(&s, &v, &mellinger).unwrap().sim_rms_m - f.real_rms_m).abs() > 1e-3);
    let uncompensated = ClosedLoopOptions { battery_compensation: false, ..Default::default() };
    assert!((fly_log(&s, &v, &uncompensated).unwrap().sim_rms_m - f.real_rms_m).abs() > 1e-4);
}
