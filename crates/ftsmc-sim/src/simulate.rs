//! The run loop: a controller on its own clock (zero-order hold at the
//! control period), the plant integrated by RK4 between control ticks
//! (restarting at each tick, where the input jumps), metrics accumulated
//! online and an optional time series recorded at a lower rate.
//!
//! A run that diverges is an outcome ([`ExitStatus::Diverged`] with the
//! reason and time), never a panic.

use ftsmc_core::allocation::{forces_from_squared_speeds, residual_speed, rotor_speeds};
use ftsmc_core::cascade::Controller;
use ftsmc_core::law::MAX_ESTIMATES;
use ftsmc_core::model::{Command, QuadState, QuadrotorParams, Reference};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

use crate::metrics::{Metrics, MetricsAccumulator};
use crate::plant::{derivative, rk4_step};
use crate::scenario::Scenario;

/// Why a run stopped early.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case", tag = "reason")]
pub enum Divergence {
    /// A state or command component became NaN or infinite.
    NonFinite,
    /// |φ| or |θ| exceeded `simulation.max_tilt`.
    Tilt {
        /// The angle reached, rad.
        angle: f64,
    },
    /// A position error exceeded `simulation.max_position_error`.
    PositionError {
        /// The error reached, m.
        error: f64,
    },
}

/// How a run ended.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case", tag = "status")]
pub enum ExitStatus {
    /// Ran for the whole duration.
    Completed,
    /// Stopped at `time` (s) for `divergence`.
    Diverged {
        /// What went wrong.
        divergence: Divergence,
        /// Simulated time at which it was detected, s.
        time: f64,
    },
    /// Hit the ground (`[ground]`) faster than `max_touchdown_speed`.
    Crashed {
        /// Simulated time of the touchdown, s.
        time: f64,
        /// Downward speed at touchdown, m/s.
        impact_speed: f64,
    },
}

impl ExitStatus {
    /// True for [`ExitStatus::Completed`].
    pub fn is_completed(&self) -> bool {
        matches!(self, ExitStatus::Completed)
    }

    /// Simulated time at which the run diverged (`None` if it completed).
    pub fn diverged_at(&self) -> Option<f64> {
        match self {
            ExitStatus::Diverged { time, .. } => Some(*time),
            ExitStatus::Completed | ExitStatus::Crashed { .. } => None,
        }
    }

    /// True for [`ExitStatus::Crashed`].
    pub fn is_crashed(&self) -> bool {
        matches!(self, ExitStatus::Crashed { .. })
    }

    /// Short form for table cells: `completed`, `diverged at 0.64 s` or `crashed at 1.23 s`.
    pub fn short(&self) -> String {
        match self {
            ExitStatus::Completed => "completed".into(),
            ExitStatus::Diverged { time, .. } => format!("diverged at {time:.2} s"),
            ExitStatus::Crashed { time, .. } => format!("crashed at {time:.2} s"),
        }
    }
}

impl core::fmt::Display for ExitStatus {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ExitStatus::Completed => write!(f, "completed"),
            ExitStatus::Diverged { divergence, time } => match divergence {
                Divergence::NonFinite => write!(f, "diverged: non-finite state at t = {time:.3} s"),
                Divergence::Tilt { angle } => write!(f, "diverged: tilt {angle:.3} rad at t = {time:.3} s"),
                Divergence::PositionError { error } => {
                    write!(f, "diverged: position error {error:.3} m at t = {time:.3} s")
                }
            },
            ExitStatus::Crashed { time, impact_speed } => {
                write!(f, "crashed: hit the ground at {impact_speed:.1} m/s at t = {time:.3} s")
            }
        }
    }
}

/// Widest row of a [`Recording`]: every column of [`recording_columns`]
/// with all estimate slots named and the mass adaptation on.
pub const MAX_RECORDING_COLUMNS: usize = 1 + 12 + 3 + 3 + 2 + 4 + 4 + 4 + 1 + 6 + 6 * MAX_ESTIMATES + 2 + 4 + 6;

/// Column names of a [`Recording`], in order (docs/outputs.md explains each):
/// `t`, the state, the references, the commanded and applied inputs, rotor
/// speeds, sliding variables, the named estimates `<name>_<axis>` of each
/// channel law (`estimate_names`, e.g. `["delta_hat", "", ""]`; `""` slots
/// are not written), `alpha_hat` and `mass_estimate` (only with mass
/// adaptation, `adapts_mass`), true mass and inertia, disturbances.
pub fn recording_columns(estimate_names: &[&str; MAX_ESTIMATES], adapts_mass: bool) -> Vec<String> {
    let mut names: Vec<String> = [
        "t",
        "x",
        "y",
        "z",
        "phi",
        "theta",
        "psi",
        "vx",
        "vy",
        "vz",
        "phi_rate",
        "theta_rate",
        "psi_rate",
        "x_ref",
        "y_ref",
        "z_ref",
        "phi_ref",
        "theta_ref",
        "psi_ref",
        "phi_demand",
        "theta_demand",
        "thrust",
        "roll_torque",
        "pitch_torque",
        "yaw_torque",
        "thrust_cmd",
        "roll_torque_cmd",
        "pitch_torque_cmd",
        "yaw_torque_cmd",
        "omega_1",
        "omega_2",
        "omega_3",
        "omega_4",
        "omega_bar",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    for axis in ftsmc_core::cascade::channel::NAMES {
        names.push(format!("s_{axis}"));
    }
    for axis in ftsmc_core::cascade::channel::NAMES {
        for name in estimate_names.iter().filter(|n| !n.is_empty()) {
            names.push(format!("{name}_{axis}"));
        }
    }
    if adapts_mass {
        names.push("alpha_hat".into());
        names.push("mass_estimate".into());
    }
    for n in ["mass_true", "inertia_1", "inertia_2", "inertia_3"] {
        names.push(n.to_string());
    }
    for axis in ftsmc_core::cascade::channel::NAMES {
        names.push(format!("d_{axis}"));
    }
    names
}

/// Time series of a run, column-major.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Recording {
    /// Column names ([`recording_columns`]).
    pub names: Vec<String>,
    /// One vector per column, all the same length.
    pub columns: Vec<Vec<f64>>,
}

impl Recording {
    /// An empty recording with these columns.
    pub fn with_columns(names: Vec<String>) -> Self {
        let columns = vec![Vec::new(); names.len()];
        Self { names, columns }
    }

    /// Append one row (`row.len()` must equal the number of columns).
    #[inline]
    pub fn push_row(&mut self, row: &[f64]) {
        debug_assert_eq!(row.len(), self.columns.len());
        for (col, &v) in self.columns.iter_mut().zip(row) {
            col.push(v);
        }
    }

    /// The column called `name` (empty slice if unknown).
    pub fn column(&self, name: &str) -> &[f64] {
        self.names.iter().position(|n| n == name).map(|i| self.columns[i].as_slice()).unwrap_or(&[])
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.columns.first().map_or(0, Vec::len)
    }

    /// True when no row was recorded.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Append the time series as CSV to `out`: a header of the column
    /// names, then one line per row, `,`-separated, `\n`-terminated, each
    /// number in its shortest round-trip form ([`push_number`]). No
    /// allocation per number or row (issue 10: the `csv` crate with a
    /// `String` per number cost ~9,600 instructions per simulated step).
    pub fn write_csv(&self, out: &mut Vec<u8>) {
        // ~20 bytes per number (sign, 17 digits, point, separator).
        out.reserve(self.names.iter().map(|n| n.len() + 1).sum::<usize>() + self.len() * self.columns.len() * 20);
        for (j, name) in self.names.iter().enumerate() {
            if j > 0 {
                out.push(b',');
            }
            out.extend_from_slice(name.as_bytes());
        }
        out.push(b'\n');
        let mut buffer = zmij::Buffer::new();
        for i in 0..self.len() {
            for (j, column) in self.columns.iter().enumerate() {
                if j > 0 {
                    out.push(b',');
                }
                push_number_with(&mut buffer, out, column[i]);
            }
            out.push(b'\n');
        }
    }

    /// [`Recording::write_csv`] into a new buffer.
    pub fn to_csv(&self) -> Vec<u8> {
        let mut out = Vec::new();
        self.write_csv(&mut out);
        out
    }
}

/// Append `v` to `out` in its shortest round-trip decimal form, parsing
/// back to the same bits (`0.3`, `1.0`, `-2.5e-7`, `1.2e+16`: positional for
/// decimal exponents −5…15, else scientific), or `NaN`, `inf`, `-inf` when
/// not finite (spelled as pandas and MATLAB read them).
///
/// The digits come from `zmij` (Schubfach/yy; dtolnay's successor to `ryu`,
/// the formatter serde_json uses, so summary.json prints numbers the same
/// way): on a scenario-2 flight it needs ~220 instructions per number
/// against ~360 for `ryu` and ~1,500 for `format!("{v}")` into a `String`.
pub fn push_number(out: &mut Vec<u8>, v: f64) {
    push_number_with(&mut zmij::Buffer::new(), out, v);
}

#[inline]
fn push_number_with(buffer: &mut zmij::Buffer, out: &mut Vec<u8>, v: f64) {
    if v.is_finite() {
        out.extend_from_slice(buffer.format_finite(v).as_bytes());
    } else if v.is_nan() {
        out.extend_from_slice(b"NaN");
    } else if v > 0.0 {
        out.extend_from_slice(b"inf");
    } else {
        out.extend_from_slice(b"-inf");
    }
}

/// One row of a [`Recording`] being assembled on the stack.
struct Row {
    values: [f64; MAX_RECORDING_COLUMNS],
    len: usize,
}

impl Row {
    #[inline]
    fn new() -> Self {
        Self { values: [0.0; MAX_RECORDING_COLUMNS], len: 0 }
    }

    #[inline]
    fn push(&mut self, v: f64) {
        self.values[self.len] = v;
        self.len += 1;
    }

    #[inline]
    fn extend(&mut self, vs: &[f64]) {
        self.values[self.len..self.len + vs.len()].copy_from_slice(vs);
        self.len += vs.len();
    }

    fn as_slice(&self) -> &[f64] {
        &self.values[..self.len]
    }
}

/// Result of one flight.
#[derive(Clone, Debug)]
pub struct RunOutput {
    /// Controller name.
    pub controller: String,
    /// Scenario name.
    pub scenario: String,
    /// How the run ended.
    pub exit: ExitStatus,
    /// Metrics up to the end (or divergence).
    pub metrics: Metrics,
    /// Time series (empty when recording is off).
    pub recording: Recording,
    /// Control steps executed.
    pub steps: u64,
    /// The success envelope's verdict (`None`: the scenario has no `[envelope]`).
    pub envelope: Option<crate::envelope::Verdict>,
}

impl RunOutput {
    /// Completed and inside the scenario's envelope (just completed without one).
    pub fn success(&self) -> bool {
        self.envelope.as_ref().map_or(self.exit.is_completed(), |v| v.success)
    }
}

/// Plant-side variations of a scenario evaluated in time: payload, inertia
/// variation, drag noise and disturbances. The controller never sees these.
pub struct Environment<'a> {
    scenario: &'a Scenario,
    drag_rngs: Option<[ChaCha8Rng; 6]>,
    drag_factor: [f64; 6],
}

impl<'a> Environment<'a> {
    /// Drag noise streams are derived from `scenario.seed`: stream `k` for
    /// coefficient `k` (K_f1x, K_f1y, K_f1z, K_f2x, K_f2y, K_f2z).
    pub fn new(scenario: &'a Scenario) -> Self {
        let drag_rngs = scenario.drag_noise.map(|_| {
            core::array::from_fn(|k| {
                let mut rng = ChaCha8Rng::seed_from_u64(scenario.seed);
                rng.set_stream(1 + k as u64);
                rng
            })
        });
        Self { scenario, drag_rngs, drag_factor: [1.0; 6] }
    }

    /// Draw the drag multipliers for the next control period.
    pub fn next_period(&mut self) {
        if let (Some(rngs), Some(noise)) = (&mut self.drag_rngs, self.scenario.drag_noise) {
            for (factor, rng) in self.drag_factor.iter_mut().zip(rngs.iter_mut()) {
                let w: f64 = StandardNormal.sample(rng);
                *factor = (1.0 + noise.std * w).max(0.0);
            }
        }
    }

    /// Drag multipliers of the current period.
    pub fn drag_factor(&self) -> [f64; 6] {
        self.drag_factor
    }

    /// The smooth time-varying plant inputs at `t` (s): true mass, inertia
    /// and disturbances (drag noise is per control period and kept apart).
    #[inline]
    pub fn time_varying(&self, t: f64) -> TimeVarying {
        let s = self.scenario;
        let base = s.actual_plant.unwrap_or(s.plant);
        let mut mass = base.mass;
        if let Some(payload) = &s.payload {
            mass += payload.added_mass(t);
        }
        let mut inertia = base.inertia;
        if let Some(var) = &s.inertia_variation {
            let scale = 1.0 + var.value(t);
            for i in &mut inertia {
                *i *= scale;
            }
        }
        TimeVarying { mass, inertia, disturbance: s.disturbance.at(t) }
    }

    /// Plant parameters for given time-varying inputs and the current
    /// period's drag noise.
    #[inline]
    pub fn params_with(&self, tv: &TimeVarying) -> QuadrotorParams {
        let s = self.scenario;
        let mut p = s.actual_plant.unwrap_or(s.plant);
        p.mass = tv.mass;
        p.inertia = tv.inertia;
        for i in 0..3 {
            p.drag_translational[i] *= self.drag_factor[i];
            p.drag_rotational[i] *= self.drag_factor[3 + i];
        }
        p
    }

    /// Plant parameters at time `t` (s).
    #[inline]
    pub fn params(&self, t: f64) -> QuadrotorParams {
        self.params_with(&self.time_varying(t))
    }

    /// Disturbances `[D_x … D_ψ]` at `t`.
    #[inline]
    pub fn disturbance(&self, t: f64) -> [f64; 6] {
        self.scenario.disturbance.at(t)
    }
}

/// Mass (kg), inertia (kg·m²) and disturbances (m/s², rad/s²) at one instant.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TimeVarying {
    /// True mass, kg.
    pub mass: f64,
    /// True `[I1, I2, I3]`, kg·m².
    pub inertia: [f64; 3],
    /// `[D_x, D_y, D_z, D_φ, D_θ, D_ψ]`.
    pub disturbance: [f64; 6],
}

impl TimeVarying {
    /// Linear interpolation `a + w (b − a)`.
    #[inline]
    pub fn lerp(a: &Self, b: &Self, w: f64) -> Self {
        let l = |x: f64, y: f64| x + w * (y - x);
        Self {
            mass: l(a.mass, b.mass),
            inertia: core::array::from_fn(|i| l(a.inertia[i], b.inertia[i])),
            disturbance: core::array::from_fn(|i| l(a.disturbance[i], b.disturbance[i])),
        }
    }
}

/// The reference of `scenario` at time `t`.
#[inline]
pub fn reference_at(scenario: &Scenario, t: f64) -> Reference {
    let r = &scenario.reference;
    let (x, y, z, psi) = (r.x.sample(t), r.y.sample(t), r.z.sample(t), r.psi.sample(t));
    Reference {
        position: [x.value, y.value, z.value],
        velocity: [x.rate, y.rate, z.rate],
        acceleration: [x.acceleration, y.acceleration, z.acceleration],
        yaw: psi.value,
        yaw_rate: psi.rate,
        yaw_acceleration: psi.acceleration,
    }
}

/// Options of one run (construct with `RunOptions { record: false, ..Default::default() }`).
#[derive(Clone, Copy)]
pub struct RunOptions<'a> {
    /// Record the time series at `simulation.record_rate`.
    pub record: bool,
    /// Called with the number of control steps flown since the last call,
    /// every [`PROGRESS_EVERY`] steps and once at the end (the remainder of
    /// the planned steps, so a diverged run still adds its planned total).
    pub progress: Option<&'a (dyn Fn(u64) + Sync)>,
}

/// Control steps between two [`RunOptions::progress`] calls.
pub const PROGRESS_EVERY: u64 = 1000;

impl Default for RunOptions<'_> {
    fn default() -> Self {
        Self { record: true, progress: None }
    }
}

impl core::fmt::Debug for RunOptions<'_> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("RunOptions").field("record", &self.record).field("progress", &self.progress.is_some()).finish()
    }
}

/// Control steps a flight of `scenario` plans (its progress total).
pub fn planned_steps(scenario: &Scenario) -> u64 {
    (scenario.duration / scenario.control_period()).round() as u64
}

/// The command as the rotors deliver it: the applied thrust and torques
/// (after the rotor-speed limits, when set), the rotor speeds (rad/s) and
/// their residual Ω̄.
fn realise(command: &Command, plant: &QuadrotorParams, max_rotor_speed: Option<f64>) -> (Command, [f64; 4], f64) {
    let omega = rotor_speeds(plant, command, max_rotor_speed.unwrap_or(f64::INFINITY));
    let applied = match max_rotor_speed {
        Some(_) => forces_from_squared_speeds(plant, &omega.map(|o| o * o)),
        None => *command,
    };
    (applied, omega, residual_speed(&omega))
}

/// Fly `controller` through `scenario`.
pub fn simulate(scenario: &Scenario, controller: &mut dyn Controller, options: RunOptions<'_>) -> RunOutput {
    // Hook (issue 11): rigid body, real actuators or a ground fly the realistic loop.
    if crate::truth::is_realistic(scenario) {
        return crate::truth::simulate_realistic(scenario, controller, options);
    }
    let sim = &scenario.simulation;
    let dt = scenario.control_period();
    let steps = (scenario.duration / dt).round() as u64;
    let h = dt / sim.substeps as f64;
    let record_every = if options.record && sim.record_rate > 0.0 {
        ((sim.control_rate / sim.record_rate).round() as u64).max(1)
    } else {
        0
    };

    let mut env = Environment::new(scenario);
    let mut x = scenario.initial_state.state().to_array();
    let mut metrics = MetricsAccumulator::new(dt, sim.settling_band, sim.settling_floor, sim.steady_state_after)
        .with_window(sim.metrics_window);
    let estimate_names = controller.estimate_names();
    let adapts_mass = controller.adapts_mass();
    let mut recording = if record_every > 0 {
        Recording::with_columns(recording_columns(&estimate_names, adapts_mass))
    } else {
        Recording::default()
    };
    // The estimate slots written: (slot) for each named one.
    let named_slots: Vec<usize> = (0..MAX_ESTIMATES).filter(|&k| !estimate_names[k].is_empty()).collect();
    if let Some(per_row) = steps.checked_div(record_every) {
        let rows = (per_row + 1) as usize;
        for c in &mut recording.columns {
            c.reserve(rows);
        }
    }
    let mut exit = ExitStatus::Completed;
    let mut executed = 0;
    let mut envelope = crate::envelope::Tracker::new(scenario.envelope); // issue 11 hook
    envelope.observe(0.0, &x[0..3], &reference_at(scenario, 0.0).position, &x[3..5]);

    // Time-varying plant inputs are evaluated once per substep boundary and
    // interpolated linearly inside the substep (RK4 stage times); this keeps
    // the integration second-order in the inputs' time variation while
    // evaluating each sinusoid once per substep instead of four times.
    let mut tv_now = env.time_varying(0.0);
    let mut reference = reference_at(scenario, 0.0);
    for k in 0..steps {
        let t = k as f64 * dt;
        let state = QuadState::from_array(&x);
        let command = controller.update(&state, &reference, dt);
        let telemetry = controller.telemetry();
        env.next_period();
        let plant_now = env.params_with(&tv_now);
        let (applied, omega, omega_bar) = realise(&command, &plant_now, sim.max_rotor_speed);

        let mut errors = [0.0; 6];
        for i in 0..3 {
            errors[i] = x[i] - reference.position[i];
        }
        errors[3] = x[3] - telemetry.attitude_reference[0];
        errors[4] = x[4] - telemetry.attitude_reference[1];
        errors[5] = x[5] - reference.yaw;
        let u = [applied.thrust, applied.torque[0], applied.torque[1], applied.torque[2]];
        if !(u.iter().all(|v| v.is_finite())) {
            exit = ExitStatus::Diverged { divergence: Divergence::NonFinite, time: t };
            break;
        }
        metrics.observe(t, &errors, &u);

        if record_every > 0 && k % record_every == 0 {
            let mut row = Row::new();
            row.push(t);
            row.extend(&x);
            row.extend(&reference.position);
            row.extend(&telemetry.attitude_reference);
            row.extend(&telemetry.attitude_demand);
            row.extend(&u);
            row.extend(&[command.thrust, command.torque[0], command.torque[1], command.torque[2]]);
            row.extend(&omega);
            row.push(omega_bar);
            row.extend(&telemetry.sliding);
            for est in &telemetry.estimates {
                for &slot in &named_slots {
                    row.push(est[slot]);
                }
            }
            if adapts_mass {
                row.push(telemetry.alpha_hat);
                row.push(telemetry.alpha_hat * scenario.plant.mass);
            }
            row.push(plant_now.mass);
            row.extend(&plant_now.inertia);
            row.extend(&tv_now.disturbance);
            recording.push_row(row.as_slice());
        }

        // Plant between ticks: RK4 substeps with the command held.
        for j in 0..sim.substeps {
            let t0 = t + j as f64 * h;
            let tv_next = env.time_varying(t0 + h);
            let (a, b, env_ref) = (tv_now, tv_next, &env);
            let f = |tau: f64, s: &[f64; 12]| {
                let tv = TimeVarying::lerp(&a, &b, (tau - t0) / h);
                derivative(s, &applied, omega_bar, &env_ref.params_with(&tv), &tv.disturbance)
            };
            x = rk4_step(f, t0, &x, h);
            tv_now = tv_next;
        }
        executed = k + 1;
        if let Some(progress) = options.progress {
            if executed % PROGRESS_EVERY == 0 {
                progress(PROGRESS_EVERY);
            }
        }

        let t_next = (k + 1) as f64 * dt;
        reference = reference_at(scenario, t_next);
        envelope.observe(t_next, &x[0..3], &reference.position, &x[3..5]);
        if let Some(divergence) = check_divergence(scenario, &x, &reference) {
            exit = ExitStatus::Diverged { divergence, time: t_next };
            break;
        }
    }

    if let Some(progress) = options.progress {
        progress(steps - executed / PROGRESS_EVERY * PROGRESS_EVERY);
    }
    RunOutput {
        controller: controller.name().to_string(),
        scenario: scenario.name.clone(),
        envelope: envelope.verdict(&exit),
        exit,
        metrics: metrics.finish(),
        recording,
        steps: executed,
    }
}

pub(crate) fn check_divergence(scenario: &Scenario, x: &[f64; 12], reference: &Reference) -> Option<Divergence> {
    if x.iter().any(|v| !v.is_finite()) {
        return Some(Divergence::NonFinite);
    }
    let sim = &scenario.simulation;
    for &angle in &x[3..5] {
        if angle.abs() > sim.max_tilt {
            return Some(Divergence::Tilt { angle });
        }
    }
    for i in 0..3 {
        let error = (x[i] - reference.position[i]).abs();
        if error > sim.max_position_error {
            return Some(Divergence::PositionError { error });
        }
    }
    None
}
