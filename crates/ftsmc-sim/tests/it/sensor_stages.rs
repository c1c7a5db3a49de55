//! The sensor stages (`sensors::{imu, gnss, baro, mag, estimator}`): each
//! model's statistics against its parameters, determinism and reseeding,
//! the latency line, and the refusals of bad input.

use ftsmc_core::measured::Measurement;
use ftsmc_core::model::QuadState;
use ftsmc_sim::sensors::baro::{isa_altitude, isa_pressure, Baro, BaroParams};
use ftsmc_sim::sensors::estimator::{check_sources, EstimatorStage, FailureReason, MotionCapture, Passthrough};
use ftsmc_sim::sensors::gnss::{Gnss, GnssParams};
use ftsmc_sim::sensors::imu::{AxisError, Imu, ImuClass, ImuParams};
use ftsmc_sim::sensors::mag::{Mag, MagParams};
use ftsmc_sim::sensors::{
    Reading, SensorModel, SensorParams, SensorStage, SensorTruth, Sensors, Stage, StageClock, GYROSCOPE_STREAM,
};

fn truth_at<'a>(t: f64, state: &'a QuadState) -> SensorTruth<'a> {
    SensorTruth { t, state, body: None, acceleration: [0.0; 3], gravity: 9.81 }
}

/// Allan deviation of `x` (rate samples at `dt`) at cluster time `m · dt`
/// (non-overlapping clusters, IEEE Std 952-1997 Annex C).
fn allan_deviation(x: &[f64], m: usize) -> f64 {
    let means: Vec<f64> = x.chunks_exact(m).map(|c| c.iter().sum::<f64>() / m as f64).collect();
    let n = means.len() - 1;
    let s: f64 = means.windows(2).map(|w| (w[1] - w[0]) * (w[1] - w[0])).sum();
    (s / (2.0 * n as f64)).sqrt()
}

/// The gyroscope's Allan deviation at τ = 1 s is its white-noise density
/// (σ_A(τ) = N / √τ) within sampling error, over an hour at 200 Hz with the
/// bias terms off; with the px4-sitl bias it is still within 10 % at 1 s.
#[test]
fn gyro_allan_deviation_at_one_second_is_the_noise_density() {
    let mut model = ImuParams::of_class(ImuClass::Px4Sitl).gyroscope;
    model.bias_random_walk = 0.0;
    model.turn_on_bias = 0.0;
    let dt = 1.0 / 200.0;
    let n = 200 * 3600;
    let mut err = AxisError::new(model, 7, GYROSCOPE_STREAM);
    let x: Vec<f64> = (0..n).map(|_| err.corrupt([0.0; 3], dt)[0]).collect();
    let adev = allan_deviation(&x, 200);
    // 3599 cluster differences: relative standard error ≈ 1/√(2·3599) ≈ 1.2 %.
    let rel = adev / model.noise_density - 1.0;
    assert!(rel.abs() < 0.05, "Allan deviation {adev} vs N = {} ({rel:+.3})", model.noise_density);
    // At τ = 10 s the white branch falls as 1/√τ.
    let adev10 = allan_deviation(&x, 2000);
    let rel10 = adev10 / (model.noise_density / 10f64.sqrt()) - 1.0;
    assert!(rel10.abs() < 0.15, "τ = 10 s: {adev10} ({rel10:+.3})");
}

/// The bias is a Gauss–Markov process: with τ = ∞ it walks as K √t
/// (variance K² t across independent keys), and its draws are keyed.
#[test]
fn gyro_bias_random_walk_grows_as_k_root_t() {
    let mut model = ImuParams::of_class(ImuClass::Px4Sitl).gyroscope;
    model.bias_correlation_time = f64::INFINITY;
    model.turn_on_bias = 0.0;
    let (dt, steps, keys) = (0.01, 10_000, 400u64);
    let mut sum_sq = 0.0;
    for key in 0..keys {
        let mut err = AxisError::new(model, key, GYROSCOPE_STREAM);
        for _ in 0..steps {
            err.corrupt([0.0; 3], dt);
        }
        sum_sq += err.bias().iter().map(|b| b * b).sum::<f64>();
    }
    let var = sum_sq / (3.0 * keys as f64);
    let want = model.bias_random_walk * model.bias_random_walk * dt * steps as f64;
    // 1200 samples of a chi-square: relative error ≈ √(2/1200) ≈ 4 %.
    assert!((var / want - 1.0).abs() < 0.15, "bias variance {var} vs K² t = {want}");
}

/// The accelerometer at rest and level reads +g along body z (specific
/// force); rolled by 90° it reads g along body −y... and saturates at its range.
#[test]
fn accelerometer_reads_specific_force_and_saturates() {
    let mut params = ImuParams::of_class(ImuClass::Bmi088);
    params.accelerometer.noise_density = 1e-12;
    params.accelerometer.bias_random_walk = 0.0;
    params.gyroscope.noise_density = 1e-12;
    params.gyroscope.bias_random_walk = 0.0;
    let mut imu = Imu::new(&params, 1);
    let level = QuadState::default();
    let Reading::Imu(r) = imu.sample(&truth_at(0.0, &level), 1e-3) else { panic!("an IMU reading") };
    assert!((r.specific_force[2] - 9.81).abs() < 2e-3, "{:?}", r.specific_force);
    assert!(r.specific_force[0].abs() < 2e-3 && r.specific_force[1].abs() < 2e-3);
    let rolled = QuadState { attitude: [core::f64::consts::FRAC_PI_2, 0.0, 0.0], ..QuadState::default() };
    let Reading::Imu(r) = imu.sample(&truth_at(0.0, &rolled), 1e-3) else { panic!() };
    assert!((r.specific_force[1] - 9.81).abs() < 2e-3 && r.specific_force[2].abs() < 2e-3, "{:?}", r.specific_force);
    let hard = SensorTruth { t: 0.0, state: &level, body: None, acceleration: [1e4, 0.0, 0.0], gravity: 9.81 };
    let Reading::Imu(r) = imu.sample(&hard, 1e-3) else { panic!() };
    assert_eq!(r.specific_force[0], params.accelerometer.range);
    // Quantised: a multiple of one LSB.
    let q = r.specific_force[2] / params.accelerometer.resolution;
    assert!((q - q.round()).abs() < 1e-9);
}

/// GNSS position error: stationary standard deviation σ and lag-one
/// autocorrelation e^{−Δt/τ} of its Gauss–Markov process.
#[test]
fn gnss_error_autocorrelation_matches_its_time_constant() {
    let params = GnssParams { position_std: 1.5, position_correlation_time: 2.0, ..GnssParams::default() };
    let mut gnss = Gnss::new(params, 3);
    let state = QuadState::default();
    let dt = 1.0 / params.rate_hz;
    let e: Vec<f64> = (0..200_000)
        .map(|k| match gnss.sample(&truth_at(k as f64 * dt, &state), dt) {
            Reading::Gnss(r) => r.position[0],
            _ => unreachable!(),
        })
        .collect();
    let n = e.len() as f64;
    let var = e.iter().map(|x| x * x).sum::<f64>() / n;
    assert!((var.sqrt() / 1.5 - 1.0).abs() < 0.05, "std {}", var.sqrt());
    for lag in [1usize, 8, 16] {
        let c = e.windows(lag + 1).map(|w| w[0] * w[lag]).sum::<f64>() / (n - lag as f64) / var;
        let want = ftsmc_core::math::exp(-(lag as f64) * dt / 2.0);
        assert!((c - want).abs() < 0.03, "lag {lag}: autocorrelation {c} vs {want}");
    }
}

/// Fix loss: the chain's fraction of time without a fix is
/// mean_outage / (mean_fix + mean_outage); the scheduled window has no fix
/// and NaN readings.
#[test]
fn gnss_fix_loss() {
    let params =
        GnssParams { mean_fix_s: 30.0, mean_outage_s: 10.0, outage: Some([5.0, 6.0]), ..GnssParams::default() };
    let mut gnss = Gnss::new(params, 11);
    let state = QuadState::default();
    let dt = 1.0 / params.rate_hz;
    let (mut lost, n) = (0usize, 400_000usize);
    for k in 0..n {
        let t = 1000.0 + k as f64 * dt;
        if let Reading::Gnss(r) = gnss.sample(&truth_at(t, &state), dt) {
            if !r.fix {
                lost += 1;
                assert!(r.position[0].is_nan());
            }
        }
    }
    let fraction = lost as f64 / n as f64;
    assert!((fraction - 0.25).abs() < 0.03, "outage fraction {fraction}");
    let mut gnss = Gnss::new(GnssParams { outage: Some([5.0, 6.0]), ..GnssParams::default() }, 11);
    let Reading::Gnss(r) = gnss.sample(&truth_at(5.5, &state), dt) else { panic!() };
    assert!(!r.fix && r.velocity[2].is_nan());
    let Reading::Gnss(r) = gnss.sample(&truth_at(6.0, &state), dt) else { panic!() };
    assert!(r.fix && r.position[0].is_finite());
}

/// The ISA troposphere: 101325 Pa at sea level, 89874.6 Pa at 1000 m
/// (U.S. Standard Atmosphere 1976, Table I), and the altitude of a
/// pressure is its inverse; the barometer's drift grows at its rate and
/// its noise has its std.
#[test]
fn barometer_isa_noise_and_drift() {
    assert!((isa_pressure(0.0) - 101_325.0).abs() < 1e-9);
    assert!((isa_pressure(1000.0) - 89_874.6).abs() < 1.0, "{}", isa_pressure(1000.0));
    for h in [-200.0, 0.0, 37.5, 1500.0, 9000.0] {
        assert!((isa_altitude(isa_pressure(h)) - h).abs() < 1e-6);
    }
    let params = BaroParams { drift_rate: 0.5, origin_altitude: 400.0, ..BaroParams::default() };
    let mut baro = Baro::new(params, 5);
    let state = QuadState { position: [0.0, 0.0, 10.0], ..QuadState::default() };
    let dt = 1.0 / params.rate_hz;
    let n = 20_000;
    let mut residual = Vec::with_capacity(n);
    for k in 0..n {
        let Reading::Baro(r) = baro.sample(&truth_at(k as f64 * dt, &state), dt) else { panic!() };
        residual.push(r.pressure - isa_pressure(410.0) - 0.5 * k as f64 * dt);
    }
    let mean = residual.iter().sum::<f64>() / n as f64;
    let std = (residual.iter().map(|r| (r - mean) * (r - mean)).sum::<f64>() / n as f64).sqrt();
    assert!(mean.abs() < 0.05 && (std - 1.0).abs() < 0.03, "mean {mean}, std {std}");
    assert!((baro.drift() - 0.5 * n as f64 * dt).abs() < 1e-6);
    // The altitude is that of the drifted pressure (1 Pa RMS noise is
    // about 9 cm): 500 Pa of drift reads some 43 m low.
    let drift = baro.drift();
    let Reading::Baro(r) = baro.sample(&truth_at(0.0, &state), dt) else { panic!() };
    let want = isa_altitude(isa_pressure(410.0) + drift) - 400.0;
    assert!((r.altitude - want).abs() < 0.5 && want < -30.0, "{} vs {want}", r.altitude);
}

/// The magnetometer: level at yaw 0 it reads the world field, whose
/// horizontal heading is the declination and dip the inclination; yawed
/// by the declination the field's horizontal part is along body x.
#[test]
fn magnetometer_field_and_declination_geometry() {
    let params = MagParams {
        declination: 0.2,
        inclination: 1.0,
        noise_std: [0.0; 3],
        hard_iron: [0.01, -0.02, 0.03],
        ..MagParams::default()
    };
    let w = params.world_field();
    assert!((ftsmc_core::math::atan2(w[1], w[0]) - 0.2).abs() < 1e-12);
    assert!((ftsmc_core::math::atan2(-w[2], (w[0] * w[0] + w[1] * w[1]).sqrt()) - 1.0).abs() < 1e-12);
    assert!(((w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt() - 0.5).abs() < 1e-12);
    let mut mag = Mag::new(params, 2);
    let level = QuadState::default();
    let Reading::Mag(r) = mag.sample(&truth_at(0.0, &level), 0.02) else { panic!() };
    for k in 0..3 {
        assert!((r.field[k] - w[k] - params.hard_iron[k]).abs() < 1e-12);
    }
    let yawed = QuadState { attitude: [0.0, 0.0, 0.2], ..QuadState::default() };
    let Reading::Mag(r) = mag.sample(&truth_at(0.0, &yawed), 0.02) else { panic!() };
    assert!((r.field[1] - params.hard_iron[1]).abs() < 1e-12, "{:?}", r.field);
    assert!(r.field[0] > 0.0);
}

/// Same key ⇒ same bits; reseeding re-derives the draws (those of a fresh
/// model of the new key) and changes them.
#[test]
fn determinism_and_reseed() {
    let state = QuadState { position: [1.0, 2.0, 3.0], ..QuadState::default() };
    let run = |key: u64, reseed: Option<u64>| {
        let mut stage = Stage::new(Gnss::new(GnssParams::default(), key), GnssParams::default().clock());
        let mut out = Vec::new();
        for k in 0..400 {
            if k == 200 {
                if let Some(r) = reseed {
                    stage.reseed(r);
                }
            }
            stage.step(&truth_at(k as f64 * 0.005, &state), &mut |s| {
                if let Reading::Gnss(g) = s.reading {
                    out.push(g.position[0].to_bits());
                }
            });
        }
        out
    };
    assert_eq!(run(9, None), run(9, None));
    assert_ne!(run(9, None), run(10, None));
    let (a, b) = (run(9, None), run(9, Some(77)));
    let half = a.len() / 2 - 2;
    assert_eq!(a[..half], b[..half]);
    assert_ne!(a[half + 4..], b[half + 4..]);
    // IMU too.
    let p = ImuParams::of_class(ImuClass::Px4Sitl);
    let sample = |imu: &mut Imu| match imu.sample(&truth_at(0.0, &state), 0.004) {
        Reading::Imu(r) => r.body_rates.map(f64::to_bits),
        _ => unreachable!(),
    };
    let (mut x, mut y) = (Imu::new(&p, 4), Imu::new(&p, 4));
    assert_eq!(sample(&mut x), sample(&mut y));
    y.reseed(5);
    assert_ne!(sample(&mut x), sample(&mut y));
}

/// The stage's clock and latency line: a 10 Hz sensor stepped at 1 kHz
/// takes a sample every 100 steps and hands it on 150 ms later.
#[test]
fn stage_clock_and_latency() {
    let state = QuadState::default();
    let clock = StageClock { rate_hz: 10.0, latency_s: 0.15 };
    let mut stage =
        Stage::new(Baro::new(BaroParams { rate_hz: 10.0, latency_s: 0.15, ..BaroParams::default() }, 1), clock);
    let mut got = Vec::new();
    for k in 0..1000u32 {
        let t = f64::from(k) * 1e-3;
        stage.step(&truth_at(t, &state), &mut |s| got.push((s.t_sample, s.t_available, t)));
    }
    assert_eq!(got.len(), 9, "{got:?}");
    for (i, (ts, ta, t)) in got.iter().enumerate() {
        assert!((ts - i as f64 * 0.1).abs() < 1e-9 && (ta - ts - 0.15).abs() < 1e-9 && (t - ta).abs() < 1e-9);
    }
    let mut row = [0.0; 2];
    stage.record(&mut row);
    assert!(row[0] > 9e4 && row[1].abs() < 1.0, "{row:?}");
}

/// The motion-capture stage gives [`Sensors::measure_full`]'s bits, and
/// passthrough hands them on; before any reading passthrough fails with a
/// reason and a time instead of inventing a state.
#[test]
fn passthrough_keeps_the_motion_capture_bits() {
    let mut params = SensorParams::default();
    params.position.std = [0.01, 0.02, 0.0];
    params.angular_rate.std = [1e-3; 3];
    params.latency = 3;
    let mut legacy = Sensors::new(params, 500.0, 42);
    let mut stage = MotionCapture::new(params, 500.0, 42);
    let mut est = Passthrough::default();
    let err = est.output(0.0).unwrap_err();
    assert_eq!(err.reason, FailureReason::NoReading);
    for k in 0..300 {
        let s =
            QuadState { position: [k as f64 * 1e-3, 0.5, 1.0], angular_rate: [0.1, 0.0, 0.2], ..QuadState::default() };
        let want = legacy.measure_full(&Measurement::euler(s));
        stage.step(&truth_at(k as f64 / 500.0, &s), &mut |r| est.accept(r));
        let got = est.output(k as f64 / 500.0).unwrap();
        assert_eq!(got.euler.to_array().map(f64::to_bits), want.euler.to_array().map(f64::to_bits), "period {k}");
    }
}

/// An estimator without the sensors it needs is refused with its name and
/// the missing quantity.
#[test]
fn estimator_without_its_sources_is_refused() {
    let est = Passthrough::default();
    let gnss = Stage::new(Gnss::new(GnssParams::default(), 1), GnssParams::default().clock());
    let imu_params = ImuParams::of_class(ImuClass::Px4Sitl);
    let imu = Stage::new(Imu::new(&imu_params, 1), imu_params.clock());
    let e = check_sources(&est, &[&gnss, &imu]).unwrap_err();
    assert!(e.contains("sensors.estimator = \"passthrough\"") && e.contains("attitude"), "{e}");
    assert!(!e.contains("position"), "{e}");
    let mocap = MotionCapture::new(SensorParams::default(), 500.0, 1);
    assert!(check_sources(&est, &[&mocap]).is_ok());
}

/// Bad values are refused with the key named: a rate above the physics
/// rate, non-positive rates and densities, NaN.
#[test]
fn bad_sensor_parameters_are_refused_naming_the_key() {
    let physics = 2000.0;
    let field = |r: Result<(), ftsmc_core::law::GainError>| r.unwrap_err().to_string();
    let gnss = GnssParams { rate_hz: -1.0, ..GnssParams::default() };
    assert!(field(gnss.check(physics)).starts_with("gnss.rate_hz = -1"));
    let gnss = GnssParams { rate_hz: 4000.0, ..GnssParams::default() };
    assert!(field(gnss.check(physics)).contains("simulation.control_rate"));
    let gnss = GnssParams { position_std: f64::NAN, ..GnssParams::default() };
    assert!(field(gnss.check(physics)).starts_with("gnss.position_std = NaN"));
    let gnss = GnssParams { mean_fix_s: 10.0, mean_outage_s: 0.0, ..GnssParams::default() };
    assert!(field(gnss.check(physics)).starts_with("gnss.mean_outage_s"));
    let mut imu = ImuParams::of_class(ImuClass::Bmi088);
    imu.gyroscope.noise_density = 0.0;
    assert!(field(imu.check(physics)).starts_with("inertial.gyroscope.noise_density = 0"));
    let mut imu = ImuParams::of_class(ImuClass::Bmi088);
    imu.accelerometer.noise_density = -1e-3;
    assert!(field(imu.check(physics)).starts_with("inertial.accelerometer.noise_density"));
    let mut imu = ImuParams::of_class(ImuClass::Bmi088);
    imu.latency_s = f64::NAN;
    assert!(field(imu.check(physics)).starts_with("inertial.latency_s"));
    let baro = BaroParams { noise_std: -1.0, ..BaroParams::default() };
    assert!(field(baro.check(physics)).starts_with("barometer.noise_std = -1"));
    let mag = MagParams { strength: 0.0, ..MagParams::default() };
    assert!(field(mag.check(physics)).starts_with("magnetometer.strength = 0"));
    let mag = MagParams { inclination: 2.0, ..MagParams::default() };
    assert!(field(mag.check(physics)).starts_with("magnetometer.inclination"));
    // The defaults and classes pass.
    assert!(GnssParams::default().check(physics).is_ok());
    assert!(BaroParams::default().check(physics).is_ok());
    assert!(MagParams::default().check(physics).is_ok());
    assert!(ImuParams::of_class(ImuClass::Px4Sitl).check(physics).is_ok());
    assert!(ImuParams::of_class(ImuClass::Bmi088).check(physics).is_ok());
    // A BMI088 at 1 kHz is faster than a 500 Hz physics step.
    assert!(field(ImuParams::of_class(ImuClass::Bmi088).check(500.0)).starts_with("inertial.rate_hz = 1000"));
    // Unknown keys are refused by the TOML tables.
    let e = toml::from_str::<GnssParams>("rate_hz = 5.0\nrate = 3.0").unwrap_err().to_string();
    assert!(e.contains("rate"), "{e}");
    let ok: GnssParams = toml::from_str("rate_hz = 5.0\nlatency_s = 0.1").unwrap();
    assert_eq!((ok.rate_hz, ok.latency_s), (5.0, 0.1));
}
