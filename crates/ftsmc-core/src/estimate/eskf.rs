//! Error-state Kalman filter (ESKF) of position, velocity, attitude and
//! IMU biases, after Sola 2017, *Quaternion kinematics for the error-state
//! Kalman filter*, arXiv:1711.02508 (§5 for the IMU model, §6 for the
//! updates, §6.3 for the reset), with the attitude error local (body
//! frame) and gravity known.
//!
//! # State
//!
//! Nominal state `x = (p, v, q, b_g, b_a)`: position (m, world), velocity
//! (m/s, world), attitude (unit quaternion body → world), gyro bias
//! (rad/s), accelerometer bias (m/s²). Error state
//! `δx = [δp, δv, δθ, δb_g, δb_a]` (15, layout [`super::index`]) with
//! `p_t = p + δp`, `v_t = v + δv`, `q_t = q ⊗ Exp(δθ)`, `b_t = b + δb`;
//! covariance `P = E[δx δxᵀ]`.
//!
//! # Propagation (Sola eq. 260 and 269–270)
//!
//! An IMU sample `(ω_m, a_m)` at time `t` holds over `Δt = t − t_prev`.
//! With `ω = ω_m − b_g`, `a = a_m − b_a`, `R = R(q)` and `g = [0, 0, −g₀]`:
//!
//! ```text
//! p ← p + v Δt + ½ (R a + g) Δt²      b_g ← b_g
//! v ← v + (R a + g) Δt                 b_a ← b_a
//! q ← q ⊗ Exp(ω Δt)
//! P ← F P Fᵀ + Q,   F = I + blocks:  F[δp,δv] = I Δt
//!                                    F[δv,δθ] = −R [a]× Δt,  F[δv,δb_a] = −R Δt
//!                                    F[δθ,δθ] = R(Exp(ω Δt))ᵀ, F[δθ,δb_g] = −I Δt
//! ```
//!
//! `Q = diag(0, σ_a² Δt I, σ_g² Δt I, σ_bg² Δt I, σ_ba² Δt I)`: the IMU noise
//! densities `σ_a` (m/s²/√Hz), `σ_g` (rad/s/√Hz) and the bias random walks
//! `σ_bg` (rad/s²/√Hz), `σ_ba` (m/s³/√Hz) are continuous-time white-noise
//! densities, discretised to first order over the IMU period (`Q_d ≈ G Q_c Gᵀ Δt`,
//! Sola eq. 262–265 with `σ²_discrete = σ²_density / Δt`).
//!
//! # Updates (Sola §6.1–6.3)
//!
//! A reading `z = h(x_t) + n`, `n ~ N(0, R)`, gives the innovation
//! `y = z − h(x)` and `H = ∂h/∂δx` at `δx = 0`; `S = H P Hᵀ + R`,
//! `NIS = yᵀ S⁻¹ y`, gated ([`super::gating`]); if accepted
//! `K = P Hᵀ S⁻¹`, `δx = K y`, and
//! `P ← (I − K H) P (I − K H)ᵀ + K R Kᵀ` — the Joseph form, which keeps `P`
//! symmetric positive semi-definite under rounding and is valid for any gain
//! (the short form `(I − K H) P` is not once `K` is off-optimal by
//! rounding). Then the error is injected (`p += δp`, `v += δv`,
//! `q ← q ⊗ Exp(δθ)`, `b += δb`) and the covariance reset,
//! `P ← G P Gᵀ`, `G = diag(I, I, I − [½ δθ]×, I, I)` (Sola eq. 287).
//! `P` is symmetrised (`(P + Pᵀ)/2`) after every step.
//!
//! | reading | `y` | `H` (non-zero blocks) | `R` |
//! |---|---|---|---|
//! | GNSS | `[p_m − p, v_m − v]` | `I` at `δp`, `I` at `δv` | `diag(σ_p², σ_v²)` |
//! | baro | `h_m − p_z` | `1` at `δp_z` | `σ_h²` |
//! | magnetometer (vector) | `m_b − Rᵀ m_w` | `[Rᵀ m_w]×` at `δθ` | `σ_m² I` |
//! | motion capture | `[p_m − p, Log(q* ⊗ q_m)]` | `I` at `δp`, `I` at `δθ` | `diag(σ_p² I, σ_θ² I)` |
//!
//! The magnetometer is fused as a full vector against the configured world
//! field `m_w` (so it also informs roll and pitch, weighted by its noise);
//! the motion-capture attitude residual is the rotation vector, to first
//! order in `δθ`. Barometer and magnetometer biases are not estimated.
//!
//! # Divergence
//!
//! After every step: any nominal-state component non-finite, any element
//! of `P` non-finite, a negative variance, or a variance above
//! [`EskfConfig::max_variance`] ⇒ [`EstimateError::Diverged`] with the time
//! and reason; the filter then refuses every further call with that error.

use super::gating::Gate;
use super::matrix::{self, Matrix};
use super::{
    check_finite, check_non_negative, check_positive, index, reading_finite, reading_std, ConfigError,
    DivergenceReason, Estimate, EstimateError, GatedOut, GnssFix, ImuSample, MagReading, MocapReading, UpdateKind,
    UpdateReport,
};
use super::{quaternion, BaroReading};
use crate::kinematics::{euler_from_quaternion, rotation_from_quaternion};

/// Parameters of the [`Eskf`]: IMU noise model, initial uncertainty, world
/// constants, gate and divergence bound.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Deserialize, serde::Serialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "kebab-case", deny_unknown_fields, default))]
pub struct EskfConfig {
    /// Gyro white-noise density `σ_g`, rad/s/√Hz (default 3e-3).
    pub gyro_noise: f64,
    /// Accelerometer white-noise density `σ_a`, m/s²/√Hz (default 3e-2).
    pub accel_noise: f64,
    /// Gyro-bias random walk `σ_bg`, rad/s²/√Hz (default 1e-4).
    pub gyro_bias_random_walk: f64,
    /// Accelerometer-bias random walk `σ_ba`, m/s³/√Hz (default 1e-3).
    pub accel_bias_random_walk: f64,
    /// Gravity `g₀`, m/s² (default 9.80665, the standard gravity).
    pub gravity: f64,
    /// Earth magnetic field in the world frame, unit of the magnetometer
    /// readings (default `[0.2, 0, −0.45]` gauss, a mid-latitude field with
    /// world `x` to magnetic north).
    pub magnetic_field: [f64; 3],
    /// Initial standard deviation of each position component, m (default 1).
    pub initial_position_std: f64,
    /// Initial standard deviation of each velocity component, m/s (default 0.5).
    pub initial_velocity_std: f64,
    /// Initial standard deviation of each attitude-error component, rad (default 0.1).
    pub initial_attitude_std: f64,
    /// Initial standard deviation of each gyro-bias component, rad/s (default 0.01).
    pub initial_gyro_bias_std: f64,
    /// Initial standard deviation of each accelerometer-bias component, m/s² (default 0.1).
    pub initial_accel_bias_std: f64,
    /// Gate probability `p` of the chi-square innovation gate, `0 < p < 1` (default 0.999).
    pub gate_probability: f64,
    /// Largest variance any error-state component may reach before the
    /// filter is declared diverged, in the square of that component's unit
    /// (default 1e6: a 1 km position standard deviation).
    pub max_variance: f64,
}

impl Default for EskfConfig {
    fn default() -> Self {
        Self {
            gyro_noise: 3e-3,
            accel_noise: 3e-2,
            gyro_bias_random_walk: 1e-4,
            accel_bias_random_walk: 1e-3,
            gravity: 9.80665,
            magnetic_field: [0.2, 0.0, -0.45],
            initial_position_std: 1.0,
            initial_velocity_std: 0.5,
            initial_attitude_std: 0.1,
            initial_gyro_bias_std: 0.01,
            initial_accel_bias_std: 0.1,
            gate_probability: 0.999,
            max_variance: 1e6,
        }
    }
}

impl EskfConfig {
    /// Check every field: noise densities and standard deviations finite and
    /// `> 0` (the bias random walks may be 0), the field finite and not zero,
    /// `0 < gate-probability < 1`, `max-variance > 0`.
    pub fn check(&self) -> Result<(), ConfigError> {
        check_positive("gyro-noise", self.gyro_noise)?;
        check_positive("accel-noise", self.accel_noise)?;
        check_non_negative("gyro-bias-random-walk", self.gyro_bias_random_walk)?;
        check_non_negative("accel-bias-random-walk", self.accel_bias_random_walk)?;
        check_positive("gravity", self.gravity)?;
        check_finite("magnetic-field", &self.magnetic_field)?;
        let m = self.magnetic_field;
        let n2 = m[0] * m[0] + m[1] * m[1] + m[2] * m[2];
        if n2.is_nan() || n2 <= 0.0 {
            return Err(ConfigError { field: "magnetic-field", value: n2, expected: "a non-zero vector" });
        }
        check_positive("initial-position-std", self.initial_position_std)?;
        check_positive("initial-velocity-std", self.initial_velocity_std)?;
        check_positive("initial-attitude-std", self.initial_attitude_std)?;
        check_positive("initial-gyro-bias-std", self.initial_gyro_bias_std)?;
        check_positive("initial-accel-bias-std", self.initial_accel_bias_std)?;
        let p = self.gate_probability;
        if !(p > 0.0 && p < 1.0) {
            return Err(ConfigError { field: "gate-probability", value: p, expected: "0 < p < 1" });
        }
        check_positive("max-variance", self.max_variance)?;
        Ok(())
    }

    /// The initial covariance `P₀ = diag(σ_p² I, σ_v² I, σ_θ² I, σ_bg² I, σ_ba² I)`.
    pub fn initial_covariance(&self) -> Matrix<15, 15> {
        let stds = [
            self.initial_position_std,
            self.initial_velocity_std,
            self.initial_attitude_std,
            self.initial_gyro_bias_std,
            self.initial_accel_bias_std,
        ];
        let mut p = matrix::zeros::<15, 15>();
        for (block, s) in stds.iter().enumerate() {
            for i in 0..3 {
                p[3 * block + i][3 * block + i] = s * s;
            }
        }
        p
    }
}

/// The nominal state the filter starts from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InitialState {
    /// Position, m, world frame.
    pub position: [f64; 3],
    /// Velocity, m/s, world frame.
    pub velocity: [f64; 3],
    /// Attitude, quaternion `[w, x, y, z]` body → world (normalised by the filter).
    pub quaternion: [f64; 4],
    /// Gyro bias, rad/s.
    pub gyro_bias: [f64; 3],
    /// Accelerometer bias, m/s².
    pub accel_bias: [f64; 3],
}

impl Default for InitialState {
    fn default() -> Self {
        Self {
            position: [0.0; 3],
            velocity: [0.0; 3],
            quaternion: [1.0, 0.0, 0.0, 0.0],
            gyro_bias: [0.0; 3],
            accel_bias: [0.0; 3],
        }
    }
}

/// The error-state Kalman filter (module docs for the equations).
#[derive(Clone, Debug)]
pub struct Eskf {
    config: EskfConfig,
    gate: Gate,
    position: [f64; 3],
    velocity: [f64; 3],
    quaternion: [f64; 4],
    gyro_bias: [f64; 3],
    accel_bias: [f64; 3],
    covariance: Matrix<15, 15>,
    time: Option<f64>,
    body_rate: [f64; 3],
    last_update: Option<UpdateReport>,
    gated_out: GatedOut,
    diverged: Option<EstimateError>,
}

impl Eskf {
    /// A filter at `initial` with covariance [`EskfConfig::initial_covariance`];
    /// the first IMU sample sets its time.
    pub fn new(config: EskfConfig, initial: InitialState) -> Result<Self, ConfigError> {
        config.check()?;
        check_finite("initial.position", &initial.position)?;
        check_finite("initial.velocity", &initial.velocity)?;
        check_finite("initial.quaternion", &initial.quaternion)?;
        check_finite("initial.gyro-bias", &initial.gyro_bias)?;
        check_finite("initial.accel-bias", &initial.accel_bias)?;
        let q = initial.quaternion;
        let n2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
        if n2.is_nan() || n2 <= 0.0 {
            return Err(ConfigError { field: "initial.quaternion", value: n2, expected: "a non-zero quaternion" });
        }
        Ok(Self {
            config,
            gate: Gate::new(config.gate_probability),
            position: initial.position,
            velocity: initial.velocity,
            quaternion: quaternion::normalize(&q),
            gyro_bias: initial.gyro_bias,
            accel_bias: initial.accel_bias,
            covariance: config.initial_covariance(),
            time: None,
            body_rate: [0.0; 3],
            last_update: None,
            gated_out: GatedOut::default(),
            diverged: None,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &EskfConfig {
        &self.config
    }

    /// The current estimate (nominal state, covariance, last update, gate counts).
    pub fn estimate(&self) -> Estimate {
        Estimate {
            time: self.time.unwrap_or(f64::NAN),
            position: self.position,
            velocity: self.velocity,
            quaternion: self.quaternion,
            euler: euler_from_quaternion(&self.quaternion),
            body_rate: self.body_rate,
            gyro_bias: self.gyro_bias,
            accel_bias: self.accel_bias,
            covariance: self.covariance,
            last_update: self.last_update,
            gated_out: self.gated_out,
        }
    }

    /// Propagate the nominal state and the covariance over the interval that
    /// ends at `imu.time` (Sola eq. 260, 269–270; module docs). The first
    /// sample only sets the time and the body rate.
    pub fn predict(&mut self, imu: &ImuSample) -> Result<(), EstimateError> {
        self.refuse_if_diverged()?;
        reading_finite("imu.time", &[imu.time])?;
        reading_finite("imu.gyro", &imu.gyro)?;
        reading_finite("imu.specific-force", &imu.specific_force)?;
        let Some(previous) = self.time else {
            self.time = Some(imu.time);
            self.body_rate = sub3(&imu.gyro, &self.gyro_bias);
            return Ok(());
        };
        let dt = imu.time - previous;
        if dt.is_nan() || dt <= 0.0 {
            return Err(EstimateError::TimeNotIncreasing { previous, time: imu.time });
        }
        let omega = sub3(&imu.gyro, &self.gyro_bias);
        let accel = sub3(&imu.specific_force, &self.accel_bias);
        let r = rotation_from_quaternion(&self.quaternion);
        let ra = crate::math::mat_vec(&r, &accel);
        let a_world = [ra[0], ra[1], ra[2] - self.config.gravity];
        for i in 0..3 {
            self.position[i] += self.velocity[i] * dt + 0.5 * a_world[i] * dt * dt;
            self.velocity[i] += a_world[i] * dt;
        }
        let dq = quaternion::exp(&scale3(&omega, dt));
        self.quaternion = quaternion::normalize(&quaternion::multiply(&self.quaternion, &dq));

        let f = transition_matrix(&r, &accel, &dq, dt);
        let mut p = matrix::mul_transpose(&matrix::mul(&f, &self.covariance), &f);
        let c = &self.config;
        let q_diag = [
            0.0,
            c.accel_noise * c.accel_noise * dt,
            c.gyro_noise * c.gyro_noise * dt,
            c.gyro_bias_random_walk * c.gyro_bias_random_walk * dt,
            c.accel_bias_random_walk * c.accel_bias_random_walk * dt,
        ];
        for (block, q) in q_diag.iter().enumerate() {
            for i in 0..3 {
                p[3 * block + i][3 * block + i] += q;
            }
        }
        matrix::symmetrize(&mut p);
        self.covariance = p;
        self.time = Some(imu.time);
        self.body_rate = omega;
        self.check_divergence()
    }

    /// Fuse a GNSS fix (position and velocity); `Ok(None)` when the fix is
    /// marked invalid (nothing changes).
    pub fn update_gnss(&mut self, fix: &GnssFix) -> Result<Option<UpdateReport>, EstimateError> {
        self.refuse_if_diverged()?;
        if !fix.valid {
            return Ok(None);
        }
        reading_finite("gnss.position", &fix.position)?;
        reading_finite("gnss.velocity", &fix.velocity)?;
        reading_std("gnss.position-std", &fix.position_std)?;
        reading_std("gnss.velocity-std", &fix.velocity_std)?;
        let mut y = [0.0; 6];
        let mut h = matrix::zeros::<6, 15>();
        let mut r = [0.0; 6];
        for i in 0..3 {
            y[i] = fix.position[i] - self.position[i];
            y[3 + i] = fix.velocity[i] - self.velocity[i];
            h[i][index::POSITION + i] = 1.0;
            h[3 + i][index::VELOCITY + i] = 1.0;
            r[i] = fix.position_std[i] * fix.position_std[i];
            r[3 + i] = fix.velocity_std[i] * fix.velocity_std[i];
        }
        self.update(UpdateKind::Gnss, &y, &h, &r).map(Some)
    }

    /// Fuse a barometric altitude (world `z`).
    pub fn update_baro(&mut self, baro: &BaroReading) -> Result<UpdateReport, EstimateError> {
        self.refuse_if_diverged()?;
        reading_finite("baro.altitude", &[baro.altitude])?;
        reading_std("baro.std", &[baro.std])?;
        let mut h = matrix::zeros::<1, 15>();
        h[0][index::POSITION + 2] = 1.0;
        self.update(UpdateKind::Baro, &[baro.altitude - self.position[2]], &h, &[baro.std * baro.std])
    }

    /// Fuse a magnetometer field vector against [`EskfConfig::magnetic_field`].
    pub fn update_mag(&mut self, mag: &MagReading) -> Result<UpdateReport, EstimateError> {
        self.refuse_if_diverged()?;
        reading_finite("mag.field", &mag.field)?;
        reading_std("mag.std", &[mag.std])?;
        let r = rotation_from_quaternion(&self.quaternion);
        let predicted = crate::math::mat_t_vec(&r, &self.config.magnetic_field);
        let y = sub3(&mag.field, &predicted);
        let block = matrix::skew(&predicted);
        let mut h = matrix::zeros::<3, 15>();
        for i in 0..3 {
            for j in 0..3 {
                h[i][index::ATTITUDE + j] = block[i][j];
            }
        }
        let v = mag.std * mag.std;
        self.update(UpdateKind::Mag, &y, &h, &[v; 3])
    }

    /// Fuse a motion-capture position and attitude.
    pub fn update_mocap(&mut self, mocap: &MocapReading) -> Result<UpdateReport, EstimateError> {
        self.refuse_if_diverged()?;
        reading_finite("mocap.position", &mocap.position)?;
        reading_finite("mocap.quaternion", &mocap.quaternion)?;
        reading_std("mocap.position-std", &[mocap.position_std])?;
        reading_std("mocap.attitude-std", &[mocap.attitude_std])?;
        let qm = quaternion::normalize(&mocap.quaternion);
        reading_finite("mocap.quaternion", &qm)?;
        let dtheta = quaternion::difference(&self.quaternion, &qm);
        let mut y = [0.0; 6];
        let mut h = matrix::zeros::<6, 15>();
        let mut r = [0.0; 6];
        for i in 0..3 {
            y[i] = mocap.position[i] - self.position[i];
            y[3 + i] = dtheta[i];
            h[i][index::POSITION + i] = 1.0;
            h[3 + i][index::ATTITUDE + i] = 1.0;
            r[i] = mocap.position_std * mocap.position_std;
            r[3 + i] = mocap.attitude_std * mocap.attitude_std;
        }
        self.update(UpdateKind::Mocap, &y, &h, &r)
    }

    /// The gated Kalman update, Joseph covariance, injection and reset of
    /// the module docs, for a reading of `M` components.
    fn update<const M: usize>(
        &mut self,
        kind: UpdateKind,
        y: &[f64; M],
        h: &Matrix<M, 15>,
        r: &[f64; M],
    ) -> Result<UpdateReport, EstimateError> {
        let Some(time) = self.time else {
            return Err(EstimateError::NotStarted);
        };
        let pht = matrix::mul_transpose(&self.covariance, h);
        let mut s = matrix::mul(h, &pht);
        for i in 0..M {
            s[i][i] += r[i];
        }
        matrix::symmetrize(&mut s);
        let Some(l) = matrix::cholesky(&s) else {
            return Err(self.diverge(time, DivergenceReason::NonFiniteCovariance));
        };
        let w = matrix::forward_substitute(&l, y);
        let nis = w.iter().map(|v| v * v).fold(0.0, |a, b| a + b);
        let threshold = self.gate.threshold(M);
        let mut report = UpdateReport {
            kind,
            dimension: M,
            innovation: [0.0; 6],
            innovation_std: [0.0; 6],
            nis,
            threshold,
            accepted: nis <= threshold,
        };
        for i in 0..M {
            report.innovation[i] = y[i];
            report.innovation_std[i] = crate::math::sqrt(s[i][i]);
        }
        self.last_update = Some(report);
        if !report.accepted {
            let count = match kind {
                UpdateKind::Gnss => &mut self.gated_out.gnss,
                UpdateKind::Baro => &mut self.gated_out.baro,
                UpdateKind::Mag => &mut self.gated_out.mag,
                UpdateKind::Mocap => &mut self.gated_out.mocap,
            };
            *count = count.saturating_add(1);
            return Ok(report);
        }
        // K = P Hᵀ S⁻¹ = (S⁻¹ H P)ᵀ, S symmetric.
        let gain = matrix::transpose(&matrix::cholesky_solve(&l, &matrix::transpose(&pht)));
        let dx = matrix::mat_vec(&gain, y);
        // Joseph form: (I − K H) P (I − K H)ᵀ + K R Kᵀ.
        let mut a = matrix::identity::<15>();
        let kh = matrix::mul(&gain, h);
        for i in 0..15 {
            for j in 0..15 {
                a[i][j] -= kh[i][j];
            }
        }
        let mut p = matrix::mul_transpose(&matrix::mul(&a, &self.covariance), &a);
        let mut kr = gain;
        for row in kr.iter_mut() {
            for (k, rk) in row.iter_mut().zip(r.iter()) {
                *k *= rk;
            }
        }
        let krk = matrix::mul_transpose(&kr, &gain);
        for i in 0..15 {
            for j in 0..15 {
                p[i][j] += krk[i][j];
            }
        }
        self.inject(&dx);
        // Reset (Sola eq. 287): G = diag(I, I, I − [½ δθ]×, I, I).
        let mut g = matrix::identity::<15>();
        let half = [dx[index::ATTITUDE] * 0.5, dx[index::ATTITUDE + 1] * 0.5, dx[index::ATTITUDE + 2] * 0.5];
        let sk = matrix::skew(&half);
        for i in 0..3 {
            for j in 0..3 {
                g[index::ATTITUDE + i][index::ATTITUDE + j] -= sk[i][j];
            }
        }
        let mut p = matrix::mul_transpose(&matrix::mul(&g, &p), &g);
        matrix::symmetrize(&mut p);
        self.covariance = p;
        self.check_divergence()?;
        Ok(report)
    }

    /// `x ← x ⊕ δx` (Sola eq. 283).
    fn inject(&mut self, dx: &[f64; 15]) {
        for i in 0..3 {
            self.position[i] += dx[index::POSITION + i];
            self.velocity[i] += dx[index::VELOCITY + i];
            self.gyro_bias[i] += dx[index::GYRO_BIAS + i];
            self.accel_bias[i] += dx[index::ACCEL_BIAS + i];
        }
        let dtheta = [dx[index::ATTITUDE], dx[index::ATTITUDE + 1], dx[index::ATTITUDE + 2]];
        self.quaternion = quaternion::normalize(&quaternion::multiply(&self.quaternion, &quaternion::exp(&dtheta)));
    }

    fn refuse_if_diverged(&self) -> Result<(), EstimateError> {
        match self.diverged {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    fn diverge(&mut self, time: f64, reason: DivergenceReason) -> EstimateError {
        let e = EstimateError::Diverged { time, reason };
        self.diverged = Some(e);
        e
    }

    /// The divergence checks of the module docs.
    fn check_divergence(&mut self) -> Result<(), EstimateError> {
        let time = self.time.unwrap_or(f64::NAN);
        let state_ok = [self.position, self.velocity, self.gyro_bias, self.accel_bias]
            .iter()
            .all(|v| v.iter().all(|x| x.is_finite()))
            && self.quaternion.iter().all(|x| x.is_finite());
        if !state_ok {
            return Err(self.diverge(time, DivergenceReason::NonFiniteState));
        }
        if !self.covariance.iter().all(|row| row.iter().all(|x| x.is_finite())) {
            return Err(self.diverge(time, DivergenceReason::NonFiniteCovariance));
        }
        for i in 0..15 {
            let value = self.covariance[i][i];
            if value < 0.0 {
                return Err(self.diverge(time, DivergenceReason::NegativeVariance { index: i, value }));
            }
            if value > self.config.max_variance {
                let bound = self.config.max_variance;
                return Err(self.diverge(time, DivergenceReason::VarianceBound { index: i, value, bound }));
            }
        }
        Ok(())
    }
}

/// The error-state transition `F` of one IMU step (Sola eq. 269; module
/// docs): `r = R(q)` before the step, `accel = a_m − b_a`,
/// `dq = Exp((ω_m − b_g) Δt)`.
fn transition_matrix(r: &[[f64; 3]; 3], accel: &[f64; 3], dq: &[f64; 4], dt: f64) -> Matrix<15, 15> {
    let mut f = matrix::identity::<15>();
    let ra_skew = matrix::mul(r, &matrix::skew(accel));
    let rdq = rotation_from_quaternion(dq);
    for i in 0..3 {
        f[index::POSITION + i][index::VELOCITY + i] = dt;
        f[index::ATTITUDE + i][index::GYRO_BIAS + i] = -dt;
        for j in 0..3 {
            f[index::VELOCITY + i][index::ATTITUDE + j] = -ra_skew[i][j] * dt;
            f[index::VELOCITY + i][index::ACCEL_BIAS + j] = -r[i][j] * dt;
            f[index::ATTITUDE + i][index::ATTITUDE + j] = rdq[j][i];
        }
    }
    f
}

fn sub3(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn scale3(a: &[f64; 3], k: f64) -> [f64; 3] {
    [a[0] * k, a[1] * k, a[2] * k]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bad_configuration_is_refused_naming_the_field() {
        let bad = EskfConfig { gyro_noise: -1.0, ..EskfConfig::default() };
        assert_eq!(Eskf::new(bad, InitialState::default()).unwrap_err().field, "gyro-noise");
        let bad = EskfConfig { accel_noise: f64::NAN, ..EskfConfig::default() };
        assert_eq!(Eskf::new(bad, InitialState::default()).unwrap_err().field, "accel-noise");
        let bad = EskfConfig { gate_probability: 1.0, ..EskfConfig::default() };
        assert_eq!(Eskf::new(bad, InitialState::default()).unwrap_err().field, "gate-probability");
        let bad = EskfConfig { magnetic_field: [0.0; 3], ..EskfConfig::default() };
        assert_eq!(Eskf::new(bad, InitialState::default()).unwrap_err().field, "magnetic-field");
        let zero_q = InitialState { quaternion: [0.0; 4], ..InitialState::default() };
        assert_eq!(Eskf::new(EskfConfig::default(), zero_q).unwrap_err().field, "initial.quaternion");
    }

    #[test]
    fn non_finite_and_out_of_order_readings_are_refused_and_a_blow_up_is_a_divergence() {
        let mut f = Eskf::new(EskfConfig::default(), InitialState::default()).unwrap();
        assert_eq!(f.update_baro(&BaroReading { time: 0.0, altitude: 0.0, std: 1.0 }), Err(EstimateError::NotStarted));
        let hover = ImuSample { time: 0.0, gyro: [0.0; 3], specific_force: [0.0, 0.0, 9.80665] };
        f.predict(&hover).unwrap();
        assert!(matches!(f.predict(&hover), Err(EstimateError::TimeNotIncreasing { .. })));
        let nan = ImuSample { time: 0.01, gyro: [f64::NAN, 0.0, 0.0], ..hover };
        assert!(matches!(f.predict(&nan), Err(EstimateError::BadReading { field: "imu.gyro", .. })));
        let bad_std = BaroReading { time: 0.0, altitude: 0.0, std: 0.0 };
        assert!(matches!(f.update_baro(&bad_std), Err(EstimateError::BadReading { field: "baro.std", .. })));
        // Hours without an absolute reading: the position variance passes the bound.
        let mut t = 0.0;
        let err = loop {
            t += 10.0;
            if let Err(e) = f.predict(&ImuSample { time: t, ..hover }) {
                break e;
            }
        };
        let EstimateError::Diverged { time, reason } = err else { panic!("{err:?}") };
        assert_eq!(time, t);
        assert!(matches!(reason, DivergenceReason::VarianceBound { .. }), "{reason:?}");
        assert_eq!(f.predict(&ImuSample { time: t + 1.0, ..hover }), Err(err));
    }
}
