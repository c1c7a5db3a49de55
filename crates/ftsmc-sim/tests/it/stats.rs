//! The statistics module against what it promises: coverage measured by
//! simulation on synthetic binomial and skewed samples equals the exact
//! coverage within Monte Carlo error; bounds are ordered and narrow as the
//! sample grows; the sequential campaign keeps its error rate under early
//! stopping and finds a real difference. Pure arithmetic: seconds.
//!
//! `cargo test -p ftsmc-sim --test stats -- --nocapture` prints the
//! coverage table of docs/statistics.md.

use ftsmc_core::math::{cos, exp, ln};
use ftsmc_sim::rng::chacha_stream;
use ftsmc_sim::stats::order::{quantile_interval, quantile_ranks};
use ftsmc_sim::stats::paired::{error_test, success_test, Verdict};
use ftsmc_sim::stats::rate::{clopper_pearson, wilson};
use ftsmc_sim::stats::sequential::Campaign;
use ftsmc_sim::stats::Interval;
use proptest::prelude::*;
use rand::RngExt;
use statrs::distribution::{Binomial, Discrete};

const SAMPLES: usize = 10_000;

/// Exact coverage of a rate interval: Σ P(k) over the k whose interval holds p.
fn exact_coverage(n: u64, p: f64, interval: &dyn Fn(u64, u64) -> Interval) -> f64 {
    let d = Binomial::new(p, n).unwrap();
    (0..=n).filter(|&k| interval(k, n).contains(p)).map(|k| d.pmf(k)).sum()
}

/// `|simulated − exact|` within 4 Monte Carlo standard errors.
fn agrees(simulated: f64, exact: f64) -> bool {
    let se = (exact * (1.0 - exact) / SAMPLES as f64).sqrt();
    (simulated - exact).abs() <= 4.0 * se + 1e-9
}

#[test]
fn rate_intervals_cover_as_computed_exactly() {
    let w = |k, n| wilson(k, n, 0.95).unwrap();
    let cp = |k, n| clopper_pearson(k, n, 0.95).unwrap();
    println!("| n | p | Wilson exact | Wilson simulated | Clopper–Pearson exact | simulated |");
    for (stream, &(n, p)) in
        [(10u64, 0.02), (10, 0.5), (10, 0.98), (200, 0.02), (200, 0.5), (200, 0.98)].iter().enumerate()
    {
        let mut rng = chacha_stream(36, stream as u64);
        let ks: Vec<u64> = (0..SAMPLES).map(|_| (0..n).filter(|_| rng.random::<f64>() < p).count() as u64).collect();
        let sim = |f: &dyn Fn(u64, u64) -> Interval| {
            ks.iter().filter(|&&k| f(k, n).contains(p)).count() as f64 / SAMPLES as f64
        };
        let (we, ws) = (exact_coverage(n, p, &w), sim(&w));
        let (ce, cs) = (exact_coverage(n, p, &cp), sim(&cp));
        println!("| {n} | {p} | {:.4} | {:.4} | {:.4} | {:.4} |", we, ws, ce, cs);
        assert!(agrees(ws, we), "Wilson n={n} p={p}: simulated {ws}, exact {we}");
        assert!(agrees(cs, ce), "Clopper–Pearson n={n} p={p}: simulated {cs}, exact {ce}");
        // Clopper–Pearson guarantees the level.
        assert!(ce >= 0.95, "Clopper–Pearson n={n} p={p}: {ce}");
    }
    // Wilson's known dip near the edge (docs/statistics.md).
    let dip = exact_coverage(200, 0.02, &w);
    assert!((0.92..0.95).contains(&dip), "{dip}");
}

#[test]
fn quantile_intervals_cover_a_skewed_distribution() {
    // Log-normal(0, 1): median 1, p95 = exp(1.6449).
    let truth = [(0.5, 1.0f64), (0.95, exp(1.644_853_626_951_472_2))];
    println!("| n | quantile | exact | simulated |");
    for (stream, &n) in [10usize, 200].iter().enumerate() {
        let mut rng = chacha_stream(3600, stream as u64);
        let samples: Vec<Vec<f64>> = (0..SAMPLES)
            .map(|_| {
                let mut v: Vec<f64> = (0..n)
                    .map(|_| {
                        // Box–Muller from two uniforms in (0, 1].
                        let (u1, u2) = (1.0 - rng.random::<f64>(), rng.random::<f64>());
                        exp((-2.0 * ln(u1)).sqrt() * cos(std::f64::consts::TAU * u2))
                    })
                    .collect();
                v.sort_by(f64::total_cmp);
                v
            })
            .collect();
        for &(q, xi) in &truth {
            let (_, _, exact) = quantile_ranks(n as u64, q, 0.95).unwrap();
            let hits = samples.iter().filter(|v| quantile_interval(v, q, 0.95).unwrap().unwrap().contains(xi)).count();
            let sim = hits as f64 / SAMPLES as f64;
            println!("| {n} | {q} | {exact:.4} | {sim:.4} |");
            assert!(agrees(sim, exact), "n={n} q={q}: simulated {sim}, exact {exact}");
            assert!(exact >= 0.95, "n={n} q={q}: {exact}");
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn rate_bounds_are_ordered_and_narrow_with_n(k in 0u64..500, extra in 0u64..500, c in 0.5f64..0.999) {
        let n = k + extra;
        for f in [wilson, clopper_pearson] {
            let i = f(k, n, c).unwrap();
            if n > 0 {
                prop_assert!(i.lo <= i.estimate && i.estimate <= i.hi, "{:?}", i);
                prop_assert!(0.0 <= i.lo && i.hi <= 1.0);
                // The same proportion from four times the runs: narrower.
                let wide = f(4 * k, 4 * n, c).unwrap();
                prop_assert!(wide.width() < i.width(), "{:?} {:?}", i, wide);
            }
        }
    }

    #[test]
    fn quantile_bounds_are_ordered_and_narrow_with_n(
        v in proptest::collection::vec(0.0f64..100.0, 1..300), q in prop_oneof![Just(0.5), Just(0.95)]
    ) {
        let mut v = v;
        v.sort_by(f64::total_cmp);
        let i = quantile_interval(&v, q, 0.95).unwrap().unwrap();
        prop_assert!(i.lo <= i.estimate && i.estimate <= i.hi, "{:?}", i);
    }
}

#[test]
fn quantile_rank_span_narrows_with_n() {
    // The ranks' span as a share of n shrinks as n grows.
    let mut last = f64::INFINITY;
    for n in [20u64, 50, 100, 200, 500, 1000] {
        let (l, u, _) = quantile_ranks(n, 0.5, 0.95).unwrap();
        let share = (u - l) as f64 / n as f64;
        assert!(share < last, "n={n}: {share} ≥ {last}");
        last = share;
    }
}

/// A campaign of three contestants (three pairs, success and error each),
/// looks every `batch` runs up to `max_runs`, on synthetic paired data:
/// errors log-normal with medians `1 + shift[c]`, success probability
/// `rate[c]`. Returns the verdicts of the six tests and the runs flown.
fn campaign(seed: u64, shift: [f64; 3], rate: [f64; 3], batch: u64, max_runs: u64) -> (Vec<Option<Verdict>>, u64) {
    let mut rng = chacha_stream(seed, 7);
    let pairs = [(0usize, 1usize), (0, 2), (1, 2)];
    let mut errors: [Vec<f64>; 3] = Default::default();
    let mut success: [Vec<bool>; 3] = Default::default();
    let mut c = Campaign::new(6, max_runs, 0.05);
    let mut runs = 0;
    while runs < max_runs {
        for _ in 0..batch {
            // One draw shared by the three contestants (the pairing) plus noise of its own.
            let common: f64 = rng.random::<f64>();
            for k in 0..3 {
                let own = rng.random::<f64>();
                errors[k].push((1.0 + shift[k]) * (0.5 + common + 0.5 * own));
                success[k].push(rng.random::<f64>() < rate[k]);
            }
        }
        runs += batch;
        let tests: Vec<_> = pairs
            .iter()
            .flat_map(|&(a, b)| {
                [
                    success_test(&success[a], &success[b], 0.95).unwrap(),
                    error_test(&errors[a], &errors[b], 0.95).unwrap(),
                ]
            })
            .collect();
        c.look(runs, &tests);
        if c.decided().iter().all(Option::is_some) {
            break;
        }
    }
    (c.decided().iter().map(|d| d.map(|(v, _)| v)).collect(), runs)
}

#[test]
fn sequential_campaigns_keep_their_error_rate_without_a_difference() {
    let campaigns = 2000;
    let false_alarms =
        (0..campaigns).filter(|&s| campaign(s, [0.0; 3], [0.9; 3], 20, 200).0.iter().any(Option::is_some)).count();
    let rate = false_alarms as f64 / campaigns as f64;
    println!("no difference: {false_alarms}/{campaigns} campaigns declared one ({:.1} %)", 100.0 * rate);
    assert!(rate <= 0.06, "{rate}");
}

#[test]
fn sequential_campaigns_find_a_real_difference_the_right_way() {
    // Contestant 0 has 10 % lower errors than 1, 20 % lower than 2.
    let campaigns = 200;
    let mut right = 0;
    let mut wrong = 0;
    let mut runs_used = 0;
    for s in 0..campaigns {
        let (v, runs) = campaign(10_000 + s, [0.0, 0.1, 0.2], [0.9; 3], 20, 400);
        runs_used += runs;
        // Tests 1, 3, 5 are the error tests of pairs (0,1), (0,2), (1,2): A better each time.
        for &t in &[1usize, 3, 5] {
            match v[t] {
                Some(Verdict::ABetter) => right += 1,
                Some(Verdict::BBetter) => wrong += 1,
                _ => {}
            }
        }
    }
    let power = right as f64 / (3 * campaigns) as f64;
    println!(
        "10 % / 20 % differences: {right} right, {wrong} wrong of {} ({:.1} % power), mean runs {}",
        3 * campaigns,
        100.0 * power,
        runs_used / campaigns
    );
    assert_eq!(wrong, 0);
    assert!(power >= 0.9, "{power}");
}
