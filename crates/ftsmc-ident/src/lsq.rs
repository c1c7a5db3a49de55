//! Linear least squares through normal equations, accumulated per flight
//! segment so that a bootstrap over segments only adds small matrices.
//!
//! For rows `y_k ≈ x_kᵀ β` the sums `XᵀX`, `Xᵀy`, `yᵀy`, `Σy` and `n` give
//! `β = (XᵀX)⁻¹ Xᵀy`, the residual sum of squares
//! `SSE = yᵀy − 2βᵀXᵀy + βᵀXᵀXβ` and the total `SST = yᵀy − (Σy)²/n`, so
//! `R² = 1 − SSE/SST` (Montgomery, Peck and Vining, "Introduction to Linear
//! Regression Analysis", 5th ed., §3.2–3.3).

/// Sums of the normal equations of `K` regressors.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Normal<const K: usize> {
    /// `XᵀX`.
    pub xtx: [[f64; K]; K],
    /// `Xᵀy`.
    pub xty: [f64; K],
    /// `yᵀy`.
    pub yty: f64,
    /// `Σ y`.
    pub ysum: f64,
    /// Number of rows.
    pub n: f64,
}

impl<const K: usize> Default for Normal<K> {
    fn default() -> Self {
        Self { xtx: [[0.0; K]; K], xty: [0.0; K], yty: 0.0, ysum: 0.0, n: 0.0 }
    }
}

/// A fit: coefficients, residual and total sums of squares.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fit<const K: usize> {
    /// β (zero for the columns left out).
    pub beta: [f64; K],
    /// Residual sum of squares.
    pub sse: f64,
    /// Total sum of squares about the mean.
    pub sst: f64,
}

impl<const K: usize> Fit<K> {
    /// `1 − SSE/SST` (NaN when the target does not vary).
    pub fn r2(&self) -> f64 {
        1.0 - self.sse / self.sst
    }
}

impl<const K: usize> Normal<K> {
    /// Adds the row `y ≈ xᵀβ`.
    pub fn push(&mut self, x: &[f64; K], y: f64) {
        for i in 0..K {
            for j in 0..K {
                self.xtx[i][j] += x[i] * x[j];
            }
            self.xty[i] += x[i] * y;
        }
        self.yty += y * y;
        self.ysum += y;
        self.n += 1.0;
    }

    /// Adds `weight` times the sums of `other` (a segment drawn `weight` times).
    pub fn add_scaled(&mut self, other: &Self, weight: f64) {
        for i in 0..K {
            for j in 0..K {
                self.xtx[i][j] += weight * other.xtx[i][j];
            }
            self.xty[i] += weight * other.xty[i];
        }
        self.yty += weight * other.yty;
        self.ysum += weight * other.ysum;
        self.n += weight * other.n;
    }

    /// Least squares on the columns `cols` only (the others' β are zero);
    /// `None` if those columns' `XᵀX` is singular (Cholesky fails).
    pub fn solve(&self, cols: &[usize]) -> Option<Fit<K>> {
        let m = cols.len();
        let mut a = vec![vec![0.0; m]; m];
        let mut b = vec![0.0; m];
        for (i, &ci) in cols.iter().enumerate() {
            for (j, &cj) in cols.iter().enumerate() {
                a[i][j] = self.xtx[ci][cj];
            }
            b[i] = self.xty[ci];
        }
        let x = cholesky_solve(a, b)?;
        let mut beta = [0.0; K];
        for (i, &ci) in cols.iter().enumerate() {
            beta[ci] = x[i];
        }
        let mut quad = 0.0;
        let mut lin = 0.0;
        for i in 0..K {
            lin += beta[i] * self.xty[i];
            for j in 0..K {
                quad += beta[i] * self.xtx[i][j] * beta[j];
            }
        }
        let sse = (self.yty - 2.0 * lin + quad).max(0.0);
        let sst = self.yty - self.ysum * self.ysum / self.n;
        Some(Fit { beta, sse, sst })
    }
}

/// Solves `A x = b` for a symmetric positive definite `A` (Cholesky,
/// `A = L Lᵀ`); `None` when a pivot is not positive relative to the
/// diagonal's scale (singular or indefinite).
pub fn cholesky_solve(a: Vec<Vec<f64>>, b: Vec<f64>) -> Option<Vec<f64>> {
    let n = b.len();
    let scale = (0..n).map(|i| a[i][i].abs()).fold(0.0, f64::max);
    if scale.is_nan() || scale <= 0.0 || !scale.is_finite() {
        return None;
    }
    let mut l = vec![vec![0.0; n]; n];
    for i in 0..n {
        for j in 0..=i {
            let mut s = a[i][j];
            for k in 0..j {
                s -= l[i][k] * l[j][k];
            }
            if i == j {
                if s.is_nan() || s <= 1e-12 * scale {
                    return None;
                }
                l[i][i] = s.sqrt();
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    let mut y = vec![0.0; n];
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s -= l[i][k] * y[k];
        }
        y[i] = s / l[i][i];
    }
    let mut x = vec![0.0; n];
    for i in (0..n).rev() {
        let mut s = y[i];
        for k in i + 1..n {
            s -= l[k][i] * x[k];
        }
        x[i] = s / l[i][i];
    }
    Some(x)
}

/// The `p`-quantile (0–1) of `values` by linear interpolation between order
/// statistics (Hyndman and Fan 1996, definition 7); NaN for none.
pub fn quantile(values: &[f64], p: f64) -> f64 {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let h = (v.len() - 1) as f64 * p;
    let lo = h.floor() as usize;
    let hi = (lo + 1).min(v.len() - 1);
    v[lo] + (h - lo as f64) * (v[hi] - v[lo])
}

/// `⌊x · n / 2⁶⁴⌋` for a uniform 64-bit `x`: an index below `n` (Lemire's
/// multiply-shift; bias below `n / 2⁶⁴`).
pub fn index_below(x: u64, n: usize) -> usize {
    ((x as u128 * n as u128) >> 64) as usize
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_an_exact_line_and_reports_r2_one() {
        let mut n = Normal::<2>::default();
        for k in 0..20 {
            let x = k as f64 * 0.1;
            n.push(&[x, 1.0], 3.0 * x - 2.0);
        }
        let fit = n.solve(&[0, 1]).unwrap();
        assert!((fit.beta[0] - 3.0).abs() < 1e-12 && (fit.beta[1] + 2.0).abs() < 1e-12, "{:?}", fit.beta);
        assert!((fit.r2() - 1.0).abs() < 1e-12);
        // A column of zeros is singular.
        let mut z = Normal::<2>::default();
        z.push(&[1.0, 0.0], 1.0);
        z.push(&[2.0, 0.0], 2.0);
        assert!(z.solve(&[0, 1]).is_none());
        assert!(z.solve(&[0]).is_some());
    }

    #[test]
    fn quantile_interpolates_order_statistics() {
        assert_eq!(quantile(&[3.0, 1.0, 2.0], 0.5), 2.0);
        assert_eq!(quantile(&[0.0, 10.0], 0.25), 2.5);
        assert!(quantile(&[], 0.5).is_nan());
    }
}
