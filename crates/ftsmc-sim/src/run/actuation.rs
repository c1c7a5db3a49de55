//! The actuator stage of a flight: what the rotors make of the controller's
//! command, chosen once per flight from the scenario (`ActuatorStage::of`).
//!
//! | stage | when | applied command | rotor speeds |
//! |---|---|---|---|
//! | ideal | no `[actuators]` (or the default one) and no `simulation.max_rotor_speed`, paper truth model | the command itself (Eq. 1 has no rotors: negative thrust flies) | paper Eq. 2 inverted, `ω ≥ 0` |
//! | clamp | `[actuators] mixer = "clamp"` (or the deprecated `simulation.max_rotor_speed`) | what the clamped speeds produce | Eq. 2 inverted, each clamped to `[ω_min, ω_max]`, reached at once |
//! | rotors | any other `[actuators]`, and the rigid body without `[actuators]` | [`Mixer::mix`] (`thrust-first`, `px4`, `px4-airmode`) | first-order lag with exact exponentials, motor noise |
//!
//! The ideal and clamp stages hold a constant wrench (and rotor speeds) over
//! the control period; the rotor stage hands the truth model the lagged
//! rotor speeds at each RK4 stage time.

use core::cell::Cell;
use ftsmc_core::allocation::{forces_from_squared_speeds, rotor_speeds, squared_speeds_from_forces};
use ftsmc_core::math::sqrt;
use ftsmc_core::model::{Command, QuadrotorParams};

use rand_chacha::ChaCha8Rng;

use crate::actuators::{motor_noise_rng, ActuatorParams, HeldCommand, Mixer, MixerKind, Motors};
use crate::scenario::Scenario;
use crate::vehicle::VehicleModel;

/// The rotor limits, lag, noise and mixer a flight of `scenario` uses:
/// `[actuators]`, or for a file with the deprecated
/// `simulation.max_rotor_speed` (and no `[actuators]`) the per-rotor clamp
/// `[actuators] max_rotor_speed = …, mixer = "clamp"` it always meant on the paper plant.
pub fn actuators(scenario: &Scenario) -> ActuatorParams {
    scenario.actuators.unwrap_or(match scenario.simulation.max_rotor_speed {
        Some(max_rotor_speed) => {
            ActuatorParams { max_rotor_speed, mixer: MixerKind::Clamp, ..ActuatorParams::default() }
        }
        None => ActuatorParams::default(),
    })
}

/// What the actuator stage delivers in one control period.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Delivered {
    /// Thrust and torques the rotors are asked for after the mixer (N, N·m).
    pub applied: Command,
    /// Rotor speed commands (held speeds for the ideal and clamp stages), rad/s.
    pub target: [f64; 4],
    /// Rotor speeds at the tick, rad/s.
    pub omega: [f64; 4],
    /// The command could not be delivered.
    pub saturated: bool,
    /// This period's standard-normal motor noise draws.
    pub noise: [f64; 4],
    /// The unlimited rotor-speed demand when the stage computed it (paper
    /// Eq. 2 inverted with the true plant's coefficients), rad/s.
    pub demand: Option<[f64; 4]>,
}

/// The rotors as the truth model sees them inside a control period.
#[derive(Clone, Copy)]
pub(crate) enum Drive<'a> {
    /// A wrench and rotor speeds held over the period.
    Held {
        /// Thrust and torques, N and N·m.
        applied: &'a Command,
        /// Rotor speeds, rad/s.
        speeds: &'a [f64; 4],
        /// Their residual Ω̄, rad/s.
        omega_bar: f64,
    },
    /// Lagged motors following the period's commands from their state at
    /// the substep start.
    Lagged {
        /// The motors at the start of the substep.
        motors: &'a Motors,
        /// The lag's decay factors, cached per stage step ([`DecayCache`]).
        decay: &'a DecayCache,
        /// The commands and noise draws of the period, prepared for this
        /// substep ([`ActuatorStage::held`]).
        held: &'a HeldCommand,
    },
}

impl Drive<'_> {
    /// Rotor speeds `dt` seconds into the substep (an RK4 stage time minus
    /// the substep's start), rad/s: the lagged speeds
    /// ([`Motors::speeds_decayed`]) with the period's noise
    /// ([`Motors::with_noise`]).
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub(crate) fn speeds_after(&self, dt: f64) -> [f64; 4] {
        match self {
            Drive::Held { speeds, .. } => **speeds,
            Drive::Lagged { motors, decay, held } => held.speeds(&decay.get(motors, dt)),
        }
    }
}

impl Delivered {
    /// Nothing delivered yet (a flight before its first period).
    pub(crate) fn none() -> Self {
        Self {
            applied: Command::default(),
            target: [0.0; 4],
            omega: [0.0; 4],
            saturated: false,
            noise: [0.0; 4],
            demand: None,
        }
    }
}

/// The actuator stage of one flight.
// One value per flight: the size difference between variants does not matter.
#[allow(clippy::large_enum_variant)]
pub(crate) enum ActuatorStage {
    /// The command applied as is (paper truth model only).
    Ideal,
    /// Eq. 2 inverted and clamped per rotor, reached at once; `mixer` for the
    /// rigid body's allocation, `None` for the paper plant's Eq. 2.
    Clamp { min: f64, max: f64, mixer: Option<Mixer> },
    /// Mixer, lagged motors (with their decay factors over half and a whole
    /// substep, computed once) and their noise stream.
    Rotors { mixer: Mixer, motors: Motors, rng: ChaCha8Rng, decay: DecayCache },
}

impl ActuatorStage {
    /// The stage for `scenario` (see the module table); `allocation` is the
    /// truth model's `u = A ω²` and `hover` its hover rotor speed (rad/s),
    /// where lagged motors start; `h` the RK4 substep, s.
    pub(crate) fn of(scenario: &Scenario, allocation: [[f64; 4]; 4], hover: f64, h: f64) -> Self {
        let act = actuators(scenario);
        let paper = scenario.vehicle.model == VehicleModel::Paper;
        let mixer = || Mixer::new(allocation, &act).expect("validated by Scenario::validate");
        if paper && act == ActuatorParams::default() {
            return ActuatorStage::Ideal;
        }
        match act.mixer {
            MixerKind::Clamp => {
                ActuatorStage::Clamp { min: act.min_rotor_speed, max: act.max_rotor_speed, mixer: (!paper).then(mixer) }
            }
            MixerKind::ThrustFirst | MixerKind::Px4 | MixerKind::Px4Exact | MixerKind::Px4ExactAirmode => {
                let motors = Motors::new(&act, [hover; 4]);
                let decay = DecayCache::new(&motors, h);
                ActuatorStage::Rotors { mixer: mixer(), motors, rng: motor_noise_rng(scenario.seed), decay }
            }
        }
    }

    /// From now on the motors' noise draws from the stream of `seed`
    /// ([`motor_noise_rng`]) at its first word; motor speeds carry over.
    pub(crate) fn reseed_noise(&mut self, seed: u64) {
        if let ActuatorStage::Rotors { rng, .. } = self {
            *rng = motor_noise_rng(seed);
        }
    }

    /// What the rotors make of `command` this period, written into `out`
    /// (the lane's delivery, assigned in place rather than returned and
    /// copied);
    /// `plant` is the true plant of the period (paper Eq. 2's coefficients
    /// for the ideal and clamp stages on the paper truth model).
    #[inline]
    pub(crate) fn deliver_into(&mut self, command: &Command, plant: &QuadrotorParams, out: &mut Delivered) {
        *out = match self {
            ActuatorStage::Ideal => {
                let target = rotor_speeds(plant, command, f64::INFINITY);
                let demand = Some(target);
                Delivered { applied: *command, target, omega: target, saturated: false, noise: [0.0; 4], demand }
            }
            ActuatorStage::Clamp { min, max, mixer: None } => {
                let w = squared_speeds_from_forces(plant, command);
                let (w_min, w_max) = (*min * *min, *max * *max);
                let saturated = !w.iter().all(|&wi| wi >= w_min && wi <= w_max);
                let target = rotor_speeds(plant, command, *max).map(|o| if o < *min { *min } else { o });
                let applied = forces_from_squared_speeds(plant, &target.map(|o| o * o));
                let demand = Some(w.map(|wi| sqrt(wi.clamp(0.0, f64::INFINITY))));
                Delivered { applied, target, omega: target, saturated, noise: [0.0; 4], demand }
            }
            ActuatorStage::Clamp { mixer: Some(mixer), .. } => {
                let m = mixer.mix_clamped(command);
                Delivered {
                    applied: m.applied,
                    target: m.rotor_speeds,
                    omega: m.rotor_speeds,
                    saturated: m.saturated,
                    noise: [0.0; 4],
                    demand: None,
                }
            }
            ActuatorStage::Rotors { mixer, motors, rng, .. } => {
                let m = mixer.mix(command);
                let noise = motors.sample_noise(rng);
                let omega = motors.with_noise(&motors.speeds(), &noise);
                Delivered {
                    applied: m.applied,
                    target: m.rotor_speeds,
                    omega,
                    saturated: m.saturated,
                    noise,
                    demand: None,
                }
            }
        };
    }

    /// True when [`ActuatorStage::deliver_into`] reads the true plant (the
    /// ideal stage and the paper plant's clamp: Eq. 2's coefficients).
    #[inline]
    pub(crate) fn reads_plant(&self) -> bool {
        matches!(self, ActuatorStage::Ideal | ActuatorStage::Clamp { mixer: None, .. })
    }

    /// The lagged motors' command and noise over the next substep
    /// ([`Motors::held`], from the motors at its start), into `held`; the
    /// other stages hold their rotors and leave it as it is.
    #[inline]
    pub(crate) fn held(&self, delivered: &Delivered, held: &mut HeldCommand) {
        if let ActuatorStage::Rotors { motors, .. } = self {
            *held = motors.held(&delivered.target, &delivered.noise);
        }
    }

    /// How the truth model sees the rotors over the next substep (`held`:
    /// what [`ActuatorStage::held`] prepared for it).
    #[inline]
    pub(crate) fn drive<'a>(&'a self, delivered: &'a Delivered, omega_bar: f64, held: &'a HeldCommand) -> Drive<'a> {
        match self {
            ActuatorStage::Rotors { motors, decay, .. } => Drive::Lagged { motors, decay, held },
            _ => Drive::Held { applied: &delivered.applied, speeds: &delivered.target, omega_bar },
        }
    }

    /// Advance the motors by one substep towards `target`.
    #[inline]
    pub(crate) fn advance(&mut self, target: &[f64; 4]) {
        if let ActuatorStage::Rotors { motors, decay, .. } = self {
            motors.advance_decayed(target, &decay.whole);
        }
    }
}

/// The motor lag's decay factors `[e^{−dt/τ_up}, e^{−dt/τ_down}]`
/// ([`Motors::decay`]) for the few step lengths a flight uses, each
/// computed once. The RK4 stage offsets `(t0 + h/2) − t0` and `(t0 + h) − t0`
/// differ from `h/2` and `h` in their last bits depending on `t0`, so the
/// factors are cached by the exact offset: the rotor speeds are the very
/// bits [`Motors::speeds_after`] gives, without its exponentials.
pub(crate) struct DecayCache {
    /// Factors over a whole substep `h` (motor advance).
    pub whole: [f64; 2],
    slots: [Cell<(u64, [f64; 2])>; 1 << SLOT_BITS],
}

/// log2 of the number of [`DecayCache`] slots.
const SLOT_BITS: u32 = 6;

impl DecayCache {
    /// A cache for `motors` and substeps of `h` seconds.
    pub(crate) fn new(motors: &Motors, h: f64) -> Self {
        // NaN bits never equal a real offset's: every slot starts empty.
        Self { whole: motors.decay(h), slots: core::array::from_fn(|_| Cell::new((f64::NAN.to_bits(), [1.0; 2]))) }
    }

    /// The factors over `dt` seconds.
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub(crate) fn get(&self, motors: &Motors, dt: f64) -> [f64; 2] {
        if dt == 0.0 {
            return [1.0; 2];
        }
        let key = dt.to_bits();
        // An offset is `(t0 + h/2) − t0` or `(t0 + h) − t0`, a multiple of
        // the ulp of `t0`: its low mantissa bits are zeros and its variants
        // differ in the middle bits, so the slot comes from all the bits
        // (Fibonacci hashing), not the low ones.
        let slot = &self.slots[(key.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> (64 - SLOT_BITS)) as usize];
        let (k, v) = slot.get();
        if k == key {
            return v;
        }
        let v = motors.decay(dt);
        slot.set((key, v));
        v
    }
}
