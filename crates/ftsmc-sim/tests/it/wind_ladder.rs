//! The wind ladder's presets (`[wind] preset`, `speed`, `direction`,
//! `altitude`): mean wind by MIL-F-8785C's logarithmic profile, Dryden
//! turbulence carried at the mean wind, and the statistics per rung that
//! docs/results.md reports (mean, σ, share of the u variance below 0.1 Hz),
//! measured on the generator's own samples against the closed forms.
//! Run with `--nocapture` to print the per-rung statistics.

use std::f64::consts::PI;

use ftsmc_sim::environment::wind::{mean_wind_at, TurbulenceParams, Wind, WindParams, WindPreset, FOOT, KNOT};

fn preset(p: WindPreset) -> WindParams {
    WindParams { preset: Some(p), altitude: Some(5.0), ..WindParams::default() }
}

/// Mean, σ and share of variance below 0.1 Hz of the along-wind component
/// `u` of `params`, sampled every `dt` for `segments` segments of `seconds`
/// each: the share is the sum of the one-sided periodogram bins below 0.1 Hz
/// over the variance (Parseval), averaged over the segments.
fn measured(params: WindParams, seed: u64, dt: f64, seconds: f64, segments: usize) -> (f64, f64, f64) {
    let mut w = Wind::new(params, dt, seed).unwrap();
    let e_u = w.axes()[0];
    let n = (seconds / dt).round() as usize;
    let kmax = (0.1 * seconds).round() as usize; // bins k/T < 0.1 Hz
    let (mut sum, mut sum2, mut count) = (0.0, 0.0, 0usize);
    let mut share = 0.0;
    for _ in 0..segments {
        let u: Vec<f64> = (0..n)
            .map(|k| {
                let v = w.step(k as f64 * dt);
                v[0] * e_u[0] + v[1] * e_u[1] + v[2] * e_u[2]
            })
            .collect();
        let mean = u.iter().sum::<f64>() / n as f64;
        sum += u.iter().sum::<f64>();
        sum2 += u.iter().map(|x| x * x).sum::<f64>();
        count += n;
        let var: f64 = u.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        let mut low = 0.0;
        for k in 1..kmax {
            let (mut re, mut im) = (0.0, 0.0);
            for (j, x) in u.iter().enumerate() {
                let a = 2.0 * PI * (k * j) as f64 / n as f64;
                re += (x - mean) * ftsmc_core::math::cos(a);
                im -= (x - mean) * ftsmc_core::math::sin(a);
            }
            low += 2.0 * (re * re + im * im) / (n as f64 * n as f64);
        }
        share += low / var;
    }
    let mean = sum / count as f64;
    (mean, (sum2 / count as f64 - mean * mean).sqrt(), share / segments as f64)
}

#[test]
fn presets_give_the_mean_wind_of_the_log_profile_and_the_8785c_intensities() {
    // u(h) = W20 ln(h/z0)/ln(20 ft/z0), z0 = 0.15 ft: 0.9595 W20 at 5 m.
    let ratio = ftsmc_core::math::ln(5.0 / (0.15 * FOOT)) / ftsmc_core::math::ln(20.0 / 0.15f64);
    assert!((ratio - 0.9595).abs() < 1e-4, "{ratio}");
    assert_eq!(mean_wind_at(15.0 * KNOT, 20.0 * FOOT), 15.0 * KNOT);
    assert_eq!(mean_wind_at(15.0 * KNOT, 0.01), 0.0);
    let table = [
        (WindPreset::Breeze, 2.468, 0.499, 0.93),
        (WindPreset::Light, 7.404, 1.498, 0.80),
        (WindPreset::Moderate, 14.807, 2.995, 0.64),
    ];
    for (p, mean, sigma_u, share) in table {
        let s = preset(p).summary();
        assert!((s.mean_speed - mean).abs() < 2e-3, "{p:?} mean {}", s.mean_speed);
        assert!((s.sigma[0] - sigma_u).abs() < 2e-3, "{p:?} σ_u {}", s.sigma[0]);
        assert!((s.sigma[2] - 0.1 * p.w20()).abs() < 1e-12, "{p:?} σ_w {}", s.sigma[2]);
        assert_eq!(s.airspeed, Some(s.mean_speed), "{p:?}: the Dryden airspeed is the mean wind");
        let got = s.u_share_below_0_1_hz.unwrap();
        assert!((got - share).abs() < 0.01, "{p:?} share {got}");
        // Resolved: the mean along +x, turbulence of the preset's W20 at 5 m.
        let r = preset(p).resolved();
        assert!((r.mean[0] - mean).abs() < 2e-3 && r.mean[1] == 0.0 && r.mean[2] == 0.0, "{:?}", r.mean);
        let t = r.turbulence.unwrap();
        assert_eq!(t.altitude, 5.0);
    }
    // Calm is still air: no mean, no turbulence.
    let calm = preset(WindPreset::Calm).resolved();
    assert_eq!(calm.mean, [0.0; 3]);
    assert!(calm.turbulence.is_none());
}

#[test]
fn the_old_floor_made_the_moderate_turbulence_a_slow_random_wind() {
    // Moderate turbulence at 5 m carried at the 1 m/s floor (the earlier
    // realistic scenarios): 97 % of the u variance below 0.1 Hz; carried at
    // the moderate mean wind (14.8 m/s): 64 %.
    let t = TurbulenceParams { altitude: 5.0, ..TurbulenceParams::moderate() };
    let floor = t.scales().u_variance_share_below(0.1, 1.0);
    assert!(floor > 0.96, "{floor}");
    let carried = preset(WindPreset::Moderate).summary().u_share_below_0_1_hz.unwrap();
    assert!(carried < 0.7, "{carried}");
}

#[test]
fn the_generator_has_the_statistics_of_each_rung() {
    // 20 × 1000 s at 10 Hz per rung (u's corner is at most 0.065 Hz here).
    for (i, p) in [WindPreset::Breeze, WindPreset::Light, WindPreset::Moderate].into_iter().enumerate() {
        let want = preset(p).summary();
        let (mean, sigma, share) = measured(preset(p), 11 + i as u64, 0.1, 1000.0, 20);
        println!(
            "{p:?}: mean {mean:.3} m/s (model {:.3}), σ_u {sigma:.3} m/s (model {:.3}), below 0.1 Hz {:.1} % (model {:.1} %)",
            want.mean_speed,
            want.sigma[0],
            100.0 * share,
            100.0 * want.u_share_below_0_1_hz.unwrap()
        );
        assert!((mean - want.mean_speed).abs() < 0.1 * want.sigma[0], "{p:?} mean {mean}");
        assert!((sigma / want.sigma[0] - 1.0).abs() < 0.1, "{p:?} σ {sigma}");
        // The periodogram misses the variance below 1/T = 1 mHz and leaks
        // a little across 0.1 Hz: a few per cent.
        assert!((share - want.u_share_below_0_1_hz.unwrap()).abs() < 0.06, "{p:?} share {share}");
    }
}

#[test]
fn speed_and_direction_set_the_mean_wind() {
    let w = WindParams { speed: Some(4.0), direction: 90.0, ..WindParams::default() }.resolved();
    assert!(w.mean[0].abs() < 1e-12 && (w.mean[1] - 4.0).abs() < 1e-12, "{:?}", w.mean);
    // A preset's mean wind can be replaced by an explicit speed; its
    // turbulence stays.
    let w = WindParams { speed: Some(1.0), ..preset(WindPreset::Light) }.resolved();
    assert_eq!(w.mean, [1.0, 0.0, 0.0]);
    assert!(w.turbulence.is_some());
    // The wind axes follow the direction.
    let wind = Wind::new(WindParams { direction: 90.0, ..preset(WindPreset::Breeze) }, 0.01, 1).unwrap();
    let e_u = wind.axes()[0];
    assert!(e_u[0].abs() < 1e-12 && (e_u[1] - 1.0).abs() < 1e-12, "{e_u:?}");
}

#[test]
fn presets_from_toml_and_conflicts_are_refused_by_field() {
    let w: WindParams = toml::from_str("preset = \"light\"\ndirection = 45.0\naltitude = 10.0").unwrap();
    assert_eq!(w.preset, Some(WindPreset::Light));
    w.check().unwrap();
    assert!(toml::from_str::<WindParams>("preset = \"hurricane\"").is_err());
    let bad = [
        (WindParams { mean: [1.0, 0.0, 0.0], ..preset(WindPreset::Light) }, "mean"),
        (WindParams { speed: Some(2.0), mean: [1.0, 0.0, 0.0], ..WindParams::default() }, "speed"),
        (WindParams { speed: Some(-1.0), ..WindParams::default() }, "speed"),
        (WindParams { speed: Some(f64::NAN), ..WindParams::default() }, "speed"),
        (WindParams { direction: f64::INFINITY, ..WindParams::default() }, "direction"),
        (WindParams { altitude: Some(0.0), ..preset(WindPreset::Light) }, "altitude"),
        (WindParams { altitude: Some(500.0), ..preset(WindPreset::Light) }, "altitude"),
    ];
    for (p, field) in bad {
        assert_eq!(p.check().unwrap_err().field, field, "{p:?}");
    }
}
