//! The binomial law B ~ Binomial(n, p) at any n a run can reach (10¹² and beyond): its
//! probability mass by Loader's saddle-point form, its two tails as sums of those masses,
//! and the ranks of the distribution-free percentile intervals read off them exactly.
//!
//! Why not a library's CDF: `statrs::distribution::Binomial::cdf` evaluates the regularized
//! incomplete beta function by a continued fraction cut at 140 terms. Near the mean that
//! fraction needs about √(n·p·q) terms, so beyond n ≈ 10⁵ it returns an unconverged value
//! without an error (at n = 4·10⁷ the lower rank of P50's interval collapsed onto the
//! median and the interval covered 65 % of the time). The log-gamma route,
//! ln Γ(n + 1) − ln Γ(k + 1) − …, loses ε·ln Γ(n + 1) ≈ 6·10⁻³ of relative accuracy at
//! n = 10¹². Loader's form has neither problem.
//!
//! Mass (Loader, C. 2000, "Fast and accurate computation of binomial probabilities", Eq. 6):
//!
//!   b(k) = √(n / (2π·k·(n − k))) · exp(δ(n) − δ(k) − δ(n − k) − D(k, n·p) − D(n − k, n·q))
//!
//! with δ(m) = ln m! − (m + ½)·ln m + m − ½·ln 2π the Stirling remainder (tabulated to
//! m = 15, its asymptotic series above) and D(x, M) = x·ln(x/M) + M − x the deviance
//! term, summed as its series Σ 2x·v^(2j+1)/(2j + 1), v = (x − M)/(x + M), where x is near
//! M so that no cancellation occurs. Relative error about 10⁻¹⁴ at any n below 2⁵³.
//!
//! Tails: P(B ≤ k) = Σ_{j ≤ k} b(j), summed from k away from the mean through the ratio
//! b(j − 1)/b(j) = j·q / ((n − j + 1)·p), each mass re-anchored on Loader's form every
//! [`ANCHOR_EVERY`] terms so the recurrence's rounding cannot drift, with Neumaier's
//! compensated sum, and stopped once the geometric bound of the remaining terms falls below
//! 10⁻¹⁷ of the sum; P(B ≥ k) the same way upwards. Relative error about 10⁻¹³, so a rank is
//! exact unless a tail probability lies within 10⁻¹³ of its level. The cost is about
//! 8·√(n·p·q) terms per tail (10 ms at n = 10¹²), paid once per interval end: the ranks
//! are found by a walk from the normal approximation's guess, one mass per step.
//!
//! `tests/data/binomial_ranks.csv` holds the ranks of an independent 40-digit
//! computation (`scripts/binomial-reference.py`) at n = 10³ … 10¹² for every reported
//! percentile; the tests require equality.

use statrs::distribution::{ContinuousCDF, Normal};

/// A mass computed by the ratio recurrence is replaced by Loader's every this many terms.
const ANCHOR_EVERY: u64 = 256;

/// A walk from the guessed rank sums its tail afresh every this many steps, so that the
/// masses it adds or takes away cannot accumulate rounding.
const RESUM_EVERY: u32 = 64;

/// The sum stops when the bound of what is left is below this share of it.
const REST_SHARE: f64 = 1e-17;

/// δ(m) = ln m! − (m + ½)·ln m + m − ½·ln 2π for m = 0 … 15 (δ(0) = 0 by convention);
/// the values of R's `stirlerr` table (Loader 2000), checked against 40 digits in the tests.
#[allow(clippy::excessive_precision)] // the digits as published
const STIRLING_REMAINDER: [f64; 16] = [
    0.0,
    0.081_061_466_795_327_258,
    0.041_340_695_955_409_294,
    0.027_677_925_684_998_339,
    0.020_790_672_103_765_093,
    0.016_644_691_189_821_192,
    0.013_876_128_823_070_748,
    0.011_896_709_945_891_770,
    0.010_411_265_261_972_096,
    0.009_255_462_182_712_733,
    0.008_330_563_433_362_871,
    0.007_573_675_487_951_841,
    0.006_942_840_107_209_530,
    0.006_408_994_188_004_207,
    0.005_951_370_112_758_848,
    0.005_554_733_551_962_801,
];

/// δ(m), the Stirling remainder of ln m! (m a whole number as f64).
fn stirling_remainder(m: f64) -> f64 {
    const S0: f64 = 1.0 / 12.0;
    const S1: f64 = 1.0 / 360.0;
    const S2: f64 = 1.0 / 1260.0;
    const S3: f64 = 1.0 / 1680.0;
    const S4: f64 = 1.0 / 1188.0;
    if m <= 15.0 {
        return STIRLING_REMAINDER[m as usize];
    }
    let mm = m * m;
    if m > 500.0 {
        (S0 - S1 / mm) / m
    } else if m > 80.0 {
        (S0 - (S1 - S2 / mm) / mm) / m
    } else if m > 35.0 {
        (S0 - (S1 - (S2 - S3 / mm) / mm) / mm) / m
    } else {
        (S0 - (S1 - (S2 - (S3 - S4 / mm) / mm) / mm) / mm) / m
    }
}

/// D(x, M) = x·ln(x/M) + M − x ≥ 0, by its series where x is within 10 % of M.
fn deviance(x: f64, mean: f64) -> f64 {
    if (x - mean).abs() < 0.1 * (x + mean) {
        let mut v = (x - mean) / (x + mean);
        let mut sum = (x - mean) * v;
        if sum.abs() < f64::MIN_POSITIVE {
            return sum;
        }
        let mut power = 2.0 * x * v;
        v *= v;
        for j in 1..1000 {
            power *= v;
            let next = sum + power / f64::from(2 * j + 1);
            if next == sum {
                return next;
            }
            sum = next;
        }
        return sum;
    }
    x * (x / mean).ln() + mean - x
}

/// A binomial law Binomial(n, p), 0 < p < 1, n ≥ 1.
#[derive(Debug, Clone, Copy)]
struct Law {
    n: u64,
    p: f64,
    q: f64,
}

impl Law {
    /// b(k) = P(B = k) by Loader's form (module docs).
    fn mass(&self, k: u64) -> f64 {
        let Law { n, p, q } = *self;
        let (nf, kf) = (n as f64, k as f64);
        if k == 0 {
            let log_mass = if p < 0.1 {
                -deviance(nf, nf * q) - nf * p
            } else {
                nf * q.ln()
            };
            return log_mass.exp();
        }
        if k == n {
            let log_mass = if q < 0.1 {
                -deviance(nf, nf * p) - nf * q
            } else {
                nf * p.ln()
            };
            return log_mass.exp();
        }
        let rest = nf - kf;
        let log_mass = stirling_remainder(nf)
            - stirling_remainder(kf)
            - stirling_remainder(rest)
            - deviance(kf, nf * p)
            - deviance(rest, nf * q);
        let log_factor = (2.0 * std::f64::consts::PI).ln() + kf.ln() + (-kf / nf).ln_1p();
        (log_mass - 0.5 * log_factor).exp()
    }

    /// P(B ≤ k).
    fn lower_tail(&self, k: u64) -> f64 {
        if k >= self.n {
            return 1.0;
        }
        // b(j − 1) = b(j)·j·q / ((n − j + 1)·p)
        self.tail_sum(k, |j| {
            (j > 0).then(|| {
                (
                    j - 1,
                    j as f64 * self.q / ((self.n - j + 1) as f64 * self.p),
                )
            })
        })
    }

    /// P(B ≥ k).
    fn upper_tail(&self, k: u64) -> f64 {
        if k == 0 {
            return 1.0;
        }
        if k > self.n {
            return 0.0;
        }
        // b(j + 1) = b(j)·(n − j)·p / ((j + 1)·q)
        self.tail_sum(k, |j| {
            (j < self.n).then(|| {
                (
                    j + 1,
                    (self.n - j) as f64 * self.p / ((j + 1) as f64 * self.q),
                )
            })
        })
    }

    /// Σ b(j) from j = `start` outwards; `next(j)` gives the next index and the ratio of its
    /// mass to b(j), `None` at the end of the support. The ratios fall monotonically
    /// outwards, so once one is below 1 the rest is at most b(j)·r/(1 − r).
    fn tail_sum(&self, start: u64, next: impl Fn(u64) -> Option<(u64, f64)>) -> f64 {
        let mut index = start;
        let mut term = self.mass(start);
        let (mut sum, mut compensation) = (term, 0.0);
        let mut steps = 0u64;
        while let Some((following, ratio)) = next(index) {
            if ratio < 1.0 && term * ratio / (1.0 - ratio) <= REST_SHARE * sum {
                break;
            }
            steps += 1;
            index = following;
            term = if steps.is_multiple_of(ANCHOR_EVERY) {
                self.mass(index)
            } else {
                term * ratio
            };
            // Neumaier's compensated sum.
            let total = sum + term;
            compensation += if sum.abs() >= term.abs() {
                (sum - total) + term
            } else {
                (term - total) + sum
            };
            sum = total;
        }
        sum + compensation
    }

    /// The normal approximation's guess (with Cornish–Fisher's skewness term) of the rank
    /// at which the lower tail reaches `level`, clamped to [0, n].
    fn guess(&self, level: f64) -> u64 {
        let Law { n, p, q } = *self;
        let z = Normal::standard().inverse_cdf(level.clamp(1e-300, 1.0 - 1e-16));
        let nf = n as f64;
        let guess = nf * p + z * (nf * p * q).sqrt() + (q - p) * (z * z - 1.0) / 6.0 - 0.5;
        guess.round().clamp(0.0, nf) as u64
    }

    /// The largest m with P(B ≤ m) ≤ `tail`, `None` if even P(B ≤ 0) is above it.
    fn largest_with_lower_tail_at_most(&self, tail: f64) -> Option<u64> {
        let mut m = self.guess(tail);
        let mut below = self.lower_tail(m);
        let mut steps = 0u32;
        if below <= tail {
            while m < self.n {
                let next = below + self.mass(m + 1);
                if next > tail {
                    break;
                }
                (m, below) = (m + 1, next);
                steps += 1;
                if steps.is_multiple_of(RESUM_EVERY) {
                    below = self.lower_tail(m);
                }
            }
            return Some(m);
        }
        while below > tail {
            if m == 0 {
                return None;
            }
            below -= self.mass(m);
            m -= 1;
            steps += 1;
            if steps.is_multiple_of(RESUM_EVERY) {
                below = self.lower_tail(m);
            }
        }
        Some(m)
    }

    /// The smallest m with P(B ≥ m + 1) ≤ `tail`, i.e. P(B ≤ m) ≥ 1 − `tail` (at most n).
    fn smallest_with_upper_tail_at_most(&self, tail: f64) -> u64 {
        let mut m = self.guess(1.0 - tail);
        let mut above = self.upper_tail(m + 1);
        let mut steps = 0u32;
        if above <= tail {
            while m > 0 {
                let next = above + self.mass(m);
                if next > tail {
                    break;
                }
                (m, above) = (m - 1, next);
                steps += 1;
                if steps.is_multiple_of(RESUM_EVERY) {
                    above = self.upper_tail(m + 1);
                }
            }
            return m;
        }
        while above > tail && m < self.n {
            m += 1;
            above -= self.mass(m);
            steps += 1;
            if steps.is_multiple_of(RESUM_EVERY) {
                above = self.upper_tail(m + 1);
            }
        }
        m
    }
}

/// The 0-based ranks (l, u) of the distribution-free confidence interval
/// [X_(l), X_(u)] for the quantile of probability `p` from `n` values, at `confidence`
/// (e.g. 0.95), from the exact binomial law of B, the count of values below the
/// quantile (B ~ Binomial(n, p) for a continuous distribution): P(X_(l) ≤ x_p < X_(u)) =
/// P(l + 1 ≤ B ≤ u) ≥ confidence, with l the largest rank such that P(B ≤ l) ≤ α/2 and u
/// the smallest such that P(B ≤ u) ≥ 1 − α/2 (α = 1 − confidence; Hahn & Meeker 1991
/// §5.2). `None` for an end the sample cannot bound (too few values beyond the
/// percentile: the interval is open on that side).
pub fn binomial_rank_interval(n: usize, p: f64, confidence: f64) -> (Option<usize>, Option<usize>) {
    let tail = 0.5 * (1.0 - confidence);
    let n64 = n as u64;
    if n == 0 || p.is_nan() || !(0.0..1.0).contains(&tail) {
        return (None, None);
    }
    let p = p.clamp(0.0, 1.0);
    let (lower, upper) = if p == 0.0 {
        // B ≡ 0: P(B ≤ m) = 1 for every m.
        (None, 0)
    } else if p == 1.0 {
        // B ≡ n: P(B ≤ m) = 0 below n.
        (Some(n64 - 1), n64)
    } else {
        let law = Law {
            n: n64,
            p,
            q: 1.0 - p,
        };
        (
            law.largest_with_lower_tail_at_most(tail),
            law.smallest_with_upper_tail_at_most(tail),
        )
    };
    (
        lower.filter(|&r| r < n64).map(|r| r as usize),
        Some(upper).filter(|&r| r < n64).map(|r| r as usize),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    #[allow(clippy::excessive_precision)] // the reference's digits as computed
    fn stirling_remainders_match_a_40_digit_reference() {
        // δ(m) = ln Γ(m + 1) − (m + ½)·ln m + m − ½·ln 2π by mpmath at 40 digits, at the
        // table's ends and on both sides of each switch between the series' lengths. δ enters
        // the mass's exponent, so its absolute error is the mass's relative error: below
        // 5e-16, the first omitted term of the series being 691/(360360·m¹¹) ≤ 1.1e-16.
        let reference = [
            (1u64, 0.081_061_466_795_327_258_22),
            (2, 0.041_340_695_955_409_294_094),
            (5, 0.016_644_691_189_821_192_163),
            (15, 0.005_554_733_551_962_801_371),
            (16, 0.005_207_655_919_609_640_440_7),
            (20, 0.004_166_319_691_996_922_457_5),
            (35, 0.002_380_887_608_234_111_985_7),
            (36, 0.002_314_755_290_514_683_866_8),
            (51, 0.001_633_965_989_907_857_695_5),
            (80, 0.001_041_661_241_561_619_068_5),
            (81, 0.001_028_801_357_710_777_509_4),
            (100, 0.000_833_330_555_634_914_683_38),
            (500, 0.000_166_666_644_444_469_841_19),
            (501, 0.000_166_333_976_579_932_705_18),
            (1000, 0.000_083_333_330_555_556_349_206),
            (1_000_000, 8.333_333_333_333_055_555_6e-8),
        ];
        for (m, exact) in reference {
            let error = (stirling_remainder(m as f64) - exact).abs();
            assert!(
                error < 5e-16,
                "δ({m}) = {} against {exact}",
                stirling_remainder(m as f64)
            );
        }
    }

    #[test]
    fn masses_sum_to_one_and_match_the_product_form_at_small_n() {
        // At n ≤ 60 the mass is C(n, k)·p^k·q^(n−k) in plain arithmetic to 1e-13.
        for (n, p) in [
            (1u64, 0.3),
            (7, 0.3),
            (20, 0.5),
            (60, 0.00135),
            (60, 0.99865),
        ] {
            let law = Law { n, p, q: 1.0 - p };
            let mut total = 0.0;
            let mut choose = 1.0f64;
            for k in 0..=n {
                let product = choose * p.powi(k as i32) * (1.0 - p).powi((n - k) as i32);
                let mass = law.mass(k);
                assert!(
                    (mass - product).abs() <= 1e-13 * product.max(1e-300),
                    "n {n} p {p} k {k}: {mass} against {product}"
                );
                total += mass;
                choose *= (n - k) as f64 / (k + 1) as f64;
            }
            assert!((total - 1.0).abs() < 1e-13, "n {n} p {p}: {total}");
        }
    }

    #[test]
    fn tails_add_up_to_one_at_large_n() {
        // P(B ≤ k) + P(B ≥ k + 1) = 1: the two tails are summed independently, in opposite
        // directions, so their sum checks both to about 1e-13.
        for (n, p) in [
            (1_000_000u64, 0.5),
            (10u64.pow(12), 0.5),
            (10u64.pow(10), 0.00135),
        ] {
            let law = Law { n, p, q: 1.0 - p };
            let sd = (n as f64 * p * (1.0 - p)).sqrt();
            for z in [-3.0, -1.0, 0.0, 0.5, 2.0] {
                let k = (n as f64 * p + z * sd) as u64;
                let total = law.lower_tail(k) + law.upper_tail(k + 1);
                assert!((total - 1.0).abs() < 1e-12, "n {n} p {p} k {k}: {total}");
            }
        }
    }

    #[test]
    fn binomial_ranks_hold_their_coverage_exactly() {
        // P(l + 1 ≤ B ≤ u) ≥ 95 % with B ~ Binomial(n, p), and neither end can move
        // inwards without dropping below it (the interval is the shortest of its form).
        use statrs::distribution::{Binomial, DiscreteCDF};
        for (n, p) in [
            (1000, 0.5),
            (1000, 0.99865),
            (20_000, 0.00135),
            (100, 0.5),
            (7, 0.3),
        ] {
            let law = Binomial::new(p, n as u64).unwrap();
            let cdf = |k: i64| if k < 0 { 0.0 } else { law.cdf(k as u64) };
            let (l, u) = binomial_rank_interval(n, p, 0.95);
            let lo = l.map_or(-1, |l| l as i64);
            let hi = u.map_or(n as i64, |u| u as i64);
            let coverage = cdf(hi) - cdf(lo);
            assert!(coverage >= 0.95, "{n} {p}: {coverage}");
            assert!(
                cdf(lo) <= 0.025 && cdf(lo + 1) > 0.025 || l.is_none(),
                "{n} {p}"
            );
            assert!(
                cdf(hi) >= 0.975 && cdf(hi - 1) < 0.975 || u.is_none(),
                "{n} {p}"
            );
        }
        // n·(1 − p) = 1.35 values expected above P99.865 of 1000: the upper end is open.
        assert_eq!(binomial_rank_interval(1000, 0.99865, 0.95).1, None);
        // The normal approximation at p = 0.5, n = 10⁴: ranks 4902 and 5098 (± 98).
        let (l, u) = binomial_rank_interval(10_000, 0.5, 0.95);
        assert!((4900..=4903).contains(&l.unwrap()) && (5097..=5100).contains(&u.unwrap()));
    }
}
