//! FTAFTSMC, the paper's controller (§3, Eq. 9–17 and 44), and its variant
//! with the mass adaptation switched off; both read `[ftaftsmc]`.

use ftsmc_core::cascade::{Cascade, MassAdaptation};
use ftsmc_core::ftaftsmc::{FtaftsmcAxis, FtaftsmcGains};
use ftsmc_core::lanes::Lanes;
use serde::{Deserialize, Serialize};

use super::{check_axes, AxisLawVisitor, BoxedController, BuildContext, Declaration, GainSection, InvalidGain};
use crate::axes::AxisSet;

/// FTAFTSMC configuration, `[ftaftsmc]`: mass adaptation and per-channel
/// gains (Tables 4–5).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct FtaftsmcConfig {
    /// Mass adaptation of §3.2 (β1, β2 of Table 5).
    pub mass_adaptation: MassAdaptation,
    /// x channel (Table 5).
    pub x: FtaftsmcGains,
    /// y channel (Table 5).
    pub y: FtaftsmcGains,
    /// z channel (Table 5).
    pub z: FtaftsmcGains,
    /// Roll channel (Table 4).
    pub phi: FtaftsmcGains,
    /// Pitch channel (Table 4).
    pub theta: FtaftsmcGains,
    /// Yaw channel (Table 4).
    pub psi: FtaftsmcGains,
}

impl FtaftsmcConfig {
    /// The six channel gain sets.
    pub fn gains(&self) -> AxisSet<FtaftsmcGains> {
        AxisSet { x: self.x, y: self.y, z: self.z, phi: self.phi, theta: self.theta, psi: self.psi }
    }
}

impl Default for FtaftsmcConfig {
    /// Tables 4–5 with the mass adaptation on.
    fn default() -> Self {
        Self {
            mass_adaptation: MassAdaptation::PAPER,
            x: FtaftsmcGains::PAPER_XY,
            y: FtaftsmcGains::PAPER_XY,
            z: FtaftsmcGains::PAPER_Z,
            phi: FtaftsmcGains::PAPER_ROLL_PITCH,
            theta: FtaftsmcGains::PAPER_ROLL_PITCH,
            psi: FtaftsmcGains::PAPER_YAW,
        }
    }
}

impl GainSection for FtaftsmcConfig {
    const KEY: &'static str = "ftaftsmc";
    const CORE_ARRAYS: &'static [(&'static str, usize)] = &[("mass_adaptation.alpha_hat_bounds", 2)];

    fn defaults() -> Self {
        Self::default()
    }

    fn check(&self) -> Result<(), InvalidGain> {
        self.mass_adaptation.check().map_err(|e| InvalidGain::at("mass_adaptation", e))?;
        check_axes(&self.gains(), FtaftsmcGains::check)
    }
}

/// The cascade of six FTAFTSMC laws with mass adaptation `mass_adaptation`.
fn cascade(
    config: &FtaftsmcConfig,
    mass_adaptation: MassAdaptation,
    ctx: &BuildContext,
) -> Result<BoxedController, String> {
    let laws = config.gains().to_array().map(FtaftsmcAxis::new);
    Ok(Box::new(Cascade::new(ctx.cascade_config(mass_adaptation), laws).map_err(|e| e.to_string())?))
}

/// [`cascade`] on `N` lanes, its updates on the detected instruction set.
fn cascade_lanes<const N: usize>(
    config: &FtaftsmcConfig,
    mass_adaptation: MassAdaptation,
    ctx: &BuildContext,
) -> Option<Result<super::LaneController<N>, String>> {
    let laws = config.gains().to_array().map(FtaftsmcAxis::<Lanes<N>>::with_gains);
    super::generic::on_lanes(Cascade::<_, Lanes<N>>::with_laws(ctx.cascade_config(mass_adaptation), laws))
}

/// `ftaftsmc`: the paper's controller.
pub struct Ftaftsmc;

impl Declaration for Ftaftsmc {
    const NAME: &'static str = "ftaftsmc";
    const LABEL: &'static str = "FTAFTSMC";
    const DESCRIPTION: &'static str =
        "fixed-time adaptive fast terminal SMC with mass adaptation (the paper's controller)";
    type Section = FtaftsmcConfig;

    fn build(config: &FtaftsmcConfig, ctx: &BuildContext) -> Result<BoxedController, String> {
        cascade(config, config.mass_adaptation, ctx)
    }

    fn build_lanes<const N: usize>(
        config: &FtaftsmcConfig,
        ctx: &BuildContext,
    ) -> Option<Result<super::LaneController<N>, String>> {
        cascade_lanes(config, config.mass_adaptation, ctx)
    }

    fn visit_axis_law<V: AxisLawVisitor>(config: &FtaftsmcConfig, axis: usize, visitor: V) -> Option<V::Output> {
        Some(visitor.visit(FtaftsmcAxis::new(config.gains().to_array()[axis])))
    }

    /// Eq. 38: `1/(λ2 (q2 − 1)) + 1/(γ2 (1 − p2))`.
    fn reaching_time_bound(config: &FtaftsmcConfig, axis: usize) -> Option<f64> {
        Some(config.gains().to_array()[axis].reaching_time_bound())
    }
}

/// `ftaftsmc-no-mass`: FTAFTSMC with the mass adaptation of §3.2 switched
/// off (`U1 = u1`), the same `[ftaftsmc]` gains otherwise.
pub struct FtaftsmcNoMass;

impl Declaration for FtaftsmcNoMass {
    const NAME: &'static str = "ftaftsmc-no-mass";
    const LABEL: &'static str = "FTAFTSMC (no mass adaptation)";
    const DESCRIPTION: &'static str = "FTAFTSMC with the mass adaptation of §3.2 switched off (U1 = u1)";
    type Section = FtaftsmcConfig;

    fn build(config: &FtaftsmcConfig, ctx: &BuildContext) -> Result<BoxedController, String> {
        cascade(config, MassAdaptation { enabled: false, ..config.mass_adaptation }, ctx)
    }

    fn build_lanes<const N: usize>(
        config: &FtaftsmcConfig,
        ctx: &BuildContext,
    ) -> Option<Result<super::LaneController<N>, String>> {
        cascade_lanes(config, MassAdaptation { enabled: false, ..config.mass_adaptation }, ctx)
    }

    fn visit_axis_law<V: AxisLawVisitor>(config: &FtaftsmcConfig, axis: usize, visitor: V) -> Option<V::Output> {
        Ftaftsmc::visit_axis_law(config, axis, visitor)
    }

    fn reaching_time_bound(config: &FtaftsmcConfig, axis: usize) -> Option<f64> {
        Ftaftsmc::reaching_time_bound(config, axis)
    }
}

/// The gains that fly the channel law `ë = v` exactly `a` times faster:
/// if `e(t)` is a closed-loop trajectory under `g`, then `e(a t)` is one
/// under `time_scaled(g, a)` (from `(e, a ė)`, with δ̂ scaled by `a`).
///
/// Derivation (Eq. 5–17), writing `ẽ(t) = e(a t)`, so `dẽ/dt = a ė` and
/// `d²ẽ/dt² = a² ë`: the surface `S = ė + Y(e)[λ sig^q(e) + γ S_Δ(e) + η e]`
/// becomes `a S` when λ, γ, η → ×a (Y, S_Δ and ε depend on e only);
/// `ϖ` (Eq. 13), a time derivative of the bracket, then scales by a².
/// The reaching law (Eq. 15) must give `a² ϖ2` at `a S`:
/// `λ2 sig^q2(S)` → λ2 × a^(2−q2), `γ2 sig^p2(S)` → γ2 × a^(2−p2),
/// `η2 S` → η2 × a, and `δ̂/(2ξ²) S` with ξ unchanged needs δ̂ → ×a.
/// Eq. 17 keeps δ̂ scaled by `a` when `dδ̂/dt` scales by a²:
/// `α1 (a² S²/(2ξ²) − α2' a δ̂) = a² α1 (S²/(2ξ²) − α2 δ̂)` with α2' = a α2
/// (α1 unchanged). Exponents, ℵ1–ℵ3, ε, ξ and α1 are unchanged.
pub fn time_scaled(g: &FtaftsmcGains, a: f64) -> FtaftsmcGains {
    FtaftsmcGains {
        lambda: g.lambda * a,
        gamma: g.gamma * a,
        eta: g.eta * a,
        lambda2: g.lambda2 * ftsmc_core::math::powf(a, 2.0 - g.q2),
        gamma2: g.gamma2 * ftsmc_core::math::powf(a, 2.0 - g.p2),
        eta2: g.eta2 * a,
        alpha2: g.alpha2 * a,
        delta_hat0: g.delta_hat0 * a,
        ..*g
    }
}

/// Apply `f` to the gain sets of the channels in `axes` (0..6 = x, y, z, φ, θ, ψ).
fn each(config: &mut FtaftsmcConfig, axes: &[usize], f: impl Fn(&mut FtaftsmcGains)) {
    for &axis in axes {
        let g = match axis {
            0 => &mut config.x,
            1 => &mut config.y,
            2 => &mut config.z,
            3 => &mut config.phi,
            4 => &mut config.theta,
            _ => &mut config.psi,
        };
        f(g);
    }
}

/// Time scale of the channels `axes` by `a` ([`time_scaled`]).
fn scale_time(t: &mut super::tune_param::TuneTarget<'_>, axes: &[usize], a: f64) {
    each(&mut t.gains.ftaftsmc, axes, |g| *g = time_scaled(g, a));
}

/// Reaching-law factor: λ2, γ2, η2 of the channels `axes` times `k`.
fn scale_reaching(t: &mut super::tune_param::TuneTarget<'_>, axes: &[usize], k: f64) {
    each(&mut t.gains.ftaftsmc, axes, |g| {
        g.lambda2 *= k;
        g.gamma2 *= k;
        g.eta2 *= k;
    });
}

/// What `ftsmc tune` searches for `ftaftsmc` (`with_mass`) and
/// `ftaftsmc-no-mass`: an exact time scale per loop ([`time_scaled`]:
/// x/y, z, φ/θ, ψ), reaching-law factors for the position and attitude
/// loops, the δ̂ adaptation (α1, α2, ξ), the mass adaptation rate β1 (with
/// mass adaptation only) and the command filter's ω_n.
pub fn tune_parameters(with_mass: bool) -> Vec<super::tune_param::TuneParam> {
    use super::tune_param::{TuneParam, COMMAND_FILTER};
    let mut list = vec![
        TuneParam::factor(
            "time_xy",
            "time scale a of the x, y laws (λ, γ, η, η2, α2 ×a; λ2 ×a^(2−q2); γ2 ×a^(2−p2))",
            0.05,
            20.0,
            |t, a| scale_time(t, &[0, 1], a),
        ),
        TuneParam::factor("time_z", "time scale a of the z law (as time_xy)", 0.05, 20.0, |t, a| {
            scale_time(t, &[2], a)
        }),
        TuneParam::factor("time_roll_pitch", "time scale a of the φ, θ laws (as time_xy)", 0.05, 20.0, |t, a| {
            scale_time(t, &[3, 4], a)
        }),
        TuneParam::factor("time_yaw", "time scale a of the ψ law (as time_xy)", 0.05, 20.0, |t, a| {
            scale_time(t, &[5], a)
        }),
        TuneParam::factor("reaching_position", "factor on λ2, γ2, η2 of x, y, z (Eq. 15)", 0.001, 20.0, |t, k| {
            scale_reaching(t, &[0, 1, 2], k)
        }),
        TuneParam::factor(
            "reaching_attitude",
            "factor on λ2, γ2, η2 of φ, θ, ψ (Eq. 15)",
            0.001,
            20.0,
            |t, k| scale_reaching(t, &[3, 4, 5], k),
        ),
        TuneParam::factor(
            "alpha1",
            "factor on the δ̂ adaptation rate α1 of every channel (Eq. 17)",
            0.01,
            100.0,
            |t, k| each(&mut t.gains.ftaftsmc, &[0, 1, 2, 3, 4, 5], |g| g.alpha1 *= k),
        ),
        TuneParam::factor("alpha2", "factor on the δ̂ leakage α2 of every channel (Eq. 17)", 0.01, 100.0, |t, k| {
            each(&mut t.gains.ftaftsmc, &[0, 1, 2, 3, 4, 5], |g| g.alpha2 *= k)
        }),
        TuneParam::factor("xi", "factor on ξ of every channel (Eq. 15, 17)", 0.1, 10.0, |t, k| {
            each(&mut t.gains.ftaftsmc, &[0, 1, 2, 3, 4, 5], |g| g.xi *= k)
        }),
    ];
    if with_mass {
        list.push(TuneParam::factor(
            "beta1",
            "factor on the mass adaptation rate β1 (Eq. 44)",
            0.01,
            100.0,
            |t, k| t.gains.ftaftsmc.mass_adaptation.beta1 *= k,
        ));
    }
    list.push(COMMAND_FILTER);
    list
}

/// [`tune_parameters`] of `ftaftsmc` (with the mass adaptation's β1).
pub fn tune_parameters_with_mass() -> Vec<super::tune_param::TuneParam> {
    tune_parameters(true)
}

/// [`tune_parameters`] of `ftaftsmc-no-mass` (without β1).
pub fn tune_parameters_no_mass() -> Vec<super::tune_param::TuneParam> {
    tune_parameters(false)
}
