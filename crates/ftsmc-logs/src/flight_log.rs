//! [`FlightLog`]: one flight on one time base, whatever log it came from.
//!
//! Every channel but time is optional (a log lacks what it did not record)
//! and, when present, has one sample per time stamp. Values are kept in the
//! frames of the log they came from ([`Frame`] says which); no reader
//! rotates or filters anything. Where a log samples its signals on
//! different clocks (PX4 ULog topics), the reader holds each signal's latest
//! sample at every time stamp (zero-order hold), never interpolates.

use crate::error::LogError;

/// The axes of the world frame and of the body frame the values are in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Frame {
    /// World north-east-down, body forward-right-down: PX4's frames
    /// (PX4 User Guide, "Flight Controller/Sensor Orientation"; uORB
    /// `vehicle_local_position`, `vehicle_attitude`).
    NedFrd,
    /// World with z up (a motion-capture frame), body forward-left-up: the
    /// Crazyflie's body frame (Bitcraze, "Coordinate system") with Vicon
    /// ground truth, as in NanoBench (Ullah and Baca, arXiv:2603.09908).
    ZUpFlu,
    /// Not stated by the log (the generic CSV without a `# frame:` line).
    Unspecified,
}

/// What the motor commands are a number of.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MotorUnit {
    /// Normalised command, 0 (off) to 1 (full): PX4's `actuator_motors`
    /// and the generic CSV.
    Normalised,
    /// PWM pulse width, µs (about 1000–2000): PX4's `actuator_outputs`.
    PwmMicroseconds,
    /// The Crazyflie's 16-bit motor PWM ratio, 0–65535 (its `motor.m1`…`m4`
    /// log variables).
    Crazyflie16Bit,
}

/// Commands of the four motors, one row per time stamp.
#[derive(Clone, Debug, PartialEq)]
pub struct Motors {
    /// Unit of every value.
    pub unit: MotorUnit,
    /// Motor 1…4 of the log's own numbering (PX4 outputs 1–4; Crazyflie
    /// m1–m4).
    pub values: Vec<[f64; 4]>,
}

/// One flight: a time vector and the channels a log recorded on it.
#[derive(Clone, Debug, PartialEq)]
pub struct FlightLog {
    /// Where it came from (the path, as given).
    pub source: String,
    /// Axes of every vector and of the attitude.
    pub frame: Frame,
    /// Time of the first sample on the log's own clock, s (PX4: since boot;
    /// NanoBench: Unix time of the Vicon host).
    pub time_origin_s: f64,
    /// Time since `time_origin_s`, s: starts at 0, strictly increasing.
    pub time_s: Vec<f64>,
    /// Position of the vehicle in the world frame, m.
    pub position_m: Option<Vec<[f64; 3]>>,
    /// Velocity in the world frame, m/s.
    pub velocity_m_s: Option<Vec<[f64; 3]>>,
    /// Attitude, unit quaternion `[w, x, y, z]` (scalar first) rotating
    /// body-frame vectors into the world frame.
    pub attitude_wxyz: Option<Vec<[f64; 4]>>,
    /// Angular velocity of the body in the body frame (p, q, r), rad/s.
    pub body_rates_rad_s: Option<Vec<[f64; 3]>>,
    /// Accelerometer: specific force in the body frame, m/s² (about
    /// `[0, 0, -9.81]` at rest in FRD, `[0, 0, +9.81]` in FLU).
    pub accel_m_s2: Option<Vec<[f64; 3]>>,
    /// Motor commands.
    pub motors: Option<Motors>,
    /// Battery voltage, V.
    pub battery_v: Option<Vec<f64>>,
    /// The flight controller's position and yaw set-point, when logged.
    pub setpoint: Option<Setpoint>,
}

/// A flight controller's set-point, one row per time stamp, in the log's
/// frames ([`Frame`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Setpoint {
    /// Position set-point in the world frame, m.
    pub position_m: Vec<[f64; 3]>,
    /// Yaw (heading) set-point, rad.
    pub yaw_rad: Vec<f64>,
}

impl FlightLog {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.time_s.len()
    }

    /// No samples (never true of a log a reader returned).
    pub fn is_empty(&self) -> bool {
        self.time_s.is_empty()
    }

    /// Duration from the first sample to the last, s.
    pub fn duration_s(&self) -> f64 {
        self.time_s.last().copied().unwrap_or(0.0)
    }

    /// Checks what every reader promises: at least two samples, time
    /// strictly increasing and finite, every channel as long as time and
    /// finite. The error names the channel, the sample and the value.
    pub fn validate(&self) -> Result<(), LogError> {
        let file = || self.source.clone();
        if self.time_s.len() < 2 {
            return Err(LogError::Missing {
                file: file(),
                what: "samples".into(),
                found: format!("{} sample(s), a flight log needs at least 2", self.time_s.len()),
            });
        }
        for (i, &t) in self.time_s.iter().enumerate() {
            if !t.is_finite() {
                return Err(LogError::NotFinite { file: file(), field: "time".into(), index: i, time: t, value: t });
            }
            if i > 0 && t <= self.time_s[i - 1] {
                return Err(LogError::NonMonotonicTime {
                    file: file(),
                    channel: "time".into(),
                    index: i,
                    previous: self.time_origin_s + self.time_s[i - 1],
                    next: self.time_origin_s + t,
                });
            }
        }
        let n = self.time_s.len();
        let mut channels: Vec<(&str, Vec<&[f64]>)> = Vec::new();
        fn rows3(v: &Option<Vec<[f64; 3]>>) -> Option<Vec<&[f64]>> {
            v.as_ref().map(|v| v.iter().map(|r| &r[..]).collect())
        }
        if let Some(rows) = rows3(&self.position_m) {
            channels.push(("position", rows));
        }
        if let Some(rows) = rows3(&self.velocity_m_s) {
            channels.push(("velocity", rows));
        }
        if let Some(rows) = &self.attitude_wxyz {
            channels.push(("attitude", rows.iter().map(|r| &r[..]).collect()));
        }
        if let Some(rows) = rows3(&self.body_rates_rad_s) {
            channels.push(("body rates", rows));
        }
        if let Some(rows) = rows3(&self.accel_m_s2) {
            channels.push(("accelerometer", rows));
        }
        if let Some(m) = &self.motors {
            channels.push(("motors", m.values.iter().map(|r| &r[..]).collect()));
        }
        if let Some(v) = &self.battery_v {
            channels.push(("battery voltage", v.iter().map(std::slice::from_ref).collect()));
        }
        if let Some(sp) = &self.setpoint {
            channels.push(("position set-point", sp.position_m.iter().map(|r| &r[..]).collect()));
            channels.push(("yaw set-point", sp.yaw_rad.iter().map(std::slice::from_ref).collect()));
        }
        for (name, rows) in channels {
            if rows.len() != n {
                return Err(LogError::Malformed {
                    file: file(),
                    format: "flight log",
                    offset: 0,
                    detail: format!("{name} has {} samples, time has {n}", rows.len()),
                });
            }
            for (i, row) in rows.iter().enumerate() {
                if let Some((k, &v)) = row.iter().enumerate().find(|(_, v)| !v.is_finite()) {
                    return Err(LogError::NotFinite {
                        file: file(),
                        field: format!("{name}[{k}]"),
                        index: i,
                        time: self.time_origin_s + self.time_s[i],
                        value: v,
                    });
                }
            }
        }
        Ok(())
    }
}
