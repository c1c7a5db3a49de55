//! ftsmc-core's estimators on real Crazyflie 2.1 flights (NanoBench, the
//! four flights `data/fetch.sh` brings): the Mahony filter on the IMU alone
//! and the ESKF on the IMU with the Vicon position and velocity fused as
//! 10 Hz position fixes, against the Vicon attitude, beside the onboard
//! estimate the log holds (`att_stateEstimate_q*`). A measurement, printed
//! as RMS roll, pitch and yaw errors in degrees over the motors-on span;
//! the assertion is only a sanity bound (roll and pitch RMS below 8°), not
//! a claim of accuracy. The log holds the IMU at 100 Hz (the onboard
//! estimator integrates it at 1 kHz), which both filters here integrate as
//! it is; the Vicon fixes have position std 0.02 m and velocity std 0.1 m/s.
//!
//! `cargo test -p ftsmc-logs --test estimators_nanobench -- --include-ignored --nocapture`

use crate::common::data_dir;
use ftsmc_core::estimate::{Eskf, EskfConfig, GnssFix, ImuSample, InitialState, Mahony, MahonyConfig};
use ftsmc_core::kinematics::euler_from_quaternion;
use ftsmc_logs::{table::read_table, LogLimits};

const FLIGHTS: [&str; 4] =
    ["B2_circle_slow_rep1", "B3_figure8_slow_rep1", "B2_circle_fast_rep1", "B3_figure8_fast_rep1"];
const G: f64 = 9.80665;

fn wrap(a: f64) -> f64 {
    let tau = 2.0 * std::f64::consts::PI;
    a - tau * ((a + std::f64::consts::PI) / tau).floor()
}

/// RMS of the Z-Y-X Euler differences, degrees, over the rows `rows`.
fn rms_deg(est: &[[f64; 4]], truth: &[[f64; 4]], rows: &[usize]) -> [f64; 3] {
    let mut s = [0.0; 3];
    for &k in rows {
        let (e, t) = (euler_from_quaternion(&est[k]), euler_from_quaternion(&truth[k]));
        for i in 0..3 {
            s[i] += wrap(e[i] - t[i]).powi(2);
        }
    }
    s.map(|v| (v / rows.len() as f64).sqrt().to_degrees())
}

#[test]
#[ignore = "needs the samples: run data/fetch.sh (data/README.md)"]
fn mahony_and_eskf_attitude_against_vicon_on_nanobench_flights() {
    println!("flight | estimator | RMS roll, pitch, yaw (deg) over the motors-on span");
    for flight in FLIGHTS {
        let path = data_dir().join("nanobench").join(format!("{flight}.csv"));
        let table = read_table(&path, &LogLimits::default()).unwrap();
        let col = |n: &str| table.column(n).unwrap_or_else(|| panic!("{flight}: no column {n}"));
        let t = col("t");
        let [px, py, pz, vx, vy, vz] = ["px", "py", "pz", "vx", "vy", "vz"].map(col);
        let [qx, qy, qz, qw] = ["qx", "qy", "qz", "qw"].map(col);
        let [ox, oy, oz, ow] =
            ["att_stateEstimate_qx", "att_stateEstimate_qy", "att_stateEstimate_qz", "att_stateEstimate_qw"].map(col);
        let [gx, gy, gz] = ["imu_gyro_x", "imu_gyro_y", "imu_gyro_z"].map(col);
        let [ax, ay, az] = ["imu_acc_x", "imu_acc_y", "imu_acc_z"].map(col);
        let m1 = col("motor_motor_m1");
        let n = table.rows();
        let vicon: Vec<[f64; 4]> = (0..n).map(|k| [qw[k], qx[k], qy[k], qz[k]]).collect();
        let onboard: Vec<[f64; 4]> = (0..n).map(|k| [ow[k], ox[k], oy[k], oz[k]]).collect();
        let flying: Vec<usize> = (0..n).filter(|&k| m1[k] > 0.0).collect();

        let mut mahony = Mahony::new(MahonyConfig { mag_weight: 0.0, ..MahonyConfig::default() }, vicon[0]).unwrap();
        let config = EskfConfig {
            gyro_noise: 1e-2,
            accel_noise: 0.3,
            initial_position_std: 0.05,
            initial_velocity_std: 0.1,
            initial_attitude_std: 0.05,
            initial_gyro_bias_std: 0.02,
            initial_accel_bias_std: 0.3,
            ..EskfConfig::default()
        };
        let initial = InitialState {
            position: [px[0], py[0], pz[0]],
            velocity: [vx[0], vy[0], vz[0]],
            quaternion: vicon[0],
            ..InitialState::default()
        };
        let mut eskf = Eskf::new(config, initial).unwrap();
        let (mut q_mahony, mut q_eskf) = (Vec::with_capacity(n), Vec::with_capacity(n));
        let mut last_time = f64::NEG_INFINITY;
        for k in 0..n {
            let time = t[k] - t[0];
            if time > last_time {
                let imu =
                    ImuSample { time, gyro: [gx[k], gy[k], gz[k]], specific_force: [ax[k] * G, ay[k] * G, az[k] * G] };
                mahony.update(&imu, None).unwrap();
                eskf.predict(&imu).unwrap();
                if k % 10 == 0 {
                    let fix = GnssFix {
                        time,
                        position: [px[k], py[k], pz[k]],
                        velocity: [vx[k], vy[k], vz[k]],
                        position_std: [0.02; 3],
                        velocity_std: [0.1; 3],
                        valid: true,
                    };
                    eskf.update_gnss(&fix).unwrap();
                }
                last_time = time;
            }
            q_mahony.push(mahony.estimate().quaternion);
            q_eskf.push(eskf.estimate().quaternion);
        }
        let e = eskf.estimate();
        let rows = [
            ("onboard", rms_deg(&onboard, &vicon, &flying)),
            ("mahony", rms_deg(&q_mahony, &vicon, &flying)),
            ("eskf", rms_deg(&q_eskf, &vicon, &flying)),
        ];
        for (name, r) in rows {
            println!("{flight} | {name} | {:.2}, {:.2}, {:.2}", r[0], r[1], r[2]);
        }
        println!(
            "{flight} | eskf | gated-out fixes {}, final gyro bias {:?} rad/s, accel bias {:?} m/s^2",
            e.gated_out.gnss, e.gyro_bias, e.accel_bias
        );
        for (name, r) in rows {
            assert!(r[0] < 8.0 && r[1] < 8.0, "{flight} {name}: {r:?}");
        }
    }
}
