//! Fixed-size dense matrices `[[f64; C]; R]` (row major) and the few
//! operations the estimators need: products, transposes, a Cholesky
//! factorisation and its solves. No allocation, no `unsafe`, and every sum
//! runs over its index in increasing order with plain `a * b + c` (Rust
//! never fuses these into an FMA), so results are the same bits on every
//! CPU.

/// An `R × C` matrix, row major: `m[i][j]` is row `i`, column `j`.
pub type Matrix<const R: usize, const C: usize> = [[f64; C]; R];

/// The `R × C` zero matrix.
pub const fn zeros<const R: usize, const C: usize>() -> Matrix<R, C> {
    [[0.0; C]; R]
}

/// The `N × N` identity.
pub fn identity<const N: usize>() -> Matrix<N, N> {
    let mut m = zeros::<N, N>();
    for i in 0..N {
        m[i][i] = 1.0;
    }
    m
}

/// `A B` (`R × K` times `K × C`), each element `Σ_k a_ik b_kj` summed in
/// increasing `k`.
pub fn mul<const R: usize, const K: usize, const C: usize>(a: &Matrix<R, K>, b: &Matrix<K, C>) -> Matrix<R, C> {
    let mut m = zeros::<R, C>();
    for i in 0..R {
        for j in 0..C {
            let mut s = 0.0;
            for k in 0..K {
                s += a[i][k] * b[k][j];
            }
            m[i][j] = s;
        }
    }
    m
}

/// `A Bᵀ` (`R × K` times the transpose of `C × K`).
pub fn mul_transpose<const R: usize, const K: usize, const C: usize>(
    a: &Matrix<R, K>,
    b: &Matrix<C, K>,
) -> Matrix<R, C> {
    let mut m = zeros::<R, C>();
    for i in 0..R {
        for j in 0..C {
            let mut s = 0.0;
            for k in 0..K {
                s += a[i][k] * b[j][k];
            }
            m[i][j] = s;
        }
    }
    m
}

/// `Aᵀ`.
pub fn transpose<const R: usize, const C: usize>(a: &Matrix<R, C>) -> Matrix<C, R> {
    let mut m = zeros::<C, R>();
    for i in 0..R {
        for j in 0..C {
            m[j][i] = a[i][j];
        }
    }
    m
}

/// `A x`.
pub fn mat_vec<const R: usize, const C: usize>(a: &Matrix<R, C>, x: &[f64; C]) -> [f64; R] {
    let mut y = [0.0; R];
    for i in 0..R {
        let mut s = 0.0;
        for k in 0..C {
            s += a[i][k] * x[k];
        }
        y[i] = s;
    }
    y
}

/// `A ← (A + Aᵀ)/2`: removes the rounding asymmetry of a covariance.
pub fn symmetrize<const N: usize>(a: &mut Matrix<N, N>) {
    for i in 0..N {
        for j in (i + 1)..N {
            let s = (a[i][j] + a[j][i]) * 0.5;
            a[i][j] = s;
            a[j][i] = s;
        }
    }
}

/// Lower-triangular `L` with `A = L Lᵀ` (Cholesky–Banachiewicz), or `None`
/// when `A` is not numerically positive definite (a pivot `≤ 0` or not
/// finite). Reads the lower triangle of `A` only.
pub fn cholesky<const N: usize>(a: &Matrix<N, N>) -> Option<Matrix<N, N>> {
    let mut l = zeros::<N, N>();
    for i in 0..N {
        for j in 0..=i {
            let mut s = a[i][j];
            for k in 0..j {
                s -= l[i][k] * l[j][k];
            }
            if i == j {
                if !(s > 0.0 && s.is_finite()) {
                    return None;
                }
                l[i][i] = crate::math::sqrt(s);
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    Some(l)
}

/// `L⁻¹ b` by forward substitution (`L` lower triangular, non-zero diagonal).
pub fn forward_substitute<const N: usize>(l: &Matrix<N, N>, b: &[f64; N]) -> [f64; N] {
    let mut y = [0.0; N];
    for i in 0..N {
        let mut s = b[i];
        for k in 0..i {
            s -= l[i][k] * y[k];
        }
        y[i] = s / l[i][i];
    }
    y
}

/// `L⁻ᵀ y` by back substitution (`L` lower triangular, non-zero diagonal).
pub fn back_substitute<const N: usize>(l: &Matrix<N, N>, y: &[f64; N]) -> [f64; N] {
    let mut x = [0.0; N];
    for i in (0..N).rev() {
        let mut s = y[i];
        for k in (i + 1)..N {
            s -= l[k][i] * x[k];
        }
        x[i] = s / l[i][i];
    }
    x
}

/// `A⁻¹ B` for `A = L Lᵀ` (`L` from [`cholesky`]), column by column.
pub fn cholesky_solve<const N: usize, const C: usize>(l: &Matrix<N, N>, b: &Matrix<N, C>) -> Matrix<N, C> {
    let mut x = zeros::<N, C>();
    for j in 0..C {
        let mut col = [0.0; N];
        for i in 0..N {
            col[i] = b[i][j];
        }
        let sol = back_substitute(l, &forward_substitute(l, &col));
        for i in 0..N {
            x[i][j] = sol[i];
        }
    }
    x
}

/// `[v]×`, the skew-symmetric matrix of the cross product: `[v]× u = v × u`.
pub fn skew(v: &[f64; 3]) -> Matrix<3, 3> {
    [[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cholesky_solves_a_positive_definite_system_and_refuses_an_indefinite_one() {
        let a: Matrix<3, 3> = [[4.0, 1.0, 0.5], [1.0, 3.0, 0.2], [0.5, 0.2, 2.0]];
        let l = cholesky(&a).unwrap();
        let back = mul_transpose(&l, &l);
        for i in 0..3 {
            for j in 0..3 {
                assert!((back[i][j] - a[i][j]).abs() < 1e-14);
            }
        }
        let b: Matrix<3, 1> = [[1.0], [2.0], [3.0]];
        let x = cholesky_solve(&l, &b);
        let ax = mul(&a, &x);
        for i in 0..3 {
            assert!((ax[i][0] - b[i][0]).abs() < 1e-13);
        }
        assert!(cholesky(&[[1.0, 2.0], [2.0, 1.0]]).is_none());
        assert!(cholesky(&[[f64::NAN]]).is_none());
    }
}
