//! Sensors at their own rates (`[sensors] imu = { sample_rate, latency }`):
//! attitude and rates on the IMU's clock, position and velocity on the
//! motion capture's, each quantity on its own random stream.

use ftsmc_core::model::QuadState;
use ftsmc_sim::sensors::{QuantityError, SensorClock, SensorParams, Sensors};

const CONTROL_HZ: f64 = 1000.0;

fn ramp(v: f64) -> QuadState {
    QuadState { position: [v; 3], attitude: [v; 3], velocity: [v; 3], angular_rate: [v; 3] }
}

fn mocap_and_imu() -> SensorParams {
    SensorParams {
        sample_rate: Some(200.0),
        latency: 6,
        imu: Some(SensorClock { sample_rate: Some(1000.0), latency: 1 }),
        ..SensorParams::default()
    }
}

#[test]
fn the_imu_keeps_its_own_rate_and_latency_and_the_mocap_its_own() {
    let mut s = Sensors::new(mocap_and_imu(), CONTROL_HZ, 3);
    for n in 0..100u32 {
        let seen = s.measure(&ramp(f64::from(n)));
        // IMU: every period, one period late.
        let imu = f64::from(n.saturating_sub(1));
        assert_eq!(seen.attitude, [imu; 3], "n = {n}");
        assert_eq!(seen.angular_rate, [imu; 3], "n = {n}");
        // Mocap: a sample every 5th period, held, 6 periods late.
        let late = n.saturating_sub(6);
        let mocap = f64::from(late - late % 5);
        assert_eq!(seen.position, [mocap; 3], "n = {n}");
        assert_eq!(seen.velocity, [mocap; 3], "n = {n}");
    }
}

#[test]
fn without_an_imu_clock_everything_shares_one_and_noise_streams_do_not_move() {
    let noisy = QuantityError { std: [1e-3; 3], bias: [0.0; 3] };
    let base = SensorParams {
        position: noisy,
        velocity: noisy,
        attitude: noisy,
        angular_rate: noisy,
        sample_rate: Some(1000.0),
        latency: 0,
        ..SensorParams::default()
    };
    let with_imu = SensorParams { imu: Some(SensorClock { sample_rate: Some(1000.0), latency: 0 }), ..base };
    let (mut a, mut b) = (Sensors::new(base, CONTROL_HZ, 9), Sensors::new(with_imu, CONTROL_HZ, 9));
    for n in 0..50 {
        let truth = ramp(0.01 * f64::from(n));
        // Same clocks: the same draws from the same streams, bit for bit.
        let (x, y) = (a.measure(&truth), b.measure(&truth));
        assert_eq!(x.to_array().map(f64::to_bits), y.to_array().map(f64::to_bits), "n = {n}");
    }
}

#[test]
fn bad_imu_clocks_are_refused_by_field() {
    let bad = |c: SensorClock| SensorParams { imu: Some(c), ..SensorParams::default() }.check().unwrap_err().field;
    assert_eq!(bad(SensorClock { sample_rate: Some(0.0), latency: 0 }), "imu.sample_rate");
    assert_eq!(bad(SensorClock { sample_rate: Some(f64::NAN), latency: 0 }), "imu.sample_rate");
    assert_eq!(bad(SensorClock { sample_rate: None, latency: 200_000 }), "imu.latency");
    let p: SensorParams =
        toml::from_str("sample_rate = 200.0\nlatency = 6\nimu = { sample_rate = 1000.0, latency = 1 }").unwrap();
    assert_eq!(p, mocap_and_imu());
    assert!(toml::from_str::<SensorParams>("imu = { rate = 1000.0 }").is_err());
}
