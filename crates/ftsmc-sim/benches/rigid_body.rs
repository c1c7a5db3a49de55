//! Speed of one plant integration step (run on demand:
//! `cargo bench -p ftsmc-sim --bench rigid_body`).
//!
//! Each benchmark integrates 1000 RK4 steps of 1 ms with the rotor speeds of
//! a hovering, slightly tilted vehicle held; throughput is in plant steps.
//!
//! - `rk4-step/paper`: paper Eq. 1 ([`ftsmc_sim::vehicle::paper::derivative`] + `rk4_step`).
//! - `rk4-step/rigid-body`: the rigid-body model of the paper vehicle (aero off,
//!   rotor gyroscopic torque on), quaternion renormalised each step.
//! - `rk4-step/rigid-body-aero`: the RotorPy Hummingbird with parasitic and
//!   rotor drag in a 3 m/s wind.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use ftsmc_core::allocation::{residual_speed, rotor_speeds};
use ftsmc_core::model::{Command, QuadState, QuadrotorParams};
use ftsmc_sim::vehicle::paper::{derivative, rk4_step};
use ftsmc_sim::vehicle::{from_quad_state, RigidBody, RigidBodyInput, RigidBodyParams};

const STEPS: u64 = 1000;
const H: f64 = 1e-3;

fn start() -> QuadState {
    QuadState {
        position: [0.0, 0.0, 1.0],
        attitude: [0.05, -0.03, 0.2],
        velocity: [0.5, -0.2, 0.1],
        angular_rate: [0.1, -0.05, 0.02],
    }
}

fn steps(c: &mut Criterion) {
    let p = QuadrotorParams::default();
    let command = Command { thrust: p.mass * p.gravity, torque: [1e-3, -1e-3, 2e-4] };
    let omega = rotor_speeds(&p, &command, f64::INFINITY);
    let omega_bar = residual_speed(&omega);
    let mut group = c.benchmark_group("rk4-step");
    group.throughput(Throughput::Elements(STEPS));

    group.bench_function("paper", |b| {
        b.iter(|| {
            let mut x = start().to_array();
            for k in 0..STEPS {
                x = rk4_step(|_, s| derivative(s, &command, omega_bar, &p, &[0.0; 6]), k as f64 * H, &x, H);
            }
            black_box(x)
        })
    });

    let body = RigidBody::new(RigidBodyParams::from_paper(&p)).unwrap();
    let input = RigidBodyInput { rotor_speeds: omega, ..Default::default() };
    group.bench_function("rigid-body", |b| {
        b.iter(|| {
            let mut x = from_quad_state(&start());
            for _ in 0..STEPS {
                x = body.step(&x, black_box(&input), H);
            }
            black_box(x)
        })
    });

    let hb = RigidBodyParams::hummingbird();
    let aero = RigidBody::new(hb).unwrap();
    let input =
        RigidBodyInput { rotor_speeds: [hb.hover_rotor_speed(); 4], wind: [3.0, 0.0, 0.0], ..Default::default() };
    group.bench_function("rigid-body-aero", |b| {
        b.iter(|| {
            let mut x = from_quad_state(&start());
            for _ in 0..STEPS {
                x = aero.step(&x, black_box(&input), H);
            }
            black_box(x)
        })
    });
    group.finish();
}

criterion_group!(benches, steps);
criterion_main!(benches);
