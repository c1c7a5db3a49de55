//! Setpoint helpers shared by the full-state controllers ([`crate::pid`],
//! [`crate::se3`]): the tilt limit of a thrust direction, the finiteness
//! check of a reference and the sine and cosine of the reference heading
//! kept from one period to the next. Their own module, so neither
//! controller imports the other for them. Generic over the number type
//! ([`crate::lanes`]): the same bits per lane as on `f64`.

use crate::lanes::{branch, Mask, Real};
use crate::math::{cos, finite_probe, sin, Vec3};
use crate::measured::BodyAttitude;
use crate::model::{Command, QuadState, Reference};

/// The tilt limit of a thrust direction with `cos(max_tilt)` and
/// `sin(max_tilt)` taken once (the limit is a gain, constant over a flight
/// and the same in every lane).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct TiltLimit {
    cos: f64,
    sin: f64,
}

impl TiltLimit {
    /// The limit `max_tilt` (rad) from the vertical.
    pub(crate) fn new(max_tilt: f64) -> Self {
        Self { cos: cos(max_tilt), sin: sin(max_tilt) }
    }

    /// Rotate the unit vector `b` towards the vertical so that its angle to
    /// `e₃` is at most `max_tilt` (PX4 `ControlMath::limitTilt`, z up); per
    /// lane for lanes.
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub(crate) fn apply<R: Real>(&self, b: Vec3<R>) -> Vec3<R> {
        let limit_cos = R::splat(self.cos);
        branch(
            b[2].ge(limit_cos),
            #[cfg_attr(not(debug_assertions), inline(always))]
            || b,
            #[cfg_attr(not(debug_assertions), inline(always))]
            || {
                let horizontal = (b[0] * b[0] + b[1] * b[1]).sqrt();
                let (hx, hy) = branch(
                    horizontal.gt(R::splat(1e-12)),
                    #[cfg_attr(not(debug_assertions), inline(always))]
                    || (b[0] / horizontal, b[1] / horizontal),
                    #[cfg_attr(not(debug_assertions), inline(always))]
                    || (R::splat(1.0), R::splat(0.0)),
                );
                // `hx · s`: the product `s hx` with its operands swapped (same bits).
                [hx * self.sin, hy * self.sin, limit_cos]
            },
        )
    }
}

/// Every component of the reference is finite (per lane).
#[cfg_attr(not(debug_assertions), inline(always))]
pub(crate) fn reference_finite<R: Real>(r: &Reference<R>) -> R::Mask {
    (finite_probe(&r.position)
        + finite_probe(&r.velocity)
        + finite_probe(&r.acceleration)
        + finite_probe(&[r.yaw, r.yaw_rate, r.yaw_acceleration]))
    .eq(R::splat(0.0))
}

/// Which lanes of a full-state controller's inputs are finite (state,
/// body attitude when given, reference); `None` when `dt` is not finite or
/// no lane is (every lane then gets [`nan_command`] and keeps its states).
#[cfg_attr(not(debug_assertions), inline(always))]
pub(crate) fn finite_lanes<R: Real>(
    dt: f64,
    state: &QuadState<R>,
    attitude: Option<&BodyAttitude<R>>,
    reference: &Reference<R>,
) -> Option<R::Mask> {
    if !dt.is_finite() {
        return None;
    }
    let mut ok = state.is_finite();
    if let Some(b) = attitude {
        ok = ok & b.is_finite();
    }
    ok = ok & reference_finite(reference);
    ok.any().then_some(ok)
}

/// The command of a lane whose inputs are not finite: NaN thrust and torques.
#[cfg_attr(not(debug_assertions), inline(always))]
pub(crate) fn nan_command<R: Real>() -> Command<R> {
    Command { thrust: R::splat(f64::NAN), torque: [R::splat(f64::NAN); 3] }
}

/// `(sin ψ, cos ψ)` of the last heading ψ (rad), per lane: recomputed
/// ([`Real::sin_cos`]) only when the bits of ψ change in some lane, so a
/// constant heading reference is not reduced and expanded again every
/// period. Always the bits of `sin_cos(ψ)` (as [`crate::math::SinCosCache`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct HeadingSinCos<R: Real> {
    heading: R,
    value: (R, R),
}

impl<R: Real> HeadingSinCos<R> {
    /// A cache holding `sin_cos(0)` in every lane.
    pub(crate) fn new() -> Self {
        let heading = R::splat(0.0);
        Self { heading, value: heading.sin_cos() }
    }

    /// `(sin ψ, cos ψ)`, the bits of [`Real::sin_cos`]`(ψ)`.
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub(crate) fn get(&mut self, heading: R) -> (R, R) {
        if (0..R::LANES).any(|i| heading.get_lane(i).to_bits() != self.heading.get_lane(i).to_bits()) {
            self.value = heading.sin_cos();
            self.heading = heading;
        }
        self.value
    }
}

/// Inputs and comparisons shared by the lane-equivalence tests of the
/// full-state controllers (`pid.rs`, `se3.rs`): a deterministic generator
/// of per-lane flights that take different branches, and the bits of a
/// telemetry record.
#[cfg(test)]
pub(crate) mod lane_tests {
    use crate::controller::Telemetry;
    use crate::kinematics::quaternion_from_euler;
    use crate::law::MAX_ESTIMATES;
    use crate::measured::{BodyAttitude, Measurement};
    use crate::model::{QuadState, Reference};

    /// A 64-bit linear congruential generator (Knuth's MMIX constants).
    pub(crate) struct Lcg(pub(crate) u64);

    impl Lcg {
        /// Uniform in `[−1, 1)`.
        pub(crate) fn uniform(&mut self) -> f64 {
            self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((self.0 >> 11) as f64) / ((1u64 << 52) as f64) - 1.0
        }
        fn vec3(&mut self, scale: f64) -> [f64; 3] {
            [self.uniform() * scale, self.uniform() * scale, self.uniform() * scale]
        }
    }

    /// Control period of step `step`, s: 1 ms, 2 ms every 97th step (the
    /// filter weights are recomputed), 0 at step 90 (no differencing) and
    /// NaN at step 80 (every lane's command NaN).
    pub(crate) fn dt_at(step: usize) -> f64 {
        match step {
            80 => f64::NAN,
            90 => 0.0,
            s if s % 97 == 0 => 2e-3,
            _ => 1e-3,
        }
    }

    /// Lane `lane`'s measurement, reference and actuator-saturation report
    /// at `step`. Lanes take different branches by `lane % 5`:
    /// 0 at the reference (errors 0 or ~1e-12, the filters and integrators
    /// near 0); 1 far from it and fast (velocity limits, tilt limit, thrust
    /// cap, horizontal scaling); 2 asked to descend fast (thrust floor,
    /// vertical anti-windup); 3 upside down with the demanded thrust axis
    /// exactly vertical on even steps (reversed thrust axis: PX4's corner
    /// case and the half-turn branch of the shortest arc); 4 anything.
    /// Non-finite inputs at some steps in some lanes.
    pub(crate) fn flight_inputs(
        rng: &mut Lcg,
        lane: usize,
        step: usize,
        with_body: bool,
    ) -> (Measurement, Reference, bool) {
        let pi = core::f64::consts::PI;
        let mut s = QuadState::default();
        let mut r = Reference::default();
        match lane % 5 {
            0 => {
                r.position = rng.vec3(5.0);
                let tiny = if step % 3 == 0 { 0.0 } else { 1e-12 };
                s.position = core::array::from_fn(|i| r.position[i] + rng.uniform() * tiny);
                s.velocity = rng.vec3(tiny);
                s.attitude = [rng.uniform() * tiny, rng.uniform() * tiny, 0.0];
                r.yaw = 0.0;
            }
            1 => {
                s.position = rng.vec3(50.0);
                r.position = rng.vec3(50.0);
                s.velocity = rng.vec3(20.0);
                r.velocity = rng.vec3(15.0);
                r.acceleration = rng.vec3(10.0);
                s.attitude = [rng.uniform() * 0.8, rng.uniform() * 0.8, rng.uniform() * pi];
                s.angular_rate = rng.vec3(8.0);
                r.yaw = rng.uniform() * pi;
                r.yaw_rate = rng.uniform() * 3.0;
            }
            2 => {
                s.position = [0.0, 0.0, 20.0 + rng.uniform()];
                r.position = [rng.uniform() * 0.1, 0.0, -20.0];
                s.velocity = [0.0, 0.0, 5.0 + rng.uniform()];
                s.attitude = [rng.uniform() * 0.1, rng.uniform() * 0.1, 0.3];
                s.angular_rate = rng.vec3(0.5);
                r.yaw = 0.3;
            }
            3 => {
                let exact = step % 2 == 0;
                s.position = [1.0, -2.0, 3.0];
                r.position = [1.0, -2.0, 3.0 + rng.uniform()];
                s.attitude =
                    if exact { [pi, 0.0, 0.0] } else { [pi - 0.01 * rng.uniform(), 0.02 * rng.uniform(), 0.5] };
                s.angular_rate = if exact { [0.0; 3] } else { rng.vec3(1.0) };
                r.yaw = if exact { 0.0 } else { 0.5 };
            }
            _ => {
                s.position = rng.vec3(3.0);
                r.position = rng.vec3(3.0);
                s.velocity = rng.vec3(2.0);
                r.velocity = rng.vec3(1.0);
                r.acceleration = rng.vec3(2.0);
                s.attitude = [rng.uniform() * 1.5, rng.uniform() * 1.2, rng.uniform() * pi];
                s.angular_rate = rng.vec3(4.0);
                r.yaw = rng.uniform() * pi;
                r.yaw_rate = rng.uniform();
                r.yaw_acceleration = rng.uniform();
            }
        }
        let body = with_body.then(|| BodyAttitude {
            quaternion: quaternion_from_euler(&s.attitude),
            body_rates: crate::kinematics::body_rates_from_euler_rates(&s.attitude, &s.angular_rate),
        });
        let mut m = Measurement { euler: s, body };
        // Non-finite inputs: in one lane at a time, and in every lane at step 70.
        match (step, lane) {
            (0, 2) | (40, 1) => m.euler.position[0] = f64::NAN,
            (41, 2) => r.yaw = f64::INFINITY,
            (42, 3) => r.acceleration[1] = f64::NEG_INFINITY,
            (43, 0) => match m.body.as_mut() {
                Some(b) => b.quaternion[2] = f64::NAN,
                None => m.euler.angular_rate[2] = f64::NAN,
            },
            (70, _) => m.euler.velocity[1] = f64::NAN,
            _ => {}
        }
        let saturated = rng.uniform() > 0.3;
        (m, r, saturated)
    }

    /// Number of values [`telemetry_bits`] returns.
    pub(crate) const TELEMETRY_VALUES: usize = 11 + 6 * MAX_ESTIMATES + 4 + 2;

    /// The bits of every value of a telemetry record (flags as 0/1, the
    /// sliding-mode part's presence last).
    pub(crate) fn telemetry_bits(t: &Telemetry) -> [u64; TELEMETRY_VALUES] {
        let mut out = [0u64; TELEMETRY_VALUES];
        let values = t
            .attitude_reference
            .iter()
            .chain(&t.attitude_reference_rate)
            .chain(&t.attitude_reference_acceleration)
            .chain(&t.attitude_demand)
            .chain(t.estimates.iter().flatten())
            .chain(&t.commanded_acceleration)
            .chain(core::iter::once(&t.nominal_thrust));
        let mut n = 0;
        for v in values {
            out[n] = v.to_bits();
            n += 1;
        }
        out[n] = u64::from(t.thrust_limited);
        out[n + 1] = u64::from(t.sliding_mode.is_some());
        assert_eq!(n + 2, TELEMETRY_VALUES);
        out
    }
}
