//! How the TSM-STA gains (not published) are chosen: one documented,
//! reproducible procedure that treats the two baselines alike.
//!
//! **Procedure.** On paper scenario 1, TSM-STA must reach the same 2 %
//! settling time as RANFTSMC with its published gains: on the yaw channel
//! (attitude loop) and on the slowest of x, y, z (position loop). Each loop's
//! gains are a base set scaled by one *time-scale factor* `a`:
//! `λ = λ₀ a^(p/q)`, `k1 = k1₀ a²`, `k2 = k2₀ a³`. For the double integrator
//! `ë = v` this is exactly the time scaling `t → t/a` of the closed loop
//! (surface `s = e + (1/λ) sig^(p/q)(ė)` and the super-twisting law keep
//! their shape), so `a` sets the speed and nothing else. `a` is found by
//! bisection on `log a` (settling time decreases with `a`), attitude loop
//! first, then position, then the attitude loop once more with the final
//! position gains. Rerun with `ftsmc tune-tsm-sta`.

use ftsmc_core::tsm_sta::TsmStaGains;

use crate::axes::AxisSet;
use crate::run::RunOptions;
use crate::scenario::Scenario;

/// Scale a base gain set by the time-scale factor `a`.
pub fn time_scaled(base: &TsmStaGains, a: f64) -> TsmStaGains {
    TsmStaGains {
        lambda: base.lambda * ftsmc_core::math::powf(a, base.p / base.q),
        k1: base.k1 * a * a,
        k2: base.k2 * a * a * a,
        ..*base
    }
}

/// Result of the procedure.
#[derive(Clone, Debug, PartialEq)]
pub struct TuningReport {
    /// Position-loop factor.
    pub position_scale: f64,
    /// Attitude-loop factor.
    pub attitude_scale: f64,
    /// The chosen gains.
    pub gains: AxisSet<TsmStaGains>,
    /// RANFTSMC targets `[slowest of x, y, z, ψ]`, s.
    pub target: [f64; 2],
    /// TSM-STA achieved `[slowest of x, y, z, ψ]`, s.
    pub achieved: [f64; 2],
}

fn settling(scenario: &Scenario, name: &str) -> Result<[f64; 2], String> {
    let run = crate::registry::run(name, scenario, RunOptions { record: false, ..Default::default() })?;
    if !run.exit.is_completed() {
        return Ok([f64::INFINITY; 2]);
    }
    let st = run.metrics.settling_time;
    let inf = |v: Option<f64>| v.unwrap_or(f64::INFINITY);
    Ok([inf(st.x).max(inf(st.y)).max(inf(st.z)), inf(st.psi)])
}

fn bisect(mut f: impl FnMut(f64) -> Result<f64, String>, target: f64) -> Result<f64, String> {
    // Settling time decreases with a: find a with f(a) = target on a log grid.
    let (mut lo, mut hi) = (ftsmc_core::math::ln(0.02f64), ftsmc_core::math::ln(50.0f64));
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if f(ftsmc_core::math::exp(mid))? > target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(ftsmc_core::math::exp(0.5 * (lo + hi)))
}

/// Run the procedure on `scenario` (normally paper scenario 1), starting
/// from the base gains `base_position` and `base_attitude`.
pub fn tune_tsm_sta(
    scenario: &Scenario,
    base_position: &TsmStaGains,
    base_attitude: &TsmStaGains,
) -> Result<TuningReport, String> {
    let target = settling(scenario, "ranftsmc")?;
    let mut s = scenario.clone();
    let mut position_scale = 1.0;
    let mut attitude_scale = 1.0;
    let apply = |s: &mut Scenario, pos: f64, att: f64| {
        s.gains.tsm_sta = AxisSet::split(time_scaled(base_position, pos), time_scaled(base_attitude, att));
    };
    for pass in 0..2 {
        attitude_scale = bisect(
            |a| {
                let mut t = s.clone();
                apply(&mut t, position_scale, a);
                settling(&t, "tsm-sta").map(|v| v[1])
            },
            target[1],
        )?;
        apply(&mut s, position_scale, attitude_scale);
        if pass == 0 {
            position_scale = bisect(
                |a| {
                    let mut t = s.clone();
                    apply(&mut t, a, attitude_scale);
                    settling(&t, "tsm-sta").map(|v| v[0])
                },
                target[0],
            )?;
            apply(&mut s, position_scale, attitude_scale);
        }
    }
    let achieved = settling(&s, "tsm-sta")?;
    Ok(TuningReport { position_scale, attitude_scale, gains: s.gains.tsm_sta.clone(), target, achieved })
}
