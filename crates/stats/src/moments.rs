//! Streaming-mergeable central moments (count, mean, second to fourth central
//! sums, minimum and maximum).
//!
//! A chunk is summarised with a two-pass algorithm (mean first, then centered
//! power sums), and summaries are combined with the pairwise update formulas
//! of Chan, Golub & LeVeque (1979) extended to the third and fourth moments by
//! Pébay, "Formulas for robust, one-pass parallel computation of covariances
//! and arbitrary-order statistical moments", Sandia report SAND2008-6212
//! (2008), equations (2.1)–(2.4) / (3.1).
//!
//! Merging is deterministic but not bit-commutative: the engine must merge
//! chunk summaries in a fixed order (chunk order) to get bit-identical results
//! whatever the thread count.

/// Number of independent accumulators used by [`Moments::from_slice`] so that
/// the summation loops vectorise (floating-point addition is not associative,
/// so the compiler cannot do this on its own).
const LANES: usize = 4;

/// The instruction sets [`Moments::from_slice`] may use (the processor's report, read once).
static ARCH: std::sync::LazyLock<pulp::Arch> = std::sync::LazyLock::new(pulp::Arch::new);

/// Count, mean, central power sums, minimum and maximum of a set of values.
///
/// `m2`, `m3` and `m4` are the sums of `(x - mean)^k` for k = 2, 3, 4 (not
/// divided by n). An empty summary has `n == 0`, `mean == 0`, all sums 0,
/// `min == +inf` and `max == -inf`.
#[derive(Clone, Debug, PartialEq)]
pub struct Moments {
    /// Number of values.
    pub n: u64,
    /// Arithmetic mean (0 when empty).
    pub mean: f64,
    /// Sum of squared deviations from the mean.
    pub m2: f64,
    /// Sum of cubed deviations from the mean.
    pub m3: f64,
    /// Sum of fourth powers of deviations from the mean.
    pub m4: f64,
    /// Smallest value (+inf when empty).
    pub min: f64,
    /// Largest value (-inf when empty).
    pub max: f64,
}

/// [`Moments::from_slice`] as an operation `pulp` compiles once per instruction set.
struct Summary<'a>(&'a [f64]);

impl pulp::WithSimd for Summary<'_> {
    type Output = Moments;
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) -> Moments {
        Moments::summarise(self.0)
    }
}

impl Default for Moments {
    fn default() -> Self {
        Self::new()
    }
}

/// `value` if it is below `current`, else `current`: compare-and-select, one instruction
/// per lane where f64::min needs a NaN fix-up (a NaN `value` compares false and is
/// skipped, as with f64::min).
#[inline(always)]
fn smaller(current: f64, value: f64) -> f64 {
    if value < current {
        value
    } else {
        current
    }
}

/// `value` if it is above `current`, else `current` (see [`smaller`]).
#[inline(always)]
fn larger(current: f64, value: f64) -> f64 {
    if value > current {
        value
    } else {
        current
    }
}

impl Moments {
    /// The empty summary: n 0, mean and sums 0, min +inf, max -inf.
    pub fn new() -> Moments {
        Moments {
            n: 0,
            mean: 0.0,
            m2: 0.0,
            m3: 0.0,
            m4: 0.0,
            min: f64::INFINITY,
            max: f64::NEG_INFINITY,
        }
    }

    /// Summarises a slice with a two-pass algorithm: the mean (refined by the
    /// mean of the first-pass residuals), then the centered power sums.
    ///
    /// The loops use a fixed number of independent accumulators so they
    /// vectorise; the result depends only on the slice contents, never on
    /// the machine or thread. NaN values are not expected (the caller filters
    /// them); if present they propagate into the mean and sums but are
    /// ignored by min/max.
    ///
    /// Built for the widest instruction set the processor has (`pulp`, chosen at run time):
    /// the same operations in the same order in every build, so the same bits (tested).
    pub fn from_slice(values: &[f64]) -> Moments {
        ARCH.dispatch(Summary(values))
    }

    /// [`Moments::from_slice`], inlined into each instruction set's build.
    #[inline(always)]
    fn summarise(values: &[f64]) -> Moments {
        if values.is_empty() {
            return Moments::new();
        }
        let count = values.len() as f64;

        let mut sums = [0.0_f64; LANES];
        let mut mins = [f64::INFINITY; LANES];
        let mut maxs = [f64::NEG_INFINITY; LANES];
        let chunks = values.chunks_exact(LANES);
        let remainder = chunks.remainder();
        for chunk in chunks {
            for lane in 0..LANES {
                let value = chunk[lane];
                sums[lane] += value;
                mins[lane] = smaller(mins[lane], value);
                maxs[lane] = larger(maxs[lane], value);
            }
        }
        for (lane, &value) in remainder.iter().enumerate() {
            sums[lane] += value;
            mins[lane] = smaller(mins[lane], value);
            maxs[lane] = larger(maxs[lane], value);
        }
        let sum = (sums[0] + sums[1]) + (sums[2] + sums[3]);
        let min = mins.iter().fold(f64::INFINITY, |a, &b| a.min(b));
        let max = maxs.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b));
        let rough_mean = sum / count;

        let mut d1 = [0.0_f64; LANES];
        let mut d2 = [0.0_f64; LANES];
        let mut d3 = [0.0_f64; LANES];
        let mut d4 = [0.0_f64; LANES];
        let chunks = values.chunks_exact(LANES);
        for chunk in chunks {
            for lane in 0..LANES {
                let d = chunk[lane] - rough_mean;
                let d_squared = d * d;
                d1[lane] += d;
                d2[lane] += d_squared;
                d3[lane] += d_squared * d;
                d4[lane] += d_squared * d_squared;
            }
        }
        for (lane, &value) in remainder.iter().enumerate() {
            let d = value - rough_mean;
            let d_squared = d * d;
            d1[lane] += d;
            d2[lane] += d_squared;
            d3[lane] += d_squared * d;
            d4[lane] += d_squared * d_squared;
        }
        let reduce = |lanes: [f64; LANES]| (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]);
        let s1 = reduce(d1);
        let s2 = reduce(d2);
        let s3 = reduce(d3);
        let s4 = reduce(d4);

        // Shift the sums about `rough_mean` to sums about the refined mean
        // `rough_mean + c` with c = s1 / n (binomial expansion; removes the
        // rounding error of the first pass).
        let c = s1 / count;
        let mean = rough_mean + c;
        let m2 = (s2 - c * s1).max(0.0);
        let m3 = s3 - 3.0 * c * s2 + 2.0 * c * c * s1;
        let m4 = (s4 - 4.0 * c * s3 + 6.0 * c * c * s2 - 3.0 * c * c * c * s1).max(0.0);

        Moments {
            n: values.len() as u64,
            mean,
            m2,
            m3,
            m4,
            min,
            max,
        }
    }

    /// Combines `other` into `self` (Pébay 2008, eq. 3.1 with p = 2, 3, 4;
    /// Chan et al. 1979 for the mean and m2). Either side may be empty.
    ///
    /// Deterministic; not bit-commutative, so merge in a fixed order.
    pub fn merge(&mut self, other: &Moments) {
        if other.n == 0 {
            return;
        }
        if self.n == 0 {
            *self = other.clone();
            return;
        }
        let n_a = self.n as f64;
        let n_b = other.n as f64;
        let n = n_a + n_b;
        let delta = other.mean - self.mean;
        let delta_over_n = delta / n;
        let delta_over_n_squared = delta_over_n * delta_over_n;
        let n_a_n_b = n_a * n_b;

        let m2 = self.m2 + other.m2 + delta * delta_over_n * n_a_n_b;
        let m3 = self.m3
            + other.m3
            + delta * delta_over_n_squared * n_a_n_b * (n_a - n_b)
            + 3.0 * delta_over_n * (n_a * other.m2 - n_b * self.m2);
        let m4 = self.m4
            + other.m4
            + delta
                * delta_over_n
                * delta_over_n_squared
                * n_a_n_b
                * (n_a * n_a - n_a_n_b + n_b * n_b)
            + 6.0 * delta_over_n_squared * (n_a * n_a * other.m2 + n_b * n_b * self.m2)
            + 4.0 * delta_over_n * (n_a * other.m3 - n_b * self.m3);

        self.mean += delta_over_n * n_b;
        self.n += other.n;
        self.m2 = m2.max(0.0);
        self.m3 = m3;
        self.m4 = m4.max(0.0);
        self.min = self.min.min(other.min);
        self.max = self.max.max(other.max);
    }

    /// Sample variance `m2 / (n - 1)`; 0 when n < 2.
    pub fn variance(&self) -> f64 {
        if self.n < 2 {
            0.0
        } else {
            (self.m2 / (self.n - 1) as f64).max(0.0)
        }
    }

    /// Sample standard deviation `sqrt(variance())`; 0 when n < 2.
    pub fn sd(&self) -> f64 {
        self.variance().sqrt()
    }

    /// Skewness g1 = sqrt(n)·m3 / m2^1.5 (population-moment estimator,
    /// Joanes & Gill 1998 "g1"); 0 when m2 == 0 or n == 0.
    pub fn skewness(&self) -> f64 {
        if self.n == 0 || self.m2 <= 0.0 {
            return 0.0;
        }
        (self.n as f64).sqrt() * self.m3 / (self.m2 * self.m2.sqrt())
    }

    /// Excess kurtosis g2 = n·m4 / m2² − 3 (population-moment estimator,
    /// Joanes & Gill 1998 "g2"); 0 when m2 == 0 or n == 0.
    pub fn excess_kurtosis(&self) -> f64 {
        if self.n == 0 || self.m2 <= 0.0 {
            return 0.0;
        }
        self.n as f64 * self.m4 / (self.m2 * self.m2) - 3.0
    }

    /// Standard error of the mean, σ/√n (0 when n == 0).
    pub fn mean_standard_error(&self) -> f64 {
        if self.n == 0 {
            return 0.0;
        }
        self.sd() / (self.n as f64).sqrt()
    }

    /// Standard error of the standard deviation by the delta method, σ·√((κ + 2)/(4n))
    /// with κ the excess kurtosis (σ/√(2n) for a normal sample); 0 when n == 0.
    pub fn sd_standard_error(&self) -> f64 {
        if self.n == 0 {
            return 0.0;
        }
        self.sd() * ((self.excess_kurtosis() + 2.0).max(0.0) / (4.0 * self.n as f64)).sqrt()
    }
}

/// Standard error s/√R of a figure estimated by R independent replicates (Latin
/// hypercube or RQMC), s the standard deviation of the replicate values (divisor R − 1):
/// NaN for fewer than two values or a non-finite one.
pub fn replicate_standard_error(values: &[f64]) -> f64 {
    let r = values.len();
    if r < 2 || values.iter().any(|v| !v.is_finite()) {
        return f64::NAN;
    }
    let mean = values.iter().sum::<f64>() / r as f64;
    let variance = values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (r - 1) as f64;
    (variance / r as f64).sqrt()
}

/// The quantile at probability `p` of Student's t with `degrees_of_freedom` (the
/// replicate intervals' t, R − 1 degrees of freedom).
pub fn student_t_quantile(degrees_of_freedom: f64, p: f64) -> f64 {
    use statrs::distribution::{ContinuousCDF, StudentsT};
    StudentsT::new(0.0, 1.0, degrees_of_freedom)
        .expect("positive degrees of freedom")
        .inverse_cdf(p)
}

/// Binomial standard error √(p(1 − p)/n) of an estimated fraction, with p raised to at
/// least 1/n so that a fraction of 0 still has an error of one count's worth.
pub fn proportion_standard_error(fraction: f64, n: u64) -> f64 {
    let nf = n.max(1) as f64;
    let p = fraction.max(1.0 / nf);
    (p * (1.0 - p) / nf).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_instruction_set_summarises_to_the_same_bits() {
        // The baseline build, AVX2 and AVX-512 where this processor has them, and the
        // dispatch: lengths around the four lanes, values of mixed sign and scale, a NaN.
        use pulp::Simd;
        let mut state = 7_u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.3) * 1e3
        };
        let bits = |m: &Moments| [m.mean, m.m2, m.m3, m.m4, m.min, m.max].map(f64::to_bits);
        for n in [0, 1, 3, 4, 5, 63, 1000, 4099] {
            let mut values: Vec<f64> = (0..n).map(|i| next() * (1.0 + i as f64)).collect();
            if n == 63 {
                values[20] = f64::NAN;
            }
            let baseline = Simd::vectorize(pulp::Scalar::new(), Summary(&values));
            let mut builds = vec![Moments::from_slice(&values)];
            #[cfg(target_arch = "x86_64")]
            {
                if let Some(simd) = pulp::x86::V3::try_new() {
                    builds.push(Simd::vectorize(simd, Summary(&values)));
                }
                if let Some(simd) = pulp::x86::V4::try_new() {
                    builds.push(Simd::vectorize(simd, Summary(&values)));
                }
            }
            for build in &builds {
                assert_eq!(build.n, baseline.n);
                assert_eq!(bits(build), bits(&baseline), "{n} values");
            }
        }
    }

    fn relative_difference(a: f64, b: f64) -> f64 {
        if a == b {
            0.0
        } else {
            (a - b).abs() / a.abs().max(b.abs())
        }
    }

    /// Deterministic pseudo-random data (64-bit LCG, Knuth MMIX constants).
    fn lcg_values(count: usize, seed: u64) -> Vec<f64> {
        let mut state = seed;
        (0..count)
            .map(|_| {
                state = state
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                let uniform = (state >> 11) as f64 / (1u64 << 53) as f64;
                // Skewed, shifted data: exercises m3 and m4.
                10.0 + uniform * uniform * 3.0 - uniform
            })
            .collect()
    }

    #[test]
    fn one_to_ten_known_values() {
        // 1..=10: mean 5.5, sum of squared deviations 82.5, sample variance
        // 82.5 / 9 = 9.1666..., symmetric so g1 = 0; sum of fourth powers of
        // deviations 2·(0.5⁴+1.5⁴+2.5⁴+3.5⁴+4.5⁴) = 1208.625, so
        // g2 = 10·1208.625/82.5² − 3 = −1.2242424... (hand computation; equals
        // scipy.stats.kurtosis(range(1, 11)) with the default bias=True).
        let values: Vec<f64> = (1..=10).map(f64::from).collect();
        let moments = Moments::from_slice(&values);
        assert_eq!(moments.n, 10);
        assert!((moments.mean - 5.5).abs() < 1e-15);
        assert!((moments.variance() - 82.5 / 9.0).abs() < 1e-12);
        assert!((moments.variance() - 9.166_666_666_666_666).abs() < 1e-12);
        assert!(moments.skewness().abs() < 1e-12);
        assert!((moments.excess_kurtosis() - (-1.224_242_424_242_424_2)).abs() < 1e-12);
        assert_eq!(moments.min, 1.0);
        assert_eq!(moments.max, 10.0);
    }

    #[test]
    fn skewed_known_values() {
        // Data {1, 2, 3, 10}: mean 4, deviations −3, −2, −1, 6:
        // m2 = 9+4+1+36 = 50, m3 = −27−8−1+216 = 180, m4 = 81+16+1+1296 = 1394
        // (hand computation). g1 = sqrt(4)·180/50^1.5, g2 = 4·1394/2500 − 3.
        let moments = Moments::from_slice(&[1.0, 2.0, 3.0, 10.0]);
        assert!((moments.m2 - 50.0).abs() < 1e-12);
        assert!((moments.m3 - 180.0).abs() < 1e-12);
        assert!((moments.m4 - 1394.0).abs() < 1e-12);
        let expected_skewness = 2.0 * 180.0 / 50.0_f64.powf(1.5);
        assert!((moments.skewness() - expected_skewness).abs() < 1e-12);
        assert!((moments.excess_kurtosis() - (4.0 * 1394.0 / 2500.0 - 3.0)).abs() < 1e-12);
    }

    #[test]
    fn merging_arbitrary_splits_matches_whole() {
        let values = lcg_values(10_007, 42);
        let whole = Moments::from_slice(&values);
        for split_sizes in [
            vec![1, 10_006],
            vec![10_006, 1],
            vec![4096, 4096, 1815],
            vec![3, 5, 7, 11, 13, 9968],
            vec![5000, 0, 5007],
        ] {
            let mut merged = Moments::new();
            let mut start = 0;
            for size in split_sizes {
                merged.merge(&Moments::from_slice(&values[start..start + size]));
                start += size;
            }
            assert_eq!(merged.n, whole.n);
            assert!(relative_difference(merged.mean, whole.mean) < 1e-12);
            assert!(relative_difference(merged.m2, whole.m2) < 1e-12);
            assert!(relative_difference(merged.m3, whole.m3) < 1e-12);
            assert!(relative_difference(merged.m4, whole.m4) < 1e-12);
            assert_eq!(merged.min, whole.min);
            assert_eq!(merged.max, whole.max);
        }
        // One value at a time (the worst case for the update formulas).
        let mut merged = Moments::new();
        for &value in &values {
            merged.merge(&Moments::from_slice(&[value]));
        }
        assert!(relative_difference(merged.m2, whole.m2) < 1e-12);
        assert!(relative_difference(merged.m3, whole.m3) < 1e-10);
        assert!(relative_difference(merged.m4, whole.m4) < 1e-12);
    }

    #[test]
    fn empty_and_single() {
        let empty = Moments::from_slice(&[]);
        assert_eq!(empty, Moments::new());
        assert_eq!(empty.variance(), 0.0);
        assert_eq!(empty.skewness(), 0.0);
        assert_eq!(empty.excess_kurtosis(), 0.0);
        let mut single = Moments::from_slice(&[3.5]);
        assert_eq!(single.variance(), 0.0);
        assert_eq!(single.sd(), 0.0);
        assert_eq!(single.skewness(), 0.0);
        single.merge(&Moments::new());
        assert_eq!(single, Moments::from_slice(&[3.5]));
        let mut from_empty = Moments::new();
        from_empty.merge(&single);
        assert_eq!(from_empty, single);
        let constant = Moments::from_slice(&[2.0; 9]);
        assert_eq!(constant.variance(), 0.0);
        assert_eq!(constant.skewness(), 0.0);
        assert_eq!(constant.excess_kurtosis(), 0.0);
    }

    #[test]
    fn merge_is_deterministic() {
        let values = lcg_values(1000, 7);
        let run = || {
            let mut merged = Moments::new();
            for chunk in values.chunks(97) {
                merged.merge(&Moments::from_slice(chunk));
            }
            merged
        };
        let first = run();
        let second = run();
        assert_eq!(first.mean.to_bits(), second.mean.to_bits());
        assert_eq!(first.m4.to_bits(), second.m4.to_bits());
    }
}
