//! The outer/inner cascade shared by every controller (paper §3.1–3.3).
//!
//! Outer loop (position): each channel's [`AxisLaw`] gives a commanded
//! acceleration `a_i = q̈_d + v_fb,i` (Eq. 18–20); the thrust is
//! `u1 = m (a_z + g)/(cφ cθ)` (Eq. 20 with gravity, erratum 1), optionally
//! scaled by the mass estimate, `U1 = α̂ u1` (§3.2, Eq. 44); the virtual
//! controls `u_x = m a_x / U1`, `u_y = m a_y / U1` (Remark 2) are inverted to
//! the desired roll and pitch (Eq. 52, corrected). Inner loop (attitude): the
//! same kind of law on φ, θ, ψ, and torques that cancel the plant's coupling,
//! gyroscopic and drag terms (Eq. 56–58, corrected).
//!
//! # Saturation remedies
//!
//! The paper assumes actuators that deliver any thrust and torque; its gains
//! ask for a negative thrust and ±1.5 N·m torques at 6 Hz in scenario 1, and
//! with a rotor-speed limit FTAFTSMC flips (docs/results.md, "Beyond the paper"). Four options of
//! [`CascadeSettings`] and [`MassAdaptation`] make the cascade aware of
//! saturation. Each is off or inert by default, and with the defaults the
//! cascade is bit-identical to the paper's form (the paper scenarios print
//! the same numbers).
//!
//! * **Tilt limit**, [`CascadeSettings::max_tilt`] (rad, always on, default
//!   0.6 rad ≈ 34°): the asin arguments of Eq. 52 are clamped to
//!   `±sin(max_tilt)`, so no horizontal demand asks for more than this tilt
//!   and the vertical component of the thrust keeps at least `cos(max_tilt)`
//!   of `U1`. It bounds the attitude *demand*, not the attitude.
//! * **Thrust bound**, [`CascadeSettings::thrust_limits`] (N, `[min, max]`,
//!   default none): `U1 = α̂ u1` (or `u1` without mass adaptation) is bounded
//!   to `[min, max]` right after Eq. 44's scaling and *before* Remark 2, so
//!   the virtual controls are `u_x = m a_x / U1_bounded` (`α̂ m a_x / …` with
//!   `compensate_horizontal`): the attitude demanded is the one that gives
//!   the commanded horizontal acceleration with the thrust the rotors will
//!   really produce, not with a thrust they cannot give. When `max` clips,
//!   the demanded tilt grows (up to `max_tilt`) to keep the horizontal
//!   acceleration and the vertical one falls short; when `min` clips a
//!   negative or tiny `u1`, the Remark 2 guard `U1 >= 1e-3 m g` applies as
//!   before. The bounded `U1` is the command's thrust and the one used for
//!   the rotor-speed estimate of the gyroscopic cancellation. Eq. 44 still
//!   sees the unbounded `u1` (it is the paper's law). Set it to what the
//!   mixer can give with some torque margin left, e.g. a fraction of
//!   `4 k_f ω_max²`. [`Telemetry::thrust_limited`] reports when it clipped.
//! * **α̂ projection**, [`MassAdaptation::alpha_hat_bounds`] (`[min, max]`,
//!   default none): α̂ is projected onto the interval after each Eq. 44 step.
//!   Without it Eq. 44 winds α̂ up whenever `u1` is negative (fast descents),
//!   and the thrust `α̂ u1` follows it.
//! * **Freezing the adaptation while the actuators saturate**,
//!   [`CascadeSettings::freeze_adaptation_on_saturation`] (default false):
//!   the simulator reports after each period whether its mixer could realise
//!   the command ([`Controller::actuator_feedback`]); while the last report
//!   is "saturated", each update holds δ̂ (FTAFTSMC, Eq. 17), `â` (RANFTSMC),
//!   ν (TSM-STA's super-twisting integral: conditional-integration
//!   anti-windup) and α̂ (Eq. 44; the `alpha_hat_bounds` projection is then
//!   not applied either, α̂ simply keeps its value) through
//!   [`AxisLaw::set_adaptation_frozen`]. The outputs still respond to the
//!   error with the held states; only the state increments are skipped, so
//!   the adaptive gains do not grow on errors the actuators cannot remove.
//!   Only the simulator's report freezes: the thrust bound clipping `U1` by
//!   itself does not. With no report, or reports of `false`, the cascade is
//!   bit-identical to the option off. [`SlidingTelemetry::adaptation_frozen`]
//!   reports when the states were held.

use crate::allocation::{residual_speed, rotor_speeds};
use crate::law::{
    check_closed, check_gain, check_left_open, check_open, saturate, AxisLaw, GainError, INPUT_LIMIT, MAX_ESTIMATES,
    STATE_LIMIT,
};
use crate::math::{asin, cos, sin_cos, sqrt, SinCosCache};
use crate::model::{Command, QuadState, QuadrotorParams, Reference};

// The controller interface lives in its own module; re-exported here so
// `ftsmc_core::cascade::{Controller, Telemetry, channel}` keep compiling.
pub use crate::controller::{channel, Controller, SlidingTelemetry, Telemetry};

/// How the desired-attitude derivatives φ̇_d, φ̈_d, θ̇_d, θ̈_d are obtained
/// (the paper does not say; see docs/paper-errata.md).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Deserialize, serde::Serialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "kebab-case"))]
pub enum AttitudeDerivatives {
    /// Pass φ_d, θ_d through a second-order command filter whose states give
    /// the reference and its two derivatives.
    CommandFilter,
    /// Use φ_d, θ_d directly with zero derivatives.
    Zero,
}

/// Where the attitude command filter starts (the paper does not say; see
/// docs/paper-errata.md and docs/results.md, "Command filter").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Deserialize, serde::Serialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "kebab-case"))]
pub enum FilterInit {
    /// `r(0) = φ_d(0), θ_d(0)`, `ṙ(0) = 0`: the filter starts at the first
    /// Eq. 52 demand, so the inner loop sees the whole initial attitude
    /// demand as an error at once (default: the published numbers of
    /// docs/results.md were produced this way).
    #[default]
    FirstDemand,
    /// `r(0) = φ(0), θ(0)`, `ṙ(0) = φ̇(0), θ̇(0)` (the measured attitude and
    /// its rate): the filter starts at the vehicle and slews towards the
    /// demand at its own bandwidth, so the attitude error starts at zero.
    VehicleAttitude,
}

/// Second-order command filter `r̈ = ω_n²(u − r) − 2ζω_n ṙ`, stepped on the
/// control clock with semi-implicit (symplectic) Euler,
/// `ṙ_{k+1} = ṙ_k + dt r̈_k`, `r_{k+1} = r_k + dt ṙ_{k+1}`; the reference
/// used at tick k is `(r_k, ṙ_k, r̈_k)`.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Deserialize, serde::Serialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct CommandFilterParams {
    /// Natural frequency ω_n, rad/s (default 50).
    pub natural_frequency: f64,
    /// Damping ratio ζ (default 1, critically damped).
    pub damping: f64,
}

impl Default for CommandFilterParams {
    fn default() -> Self {
        Self { natural_frequency: 50.0, damping: 1.0 }
    }
}

/// Cascade options common to all controllers.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Deserialize, serde::Serialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields, default))]
pub struct CascadeSettings {
    /// Desired-attitude derivative option (default `command-filter`).
    pub attitude_derivatives: AttitudeDerivatives,
    /// Command filter parameters (used with `command-filter`).
    pub command_filter: CommandFilterParams,
    /// Maximum desired tilt, rad: the asin arguments of Eq. 52 are clamped to
    /// `±sin(max_tilt)` (default 0.6 rad ≈ 34°). Scenario key
    /// `max_demanded_tilt` (a limit on the demand, not on the flown tilt).
    #[cfg_attr(feature = "serde", serde(rename = "max_demanded_tilt"))]
    pub max_tilt: f64,
    /// Initial state of the command filter, `"first-demand"` (default) or
    /// `"vehicle-attitude"` (rad and rad/s of the measured roll and pitch at
    /// the first control tick). Ignored with `attitude_derivatives = "zero"`.
    /// The default reproduces the published Table 3; docs/results.md reports
    /// Table 3 under both.
    pub filter_init: FilterInit,
    /// Saturation remedy: bound the thrust command `U1` to `[min, max]`, N
    /// (what the rotors can give, e.g. `4 k_f ω_min²` and `4 k_f ω_max²`),
    /// *before* the attitude demand is computed from it, so that the demanded
    /// tilt is the one that realises the horizontal acceleration with the
    /// thrust that will really be produced. Default none (the paper: `U1`
    /// unbounded, it may even be negative). Requires `0 <= min < max <= 1e100`
    /// (the finiteness guarantee of [`Cascade::new`] covers thrusts up to
    /// there). See the module docs, "Saturation remedies".
    #[cfg_attr(feature = "serde", serde(skip_serializing_if = "Option::is_none"))]
    pub thrust_limits: Option<[f64; 2]>,
    /// Saturation remedy: hold the adaptive states (δ̂ of FTAFTSMC, `â` of
    /// RANFTSMC, ν of TSM-STA, and α̂ of the mass adaptation) during every
    /// update that follows a [`Controller::actuator_feedback`] report of
    /// saturation. Default false (the paper: the adaptive laws integrate
    /// whatever the actuators do). See the module docs, "Saturation remedies".
    #[cfg_attr(feature = "serde", serde(skip_serializing_if = "core::ops::Not::not"))]
    pub freeze_adaptation_on_saturation: bool,
}

impl Default for CascadeSettings {
    fn default() -> Self {
        Self {
            attitude_derivatives: AttitudeDerivatives::CommandFilter,
            command_filter: CommandFilterParams::default(),
            max_tilt: 0.6,
            filter_init: FilterInit::FirstDemand,
            thrust_limits: None,
            freeze_adaptation_on_saturation: false,
        }
    }
}

impl CascadeSettings {
    /// Range checks: ω_n and ζ in `(0, 1e6]` (the filter forms ω_n² times
    /// states up to 1e100), `0 < max_tilt < π/2` (NaN rejected), and when
    /// given `0 <= thrust_limits[0] < thrust_limits[1] <= 1e100` (a minimum
    /// thrust of 1e300 N would overflow the rotor-speed estimate of the
    /// gyroscopic cancellation; the cascade's own thrust stays below ~1e120).
    /// `filter_init` and `freeze_adaptation_on_saturation` have no range:
    /// every value is valid, and a misspelt one is refused when the scenario
    /// is parsed.
    pub fn check(&self) -> Result<(), GainError> {
        check_gain("command_filter.natural_frequency", self.command_filter.natural_frequency)?;
        check_gain("command_filter.damping", self.command_filter.damping)?;
        check_open(
            "max_demanded_tilt",
            self.max_tilt,
            0.0,
            core::f64::consts::FRAC_PI_2,
            "0 < max_demanded_tilt < π/2",
        )?;
        if let Some([lo, hi]) = self.thrust_limits {
            check_closed("thrust_limits[0]", lo, 0.0, STATE_LIMIT, "0 <= thrust_limits[0] < 1e100 (N)")?;
            check_left_open(
                "thrust_limits[1]",
                hi,
                lo,
                STATE_LIMIT,
                "thrust_limits[0] < thrust_limits[1] <= 1e100 (N)",
            )?;
        }
        Ok(())
    }
}

/// Mass adaptation of §3.2: `U1 = α̂ u1`, `dα̂/dt = −β1 (S_z u1 cθ cφ / m + β2 α̂)` (Eq. 44).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Deserialize, serde::Serialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct MassAdaptation {
    /// Switch the adaptation on or off (off: `U1 = u1`, α̂ stays at `alpha_hat0`).
    pub enabled: bool,
    /// β1 > 0, adaptation rate (Table 5: 0.8).
    pub beta1: f64,
    /// β2 > 0, leakage (Table 5: 0.01).
    pub beta2: f64,
    /// α̂(0) > 0 (default 1: nominal mass).
    #[cfg_attr(feature = "serde", serde(default = "one"))]
    pub alpha_hat0: f64,
    /// Use the estimated mass in the horizontal virtual controls,
    /// `u_x = α̂ m a_x / U1` (default false: Remark 2 as printed,
    /// `u_x = m a_x / U1`, which leaves x and y uncompensated; see
    /// docs/paper-errata.md E12).
    #[cfg_attr(feature = "serde", serde(default))]
    pub compensate_horizontal: bool,
    /// Optional projection of α̂ onto `[min, max]` after each update (not in
    /// the paper; default none). Without it Eq. 44 winds α̂ up whenever the
    /// computed u1 is negative, e.g. during a fast descent.
    #[cfg_attr(feature = "serde", serde(default, skip_serializing_if = "Option::is_none"))]
    pub alpha_hat_bounds: Option<[f64; 2]>,
}

#[cfg(feature = "serde")]
fn one() -> f64 {
    1.0
}

impl MassAdaptation {
    /// Table 5 values, enabled.
    pub const PAPER: Self = Self {
        enabled: true,
        beta1: 0.8,
        beta2: 0.01,
        alpha_hat0: 1.0,
        compensate_horizontal: false,
        alpha_hat_bounds: None,
    };
    /// No adaptation (`U1 = u1`).
    pub const OFF: Self = Self { enabled: false, ..Self::PAPER };

    /// Range checks: β1, β2 in `(0, 1e6]`, α̂(0) in `(0, 1e100]`, and when
    /// given `0 < alpha_hat_bounds[0] < alpha_hat_bounds[1] <= 1e100` with
    /// α̂(0) inside (NaN and inverted bounds rejected). α̂ is saturated at
    /// ±1e100 ([`crate::law::STATE_LIMIT`]) in any case.
    pub fn check(&self) -> Result<(), GainError> {
        check_gain("beta1", self.beta1)?;
        check_gain("beta2", self.beta2)?;
        check_left_open(
            "alpha_hat0",
            self.alpha_hat0,
            0.0,
            STATE_LIMIT,
            "0 < alpha_hat0 <= 1e100 (alpha_hat is saturated at 1e100)",
        )?;
        if let Some([lo, hi]) = self.alpha_hat_bounds {
            check_open("alpha_hat_bounds[0]", lo, 0.0, STATE_LIMIT, "0 < alpha_hat_bounds[0] < 1e100")?;
            check_left_open(
                "alpha_hat_bounds[1]",
                hi,
                lo,
                STATE_LIMIT,
                "alpha_hat_bounds[0] < alpha_hat_bounds[1] <= 1e100",
            )?;
            if !(self.alpha_hat0 >= lo && self.alpha_hat0 <= hi) {
                return Err(GainError {
                    field: "alpha_hat0",
                    value: self.alpha_hat0,
                    expected: "alpha_hat0 inside alpha_hat_bounds",
                });
            }
        }
        Ok(())
    }
}

/// Everything the cascade needs besides the six axis laws.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CascadeConfig {
    /// Nominal model used for cancellation (the plant may differ).
    pub model: QuadrotorParams,
    /// Common options.
    pub settings: CascadeSettings,
    /// Mass adaptation (FTAFTSMC only; [`MassAdaptation::OFF`] for the baselines).
    pub mass_adaptation: MassAdaptation,
}

#[derive(Clone, Copy, Debug, Default)]
struct FilterState {
    value: f64,
    rate: f64,
    initialised: bool,
}

/// Smallest `cφ cθ` used when dividing by it (tilt ≈ 87°); beyond this the
/// simulation declares divergence anyway.
const MIN_TILT_COSINE: f64 = 0.05;

/// The cascade of six axis laws of type `L`.
#[derive(Clone, Debug)]
pub struct Cascade<L: AxisLaw> {
    /// Configuration.
    pub config: CascadeConfig,
    /// Laws for `[x, y, z, φ, θ, ψ]`.
    pub laws: [L; 6],
    filter: [FilterState; 2],
    alpha_hat: f64,
    last_command: Command,
    telemetry: Telemetry,
    /// `sin(max_tilt)`, the clamp of the asin arguments of Eq. 52.
    tilt_limit: f64,
    /// Last [`Controller::actuator_feedback`] report.
    actuator_saturated: bool,
    /// `sin`, `cos` of the last reference heading ψ_d (Eq. 52).
    yaw_sin_cos: SinCosCache,
}

impl<L: AxisLaw> Cascade<L> {
    /// The telemetry before the first update: zeros, and α̂ at `alpha_hat`.
    fn initial_telemetry(alpha_hat: f64) -> Telemetry {
        Telemetry {
            sliding_mode: Some(SlidingTelemetry { alpha_hat, ..SlidingTelemetry::default() }),
            ..Telemetry::default()
        }
    }

    /// Build from a configuration and the six channel laws `[x, y, z, φ, θ, ψ]`,
    /// after validating everything: the nominal model
    /// ([`QuadrotorParams::check`]), the settings ([`CascadeSettings::check`],
    /// e.g. a NaN `max_tilt`), the mass adaptation ([`MassAdaptation::check`],
    /// e.g. inverted `alpha_hat_bounds`) and the gains of each law
    /// ([`AxisLaw::check_gains`]). The first problem found is returned.
    ///
    /// With a configuration accepted here, [`Controller::update`] returns a
    /// finite command for every finite state, reference and
    /// `0 <= dt <= DT_MAX`, and a NaN command, with every internal state
    /// left unchanged, when any of them is not finite.
    pub fn new(config: CascadeConfig, laws: [L; 6]) -> Result<Self, GainError> {
        config.model.check()?;
        config.settings.check()?;
        config.mass_adaptation.check()?;
        for law in &laws {
            law.check_gains()?;
        }
        Ok(Self::new_unchecked(config, laws))
    }

    /// [`Cascade::new`] without validation. Never panics, whatever the
    /// configuration (a NaN `max_tilt` or inverted `alpha_hat_bounds` give
    /// NaN or meaningless commands instead); the finiteness guarantee of
    /// [`Cascade::new`] holds only for configurations it would accept.
    pub fn new_unchecked(config: CascadeConfig, laws: [L; 6]) -> Self {
        let hover = Command { thrust: config.model.mass * config.model.gravity, torque: [0.0; 3] };
        Self {
            config,
            laws,
            filter: [FilterState::default(); 2],
            alpha_hat: config.mass_adaptation.alpha_hat0,
            last_command: hover,
            telemetry: Self::initial_telemetry(config.mass_adaptation.alpha_hat0),
            tilt_limit: crate::math::sin(config.settings.max_tilt),
            actuator_saturated: false,
            yaw_sin_cos: SinCosCache::new(),
        }
    }

    /// Current mass-ratio estimate α̂.
    pub fn alpha_hat(&self) -> f64 {
        self.alpha_hat
    }

    /// Last [`Controller::actuator_feedback`] report (false until the first).
    pub fn actuator_saturated(&self) -> bool {
        self.actuator_saturated
    }

    /// `thrust` bounded to `[lo, hi]` (no `f64::clamp`: never panics);
    /// unchanged without bounds.
    #[inline]
    fn bound_thrust(thrust: f64, limits: Option<[f64; 2]>) -> f64 {
        match limits {
            Some([lo, _]) if thrust < lo => lo,
            Some([_, hi]) if thrust > hi => hi,
            _ => thrust,
        }
    }

    /// Desired roll and pitch from the virtual controls (Eq. 52 corrected:
    /// θ_d divides by cos φ_d), asin arguments clamped to `±sin(max_tilt)`.
    pub fn desired_roll_pitch(ux: f64, uy: f64, yaw_d: f64, max_tilt: f64) -> [f64; 2] {
        Self::desired_roll_pitch_limited(ux, uy, yaw_d, crate::math::sin(max_tilt))
    }

    /// [`Cascade::desired_roll_pitch`] with the clamp `limit = sin(max_tilt)` precomputed.
    #[inline]
    pub fn desired_roll_pitch_limited(ux: f64, uy: f64, yaw_d: f64, limit: f64) -> [f64; 2] {
        Self::desired_roll_pitch_at(ux, uy, sin_cos(yaw_d), limit)
    }

    /// [`Cascade::desired_roll_pitch_limited`] with `(sin ψ_d, cos ψ_d)` given.
    #[inline]
    fn desired_roll_pitch_at(ux: f64, uy: f64, (s_psi, c_psi): (f64, f64), limit: f64) -> [f64; 2] {
        // `saturate`, not `f64::clamp`: it does not panic on a NaN limit.
        let sin_roll = saturate(ux * s_psi - uy * c_psi, limit);
        let roll = asin(sin_roll);
        // cos φ_d = √((1 − sin φ_d)(1 + sin φ_d)), equal to cos(asin(·)) to
        // rounding (|sin φ_d| <= sin(max_tilt) < 1), without the cosine.
        let cos_roll = sqrt((1.0 - sin_roll) * (1.0 + sin_roll));
        let pitch = asin(saturate((ux * c_psi + uy * s_psi) / cos_roll, limit));
        [roll, pitch]
    }

    fn attitude_reference(&mut self, demand: [f64; 2], state: &QuadState, dt: f64) -> ([f64; 2], [f64; 2], [f64; 2]) {
        match self.config.settings.attitude_derivatives {
            AttitudeDerivatives::Zero => (demand, [0.0; 2], [0.0; 2]),
            AttitudeDerivatives::CommandFilter => {
                let wn = self.config.settings.command_filter.natural_frequency;
                let zeta = self.config.settings.command_filter.damping;
                let mut value = [0.0; 2];
                let mut rate = [0.0; 2];
                let mut accel = [0.0; 2];
                for i in 0..2 {
                    let f = &mut self.filter[i];
                    if !f.initialised {
                        *f = match self.config.settings.filter_init {
                            FilterInit::FirstDemand => FilterState { value: demand[i], rate: 0.0, initialised: true },
                            FilterInit::VehicleAttitude => FilterState {
                                value: saturate(state.attitude[i], STATE_LIMIT),
                                rate: saturate(state.angular_rate[i], STATE_LIMIT),
                                initialised: true,
                            },
                        };
                    }
                    let a = wn * wn * (demand[i] - f.value) - 2.0 * zeta * wn * f.rate;
                    value[i] = f.value;
                    rate[i] = f.rate;
                    accel[i] = a;
                    // Semi-implicit Euler on the control clock, states
                    // saturated so that an unstable ω_n·dt stays finite.
                    f.rate = saturate(f.rate + dt * a, STATE_LIMIT);
                    f.value = saturate(f.value + dt * f.rate, STATE_LIMIT);
                }
                (value, rate, accel)
            }
        }
    }
}

impl<L: AxisLaw> Controller for Cascade<L> {
    fn name(&self) -> &'static str {
        L::NAME
    }

    /// See [`Cascade::new`] for the finiteness contract. Guards, all no-ops
    /// on meaningful inputs: commanded accelerations and the angular rates
    /// used in the cancellation terms clamped to `±INPUT_LIMIT`; `S_z` in
    /// Eq. 44, α̂ and the command-filter states saturated to `±STATE_LIMIT`.
    fn update(&mut self, state: &QuadState, reference: &Reference, dt: f64) -> Command {
        if !(dt.is_finite() && state.is_finite() && crate::setpoint::reference_finite(reference)) {
            return Command { thrust: f64::NAN, torque: [f64::NAN; 3] };
        }
        // Finite inputs whose differences overflow (x = 1e308, x_d = -1e308)
        // are non-finite intermediates: the same NaN, before any state moves
        // (otherwise the attitude reference filter keeps a NaN for good).
        let yaw = [state.attitude[2] - reference.yaw, state.angular_rate[2] - reference.yaw_rate];
        let differences = [
            state.position[0] - reference.position[0],
            state.position[1] - reference.position[1],
            state.position[2] - reference.position[2],
            state.velocity[0] - reference.velocity[0],
            state.velocity[1] - reference.velocity[1],
            state.velocity[2] - reference.velocity[2],
            yaw[0],
            yaw[1],
        ];
        if crate::math::finite_probe(&differences) != 0.0 {
            return Command { thrust: f64::NAN, torque: [f64::NAN; 3] };
        }
        let model = self.config.model;
        let m = model.mass;
        let g = model.gravity;
        let settings = self.config.settings;

        // Saturation remedy: hold every adaptive state after a saturation
        // report. Set on all six laws every update (a store), so a law
        // replaced through the public `laws` field is still governed.
        let frozen = settings.freeze_adaptation_on_saturation && self.actuator_saturated;
        for law in &mut self.laws {
            law.set_adaptation_frozen(frozen);
        }

        // Outer loop: commanded accelerations (Eq. 18–20).
        let mut accel = [0.0; 3];
        for i in 0..3 {
            let e = state.position[i] - reference.position[i];
            let e_dot = state.velocity[i] - reference.velocity[i];
            accel[i] = saturate(reference.acceleration[i] + self.laws[i].update(e, e_dot, dt), INPUT_LIMIT);
        }
        let [phi, theta, _] = state.attitude;
        let tilt_cos = (cos(phi) * cos(theta)).max(MIN_TILT_COSINE);
        let nominal_thrust = m * (accel[2] + g) / tilt_cos;

        // Mass adaptation (§3.2, Eq. 44): U1 = α̂ u1.
        let ma = self.config.mass_adaptation;
        let unbounded_thrust = if ma.enabled { self.alpha_hat * nominal_thrust } else { nominal_thrust };
        // Saturation remedy: U1 bounded to what the rotors can give, before
        // Remark 2 uses it, so the attitude demand matches the real thrust.
        let thrust = Self::bound_thrust(unbounded_thrust, settings.thrust_limits);
        let horizontal_mass = if ma.enabled && ma.compensate_horizontal { self.alpha_hat * m } else { m };
        if ma.enabled && !frozen {
            let s_z = saturate(self.laws[2].sliding_variable(), STATE_LIMIT);
            let rate = -ma.beta1 * (s_z * nominal_thrust * tilt_cos / m + ma.beta2 * self.alpha_hat);
            self.alpha_hat += dt * rate;
            if let Some([lo, hi]) = ma.alpha_hat_bounds {
                // Not `f64::clamp`, which panics on NaN or inverted bounds.
                if self.alpha_hat < lo {
                    self.alpha_hat = lo;
                } else if self.alpha_hat > hi {
                    self.alpha_hat = hi;
                }
            }
            self.alpha_hat = saturate(self.alpha_hat, STATE_LIMIT);
        }

        // Remark 2: u_x = m a_x / U1, u_y = m a_y / U1; guard U1 → 0.
        let thrust_for_inversion = thrust.max(1e-3 * m * g);
        let ux = horizontal_mass * accel[0] / thrust_for_inversion;
        let uy = horizontal_mass * accel[1] / thrust_for_inversion;
        let demand = Self::desired_roll_pitch_at(ux, uy, self.yaw_sin_cos.get(reference.yaw), self.tilt_limit);
        let (att_ref, att_rate, att_accel) = self.attitude_reference(demand, state, dt);
        let reference_attitude = [att_ref[0], att_ref[1], reference.yaw];
        let reference_rate = [att_rate[0], att_rate[1], reference.yaw_rate];
        let reference_accel = [att_accel[0], att_accel[1], reference.yaw_acceleration];

        // Inner loop: angular accelerations then torques (Eq. 56–58).
        let mut angular_accel = [0.0; 3];
        for i in 0..3 {
            let e = state.attitude[i] - reference_attitude[i];
            let e_dot = state.angular_rate[i] - reference_rate[i];
            angular_accel[i] = saturate(reference_accel[i] + self.laws[3 + i].update(e, e_dot, dt), INPUT_LIMIT);
        }
        let [p, q, r] = state.angular_rate.map(|w| saturate(w, INPUT_LIMIT));
        let [i1, i2, i3] = model.inertia;
        let [k1, k2, k3] = model.drag_rotational;
        let omega_bar = residual_speed(&rotor_speeds(&model, &self.last_command, f64::INFINITY));
        let jr = model.rotor_inertia;
        // Plant (SPEC §1): I φ̈ = coupling − J_r Ω̄ θ̇ − K φ̇|φ̇| + u, so u = I v − (…).
        let torque = [
            i1 * angular_accel[0] - ((i2 - i3) * q * r - jr * omega_bar * q - k1 * p * p.abs()),
            i2 * angular_accel[1] - ((i3 - i1) * p * r + jr * omega_bar * p - k2 * q * q.abs()),
            i3 * angular_accel[2] - ((i1 - i2) * p * q - k3 * r * r.abs()),
        ];
        let command = Command { thrust, torque };
        self.last_command = command;

        let mut sliding = [0.0; 6];
        let mut estimates = [[0.0; MAX_ESTIMATES]; 6];
        for i in 0..6 {
            sliding[i] = self.laws[i].sliding_variable();
            estimates[i] = self.laws[i].estimates();
        }
        self.telemetry = Telemetry {
            attitude_reference: reference_attitude,
            attitude_reference_rate: reference_rate,
            attitude_reference_acceleration: reference_accel,
            attitude_demand: demand,
            estimates,
            commanded_acceleration: accel,
            nominal_thrust,
            thrust_limited: thrust != unbounded_thrust,
            sliding_mode: Some(SlidingTelemetry { sliding, alpha_hat: self.alpha_hat, adaptation_frozen: frozen }),
        };
        command
    }

    fn telemetry(&self) -> &Telemetry {
        &self.telemetry
    }

    fn estimate_names(&self) -> [&'static str; MAX_ESTIMATES] {
        L::ESTIMATE_NAMES
    }

    fn adapts_mass(&self) -> bool {
        self.config.mass_adaptation.enabled
    }

    fn reset(&mut self) {
        for law in &mut self.laws {
            law.reset();
        }
        let hover = Command { thrust: self.config.model.mass * self.config.model.gravity, torque: [0.0; 3] };
        self.filter = [FilterState::default(); 2];
        self.alpha_hat = self.config.mass_adaptation.alpha_hat0;
        self.last_command = hover;
        self.actuator_saturated = false;
        self.telemetry = Self::initial_telemetry(self.alpha_hat);
    }

    fn actuator_feedback(&mut self, saturated: bool) {
        self.actuator_saturated = saturated;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ftaftsmc::{FtaftsmcAxis, FtaftsmcGains};

    fn paper_ftaftsmc(settings: CascadeSettings) -> Cascade<FtaftsmcAxis> {
        let xy = FtaftsmcAxis::new(FtaftsmcGains::PAPER_XY);
        let laws = [
            xy,
            xy,
            FtaftsmcAxis::new(FtaftsmcGains::PAPER_Z),
            FtaftsmcAxis::new(FtaftsmcGains::PAPER_ROLL_PITCH),
            FtaftsmcAxis::new(FtaftsmcGains::PAPER_ROLL_PITCH),
            FtaftsmcAxis::new(FtaftsmcGains::PAPER_YAW),
        ];
        let config =
            CascadeConfig { model: QuadrotorParams::default(), settings, mass_adaptation: MassAdaptation::PAPER };
        Cascade::new(config, laws).unwrap()
    }

    fn paper_config(settings: CascadeSettings, mass_adaptation: MassAdaptation) -> CascadeConfig {
        CascadeConfig { model: QuadrotorParams::default(), settings, mass_adaptation }
    }

    fn paper_laws() -> [FtaftsmcAxis; 6] {
        paper_ftaftsmc(CascadeSettings::default()).laws
    }

    /// Issue 9: a NaN `max_tilt` reached `f64::clamp(NaN, NaN)` in
    /// `Cascade::update` and panicked; `Cascade::new` now refuses it.
    #[test]
    fn new_rejects_a_nan_max_tilt_and_unchecked_does_not_panic() {
        let settings = CascadeSettings { max_tilt: f64::NAN, ..CascadeSettings::default() };
        let err = Cascade::new(paper_config(settings, MassAdaptation::PAPER), paper_laws()).unwrap_err();
        assert_eq!(err.field, "max_demanded_tilt");
        let mut c = Cascade::new_unchecked(paper_config(settings, MassAdaptation::PAPER), paper_laws());
        let reference = Reference { position: [0.3, -0.2, 1.0], ..Reference::default() };
        c.update(&QuadState::default(), &reference, 1e-3);
    }

    /// Issue 9: inverted `alpha_hat_bounds` reached `f64::clamp(lo, hi)` with
    /// `lo > hi` and panicked; `Cascade::new` now refuses them.
    #[test]
    fn new_rejects_inverted_alpha_hat_bounds_and_unchecked_does_not_panic() {
        for bounds in [[2.0, 0.5], [f64::NAN, 2.0], [0.5, f64::NAN]] {
            let ma = MassAdaptation { alpha_hat_bounds: Some(bounds), ..MassAdaptation::PAPER };
            let err = Cascade::new(paper_config(CascadeSettings::default(), ma), paper_laws()).unwrap_err();
            assert!(err.field.starts_with("alpha_hat_bounds"), "{err}");
            let mut c = Cascade::new_unchecked(paper_config(CascadeSettings::default(), ma), paper_laws());
            let reference = Reference { position: [0.0, 0.0, 1.0], ..Reference::default() };
            c.update(&QuadState::default(), &reference, 1e-3);
        }
    }

    #[test]
    fn new_rejects_bad_law_gains_and_model() {
        let mut laws = paper_laws();
        laws[4] = FtaftsmcAxis::new(FtaftsmcGains { xi: 0.0, ..FtaftsmcGains::PAPER_ROLL_PITCH });
        let err = Cascade::new(paper_config(CascadeSettings::default(), MassAdaptation::PAPER), laws).unwrap_err();
        assert_eq!(err.field, "xi");
        let config = CascadeConfig {
            model: QuadrotorParams { mass: f64::NAN, ..QuadrotorParams::default() },
            ..paper_config(CascadeSettings::default(), MassAdaptation::PAPER)
        };
        assert_eq!(Cascade::new(config, paper_laws()).unwrap_err().field, "mass");
    }

    /// A non-finite measurement gives a NaN command (the simulator reports
    /// divergence) and leaves α̂, the filter and the law states unchanged.
    #[test]
    fn a_non_finite_state_does_not_poison_the_cascade() {
        let mut c = paper_ftaftsmc(CascadeSettings::default());
        let reference = Reference { position: [0.5, -0.5, 1.0], ..Reference::default() };
        for _ in 0..20 {
            c.update(&QuadState::default(), &reference, 1e-3);
        }
        let before = (c.alpha_hat(), c.laws.map(|l| l.delta_hat), c.filter.map(|f| (f.value, f.rate)));
        let bad = QuadState { velocity: [0.0, f64::NAN, 0.0], ..QuadState::default() };
        let cmd = c.update(&bad, &reference, 1e-3);
        assert!(cmd.thrust.is_nan() && cmd.torque.iter().all(|t| t.is_nan()));
        let after = (c.alpha_hat(), c.laws.map(|l| l.delta_hat), c.filter.map(|f| (f.value, f.rate)));
        assert_eq!(before, after);
        let cmd = c.update(&QuadState::default(), &reference, 1e-3);
        assert!(cmd.thrust.is_finite() && cmd.torque.iter().all(|t| t.is_finite()));
    }

    #[test]
    fn desired_attitude_inverts_eq2_exactly() {
        for &(phi, theta, psi) in &[(0.1, -0.2, 0.3), (-0.3, 0.25, -1.2), (0.0, 0.4, 2.0)] {
            let (sp, cp) = (crate::math::sin(phi), crate::math::cos(phi));
            let (st, _) = (crate::math::sin(theta), crate::math::cos(theta));
            let (ss, cs) = (crate::math::sin(psi), crate::math::cos(psi));
            let ux = cp * st * cs + sp * ss;
            let uy = cp * st * ss - sp * cs;
            let [r, p] = Cascade::<FtaftsmcAxis>::desired_roll_pitch(ux, uy, psi, 1.2);
            assert!((r - phi).abs() < 1e-12 && (p - theta).abs() < 1e-12, "{r} {p}");
        }
    }

    #[test]
    fn horizontal_compensation_uses_the_estimated_mass() {
        // With α̂ = 1.5 and the same commanded acceleration, the SPEC form
        // asks for a tilt 1.5 times smaller than the compensated form.
        let state = QuadState::default();
        let reference = Reference { position: [0.1, 0.0, 0.0], ..Reference::default() };
        let demand = |compensate: bool| {
            let ma = MassAdaptation { alpha_hat0: 1.5, compensate_horizontal: compensate, ..MassAdaptation::PAPER };
            let mut c = paper_ftaftsmc(CascadeSettings {
                attitude_derivatives: AttitudeDerivatives::Zero,
                ..CascadeSettings::default()
            });
            c.config.mass_adaptation = ma;
            c.alpha_hat = 1.5;
            c.update(&state, &reference, 1e-3);
            c.telemetry().attitude_demand[1]
        };
        let (spec, compensated) = (demand(false), demand(true));
        assert!(spec != 0.0);
        assert!((crate::math::sin(compensated) / crate::math::sin(spec) - 1.5).abs() < 1e-9, "{spec} {compensated}");
    }

    /// The filter's first output is the first Eq. 52 demand by default, and
    /// the vehicle's roll and pitch (and rates) with `vehicle-attitude`.
    #[test]
    fn command_filter_starts_at_first_demand_or_vehicle_attitude() {
        let state = QuadState { attitude: [0.05, -0.03, 0.0], angular_rate: [0.2, -0.1, 0.0], ..QuadState::default() };
        let reference = Reference { position: [1.0, -1.0, 1.0], ..Reference::default() };
        let mut c = paper_ftaftsmc(CascadeSettings::default());
        assert_eq!(CascadeSettings::default().filter_init, FilterInit::FirstDemand);
        c.update(&state, &reference, 1e-3);
        let t = *c.telemetry();
        assert!(t.attitude_demand.iter().all(|d| d.abs() > 0.1), "{:?}", t.attitude_demand);
        assert_eq!(&t.attitude_reference[..2], &t.attitude_demand[..]);
        assert_eq!(&t.attitude_reference_rate[..2], &[0.0, 0.0]);

        let settings = CascadeSettings { filter_init: FilterInit::VehicleAttitude, ..CascadeSettings::default() };
        let mut c = paper_ftaftsmc(settings);
        c.update(&state, &reference, 1e-3);
        let t = *c.telemetry();
        assert_eq!(&t.attitude_reference[..2], &state.attitude[..2]);
        assert_eq!(&t.attitude_reference_rate[..2], &state.angular_rate[..2]);
        // It then moves towards the demand, and starts again after a reset.
        let first = t.attitude_reference[0];
        for _ in 0..50 {
            c.update(&state, &reference, 1e-3);
        }
        let t2 = *c.telemetry();
        assert!((t2.attitude_reference[0] - t2.attitude_demand[0]).abs() < (first - t.attitude_demand[0]).abs());
        c.reset();
        c.update(&state, &reference, 1e-3);
        assert_eq!(&c.telemetry().attitude_reference[..2], &state.attitude[..2]);
    }

    #[test]
    fn hover_at_reference_gives_weight_and_zero_torque() {
        let mut c = paper_ftaftsmc(CascadeSettings::default());
        let state = QuadState { position: [0.0, 0.0, 1.0], ..QuadState::default() };
        let reference = Reference { position: [0.0, 0.0, 1.0], ..Reference::default() };
        let cmd = c.update(&state, &reference, 1e-3);
        let p = QuadrotorParams::default();
        assert!((cmd.thrust - p.mass * p.gravity).abs() < 1e-12, "{}", cmd.thrust);
        assert!(cmd.torque.iter().all(|t| t.abs() < 1e-15));
    }

    fn zero_derivatives(thrust_limits: Option<[f64; 2]>) -> CascadeSettings {
        CascadeSettings { attitude_derivatives: AttitudeDerivatives::Zero, thrust_limits, ..CascadeSettings::default() }
    }

    /// Issue 11 item 6: the thrust bound acts on U1 before Remark 2, so the
    /// attitude demand is computed from the bounded thrust (and Eq. 44 still
    /// sees the unbounded u1).
    #[test]
    fn thrust_limits_bound_u1_and_the_attitude_demand_uses_the_bounded_u1() {
        let m = QuadrotorParams::default().mass;
        let g = QuadrotorParams::default().gravity;
        let state = QuadState::default();
        let climb = Reference { position: [1.0, -0.5, 5.0], yaw: 0.2, ..Reference::default() };
        let step = |limits: Option<[f64; 2]>, reference: &Reference| {
            let mut c = paper_ftaftsmc(zero_derivatives(limits));
            let cmd = c.update(&state, reference, 1e-3);
            (cmd, *c.telemetry(), c.alpha_hat())
        };
        let demand_for = |t: &Telemetry, thrust: f64, yaw: f64| {
            let [ax, ay, _] = t.commanded_acceleration;
            Cascade::<FtaftsmcAxis>::desired_roll_pitch(m * ax / thrust, m * ay / thrust, yaw, 0.6)
        };

        // Upper bound: a fast climb asks for more than the rotors give.
        let (free, free_t, free_alpha) = step(None, &climb);
        assert!(!free_t.thrust_limited);
        let hi = 0.5 * free.thrust;
        assert!(hi > m * g, "the climb must ask for more than hover: {}", free.thrust);
        let (cmd, t, alpha) = step(Some([0.0, hi]), &climb);
        assert_eq!(cmd.thrust.to_bits(), hi.to_bits());
        assert!(t.thrust_limited);
        assert_eq!(t.attitude_demand.map(f64::to_bits), demand_for(&t, hi, climb.yaw).map(f64::to_bits));
        // Half the thrust: the demanded tilt grows to keep the horizontal acceleration.
        assert_eq!(
            free_t.attitude_demand.map(f64::to_bits),
            demand_for(&free_t, free.thrust, climb.yaw).map(f64::to_bits)
        );
        for i in 0..2 {
            assert!(t.attitude_demand[i].abs() > free_t.attitude_demand[i].abs(), "{t:?} {free_t:?}");
        }
        assert_eq!(
            (t.nominal_thrust.to_bits(), alpha.to_bits()),
            (free_t.nominal_thrust.to_bits(), free_alpha.to_bits())
        );

        // Lower bound: near hover, a minimum above the weight lifts U1.
        let hover = Reference { position: [0.3, 0.2, 0.0], ..Reference::default() };
        let lo = 1.5 * m * g;
        let (cmd, t, _) = step(Some([lo, 3.0 * m * g]), &hover);
        assert_eq!(cmd.thrust.to_bits(), lo.to_bits());
        assert!(t.thrust_limited && t.attitude_demand.iter().all(|d| *d != 0.0));
        assert_eq!(t.attitude_demand.map(f64::to_bits), demand_for(&t, lo, 0.0).map(f64::to_bits));

        // Inside the bounds nothing changes, bit for bit.
        let (free, free_t, _) = step(None, &hover);
        let (cmd, t, _) = step(Some([0.0, 1e3]), &hover);
        assert_eq!(cmd.thrust.to_bits(), free.thrust.to_bits());
        assert_eq!(cmd.torque.map(f64::to_bits), free.torque.map(f64::to_bits));
        assert_eq!(t, free_t);
        assert!(!t.thrust_limited);
    }

    #[test]
    fn thrust_limits_are_validated() {
        for (limits, field) in [
            ([-1.0, 10.0], "thrust_limits[0]"),
            ([f64::NAN, 10.0], "thrust_limits[0]"),
            ([f64::INFINITY, f64::INFINITY], "thrust_limits[0]"),
            ([1e200, 1e201], "thrust_limits[0]"),
            ([0.0, 1e101], "thrust_limits[1]"),
            ([5.0, 5.0], "thrust_limits[1]"),
            ([5.0, 1.0], "thrust_limits[1]"),
            ([0.0, f64::INFINITY], "thrust_limits[1]"),
            ([0.0, f64::NAN], "thrust_limits[1]"),
        ] {
            let settings = zero_derivatives(Some(limits));
            assert_eq!(settings.check().unwrap_err().field, field, "{limits:?}");
            let err = Cascade::new(paper_config(settings, MassAdaptation::PAPER), paper_laws()).unwrap_err();
            assert_eq!(err.field, field);
            // Unchecked, it must not panic.
            let mut c = Cascade::new_unchecked(paper_config(settings, MassAdaptation::PAPER), paper_laws());
            c.update(&QuadState::default(), &Reference { position: [0.5, 0.0, 1.0], ..Reference::default() }, 1e-3);
        }
        zero_derivatives(Some([0.0, 10.0])).check().unwrap();
        zero_derivatives(Some([1e99, 1e100])).check().unwrap();
        assert_eq!(CascadeSettings::default().thrust_limits, None);
        assert!(!CascadeSettings::default().freeze_adaptation_on_saturation);
    }

    /// A swinging vehicle chasing an offset reference: step `k`.
    fn wobble(k: usize) -> (QuadState, Reference) {
        let t = k as f64 * 1e-3;
        let state = QuadState {
            position: [0.2 * crate::math::sin(3.0 * t), -0.1 * crate::math::cos(2.0 * t), 0.5 * t],
            velocity: [0.6 * crate::math::cos(3.0 * t), 0.2 * crate::math::sin(2.0 * t), 0.5],
            attitude: [0.1 * crate::math::sin(7.0 * t), -0.08 * crate::math::cos(5.0 * t), 0.02 * t],
            angular_rate: [0.7 * crate::math::cos(7.0 * t), 0.4 * crate::math::sin(5.0 * t), 0.02],
        };
        let reference = Reference { position: [1.0, -0.5, 2.0], ..Reference::default() };
        (state, reference)
    }

    fn command_bits(c: &Command) -> [u64; 4] {
        [c.thrust.to_bits(), c.torque[0].to_bits(), c.torque[1].to_bits(), c.torque[2].to_bits()]
    }

    /// Issue 11 item 6, for one controller built by `make`:
    /// - option on with `actuator_feedback(false)`, and option off with
    ///   `actuator_feedback(true)`, are bit-identical to the defaults;
    /// - option on after `actuator_feedback(true)`: the law states and α̂
    ///   hold bit for bit while the commands still follow the error;
    /// - `actuator_feedback(false)` releases them, `reset` clears the report.
    fn check_cascade_freeze<L: AxisLaw + Clone>(make: impl Fn(CascadeSettings) -> Cascade<L>) {
        let freeze = CascadeSettings { freeze_adaptation_on_saturation: true, ..CascadeSettings::default() };
        let mut on = make(freeze);
        let mut off = make(CascadeSettings::default());
        let mut ignored = make(CascadeSettings::default());
        for k in 0..40 {
            let (state, reference) = wobble(k);
            on.actuator_feedback(false);
            ignored.actuator_feedback(true);
            let a = on.update(&state, &reference, 1e-3);
            let b = off.update(&state, &reference, 1e-3);
            let c = ignored.update(&state, &reference, 1e-3);
            assert_eq!(command_bits(&a), command_bits(&b), "step {k}");
            assert_eq!(command_bits(&c), command_bits(&b), "step {k}");
            assert_eq!(on.telemetry(), off.telemetry());
            assert_eq!(ignored.telemetry(), off.telemetry());
            assert!(!on.telemetry().sliding_mode.unwrap().adaptation_frozen);
        }

        on.actuator_feedback(true);
        assert!(on.actuator_saturated());
        let held = (on.telemetry().estimates, on.alpha_hat());
        let held_bits = (held.0.map(|e| e.map(f64::to_bits)), held.1.to_bits());
        let mut commands = [[0u64; 4]; 10];
        for (i, k) in (40..50).enumerate() {
            let (state, reference) = wobble(k);
            let cmd = on.update(&state, &reference, 1e-3);
            assert!(cmd.thrust.is_finite() && cmd.torque.iter().all(|t| t.is_finite()));
            commands[i] = command_bits(&cmd);
            let t = on.telemetry();
            assert!(t.sliding_mode.unwrap().adaptation_frozen);
            assert_eq!((t.estimates.map(|e| e.map(f64::to_bits)), on.alpha_hat().to_bits()), held_bits, "step {k}");
        }
        assert!(commands.windows(2).all(|w| w[0] != w[1]), "frozen commands ignore the error");

        on.actuator_feedback(false);
        let (state, reference) = wobble(50);
        on.update(&state, &reference, 1e-3);
        assert!(!on.telemetry().sliding_mode.unwrap().adaptation_frozen);
        assert_ne!(on.telemetry().estimates, held.0, "released states do not move");

        on.actuator_feedback(true);
        on.reset();
        assert!(!on.actuator_saturated());
        on.update(&state, &reference, 1e-3);
        assert!(!on.telemetry().sliding_mode.unwrap().adaptation_frozen);
    }

    #[test]
    fn freezing_on_saturation_holds_delta_hat_and_alpha_hat() {
        check_cascade_freeze(paper_ftaftsmc);
        // α̂ moves when released (the generic check looks at the laws only).
        let mut c =
            paper_ftaftsmc(CascadeSettings { freeze_adaptation_on_saturation: true, ..CascadeSettings::default() });
        let (state, reference) = wobble(3);
        c.actuator_feedback(true);
        c.update(&state, &reference, 1e-3);
        assert_eq!(c.alpha_hat(), MassAdaptation::PAPER.alpha_hat0);
        c.actuator_feedback(false);
        c.update(&state, &reference, 1e-3);
        assert_ne!(c.alpha_hat(), MassAdaptation::PAPER.alpha_hat0);
    }

    #[test]
    fn freezing_on_saturation_holds_a_hat_of_ranftsmc() {
        use crate::ranftsmc::{RanftsmcAxis, RanftsmcGains};
        check_cascade_freeze(|settings| {
            let p = RanftsmcAxis::new(RanftsmcGains::PAPER_POSITION);
            let a = RanftsmcAxis::new(RanftsmcGains::PAPER_ATTITUDE);
            Cascade::new(paper_config(settings, MassAdaptation::OFF), [p, p, p, a, a, a]).unwrap()
        });
    }

    #[test]
    fn freezing_on_saturation_holds_nu_of_tsm_sta() {
        use crate::tsm_sta::{TsmStaAxis, TsmStaGains};
        check_cascade_freeze(|settings| {
            let p = TsmStaAxis::new(TsmStaGains::DEFAULT_POSITION);
            let a = TsmStaAxis::new(TsmStaGains::DEFAULT_ATTITUDE);
            Cascade::new(paper_config(settings, MassAdaptation::OFF), [p, p, p, a, a, a]).unwrap()
        });
    }
}
