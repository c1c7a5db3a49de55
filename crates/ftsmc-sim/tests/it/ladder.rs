//! The wind ladder's scenarios (`scenarios/realistic-<level>-<n>.toml`):
//! they load as built-ins, share one vehicle, sensors and PX4 mixer, differ
//! only in wind and envelope; `realistic-scenario-1/2` are the moderate
//! rung; and a small Monte Carlo shows the calm rung flown by the
//! practitioners' controllers with default gains inside its envelope and
//! success falling on the moderate rung; scenario 2's rungs keep the
//! payload within the Hummingbird's rated one, and SE(3) flies calm-2. The
//! 200-run calibration is `ftsmc montecarlo realistic-<level>-<n> --runs 200
//! -c pid,se3,ftaftsmc` (docs/results.md, "The wind ladder").

use ftsmc_sim::actuators::MixerKind;
use ftsmc_sim::batch::montecarlo::{run_batch, BatchOptions};
use ftsmc_sim::environment::wind::WindPreset;
use ftsmc_sim::scenario::distributions::Dist;
use ftsmc_sim::scenario::ladder::{LADDER, LEVELS};
use ftsmc_sim::scenario::{Scenario, BUILT_IN_SCENARIOS, REALISTIC_SCENARIO_1, REALISTIC_SCENARIO_2};

fn load(name: &str) -> Scenario {
    let (file, text) = LADDER.iter().find(|(f, _)| f.trim_end_matches(".toml") == name).unwrap();
    Scenario::from_toml_str(text, file).unwrap()
}

#[test]
fn every_rung_loads_shares_the_vehicle_and_differs_in_wind_and_envelope() {
    for (file, _) in LADDER {
        assert!(BUILT_IN_SCENARIOS.iter().any(|(f, _)| *f == file), "{file} is not built in");
    }
    for n in [1, 2] {
        let calm = load(&format!("realistic-calm-{n}"));
        let mut last_envelope = 0.0;
        for (level, preset) in
            LEVELS.iter().zip([WindPreset::Calm, WindPreset::Breeze, WindPreset::Light, WindPreset::Moderate])
        {
            let s = load(&format!("realistic-{level}-{n}"));
            assert_eq!(s.name, format!("realistic-{level}-{n}"));
            assert_eq!(s.actuators.unwrap().mixer, MixerKind::Px4, "{}", s.name);
            assert_eq!(s.sensors, calm.sensors, "{}", s.name);
            assert!(s.sensors.unwrap().imu.is_some(), "{}", s.name);
            assert_eq!(s.vehicle, calm.vehicle, "{}", s.name);
            assert_eq!(s.montecarlo, calm.montecarlo, "{}", s.name);
            assert_eq!(s.wind.as_ref().unwrap().preset, Some(preset), "{}", s.name);
            let e = s.envelope.unwrap().max_position_error.unwrap();
            assert!(e > last_envelope, "{}: envelope {e} after {last_envelope}", s.name);
            last_envelope = e;
        }
    }
}

#[test]
fn realistic_scenario_1_and_2_are_the_moderate_rung() {
    for (n, text) in [(1, REALISTIC_SCENARIO_1), (2, REALISTIC_SCENARIO_2)] {
        let alias = Scenario::from_toml_str(text, &format!("realistic-scenario-{n}.toml")).unwrap();
        let rung = load(&format!("realistic-moderate-{n}"));
        assert_eq!(alias.name, format!("realistic-scenario-{n}"));
        assert_eq!(alias.wind, rung.wind);
        assert_eq!(alias.envelope, rung.envelope);
        assert_eq!(alias.actuators, rung.actuators);
        assert_eq!(alias.sensors, rung.sensors);
    }
}

/// AscTec's maximum payload for the Hummingbird, kg (manufacturer's
/// specification; the scenario files cite it).
const HUMMINGBIRD_RATED_PAYLOAD: f64 = 0.2;

#[test]
fn scenario_2_rungs_never_load_the_hummingbird_beyond_its_rated_payload() {
    for level in LEVELS {
        let s = load(&format!("realistic-{level}-2"));
        let nominal = s.payload.as_ref().unwrap().mass;
        assert!(nominal > 0.0 && nominal <= HUMMINGBIRD_RATED_PAYLOAD, "{}: payload {nominal} kg", s.name);
        match s.montecarlo.as_ref().unwrap().payload_mass {
            Some(Dist::Normal { low: Some(low), high: Some(high), .. }) => {
                assert!(low >= 0.0 && high <= HUMMINGBIRD_RATED_PAYLOAD, "{}: draws in [{low}, {high}] kg", s.name);
            }
            ref other => panic!("{}: payload draws {other:?} are not bounded by the rated payload", s.name),
        }
    }
}

/// Successes out of `runs` Monte Carlo runs of `scenario` per controller.
fn successes(scenario: &str, controllers: &[&str], runs: u64) -> Vec<usize> {
    let s = load(scenario);
    let spec = s.montecarlo.clone().unwrap_or_default();
    let names: Vec<String> = controllers.iter().map(|c| (*c).to_string()).collect();
    let rows = run_batch(&s, &spec, &names, BatchOptions::new(runs, s.seed)).unwrap();
    names.iter().map(|n| rows.iter().filter(|r| &r.controller == n && r.success).count()).collect()
}

#[test]
fn default_se3_flies_calm_scenario_2_within_the_rated_payload() {
    let calm = successes("realistic-calm-2", &["se3"], 12);
    assert_eq!(calm, vec![12], "calm-2 successes (se3) out of 12");
}

#[test]
fn default_pid_and_se3_fly_the_calm_rung_and_success_falls_in_moderate_wind() {
    let calm = successes("realistic-calm-1", &["pid", "se3"], 12);
    assert_eq!(calm, vec![12, 12], "calm-1 successes (pid, se3) out of 12");
    let moderate = successes("realistic-moderate-1", &["pid", "se3"], 12);
    for (c, m) in calm.iter().zip(&moderate) {
        assert!(m < c, "moderate-1 {moderate:?} vs calm-1 {calm:?}");
    }
}
