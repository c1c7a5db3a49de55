//! Z-Y-X Euler-angle kinematics of the paper's Eq. 1 attitude `[φ, θ, ψ]`:
//! the body-to-world rotation, its inverse, and the Euler-rate to body-rate
//! map. The one place the control laws take these from (PID and SE(3) use
//! them to leave the Euler interface); built on [`crate::math`]'s `libm`
//! trigonometry, so bit-identical on every platform.

use crate::math::{asin, atan2, sin_cos, Mat3, Vec3};

/// Body-to-world rotation `R = R_z(ψ) R_y(θ) R_x(φ)` of Z-Y-X Euler angles
/// `[φ, θ, ψ]` (rad); its third column `R e₃` is the thrust direction of
/// paper Eq. 1 (`cφ sθ cψ + sφ sψ`, `cφ sθ sψ − sφ cψ`, `cφ cθ`).
pub fn rotation_from_euler(euler: &Vec3) -> Mat3 {
    let (sf, cf) = sin_cos(euler[0]);
    let (st, ct) = sin_cos(euler[1]);
    let (ss, cs) = sin_cos(euler[2]);
    [
        [cs * ct, cs * st * sf - ss * cf, cs * st * cf + ss * sf],
        [ss * ct, ss * st * sf + cs * cf, ss * st * cf - cs * sf],
        [-st, ct * sf, ct * cf],
    ]
}

/// Z-Y-X Euler angles `[φ, θ, ψ]` (rad) of a rotation matrix: φ, ψ in
/// `[−π, π]`, θ in `[−π/2, π/2]` (inverse of [`rotation_from_euler`] away
/// from θ = ±π/2).
pub fn euler_from_rotation(r: &Mat3) -> Vec3 {
    // `saturate`, not `f64::clamp`: no panic path, NaN passes through.
    let s = crate::law::saturate(-r[2][0], 1.0);
    [atan2(r[2][1], r[2][2]), asin(s), atan2(r[1][0], r[0][0])]
}

/// Body rates `Ω = W(φ, θ) η̇` (rad/s) from Z-Y-X Euler rates `η̇` at
/// `euler`: `p = φ̇ − ψ̇ sθ`, `q = θ̇ cφ + ψ̇ cθ sφ`, `r = −θ̇ sφ + ψ̇ cθ cφ`.
/// Exact, defined everywhere.
pub fn body_rates_from_euler_rates(euler: &Vec3, rates: &Vec3) -> Vec3 {
    let (sf, cf) = sin_cos(euler[0]);
    let (st, ct) = sin_cos(euler[1]);
    let [df, dt, ds] = *rates;
    [df - ds * st, dt * cf + ds * ct * sf, -dt * sf + ds * ct * cf]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{cross, mat_t_mat, mat_t_vec, mat_vec, norm};

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
