//! Missions: what a scenario is flown for besides the paper's steps, and
//! metrics that separate the transient from tracking.
//!
//! A rung of the wind ladder flies the paper's simultaneous steps (1 m in
//! x, y, z, 0.5 rad in ψ): its RMS position error is mostly the step
//! transient. [`mission_scenario`] turns any scenario into one of
//! [`Mission`]: the same vehicle, sensors, wind, Monte Carlo and seed,
//! another reference and initial state.
//!
//! - `steps`: the scenario as written.
//! - `hover`: hold the steps' target `p*` (the reference at the end of the
//!   run, with its heading ψ*) from rest at it.
//! - `figure-eight`: the library's figure-eight `p* + (a sin θ, (a/2) sin 2θ, 0)`,
//!   8 s per lap, 2 s smooth start, from rest at `p*`; `a` is sized for the
//!   vehicle ([`mission_size`]); its time is stretched where the vehicle
//!   cannot fly it (`time_scale = "fit"`).
//! - `waypoints`: minimum snap through `p*`, `p* + (a, 0, 0)`,
//!   `p* + (a, a, a/2)`, `p* + (0, a, a/2)` and back to `p*`, heading ψ*
//!   held, over 3/4 of the run (resting at `p*` after), `time_scale = "fit"`.
//!
//! # Tracking metrics ([`tracking`])
//!
//! With the settling window `T_s` ([`MissionOptions::window`], s) and the
//! band `b` ([`MissionOptions::band`], m), over a flight of `T` s whose
//! position error is `e(t) = p(t) − p_d(t)`:
//!
//! - **RMS after the window**: `sqrt( (1/(T − T_s)) ∫_{T_s}^{T} ‖e‖² dt )`,
//!   m (the left-rectangle sum at the control rate, as every metric of
//!   [`crate::metrics`]);
//! - **max deviation after the window**: `max_{t ≥ T_s} ‖e(t)‖`, m, at the
//!   control period boundaries (the envelope's own evaluation,
//!   [`crate::margin`]); only for a scenario with `[envelope]
//!   max_position_error`;
//! - **time to settle**: the earliest sample time after which every
//!   position axis stays within `max(settling_band · |e_i(0)|, b)` to the
//!   end of the flight (`|e_i(0)| = 0` in a mission: the band is `b`), s;
//!   none when an axis is still outside at the end.

use serde::Serialize;

use crate::margin::Margin;
use crate::metrics::Metrics;
use crate::scenario::{Scenario, ScenarioError};

/// What a scenario is flown for (module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Mission {
    /// The scenario's own reference (the paper's steps on the ladder).
    Steps,
    /// Hold the steps' target from rest at it.
    Hover,
    /// A figure-eight about the target, sized for the vehicle.
    FigureEight,
    /// Minimum snap through four 3-D waypoints about the target and back.
    Waypoints,
}

impl Mission {
    /// Every mission, `steps` first.
    pub const ALL: [Mission; 4] = [Mission::Steps, Mission::Hover, Mission::FigureEight, Mission::Waypoints];

    /// Its name on the command line and in files: `steps`, `hover`,
    /// `figure-eight`, `waypoints`.
    pub fn name(self) -> &'static str {
        match self {
            Mission::Steps => "steps",
            Mission::Hover => "hover",
            Mission::FigureEight => "figure-eight",
            Mission::Waypoints => "waypoints",
        }
    }

    /// The mission named `name` ([`Mission::name`]), if any.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }

    /// The names joined for an error message: `steps, hover, figure-eight, waypoints`.
    pub fn names_joined() -> String {
        Self::ALL.map(Mission::name).join(", ")
    }
}

/// Default settling window `T_s`, s: the tracking metrics start here.
pub const DEFAULT_SETTLING_WINDOW: f64 = 5.0;

/// Default settling band `b`, m, of the time to settle.
pub const DEFAULT_SETTLING_BAND: f64 = 0.1;

/// Period of a lap of the figure-eight mission, s.
pub const FIGURE_EIGHT_PERIOD: f64 = 8.0;

/// The mission size `a` in arm lengths ([`mission_size`]).
pub const SIZE_IN_ARM_LENGTHS: f64 = 6.0;

/// How missions are flown and measured (module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct MissionOptions {
    /// Settling window `T_s`, s (default [`DEFAULT_SETTLING_WINDOW`]): the
    /// tracking metrics cover `[T_s, T]`, and a mission's `[envelope]`
    /// checks the position from `T_s` on.
    pub window: f64,
    /// Settling band `b`, m (default [`DEFAULT_SETTLING_BAND`]).
    pub band: f64,
}

impl Default for MissionOptions {
    fn default() -> Self {
        Self { window: DEFAULT_SETTLING_WINDOW, band: DEFAULT_SETTLING_BAND }
    }
}

/// The size `a` of the figure-eight and of the waypoint square, m:
/// [`SIZE_IN_ARM_LENGTHS`] arm lengths (`plant.arm_length`) rounded to
/// 5 cm, at least 0.1 m: 1.0 m for the Hummingbird (0.17 m arms), 0.3 m
/// for a Crazyflie (0.046 m).
pub fn mission_size(scenario: &Scenario) -> f64 {
    ((SIZE_IN_ARM_LENGTHS * scenario.plant.arm_length * 20.0).round() / 20.0).max(0.1)
}

/// The mission's target `(p*, ψ*)`: the scenario's reference at the end of
/// the run (m, rad).
pub fn target(scenario: &Scenario) -> ([f64; 3], f64) {
    let r = crate::run::reference_at(scenario, scenario.duration);
    (r.position, r.yaw)
}

fn num(v: f64) -> toml::Value {
    toml::Value::Float(v)
}

fn vec3(v: [f64; 3]) -> toml::Value {
    toml::Value::Array(v.iter().map(|&x| num(x)).collect())
}

fn table(entries: Vec<(&str, toml::Value)>) -> toml::Value {
    toml::Value::Table(entries.into_iter().map(|(k, v)| (k.to_string(), v)).collect())
}

/// `base` flown for `mission` (module documentation), named
/// `<base name>-<mission>`; `steps` returns `base` unchanged. Refused with
/// the scenario's error: a window outside `[0, duration)`, a band that is
/// not positive, or a mission the vehicle cannot fly even stretched.
pub fn mission_scenario(base: &Scenario, mission: Mission, options: MissionOptions) -> Result<Scenario, ScenarioError> {
    if mission == Mission::Steps {
        return Ok(base.clone());
    }
    let refuse =
        |message: String| ScenarioError::Parse { path: format!("{} --mission {}", base.name, mission.name()), message };
    if !(options.window.is_finite() && options.window >= 0.0 && options.window < base.duration) {
        return Err(refuse(format!(
            "settling window {} s: expected 0 <= window < duration = {} s",
            crate::text::show(options.window),
            crate::text::show(base.duration)
        )));
    }
    if !(options.band.is_finite() && options.band > 0.0) {
        return Err(refuse(format!(
            "settling band {} m: expected a finite band > 0 m",
            crate::text::show(options.band)
        )));
    }
    let (p, yaw) = target(base);
    let a = mission_size(base);
    let trajectory = match mission {
        Mission::Steps => unreachable!("returned above"),
        Mission::Hover => table(vec![("type", "hover".into()), ("center", vec3(p)), ("yaw", num(yaw))]),
        Mission::FigureEight => table(vec![
            ("type", "figure-eight".into()),
            ("center", vec3(p)),
            ("amplitude", toml::Value::Array(vec![num(a), num(0.5 * a)])),
            ("period", num(FIGURE_EIGHT_PERIOD)),
            ("ramp", num(2.0)),
            ("yaw", num(yaw)),
        ]),
        Mission::Waypoints => {
            let w =
                [p, [p[0] + a, p[1], p[2]], [p[0] + a, p[1] + a, p[2] + 0.5 * a], [p[0], p[1] + a, p[2] + 0.5 * a], p];
            table(vec![
                ("type", "min-snap".into()),
                ("waypoints", toml::Value::Array(w.iter().map(|&x| vec3(x)).collect())),
                ("yaw", toml::Value::Array(vec![num(yaw); w.len()])),
                ("duration", num(0.75 * base.duration)),
            ])
        }
    };
    let mut reference = vec![("trajectory", trajectory)];
    if mission != Mission::Hover {
        reference.push(("time_scale", "fit".into()));
    }
    let mut overrides: Vec<(String, toml::Value)> = vec![
        ("name".into(), format!("{}-{}", base.name, mission.name()).into()),
        ("reference".into(), table(reference)),
        ("initial_state.position".into(), vec3(p)),
        ("initial_state.velocity".into(), vec3([0.0; 3])),
        ("initial_state.attitude".into(), vec3([0.0, 0.0, yaw])),
        ("initial_state.angular_rate".into(), vec3([0.0; 3])),
        ("simulation.steady_state_after".into(), num(options.window)),
        ("simulation.metrics_window".into(), toml::Value::Array(vec![num(options.window), num(base.duration)])),
        ("simulation.settling_floor".into(), num(options.band)),
    ];
    if base.envelope.is_some() {
        overrides.push(("envelope.settle_after".into(), num(options.window)));
    }
    base.with_overrides(&overrides).map(|loaded| loaded.scenario)
}

/// The tracking metrics of one flight (module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Tracking {
    /// RMS of `‖p − p_d‖` over `[T_s, T]`, m.
    pub rms_after: f64,
    /// `max ‖p − p_d‖` for `t ≥ T_s`, m (`None` without an envelope position limit).
    pub max_after: Option<f64>,
    /// Time to settle into the band, s (`None`: still outside at the end).
    pub settle_time: Option<f64>,
}

/// The tracking metrics of a flight flown by [`mission_scenario`] with
/// settling window `window` (s): from its metrics (`ise_window` over
/// `[window, T]`, the per-axis settling times) and its margin to an
/// envelope of `max_position_error` (m). `None` when the flight holds no
/// windowed ISE or ended at or before the window.
pub fn tracking(
    metrics: &Metrics,
    margin: Option<&Margin>,
    max_position_error: Option<f64>,
    window: f64,
) -> Option<Tracking> {
    let ise = metrics.ise_window.as_ref()?;
    let span = metrics.duration - window;
    if span <= 0.0 {
        return None;
    }
    let rms_after = ((ise.x + ise.y + ise.z) / span).sqrt();
    let max_after = match (max_position_error, margin.and_then(|m| m.position)) {
        (Some(limit), Some(slack)) => Some(limit - slack),
        _ => None,
    };
    let s = &metrics.settling_time;
    let settle_time = match (s.x, s.y, s.z) {
        (Some(x), Some(y), Some(z)) => Some(x.max(y).max(z)),
        _ => None,
    };
    Some(Tracking { rms_after, max_after, settle_time })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::envelope::Envelope;
    use crate::margin::{End, MarginTracker};
    use crate::metrics::MetricsAccumulator;

    #[test]
    fn tracking_metrics_of_a_hand_computed_error_history() {
        // Samples every 1 s at t = 0..5, window T_s = 2 s, band 0.1 m.
        let ex = [0.0, 0.5, 0.3, 0.05, 0.0, 0.0];
        let ey = [0.0, 0.0, 0.0, 0.04, -0.03, 0.0];
        let ez = [0.0, 0.0, 0.4, 0.0, 0.0, 0.0];
        let window = 2.0;
        let mut acc = MetricsAccumulator::new(1.0, 0.02, 0.1, window).with_window(Some([window, 6.0]));
        let envelope = Envelope { settle_after: window, max_position_error: Some(1.0), max_tilt: None };
        let mut margin = MarginTracker::new(Some(envelope), None);
        for k in 0..6 {
            let e = [ex[k], ey[k], ez[k], 0.0, 0.0, 0.0];
            acc.observe(k as f64, &e, &[0.0; 4]);
            margin.update(k as f64, &e[..3], &[0.0; 3], &[0.0, 0.0]);
        }
        let metrics = acc.finish();
        let margin = margin.finish(End::Completed, 6.0);
        let t = tracking(&metrics, margin.as_ref(), Some(1.0), window).unwrap();
        // Σ_{t ≥ 2} ‖e‖² = (0.3² + 0.4²) + (0.05² + 0.04²) + 0.03² = 0.255 over 6 − 2 = 4 s.
        assert!((t.rms_after - (0.255f64 / 4.0).sqrt()).abs() < 1e-12, "{t:?}");
        // max ‖e‖ from t = 2 on: ‖(0.3, 0, 0.4)‖ = 0.5 (the 0.5 at t = 1 is before the window).
        assert!((t.max_after.unwrap() - 0.5).abs() < 1e-12, "{t:?}");
        // x and z are last outside 0.1 m at t = 2, so every axis is inside from t = 3.
        assert_eq!(t.settle_time, Some(3.0));
        // Without an envelope position limit there is no max deviation; without the window no metrics.
        assert_eq!(tracking(&metrics, margin.as_ref(), None, window).unwrap().max_after, None);
        let plain = MetricsAccumulator::new(1.0, 0.02, 0.1, window).finish();
        assert!(tracking(&plain, None, None, window).is_none());
    }

    #[test]
    fn an_axis_outside_the_band_at_the_end_has_not_settled() {
        let mut acc = MetricsAccumulator::new(0.5, 0.02, 0.1, 1.0).with_window(Some([1.0, 3.0]));
        for k in 0..6 {
            let z = if k == 5 { 0.2 } else { 0.0 };
            acc.observe(0.5 * k as f64, &[0.0, 0.0, z, 0.0, 0.0, 0.0], &[0.0; 4]);
        }
        let t = tracking(&acc.finish(), None, None, 1.0).unwrap();
        assert_eq!(t.settle_time, None);
        // Σ over t = 1, 1.5, 2, 2.5 of ‖e‖² · 0.5 s = 0.2² · 0.5 over 3 − 1 = 2 s.
        assert!((t.rms_after - (0.02f64 / 2.0).sqrt()).abs() < 1e-12, "{t:?}");
    }

    #[test]
    fn missions_of_a_rung_start_at_rest_on_their_reference_and_steps_is_the_rung() {
        let rung =
            Scenario::from_toml_str(crate::scenario::ladder::REALISTIC_LIGHT_1, "realistic-light-1.toml").unwrap();
        let options = MissionOptions::default();
        let steps = mission_scenario(&rung, Mission::Steps, options).unwrap();
        assert_eq!(steps.to_toml().unwrap(), rung.to_toml().unwrap());
        let (p, yaw) = target(&rung);
        assert_eq!((p, yaw), ([1.0, 1.0, 1.0], 0.5));
        assert_eq!(mission_size(&rung), 1.0);
        for mission in [Mission::Hover, Mission::FigureEight, Mission::Waypoints] {
            let s = mission_scenario(&rung, mission, options).unwrap();
            assert_eq!(s.name, format!("realistic-light-1-{}", mission.name()));
            let r0 = crate::run::reference_at(&s, 0.0);
            assert_eq!(r0.position, p, "{mission:?}");
            assert_eq!(s.initial_state.position, p);
            assert_eq!(s.simulation.metrics_window, Some([5.0, rung.duration]));
            assert_eq!(s.envelope.unwrap().settle_after, 5.0);
            assert_eq!(s.wind, rung.wind, "the rung's wind");
            assert_eq!(s.seed, rung.seed);
            let mid = crate::run::reference_at(&s, 6.0).position;
            let moved = (0..3).map(|i| (mid[i] - p[i]).abs()).fold(0.0, f64::max);
            assert_eq!(moved > 0.1, mission != Mission::Hover, "{mission:?}: {mid:?}");
        }
        for bad in [MissionOptions { window: 20.0, ..options }, MissionOptions { band: 0.0, ..options }] {
            let e = mission_scenario(&rung, Mission::Hover, bad).unwrap_err().to_string();
            assert!(e.contains("realistic-light-1 --mission hover") && e.contains("settling"), "{e}");
        }
        assert_eq!(Mission::from_name("figure-eight"), Some(Mission::FigureEight));
        assert_eq!(Mission::from_name("eight"), None);
    }
}
