//! `ftsmc tune`: the time-scaling maps, the parameter maps through the
//! tuned TOML, held-out seeds, and thread-count independence.

use ftsmc_core::ftaftsmc::{FtaftsmcAxis, FtaftsmcGains};
use ftsmc_core::law::AxisLaw;
use ftsmc_core::ranftsmc::{RanftsmcAxis, RanftsmcGains};
use ftsmc_core::tsm_sta::{TsmStaAxis, TsmStaGains};
use ftsmc_sim::controllers::{ftaftsmc, ranftsmc, tsm_sta};
use ftsmc_sim::scenario::tune_section::TuneSection;
use ftsmc_sim::tune::{
    evaluate, held_out_indices, judge, training_indices, tune, tune_with, tuned_toml, OutcomeStats, TuneOptions,
};
use ftsmc_sim::Scenario;

/// Fly `ë = v` with `law` sampled every `dt` (exact zero-order-hold
/// integration of the double integrator) from `(e0, ė0)` for `steps`
/// steps; `(e, ė, S)` after every step (`S` of the update that led there).
fn fly<L: AxisLaw>(mut law: L, e0: f64, ed0: f64, dt: f64, steps: usize) -> Vec<(f64, f64, f64)> {
    let (mut e, mut ed) = (e0, ed0);
    (0..steps)
        .map(|_| {
            let v = law.update(e, ed, dt);
            e += dt * ed + 0.5 * dt * dt * v;
            ed += dt * v;
            (e, ed, law.sliding_variable())
        })
        .collect()
}

/// The law with gains scaled by `a` flies `e(a t)`: the same states after
/// the same number of steps of `dt / a`, with ė × a. While the loop
/// reaches the surface the two agree to 1e-9 of the trajectory's size
/// (rounding only); once it slides, the discrete chattering around S = 0
/// (where `sig^p2` has an infinite slope) amplifies rounding, so the rest
/// is held to 1e-4 — a wrong map is off by 1e-2 or more (checked below).
fn assert_time_scaled<L: AxisLaw>(name: &str, plain: L, scaled: L, a: f64) {
    let (e0, ed0, dt, steps) = (0.8, -0.3, 1e-3, 2000);
    let slow = fly(plain, e0, ed0, dt, steps);
    let fast = fly(scaled, e0, a * ed0, dt / a, steps);
    let scale = slow.iter().map(|(e, ed, _)| e.abs().max(ed.abs())).fold(0.0, f64::max);
    let s0 = slow[0].2.abs();
    let mut reaching = true;
    for (k, ((e, ed, s), (fe, fed, _))) in slow.iter().zip(&fast).enumerate() {
        reaching &= s.abs() > 1e-3 * s0;
        let tol = if reaching { 1e-9 } else { 1e-4 } * scale;
        assert!((e - fe).abs() <= tol, "{name}, a = {a}, step {k}: e {e} vs {fe}");
        assert!((a * ed - fed).abs() <= tol * a, "{name}, a = {a}, step {k}: a ė {} vs {fed}", a * ed);
    }
    assert!((slow[steps - 1].0 - e0).abs() > 1e-2, "{name}: the channel did not move");
}

#[test]
fn ftaftsmc_time_scaling_gives_time_scaled_trajectories() {
    let with_delta = FtaftsmcGains { delta_hat0: 0.3, ..FtaftsmcGains::PAPER_Z };
    for (name, g) in [
        ("xy", FtaftsmcGains::PAPER_XY),
        ("z", with_delta),
        ("roll-pitch", FtaftsmcGains::PAPER_ROLL_PITCH),
        ("yaw", FtaftsmcGains::PAPER_YAW),
    ] {
        for a in [0.37, 2.5, 7.0] {
            assert_time_scaled(name, FtaftsmcAxis::new(g), FtaftsmcAxis::new(ftaftsmc::time_scaled(&g, a)), a);
        }
    }
    // Scaling only λ, γ, η (not the reaching law) is not a time scaling.
    let g = FtaftsmcGains::PAPER_XY;
    let partial = FtaftsmcGains { lambda: g.lambda * 2.5, gamma: g.gamma * 2.5, eta: g.eta * 2.5, ..g };
    let slow = fly(FtaftsmcAxis::new(g), 0.8, -0.3, 1e-3, 2000);
    let fast = fly(FtaftsmcAxis::new(partial), 0.8, -0.75, 1e-3 / 2.5, 2000);
    let worst = slow.iter().zip(&fast).map(|(s, f)| (s.0 - f.0).abs()).fold(0.0, f64::max);
    assert!(worst > 1e-2, "{worst}");
}

#[test]
fn ranftsmc_time_scaling_gives_time_scaled_trajectories() {
    let smooth = RanftsmcGains {
        sign_smoothing: 0.05,
        a0_hat0: 0.2,
        a1_hat0: 0.1,
        a2_hat0: 0.3,
        ..RanftsmcGains::PAPER_POSITION
    };
    for (name, g) in [
        ("smoothed position", smooth),
        ("attitude", RanftsmcGains { sign_smoothing: 0.02, ..RanftsmcGains::PAPER_ATTITUDE }),
    ] {
        for a in [0.5, 3.0] {
            assert_time_scaled(name, RanftsmcAxis::new(g), RanftsmcAxis::new(ranftsmc::time_scaled(&g, a)), a);
        }
    }
}

#[test]
fn tsm_sta_time_scaling_gives_time_scaled_trajectories() {
    for (name, g) in [
        ("position", TsmStaGains { sign_smoothing: 0.05, ..TsmStaGains::BASE_POSITION }),
        ("position, a = 1 base", TsmStaGains { sign_smoothing: 0.01, k1: 4.0, k2: 2.0, ..TsmStaGains::BASE_POSITION }),
    ] {
        for a in [0.5, 3.0] {
            assert_time_scaled(name, TsmStaAxis::new(g), TsmStaAxis::new(tsm_sta::time_scaled(&g, a)), a);
        }
    }
}

#[test]
fn held_out_seeds_never_meet_training_seeds() {
    use ftsmc_sim::batch::montecarlo::run_seed;
    for master in [0u64, 1, 7, 42, u64::MAX] {
        let train: std::collections::HashSet<u64> =
            training_indices(50).into_iter().map(|i| run_seed(master, i)).collect();
        let held = held_out_indices(master, 50, 300);
        assert_eq!(held.len(), 300);
        assert!(held.iter().all(|i| !training_indices(50).contains(i)));
        assert!(held.iter().all(|&i| !train.contains(&run_seed(master, i))), "seed {master}");
    }
}

/// The start and three generations of 4 samples and their mean, the second
/// and third with the anchor beside them, 2 flights each (no race: a
/// tenth of this budget cannot fly one).
const TINY_BUDGET: u64 = 2 * (1 + 5 + 6 + 6);

/// A short realistic scenario and a tiny tune of it.
fn tiny(controller: &str, threads: usize) -> (Scenario, ftsmc_sim::tune::TuneResult) {
    let mut s =
        Scenario::from_toml_str(ftsmc_sim::scenario::REALISTIC_SCENARIO_2, "realistic-scenario-2.toml").unwrap();
    s.duration = 1.5;
    s.tune = Some(TuneSection { runs: 2, validation_runs: 3, population: Some(4), ..TuneSection::default() });
    let options = TuneOptions { controller: controller.to_string(), budget: TINY_BUDGET, seed: 5 };
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    let r = pool.install(|| tune(&s, &options, &|_| {})).unwrap();
    (s, r)
}

/// What `ftsmc.tune(..., client=...)` does: each generation's candidates
/// sent as TOML text in batches of at most 3 to a "worker" that rebuilds
/// them and evaluates them, the statistics sent back as numbers. The
/// result equals the local tune's.
#[test]
fn a_tune_evaluated_in_batches_through_toml_equals_the_local_tune() {
    let (s, local) = tiny("tsm-sta", 2);
    let options = TuneOptions { controller: "tsm-sta".into(), budget: TINY_BUDGET, seed: 5 };
    let calls = std::sync::atomic::AtomicUsize::new(0);
    let remote = |scenarios: &[Scenario], indices: &[u64]| -> Result<Vec<OutcomeStats>, String> {
        calls.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let mut out = Vec::new();
        for batch in scenarios.chunks(3) {
            let texts: Vec<String> = batch.iter().map(|c| c.to_toml().unwrap()).collect();
            let rebuilt: Vec<Scenario> =
                texts.iter().map(|t| Scenario::from_toml_str(t, "sent.toml").unwrap()).collect();
            let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
            let stats = pool.install(|| evaluate(&rebuilt, "tsm-sta", 5, indices, &|_| {}))?;
            out.extend(stats.iter().map(|st| OutcomeStats::from_values(&st.to_values()).unwrap()));
        }
        Ok(out)
    };
    let r = tune_with(&s, &options, &remote).unwrap();
    assert_eq!(calls.into_inner(), 1 + 3 + 1, "start, three generations, held-out");
    assert_eq!(format!("{:?}", r.history), format!("{:?}", local.history));
    assert_eq!(r.tuned, local.tuned);
    assert_eq!(format!("{:?}", r.held_out), format!("{:?}", local.held_out));
    // A wrong count from the evaluator is an error, not a silently shorter history.
    let short = |_: &[Scenario], _: &[u64]| -> Result<Vec<OutcomeStats>, String> { Ok(Vec::new()) };
    assert!(tune_with(&s, &options, &short).unwrap_err().contains("returned 0 statistics for 1"));
    assert!(OutcomeStats::from_values(&[1.5; OutcomeStats::VALUES]).is_none());
}

#[test]
fn a_tiny_tune_is_identical_with_one_and_two_threads() {
    let (_, one) = tiny("ftaftsmc", 1);
    let (_, two) = tiny("ftaftsmc", 2);
    // Debug strings: NaN statistics (no completed run) compare equal there.
    assert_eq!(format!("{:?}", one.history), format!("{:?}", two.history));
    assert_eq!(one.tuned, two.tuned);
    assert_eq!(format!("{:?}", one.held_out), format!("{:?}", two.held_out));
    assert_eq!(one.history.len(), 1 + 5 + 6 + 6);
    assert_eq!(one.training_flights, TINY_BUDGET);
    // Each generation flew its own draws, common to its entries.
    for e in &one.history {
        assert_eq!(e.role == ftsmc_sim::tune::Role::Start, e.generation == 0);
    }
    assert_eq!(one.training_indices, ftsmc_sim::tune::generation_indices(0, 2 * 4));
    let a = tuned_toml(&one, Some("realistic-scenario-2"), "test").unwrap();
    let b = tuned_toml(&two, Some("realistic-scenario-2"), "test").unwrap();
    assert_eq!(a, b);
    // The search moved: not every candidate is the start.
    assert!(one.history.iter().any(|h| h.values != one.history[0].values));
    // `judge` (what `reproduce` flies for the committed files) gives the
    // tune's own held-out statistics: the same held-out draws.
    let held = one.held_out.unwrap();
    let judged = judge(&one.tuned, "ftaftsmc", 5, 2, 3, &|_| {}).unwrap();
    assert_eq!(format!("{judged:?}"), format!("{:?}", held.tuned));
    let judged = judge(&one.start, "ftaftsmc", 5, 2, 3, &|_| {}).unwrap();
    assert_eq!(format!("{judged:?}"), format!("{:?}", held.start));
}

#[test]
fn the_tuned_toml_round_trips_the_parameter_map() {
    for controller in ["pid", "se3", "tsm-sta"] {
        let (base, mut r) = tiny(controller, 2);
        // Whatever the tiny search found, map a point away from the start
        // (every parameter moved) into the result, as a tune would.
        let values = r.space.values(&vec![0.63; r.space.dims.len()]);
        r.tuned = Scenario { controllers: vec![controller.to_string()], ..r.space.apply(&r.start, &values).unwrap() };
        let best = r.best;
        r.history[best].values = values;
        let expected = Scenario { name: format!("{}-{controller}-tuned", base.name), ..r.tuned.clone() };
        // Extending the built-in scenario, and complete (no base): both load
        // to the tuned scenario, wherever the file is.
        for base_name in [Some("realistic-scenario-2"), None] {
            let text = tuned_toml(&r, base_name, "test").unwrap();
            let tmp = tempfile::Builder::new().prefix(&format!("ftsmc-tune-test-{controller}-")).tempdir().unwrap();
            std::fs::write(tmp.path().join("tuned.toml"), &text).unwrap();
            let loaded = Scenario::from_file(&tmp.path().join("tuned.toml")).unwrap_or_else(|e| panic!("{e}\n{text}"));
            assert_eq!(loaded, expected, "{controller} {base_name:?}\n{text}");
            assert_eq!(text.lines().any(|l| l.starts_with("extends")), base_name.is_some(), "{text}");
            if base_name.is_some() {
                // Below the header: the gains, and the keys the test scenario
                // changed from the built-in one (duration, [tune]).
                let body: Vec<&str> = text.lines().filter(|l| l.starts_with('[')).collect();
                assert!(
                    body.iter().all(|l| l.starts_with(&format!("[{controller}"))
                        || l.starts_with("[cascade")
                        || l.starts_with("[tune")),
                    "{body:?}"
                );
                assert!(text.contains("\nduration = 1.5\n"), "{text}");
            }
        }
        assert_ne!(r.tuned.gains, base.gains, "{controller}: the tune changed nothing");
    }
}

/// The vehicle a tune flew travels with its file: a scenario whose vehicle
/// was switched by an override (`--set vehicle.preset=…`, Python's
/// `with_overrides`) gives a tuned file that flies that vehicle, not the
/// built-in scenario's, and is named after it.
#[test]
fn a_tuned_file_keeps_an_overridden_vehicle() {
    let (file, text) = ftsmc_sim::scenario::resolve::built_in("realistic-calm-1").unwrap();
    let s = Scenario::from_toml_str(text, file).unwrap();
    let set = |k: &str, v: &str| (k.to_string(), toml::Value::String(v.to_string()));
    let mut s = s.with_overrides(&[set("vehicle.preset", "crazyflie-2")]).unwrap().scenario;
    assert_eq!(s.name, "realistic-calm-1-crazyflie-2", "the name follows the vehicle");
    s.duration = 1.5;
    s.tune = Some(TuneSection { runs: 2, validation_runs: 3, population: Some(4), ..TuneSection::default() });
    let options = TuneOptions { controller: "pid".into(), budget: TINY_BUDGET, seed: 5 };
    let r = tune(&s, &options, &|_| {}).unwrap();
    let text = tuned_toml(&r, Some("realistic-calm-1"), "test").unwrap();
    let loaded = Scenario::from_toml_str(&text, "elsewhere/pid.tuned.toml").unwrap_or_else(|e| panic!("{e}\n{text}"));
    assert_eq!(loaded.vehicle, s.vehicle, "{text}");
    assert_eq!(loaded.plant, s.plant);
    assert_eq!(loaded.actuators, s.actuators);
    assert_eq!(loaded.gains, r.tuned.gains);
    assert_eq!(loaded.name, "realistic-calm-1-crazyflie-2-pid-tuned");
    assert!(text.contains("# Vehicle: crazyflie-2"), "{text}");
}

/// A scenario text with one `[[tune.extra]]` of `key` (any range).
fn with_extra(key: &str) -> String {
    format!(
        "extends = \"paper-scenario-1\"\nname = \"extra\"\n\n[tune]\nruns = 1\n\n[[tune.extra]]\nkey = \"{key}\"\nlow = 1.0\nhigh = 100.0\n"
    )
}

#[test]
fn tune_extra_refuses_anything_but_a_declared_gain() {
    // The seed, the duration, a rate, a vehicle limit of the pid section,
    // an unknown key and a structural one: refused when the file is loaded,
    // the message naming the file and the key.
    for key in ["seed", "duration", "simulation.control_rate", "pid.thrust_max", "no.such.key", "controllers"] {
        let err = Scenario::from_toml_str(&with_extra(key), "my-tune.toml").expect_err(key).to_string();
        assert!(err.starts_with("my-tune.toml:") && err.contains(&format!("\"{key}\"")), "{key}: {err}");
        assert!(err.contains("tune.extra[0].key") && err.lines().next().unwrap().len() <= 300, "{err}");
    }
    // Gains of a controller's own section and the command filter load.
    for key in ["pid.rate_p.0", "ftaftsmc.x.lambda", "cascade.command_filter.damping"] {
        Scenario::from_toml_str(&with_extra(key), "my-tune.toml").unwrap_or_else(|e| panic!("{key}: {e}"));
    }
}

#[test]
fn tune_refuses_a_key_of_another_controller_and_never_spins() {
    let base = Scenario::from_toml_str(&with_extra("ftaftsmc.x.lambda"), "t.toml").unwrap();
    let options = TuneOptions { controller: "pid".into(), budget: 5, seed: 1 };
    // A gain of another controller: refused by the search (before any flight).
    let err = tune(&base, &options, &|_| {}).unwrap_err();
    assert!(err.contains("ftaftsmc.x.lambda") && err.contains("pid"), "{err}");
    // Keys set past the loader (as a program may): refused the same way.
    for key in ["seed", "duration"] {
        let mut s = base.clone();
        s.tune.as_mut().unwrap().extra[0].key = key.into();
        let err = tune(&s, &options, &|_| {}).unwrap_err();
        assert!(err.contains(&format!("\"{key}\"")), "{key}: {err}");
    }
}

#[test]
fn a_search_whose_candidates_are_all_invalid_ends_within_its_budget() {
    // Every candidate sets the z velocity D gain negative (invalid), so none
    // flies; the budget still counts them, and the search ends after the
    // generations the budget pays for, handing back the start.
    let text = "extends = \"paper-scenario-1\"\nname = \"invalid\"\nduration = 0.05\n\n[tune]\nruns = 1\nvalidation_runs = 0\npopulation = 2\nparameters = []\n\n[[tune.extra]]\nkey = \"pid.velocity_d.2\"\nlow = -2.0\nhigh = -1.0\nlog = false\n";
    let base = Scenario::from_toml_str(text, "invalid.toml").unwrap();
    let options = TuneOptions { controller: "pid".into(), budget: 12, seed: 3 };
    let r = tune(&base, &options, &|_| {}).unwrap();
    // Start (1 flight) + 3 generations of 2 samples, their mean and (in the
    // second and third) the anchor, 1 flight charged each: 1 + 3 + 4 + 4.
    assert_eq!(r.history.iter().map(|e| e.generation).max(), Some(3));
    assert!(r.history[1..].iter().all(|e| e.error.is_some()), "{:?}", r.history);
    assert_eq!((r.training_flights, r.best), (1, 0));
    assert_eq!(r.tuned.gains.pid, base.gains.pid);
}

/// A start on a cliff: the paper's plant (no random draws, short flights)
/// with a tight tilt limit (0.25 rad; the start peaks at 0.14) and every
/// declared parameter of `controller` searched over factors 10⁻³ … 10³.
/// A step of a fixed fraction of that range (`sigma = 0.3`: ×60 at one
/// standard deviation) makes almost every candidate diverge; the tuner
/// must still hand back better gains than the start.
fn cliff(controller: &str, sigma: Option<f64>) -> Scenario {
    let mut s = Scenario::from_toml_str(ftsmc_sim::scenario::PAPER_SCENARIO_1, "paper-scenario-1.toml").unwrap();
    s.name = "cliff".into();
    s.duration = 4.0;
    s.simulation.max_tilt = 0.25;
    let bounds = ftsmc_sim::controllers::tunable::parameters(controller)
        .unwrap()
        .iter()
        .map(|p| (p.name.to_string(), [1e-3, 1e3]))
        .collect();
    s.tune = Some(TuneSection {
        runs: 1,
        validation_runs: 2,
        population: Some(6),
        race: 1,
        race_runs: 2,
        race_final_runs: 2,
        sigma,
        bounds,
        ..TuneSection::default()
    });
    s
}

#[test]
fn a_tune_whose_start_sits_on_a_cliff_recovers_and_improves() {
    // 120 flights: with the first tuner's step the search needs four runs,
    // the step halved three times, before its samples stop crashing.
    let options = TuneOptions { controller: "tsm-sta".into(), budget: 120, seed: 4 };
    // The step of the first tuner: most of the first generations diverge,
    // and the search restarts from the start with a smaller step.
    let old_step = tune(&cliff("tsm-sta", Some(0.3)), &options, &|_| {}).unwrap();
    let first = &old_step.generations[0];
    assert!(first.failed * 3 >= 2 * first.population, "{:?}", old_step.generations);
    assert!(
        old_step.generations.iter().any(|g| g.restarted == Some(ftsmc_sim::tune::RestartReason::NoProgress)),
        "{:?}",
        old_step.generations
    );
    // The default step (×1.4) and the restart policy: better gains, on the
    // training draws, in the race and on the held-out draws.
    for r in [&old_step, &tune(&cliff("tsm-sta", None), &options, &|_| {}).unwrap()] {
        // The search moved off the start; two held-out draws cannot show a
        // paired difference, so the headline does not call it improved.
        assert!(r.best != 0, "{:?}", r.generations);
        assert!(!r.improved && r.improved_reason.contains("McNemar"), "{}", r.improved_reason);
        assert!(r.best().cost < r.history[0].cost);
        let h = r.held_out.unwrap();
        assert_eq!(h.tuned.completed, h.tuned.runs);
        assert!(h.tuned.cost(&r.settings) < h.start.cost(&r.settings), "{h:?}");
        assert!(r.training_flights + r.race_flights <= options.budget);
    }
}

#[test]
fn a_tiny_budget_that_finds_nothing_says_so() {
    // One generation of steps as wide as the whole range (sigma = 1): every
    // candidate diverges, so the start is handed back, marked as such.
    let s = cliff("tsm-sta", Some(1.0));
    let options = TuneOptions { controller: "tsm-sta".into(), budget: 8, seed: 4 };
    let r = tune(&s, &options, &|_| {}).unwrap();
    assert_eq!(r.generations.len(), 1);
    assert!(!r.improved && r.best == 0, "{:?}", r.history);
    assert_eq!(r.tuned.gains, r.start.gains);
    let text = tuned_toml(&r, Some("paper-scenario-1"), "test").unwrap();
    assert!(text.contains("# Improved: false") && text.contains("larger --budget"), "{text}");
}

#[test]
fn the_budget_is_honoured_and_every_flight_is_counted() {
    let s = cliff("tsm-sta", None);
    for budget in [8u64, 13, 20, 41, 80] {
        let flown = std::sync::atomic::AtomicU64::new(0);
        let options = TuneOptions { controller: "tsm-sta".into(), budget, seed: 9 };
        let r = tune(&s, &options, &|n| {
            flown.fetch_add(n, std::sync::atomic::Ordering::Relaxed);
        })
        .unwrap();
        let spent = r.training_flights + r.race_flights;
        assert!(spent <= budget, "budget {budget}: {spent} flown");
        // Within one generation of the budget (6 samples, the mean and the
        // anchor, 1 run each) and the tenth of it kept for a race that may
        // have had fewer contenders.
        assert!(budget - spent < 8 + budget / 10, "budget {budget}: only {spent} flown");
        assert_eq!(flown.into_inner(), spent + r.held_out_flights, "budget {budget}");
    }
}

#[test]
fn training_race_and_held_out_draws_never_meet_a_default_monte_carlo() {
    use ftsmc_sim::batch::montecarlo::run_seed;
    use ftsmc_sim::tune::{race_indices, HELD_OUT_OFFSET, RACE_OFFSET, TRAINING_OFFSET};
    // The tuned file keeps its scenario's seed, which is the tune's seed by
    // default: its own Monte Carlo flies run indices 0, 1, … of that seed.
    let (s, r) = tiny("pid", 1);
    let tuned = tuned_toml(&r, Some("realistic-scenario-2"), "test").unwrap();
    let loaded = Scenario::from_toml_str(&tuned, "tuned.toml").unwrap();
    assert_eq!(loaded.seed, s.seed, "the tuned file keeps the scenario's seed");
    assert_eq!(r.options.seed, 5);
    let mut tune_draws: Vec<u64> = r.training_indices.clone();
    tune_draws.extend(&r.race_indices);
    tune_draws.extend(&r.held_out_indices);
    assert!(tune_draws.iter().all(|&i| i >= HELD_OUT_OFFSET), "{tune_draws:?}");
    for master in [r.options.seed, s.seed, 0, 1, 42, u64::MAX] {
        let montecarlo: std::collections::HashSet<u64> = (0..20_000).map(|i| run_seed(master, i)).collect();
        for master_tune in [r.options.seed, master] {
            for &i in &tune_draws {
                assert!(!montecarlo.contains(&run_seed(master_tune, i)), "seed {master}: run {i} re-flown");
            }
        }
    }
    // The three sets of the tune are disjoint too.
    assert!(training_indices(1000).iter().all(|&i| (TRAINING_OFFSET..RACE_OFFSET).contains(&i)));
    assert!(race_indices(1000).iter().all(|&i| i >= RACE_OFFSET));
    assert!(held_out_indices(5, 1000, 1000).iter().all(|&i| (HELD_OUT_OFFSET..TRAINING_OFFSET).contains(&i)));
}

/// `improved` is the headline on the paired held-out draws: success first
/// (McNemar), then RMS position error (Wilcoxon), never the cost.
#[test]
fn improved_means_better_on_the_headline() {
    use ftsmc_sim::tune::{headline, Comparison, FlightOutcome};
    let flight = |success: bool, rms: f64| FlightOutcome {
        completed: success,
        crashed: false,
        success,
        time: 1.0,
        rms,
        thrust_activity: 0.0,
        torque_activity: 0.0,
        saturated: 0.0,
        margin: None,
    };
    let judge = |a: Vec<FlightOutcome>, b: Vec<FlightOutcome>| {
        let c = Comparison { start: OutcomeStats::of(&a, 1.0), tuned: OutcomeStats::of(&b, 1.0) };
        headline(Some(&[a, b]), Some(&c), 0.95)
    };
    let n = 40;
    let start: Vec<FlightOutcome> = (0..n).map(|i| flight(true, 0.356 + 1e-4 * i as f64)).collect();
    // Lower RMS on every draw, the same successes: improved.
    let better: Vec<FlightOutcome> = start.iter().map(|f| flight(true, f.rms - 0.01)).collect();
    let (yes, why) = judge(start.clone(), better);
    assert!(yes && why.contains("Wilcoxon on RMS: tuned better"), "{why}");
    // Worse RMS and one success fewer (the X500 case): not improved.
    let mut worse: Vec<FlightOutcome> = start.iter().map(|f| flight(true, f.rms + 0.007)).collect();
    worse[3] = flight(false, f64::NAN);
    let (yes, why) = judge(start.clone(), worse);
    assert!(!yes && why.contains("39/40 against the start's 40/40"), "{why}");
    // Lower RMS but one success fewer, not significant on success: still
    // not improved (success comes first).
    let mut mixed: Vec<FlightOutcome> = start.iter().map(|f| flight(true, f.rms - 0.01)).collect();
    mixed[0] = flight(false, f64::NAN);
    assert!(!judge(start.clone(), mixed).0);
    // Many more successes: improved whatever the RMS.
    let failing: Vec<FlightOutcome> = (0..n).map(|i| flight(i % 2 == 0, 0.3)).collect();
    let all: Vec<FlightOutcome> = (0..n).map(|_| flight(true, 0.5)).collect();
    let (yes, why) = judge(failing, all);
    assert!(yes && why.contains("McNemar on success: tuned better"), "{why}");
}
