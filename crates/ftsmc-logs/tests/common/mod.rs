//! Test support: a minimal ULog writer (PX4 User Guide, "ULog File Format":
//! 16-byte header, then messages of `uint16_t size`, `uint8_t type`, body)
//! and synthetic logs built with it, so that every reader test runs on
//! bytes whose every value is known, without the third-party samples.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// Writes ULog messages into a byte vector.
pub struct UlogWriter {
    pub bytes: Vec<u8>,
    /// Offset of the end of each message written (for cuts inside one).
    pub ends: Vec<usize>,
}

impl UlogWriter {
    /// The header (version 1, start time `start_us`) and a flag-bits message.
    pub fn new(start_us: u64) -> Self {
        let mut bytes = b"ULog\x01\x12\x35".to_vec();
        bytes.push(1);
        bytes.extend_from_slice(&start_us.to_le_bytes());
        let mut w = Self { bytes, ends: Vec::new() };
        w.message(b'B', &[0u8; 40]);
        w
    }

    pub fn message(&mut self, kind: u8, body: &[u8]) {
        self.bytes.extend_from_slice(&(body.len() as u16).to_le_bytes());
        self.bytes.push(kind);
        self.bytes.extend_from_slice(body);
        self.ends.push(self.bytes.len());
    }

    /// A format definition, `name:type field;type field;…;` (each field
    /// ends with `;`, as PX4 writes them).
    pub fn format(&mut self, text: &str) {
        self.message(b'F', text.as_bytes());
    }

    pub fn param_f32(&mut self, name: &str, value: f32) {
        let key = format!("float {name}");
        let mut body = vec![key.len() as u8];
        body.extend_from_slice(key.as_bytes());
        body.extend_from_slice(&value.to_le_bytes());
        self.message(b'P', &body);
    }

    pub fn subscribe(&mut self, msg_id: u16, multi_id: u8, name: &str) {
        let mut body = vec![multi_id];
        body.extend_from_slice(&msg_id.to_le_bytes());
        body.extend_from_slice(name.as_bytes());
        self.message(b'A', &body);
    }

    pub fn data(&mut self, msg_id: u16, payload: &[u8]) {
        let mut body = msg_id.to_le_bytes().to_vec();
        body.extend_from_slice(payload);
        self.message(b'D', &body);
    }

    pub fn log_line(&mut self, timestamp_us: u64, text: &str) {
        let mut body = vec![b'6'];
        body.extend_from_slice(&timestamp_us.to_le_bytes());
        body.extend_from_slice(text.as_bytes());
        self.message(b'L', &body);
    }
}

/// Little-endian payload builder.
#[derive(Default)]
pub struct Payload(pub Vec<u8>);

impl Payload {
    pub fn u64(mut self, v: u64) -> Self {
        self.0.extend_from_slice(&v.to_le_bytes());
        self
    }
    pub fn f32(mut self, v: f32) -> Self {
        self.0.extend_from_slice(&v.to_le_bytes());
        self
    }
    pub fn i16(mut self, v: i16) -> Self {
        self.0.extend_from_slice(&v.to_le_bytes());
        self
    }
    pub fn u8(mut self, v: u8) -> Self {
        self.0.push(v);
        self
    }
}

/// One synthetic topic: its samples as (time µs, values).
pub type Samples = Vec<(u64, Vec<f32>)>;

/// What a synthetic flight logged, topic by topic.
pub struct Synthetic {
    pub writer: UlogWriter,
    pub attitude: Samples,
    pub position: Samples,
    pub sensors: Samples,
    pub motors: Samples,
    pub battery: Samples,
}

pub const ATTITUDE_ID: u16 = 0;
pub const POSITION_ID: u16 = 1;
pub const SENSORS_ID: u16 = 2;
pub const MOTORS_ID: u16 = 3;
pub const BATTERY_ID: u16 = 4;
pub const NESTED_ID: u16 = 5;

/// Options of a synthetic flight.
#[derive(Clone, Copy)]
pub struct Options {
    /// Log `vehicle_attitude`.
    pub attitude: bool,
    /// Sample of `vehicle_attitude` whose time stamp goes back 5 ms.
    pub attitude_step_back: Option<usize>,
    /// Sample of `vehicle_local_position` whose `x` is NaN.
    pub nan_position: Option<usize>,
}

impl Default for Options {
    fn default() -> Self {
        Self { attitude: true, attitude_step_back: None, nan_position: None }
    }
}

/// A 2-s flight: attitude at 100 Hz (rotation about z), local position at
/// 50 Hz, sensor_combined at 200 Hz, actuator_motors at 100 Hz (offset
/// 3 ms), battery at 10 Hz; plus a topic of a nested type. Messages are
/// written in time order, as PX4's logger does.
pub fn synthetic(options: Options) -> Synthetic {
    let mut w = UlogWriter::new(1_000_000);
    w.format("vehicle_attitude:uint64_t timestamp;float[4] q;uint8_t[4] _padding0;");
    w.format("vehicle_local_position:uint64_t timestamp;float x;float y;float z;float vx;float vy;float vz;");
    w.format("sensor_combined:uint64_t timestamp;float[3] gyro_rad;float[3] accelerometer_m_s2;");
    w.format("actuator_motors:uint64_t timestamp;float[12] control;");
    w.format("battery_status:uint64_t timestamp;float voltage_v;");
    w.format("inner_t:float a;int16_t[2] b;uint8_t[2] _padding0;");
    w.format("nested_topic:uint64_t timestamp;inner_t[2] inner;uint8_t flag;");
    w.param_f32("MC_ROLLRATE_P", 0.15);
    if options.attitude {
        w.subscribe(ATTITUDE_ID, 0, "vehicle_attitude");
    }
    w.subscribe(POSITION_ID, 0, "vehicle_local_position");
    w.subscribe(SENSORS_ID, 0, "sensor_combined");
    w.subscribe(MOTORS_ID, 0, "actuator_motors");
    w.subscribe(BATTERY_ID, 0, "battery_status");
    w.subscribe(NESTED_ID, 0, "nested_topic");
    let t0 = 2_000_000u64;
    // (position in the file, time stamp, msg_id, values): the file is in
    // nominal time order, so a stepped-back time stamp goes back in it.
    let mut events: Vec<(u64, u64, u16, Vec<f32>)> = Vec::new();
    let mut s = Synthetic {
        writer: UlogWriter { bytes: Vec::new(), ends: Vec::new() },
        attitude: Vec::new(),
        position: Vec::new(),
        sensors: Vec::new(),
        motors: Vec::new(),
        battery: Vec::new(),
    };
    for k in 0..200u64 {
        let nominal = t0 + 10_000 * k;
        let t = if options.attitude_step_back == Some(k as usize) { nominal - 15_000 } else { nominal };
        let half = 0.005 * k as f32;
        let v = vec![half.cos(), 0.0, 0.0, half.sin()];
        if options.attitude {
            s.attitude.push((t, v.clone()));
            events.push((nominal, t, ATTITUDE_ID, v));
        }
    }
    for k in 0..100u64 {
        let t = t0 + 20_000 * k + 1_000;
        let x = if options.nan_position == Some(k as usize) { f32::NAN } else { 0.01 * k as f32 };
        let v = vec![x, -0.02 * k as f32, -1.0, 0.5, -1.0, 0.0];
        s.position.push((t, v.clone()));
        events.push((t, t, POSITION_ID, v));
    }
    for k in 0..400u64 {
        let t = t0 + 5_000 * k;
        let v = vec![0.001 * k as f32, 0.0, 0.1, 0.0, 0.0, -9.81];
        s.sensors.push((t, v.clone()));
        events.push((t, t, SENSORS_ID, v));
    }
    for k in 0..200u64 {
        let t = t0 + 10_000 * k + 3_000;
        let mut v = vec![0.5 + 0.001 * k as f32, 0.51, 0.52, 0.53];
        v.extend([0.0; 8]);
        s.motors.push((t, v.clone()));
        events.push((t, t, MOTORS_ID, v));
    }
    for k in 0..20u64 {
        let t = t0 + 100_000 * k + 500;
        let v = vec![16.8 - 0.01 * k as f32];
        s.battery.push((t, v.clone()));
        events.push((t, t, BATTERY_ID, v));
    }
    for k in 0..5u64 {
        let t = t0 + 400_000 * k;
        events.push((t, t, NESTED_ID, vec![k as f32]));
    }
    events.sort_by_key(|e| e.0);
    for (k, (_, t, id, v)) in events.into_iter().enumerate() {
        if k == 10 {
            w.log_line(t, "takeoff");
        }
        let mut p = Payload::default().u64(t);
        if id == NESTED_ID {
            for i in 0..2 {
                p = p.f32(v[0] + i as f32).i16(-3).i16(i as i16).u8(0).u8(0);
            }
            p = p.u8(7);
        } else {
            for x in &v {
                p = p.f32(*x);
            }
            if id == ATTITUDE_ID {
                p = p.u8(0).u8(0).u8(0).u8(0);
            }
        }
        w.data(id, &p.0);
    }
    s.writer = w;
    s
}

/// The error of a read that must fail (a short panic message if it did not,
/// rather than the whole log).
pub fn fails<T>(result: Result<T, ftsmc_logs::LogError>) -> ftsmc_logs::LogError {
    match result {
        Ok(_) => panic!("expected an error, the read succeeded"),
        Err(e) => e,
    }
}

/// Writes `bytes` to a new file `name` in `dir`.
pub fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

/// The 51-column header of NanoBench's flight CSV files.
pub const NANOBENCH_HEADER: &str = "t,px,py,pz,qx,qy,qz,qw,roll,pitch,yaw,vx,vy,vz,wx_vicon,wy_vicon,wz_vicon,imu_acc_x,imu_acc_y,imu_acc_z,imu_gyro_x,imu_gyro_y,imu_gyro_z,motor_motor_m1,motor_motor_m2,motor_motor_m3,motor_motor_m4,est_stateEstimate_x,est_stateEstimate_y,est_stateEstimate_z,est_stateEstimate_vx,est_stateEstimate_vy,est_stateEstimate_vz,est_stateEstimate_ax,est_stateEstimate_ay,est_stateEstimate_az,att_stateEstimate_roll,att_stateEstimate_pitch,att_stateEstimate_yaw,att_stateEstimate_qx,att_stateEstimate_qy,att_stateEstimate_qz,att_stateEstimate_qw,sp_ctrltarget_x,sp_ctrltarget_y,sp_ctrltarget_z,sp_ctrltarget_yaw,pid_controller_roll,pid_controller_pitch,pid_controller_yaw,pid_controller_cmd_thrust,pwr_pm_vbat";

/// A NanoBench-format CSV of `rows` rows at 100 Hz: row `i` has `t` =
/// 1772426634 + i/100 and every other column `c` (0-based after `t`) the
/// value `c + i/1000`.
pub fn nanobench_csv(rows: usize) -> String {
    let n = NANOBENCH_HEADER.split(',').count();
    let mut s = format!("{NANOBENCH_HEADER}\n");
    for i in 0..rows {
        s += &format!("{:.9}", 1772426634.0 + i as f64 / 100.0);
        for c in 1..n {
            s += &format!(",{:.9}", c as f64 + i as f64 / 1000.0);
        }
        s.push('\n');
    }
    s
}

/// The repository's `data/` folder.
pub fn data_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data")
}
