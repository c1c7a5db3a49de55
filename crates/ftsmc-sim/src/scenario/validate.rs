//! Validation of a parsed scenario: every value range-checked, names,
//! controller names, array lengths, Monte Carlo section and cost limits;
//! errors name the file, the dotted key and the value.

use super::*;

/// Fixed-size arrays of `ftsmc-core` structs read from scenario files, as
/// `(dotted path, length)`. Those structs derive serde's own `[f64; N]`,
/// which ignores extra elements, so their lengths are checked on the TOML
/// tree before deserializing. The gain sections declare their own
/// ([`crate::controllers::GainSection::CORE_ARRAYS`]).
const CORE_ARRAYS: [(&str, usize); 10] = [
    ("plant.inertia", 3),
    ("plant.drag_translational", 3),
    ("plant.drag_rotational", 3),
    ("actual_plant.inertia", 3),
    ("actual_plant.drag_translational", 3),
    ("actual_plant.drag_rotational", 3),
    ("vehicle.drag_translational", 3),
    ("vehicle.drag_rotational", 3),
    ("vehicle.parasitic_drag", 3),
    ("vehicle.spin", 4),
];

/// Longest scenario `name`, characters.
pub const MAX_NAME_CHARS: usize = 64;

/// A scenario `name` is used as a directory name under `--out`, so it must
/// be one plain file-name component: 1–64 characters from `A–Z a–z 0–9 . _ -`,
/// not starting with `.` (so never `.`, `..` or a hidden file).
pub fn check_name(name: &str) -> Result<(), &'static str> {
    let ok_chars = name.chars().all(|c| c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-'));
    if name.is_empty() || name.len() > MAX_NAME_CHARS || !ok_chars || name.starts_with('.') {
        Err("1-64 characters from A-Z a-z 0-9 . _ - not starting with `.` (the name is a directory under --out)")
    } else {
        Ok(())
    }
}

/// Lengths of the `ftsmc-core` arrays ([`CORE_ARRAYS`] and the gain
/// sections') in the resolved TOML table: `Err((dotted path, message))`.
pub(crate) fn check_core_array_lengths(root: &toml::Table) -> Result<(), (String, String)> {
    let sections = GainSections::core_arrays();
    let all = CORE_ARRAYS.iter().map(|(p, n)| (*p, *n)).chain(sections.iter().map(|(p, n)| (p.as_str(), *n)));
    for (path, len) in all {
        let mut parts = path.split('.');
        let first = parts.next().and_then(|k| root.get(k));
        let value = parts.fold(first, |v, k| v.and_then(|v| v.get(k)));
        if let Some(toml::Value::Array(a)) = value {
            if a.len() != len {
                return Err((
                    path.to_string(),
                    format!("`{path}`: invalid length {}, expected an array of exactly {len} numbers", a.len()),
                ));
            }
        }
    }
    Ok(())
}

impl Scenario {
    /// The limits a trajectory is checked against
    /// ([`crate::trajectory::feasibility`]): the true mass and gravity,
    /// the collective thrust `4 k_f ω_max²` of the rotor limit (`[actuators]
    /// max_rotor_speed` or `simulation.max_rotor_speed`; none with ideal
    /// actuators) and the controllers' tilt demand limit
    /// (`cascade.max_demanded_tilt`), no body-rate limit.
    pub fn trajectory_limits(&self) -> crate::trajectory::feasibility::VehicleLimits {
        let (_, p) = self.truth_allocation();
        let limit =
            self.actuators.map(|a| a.max_rotor_speed).filter(|w| w.is_finite()).or(self.simulation.max_rotor_speed);
        crate::trajectory::feasibility::VehicleLimits {
            mass: self.true_mass().0,
            gravity: p.gravity,
            max_thrust: limit.map(|w| 4.0 * p.lift_coefficient * w * w),
            max_tilt: self.cascade.max_tilt.min(self.simulation.max_tilt),
            max_body_rate: None,
        }
    }

    /// The trajectory's feasibility ([`crate::trajectory::feasibility::check`]
    /// against [`Scenario::trajectory_limits`] over the run):
    /// `Err((key, value, expected))` naming the first violation.
    pub fn check_trajectory_feasibility(&self) -> Result<(), (String, String, String)> {
        let Some(trajectory) = &self.reference.trajectory else { return Ok(()) };
        let limits = self.trajectory_limits();
        crate::trajectory::feasibility::check(trajectory, &limits, self.duration).map_err(|v| {
            let stretched = if trajectory.stretch() > 1.0 {
                format!(" (time stretched by {})", show(trajectory.stretch()))
            } else {
                String::new()
            };
            (
                "reference.trajectory".to_string(),
                format!("a trajectory that {v}{stretched}"),
                "a trajectory the vehicle can fly (slow it down, or set [reference] time_scale = \"fit\")".to_string(),
            )
        })
    }

    /// Range-check every value; the error names `path` and the dotted key.
    pub fn validate(&self, path: &str) -> Result<(), ScenarioError> {
        let invalid = |key: String, value: String, expected: &str| ScenarioError::Invalid {
            path: path.to_string(),
            key,
            value,
            expected: expected.to_string(),
        };
        let gain = |prefix: &str, e: GainError| invalid(format!("{prefix}.{}", e.field), show(e.value), e.expected);
        let positive = |key: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(invalid(key.to_string(), show(v), "a finite value > 0"))
            }
        };
        let non_negative = |key: &str, v: f64| {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                Err(invalid(key.to_string(), show(v), "a finite value >= 0"))
            }
        };
        let finite = |key: &str, v: f64| {
            if v.is_finite() {
                Ok(())
            } else {
                Err(invalid(key.to_string(), show(v), "a finite number"))
            }
        };

        if let Err(rule) = check_name(&self.name) {
            return Err(invalid("name".into(), format!("\"{}\"", show_str(&self.name)), rule));
        }
        if self.controllers.is_empty() {
            return Err(invalid("controllers".into(), "[]".into(), "at least one controller name"));
        }
        if let Err((key, v)) = self.limits.check() {
            return Err(invalid(format!("limits.{key}"), show(v), "a number > 0"));
        }
        positive("duration", self.duration)?;
        let sim = &self.simulation;
        positive("simulation.control_rate", sim.control_rate)?;
        if (self.duration / self.control_period()).round() < 1.0 {
            return Err(invalid(
                "duration".into(),
                show(self.duration),
                &format!("at least one control period (>= 1/control_rate = {} s)", show(self.control_period())),
            ));
        }
        if sim.substeps == 0 {
            return Err(invalid("simulation.substeps".into(), "0".into(), "an integer >= 1"));
        }
        non_negative("simulation.record_rate", sim.record_rate)?;
        if sim.record_rate > sim.control_rate {
            return Err(invalid(
                "simulation.record_rate".into(),
                show(sim.record_rate),
                "a rate <= simulation.control_rate",
            ));
        }
        positive("simulation.max_position_error", sim.max_position_error)?;
        positive("simulation.max_tilt", sim.max_tilt)?;
        positive("simulation.settling_band", sim.settling_band)?;
        positive("simulation.settling_floor", sim.settling_floor)?;
        non_negative("simulation.steady_state_after", sim.steady_state_after)?;
        if let Some([start, end]) = sim.metrics_window {
            if !(start.is_finite() && end.is_finite() && start <= end) {
                return Err(invalid(
                    "simulation.metrics_window".into(),
                    format!("[{}, {}]", show(start), show(end)),
                    "a window [start, end] with start <= end",
                ));
            }
        }
        if let Some(w) = sim.max_rotor_speed {
            positive("simulation.max_rotor_speed", w)?;
            if self.actuators.is_some() {
                return Err(invalid(
                    "simulation.max_rotor_speed".into(),
                    show(w),
                    "not together with [actuators]: write it as [actuators] max_rotor_speed (and mixer = \"clamp\" for the per-rotor clamp this deprecated key means)",
                ));
            }
        }

        self.plant.check().map_err(|e| gain("plant", e))?;
        // The true vehicle: no key the model cannot fly, and the values it
        // flies (the keys [vehicle] gives, or [plant]'s) in range.
        self.vehicle.check_model_keys().map_err(|(key, value, expected)| invalid(key, value, &expected))?;
        self.vehicle.check(&self.plant).map_err(|(prefix, e)| gain(&prefix, e))?;
        let init = &self.initial_state;
        for (name, v) in [
            ("position", init.position),
            ("attitude", init.attitude),
            ("velocity", init.velocity),
            ("angular_rate", init.angular_rate),
        ] {
            for (i, x) in v.iter().enumerate() {
                finite(&format!("initial_state.{name}[{i}]"), *x)?;
            }
        }
        for (i, a) in init.attitude[..2].iter().enumerate() {
            if a.abs() >= sim.max_tilt {
                return Err(invalid(format!("initial_state.attitude[{i}]"), show(*a), "|angle| < simulation.max_tilt"));
            }
        }
        let signal = |prefix: String, s: &Signal| {
            s.check().map_err(|(key, value, expected)| invalid(format!("{prefix}.{key}"), value, expected))
        };
        let r = &self.reference;
        for (name, s) in [("x", &r.x), ("y", &r.y), ("z", &r.z), ("psi", &r.psi)] {
            signal(format!("reference.{name}"), s)?;
        }
        if let Some(trajectory) = &r.trajectory {
            trajectory
                .check()
                .map_err(|(key, value, expected)| invalid(format!("reference.trajectory.{key}"), value, &expected))?;
            for (name, s) in [("x", &r.x), ("y", &r.y), ("z", &r.z), ("psi", &r.psi)] {
                if !s.is_zero() {
                    return Err(invalid(
                        format!("reference.{name}"),
                        "given".into(),
                        "no `x`, `y`, `z` or `psi` beside `reference.trajectory` (the trajectory gives all four)",
                    ));
                }
            }
        } else if r.time_scale != crate::trajectory::TimeScale::Fixed {
            return Err(invalid("reference.time_scale".into(), "\"fit\"".into(), "a `reference.trajectory` to fit"));
        }
        for (name, s) in self.disturbance.named() {
            signal(format!("disturbance.{name}"), s)?;
        }
        if let Some(p) = &self.payload {
            finite("payload.mass", p.mass)?;
            let (true_mass, which) = self.true_mass();
            if p.mass <= -true_mass {
                return Err(invalid(
                    "payload.mass".into(),
                    show(p.mass),
                    &format!("a mass change > -{which} = -{} (the true mass must stay > 0)", show(true_mass)),
                ));
            }
            finite("payload.start", p.start)?;
            match (p.decay_start, p.tau) {
                (Some(t2), Some(tau)) => {
                    finite("payload.decay_start", t2)?;
                    if t2 < p.start {
                        return Err(invalid("payload.decay_start".into(), show(t2), "decay_start >= payload.start"));
                    }
                    positive("payload.tau", tau)?;
                }
                (Some(t2), None) => {
                    return Err(invalid(
                        "payload.tau".into(),
                        "missing".into(),
                        &format!("a time constant > 0 (decay_start = {} is set)", show(t2)),
                    ))
                }
                (None, Some(tau)) => positive("payload.tau", tau)?,
                (None, None) => {}
            }
        }
        if let Some(s) = &self.inertia_variation {
            signal("inertia_variation".into(), s)?;
        }
        if let Some(n) = &self.drag_noise {
            non_negative("drag_noise.std", n.std)?;
        }
        self.cascade.check().map_err(|e| gain("cascade", e))?;
        self.gains.check().map_err(|e| invalid(e.key, e.value, &e.expected))?;
        for name in &self.controllers {
            crate::controllers::check_name(name).map_err(|known| ScenarioError::UnknownController {
                path: path.to_string(),
                name: name.clone(),
                known,
            })?;
        }
        check_realism(self).map_err(|(prefix, e)| gain(&prefix, e))?;
        if let Some(s) = &self.sensors {
            crate::sensors::pipeline::check(s, sim.control_rate)
                .map_err(|e| invalid(format!("sensors.{}", e.key), e.value, &e.expected))?;
        }
        if let Some(t) = &self.tune {
            t.check().map_err(|(key, e)| invalid(format!("tune.{key}"), show(e.value), e.expected))?;
            // Only gains are tunable: never the seed, the duration or anything
            // else the search is judged on.
            for (i, e) in t.extra.iter().enumerate() {
                crate::controllers::tunable::check_extra_key_any(&e.key).map_err(|why| {
                    invalid(
                        format!("tune.extra[{i}].key"),
                        format!("\"{}\"", show_str(&e.key)),
                        &format!("a tunable gain; {why}"),
                    )
                })?;
            }
        }
        // The rigid body flies the payload too: its mass with the payload
        // must stay in the rigid body's valid range.
        if let (crate::vehicle::VehicleModel::RigidBody, Some(p)) = (self.vehicle.model, &self.payload) {
            let mut rb = self.rigid_body_params();
            let body_mass = rb.mass;
            if rb.check().is_ok() {
                rb.mass += p.mass;
                if let Err(e) = rb.check() {
                    return Err(invalid(
                        "payload.mass".into(),
                        show(p.mass),
                        &format!(
                            "a payload keeping the rigid body's {} ({} kg + payload = {}) in range: {}",
                            e.field,
                            show(body_mass),
                            show(rb.mass),
                            e.expected
                        ),
                    ));
                }
            }
        }
        if let Some(mc) = &self.montecarlo {
            mc.check_against(self).map_err(|(key, value, expected)| invalid(key, value, &expected))?;
        }
        self.check_cost(self.controllers.len())
            .map_err(|limit| ScenarioError::Limit { path: path.to_string(), limit })?;
        // After the cost limits (the check samples the run's span) and the
        // vehicle's own checks (its limits are read from them). With
        // `time_scale = "fit"` the loader stretches the trajectory first
        // and checks it then (`resolve::fit_trajectory`).
        if self.reference.time_scale == crate::trajectory::TimeScale::Fixed {
            self.check_trajectory_feasibility().map_err(|(key, value, expected)| invalid(key, value, &expected))?;
        }
        // Last: the search space is checked against a scenario that is valid
        // itself, so an error of the scenario is never reported as one of
        // `[falsify]`.
        if let Some(f) = &self.falsify {
            f.check().and_then(|()| f.check_against(self, path)).map_err(|(key, message)| ScenarioError::Parse {
                path: path.to_string(),
                message: format!("`{key}`: {message}"),
            })?;
        }
        Ok(())
    }

    /// Price one flight with each of `n_controllers` controllers (steps
    /// including substeps, recorded rows, output bytes) against
    /// [`Scenario::limits`]; called by [`Scenario::validate`] with the
    /// scenario's own controller list.
    pub fn check_cost(&self, n_controllers: usize) -> Result<crate::limits::Cost, LimitError> {
        crate::limits::check_flight(&self.flight_size(), n_controllers)
    }
}

/// Validation of the realism keys (`[vehicle]`, `[actuators]`, `[ground]`, `[envelope]`):
/// `(dotted key prefix, error)` of the first bad value.
pub(super) fn check_realism(scenario: &Scenario) -> Result<(), (String, GainError)> {
    if let Some(a) = &scenario.actuators {
        a.check().map_err(|e| ("actuators".to_string(), e))?;
        let (allocation, _) = scenario.truth_allocation();
        crate::actuators::Mixer::new(allocation, a).map_err(|e| ("actuators".to_string(), e))?;
    }
    if let Some(g) = &scenario.ground {
        g.check().map_err(|e| ("ground".to_string(), e))?;
        let z0 = scenario.initial_state.position[2];
        if g.enabled && z0 < g.height {
            return Err((
                "initial_state.position".to_string(),
                GainError { field: "2", value: z0, expected: "a start at or above ground.height" },
            ));
        }
    }
    if let Some(w) = &scenario.wind {
        w.check().map_err(|e| ("wind".to_string(), e))?;
        // The loop samples the wind once per RK4 substep.
        let h = scenario.control_period() / f64::from(scenario.simulation.substeps);
        crate::environment::wind::Wind::new(w.clone(), h, scenario.seed).map_err(|e| ("wind".to_string(), e))?;
    }
    if let Some(s) = &scenario.sensors {
        s.check().map_err(|e| ("sensors".to_string(), e))?;
    }
    if let Some(e) = &scenario.envelope {
        e.check().map_err(|e| ("envelope".to_string(), e))?;
    }
    Ok(())
}
