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
//!
//! # Lanes
//!
//! `Cascade<L, R>` is generic over the number type ([`crate::lanes`]):
//! `Cascade<FtaftsmcAxis>` is one flight (`R = f64`), and
//! `Cascade<FtaftsmcAxis<Lanes<N>>, Lanes<N>>` (built with
//! [`Cascade::with_laws`]) flies `N` flights with one configuration, each
//! lane with the bits of the one-flight cascade. Everything above holds per
//! lane: the attitude demand, the thrust and tilt limits, α̂ and its freeze
//! (the saturation report is a per-lane mask), the command filter (a lane
//! restarted with [`Controller::reset_lane`] starts its filter again), and
//! the refusal of a non-finite state or reference (NaN command in that
//! lane, every state of that lane kept).

use crate::allocation::{residual_speed, rotor_speeds};
use crate::lanes::{branch, Blend, Lanewise, Mask, Real};
use crate::law::{
    check_closed, check_gain, check_left_open, check_open, saturate, AxisLaw, GainError, INPUT_LIMIT, MAX_ESTIMATES,
    STATE_LIMIT,
};
use crate::math::{finite_probe, sin_cos};
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

/// One command-filter channel: value, rate and whether it has started
/// (per lane: a lane restarted by [`Controller::reset_lane`] starts again).
#[derive(Clone, Copy, Debug, Default)]
struct FilterState<R: Real = f64> {
    value: R,
    rate: R,
    initialised: R::Mask,
}
crate::lanewise_struct!(FilterState { value, rate, initialised });

/// `(sin ψ_d, cos ψ_d)` of the last reference heading of each lane, computed
/// again only for the lanes whose heading bits changed: [`sin_cos`] of each
/// lane's argument, bit for bit (one [`crate::math::SinCosCache`] per lane).
#[derive(Clone, Copy, Debug)]
struct YawSinCos<R: Real = f64> {
    arg: R,
    sin: R,
    cos: R,
}

impl<R: Real> YawSinCos<R> {
    fn new() -> Self {
        let (s, c) = sin_cos(0.0);
        Self { arg: R::splat(0.0), sin: R::splat(s), cos: R::splat(c) }
    }

    #[cfg_attr(not(debug_assertions), inline(always))]
    fn get(&mut self, x: R) -> (R, R) {
        for i in 0..R::LANES {
            let xi = x.get_lane(i);
            if xi.to_bits() != self.arg.get_lane(i).to_bits() {
                let (s, c) = sin_cos(xi);
                self.sin.put_lane(i, s);
                self.cos.put_lane(i, c);
                self.arg.put_lane(i, xi);
            }
        }
        (self.sin, self.cos)
    }
}

/// Smallest `cφ cθ` used when dividing by it (tilt ≈ 87°); beyond this the
/// simulation declares divergence anyway.
const MIN_TILT_COSINE: f64 = 0.05;

/// The cascade of six axis laws of type `L`, of one flight (`R = f64`, the
/// default) or of several side by side (`R` a lane type with `L` the laws
/// on lanes, e.g. `Cascade<FtaftsmcAxis<Lanes<4>>, Lanes<4>>`): the
/// configuration is shared, lane `i`'s command, telemetry and states have
/// the bits of the one-flight cascade fed lane `i`'s states and references.
#[derive(Clone, Debug)]
pub struct Cascade<L, R: Real = f64> {
    /// Configuration.
    pub config: CascadeConfig,
    /// Laws for `[x, y, z, φ, θ, ψ]`.
    pub laws: [L; 6],
    filter: [FilterState<R>; 2],
    alpha_hat: R,
    last_command: Command<R>,
    telemetry: Telemetry<R>,
    /// `sin(max_tilt)`, the clamp of the asin arguments of Eq. 52.
    tilt_limit: f64,
    /// Last [`Controller::actuator_feedback`] report.
    actuator_saturated: R::Mask,
    /// The freeze flag last given to the laws
    /// ([`AxisLaw::set_adaptation_frozen`]), kept in the lanes whose
    /// update is refused (non-finite input) as the scalar cascade keeps it.
    laws_frozen: R::Mask,
    /// `sin`, `cos` of the last reference heading ψ_d (Eq. 52).
    yaw_sin_cos: YawSinCos<R>,
}

impl<L: AxisLaw> Cascade<L> {
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
    ///
    /// One flight; [`Cascade::with_laws`] builds the cascade on lanes.
    pub fn new(config: CascadeConfig, laws: [L; 6]) -> Result<Self, GainError> {
        Self::with_laws(config, laws)
    }

    /// [`Cascade::new`] without validation. Never panics, whatever the
    /// configuration (a NaN `max_tilt` or inverted `alpha_hat_bounds` give
    /// NaN or meaningless commands instead); the finiteness guarantee of
    /// [`Cascade::new`] holds only for configurations it would accept.
    pub fn new_unchecked(config: CascadeConfig, laws: [L; 6]) -> Self {
        Self::with_laws_unchecked(config, laws)
    }

    /// Desired roll and pitch from the virtual controls (Eq. 52 corrected:
    /// θ_d divides by cos φ_d), asin arguments clamped to `±sin(max_tilt)`.
    pub fn desired_roll_pitch(ux: f64, uy: f64, yaw_d: f64, max_tilt: f64) -> [f64; 2] {
        Self::desired_roll_pitch_limited(ux, uy, yaw_d, crate::math::sin(max_tilt))
    }

    /// [`Cascade::desired_roll_pitch`] with the clamp `limit = sin(max_tilt)` precomputed.
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn desired_roll_pitch_limited(ux: f64, uy: f64, yaw_d: f64, limit: f64) -> [f64; 2] {
        desired_roll_pitch_at(ux, uy, sin_cos(yaw_d), limit)
    }
}

/// `thrust` bounded to `[lo, hi]` (no `f64::clamp`: never panics; the lower
/// bound tested first); unchanged without bounds.
#[cfg_attr(not(debug_assertions), inline(always))]
fn bound_thrust<R: Real>(thrust: R, limits: Option<[f64; 2]>) -> R {
    match limits {
        Some([lo, hi]) => {
            let (lo, hi) = (R::splat(lo), R::splat(hi));
            R::select(thrust.lt(lo), lo, R::select(thrust.gt(hi), hi, thrust))
        }
        None => thrust,
    }
}

/// [`Cascade::desired_roll_pitch_limited`] with `(sin ψ_d, cos ψ_d)` given,
/// per lane for lanes.
#[cfg_attr(not(debug_assertions), inline(always))]
fn desired_roll_pitch_at<R: Real>(ux: R, uy: R, (s_psi, c_psi): (R, R), limit: f64) -> [R; 2] {
    let limit = R::splat(limit);
    // `saturate`, not `f64::clamp`: it does not panic on a NaN limit.
    let sin_roll = saturate(ux * s_psi - uy * c_psi, limit);
    let roll = sin_roll.asin();
    // cos φ_d = √((1 − sin φ_d)(1 + sin φ_d)), equal to cos(asin(·)) to
    // rounding (|sin φ_d| <= sin(max_tilt) < 1), without the cosine.
    let cos_roll = ((R::splat(1.0) - sin_roll) * (sin_roll + 1.0)).sqrt();
    let pitch = saturate((ux * c_psi + uy * s_psi) / cos_roll, limit).asin();
    [roll, pitch]
}

/// Every component of the reference is finite (per lane).
#[cfg_attr(not(debug_assertions), inline(always))]
fn reference_finite<R: Real>(r: &Reference<R>) -> R::Mask {
    (finite_probe(&r.position)
        + finite_probe(&r.velocity)
        + finite_probe(&r.acceleration)
        + finite_probe(&[r.yaw, r.yaw_rate, r.yaw_acceleration]))
    .eq(R::splat(0.0))
}

impl<R: Real, L: AxisLaw<R>> Cascade<L, R> {
    /// The telemetry before the first update: zeros, and α̂ at `alpha_hat`.
    fn initial_telemetry(alpha_hat: f64) -> Telemetry<R> {
        Telemetry {
            sliding_mode: Some(SlidingTelemetry { alpha_hat: R::splat(alpha_hat), ..SlidingTelemetry::default() }),
            ..Telemetry::default()
        }
    }

    /// The hover command `m g`, zero torques (the command before the first
    /// update, for the gyroscopic cancellation).
    fn hover(model: &QuadrotorParams) -> Command<R> {
        Command { thrust: R::splat(model.mass * model.gravity), torque: [R::splat(0.0); 3] }
    }

    /// [`Cascade::new`] for any number type: the same validation, every
    /// lane at the initial states.
    pub fn with_laws(config: CascadeConfig, laws: [L; 6]) -> Result<Self, GainError> {
        config.model.check()?;
        config.settings.check()?;
        config.mass_adaptation.check()?;
        for law in &laws {
            law.check_gains()?;
        }
        Ok(Self::with_laws_unchecked(config, laws))
    }

    /// [`Cascade::new_unchecked`] for any number type.
    pub fn with_laws_unchecked(config: CascadeConfig, laws: [L; 6]) -> Self {
        Self {
            config,
            laws,
            filter: [FilterState::default(); 2],
            alpha_hat: R::splat(config.mass_adaptation.alpha_hat0),
            last_command: Self::hover(&config.model),
            telemetry: Self::initial_telemetry(config.mass_adaptation.alpha_hat0),
            tilt_limit: crate::math::sin(config.settings.max_tilt),
            actuator_saturated: R::Mask::splat(false),
            laws_frozen: R::Mask::splat(false),
            yaw_sin_cos: YawSinCos::new(),
        }
    }

    /// Current mass-ratio estimate α̂ (per lane).
    pub fn alpha_hat(&self) -> R {
        self.alpha_hat
    }

    /// Last [`Controller::actuator_feedback`] report (false until the first).
    pub fn actuator_saturated(&self) -> R::Mask {
        self.actuator_saturated
    }

    /// The command filter's output `(r, ṙ, r̈)` for the Eq. 52 demand, and
    /// its states advanced by `dt` (per lane: a lane not yet initialised
    /// starts from its own demand or attitude).
    fn attitude_reference(&mut self, demand: [R; 2], state: &QuadState<R>, dt: f64) -> ([R; 2], [R; 2], [R; 2]) {
        let zero = R::splat(0.0);
        match self.config.settings.attitude_derivatives {
            AttitudeDerivatives::Zero => (demand, [zero; 2], [zero; 2]),
            AttitudeDerivatives::CommandFilter => {
                let wn = self.config.settings.command_filter.natural_frequency;
                let zeta = self.config.settings.command_filter.damping;
                let init = self.config.settings.filter_init;
                let limit = R::splat(STATE_LIMIT);
                let mut value = [zero; 2];
                let mut rate = [zero; 2];
                let mut accel = [zero; 2];
                for i in 0..2 {
                    let current = self.filter[i];
                    let f = branch(
                        current.initialised,
                        #[cfg_attr(not(debug_assertions), inline(always))]
                        || current,
                        #[cfg_attr(not(debug_assertions), inline(always))]
                        || match init {
                            FilterInit::FirstDemand => {
                                FilterState { value: demand[i], rate: zero, initialised: R::Mask::splat(true) }
                            }
                            FilterInit::VehicleAttitude => FilterState {
                                value: saturate(state.attitude[i], limit),
                                rate: saturate(state.angular_rate[i], limit),
                                initialised: R::Mask::splat(true),
                            },
                        },
                    );
                    let a = (demand[i] - f.value) * (wn * wn) - f.rate * (2.0 * zeta * wn);
                    value[i] = f.value;
                    rate[i] = f.rate;
                    accel[i] = a;
                    // Semi-implicit Euler on the control clock, states
                    // saturated so that an unstable ω_n·dt stays finite.
                    let next_rate = saturate(f.rate + a * dt, limit);
                    let next_value = saturate(f.value + next_rate * dt, limit);
                    self.filter[i] = FilterState { value: next_value, rate: next_rate, initialised: f.initialised };
                }
                (value, rate, accel)
            }
        }
    }
}

impl<R: Real, L: AxisLaw<R>> Controller<R> for Cascade<L, R> {
    fn name(&self) -> &'static str {
        L::NAME
    }

    /// See [`Cascade::new`] for the finiteness contract. Guards, all no-ops
    /// on meaningful inputs: commanded accelerations and the angular rates
    /// used in the cancellation terms clamped to `±INPUT_LIMIT`; `S_z` in
    /// Eq. 44, α̂ and the command-filter states saturated to `±STATE_LIMIT`.
    ///
    /// Lanes: a lane whose state or reference is not finite gets a NaN
    /// command and keeps every state (its laws are fed NaN errors, which
    /// leaves them untouched by the [`AxisLaw::update`] contract); the
    /// other lanes fly on.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn update(&mut self, state: &QuadState<R>, reference: &Reference<R>, dt: f64) -> Command<R> {
        let nan = Command { thrust: R::splat(f64::NAN), torque: [R::splat(f64::NAN); 3] };
        if !dt.is_finite() {
            return nan;
        }
        let inputs_ok = state.is_finite() & reference_finite(reference);
        if !inputs_ok.any() {
            return nan;
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
        let ok = inputs_ok & finite_probe(&differences).eq(R::splat(0.0));
        if !ok.any() {
            return nan;
        }
        // Lanes whose input is refused: NaN errors to the laws (they keep
        // their states), every cascade state restored below. For one flight
        // `ok` is true here and this is the identity.
        let refuse = |x: R| R::select(ok, x, R::splat(f64::NAN));
        let model = self.config.model;
        let m = model.mass;
        let g = model.gravity;
        let settings = self.config.settings;
        let limit = R::splat(INPUT_LIMIT);
        let old_filter = self.filter;

        // Saturation remedy: hold every adaptive state after a saturation
        // report. Set on all six laws every update (a store), so a law
        // replaced through the public `laws` field is still governed.
        let frozen =
            if settings.freeze_adaptation_on_saturation { self.actuator_saturated } else { R::Mask::splat(false) };
        let laws_frozen = R::Mask::blend(ok, frozen, self.laws_frozen);
        self.laws_frozen = laws_frozen;
        for law in &mut self.laws {
            law.set_adaptation_frozen(laws_frozen);
        }

        // Outer loop: commanded accelerations (Eq. 18–20).
        let mut accel = [R::splat(0.0); 3];
        for i in 0..3 {
            let e = refuse(state.position[i] - reference.position[i]);
            let e_dot = state.velocity[i] - reference.velocity[i];
            accel[i] = saturate(reference.acceleration[i] + self.laws[i].update(e, e_dot, dt), limit);
        }
        let [phi, theta, _] = state.attitude;
        let tilt_cos = (phi.cos() * theta.cos()).max(R::splat(MIN_TILT_COSINE));
        let nominal_thrust = (accel[2] + g) * m / tilt_cos;

        // Mass adaptation (§3.2, Eq. 44): U1 = α̂ u1.
        let ma = self.config.mass_adaptation;
        let unbounded_thrust = if ma.enabled { self.alpha_hat * nominal_thrust } else { nominal_thrust };
        // Saturation remedy: U1 bounded to what the rotors can give, before
        // Remark 2 uses it, so the attitude demand matches the real thrust.
        let thrust = bound_thrust(unbounded_thrust, settings.thrust_limits);
        let horizontal_mass = if ma.enabled && ma.compensate_horizontal { self.alpha_hat * m } else { R::splat(m) };
        if ma.enabled {
            let s_z = saturate(self.laws[2].sliding_variable(), R::splat(STATE_LIMIT));
            let rate = (s_z * nominal_thrust * tilt_cos / m + self.alpha_hat * ma.beta2) * -ma.beta1;
            let mut alpha_hat = self.alpha_hat + rate * dt;
            if let Some([lo, hi]) = ma.alpha_hat_bounds {
                // Not `f64::clamp`, which panics on NaN or inverted bounds.
                let (lo, hi) = (R::splat(lo), R::splat(hi));
                alpha_hat = R::select(alpha_hat.lt(lo), lo, R::select(alpha_hat.gt(hi), hi, alpha_hat));
            }
            let alpha_hat = saturate(alpha_hat, R::splat(STATE_LIMIT));
            self.alpha_hat = R::select(ok & !frozen, alpha_hat, self.alpha_hat);
        }

        // Remark 2: u_x = m a_x / U1, u_y = m a_y / U1; guard U1 → 0.
        let thrust_for_inversion = thrust.max(R::splat(1e-3 * m * g));
        let ux = horizontal_mass * accel[0] / thrust_for_inversion;
        let uy = horizontal_mass * accel[1] / thrust_for_inversion;
        let demand = desired_roll_pitch_at(ux, uy, self.yaw_sin_cos.get(reference.yaw), self.tilt_limit);
        let (att_ref, att_rate, att_accel) = self.attitude_reference(demand, state, dt);
        self.filter = <[FilterState<R>; 2]>::blend(ok, self.filter, old_filter);
        let reference_attitude = [att_ref[0], att_ref[1], reference.yaw];
        let reference_rate = [att_rate[0], att_rate[1], reference.yaw_rate];
        let reference_accel = [att_accel[0], att_accel[1], reference.yaw_acceleration];

        // Inner loop: angular accelerations then torques (Eq. 56–58).
        let mut angular_accel = [R::splat(0.0); 3];
        for i in 0..3 {
            let e = refuse(state.attitude[i] - reference_attitude[i]);
            let e_dot = state.angular_rate[i] - reference_rate[i];
            angular_accel[i] = saturate(reference_accel[i] + self.laws[3 + i].update(e, e_dot, dt), limit);
        }
        let [p, q, r] = state.angular_rate.map(|w| saturate(w, limit));
        let [i1, i2, i3] = model.inertia;
        let [k1, k2, k3] = model.drag_rotational;
        let omega_bar = residual_speed(&rotor_speeds(&model, &self.last_command, f64::INFINITY));
        let jr = model.rotor_inertia;
        // Plant (paper Eq. 1): I φ̈ = coupling − J_r Ω̄ θ̇ − K φ̇|φ̇| + u, so u = I v − (…).
        let torque = [
            angular_accel[0] * i1 - (q * (i2 - i3) * r - omega_bar * jr * q - p * k1 * p.abs()),
            angular_accel[1] * i2 - (p * (i3 - i1) * r + omega_bar * jr * p - q * k2 * q.abs()),
            angular_accel[2] * i3 - (p * (i1 - i2) * q - r * k3 * r.abs()),
        ];
        let command = Command { thrust, torque };
        self.last_command = Command::blend(ok, command, self.last_command);

        let mut sliding = [R::splat(0.0); 6];
        let mut estimates = [[R::splat(0.0); MAX_ESTIMATES]; 6];
        for i in 0..6 {
            sliding[i] = self.laws[i].sliding_variable();
            estimates[i] = self.laws[i].estimates();
        }
        let telemetry = Telemetry {
            attitude_reference: reference_attitude,
            attitude_reference_rate: reference_rate,
            attitude_reference_acceleration: reference_accel,
            attitude_demand: demand,
            estimates,
            commanded_acceleration: accel,
            nominal_thrust,
            thrust_limited: !thrust.eq(unbounded_thrust),
            sliding_mode: Some(SlidingTelemetry { sliding, alpha_hat: self.alpha_hat, adaptation_frozen: frozen }),
        };
        self.telemetry = Telemetry::blend(ok, telemetry, self.telemetry);
        Command::blend(ok, command, nan)
    }

    fn telemetry(&self) -> &Telemetry<R> {
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
        self.filter = [FilterState::default(); 2];
        self.alpha_hat = R::splat(self.config.mass_adaptation.alpha_hat0);
        self.last_command = Self::hover(&self.config.model);
        self.actuator_saturated = R::Mask::splat(false);
        self.laws_frozen = R::Mask::splat(false);
        self.telemetry = Self::initial_telemetry(self.config.mass_adaptation.alpha_hat0);
    }

    /// Lane `lane` back to the initial states (laws through
    /// [`AxisLaw::reset_lane`], filter, α̂, last command, saturation report,
    /// telemetry), the other lanes untouched.
    fn reset_lane(&mut self, lane: usize) {
        for law in &mut self.laws {
            law.reset_lane(lane);
        }
        for f in &mut self.filter {
            f.put_lane(lane, FilterState::default());
        }
        let alpha_hat0 = self.config.mass_adaptation.alpha_hat0;
        self.alpha_hat.put_lane(lane, alpha_hat0);
        let model = self.config.model;
        self.last_command.put_lane(lane, Command { thrust: model.mass * model.gravity, torque: [0.0; 3] });
        self.actuator_saturated.put_lane(lane, false);
        self.laws_frozen.put_lane(lane, false);
        self.telemetry.put_lane(lane, Cascade::<L, R>::initial_telemetry(alpha_hat0).get_lane(0));
    }

    fn actuator_feedback(&mut self, saturated: R::Mask) {
        self.actuator_saturated = saturated;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ftaftsmc::{FtaftsmcAxis, FtaftsmcGains};
    use crate::lanes::{LaneMask, Lanes};

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

    /// Regression: a NaN `max_tilt` reached `f64::clamp(NaN, NaN)` in
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

    /// Regression: inverted `alpha_hat_bounds` reached `f64::clamp(lo, hi)` with
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

    /// Saturation remedy: the thrust bound acts on U1 before Remark 2, so the
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

    /// Saturation remedies, for one controller built by `make`:
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

    /// Knuth's MMIX LCG for the lane tests: uniform in `[-1, 1)`.
    struct Lcg(u64);

    impl Lcg {
        fn next(&mut self) -> f64 {
            self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        }
    }

    /// Every number of a one-flight telemetry, as bits (masks as 0/1).
    fn telemetry_bits(t: &Telemetry) -> Vec<u64> {
        let mut v = Vec::new();
        v.extend(t.attitude_reference.map(f64::to_bits));
        v.extend(t.attitude_reference_rate.map(f64::to_bits));
        v.extend(t.attitude_reference_acceleration.map(f64::to_bits));
        v.extend(t.attitude_demand.map(f64::to_bits));
        for e in t.estimates {
            v.extend(e.map(f64::to_bits));
        }
        v.extend(t.commanded_acceleration.map(f64::to_bits));
        v.push(t.nominal_thrust.to_bits());
        v.push(u64::from(t.thrust_limited));
        let sm = t.sliding_mode.expect("the cascade reports its sliding part");
        v.extend(sm.sliding.map(f64::to_bits));
        v.push(sm.alpha_hat.to_bits());
        v.push(u64::from(sm.adaptation_frozen));
        v
    }

    /// The states of a one-flight cascade the telemetry does not show, as
    /// bits: α̂, the filter, the last command, the saturation report, the
    /// laws' freeze flag and every law state.
    fn state_bits(c: &Cascade<FtaftsmcAxis>) -> Vec<u64> {
        let mut v = vec![c.alpha_hat.to_bits(), u64::from(c.actuator_saturated), u64::from(c.laws_frozen)];
        for f in c.filter {
            v.extend([f.value.to_bits(), f.rate.to_bits(), u64::from(f.initialised)]);
        }
        v.extend(command_bits(&c.last_command));
        for l in &c.laws {
            let t = l.last;
            v.extend(
                [l.delta_hat, t.y, t.y_dot, t.s_delta, t.s_delta_dot, t.s, t.varpi, l.last_reaching].map(f64::to_bits),
            );
            v.push(u64::from(l.adaptation_frozen()));
        }
        v
    }

    /// Lane `i` of a cascade on lanes, as a one-flight cascade's states.
    fn lane_state_bits<const N: usize>(c: &Cascade<FtaftsmcAxis<Lanes<N>>, Lanes<N>>, i: usize) -> Vec<u64> {
        let laws: [FtaftsmcAxis; 6] = core::array::from_fn(|k| c.laws[k].get_lane(i));
        let one = Cascade {
            config: c.config,
            laws,
            filter: c.filter.map(|f| f.get_lane(i)),
            alpha_hat: c.alpha_hat.get_lane(i),
            last_command: c.last_command.get_lane(i),
            telemetry: c.telemetry.get_lane(i),
            tilt_limit: c.tilt_limit,
            actuator_saturated: c.actuator_saturated.get_lane(i),
            laws_frozen: c.laws_frozen.get_lane(i),
            yaw_sin_cos: YawSinCos::new(),
        };
        state_bits(&one)
    }

    /// What the lane test saw, to check that every case happened.
    #[derive(Debug, Default)]
    struct Seen {
        refused: usize,
        frozen: usize,
        thrust_limited: usize,
        tilt_limited: usize,
        resets: usize,
    }

    /// The cascade of FTAFTSMC laws on `Lanes<N>` against `N` one-flight
    /// cascades fed each lane's measurements and references, 300 periods:
    /// per lane and bit for bit, commands, telemetry and every state. The
    /// lanes fly different wobbles towards different references (some far
    /// enough to hit the tilt and thrust limits), report actuator
    /// saturation at different times, one gets a NaN measurement and one an
    /// infinite reference at some period, and one is restarted with
    /// `reset_lane` mid-run (its scalar twin with `reset`).
    fn cascade_lanes_match_scalar<const N: usize>(
        settings: CascadeSettings,
        mass_adaptation: MassAdaptation,
        seed: u64,
    ) -> Seen {
        let config = paper_config(settings, mass_adaptation);
        let g = [
            FtaftsmcGains::PAPER_XY,
            FtaftsmcGains::PAPER_XY,
            FtaftsmcGains::PAPER_Z,
            FtaftsmcGains::PAPER_ROLL_PITCH,
            FtaftsmcGains::PAPER_ROLL_PITCH,
            FtaftsmcGains::PAPER_YAW,
        ];
        let mut lanes =
            Cascade::<FtaftsmcAxis<Lanes<N>>, Lanes<N>>::with_laws(config, g.map(FtaftsmcAxis::with_gains)).unwrap();
        let mut scalar: [Cascade<FtaftsmcAxis>; N] =
            core::array::from_fn(|_| Cascade::new(config, g.map(FtaftsmcAxis::new)).unwrap());
        let mut rng = Lcg(seed);
        let mut seen = Seen::default();
        let tilt_sin = crate::math::sin(settings.max_tilt);
        for k in 0..300 {
            let mut states = [QuadState::default(); N];
            let mut references = [Reference::default(); N];
            for i in 0..N {
                let (mut state, _) = wobble(k + 37 * i);
                for v in [&mut state.position, &mut state.velocity, &mut state.attitude, &mut state.angular_rate] {
                    for x in v.iter_mut() {
                        *x += 0.05 * rng.next();
                    }
                }
                let far = 1.0 + 4.0 * (i % 3) as f64;
                references[i] = Reference {
                    position: [far * rng.next(), far * rng.next(), 1.0 + far * rng.next()],
                    velocity: [0.1 * rng.next(), 0.0, 0.2 * rng.next()],
                    acceleration: [0.0, 0.1 * rng.next(), 0.0],
                    // Lane 0 keeps its heading (the sin/cos cache hits), the others move it.
                    yaw: if i == 0 { 0.3 } else { 0.5 * rng.next() },
                    yaw_rate: 0.01 * i as f64,
                    yaw_acceleration: 0.0,
                };
                if i % 4 == 1 && k % 11 == 0 {
                    // Exactly at the reference: zero errors.
                    state.position = references[i].position;
                    state.velocity = references[i].velocity;
                }
                states[i] = state;
            }
            if k == 90 {
                states[1].velocity[2] = f64::NAN;
            }
            if k == 91 {
                references[2 % N].yaw = f64::INFINITY;
            }
            if k == 92 {
                // Finite, but the difference overflows.
                states[3 % N].position[0] = 1e308;
                references[3 % N].position[0] = -1e308;
            }
            if k == 150 {
                lanes.reset_lane(1);
                scalar[1].reset();
                seen.resets += 1;
            }
            // Lane i reports saturation during its own window of periods.
            let saturated: [bool; N] = core::array::from_fn(|i| (k + 13 * i) % 60 >= 40);
            let mut report = LaneMask::<N>::splat(false);
            for i in 0..N {
                report.put_lane(i, saturated[i]);
            }
            lanes.actuator_feedback(report);
            let state = QuadState::<Lanes<N>>::default();
            let mut state = state;
            let mut reference = Reference::<Lanes<N>>::default();
            for i in 0..N {
                state.put_lane(i, states[i]);
                reference.put_lane(i, references[i]);
            }
            let dt = if k == 200 { 0.0 } else { 1e-3 };
            let cmd = lanes.update(&state, &reference, dt);
            for i in 0..N {
                scalar[i].actuator_feedback(saturated[i]);
                let want = scalar[i].update(&states[i], &references[i], dt);
                assert_eq!(command_bits(&cmd.get_lane(i)), command_bits(&want), "N={N} step {k} lane {i}");
                let t = scalar[i].telemetry();
                assert_eq!(
                    telemetry_bits(&lanes.telemetry().get_lane(i)),
                    telemetry_bits(t),
                    "N={N} step {k} lane {i}"
                );
                assert_eq!(lane_state_bits(&lanes, i), state_bits(&scalar[i]), "N={N} step {k} lane {i}");
                assert_eq!(lanes.alpha_hat().get_lane(i).to_bits(), scalar[i].alpha_hat().to_bits());
                seen.refused += usize::from(want.thrust.is_nan());
                let sm = t.sliding_mode.unwrap();
                seen.frozen += usize::from(sm.adaptation_frozen && !want.thrust.is_nan());
                seen.thrust_limited += usize::from(t.thrust_limited && !want.thrust.is_nan());
                seen.tilt_limited += usize::from(
                    !want.thrust.is_nan()
                        && t.attitude_demand.iter().any(|d| crate::math::sin(*d).abs() >= tilt_sin * (1.0 - 1e-12)),
                );
            }
        }
        seen
    }

    /// The cascade on lanes flies each lane with the bits of the one-flight
    /// cascade, with the paper's settings and with each saturation remedy
    /// and option of the settings on.
    #[test]
    fn lanes_give_each_flight_the_bits_of_the_scalar_cascade() {
        let paper = CascadeSettings::default();
        let freeze = CascadeSettings { freeze_adaptation_on_saturation: true, ..paper };
        let thrust = CascadeSettings { thrust_limits: Some([5.0, 9.0]), ..paper };
        let tilt = CascadeSettings { max_tilt: 0.15, ..paper };
        let vehicle_init = CascadeSettings { filter_init: FilterInit::VehicleAttitude, ..paper };
        let zero = CascadeSettings { attitude_derivatives: AttitudeDerivatives::Zero, ..paper };
        let slow_filter =
            CascadeSettings { command_filter: CommandFilterParams { natural_frequency: 8.0, damping: 0.7 }, ..paper };
        let all = CascadeSettings {
            freeze_adaptation_on_saturation: true,
            thrust_limits: Some([5.0, 9.0]),
            max_tilt: 0.2,
            filter_init: FilterInit::VehicleAttitude,
            ..paper
        };
        let bounded =
            MassAdaptation { alpha_hat_bounds: Some([0.9, 1.1]), compensate_horizontal: true, ..MassAdaptation::PAPER };
        let cases = [
            (paper, MassAdaptation::PAPER),
            (freeze, MassAdaptation::PAPER),
            (thrust, MassAdaptation::PAPER),
            (tilt, MassAdaptation::PAPER),
            (vehicle_init, MassAdaptation::PAPER),
            (zero, MassAdaptation::PAPER),
            (slow_filter, MassAdaptation::PAPER),
            (paper, MassAdaptation::OFF),
            (paper, bounded),
            (all, bounded),
        ];
        for (j, (settings, ma)) in cases.into_iter().enumerate() {
            let four = cascade_lanes_match_scalar::<4>(settings, ma, 5 + j as u64);
            let eight = cascade_lanes_match_scalar::<8>(settings, ma, 71 + j as u64);
            for seen in [&four, &eight] {
                assert!(seen.refused >= 3 && seen.resets == 1, "{seen:?}");
                assert_eq!(seen.frozen > 0, settings.freeze_adaptation_on_saturation, "{seen:?}");
                assert_eq!(seen.thrust_limited > 0, settings.thrust_limits.is_some(), "{seen:?}");
                assert!(seen.tilt_limited > 0, "the tilt limit never acted: {seen:?}");
            }
        }
    }
}
