//! Every controller declared once.
//!
//! A controller is one [`Declaration`] in its own file: its registry name,
//! label, one-line description, the [`GainSection`] it reads (the section's
//! TOML key, serde type, defaults and validation), a constructor, and
//! optionally its per-axis sliding law (for the fixed-time sweep of
//! `analysis::fixed_time`) and its reaching-time bound. The list at the
//! bottom of this file (`declare_controllers!`) names each gain section once,
//! with the controllers that read it; from it the macro generates
//!
//! - [`GainSections`], the typed gain sections of a scenario
//!   (`scenario.gains.ftaftsmc`, …), with their defaults, serialization,
//!   parsing ([`GainSections::take_from`]) and validation
//!   ([`GainSections::check`]);
//! - [`CONTROLLERS`] and [`DECLARED`], the names in list order;
//! - the name → declaration dispatch: [`build`], [`visit_axis_law`],
//!   [`reaching_time_bound`], [`label`].
//!
//! Nothing here knows of the scenario file as a whole: a controller is built
//! from its own gain section and a small [`BuildContext`] (nominal plant,
//! cascade settings, control period), so this module sits on a low floor and
//! the scenario, the run loop and the analyses all use it.
//!
//! # Adding a controller
//!
//! 1. Write the law in `ftsmc-core` (a per-axis [`ftsmc_core::law::AxisLaw`]
//!    wrapped in the cascade, or a full-state [`Controller`]) with a gain
//!    struct that derives `Clone, Debug, PartialEq` and, under the core's
//!    `serde` feature, `Deserialize, Serialize` with `deny_unknown_fields`,
//!    and has a `check()` returning [`GainError`].
//! 2. Add `src/controllers/NAME.rs` here. A per-axis law flown in the
//!    cascade (as RANFTSMC and TSM-STA) needs only
//!    `impl generic::ChannelGains` for its gain struct (TOML key, name,
//!    label, description, defaults, check, the law on any number type) and
//!    `pub type NAME = generic::CascadeOf<Gains>;`. A full-state controller
//!    (as PID and SE(3)) needs `impl GainSection` for its gain struct and
//!    `impl generic::FullStateGains` (name, label, description, the
//!    constructor on any number type), then
//!    `pub type NAME = generic::FullState<Gains>;`. Anything else is a unit
//!    struct with its own `impl Declaration` (`NAME`, `LABEL`,
//!    `DESCRIPTION`, `type Section`, `build`; `build_lanes` for a lane
//!    form; `visit_axis_law` and `reaching_time_bound` for per-axis
//!    sliding laws), as FTAFTSMC, whose section also holds the mass
//!    adaptation.
//! 3. Add `pub mod NAME;` and one line to the list at the bottom of this
//!    file: `field: NAME::Gains => [NAME::Controller { tune: NAME::tune_parameters }],`,
//!    naming what `ftsmc tune` may change in it (a `tune_parameters()`
//!    beside its gains returning [`tune_param::TuneParam`]s, see
//!    [`tunable`]), or `{ tune: tune_param::none }` for nothing yet: the
//!    list does not compile without it.
//!
//! That is all: the scenario reads, defaults, writes and validates
//! `[KEY]`, every command (`run`, `montecarlo`, `reproduce`) can fly it, and
//! `ftsmc list` shows it. A full-state controller, for example a PID whose
//! gains are `ftsmc_core::pid::PidGains`, is declared as
//!
//! ```ignore
//! // src/controllers/pid.rs
//! impl GainSection for ftsmc_core::pid::PidGains {
//!     const KEY: &'static str = "pid";
//!     fn defaults() -> Self { Self::default() }
//!     // `PidGains::check` is the gain struct's own (inherent) check.
//!     fn check(&self) -> Result<(), InvalidGain> { PidGains::check(self).map_err(|e| InvalidGain::at("", e)) }
//! }
//! impl FullStateGains for ftsmc_core::pid::PidGains {
//!     const NAME: &'static str = "pid";
//!     const LABEL: &'static str = "PID (PX4 cascade)";
//!     const DESCRIPTION: &'static str = "PX4-style cascaded P/PID position, velocity, attitude and rate loops";
//!     type On<R: Real> = ftsmc_core::pid::PidController<R>;
//!     fn build<R: Real>(plant: QuadrotorParams, gains: Self) -> Result<Self::On<R>, GainError> {
//!         ftsmc_core::pid::PidController::splat(plant, gains)
//!     }
//! }
//! pub type Pid = FullState<ftsmc_core::pid::PidGains>;
//! // the list:  pid: ftsmc_core::pid::PidGains => [pid::Pid],
//! ```
//!
//! A section's position in the list is its position in a written
//! `scenario.toml`; append new sections at the end. Several controllers may
//! share one section (`ftaftsmc` and `ftaftsmc-no-mass` both read
//! `[ftaftsmc]`). `tests/registry.rs` checks that every declared controller
//! builds from the default scenario and flies, that names are unique and
//! that every section rejects an unknown key.

use ftsmc_core::cascade::{CascadeConfig, CascadeSettings, Controller, MassAdaptation};
use ftsmc_core::law::{AxisLaw, GainError};
use ftsmc_core::model::QuadrotorParams;
use ftsmc_core::rotor_layout::RotorGeometry;
use serde::de::DeserializeOwned;
use serde::Serialize;

use crate::axes::AxisSet;
use crate::text::show;

pub mod crazyflie_pid;
pub mod ftaftsmc;
pub mod generic;
pub mod mellinger;
pub mod on_isa;
pub mod per_lane;
pub mod pid;
pub mod px4_params;
pub mod ranftsmc;
pub mod se3;
pub mod tsm_sta;
pub mod tunable;
pub mod tune_param;

/// A boxed controller ready to fly.
pub type BoxedController = Box<dyn Controller + Send>;

/// A controller flying `N` lanes, as [`build_lanes`] returns it.
pub type LaneController<const N: usize> = Box<dyn Controller<ftsmc_core::lanes::Lanes<N>> + Send>;

/// The three controllers compared in the paper, in table order; also the
/// default `controllers` list of a scenario.
pub const PAPER_CONTROLLERS: [&str; 3] = ["ranftsmc", "tsm-sta", "ftaftsmc"];

/// What a controller is built from besides its own gain section.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BuildContext {
    /// Nominal plant parameters (the controller's model, `[plant]`; the true
    /// plant may differ).
    pub plant: QuadrotorParams,
    /// Cascade options shared by the cascaded controllers (`[cascade]`).
    pub cascade: CascadeSettings,
    /// Control period, s (`1 / simulation.control_rate`).
    pub control_period: f64,
}

impl BuildContext {
    /// The cascade configuration of a cascaded controller with `mass_adaptation`.
    pub fn cascade_config(&self, mass_adaptation: MassAdaptation) -> CascadeConfig {
        CascadeConfig { model: self.plant, settings: self.cascade, mass_adaptation }
    }
}

/// What a scenario tells its controllers about the vehicle when their
/// default gains are derived from it ([`GainSection::defaults_for`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NominalVehicle {
    /// Nominal plant parameters (`[plant]`).
    pub plant: QuadrotorParams,
    /// Largest collective thrust the rotors give, N: `4 b ω_max²` with the
    /// nominal lift coefficient `b` and the rotor limit ω_max of
    /// `[actuators]` (or `simulation.max_rotor_speed`); `None` when the
    /// rotors are unlimited (the paper plant).
    pub max_thrust: Option<f64>,
    /// The rotor layout PX4's allocation is normalised on
    /// ([`ftsmc_core::pid::PidGains::for_vehicle_on`]): the true vehicle's
    /// (`[vehicle] configuration`, `rotor_positions`, `spin` on the rigid
    /// body; paper Eq. 2's "+" with `[plant] arm_length` on Eq. 1).
    pub geometry: RotorGeometry,
}

impl Default for NominalVehicle {
    /// The paper vehicle with unlimited rotors.
    fn default() -> Self {
        Self::new(QuadrotorParams::default(), None)
    }
}

impl NominalVehicle {
    /// The vehicle with nominal `plant` whose rotors stop at
    /// `max_rotor_speed` rad/s (`None` or infinite: unlimited), on paper
    /// Eq. 2's "+" layout ([`NominalVehicle::on`] for another).
    pub fn new(plant: QuadrotorParams, max_rotor_speed: Option<f64>) -> Self {
        let max_thrust =
            max_rotor_speed.filter(|w| w.is_finite() && *w > 0.0).map(|w| 4.0 * plant.lift_coefficient * w * w);
        Self { plant, max_thrust, geometry: RotorGeometry::Plus { arm_length: plant.arm_length } }
    }

    /// This vehicle on the rotor layout `geometry`.
    pub fn on(self, geometry: RotorGeometry) -> Self {
        Self { geometry, ..self }
    }

    /// A collective-thrust cap for a controller that keeps `margin` (0..1)
    /// of the rotors' thrust for torque: `(1 − margin) × max_thrust`, at
    /// least 1.05 m g (an under-powered vehicle still gets a valid cap);
    /// without a rotor limit `unlimited` m g.
    pub fn thrust_cap(&self, margin: f64, unlimited: f64) -> f64 {
        let weight = self.plant.mass * self.plant.gravity;
        self.max_thrust.map_or(unlimited * weight, |t| ((1.0 - margin) * t).max(1.05 * weight))
    }
}

/// An invalid value in a gain section: the dotted key, the value as shown
/// and what is allowed (becomes `ScenarioError::Invalid`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct InvalidGain {
    /// Dotted key (below the section in [`GainSection::check`], from the
    /// scenario root in [`GainSections::check`]).
    pub key: String,
    /// The offending value, as shown in messages.
    pub value: String,
    /// What is allowed.
    pub expected: String,
}

impl InvalidGain {
    /// A [`GainError`] of the table at dotted `prefix` (empty: the section
    /// itself), e.g. `InvalidGain::at("x", e)` for `[KEY.x]`.
    pub fn at(prefix: &str, e: GainError) -> Self {
        let key = if prefix.is_empty() { e.field.to_string() } else { format!("{prefix}.{}", e.field) };
        Self { key, value: show(e.value), expected: e.expected.to_string() }
    }

    /// The same error with `section.` in front of its key.
    pub fn under(self, section: &str) -> Self {
        Self { key: format!("{section}.{}", self.key), ..self }
    }
}

/// Check the six channel gain sets of an [`AxisSet`] section with `check`.
pub fn check_axes<G>(set: &AxisSet<G>, check: impl Fn(&G) -> Result<(), GainError>) -> Result<(), InvalidGain> {
    for (axis, g) in set.named() {
        check(g).map_err(|e| InvalidGain::at(axis, e))?;
    }
    Ok(())
}

/// A gain section of the scenario file, `[KEY]`: its serde type, defaults
/// and validation. Parsed with the type's own serde (use
/// `#[serde(deny_unknown_fields)]`: an unknown key is then an error naming
/// it), after the built-in defaults of [`GainSection::defaults`] have been
/// merged under the files' values key by key.
pub trait GainSection:
    Clone + core::fmt::Debug + PartialEq + Serialize + DeserializeOwned + Send + Sync + 'static
{
    /// The section's TOML key (`"ftaftsmc"` for `[ftaftsmc]`).
    const KEY: &'static str;
    /// Fixed-length arrays inside the section whose serde ignores extra
    /// elements (`[f64; N]` of `ftsmc-core` structs), as (dotted path below
    /// the section, length); their lengths are checked on the TOML tree.
    const CORE_ARRAYS: &'static [(&'static str, usize)] = &[];
    /// Keys below the section that are the vehicle's limits, not gains
    /// (thrust, tilt and rate caps, …), as dotted paths below the section:
    /// `ftsmc tune` never changes them and `[[tune.extra]]` refuses them
    /// (`tunable::check_extra_key`). Every other numeric key of the
    /// section is a tunable gain.
    const LIMITS: &'static [&'static str] = &[];
    /// The built-in gains of the paper's vehicle.
    fn defaults() -> Self;
    /// The built-in gains for a scenario flying `vehicle`: what a scenario
    /// gets without a `[KEY]` table, and what the keys a `[KEY]` table omits
    /// take. The default is [`GainSection::defaults`] whatever the vehicle
    /// (the paper's gains); a controller whose gains are derived from the
    /// vehicle (`pid`, `se3`) overrides it.
    fn defaults_for(vehicle: &NominalVehicle) -> Self {
        let _ = vehicle;
        Self::defaults()
    }
    /// Range-check every value; keys in the error are below the section.
    fn check(&self) -> Result<(), InvalidGain>;
}

/// Something done with a per-axis sliding law whose type is only known to
/// its declaration (the fixed-time sweep is one): see
/// [`Declaration::visit_axis_law`].
pub trait AxisLawVisitor {
    /// What the visit returns.
    type Output;
    /// Use the channel law `law` (fresh, at its initial state).
    fn visit<L: AxisLaw + Clone>(self, law: L) -> Self::Output;
}

/// One controller: name, label, description, gain section and constructor.
pub trait Declaration {
    /// Registry name (`-c NAME`, the `controllers` list, output file names).
    const NAME: &'static str;
    /// Human-readable label for figures and tables.
    const LABEL: &'static str;
    /// One line for `ftsmc list`.
    const DESCRIPTION: &'static str;
    /// The gain section it reads.
    type Section: GainSection;
    /// Build the controller from its gain section and the context.
    fn build(gains: &Self::Section, ctx: &BuildContext) -> Result<BoxedController, String>;
    /// The same controller on `N` lanes ([`ftsmc_core::lanes`]), when it has
    /// a lane implementation: `None` (the default) flies `N` one-flight
    /// controllers side by side instead ([`per_lane::PerLane`]), the same
    /// bits without the vector speed-up.
    fn build_lanes<const N: usize>(
        gains: &Self::Section,
        ctx: &BuildContext,
    ) -> Option<Result<LaneController<N>, String>> {
        let _ = (gains, ctx);
        None
    }
    /// Hand the per-axis sliding law of channel `axis` (0..6 = x, y, z, φ,
    /// θ, ψ) to `visitor`; `None` (the default) for a controller without
    /// per-axis sliding laws (full-state controllers).
    fn visit_axis_law<V: AxisLawVisitor>(gains: &Self::Section, axis: usize, visitor: V) -> Option<V::Output> {
        let _ = (gains, axis, visitor);
        None
    }
    /// A reaching-time bound of channel `axis`, s, when the law has one
    /// independent of the initial conditions (FTAFTSMC, Eq. 38); default none.
    fn reaching_time_bound(gains: &Self::Section, axis: usize) -> Option<f64> {
        let _ = (gains, axis);
        None
    }
}

/// What the list says about one declared controller.
#[derive(Clone, Copy, Debug)]
pub struct Declared {
    /// [`Declaration::NAME`].
    pub name: &'static str,
    /// [`Declaration::LABEL`].
    pub label: &'static str,
    /// [`Declaration::DESCRIPTION`].
    pub description: &'static str,
    /// The [`GainSection::KEY`] it reads.
    pub section: &'static str,
    /// What `ftsmc tune` may change in it: the `tune_parameters` function
    /// its list line names next to it (`{ tune: NAME::tune_parameters }`),
    /// [`tune_param::none`] for a controller that declares none. The list
    /// cannot name a controller without one (the macro requires it).
    pub tune_parameters: fn() -> Vec<tune_param::TuneParam>,
}

/// A declared section that could not be deserialized.
#[derive(Debug)]
pub struct SectionParseError {
    /// The section's key.
    pub section: &'static str,
    /// The serde error (key paths below the section).
    pub error: toml::de::Error,
}

/// `Ok(())` for a declared name; otherwise the declared names, comma-separated.
pub fn check_name(name: &str) -> Result<(), String> {
    if DECLARED.iter().any(|d| d.name == name) {
        Ok(())
    } else {
        Err(known_names())
    }
}

/// The declared names, comma-separated.
fn known_names() -> String {
    DECLARED.iter().map(|d| d.name).collect::<Vec<_>>().join(", ")
}

/// The label of a declared controller.
pub fn label(name: &str) -> Option<&'static str> {
    DECLARED.iter().find(|d| d.name == name).map(|d| d.label)
}

/// Remove section `S` from `table` and deserialize it over
/// `S::defaults_for(vehicle)` (tables merged key by key, other values replaced).
fn take_section<S: GainSection>(table: &mut toml::Table, vehicle: &NominalVehicle) -> Result<S, SectionParseError> {
    let defaults = S::defaults_for(vehicle);
    let Some(value) = table.remove(S::KEY) else { return Ok(defaults) };
    let value = match (toml::Value::try_from(&defaults), value) {
        (Ok(toml::Value::Table(mut base)), toml::Value::Table(top)) => {
            merge_tables(&mut base, top);
            toml::Value::Table(base)
        }
        // Not a table (the type's own error says so), or defaults that do
        // not serialize as one: parse what the file wrote.
        (_, value) => value,
    };
    S::deserialize(value).map_err(|error| SectionParseError { section: S::KEY, error })
}

/// Merge `top` into `base`: tables key by key, any other value replaced.
fn merge_tables(base: &mut toml::Table, top: toml::Table) {
    for (key, value) in top {
        match (base.get_mut(&key), value) {
            (Some(toml::Value::Table(b)), toml::Value::Table(t)) => merge_tables(b, t),
            (_, value) => {
                base.insert(key, value);
            }
        }
    }
}

/// Generates the gain sections, the name lists and the dispatch from the
/// list of `field: SectionType => [Controller, …]` lines.
macro_rules! declare_controllers {
    ($( $field:ident : $section:ty => [ $( $controller:ty { tune: $tune:path } ),+ $(,)? ] ),+ $(,)?) => {
        /// The gain section of every declared controller, one field per
        /// section (see the list in `controllers/mod.rs`). In a scenario:
        /// `scenario.gains`, written as the top-level tables `[KEY]`.
        #[derive(Clone, Debug, PartialEq)]
        pub struct GainSections {
            $(
                #[doc = concat!(
                    "Gain section read by ", stringify!($( $controller ),+),
                    " (its TOML key is the type's `GainSection::KEY`)."
                )]
                pub $field: $section,
            )+
        }

        impl Default for GainSections {
            fn default() -> Self {
                Self { $( $field: <$section as GainSection>::defaults(), )+ }
            }
        }

        /// Written as a map `KEY → section`, in list order (flattened into
        /// the scenario's top level).
        impl Serialize for GainSections {
            fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
                use serde::ser::SerializeMap as _;
                let mut map = serializer.serialize_map(Some(GainSections::KEYS.len()))?;
                $( map.serialize_entry(<$section as GainSection>::KEY, &self.$field)?; )+
                map.end()
            }
        }

        impl GainSections {
            /// The sections' TOML keys, in list order.
            pub const KEYS: &'static [&'static str] = &[ $( <$section as GainSection>::KEY ),+ ];

            /// Range-check every section; the key in the error starts with the section's.
            pub fn check(&self) -> Result<(), InvalidGain> {
                $( GainSection::check(&self.$field).map_err(|e| e.under(<$section as GainSection>::KEY))?; )+
                Ok(())
            }

            /// Remove every declared section from `table` and deserialize it
            /// with its type, over the defaults for `vehicle`
            /// ([`GainSection::defaults_for`]) key by key; a section absent
            /// from `table` gets those defaults.
            pub fn take_from(table: &mut toml::Table, vehicle: &NominalVehicle) -> Result<Self, SectionParseError> {
                Ok(Self { $( $field: take_section::<$section>(table, vehicle)?, )+ })
            }

            /// The keys of the sections whose gains are exactly their
            /// defaults for `vehicle`: dropping those tables from a written
            /// scenario loses nothing, and lets them follow a changed `[plant]`.
            pub fn keys_at_defaults(&self, vehicle: &NominalVehicle) -> Vec<&'static str> {
                let mut keys = Vec::new();
                $(
                    if self.$field == <$section as GainSection>::defaults_for(vehicle) {
                        keys.push(<$section as GainSection>::KEY);
                    }
                )+
                keys
            }

            /// Every section's defaults for `vehicle` ([`GainSection::defaults_for`]).
            pub fn defaults_for(vehicle: &NominalVehicle) -> Self {
                Self { $( $field: <$section as GainSection>::defaults_for(vehicle), )+ }
            }

            /// Every section's key with its [`GainSection::LIMITS`] (keys that
            /// `ftsmc tune` may not change), in list order.
            pub const LIMITS: &'static [(&'static str, &'static [&'static str])] =
                &[ $( (<$section as GainSection>::KEY, <$section as GainSection>::LIMITS) ),+ ];

            /// Every section's [`GainSection::CORE_ARRAYS`], as (dotted path
            /// from the scenario root, length).
            pub fn core_arrays() -> Vec<(String, usize)> {
                let mut out = Vec::new();
                $(
                    for (path, len) in <$section as GainSection>::CORE_ARRAYS {
                        out.push((format!("{}.{path}", <$section as GainSection>::KEY), *len));
                    }
                )+
                out
            }
        }

        /// Every declared controller, in list order.
        pub const DECLARED: &[Declared] = &[
            $($(
                Declared {
                    name: <$controller as Declaration>::NAME,
                    label: <$controller as Declaration>::LABEL,
                    description: <$controller as Declaration>::DESCRIPTION,
                    section: <$section as GainSection>::KEY,
                    tune_parameters: $tune,
                },
            )+)+
        ];

        /// Every declared name with its one-line description, in list order.
        pub const CONTROLLERS: &[(&str, &str)] = &[
            $($( (<$controller as Declaration>::NAME, <$controller as Declaration>::DESCRIPTION), )+)+
        ];

        /// Build the declared controller `name` from its section of `gains`.
        /// Unknown `name`: the declared names.
        pub fn build(name: &str, gains: &GainSections, ctx: &BuildContext) -> Result<BoxedController, String> {
            $($(
                if name == <$controller as Declaration>::NAME {
                    return <$controller as Declaration>::build(&gains.$field, ctx);
                }
            )+)+
            Err(known_names())
        }

        /// Build the declared controller `name` on `N` lanes: its lane
        /// implementation, or `N` one-flight controllers side by side
        /// ([`per_lane::PerLane`]). Unknown `name`: the declared names.
        pub fn build_lanes<const N: usize>(name: &str, gains: &GainSections, ctx: &BuildContext) -> Result<LaneController<N>, String> {
            $($(
                if name == <$controller as Declaration>::NAME {
                    if let Some(built) = <$controller as Declaration>::build_lanes::<N>(&gains.$field, ctx) {
                        return built;
                    }
                    let mut flights = Vec::with_capacity(N);
                    for _ in 0..N {
                        flights.push(<$controller as Declaration>::build(&gains.$field, ctx)?);
                    }
                    let flights: [BoxedController; N] = match flights.try_into() {
                        Ok(f) => f,
                        Err(_) => unreachable!("N controllers built"),
                    };
                    return Ok(Box::new(per_lane::PerLane::new(flights)));
                }
            )+)+
            Err(known_names())
        }

        /// Hand the per-axis law of channel `axis` of controller `name` to
        /// `visitor`: `Ok(None)` when the controller has none, `Err(known
        /// names)` for an unknown name.
        pub fn visit_axis_law<V: AxisLawVisitor>(
            name: &str,
            gains: &GainSections,
            axis: usize,
            visitor: V,
        ) -> Result<Option<V::Output>, String> {
            $($(
                if name == <$controller as Declaration>::NAME {
                    return Ok(<$controller as Declaration>::visit_axis_law(&gains.$field, axis, visitor));
                }
            )+)+
            Err(known_names())
        }

        /// The TOML key of the gain section controller `name` reads
        /// (`"ftaftsmc"` for `ftaftsmc-no-mass`); `None` for an unknown name.
        pub fn section_key(name: &str) -> Option<&'static str> {
            $($(
                if name == <$controller as Declaration>::NAME {
                    return Some(<$section as GainSection>::KEY);
                }
            )+)+
            None
        }

        /// Whether controller `name` flies gains nobody fitted to `vehicle`:
        /// its section of `gains` is exactly [`GainSection::defaults`] (the
        /// gains published for the paper's vehicle) and those defaults do not
        /// follow the vehicle (`defaults_for(vehicle) == defaults()`; the
        /// PID and SE(3) defaults are derived from it, so they never do).
        /// `None` for an unknown name.
        pub fn flies_paper_defaults(name: &str, gains: &GainSections, vehicle: &NominalVehicle) -> Option<bool> {
            $($(
                if name == <$controller as Declaration>::NAME {
                    let paper = <$section as GainSection>::defaults();
                    return Some(gains.$field == paper && <$section as GainSection>::defaults_for(vehicle) == paper);
                }
            )+)+
            None
        }

        /// The reaching-time bound of channel `axis` of controller `name`,
        /// s, when it has one (see [`Declaration::reaching_time_bound`]).
        pub fn reaching_time_bound(name: &str, gains: &GainSections, axis: usize) -> Option<f64> {
            $($(
                if name == <$controller as Declaration>::NAME {
                    return <$controller as Declaration>::reaching_time_bound(&gains.$field, axis);
                }
            )+)+
            None
        }
    };
}

// The list: one line per gain section, `field: type => [controllers that read it]`.
// Order = order of `ftsmc list` and of the sections in a written scenario.toml.
declare_controllers! {
    ftaftsmc: ftaftsmc::FtaftsmcConfig => [
        ftaftsmc::Ftaftsmc { tune: ftaftsmc::tune_parameters_with_mass },
        ftaftsmc::FtaftsmcNoMass { tune: ftaftsmc::tune_parameters_no_mass },
    ],
    ranftsmc: AxisSet<ftsmc_core::ranftsmc::RanftsmcGains> => [ranftsmc::Ranftsmc { tune: ranftsmc::tune_parameters }],
    tsm_sta: AxisSet<ftsmc_core::tsm_sta::TsmStaGains> => [tsm_sta::TsmSta { tune: tsm_sta::tune_parameters }],
    pid: ftsmc_core::pid::PidGains => [pid::Pid { tune: pid::tune_parameters }],
    se3: ftsmc_core::se3::Se3Gains => [se3::Se3 { tune: se3::tune_parameters }],
    crazyflie_pid: ftsmc_core::crazyflie_pid::CrazyfliePidGains => [crazyflie_pid::CrazyfliePid { tune: tune_param::none }],
    mellinger: ftsmc_core::mellinger::MellingerGains => [mellinger::Mellinger { tune: tune_param::none }],
}

/// A controller planted in a list of its own: one list line (with its
/// `tune`) and its law are all it takes to be declared, built, labelled
/// and tuned; nothing else names it.
#[cfg(test)]
#[allow(dead_code)] // the macro generates the whole dispatch; the test uses part of it
mod planted {
    use super::*;

    /// A new controller: PID's law under another name, with one tunable.
    pub struct Planted;

    impl Declaration for Planted {
        const NAME: &'static str = "planted";
        const LABEL: &'static str = "Planted";
        const DESCRIPTION: &'static str = "a controller declared only in this test's list";
        type Section = ftsmc_core::pid::PidGains;
        fn build(gains: &Self::Section, ctx: &BuildContext) -> Result<BoxedController, String> {
            <pid::Pid as Declaration>::build(gains, ctx)
        }
    }

    fn planted_tunables() -> Vec<tune_param::TuneParam> {
        vec![tune_param::TuneParam::factor("planted_p", "factor on position_p", 0.5, 2.0, |t, k| {
            tune_param::scale(&mut t.gains.pid.position_p, &[0, 1, 2], k)
        })]
    }

    declare_controllers! {
        pid: ftsmc_core::pid::PidGains => [pid::Pid { tune: pid::tune_parameters }, Planted { tune: planted_tunables }],
    }

    #[test]
    fn a_planted_controller_needs_only_its_list_line() {
        let d = DECLARED.iter().find(|d| d.name == "planted").expect("declared");
        assert_eq!((d.label, d.section), ("Planted", "pid"));
        assert!(CONTROLLERS.iter().any(|(n, _)| *n == "planted"));
        let names: Vec<&str> = tunable::parameters_in(DECLARED, "planted").unwrap().iter().map(|p| p.name).collect();
        assert_eq!(names, ["planted_p"]);
        assert_eq!(tunable::tunable_in(DECLARED), ["pid", "planted"]);
        assert!(tunable::parameters_in(DECLARED, "se3").is_err(), "not in the planted list");
        let ctx = BuildContext {
            plant: QuadrotorParams::default(),
            cascade: CascadeSettings::default(),
            control_period: 0.001,
        };
        assert!(build("planted", &GainSections::default(), &ctx).is_ok());
        assert_eq!(section_key("planted"), Some("pid"));
    }
}
