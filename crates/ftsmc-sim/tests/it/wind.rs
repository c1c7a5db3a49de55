//! Wind model (`environment/wind.rs`): 1−cosine gust shape, Dryden scales
//! against hand computation, the turbulence generator against its analytic
//! spectrum (Welch PSD) and variance, determinism per seed, stream
//! independence, parameter files and range checks.
//!
//! PSD conventions used here: the analytic `Φ(ω)` of the module is one-sided
//! in rad/s (∫₀^∞ Φ dω = σ²); the Welch estimate is one-sided in Hz
//! (∫₀^{fs/2} P df = variance), so `S(f) = 2π Φ(2πf)`. The generator is an
//! exact discretisation, so the sampled sequence's spectrum is the aliased
//! continuous one, `S_a(f) = Σ_m S(|f + m fs|)`, which is what is compared.

use std::f64::consts::PI;

use ftsmc_sim::actuators::MOTOR_NOISE_STREAM;
use ftsmc_sim::environment::wind::{
    Dryden, Gust, Intensity, TurbulenceParams, Wind, WindParams, KNOT, WIND_TURBULENCE_STREAMS,
};

// ---------------------------------------------------------------- gusts

#[test]
fn one_minus_cosine_gust_shape() {
    let g = Gust { start: 2.0, duration: 4.0, amplitude: [3.0, -2.0, 1.0] };
    // Zero outside, and at both ends.
    for t in [0.0, 1.999, 2.0, 6.0, 6.001, 100.0] {
        for c in g.velocity(t) {
            assert!(c.abs() < 1e-12, "t = {t}: {c}");
        }
    }
    // Peak A at mid-gust.
    let mid = g.velocity(4.0);
    for (m, a) in mid.iter().zip(g.amplitude) {
        assert!((m - a).abs() < 1e-12);
    }
    // Half amplitude at the quarter points; symmetric.
    let q = g.velocity(3.0);
    let q3 = g.velocity(5.0);
    for i in 0..3 {
        assert!((q[i] - 0.5 * g.amplitude[i]).abs() < 1e-12);
        assert!((q3[i] - q[i]).abs() < 1e-12);
    }
    // Continuous (and C¹): the value near the ends is O(ε²).
    let eps = 1e-4;
    for t in [2.0 + eps, 6.0 - eps] {
        let v = g.velocity(t)[0];
        assert!(v.abs() < 3.0 * (PI * eps / 4.0).powi(2) * 1.01 + 1e-15, "{v}");
    }
    // Matches the formula everywhere inside.
    for k in 0..=400 {
        let t = 2.0 + 4.0 * k as f64 / 400.0;
        let want = 0.5 * (1.0 - ftsmc_core::math::cos(2.0 * PI * (t - 2.0) / 4.0));
        assert!((g.velocity(t)[1] - (-2.0) * want).abs() < 1e-12);
    }
}

#[test]
fn mean_plus_gusts_in_the_wind() {
    let params = WindParams {
        mean: [1.0, 2.0, 0.0],
        gusts: vec![
            Gust { start: 1.0, duration: 2.0, amplitude: [0.0, 0.0, 4.0] },
            Gust { start: 1.5, duration: 1.0, amplitude: [2.0, 0.0, 0.0] },
        ],
        turbulence: None,
        ..WindParams::default()
    };
    let mut w = Wind::new(params, 0.01, 7).unwrap();
    assert_eq!(w.step(0.0), [1.0, 2.0, 0.0]);
    let v = w.step(2.0);
    assert!((v[0] - 3.0).abs() < 1e-12 && (v[1] - 2.0).abs() < 1e-12 && (v[2] - 4.0).abs() < 1e-12, "{v:?}");
    assert_eq!(w.step(3.5), [1.0, 2.0, 0.0]);
}

// ---------------------------------------------------------------- scales

#[test]
fn moderate_scales_at_10_m_match_hand_computation() {
    // h = 10 m = 32.8084 ft; 0.177 + 0.000823 h = 0.2040013;
    // W20 = 30 kt = 15.4333 m/s; σ_w = 1.54333 m/s;
    // σ_u = σ_v = 1.54333 / 0.2040013^0.4 = 2.914785 m/s;
    // L_u = L_v = 32.8084 ft / 0.2040013^1.2 = 221.02 ft = 67.36595 m; L_w = 10 m.
    let s = TurbulenceParams::moderate().scales();
    let close = |a: f64, b: f64| (a - b).abs() < 1e-5 * b;
    assert!(close(s.sigma[2], 1.543_333), "{s:?}");
    assert!(close(s.sigma[0], 2.914_785) && close(s.sigma[1], 2.914_785), "{s:?}");
    assert!(close(s.length[0], 67.365_95) && close(s.length[1], 67.365_95), "{s:?}");
    assert!(close(s.length[2], 10.0), "{s:?}");
    assert!((Intensity::Light.w20() - 7.716_667).abs() < 1e-5);
    assert!((Intensity::Moderate.w20() - 15.433_333).abs() < 1e-5);
    assert!((Intensity::Severe.w20() - 23.15).abs() < 1e-5);
    assert!((KNOT - 0.514_444).abs() < 1e-6);
}

// ---------------------------------------------------------------- spectrum

/// One-sided temporal PSD per rad/s, MIL-F-8785C form (the module's).
fn phi(axis: usize, sigma: f64, l: f64, v: f64, omega: f64) -> f64 {
    let lo = l * omega / v; // L Ω
    let spatial = if axis == 0 {
        sigma * sigma * (2.0 * l / PI) / (1.0 + lo * lo)
    } else {
        sigma * sigma * (l / PI) * (1.0 + 3.0 * lo * lo) / (1.0 + lo * lo).powi(2)
    };
    spatial / v
}

/// In-place iterative radix-2 FFT.
fn fft(re: &mut [f64], im: &mut [f64]) {
    let n = re.len();
    assert!(n.is_power_of_two());
    let mut j = 0;
    for i in 1..n {
        let mut bit = n >> 1;
        while j & bit != 0 {
            j ^= bit;
            bit >>= 1;
        }
        j |= bit;
        if i < j {
            re.swap(i, j);
            im.swap(i, j);
        }
    }
    let mut len = 2;
    while len <= n {
        let ang = -2.0 * PI / len as f64;
        let (wr, wi) = (ftsmc_core::math::cos(ang), ftsmc_core::math::sin(ang));
        for start in (0..n).step_by(len) {
            let (mut cr, mut ci) = (1.0, 0.0);
            for k in 0..len / 2 {
                let (a, b) = (start + k, start + k + len / 2);
                let tr = re[b] * cr - im[b] * ci;
                let ti = re[b] * ci + im[b] * cr;
                re[b] = re[a] - tr;
                im[b] = im[a] - ti;
                re[a] += tr;
                im[a] += ti;
                let ncr = cr * wr - ci * wi;
                ci = cr * wi + ci * wr;
                cr = ncr;
            }
        }
        len <<= 1;
    }
}

/// Welch one-sided PSD per Hz, Hann windows, 50 % overlap; bins 0..nseg/2.
fn welch(x: &[f64], nseg: usize, dt: f64) -> Vec<f64> {
    let w: Vec<f64> = (0..nseg).map(|i| 0.5 - 0.5 * ftsmc_core::math::cos(2.0 * PI * i as f64 / nseg as f64)).collect();
    let wss: f64 = w.iter().map(|v| v * v).sum();
    let mut acc = vec![0.0; nseg / 2 + 1];
    let mut count = 0;
    let mut start = 0;
    let (mut re, mut im) = (vec![0.0; nseg], vec![0.0; nseg]);
    while start + nseg <= x.len() {
        for i in 0..nseg {
            re[i] = x[start + i] * w[i];
            im[i] = 0.0;
        }
        fft(&mut re, &mut im);
        for (k, a) in acc.iter_mut().enumerate() {
            *a += re[k] * re[k] + im[k] * im[k];
        }
        count += 1;
        start += nseg / 2;
    }
    acc.iter().map(|a| 2.0 * a * dt / (wss * count as f64)).collect()
}

const DT: f64 = 0.01;
const N: usize = 1 << 20;
const V: f64 = 10.0;

fn sample(seed: u64, airspeed: f64) -> (Dryden, [Vec<f64>; 3]) {
    let mut d = Dryden::new(TurbulenceParams::moderate(), DT, airspeed, seed);
    let mut out = [Vec::with_capacity(N), Vec::with_capacity(N), Vec::with_capacity(N)];
    for _ in 0..N {
        let s = d.step();
        for k in 0..3 {
            out[k].push(s[k]);
        }
    }
    (d, out)
}

/// Welch/analytic ratios in log-spaced bands between max(1/(10 T_L), 4 df)
/// and Nyquist/3, per axis, for a sample at airspeed `v`.
fn psd_band_ratios(seed: u64, v: f64) -> [Vec<f64>; 3] {
    let (d, x) = sample(seed, v);
    let v = d.airspeed(); // the floor applies
    let sc = d.scales();
    let nseg = 1 << 14;
    let mut out: [Vec<f64>; 3] = Default::default();
    let fs = 1.0 / DT;
    let df = fs / nseg as f64;
    for axis in 0..3 {
        let p = welch(&x[axis], nseg, DT);
        let (sigma, l) = (sc.sigma[axis], sc.length[axis]);
        let t_l = l / v;
        let s_alias = |f: f64| -> f64 {
            (-200i32..=200).map(|m| 2.0 * PI * phi(axis, sigma, l, v, 2.0 * PI * (f + m as f64 * fs).abs())).sum()
        };
        let f_lo = (1.0 / (10.0 * t_l)).max(4.0 * df);
        let f_hi = fs / 6.0; // Nyquist / 3
        let bands = 10;
        let mut ratios = Vec::new();
        for b in 0..bands {
            let e0 = f_lo * ftsmc_core::math::powf(f_hi / f_lo, b as f64 / bands as f64);
            let e1 = f_lo * ftsmc_core::math::powf(f_hi / f_lo, (b + 1) as f64 / bands as f64);
            let (mut est, mut ana) = (0.0, 0.0);
            for (k, pk) in p.iter().enumerate() {
                let f = k as f64 * df;
                if f >= e0 && f < e1 {
                    est += pk;
                    ana += s_alias(f);
                }
            }
            if ana > 0.0 {
                ratios.push(est / ana);
            }
        }
        eprintln!("V = {v} m/s, axis {axis}: f in [{f_lo:.4}, {f_hi:.2}] Hz, Welch/analytic per band: {ratios:.3?}");
        out[axis] = ratios;
    }
    out
}

fn assert_ratios(ratios: &[Vec<f64>; 3]) {
    for (axis, r) in ratios.iter().enumerate() {
        assert!(r.len() >= 8, "{r:?}");
        for x in r {
            assert!((0.7..=1.3).contains(x), "axis {axis}: band ratio {x} outside ±30 %: {r:?}");
        }
        let mean = r.iter().sum::<f64>() / r.len() as f64;
        assert!((mean - 1.0).abs() < 0.1, "axis {axis}: mean ratio {mean}");
    }
}

#[test]
fn dryden_welch_psd_matches_the_analytic_spectrum() {
    // 2^20 steps at dt = 0.01 s (10486 s), V = 10 m/s, moderate, h = 10 m:
    // T_u = T_v = L/V = 6.74 s, T_w = 1 s. Segments of 2^14 (df = 0.0061 Hz).
    assert_ratios(&psd_band_ratios(2024, V));
}

#[test]
fn dryden_welch_psd_at_the_hover_airspeed_floor() {
    // Hover: V = airspeed floor = 1 m/s (T_u = 67 s, T_w = 10 s).
    assert_ratios(&psd_band_ratios(77, 0.0));
}

#[test]
fn dryden_variance_is_sigma_squared() {
    for seed in [1, 2, 3] {
        let (d, x) = sample(seed, V);
        for axis in 0..3 {
            let s = d.scales().sigma[axis];
            let mean = x[axis].iter().sum::<f64>() / N as f64;
            let var = x[axis].iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / N as f64;
            eprintln!("seed {seed} axis {axis}: var / σ² = {:.4}, mean {mean:+.4} m/s", var / (s * s));
            assert!((var / (s * s) - 1.0).abs() < 0.1, "seed {seed} axis {axis}: var {var}, σ² {}", s * s);
        }
    }
}

// ---------------------------------------------------------------- airspeed, frame

#[test]
fn airspeed_floor_and_wind_axes() {
    let turb = Some(TurbulenceParams::moderate());
    let calm = Wind::new(WindParams { turbulence: turb, ..WindParams::default() }, DT, 1).unwrap();
    assert_eq!(calm.turbulence().unwrap().airspeed(), 1.0);
    assert_eq!(calm.axes(), [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
    let mut windy =
        Wind::new(WindParams { mean: [3.0, 4.0, 0.0], turbulence: turb, ..WindParams::default() }, DT, 1).unwrap();
    assert_eq!(windy.turbulence().unwrap().airspeed(), 5.0);
    let a = windy.axes();
    assert!((a[0][0] - 0.6).abs() < 1e-15 && (a[0][1] - 0.8).abs() < 1e-15);
    assert!((a[1][0] + 0.8).abs() < 1e-15 && (a[1][1] - 0.6).abs() < 1e-15);
    windy.set_airspeed(0.2);
    assert_eq!(windy.turbulence().unwrap().airspeed(), 1.0);
    windy.set_airspeed(12.0);
    assert_eq!(windy.turbulence().unwrap().airspeed(), 12.0);
}

// ---------------------------------------------------------------- determinism, streams

fn turbulent(seed: u64, gusts: Vec<Gust>) -> Vec<[f64; 3]> {
    let params = WindParams { gusts, turbulence: Some(TurbulenceParams::moderate()), ..WindParams::default() };
    let mut w = Wind::new(params, DT, seed).unwrap();
    (0..2000).map(|k| w.step(k as f64 * DT)).collect()
}

#[test]
fn deterministic_per_seed_and_gusts_leave_turbulence_unchanged() {
    let a = turbulent(5, vec![]);
    assert_eq!(a, turbulent(5, vec![]));
    assert_ne!(a, turbulent(6, vec![]));
    let g = Gust { start: 5.0, duration: 4.0, amplitude: [1.0, 2.0, -3.0] };
    let b = turbulent(5, vec![g]);
    for (k, (x, y)) in a.iter().zip(&b).enumerate() {
        let gv = g.velocity(k as f64 * DT);
        for i in 0..3 {
            assert!((y[i] - x[i] - gv[i]).abs() < 1e-12);
        }
    }
}

#[test]
fn turbulence_streams_are_distinct_from_the_other_sources() {
    for s in WIND_TURBULENCE_STREAMS {
        assert!(!(1..=6).contains(&s), "drag noise uses streams 1-6");
        assert_ne!(s, MOTOR_NOISE_STREAM);
        assert!(s < 100, "Monte Carlo sampling uses streams 100+");
    }
    let mut sorted = WIND_TURBULENCE_STREAMS;
    sorted.sort_unstable();
    assert!(sorted.windows(2).all(|w| w[0] != w[1]));
}

// ---------------------------------------------------------------- files and checks

const FILE: &str = r#"
mean = [3.0, 0.0, 0.0]

[[gusts]]
start = 1.0
duration = 2.0
amplitude = [0.0, 5.0, 0.0]

[turbulence]
intensity = "moderate"
altitude = 20.0
"#;

#[test]
fn params_from_toml_defaults_and_round_trip() {
    let p: WindParams = toml::from_str(FILE).unwrap();
    assert_eq!(p.mean, [3.0, 0.0, 0.0]);
    assert_eq!(p.gusts.len(), 1);
    let t = p.turbulence.unwrap();
    assert_eq!(t.intensity, Intensity::Moderate);
    assert_eq!(t.altitude, 20.0);
    assert_eq!(t.airspeed_floor, 1.0);
    p.check().unwrap();
    let back: WindParams = toml::from_str(&toml::to_string(&p).unwrap()).unwrap();
    assert_eq!(back, p);

    let w20: WindParams = toml::from_str("[turbulence]\nintensity = { w20 = 7.5 }\n").unwrap();
    let t = w20.turbulence.unwrap();
    assert_eq!(t.intensity, Intensity::W20(7.5));
    assert_eq!(t.altitude, 10.0);
    let back: WindParams = toml::from_str(&toml::to_string(&w20).unwrap()).unwrap();
    assert_eq!(back, w20);

    let still: WindParams = toml::from_str("").unwrap();
    assert_eq!(still, WindParams::default());
    assert_eq!(toml::from_str::<WindParams>(&toml::to_string(&still).unwrap()).unwrap(), still);
}

#[test]
fn unknown_keys_and_names_are_rejected() {
    for bad in [
        "turbulance = { intensity = \"light\" }",
        "[turbulence]\nintensity = \"light\"\nsigma = 1.0",
        "[turbulence]\nintensity = \"extreme\"",
        "[turbulence]\nintensity = { w21 = 3.0 }",
        "[turbulence]\naltitude = 10.0",
        "[[gusts]]\nstrat = 1.0\nduration = 1.0\namplitude = [0.0, 0.0, 0.0]",
        "mean = [1.0, 2.0]",
    ] {
        assert!(toml::from_str::<WindParams>(bad).is_err(), "accepted: {bad}");
    }
}

#[test]
fn bad_values_are_rejected_with_their_field() {
    let turb = |f: &dyn Fn(&mut TurbulenceParams)| {
        let mut t = TurbulenceParams::moderate();
        f(&mut t);
        WindParams { turbulence: Some(t), ..WindParams::default() }
    };
    let gust = |start: f64, duration: f64, a: f64| WindParams {
        gusts: vec![Gust { start, duration, amplitude: [0.0, a, 0.0] }],
        ..WindParams::default()
    };
    let cases: Vec<(WindParams, &str)> = vec![
        (WindParams { mean: [f64::NAN, 0.0, 0.0], ..WindParams::default() }, "mean"),
        (WindParams { mean: [0.0, 0.0, 1e3], ..WindParams::default() }, "mean"),
        (gust(-1.0, 1.0, 1.0), "gusts.start"),
        (gust(0.0, 0.0, 1.0), "gusts.duration"),
        (gust(0.0, f64::NAN, 1.0), "gusts.duration"),
        (gust(0.0, 1.0, f64::INFINITY), "gusts.amplitude"),
        (turb(&|t| t.intensity = Intensity::W20(-1.0)), "turbulence.intensity.w20"),
        (turb(&|t| t.altitude = 500.0), "turbulence.altitude"),
        (turb(&|t| t.altitude = 0.0), "turbulence.altitude"),
        (turb(&|t| t.airspeed_floor = 0.0), "turbulence.airspeed_floor"),
        (turb(&|t| t.airspeed_floor = f64::NAN), "turbulence.airspeed_floor"),
    ];
    for (p, field) in cases {
        let e = p.check().unwrap_err();
        assert_eq!(e.field, field, "{e}");
        assert_eq!(Wind::new(p, DT, 0).unwrap_err().field, field);
    }
    assert_eq!(Wind::new(WindParams::default(), 0.0, 0).unwrap_err().field, "dt");
    assert_eq!(Wind::new(WindParams::default(), f64::NAN, 0).unwrap_err().field, "dt");
}

#[test]
fn changing_the_airspeed_keeps_the_variance() {
    // The states are scaled so that their stationary law does not depend on
    // V: switching from the floor to 10 m/s mid-flight leaves σ² unchanged.
    let mut d = Dryden::new(TurbulenceParams::moderate(), DT, 0.0, 9);
    for _ in 0..1000 {
        d.step();
    }
    d.set_airspeed(V);
    let n = 1 << 19;
    let mut sum = [0.0; 3];
    for _ in 0..n {
        let s = d.step();
        for k in 0..3 {
            sum[k] += s[k] * s[k];
        }
    }
    for k in 0..3 {
        let sigma = d.scales().sigma[k];
        let ratio = sum[k] / n as f64 / (sigma * sigma);
        eprintln!("after the switch, axis {k}: mean square / σ² = {ratio:.4}");
        assert!((ratio - 1.0).abs() < 0.1, "axis {k}: {ratio}");
    }
}
