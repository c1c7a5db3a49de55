//! The sensor model (`ftsmc_sim::sensors`): latency, noise statistics,
//! per-source streams, sample-and-hold, the perfect default, and its
//! parameters' validation.

use ftsmc_core::model::QuadState;
use ftsmc_sim::sensors::{QuantityError, RateFrame, SensorParams, Sensors};

const CONTROL_HZ: f64 = 1000.0;

/// Every component equal to `v` (a ramp when `v` is the period index).
fn flat(v: f64) -> QuadState {
    QuadState { position: [v; 3], attitude: [v; 3], velocity: [v; 3], angular_rate: [v; 3] }
}

fn noisy(std: f64, bias: f64) -> QuantityError {
    QuantityError { std: [std, 2.0 * std, 0.5 * std], bias: [bias, -bias, 0.0] }
}

fn all_noisy() -> SensorParams {
    SensorParams {
        position: noisy(1e-3, 2e-3),
        velocity: noisy(1e-2, -5e-3),
        attitude: noisy(2e-3, 1e-3),
        angular_rate: noisy(1e-2, 3e-3),
        ..SensorParams::default()
    }
}

fn bits(s: &QuadState) -> [u64; 12] {
    s.to_array().map(f64::to_bits)
}

#[test]
fn latency_shifts_a_ramp_by_exactly_k_periods() {
    for k in [0u32, 1, 3, 17] {
        let mut sensors = Sensors::new(SensorParams { latency: k, ..SensorParams::default() }, CONTROL_HZ, 7);
        for n in 0..200u32 {
            let seen = sensors.measure(&flat(f64::from(n)));
            // Before `k` periods have elapsed, the first reading (0).
            let expected = f64::from(n.saturating_sub(k));
            assert_eq!(bits(&seen), bits(&flat(expected)), "latency {k}, period {n}");
        }
    }
}

#[test]
fn a_100_hz_sensor_at_1_khz_holds_each_sample_for_10_periods() {
    let params = SensorParams { sample_rate: Some(100.0), ..SensorParams::default() };
    let mut sensors = Sensors::new(params, CONTROL_HZ, 7);
    for n in 0..1000u32 {
        let seen = sensors.measure(&flat(f64::from(n)));
        assert_eq!(seen, flat(f64::from(10 * (n / 10))), "period {n}");
    }
    // With latency the held sequence is delayed as a whole.
    let params = SensorParams { sample_rate: Some(100.0), latency: 3, ..SensorParams::default() };
    let mut sensors = Sensors::new(params, CONTROL_HZ, 7);
    for n in 0..1000u32 {
        let seen = sensors.measure(&flat(f64::from(n)));
        assert_eq!(seen, flat(f64::from(10 * (n.saturating_sub(3) / 10))), "period {n}");
    }
    // A sensor at or above the control rate gives a fresh sample each period.
    let params = SensorParams { sample_rate: Some(4000.0), ..SensorParams::default() };
    let mut sensors = Sensors::new(params, CONTROL_HZ, 7);
    for n in 0..100u32 {
        assert_eq!(sensors.measure(&flat(f64::from(n))), flat(f64::from(n)));
    }
}

#[test]
fn a_non_integer_rate_ratio_samples_on_schedule() {
    // 300 Hz at 1 kHz: samples at periods k where ⌊0.3 k⌋ moves on.
    let params = SensorParams { sample_rate: Some(300.0), ..SensorParams::default() };
    let mut sensors = Sensors::new(params, CONTROL_HZ, 7);
    let mut samples = 0;
    let mut last = f64::NAN;
    for n in 0..1000u32 {
        let seen = sensors.measure(&flat(f64::from(n))).position[0];
        if seen != last {
            samples += 1;
            last = seen;
        }
    }
    assert_eq!(samples, 300);
}

#[test]
fn noise_has_the_configured_mean_and_variance() {
    const N: usize = 200_000;
    let params = all_noisy();
    let mut sensors = Sensors::new(params, CONTROL_HZ, 2024);
    let truth = QuadState {
        position: [1.0, -2.0, 3.0],
        attitude: [0.1, -0.2, 0.3],
        velocity: [0.5, 0.0, -0.5],
        angular_rate: [0.05, -0.01, 0.2],
    };
    let t = truth.to_array();
    let mut sum = [0.0; 12];
    let mut sum_sq = [0.0; 12];
    for _ in 0..N {
        let e = sensors.measure(&truth).to_array();
        for i in 0..12 {
            let d = e[i] - t[i];
            sum[i] += d;
            sum_sq[i] += d * d;
        }
    }
    let quantities = [params.position, params.attitude, params.velocity, params.angular_rate];
    let n = N as f64;
    let mut worst_mean: f64 = 0.0;
    let mut worst_var: f64 = 0.0;
    for i in 0..12 {
        let q = quantities[i / 3];
        let (std, bias) = (q.std[i % 3], q.bias[i % 3]);
        let mean = sum[i] / n;
        let var = (sum_sq[i] - n * mean * mean) / (n - 1.0);
        if std == 0.0 {
            assert!((mean - bias).abs() <= 1e-15 && var.abs() <= 1e-25, "component {i}: mean {mean}, var {var}");
            continue;
        }
        // Three standard errors of the mean and of the sample variance.
        let mean_tol = 3.0 * std / n.sqrt();
        let var_tol = 3.0 * std * std * (2.0 / (n - 1.0)).sqrt();
        let (mean_z, var_z) =
            ((mean - bias) / (std / n.sqrt()), (var - std * std) / (std * std * (2.0 / (n - 1.0)).sqrt()));
        worst_mean = worst_mean.max(mean_z.abs());
        worst_var = worst_var.max(var_z.abs());
        assert!((mean - bias).abs() <= mean_tol, "component {i}: mean {mean} vs bias {bias} (±{mean_tol})");
        assert!((var - std * std).abs() <= var_tol, "component {i}: var {var} vs {} (±{var_tol})", std * std);
    }
    println!("worst |mean error| = {worst_mean:.2} SE, worst |variance error| = {worst_var:.2} SE over {N} samples");
}

#[test]
fn every_source_on_is_deterministic_per_seed() {
    let params = SensorParams { rates: RateFrame::Body, sample_rate: Some(250.0), latency: 2, ..all_noisy() };
    let run = |seed: u64| {
        let mut sensors = Sensors::new(params, CONTROL_HZ, seed);
        (0..2000).map(|n| bits(&sensors.measure(&flat(1e-3 * f64::from(n))))).collect::<Vec<_>>()
    };
    assert_eq!(run(11), run(11));
    assert_ne!(run(11), run(12));
}

#[test]
fn adding_one_source_leaves_the_others_bit_identical() {
    let base = SensorParams { velocity: QuantityError::default(), ..all_noisy() };
    let with_velocity = all_noisy();
    let mut a = Sensors::new(base, CONTROL_HZ, 5);
    let mut b = Sensors::new(with_velocity, CONTROL_HZ, 5);
    let mut velocity_differs = false;
    for n in 0..5000 {
        let truth = flat(1e-3 * f64::from(n));
        let (x, y) = (a.measure(&truth), b.measure(&truth));
        for (p, q) in [(x.position, y.position), (x.attitude, y.attitude), (x.angular_rate, y.angular_rate)] {
            assert_eq!(p.map(f64::to_bits), q.map(f64::to_bits), "period {n}");
        }
        velocity_differs |= x.velocity != y.velocity;
    }
    assert!(velocity_differs);

    // Noise on one axis only does not change another axis's draws.
    let one_axis = |std_y: f64| SensorParams {
        position: QuantityError { std: [1e-3, std_y, 0.0], bias: [0.0; 3] },
        ..SensorParams::default()
    };
    let mut a = Sensors::new(one_axis(0.0), CONTROL_HZ, 5);
    let mut b = Sensors::new(one_axis(1e-3), CONTROL_HZ, 5);
    for _ in 0..1000 {
        let truth = flat(0.0);
        assert_eq!(a.measure(&truth).position[0].to_bits(), b.measure(&truth).position[0].to_bits());
    }
}

#[test]
fn the_perfect_default_returns_the_truth_bit_exactly() {
    let params = SensorParams::default();
    assert!(params.is_perfect());
    let mut sensors = Sensors::new(params, CONTROL_HZ, 1);
    for n in 0..1000u32 {
        let v = f64::from(n) * 0.123_456_789 - 50.0;
        let truth = QuadState {
            position: [v, -0.0, 1e-300],
            attitude: [ftsmc_core::math::sin(v), -ftsmc_core::math::cos(v), 0.0],
            velocity: [-v, f64::MIN_POSITIVE, 3.0],
            angular_rate: [v * 1e-7, -0.0, -v],
        };
        assert_eq!(bits(&sensors.measure(&truth)), bits(&truth), "period {n}");
    }
}

#[test]
fn body_rates_are_corrupted_in_the_body_frame_and_mapped_back() {
    // No error: the Euler → body → Euler round trip at the true attitude.
    let params = SensorParams { rates: RateFrame::Body, ..SensorParams::default() };
    let mut sensors = Sensors::new(params, CONTROL_HZ, 1);
    let truth = QuadState { attitude: [0.3, -0.4, 1.0], angular_rate: [0.2, -0.1, 0.5], ..QuadState::default() };
    let seen = sensors.measure(&truth);
    for k in 0..3 {
        assert!((seen.angular_rate[k] - truth.angular_rate[k]).abs() < 1e-14, "{seen:?}");
    }
    // Level, a gyro bias on p is a bias on φ̇; on r (yawed 0) a bias on ψ̇.
    let params = SensorParams {
        rates: RateFrame::Body,
        angular_rate: QuantityError { std: [0.0; 3], bias: [0.01, 0.0, -0.02] },
        ..SensorParams::default()
    };
    let mut sensors = Sensors::new(params, CONTROL_HZ, 1);
    let seen = sensors.measure(&QuadState::default());
    assert_eq!(seen.angular_rate, [0.01, 0.0, -0.02]);
    // At gimbal lock the conversion stays finite.
    let mut sensors = Sensors::new(params, CONTROL_HZ, 1);
    let seen =
        sensors.measure(&QuadState { attitude: [0.0, std::f64::consts::FRAC_PI_2, 0.0], ..QuadState::default() });
    assert!(seen.angular_rate.iter().all(|r| r.is_finite()), "{seen:?}");
}

#[test]
fn params_round_trip_through_toml() {
    let params = SensorParams { rates: RateFrame::Body, sample_rate: Some(200.0), latency: 4, ..all_noisy() };
    let text = toml::to_string(&params).expect("serialize");
    let back: SensorParams = toml::from_str(&text).expect("deserialize");
    assert_eq!(back, params);
    let default: SensorParams = toml::from_str("").expect("empty is the default");
    assert_eq!(default, SensorParams::default());
    let text = toml::to_string(&SensorParams::default()).expect("serialize default");
    assert_eq!(toml::from_str::<SensorParams>(&text).expect("deserialize default"), SensorParams::default());
    let partial: SensorParams =
        toml::from_str("rates = \"body\"\nlatency = 2\n[position]\nstd = [1e-3, 1e-3, 2e-3]\n").expect("partial");
    assert_eq!(partial.position.std, [1e-3, 1e-3, 2e-3]);
    assert_eq!(partial.position.bias, [0.0; 3]);
    assert_eq!(partial.rates, RateFrame::Body);
}

#[test]
fn unknown_keys_and_values_are_rejected() {
    for text in [
        "latancy = 2",
        "[position]\nsdt = [0.0, 0.0, 0.0]",
        "rates = \"quaternion\"",
        "[velocity]\nstd = [0.1, 0.1]",
        "latency = -1",
    ] {
        assert!(toml::from_str::<SensorParams>(text).is_err(), "accepted {text:?}");
    }
}

#[test]
fn bad_values_are_rejected_with_the_field_named() {
    assert_eq!(SensorParams::default().check(), Ok(()));
    assert_eq!(all_noisy().check(), Ok(()));
    let q = |std: f64, bias: f64| QuantityError { std: [0.0, std, 0.0], bias: [0.0, 0.0, bias] };
    let cases: [(SensorParams, &str); 9] = [
        (SensorParams { position: q(-1e-3, 0.0), ..Default::default() }, "position.std"),
        (SensorParams { velocity: q(f64::NAN, 0.0), ..Default::default() }, "velocity.std"),
        (SensorParams { attitude: q(f64::INFINITY, 0.0), ..Default::default() }, "attitude.std"),
        (SensorParams { angular_rate: q(0.0, f64::NAN), ..Default::default() }, "angular_rate.bias"),
        (SensorParams { position: q(0.0, -1e4), ..Default::default() }, "position.bias"),
        (SensorParams { sample_rate: Some(0.0), ..Default::default() }, "sample_rate"),
        (SensorParams { sample_rate: Some(-100.0), ..Default::default() }, "sample_rate"),
        (SensorParams { sample_rate: Some(f64::NAN), ..Default::default() }, "sample_rate"),
        (SensorParams { latency: 1_000_000, ..Default::default() }, "latency"),
    ];
    for (params, field) in cases {
        let err = params.check().expect_err(field);
        assert_eq!(err.field, field);
        assert!(err.to_string().contains(field), "{err}");
    }
}
