//! Full-state controllers (PID, SE(3)) given the attitude as a quaternion
//! and body rates ([`Measurement::body`]) fly the same law as when they
//! rebuild both from the Euler state: over a swinging, yawing trajectory
//! (tilts to 0.9 rad, every yaw quadrant, rates to 3 rad/s) the commands of
//! two controllers fed the two forms agree to 1e-9 relative (both forms are
//! the same rotation to rounding; the PID's derivative filter divides
//! rounding by dt), and `update_measured` without a body attitude is
//! `update` bit for bit.

use ftsmc_core::controller::Controller;
use ftsmc_core::kinematics::{body_rates_from_euler_rates, quaternion_from_euler};
use ftsmc_core::measured::{BodyAttitude, Measurement};
use ftsmc_core::model::{Command, QuadState, QuadrotorParams, Reference};
use ftsmc_core::{PidController, PidGains, Se3Controller, Se3Gains};

fn state(t: f64) -> QuadState {
    QuadState {
        position: [0.3 * ftsmc_core::math::sin(1.3 * t), -0.2 * ftsmc_core::math::cos(0.7 * t), 1.0 + 0.1 * t],
        velocity: [0.4 * ftsmc_core::math::cos(1.3 * t), 0.1 * ftsmc_core::math::sin(0.7 * t), 0.1],
        attitude: [0.9 * ftsmc_core::math::sin(2.0 * t), -0.7 * ftsmc_core::math::cos(1.5 * t), -3.0 + 1.7 * t],
        angular_rate: [1.8 * ftsmc_core::math::cos(2.0 * t), 1.05 * ftsmc_core::math::sin(1.5 * t), 1.7],
    }
}

fn body(s: &QuadState, negate: bool) -> BodyAttitude {
    let q = quaternion_from_euler(&s.attitude);
    BodyAttitude {
        // q and −q are the same rotation: the controllers must not care.
        quaternion: if negate { q.map(|v| -v) } else { q },
        body_rates: body_rates_from_euler_rates(&s.attitude, &s.angular_rate),
    }
}

fn close(a: &Command, b: &Command) {
    let pairs =
        [(a.thrust, b.thrust), (a.torque[0], b.torque[0]), (a.torque[1], b.torque[1]), (a.torque[2], b.torque[2])];
    for (x, y) in pairs {
        assert!(x.is_finite() && y.is_finite());
        assert!((x - y).abs() <= 1e-9 * x.abs().max(y.abs()).max(1e-3), "{a:?} vs {b:?}");
    }
}

fn fly<C: Controller + Clone>(c: C) {
    let (mut euler, mut quat, mut plain) = (c.clone(), c.clone(), c);
    let reference = Reference { position: [0.5, -0.5, 2.0], yaw: 0.3, yaw_rate: 0.2, ..Reference::default() };
    for k in 0..6000 {
        let t = k as f64 * 1e-3;
        let s = state(t);
        let a = euler.update(&s, &reference, 1e-3);
        let b = quat.update_measured(&Measurement { euler: s, body: Some(body(&s, k % 2 == 1)) }, &reference, 1e-3);
        let c = plain.update_measured(&Measurement::euler(s), &reference, 1e-3);
        close(&a, &b);
        assert_eq!(a, c, "update_measured without a body attitude is update");
        let (ta, tb) = (euler.telemetry(), quat.telemetry());
        for i in 0..3 {
            assert!((ta.attitude_reference[i] - tb.attitude_reference[i]).abs() < 1e-9);
        }
    }
}

#[test]
fn pid_sees_the_same_attitude_through_the_quaternion() {
    let p = QuadrotorParams::default();
    fly(PidController::new(p, PidGains::for_vehicle(&p)).unwrap());
}

#[test]
fn se3_sees_the_same_attitude_through_the_quaternion() {
    let p = QuadrotorParams::default();
    fly(Se3Controller::new(p, Se3Gains::for_vehicle(&p)).unwrap());
}

#[test]
fn a_non_finite_body_attitude_gives_a_nan_command() {
    let p = QuadrotorParams::default();
    let mut c = PidController::new(p, PidGains::for_vehicle(&p)).unwrap();
    let s = state(0.0);
    let mut b = body(&s, false);
    b.body_rates[1] = f64::NAN;
    let cmd = c.update_measured(&Measurement { euler: s, body: Some(b) }, &Reference::default(), 1e-3);
    assert!(cmd.thrust.is_nan());
}

#[test]
fn the_body_attitude_is_what_the_controllers_fly() {
    // Given a body attitude of another rotation, PID and SE(3) follow it,
    // not the Euler angles beside it (otherwise the tests above prove nothing).
    let p = QuadrotorParams::default();
    let s = state(0.4);
    let mut other = s;
    other.attitude[0] += 0.2;
    let m = Measurement { euler: s, body: Some(body(&other, false)) };
    let reference = Reference::default();
    let mut pid = PidController::new(p, PidGains::for_vehicle(&p)).unwrap();
    let (mut pid_other, mut pid_euler) = (pid.clone(), pid.clone());
    let a = pid.update_measured(&m, &reference, 1e-3);
    close(&a, &pid_other.update(&other, &reference, 1e-3));
    assert!((a.torque[0] - pid_euler.update(&s, &reference, 1e-3).torque[0]).abs() > 1e-3);
    let mut se3 = Se3Controller::new(p, Se3Gains::for_vehicle(&p)).unwrap();
    let a = se3.update_measured(&m, &reference, 1e-3);
    let b = se3.clone().update(&s, &reference, 1e-3);
    assert!((a.torque[0] - b.torque[0]).abs() > 1e-3, "{a:?} {b:?}");
}
