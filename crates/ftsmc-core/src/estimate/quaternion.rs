//! Unit-quaternion algebra of the estimators, in ftsmc's convention
//! ([`crate::kinematics`]): `q = [w, x, y, z]`, scalar first, Hamilton
//! product, body → world (`v_w = R(q) v_b`). Local perturbations are on the
//! right, `q_true = q ⊗ Exp(δθ)` with `δθ` in the body frame (Sola 2017,
//! "Quaternion kinematics for the error-state Kalman filter",
//! arXiv:1711.02508, §4.1 and eq. 101 and 105 for `Exp` and `Log`).

use crate::math::{atan2, sin_cos, sqrt};

/// Hamilton product `a ⊗ b` (Sola 2017 eq. 12).
pub fn multiply(a: &[f64; 4], b: &[f64; 4]) -> [f64; 4] {
    let [aw, ax, ay, az] = *a;
    let [bw, bx, by, bz] = *b;
    [
        aw * bw - ax * bx - ay * by - az * bz,
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
    ]
}

/// Conjugate `q* = [w, −x, −y, −z]`, the inverse of a unit quaternion.
pub fn conjugate(q: &[f64; 4]) -> [f64; 4] {
    [q[0], -q[1], -q[2], -q[3]]
}

/// `q / |q|`; the identity for a zero or non-finite norm is *not* returned
/// (the NaN propagates, so the estimator's divergence check sees it).
pub fn normalize(q: &[f64; 4]) -> [f64; 4] {
    let n = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    [q[0] / n, q[1] / n, q[2] / n, q[3] / n]
}

/// Below this rotation angle (rad) [`exp`] and [`log`] use their Taylor
/// series (exact to double precision there).
const SMALL_ANGLE: f64 = 1e-8;

/// `Exp(θ) = [cos(|θ|/2), sin(|θ|/2) θ/|θ|]`, the unit quaternion of the
/// rotation vector `θ` (rad) (Sola 2017 eq. 101); `[1 − |θ|²/8, θ/2]` below
/// 1e-8 rad.
pub fn exp(theta: &[f64; 3]) -> [f64; 4] {
    let angle2 = theta[0] * theta[0] + theta[1] * theta[1] + theta[2] * theta[2];
    let angle = sqrt(angle2);
    if angle < SMALL_ANGLE {
        [1.0 - angle2 / 8.0, theta[0] * 0.5, theta[1] * 0.5, theta[2] * 0.5]
    } else {
        let (s, c) = sin_cos(angle * 0.5);
        let k = s / angle;
        [c, theta[0] * k, theta[1] * k, theta[2] * k]
    }
}

/// `Log(q)`, the rotation vector (rad) of a unit quaternion, of angle in
/// `[0, π]` (`q` and `−q` give the same vector) (Sola 2017 eq. 105).
pub fn log(q: &[f64; 4]) -> [f64; 3] {
    let (w, v) = if q[0] < 0.0 { (-q[0], [-q[1], -q[2], -q[3]]) } else { (q[0], [q[1], q[2], q[3]]) };
    let n = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    let k = if n < SMALL_ANGLE { 2.0 / w } else { 2.0 * atan2(n, w) / n };
    [v[0] * k, v[1] * k, v[2] * k]
}

/// Rotation vector `Log(a* ⊗ b)` (rad, in `a`'s body frame) that takes `a`
/// to `b`: `b = a ⊗ Exp(δθ)`.
pub fn difference(a: &[f64; 4], b: &[f64; 4]) -> [f64; 3] {
    log(&multiply(&conjugate(a), b))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp_and_log_are_inverse_and_the_product_composes_rotations() {
        for theta in [[0.3, -0.2, 1.1], [1e-10, 0.0, -2e-10], [0.0, 3.0, 0.0]] {
            let back = log(&exp(&theta));
            for i in 0..3 {
                assert!((back[i] - theta[i]).abs() < 1e-14, "{theta:?} -> {back:?}");
            }
        }
        let a = exp(&[0.1, 0.2, 0.3]);
        let b = exp(&[-0.4, 0.1, 0.05]);
        let ab = multiply(&a, &b);
        let (ra, rb, rab) = (
            crate::kinematics::rotation_from_quaternion(&a),
            crate::kinematics::rotation_from_quaternion(&b),
            crate::kinematics::rotation_from_quaternion(&ab),
        );
        for i in 0..3 {
            for j in 0..3 {
                let s: f64 = (0..3).map(|k| ra[i][k] * rb[k][j]).sum();
                assert!((s - rab[i][j]).abs() < 1e-14);
            }
        }
        let d = difference(&a, &ab);
        let eb = log(&b);
        for i in 0..3 {
            assert!((d[i] - eb[i]).abs() < 1e-14);
        }
    }
}
