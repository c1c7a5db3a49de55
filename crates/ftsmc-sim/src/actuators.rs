//! Actuators: rotor speed limits, first-order motor lag with separate
//! spin-up and spin-down time constants, optional motor-speed noise, and the
//! mixer that turns a commanded thrust and torques into rotor speed commands
//! under saturation.
//!
//! The pieces, in the order a run loop would use them each control period:
//!
//! 1. [`Mixer::mix`]: [`Command`] → rotor speed commands within
//!    `[ω_min, ω_max]`, plus the command actually achievable ([`MixerOutput`]).
//! 2. [`Motors::speeds_after`] / [`Motors::advance`]: the rotor speeds follow
//!    the commands through the lag, integrated exactly.
//! 3. [`Motors::sample_noise`] / [`Motors::with_noise`]: optional Gaussian
//!    noise on the speeds the plant sees, drawn from a generator the caller
//!    owns ([`motor_noise_rng`]).
//!
//! [`ActuatorParams::default`] is the ideal actuator (no limits, no lag, no
//! noise), under which the mixer reproduces the paper's Eq. 2 allocation.

use ftsmc_core::law::GainError;
use ftsmc_core::model::{Command, QuadrotorParams};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::desaturation::SequentialDesaturation;
use crate::gauss::standard_normal;

/// ChaCha stream of the motor-speed noise generator. The run loop's drag
/// noise uses streams 1–6 of the scenario seed (`environment`); motors use
/// this one, so turning motor noise on or off changes no other stream.
pub const MOTOR_NOISE_STREAM: u64 = 16;

/// The motor-noise generator of a run: `ChaCha8Rng` seeded with the run's
/// seed, stream [`MOTOR_NOISE_STREAM`].
pub fn motor_noise_rng(seed: u64) -> ChaCha8Rng {
    crate::rng::chacha_stream(seed, MOTOR_NOISE_STREAM)
}

/// How the motor-noise standard deviation is expressed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum NoiseScale {
    /// σ in rad/s: `ω_noisy = ω + σ z`.
    Absolute,
    /// σ as a fraction of the current speed: `ω_noisy = ω (1 + σ z)`.
    Relative,
}

/// Gaussian motor-speed noise, drawn once per control period and per rotor
/// (`z ~ N(0, 1)`), added to the lagged speed and clamped to the limits.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MotorNoise {
    /// Standard deviation σ: rad/s ([`NoiseScale::Absolute`]) or a fraction
    /// ([`NoiseScale::Relative`]). RotorPy's Hummingbird uses 50 rad/s absolute
    /// (`hummingbird_params.py`, `motor_noise_std`).
    pub std: f64,
    /// Absolute or relative σ.
    pub scale: NoiseScale,
}

/// How the mixer gives up authority when the rotors saturate
/// (`[actuators] mixer = "thrust-first" | "px4" | "px4-exact" |
/// "px4-exact-airmode" | "clamp"`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum MixerKind {
    /// Priority thrust, then roll/pitch, then yaw (the collective thrust is
    /// kept whenever it is feasible by itself; [`Mixer`]). Default, so the
    /// scenarios written before the PX4 mixer keep their results.
    #[default]
    ThrustFirst,
    /// PX4's own allocation with airmode off (`MC_AIRMODE` = 0, its
    /// default), step for step as `ControlAllocationSequentialDesaturation`
    /// does it ([`crate::desaturation`]): thrust only lowered, roll then
    /// pitch desaturated each on its own (the tilting torque may turn),
    /// thrust lowered by up to 0.15 of its range for yaw, then every rotor
    /// clipped. Needs a finite `max_rotor_speed`.
    Px4,
    /// PX4's priorities solved exactly (ftsmc's own allocation, not PX4's
    /// algorithm): roll and pitch are kept by **lowering** the collective
    /// thrust (never raising it); roll/pitch are scaled down together (their
    /// direction kept) only when no thrust at or below the command fits
    /// them; yaw is added last and scaled to fit; no rotor is left clipped.
    Px4Exact,
    /// As [`MixerKind::Px4Exact`], but the collective thrust may also be
    /// raised (at low throttle) to keep roll/pitch authority, PX4's
    /// `MC_AIRMODE` = 1 priorities solved exactly. Also read as `"px4-airmode"`.
    #[serde(alias = "px4-airmode")]
    Px4ExactAirmode,
    /// Paper Eq. 2 inverted and each rotor speed clamped to `[ω_min, ω_max]`
    /// on its own (thrust and torques change together; [`Mixer::mix_clamped`]).
    /// The rotors reach the clamped speeds at once: no lag, no noise. What the
    /// deprecated `simulation.max_rotor_speed` means.
    Clamp,
}

fn is_thrust_first(m: &MixerKind) -> bool {
    *m == MixerKind::ThrustFirst
}

/// Motor limits, lag and noise. Defaults: the ideal actuator — no limits
/// (`ω_min = 0`, `ω_max = ∞`), no lag (τ = 0), no noise.
///
/// Real vehicle classes (see `docs` of [`ActuatorParams::crazyflie`],
/// [`ActuatorParams::hummingbird`], [`ActuatorParams::px4_x500`]).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct ActuatorParams {
    /// Lowest rotor speed ω_min, rad/s (default 0).
    pub min_rotor_speed: f64,
    /// Highest rotor speed ω_max, rad/s (default ∞: `inf` in TOML).
    pub max_rotor_speed: f64,
    /// Spin-up time constant τ_up, s, used while `ω_cmd > ω` (default 0: no lag).
    pub time_constant_up: f64,
    /// Spin-down time constant τ_down, s, used while `ω_cmd ≤ ω` (default 0: no lag).
    pub time_constant_down: f64,
    /// Motor-speed noise (default none).
    pub noise: Option<MotorNoise>,
    /// Desaturation strategy of the mixer (default `"thrust-first"`).
    #[serde(skip_serializing_if = "is_thrust_first")]
    pub mixer: MixerKind,
}

impl Default for ActuatorParams {
    fn default() -> Self {
        Self {
            min_rotor_speed: 0.0,
            max_rotor_speed: f64::INFINITY,
            time_constant_up: 0.0,
            time_constant_down: 0.0,
            noise: None,
            mixer: MixerKind::ThrustFirst,
        }
    }
}

fn closed(field: &'static str, value: f64, lo: f64, hi: f64, expected: &'static str) -> Result<(), GainError> {
    if (lo..=hi).contains(&value) {
        Ok(())
    } else {
        Err(GainError { field, value, expected })
    }
}

impl ActuatorParams {
    /// Crazyflie 2.0 motors as RotorPy `crazyflie_params.py` gives them:
    /// τ = 0.072 s both ways (Eschmann et al. 2024), ω in `[0, 2500]` rad/s, no noise.
    pub fn crazyflie() -> Self {
        Self { max_rotor_speed: 2500.0, time_constant_up: 0.072, time_constant_down: 0.072, ..Self::default() }
    }

    /// AscTec Hummingbird motors as RotorPy `hummingbird_params.py` gives
    /// them: τ = 0.005 s both ways, ω in `[0, 1500]` rad/s, noise σ = 50 rad/s absolute.
    pub fn hummingbird() -> Self {
        Self {
            max_rotor_speed: 1500.0,
            time_constant_up: 0.005,
            time_constant_down: 0.005,
            noise: Some(MotorNoise { std: 50.0, scale: NoiseScale::Absolute }),
            ..Self::default()
        }
    }

    /// PX4 x500 (2.0 kg) motors of the Gazebo model (PX4-gazebo-models
    /// `models/x500/model.sdf`, `MulticopterMotorModel`): τ_up 0.0125 s,
    /// τ_down 0.025 s, ω_max 1000 rad/s (older `sitl_gazebo` versions had
    /// 1100), ω_min 0, no noise.
    pub fn px4_x500() -> Self {
        Self { max_rotor_speed: 1000.0, time_constant_up: 0.0125, time_constant_down: 0.025, ..Self::default() }
    }

    /// Reject non-physical values:
    ///
    /// | parameter | range |
    /// |---|---|
    /// | `min_rotor_speed` (rad/s) | `[0, 1e6]` |
    /// | `max_rotor_speed` (rad/s) | `> min_rotor_speed`, may be ∞ |
    /// | time constants (s) | `[0, 1e3]` |
    /// | noise σ | `[0, 1e6]` rad/s absolute, `[0, 10]` relative |
    pub fn check(&self) -> Result<(), GainError> {
        closed("min_rotor_speed", self.min_rotor_speed, 0.0, 1e6, "0 <= min_rotor_speed <= 1e6 rad/s")?;
        if self.max_rotor_speed.is_nan() || self.max_rotor_speed <= self.min_rotor_speed {
            return Err(GainError {
                field: "max_rotor_speed",
                value: self.max_rotor_speed,
                expected: "max_rotor_speed > min_rotor_speed (rad/s; inf for no limit)",
            });
        }
        closed("time_constant_up", self.time_constant_up, 0.0, 1e3, "0 <= time_constant_up <= 1e3 s (0: no lag)")?;
        closed(
            "time_constant_down",
            self.time_constant_down,
            0.0,
            1e3,
            "0 <= time_constant_down <= 1e3 s (0: no lag)",
        )?;
        if let Some(noise) = self.noise {
            match noise.scale {
                NoiseScale::Absolute => closed("noise.std", noise.std, 0.0, 1e6, "0 <= std <= 1e6 rad/s")?,
                NoiseScale::Relative => closed("noise.std", noise.std, 0.0, 10.0, "0 <= std <= 10 (fraction)")?,
            }
        }
        if self.mixer == MixerKind::Px4 && !self.max_rotor_speed.is_finite() {
            return Err(GainError {
                field: "mixer",
                value: self.max_rotor_speed,
                expected:
                    "mixer = \"px4\" with a finite max_rotor_speed (PX4's motor setpoints are fractions of full thrust)",
            });
        }
        if self.mixer == MixerKind::Clamp {
            if self.time_constant_up != 0.0 || self.time_constant_down != 0.0 {
                let value = self.time_constant_up.max(self.time_constant_down);
                return Err(GainError {
                    field: "mixer",
                    value,
                    expected: "mixer = \"clamp\" with time_constant_up = time_constant_down = 0 (or mixer = \"thrust-first\" for lagged motors)",
                });
            }
            if let Some(noise) = self.noise {
                return Err(GainError {
                    field: "mixer",
                    value: noise.std,
                    expected:
                        "mixer = \"clamp\" without [actuators.noise] (or mixer = \"thrust-first\" for noisy motors)",
                });
            }
        }
        Ok(())
    }

    /// Clamp a rotor speed to `[ω_min, ω_max]`.
    pub fn clamp_speed(&self, omega: f64) -> f64 {
        omega.clamp(self.min_rotor_speed, self.max_rotor_speed)
    }
}

/// The four motors' speeds and their lag.
///
/// The lag `ω̇ = (ω_cmd − ω)/τ` is integrated **exactly** over any interval
/// `dt` with the command held: `ω(t+dt) = ω_cmd + (ω(t) − ω_cmd) e^{−dt/τ}`,
/// τ = τ_up if `ω_cmd > ω(t)` and τ_down otherwise. With the command held
/// the speed moves monotonically towards it, so the choice of τ cannot
/// change within the interval and the formula is exact for any step size;
/// τ = 0 means `ω(t+dt) = ω_cmd` at once. Commands are clamped to the
/// limits first, and the speed stays inside them.
///
/// The rotor speeds inside a plant integration step are available in closed
/// form ([`Motors::speeds_after`]), so a run loop can evaluate them at each
/// RK4 stage instead of holding them over the step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Motors {
    params: ActuatorParams,
    speeds: [f64; 4],
    /// `[τ_up ≠ 0, τ_down ≠ 0]`: which direction lags (worked out once).
    lag: [bool; 2],
}

/// `v.clamp(lo, hi)` for limits known to be ordered ([`ActuatorParams::check`]):
/// `f64::clamp`'s two comparisons in its order (NaN stays NaN), without
/// its assertion on the limits.
#[cfg_attr(not(debug_assertions), inline(always))]
fn clamp_ordered(v: f64, lo: f64, hi: f64) -> f64 {
    let v = if v < lo { lo } else { v };
    if v > hi {
        hi
    } else {
        v
    }
}

impl Motors {
    /// Motors at `initial` speeds (rad/s, clamped to the limits).
    pub fn new(params: &ActuatorParams, initial: [f64; 4]) -> Self {
        let lag = [params.time_constant_up != 0.0, params.time_constant_down != 0.0];
        Self { params: *params, speeds: initial.map(|w| params.clamp_speed(w)), lag }
    }

    /// The parameters.
    pub fn params(&self) -> &ActuatorParams {
        &self.params
    }

    /// Current (noise-free) rotor speeds, rad/s.
    pub fn speeds(&self) -> [f64; 4] {
        self.speeds
    }

    /// Rotor speeds `dt ≥ 0` seconds from now with `command` (rad/s) held,
    /// without changing the motors.
    pub fn speeds_after(&self, command: &[f64; 4], dt: f64) -> [f64; 4] {
        let p = &self.params;
        core::array::from_fn(|i| {
            let target = p.clamp_speed(command[i]);
            let now = self.speeds[i];
            let tau = if target > now { p.time_constant_up } else { p.time_constant_down };
            if tau == 0.0 {
                target
            } else {
                target + (now - target) * ftsmc_core::math::exp(-dt / tau)
            }
        })
    }

    /// Advance the motors by `h` seconds with `command` (rad/s) held.
    pub fn advance(&mut self, command: &[f64; 4], h: f64) {
        self.speeds = self.speeds_after(command, h);
    }

    /// The lag's decay factors `[e^{−dt/τ_up}, e^{−dt/τ_down}]` over `dt`
    /// seconds (1 for τ = 0, where they are not used): computed once for a
    /// step size that does not change, then [`Motors::speeds_decayed`].
    pub fn decay(&self, dt: f64) -> [f64; 2] {
        let f = |tau: f64| if tau == 0.0 { 1.0 } else { ftsmc_core::math::exp(-dt / tau) };
        [f(self.params.time_constant_up), f(self.params.time_constant_down)]
    }

    /// [`Motors::speeds_after`] with the decay factors of [`Motors::decay`]
    /// for that `dt` (same formula, no exponential evaluated; each rotor
    /// without branches: the lagged value is formed and kept where the
    /// direction's τ is nonzero).
    #[inline]
    pub fn speeds_decayed(&self, command: &[f64; 4], decay: &[f64; 2]) -> [f64; 4] {
        let p = &self.params;
        let mut w = [0.0; 4];
        for i in 0..4 {
            let target = clamp_ordered(command[i], p.min_rotor_speed, p.max_rotor_speed);
            let now = self.speeds[i];
            let up = target > now;
            let e = if up { decay[0] } else { decay[1] };
            let lagged = if up { self.lag[0] } else { self.lag[1] };
            let moved = target + (now - target) * e;
            w[i] = if lagged { moved } else { target };
        }
        w
    }

    /// [`Motors::advance`] by the `dt` of `decay` ([`Motors::decay`]).
    #[inline]
    pub fn advance_decayed(&mut self, command: &[f64; 4], decay: &[f64; 2]) {
        self.speeds = self.speeds_decayed(command, decay);
    }

    /// The motors from now on with `command` (rad/s) and the noise draws `z`
    /// ([`Motors::sample_noise`]) held, prepared for [`HeldCommand::speeds`].
    #[inline]
    pub fn held(&self, command: &[f64; 4], z: &[f64; 4]) -> HeldCommand {
        let p = &self.params;
        let mut held = HeldCommand {
            target: [0.0; 4],
            gap: [0.0; 4],
            lagged: [false; 4],
            up: [false; 4],
            noise: p.noise.map(|n| match n.scale {
                NoiseScale::Absolute => (n.scale, z.map(|zi| n.std * zi)),
                NoiseScale::Relative => (n.scale, z.map(|zi| 1.0 + n.std * zi)),
            }),
            limits: [p.min_rotor_speed, p.max_rotor_speed],
        };
        for i in 0..4 {
            let target = clamp_ordered(command[i], p.min_rotor_speed, p.max_rotor_speed);
            let now = self.speeds[i];
            let up = target > now;
            held.target[i] = target;
            held.gap[i] = now - target;
            held.up[i] = up;
            held.lagged[i] = if up { self.lag[0] } else { self.lag[1] };
        }
        held
    }

    /// Draw one standard-normal sample per rotor (rotors 1..4 in order) for
    /// the next period's noise; all zeros, **without touching `rng`**, when
    /// the noise is off.
    #[inline]
    pub fn sample_noise(&self, rng: &mut ChaCha8Rng) -> [f64; 4] {
        match self.params.noise {
            Some(_) => core::array::from_fn(|_| standard_normal(rng)),
            None => [0.0; 4],
        }
    }

    /// Speeds with the noise `z` (from [`Motors::sample_noise`]) applied and
    /// clamped to the limits, rad/s; `speeds` unchanged when noise is off.
    #[inline]
    pub fn with_noise(&self, speeds: &[f64; 4], z: &[f64; 4]) -> [f64; 4] {
        match self.params.noise {
            None => *speeds,
            Some(noise) => core::array::from_fn(|i| {
                let w = match noise.scale {
                    NoiseScale::Absolute => speeds[i] + noise.std * z[i],
                    NoiseScale::Relative => speeds[i] * (1.0 + noise.std * z[i]),
                };
                self.params.clamp_speed(w)
            }),
        }
    }
}

/// The motors over one plant step with a command and the period's noise
/// held ([`Motors::held`]): the clamped command, the gap `ω − ω_cmd`, which
/// time constant applies and the noise term of each rotor, worked out once,
/// so that the speeds at each RK4 stage time ([`HeldCommand::speeds`]) are
/// one multiply-add and the noise away.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HeldCommand {
    /// Commands clamped to `[ω_min, ω_max]`, rad/s.
    pub(crate) target: [f64; 4],
    /// `ω − ω_cmd` at the start of the step, rad/s.
    pub(crate) gap: [f64; 4],
    /// The rotor lags: the time constant of its direction is nonzero (else
    /// the command is reached at once).
    pub(crate) lagged: [bool; 4],
    /// The rotor spins up (`ω_cmd > ω`: τ_up and the first decay factor;
    /// else τ_down and the second).
    pub(crate) up: [bool; 4],
    /// The noise, per rotor: `σ z` (absolute) or `1 + σ z` (relative).
    pub(crate) noise: Option<(NoiseScale, [f64; 4])>,
    /// `[ω_min, ω_max]`, rad/s.
    pub(crate) limits: [f64; 2],
}

impl HeldCommand {
    /// Rotor speeds after the `dt` of `decay` ([`Motors::decay`]), rad/s:
    /// `motors.with_noise(&motors.speeds_decayed(command, decay), z)` of the
    /// [`Motors::held`] call that made this, bit for bit.
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn speeds(&self, decay: &[f64; 2]) -> [f64; 4] {
        let [lo, hi] = self.limits;
        let mut w = self.target;
        for i in 0..4 {
            if self.lagged[i] {
                w[i] += self.gap[i] * if self.up[i] { decay[0] } else { decay[1] };
            }
        }
        match &self.noise {
            None => {}
            Some((NoiseScale::Absolute, add)) => {
                for i in 0..4 {
                    w[i] = (w[i] + add[i]).clamp(lo, hi);
                }
            }
            Some((NoiseScale::Relative, mul)) => {
                for i in 0..4 {
                    w[i] = (w[i] * mul[i]).clamp(lo, hi);
                }
            }
        }
        w
    }
}

/// What the mixer made of a command.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MixerOutput {
    /// The command asked for (non-finite components replaced by 0).
    pub commanded: Command,
    /// The command the rotor speeds produce (within rounding): equal to
    /// `commanded` unless `saturated`.
    pub applied: Command,
    /// Rotor speed commands ω_1..ω_4, rad/s, within `[ω_min, ω_max]`.
    pub rotor_speeds: [f64; 4],
    /// `true` when `applied` differs from `commanded`.
    pub saturated: bool,
}

/// Turns thrust and torques into rotor speeds under the rotor limits.
///
/// Which authority gives way first is [`MixerKind`] (`[actuators] mixer`);
/// the default, thrust first, is described here. `"px4"` is PX4's own
/// sequential desaturation ([`crate::desaturation`]). With `"px4-exact"`
/// step 1 and 2 follow PX4's priorities solved exactly: the collective thrust
/// is lowered (never raised; with `"px4-exact-airmode"` also raised) as far
/// as needed to keep roll and pitch, and roll/pitch are scaled only when no
/// such thrust exists; yaw stays last.
///
/// With `u = [U1, u2, u3, u4]` (N, N·m) and the allocation `u = A w`
/// (`w_i = ω_i²`), the squared speeds are `w = A⁻¹ u`. When every `w_i` lies
/// in `[ω_min², ω_max²]` the command is feasible and is applied unchanged.
/// Otherwise the mixer gives up authority in a fixed priority, **thrust,
/// then roll/pitch, then yaw**:
///
/// 1. Thrust: `U1` is clipped to the range it can have with zero torques
///    (`[max_i ω_min²/c_i, min_i ω_max²/c_i]`, `c = A⁻¹ e_1`; for a
///    symmetric vehicle `[4 k_f ω_min², 4 k_f ω_max²]`). It is changed only
///    when it is infeasible by itself.
/// 2. Roll and pitch: scaled together by the largest `s_rp ∈ [0, 1]` that
///    keeps every `w_i` in range with that thrust and no yaw torque (the
///    direction of the tilting torque is kept).
/// 3. Yaw: scaled by the largest `s_y ∈ [0, 1]` that keeps every `w_i` in
///    range on top of steps 1–2.
///
/// Each step is the exact maximisation of one scale factor over an interval
/// (the squared speeds are affine in it), so the result is the
/// lexicographic optimum for this priority: thrust and roll/pitch are kept
/// exactly whenever that is possible, yaw is the first to give way. (PX4's
/// "airmode" instead lowers collective thrust to keep roll/pitch authority
/// near full throttle; not implemented.) Non-finite command components are
/// treated as 0 and flag the output as saturated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mixer {
    allocation: [[f64; 4]; 4],
    inverse: [[f64; 4]; 4],
    /// The columns of `inverse` (`columns[k][i] = inverse[i][k]`): the
    /// squared speeds `A⁻¹ u` as four columns scaled and added, each
    /// rotor's sum in the order of its row (the compiler works on several
    /// rotors at once).
    columns: [[f64; 4]; 4],
    w_min: f64,
    w_max: f64,
    thrust_range: [f64; 2],
    kind: MixerKind,
    /// PX4's allocation, for [`MixerKind::Px4`].
    px4: Option<SequentialDesaturation>,
}

/// Paper Eq. 2 as a matrix (`[U1, u2, u3, u4]ᵀ = A [ω1², .., ω4²]ᵀ`).
pub fn paper_allocation_matrix(p: &QuadrotorParams) -> [[f64; 4]; 4] {
    let b = p.lift_coefficient;
    let bl = b * p.arm_length;
    let d = p.yaw_drag_coefficient;
    [[b, b, b, b], [0.0, -bl, 0.0, bl], [-bl, 0.0, bl, 0.0], [d, -d, d, -d]]
}

impl Mixer {
    /// A mixer for the allocation `u = A w` (rows U1, u2, u3, u4; columns
    /// rotors 1..4; e.g. `RigidBodyParams::allocation_matrix` or
    /// [`paper_allocation_matrix`]) and the rotor limits of `actuators`.
    /// Errors if the limits are invalid, `A` is singular, or some rotor does
    /// not carry a positive share of the thrust.
    pub fn new(allocation: [[f64; 4]; 4], actuators: &ActuatorParams) -> Result<Self, GainError> {
        actuators.check()?;
        let inverse = ftsmc_core::rotor_layout::invert4(&allocation).ok_or(GainError {
            field: "allocation",
            value: allocation[0][0],
            expected: "an invertible allocation matrix",
        })?;
        let w_min = actuators.min_rotor_speed * actuators.min_rotor_speed;
        let w_max = actuators.max_rotor_speed * actuators.max_rotor_speed;
        let mut thrust_range = [0.0f64, f64::INFINITY];
        for row in &inverse {
            let c = row[0];
            if c.is_nan() || c <= 0.0 {
                return Err(GainError {
                    field: "allocation",
                    value: c,
                    expected: "every rotor carries a positive share of the thrust",
                });
            }
            thrust_range[0] = thrust_range[0].max(w_min / c);
            thrust_range[1] = thrust_range[1].min(w_max / c);
        }
        if thrust_range[0] > thrust_range[1] {
            return Err(GainError {
                field: "min_rotor_speed",
                value: actuators.min_rotor_speed,
                expected: "a speed range wide enough for some torque-free thrust",
            });
        }
        let columns = core::array::from_fn(|k| core::array::from_fn(|i| inverse[i][k]));
        let px4 = (actuators.mixer == MixerKind::Px4).then(|| SequentialDesaturation::new(&inverse, w_min, w_max));
        Ok(Self { allocation, inverse, columns, w_min, w_max, thrust_range, kind: actuators.mixer, px4 })
    }

    /// The mixer of paper Eq. 2 ([`paper_allocation_matrix`]).
    pub fn for_paper(p: &QuadrotorParams, actuators: &ActuatorParams) -> Result<Self, GainError> {
        Self::new(paper_allocation_matrix(p), actuators)
    }

    /// Collective thrust range with zero torques `[U1_min, U1_max]`, N.
    pub fn thrust_range(&self) -> [f64; 2] {
        self.thrust_range
    }

    /// Thrust and torques of squared rotor speeds (`A w`).
    pub fn forces(&self, squared_speeds: &[f64; 4]) -> Command {
        let row = |k: usize| (0..4).map(|i| self.allocation[k][i] * squared_speeds[i]).sum::<f64>();
        Command { thrust: row(0), torque: [row(1), row(2), row(3)] }
    }

    /// `A⁻¹ u`, rotor `i`'s entry `Σ_k inverse[i][k] u[k]` summed in the
    /// order of `k` (the float sum starts at `−0.0`, which `−0.0 + x = x`
    /// for every `x` drops).
    #[inline]
    fn squared(&self, u: &[f64; 4]) -> [f64; 4] {
        let c = &self.columns;
        let mut w = [0.0; 4];
        for i in 0..4 {
            w[i] = c[0][i] * u[0] + c[1][i] * u[1] + c[2][i] * u[2] + c[3][i] * u[3];
        }
        w
    }

    /// Largest `s ∈ [0, 1]` with `base + s·dir` inside `[w_min, w_max]`
    /// (`base` feasible up to rounding).
    fn max_scale(&self, base: &[f64; 4], dir: &[f64; 4]) -> f64 {
        let mut s = 1.0f64;
        for i in 0..4 {
            if dir[i] > 0.0 {
                s = s.min((self.w_max - base[i]) / dir[i]);
            } else if dir[i] < 0.0 {
                s = s.min((self.w_min - base[i]) / dir[i]);
            }
        }
        s.max(0.0)
    }

    /// The exact desaturation of roll/pitch by the collective thrust
    /// ([`MixerKind::Px4Exact`]): the largest roll/pitch scale `s ∈ [0, 1]` for
    /// which some collective thrust `T` puts every rotor in range, with
    /// `T <= requested` unless `raise` (airmode), then the feasible `T`
    /// nearest `requested`. With `w_i = c_i T + s r_i` (`c = A⁻¹ e₁`, `r` the
    /// roll/pitch part of `A⁻¹ u`), rotor `i` needs
    /// `T ∈ [(w_min − s r_i)/c_i, (w_max − s r_i)/c_i]`; `s` is feasible when
    /// every lower bound is below every upper bound (and below `requested`
    /// without airmode): pairwise linear inequalities in `s`, solved exactly.
    fn keep_roll_pitch(&self, requested: f64, rp: &[f64; 4], raise: bool) -> (f64, f64) {
        let c: [f64; 4] = core::array::from_fn(|i| self.inverse[i][0]);
        let mut s = 1.0f64;
        // lower_i(s) <= upper_j(s):  s (r_j/c_j − r_i/c_i) <= w_max/c_j − w_min/c_i.
        for i in 0..4 {
            for j in 0..4 {
                let coef = rp[j] / c[j] - rp[i] / c[i];
                let rhs = self.w_max / c[j] - self.w_min / c[i];
                if coef > 0.0 {
                    s = s.min(rhs / coef);
                }
            }
            if !raise {
                // lower_i(s) <= requested:  −s r_i/c_i <= requested − w_min/c_i.
                let coef = -rp[i] / c[i];
                let rhs = requested - self.w_min / c[i];
                if coef > 0.0 {
                    s = s.min(rhs / coef);
                }
            }
        }
        let s = s.max(0.0);
        let lower = (0..4).map(|i| (self.w_min - s * rp[i]) / c[i]).fold(f64::NEG_INFINITY, f64::max);
        let upper = (0..4).map(|i| (self.w_max - s * rp[i]) / c[i]).fold(f64::INFINITY, f64::min);
        let thrust = if raise { requested.clamp(lower, upper.max(lower)) } else { requested.min(upper).max(lower) };
        (thrust, s)
    }

    /// Rotor speed commands for `command` with each squared speed clamped to
    /// `[ω_min², ω_max²]` on its own ([`MixerKind::Clamp`]); `applied` is what
    /// the clamped speeds produce (`A w`), `saturated` whether any rotor was clamped.
    pub fn mix_clamped(&self, command: &Command) -> MixerOutput {
        let finite = |v: f64| if v.is_finite() { v } else { 0.0 };
        let commanded = Command { thrust: finite(command.thrust), torque: command.torque.map(finite) };
        let u = [commanded.thrust, commanded.torque[0], commanded.torque[1], commanded.torque[2]];
        let w = self.squared(&u);
        let clamped = w.map(|wi| wi.clamp(self.w_min, self.w_max));
        let saturated = commanded != *command || clamped != w;
        let applied = if saturated { self.forces(&clamped) } else { commanded };
        MixerOutput { commanded, applied, rotor_speeds: clamped.map(f64::sqrt), saturated }
    }

    /// Rotor speed commands for `command` under the documented priority.
    pub fn mix(&self, command: &Command) -> MixerOutput {
        if self.kind == MixerKind::Clamp {
            return self.mix_clamped(command);
        }
        let raw = [command.thrust, command.torque[0], command.torque[1], command.torque[2]];
        // `x − x` is +0 for a finite `x` and NaN otherwise: the sum is 0
        // exactly when every component is finite (then nothing is replaced).
        #[allow(clippy::eq_op)] // `x − x` on purpose: the finiteness test above
        let all_finite = (raw[0] - raw[0]) + (raw[1] - raw[1]) + (raw[2] - raw[2]) + (raw[3] - raw[3]) == 0.0;
        let finite = |v: f64| if v.is_finite() { v } else { 0.0 };
        let commanded = if all_finite {
            *command
        } else {
            Command { thrust: finite(command.thrust), torque: command.torque.map(finite) }
        };
        let u = [commanded.thrust, commanded.torque[0], commanded.torque[1], commanded.torque[2]];
        if let Some(px4) = &self.px4 {
            let a = px4.allocate(&u);
            let w = a.setpoints.map(|ai| ai * self.w_max);
            let rotor_speeds = w.map(|wi| wi.clamp(self.w_min, self.w_max).sqrt());
            let applied = if a.changed { self.forces(&w) } else { commanded };
            let saturated = !all_finite || a.changed;
            return MixerOutput { commanded, applied, rotor_speeds, saturated };
        }
        let w = self.squared(&u);
        let speeds = |w: &[f64; 4]| w.map(|wi| wi.clamp(self.w_min, self.w_max).sqrt());
        // Every rotor tested (no early exit): the same answer, without branches.
        let in_range = w.iter().fold(true, |ok, &wi| ok & (wi >= self.w_min) & (wi <= self.w_max));
        if all_finite && in_range {
            return MixerOutput { commanded, applied: commanded, rotor_speeds: speeds(&w), saturated: false };
        }
        let column = |k: usize, scale: f64| -> [f64; 4] { core::array::from_fn(|i| self.inverse[i][k] * scale) };
        let rp = {
            let (a, b) = (column(1, u[1]), column(2, u[2]));
            core::array::from_fn(|i| a[i] + b[i])
        };
        let requested = commanded.thrust.clamp(self.thrust_range[0], self.thrust_range[1]);
        let (thrust, s_rp) = match self.kind {
            MixerKind::ThrustFirst | MixerKind::Clamp | MixerKind::Px4 => {
                (requested, self.max_scale(&column(0, requested), &rp))
            }
            MixerKind::Px4Exact => self.keep_roll_pitch(requested, &rp, false),
            MixerKind::Px4ExactAirmode => self.keep_roll_pitch(requested, &rp, true),
        };
        let base = column(0, thrust);
        let base: [f64; 4] = core::array::from_fn(|i| base[i] + s_rp * rp[i]);
        let yaw = column(3, u[3]);
        let s_y = self.max_scale(&base, &yaw);
        let w: [f64; 4] = core::array::from_fn(|i| base[i] + s_y * yaw[i]);
        let applied = Command { thrust, torque: [s_rp * u[1], s_rp * u[2], s_y * u[3]] };
        let saturated = !all_finite || applied != commanded;
        MixerOutput { commanded, applied, rotor_speeds: speeds(&w), saturated }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// The squared speeds from the columns are the row sums
    /// `Σ_k inverse[i][k] u[k]` bit for bit, signed zeros and non-finite
    /// commands included, for the paper's and a "×" rigid body's allocation.
    #[test]
    fn squared_speeds_from_columns_are_the_row_sums_bit_for_bit() {
        let rigid = crate::vehicle::RigidBodyParams {
            configuration: crate::vehicle::Configuration::Cross,
            ..crate::vehicle::RigidBodyParams::hummingbird()
        };
        let allocations = [paper_allocation_matrix(&QuadrotorParams::default()), rigid.allocation_matrix()];
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let specials = [0.0, -0.0, 1e-300, -1e300, f64::INFINITY, f64::NAN];
        for a in allocations {
            let mixer = Mixer::new(a, &ActuatorParams::hummingbird()).unwrap();
            for n in 0..20_000 {
                let mut u: [f64; 4] = core::array::from_fn(|_| rng.random_range(-20.0..20.0));
                if n % 3 == 0 {
                    u[n % 4] = specials[n % specials.len()];
                }
                if n % 5 == 0 {
                    u[(n + 1) % 4] = -0.0;
                }
                let sums: [f64; 4] = core::array::from_fn(|i| (0..4).map(|k| mixer.inverse[i][k] * u[k]).sum());
                let bits = |w: [f64; 4]| w.map(|v| if v.is_nan() { u64::MAX } else { v.to_bits() });
                assert_eq!(bits(mixer.squared(&u)), bits(sums), "{u:?}");
            }
        }
    }
}
