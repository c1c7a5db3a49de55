//! TSM-STA, a nonsingular terminal sliding surface with a super-twisting
//! reaching law (the paper's ref. \[2\]); reads `[tsm-sta]`.

use ftsmc_core::lanes::Real;
use ftsmc_core::law::GainError;
use ftsmc_core::tsm_sta::{TsmStaAxis, TsmStaGains};

use super::generic::{CascadeOf, ChannelGains};
use crate::axes::AxisSet;

/// `tsm-sta`: six TSM-STA laws in the cascade, no mass adaptation.
pub type TsmSta = CascadeOf<TsmStaGains>;

/// `[tsm-sta.x]` … `[tsm-sta.psi]`: one gain set per channel (default: the
/// gains of the tuning procedure in `analysis::tuning`, position on x, y, z
/// and attitude on φ, θ, ψ).
impl ChannelGains for TsmStaGains {
    const KEY: &'static str = "tsm-sta";
    const NAME: &'static str = "tsm-sta";
    const LABEL: &'static str = "TSM-STA [2]";
    const DESCRIPTION: &'static str =
        "nonsingular terminal sliding surface with super-twisting reaching law (ref. [2])";
    type Law<R: Real> = TsmStaAxis<R>;

    fn defaults() -> AxisSet<Self> {
        AxisSet::split(TsmStaGains::DEFAULT_POSITION, TsmStaGains::DEFAULT_ATTITUDE)
    }

    fn check(&self) -> Result<(), GainError> {
        TsmStaGains::check(self)
    }

    fn law<R: Real>(self) -> TsmStaAxis<R> {
        TsmStaAxis::splat(self)
    }
}

/// The gains that fly the channel law `ë = v` exactly `a` times faster
/// (`e(t)` → `e(a t)`, from `(e, a ė)` with ν ×a²): with `ẽ(t) = e(a t)`
/// the surface `s = e + sig^(p/q)(ė)/λ` is unchanged when λ → λ a^(p/q); the
/// equivalent term `−(λ q/p) |ė|^(2−p/q) sign(ė)` then scales by a², the
/// super-twisting term `k1 |s|^½ sign(s)` needs k1 ×a², and `ν̇ = −k2 sign(s)`
/// with ν ×a² needs k2 ×a³. p, q and the boundary layer are unchanged.
pub fn time_scaled(g: &TsmStaGains, a: f64) -> TsmStaGains {
    TsmStaGains {
        lambda: g.lambda * ftsmc_core::math::powf(a, g.p / g.q),
        k1: g.k1 * a * a,
        k2: g.k2 * a * a * a,
        ..*g
    }
}

/// What `ftsmc tune` searches for `tsm-sta`: an exact time scale per loop
/// ([`time_scaled`]), the super-twisting gains k1 and k2 per loop group
/// (their ratio sets the twisting), and the command filter's ω_n.
pub fn tune_parameters() -> Vec<super::tune_param::TuneParam> {
    use super::tune_param::{TuneParam, COMMAND_FILTER};
    vec![
        TuneParam::factor(
            "time_xy",
            "time scale a of the x, y laws (λ ×a^(p/q), k1 ×a², k2 ×a³)",
            0.05,
            20.0,
            |t, a| t.gains.tsm_sta.each_mut(&[0, 1], |g| *g = time_scaled(g, a)),
        ),
        TuneParam::factor("time_z", "time scale a of the z law (as time_xy)", 0.05, 20.0, |t, a| {
            t.gains.tsm_sta.each_mut(&[2], |g| *g = time_scaled(g, a))
        }),
        TuneParam::factor("time_roll_pitch", "time scale a of the φ, θ laws (as time_xy)", 0.05, 20.0, |t, a| {
            t.gains.tsm_sta.each_mut(&[3, 4], |g| *g = time_scaled(g, a))
        }),
        TuneParam::factor("time_yaw", "time scale a of the ψ law (as time_xy)", 0.05, 20.0, |t, a| {
            t.gains.tsm_sta.each_mut(&[5], |g| *g = time_scaled(g, a))
        }),
        TuneParam::factor("k1_position", "factor on k1 of x, y, z", 0.05, 20.0, |t, k| {
            t.gains.tsm_sta.each_mut(&[0, 1, 2], |g| g.k1 *= k)
        }),
        TuneParam::factor("k2_position", "factor on k2 of x, y, z", 0.05, 20.0, |t, k| {
            t.gains.tsm_sta.each_mut(&[0, 1, 2], |g| g.k2 *= k)
        }),
        TuneParam::factor("k1_attitude", "factor on k1 of φ, θ, ψ", 0.05, 20.0, |t, k| {
            t.gains.tsm_sta.each_mut(&[3, 4, 5], |g| g.k1 *= k)
        }),
        TuneParam::factor("k2_attitude", "factor on k2 of φ, θ, ψ", 0.05, 20.0, |t, k| {
            t.gains.tsm_sta.each_mut(&[3, 4, 5], |g| g.k2 *= k)
        }),
        COMMAND_FILTER,
    ]
}
