//! A flight log in ftsmc's frames and rotor numbering.
//!
//! ftsmc's rigid body (`ftsmc_sim::vehicle::rigid_body`) has the world z
//! axis up and the body axes forward-left-up; rotors are numbered by its
//! layout (the `crazyflie-2.1` preset: 1 front-left, 2 front-right, 3
//! back-right, 4 back-left). A log is brought there:
//!
//! | log frame | position, velocity | attitude `[w,x,y,z]` | rates, accelerometer |
//! |---|---|---|---|
//! | `ZUpFlu` (NanoBench, the generic CSV with `# frame: zup-flu`) | as logged | as logged | as logged |
//! | `NedFrd` (PX4) | `(x, −y, −z)` | `(w, x, −y, −z)` | `(x, −y, −z)` |
//!
//! (the NED→z-up change is the half turn about x, `S = diag(1, −1, −1)`,
//! applied to both frames: `R' = S R S`). Motor commands become 0–1:
//! Crazyflie 16-bit PWM ÷ 65535, PX4 PWM `(µs − 1000)/1000`, normalised as
//! they are; and they are renumbered by [`MotorOrder`]. A set-point is
//! turned like a position (yaw: `−ψ` from NED).

use ftsmc_logs::{FlightLog, Frame, MotorUnit, Setpoint};

use crate::error::IdentError;

/// Which log motor each ftsmc rotor is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MotorOrder {
    /// Rotor `i` is log motor `i` (the generic CSV: ftsmc's own numbering).
    Same,
    /// Crazyflie: m1 front-right, m2 back-right, m3 back-left, m4 front-left
    /// (Bitcraze, "Crazyflie 2.x coordinate system"), so rotors 1–4 are
    /// m4, m1, m2, m3.
    Crazyflie,
    /// PX4 "Quadrotor x" (PX4 Airframe Reference): 1 front-right, 2
    /// back-left, 3 front-left, 4 back-right, so rotors 1–4 are 3, 1, 4, 2.
    Px4QuadX,
}

impl MotorOrder {
    /// Log motor index (0-based) of each ftsmc rotor.
    pub fn log_index(self) -> [usize; 4] {
        match self {
            MotorOrder::Same => [0, 1, 2, 3],
            MotorOrder::Crazyflie => [3, 0, 1, 2],
            MotorOrder::Px4QuadX => [2, 0, 3, 1],
        }
    }

    /// The order a log implies: Crazyflie 16-bit commands → Crazyflie; a
    /// PX4 (NED/FRD) log → PX4 quad-x; otherwise ftsmc's own.
    pub fn of(log: &FlightLog) -> Self {
        match (log.frame, log.motors.as_ref().map(|m| m.unit)) {
            (_, Some(MotorUnit::Crazyflie16Bit)) => MotorOrder::Crazyflie,
            (Frame::NedFrd, _) => MotorOrder::Px4QuadX,
            _ => MotorOrder::Same,
        }
    }
}

/// One flight, every channel present, in ftsmc's frames (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// The log's path.
    pub source: String,
    /// Time since the first sample, s.
    pub time_s: Vec<f64>,
    /// World position, m (zeros when the log has none: no model term uses it).
    pub position_m: Vec<[f64; 3]>,
    /// World velocity, m/s.
    pub velocity_m_s: Vec<[f64; 3]>,
    /// Attitude, body → world, `[w, x, y, z]`.
    pub attitude_wxyz: Vec<[f64; 4]>,
    /// Body rates (p, q, r), rad/s.
    pub body_rates_rad_s: Vec<[f64; 3]>,
    /// Specific force in the body frame (the accelerometer), m/s².
    pub specific_force_m_s2: Vec<[f64; 3]>,
    /// Rotor commands 0–1 in ftsmc's rotor numbering.
    pub commands: Vec<[f64; 4]>,
    /// Battery voltage, V, when logged.
    pub battery_v: Option<Vec<f64>>,
    /// How the log's motors were renumbered.
    pub order: MotorOrder,
    /// The flight controller's position set-point (world, m) and yaw
    /// set-point (rad), when logged.
    pub setpoint: Option<Setpoint>,
}

impl Series {
    /// Every log at `paths` read ([`ftsmc_logs::read_log`], default limits)
    /// and turned into a series for `purpose` ([`Series::from_log`]); the
    /// first bad log's error names its file.
    pub fn read_all<P: AsRef<std::path::Path>>(paths: &[P], purpose: &'static str) -> Result<Vec<Self>, IdentError> {
        let limits = ftsmc_logs::LogLimits::default();
        paths.iter().map(|p| Series::from_log(&ftsmc_logs::read_log(p.as_ref(), &limits)?, purpose)).collect()
    }

    /// The log in ftsmc's frames; `purpose` names the computation in the
    /// error when a channel is missing. Needs velocity, attitude, body
    /// rates, accelerometer and motors.
    pub fn from_log(log: &FlightLog, purpose: &'static str) -> Result<Self, IdentError> {
        let file = || log.source.clone();
        let missing = |channel| IdentError::MissingChannel { file: file(), channel, purpose };
        let velocity = log.velocity_m_s.as_ref().ok_or_else(|| missing("velocity"))?;
        let attitude = log.attitude_wxyz.as_ref().ok_or_else(|| missing("attitude"))?;
        let rates = log.body_rates_rad_s.as_ref().ok_or_else(|| missing("body rates (gyro)"))?;
        let accel = log.accel_m_s2.as_ref().ok_or_else(|| missing("accelerometer"))?;
        let motors = log.motors.as_ref().ok_or_else(|| missing("motor commands"))?;
        let flip = match log.frame {
            Frame::ZUpFlu => false,
            Frame::NedFrd => true,
            Frame::Unspecified => return Err(IdentError::UnspecifiedFrame { file: file() }),
        };
        let v3 = |v: &[f64; 3]| if flip { [v[0], -v[1], -v[2]] } else { *v };
        let order = MotorOrder::of(log);
        let idx = order.log_index();
        let normalise = |x: f64| match motors.unit {
            MotorUnit::Normalised => x,
            MotorUnit::PwmMicroseconds => ((x - 1000.0) / 1000.0).clamp(0.0, 1.0),
            MotorUnit::Crazyflie16Bit => x / 65535.0,
        };
        let n = log.len();
        Ok(Series {
            source: log.source.clone(),
            time_s: log.time_s.clone(),
            position_m: log.position_m.as_ref().map_or_else(|| vec![[0.0; 3]; n], |p| p.iter().map(v3).collect()),
            velocity_m_s: velocity.iter().map(v3).collect(),
            attitude_wxyz: attitude.iter().map(|q| if flip { [q[0], q[1], -q[2], -q[3]] } else { *q }).collect(),
            body_rates_rad_s: rates.iter().map(v3).collect(),
            specific_force_m_s2: accel.iter().map(v3).collect(),
            commands: motors.values.iter().map(|m| idx.map(|i| normalise(m[i]))).collect(),
            battery_v: log.battery_v.clone(),
            order,
            setpoint: log.setpoint.as_ref().map(|sp| Setpoint {
                position_m: sp.position_m.iter().map(v3).collect(),
                yaw_rad: sp.yaw_rad.iter().map(|&y| if flip { -y } else { y }).collect(),
            }),
        })
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.time_s.len()
    }

    /// No samples.
    pub fn is_empty(&self) -> bool {
        self.time_s.is_empty()
    }

    /// Every rotor command at sample `k` is at least `min` (the vehicle flies).
    pub fn flying(&self, k: usize, min: f64) -> bool {
        self.commands[k].iter().all(|&u| u >= min)
    }
}

/// Rotates a world vector into the body frame: `Rᵀ v` for the attitude `q`
/// (`[w, x, y, z]`, body → world).
pub fn world_to_body(q: &[f64; 4], v: &[f64; 3]) -> [f64; 3] {
    let r = ftsmc_sim::vehicle::rigid_body::rotation_matrix(q);
    [
        r[0][0] * v[0] + r[1][0] * v[1] + r[2][0] * v[2],
        r[0][1] * v[0] + r[1][1] * v[1] + r[2][1] * v[2],
        r[0][2] * v[0] + r[1][2] * v[1] + r[2][2] * v[2],
    ]
}
