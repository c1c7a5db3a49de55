//! Adaptive multilevel splitting (`ftsmc_sim::falsify::splitting`) on a
//! problem whose failure is driven by many noise inputs and whose failure
//! probability is known: a Gaussian random walk of [`STEPS`] steps
//! crossing a barrier `b`.
//!
//! The reference `p = P(max_{j ≤ n} S_j > b)`, `S_j = X_1 + … + X_j`,
//! `X_i ~ N(0, 1)`, is computed by the density recursion of the walk killed
//! at the barrier, `f_{j+1}(x) = ∫_{−∞}^{b} f_j(y) φ(x − y) dy`,
//! `p = Σ_j ∫ f_j(y) (1 − Φ(b − y)) dy` (the mass killed at each step,
//! summed: no `1 − (1 − p)` cancellation), trapezoid rule on a grid of
//! step [`GRID`]. That recursion is the exact law of the discrete walk up
//! to its quadrature error, which the tests bound: it agrees with itself at
//! half the grid step, with the closed form `1 − Φ(b)` of one step, and
//! with the Sparre Andersen theorem at `b = 0`,
//! `P(S_1 ≤ 0, …, S_n ≤ 0) = C(2n, n)/4ⁿ` for any symmetric continuous
//! step law (Feller 1971, "An introduction to probability theory and its
//! applications", vol. II, §XII.7). No approximation (the Brownian one with
//! Siegmund's correction is off by 5 % at 50 steps) is a reference.
//!
//! The longer coverage sweep is `#[ignore]`d:
//! `cargo test -p ftsmc-sim --release --test splitting -- --ignored`.

use ftsmc_sim::falsify::splitting::{estimate, Estimate, Settings, Splitting};
use ftsmc_sim::rng::chacha_stream;
use rand::Rng;

/// Steps of the walk.
const STEPS: usize = 50;
/// Grid step of the reference recursion.
const GRID: f64 = 0.02;

fn phi(x: f64) -> f64 {
    ftsmc_core::math::exp(-0.5 * x * x) / (2.0 * core::f64::consts::PI).sqrt()
}

/// `P(max_{j ≤ steps} S_j > b)` by the killed-density recursion on a grid of step `h`.
fn reference_p(b: f64, steps: usize, h: f64) -> f64 {
    // Grid x_i = b − i h, i = 0..m, down to 7 standard deviations of the
    // walk's end below 0 (the mass below is negligible).
    let low = -7.0 * (steps as f64).sqrt();
    let m = ((b - low) / h).ceil() as usize;
    let width = (9.0 / h).ceil() as usize;
    let kernel: Vec<f64> = (0..=width).map(|d| phi(d as f64 * h)).collect();
    let sf = |x: f64| ftsmc_sim::stats::normal_sf(x);
    // Step 1 from S_0 = 0: killed mass 1 − Φ(b); density φ(x) below b.
    let mut p = sf(b);
    let mut f: Vec<f64> = (0..=m).map(|i| phi(b - i as f64 * h)).collect();
    let trapezoid = |i: usize| if i == 0 || i == m { 0.5 * h } else { h };
    for _ in 1..steps {
        p += (0..=m).map(|i| trapezoid(i) * f[i] * sf(i as f64 * h)).sum::<f64>();
        let next: Vec<f64> = (0..=m)
            .map(|i| {
                let (a, z) = (i.saturating_sub(width), (i + width).min(m));
                (a..=z).map(|j| trapezoid(j) * f[j] * kernel[i.abs_diff(j)]).sum()
            })
            .collect();
        f = next;
    }
    p
}

/// The walk: a path of positions `S_1 … S_n`; its running margin
/// `b − max_{i ≤ j} S_i`.
struct Walk {
    barrier: f64,
}

#[derive(Clone)]
struct Path {
    positions: Vec<f64>,
}

impl Walk {
    /// Extend `positions` to [`STEPS`] with normals of stream 0 of `key`.
    fn continue_from(&self, mut positions: Vec<f64>, key: u64) -> Path {
        let mut rng = chacha_stream(key, 0);
        let mut s = positions.last().copied().unwrap_or(0.0);
        while positions.len() < STEPS {
            s += ftsmc_sim::gauss::standard_normal(&mut rng);
            positions.push(s);
        }
        Path { positions }
    }
}

impl Splitting for Walk {
    type Path = Path;

    fn start(&self, key: u64) -> Path {
        self.continue_from(Vec::with_capacity(STEPS), key)
    }

    fn margin(&self, path: &Path) -> f64 {
        self.barrier - path.positions.iter().copied().fold(f64::NEG_INFINITY, f64::max)
    }

    fn branch(&self, parent: &Path, level: f64, key: u64) -> Path {
        // The first step whose running margin b − max S is below the level.
        let j = parent.positions.iter().position(|&s| self.barrier - s < level).expect("the parent is below the level");
        self.continue_from(parent.positions[..=j].to_vec(), key)
    }
}

/// Barriers of p ≈ 1e-2, 1e-3, 1e-5 (the exact p of each is [`reference_p`]'s).
const BARRIERS: [(f64, f64); 3] = [(1e-2, 17.63), (1e-3, 22.68), (1e-5, 30.65)];

/// 20 repetitions of 200 particles: the t interval over fewer repetitions
/// (10 of 100 were tried) is as wide as the estimate at 1e-5 (mean relative
/// half-width 0.72) and undercovers there (0.85 over 40 seeds), the
/// repetitions' estimates being right-skewed.
fn settings() -> Settings {
    Settings::new(200, 20, 2_000_000, 0.95)
}

/// `C(2n, n)/4ⁿ` as a product, `Π_{k=1}^{n} (2k − 1)/(2k)` (no overflow).
fn sparre_andersen(n: usize) -> f64 {
    (1..=n).map(|k| (2 * k - 1) as f64 / (2 * k) as f64).product()
}

/// The reference recursion is exact where a closed form exists (one step;
/// the Sparre Andersen theorem at `b = 0` for 1, 2, 10 and 50 steps, to
/// 1e-4 relative: the trapezoid error is largest at b = 0, where the mass sits at the barrier), agrees with itself at half the grid step (2e-3
/// relative), and the barriers give the probabilities they are named for.
#[test]
fn the_reference_is_exact_where_known_and_converged() {
    for b in [0.0, 1.5, 3.0] {
        let exact = ftsmc_sim::stats::normal_sf(b);
        let p = reference_p(b, 1, GRID);
        assert!((p / exact - 1.0).abs() < 1e-12, "one step, b = {b}: {p:e} against {exact:e}");
    }
    for n in [2, 10, STEPS] {
        let exact = 1.0 - sparre_andersen(n);
        let p = reference_p(0.0, n, GRID);
        assert!((p / exact - 1.0).abs() < 1e-4, "b = 0, {n} steps: {p:.9} against Sparre Andersen's {exact:.9}");
    }
    for (target, b) in BARRIERS {
        let p = reference_p(b, STEPS, GRID);
        let fine = reference_p(b, STEPS, GRID / 2.0);
        assert!((p / fine - 1.0).abs() < 2e-3, "b = {b}: {p:e} at h = {GRID}, {fine:e} at h/2");
        assert!(p > 0.8 * target && p < 1.25 * target, "b = {b}: p = {p:e}, meant ≈ {target:e}");
    }
}

/// Plain Monte Carlo of the walk agrees with the reference at p ≈ 1e-2
/// (the walk and the margin are what the reference describes).
#[test]
fn plain_monte_carlo_of_the_walk_matches_the_reference() {
    let (_, b) = BARRIERS[0];
    let walk = Walk { barrier: b };
    let n = 40_000u64;
    let mut keys = chacha_stream(99, 0);
    let failures = (0..n).filter(|_| walk.margin(&walk.start(keys.next_u64())) < 0.0).count() as u64;
    let i = ftsmc_sim::stats::rate::wilson(failures, n, 0.999).unwrap();
    let p = reference_p(b, STEPS, GRID);
    assert!(i.lo <= p && p <= i.hi, "{failures}/{n}: [{}, {}] misses {p:e}", i.lo, i.hi);
}

/// Coverage of the interval over `seeds` seeds at barrier `b`: the share of
/// intervals holding the reference, and the mean relative half-width.
fn coverage(b: f64, seeds: u64, settings: Settings) -> (f64, f64, Vec<Estimate>) {
    let p = reference_p(b, STEPS, GRID);
    let walk = Walk { barrier: b };
    let estimates: Vec<Estimate> = (0..seeds).map(|s| estimate(&walk, settings, 1000 + s).unwrap()).collect();
    let covered = estimates.iter().filter(|e| e.lo <= p && p <= e.hi).count() as f64 / seeds as f64;
    let width = estimates.iter().map(|e| 0.5 * (e.hi - e.lo) / p).sum::<f64>() / seeds as f64;
    (covered, width, estimates)
}

/// The nominal 95 % less three binomial standard errors of `seeds` seeds.
fn lowest_coverage(seeds: u64) -> f64 {
    0.95 - 3.0 * (0.95f64 * 0.05 / seeds as f64).sqrt()
}

/// At p ≈ 1e-2, 1e-3 and 1e-5 the 95 % interval holds the known p for all
/// but a Monte Carlo error's share of 40 seeds, every estimate is reliable
/// at these settings, the intervals are informative (mean relative
/// half-width below 0.6), and the estimate is unbiased within its error.
#[test]
fn the_interval_covers_the_known_probability() {
    let seeds = 40;
    for (target, b) in BARRIERS {
        let p = reference_p(b, STEPS, GRID);
        let (covered, width, estimates) = coverage(b, seeds, settings());
        let reliable = estimates.iter().filter(|e| e.reliable).count();
        let mean = estimates.iter().map(|e| e.p).sum::<f64>() / seeds as f64;
        let spread = (estimates.iter().map(|e| (e.p - mean) * (e.p - mean)).sum::<f64>() / (seeds - 1) as f64).sqrt();
        let flights = estimates.iter().map(|e| e.flights as f64).sum::<f64>() / seeds as f64;
        eprintln!(
            "p = {p:.3e} (≈ {target:e}): coverage {covered:.3}, mean relative half-width {width:.3}, \
             mean {mean:.3e} (sd of estimates {spread:.2e}), {reliable}/{seeds} reliable, {flights:.0} flights"
        );
        assert!(covered >= lowest_coverage(seeds), "p = {p:e}: coverage {covered} of {seeds} seeds");
        assert_eq!(reliable, seeds as usize, "p = {p:e}");
        assert!(width < 0.6, "p = {p:e}: mean relative half-width {width}");
        let z = (mean - p) / (spread / (seeds as f64).sqrt());
        assert!(z.abs() < 4.0, "p = {p:e}: mean of estimates {mean:e}, {z:.1} standard errors off");
    }
}

/// Longer sweep: 200 seeds at each p (about a minute in release).
#[test]
#[ignore]
fn the_interval_covers_the_known_probability_over_200_seeds() {
    for (_, b) in BARRIERS {
        let (covered, width, _) = coverage(b, 200, settings());
        eprintln!("b = {b}: coverage {covered:.3}, mean relative half-width {width:.3}");
        assert!(covered >= lowest_coverage(200), "b = {b}: coverage {covered}");
    }
}

/// Tiny budgets and too few repetitions are flagged unreliable, with settings to try.
#[test]
fn tiny_budgets_are_unreliable() {
    let walk = Walk { barrier: BARRIERS[2].1 };
    // The budget only starts the particles: no level can be split.
    let starved = estimate(&walk, Settings::new(20, 10, 200, 0.95), 5).unwrap();
    assert!(!starved.reliable, "{starved:?}");
    assert!(starved.repetitions.iter().all(|r| !r.finished));
    let s = starved.suggested().expect("a suggestion");
    assert!(s.particles > 20 && s.budget > 200);
    assert!(starved.plain_mc_equivalent().is_nan() && starved.flights_for_cov(0.3).is_nan());
    // Two repetitions: t on one degree of freedom.
    let few = estimate(&walk, Settings::new(50, 2, 1_000_000, 0.95), 5).unwrap();
    assert!(few.repetitions.iter().all(|r| r.finished));
    assert!(!few.reliable);
    // Three particles: extinction is common at 1e-5.
    let tiny = estimate(&walk, Settings::new(3, 10, 1_000_000, 0.95), 5).unwrap();
    assert!(tiny.repetitions.iter().any(|r| r.extinct), "{tiny:?}");
    assert!(!tiny.reliable);
}

/// The same seed gives the same bits on 1, 2 and 3 threads; another seed another estimate.
#[test]
fn bits_do_not_depend_on_threads() {
    let walk = Walk { barrier: BARRIERS[1].1 };
    let run = |threads: usize, seed: u64| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| estimate(&walk, Settings::new(40, 6, 1_000_000, 0.95), seed).unwrap())
    };
    let one = run(1, 8);
    for threads in [2, 3] {
        let other = run(threads, 8);
        assert_eq!(one.p.to_bits(), other.p.to_bits(), "{threads} threads");
        assert_eq!(one, other, "{threads} threads");
    }
    assert_ne!(one.p.to_bits(), run(2, 9).p.to_bits());
}

/// realistic-breeze-1 (turbulence, sensor noise) cut to 4 s with the
/// envelope checked from 3 s, flown by PID: a real flight's whole random
/// input, failing in about one flight of six (a tighter envelope, 0.05 m
/// and 0.05 rad from 1 s, failed every flight, so no level was ever split
/// and the thread-count check below had nothing to compare).
fn breeze() -> ftsmc_sim::falsify::FlightSplitting {
    let text = "extends = \"realistic-breeze-1\"\nname = \"short-breeze\"\nduration = 4.0\n\
                [envelope]\nsettle_after = 3.0\nmax_position_error = 0.3\nmax_tilt = 0.8\n\
                [falsify]\nwind_speed = { low = 0.0, high = 3.0 }\n";
    let base =
        ftsmc_sim::scenario::Scenario::from_toml_str(text, "short-breeze.toml").unwrap_or_else(|e| panic!("{e}"));
    assert!(ftsmc_sim::falsify::noise_driven(&base), "breeze flights draw noise");
    ftsmc_sim::falsify::FlightSplitting { problem: ftsmc_sim::falsify::Problem::new(&base, "pid").unwrap() }
}

/// A branch of a real flight is its parent up to the branch boundary —
/// the same running margins, bit for bit — and a flight of its own after
/// it (fresh turbulence and sensor noise); flying it again gives the same bits.
#[test]
fn a_branched_flight_is_its_parent_up_to_the_branch() {
    let problem = breeze();
    let parent = problem.start(11);
    assert!(parent.record.len() > 3, "the running margin falls over the flight: {:?}", parent.record);
    // Branch where the running margin first fell below its middle value.
    let (k, m) = parent.record[parent.record.len() / 2];
    let level = (m + parent.record[parent.record.len() / 2 - 1].1) / 2.0;
    let child = problem.branch(&parent, level, 99);
    assert_eq!(child.reseeds, vec![(k, 99)]);
    let before = |p: &ftsmc_sim::falsify::FlightPath| -> Vec<(u64, u64)> {
        p.record.iter().filter(|r| r.0 <= k).map(|r| (r.0, r.1.to_bits())).collect()
    };
    assert_eq!(before(&child), before(&parent));
    let after = |p: &ftsmc_sim::falsify::FlightPath| -> Vec<(u64, u64)> {
        p.record.iter().filter(|r| r.0 > k).map(|r| (r.0, r.1.to_bits())).collect()
    };
    assert_ne!(after(&child), after(&parent), "fresh noise after the branch");
    let again = problem.branch(&parent, level, 99);
    assert_eq!(again.margin.to_bits(), child.margin.to_bits());
    assert_eq!(again.record, child.record);
    // A branch of the branch keeps the first reseed and adds its own.
    let last = child.record.last().unwrap();
    let grandchild = problem.branch(&child, last.1 + 1e-12, 5);
    assert_eq!(grandchild.reseeds[0], (k, 99));
    assert_eq!(grandchild.reseeds.len(), 2);
}

/// Splitting of real flights gives the same bits on 1 and 3 threads.
#[test]
fn real_flight_splitting_does_not_depend_on_threads() {
    let problem = breeze();
    let settings = Settings { particles: 4, kill: 1, repetitions: 2, budget: 24, confidence: 0.95 };
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| estimate(&problem, settings, 3).unwrap())
    };
    let one = run(1);
    assert!(one.flights > 8, "some levels were split: {one:?}");
    assert_eq!(one, run(3));
}
