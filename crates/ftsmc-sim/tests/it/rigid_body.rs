//! The rigid-body truth model against hand computations, the paper plant,
//! and the conservation laws of torque-free flight.

use ftsmc_core::allocation::{forces_from_squared_speeds, residual_speed, rotor_speeds};
use ftsmc_core::model::{Command, QuadState, QuadrotorParams};
use ftsmc_sim::vehicle::paper as plant;
use ftsmc_sim::vehicle::rigid_body::{index, STATE_LEN};
use ftsmc_sim::vehicle::{
    body_rates_to_euler_rates, euler_rates_to_body_rates, euler_to_quaternion, from_quad_state, quaternion_to_euler,
    to_quad_state, try_to_quad_state, Configuration, RigidBody, RigidBodyInput, RigidBodyParams, RigidBodyState,
};

fn paper_body(p: &QuadrotorParams) -> RigidBody {
    RigidBody::new(RigidBodyParams::from_paper(p)).unwrap()
}

fn level_state(yaw: f64) -> RigidBodyState {
    from_quad_state(&QuadState { position: [0.3, -0.2, 1.0], attitude: [0.0, 0.0, yaw], ..QuadState::default() })
}

fn quat_norm(x: &RigidBodyState) -> f64 {
    x[index::QUATERNION..index::QUATERNION + 4].iter().map(|v| v * v).sum::<f64>().sqrt()
}

#[test]
fn hover_rotor_speeds_from_the_paper_allocation_are_an_equilibrium() {
    let p = QuadrotorParams::default();
    let body = paper_body(&p);
    let hover = Command { thrust: p.mass * p.gravity, torque: [0.0; 3] };
    let omega = rotor_speeds(&p, &hover, f64::INFINITY);
    assert!((omega[0] - body.params().hover_rotor_speed()).abs() < 1e-9);
    for yaw in [0.0, 0.4, -2.5] {
        let d = body.derivative(&level_state(yaw), &RigidBodyInput { rotor_speeds: omega, ..Default::default() });
        assert!(d.iter().all(|v| v.abs() < 1e-12), "yaw {yaw}: {d:?}");
    }
}

#[test]
fn allocation_matrix_is_paper_eq_2() {
    let p = QuadrotorParams::default();
    let a = RigidBodyParams::from_paper(&p).allocation_matrix();
    let w = [5.0e4, 6.1e4, 7.3e4, 4.4e4];
    let c = forces_from_squared_speeds(&p, &w);
    let row = |k: usize| (0..4).map(|i| a[k][i] * w[i]).sum::<f64>();
    let expected = [c.thrust, c.torque[0], c.torque[1], c.torque[2]];
    for k in 0..4 {
        assert!((row(k) - expected[k]).abs() <= 1e-12 * expected[k].abs().max(1e-3), "row {k}");
    }
}

#[test]
fn yaw_torque_from_a_moment_imbalance() {
    // ω1² = ω3² = w(1+δ), ω2² = ω4² = w(1−δ): thrust unchanged, roll/pitch
    // zero, yaw torque k_m (ω1² − ω2² + ω3² − ω4²) = 4 k_m w δ.
    let p = QuadrotorParams::default();
    let body = paper_body(&p);
    let w = p.mass * p.gravity / (4.0 * p.lift_coefficient);
    let delta = 0.1;
    let hi = (w * (1.0 + delta)).sqrt();
    let lo = (w * (1.0 - delta)).sqrt();
    let input = RigidBodyInput { rotor_speeds: [hi, lo, hi, lo], ..Default::default() };
    let d = body.derivative(&level_state(0.0), &input);
    let yaw_accel = 4.0 * p.yaw_drag_coefficient * w * delta / p.inertia[2];
    assert!((d[index::BODY_RATES + 2] - yaw_accel).abs() < 1e-12 * yaw_accel, "{d:?}");
    for k in [index::VELOCITY, index::VELOCITY + 1, index::VELOCITY + 2, index::BODY_RATES, index::BODY_RATES + 1] {
        assert!(d[k].abs() < 1e-12, "component {k}: {}", d[k]);
    }
}

#[test]
fn translational_lift_adds_k_h_times_the_in_plane_airspeed_squared_to_each_rotor() {
    // RotorPy's translational lift: T_i += k_h (v_x² + v_y²) of rotor i's local
    // airspeed in body axes. Off by default; on, a level vehicle flying at
    // (3, −1, 0.5) m/s in still air gains 4 k_h (9 + 1) N of thrust.
    let base = RigidBodyParams { rotor_inertia: 0.0, ..RigidBodyParams::from_paper(&QuadrotorParams::default()) };
    assert_eq!(base.translational_lift, 0.0, "off by default");
    let lifted = RigidBodyParams { translational_lift: 3.39e-3, ..base };
    let omega = base.hover_rotor_speed();
    let mut x = level_state(0.0);
    x[index::VELOCITY..index::VELOCITY + 3].copy_from_slice(&[3.0, -1.0, 0.5]);
    let input = RigidBodyInput { rotor_speeds: [omega; 4], ..Default::default() };
    let off = RigidBody::new(base).unwrap().body_wrench(&x, &input);
    let on = RigidBody::new(lifted).unwrap().body_wrench(&x, &input);
    let extra = 4.0 * lifted.translational_lift * (9.0 + 1.0);
    assert!((on.force[2] - off.force[2] - extra).abs() < 1e-12, "{} vs {}", on.force[2] - off.force[2], extra);
    assert_eq!((on.force[0], on.force[1]), (off.force[0], off.force[1]), "lift acts along body z only");
    // Equal on every rotor: no moment.
    for k in 0..3 {
        assert!((on.torque[k] - off.torque[k]).abs() < 1e-12, "torque {:?} vs {:?}", on.torque, off.torque);
    }
    // A negative coefficient is refused by name.
    let bad = RigidBodyParams { translational_lift: -1.0, ..base };
    assert_eq!(RigidBody::new(bad).unwrap_err().field, "translational_lift");
}

#[test]
fn rotor_and_parasitic_drag_at_a_known_airspeed() {
    let params = RigidBodyParams {
        rotor_drag_xy: 1.0e-4,
        rotor_drag_z: 2.0e-4,
        parasitic_drag: [0.5e-2, 0.7e-2, 1e-2],
        rotor_inertia: 0.0,
        ..RigidBodyParams::from_paper(&QuadrotorParams::default())
    };
    let body = RigidBody::new(params).unwrap();
    let omega = params.hover_rotor_speed();
    // Yaw 90°: body x is world y, body y is world −x.
    let mut x = level_state(core::f64::consts::FRAC_PI_2);
    x[index::VELOCITY..index::VELOCITY + 3].copy_from_slice(&[2.0, -1.0, 0.5]);
    let wind = [0.5, 0.0, 0.0];
    let input = RigidBodyInput { rotor_speeds: [omega; 4], wind, ..Default::default() };
    // Air velocity in the world (1.5, −1, 0.5) → body (−1, −1.5, 0.5).
    let va = [-1.0, -1.5, 0.5];
    let speed = (1.0f64 + 2.25 + 0.25).sqrt();
    let expected = [
        -4.0 * omega * params.rotor_drag_xy * va[0] - speed * params.parasitic_drag[0] * va[0],
        -4.0 * omega * params.rotor_drag_xy * va[1] - speed * params.parasitic_drag[1] * va[1],
        params.mass * params.gravity
            - 4.0 * omega * params.rotor_drag_z * va[2]
            - speed * params.parasitic_drag[2] * va[2],
    ];
    let w = body.body_wrench(&x, &input);
    for k in 0..3 {
        assert!((w.force[k] - expected[k]).abs() < 1e-12, "force {k}: {:?} vs {expected:?}", w.force);
        // Same drag on every rotor and Σ r_i = 0: no moment.
        assert!(w.torque[k].abs() < 1e-12, "torque {:?}", w.torque);
    }
    // World acceleration: body force rotated by 90° about z, weight cancelled.
    let d = body.derivative(&x, &input);
    let m = params.mass;
    let acc = [-expected[1] / m, expected[0] / m, expected[2] / m - params.gravity];
    for k in 0..3 {
        assert!((d[index::VELOCITY + k] - acc[k]).abs() < 1e-12, "{k}: {} vs {}", d[index::VELOCITY + k], acc[k]);
    }

    // A yaw rate r with the vehicle at rest in still air: every rotor sees
    // the tangential airspeed Ω × r_i; Σ r_i × H_i = −4 ω k_d l² r ẑ.
    let mut spin = level_state(0.0);
    spin[index::BODY_RATES + 2] = 3.0;
    let w = body.body_wrench(&spin, &RigidBodyInput { rotor_speeds: [omega; 4], ..Default::default() });
    let l = params.arm_length;
    let damping = -4.0 * omega * params.rotor_drag_xy * l * l * 3.0;
    assert!((w.torque[2] - damping).abs() < 1e-12 * damping.abs(), "{:?} vs {damping}", w.torque);
    assert!(w.force[0].abs() < 1e-15 && w.force[1].abs() < 1e-15);
}

#[test]
fn gyroscopic_torque_hand_computed() {
    // ω1 = ω3 = a (clockwise), ω2 = ω4 = b (counter-clockwise):
    // h_r = J_r (2b − 2a) ẑ; with Ω = (p, q, 0), −Ω × h_r = (−q h, p h, 0).
    let p = QuadrotorParams::default();
    let body = paper_body(&p);
    let (a, b) = (260.0, 230.0);
    let h = p.rotor_inertia * (2.0 * b - 2.0 * a);
    let mut x = level_state(0.0);
    x[index::BODY_RATES] = 0.7;
    x[index::BODY_RATES + 1] = -0.4;
    let d = body.derivative(&x, &RigidBodyInput { rotor_speeds: [a, b, a, b], ..Default::default() });
    let expected_x = -(-0.4) * h / p.inertia[0];
    let expected_y = 0.7 * h / p.inertia[1];
    assert!((d[index::BODY_RATES] - expected_x).abs() < 1e-12, "{} vs {expected_x}", d[index::BODY_RATES]);
    assert!((d[index::BODY_RATES + 1] - expected_y).abs() < 1e-12, "{} vs {expected_y}", d[index::BODY_RATES + 1]);
}

/// Commands, Euler states and the paper plant's accelerations for the
/// comparisons below (paper drags set to zero: aero off).
/// Returns (translational, rotational differences, paper gyroscopic term,
/// this model's gyroscopic term), accelerations in m/s² and rad/s².
fn compare_with_paper(rotor_inertia: f64, eps: f64) -> ([f64; 3], [f64; 3], [f64; 3], [f64; 3]) {
    let p = QuadrotorParams {
        drag_translational: [0.0; 3],
        drag_rotational: [0.0; 3],
        rotor_inertia,
        ..QuadrotorParams::default()
    };
    let body = paper_body(&p);
    let command = Command { thrust: 7.9, torque: [1.2e-2, -0.8e-2, 1.5e-3] };
    let omega = rotor_speeds(&p, &command, f64::INFINITY);
    let state = QuadState {
        position: [1.0, 2.0, 3.0],
        attitude: [0.8 * eps, -0.6 * eps, 0.7],
        velocity: [0.4, -0.3, 0.2],
        angular_rate: [0.9 * eps, 0.5 * eps, -1.1 * eps],
    };
    let paper = plant::derivative(&state.to_array(), &command, residual_speed(&omega), &p, &[0.0; 6]);
    let x = from_quad_state(&state);
    let d = body.derivative(&x, &RigidBodyInput { rotor_speeds: omega, ..Default::default() });
    let mut trans = [0.0; 3];
    let mut rot = [0.0; 3];
    let mut gyro = [0.0; 3];
    for k in 0..3 {
        trans[k] = d[index::VELOCITY + k] - paper[plant::index::VX + k];
        // The paper plant takes body torques as Euler accelerations.
        rot[k] = d[index::BODY_RATES + k] - paper[plant::index::P + k];
        assert!((d[index::POSITION + k] - paper[k]).abs() < 1e-15);
    }
    let omega_bar = residual_speed(&omega);
    gyro[0] = -rotor_inertia * omega_bar * state.angular_rate[1] / p.inertia[0];
    gyro[1] = rotor_inertia * omega_bar * state.angular_rate[0] / p.inertia[1];
    // −Ω × h_r with h_r = J_r Σ s_i ω_i ẑ = −J_r Ω̄ ẑ and body rates Ω.
    let body_rates = &x[index::BODY_RATES..index::BODY_RATES + 3];
    let h = -rotor_inertia * omega_bar;
    let gyro_body = [-body_rates[1] * h / p.inertia[0], body_rates[0] * h / p.inertia[1], 0.0];
    (trans, rot, gyro, gyro_body)
}

#[test]
fn small_angle_agreement_with_the_paper_plant() {
    // Without rotor gyroscopic effects and aerodynamics, the same command:
    // translation agrees exactly (same Z-Y-X rotation); the body angular
    // acceleration matches the paper's Euler acceleration, with angles and
    // rates of order ε, to O(ε³): body rates differ from Euler rates by
    // O(ε²) and enter only through Ω × JΩ (measured: 8.4e-4, 1.0e-4,
    // 1.2e-5 rad/s² at ε = 0.1, 0.05, 0.025).
    let mut last = f64::NAN;
    for eps in [0.1, 0.05, 0.025] {
        let (trans, rot, _, _) = compare_with_paper(0.0, eps);
        for k in 0..3 {
            assert!(trans[k].abs() < 1e-12, "ε {eps}: translational {trans:?}");
        }
        let err = rot.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(err <= eps * eps * eps, "ε {eps}: rotational {rot:?}");
        if last.is_finite() {
            // Halving ε divides the error by about 8 (third order).
            assert!(err <= last / 7.0, "ε {eps}: {err} vs {last}");
        }
        last = err;
    }
}

#[test]
fn gyroscopic_torque_is_opposite_to_the_paper_plant() {
    // With J_r > 0 the two models differ by exactly their gyroscopic terms,
    // and this model's term is the paper's with the opposite sign (to O(ε)
    // relative: body rates vs Euler rates). Module docs of `rigid_body`: the
    // paper's sign corresponds to rotors spinning against its own yaw allocation.
    for eps in [0.1, 0.05, 0.025] {
        let (_, rot, gyro, gyro_body) = compare_with_paper(2.8385e-5, eps);
        let (_, rot0, _, _) = compare_with_paper(0.0, eps);
        for k in 0..2 {
            let diff = rot[k] - rot0[k];
            assert!(gyro[k].abs() > 1e-4, "the test needs a visible gyroscopic term: {gyro:?}");
            assert!((diff - (gyro_body[k] - gyro[k])).abs() < 1e-12, "axis {k}: {diff}");
            assert!(gyro_body[k] * gyro[k] < 0.0, "axis {k}: same sign {gyro_body:?} {gyro:?}");
            let relative = (gyro_body[k] + gyro[k]).abs() / gyro[k].abs();
            assert!(relative < 2.0 * eps, "axis {k}: {relative}");
        }
    }
}

/// A tumbling body: full asymmetric inertia, rates near the intermediate axis.
fn tumbling() -> (RigidBody, RigidBodyState) {
    let params = RigidBodyParams {
        inertia: [[2.0e-3, 1.0e-4, -2.0e-4], [1.0e-4, 3.5e-3, 1.5e-4], [-2.0e-4, 1.5e-4, 5.0e-3]],
        ..RigidBodyParams::default()
    };
    let body = RigidBody::new(params).unwrap();
    let mut x = from_quad_state(&QuadState {
        position: [0.0, 0.0, 10.0],
        attitude: [0.3, -0.2, 1.0],
        velocity: [1.0, 0.0, 2.0],
        ..QuadState::default()
    });
    x[index::BODY_RATES..index::BODY_RATES + 3].copy_from_slice(&[0.2, 4.0, -0.3]);
    (body, x)
}

#[test]
fn torque_free_tumbling_conserves_angular_momentum_and_energy() {
    // 10 s at 1 kHz (RK4, renormalised): measured drift 1.1e-12 (‖L‖
    // relative) and 7e-14 (energy relative).
    let (body, mut x) = tumbling();
    let input = RigidBodyInput::default();
    let l0 = body.angular_momentum_world(&x, &input.rotor_speeds);
    let e0 = body.rotational_energy(&x);
    let l_norm = l0.iter().map(|v| v * v).sum::<f64>().sqrt();
    let mut max_axis_change = 0.0f64;
    let omega0 = [x[10], x[11], x[12]];
    for _ in 0..10_000 {
        x = body.step(&x, &input, 1e-3);
        let l = body.angular_momentum_world(&x, &input.rotor_speeds);
        for k in 0..3 {
            assert!((l[k] - l0[k]).abs() < 1e-11 * l_norm, "L drifted: {l:?} vs {l0:?}");
        }
        let e = body.rotational_energy(&x);
        assert!((e - e0).abs() < 1e-12 * e0, "energy drifted: {e} vs {e0}");
        max_axis_change = max_axis_change.max((x[11] - omega0[1]).abs());
    }
    // It really tumbles: the rate about the intermediate axis changes sign.
    assert!(max_axis_change > 4.0, "{max_axis_change}");
    // Free fall: the centre of mass follows the parabola exactly (RK4 is exact for it).
    assert!((x[index::POSITION + 2] - (10.0 + 2.0 * 10.0 - 0.5 * 9.81 * 100.0)).abs() < 1e-9);
}

#[test]
fn quaternion_norm_is_preserved() {
    let (body, x0) = tumbling();
    let input = RigidBodyInput::default();
    // Short horizon (1 s at 1 kHz), no renormalisation: RK4 alone.
    let mut x = x0;
    for _ in 0..1000 {
        x = body.step_unnormalized(&x, &input, 1e-3);
    }
    // Measured: 7e-15.
    assert!((quat_norm(&x) - 1.0).abs() < 1e-12, "{}", quat_norm(&x) - 1.0);
    // With renormalisation, any horizon: to rounding.
    let mut x = x0;
    for _ in 0..20_000 {
        x = body.step(&x, &input, 1e-3);
    }
    assert!((quat_norm(&x) - 1.0).abs() < 4.0 * f64::EPSILON, "{}", quat_norm(&x) - 1.0);
}

#[test]
fn euler_quaternion_and_rate_conversions_round_trip() {
    for &euler in &[[0.0, 0.0, 0.0], [0.3, -0.2, 1.0], [-2.9, 1.2, -3.0], [1.0, -1.5, 2.5]] {
        let q = euler_to_quaternion(&euler);
        let back = quaternion_to_euler(&q);
        let back_neg = quaternion_to_euler(&q.map(|v| -v));
        for k in 0..3 {
            assert!((back[k] - euler[k]).abs() < 1e-12, "{euler:?} → {back:?}");
            assert!((back_neg[k] - euler[k]).abs() < 1e-12);
        }
        let rates = [0.4, -1.3, 2.2];
        let body = euler_rates_to_body_rates(&euler, &rates);
        let again = body_rates_to_euler_rates(&euler, &body).unwrap();
        for k in 0..3 {
            assert!((again[k] - rates[k]).abs() < 1e-10 * (1.0 + rates[k].abs()), "{euler:?}: {again:?}");
        }
    }
    // Euler angles via the quaternion give the paper's thrust direction.
    let euler = [0.3, -0.2, 1.0];
    let r = ftsmc_sim::vehicle::rigid_body::rotation_matrix(&euler_to_quaternion(&euler));
    let (sf, cf) = ftsmc_core::math::sin_cos(euler[0]);
    let (st, ct) = ftsmc_core::math::sin_cos(euler[1]);
    let (sp, cp) = ftsmc_core::math::sin_cos(euler[2]);
    let z_b = [cf * st * cp + sf * sp, cf * st * sp - sf * cp, cf * ct];
    for k in 0..3 {
        assert!((r[k][2] - z_b[k]).abs() < 1e-15);
    }
}

#[test]
fn quad_state_round_trip_and_gimbal_lock() {
    let s = QuadState {
        position: [1.0, -2.0, 3.0],
        attitude: [0.2, -0.4, 2.0],
        velocity: [0.5, 0.6, -0.7],
        angular_rate: [0.3, -0.9, 1.4],
    };
    let x = from_quad_state(&s);
    assert_eq!(x.len(), STATE_LEN);
    let back = try_to_quad_state(&x).unwrap();
    let a = back.to_array();
    let b = s.to_array();
    for k in 0..12 {
        assert!((a[k] - b[k]).abs() < 1e-12, "{k}: {a:?} vs {b:?}");
    }
    assert_eq!(to_quad_state(&x), back);

    // Pitch exactly 90°: the checked conversion refuses, the clamped one stays finite.
    let mut locked = x;
    locked[index::QUATERNION..index::QUATERNION + 4].copy_from_slice(&euler_to_quaternion(&[
        0.0,
        core::f64::consts::FRAC_PI_2,
        0.0,
    ]));
    assert!(try_to_quad_state(&locked).is_err());
    let clamped = to_quad_state(&locked);
    assert!(clamped.angular_rate.iter().all(|v| v.is_finite()), "{clamped:?}");
}

#[test]
fn cross_layout_and_presets_check() {
    for params in [RigidBodyParams::default(), RigidBodyParams::crazyflie(), RigidBodyParams::hummingbird()] {
        params.check().unwrap();
    }
    let cf = RigidBodyParams::crazyflie();
    assert_eq!(cf.configuration, Configuration::Cross);
    let r = cf.rotor_positions();
    for ri in r {
        assert!(((ri[0] * ri[0] + ri[1] * ri[1]).sqrt() - cf.arm_length).abs() < 1e-15);
    }
    // Rotor 1 front-left, 2 front-right (RotorPy's layout).
    assert!(r[0][0] > 0.0 && r[0][1] > 0.0 && r[1][0] > 0.0 && r[1][1] < 0.0);
}

#[test]
fn params_check_and_serde() {
    let bad =
        RigidBodyParams { inertia: [[1e-3, 2e-3, 0.0], [2e-3, 1e-3, 0.0], [0.0, 0.0, 1e-3]], ..Default::default() };
    assert!(bad.check().is_err(), "indefinite inertia must be refused");
    let asym =
        RigidBodyParams { inertia: [[1e-3, 1e-4, 0.0], [0.0, 1e-3, 0.0], [0.0, 0.0, 1e-3]], ..Default::default() };
    assert_eq!(asym.check().unwrap_err().field, "inertia[0][1]");
    let neg = RigidBodyParams { rotor_drag_xy: -1.0, ..Default::default() };
    assert_eq!(neg.check().unwrap_err().field, "rotor_drag_xy");
    assert!(RigidBody::new(RigidBodyParams { mass: f64::NAN, ..Default::default() }).is_err());

    let text = toml::to_string(&RigidBodyParams::hummingbird()).unwrap();
    let back: RigidBodyParams = toml::from_str(&text).unwrap();
    assert_eq!(back, RigidBodyParams::hummingbird());
    let partial: RigidBodyParams =
        toml::from_str("mass = 1.0\nconfiguration = \"cross\"\nspin = [\"ccw\", \"cw\", \"ccw\", \"cw\"]").unwrap();
    assert_eq!(partial.mass, 1.0);
    assert_eq!(partial.arm_length, RigidBodyParams::default().arm_length);
    assert!(toml::from_str::<RigidBodyParams>("mass = 1.0\nmas = 2.0").is_err());
}
