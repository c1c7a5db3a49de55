//! Paper scenario 2: seeded noise, payload and the mass adaptation.

use ftsmc_sim::environment::Environment;
use ftsmc_sim::registry;
use ftsmc_sim::run::RunOptions;
use ftsmc_sim::scenario::{Scenario, PAPER_SCENARIO_2};

fn paper_2() -> Scenario {
    Scenario::from_toml_str(PAPER_SCENARIO_2, "paper-scenario-2.toml").unwrap()
}

#[test]
fn same_seed_same_series_different_seed_different_drag_noise() {
    let mut s = paper_2();
    s.duration = 12.0;
    let a = registry::run("ftaftsmc", &s, RunOptions::default()).unwrap();
    let b = registry::run("ftaftsmc", &s, RunOptions::default()).unwrap();
    assert_eq!(a.recording, b.recording, "same seed must give identical time series");
    assert_eq!(a.metrics, b.metrics);

    let mut other = s.clone();
    other.seed += 1;
    let c = registry::run("ftaftsmc", &other, RunOptions::default()).unwrap();
    assert_ne!(a.recording.column("x"), c.recording.column("x"), "another seed must change the flight");

    // The noise itself: same seed, same draws; other seed, other draws.
    let draws = |scenario: &Scenario| {
        let mut env = Environment::new(scenario.environment());
        (0..50)
            .map(|_| {
                env.next_period();
                env.drag_factor()
            })
            .collect::<Vec<_>>()
    };
    assert_eq!(draws(&s), draws(&s));
    assert_ne!(draws(&s), draws(&other));
    // One stream per coefficient: the six factors differ from each other.
    let first = draws(&s)[0];
    assert!(first.windows(2).all(|w| w[0] != w[1]), "{first:?}");
}

#[test]
fn drag_noise_has_the_declared_spread() {
    let s = paper_2();
    let mut env = Environment::new(s.environment());
    let n = 20_000;
    let mut sum = 0.0;
    let mut sq = 0.0;
    for _ in 0..n {
        env.next_period();
        let f = env.drag_factor()[0];
        assert!(f >= 0.0);
        sum += f;
        sq += f * f;
    }
    let mean = sum / n as f64;
    let std = (sq / n as f64 - mean * mean).sqrt();
    assert!((mean - 1.0).abs() < 0.01, "{mean}");
    assert!((std - 0.25).abs() < 0.01, "{std}");
}

#[test]
fn plant_sees_payload_inertia_and_disturbances_at_documented_times() {
    let s = paper_2();
    let env = Environment::new(s.environment());
    let m = s.plant.mass;
    assert_eq!(env.params(9.9).mass, m);
    assert!((env.params(25.0).mass - (m + 0.37)).abs() < 1e-12);
    assert!((env.params(43.0).mass - (m + 0.37 * ftsmc_core::math::exp(-1.0f64))).abs() < 1e-12);
    let t = 10.3;
    let scale = 1.0
        + 0.15 * ftsmc_core::math::sin(2.0 * std::f64::consts::PI * 0.5 * t)
        + 0.10 * ftsmc_core::math::sin(2.0 * std::f64::consts::PI * 2.0 * t);
    assert!((env.params(t).inertia[0] - s.plant.inertia[0] * scale).abs() < 1e-15);
    assert_eq!(env.params(45.0).inertia, s.plant.inertia);
    let d = env.disturbance(20.0);
    assert!((d[0] - (0.5 * ftsmc_core::math::sin(8.0f64) + 0.3 * ftsmc_core::math::sin(26.0f64))).abs() < 1e-12);
    assert!((d[2] - (0.5 * ftsmc_core::math::cos(14.0f64) + 0.7 * ftsmc_core::math::sin(6.0f64))).abs() < 1e-12);
    assert_eq!(env.disturbance(5.0), [0.0; 6]);
}

#[test]
fn mass_adaptation_lowers_z_ise_under_the_payload_and_tracks_the_mass_ratio() {
    let s = paper_2();
    let with = registry::run("ftaftsmc", &s, RunOptions::default()).unwrap();
    let without = registry::run("ftaftsmc-no-mass", &s, RunOptions::default()).unwrap();
    assert!(with.exit.is_completed() && without.exit.is_completed());
    let (zw, zn) = (with.metrics.ise_window.unwrap().z, without.metrics.ise_window.unwrap().z);
    println!("z ISE 10–40 s: with {zw:.3e}, without {zn:.3e}");
    assert!(zw < zn, "with {zw} vs without {zn}");

    let t = with.recording.column("t");
    let alpha = with.recording.column("alpha_hat");
    let k = t.iter().position(|&v| v >= 30.0).unwrap();
    let ratio = (s.plant.mass + 0.37) / s.plant.mass;
    println!("α̂(30 s) = {:.4}, true ratio {ratio:.4}", alpha[k]);
    assert!((alpha[k] - ratio).abs() < 0.1 * ratio, "α̂(30) = {} vs {ratio}", alpha[k]);
    // Before the payload, α̂ stays near 1.
    let k9 = t.iter().position(|&v| v >= 9.0).unwrap();
    assert!((alpha[k9] - 1.0).abs() < 0.05, "{}", alpha[k9]);
}

fn rejects(text: &str, key: &str) {
    let err = Scenario::from_toml_str(text, "bad.toml").expect_err("must be rejected").to_string();
    assert!(err.contains("bad.toml") && err.contains(key), "expected `{key}` in: {err}");
}

#[test]
fn bad_building_blocks_name_the_key_and_value() {
    rejects(
        &PAPER_SCENARIO_2.replacen(
            "window = [10.0, 40.0]\nterms = [\n  { type = \"sine\", amplitude = 0.5, omega = 0.4 }",
            "window = [40.0, 10.0]\nterms = [\n  { type = \"sine\", amplitude = 0.5, omega = 0.4 }",
            1,
        ),
        "`disturbance.x.window` = [40, 10]",
    );
    rejects(&PAPER_SCENARIO_2.replace("tau = 3.0", "tau = -3.0"), "`payload.tau` = -3");
    rejects(&PAPER_SCENARIO_2.replace("std = 0.25", "std = -0.25"), "`drag_noise.std` = -0.25");
    rejects(
        &PAPER_SCENARIO_2.replace(
            "{ type = \"cosine\", amplitude = 0.5, omega = 0.7 }]",
            "{ type = \"sawtooth\", amplitude = 0.5 }]",
        ),
        "sawtooth",
    );
    rejects(&PAPER_SCENARIO_2.replace("decay_start = 40.0", "decay_start = 5.0"), "payload.decay_start");
    rejects(
        &PAPER_SCENARIO_2.replace(
            "mass = { dist = \"uniform\", low = 0.666, high = 0.814 }",
            "mass = { dist = \"uniform\", low = 0.9, high = 0.8 }",
        ),
        "montecarlo.mass.high",
    );
    rejects(&PAPER_SCENARIO_2.replace("{ dist = \"log-normal\", mu = 0.0,", "{ dist = \"gamma\", mu = 0.0,"), "gamma");
    rejects(
        &PAPER_SCENARIO_2.replace("alpha_hat0 = 1.0\n", "alpha_hat0 = 1.0\nalpha_hat_bounds = [2.0, 1.0]\n"),
        "ftaftsmc.mass_adaptation.alpha_hat_bounds[1]",
    );
    rejects(
        &PAPER_SCENARIO_2.replace("alpha_hat0 = 1.0\n", "alpha_hat0 = 1.0\nalpha_hat_bounds = [1.5, 3.0]\n"),
        "ftaftsmc.mass_adaptation.alpha_hat0",
    );
}
