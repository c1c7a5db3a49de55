//! Z-Y-X Euler-angle kinematics of the paper's Eq. 1 attitude `[φ, θ, ψ]`:
//! the body-to-world rotation, its inverse, the Euler-rate to body-rate
//! map, and the unit quaternion `[w, x, y, z]` (scalar first, Hamilton
//! product, body → world) of the same rotation. The one place the control
//! laws, the simulator's truth model and Python take these from (PID and
//! SE(3) use them to leave the Euler interface); built on [`crate::math`]'s
//! `libm` trigonometry, so bit-identical on every platform.
//!
//! Every function is generic over the number type ([`crate::lanes`]): `f64`
//! for one flight, lanes for several side by side, the same bits per lane.

use crate::lanes::Real;
use crate::math::{Mat3, Vec3};

/// Body-to-world rotation `R = R_z(ψ) R_y(θ) R_x(φ)` of Z-Y-X Euler angles
/// `[φ, θ, ψ]` (rad); its third column `R e₃` is the thrust direction of
/// paper Eq. 1 (`cφ sθ cψ + sφ sψ`, `cφ sθ sψ − sφ cψ`, `cφ cθ`).
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn rotation_from_euler<R: Real>(euler: &Vec3<R>) -> Mat3<R> {
    let (sf, cf) = euler[0].sin_cos();
    let (st, ct) = euler[1].sin_cos();
    let (ss, cs) = euler[2].sin_cos();
    [
        [cs * ct, cs * st * sf - ss * cf, cs * st * cf + ss * sf],
        [ss * ct, ss * st * sf + cs * cf, ss * st * cf - cs * sf],
        [-st, ct * sf, ct * cf],
    ]
}

/// Z-Y-X Euler angles `[φ, θ, ψ]` (rad) of a rotation matrix: φ, ψ in
/// `[−π, π]`, θ in `[−π/2, π/2]` (inverse of [`rotation_from_euler`] away
/// from θ = ±π/2).
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn euler_from_rotation<R: Real>(r: &Mat3<R>) -> Vec3<R> {
    // `saturate`, not `f64::clamp`: no panic path, NaN passes through.
    let s = crate::law::saturate(-r[2][0], R::splat(1.0));
    [r[2][1].atan2(r[2][2]), s.asin(), r[1][0].atan2(r[0][0])]
}

/// Roll and pitch `[φ, θ]` (rad) of a rotation matrix: the first two
/// components of [`euler_from_rotation`], same bits, without the yaw's
/// `atan2` (for the controllers that report only the demanded tilt).
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn roll_pitch_from_rotation<R: Real>(r: &Mat3<R>) -> [R; 2] {
    let s = crate::law::saturate(-r[2][0], R::splat(1.0));
    [r[2][1].atan2(r[2][2]), s.asin()]
}

/// Body rates `Ω = W(φ, θ) η̇` (rad/s) from Z-Y-X Euler rates `η̇` at
/// `euler`: `p = φ̇ − ψ̇ sθ`, `q = θ̇ cφ + ψ̇ cθ sφ`, `r = −θ̇ sφ + ψ̇ cθ cφ`.
/// Exact, defined everywhere.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn body_rates_from_euler_rates<R: Real>(euler: &Vec3<R>, rates: &Vec3<R>) -> Vec3<R> {
    let (sf, cf) = euler[0].sin_cos();
    let (st, ct) = euler[1].sin_cos();
    let [df, dt, ds] = *rates;
    [df - ds * st, dt * cf + ds * ct * sf, -dt * sf + ds * ct * cf]
}

/// Unit quaternion `[w, x, y, z]` of Z-Y-X Euler angles `[φ, θ, ψ]` (rad):
/// `q = q_z(ψ) ⊗ q_y(θ) ⊗ q_x(φ)`, so that
/// [`rotation_from_quaternion`]`(q)` = [`rotation_from_euler`]`(euler)`.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn quaternion_from_euler<R: Real>(euler: &Vec3<R>) -> [R; 4] {
    quaternion_from_half_angles(half_angle(euler[0]), half_angle(euler[1]), half_angle(euler[2]))
}

/// `[sin(a/2), cos(a/2)]` of an angle `a` (rad), the inputs of
/// [`quaternion_from_half_angles`] and [`full_angle`].
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn half_angle<R: Real>(a: R) -> [R; 2] {
    // `a · 0.5`: the product `0.5 a` with its operands swapped (same bits).
    let (s, c) = (a * 0.5).sin_cos();
    [s, c]
}

/// [`quaternion_from_euler`] from the sines and cosines of the half angles
/// `[sin(φ/2), cos(φ/2)]`, `[sin(θ/2), cos(θ/2)]`, `[sin(ψ/2), cos(ψ/2)]`
/// ([`half_angle`]).
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn quaternion_from_half_angles<R: Real>([sr, cr]: [R; 2], [sp, cp]: [R; 2], [sy, cy]: [R; 2]) -> [R; 4] {
    [cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy]
}

/// `[sin a, cos a]` from `[sin(a/2), cos(a/2)]` by the double-angle formulas
/// `sin a = 2 s c`, `cos a = (c − s)(c + s)`: equal to `sin_cos(a)` within a
/// few units in the last place, without a second evaluation (a reading
/// that needs both its quaternion and its Euler rates takes the half
/// angles once).
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn full_angle<R: Real>([s, c]: [R; 2]) -> [R; 2] {
    [s * 2.0 * c, (c - s) * (c + s)]
}

/// `cos θ` clamped away from 0 to `±`[`GIMBAL_LOCK_COS`] (the sign of
/// `cos θ`; positive at 0 and for NaN), as [`euler_rates_from_body_rates`]
/// divides by it.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn gimbal_clamped_cos<R: Real>(c: R) -> R {
    let limit = R::splat(GIMBAL_LOCK_COS);
    R::select(c.abs().ge(limit), c, R::select(c.lt(R::splat(0.0)), -limit, limit))
}

/// Body-to-world rotation matrix of a unit quaternion `[w, x, y, z]`
/// (`v_w = R v_b`; no trigonometry).
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn rotation_from_quaternion<R: Real>(q: &[R; 4]) -> Mat3<R> {
    let [w, x, y, z] = *q;
    let one = R::splat(1.0);
    [
        [one - (y * y + z * z) * 2.0, (x * y - w * z) * 2.0, (x * z + w * y) * 2.0],
        [(x * y + w * z) * 2.0, one - (x * x + z * z) * 2.0, (y * z - w * x) * 2.0],
        [(x * z - w * y) * 2.0, (y * z + w * x) * 2.0, one - (x * x + y * y) * 2.0],
    ]
}

/// Z-Y-X Euler angles `[φ, θ, ψ]` (rad) of a unit quaternion: φ, ψ in
/// `[−π, π]`, θ in `[−π/2, π/2]`; `q` and `−q` give the same angles. At
/// θ = ±π/2 only φ ∓ ψ is defined.
pub fn euler_from_quaternion<R: Real>(q: &[R; 4]) -> Vec3<R> {
    let [w, x, y, z] = *q;
    let one = R::splat(1.0);
    let s = crate::law::saturate((w * y - x * z) * 2.0, one);
    [
        ((w * x + y * z) * 2.0).atan2(one - (x * x + y * y) * 2.0),
        s.asin(),
        ((w * z + x * y) * 2.0).atan2(one - (y * y + z * z) * 2.0),
    ]
}

/// Smallest `|cos θ|` [`euler_rates_from_body_rates`] divides by: within
/// about 1e-6 rad of θ = ±π/2 (gimbal lock) `cos θ` is clamped to
/// `±GIMBAL_LOCK_COS`, so the rates stay finite.
pub const GIMBAL_LOCK_COS: f64 = 1e-6;

/// Z-Y-X Euler rates `η̇ = W⁻¹(φ, θ) Ω` (rad/s) from body rates Ω at
/// `euler`: `φ̇ = p + (q sφ + r cφ) tθ`, `θ̇ = q cφ − r sφ`,
/// `ψ̇ = (q sφ + r cφ)/cθ`, with `cos θ` clamped to `±`[`GIMBAL_LOCK_COS`]
/// (the sign of cos θ; positive at 0) near the singularity.
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn euler_rates_from_body_rates<R: Real>(euler: &Vec3<R>, body_rates: &Vec3<R>) -> Vec3<R> {
    let (sf, cf) = euler[0].sin_cos();
    let (st, c) = euler[1].sin_cos();
    let c = gimbal_clamped_cos(c);
    euler_rates_from_body_rates_with([sf, cf], [st, c], body_rates)
}

/// [`euler_rates_from_body_rates`] from the sines and cosines of φ and θ,
/// `[sφ, cφ]` and `[sθ, cθ]`, however they were obtained (the truth model
/// reads them off its quaternion); `cθ` must be away from 0 (the caller's
/// clamp or check).
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn euler_rates_from_body_rates_with<R: Real>([sf, cf]: [R; 2], [st, c]: [R; 2], body_rates: &Vec3<R>) -> Vec3<R> {
    let [p, q, r] = *body_rates;
    let a = q * sf + r * cf;
    [p + a * st / c, q * cf - r * sf, a / c]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{cross, mat_t_mat, mat_t_vec, mat_vec, norm, sin_cos};

    use proptest::prelude::*;

    #[test]
    fn full_angles_from_half_angles_are_sin_cos_to_a_few_ulp() {
        let mut worst = 0.0f64;
        for k in -4000..=4000 {
            let a = f64::from(k) * 1e-3 * core::f64::consts::PI;
            let [s, c] = full_angle(half_angle(a));
            let (ws, wc) = sin_cos(a);
            worst = worst.max((s - ws).abs()).max((c - wc).abs());
        }
        assert!(worst <= 4.0 * f64::EPSILON, "{worst:e}");
    }

    proptest! {
        /// Euler → quaternion → rotation equals Euler → rotation; rotation and
        /// quaternion both give the angles back; Euler rates → body rates →
        /// Euler rates is the identity (away from gimbal lock).
        #[test]
        fn euler_quaternion_rotation_round_trips(
            phi in -3.1f64..3.1, theta in -1.5f64..1.5, psi in -3.1f64..3.1,
            dphi in -10.0f64..10.0, dtheta in -10.0f64..10.0, dpsi in -10.0f64..10.0,
        ) {
            let e = [phi, theta, psi];
            let q = quaternion_from_euler(&e);
            let n = q.iter().map(|v| v * v).sum::<f64>();
            prop_assert!((n - 1.0).abs() < 1e-14);
            let rq = rotation_from_quaternion(&q);
            let re = rotation_from_euler(&e);
            for i in 0..3 {
                for j in 0..3 {
                    prop_assert!((rq[i][j] - re[i][j]).abs() < 1e-14);
                }
            }
            let tol = 1e-12 / crate::math::cos(theta);
            let from_q = euler_from_quaternion(&q);
            let from_r = euler_from_rotation(&re);
            let minus_q = euler_from_quaternion(&q.map(|v| -v));
            for i in 0..3 {
                prop_assert!((from_q[i] - e[i]).abs() < tol, "{:?} -> {:?}", e, from_q);
                prop_assert!((from_r[i] - e[i]).abs() < tol);
                prop_assert!((minus_q[i] - e[i]).abs() < tol);
            }
            let rates = [dphi, dtheta, dpsi];
            let body = body_rates_from_euler_rates(&e, &rates);
            let back = euler_rates_from_body_rates(&e, &body);
            for i in 0..3 {
                prop_assert!((back[i] - rates[i]).abs() < 1e-9 * (1.0 + rates[i].abs()) / crate::math::cos(theta));
            }
        }
    }

    /// Every function on `Lanes<4>` gives, lane by lane, the bits of the
    /// `f64` function on that lane's arguments (angles over several turns,
    /// at gimbal lock, `cos θ` of either sign near 0, NaN).
    #[test]
    fn lanes_give_the_bits_of_one_flight() {
        use crate::lanes::{Lanes, Lanewise};
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<std::vec::Vec<_>>();
        let samples = [0.3, -2.9, 7.5, core::f64::consts::FRAC_PI_2, -1e-7, 0.0, f64::NAN, 1e-300];
        for k in 0..samples.len() {
            let pick = |j: usize| Lanes::<4>::from_fn(|i| samples[(k + 3 * i + j) % samples.len()]);
            let e = [pick(0), pick(1), pick(2)];
            let w = [pick(3), pick(4) * 5.0, pick(5)];
            let q = quaternion_from_euler(&e);
            for i in 0..4 {
                let (ei, wi, qi) = (e.get_lane(i), w.get_lane(i), q.get_lane(i));
                assert_eq!(bits(&qi), bits(&quaternion_from_euler(&ei)));
                assert_eq!(
                    bits(rotation_from_euler(&e).get_lane(i).as_flattened()),
                    bits(rotation_from_euler(&ei).as_flattened())
                );
                assert_eq!(
                    bits(rotation_from_quaternion(&q).get_lane(i).as_flattened()),
                    bits(rotation_from_quaternion(&qi).as_flattened())
                );
                let r = rotation_from_euler(&e);
                assert_eq!(bits(&euler_from_rotation(&r).get_lane(i)), bits(&euler_from_rotation(&r.get_lane(i))));
                assert_eq!(
                    bits(&roll_pitch_from_rotation(&r).get_lane(i)),
                    bits(&roll_pitch_from_rotation(&r.get_lane(i)))
                );
                assert_eq!(bits(&euler_from_quaternion(&q).get_lane(i)), bits(&euler_from_quaternion(&qi)));
                assert_eq!(
                    bits(&body_rates_from_euler_rates(&e, &w).get_lane(i)),
                    bits(&body_rates_from_euler_rates(&ei, &wi))
                );
                assert_eq!(
                    bits(&euler_rates_from_body_rates(&e, &w).get_lane(i)),
                    bits(&euler_rates_from_body_rates(&ei, &wi))
                );
                assert_eq!(bits(&full_angle(half_angle(e[1])).get_lane(i)), bits(&full_angle(half_angle(ei[1]))));
                let c = e[1] * 1e-6;
                assert_eq!(gimbal_clamped_cos(c).get_lane(i).to_bits(), gimbal_clamped_cos(c.get_lane(i)).to_bits());
            }
        }
    }

    #[test]
    fn euler_rates_stay_finite_at_gimbal_lock() {
        let w = euler_rates_from_body_rates(&[0.2, core::f64::consts::FRAC_PI_2, 0.0], &[0.1, 0.2, 0.3]);
        assert!(w.iter().all(|v| v.is_finite()));
        assert!(w[2].abs() > 1e4);
    }

    #[test]
    fn rotation_and_euler_round_trip_and_body_rates() {
        let e = [0.3, -0.4, 2.0];
        let r = rotation_from_euler(&e);
        let back = euler_from_rotation(&r);
        for i in 0..3 {
            assert!((back[i] - e[i]).abs() < 1e-12);
        }
        // Orthonormal: RᵀR = I.
        let rtr = mat_t_mat(&r, &r);
        for i in 0..3 {
            for j in 0..3 {
                assert!((rtr[i][j] - if i == j { 1.0 } else { 0.0 }).abs() < 1e-12);
            }
        }
        // A pure yaw rate is the world z axis in the body frame: Ω = Rᵀ e₃ ψ̇.
        let w = body_rates_from_euler_rates(&e, &[0.0, 0.0, 1.5]);
        let z = mat_t_vec(&r, &[0.0, 0.0, 1.5]);
        for i in 0..3 {
            assert!((w[i] - z[i]).abs() < 1e-12);
        }
        assert_eq!(cross(&[1.0, 0.0, 0.0], &[0.0, 1.0, 0.0]), [0.0, 0.0, 1.0]);
        assert_eq!(mat_vec(&r, &[0.0, 0.0, 0.0]), [0.0; 3]);
        assert!((norm(&[3.0, 4.0, 0.0]) - 5.0).abs() < 1e-15);
    }
}
