//! RANFTSMC, the robust adaptive nonsingular fast terminal SMC of Labbadi &
//! Cherkaoui 2020 (the paper's ref. \[19\]); reads `[ranftsmc]`.

use ftsmc_core::lanes::Real;
use ftsmc_core::law::GainError;
use ftsmc_core::ranftsmc::{RanftsmcAxis, RanftsmcGains};

use super::generic::{CascadeOf, ChannelGains};
use crate::axes::AxisSet;

/// `ranftsmc`: six RANFTSMC laws in the cascade, no mass adaptation.
pub type Ranftsmc = CascadeOf<RanftsmcGains>;

/// `[ranftsmc.x]` … `[ranftsmc.psi]`: one gain set per channel (default:
/// the published gains, position on x, y, z and attitude on φ, θ, ψ).
impl ChannelGains for RanftsmcGains {
    const KEY: &'static str = "ranftsmc";
    const NAME: &'static str = "ranftsmc";
    const LABEL: &'static str = "RANFTSMC [19]";
    const DESCRIPTION: &'static str =
        "robust adaptive nonsingular fast terminal SMC (Labbadi & Cherkaoui 2020, ref. [19])";
    type Law<R: Real> = RanftsmcAxis<R>;

    fn defaults() -> AxisSet<Self> {
        AxisSet::split(RanftsmcGains::PAPER_POSITION, RanftsmcGains::PAPER_ATTITUDE)
    }

    fn check(&self) -> Result<(), GainError> {
        RanftsmcGains::check(self)
    }

    fn law<R: Real>(self) -> RanftsmcAxis<R> {
        RanftsmcAxis::splat(self)
    }
}

/// The gains that fly the channel law `ë = v` exactly `a` times faster
/// (`e(t)` → `e(a t)`, from `(e, a ė)` with `â0, â1` ×a², `â2` ×a).
///
/// With `ẽ(t) = e(a t)`: σ = e + b1 sig^α(e) + b2 sig^β(ė) is unchanged when
/// b2 → b2 a^(−β); the equivalent term `−1/(β b2) |ė|^(2−β)(…)` then scales
/// by a² by itself; `c σ` needs c ×a²; the switching gain
/// `(â0 + â1|e| + â2|ė| + h)` needs â0, â1, h ×a² and â2 ×a. The adaptive
/// laws `dâ0/dt = μ0 |σ| |ė|^(β−1)`, `dâ1/dt = μ1 |σ| |e| |ė|^(β−1)` then
/// need μ0, μ1 ×a^(4−β), and `dâ2/dt = μ2 |σ| |ė|^β` needs μ2 ×a^(2−β).
/// α, β, b1 and the boundary layer (on σ) are unchanged.
pub fn time_scaled(g: &RanftsmcGains, a: f64) -> RanftsmcGains {
    let a2 = a * a;
    RanftsmcGains {
        b2: g.b2 * ftsmc_core::math::powf(a, -g.beta),
        c: g.c * a2,
        h: g.h * a2,
        mu0: g.mu0 * ftsmc_core::math::powf(a, 4.0 - g.beta),
        mu1: g.mu1 * ftsmc_core::math::powf(a, 4.0 - g.beta),
        mu2: g.mu2 * ftsmc_core::math::powf(a, 2.0 - g.beta),
        a0_hat0: g.a0_hat0 * a2,
        a1_hat0: g.a1_hat0 * a2,
        a2_hat0: g.a2_hat0 * a,
        ..*g
    }
}

/// What `ftsmc tune` searches for `ranftsmc`: an exact time scale per loop
/// ([`time_scaled`]), the linear reaching gain c and the adaptation rates
/// μ per loop group, and the command filter's ω_n.
pub fn tune_parameters() -> Vec<super::tune_param::TuneParam> {
    use super::tune_param::{TuneParam, COMMAND_FILTER};
    vec![
        TuneParam::factor(
            "time_xy",
            "time scale a of the x, y laws (b2 ×a^−β; c, h ×a²; μ0, μ1 ×a^(4−β); μ2 ×a^(2−β))",
            0.05,
            20.0,
            |t, a| t.gains.ranftsmc.each_mut(&[0, 1], |g| *g = time_scaled(g, a)),
        ),
        TuneParam::factor("time_z", "time scale a of the z law (as time_xy)", 0.05, 20.0, |t, a| {
            t.gains.ranftsmc.each_mut(&[2], |g| *g = time_scaled(g, a))
        }),
        TuneParam::factor("time_roll_pitch", "time scale a of the φ, θ laws (as time_xy)", 0.05, 20.0, |t, a| {
            t.gains.ranftsmc.each_mut(&[3, 4], |g| *g = time_scaled(g, a))
        }),
        TuneParam::factor("time_yaw", "time scale a of the ψ law (as time_xy)", 0.05, 20.0, |t, a| {
            t.gains.ranftsmc.each_mut(&[5], |g| *g = time_scaled(g, a))
        }),
        TuneParam::factor("reaching_position", "factor on c and h of x, y, z", 0.05, 20.0, |t, k| {
            t.gains.ranftsmc.each_mut(&[0, 1, 2], |g| {
                g.c *= k;
                g.h *= k
            })
        }),
        TuneParam::factor("reaching_attitude", "factor on c and h of φ, θ, ψ", 0.05, 20.0, |t, k| {
            t.gains.ranftsmc.each_mut(&[3, 4, 5], |g| {
                g.c *= k;
                g.h *= k
            })
        }),
        TuneParam::factor("adaptation", "factor on μ0, μ1, μ2 of every channel", 0.01, 100.0, |t, k| {
            t.gains.ranftsmc.each_mut(&[0, 1, 2, 3, 4, 5], |g| {
                g.mu0 *= k;
                g.mu1 *= k;
                g.mu2 *= k
            })
        }),
        COMMAND_FILTER,
    ]
}
