//! Process-capability indices and the out-of-specification fraction.
//!
//! * Moment method: Cp = (U − L) / (6σ), Cpk = min(Cpu, Cpl) with
//!   Cpu = (U − μ) / (3σ) and Cpl = (μ − L) / (3σ) (Montgomery,
//!   "Introduction to Statistical Quality Control", ch. 8; ISO 22514-2).
//! * Percentile method (Clements 1989, "Process capability calculations for
//!   non-normal distributions", Quality Progress 22(9); ISO 22514-2:2017
//!   method with quantiles): Cp = (U − L) / (P99.865 − P0.135),
//!   Cpu = (U − P50) / (P99.865 − P50), Cpl = (P50 − L) / (P50 − P0.135).
//! * Out-of-spec fraction: Clopper & Pearson (1934), "The use of confidence
//!   or fiducial limits illustrated in the case of the binomial",
//!   Biometrika 26(4): the exact two-sided interval
//!   [B(α/2; k, n − k + 1), B(1 − α/2; k + 1, n − k)] with B the Beta
//!   quantile function. The Beta quantile is found by bisection on the
//!   regularized incomplete beta function I_x(a, b), evaluated with the
//!   continued fraction of Numerical Recipes (Press et al., 3rd ed., §6.4,
//!   modified Lentz method) and `statrs` log-gamma. (statrs 0.18's own
//!   `Beta::inverse_cdf` does not terminate for shape parameters around
//!   10^9, and its `beta_reg` stops after 140 terms, which is inaccurate
//!   when both shapes are large; sample counts here reach 10^9.)
//!
//! An index needs a positive, finite spread: with σ = 0 (or coinciding percentiles) the
//! ratio has no meaningful value, so the index is `None` (reported as n/a with the
//! reason), never ±inf or NaN. A Cp needs both limits, a Cpk at least one.

use statrs::function::gamma::ln_gamma;

/// Specification limits; either may be absent (one-sided specification).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpecLimits {
    /// Lower specification limit L, if any.
    pub lower: Option<f64>,
    /// Upper specification limit U, if any.
    pub upper: Option<f64>,
}

/// Capability indices; `None` where an index is undefined (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MomentCapability {
    /// Cp, only when both limits are set and the spread is positive.
    pub cp: Option<f64>,
    /// Cpk: the minimum of Cpu and Cpl over the limits that are set (Cpu or Cpl alone for
    /// a one-sided specification), when at least one is set and the spread is positive.
    pub cpk: Option<f64>,
}

/// Estimated fraction with an exact confidence interval.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProportionEstimate {
    /// Point estimate k / n (0 when n = 0).
    pub fraction: f64,
    /// Lower confidence limit.
    pub lower: f64,
    /// Upper confidence limit.
    pub upper: f64,
}

impl ProportionEstimate {
    /// The estimate in parts per million: (fraction, lower, upper) · 10^6.
    pub fn to_ppm(&self) -> (f64, f64, f64) {
        (self.fraction * 1e6, self.lower * 1e6, self.upper * 1e6)
    }
}

/// `numerator / denominator` when the denominator (a spread) is positive and the ratio
/// finite; `None` otherwise (module docs).
fn index_ratio(numerator: f64, denominator: f64) -> Option<f64> {
    let ratio = numerator / denominator;
    (denominator > 0.0 && ratio.is_finite()).then_some(ratio)
}

/// Shared Cp / Cpk assembly: `upper_side(U)` and `lower_side(L)` give Cpu and
/// Cpl, `spread` is the full-width denominator of Cp.
fn assemble(
    limits: SpecLimits,
    spread: f64,
    upper_side: impl Fn(f64) -> Option<f64>,
    lower_side: impl Fn(f64) -> Option<f64>,
) -> MomentCapability {
    let cp = match (limits.lower, limits.upper) {
        (Some(lower), Some(upper)) => index_ratio(upper - lower, spread),
        _ => None,
    };
    let cpu = limits.upper.map(upper_side);
    let cpl = limits.lower.map(lower_side);
    // Any side set but undefined makes the whole Cpk undefined.
    let cpk = match (cpu, cpl) {
        (None, None) => None,
        (Some(u), None) => u,
        (None, Some(l)) => l,
        (Some(u), Some(l)) => u.zip(l).map(|(u, l)| u.min(l)),
    };
    MomentCapability { cp, cpk }
}

/// Moment-method capability from the mean μ and standard deviation σ:
/// Cp = (U − L) / (6σ) (both limits only), Cpk = min((U − μ) / (3σ),
/// (μ − L) / (3σ)) over the limits that are set.
///
/// σ = 0 (or negative or NaN): no index (`None`).
pub fn capability_from_moments(mean: f64, sd: f64, limits: SpecLimits) -> MomentCapability {
    assemble(
        limits,
        6.0 * sd,
        |upper| index_ratio(upper - mean, 3.0 * sd),
        |lower| index_ratio(mean - lower, 3.0 * sd),
    )
}

/// Percentile-method capability (ISO 22514-2 / Clements 1989) from the
/// 0.135 %, 50 % and 99.865 % percentiles:
/// Cp = (U − L) / (P99.865 − P0.135) (both limits only),
/// Cpk = min((U − P50) / (P99.865 − P50), (P50 − L) / (P50 − P0.135)) over
/// the limits that are set. A zero-width denominator gives no index, as in
/// [`capability_from_moments`].
pub fn capability_percentile_method(
    p00135: f64,
    p50: f64,
    p99865: f64,
    limits: SpecLimits,
) -> MomentCapability {
    assemble(
        limits,
        p99865 - p00135,
        |upper| index_ratio(upper - p50, p99865 - p50),
        |lower| index_ratio(p50 - lower, p50 - p00135),
    )
}

/// Whether Cpk = min(Cpu, Cpl) is taken on the upper side (the mean nearer U, or U alone).
pub fn cpk_on_upper_side(mean: f64, limits: SpecLimits) -> bool {
    match (limits.lower, limits.upper) {
        (Some(l), Some(u)) => u - mean <= mean - l,
        (None, Some(_)) => true,
        _ => false,
    }
}

/// Standard error of the moment-method Cpk by the delta method on Cpk = ±(limit − μ)/(3σ),
/// with Var(μ̂) = σ²/n, Var(s) = σ²(κ + 2)/(4n) and Cov(μ̂, s) = γ1·σ²/(2n) (κ the excess
/// kurtosis, γ1 the skewness): Var = 1/(9n) + Cpk²(κ + 2)/(4n) ± Cpk·γ1/(3n), + on the
/// upper side. For a normal output (κ = γ1 = 0) this is Bissell's (1990) 1/(9n) +
/// Cpk²/(2n). The variance is kept at or above 1/(9n), the mean's share alone.
pub fn cpk_standard_error(
    cpk: f64,
    upper_side: bool,
    n: u64,
    skewness: f64,
    excess_kurtosis: f64,
) -> f64 {
    let nf = n as f64;
    let sign = if upper_side { 1.0 } else { -1.0 };
    let variance = 1.0 / (9.0 * nf)
        + cpk * cpk * (excess_kurtosis + 2.0).max(0.0) / (4.0 * nf)
        + sign * cpk * skewness / (3.0 * nf);
    variance.max(1.0 / (9.0 * nf)).sqrt()
}

/// Clopper–Pearson exact two-sided interval for the out-of-spec fraction,
/// from `n_out` out-of-spec samples among `n`, at `confidence` (e.g. 0.95).
///
/// lower = 0 when `n_out` = 0, upper = 1 when `n_out` = n. Edge cases never
/// panic: n = 0 gives fraction 0 and the interval [0, 1]; `n_out` > n is
/// treated as n; `confidence` is clamped into [0, 1] and NaN means 0.95.
pub fn out_of_spec_interval(n_out: u64, n: u64, confidence: f64) -> ProportionEstimate {
    if n == 0 {
        return ProportionEstimate {
            fraction: 0.0,
            lower: 0.0,
            upper: 1.0,
        };
    }
    let n_out = n_out.min(n);
    let confidence = if confidence.is_nan() {
        0.95
    } else {
        confidence.clamp(0.0, 1.0)
    };
    let tail = (1.0 - confidence) / 2.0;
    let successes = n_out as f64;
    let failures = (n - n_out) as f64;
    let fraction = successes / n as f64;
    let lower = if n_out == 0 {
        0.0
    } else {
        beta_quantile(successes, failures + 1.0, tail)
    };
    let upper = if n_out == n {
        1.0
    } else {
        beta_quantile(successes + 1.0, failures, 1.0 - tail)
    };
    ProportionEstimate {
        fraction,
        lower: lower.min(fraction),
        upper: upper.max(fraction),
    }
}

/// Largest number of continued-fraction terms; convergence needs about
/// sqrt(max(a, b)) terms, i.e. a few 10^4 for a and b near 10^9.
const MAX_CONTINUED_FRACTION_TERMS: u32 = 1_000_000;

/// Continued fraction for I_x(a, b) (Numerical Recipes §6.4, `betacf`),
/// modified Lentz evaluation. Converges fast for x < (a + 1) / (a + b + 2).
fn incomplete_beta_continued_fraction(a: f64, b: f64, x: f64) -> f64 {
    let tiny = f64::MIN_POSITIVE / f64::EPSILON;
    let guard = |value: f64| if value.abs() < tiny { tiny } else { value };
    let sum = a + b;
    let mut c = 1.0;
    let mut d = 1.0 / guard(1.0 - sum * x / (a + 1.0));
    let mut result = d;
    for term in 1..=MAX_CONTINUED_FRACTION_TERMS {
        let m = f64::from(term);
        let two_m = 2.0 * m;
        let even = m * (b - m) * x / ((a - 1.0 + two_m) * (a + two_m));
        d = 1.0 / guard(1.0 + even * d);
        c = guard(1.0 + even / c);
        result *= d * c;
        let odd = -(a + m) * (sum + m) * x / ((a + two_m) * (a + 1.0 + two_m));
        d = 1.0 / guard(1.0 + odd * d);
        c = guard(1.0 + odd / c);
        let step = d * c;
        result *= step;
        if (step - 1.0).abs() <= 1e-15 {
            break;
        }
    }
    result
}

/// Stirling-series remainder ln Γ(z) − [(z − ½)·ln z − z + ½·ln 2π]
/// (Abramowitz & Stegun 6.1.41), truncation error below 1e-12 for z ≥ 10.
fn stirling_remainder(z: f64) -> f64 {
    let inverse = 1.0 / z;
    let inverse_squared = inverse * inverse;
    inverse
        * (1.0 / 12.0
            - inverse_squared
                * (1.0 / 360.0 - inverse_squared * (1.0 / 1260.0 - inverse_squared / 1680.0)))
}

/// ln B(a, b) = ln Γ(a) + ln Γ(b) − ln Γ(a + b). When the larger argument
/// is ≥ 10, ln Γ(large + small) − ln Γ(large) is taken from the Stirling
/// series as a difference (no cancellation between two ~10^10 log-gammas
/// when n ~ 10^9); otherwise plain log-gammas.
fn ln_beta_function(a: f64, b: f64) -> f64 {
    let (small, large) = if a <= b { (a, b) } else { (b, a) };
    if large < 10.0 {
        return ln_gamma(a) + ln_gamma(b) - ln_gamma(a + b);
    }
    let log_gamma_difference =
        (large - 0.5) * (small / large).ln_1p() + small * (large + small).ln() - small
            + (stirling_remainder(large + small) - stirling_remainder(large));
    ln_gamma(small) - log_gamma_difference
}

/// Regularized incomplete beta function I_x(a, b) for a, b > 0, the CDF of
/// the Beta(a, b) distribution at x (Numerical Recipes §6.4, `betai`).
fn regularized_incomplete_beta(a: f64, b: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    let log_prefactor = a * x.ln() + b * (-x).ln_1p() - ln_beta_function(a, b);
    let prefactor = log_prefactor.exp();
    let value = if x < (a + 1.0) / (a + b + 2.0) {
        prefactor * incomplete_beta_continued_fraction(a, b, x) / a
    } else {
        1.0 - prefactor * incomplete_beta_continued_fraction(b, a, 1.0 - x) / b
    };
    value.clamp(0.0, 1.0)
}

/// Quantile of Beta(a, b) at `probability`, by bisection on
/// [`regularized_incomplete_beta`] to a relative precision of 1e-14.
fn beta_quantile(a: f64, b: f64, probability: f64) -> f64 {
    if probability.is_nan() || probability <= 0.0 {
        return 0.0;
    }
    if probability >= 1.0 {
        return 1.0;
    }
    let (mut low, mut high) = (0.0_f64, 1.0_f64);
    // At most ~1100 halvings reach the smallest subnormal; the relative
    // stopping rule ends far earlier (about log2(1/x) + 47 steps).
    for _ in 0..1100 {
        let middle = 0.5 * (low + high);
        if high - low <= 1e-14 * high || middle <= low || middle >= high {
            break;
        }
        if regularized_incomplete_beta(a, b, middle) < probability {
            low = middle;
        } else {
            high = middle;
        }
    }
    0.5 * (low + high)
}

#[cfg(test)]
mod tests {
    use super::*;

    const BOTH: SpecLimits = SpecLimits {
        lower: Some(-3.0),
        upper: Some(3.0),
    };

    fn close(a: f64, b: f64, tolerance: f64) -> bool {
        (a - b).abs() <= tolerance
    }

    #[test]
    fn moment_method_easy_cases() {
        // Centred, σ = 1, limits ±3: Cp = 6/6 = 1, Cpk = 3/3 = 1.
        let centred = capability_from_moments(0.0, 1.0, BOTH);
        assert_eq!(centred.cp, Some(1.0));
        assert_eq!(centred.cpk, Some(1.0));
        // Mean 1, σ = 0.5: Cp = 6/3 = 2, Cpu = 2/1.5 = 1.333..., Cpl = 4/1.5.
        let shifted = capability_from_moments(1.0, 0.5, BOTH);
        assert_eq!(shifted.cp, Some(2.0));
        assert!(close(shifted.cpk.unwrap(), 4.0 / 3.0, 1e-15));
        // Mean outside: Cpk negative, (3 − 4)/3 = −1/3.
        let outside = capability_from_moments(4.0, 1.0, BOTH);
        assert!(close(outside.cpk.unwrap(), -1.0 / 3.0, 1e-15));
    }

    #[test]
    fn moment_method_one_sided() {
        let upper_only = SpecLimits {
            lower: None,
            upper: Some(10.0),
        };
        let result = capability_from_moments(4.0, 2.0, upper_only);
        assert_eq!(result.cp, None);
        assert_eq!(result.cpk, Some(1.0)); // (10 − 4)/(3·2)
        let lower_only = SpecLimits {
            lower: Some(1.0),
            upper: None,
        };
        let result = capability_from_moments(4.0, 2.0, lower_only);
        assert_eq!(result.cp, None);
        assert_eq!(result.cpk, Some(0.5)); // (4 − 1)/(3·2)
        let none = SpecLimits {
            lower: None,
            upper: None,
        };
        let result = capability_from_moments(4.0, 2.0, none);
        assert_eq!(result.cp, None);
        assert_eq!(result.cpk, None);
    }

    #[test]
    fn zero_spread_gives_no_index_never_inf_or_nan() {
        let none = MomentCapability {
            cp: None,
            cpk: None,
        };
        for mean in [1.0, 5.0, 3.0] {
            assert_eq!(capability_from_moments(mean, 0.0, BOTH), none);
        }
        assert_eq!(capability_from_moments(1.0, f64::NAN, BOTH), none);
        assert_eq!(capability_percentile_method(2.0, 2.0, 2.0, BOTH), none);
        // A spread so small that the ratio overflows is no index either.
        assert_eq!(capability_from_moments(1.0, 1e-320, BOTH), none);
        // One side of zero width (P50 = P99.865) leaves Cpk undefined, Cp defined.
        let one_side = capability_percentile_method(-1.0, 2.0, 2.0, BOTH);
        assert_eq!(one_side.cp, Some(2.0));
        assert_eq!(one_side.cpk, None);
    }

    #[test]
    fn percentile_method() {
        // Normal(0, 1): P0.135 = −3, P50 = 0, P99.865 = 3 (the 3σ points), so
        // the percentile method reproduces the moment method: Cp = Cpk = 1.
        let normal = capability_percentile_method(-3.0, 0.0, 3.0, BOTH);
        assert_eq!(normal.cp, Some(1.0));
        assert_eq!(normal.cpk, Some(1.0));
        // Skewed: P0.135 = −1, P50 = 0, P99.865 = 4, limits ±3:
        // Cp = 6/5, Cpu = 3/4, Cpl = 3/1 → Cpk = 0.75.
        let skewed = capability_percentile_method(-1.0, 0.0, 4.0, BOTH);
        assert_eq!(skewed.cp, Some(1.2));
        assert_eq!(skewed.cpk, Some(0.75));
    }

    #[test]
    fn clopper_pearson_known_values() {
        // 0 of 100 at 95 %: upper = 1 − 0.025^(1/100) = 0.0362167 (closed
        // form for k = 0; also R binom.test(0, 100)$conf.int).
        let none = out_of_spec_interval(0, 100, 0.95);
        assert_eq!(none.fraction, 0.0);
        assert_eq!(none.lower, 0.0);
        assert!(close(none.upper, 1.0 - 0.025f64.powf(0.01), 1e-9));
        assert!(close(none.upper, 0.036_216_7, 1e-7));
        // 5 of 100 at 95 %: R binom.test(5, 100)$conf.int =
        // [0.01643188, 0.11283491].
        let five = out_of_spec_interval(5, 100, 0.95);
        assert_eq!(five.fraction, 0.05);
        assert!(close(five.lower, 0.016_431_88, 1e-7));
        assert!(close(five.upper, 0.112_834_91, 1e-7));
        // All out of spec: mirror of the k = 0 case, lower = 0.025^(1/100).
        let all = out_of_spec_interval(100, 100, 0.95);
        assert_eq!(all.upper, 1.0);
        assert!(close(all.lower, 0.025f64.powf(0.01), 1e-9));
        let (ppm, lower_ppm, upper_ppm) = five.to_ppm();
        assert!(close(ppm, 50_000.0, 1e-6));
        assert!(lower_ppm < ppm && ppm < upper_ppm);
    }

    #[test]
    fn clopper_pearson_edge_cases() {
        let empty = out_of_spec_interval(0, 0, 0.95);
        assert_eq!((empty.fraction, empty.lower, empty.upper), (0.0, 0.0, 1.0));
        let too_many = out_of_spec_interval(7, 5, 0.95);
        assert_eq!(too_many.fraction, 1.0);
        assert_eq!(too_many.upper, 1.0);
        for confidence in [f64::NAN, -1.0, 0.0, 1.0, 2.0] {
            let estimate = out_of_spec_interval(3, 1000, confidence);
            assert!(estimate.lower <= estimate.fraction && estimate.fraction <= estimate.upper);
            assert!(estimate.lower >= 0.0 && estimate.upper <= 1.0);
        }
        // Large n: 0 of 10^9 at 95 %: upper ≈ −ln(0.025)/n = 3.689e-9.
        let large = out_of_spec_interval(0, 1_000_000_000, 0.95);
        assert!(close(large.upper, -(0.025f64.ln()) / 1e9, 1e-13));
        let large_some = out_of_spec_interval(12, 1_000_000_000, 0.95);
        assert!(large_some.lower < 12e-9 && 12e-9 < large_some.upper);
        // Half out of 10^6: symmetric interval around 0.5, half-width close to
        // the normal approximation 1.959964·sqrt(0.25/10^6) = 9.79982e-4
        // (Clopper–Pearson is slightly wider).
        let half = out_of_spec_interval(500_000, 1_000_000, 0.95);
        assert!(close(0.5 - half.lower, half.upper - 0.5, 1e-9));
        assert!(close(half.upper - 0.5, 9.79982e-4, 2e-6));
    }

    #[test]
    fn incomplete_beta_closed_forms() {
        // I_x(1, b) = 1 − (1 − x)^b and I_x(a, 1) = x^a (Abramowitz & Stegun
        // 26.5.x special cases; direct integration of the Beta density).
        for (b, x) in [(1.0, 0.3_f64), (10.0, 0.05), (1e9, 3e-9), (2.5, 0.9)] {
            let expected = -(b * (-x).ln_1p()).exp_m1();
            let got = regularized_incomplete_beta(1.0, b, x);
            assert!(
                close(got, expected, 1e-9 * expected),
                "{b} {x}: {got} {expected}"
            );
        }
        for (a, x) in [(3.0, 0.5_f64), (7.5, 0.99)] {
            assert!(close(
                regularized_incomplete_beta(a, 1.0, x),
                x.powf(a),
                1e-12
            ));
        }
        // ln B(a, b) against direct log-gammas where those are accurate, and
        // ln B(1, b) = −ln b exactly (B(1, b) = 1/b).
        for (a, b) in [(3.0, 12.0), (0.5, 40.0), (25.0, 30.0), (2.0, 9.0)] {
            let direct = ln_gamma(a) + ln_gamma(b) - ln_gamma(a + b);
            assert!(close(ln_beta_function(a, b), direct, 1e-11), "{a} {b}");
        }
        assert!(close(ln_beta_function(1.0, 1e9), -(1e9f64.ln()), 1e-12));
        // Symmetry I_0.5(a, a) = 0.5 even for large a.
        for a in [2.0, 1e3, 5e5, 5e8] {
            assert!(
                close(regularized_incomplete_beta(a, a, 0.5), 0.5, 1e-6),
                "{a}"
            );
        }
    }
}
