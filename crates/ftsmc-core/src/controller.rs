//! The controller interface: the [`Controller`] trait every complete
//! quadrotor controller implements (the paper's cascade of §3.1–3.3, PID,
//! SE(3)), the [`Telemetry`] it reports after each update (what every
//! controller computes, and the sliding-mode part, [`SlidingTelemetry`],
//! only the paper's cascade has), and the
//! [`channel`] indices of its six-element arrays. Kept apart from the laws
//! (`law`, `ftaftsmc`, ...) and from the cascade that combines them, so a
//! new controller depends on this interface only.

use crate::lanes::Real;
use crate::law::MAX_ESTIMATES;
use crate::measured::Measurement;
use crate::model::{Command, QuadState, Reference};

/// Channel indices into the six-element arrays of [`Telemetry`].
pub mod channel {
    /// x position.
    pub const X: usize = 0;
    /// y position.
    pub const Y: usize = 1;
    /// z position (altitude).
    pub const Z: usize = 2;
    /// Roll φ.
    pub const PHI: usize = 3;
    /// Pitch θ.
    pub const THETA: usize = 4;
    /// Yaw ψ.
    pub const PSI: usize = 5;
    /// Names as used in outputs.
    pub const NAMES: [&str; 6] = ["x", "y", "z", "phi", "theta", "psi"];
}

/// The sliding-mode part of [`Telemetry`]: what only the paper's cascade of
/// sliding-mode laws (FTAFTSMC, RANFTSMC, TSM-STA) computes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SlidingTelemetry<R: Real = f64> {
    /// Sliding variables `[S_x, S_y, S_z, S_φ, S_θ, S_ψ]` (paper Eq. 5 for
    /// FTAFTSMC; each law's own surface otherwise).
    pub sliding: [R; 6],
    /// Mass ratio estimate α̂ (estimated mass = α̂ m, paper Eq. 20; its
    /// initial value when the adaptation is off).
    pub alpha_hat: R,
    /// The adaptive states were held at this update
    /// ([`CascadeSettings::freeze_adaptation_on_saturation`](crate::cascade::CascadeSettings::freeze_adaptation_on_saturation)).
    pub adaptation_frozen: R::Mask,
}

/// What the controller computed at its last update, for recording: the
/// quantities every controller has, and [`Telemetry::sliding_mode`] for the
/// sliding-mode cascade.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Telemetry<R: Real = f64> {
    /// Attitude reference actually tracked `[φ_ref, θ_ref, ψ_d]`, rad
    /// (filtered when the command filter is on).
    pub attitude_reference: [R; 3],
    /// Its rate, rad/s.
    pub attitude_reference_rate: [R; 3],
    /// Its acceleration, rad/s².
    pub attitude_reference_acceleration: [R; 3],
    /// Raw Eq. 52 output `[φ_d, θ_d]` before filtering, rad.
    pub attitude_demand: [R; 2],
    /// Adaptive / internal states of each channel ([`AxisLaw::estimates`](crate::law::AxisLaw::estimates)).
    pub estimates: [[R; MAX_ESTIMATES]; 6],
    /// Commanded accelerations `[a_x, a_y, a_z]`, m/s².
    pub commanded_acceleration: [R; 3],
    /// Thrust before mass adaptation u1, N.
    pub nominal_thrust: R,
    /// The thrust bound ([`CascadeSettings::thrust_limits`](crate::cascade::CascadeSettings::thrust_limits)) changed `U1`
    /// at this update.
    pub thrust_limited: R::Mask,
    /// Sliding variables, α̂ and the adaptation hold: `Some` for the paper's
    /// sliding-mode cascade, `None` for controllers without sliding
    /// surfaces (PID, SE(3)).
    pub sliding_mode: Option<SlidingTelemetry<R>>,
}
crate::lanewise_struct!(SlidingTelemetry { sliding, alpha_hat, adaptation_frozen });
crate::lanewise_struct!(Telemetry {
    attitude_reference,
    attitude_reference_rate,
    attitude_reference_acceleration,
    attitude_demand,
    estimates,
    commanded_acceleration,
    nominal_thrust,
    thrust_limited,
    sliding_mode,
});

/// A complete quadrotor controller: state and reference in, command out.
///
/// `R` is the number type ([`crate::lanes`]): `f64` (the default) flies one
/// flight; a lane type flies several side by side, each lane its own flight
/// with the controller's gains, and every lane's command has the bits the
/// same controller would compute for that flight alone.
pub trait Controller<R: Real = f64> {
    /// Machine name (e.g. `"ftaftsmc"`).
    fn name(&self) -> &'static str;
    /// One control period: compute the command from the measured state and
    /// the reference, and advance internal states by `dt` (s).
    ///
    /// Contract: every component of `state` and `reference` is finite and
    /// `dt` is a positive finite time step. The laws do not check it (the
    /// update stays branch-free per lane in the simulator's loop): a NaN or
    /// infinite input gives a non-finite command, which the simulator
    /// treats as a diverged flight. A caller whose inputs come from
    /// elsewhere (another simulator, a user) checks them with
    /// [`check_input`] or calls [`update_checked`].
    fn update(&mut self, state: &QuadState<R>, reference: &Reference<R>, dt: f64) -> Command<R>;
    /// [`Controller::update`] from a [`Measurement`], which may carry the
    /// attitude quaternion and body rates beside the Euler state. The
    /// default flies the Euler state; full-state controllers (PID, SE(3))
    /// take the quaternion and body rates when given, instead of rebuilding
    /// them from the Euler angles (the same attitude to rounding).
    fn update_measured(&mut self, measured: &Measurement<R>, reference: &Reference<R>, dt: f64) -> Command<R> {
        self.update(&measured.euler, reference, dt)
    }
    /// True when [`Controller::update_measured`] uses [`Measurement::body`]
    /// (the simulator then provides it; otherwise it spares the conversion).
    /// The default: false.
    fn uses_body_attitude(&self) -> bool {
        false
    }
    /// Quantities computed at the last update.
    fn telemetry(&self) -> &Telemetry<R>;
    /// Names of the channel laws' [`Telemetry::estimates`] slots
    /// ([`AxisLaw::ESTIMATE_NAMES`](crate::law::AxisLaw::ESTIMATE_NAMES), `""` for an unused slot). The default:
    /// no internal states, every slot unnamed.
    fn estimate_names(&self) -> [&'static str; MAX_ESTIMATES] {
        [""; MAX_ESTIMATES]
    }
    /// True when the mass adaptation of §3.2 is on, i.e.
    /// [`SlidingTelemetry::alpha_hat`] changes (otherwise it stays at its initial
    /// value). The default: false.
    fn adapts_mass(&self) -> bool {
        false
    }
    /// Restore initial internal states (every lane).
    fn reset(&mut self);
    /// Restore lane `lane`'s initial internal states, leaving the other
    /// lanes as they are: a new flight starts in that lane. The default,
    /// [`Controller::reset`], is right for one flight only; a controller
    /// that flies lanes overrides it.
    fn reset_lane(&mut self, lane: usize) {
        let _ = lane;
        self.reset();
    }
    /// Actuator feedback: called by the simulator after it has mixed the
    /// command of each control period into rotor speeds; `saturated` is true
    /// (per lane) when the mixer could not realise that command (a rotor
    /// limit was hit and thrust or torque was given up). The report holds
    /// until the next call and is cleared by [`Controller::reset`].
    ///
    /// The default ignores it. [`Cascade`](crate::cascade::Cascade) stores it and, with
    /// [`CascadeSettings::freeze_adaptation_on_saturation`](crate::cascade::CascadeSettings::freeze_adaptation_on_saturation), holds its
    /// adaptive states during the following updates while it is true.
    fn actuator_feedback(&mut self, saturated: R::Mask) {
        let _ = saturated;
    }
}

/// An input of [`Controller::update`] outside its contract: a state or
/// reference component that is not finite, or a `dt` that is not a
/// positive finite time step. Its `Display` names the field:
/// `state.position[1] is nan`, `reference.yaw is inf`, `dt is 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InvalidInput {
    /// The field: `state.position`, `state.attitude`, `state.velocity`,
    /// `state.angular_rate`, `reference.position`, `reference.velocity`,
    /// `reference.acceleration`, `reference.yaw`, `reference.yaw_rate`,
    /// `reference.yaw_acceleration` or `dt`.
    pub field: &'static str,
    /// The element of an array field (`None` for a scalar).
    pub index: Option<usize>,
    /// The offending value.
    pub value: f64,
}

impl core::fmt::Display for InvalidInput {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.field)?;
        if let Some(i) = self.index {
            write!(f, "[{i}]")?;
        }
        // NaN as Python and the CSV files spell it.
        if self.value.is_nan() {
            f.write_str(" is nan")
        } else {
            write!(f, " is {}", self.value)
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for InvalidInput {}

/// The first input of [`Controller::update`] outside its contract, in the
/// order state (position, attitude, velocity, angular rate), reference
/// (position, velocity, acceleration, yaw, yaw rate, yaw acceleration),
/// `dt`; `Ok` when every state and reference component is finite and `dt`
/// is positive and finite.
pub fn check_input(state: &QuadState, reference: &Reference, dt: f64) -> Result<(), InvalidInput> {
    let arrays: [(&'static str, &[f64; 3]); 7] = [
        ("state.position", &state.position),
        ("state.attitude", &state.attitude),
        ("state.velocity", &state.velocity),
        ("state.angular_rate", &state.angular_rate),
        ("reference.position", &reference.position),
        ("reference.velocity", &reference.velocity),
        ("reference.acceleration", &reference.acceleration),
    ];
    for (field, values) in arrays {
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(InvalidInput { field, index: Some(i), value: values[i] });
        }
    }
    let scalars = [
        ("reference.yaw", reference.yaw),
        ("reference.yaw_rate", reference.yaw_rate),
        ("reference.yaw_acceleration", reference.yaw_acceleration),
    ];
    for (field, value) in scalars {
        if !value.is_finite() {
            return Err(InvalidInput { field, index: None, value });
        }
    }
    if !(dt.is_finite() && dt > 0.0) {
        return Err(InvalidInput { field: "dt", index: None, value: dt });
    }
    Ok(())
}

/// [`Controller::update`] with its inputs checked first ([`check_input`]):
/// an input outside the contract is an error naming it, and the controller
/// is not updated (its internal states are left as they were).
pub fn update_checked<C: Controller + ?Sized>(
    controller: &mut C,
    state: &QuadState,
    reference: &Reference,
    dt: f64,
) -> Result<Command, InvalidInput> {
    check_input(state, reference, dt)?;
    Ok(controller.update(state, reference, dt))
}

/// One `impl Controller<R>` that forwards every method to the controller
/// behind a pointer (`&mut C`, `Box<C>`), so the two cannot drift apart.
macro_rules! forward_controller {
    ($(#[$attr:meta])* $ptr:ty) => {
        $(#[$attr])*
        impl<R: Real, C: Controller<R> + ?Sized> Controller<R> for $ptr {
            fn name(&self) -> &'static str {
                (**self).name()
            }
            #[cfg_attr(not(debug_assertions), inline(always))]
            fn update(&mut self, state: &QuadState<R>, reference: &Reference<R>, dt: f64) -> Command<R> {
                (**self).update(state, reference, dt)
            }
            #[cfg_attr(not(debug_assertions), inline(always))]
            fn update_measured(&mut self, measured: &Measurement<R>, reference: &Reference<R>, dt: f64) -> Command<R> {
                (**self).update_measured(measured, reference, dt)
            }
            fn uses_body_attitude(&self) -> bool {
                (**self).uses_body_attitude()
            }
            fn telemetry(&self) -> &Telemetry<R> {
                (**self).telemetry()
            }
            fn estimate_names(&self) -> [&'static str; MAX_ESTIMATES] {
                (**self).estimate_names()
            }
            fn adapts_mass(&self) -> bool {
                (**self).adapts_mass()
            }
            fn reset(&mut self) {
                (**self).reset();
            }
            fn reset_lane(&mut self, lane: usize) {
                (**self).reset_lane(lane);
            }
            fn actuator_feedback(&mut self, saturated: R::Mask) {
                (**self).actuator_feedback(saturated);
            }
        }
    };
}

forward_controller!(
    /// Forwards every method to the controller behind the reference (a flight
    /// may borrow the controller it flies).
    &mut C
);
forward_controller!(
    /// Forwards every method to the boxed controller (a flight may own the
    /// controller it flies).
    #[cfg(feature = "std")]
    std::boxed::Box<C>
);

#[cfg(test)]
mod tests {
    use super::*;

    /// A controller that counts its updates and returns its input's x.
    struct Echo(usize, Telemetry);

    impl Controller for Echo {
        fn name(&self) -> &'static str {
            "echo"
        }
        fn update(&mut self, state: &QuadState, _: &Reference, _: f64) -> Command {
            self.0 += 1;
            Command { thrust: state.position[0], torque: [0.0; 3] }
        }
        fn telemetry(&self) -> &Telemetry {
            &self.1
        }
        fn reset(&mut self) {
            self.0 = 0;
        }
    }

    #[test]
    fn check_input_names_the_first_field_outside_the_contract() {
        let (state, reference) = (QuadState::default(), Reference::default());
        assert_eq!(check_input(&state, &reference, 0.01), Ok(()));
        let mut s = state;
        s.position[1] = f64::NAN;
        s.velocity[0] = f64::INFINITY;
        let e = check_input(&s, &reference, 0.01).unwrap_err();
        assert_eq!((e.field, e.index), ("state.position", Some(1)));
        assert_eq!(e.to_string(), "state.position[1] is nan");
        let mut r = reference;
        r.yaw_rate = f64::NEG_INFINITY;
        assert_eq!(check_input(&state, &r, 0.01).unwrap_err().to_string(), "reference.yaw_rate is -inf");
        let mut r = reference;
        r.acceleration[2] = f64::INFINITY;
        assert_eq!(check_input(&state, &r, 0.01).unwrap_err().to_string(), "reference.acceleration[2] is inf");
        for dt in [0.0, -0.01, f64::NAN, f64::INFINITY] {
            assert_eq!(check_input(&state, &reference, dt).unwrap_err().field, "dt", "{dt}");
        }
    }

    #[test]
    fn update_checked_updates_only_on_valid_input() {
        let mut c = Echo(0, Telemetry::default());
        let mut state = QuadState::default();
        state.position[0] = 2.0;
        let u = update_checked(&mut c, &state, &Reference::default(), 0.01).unwrap();
        assert_eq!((u.thrust, c.0), (2.0, 1));
        state.attitude[2] = f64::NAN;
        let e = update_checked(&mut c, &state, &Reference::default(), 0.01).unwrap_err();
        assert_eq!((e.field, e.index, c.0), ("state.attitude", Some(2), 1));
    }
}
