//! The readers on synthetic logs whose every value is known: ULog topics
//! as columns (names, nesting, padding, instances), the FlightLog of a ULog
//! (zero-order hold onto the attitude time stamps), NanoBench and the
//! generic CSV (units, quaternion order, optional groups).

use crate::common::*;
use ftsmc_logs::nanobench::STANDARD_GRAVITY_M_S2;
use ftsmc_logs::ulog::{read_ulog, read_ulog_flight, UlogStream};
use ftsmc_logs::{read_log, Frame, LogLimits, MotorUnit};

#[test]
fn ulog_topics_come_out_as_named_columns_with_every_value() {
    let tmp = tempfile::tempdir().unwrap();
    let s = synthetic(Options::default());
    let path = write(tmp.path(), "flight.ulg", &s.writer.bytes);
    let data = read_ulog(&path, &LogLimits::default(), None).unwrap();
    let att = data.topic("vehicle_attitude", 0).unwrap();
    assert_eq!(att.topic.fields, ["timestamp", "q[0]", "q[1]", "q[2]", "q[3]"]);
    assert_eq!(att.time_s.len(), s.attitude.len());
    for (k, (t, v)) in s.attitude.iter().enumerate() {
        assert_eq!(att.time_s[k], *t as f64 / 1e6);
        assert_eq!(att.column("timestamp").unwrap()[k], *t as f64);
        for i in 0..4 {
            assert_eq!(att.column(&format!("q[{i}]")).unwrap()[k], f64::from(v[i]));
        }
    }
    let nested = data.topic("nested_topic", 0).unwrap();
    assert_eq!(
        nested.topic.fields,
        [
            "timestamp",
            "inner[0].a",
            "inner[0].b[0]",
            "inner[0].b[1]",
            "inner[1].a",
            "inner[1].b[0]",
            "inner[1].b[1]",
            "flag"
        ]
    );
    assert_eq!(nested.column("inner[1].a").unwrap(), [1.0, 2.0, 3.0, 4.0, 5.0]);
    assert_eq!(nested.column("inner[1].b[0]").unwrap(), [-3.0; 5]);
    assert_eq!(nested.column("inner[1].b[1]").unwrap(), [1.0; 5]);
    assert_eq!(nested.column("flag").unwrap(), [7.0; 5]);
    assert_eq!(data.parameters.get("MC_ROLLRATE_P").copied(), Some(f64::from(0.15f32)));
    let names: Vec<&str> = data.topics.iter().map(|t| t.topic.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "actuator_motors",
            "battery_status",
            "nested_topic",
            "sensor_combined",
            "vehicle_attitude",
            "vehicle_local_position"
        ]
    );
}

#[test]
fn the_stream_yields_messages_in_file_order_and_only_the_topics_asked_for() {
    let tmp = tempfile::tempdir().unwrap();
    let s = synthetic(Options::default());
    let path = write(tmp.path(), "flight.ulg", &s.writer.bytes);
    let stream = UlogStream::open(&path, &LogLimits::default(), Some(&["battery_status"])).unwrap();
    let records: Vec<_> = stream.map(Result::unwrap).collect();
    assert_eq!(records.len(), s.battery.len());
    for (r, (t, v)) in records.iter().zip(&s.battery) {
        assert_eq!(r.topic.name, "battery_status");
        assert_eq!(r.time_s, *t as f64 / 1e6);
        assert_eq!(r.values, [*t as f64, f64::from(v[0])]);
    }
    let all = UlogStream::open(&path, &LogLimits::default(), None).unwrap();
    let times: Vec<f64> = all.map(|r| r.unwrap().time_s).collect();
    assert!(times.windows(2).all(|w| w[0] <= w[1]));
    assert_eq!(times.len(), 200 + 100 + 400 + 200 + 20 + 5);
}

/// The latest sample at or before `t` (a plain scan, independent of the
/// reader's two-pointer walk).
fn latest(samples: &Samples, t: u64) -> &[f32] {
    &samples.iter().rev().find(|(ts, _)| *ts <= t).unwrap().1
}

#[test]
fn a_ulog_flight_holds_every_channel_at_its_latest_sample() {
    let tmp = tempfile::tempdir().unwrap();
    let s = synthetic(Options::default());
    let path = write(tmp.path(), "flight.ulg", &s.writer.bytes);
    let log = read_ulog_flight(&path, &LogLimits::default()).unwrap();
    assert_eq!(log.frame, Frame::NedFrd);
    // Every channel has a sample from 2.003 s (the motors' first): the
    // first attitude time stamp at or after it is 2.010 s.
    assert_eq!(log.time_origin_s, 2.01);
    let base: Vec<u64> = s.attitude.iter().map(|a| a.0).filter(|&t| t >= 2_003_000).collect();
    assert_eq!(log.len(), base.len());
    let motors = log.motors.as_ref().unwrap();
    assert_eq!(motors.unit, MotorUnit::Normalised);
    for (k, &t) in base.iter().enumerate() {
        assert_eq!(log.time_s[k], t as f64 / 1e6 - 2.01);
        let q = latest(&s.attitude, t);
        assert_eq!(log.attitude_wxyz.as_ref().unwrap()[k], [0, 1, 2, 3].map(|i| f64::from(q[i])));
        let p = latest(&s.position, t);
        assert_eq!(log.position_m.as_ref().unwrap()[k], [0, 1, 2].map(|i| f64::from(p[i])));
        assert_eq!(log.velocity_m_s.as_ref().unwrap()[k], [3, 4, 5].map(|i| f64::from(p[i])));
        let g = latest(&s.sensors, t);
        assert_eq!(log.body_rates_rad_s.as_ref().unwrap()[k], [0, 1, 2].map(|i| f64::from(g[i])));
        assert_eq!(log.accel_m_s2.as_ref().unwrap()[k], [3, 4, 5].map(|i| f64::from(g[i])));
        let m = latest(&s.motors, t);
        assert_eq!(motors.values[k], [0, 1, 2, 3].map(|i| f64::from(m[i])));
        assert_eq!(log.battery_v.as_ref().unwrap()[k], f64::from(latest(&s.battery, t)[0]));
    }
    // read_log tells ULog by its magic, whatever the file's name.
    let renamed = write(tmp.path(), "flight.bin", &s.writer.bytes);
    assert_eq!(read_log(&renamed, &LogLimits::default()).unwrap().time_s, log.time_s);
}

#[test]
fn a_nanobench_flight_is_read_in_si_units_with_the_scalar_first() {
    let tmp = tempfile::tempdir().unwrap();
    let path = write(tmp.path(), "B0_test_rep1.csv", nanobench_csv(50).as_bytes());
    let log = read_log(&path, &LogLimits::default()).unwrap();
    let names: Vec<&str> = NANOBENCH_HEADER.split(',').collect();
    let col = |name: &str, i: usize| names.iter().position(|n| *n == name).unwrap() as f64 + i as f64 / 1000.0;
    assert_eq!(log.frame, Frame::ZUpFlu);
    assert_eq!(log.len(), 50);
    assert_eq!(log.time_origin_s, 1772426634.0);
    for i in [0, 17, 49] {
        assert!((log.time_s[i] - i as f64 / 100.0).abs() < 1e-6, "{}", log.time_s[i]);
        assert_eq!(log.position_m.as_ref().unwrap()[i], [col("px", i), col("py", i), col("pz", i)]);
        assert_eq!(log.velocity_m_s.as_ref().unwrap()[i], [col("vx", i), col("vy", i), col("vz", i)]);
        assert_eq!(log.attitude_wxyz.as_ref().unwrap()[i], [col("qw", i), col("qx", i), col("qy", i), col("qz", i)]);
        assert_eq!(
            log.body_rates_rad_s.as_ref().unwrap()[i],
            [col("imu_gyro_x", i), col("imu_gyro_y", i), col("imu_gyro_z", i)]
        );
        assert_eq!(
            log.accel_m_s2.as_ref().unwrap()[i],
            [col("imu_acc_x", i), col("imu_acc_y", i), col("imu_acc_z", i)].map(|g| g * STANDARD_GRAVITY_M_S2)
        );
        let m = log.motors.as_ref().unwrap();
        assert_eq!(m.unit, MotorUnit::Crazyflie16Bit);
        assert_eq!(m.values[i], [1, 2, 3, 4].map(|k| col(&format!("motor_motor_m{k}"), i)));
        assert_eq!(log.battery_v.as_ref().unwrap()[i], col("pwr_pm_vbat", i));
    }
}

#[test]
fn the_generic_csv_reads_the_groups_it_has_and_its_frame() {
    let tmp = tempfile::tempdir().unwrap();
    let text =
        "# frame: ned-frd\n# vehicle: test\ntime_s,x_m,y_m,z_m,battery_v,extra\n10.0,1,2,3,12.5,x\n10.5,4,5,6,12.4,y\n";
    let path = write(tmp.path(), "g.csv", text.as_bytes());
    // `extra` is not a number: ignored columns must still be numbers.
    let err = read_log(&path, &LogLimits::default()).unwrap_err().to_string();
    assert!(err.contains("line 4, column `extra`: `x` is not a number"), "{err}");
    let text = text.replace(",x\n", ",0\n").replace(",y\n", ",1\n");
    let path = write(tmp.path(), "g.csv", text.as_bytes());
    let log = read_log(&path, &LogLimits::default()).unwrap();
    assert_eq!(log.frame, Frame::NedFrd);
    assert_eq!(log.time_origin_s, 10.0);
    assert_eq!(log.time_s, [0.0, 0.5]);
    assert_eq!(log.position_m, Some(vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]));
    assert_eq!(log.battery_v, Some(vec![12.5, 12.4]));
    assert_eq!(log.velocity_m_s, None);
    assert_eq!(log.attitude_wxyz, None);
    assert_eq!(log.motors, None);
    let plain = write(
        tmp.path(),
        "h.csv",
        b"time_s,qw,qx,qy,qz,motor1,motor2,motor3,motor4\n0,1,0,0,0,0.1,0.2,0.3,0.4\n1,1,0,0,0,0.5,0.6,0.7,0.8\n",
    );
    let log = read_log(&plain, &LogLimits::default()).unwrap();
    assert_eq!(log.frame, Frame::Unspecified);
    assert_eq!(log.attitude_wxyz, Some(vec![[1.0, 0.0, 0.0, 0.0]; 2]));
    let m = log.motors.unwrap();
    assert_eq!(m.unit, MotorUnit::Normalised);
    assert_eq!(m.values[1], [0.5, 0.6, 0.7, 0.8]);
}

#[test]
fn the_generic_csv_example_of_docs_logs_md_reads_as_documented() {
    let doc =
        std::fs::read_to_string(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/logs.md")).unwrap();
    let start = doc.find("```csv\n").expect("docs/logs.md has a ```csv example") + "```csv\n".len();
    let example = &doc[start..start + doc[start..].find("```").unwrap()];
    let tmp = tempfile::tempdir().unwrap();
    let log = read_log(&write(tmp.path(), "example.csv", example.as_bytes()), &LogLimits::default()).unwrap();
    assert_eq!(log.frame, Frame::NedFrd);
    assert_eq!(log.time_s, [0.0, 0.01]);
    assert_eq!(log.position_m, Some(vec![[0.0, 0.0, -1.0]; 2]));
    assert_eq!(log.attitude_wxyz, Some(vec![[1.0, 0.0, 0.0, 0.0]; 2]));
    assert_eq!(log.battery_v, Some(vec![16.4; 2]));
}
