//! A small ask/tell CMA-ES (Hansen, "The CMA Evolution Strategy: A
//! Tutorial", arXiv:1604.00772, 2016: the (μ/μ_w, λ) strategy with
//! cumulative step-size adaptation, rank-one and rank-μ covariance updates
//! and the default parameters of its Table 1).
//!
//! Written here rather than taken from a crate: the `cmaes` crate (0.2,
//! last released 2022) drives the objective itself instead of offering
//! ask/tell, and it and `haru_cmaes` bring nalgebra (and a second `rand`);
//! this one is ~200 lines on `rand_chacha`, which ftsmc already uses, and
//! its only randomness is one ChaCha8 stream seeded by the caller, drawn
//! in `ask` on the calling thread: the same seed gives the same candidates
//! whatever evaluates them, on however many threads.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::gauss::standard_normal;

/// CMA-ES state for minimisation in `n` dimensions.
#[derive(Clone, Debug)]
pub struct Cmaes {
    n: usize,
    lambda: usize,
    mu: usize,
    weights: Vec<f64>,
    mueff: f64,
    cc: f64,
    cs: f64,
    c1: f64,
    cmu: f64,
    damps: f64,
    chi_n: f64,
    mean: Vec<f64>,
    sigma: f64,
    /// Covariance C (row-major n × n).
    c: Vec<f64>,
    /// Eigenvectors of C (columns, row-major n × n).
    b: Vec<f64>,
    /// Square roots of the eigenvalues of C.
    d: Vec<f64>,
    pc: Vec<f64>,
    ps: Vec<f64>,
    generation: u64,
    rng: ChaCha8Rng,
}

impl Cmaes {
    /// A search around `mean` with step `sigma` (> 0), population `lambda`
    /// (`None`: `4 + ⌊3 ln n⌋`, at least 2) and the random stream `seed`.
    pub fn new(mean: Vec<f64>, sigma: f64, lambda: Option<usize>, seed: u64) -> Self {
        let n = mean.len().max(1);
        let lambda = lambda.unwrap_or(4 + (3.0 * ftsmc_core::math::ln(n as f64)).floor() as usize).max(2);
        let mu = lambda / 2;
        let raw: Vec<f64> = (1..=mu)
            .map(|i| ftsmc_core::math::ln((lambda as f64 + 1.0) / 2.0) - ftsmc_core::math::ln(i as f64))
            .collect();
        let sum: f64 = raw.iter().sum();
        let weights: Vec<f64> = raw.iter().map(|w| w / sum).collect();
        let mueff = 1.0 / weights.iter().map(|w| w * w).sum::<f64>();
        let nf = n as f64;
        let cc = (4.0 + mueff / nf) / (nf + 4.0 + 2.0 * mueff / nf);
        let cs = (mueff + 2.0) / (nf + mueff + 5.0);
        let c1 = 2.0 / ((nf + 1.3).powi(2) + mueff);
        let cmu = (1.0 - c1).min(2.0 * (mueff - 2.0 + 1.0 / mueff) / ((nf + 2.0).powi(2) + mueff));
        let damps = 1.0 + 2.0 * (((mueff - 1.0) / (nf + 1.0)).sqrt() - 1.0).max(0.0) + cs;
        let chi_n = nf.sqrt() * (1.0 - 1.0 / (4.0 * nf) + 1.0 / (21.0 * nf * nf));
        let mut identity = vec![0.0; n * n];
        for i in 0..n {
            identity[i * n + i] = 1.0;
        }
        let mut mean = mean;
        mean.resize(n, 0.0);
        Self {
            n,
            lambda,
            mu,
            weights,
            mueff,
            cc,
            cs,
            c1,
            cmu,
            damps,
            chi_n,
            mean,
            sigma,
            c: identity.clone(),
            b: identity,
            d: vec![1.0; n],
            pc: vec![0.0; n],
            ps: vec![0.0; n],
            generation: 0,
            rng: ChaCha8Rng::seed_from_u64(seed),
        }
    }

    /// Population size λ.
    pub fn population(&self) -> usize {
        self.lambda
    }

    /// Current mean of the search distribution.
    pub fn mean(&self) -> &[f64] {
        &self.mean
    }

    /// Current step size σ.
    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    /// The largest standard deviation of the search distribution along a
    /// principal axis, `σ · max(D)` (in the caller's coordinates): how far
    /// the next candidates may still move. A restart policy watches it for
    /// a collapsed step.
    pub fn max_std(&self) -> f64 {
        self.sigma * self.d.iter().copied().fold(0.0, f64::max)
    }

    /// λ new candidates `m + σ B D z`, `z ~ N(0, I)`.
    pub fn ask(&mut self) -> Vec<Vec<f64>> {
        let n = self.n;
        (0..self.lambda)
            .map(|_| {
                let z: Vec<f64> = (0..n).map(|_| standard_normal(&mut self.rng)).collect();
                (0..n)
                    .map(|i| {
                        let y: f64 = (0..n).map(|j| self.b[i * n + j] * self.d[j] * z[j]).sum();
                        self.mean[i] + self.sigma * y
                    })
                    .collect()
            })
            .collect()
    }

    /// Update the distribution from the candidates of the last [`Cmaes::ask`]
    /// and their costs (lower is better; NaN counts as worst; ties keep
    /// the candidates' order).
    pub fn tell(&mut self, candidates: &[Vec<f64>], costs: &[f64]) {
        let n = self.n;
        let mut order: Vec<usize> = (0..candidates.len().min(costs.len())).collect();
        let key = |i: usize| if costs[i].is_nan() { f64::INFINITY } else { costs[i] };
        order.sort_by(|&a, &b| key(a).total_cmp(&key(b)).then(a.cmp(&b)));
        let mu = self.mu.min(order.len());
        let old = self.mean.clone();
        let ys: Vec<Vec<f64>> =
            order[..mu].iter().map(|&k| (0..n).map(|i| (candidates[k][i] - old[i]) / self.sigma).collect()).collect();
        let yw: Vec<f64> = (0..n).map(|i| (0..mu).map(|k| self.weights[k] * ys[k][i]).sum()).collect();
        for i in 0..n {
            self.mean[i] = old[i] + self.sigma * yw[i];
        }
        // C^(-1/2) y_w = B D^-1 Bᵀ y_w
        let bt_y: Vec<f64> =
            (0..n).map(|j| (0..n).map(|i| self.b[i * n + j] * yw[i]).sum::<f64>() / self.d[j]).collect();
        let inv_sqrt_y: Vec<f64> = (0..n).map(|i| (0..n).map(|j| self.b[i * n + j] * bt_y[j]).sum()).collect();
        let ks = (self.cs * (2.0 - self.cs) * self.mueff).sqrt();
        for i in 0..n {
            self.ps[i] = (1.0 - self.cs) * self.ps[i] + ks * inv_sqrt_y[i];
        }
        let ps_norm = self.ps.iter().map(|v| v * v).sum::<f64>().sqrt();
        self.generation += 1;
        let denom = (1.0 - (1.0 - self.cs).powi(2 * self.generation.min(1 << 20) as i32)).sqrt();
        let hsig = ps_norm / denom / self.chi_n < 1.4 + 2.0 / (n as f64 + 1.0);
        let kc = (self.cc * (2.0 - self.cc) * self.mueff).sqrt();
        for i in 0..n {
            self.pc[i] = (1.0 - self.cc) * self.pc[i] + if hsig { kc * yw[i] } else { 0.0 };
        }
        let dh = if hsig { 0.0 } else { self.cc * (2.0 - self.cc) };
        for i in 0..n {
            for j in 0..n {
                let rank_mu: f64 = (0..mu).map(|k| self.weights[k] * ys[k][i] * ys[k][j]).sum();
                let cij = self.c[i * n + j];
                self.c[i * n + j] = (1.0 - self.c1 - self.cmu) * cij
                    + self.c1 * (self.pc[i] * self.pc[j] + dh * cij)
                    + self.cmu * rank_mu;
            }
        }
        // Cumulative step-size adaptation, the exponent capped at 1 (Hansen
        // 2016, Eq. 44 and its footnote): σ grows at most ×e per generation.
        self.sigma *= ftsmc_core::math::exp(((self.cs / self.damps) * (ps_norm / self.chi_n - 1.0)).min(1.0));
        self.decompose();
    }

    /// Eigendecomposition of C (cyclic Jacobi), kept symmetric and positive.
    fn decompose(&mut self) {
        let n = self.n;
        for i in 0..n {
            for j in 0..i {
                let v = 0.5 * (self.c[i * n + j] + self.c[j * n + i]);
                self.c[i * n + j] = v;
                self.c[j * n + i] = v;
            }
        }
        let (values, vectors) = jacobi_eigen(&self.c, n);
        self.b = vectors;
        self.d = values.iter().map(|v| v.max(1e-300).sqrt()).collect();
    }
}

/// Eigenvalues and eigenvectors (columns of a row-major matrix) of the
/// symmetric `n × n` matrix `a`, by cyclic Jacobi rotations.
pub fn jacobi_eigen(a: &[f64], n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut a = a.to_vec();
    let mut v = vec![0.0; n * n];
    for i in 0..n {
        v[i * n + i] = 1.0;
    }
    for _sweep in 0..100 {
        let off: f64 = (0..n)
            .flat_map(|i| (0..n).filter(move |&j| j != i).map(move |j| (i, j)))
            .map(|(i, j)| a[i * n + j].powi(2))
            .sum();
        let diag: f64 = (0..n).map(|i| a[i * n + i].powi(2)).sum();
        if off <= 1e-30 * diag || off == 0.0 {
            break;
        }
        for p in 0..n {
            for q in p + 1..n {
                let apq = a[p * n + q];
                if apq == 0.0 {
                    continue;
                }
                let theta = (a[q * n + q] - a[p * n + p]) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..n {
                    let (akp, akq) = (a[k * n + p], a[k * n + q]);
                    a[k * n + p] = c * akp - s * akq;
                    a[k * n + q] = s * akp + c * akq;
                }
                for k in 0..n {
                    let (apk, aqk) = (a[p * n + k], a[q * n + k]);
                    a[p * n + k] = c * apk - s * aqk;
                    a[q * n + k] = s * apk + c * aqk;
                }
                for k in 0..n {
                    let (vkp, vkq) = (v[k * n + p], v[k * n + q]);
                    v[k * n + p] = c * vkp - s * vkq;
                    v[k * n + q] = s * vkp + c * vkq;
                }
            }
        }
    }
    ((0..n).map(|i| a[i * n + i]).collect(), v)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn minimise(
        f: impl Fn(&[f64]) -> f64,
        start: Vec<f64>,
        sigma: f64,
        seed: u64,
        generations: usize,
    ) -> (Vec<f64>, f64) {
        let mut es = Cmaes::new(start, sigma, None, seed);
        let mut best = (Vec::new(), f64::INFINITY);
        for _ in 0..generations {
            let xs = es.ask();
            let fs: Vec<f64> = xs.iter().map(|x| f(x)).collect();
            for (x, v) in xs.iter().zip(&fs) {
                if *v < best.1 {
                    best = (x.clone(), *v);
                }
            }
            es.tell(&xs, &fs);
        }
        best
    }

    #[test]
    fn finds_the_minimum_of_an_ill_conditioned_ellipsoid() {
        let f = |x: &[f64]| {
            x.iter().enumerate().map(|(i, v)| ftsmc_core::math::powf(1e3f64, i as f64 / 4.0) * (v - 1.0).powi(2)).sum()
        };
        let (x, v) = minimise(f, vec![0.0; 5], 0.5, 3, 400);
        assert!(v < 1e-10, "{v}");
        assert!(x.iter().all(|xi| (xi - 1.0).abs() < 1e-4), "{x:?}");
    }

    #[test]
    fn finds_the_rosenbrock_valley_minimum() {
        let f =
            |x: &[f64]| (0..x.len() - 1).map(|i| 100.0 * (x[i + 1] - x[i] * x[i]).powi(2) + (1.0 - x[i]).powi(2)).sum();
        let (_, v) = minimise(f, vec![0.0; 4], 0.3, 11, 1500);
        assert!(v < 1e-8, "{v}");
    }

    /// Cumulative step-size adaptation must lengthen the step on a linear
    /// slope (Hansen 2016, Sec. 4.2: consecutive steps correlate), so that
    /// an optimum many initial steps away is reached: with σ only ever
    /// shrinking, the search stalls a few steps from where it started.
    #[test]
    fn the_step_grows_on_a_slope_and_reaches_a_far_optimum() {
        let mut es = Cmaes::new(vec![0.0; 4], 0.1, None, 3);
        for _ in 0..10 {
            let xs = es.ask();
            let costs: Vec<f64> = xs.iter().map(|x| -x[0]).collect();
            es.tell(&xs, &costs);
        }
        assert!(es.sigma() > 0.3, "σ {} after 10 generations on a slope", es.sigma());
        let far = |x: &[f64]| x.iter().map(|v| (v - 30.0) * (v - 30.0)).sum::<f64>();
        let (_, v) = minimise(far, vec![0.0; 4], 0.3, 8, 400);
        assert!(v < 1e-6, "{v}");
    }

    #[test]
    fn same_seed_same_candidates_and_other_seed_other_ones() {
        let mut a = Cmaes::new(vec![0.5; 3], 0.2, None, 9);
        let mut b = Cmaes::new(vec![0.5; 3], 0.2, None, 9);
        let mut c = Cmaes::new(vec![0.5; 3], 0.2, None, 10);
        let (xa, xb, xc) = (a.ask(), b.ask(), c.ask());
        assert_eq!(xa, xb);
        assert_ne!(xa, xc);
        assert_eq!(a.population(), 7);
    }

    #[test]
    fn jacobi_reconstructs_a_symmetric_matrix() {
        let m = [4.0, 1.0, 0.5, 1.0, 3.0, 0.2, 0.5, 0.2, 1.0];
        let (w, v) = jacobi_eigen(&m, 3);
        for i in 0..3 {
            for j in 0..3 {
                let r: f64 = (0..3).map(|k| v[i * 3 + k] * w[k] * v[j * 3 + k]).sum();
                assert!((r - m[i * 3 + j]).abs() < 1e-12);
            }
        }
    }
}
