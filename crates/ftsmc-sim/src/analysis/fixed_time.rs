//! Measuring the fixed-time claim (paper Eq. 38, 63, 78).
//!
//! The bound speaks of one channel with exact model cancellation: the error
//! dynamics are a double integrator `ë = v_fb`. [`decoupled_channel`] flies
//! exactly that (zero-order hold at the control period, exact integration of
//! the double integrator between ticks) from `e(0) = e0`, `ė(0) = 0`, and
//! reports when the sliding variable first enters a band (reaching time) and
//! when the error enters and stays within a fraction of `|e0|` (settling).

use ftsmc_core::law::{AxisLaw, MAX_ESTIMATES};
use serde::Serialize;

use crate::controllers::AxisLawVisitor;
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
        (0..=n).map(|k| ftsmc_core::math::powf(10f64, lo as f64 + k as f64 / per_decade as f64)).collect()
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
    /// Continuous-time closed loop (what the theorem speaks of): the law,
    /// with its adaptive states, is integrated as an ODE by an adaptive
    /// Dormand–Prince 5(4) method (tolerances 1e-10) and the first time
    /// `|S|` reaches the band is located on its dense output; the run stops
    /// there.
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

/// Absolute and relative tolerances of the continuous-mode integrator.
const CONTINUOUS_TOLERANCE: f64 = 1e-10;
/// Most accepted + rejected steps of one continuous run before giving up
/// (reported as not reached).
const CONTINUOUS_MAX_STEPS: u64 = 5_000_000;

/// Closed-loop state `[e, ė, z0, z1, z2]` (z = the law's adaptive states).
type Y = [f64; 2 + MAX_ESTIMATES];

/// The closed loop `ë = v_fb` as an ODE. Laws that implement
/// [`AxisLaw::continuous_rhs`] give the adaptive-state rates, which are then
/// integrated with the same high order as `e`, `ė`. For a law that does not,
/// the adaptive states are held over each step (`v` from
/// `update(e, ė, 0)`, which does not advance them) and advanced by explicit
/// Euler over each accepted step with [`AxisLaw::update`].
struct ClosedLoop<'a, L: AxisLaw> {
    law: &'a mut L,
    exposes_rates: bool,
}

impl<L: AxisLaw> ClosedLoop<'_, L> {
    /// `(dy/dt, S)` at `y`.
    fn rhs(&mut self, y: &Y) -> (Y, f64) {
        let est = [y[2], y[3], y[4]];
        let (v, s, rates) = match self.law.continuous_rhs(y[0], y[1], est) {
            Some(r) => (r.v, r.s, r.estimates_rate),
            None => {
                let v = self.law.update(y[0], y[1], 0.0);
                (v, self.law.sliding_variable(), [0.0; MAX_ESTIMATES])
            }
        };
        ([y[1], v, rates[0], rates[1], rates[2]], s)
    }

    /// `S` at `y`.
    fn sliding(&mut self, y: &Y) -> f64 {
        self.rhs(y).1
    }
}

// Dormand–Prince 5(4) tableau (Hairer, Nørsett & Wanner, Solving ODE I, §II.5);
// the nodes c = (0, 1/5, 3/10, 4/5, 8/9, 1, 1) are not needed (autonomous system).
const A: [[f64; 6]; 7] = [
    [0.0; 6],
    [1.0 / 5.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
    [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
    [19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0, 0.0, 0.0],
    [9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0, 0.0],
    [35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0],
];
/// 5th-order solution minus the embedded 4th-order one.
const E: [f64; 7] =
    [71.0 / 57600.0, 0.0, -71.0 / 16695.0, 71.0 / 1920.0, -17253.0 / 339200.0, 22.0 / 525.0, -1.0 / 40.0];
/// Coefficients of the 4th-order continuous extension (Hairer's `contd5`).
const D: [f64; 7] = [
    -12715105075.0 / 11282082432.0,
    0.0,
    87487479700.0 / 32700410799.0,
    -10690763975.0 / 1880347072.0,
    701980252875.0 / 199316789632.0,
    -1453857185.0 / 822651844.0,
    69997945.0 / 29380423.0,
];

/// Dense output of one accepted step from `t0` with length `h`.
struct Dense {
    t0: f64,
    h: f64,
    r: [Y; 5],
}

impl Dense {
    fn new(t0: f64, h: f64, y0: &Y, y1: &Y, k: &[Y; 7]) -> Self {
        let mut r = [[0.0; 5]; 5];
        for i in 0..5 {
            let diff = y1[i] - y0[i];
            let bspl = h * k[0][i] - diff;
            r[0][i] = y0[i];
            r[1][i] = diff;
            r[2][i] = bspl;
            r[3][i] = diff - h * k[6][i] - bspl;
            r[4][i] = h * (0..7).map(|j| D[j] * k[j][i]).sum::<f64>();
        }
        Self { t0, h, r }
    }

    /// State at `t0 + θ h`, `0 ≤ θ ≤ 1` (4th order, exact at both ends).
    fn at(&self, theta: f64) -> Y {
        let t1 = 1.0 - theta;
        let mut y = [0.0; 5];
        for (i, yi) in y.iter_mut().enumerate() {
            let r = |j: usize| self.r[j][i];
            *yi = r(0) + theta * (r(1) + t1 * (r(2) + theta * (r(3) + t1 * r(4))));
        }
        y
    }
}

/// Continuous closed loop integrated with Dormand–Prince 5(4): adaptive
/// step (PI controller, tolerances [`CONTINUOUS_TOLERANCE`]), stopping at the
/// first time `|S| = band`, located on the 4th-order dense output by
/// bisection to 1e-15 of the step. The law is non-Lipschitz at S = 0 (and
/// some at ė = 0); the run stops at the band, and a step that collapses
/// below 1e-15·max(t, 1e-3) s, or [`CONTINUOUS_MAX_STEPS`] steps, end the
/// run as "not reached".
fn continuous_channel<L: AxisLaw>(law: &mut L, e0: f64, settings: &SweepSettings) -> ChannelTimes {
    law.reset();
    let band = settings.reaching_band;
    let exposes_rates = law.continuous_rhs(e0, 0.0, law.estimates()).is_some();
    let mut sys = ClosedLoop { law, exposes_rates };
    let est = sys.law.estimates();
    let mut y: Y = [e0, 0.0, est[0], est[1], est[2]];
    let (mut f, s0) = sys.rhs(&y);
    let not_reached = |s0| ChannelTimes { e0, s0, reaching_time: None, settling_time: None, diverged_at: None };
    let diverged = |s0, t| ChannelTimes { e0, s0, reaching_time: None, settling_time: None, diverged_at: Some(t) };
    if !(s0.is_finite() && f.iter().all(|v| v.is_finite())) {
        return diverged(s0, 0.0);
    }
    if s0.abs() <= band {
        return ChannelTimes { e0, s0, reaching_time: Some(0.0), settling_time: None, diverged_at: None };
    }
    let tol = CONTINUOUS_TOLERANCE;
    let scale = |a: f64, b: f64| tol + tol * a.abs().max(b.abs());
    // Initial step (Hairer's heuristic, one Euler probe).
    let mut h = {
        let d0 = rms(&y, &y, &scale, |i| y[i]);
        let d1 = rms(&y, &y, &scale, |i| f[i]);
        let h0 = if d0 < 1e-5 || d1 < 1e-5 { 1e-6 } else { 0.01 * d0 / d1 };
        let y1: Y = core::array::from_fn(|i| y[i] + h0 * f[i]);
        let (f1, _) = sys.rhs(&y1);
        let d2 = rms(&y, &y, &scale, |i| f1[i] - f[i]) / h0;
        let h1 =
            if d1.max(d2) <= 1e-15 { (h0 * 1e-3).max(1e-6) } else { ftsmc_core::math::powf(0.01 / d1.max(d2), 0.2) };
        (100.0 * h0).min(h1).min(settings.dt)
    };
    let mut t = 0.0;
    let mut err_prev: f64 = 1e-4;
    let mut rejected_last = false;
    for _ in 0..CONTINUOUS_MAX_STEPS {
        if t >= settings.t_max {
            return not_reached(s0);
        }
        h = h.min(settings.t_max - t);
        if h < 1e-15 * t.max(1e-3) {
            return not_reached(s0);
        }
        // Stages (FSAL: k[0] = f(y)).
        let mut k: [Y; 7] = [[0.0; 5]; 7];
        k[0] = f;
        let mut finite = true;
        for st in 1..7 {
            let yi: Y = core::array::from_fn(|i| y[i] + h * (0..st).map(|j| A[st][j] * k[j][i]).sum::<f64>());
            k[st] = sys.rhs(&yi).0;
            finite &= k[st].iter().all(|v| v.is_finite());
        }
        let y_new: Y = core::array::from_fn(|i| y[i] + h * (0..6).map(|j| A[6][j] * k[j][i]).sum::<f64>());
        let err = if finite && y_new.iter().all(|v| v.is_finite()) {
            rms(&y, &y_new, &scale, |i| h * (0..7).map(|j| E[j] * k[j][i]).sum::<f64>())
        } else {
            f64::INFINITY
        };
        if err <= 1.0 {
            // Accepted: look for |S| ≤ band inside the step on the dense output.
            let dense = Dense::new(t, h, &y, &y_new, &k);
            let g = |sys: &mut ClosedLoop<L>, theta: f64| sys.sliding(&dense.at(theta)).abs() - band;
            let mut lo = 0.0;
            let mut hit = None;
            for theta in [0.25, 0.5, 0.75, 1.0] {
                if g(&mut sys, theta) <= 0.0 {
                    hit = Some(theta);
                    break;
                }
                lo = theta;
            }
            if let Some(mut hi) = hit {
                for _ in 0..60 {
                    let mid = 0.5 * (lo + hi);
                    if g(&mut sys, mid) <= 0.0 {
                        hi = mid;
                    } else {
                        lo = mid;
                    }
                    if (hi - lo) * h <= 1e-15 * (t + h) {
                        break;
                    }
                }
                let reach = dense.t0 + 0.5 * (lo + hi) * dense.h;
                return ChannelTimes { e0, s0, reaching_time: Some(reach), settling_time: None, diverged_at: None };
            }
            if !sys.exposes_rates {
                // Held adaptive states: advance them by explicit Euler over the step.
                sys.law.update(y[0], y[1], h);
                let est = sys.law.estimates();
                y = [y_new[0], y_new[1], est[0], est[1], est[2]];
            } else {
                y = y_new;
            }
            t += h;
            let (f_new, s) = sys.rhs(&y);
            if !(s.is_finite() && f_new.iter().all(|v| v.is_finite())) {
                return diverged(s0, t);
            }
            f = f_new;
            // PI step-size controller (Gustafsson): exponents 0.7/5 and 0.4/5.
            let err = err.max(1e-10);
            let mut fac = 0.9 * ftsmc_core::math::powf(err, -0.14) * ftsmc_core::math::powf(err_prev, 0.08);
            fac = fac.clamp(0.2, if rejected_last { 1.0 } else { 5.0 });
            err_prev = err;
            rejected_last = false;
            h = (h * fac).min(settings.dt);
        } else {
            let fac = if err.is_finite() { (0.9 * ftsmc_core::math::powf(err, -0.2)).clamp(0.1, 0.9) } else { 0.1 };
            h *= fac;
            rejected_last = true;
        }
    }
    not_reached(s0)
}

/// RMS over the components of `v(i)`, each scaled by `scale(a_i, b_i)`.
fn rms(a: &Y, b: &Y, scale: &impl Fn(f64, f64) -> f64, v: impl Fn(usize) -> f64) -> f64 {
    let n = a.len() as f64;
    ((0..a.len()).map(|i| (v(i) / scale(a[i], b[i])).powi(2)).sum::<f64>() / n).sqrt()
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
    let run = crate::registry::run(controller, &s, crate::run::RunOptions::default())?;
    let name = ftsmc_core::cascade::channel::NAMES[axis];
    let t = run.recording.column("t");
    let sv = run.recording.column(&format!("s_{name}"));
    // The recorded S is the controller's value at each tick.
    let reaching = t.iter().zip(sv).find(|(_, s)| s.abs() <= settings.reaching_band).map(|(t, _)| *t);
    let settling = match run.exit {
        crate::run::ExitStatus::Completed => *run.metrics.settling_time.get(name).unwrap_or(&None),
        _ => None,
    };
    let diverged_at = match run.exit {
        crate::run::ExitStatus::Diverged { time, .. } => Some(time),
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

/// [`sweep`] as a visitor of a declaration's per-axis law.
struct SweepVisitor<'a> {
    settings: &'a SweepSettings,
    sampling: Sampling,
}

impl AxisLawVisitor for SweepVisitor<'_> {
    type Output = Vec<ChannelTimes>;
    fn visit<L: AxisLaw + Clone>(self, law: L) -> Vec<ChannelTimes> {
        sweep(&law, self.settings, self.sampling)
    }
}

/// Sweep the decoupled channel `axis` (0..6 = x, y, z, φ, θ, ψ) of
/// controller `name` with the gains of `scenario` (see the module docs),
/// using the per-axis law its declaration gives
/// ([`crate::controllers::Declaration::visit_axis_law`]). An error for an
/// unknown name or a controller without per-axis sliding laws.
pub fn sweep_channel(
    name: &str,
    scenario: &Scenario,
    axis: usize,
    settings: &SweepSettings,
    sampling: Sampling,
) -> Result<Vec<ChannelTimes>, String> {
    crate::controllers::visit_axis_law(name, &scenario.gains, axis, SweepVisitor { settings, sampling })?.ok_or_else(
        || format!("controller `{name}` has no per-axis sliding law: the decoupled-channel sweep does not apply"),
    )
}

/// The reaching-time bound for `axis` of controller `name`, when its
/// declaration has one ([`crate::controllers::Declaration::reaching_time_bound`]):
/// FTAFTSMC's Eq. 38; the baselines are finite-time with
/// initial-condition-dependent bounds (Eq. 36–37) and have none.
pub fn reaching_time_bound(name: &str, scenario: &Scenario, axis: usize) -> Option<f64> {
    crate::controllers::reaching_time_bound(name, &scenario.gains, axis)
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

    /// `S = ė + c e`, `v = −c ė − k S`: `Ṡ = −k S`, so from rest
    /// `|S| = band` at `T = ln(c |e0| / band) / k`. No adaptive state and no
    /// `continuous_rhs` (the held-state path).
    #[derive(Clone)]
    struct Linear {
        c: f64,
        k: f64,
        s: f64,
    }

    impl AxisLaw for Linear {
        const NAME: &'static str = "linear";
        const ESTIMATE_NAMES: [&'static str; MAX_ESTIMATES] = ["", "", ""];
        fn update(&mut self, e: f64, e_dot: f64, _dt: f64) -> f64 {
            self.s = e_dot + self.c * e;
            -self.c * e_dot - self.k * self.s
        }
        fn sliding_variable(&self) -> f64 {
            self.s
        }
        fn estimates(&self) -> [f64; MAX_ESTIMATES] {
            [0.0; MAX_ESTIMATES]
        }
        fn reset(&mut self) {
            self.s = 0.0;
        }
        fn check_gains(&self) -> Result<(), ftsmc_core::law::GainError> {
            Ok(())
        }
    }

    /// `S = ė + c e`, `v = −c ė − z S` with an adaptive gain `ż = a`:
    /// `Ṡ = −z S`, so `ln(|S0| / band) = z0 T + a T²/2`.
    #[derive(Clone)]
    struct Ramped {
        c: f64,
        a: f64,
        z0: f64,
        z: f64,
        s: f64,
    }

    impl AxisLaw for Ramped {
        const NAME: &'static str = "ramped";
        const ESTIMATE_NAMES: [&'static str; MAX_ESTIMATES] = ["z", "", ""];
        fn update(&mut self, e: f64, e_dot: f64, dt: f64) -> f64 {
            self.s = e_dot + self.c * e;
            let v = -self.c * e_dot - self.z * self.s;
            self.z += dt * self.a;
            v
        }
        fn sliding_variable(&self) -> f64 {
            self.s
        }
        fn estimates(&self) -> [f64; MAX_ESTIMATES] {
            [self.z, 0.0, 0.0]
        }
        fn reset(&mut self) {
            self.z = self.z0;
            self.s = 0.0;
        }
        fn check_gains(&self) -> Result<(), ftsmc_core::law::GainError> {
            Ok(())
        }
        fn continuous_rhs(
            &self,
            e: f64,
            e_dot: f64,
            est: [f64; MAX_ESTIMATES],
        ) -> Option<ftsmc_core::law::ContinuousRhs> {
            let s = e_dot + self.c * e;
            Some(ftsmc_core::law::ContinuousRhs {
                v: -self.c * e_dot - est[0] * s,
                s,
                estimates_rate: [self.a, 0.0, 0.0],
            })
        }
    }

    #[test]
    fn continuous_reaching_time_matches_the_analytic_one() {
        let settings = SweepSettings::default();
        let band = settings.reaching_band;
        for &e0 in &[1e-3f64, 0.05, -1.0, 100.0] {
            for &(c, k) in &[(1.0, 2.0), (3.0, 50.0), (0.5, 0.3)] {
                let exact = ftsmc_core::math::ln(c * e0.abs() / band) / k;
                let mut law = Linear { c, k, s: 0.0 };
                let r = decoupled_channel(&mut law, e0, &settings, Sampling::Continuous);
                if exact <= 0.0 {
                    assert_eq!(r.reaching_time, Some(0.0));
                    continue;
                }
                let t = r.reaching_time.unwrap_or_else(|| panic!("e0 {e0}: not reached"));
                assert!((t / exact - 1.0).abs() < 1e-6, "linear e0 {e0} c {c} k {k}: {t} vs {exact}");
            }
            for &(c, a, z0) in &[(1.0, 5.0, 0.5), (2.0, 1e4, 1.0), (0.5, 0.1, 3.0)] {
                let l = ftsmc_core::math::ln(c * e0.abs() / band);
                if l <= 0.0 {
                    continue;
                }
                let exact = (-z0 + (z0 * z0 + 2.0 * a * l).sqrt()) / a;
                let mut law = Ramped { c, a, z0, z: z0, s: 0.0 };
                let t = decoupled_channel(&mut law, e0, &settings, Sampling::Continuous)
                    .reaching_time
                    .unwrap_or_else(|| panic!("e0 {e0}: not reached"));
                assert!((t / exact - 1.0).abs() < 1e-6, "ramped e0 {e0} c {c} a {a}: {t} vs {exact}");
            }
        }
    }

    #[test]
    fn continuous_run_reports_not_reached_within_t_max() {
        // Ṡ = −k S with k tiny: the band is hours away.
        let settings = SweepSettings { t_max: 2.0, ..SweepSettings::default() };
        let r = decoupled_channel(&mut Linear { c: 1.0, k: 1e-3, s: 0.0 }, 1.0, &settings, Sampling::Continuous);
        assert_eq!((r.reaching_time, r.diverged_at), (None, None));
    }

    #[test]
    fn log_magnitudes_cover_the_decades() {
        let m = SweepSettings::log_magnitudes(-3, 2, 3);
        assert_eq!(m.len(), 16);
        assert!((m[0] - 1e-3).abs() < 1e-15 && (m[15] - 100.0).abs() < 1e-9);
    }
}
