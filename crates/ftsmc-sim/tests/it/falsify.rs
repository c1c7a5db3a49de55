//! `[falsify]`, the worst-case search and the failure-probability estimate
//! (`ftsmc_sim::falsify`, docs/falsification.md).

use ftsmc_sim::falsify::rare::{cross_entropy, RareObjective};
use ftsmc_sim::falsify::search::{cmaes, random};
use ftsmc_sim::falsify::{Objective, Problem, RareProblem};
use ftsmc_sim::scenario::Scenario;
use ftsmc_sim::RunOptions;

/// realistic-calm-1 cut to 4 s, the envelope checked from 2 s, one gust searched.
fn short(extra: &str) -> String {
    format!(
        "extends = \"realistic-calm-1\"\nname = \"short\"\nduration = 4.0\n\
         [envelope]\nsettle_after = 2.0\nmax_position_error = 0.5\n\
         [falsify]\ngusts = 1\nwind_speed = {{ low = 0.0, high = 3.0 }}\n\
         gust_onset = {{ low = 1.0, high = 3.5 }}\ngust_length = {{ low = 0.3, high = 2.0 }}\n\
         gust_amplitude = {{ low = 0.0, high = 6.0, nominal = {{ mean = 0.0, std = 2.0 }} }}\n\
         gust_direction = {{ low = -180.0, high = 180.0 }}\n{extra}"
    )
}

fn load(text: &str) -> Scenario {
    Scenario::from_toml_str(text, "short.toml").unwrap_or_else(|e| panic!("{e}"))
}

fn refused(text: &str) -> String {
    Scenario::from_toml_str(text, "bad.toml").expect_err("refused").to_string()
}

#[test]
fn bad_search_spaces_are_refused_naming_file_key_and_value() {
    let base = "extends = \"paper-scenario-1\"\nname = \"b\"\n";
    let e = refused(&format!("{base}[falsify]\nbudget = 10\n"));
    assert!(e.contains("bad.toml") && e.contains("`falsify`") && e.contains("empty search space"), "{e}");
    let e = refused(&format!("{base}[falsify]\nwind_speed = {{ low = 3.0, high = 1.0 }}\n"));
    assert!(e.contains("falsify.wind_speed") && e.contains("low = 3") && e.contains("inverted"), "{e}");
    let e = refused(&format!("{base}[falsify]\nwind_speed = {{ low = 2.0, high = 2.0 }}\n"));
    assert!(e.contains("falsify.wind_speed") && e.contains("empty interval"), "{e}");
    let e = refused(&format!("{base}[falsify]\nwind_speed = {{ low = 0.0, high = inf }}\n"));
    assert!(e.contains("falsify.wind_speed") && e.contains("finite"), "{e}");
    let e = refused(&format!("{base}[falsify]\nbudget = 0\nwind_speed = {{ low = 0.0, high = 1.0 }}\n"));
    assert!(e.contains("falsify.budget") && e.contains("budget = 0"), "{e}");
    // 500 m/s of wind leaves [wind]'s valid range; a negative payload the vehicle's.
    let e = refused(&format!("{base}[falsify]\nwind_speed = {{ low = 0.0, high = 500.0 }}\n"));
    assert!(e.contains("falsify.wind_speed") && e.contains("500") && e.contains("valid range"), "{e}");
    let e = refused(&format!("{base}[falsify]\npayload_mass = {{ low = -5.0, high = 0.1 }}\n"));
    assert!(e.contains("falsify.payload_mass") && e.contains("-5"), "{e}");
    let e = refused(&format!("{base}[falsify]\ngust_onset = {{ low = 1.0, high = 2.0 }}\n"));
    assert!(e.contains("falsify.gust_length") && e.contains("missing"), "{e}");
    let e = refused(&format!(
        "{base}[falsify]\nwind_speed = {{ low = 0.0, high = 1.0, nominal = {{ mean = 0.0, std = 0.0 }} }}\n"
    ));
    assert!(e.contains("falsify.wind_speed.nominal") && e.contains("std = 0"), "{e}");
    for e in [
        refused(&format!("{base}[falsify]\nwind_speed = {{ low = 0.0, high = 500.0 }}\n")),
        refused(&format!("{base}[falsify]\ngusts = 9\ngust_onset = {{ low = 1.0, high = 2.0 }}\n")),
    ] {
        assert!(e.lines().next().unwrap().chars().count() <= 300, "{e}");
    }
}

#[test]
fn every_rung_of_the_ladder_declares_a_valid_search_space() {
    for level in ["calm", "breeze", "light", "moderate"] {
        for n in [1, 2] {
            let name = format!("realistic-{level}-{n}");
            let s = Scenario::from_toml_str(&format!("extends = \"{name}\"\nname = \"x\"\n"), "x.toml")
                .unwrap_or_else(|e| panic!("{name}: {e}"));
            let f = s.falsify.as_ref().unwrap_or_else(|| panic!("{name}: no [falsify]"));
            assert_eq!(f.params().len(), 6, "{name}");
            Problem::new(&s, "pid").unwrap_or_else(|e| panic!("{name}: {e}"));
        }
    }
    // The windier rung allows the larger gusts.
    let high = |n: &str| {
        let s = Scenario::from_toml_str(&format!("extends = \"{n}\"\nname = \"x\"\n"), "x.toml").unwrap();
        s.falsify.unwrap().gust_amplitude.unwrap().high
    };
    assert!(high("realistic-calm-1") < high("realistic-breeze-1"));
    assert!(high("realistic-breeze-1") < high("realistic-light-1"));
    assert!(high("realistic-light-1") < high("realistic-moderate-1"));
}

/// A margin landscape with a narrow failure window: in gust onset (`u0`
/// within ±0.0075 of 0.637) and only at the largest amplitudes (`u2` → 1),
/// sloping towards it everywhere (the margin of a real flight falls as the
/// gust lines up with the vehicle's weak moment). Its failing volume is
/// about 1.8e-5 of the box (random search meets it with ~1.1 % per 600 draws).
struct Planted;

impl Objective for Planted {
    fn dim(&self) -> usize {
        4
    }
    fn margins(&self, points: &[Vec<f64>]) -> Vec<f64> {
        points
            .iter()
            .map(|u| 4.0 * (u[0] - 0.637).abs() + 0.5 * (1.0 - u[2]) + 0.5 * (u[1] - 0.3).abs() - 0.03)
            .collect()
    }
}

#[test]
fn a_planted_narrow_window_is_found_by_the_search_and_missed_by_random_draws() {
    let budget = 600;
    let (mut cma, mut rnd) = (0, 0);
    for seed in 0..20 {
        cma += usize::from(cmaes(&Planted, budget, seed, None).first_violation().is_some());
        rnd += usize::from(random(&Planted, budget, seed).first_violation().is_some());
    }
    println!("planted window, {budget} evaluations: CMA-ES found it in {cma}/20 seeds, random in {rnd}/20");
    assert!(cma >= 18, "CMA-ES found it in {cma} of 20 seeds");
    assert!(rnd <= 1, "random search found it in {rnd} of 20 seeds");
}

/// `P(z₀ > β)` with `β` the standard normal quantile of `1 − 1e-4`.
struct Tail(f64);

impl RareObjective for Tail {
    fn dim(&self) -> usize {
        2
    }
    fn margins(&self, _: u64, z: &[Vec<f64>]) -> Vec<f64> {
        z.iter().map(|z| self.0 - z[0]).collect()
    }
}

#[test]
fn cross_entropy_covers_a_known_rare_probability_with_far_fewer_flights() {
    let beta = ftsmc_sim::stats::normal_quantile(1.0 - 1e-4);
    // The exact tail of that β (the quantile function is accurate to ~1e-9 relative, not exact).
    let p = ftsmc_sim::stats::normal_sf(beta);
    println!("beta = {beta}, p = {p:e}");
    let tail = Tail(beta);
    let (mut covered, mut saved) = (0, Vec::new());
    for seed in 0..50 {
        let e = cross_entropy(&tail, 2000, seed, 0.95);
        covered += usize::from(e.lo <= p && p <= e.hi);
        // Plain Monte Carlo flights for the same relative half-width h: z²(1 − p)/(p h²).
        let h = e.relative_half_width();
        let z = ftsmc_sim::stats::normal_quantile(0.975);
        saved.push(z * z * (1.0 - p) / (p * h * h) / e.flights as f64);
    }
    saved.sort_by(f64::total_cmp);
    println!("p = 1e-4: covered in {covered}/50; plain MC needs {:.0}x the flights (median)", saved[25]);
    assert!(covered >= 45, "covered in {covered} of 50");
    assert!(saved[0] >= 10.0, "fewest flights saved: {}x", saved[0]);
}

/// A failure that is not rare (`p = 0.3`): the first level, at the nominal
/// law, already fails in more than ρ of its draws, so the estimator flies
/// the whole budget at the nominal law (weights 1, no level) and gives the
/// Wilson interval; it covers the truth at about the stated level.
#[test]
fn a_failure_that_is_not_rare_is_estimated_by_plain_monte_carlo_over_the_whole_budget() {
    let beta = ftsmc_sim::stats::normal_quantile(0.7);
    let p = ftsmc_sim::stats::normal_sf(beta);
    let tail = Tail(beta);
    let (mut covered, mut plain) = (0, 0);
    for seed in 0..50 {
        let e = cross_entropy(&tail, 400, seed, 0.95);
        // The switch is itself a draw: with 20 flights in the first level,
        // fewer than 2 failures (its 10 % quantile above 0) has probability
        // 0.8 %, and then the levels go on as for a rare failure.
        if e.levels.is_empty() {
            plain += 1;
            assert!(e.flights == 400 && e.final_flights == 400, "{e:?}");
            assert_eq!(e.ess, e.failures as f64, "weights are 1");
            let w = ftsmc_sim::stats::rate::wilson(e.failures, 400, 0.95).unwrap();
            assert_eq!((e.lo, e.hi), (w.lo, w.hi));
        }
        covered += usize::from(e.lo <= p && p <= e.hi);
    }
    println!("p = 0.3: plain Monte Carlo in {plain}/50 seeds, covered in {covered}/50");
    assert!(plain >= 45, "plain in {plain} of 50");
    assert!(covered >= 45, "covered in {covered} of 50");
}

#[test]
fn the_worst_case_replays_bit_for_bit_and_the_search_is_the_same_on_any_thread_count() {
    let s = load(&short(""));
    let problem = Problem::new(&s, "pid").unwrap();
    let pool = |n| rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap();
    let one = pool(1).install(|| cmaes(&problem, 24, 3, Some(problem.nominal_point())));
    let three = pool(3).install(|| cmaes(&problem, 24, 3, Some(problem.nominal_point())));
    assert_eq!(one, three, "same history on 1 and 3 threads");
    let best = one.best().unwrap();
    // The worst case as a file, read back and flown alone.
    let worst = problem.scenario(&problem.values(&best.point));
    let text = worst.to_toml().unwrap();
    let replay = Scenario::from_toml_str(&text, "worst.toml").unwrap();
    let out = ftsmc_sim::registry::run("pid", &replay, RunOptions::default()).unwrap();
    assert_eq!(out.margin.unwrap().value.to_bits(), best.margin.to_bits());
    // The rare-event problem flies the same way.
    let rp = RareProblem { problem, master: 1 };
    let a = rp.margins(5, &[vec![0.0; 5], vec![1.0; 5]]);
    let b = pool(2).install(|| rp.margins(5, &[vec![0.0; 5], vec![1.0; 5]]));
    assert_eq!(a.iter().map(|m| m.to_bits()).collect::<Vec<_>>(), b.iter().map(|m| m.to_bits()).collect::<Vec<_>>());
}

/// On a real scenario at p ≈ 1e-2 — SE(3) with gains tuned for the breeze
/// rung, 20 s flights (`tests/data/breeze-1-se3-p1e-2.toml`: a tuned file
/// kept as it was measured, so re-tuning `scenarios/tuned/` does not move
/// p) — cross-entropy (2,000 flights) and plain Monte Carlo (8,000
/// flights, Wilson) agree: their intervals overlap. About 230 CPU-seconds
/// in release, so not in the default test run:
/// `cargo test --release -p ftsmc-sim --test falsify -- --ignored`.
#[test]
#[ignore = "about 230 CPU-seconds; run on demand (docs/falsification.md)"]
fn failure_probability_agrees_with_plain_monte_carlo_on_a_real_scenario() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/breeze-1-se3-p1e-2.toml");
    let s = Scenario::from_file(std::path::Path::new(path)).unwrap();
    let rp = RareProblem { problem: Problem::new(&s, "se3").unwrap(), master: s.seed };
    let ce = cross_entropy(&rp, 2000, s.seed, 0.95);
    let mc = ftsmc_sim::falsify::rare::plain(&rp, 8000, s.seed, 0.95);
    println!(
        "cross-entropy {:.3e} [{:.3e}, {:.3e}]; plain {:.3e} [{:.3e}, {:.3e}]",
        ce.p, ce.lo, ce.hi, mc.p, mc.lo, mc.hi
    );
    assert!((0.003..0.05).contains(&mc.p), "p ≈ 1e-2 expected, plain gave {}", mc.p);
    assert!(ce.lo <= mc.hi && mc.lo <= ce.hi, "the intervals do not overlap");
}

/// The defensive mixture bounds every weight by 1/α; a zero-failure
/// estimate is one-sided, clipped to [0, 1] and unreliable; a failure the
/// proposal barely reaches is marked unreliable with a larger budget to try.
#[test]
fn cross_entropy_is_honest_about_what_it_cannot_bound() {
    use ftsmc_sim::falsify::rare::{mixture_weight, DEFENSIVE_SHARE, MIN_ESS};
    // Weights: far in the proposal's tail φ/q is huge; the mixture's is not.
    for z in [-8.0, -3.0, 0.0, 3.0, 8.0] {
        let w = mixture_weight(&[z, 0.0], &[4.0, 0.0], &[0.75, 0.75]);
        assert!(w > 0.0 && w <= 1.0 / DEFENSIVE_SHARE + 1e-12, "z = {z}: w = {w}");
    }
    // No failure reachable: 0 with a one-sided bound inside [0, 1].
    let never = Tail(1e3);
    let e = cross_entropy(&never, 40, 3, 0.95);
    assert_eq!(e.p, 0.0);
    assert!(e.one_sided && !e.reliable && e.lo == 0.0 && e.hi > 0.0 && e.hi <= 1.0, "{e:?}");
    assert!(e.suggested_budget().unwrap() > e.flights);
    assert!(e.plain_mc_equivalent.is_nan());
    // p = 1e-4 on 2,000 flights: reliable, as the coverage test relies on.
    let beta = ftsmc_sim::stats::normal_quantile(1.0 - 1e-4);
    let e = cross_entropy(&Tail(beta), 2000, 1, 0.95);
    assert!(e.reliable && e.ess >= MIN_ESS && e.suggested_budget().is_none(), "{e:?}");
    // The same on a budget too small to reach the failure region reliably.
    let e = cross_entropy(&Tail(ftsmc_sim::stats::normal_quantile(1.0 - 1e-7)), 40, 1, 0.95);
    assert!(!e.reliable, "{e:?}");
}
