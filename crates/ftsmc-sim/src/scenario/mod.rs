//! Scenario files (TOML): everything a run needs — duration, rates, plant,
//! initial state, references, disturbances, payload, parameter variation,
//! noise, and every controller's gains. Unknown keys are rejected and every
//! value is range-checked; errors name the file, the key and the value.

use std::path::Path;

use ftsmc_core::cascade::CascadeSettings;
use ftsmc_core::law::GainError;
use ftsmc_core::model::{QuadState, QuadrotorParams};
use serde::{Deserialize, Serialize};

mod deprecated;
pub mod distributions;
pub mod falsify_section;
pub mod ladder;
pub mod overrides;
pub mod resolve;
pub mod seed;
pub mod tune_section;
mod validate;

pub use crate::axes::AxisSet;
pub use crate::controllers::ftaftsmc::FtaftsmcConfig;
pub use crate::controllers::{GainSections, PAPER_CONTROLLERS};
pub use crate::environment::{DisturbanceSignals, DragNoise, Payload};
pub use crate::text::{exact_array, show, show_str, MAX_SHOWN_CHARS};
pub use distributions::{Dist, MonteCarloSpec};
pub(crate) use validate::check_core_array_lengths;
pub use validate::{check_name, MAX_NAME_CHARS};

use crate::environment::EnvironmentParams;
use crate::limits::{LimitError, Limits};
use crate::signal::Signal;

/// The paper's scenario 1 (SPEC §4), as shipped in `scenarios/paper-scenario-1.toml`.
pub const PAPER_SCENARIO_1: &str = include_str!("../../../../scenarios/paper-scenario-1.toml");
/// The paper's scenario 2 (SPEC §4), as shipped in `scenarios/paper-scenario-2.toml`.
pub const PAPER_SCENARIO_2: &str = include_str!("../../../../scenarios/paper-scenario-2.toml");

/// Paper scenario 1 with the FTAFTSMC x/y reaching law tuned against the
/// limit cycle, as shipped in `scenarios/ftaftsmc-tuned-scenario-1.toml`.
pub const FTAFTSMC_TUNED_SCENARIO_1: &str = include_str!("../../../../scenarios/ftaftsmc-tuned-scenario-1.toml");

/// Alias of `realistic-moderate-1`, the moderate rung of the wind ladder ([`ladder`]).
pub const REALISTIC_SCENARIO_1: &str = include_str!("../../../../scenarios/realistic-scenario-1.toml");
/// Alias of `realistic-moderate-2`, the moderate rung of the wind ladder ([`ladder`]).
pub const REALISTIC_SCENARIO_2: &str = include_str!("../../../../scenarios/realistic-scenario-2.toml");

/// Every scenario built into the library: `(file name, TOML text)`.
pub const BUILT_IN_SCENARIOS: [(&str, &str); 13] = [
    ("paper-scenario-1.toml", PAPER_SCENARIO_1),
    ("paper-scenario-2.toml", PAPER_SCENARIO_2),
    ("ftaftsmc-tuned-scenario-1.toml", FTAFTSMC_TUNED_SCENARIO_1),
    ("realistic-scenario-1.toml", REALISTIC_SCENARIO_1),
    ("realistic-scenario-2.toml", REALISTIC_SCENARIO_2),
    ladder::LADDER[0],
    ladder::LADDER[1],
    ladder::LADDER[2],
    ladder::LADDER[3],
    ladder::LADDER[4],
    ladder::LADDER[5],
    ladder::LADDER[6],
    ladder::LADDER[7],
];

/// The paper scenarios built into the library: `(file name, TOML text)`.
pub const PAPER_SCENARIOS: [(&str, &str); 2] =
    [("paper-scenario-1.toml", PAPER_SCENARIO_1), ("paper-scenario-2.toml", PAPER_SCENARIO_2)];

/// Why a scenario could not be loaded. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum ScenarioError {
    /// The file could not be read.
    #[error("cannot read scenario file {path}")]
    Io {
        /// File path.
        path: String,
        /// Underlying error.
        source: std::io::Error,
    },
    /// Not valid TOML, a missing or unknown key, or a value of the wrong type.
    #[error("{path}: {message}")]
    Parse {
        /// File path.
        path: String,
        /// Parser message (names the key and line).
        message: String,
    },
    /// A value outside its allowed range.
    #[error("{path}: `{key}` = {value} is invalid (expected {expected})")]
    Invalid {
        /// File path.
        path: String,
        /// Dotted key, e.g. `ftaftsmc.z.p`.
        key: String,
        /// The offending value as written.
        value: String,
        /// What is allowed.
        expected: String,
    },
    /// The file is not a regular file, or too large to be a scenario.
    #[error("{path}: {message}")]
    File {
        /// File path.
        path: String,
        /// What is wrong.
        message: String,
    },
    /// The scenario costs more than its limits allow (see [`crate::limits`]).
    #[error("{path}: {limit}")]
    Limit {
        /// File path.
        path: String,
        /// The limit exceeded, the amount requested and how to raise it.
        limit: LimitError,
    },
    /// A controller name that is not in the registry.
    #[error("{path}: unknown controller `{name}` (known: {known})")]
    UnknownController {
        /// File path (or `command line`).
        path: String,
        /// The name given.
        name: String,
        /// Known names, comma-separated.
        known: String,
    },
}

/// Integration, recording, divergence and metric settings.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct SimulationSettings {
    /// Controller rate, Hz (default 1000). The command is held constant
    /// (zero-order hold) over each control period.
    pub control_rate: f64,
    /// RK4 substeps per control period (default 1).
    pub substeps: u32,
    /// Recording rate of the time series, Hz (default 100; 0 = no time series).
    pub record_rate: f64,
    /// A run diverges when any position error exceeds this, m (default 100).
    pub max_position_error: f64,
    /// A run diverges when |φ| or |θ| exceeds this, rad (default π/2).
    pub max_tilt: f64,
    /// 2 % settling: band as a fraction of the initial error (default 0.02).
    pub settling_band: f64,
    /// Smallest settling band, channel units (default 1e-3), used when the
    /// initial error is (near) zero.
    pub settling_floor: f64,
    /// "Steady state" starts here for the max-error metric, s (default 5).
    pub steady_state_after: f64,
    /// Optional `[start, end]` window (s) for an extra windowed ISE metric.
    #[serde(skip_serializing_if = "Option::is_none", with = "exact_array::option")]
    pub metrics_window: Option<[f64; 2]>,
    /// Rotor speed limit, rad/s (default: none, ideal actuators). When set,
    /// the commanded thrust and torques are realised through rotor speeds
    /// clamped to `[0, max_rotor_speed]`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_rotor_speed: Option<f64>,
}

impl Default for SimulationSettings {
    fn default() -> Self {
        Self {
            control_rate: 1000.0,
            substeps: 1,
            record_rate: 100.0,
            max_position_error: 100.0,
            max_tilt: core::f64::consts::FRAC_PI_2,
            settling_band: 0.02,
            settling_floor: 1e-3,
            steady_state_after: 5.0,
            metrics_window: None,
            max_rotor_speed: None,
        }
    }
}

/// Initial state (defaults: all zero).
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct InitialState {
    /// `[x, y, z]`, m.
    #[serde(with = "exact_array")]
    pub position: [f64; 3],
    /// `[φ, θ, ψ]`, rad.
    #[serde(with = "exact_array")]
    pub attitude: [f64; 3],
    /// `[ẋ, ẏ, ż]`, m/s.
    #[serde(with = "exact_array")]
    pub velocity: [f64; 3],
    /// `[φ̇, θ̇, ψ̇]`, rad/s.
    #[serde(with = "exact_array")]
    pub angular_rate: [f64; 3],
}

impl InitialState {
    /// As a [`QuadState`].
    pub fn state(&self) -> QuadState {
        QuadState {
            position: self.position,
            attitude: self.attitude,
            velocity: self.velocity,
            angular_rate: self.angular_rate,
        }
    }
}

/// Desired trajectory: x_d, y_d, z_d (m) and ψ_d (rad) as signals with
/// analytic derivatives (default: hold the origin, ψ_d = 0).
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct ReferenceSignals {
    /// x_d(t), m.
    pub x: Signal,
    /// y_d(t), m.
    pub y: Signal,
    /// z_d(t), m.
    pub z: Signal,
    /// ψ_d(t), rad.
    pub psi: Signal,
    /// A 3-D trajectory with heading ([`crate::trajectory`]): when given,
    /// x_d, y_d, z_d, ψ_d and their derivatives come from it, and `x`, `y`,
    /// `z`, `psi` must be absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trajectory: Option<crate::trajectory::Trajectory>,
    /// `"fixed"` (default): refuse a trajectory the vehicle cannot fly;
    /// `"fit"`: stretch its time by the smallest factor that fits.
    #[serde(default, skip_serializing_if = "is_fixed_time_scale")]
    pub time_scale: crate::trajectory::TimeScale,
}

fn is_fixed_time_scale(t: &crate::trajectory::TimeScale) -> bool {
    *t == crate::trajectory::TimeScale::Fixed
}

impl ReferenceSignals {
    /// The same four signals bit for bit ([`Signal::same_bits`]: `-0.0`
    /// and `0.0` differ): flown on the same control grid, two such
    /// references give the same bits at every step.
    pub fn same_bits(&self, other: &ReferenceSignals) -> bool {
        self.x.same_bits(&other.x)
            && self.y.same_bits(&other.y)
            && self.z.same_bits(&other.z)
            && self.psi.same_bits(&other.psi)
            && match (&self.trajectory, &other.trajectory) {
                (None, None) => true,
                (Some(a), Some(b)) => a.same_bits(b),
                _ => false,
            }
    }
}

fn default_controllers() -> Vec<String> {
    PAPER_CONTROLLERS.iter().map(|s| s.to_string()).collect()
}

/// Read a scenario file's text, refusing anything but a regular file of at
/// most `limits.max_scenario_bytes` bytes. The type and size are checked on
/// the metadata before the file is opened (a FIFO would block `open`), and
/// the read itself is bounded, so `/dev/zero`, a FIFO, a directory or a
/// file that grows while being read are refused without reading them.
pub fn read_scenario_text(path: &Path, limits: &Limits) -> Result<String, ScenarioError> {
    use std::io::Read as _;
    let shown = path.display().to_string();
    let io = |source| ScenarioError::Io { path: shown.clone(), source };
    let not_regular = |meta: &std::fs::Metadata| {
        let kind = if meta.is_dir() { "a directory" } else { "not a regular file (a device, FIFO or socket)" };
        ScenarioError::File { path: shown.clone(), message: format!("{kind}; a scenario must be a regular file") }
    };
    // The limit, and with it switched off (`inf`) its hard bound.
    let max =
        limits.max_scenario_bytes.min(crate::limits::hard_bound("max_scenario_bytes").0).min(u64::MAX as f64) as u64;
    let too_big = |bytes: u64| ScenarioError::Limit {
        path: shown.clone(),
        limit: crate::limits::check_file_size(limits, bytes).expect_err("over the limit"),
    };
    let meta = std::fs::metadata(path).map_err(io)?;
    if !meta.is_file() {
        return Err(not_regular(&meta));
    }
    if meta.len() > max {
        return Err(too_big(meta.len()));
    }
    let file = std::fs::File::open(path).map_err(io)?;
    let meta = file.metadata().map_err(io)?;
    if !meta.is_file() {
        return Err(not_regular(&meta));
    }
    let mut bytes = Vec::new();
    file.take(max.saturating_add(1)).read_to_end(&mut bytes).map_err(io)?;
    if bytes.len() as u64 > max {
        return Err(too_big(bytes.len() as u64));
    }
    String::from_utf8(bytes).map_err(|e| ScenarioError::File {
        path: shown.clone(),
        message: format!("not UTF-8 text (invalid byte at offset {})", e.utf8_error().valid_up_to()),
    })
}

/// A complete scenario (see `docs/scenarios.md` for the file format).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// Short name used in output paths.
    pub name: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// Simulated time, s.
    pub duration: f64,
    /// Master seed of every random stream (drag noise, Monte Carlo); a seed
    /// of 2^63 or more is written as a decimal string, since TOML integers
    /// are i64 (see [`seed`]).
    #[serde(default, with = "seed")]
    pub seed: u64,
    /// Controllers to run (registry names).
    #[serde(default = "default_controllers")]
    pub controllers: Vec<String>,
    /// Integration and metric settings.
    #[serde(default)]
    pub simulation: SimulationSettings,
    /// Nominal plant parameters (the controllers' model; the true vehicle's
    /// too, key by key, unless `[vehicle]` says otherwise).
    #[serde(default)]
    pub plant: QuadrotorParams,
    /// Initial state.
    #[serde(default)]
    pub initial_state: InitialState,
    /// Desired trajectory.
    #[serde(default)]
    pub reference: ReferenceSignals,
    /// External disturbances (plant only).
    #[serde(default)]
    pub disturbance: DisturbanceSignals,
    /// Payload profile (plant only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub payload: Option<Payload>,
    /// Relative inertia variation: `I_i(t) = I_i (1 + signal(t))` (plant only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inertia_variation: Option<Signal>,
    /// Drag-coefficient noise (plant only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub drag_noise: Option<DragNoise>,
    /// Cascade options shared by all controllers.
    #[serde(default)]
    pub cascade: CascadeSettings,
    /// Every declared controller's gain section (`scenario.gains.ftaftsmc`,
    /// …; see [`crate::controllers`]), written as the top-level tables
    /// `[ftaftsmc]`, `[ranftsmc]`, `[tsm-sta]`, … in the list's order.
    ///
    /// Not read by `Scenario`'s own `Deserialize` (serde's `flatten` would
    /// lose `deny_unknown_fields` and the key paths of errors): the loaders
    /// ([`Scenario::from_toml_str`], [`Scenario::from_file`]) take the
    /// sections out of the TOML tree and parse each with its declared type.
    /// Deserializing a `Scenario` directly rejects them as unknown fields.
    #[serde(flatten, skip_deserializing)]
    pub gains: GainSections,
    /// Distributions for `ftsmc montecarlo` (ignored by single runs).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub montecarlo: Option<MonteCarloSpec>,
    /// Cost limits (see [`crate::limits`]); every key optional.
    #[serde(default, skip_serializing_if = "is_default_limits")]
    pub limits: Limits,
    // --- truth model, actuators, ground, success envelope ---
    /// The true vehicle (`[vehicle]`): which truth model flies and every
    /// true parameter that differs from `[plant]` (default: the paper plant
    /// of Eq. 1 flying `[plant]`).
    #[serde(default, skip_serializing_if = "crate::vehicle::VehicleSettings::is_default")]
    pub vehicle: crate::vehicle::VehicleSettings,
    /// Rotor limits, motor lag and noise (`[actuators]`, default: ideal).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub actuators: Option<crate::actuators::ActuatorParams>,
    /// Ground plane (`[ground]`, default: none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ground: Option<crate::environment::ground::GroundSettings>,
    /// Success envelope (`[envelope]`, default: success = completed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub envelope: Option<crate::envelope::Envelope>,
    /// Moving air (`[wind]`: mean, gusts, Dryden turbulence; default: still air).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wind: Option<crate::environment::wind::WindParams>,
    /// What the controller measures (`[sensors]`, default: the true state).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sensors: Option<crate::sensors::SensorParams>,
    /// What `ftsmc tune` searches and its cost weights (`[tune]`; ignored
    /// by every other command).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tune: Option<tune_section::TuneSection>,
    /// The search space of `ftsmc falsify` and `ftsmc failure-probability`
    /// (`[falsify]`; ignored by every other command).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub falsify: Option<falsify_section::FalsifySection>,
}

fn is_default_limits(l: &Limits) -> bool {
    *l == Limits::default()
}

impl Scenario {
    /// The true vehicle in paper form (Eq. 1's parameters): `[plant]` with
    /// the keys `[vehicle]` gives ([`crate::vehicle::VehicleSettings::true_vehicle`]).
    pub fn true_vehicle(&self) -> QuadrotorParams {
        self.vehicle.true_vehicle(&self.plant)
    }

    /// The true mass before any payload, kg, and the key it comes from
    /// (`vehicle.mass`, else `plant.mass`).
    pub fn true_mass(&self) -> (f64, &'static str) {
        match self.vehicle.mass {
            Some(m) => (m, "vehicle.mass"),
            None => (self.plant.mass, "plant.mass"),
        }
    }

    /// Rigid-body parameters of the true vehicle
    /// ([`crate::vehicle::VehicleSettings::rigid_body`]): `[plant]` with the
    /// keys `[vehicle]` gives, "+" layout, no aerodynamics unless given.
    pub fn rigid_body_params(&self) -> crate::vehicle::RigidBodyParams {
        self.vehicle.rigid_body(&self.plant)
    }

    /// What the controllers' vehicle-derived default gains are built for:
    /// the nominal `[plant]`, the rotor limit of `[actuators]` (or
    /// `simulation.max_rotor_speed`) and the true vehicle's rotor layout
    /// (the rigid body's; "+" on Eq. 1); see [`crate::controllers::GainSection::defaults_for`].
    pub fn nominal_vehicle(&self) -> crate::controllers::NominalVehicle {
        let limit =
            self.actuators.map(|a| a.max_rotor_speed).filter(|w| w.is_finite()).or(self.simulation.max_rotor_speed);
        let vehicle = crate::controllers::NominalVehicle::new(self.plant, limit);
        match self.vehicle.model {
            crate::vehicle::VehicleModel::Paper => vehicle,
            crate::vehicle::VehicleModel::RigidBody => vehicle.on(self.rigid_body_params().geometry()),
        }
    }

    /// Allocation matrix of the truth model and the paper-form parameters used
    /// for the unsaturated rotor-speed demand.
    pub fn truth_allocation(&self) -> ([[f64; 4]; 4], QuadrotorParams) {
        let base = self.true_vehicle();
        match self.vehicle.model {
            crate::vehicle::VehicleModel::Paper => (crate::actuators::paper_allocation_matrix(&base), base),
            crate::vehicle::VehicleModel::RigidBody => {
                let rb = self.rigid_body_params();
                let p = QuadrotorParams {
                    lift_coefficient: rb.thrust_coefficient,
                    yaw_drag_coefficient: rb.moment_coefficient,
                    arm_length: rb.arm_length,
                    ..base
                };
                (rb.allocation_matrix(), p)
            }
        }
    }

    /// Parse and validate TOML text; `path` is used in error messages (and
    /// relative `extends` paths resolve against its directory).
    pub fn from_toml_str(text: &str, path: &str) -> Result<Self, ScenarioError> {
        Self::from_toml_str_with_limits(text, path, &[])
    }

    /// Parse TOML text, apply command-line limit overrides (`KEY=VALUE`,
    /// see [`Limits::apply_overrides`]; they win over the file's `[limits]`)
    /// and validate.
    pub fn from_toml_str_with_limits(text: &str, path: &str, overrides: &[String]) -> Result<Self, ScenarioError> {
        Ok(Self::from_toml_str_with_warnings(text, path, overrides)?.scenario)
    }

    /// [`Scenario::from_toml_str_with_limits`], also returning the files of
    /// the `extends` chain and the unit-slip warnings (see [`resolve`]).
    pub fn from_toml_str_with_warnings(
        text: &str,
        path: &str,
        overrides: &[String],
    ) -> Result<resolve::Loaded, ScenarioError> {
        resolve::load(resolve::Source::Text { text, path }, overrides)
    }

    /// Read, parse and validate a scenario file.
    pub fn from_file(path: &Path) -> Result<Self, ScenarioError> {
        Self::from_file_with_limits(path, &[])
    }

    /// [`Scenario::from_file`] with command-line limit overrides (which may
    /// raise `max_scenario_bytes`, for every file of an `extends` chain).
    pub fn from_file_with_limits(path: &Path, overrides: &[String]) -> Result<Self, ScenarioError> {
        Ok(Self::load_with_warnings(path, overrides)?.scenario)
    }

    /// [`Scenario::from_file_with_limits`], also returning the files of the
    /// `extends` chain and the unit-slip warnings (see [`resolve`]).
    pub fn load_with_warnings(path: &Path, overrides: &[String]) -> Result<resolve::Loaded, ScenarioError> {
        resolve::load(resolve::Source::File(path), overrides)
    }

    /// Likely unit slips in this scenario (angles beyond 2π, a payload above
    /// 10× the vehicle mass, windows starting after the end of the run), as
    /// `` `key` = value: why `` lines without a file name.
    pub fn warnings(&self) -> Vec<String> {
        resolve::unit_slip_warnings(self)
            .into_iter()
            .map(|w| format!("`{}` = {}: {}", w.key, w.value, w.message))
            .collect()
    }

    /// The built-in paper scenarios, parsed.
    pub fn paper_scenarios() -> Vec<Scenario> {
        PAPER_SCENARIOS
            .iter()
            .map(|(name, text)| Self::from_toml_str(text, name).expect("built-in scenario is valid"))
            .collect()
    }

    /// Control period, s.
    pub fn control_period(&self) -> f64 {
        1.0 / self.simulation.control_rate
    }

    /// What a controller is built from besides its gain section: the
    /// nominal `[plant]`, `[cascade]` and the control period.
    pub fn build_context(&self) -> crate::controllers::BuildContext {
        crate::controllers::BuildContext {
            plant: self.plant,
            cascade: self.cascade,
            control_period: self.control_period(),
        }
    }

    /// The scenario as TOML with every default filled in (every gain
    /// section included): what `ftsmc` writes as `scenario.toml`. Loading
    /// the text back ([`Scenario::from_toml_str`]) gives an identical
    /// `Scenario`.
    pub fn to_toml(&self) -> Result<String, toml::ser::Error> {
        toml::to_string(self)
    }

    /// The sizes [`crate::limits`] prices a flight by.
    pub fn flight_size(&self) -> crate::limits::FlightSize<'_> {
        crate::limits::FlightSize {
            duration: self.duration,
            control_rate: self.simulation.control_rate,
            substeps: self.simulation.substeps,
            record_rate: self.simulation.record_rate,
            signal_cost: {
                let r = &self.reference;
                let signals = [&r.x, &r.y, &r.z, &r.psi].into_iter().chain(self.disturbance.named().map(|(_, s)| s));
                let terms: f64 =
                    signals.chain(self.inertia_variation.as_ref()).map(crate::signal::Signal::evaluation_cost).sum();
                // Every discrete gust is evaluated at every substep (a
                // 1 − cosine: priced like a sine term).
                terms
                    + self.wind.as_ref().map_or(0.0, |w| w.gusts.len() as f64)
                    + r.trajectory.as_ref().map_or(0.0, crate::trajectory::Trajectory::evaluation_cost)
            },
            limits: &self.limits,
        }
    }

    /// The environment's parameter sections (true plant, payload, inertia
    /// variation, drag noise, disturbances, seed) for [`crate::environment::Environment`].
    pub fn environment(&self) -> EnvironmentParams<'_> {
        EnvironmentParams {
            plant: self.true_vehicle(),
            payload: self.payload.as_ref(),
            inertia_variation: self.inertia_variation.as_ref(),
            drag_noise: self.drag_noise,
            disturbance: &self.disturbance,
            seed: self.seed,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::signal::{Signal, Term};

    fn helix(phase: f64) -> ReferenceSignals {
        let circle = |term: fn(f64) -> Term| Signal { terms: vec![term(phase)], window: None };
        ReferenceSignals {
            x: circle(|phase| Term::Cosine { amplitude: 1.0, omega: Some(0.5), frequency: None, phase }),
            y: circle(|phase| Term::Sine { amplitude: 1.0, omega: Some(0.5), frequency: None, phase }),
            z: Signal { terms: vec![Term::Polynomial { coefficients: vec![0.0, 0.1] }], window: None },
            psi: Signal::constant(0.0),
            ..Default::default()
        }
    }

    #[test]
    fn reference_twins_are_equal_bit_for_bit() {
        assert!(helix(0.3).same_bits(&helix(0.3)));
        assert!(!helix(0.3).same_bits(&helix(0.4)));
        // -0.0 and 0.0 are equal numbers (`PartialEq`) but not the same bits.
        assert_eq!(helix(-0.0), helix(0.0));
        assert!(!helix(-0.0).same_bits(&helix(0.0)));
        // Any one of the four signals tells them apart.
        for axis in 0..4 {
            let mut other = helix(0.3);
            let signal = match axis {
                0 => &mut other.x,
                1 => &mut other.y,
                2 => &mut other.z,
                _ => &mut other.psi,
            };
            signal.terms.push(Term::Constant { value: 0.0 });
            assert!(!other.same_bits(&helix(0.3)), "axis {axis}");
        }
        assert!(ReferenceSignals::default().same_bits(&ReferenceSignals::default()));
    }
}
