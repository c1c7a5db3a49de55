//! The one run loop: a steppable [`Flight`], per-tick observers, the
//! explicit actuator stage and what the deprecated
//! `simulation.max_rotor_speed` means.

use ftsmc_core::model::{QuadState, Reference};
use ftsmc_sim::registry;
use ftsmc_sim::run::{Flight, Observer, StepOutcome, Tick};
use ftsmc_sim::scenario::Scenario;
use ftsmc_sim::{simulate, RunOptions, RunOutput};

fn scenario(extra: &str) -> Scenario {
    let text = format!("extends = \"paper-scenario-1\"\nname = \"t\"\nduration = 4.0\n{extra}");
    Scenario::from_toml_str(&text, "test.toml").unwrap_or_else(|e| panic!("{e}"))
}

fn fly(s: &Scenario, controller: &str) -> RunOutput {
    registry::run(controller, s, RunOptions { record: true, ..Default::default() }).unwrap()
}

fn same_flight(a: &RunOutput, b: &RunOutput) {
    assert_eq!(a.exit, b.exit);
    assert_eq!(a.steps, b.steps);
    assert_eq!(a.metrics.ise, b.metrics.ise, "ISE bit for bit");
    assert_eq!(a.recording, b.recording, "every recorded number bit for bit");
}

/// The measured example: with the deprecated key a ground the
/// flight never touches switched the rotor model (per-rotor clamp → thrust
/// first) and changed z ISE 0.2386 → 0.2188. Now the key means the clamp on
/// every flight, the same as its replacement, with or without the ground.
#[test]
fn the_deprecated_rotor_limit_is_the_clamp_whatever_else_the_file_says() {
    let legacy = scenario("[simulation]\nmax_rotor_speed = 500.0\n");
    let explicit = scenario("[actuators]\nmax_rotor_speed = 500.0\nmixer = \"clamp\"\n");
    let far_ground = scenario("[simulation]\nmax_rotor_speed = 500.0\n[ground]\nenabled = true\nheight = -1000.0\n");
    for c in ["ftaftsmc", "ranftsmc"] {
        let a = fly(&legacy, c);
        same_flight(&a, &fly(&explicit, c));
        let g = fly(&far_ground, c);
        assert_eq!(a.exit, g.exit);
        assert_eq!(a.metrics.ise, g.metrics.ise, "{c}: a ground never touched changes nothing");
        // The clamp does bite: the unlimited flight differs.
        assert_ne!(a.metrics.ise, fly(&scenario(""), c).metrics.ise, "{c}");
    }
}

#[test]
fn the_deprecated_key_warns_naming_its_replacement_and_cannot_be_mixed() {
    let text = "extends = \"paper-scenario-1\"\nname = \"t\"\n[simulation]\nmax_rotor_speed = 500.0\n";
    let loaded = Scenario::from_toml_str_with_warnings(text, "old.toml", &[]).unwrap();
    let w = loaded.warnings.join("\n");
    assert!(
        w.contains("simulation.max_rotor_speed")
            && w.contains("[actuators] max_rotor_speed = 500")
            && w.contains("clamp"),
        "{w}"
    );

    let both = format!("{text}[actuators]\nmax_rotor_speed = 400.0\n");
    let err = Scenario::from_toml_str(&both, "both.toml").unwrap_err().to_string();
    assert!(err.contains("simulation.max_rotor_speed") && err.contains("[actuators]"), "{err}");
}

#[test]
fn the_clamp_mixer_refuses_lag_and_noise_with_a_message() {
    let text = "extends = \"paper-scenario-1\"\nname = \"t\"\n[actuators]\nmax_rotor_speed = 500.0\nmixer = \"clamp\"\ntime_constant_up = 0.03\n";
    let err = Scenario::from_toml_str(text, "lag.toml").unwrap_err().to_string();
    assert!(err.contains("actuators.mixer") && err.contains("thrust-first"), "{err}");
}

#[test]
fn the_clamp_mixer_flies_the_rigid_body_and_reports_saturation() {
    let s = scenario("[vehicle]\nmodel = \"rigid-body\"\n[actuators]\nmax_rotor_speed = 420.0\nmixer = \"clamp\"\n");
    let run = fly(&s, "ftaftsmc");
    assert!(run.stats.rotor_speed_max <= 420.0, "{}", run.stats.rotor_speed_max);
    assert!(run.stats.saturated_periods > 0, "FTAFTSMC's printed gains saturate 420 rad/s rotors");
}

/// Counts ticks and boundaries and keeps the largest |φ| it saw at a boundary.
#[derive(Default)]
struct Counter {
    ticks: u64,
    boundaries: u64,
    last_k: Option<u64>,
    max_roll: f64,
}

impl Observer for Counter {
    fn tick(&mut self, tick: &Tick<'_>) {
        assert_eq!(Some(tick.k), self.last_k.map_or(Some(0), |k| Some(k + 1)), "ticks in order");
        assert!(tick.omega.iter().all(|w| w.is_finite()));
        self.last_k = Some(tick.k);
        self.ticks += 1;
    }
    fn boundary(&mut self, _: f64, truth: &QuadState, _: &Reference) {
        self.boundaries += 1;
        self.max_roll = self.max_roll.max(truth.attitude[0].abs());
    }
}

#[test]
fn a_flight_stepped_by_hand_is_the_simulated_flight_and_observers_see_every_tick() {
    for extra in ["", "[vehicle]\nmodel = \"rigid-body\"\n[actuators]\nmax_rotor_speed = 600.0\ntime_constant_up = 0.02\ntime_constant_down = 0.03\n[wind]\nmean = [2.0, 0.0, 0.0]\n"] {
        let s = scenario(extra);
        let mut c1 = registry::build("pid", &s).unwrap();
        let whole = simulate(&s, c1.as_mut(), RunOptions::default());

        let mut c2 = registry::build("pid", &s).unwrap();
        let mut counter = Counter::default();
        let mut flight = Flight::new(s.clone(), c2.as_mut(), RunOptions::default());
        flight.observe_with(&mut counter);
        let mut steps = 0;
        while flight.step() == StepOutcome::Flying {
            steps += 1;
        }
        assert!(flight.exit().is_some());
        assert_eq!(flight.step(), StepOutcome::Done, "a finished flight stays finished");
        let by_hand = flight.finish();
        same_flight(&whole, &by_hand);
        assert_eq!(by_hand.stats, whole.stats);
        assert_eq!(steps + 1, whole.steps, "the last step reports Done");
        assert_eq!(counter.ticks, whole.steps);
        assert_eq!(counter.boundaries, whole.steps + 1, "t = 0 and after every period");
        assert!(whole.stats.peak_tilt >= counter.max_roll);
        // The statistics see every period; the 100 Hz recording a subset.
        let recorded = whole.recording.column("phi").iter().chain(whole.recording.column("theta")).fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(whole.stats.peak_tilt >= recorded && whole.stats.peak_tilt < recorded + 0.01, "{} vs {recorded}", whole.stats.peak_tilt);
    }
}
