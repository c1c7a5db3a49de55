//! An interval for a mean: Student's t interval (Student 1908),
//! `x̄ ± t_{n−1, (1+c)/2} · s/√n`, `s` the sample standard deviation.
//! It assumes independent draws and leans on the central limit theorem
//! for non-normal data (adequate for the tens to thousands of runs a
//! batch flies; docs/statistics.md). Deterministic: no resampling.

use super::{check_confidence, Interval, StatsError};
use statrs::distribution::{ContinuousCDF, StudentsT};

/// Mean of the finite values of `values` with its t interval at
/// `confidence`. `None` for no finite value; one value: `[−∞, ∞]`.
pub fn mean_interval(values: &[f64], confidence: f64) -> Result<Option<Interval>, StatsError> {
    check_confidence(confidence)?;
    let v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    let n = v.len();
    if n == 0 {
        return Ok(None);
    }
    let mean = v.iter().sum::<f64>() / n as f64;
    if n == 1 {
        return Ok(Some(Interval { estimate: mean, lo: f64::NEG_INFINITY, hi: f64::INFINITY }));
    }
    let var = v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1) as f64;
    let t = StudentsT::new(0.0, 1.0, (n - 1) as f64).map(|d| d.inverse_cdf(0.5 + confidence / 2.0)).unwrap_or(f64::NAN);
    let half = t * (var / n as f64).sqrt();
    Ok(Some(Interval { estimate: mean, lo: mean - half, hi: mean + half }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn t_interval_of_a_worked_sample() {
        // 1..=5: mean 3, s = √2.5, t_{4, 0.975} = 2.776445.
        let i = mean_interval(&[1.0, 2.0, 3.0, 4.0, 5.0], 0.95).unwrap().unwrap();
        let half = 2.776_445_105 * (2.5f64 / 5.0).sqrt();
        assert!((i.hi - 3.0 - half).abs() < 1e-6, "{i:?}");
        assert!((i.lo - 3.0 + half).abs() < 1e-6);
    }
}
