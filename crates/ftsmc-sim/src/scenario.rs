//! Scenario files (TOML): everything a run needs — duration, rates, plant,
//! initial state, references, disturbances, payload, parameter variation,
//! noise, and every controller's gains. Unknown keys are rejected and every
//! value is range-checked; errors name the file, the key and the value.

use std::path::Path;

use ftsmc_core::cascade::{CascadeSettings, MassAdaptation};
use ftsmc_core::ftaftsmc::FtaftsmcGains;
use ftsmc_core::law::GainError;
use ftsmc_core::model::{QuadState, QuadrotorParams};
use ftsmc_core::ranftsmc::RanftsmcGains;
use ftsmc_core::tsm_sta::TsmStaGains;
use serde::{Deserialize, Serialize};

use crate::limits::{LimitError, Limits};
use crate::signal::Signal;

/// Longest value echoed in an error message, characters (longer ones are
/// cut and end in `…`).
pub const MAX_SHOWN_CHARS: usize = 40;

/// A number for an error message: the ordinary decimal form when it is
/// short (`0.74`, `-3`), scientific otherwise (`1e308`, `5e-324`, never 309
/// digits), at most [`MAX_SHOWN_CHARS`] characters.
pub fn show(v: f64) -> String {
    let plain = v.to_string();
    if plain.len() <= 24 && (v == 0.0 || (1e-4..1e6).contains(&v.abs())) {
        plain
    } else {
        show_str(&format!("{v:e}"))
    }
}

/// Longest parser message kept in an error, characters.
const MAX_PARSE_MESSAGE_CHARS: usize = 300;

/// A TOML error as one bounded line: `TOML parse error at line L, column C (`source line`): message`
/// (the parser's own text spans several lines and quotes the source line).
pub(crate) fn parse_message(text: &str, e: &toml::de::Error) -> String {
    let mut message: String = e.message().split_whitespace().collect::<Vec<_>>().join(" ");
    if message.chars().count() > MAX_PARSE_MESSAGE_CHARS {
        message = message.chars().take(MAX_PARSE_MESSAGE_CHARS - 1).collect();
        message.push('…');
    }
    match e.span() {
        Some(span) => {
            let before = &text.as_bytes()[..span.start.min(text.len())];
            let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
            let column = before.iter().rev().take_while(|&&b| b != b'\n').count() + 1;
            let source = text.lines().nth(line - 1).unwrap_or("").trim();
            format!("TOML parse error at line {line}, column {column} (`{}`): {message}", show_str(source))
        }
        None => format!("TOML parse error: {message}"),
    }
}

/// A piece of user text for an error message: control characters escaped,
/// at most [`MAX_SHOWN_CHARS`] characters (then `…`).
pub fn show_str(s: &str) -> String {
    let escaped: String = s.chars().flat_map(char::escape_debug).collect();
    if escaped.chars().count() <= MAX_SHOWN_CHARS {
        escaped
    } else {
        let mut cut: String = escaped.chars().take(MAX_SHOWN_CHARS - 1).collect();
        cut.push('…');
        cut
    }
}

/// `#[serde(with = "exact_array")]` for fixed-size arrays in scenario files:
/// serde's own `[T; N]` reads the first N elements and, in TOML, silently
/// ignores the rest (`position = [0.5, 0.25, 0.0, 99.0, "junk", [1]]` was a
/// valid position). This reads the whole array and errors on too few or too
/// many elements, naming the length found and the length wanted.
pub mod exact_array {
    use core::fmt;
    use core::marker::PhantomData;

    use serde::de::{self, IgnoredAny, SeqAccess, Visitor};
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    struct Exact<T, const N: usize>(PhantomData<T>);

    impl<'de, T: Deserialize<'de>, const N: usize> Visitor<'de> for Exact<T, N> {
        type Value = [T; N];

        fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
            write!(f, "an array of exactly {N} numbers")
        }

        fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<[T; N], A::Error> {
            let mut items = Vec::with_capacity(N);
            while items.len() < N {
                match seq.next_element::<T>()? {
                    Some(v) => items.push(v),
                    None => return Err(de::Error::invalid_length(items.len(), &self)),
                }
            }
            let mut extra = 0usize;
            while seq.next_element::<IgnoredAny>()?.is_some() {
                extra += 1;
            }
            if extra > 0 {
                return Err(de::Error::invalid_length(N + extra, &self));
            }
            items.try_into().map_err(|_| de::Error::invalid_length(N, &self))
        }
    }

    /// Serialize as an ordinary array.
    pub fn serialize<S: Serializer, T: Serialize, const N: usize>(v: &[T; N], s: S) -> Result<S::Ok, S::Error> {
        v.as_slice().serialize(s)
    }

    /// Deserialize exactly `N` elements.
    pub fn deserialize<'de, D: Deserializer<'de>, T: Deserialize<'de>, const N: usize>(
        d: D,
    ) -> Result<[T; N], D::Error> {
        d.deserialize_seq(Exact::<T, N>(PhantomData))
    }

    /// The same for an optional array (`#[serde(default, with = "exact_array::option")]`).
    pub mod option {
        use super::*;

        struct Wrap<T, const N: usize>([T; N]);

        impl<'de, T: Deserialize<'de>, const N: usize> Deserialize<'de> for Wrap<T, N> {
            fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                super::deserialize(d).map(Wrap)
            }
        }

        /// Serialize as an ordinary optional array.
        pub fn serialize<S: Serializer, T: Serialize, const N: usize>(
            v: &Option<[T; N]>,
            s: S,
        ) -> Result<S::Ok, S::Error> {
            match v {
                Some(a) => s.serialize_some(a.as_slice()),
                None => s.serialize_none(),
            }
        }

        /// Deserialize `Some` of exactly `N` elements.
        pub fn deserialize<'de, D: Deserializer<'de>, T: Deserialize<'de>, const N: usize>(
            d: D,
        ) -> Result<Option<[T; N]>, D::Error> {
            Option::<Wrap<T, N>>::deserialize(d).map(|o| o.map(|w| w.0))
        }
    }
}

/// Fixed-size arrays of `ftsmc-core` structs read from scenario files, as
/// `(dotted path, length)`. Those structs derive serde's own `[f64; N]`,
/// which ignores extra elements, so their lengths are checked on the TOML
/// tree before deserializing.
const CORE_ARRAYS: [(&str, usize); 7] = [
    ("plant.inertia", 3),
    ("plant.drag_translational", 3),
    ("plant.drag_rotational", 3),
    ("actual_plant.inertia", 3),
    ("actual_plant.drag_translational", 3),
    ("actual_plant.drag_rotational", 3),
    ("ftaftsmc.mass_adaptation.alpha_hat_bounds", 2),
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

/// The paper's scenario 1 (SPEC §4), as shipped in `scenarios/paper-scenario-1.toml`.
pub const PAPER_SCENARIO_1: &str = include_str!("../../../scenarios/paper-scenario-1.toml");
/// The paper's scenario 2 (SPEC §4), as shipped in `scenarios/paper-scenario-2.toml`.
pub const PAPER_SCENARIO_2: &str = include_str!("../../../scenarios/paper-scenario-2.toml");

/// Paper scenario 1 with the FTAFTSMC x/y reaching law tuned against the
/// limit cycle, as shipped in `scenarios/ftaftsmc-tuned-scenario-1.toml`.
pub const FTAFTSMC_TUNED_SCENARIO_1: &str = include_str!("../../../scenarios/ftaftsmc-tuned-scenario-1.toml");

/// Every scenario built into the library: `(file name, TOML text)`.
pub const BUILT_IN_SCENARIOS: [(&str, &str); 3] = [
    ("paper-scenario-1.toml", PAPER_SCENARIO_1),
    ("paper-scenario-2.toml", PAPER_SCENARIO_2),
    ("ftaftsmc-tuned-scenario-1.toml", FTAFTSMC_TUNED_SCENARIO_1),
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

/// One value per controlled channel `x, y, z, φ, θ, ψ`.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct AxisSet<T> {
    /// x channel.
    pub x: T,
    /// y channel.
    pub y: T,
    /// z channel.
    pub z: T,
    /// Roll φ channel.
    pub phi: T,
    /// Pitch θ channel.
    pub theta: T,
    /// Yaw ψ channel.
    pub psi: T,
}

impl<T> AxisSet<T> {
    /// `[x, y, z, φ, θ, ψ]` with their names.
    pub fn named(&self) -> [(&'static str, &T); 6] {
        [("x", &self.x), ("y", &self.y), ("z", &self.z), ("phi", &self.phi), ("theta", &self.theta), ("psi", &self.psi)]
    }

    /// The value of channel `axis` (`"x"`, `"y"`, `"z"`, `"phi"`, `"theta"`, `"psi"`).
    pub fn get(&self, axis: &str) -> Option<&T> {
        self.named().into_iter().find(|(n, _)| *n == axis).map(|(_, v)| v)
    }

    /// Same position gains on x, y, z and attitude gains on φ, θ, ψ.
    pub fn split(position: T, attitude: T) -> Self
    where
        T: Clone,
    {
        Self {
            x: position.clone(),
            y: position.clone(),
            z: position,
            phi: attitude.clone(),
            theta: attitude.clone(),
            psi: attitude,
        }
    }

    /// As an array `[x, y, z, φ, θ, ψ]`.
    pub fn to_array(&self) -> [T; 6]
    where
        T: Clone,
    {
        [self.x.clone(), self.y.clone(), self.z.clone(), self.phi.clone(), self.theta.clone(), self.psi.clone()]
    }
}

impl<T: Default> Default for AxisSet<T> {
    fn default() -> Self {
        Self {
            x: T::default(),
            y: T::default(),
            z: T::default(),
            phi: T::default(),
            theta: T::default(),
            psi: T::default(),
        }
    }
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
}

/// External disturbances `D_x … D_ψ` of Eq. 1 as accelerations (m/s², rad/s²).
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct DisturbanceSignals {
    /// D_x, m/s².
    pub x: Signal,
    /// D_y, m/s².
    pub y: Signal,
    /// D_z, m/s².
    pub z: Signal,
    /// D_φ, rad/s².
    pub phi: Signal,
    /// D_θ, rad/s².
    pub theta: Signal,
    /// D_ψ, rad/s².
    pub psi: Signal,
}

impl DisturbanceSignals {
    /// `[D_x, D_y, D_z, D_φ, D_θ, D_ψ]` at `t`.
    pub fn at(&self, t: f64) -> [f64; 6] {
        [self.x.value(t), self.y.value(t), self.z.value(t), self.phi.value(t), self.theta.value(t), self.psi.value(t)]
    }

    /// With their names.
    pub fn named(&self) -> [(&'static str, &Signal); 6] {
        [("x", &self.x), ("y", &self.y), ("z", &self.z), ("phi", &self.phi), ("theta", &self.theta), ("psi", &self.psi)]
    }
}

/// Payload profile: nominal mass until `start`, `+mass` held until
/// `decay_start`, then `mass · exp(−(t − decay_start)/tau)`.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Payload {
    /// Added mass Δm, kg.
    pub mass: f64,
    /// Time the payload is picked up, s.
    pub start: f64,
    /// Time the exponential decay starts, s (default: never).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub decay_start: Option<f64>,
    /// Decay time constant τ, s (required with `decay_start`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tau: Option<f64>,
}

impl Payload {
    /// Added mass at `t`, kg.
    pub fn added_mass(&self, t: f64) -> f64 {
        if t < self.start {
            return 0.0;
        }
        match (self.decay_start, self.tau) {
            (Some(t2), Some(tau)) if t >= t2 => self.mass * (-(t - t2) / tau).exp(),
            _ => self.mass,
        }
    }
}

/// Multiplicative white Gaussian noise on every drag coefficient:
/// `K · max(0, 1 + std · w)`, `w ~ N(0, 1)` drawn once per control period,
/// one independent stream per coefficient.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DragNoise {
    /// Relative standard deviation (0.25 = 25 %).
    pub std: f64,
}

/// FTAFTSMC configuration: mass adaptation and per-channel gains (Tables 4–5).
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

/// Gain sets of the baselines (defaults: published RANFTSMC gains, tuned TSM-STA gains).
fn default_ranftsmc() -> AxisSet<RanftsmcGains> {
    AxisSet::split(RanftsmcGains::PAPER_POSITION, RanftsmcGains::PAPER_ATTITUDE)
}

fn default_tsm_sta() -> AxisSet<TsmStaGains> {
    AxisSet::split(TsmStaGains::DEFAULT_POSITION, TsmStaGains::DEFAULT_ATTITUDE)
}

fn default_controllers() -> Vec<String> {
    crate::registry::PAPER_CONTROLLERS.iter().map(|s| s.to_string()).collect()
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
    let max = limits.max_scenario_bytes.min(u64::MAX as f64) as u64;
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

/// Lengths of the `ftsmc-core` arrays ([`CORE_ARRAYS`]) in the resolved
/// TOML table: `Err((dotted path, message))`.
pub(crate) fn check_core_array_lengths(root: &toml::Table) -> Result<(), (String, String)> {
    for (path, len) in CORE_ARRAYS {
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
    /// Master seed of every random stream (drag noise, Monte Carlo).
    #[serde(default)]
    pub seed: u64,
    /// Controllers to run (registry names).
    #[serde(default = "default_controllers")]
    pub controllers: Vec<String>,
    /// Integration and metric settings.
    #[serde(default)]
    pub simulation: SimulationSettings,
    /// Nominal plant parameters (the controllers' model).
    #[serde(default)]
    pub plant: QuadrotorParams,
    /// True plant parameters when they differ from the nominal `[plant]`
    /// (model mismatch; Monte Carlo writes its draws here). Default: `[plant]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub actual_plant: Option<QuadrotorParams>,
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
    /// FTAFTSMC gains.
    #[serde(default)]
    pub ftaftsmc: FtaftsmcConfig,
    /// RANFTSMC gains per channel.
    #[serde(default = "default_ranftsmc")]
    pub ranftsmc: AxisSet<RanftsmcGains>,
    /// TSM-STA gains per channel.
    #[serde(default = "default_tsm_sta", rename = "tsm-sta")]
    pub tsm_sta: AxisSet<TsmStaGains>,
    /// Distributions for `ftsmc montecarlo` (ignored by single runs).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub montecarlo: Option<crate::montecarlo::MonteCarloSpec>,
    /// Cost limits (see [`crate::limits`]); every key optional.
    #[serde(default, skip_serializing_if = "is_default_limits")]
    pub limits: Limits,
    // --- issue 11: truth model, actuators, ground, success envelope (crate::truth) ---
    /// Truth model (`[vehicle]`, default: the paper plant).
    #[serde(default, skip_serializing_if = "crate::truth::VehicleSettings::is_default")]
    pub vehicle: crate::truth::VehicleSettings,
    /// Rotor limits, motor lag and noise (`[actuators]`, default: ideal).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub actuators: Option<crate::actuators::ActuatorParams>,
    /// Ground plane (`[ground]`, default: none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ground: Option<crate::ground::GroundSettings>,
    /// Success envelope (`[envelope]`, default: success = completed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub envelope: Option<crate::envelope::Envelope>,
}

fn is_default_limits(l: &Limits) -> bool {
    *l == Limits::default()
}

impl Scenario {
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
    /// the `extends` chain and the unit-slip warnings (see [`crate::resolve`]).
    pub fn from_toml_str_with_warnings(
        text: &str,
        path: &str,
        overrides: &[String],
    ) -> Result<crate::resolve::Loaded, ScenarioError> {
        crate::resolve::load(crate::resolve::Source::Text { text, path }, overrides)
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
    /// `extends` chain and the unit-slip warnings (see [`crate::resolve`]).
    pub fn load_with_warnings(path: &Path, overrides: &[String]) -> Result<crate::resolve::Loaded, ScenarioError> {
        crate::resolve::load(crate::resolve::Source::File(path), overrides)
    }

    /// Likely unit slips in this scenario (angles beyond 2π, a payload above
    /// 10× the vehicle mass, windows starting after the end of the run), as
    /// `` `key` = value: why `` lines without a file name.
    pub fn warnings(&self) -> Vec<String> {
        crate::resolve::unit_slip_warnings(self)
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
        }

        self.plant.check().map_err(|e| gain("plant", e))?;
        if let Some(p) = &self.actual_plant {
            p.check().map_err(|e| gain("actual_plant", e))?;
        }
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
        for (name, s) in self.disturbance.named() {
            signal(format!("disturbance.{name}"), s)?;
        }
        if let Some(p) = &self.payload {
            finite("payload.mass", p.mass)?;
            let (true_mass, which) = match &self.actual_plant {
                Some(a) => (a.mass, "actual_plant.mass"),
                None => (self.plant.mass, "plant.mass"),
            };
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
        self.ftaftsmc.mass_adaptation.check().map_err(|e| gain("ftaftsmc.mass_adaptation", e))?;
        for (axis, g) in self.ftaftsmc.gains().named() {
            g.check().map_err(|e| gain(&format!("ftaftsmc.{axis}"), e))?;
        }
        for (axis, g) in self.ranftsmc.named() {
            g.check().map_err(|e| gain(&format!("ranftsmc.{axis}"), e))?;
        }
        for (axis, g) in self.tsm_sta.named() {
            g.check().map_err(|e| gain(&format!("tsm-sta.{axis}"), e))?;
        }
        for name in &self.controllers {
            crate::registry::check_name(name).map_err(|known| ScenarioError::UnknownController {
                path: path.to_string(),
                name: name.clone(),
                known,
            })?;
        }
        crate::truth::check(self).map_err(|(prefix, e)| gain(&prefix, e))?; // issue 11 hook
        if let Some(mc) = &self.montecarlo {
            mc.check_against(self).map_err(|(key, value, expected)| invalid(key, value, &expected))?;
        }
        self.check_cost(self.controllers.len())
            .map_err(|limit| ScenarioError::Limit { path: path.to_string(), limit })?;
        Ok(())
    }

    /// Price one flight with each of `n_controllers` controllers (steps
    /// including substeps, recorded rows, output bytes) against
    /// [`Scenario::limits`]; called by [`Scenario::validate`] with the
    /// scenario's own controller list.
    pub fn check_cost(&self, n_controllers: usize) -> Result<crate::limits::Cost, LimitError> {
        crate::limits::check_flight(self, n_controllers)
    }
}
