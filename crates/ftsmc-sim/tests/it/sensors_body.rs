//! The sensor stage's body attitude (`Sensors::measure_full`): with a truth
//! that carries its quaternion and body rates and gyroscope-frame rates, the
//! reading carries the measured attitude as a quaternion and the measured
//! body rates, consistent with its Euler reading; the Euler reading is that
//! of `Sensors::measure` (same draws, clocks and latency): its angles, rates
//! of position and positions bit for bit, its Euler rates to rounding (they
//! take the sines and cosines of the measured angles from the quaternion's
//! half angles).

use ftsmc_core::kinematics::{
    body_rates_from_euler_rates, quaternion_from_euler, rotation_from_euler, rotation_from_quaternion,
};
use ftsmc_core::measured::{BodyAttitude, Measurement};
use ftsmc_core::model::QuadState;
use ftsmc_sim::sensors::{QuantityError, RateFrame, SensorClock, SensorParams, Sensors};

fn truth(n: u32) -> QuadState {
    let t = f64::from(n) * 1e-3;
    QuadState {
        position: [t, -t, 1.0],
        attitude: [0.3 * ftsmc_core::math::sin(5.0 * t), -0.2 * ftsmc_core::math::cos(3.0 * t), 1.0 + t],
        velocity: [1.0, 0.5, 0.0],
        angular_rate: [1.5 * ftsmc_core::math::cos(5.0 * t), 0.6 * ftsmc_core::math::sin(3.0 * t), 1.0],
    }
}

fn params(rates: RateFrame) -> SensorParams {
    let e = |s: f64| QuantityError { std: [s; 3], bias: [0.1 * s; 3] };
    SensorParams {
        position: e(1e-3),
        velocity: e(0.06),
        attitude: e(4e-3),
        angular_rate: e(8.7e-4),
        rates,
        sample_rate: Some(200.0),
        latency: 6,
        imu: Some(SensorClock { sample_rate: Some(1000.0), latency: 1 }),
        ..SensorParams::default()
    }
}

#[test]
fn gyroscope_readings_carry_a_consistent_body_attitude_and_the_same_euler_reading() {
    let (mut full, mut euler) =
        (Sensors::new(params(RateFrame::Body), 1000.0, 7), Sensors::new(params(RateFrame::Body), 1000.0, 7));
    for n in 0..500 {
        let s = truth(n);
        let body = BodyAttitude {
            quaternion: quaternion_from_euler(&s.attitude),
            body_rates: body_rates_from_euler_rates(&s.attitude, &s.angular_rate),
        };
        let m = full.measure_full(&Measurement { euler: s, body: Some(body) });
        let e = euler.measure(&s);
        assert_eq!(
            (m.euler.position, m.euler.velocity, m.euler.attitude),
            (e.position, e.velocity, e.attitude),
            "n = {n}"
        );
        for i in 0..3 {
            let (got, want) = (m.euler.angular_rate[i], e.angular_rate[i]);
            assert!((got - want).abs() <= 1e-14 * (1.0 + want.abs()), "n = {n}: Euler rate {i}: {got} vs {want}");
        }
        let b = m.body.expect("a body attitude with body rates measured");
        let (r, rq) = (rotation_from_euler(&m.euler.attitude), rotation_from_quaternion(&b.quaternion));
        for i in 0..3 {
            for j in 0..3 {
                assert!((r[i][j] - rq[i][j]).abs() < 1e-14);
            }
        }
        let w = body_rates_from_euler_rates(&m.euler.attitude, &m.euler.angular_rate);
        for i in 0..3 {
            assert!((w[i] - b.body_rates[i]).abs() < 1e-12, "n = {n}");
        }
    }
}

#[test]
fn no_body_attitude_without_one_in_the_truth_or_with_euler_rates() {
    let s = truth(3);
    let body = Some(BodyAttitude { quaternion: quaternion_from_euler(&s.attitude), body_rates: [0.0; 3] });
    let mut a = Sensors::new(params(RateFrame::Body), 1000.0, 7);
    assert!(a.measure_full(&Measurement::euler(s)).body.is_none());
    let mut b = Sensors::new(params(RateFrame::Euler), 1000.0, 7);
    assert!(b.measure_full(&Measurement { euler: s, body }).body.is_none());
}
