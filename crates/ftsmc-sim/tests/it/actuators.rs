//! Motors (limits, exact first-order lag, noise) and the mixer (round trip,
//! priority under saturation).

use ftsmc_core::allocation::forces_from_squared_speeds;
use ftsmc_core::model::{Command, QuadrotorParams};
use ftsmc_sim::actuators::{
    motor_noise_rng, paper_allocation_matrix, ActuatorParams, Mixer, MotorNoise, Motors, NoiseScale,
};
use ftsmc_sim::vehicle::RigidBodyParams;
use rand::{Rng, RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn lagged() -> ActuatorParams {
    ActuatorParams {
        min_rotor_speed: 50.0,
        max_rotor_speed: 900.0,
        time_constant_up: 0.05,
        time_constant_down: 0.02,
        noise: None,
        ..ActuatorParams::default()
    }
}

#[test]
fn motor_step_response_matches_the_first_order_curve() {
    let p = lagged();
    for h in [1e-4, 1e-3, 7.3e-3, 0.05] {
        // Spin up from 200 to 600 rad/s with τ_up, then down to 100 with τ_down.
        let mut motors = Motors::new(&p, [200.0; 4]);
        let n = (0.2f64 / h).round() as usize;
        for k in 1..=n {
            motors.advance(&[600.0; 4], h);
            let t = k as f64 * h;
            let exact = 600.0 + (200.0 - 600.0) * ftsmc_core::math::exp(-t / p.time_constant_up);
            for w in motors.speeds() {
                assert!((w - exact).abs() <= 1e-12 * exact, "h {h}, t {t}: {w} vs {exact}");
            }
        }
        let start = motors.speeds()[0];
        for k in 1..=n {
            motors.advance(&[100.0; 4], h);
            let t = k as f64 * h;
            let exact = 100.0 + (start - 100.0) * ftsmc_core::math::exp(-t / p.time_constant_down);
            for w in motors.speeds() {
                assert!((w - exact).abs() <= 1e-12 * start, "h {h}, t {t}: {w} vs {exact}");
            }
        }
    }
    // Mixed directions in one step, and the closed form inside a step.
    let motors = Motors::new(&p, [300.0, 300.0, 300.0, 300.0]);
    let after = motors.speeds_after(&[400.0, 200.0, 300.0, 800.0], 0.01);
    let up = |to: f64| to + (300.0 - to) * ftsmc_core::math::exp(-0.01f64 / 0.05);
    let down = |to: f64| to + (300.0 - to) * ftsmc_core::math::exp(-0.01f64 / 0.02);
    let expected = [up(400.0), down(200.0), 300.0, up(800.0)];
    for i in 0..4 {
        assert!((after[i] - expected[i]).abs() < 1e-12 * expected[i], "{after:?} vs {expected:?}");
    }
    assert_eq!(motors.speeds(), [300.0; 4], "speeds_after does not change the motors");
}

#[test]
fn zero_time_constant_means_no_lag() {
    let mut motors = Motors::new(&ActuatorParams::default(), [0.0; 4]);
    motors.advance(&[123.0, 456.0, 0.0, 1e4], 1e-3);
    assert_eq!(motors.speeds(), [123.0, 456.0, 0.0, 1e4]);
    assert_eq!(motors.speeds_after(&[7.0; 4], 0.0), [7.0; 4]);
}

#[test]
fn limits_are_respected() {
    let p = ActuatorParams { noise: Some(MotorNoise { std: 400.0, scale: NoiseScale::Absolute }), ..lagged() };
    let mut motors = Motors::new(&p, [0.0, 1e5, 500.0, -3.0]);
    assert_eq!(motors.speeds(), [50.0, 900.0, 500.0, 50.0]);
    let mut rng = motor_noise_rng(7);
    for k in 0..2000 {
        let command = if k % 2 == 0 { [2000.0, -5.0, 1e9, 0.0] } else { [f64::INFINITY, 0.0, 600.0, 899.0] };
        motors.advance(&command, 1e-3);
        let z = motors.sample_noise(&mut rng);
        for w in motors.with_noise(&motors.speeds(), &z).into_iter().chain(motors.speeds()) {
            assert!((50.0..=900.0).contains(&w), "{w}");
        }
    }
    let mixer = Mixer::for_paper(&QuadrotorParams::default(), &lagged()).unwrap();
    for thrust in [-10.0, 0.0, 3.0, 7.26, 40.0, 1e6] {
        let out = mixer.mix(&Command { thrust, torque: [0.3, -2.0, 0.05] });
        for w in out.rotor_speeds {
            assert!((50.0..=900.0).contains(&w), "thrust {thrust}: {w}");
        }
    }
}

fn relative_close(a: &Command, b: &Command, tol: f64) -> bool {
    let scale = a.thrust.abs().max(b.thrust.abs()).max(1e-30);
    let tscale = a.torque.iter().chain(&b.torque).fold(0.0f64, |m, v| m.max(v.abs())).max(1e-30);
    (a.thrust - b.thrust).abs() <= tol * scale && (0..3).all(|k| (a.torque[k] - b.torque[k]).abs() <= tol * tscale)
}

#[test]
fn mixer_round_trip_inside_the_feasible_set() {
    let p = QuadrotorParams::default();
    let limits = ActuatorParams { min_rotor_speed: 100.0, max_rotor_speed: 500.0, ..ActuatorParams::default() };
    let paper = Mixer::for_paper(&p, &limits).unwrap();
    let unbounded = Mixer::for_paper(&p, &ActuatorParams::default()).unwrap();
    let cf = RigidBodyParams::crazyflie();
    let crazyflie = Mixer::new(cf.allocation_matrix(), &ActuatorParams::crazyflie()).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    for _ in 0..2000 {
        // Squared speeds inside the limits → command → mixer → speeds → command.
        let omega: [f64; 4] = core::array::from_fn(|_| rng.random_range(100.0..500.0));
        let w = omega.map(|o| o * o);
        let command = forces_from_squared_speeds(&p, &w);
        for mixer in [&paper, &unbounded] {
            let out = mixer.mix(&command);
            assert!(!out.saturated, "{command:?}");
            assert_eq!(out.applied, command);
            let back = forces_from_squared_speeds(&p, &out.rotor_speeds.map(|o| o * o));
            assert!(relative_close(&back, &command, 1e-9), "{back:?} vs {command:?}");
            for i in 0..4 {
                assert!((out.rotor_speeds[i] - omega[i]).abs() < 1e-9 * omega[i]);
            }
        }
        let omega: [f64; 4] = core::array::from_fn(|_| rng.random_range(0.0..2500.0));
        let command = crazyflie.forces(&omega.map(|o| o * o));
        let out = crazyflie.mix(&command);
        assert!(!out.saturated);
        let back = crazyflie.forces(&out.rotor_speeds.map(|o| o * o));
        assert!(relative_close(&back, &command, 1e-9), "{back:?} vs {command:?}");
    }
    // The matrix is Eq. 2.
    let w = [1.0e4, 2.0e4, 3.0e4, 4.5e4];
    assert!(relative_close(&paper.forces(&w), &forces_from_squared_speeds(&p, &w), 1e-15));
    assert_eq!(paper_allocation_matrix(&p)[0], [p.lift_coefficient; 4]);
}

fn saturated_mixer() -> (QuadrotorParams, Mixer) {
    // ω_max = 1.2 × hover speed (≈ 297 rad/s): little headroom.
    let p = QuadrotorParams::default();
    let limits = ActuatorParams { max_rotor_speed: 1.2 * p.hover_rotor_speed(), ..ActuatorParams::default() };
    (p, Mixer::for_paper(&p, &limits).unwrap())
}

/// The rotor speeds produce the applied command, and no rotor is outside the limits.
fn assert_consistent(mixer: &Mixer, out: &ftsmc_sim::actuators::MixerOutput) {
    let back = mixer.forces(&out.rotor_speeds.map(|o| o * o));
    assert!(relative_close(&back, &out.applied, 1e-9), "{back:?} vs {:?}", out.applied);
}

#[test]
fn infeasible_yaw_is_given_up_first() {
    let (p, mixer) = saturated_mixer();
    let command = Command { thrust: p.mass * p.gravity, torque: [1e-2, -5e-3, 0.05] };
    let out = mixer.mix(&command);
    assert!(out.saturated);
    assert_eq!(out.applied.thrust, command.thrust);
    assert_eq!(out.applied.torque[0], command.torque[0]);
    assert_eq!(out.applied.torque[1], command.torque[1]);
    let yaw = out.applied.torque[2];
    assert!(yaw > 0.0 && yaw < 0.05, "{yaw}");
    assert_consistent(&mixer, &out);
    // Maximal: a little more yaw is infeasible.
    let more = Command { torque: [1e-2, -5e-3, yaw * 1.001], ..command };
    assert!(mixer.mix(&more).saturated);
    // Negative yaw likewise, symmetric.
    let neg = mixer.mix(&Command { torque: [1e-2, -5e-3, -0.05], ..command });
    assert_eq!(neg.applied.torque[..2], command.torque[..2]);
    assert!(neg.applied.torque[2] < 0.0 && neg.applied.torque[2] > -0.05);
}

#[test]
fn infeasible_roll_keeps_thrust_and_reduces_roll() {
    let (p, mixer) = saturated_mixer();
    let command = Command { thrust: p.mass * p.gravity, torque: [0.5, 0.0, 1e-4] };
    let out = mixer.mix(&command);
    assert!(out.saturated);
    assert_eq!(out.applied.thrust, command.thrust);
    let roll = out.applied.torque[0];
    assert!(roll > 0.0 && roll < 0.5, "{roll}");
    assert_eq!(out.applied.torque[1], 0.0);
    assert_consistent(&mixer, &out);
    // Roll and pitch are scaled together: the tilting-torque direction is kept.
    let both = mixer.mix(&Command { thrust: p.mass * p.gravity, torque: [0.5, -0.25, 0.0] });
    assert_eq!(both.applied.thrust, p.mass * p.gravity);
    let ratio = both.applied.torque[1] / both.applied.torque[0];
    assert!((ratio + 0.5).abs() < 1e-15, "{ratio}");
    assert!(both.applied.torque[0] < 0.5);
    assert_consistent(&mixer, &both);
}

#[test]
fn infeasible_thrust_is_clipped_last() {
    let (p, mixer) = saturated_mixer();
    let [lo, hi] = mixer.thrust_range();
    assert_eq!(lo, 0.0);
    assert!((hi - 4.0 * p.lift_coefficient * (1.2 * p.hover_rotor_speed()).powi(2)).abs() < 1e-12 * hi);
    // Thrust beyond the maximum: all rotors at ω_max, no torque left.
    let out = mixer.mix(&Command { thrust: 2.0 * hi, torque: [0.01, 0.01, 0.001] });
    assert_eq!(out.applied.thrust, hi);
    assert!(out.applied.torque.iter().all(|t| t.abs() < 1e-9), "{:?}", out.applied);
    assert_consistent(&mixer, &out);
    // Negative thrust: clipped to zero.
    let out = mixer.mix(&Command { thrust: -3.0, torque: [0.0; 3] });
    assert_eq!(out.applied.thrust, 0.0);
    assert_eq!(out.rotor_speeds, [0.0; 4]);
    // With ω_min > 0 the lower end is 4 b ω_min².
    let limits = ActuatorParams { min_rotor_speed: 100.0, ..ActuatorParams::default() };
    let mixer = Mixer::for_paper(&p, &limits).unwrap();
    let out = mixer.mix(&Command { thrust: 0.1, torque: [0.0; 3] });
    assert!((out.applied.thrust - 4.0 * p.lift_coefficient * 1e4).abs() < 1e-12);
    assert!(out.saturated);
}

#[test]
fn feasible_commands_are_unchanged_and_nonfinite_ones_are_flagged() {
    let (p, mixer) = saturated_mixer();
    let command = Command { thrust: p.mass * p.gravity, torque: [1e-3, -1e-3, 1e-4] };
    let out = mixer.mix(&command);
    assert!(!out.saturated);
    assert_eq!(out.applied, command);
    assert_eq!(out.commanded, command);
    let out = mixer.mix(&Command { thrust: f64::NAN, torque: [f64::INFINITY, 0.0, 0.0] });
    assert!(out.saturated);
    assert!(out.rotor_speeds.iter().all(|w| w.is_finite()));
    assert_eq!(out.commanded, Command::default());
}

#[test]
fn motor_noise_is_deterministic_per_seed_with_the_right_moments() {
    let abs =
        ActuatorParams { noise: Some(MotorNoise { std: 20.0, scale: NoiseScale::Absolute }), ..Default::default() };
    let rel =
        ActuatorParams { noise: Some(MotorNoise { std: 0.05, scale: NoiseScale::Relative }), ..Default::default() };
    for (params, sigma) in [(abs, 20.0), (rel, 0.05 * 400.0)] {
        let motors = Motors::new(&params, [400.0; 4]);
        let draw = |seed: u64, n: usize| {
            let mut rng = motor_noise_rng(seed);
            (0..n).map(|_| motors.with_noise(&motors.speeds(), &motors.sample_noise(&mut rng))).collect::<Vec<_>>()
        };
        assert_eq!(draw(11, 50), draw(11, 50));
        assert_ne!(draw(11, 50), draw(12, 50));
        let samples = draw(5, 50_000);
        for i in 0..4 {
            let n = samples.len() as f64;
            let mean = samples.iter().map(|s| s[i]).sum::<f64>() / n;
            let var = samples.iter().map(|s| (s[i] - mean).powi(2)).sum::<f64>() / (n - 1.0);
            // Standard error of the mean σ/√n ≈ 0.09 rad/s; of the variance ≈ σ²√(2/n) ≈ 0.6 %.
            assert!((mean - 400.0).abs() < 5.0 * sigma / n.sqrt(), "rotor {i}: mean {mean}");
            assert!((var / (sigma * sigma) - 1.0).abs() < 0.04, "rotor {i}: var {var}");
        }
    }
}

#[test]
fn motor_noise_leaves_other_streams_alone() {
    let seed = 42;
    // A drag-noise stream as `environment::Environment` derives it (stream 1 of the seed).
    let drag_stream = || {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(1);
        rng
    };
    let quiet: Vec<u64> = {
        let mut drag = drag_stream();
        (0..100).map(|_| drag.next_u64()).collect()
    };
    let noisy_params =
        ActuatorParams { noise: Some(MotorNoise { std: 0.1, scale: NoiseScale::Relative }), ..Default::default() };
    let motors = Motors::new(&noisy_params, [300.0; 4]);
    let mut motor_rng = motor_noise_rng(seed);
    let mut drag = drag_stream();
    let interleaved: Vec<u64> = (0..100)
        .map(|_| {
            motors.sample_noise(&mut motor_rng);
            drag.next_u64()
        })
        .collect();
    assert_eq!(quiet, interleaved);
    assert_ne!(motor_noise_rng(seed).next_u64(), drag_stream().next_u64());

    // Noise off: the generator is not advanced and the speeds are untouched.
    let silent = Motors::new(&ActuatorParams::default(), [300.0; 4]);
    let mut rng = motor_noise_rng(seed);
    let before = rng.clone();
    let z = silent.sample_noise(&mut rng);
    assert_eq!(rng, before);
    assert_eq!(silent.with_noise(&silent.speeds(), &z), [300.0; 4]);
}

#[test]
fn params_check_and_serde() {
    for p in [
        ActuatorParams::default(),
        ActuatorParams::crazyflie(),
        ActuatorParams::hummingbird(),
        ActuatorParams::px4_x500(),
    ] {
        p.check().unwrap();
    }
    let bad = ActuatorParams { max_rotor_speed: 10.0, min_rotor_speed: 20.0, ..Default::default() };
    assert_eq!(bad.check().unwrap_err().field, "max_rotor_speed");
    let bad = ActuatorParams { time_constant_down: -1.0, ..Default::default() };
    assert_eq!(bad.check().unwrap_err().field, "time_constant_down");
    let bad =
        ActuatorParams { noise: Some(MotorNoise { std: f64::NAN, scale: NoiseScale::Absolute }), ..Default::default() };
    assert_eq!(bad.check().unwrap_err().field, "noise.std");
    assert!(Mixer::for_paper(
        &QuadrotorParams::default(),
        &ActuatorParams { max_rotor_speed: f64::NAN, ..Default::default() }
    )
    .is_err());

    let text = toml::to_string(&ActuatorParams::hummingbird()).unwrap();
    assert_eq!(toml::from_str::<ActuatorParams>(&text).unwrap(), ActuatorParams::hummingbird());
    let ideal: ActuatorParams = toml::from_str("").unwrap();
    assert_eq!(ideal, ActuatorParams::default());
    assert!(ideal.max_rotor_speed.is_infinite());
    let text = toml::to_string(&ideal).unwrap();
    assert_eq!(toml::from_str::<ActuatorParams>(&text).unwrap(), ideal);
    let parsed: ActuatorParams = toml::from_str(
        "max_rotor_speed = 1000.0\ntime_constant_up = 0.0125\nnoise = { std = 0.02, scale = \"relative\" }",
    )
    .unwrap();
    assert_eq!(parsed.noise.unwrap().scale, NoiseScale::Relative);
    assert!(toml::from_str::<ActuatorParams>("max_rotor_sped = 1.0").is_err());
    assert!(toml::from_str::<ActuatorParams>("noise = { std = 1.0, scale = \"absolute\", mean = 0.0 }").is_err());
}

/// The speeds the truth model sees at each RK4 stage, prepared once per
/// substep (`Motors::held`), are the lagged speeds with the period's noise
/// bit for bit, for every mix of spin-up, spin-down, no lag, limits and
/// noise scale.
#[test]
fn held_command_speeds_are_the_lagged_noisy_speeds_bit_for_bit() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let noises = [
        None,
        Some(MotorNoise { std: 50.0, scale: NoiseScale::Absolute }),
        Some(MotorNoise { std: 0.3, scale: NoiseScale::Relative }),
    ];
    let lags = [(0.05, 0.02), (0.0, 0.02), (0.05, 0.0), (0.0, 0.0)];
    for noise in noises {
        for (up, down) in lags {
            let p = ActuatorParams { time_constant_up: up, time_constant_down: down, noise, ..lagged() };
            for _ in 0..50 {
                let start: [f64; 4] = core::array::from_fn(|_| rng.random_range(0.0..1000.0));
                let motors = Motors::new(&p, start);
                let command: [f64; 4] = core::array::from_fn(|_| rng.random_range(-100.0..1100.0));
                let z = motors.sample_noise(&mut rng);
                let held = motors.held(&command, &z);
                for dt in [0.0, 5e-4, 1e-3, 0.37] {
                    let decay = motors.decay(dt);
                    let expected = motors.with_noise(&motors.speeds_decayed(&command, &decay), &z);
                    assert_eq!(held.speeds(&decay).map(f64::to_bits), expected.map(f64::to_bits), "{p:?} dt {dt}");
                }
            }
        }
    }
}
