//! Any one-flight controller on lanes: [`PerLane`] holds one controller per
//! lane and updates them one after the other. It flies a controller that
//! has no lane implementation of its own (a user's controller, or one not
//! yet written for lanes) in a batch of lanes, with exactly the bits each
//! flight has alone, and no vector speed-up of the controller itself.

use ftsmc_core::cascade::{Controller, Telemetry};
use ftsmc_core::lanes::{Lanes, Lanewise};
use ftsmc_core::law::MAX_ESTIMATES;
use ftsmc_core::measured::Measurement;
use ftsmc_core::model::{Command, QuadState, Reference};

/// `N` one-flight controllers side by side, lane `i` flown by `flights[i]`.
pub struct PerLane<C: ?Sized, const N: usize> {
    flights: [Box<C>; N],
    /// The lanes' telemetry after the last update.
    telemetry: Telemetry<Lanes<N>>,
}

impl<C: Controller + ?Sized, const N: usize> PerLane<C, N> {
    /// Lane `i` flown by `flights[i]` (built alike: the batch starts new
    /// flights in a lane with [`Controller::reset_lane`], which resets that
    /// lane's controller).
    pub fn new(flights: [Box<C>; N]) -> Self {
        let mut telemetry = Telemetry::<Lanes<N>>::default();
        for (i, c) in flights.iter().enumerate() {
            telemetry.put_lane(i, *c.telemetry());
        }
        Self { flights, telemetry }
    }
}

impl<C: Controller + ?Sized, const N: usize> Controller<Lanes<N>> for PerLane<C, N> {
    fn name(&self) -> &'static str {
        self.flights[0].name()
    }

    fn update(&mut self, state: &QuadState<Lanes<N>>, reference: &Reference<Lanes<N>>, dt: f64) -> Command<Lanes<N>> {
        let mut command = Command::<Lanes<N>>::default();
        for (i, c) in self.flights.iter_mut().enumerate() {
            command.put_lane(i, c.update(&state.get_lane(i), &reference.get_lane(i), dt));
            self.telemetry.put_lane(i, *c.telemetry());
        }
        command
    }

    fn update_measured(
        &mut self,
        measured: &Measurement<Lanes<N>>,
        reference: &Reference<Lanes<N>>,
        dt: f64,
    ) -> Command<Lanes<N>> {
        let mut command = Command::<Lanes<N>>::default();
        for (i, c) in self.flights.iter_mut().enumerate() {
            command.put_lane(i, c.update_measured(&measured.get_lane(i), &reference.get_lane(i), dt));
            self.telemetry.put_lane(i, *c.telemetry());
        }
        command
    }

    fn uses_body_attitude(&self) -> bool {
        self.flights[0].uses_body_attitude()
    }

    fn telemetry(&self) -> &Telemetry<Lanes<N>> {
        &self.telemetry
    }

    fn estimate_names(&self) -> [&'static str; MAX_ESTIMATES] {
        self.flights[0].estimate_names()
    }

    fn adapts_mass(&self) -> bool {
        self.flights[0].adapts_mass()
    }

    fn reset(&mut self) {
        for i in 0..N {
            self.reset_lane(i);
        }
    }

    fn reset_lane(&mut self, lane: usize) {
        self.flights[lane].reset();
        self.telemetry.put_lane(lane, *self.flights[lane].telemetry());
    }

    fn actuator_feedback(&mut self, saturated: <Lanes<N> as ftsmc_core::lanes::Real>::Mask) {
        for (i, c) in self.flights.iter_mut().enumerate() {
            c.actuator_feedback(saturated.get_lane(i));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ftsmc_core::model::QuadrotorParams;
    use ftsmc_core::pid::{PidController, PidGains};

    /// Each lane's command and telemetry are those of its controller flown
    /// alone, and resetting one lane leaves the others alone.
    #[test]
    fn each_lane_is_its_own_controller() {
        let make = || PidController::new(QuadrotorParams::default(), PidGains::default()).expect("default gains");
        let mut lanes = PerLane::<_, 4>::new(core::array::from_fn(|_| Box::new(make())));
        let mut alone: [PidController; 4] = core::array::from_fn(|_| make());
        for step in 0..200 {
            let mut state = QuadState::<Lanes<4>>::default();
            let mut reference = Reference::<Lanes<4>>::default();
            for i in 0..4 {
                let x = 0.01 * (step as f64) * (i as f64 + 1.0);
                state.put_lane(i, QuadState { position: [x, -x, 0.5 * x], ..QuadState::default() });
                reference.put_lane(i, Reference { position: [1.0, 0.0, 1.0 + i as f64], ..Reference::default() });
            }
            if step == 100 {
                lanes.reset_lane(2);
                alone[2].reset();
            }
            let c = lanes.update(&state, &reference, 1e-3);
            for (i, a) in alone.iter_mut().enumerate() {
                let want = a.update(&state.get_lane(i), &reference.get_lane(i), 1e-3);
                let got: Command = c.get_lane(i);
                assert_eq!(got.thrust.to_bits(), want.thrust.to_bits(), "lane {i} step {step}");
                assert_eq!(got.torque.map(f64::to_bits), want.torque.map(f64::to_bits));
                assert_eq!(lanes.telemetry().get_lane(i), *a.telemetry());
            }
        }
    }
}
