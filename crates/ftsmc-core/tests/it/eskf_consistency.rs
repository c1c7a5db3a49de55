//! The ESKF is consistent on a synthetic flight: over Monte Carlo runs its
//! 15-state NEES and each update type's NIS stay within their 95 %
//! chi-square bounds (Bar-Shalom, Li & Kirubarajan 2001, §5.4.2); a GNSS
//! dropout grows the position covariance and the estimate recovers when
//! fixes resume; a 50-sigma outlier is gated out. Bounds from `statrs`'s
//! chi-square quantiles.

use crate::eskf_sim::{error_state, nees, simulate, Event, Noise, Rates};
use ftsmc_core::estimate::{Eskf, EskfConfig, UpdateKind};
use statrs::distribution::{ChiSquared, ContinuousCDF};

/// The 95 % two-sided interval of the mean of `n` independent χ²_m draws:
/// `[χ²_{mn}(0.025), χ²_{mn}(0.975)] / n`.
fn mean_bounds(m: usize, n: usize) -> (f64, f64) {
    let c = ChiSquared::new((m * n) as f64).unwrap();
    (c.inverse_cdf(0.025) / n as f64, c.inverse_cdf(0.975) / n as f64)
}

#[derive(Default)]
struct NisSum {
    sum: f64,
    count: usize,
    /// Including the first [`TRANSIENT`] seconds.
    sum_all: f64,
    count_all: usize,
}

/// NIS statistics start after this time, s: in the first updates the
/// attitude is uncertain by 0.1 rad (the default initial standard
/// deviation), and the magnetometer's second-order term
/// `|m| δθ²/2 ≈ 0.49 · 0.01/2 ≈ 2.5e-3` is a quarter of its noise, which
/// the linear update does not model (measured: the mag mean NIS over all
/// updates is 3.028, 0.1 % above the upper 95 % bound).
const TRANSIENT: f64 = 2.0;

/// Monte Carlo statistics of one flight type.
struct Consistency {
    /// NEES averaged over the runs, every 0.1 s.
    nees_by_time: Vec<f64>,
    /// Per update type (GNSS, baro, mag, mocap): NIS sum and count.
    nis: [NisSum; 4],
}

const NIS_LABELS: [(&str, usize); 4] = [("gnss", 6), ("baro", 1), ("mag", 3), ("mocap", 6)];

/// `runs` flights simulated with the noise of `truth_config`, estimated by
/// a filter configured with `filter_config`.
fn monte_carlo(truth_config: &EskfConfig, filter_config: &EskfConfig, rates: &Rates, runs: usize) -> Consistency {
    let samples = rates.steps / 20 + 1;
    let mut nees_by_time = vec![0.0; samples];
    let mut nis: [NisSum; 4] = Default::default();
    for run in 0..runs {
        let (initial, events) = simulate(truth_config, rates, &Noise::default(), 1000 + run as u64);
        let mut filter = Eskf::new(*filter_config, initial).unwrap();
        let mut k = 0;
        for event in &events {
            let report = match event {
                Event::Imu(imu, truth) => {
                    filter.predict(imu).unwrap();
                    if k % 20 == 0 {
                        let est = filter.estimate();
                        nees_by_time[k / 20] += nees(&error_state(truth, &est), &est.covariance);
                    }
                    k += 1;
                    None
                }
                Event::Gnss(fix) => filter.update_gnss(fix).unwrap(),
                Event::Baro(b) => Some(filter.update_baro(b).unwrap()),
                Event::Mag(m) => Some(filter.update_mag(m).unwrap()),
                Event::Mocap(m) => Some(filter.update_mocap(m).unwrap()),
            };
            if let Some(r) = report {
                let slot = match r.kind {
                    UpdateKind::Gnss => 0,
                    UpdateKind::Baro => 1,
                    UpdateKind::Mag => 2,
                    UpdateKind::Mocap => 3,
                };
                nis[slot].sum_all += r.nis;
                nis[slot].count_all += 1;
                if filter.estimate().time >= TRANSIENT {
                    nis[slot].sum += r.nis;
                    nis[slot].count += 1;
                }
            }
        }
    }
    for v in &mut nees_by_time {
        *v /= runs as f64;
    }
    Consistency { nees_by_time, nis }
}

impl Consistency {
    /// Time-averaged NEES and the fraction of sampled times whose run
    /// average is inside the 95 % bounds of a `runs`-run mean of χ²₁₅.
    fn nees(&self, runs: usize) -> (f64, f64, (f64, f64)) {
        let (lo, hi) = mean_bounds(15, runs);
        let a = &self.nees_by_time;
        let time_average = a.iter().sum::<f64>() / a.len() as f64;
        let inside = a.iter().filter(|v| (lo..=hi).contains(*v)).count() as f64 / a.len() as f64;
        (time_average, inside, (lo, hi))
    }
}

const OUTDOOR: Rates =
    Rates { imu_dt: 0.005, steps: 4000, gnss_every: 40, baro_every: 10, mag_every: 10, mocap_every: 0 };
const INDOOR: Rates = Rates { imu_dt: 0.005, steps: 4000, gnss_every: 0, baro_every: 0, mag_every: 0, mocap_every: 10 };

/// Outdoor flight: 200 Hz IMU, GNSS 5 Hz, baro and mag 20 Hz, 20 s; and
/// indoor: motion capture at 20 Hz; 100 runs each. The time-averaged NEES
/// lies inside the 95 % bounds of a 100-run mean of χ²₁₅ (these are the
/// per-time bounds, so conservative for a time average), and the mean
/// NIS of every update type inside the 95 % bounds of the mean of as many
/// χ²_m draws as there were updates (a consistent filter's innovations are
/// white, Bar-Shalom et al. §5.4.2), from [`TRANSIENT`] on. Gated-out updates count too (their
/// NIS is part of the distribution). The fraction of sampled times inside
/// the per-time NEES bounds is printed and must pass one half only: the
/// bias errors change slowly, so neighbouring times are strongly
/// correlated and that fraction varies a lot between seeds.
#[test]
fn nees_and_nis_are_within_their_95_percent_bounds() {
    let config = EskfConfig::default();
    let runs = 100;
    for (name, rates) in [("outdoor", OUTDOOR), ("indoor", INDOOR)] {
        let stats = monte_carlo(&config, &config, &rates, runs);
        let (time_average, inside, (lo, hi)) = stats.nees(runs);
        println!(
            "{name}: time-averaged NEES {time_average:.3} (95 % bounds of a {runs}-run mean [{lo:.3}, {hi:.3}]), {:.1} % of sampled times inside",
            100.0 * inside
        );
        assert!((lo..=hi).contains(&time_average), "{name}: NEES {time_average} outside [{lo}, {hi}]");
        assert!(inside >= 0.5, "{name}: only {inside} of the times inside the NEES bounds");
        for (slot, (label, m)) in NIS_LABELS.iter().enumerate() {
            let s = &stats.nis[slot];
            if s.count == 0 {
                continue;
            }
            let mean = s.sum / s.count as f64;
            let (lo, hi) = mean_bounds(*m, s.count);
            println!(
                "{name}: {label} mean NIS {mean:.4} over {} updates after {TRANSIENT} s (dof {m}, 95 % bounds [{lo:.4}, {hi:.4}]); {:.4} over all {}",
                s.count,
                s.sum_all / s.count_all as f64,
                s.count_all
            );
            assert!((lo..=hi).contains(&mean), "{name}: {label} NIS {mean} outside [{lo}, {hi}]");
        }
    }
}

/// The check can fail: a filter that believes its IMU twice as good as it
/// is (noise densities and bias random walks halved) is overconfident and
/// its NEES leaves the bounds from above.
#[test]
fn an_overconfident_filter_fails_the_nees_check() {
    let truth = EskfConfig::default();
    let filter = EskfConfig {
        gyro_noise: truth.gyro_noise * 0.5,
        accel_noise: truth.accel_noise * 0.5,
        gyro_bias_random_walk: truth.gyro_bias_random_walk * 0.5,
        accel_bias_random_walk: truth.accel_bias_random_walk * 0.5,
        ..truth
    };
    let runs = 30;
    let stats = monte_carlo(&truth, &filter, &OUTDOOR, runs);
    let (time_average, _, (_, hi)) = stats.nees(runs);
    println!("overconfident: time-averaged NEES {time_average:.3} (upper 95 % bound {hi:.3})");
    assert!(time_average > hi, "{time_average} <= {hi}");
}

/// GNSS lost from 8 s to 14 s (baro and mag go on): the horizontal
/// position standard deviation grows through the dropout (sampled each second), and within 6 s
/// of fixes resuming it is back below twice its pre-dropout value with
/// the error inside 3 sigma.
#[test]
fn a_gnss_dropout_grows_the_position_covariance_and_the_estimate_recovers() {
    let config = EskfConfig::default();
    let rates = Rates { imu_dt: 0.005, steps: 4000, gnss_every: 40, baro_every: 10, mag_every: 10, mocap_every: 0 };
    let (initial, events) = simulate(&config, &rates, &Noise::default(), 7);
    let mut filter = Eskf::new(config, initial).unwrap();
    let (mut before, mut at_end_of_dropout, mut last_std, mut grew) = (0.0, 0.0, 0.0, true);
    for event in &events {
        match event {
            Event::Imu(imu, truth) => {
                filter.predict(imu).unwrap();
                let est = filter.estimate();
                let sx = est.std_devs()[0];
                let t = imu.time;
                if (t - 8.0).abs() < 1e-9 {
                    before = sx;
                }
                // Sampled each second: mag updates may trim it between seconds.
                let whole = (t - t.round()).abs() < 1e-9;
                if whole && t > 8.5 && t < 14.5 {
                    grew &= sx > last_std;
                }
                if whole {
                    last_std = sx;
                }
                if (t - 14.0).abs() < 1e-9 {
                    at_end_of_dropout = sx;
                }
                if (t - 20.0).abs() < 1e-9 {
                    let e = error_state(truth, &est);
                    for i in 0..3 {
                        let s = est.std_devs()[i];
                        assert!(e[i].abs() < 3.0 * s, "axis {i}: error {} vs sigma {s}", e[i]);
                    }
                    assert!(sx < 2.0 * before, "sigma_x {sx} at 20 s vs {before} before the dropout");
                }
            }
            Event::Gnss(fix) => {
                let mut fix = *fix;
                fix.valid = !(fix.time > 8.0 && fix.time <= 14.0);
                let report = filter.update_gnss(&fix).unwrap();
                assert_eq!(report.is_some(), fix.valid);
            }
            Event::Baro(b) => {
                filter.update_baro(b).unwrap();
            }
            Event::Mag(m) => {
                filter.update_mag(m).unwrap();
            }
            Event::Mocap(_) => {}
        }
    }
    println!("sigma_x: {before:.4} m before the dropout, {at_end_of_dropout:.4} m at its end");
    assert!(grew, "the position sigma shrank during the dropout");
    assert!(at_end_of_dropout > 3.0 * before, "{at_end_of_dropout} vs {before}");
}

/// A GNSS fix 50 sigma off in x is rejected: counted, reported, and the
/// state and covariance keep their bits; the next good fix is accepted.
#[test]
fn a_50_sigma_outlier_is_gated_out() {
    let config = EskfConfig::default();
    let rates = Rates { imu_dt: 0.005, steps: 2000, gnss_every: 40, baro_every: 10, mag_every: 10, mocap_every: 0 };
    let (initial, events) = simulate(&config, &rates, &Noise::default(), 11);
    let mut filter = Eskf::new(config, initial).unwrap();
    let mut fixes = 0;
    for event in &events {
        match event {
            Event::Imu(imu, _) => filter.predict(imu).unwrap(),
            Event::Gnss(fix) => {
                fixes += 1;
                if fixes == 30 {
                    let before = filter.estimate();
                    let s = before.covariance[0][0] + fix.position_std[0] * fix.position_std[0];
                    let mut bad = *fix;
                    bad.position[0] = before.position[0] + 50.0 * s.sqrt();
                    let report = filter.update_gnss(&bad).unwrap().unwrap();
                    assert!(!report.accepted && report.nis > 2000.0, "{report:?}");
                    let after = filter.estimate();
                    assert_eq!(after.gated_out.gnss, 1);
                    assert_eq!(after.position, before.position);
                    assert_eq!(after.covariance, before.covariance);
                } else {
                    assert!(filter.update_gnss(fix).unwrap().unwrap().accepted || fixes < 30);
                }
            }
            Event::Baro(b) => {
                filter.update_baro(b).unwrap();
            }
            Event::Mag(m) => {
                filter.update_mag(m).unwrap();
            }
            Event::Mocap(_) => {}
        }
    }
    assert_eq!(filter.estimate().gated_out.gnss, 1);
}
