//! The empirical law of measured values: resampling them (the bootstrap), optionally
//! smoothed by a normal kernel with the variance kept.
//!
//! For n measured values x_1 … x_n with mean m and variance s² = (1/n)·Σ(x_i − m)²:
//!
//! - plain resampling draws x_I with I uniform on {1 … n}: one uniform u of the stream,
//!   I = ⌊u·n⌋ + 1 over the values sorted ascending, so the draw is the inverse of the
//!   empirical CDF (a quasi-random u keeps its structure). Mean m, variance s².
//! - the smoothed bootstrap adds a kernel draw h·z, z standard normal, and shrinks the sum
//!   towards m so the variance stays s² (Silverman 1986, *Density Estimation*, §6.4.1,
//!   the "shrunk" smoothed bootstrap): X = m + (x_I − m + h·z)/√(1 + h²/s²). Mean m,
//!   variance (s² + h²)/(1 + h²/s²) = s². Its values are no longer confined to the
//!   measured ones: a tail point beyond the largest measurement has a chance.
//! - the bandwidth h is given, or Silverman's rule of thumb (ibid. Eq. 3.31),
//!   h = 0.9·A·n^(−1/5) with A = min(s_{n−1}, IQR/1.34) (s_{n−1} when the IQR is 0).

use std::sync::Arc;

use rand::{Rng, RngExt};

use crate::error::DeviationError;
use crate::shown::Shown;
use crate::unit::unit_scale;

/// Mean and variance (divisor n) of the values.
fn moments(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let variance = values.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / n;
    (mean, variance)
}

/// Fewest values an empirical law takes: one value is a constant, not a distribution.
pub const MIN_EMPIRICAL_VALUES: usize = 2;

/// Measured values to resample, sorted, with their moments and the kernel bandwidth.
#[derive(Debug, Clone, PartialEq)]
pub struct EmpiricalLaw {
    sorted: Arc<[f64]>,
    bandwidth: f64,
    mean: f64,
    variance: f64,
    /// √(1 + h²/s²), the smoothed draw's shrink divisor (1 without smoothing).
    shrink: f64,
}

impl EmpiricalLaw {
    /// The law of `values` (any order) with kernel bandwidth `bandwidth` (0: plain
    /// resampling). `path` is the JSON path of the distribution object, for errors.
    pub fn new(path: &str, values: &[f64], bandwidth: f64) -> Result<Self, DeviationError> {
        if values.len() < MIN_EMPIRICAL_VALUES {
            return Err(DeviationError::invalid(
                format!("{path}.values"),
                format!(
                    "needs at least {MIN_EMPIRICAL_VALUES} values to resample, got {}",
                    values.len()
                ),
            ));
        }
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(DeviationError::invalid(
                format!("{path}.values[{i}]"),
                format!("must be a finite number, got {}", Shown(values[i])),
            ));
        }
        DeviationError::finite(&format!("{path}.bandwidth"), bandwidth)?;
        DeviationError::non_negative(&format!("{path}.bandwidth"), bandwidth)?;
        let mut sorted = values.to_vec();
        sorted.sort_by(f64::total_cmp);
        Ok(EmpiricalLaw::from_sorted(sorted, bandwidth))
    }

    /// The law of checked, sorted values with its moments and shrink divisor.
    fn from_sorted(sorted: Vec<f64>, bandwidth: f64) -> EmpiricalLaw {
        let (mean, variance) = moments(&sorted);
        let shrink = if variance > 0.0 {
            (1.0 + bandwidth * bandwidth / variance).sqrt()
        } else {
            1.0
        };
        EmpiricalLaw {
            sorted: sorted.into(),
            bandwidth,
            mean,
            variance,
            shrink,
        }
    }

    /// Silverman's rule-of-thumb bandwidth of `values`, 0.9·min(s, IQR/1.34)·n^(−1/5)
    /// (s with the n − 1 divisor; s alone when the IQR is 0). Needs two or more values.
    pub fn silverman_bandwidth(values: &[f64]) -> f64 {
        let n = values.len();
        if n < 2 {
            return 0.0;
        }
        let mut sorted = values.to_vec();
        sorted.sort_by(f64::total_cmp);
        let mean = sorted.iter().sum::<f64>() / n as f64;
        let s =
            (sorted.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n as f64 - 1.0)).sqrt();
        let quantile = |p: f64| {
            // Type 7 (linear between order statistics), as the run's percentiles.
            let h = (n as f64 - 1.0) * p;
            let (lo, frac) = (h.floor() as usize, h - h.floor());
            let hi = (lo + 1).min(n - 1);
            sorted[lo] + frac * (sorted[hi] - sorted[lo])
        };
        let iqr = quantile(0.75) - quantile(0.25);
        let spread = if iqr > 0.0 { s.min(iqr / 1.34) } else { s };
        0.9 * spread * (n as f64).powf(-0.2)
    }

    /// The values, sorted ascending.
    pub fn values(&self) -> &[f64] {
        &self.sorted
    }

    /// The kernel bandwidth h (0: plain resampling).
    pub fn bandwidth(&self) -> f64 {
        self.bandwidth
    }

    /// The mean m of the values, the law's mean.
    pub fn mean(&self) -> f64 {
        self.mean
    }

    /// The variance s² of the values (divisor n), the law's variance.
    pub fn variance(&self) -> f64 {
        self.variance
    }

    /// The law of f·X for a positive factor f (a change of unit): values and bandwidth
    /// times f ([`unit_scale`]), the moments those of the scaled values.
    pub fn scaled(&self, f: f64) -> EmpiricalLaw {
        let values: Vec<f64> = self.sorted.iter().map(|&x| unit_scale(x, f)).collect();
        EmpiricalLaw::from_sorted(values, unit_scale(self.bandwidth, f))
    }

    /// The value of the empirical inverse CDF at u in [0, 1): the ⌊u·n⌋-th smallest.
    #[inline]
    pub fn quantile_of(&self, u: f64) -> f64 {
        let n = self.sorted.len();
        self.sorted[((u * n as f64) as usize).min(n - 1)]
    }

    /// The value for the uniform u and, when smoothed, the standard normal z (module
    /// docs).
    #[inline]
    pub fn value(&self, u: f64, z: f64) -> f64 {
        let x = self.quantile_of(u);
        if self.bandwidth == 0.0 {
            return x;
        }
        if self.variance == 0.0 {
            // All values equal: the shrink leaves the constant.
            return self.mean;
        }
        self.mean + (x - self.mean + self.bandwidth * z) / self.shrink
    }

    /// Draws one value: one uniform of the stream, then, when smoothed, one ziggurat
    /// normal.
    #[inline]
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        let u: f64 = rng.random();
        let z = if self.bandwidth == 0.0 {
            0.0
        } else {
            crate::normal::Ziggurat::get().sample(rng)
        };
        self.value(u, z)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn plain_resampling_returns_each_value_at_its_share() {
        // Five values, 100,000 draws: each appears with probability 1/5; its count is
        // binomial(1e5, 0.2), sd 126.5: within 5 sd of 20,000.
        let law = EmpiricalLaw::new("d", &[3.0, -1.0, 2.0, 2.0, 7.5], 0.0).unwrap();
        assert_eq!(law.values(), &[-1.0, 2.0, 2.0, 3.0, 7.5]);
        assert_eq!(law.mean(), 13.5 / 5.0);
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        let mut counts = [0u32; 4];
        for _ in 0..100_000 {
            let x = law.sample(&mut rng);
            let k = [-1.0, 2.0, 3.0, 7.5].iter().position(|v| *v == x).unwrap();
            counts[k] += 1;
        }
        let sd = (1e5f64 * 0.2 * 0.8).sqrt();
        for (k, &c) in counts.iter().enumerate() {
            let expected = if k == 1 { 40_000.0 } else { 20_000.0 };
            let sd = if k == 1 {
                (1e5f64 * 0.4 * 0.6).sqrt()
            } else {
                sd
            };
            assert!((c as f64 - expected).abs() < 5.0 * sd, "{k}: {c}");
        }
    }

    #[test]
    fn the_smoothed_bootstrap_keeps_the_mean_and_variance() {
        // m = 2, s² = 2 for {0, 1, 2, 3, 4}; h = 1: the draws' mean within 5 SE of m and
        // their variance within 5 SE of s² (SE of a variance ≈ s²·√((κ − 1)/n), κ ≤ 3 here).
        let law = EmpiricalLaw::new("d", &[0.0, 1.0, 2.0, 3.0, 4.0], 1.0).unwrap();
        assert_eq!(law.variance(), 2.0);
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let n = 200_000;
        let draws: Vec<f64> = (0..n).map(|_| law.sample(&mut rng)).collect();
        let mean = draws.iter().sum::<f64>() / n as f64;
        let var = draws.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n as f64 - 1.0);
        assert!((mean - 2.0).abs() < 5.0 * (2.0 / n as f64).sqrt(), "{mean}");
        assert!(
            (var - 2.0).abs() < 5.0 * 2.0 * (2.0 / n as f64).sqrt(),
            "{var}"
        );
        // Not confined to the values.
        assert!(draws.iter().any(|x| x.fract() != 0.0));
    }

    #[test]
    fn silverman_rule_matches_its_hand_calculation() {
        // {1, 2, 3, 4, 10}: mean 4, s = √(54/4) = 3.6742; type-7 quartiles 2 and 4, IQR/1.34
        // = 1.4925 < s; h = 0.9·1.4925·5^(−0.2) = 1.0680.
        let h = EmpiricalLaw::silverman_bandwidth(&[10.0, 1.0, 2.0, 3.0, 4.0]);
        let expected = 0.9 * (2.0 / 1.34) * 5f64.powf(-0.2);
        assert!((h - expected).abs() < 1e-15, "{h}");
        // {1, 1, 1, 1, 5}: IQR 0, so s = √((4·0.8² + 3.2²)/4) = √3.2 instead.
        let h = EmpiricalLaw::silverman_bandwidth(&[1.0, 1.0, 1.0, 1.0, 5.0]);
        assert!(
            (h - 0.9 * 3.2f64.sqrt() * 5f64.powf(-0.2)).abs() < 1e-15,
            "{h}"
        );
    }

    #[test]
    fn bad_values_name_their_path() {
        let err = EmpiricalLaw::new("v.empirical", &[1.0], 0.0).unwrap_err();
        assert_eq!(err.path(), "v.empirical.values");
        let err = EmpiricalLaw::new("v.empirical", &[1.0, 2.0], -1.0).unwrap_err();
        assert_eq!(err.path(), "v.empirical.bandwidth");
    }
}
