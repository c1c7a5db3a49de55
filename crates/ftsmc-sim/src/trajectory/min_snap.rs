//! Minimum-snap polynomial trajectories through waypoints (Mellinger and
//! Kumar, "Minimum snap trajectory generation and control for quadrotors",
//! ICRA 2011), solved in closed form as the unconstrained quadratic
//! programme of Richter, Bry and Roy ("Polynomial trajectory planning for
//! aggressive quadrotor flight in dense indoor environments", ISRR 2013 /
//! Springer 2016, §3).
//!
//! # The problem
//!
//! Each of the four flat outputs (x, y, z, ψ) is, on segment `i` of
//! duration `T_i`, a polynomial of degree 7 in `τ = (t − t_i)/T_i`. The
//! cost is the integrated squared snap, `J = Σ_i ∫₀^{T_i} (d⁴p/dt⁴)² dt`.
//!
//! A degree-7 polynomial is fixed by its value, velocity, acceleration and
//! jerk at both ends (8 numbers). Writing every segment through these end
//! derivatives and sharing them between neighbouring segments makes the
//! curve C³ by construction; the positions at every knot and the
//! derivatives 1–3 at the first and last knot are fixed (rest: v = a = j =
//! 0), and the velocity, acceleration and jerk at the interior knots are
//! free. With `b_i` the segment's end derivatives in τ units
//! (`b = [p, T p', T² p'', T³ p''']` at both ends), the coefficients are
//! `c_i = M⁻¹ b_i` and the segment's cost is `T_i⁻⁷ b_iᵀ H b_i`,
//! `H = M⁻ᵀ Q M⁻¹` with `Q_kl = ∫₀¹ (d⁴τ^k/dτ⁴)(d⁴τ^l/dτ⁴) dτ` (Richter et
//! al. Eq. 3–8). The free derivatives `d_F` minimise `J = d_Fᵀ A d_F + 2
//! d_Fᵀ r + const`, so `A d_F = −r` (their Eq. 31). At this optimum the
//! 4th, 5th and 6th derivatives are continuous at the interior knots too
//! (the Euler–Lagrange conditions of the snap functional), which
//! `tests/trajectories.rs` checks.
//!
//! # The solve
//!
//! `A` is symmetric positive definite for increasing times and banded: the
//! three free derivatives of knot `k` meet only those of knots `k ± 1`,
//! so its half-bandwidth is 5. It is Jacobi-equilibrated (`D^{-1/2} A
//! D^{-1/2}`, unit diagonal) and factored by a banded Cholesky
//! decomposition, `O(n)` in the number of waypoints; one factorisation
//! serves the four outputs. The smallest pivot of the equilibrated
//! factorisation, `min L_ii²`, must be at least [`MIN_PIVOT`]: a smaller one
//! means the system is (numerically) singular — segment durations whose
//! ratios span many orders of magnitude — and the trajectory is refused
//! rather than flown with derivatives lost in rounding.
//!
//! (Not nalgebra: its dense LU or Cholesky is `O(n³)` and would cap the
//! waypoint count near a few hundred; the banded factorisation is the same
//! Cholesky restricted to the band.)

use super::FlatOutput;

/// Polynomial degree of every segment.
pub const DEGREE: usize = 7;
/// Coefficients per segment and output.
const N_COEF: usize = DEGREE + 1;
/// Smallest allowed pivot of the equilibrated Cholesky factorisation
/// (a reciprocal condition estimate): below it the system is refused.
pub const MIN_PIVOT: f64 = 1e-12;
/// Half-bandwidth of the free-derivative system.
const BAND: usize = 5;

/// `m! / (m − k)!`-style falling factorial `k (k−1) … (k−m+1)`.
fn falling(k: usize, m: usize) -> f64 {
    if m > k {
        return 0.0;
    }
    ((k - m + 1)..=k).map(|v| v as f64).product()
}

/// `M`: end derivatives (τ units) of `Σ c_k τ^k`: rows 0–3 at τ = 0 (order
/// 0–3), rows 4–7 at τ = 1.
fn end_matrix() -> [[f64; N_COEF]; N_COEF] {
    let mut m = [[0.0; N_COEF]; N_COEF];
    for order in 0..4 {
        m[order][order] = falling(order, order);
        for k in order..N_COEF {
            m[4 + order][k] = falling(k, order);
        }
    }
    m
}

/// Inverse of an 8×8 matrix by Gauss–Jordan elimination with partial
/// pivoting (used on the constant, well-conditioned `M` only).
fn invert(mut a: [[f64; N_COEF]; N_COEF]) -> [[f64; N_COEF]; N_COEF] {
    let mut inv = [[0.0; N_COEF]; N_COEF];
    for (i, row) in inv.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    for col in 0..N_COEF {
        let pivot = (col..N_COEF).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs())).unwrap_or(col);
        a.swap(col, pivot);
        inv.swap(col, pivot);
        let d = a[col][col];
        for k in 0..N_COEF {
            a[col][k] /= d;
            inv[col][k] /= d;
        }
        for r in 0..N_COEF {
            if r != col {
                let f = a[r][col];
                if f != 0.0 {
                    for k in 0..N_COEF {
                        a[r][k] -= f * a[col][k];
                        inv[r][k] -= f * inv[col][k];
                    }
                }
            }
        }
    }
    inv
}

/// The constant matrices of the closed form: `M⁻¹` and `H = M⁻ᵀ Q M⁻¹`.
pub fn matrices() -> ([[f64; N_COEF]; N_COEF], [[f64; N_COEF]; N_COEF]) {
    let minv = invert(end_matrix());
    // Q_kl = k(k−1)(k−2)(k−3) l(l−1)(l−2)(l−3) / (k + l − 7), k, l ≥ 4.
    let mut q = [[0.0; N_COEF]; N_COEF];
    for k in 4..N_COEF {
        for l in 4..N_COEF {
            q[k][l] = falling(k, 4) * falling(l, 4) / (k + l - 7) as f64;
        }
    }
    let mut h = [[0.0; N_COEF]; N_COEF];
    for r in 0..N_COEF {
        for s in 0..N_COEF {
            let mut acc = 0.0;
            for k in 0..N_COEF {
                for l in 0..N_COEF {
                    acc += minv[k][r] * q[k][l] * minv[l][s];
                }
            }
            h[r][s] = acc;
        }
    }
    (minv, h)
}

/// Snap cost `∫ (d⁴p/dt⁴)² dt` of one segment of duration `t` (s) whose
/// physical end derivatives are `d = [p0, v0, a0, j0, p1, v1, a1, j1]`.
pub fn segment_cost(h: &[[f64; N_COEF]; N_COEF], duration: f64, d: &[f64; N_COEF]) -> f64 {
    let b = scaled(duration, d);
    let mut j = 0.0;
    for r in 0..N_COEF {
        for s in 0..N_COEF {
            j += b[r] * h[r][s] * b[s];
        }
    }
    j / ftsmc_core::math::powf(duration, 7.0)
}

/// End derivatives in τ units: order m multiplied by `T^m`.
fn scaled(duration: f64, d: &[f64; N_COEF]) -> [f64; N_COEF] {
    let mut b = *d;
    for (r, v) in b.iter_mut().enumerate() {
        *v *= pow_i(duration, r % 4);
    }
    b
}

fn pow_i(x: f64, n: usize) -> f64 {
    (0..n).fold(1.0, |a, _| a * x)
}

/// Why the closed-form system could not be solved.
#[derive(Clone, Debug, PartialEq)]
pub struct IllConditioned {
    /// The smallest pivot of the equilibrated factorisation.
    pub pivot: f64,
    /// Interior knot whose derivatives it belongs to.
    pub knot: usize,
}

/// The solved piecewise polynomial of the four outputs.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    /// Knot times, s (strictly increasing, one per waypoint).
    pub times: Vec<f64>,
    /// Per segment and output (x, y, z, ψ): coefficients in τ.
    pub coefficients: Vec<[[f64; N_COEF]; 4]>,
    /// Per knot and output: the end derivatives `[v, a, j]` (physical units).
    pub knot_derivatives: Vec<[[f64; 3]; 4]>,
}

/// Solve the minimum-snap problem through `values[k][output]` (x, y, z, ψ at
/// knot `k`) at `times[k]`, at rest at both ends.
pub fn solve(times: &[f64], values: &[[f64; 4]]) -> Result<Plan, IllConditioned> {
    let (minv, h) = matrices();
    let knots = times.len();
    let segments = knots - 1;
    let n = 3 * knots.saturating_sub(2);
    // Global index of (knot, derivative order 1..=3), if free.
    let free = |knot: usize, order: usize| -> Option<usize> {
        (order > 0 && knot > 0 && knot < knots - 1).then(|| 3 * (knot - 1) + order - 1)
    };
    // Banded lower storage: band[i][d] = A[i][i − d].
    let mut band = vec![[0.0; BAND + 1]; n];
    let mut rhs = vec![[0.0; 4]; n];
    for i in 0..segments {
        let t = times[i + 1] - times[i];
        let g = |r: usize, s: usize| h[r][s] * pow_i(t, r % 4) * pow_i(t, s % 4) / ftsmc_core::math::powf(t, 7.0);
        for r in 0..N_COEF {
            let (knot_r, order_r) = (i + r / 4, r % 4);
            let Some(gr) = free(knot_r, order_r) else { continue };
            for s in 0..N_COEF {
                let (knot_s, order_s) = (i + s / 4, s % 4);
                match free(knot_s, order_s) {
                    Some(gs) if gs <= gr => band[gr][gr - gs] += g(r, s),
                    Some(_) => {}
                    None if order_s == 0 => {
                        for o in 0..4 {
                            rhs[gr][o] -= g(r, s) * values[knot_s][o];
                        }
                    }
                    None => {} // a fixed end derivative, 0
                }
            }
        }
    }
    // Jacobi equilibration: A' = D^-1/2 A D^-1/2, r' = D^-1/2 r.
    let scale: Vec<f64> = band.iter().map(|row| 1.0 / ftsmc_core::math::sqrt(row[0])).collect();
    for i in 0..n {
        for d in 0..=BAND.min(i) {
            band[i][d] *= scale[i] * scale[i - d];
        }
        for o in 0..4 {
            rhs[i][o] *= scale[i];
        }
    }
    // Banded Cholesky A' = L Lᵀ in place (L in `band`).
    for i in 0..n {
        for d in (0..=BAND.min(i)).rev() {
            let j = i - d;
            let mut s = band[i][d];
            for k in (i.saturating_sub(BAND)).max(j.saturating_sub(BAND))..j {
                s -= band[i][i - k] * band[j][j - k];
            }
            if d == 0 {
                if s.is_nan() || s < MIN_PIVOT {
                    return Err(IllConditioned { pivot: s, knot: i / 3 + 1 });
                }
                band[i][0] = ftsmc_core::math::sqrt(s);
            } else {
                band[i][d] = s / band[j][0];
            }
        }
    }
    // Solve L y = r', Lᵀ x = y for the four outputs.
    let mut x = rhs;
    for i in 0..n {
        for o in 0..4 {
            let mut s = x[i][o];
            for k in i.saturating_sub(BAND)..i {
                s -= band[i][i - k] * x[k][o];
            }
            x[i][o] = s / band[i][0];
        }
    }
    for i in (0..n).rev() {
        for o in 0..4 {
            let mut s = x[i][o];
            for k in (i + 1)..(i + 1 + BAND).min(n) {
                s -= band[k][k - i] * x[k][o];
            }
            x[i][o] = s / band[i][0];
        }
    }
    let mut knot_derivatives = vec![[[0.0; 3]; 4]; knots];
    for (k, kd) in knot_derivatives.iter_mut().enumerate() {
        for order in 1..4 {
            if let Some(g) = free(k, order) {
                for o in 0..4 {
                    kd[o][order - 1] = x[g][o] * scale[g];
                }
            }
        }
    }
    let coefficients = (0..segments)
        .map(|i| {
            let t = times[i + 1] - times[i];
            let mut out = [[0.0; N_COEF]; 4];
            for (o, c) in out.iter_mut().enumerate() {
                let (k0, k1) = (&knot_derivatives[i][o], &knot_derivatives[i + 1][o]);
                let d = [values[i][o], k0[0], k0[1], k0[2], values[i + 1][o], k1[0], k1[1], k1[2]];
                let b = scaled(t, &d);
                for (k, ck) in c.iter_mut().enumerate() {
                    *ck = (0..N_COEF).map(|r| minv[k][r] * b[r]).sum();
                }
            }
            out
        })
        .collect();
    Ok(Plan { times: times.to_vec(), coefficients, knot_derivatives })
}

impl Plan {
    /// Derivatives 0–4 of output `o` (x, y, z, ψ) at `t` (s): the first
    /// value before the first knot and the last after the last (at rest).
    pub fn derivatives(&self, o: usize, t: f64) -> [f64; 5] {
        let n = self.times.len();
        if n < 2 || t.is_nan() || t <= self.times[0] {
            return [self.coefficients.first().map_or(0.0, |c| c[o][0]), 0.0, 0.0, 0.0, 0.0];
        }
        if t >= self.times[n - 1] {
            let c = &self.coefficients[n - 2][o];
            return [c.iter().sum(), 0.0, 0.0, 0.0, 0.0];
        }
        let i = self.times.partition_point(|&k| k <= t).saturating_sub(1).min(n - 2);
        let tau = (t - self.times[i]) / (self.times[i + 1] - self.times[i]);
        self.segment_derivatives(i, o, tau)
    }

    /// Derivatives 0–4 (physical units) of output `o` on segment `i` at
    /// `τ ∈ [0, 1]` (its own polynomial, also at the ends: continuity tests).
    pub fn segment_derivatives(&self, i: usize, o: usize, tau: f64) -> [f64; 5] {
        let h = self.times[i + 1] - self.times[i];
        let c = &self.coefficients[i][o];
        let mut out = [0.0; 5];
        let mut scale = 1.0;
        for (m, v) in out.iter_mut().enumerate() {
            let mut acc = 0.0;
            for k in (m..N_COEF).rev() {
                acc = acc * tau + c[k] * falling(k, m);
            }
            *v = acc / scale;
            scale *= h;
        }
        out
    }

    /// The flat output at `t` (s).
    pub fn sample(&self, t: f64) -> FlatOutput {
        let [x, y, z, psi] = [0, 1, 2, 3].map(|o| self.derivatives(o, t));
        FlatOutput {
            pos: [x[0], y[0], z[0]],
            vel: [x[1], y[1], z[1]],
            acc: [x[2], y[2], z[2]],
            jerk: [x[3], y[3], z[3]],
            snap: [x[4], y[4], z[4]],
            yaw: psi[0],
            yaw_rate: psi[1],
            yaw_acc: psi[2],
        }
    }

    /// The snap cost `Σ ∫ (d⁴p/dt⁴)² dt` of output `o` (x, y, z, ψ).
    pub fn cost(&self, o: usize) -> f64 {
        let (_, h) = matrices();
        let last = self.times.len().saturating_sub(1);
        (0..last)
            .map(|i| {
                let (k0, k1) = (&self.knot_derivatives[i][o], &self.knot_derivatives[i + 1][o]);
                let p0 = self.coefficients[i][o][0];
                let p1: f64 = self.coefficients[i][o].iter().sum();
                let d = [p0, k0[0], k0[1], k0[2], p1, k1[0], k1[1], k1[2]];
                segment_cost(&h, self.times[i + 1] - self.times[i], &d)
            })
            .sum()
    }
}
