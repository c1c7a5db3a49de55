//! Minimal 3-vector, 3×3-matrix and quaternion helpers for the truth models
//! (nalgebra is not a dependency: the models need a dozen operations).
//!
//! Quaternions are `[w, x, y, z]` (scalar first, Hamilton product).
//!
//! The vector helpers are generic over the number type ([`Real`]): one
//! flight (`f64`) or flights in lanes, the same operations in the same
//! order either way.

use ftsmc_core::lanes::Real;

pub(crate) type Vec3<R = f64> = [R; 3];
pub(crate) type Mat3<R = f64> = [[R; 3]; 3];
pub(crate) type Quat<R = f64> = [R; 4];

#[cfg_attr(not(debug_assertions), inline(always))]
pub(crate) fn add<R: Real>(a: Vec3<R>, b: Vec3<R>) -> Vec3<R> {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

#[cfg_attr(not(debug_assertions), inline(always))]
pub(crate) fn sub<R: Real>(a: Vec3<R>, b: Vec3<R>) -> Vec3<R> {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[cfg_attr(not(debug_assertions), inline(always))]
pub(crate) fn dot<R: Real>(a: Vec3<R>, b: Vec3<R>) -> R {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[cfg_attr(not(debug_assertions), inline(always))]
pub(crate) fn cross<R: Real>(a: Vec3<R>, b: Vec3<R>) -> Vec3<R> {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

#[cfg_attr(not(debug_assertions), inline(always))]
pub(crate) fn norm<R: Real>(a: Vec3<R>) -> R {
    dot(a, a).sqrt()
}

#[cfg_attr(not(debug_assertions), inline(always))]
pub(crate) fn mat_vec<R: Real>(m: &Mat3<R>, v: Vec3<R>) -> Vec3<R> {
    [dot(m[0], v), dot(m[1], v), dot(m[2], v)]
}

/// `mᵀ v`.
#[cfg_attr(not(debug_assertions), inline(always))]
pub(crate) fn mat_t_vec<R: Real>(m: &Mat3<R>, v: Vec3<R>) -> Vec3<R> {
    [
        m[0][0] * v[0] + m[1][0] * v[1] + m[2][0] * v[2],
        m[0][1] * v[0] + m[1][1] * v[1] + m[2][1] * v[2],
        m[0][2] * v[0] + m[1][2] * v[1] + m[2][2] * v[2],
    ]
}

pub(crate) fn det3(m: &Mat3) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// Inverse by the adjugate; `None` when the determinant is not a normal
/// positive or negative number.
pub(crate) fn inverse3(m: &Mat3) -> Option<Mat3> {
    let det = det3(m);
    det.is_normal().then(|| adjugate_over(m, det))
}

/// [`inverse3`] when the determinant is also positive, else `None`: one
/// determinant for the check and the inverse.
pub(crate) fn inverse3_positive(m: &Mat3) -> Option<Mat3> {
    let det = det3(m);
    (det > 0.0 && det.is_normal()).then(|| adjugate_over(m, det))
}

/// The adjugate of `m` divided by `det`.
#[inline]
fn adjugate_over(m: &Mat3, det: f64) -> Mat3 {
    let c = |r0: usize, c0: usize, r1: usize, c1: usize| m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0];
    let adj = [
        [c(1, 1, 2, 2), -c(0, 1, 2, 2), c(0, 1, 1, 2)],
        [-c(1, 0, 2, 2), c(0, 0, 2, 2), -c(0, 0, 1, 2)],
        [c(1, 0, 2, 1), -c(0, 0, 2, 1), c(0, 0, 1, 1)],
    ];
    adj.map(|row| row.map(|v| v / det))
}

/// Rotation matrix of a unit quaternion (body → world: `v_w = R v_b`): the
/// formula of the core's [`ftsmc_core::kinematics::rotation_from_quaternion`]
/// with the same operations in the same order (so the same bits for `f64`;
/// the test `rotation_is_the_cores_bit_for_bit` pins it), on any [`Real`].
#[cfg_attr(not(debug_assertions), inline(always))]
pub(crate) fn rotation<R: Real>(q: Quat<R>) -> Mat3<R> {
    let [w, x, y, z] = q;
    let one = R::splat(1.0);
    [
        [one - (y * y + z * z) * 2.0, (x * y - w * z) * 2.0, (x * z + w * y) * 2.0],
        [(x * y + w * z) * 2.0, one - (x * x + z * z) * 2.0, (y * z - w * x) * 2.0],
        [(x * z - w * y) * 2.0, (y * z + w * x) * 2.0, one - (x * x + y * y) * 2.0],
    ]
}

/// `q̇ = ½ q ⊗ (0, Ω)` for body rates Ω.
#[cfg_attr(not(debug_assertions), inline(always))]
pub(crate) fn quat_derivative<R: Real>(q: Quat<R>, omega: Vec3<R>) -> Quat<R> {
    let [w, x, y, z] = q;
    let [p, r1, r2] = omega;
    [
        (-x * p - y * r1 - z * r2) * 0.5,
        (w * p + y * r2 - z * r1) * 0.5,
        (w * r1 + z * p - x * r2) * 0.5,
        (w * r2 + x * r1 - y * p) * 0.5,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_times_matrix_is_identity() {
        let m = [[2.0, 0.1, -0.3], [0.1, 3.0, 0.2], [-0.3, 0.2, 4.0]];
        let inv = inverse3(&m).unwrap();
        for i in 0..3 {
            for j in 0..3 {
                let e: f64 = (0..3).map(|k| m[i][k] * inv[k][j]).sum();
                assert!((e - if i == j { 1.0 } else { 0.0 }).abs() < 1e-14);
            }
        }
        assert!(inverse3(&[[1.0, 2.0, 3.0], [2.0, 4.0, 6.0], [0.0, 0.0, 1.0]]).is_none());
    }

    /// The generic rotation is the core's formula bit for bit, on one flight
    /// and lane by lane.
    #[test]
    fn rotation_is_the_cores_bit_for_bit() {
        use ftsmc_core::lanes::{Lanes, Lanewise};
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut u = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        for _ in 0..2000 {
            let qs: [[f64; 4]; 4] = core::array::from_fn(|_| [u(), u(), u(), u()]);
            let lanes: Quat<Lanes<4>> = core::array::from_fn(|k| Lanes(qs.map(|q| q[k])));
            let r = rotation(lanes);
            for (i, q) in qs.iter().enumerate() {
                let want = ftsmc_core::kinematics::rotation_from_quaternion(q);
                assert_eq!(rotation(*q).map(|r| r.map(f64::to_bits)), want.map(|r| r.map(f64::to_bits)));
                assert_eq!(r.get_lane(i).map(|r| r.map(f64::to_bits)), want.map(|r| r.map(f64::to_bits)));
            }
        }
    }

    #[test]
    fn rotation_of_a_quarter_turn_about_z() {
        let h = core::f64::consts::FRAC_PI_4;
        let r = rotation([ftsmc_core::math::cos(h), 0.0, 0.0, ftsmc_core::math::sin(h)]);
        let v = mat_vec(&r, [1.0, 0.0, 0.0]);
        assert!((v[0]).abs() < 1e-15 && (v[1] - 1.0).abs() < 1e-15);
        let back = mat_t_vec(&r, v);
        assert!((back[0] - 1.0).abs() < 1e-15);
    }
}
