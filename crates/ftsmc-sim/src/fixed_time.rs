//! Measuring the fixed-time claim (paper Eq. 38, 63, 78; SPEC §7).
//!
//! The bound speaks of one channel with exact model cancellation: the error
//! dynamics are a double integrator `ë = v_fb`. [`decoupled_channel`] flies
//! exactly that (zero-order hold at the control period, exact integration of
//! the double integrator between ticks) from `e(0) = e0`, `ė(0) = 0`, and
//! reports when the sliding variable first enters a band (reaching time) and
//! when the error enters and stays within a fraction of `|e0|` (settling).

use ftsmc_core::law::AxisLaw;
use serde::Serialize;

use crate::scenario::Scenario;

/// Settings of a sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepSettings {
    /// Initial error magnitudes (channel units); each is flown with both signs.
    pub magnitudes: Vec<f64>,
    /// Control period, s.
    pub dt: f64,
    /// Give up after this long, s.
    pub t_max: f64,
    /// Reaching: `|S| ≤ reaching_band` (absolute, units of S).
    pub reaching_band: f64,
    /// Settling: `|e| ≤ settling_fraction · |e0|` from then on.
    pub settling_fraction: f64,
}

impl SweepSettings {
    /// `per_decade` log-spaced magnitudes from `10^lo` to `10^hi`.
    pub fn log_magnitudes(lo: i32, hi: i32, per_decade: usize) -> Vec<f64> {
        let n = ((hi - lo) as usize) * per_decade;
        (0..=n).map(|k| 10f64.powf(lo as f64 + k as f64 / per_decade as f64)).collect()
    }
}

impl Default for SweepSettings {
    fn default() -> Self {
        Self {
            magnitudes: Self::log_magnitudes(-3, 2, 3),
            dt: 1e-3,
            t_max: 60.0,
            reaching_band: 1e-3,
            settling_fraction: 0.02,
        }
    }
}

/// How the controller is applied to the channel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Sampling {
    /// Zero-order hold at `settings.dt` (how the controller flies).
    Sampled,
    /// Continuous-time closed loop (what the theorem speaks of): the law is
    /// re-evaluated with a step small enough that S changes by at most 0.2 %
    /// per step; the run stops when S reaches the band.
    Continuous,
}

/// Times measured from one initial error.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ChannelTimes {
    /// Initial error e0.
    pub e0: f64,
    /// Initial sliding variable S(0).
    pub s0: f64,
    /// First time `|S| ≤ band`, s (`None`: not within `t_max`).
    pub reaching_time: Option<f64>,
    /// Time from which `|e| ≤ fraction·|e0|` holds to the end, s (`None`:
    /// not settled; always `None` in continuous mode, which stops at reaching).
    pub settling_time: Option<f64>,
    /// Time at which the state or command became non-finite, s.
    pub diverged_at: Option<f64>,
}

/// Fly one decoupled channel `ë = v_fb` from `e0` at rest.
pub fn decoupled_channel<L: AxisLaw>(
    law: &mut L,
    e0: f64,
    settings: &SweepSettings,
    sampling: Sampling,
) -> ChannelTimes {
    match sampling {
        Sampling::Sampled => sampled_channel(law, e0, settings),
        Sampling::Continuous => continuous_channel(law, e0, settings),
    }
}

fn sampled_channel<L: AxisLaw>(law: &mut L, e0: f64, settings: &SweepSettings) -> ChannelTimes {
    law.reset();
    let dt = settings.dt;
    let steps = (settings.t_max / dt).round() as u64;
    let band = settings.settling_fraction * e0.abs();
    let (mut e, mut e_dot) = (e0, 0.0);
    let mut reaching = None;
    let mut last_outside: Option<f64> = None;
    let mut s0 = f64::NAN;
    let mut diverged_at = None;
    for k in 0..steps {
        let t = k as f64 * dt;
        let v = law.update(e, e_dot, dt);
        let s = law.sliding_variable();
        if k == 0 {
            s0 = s;
        }
        if !(v.is_finite() && s.is_finite() && e.is_finite() && e_dot.is_finite()) {
            diverged_at = Some(t);
            break;
        }
        if reaching.is_none() && s.abs() <= settings.reaching_band {
            reaching = Some(t);
        }
        if e.abs() > band {
            last_outside = Some(t);
        }
        // Exact ZOH integration of the double integrator.
        e += e_dot * dt + 0.5 * v * dt * dt;
        e_dot += v * dt;
    }
    let end = steps as f64 * dt;
    let settling = match last_outside {
        _ if diverged_at.is_some() => None,
        None => Some(0.0),
        Some(t) if t + dt < end - 0.1 * settings.t_max => Some(t + dt),
        Some(_) => None,
    };
    ChannelTimes { e0, s0, reaching_time: reaching, settling_time: settling, diverged_at }
}

fn continuous_channel<L: AxisLaw>(law: &mut L, e0: f64, settings: &SweepSettings) -> ChannelTimes {
    const H_MIN: f64 = 1e-12;
    const MAX_STEPS: u64 = 50_000_000;
    law.reset();
    let (mut e, mut e_dot) = (e0, 0.0);
    let mut t = 0.0;
    let mut h = H_MIN;
    let mut s_prev = f64::NAN;
    let mut s0 = f64::NAN;
    for k in 0..MAX_STEPS {
        let v = law.update(e, e_dot, h);
        let s = law.sliding_variable();
        if k == 0 {
            s0 = s;
        }
        if !(v.is_finite() && s.is_finite()) {
            return ChannelTimes { e0, s0, reaching_time: None, settling_time: None, diverged_at: Some(t) };
        }
        if s.abs() <= settings.reaching_band {
            return ChannelTimes { e0, s0, reaching_time: Some(t), settling_time: None, diverged_at: None };
        }
        if t >= settings.t_max {
            break;
        }
        e += e_dot * h + 0.5 * v * h * h;
        e_dot += v * h;
        t += h;
        // Next step: at most double, and S may change by at most 0.2 %.
        let rate = if s_prev.is_finite() { (s - s_prev).abs() / h } else { 0.0 };
        s_prev = s;
        let limit = if rate > 0.0 { 0.002 * s.abs() / rate } else { f64::INFINITY };
        h = (2.0 * h).min(limit).min(settings.dt).max(H_MIN);
    }
    ChannelTimes { e0, s0, reaching_time: None, settling_time: None, diverged_at: None }
}

/// Sweep `magnitudes × {+, −}` on one channel law.
pub fn sweep<L: AxisLaw + Clone>(law: &L, settings: &SweepSettings, sampling: Sampling) -> Vec<ChannelTimes> {
    let mut out = Vec::with_capacity(2 * settings.magnitudes.len());
    for &m in &settings.magnitudes {
        for sign in [1.0, -1.0] {
            out.push(decoupled_channel(&mut law.clone(), sign * m, settings, sampling));
        }
    }
    out
}

/// Worst (largest) time of a sweep; `None` counts as infinite.
pub fn worst(times: impl IntoIterator<Item = Option<f64>>) -> Option<f64> {
    let mut worst: Option<f64> = Some(0.0);
    for t in times {
        worst = match (worst, t) {
            (Some(a), Some(b)) => Some(a.max(b)),
            _ => None,
        };
    }
    worst
}

/// Channels the full cascade can sweep over large initial errors: altitude
/// and yaw need no tilt (x and y would hit the tilt clamp).
pub const CASCADE_CHANNELS: [usize; 2] = [2, 5];

/// Fly the *full* cascade and plant of `base` (references held at zero, all
/// plant-side variations kept) from an initial error `e0` on channel `axis`
/// (2 = z, 5 = ψ), for `settings.t_max` seconds at the scenario's control
/// rate; reaching: first `|S_axis| ≤ settings.reaching_band`; settling from
/// the run's 2 % settling metric.
pub fn cascade_channel(
    controller: &str,
    base: &Scenario,
    axis: usize,
    e0: f64,
    settings: &SweepSettings,
) -> Result<ChannelTimes, String> {
    let mut s = base.clone();
    s.duration = settings.t_max;
    s.reference = crate::scenario::ReferenceSignals::default();
    s.initial_state = crate::scenario::InitialState::default();
    match axis {
        2 => s.initial_state.position[2] = e0,
        5 => s.initial_state.attitude[2] = e0,
        _ => return Err(format!("channel {axis} cannot be swept through the cascade (only z = 2 and ψ = 5)")),
    }
    s.simulation.record_rate = s.simulation.control_rate;
    // Settle to 2 % of |e0| however small e0 is.
    s.simulation.settling_band = settings.settling_fraction;
    s.simulation.settling_floor = 1e-12;
    s.simulation.max_position_error = s.simulation.max_position_error.max(10.0 * e0.abs());
    let run = crate::registry::run(controller, &s, crate::simulate::RunOptions::default())?;
    let name = ftsmc_core::cascade::channel::NAMES[axis];
    let t = run.recording.column("t");
    let sv = run.recording.column(&format!("s_{name}"));
    // The recorded S is the controller's value at each tick.
    let reaching = t.iter().zip(sv).find(|(_, s)| s.abs() <= settings.reaching_band).map(|(t, _)| *t);
    let settling = match run.exit {
        crate::simulate::ExitStatus::Completed => *run.metrics.settling_time.get(name).unwrap_or(&None),
        _ => None,
    };
    let diverged_at = match run.exit {
        crate::simulate::ExitStatus::Diverged { time, .. } => Some(time),
        _ => None,
    };
    Ok(ChannelTimes {
        e0,
        s0: sv.first().copied().unwrap_or(f64::NAN),
        reaching_time: reaching,
        settling_time: settling,
        diverged_at,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use ftsmc_core::ftaftsmc::{FtaftsmcAxis, FtaftsmcGains};

    #[test]
    fn ftaftsmc_reaching_times_stay_under_the_eq38_bound_on_every_channel() {
        // The theorem: with exact cancellation Ṡ = ϖ2, and for δ̂ ≥ 0
        // |S| reaches zero before 1/(λ2(q2−1)) + 1/(γ2(1−p2)), in continuous time.
        let settings = SweepSettings::default();
        for gains in
            [FtaftsmcGains::PAPER_XY, FtaftsmcGains::PAPER_Z, FtaftsmcGains::PAPER_ROLL_PITCH, FtaftsmcGains::PAPER_YAW]
        {
            let bound = gains.reaching_time_bound();
            let times = sweep(&FtaftsmcAxis::new(gains), &settings, Sampling::Continuous);
            for t in &times {
                let r = t.reaching_time.unwrap_or_else(|| panic!("e0 = {} never reached", t.e0));
                assert!(r <= bound, "e0 = {}: reaching {r} s > bound {bound} s", t.e0);
            }
            let w = worst(times.iter().map(|t| t.reaching_time)).unwrap();
            assert!(w > 0.0, "the sweep must include initial conditions off the surface");
        }
    }

    #[test]
    fn sampled_ftaftsmc_settles_small_and_moderate_errors_quickly() {
        // At 1 kHz the x channel settles every |e0| ≤ 1 m within the bound of
        // the reaching phase plus a few seconds of sliding.
        let settings =
            SweepSettings { magnitudes: SweepSettings::log_magnitudes(-3, 0, 2), ..SweepSettings::default() };
        let times = sweep(&FtaftsmcAxis::new(FtaftsmcGains::PAPER_XY), &settings, Sampling::Sampled);
        for t in times {
            let s = t.settling_time.unwrap_or_else(|| panic!("e0 = {} did not settle", t.e0));
            assert!(s < 10.0, "e0 = {}: settled at {s}", t.e0);
        }
    }

    #[test]
    fn log_magnitudes_cover_the_decades() {
        let m = SweepSettings::log_magnitudes(-3, 2, 3);
        assert_eq!(m.len(), 16);
        assert!((m[0] - 1e-3).abs() < 1e-15 && (m[15] - 100.0).abs() < 1e-9);
    }
}
