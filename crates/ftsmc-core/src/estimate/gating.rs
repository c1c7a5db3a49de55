//! Innovation gating by a chi-square test on the normalised innovation
//! squared (NIS).
//!
//! For a consistent filter the innovation `y` of an `m`-dimensional update
//! is zero-mean Gaussian with covariance `S = H P Hᵀ + R`, so
//! `NIS = yᵀ S⁻¹ y` is chi-square with `m` degrees of freedom. An update is
//! accepted when `NIS ≤ χ²_m(p)`, the `p` quantile (the validation gate of
//! Bar-Shalom, Li & Kirubarajan, *Estimation with Applications to Tracking
//! and Navigation*, Wiley 2001, §2.4.3 and §5.4.2); a rejected update leaves
//! the state and covariance untouched and is counted. The default gate
//! probability is 0.999: a consistent reading is rejected once in a
//! thousand, a 50-sigma outlier always (NIS ≈ 2500 against χ²₆(0.999) ≈ 22.46).
//!
//! The quantile is computed, not tabulated: the chi-square CDF of an
//! integer number of degrees of freedom `k` is the regularised lower
//! incomplete gamma function `P(k/2, x/2)`, which has closed forms — for
//! even `k`, `P(n, y) = 1 − e^{−y} Σ_{i<n} yⁱ/i!`; for odd `k`, from
//! `P(½, y) = erf(√y)` by `P(a+1, y) = P(a, y) − yᵃ e^{−y}/Γ(a+1)`
//! (Abramowitz & Stegun 1964, 6.5.13 and 26.4.4–5) — and the quantile is
//! found by bisection on it to the last bit (no iteration-order or
//! CPU-dependent path: `libm`'s `exp`, `erf` and `sqrt`).

use crate::math::{exp, sqrt};

/// `P(χ²_k ≤ x)`, the chi-square CDF with `k ≥ 1` degrees of freedom at
/// `x` (0 for `x ≤ 0`). Exact closed forms (module docs), absolute error a
/// few `1e-16`.
pub fn chi_square_cdf(x: f64, k: u32) -> f64 {
    if x.is_nan() {
        return f64::NAN;
    }
    if x <= 0.0 || k == 0 {
        return 0.0;
    }
    if x == f64::INFINITY {
        return 1.0;
    }
    let y = x * 0.5;
    let e = exp(-y);
    if k % 2 == 0 {
        // 1 − e^{−y} Σ_{i<k/2} yⁱ/i!
        let mut term = 1.0;
        let mut sum = 1.0;
        for i in 1..(k / 2) {
            term *= y / f64::from(i);
            sum += term;
        }
        1.0 - e * sum
    } else {
        // P(½, y) = erf(√y); t_a = yᵃ e^{−y}/Γ(a+1) from t_½ = 2 √y e^{−y}/√π.
        let r = sqrt(y);
        let mut p = libm::erf(r);
        let mut t = 2.0 * r * e / sqrt(core::f64::consts::PI);
        let mut a = 0.5;
        for _ in 0..(k / 2) {
            p -= t;
            a += 1.0;
            t *= y / a;
        }
        p
    }
}

/// `χ²_k(p)`, the `p` quantile of the chi-square distribution with `k ≥ 1`
/// degrees of freedom (`0 < p < 1`), by bisection on [`chi_square_cdf`]
/// until the bracket stops shrinking (the last bit). NaN for `p` outside
/// `(0, 1)` or `k = 0`.
pub fn chi_square_quantile(p: f64, k: u32) -> f64 {
    if !(p > 0.0 && p < 1.0) || k == 0 {
        return f64::NAN;
    }
    let mut lo = 0.0;
    let mut hi = f64::from(k) + 10.0 * sqrt(2.0 * f64::from(k)) + 10.0;
    while chi_square_cdf(hi, k) < p {
        lo = hi;
        hi *= 2.0;
        if hi > 1e300 {
            return f64::INFINITY;
        }
    }
    loop {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            return hi;
        }
        if chi_square_cdf(mid, k) < p {
            lo = mid;
        } else {
            hi = mid;
        }
    }
}

/// The gate thresholds `χ²_m(p)` (dimensionless) for update dimensions
/// `m = 1 … 6`, computed once for a gate probability `p`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gate {
    /// Gate probability `p`, `0 < p < 1`.
    pub probability: f64,
    /// `thresholds[m − 1] = χ²_m(p)`.
    pub thresholds: [f64; 6],
}

impl Gate {
    /// The thresholds of gate probability `probability` (`0 < p < 1`,
    /// checked by the estimator configurations).
    pub fn new(probability: f64) -> Self {
        let mut thresholds = [0.0; 6];
        for (m, t) in thresholds.iter_mut().enumerate() {
            *t = chi_square_quantile(probability, m as u32 + 1);
        }
        Self { probability, thresholds }
    }

    /// `χ²_m(p)` for an update of dimension `m` (1 … 6).
    pub fn threshold(&self, m: usize) -> f64 {
        self.thresholds[m - 1]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against published table values (NIST/SEMATECH e-Handbook of
    /// Statistical Methods, 1.3.6.7.4, upper critical values of chi-square).
    #[test]
    fn quantiles_match_the_tables() {
        let table = [
            (0.95, 1, 3.841),
            (0.95, 2, 5.991),
            (0.95, 3, 7.815),
            (0.95, 6, 12.592),
            (0.999, 1, 10.828),
            (0.999, 3, 16.266),
            (0.999, 6, 22.458),
            (0.975, 15, 27.488),
            (0.025, 15, 6.262),
        ];
        for (p, k, want) in table {
            let q = chi_square_quantile(p, k);
            assert!((q - want).abs() < 1.5e-3, "chi2_{k}({p}) = {q}, table {want}");
            assert!((chi_square_cdf(q, k) - p).abs() < 1e-14);
        }
        assert!(chi_square_quantile(1.0, 3).is_nan());
        assert!(chi_square_quantile(0.5, 0).is_nan());
    }
}
