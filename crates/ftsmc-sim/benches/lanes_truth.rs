//! Speed of the rigid body in lanes (run on demand:
//! `cargo bench -p ftsmc-sim --bench lanes_truth`).
//!
//! One RK4 substep of 1 ms of the RotorPy Hummingbird (parasitic and rotor
//! drag, translational lift, rotor gyroscopic torque, in a 3 m/s wind) as
//! the truth model integrates it: the staged RK4
//! ([`ftsmc_sim::vehicle::paper::rk4_step_staged`]) with the body's rotor
//! terms prepared once per stage time ([`RigidBody::prepare`]), then the
//! quaternion renormalised. On `f64` (one flight) and on `Lanes<4>` and
//! `Lanes<8>` (4 and 8 flights, each lane its own state and rotor speeds);
//! throughput is in flights, so the per-element times compare directly.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use ftsmc_core::lanes::{Lanes, Real};
use ftsmc_core::model::QuadState;
use ftsmc_sim::vehicle::paper::rk4_step_staged;
use ftsmc_sim::vehicle::rigid_body::normalize_quaternion;
use ftsmc_sim::vehicle::{from_quad_state, RigidBody, RigidBodyInput, RigidBodyParams, RigidBodyState};

const H: f64 = 1e-3;
/// Substeps per timed iteration.
const STEPS: u64 = 100;

/// Lane `i`'s start: a slightly tilted vehicle in motion, different per lane.
fn start(i: usize) -> RigidBodyState {
    let a = i as f64 * 0.01;
    from_quad_state(&QuadState {
        position: [0.0, 0.0, 1.0 + a],
        attitude: [0.05 + a, -0.03, 0.2 - a],
        velocity: [0.5, -0.2 + a, 0.1],
        angular_rate: [0.1, -0.05, 0.02 + a],
    })
}

fn substeps<R: Real>(body: &RigidBody<R>, x0: &RigidBodyState<R>, speeds: [R; 4]) -> RigidBodyState<R> {
    let wind = [R::splat(3.0), R::splat(-1.0), R::splat(0.0)];
    let zero = [R::splat(0.0); 3];
    let mut x = *x0;
    for k in 0..STEPS {
        let t = R::splat(k as f64 * H);
        let inputs = |tau: R| {
            // Rotor speeds that depend on the stage time, as lagged motors'.
            let w = speeds.map(|s| s + tau * 10.0);
            body.prepare(&RigidBodyInput { rotor_speeds: w, wind, force: zero, torque: zero })
        };
        x = rk4_step_staged(inputs, |input, s| body.derivative_prepared(s, input), t, &x, R::splat(H));
        normalize_quaternion(&mut x);
    }
    x
}

fn bench_lanes<R: Real>(c: &mut Criterion, group: &str, name: &str) {
    let one = RigidBody::new(RigidBodyParams::hummingbird()).unwrap();
    let hover = RigidBodyParams::hummingbird().hover_rotor_speed();
    let body = RigidBody::<R>::splat(&one);
    let mut x0 = [R::splat(0.0); 13];
    let mut speeds = [R::splat(0.0); 4];
    for i in 0..R::LANES {
        let s = start(i);
        for (k, v) in x0.iter_mut().enumerate() {
            v.put_lane(i, s[k]);
        }
        for (r, v) in speeds.iter_mut().enumerate() {
            v.put_lane(i, hover * (1.0 + 0.01 * (r as f64 - 1.5) + 0.002 * i as f64));
        }
    }
    let mut g = c.benchmark_group(group);
    g.throughput(Throughput::Elements(STEPS * R::LANES as u64));
    g.bench_function(name, |b| b.iter(|| black_box(substeps(black_box(&body), black_box(&x0), black_box(speeds)))));
    g.finish();
}

fn lanes(c: &mut Criterion) {
    bench_lanes::<f64>(c, "rigid-body-substep", "f64");
    bench_lanes::<Lanes<4>>(c, "rigid-body-substep", "lanes-4");
    bench_lanes::<Lanes<8>>(c, "rigid-body-substep", "lanes-8");
}

criterion_group!(benches, lanes);
criterion_main!(benches);
