//! State estimators of a quadrotor from onboard sensors: what a flight
//! controller runs when there is no motion capture (PX4's EKF2 fuses the
//! same readings). A pure library: no allocation, no I/O, `no_std`; the
//! readings come in as plain structs, the estimate goes out as one.
//!
//! - [`mahony`]: the explicit complementary attitude filter of Mahony,
//!   Hamel & Pflimlin 2008 (gyro, accelerometer, magnetometer).
//! - [`eskf`]: the 15-state error-state Kalman filter of Sola 2017 (IMU
//!   propagation; GNSS, barometer, magnetometer, motion-capture updates).
//! - [`gating`]: the chi-square innovation gate.
//! - [`quaternion`], [`matrix`]: the algebra both use.
//!
//! # Frames and units
//!
//! ftsmc's frames ([`crate::kinematics`]): the world frame has `z` up and
//! gravity `g = [0, 0, −g₀]`; attitude is the body → world unit quaternion
//! `[w, x, y, z]` and its Z-Y-X Euler angles `[φ, θ, ψ]` as
//! [`crate::Measurement`] carries them. Positions in m, velocities in m/s,
//! angular rates in rad/s (body frame), specific force `f = Rᵀ (a − g)` in
//! m/s² (body frame; `+g₀` along body `z` at hover).
//!
//! # Matrices
//!
//! Fixed-size arrays written by hand ([`matrix`]) rather than `nalgebra`:
//! the filter needs five operations on at most 15 × 15 matrices, the core
//! crate keeps a single dependency (`libm`), and every sum's order is
//! visible in the source, which is what the bit-reproducibility of ftsmc
//! rests on (no FMA, no order that depends on a SIMD width).

pub mod eskf;
pub mod gating;
pub mod mahony;
pub mod matrix;
pub mod quaternion;

pub use eskf::{Eskf, EskfConfig, InitialState};
pub use mahony::{Mahony, MahonyConfig};

/// One IMU sample: the gyro and accelerometer readings over the interval
/// that ends at `time` (held constant over it by the estimators).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ImuSample {
    /// Sample time, s.
    pub time: f64,
    /// Measured body rates `ω_m`, rad/s, body frame (true rate + bias + noise).
    pub gyro: [f64; 3],
    /// Measured specific force `a_m = Rᵀ (a − g)`, m/s², body frame (+ bias + noise).
    pub specific_force: [f64; 3],
}

/// One GNSS fix, in the world frame (z up, origin at the local reference).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GnssFix {
    /// Fix time, s (the estimators apply it at their current time).
    pub time: f64,
    /// Position, m, world frame.
    pub position: [f64; 3],
    /// Velocity, m/s, world frame.
    pub velocity: [f64; 3],
    /// Standard deviation of each position component, m (> 0).
    pub position_std: [f64; 3],
    /// Standard deviation of each velocity component, m/s (> 0).
    pub velocity_std: [f64; 3],
    /// False when the receiver has no fix (the reading is ignored).
    pub valid: bool,
}

/// One barometric altitude reading (height above the world origin).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BaroReading {
    /// Reading time, s.
    pub time: f64,
    /// Altitude, m (world `z`).
    pub altitude: f64,
    /// Standard deviation, m (> 0).
    pub std: f64,
}

/// One magnetometer reading: the Earth field seen in the body frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MagReading {
    /// Reading time, s.
    pub time: f64,
    /// Field vector, body frame, in the unit of the configured world
    /// reference field (gauss, or unit-free for a normalised field).
    pub field: [f64; 3],
    /// Standard deviation of each component, same unit (> 0).
    pub std: f64,
}

/// One motion-capture reading: position and attitude.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MocapReading {
    /// Reading time, s.
    pub time: f64,
    /// Position, m, world frame.
    pub position: [f64; 3],
    /// Attitude, unit quaternion `[w, x, y, z]`, body → world.
    pub quaternion: [f64; 4],
    /// Standard deviation of each position component, m (> 0).
    pub position_std: f64,
    /// Standard deviation of each component of the attitude error
    /// (rotation vector, body frame), rad (> 0).
    pub attitude_std: f64,
}

/// Which reading an update used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum UpdateKind {
    /// GNSS position and velocity (6 components).
    Gnss,
    /// Barometric altitude (1 component).
    Baro,
    /// Magnetometer field vector (3 components).
    Mag,
    /// Motion-capture position and attitude (6 components).
    Mocap,
}

/// What one measurement update saw: the innovation, its covariance's
/// diagonal and the NIS against the gate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UpdateReport {
    /// The reading.
    pub kind: UpdateKind,
    /// Number of components `m` (the first `m` entries below are used).
    pub dimension: usize,
    /// Innovation `y = z − h(x̂)`, in the reading's units (the attitude
    /// part of a motion-capture update is the rotation vector, rad).
    pub innovation: [f64; 6],
    /// `√diag(S)`, `S = H P Hᵀ + R`, the innovation's predicted standard deviations.
    pub innovation_std: [f64; 6],
    /// Normalised innovation squared `yᵀ S⁻¹ y` (dimensionless).
    pub nis: f64,
    /// Gate threshold `χ²_m(p)` it was compared with.
    pub threshold: f64,
    /// True when applied, false when gated out (state unchanged).
    pub accepted: bool,
}

/// Updates rejected by the gate so far, per reading.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GatedOut {
    /// GNSS fixes rejected.
    pub gnss: u32,
    /// Barometer readings rejected.
    pub baro: u32,
    /// Magnetometer readings rejected.
    pub mag: u32,
    /// Motion-capture readings rejected.
    pub mocap: u32,
}

/// The error-state vector's layout: `[δp, δv, δθ, δb_g, δb_a]`, each 3.
pub mod index {
    /// Position error `δp`, m (world).
    pub const POSITION: usize = 0;
    /// Velocity error `δv`, m/s (world).
    pub const VELOCITY: usize = 3;
    /// Attitude error `δθ`, rad (body frame, `q_t = q ⊗ Exp(δθ)`).
    pub const ATTITUDE: usize = 6;
    /// Gyro-bias error `δb_g`, rad/s.
    pub const GYRO_BIAS: usize = 9;
    /// Accelerometer-bias error `δb_a`, m/s².
    pub const ACCEL_BIAS: usize = 12;
    /// Size of the error state.
    pub const SIZE: usize = 15;
}

/// A navigation estimate: the ESKF's nominal state and its error-state
/// covariance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// Time of the last IMU sample propagated, s (NaN before the first sample).
    pub time: f64,
    /// Position `p`, m, world frame.
    pub position: [f64; 3],
    /// Velocity `v`, m/s, world frame.
    pub velocity: [f64; 3],
    /// Attitude, unit quaternion `[w, x, y, z]`, body → world.
    pub quaternion: [f64; 4],
    /// The same attitude as Z-Y-X Euler angles `[φ, θ, ψ]`, rad.
    pub euler: [f64; 3],
    /// Body rate `ω_m − b_g` of the last IMU sample, rad/s, body frame.
    pub body_rate: [f64; 3],
    /// Gyro bias `b_g`, rad/s.
    pub gyro_bias: [f64; 3],
    /// Accelerometer bias `b_a`, m/s².
    pub accel_bias: [f64; 3],
    /// Error-state covariance `P` (15 × 15, layout [`index`]).
    pub covariance: matrix::Matrix<15, 15>,
    /// The last measurement update, if any.
    pub last_update: Option<UpdateReport>,
    /// Updates rejected by the gate so far.
    pub gated_out: GatedOut,
}

impl Estimate {
    /// `√diag(P)`: the standard deviation of each error-state component
    /// (units of [`index`]).
    pub fn std_devs(&self) -> [f64; 15] {
        core::array::from_fn(|i| crate::math::sqrt(self.covariance[i][i]))
    }
}

/// An attitude estimate (the Mahony filter's output).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AttitudeEstimate {
    /// Time of the last IMU sample, s (NaN before the first sample).
    pub time: f64,
    /// Attitude, unit quaternion `[w, x, y, z]`, body → world.
    pub quaternion: [f64; 4],
    /// The same attitude as Z-Y-X Euler angles `[φ, θ, ψ]`, rad.
    pub euler: [f64; 3],
    /// Body rate `ω_m − b̂`, rad/s, body frame.
    pub body_rate: [f64; 3],
    /// Gyro bias `b̂`, rad/s.
    pub gyro_bias: [f64; 3],
}

/// Why an estimator declared itself diverged.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DivergenceReason {
    /// A component of the nominal state is NaN or infinite.
    NonFiniteState,
    /// An element of the covariance is NaN or infinite.
    NonFiniteCovariance,
    /// A variance (diagonal element `index` of `P`) is negative.
    NegativeVariance {
        /// Error-state index ([`index`]).
        index: usize,
        /// The variance.
        value: f64,
    },
    /// A variance grew beyond the configured bound.
    VarianceBound {
        /// Error-state index ([`index`]).
        index: usize,
        /// The variance, in the square of its component's unit.
        value: f64,
        /// The bound it exceeded.
        bound: f64,
    },
}

/// An error of an estimator step; the estimator is left unchanged by a
/// refused reading and stays diverged after a divergence.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EstimateError {
    /// The estimate diverged at `time` (s): a flight outcome, not a bug.
    Diverged {
        /// Time of the step that diverged, s.
        time: f64,
        /// What was seen.
        reason: DivergenceReason,
    },
    /// An IMU sample's time was not after the previous one's.
    TimeNotIncreasing {
        /// Previous sample time, s.
        previous: f64,
        /// This sample's time, s.
        time: f64,
    },
    /// A reading had a NaN or infinite value, or a non-positive standard deviation.
    BadReading {
        /// The reading's field (e.g. `"gnss.position_std"`).
        field: &'static str,
        /// The offending value.
        value: f64,
    },
    /// An update arrived before the first IMU sample set the time.
    NotStarted,
}

impl core::fmt::Display for EstimateError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Diverged { time, reason } => write!(f, "estimator diverged at t = {time} s: {reason:?}"),
            Self::TimeNotIncreasing { previous, time } => {
                write!(f, "IMU sample at t = {time} s is not after the previous one at {previous} s")
            }
            Self::BadReading { field, value } => write!(f, "reading {field} = {value} is not usable"),
            Self::NotStarted => write!(f, "update before the first IMU sample"),
        }
    }
}

/// Why an estimator configuration was rejected: the field, its value and
/// what was expected.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConfigError {
    /// Field name as written in configuration files (e.g. `"gyro-noise"`).
    pub field: &'static str,
    /// The offending value.
    pub value: f64,
    /// The range required, in words.
    pub expected: &'static str,
}

impl core::fmt::Display for ConfigError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{} = {} is out of range (expected {})", self.field, self.value, self.expected)
    }
}

/// `value` finite and `> 0`, else a [`ConfigError`] naming `field`.
pub(crate) fn check_positive(field: &'static str, value: f64) -> Result<(), ConfigError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(ConfigError { field, value, expected: "finite and > 0" })
    }
}

/// `value` finite and `≥ 0`, else a [`ConfigError`] naming `field`.
pub(crate) fn check_non_negative(field: &'static str, value: f64) -> Result<(), ConfigError> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(ConfigError { field, value, expected: "finite and >= 0" })
    }
}

/// Every element finite, else the first bad one as a [`ConfigError`].
pub(crate) fn check_finite(field: &'static str, values: &[f64]) -> Result<(), ConfigError> {
    match values.iter().find(|v| !v.is_finite()) {
        Some(&value) => Err(ConfigError { field, value, expected: "finite" }),
        None => Ok(()),
    }
}

/// A reading's values finite, else [`EstimateError::BadReading`].
pub(crate) fn reading_finite(field: &'static str, values: &[f64]) -> Result<(), EstimateError> {
    match values.iter().find(|v| !v.is_finite()) {
        Some(&value) => Err(EstimateError::BadReading { field, value }),
        None => Ok(()),
    }
}

/// A reading's standard deviations finite and `> 0`, else [`EstimateError::BadReading`].
pub(crate) fn reading_std(field: &'static str, values: &[f64]) -> Result<(), EstimateError> {
    match values.iter().find(|v| !(v.is_finite() && **v > 0.0)) {
        Some(&value) => Err(EstimateError::BadReading { field, value }),
        None => Ok(()),
    }
}
