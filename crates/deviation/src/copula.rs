//! The Gaussian copula: dependence between quantities of any marginal law (and the
//! sample rank correlation that checks it, [`sample_spearman`]).
//!
//! A scalar of a non-normal law that the scenario correlates is drawn through its normal
//! score: a standard normal z joins the joint normal of the scenario (correlated with the
//! other columns by the normal-score correlation ρ), and the value is x = F⁻¹(Φ(z))
//! ([`crate::ScalarDistribution::from_normal_score`]). A normal quantity is its own normal
//! score, scaled; for two normals ρ is their ordinary (Pearson) correlation.
//!
//! **Rank correlation.** F⁻¹∘Φ is increasing, so Spearman's ρ_S of two values is that of
//! their normal scores, which for a bivariate normal of correlation ρ is
//! ρ_S = (6/π)·asin(ρ/2) (Pearson 1907; Kruskal 1958, *JASA* 53, Eq. 4.2), inverted as
//! ρ = 2·sin(π·ρ_S/6) ([`normal_score_from_spearman`]). The map is odd, fixes 0 and ±1
//! and moves no value by more than 0.018.
//!
//! **Covariance of the values.** The linearised analyses (screening, RSS contributions)
//! need the covariance of the values themselves. With Z₁, Z₂ standard normals of
//! correlation ρ and f, g square-integrable, Mehler's expansion gives
//! Cov(f(Z₁), g(Z₂)) = Σ_{k≥1} ρᵏ·a_k·b_k, with a_k = E[f(Z)·h_k(Z)] the coefficients on
//! the normalised Hermite polynomials h_k = He_k/√k! (h₀ = 1, h₁ = z,
//! h_{k+1} = (z·h_k − √k·h_{k−1})/√(k+1)); Σ_{k≥1} a_k² = Var f(Z). The coefficients are
//! computed once per copula column by the midpoint rule on [−9, 9] (40,000 nodes; the
//! normal mass outside is 2e-19) and the series is summed to [`HERMITE_TERMS`] terms. For
//! an affine f (a normal column) a₁ = σ and every other coefficient is 0, so a normal
//! partner gives Cov = ρ·σ·b₁ exactly; for smooth laws the terms fall geometrically, for an
//! unsmoothed empirical law (a step function) as k^(−3/4) per jump, so near |ρ| = 1 the
//! truncated sum is a few per cent low there (the figure feeds approximations only).

/// Terms of the Mehler series summed for the covariance of two values.
pub const HERMITE_TERMS: usize = 30;

/// Nodes of the midpoint rule for the Hermite coefficients.
const NODES: usize = 56_000;
/// Half width of the integration interval, in standard deviations.
const REACH: f64 = 14.0;

/// The normal-score correlation ρ = 2·sin(π·ρ_S/6) of a Spearman rank correlation ρ_S
/// (module docs).
pub fn normal_score_from_spearman(spearman: f64) -> f64 {
    2.0 * (std::f64::consts::PI * spearman / 6.0).sin()
}

/// Spearman's rank correlation (6/π)·asin(ρ/2) of two quantities whose normal scores have
/// correlation ρ (module docs).
pub fn spearman_from_normal_score(rho: f64) -> f64 {
    6.0 / std::f64::consts::PI * (0.5 * rho).asin()
}

/// The coefficients a_1 … a_K of f(Z) on the normalised Hermite polynomials (module
/// docs), K = [`HERMITE_TERMS`].
pub fn hermite_coefficients(f: impl Fn(f64) -> f64) -> Vec<f64> {
    let step = 2.0 * REACH / NODES as f64;
    let weight = step / (2.0 * std::f64::consts::PI).sqrt();
    let mut sums = vec![0.0; HERMITE_TERMS + 1];
    let mut h = vec![0.0; HERMITE_TERMS + 1];
    let roots: Vec<f64> = (0..=HERMITE_TERMS + 1).map(|k| (k as f64).sqrt()).collect();
    for i in 0..NODES {
        let z = -REACH + (i as f64 + 0.5) * step;
        let value = f(z) * weight * (-0.5 * z * z).exp();
        h[0] = 1.0;
        h[1] = z;
        for k in 1..HERMITE_TERMS {
            h[k + 1] = (z * h[k] - roots[k] * h[k - 1]) / roots[k + 1];
        }
        for (sum, hk) in sums.iter_mut().zip(&h) {
            *sum += value * hk;
        }
    }
    sums.remove(0);
    sums
}

/// Cov(f(Z₁), g(Z₂)) from the coefficients of f and g and the correlation ρ of Z₁, Z₂
/// (module docs): Σ ρᵏ·a_k·b_k.
pub fn mehler_covariance(a: &[f64], b: &[f64], rho: f64) -> f64 {
    let mut power = 1.0;
    a.iter()
        .zip(b)
        .map(|(ak, bk)| {
            power *= rho;
            power * ak * bk
        })
        .sum()
}

/// Spearman's rank correlation of two samples: the Pearson correlation of their mid-ranks
/// (tied values share the mean of their ranks). NaN when a sample is constant or the two
/// differ in length.
pub fn sample_spearman(x: &[f64], y: &[f64]) -> f64 {
    if x.len() != y.len() {
        return f64::NAN;
    }
    pearson(&mid_ranks(x), &mid_ranks(y))
}

/// Mid-ranks (0-based; ties share the mean of their ranks).
fn mid_ranks(values: &[f64]) -> Vec<f64> {
    let mut order: Vec<usize> = (0..values.len()).collect();
    order.sort_by(|&a, &b| values[a].total_cmp(&values[b]));
    let mut ranks = vec![0.0; values.len()];
    let mut i = 0;
    while i < order.len() {
        let mut j = i;
        while j + 1 < order.len() && values[order[j + 1]] == values[order[i]] {
            j += 1;
        }
        for &k in &order[i..=j] {
            ranks[k] = 0.5 * (i + j) as f64;
        }
        i = j + 1;
    }
    ranks
}

/// Pearson's correlation of two equally long samples.
fn pearson(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (a, b) in x.iter().zip(y) {
        sxy += (a - mx) * (b - my);
        sxx += (a - mx) * (a - mx);
        syy += (b - my) * (b - my);
    }
    sxy / (sxx * syy).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ScalarDistribution;

    #[test]
    fn sample_spearman_uses_mid_ranks() {
        // x = [1, 2, 2, 3] has mid-ranks [0, 1.5, 1.5, 3], y = [1, 3, 2, 4] ranks
        // [0, 2, 1, 3]: deviations (−1.5, 0, 0, 1.5) and (−1.5, 0.5, −0.5, 1.5), so
        // r = 4.5/√(4.5·5) = 0.948683…
        let r = sample_spearman(&[1.0, 2.0, 2.0, 3.0], &[1.0, 3.0, 2.0, 4.0]);
        assert!((r - 4.5 / (22.5f64).sqrt()).abs() < 1e-15, "{r}");
        assert!(sample_spearman(&[1.0, 2.0], &[1.0]).is_nan());
    }

    #[test]
    fn spearman_and_normal_score_correlations_invert_each_other() {
        // The closed form's fixed points (0, ±1) and its round trip.
        assert_eq!(normal_score_from_spearman(0.0), 0.0);
        assert!((normal_score_from_spearman(1.0) - 1.0).abs() < 1e-15);
        assert!((normal_score_from_spearman(-1.0) + 1.0).abs() < 1e-15);
        for rho_s in [-0.9, -0.3, 0.1, 0.5, 0.77] {
            let back = spearman_from_normal_score(normal_score_from_spearman(rho_s));
            assert!((back - rho_s).abs() < 1e-15, "{rho_s}: {back}");
        }
        // ρ_S = 0.5 ↔ ρ = 2·sin(π/12) = 0.517638…
        assert!((normal_score_from_spearman(0.5) - 0.517_638_090_205_041_5).abs() < 1e-15);
    }

    #[test]
    fn mehler_covariance_matches_closed_forms() {
        // Lognormals exp(σa·Z₁), exp(σb·Z₂): Cov = e^((σa² + σb²)/2)·(e^(ρσaσb) − 1).
        let (sa, sb) = (0.4, 0.25);
        let a = hermite_coefficients(|z| (sa * z).exp());
        let b = hermite_coefficients(|z| (sb * z).exp());
        for rho in [-0.95, -0.3, 0.5, 1.0] {
            let exact = (0.5 * (sa * sa + sb * sb)).exp() * (rho * sa * sb).exp_m1();
            let series = mehler_covariance(&a, &b, rho);
            assert!(
                (series - exact).abs() < 1e-12,
                "ρ {rho}: {series} vs {exact}"
            );
        }
        // Uniforms Φ(Z₁), Φ(Z₂): their Pearson correlation is Spearman's,
        // (6/π)·asin(ρ/2), and the variance 1/12.
        let u = hermite_coefficients(crate::scalar::standard_normal_cdf);
        for rho in [-0.8, 0.2, 0.6, 0.9] {
            let correlation = 12.0 * mehler_covariance(&u, &u, rho);
            let exact = spearman_from_normal_score(rho);
            assert!((correlation - exact).abs() < 1e-9, "ρ {rho}: {correlation}");
        }
        // An affine f has a₁ = σ and nothing else.
        let affine = hermite_coefficients(|z| 3.0 + 2.0 * z);
        assert!((affine[0] - 2.0).abs() < 1e-12);
        assert!(affine[1..].iter().all(|a| a.abs() < 1e-10), "{affine:?}");
        // Σ a_k² is the variance: a Rayleigh law through its normal score.
        let rayleigh = ScalarDistribution::Rayleigh { sigma: 1.5 };
        let r = hermite_coefficients(|z| rayleigh.from_normal_score(z));
        let variance: f64 = r.iter().map(|a| a * a).sum();
        assert!(
            (variance / rayleigh.variance() - 1.0).abs() < 1e-6,
            "{variance} vs {}",
            rayleigh.variance()
        );
    }
    use crate::{EmpiricalLaw, InputSpace, InputSpaceBuilder};
    use rand::SeedableRng;

    /// Two columns of `n` rows of a two-column space.
    fn draw(space: &InputSpace, n: usize, seed: u64) -> (Vec<f64>, Vec<f64>) {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let mut rows = vec![0.0; 2 * n];
        let mut counts = space.new_constraint_counts();
        space.sample_rows(&mut rng, &mut rows, &mut counts).unwrap();
        rows.chunks_exact(2).map(|r| (r[0], r[1])).unzip()
    }

    fn pair(a: ScalarDistribution, b: ScalarDistribution, rho: f64) -> InputSpace {
        let mut builder = InputSpaceBuilder::new();
        let (ca, cb) = (
            builder.add_scalar("variables[0]", a),
            builder.add_scalar("variables[1]", b),
        );
        builder.correlate("correlations[0]", ca, cb, rho).unwrap();
        builder.build("correlations").unwrap()
    }

    /// Sample Spearman correlation of n = 200 000 rows against its target: the Fisher
    /// transform atanh(r_S) has standard error √(1.06/(n − 3)) for a bivariate normal
    /// (Fieller, Hartley & Pearson 1957, *Biometrika* 44), which is the rank law of every
    /// Gaussian copula; bound 4 standard errors. The mid-rank ties of an empirical law of
    /// m equally likely values lower r_S by a factor about √(1 − 1/m²), 2e-7 for m = 1500.
    fn assert_spearman(space: &InputSpace, target: f64, seed: u64) {
        let n = 200_000;
        let (x, y) = draw(space, n, seed);
        let r = sample_spearman(&x, &y);
        let se = (1.06 / (n as f64 - 3.0)).sqrt();
        assert!(
            (r.atanh() - target.atanh()).abs() < 4.0 * se,
            "Spearman {r} against {target} (4 SE = {})",
            4.0 * se
        );
    }

    #[test]
    fn the_copula_reproduces_a_target_spearman_correlation() {
        // Normal × Rayleigh (a pitch error and a runout of one grinding set-up).
        let normal = ScalarDistribution::Normal {
            mean: 0.0,
            sd: 0.004,
        };
        let rayleigh = ScalarDistribution::Rayleigh { sigma: 0.003 };
        for (target, seed) in [(0.6, 1), (-0.35, 2)] {
            let space = pair(
                normal.clone(),
                rayleigh.clone(),
                normal_score_from_spearman(target),
            );
            assert_spearman(&space, target, seed);
        }
        // Empirical (1500 measured values, plain resampling) × uniform.
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        let measured: Vec<f64> = (0..1500)
            .map(|_| crate::Ziggurat::get().sample(&mut rng).powi(3))
            .collect();
        let empirical =
            ScalarDistribution::Empirical(EmpiricalLaw::new("v", &measured, 0.0).unwrap());
        let uniform = ScalarDistribution::Uniform {
            lower: -1.0,
            upper: 2.0,
        };
        let target = 0.45;
        let space = pair(empirical, uniform, normal_score_from_spearman(target));
        assert_spearman(&space, target, 3);
    }

    #[test]
    fn copula_columns_keep_their_marginals_and_covariance() {
        // Rayleigh × normal at ρ = 0.7: the Rayleigh column's mean σ√(π/2) and variance
        // (4 − π)/2·σ² hold (5 SE; the variance's SE from the fourth moment), and the
        // sample covariance matches InputSpace::covariance (exact Mehler series with a
        // normal partner) within 5 SE of the product's mean.
        let rayleigh = ScalarDistribution::Rayleigh { sigma: 2.0 };
        let normal = ScalarDistribution::Normal { mean: 1.0, sd: 3.0 };
        let space = pair(rayleigh.clone(), normal, 0.7);
        let n = 200_000;
        let (x, y) = draw(&space, n, 4);
        let nf = n as f64;
        let mean = x.iter().sum::<f64>() / nf;
        let var = x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (nf - 1.0);
        let m4 = x.iter().map(|v| (v - mean).powi(4)).sum::<f64>() / nf;
        assert!(
            (mean - rayleigh.mean()).abs() < 5.0 * (var / nf).sqrt(),
            "{mean}"
        );
        assert!(
            (var - rayleigh.variance()).abs() < 5.0 * ((m4 - var * var) / nf).sqrt(),
            "{var}"
        );
        assert_eq!(space.covariance(0, 0), rayleigh.variance());
        let my = y.iter().sum::<f64>() / nf;
        let products: Vec<f64> = x
            .iter()
            .zip(&y)
            .map(|(a, b)| (a - mean) * (b - my))
            .collect();
        let cov = products.iter().sum::<f64>() / nf;
        let spread = products.iter().map(|p| (p - cov).powi(2)).sum::<f64>() / nf;
        let expected = space.covariance(0, 1);
        assert!(expected > 0.0 && expected == space.covariance(1, 0));
        assert!(
            (cov - expected).abs() < 5.0 * (spread / nf).sqrt(),
            "{cov} vs {expected}"
        );
        assert!(space.dependent(0, 1) && !space.dependent(0, 0));
        assert_eq!(space.copula_columns().len(), 1);
        assert_eq!(space.mean_row(), vec![rayleigh.mean(), 1.0]);
    }

    #[test]
    fn conditional_draws_of_a_copula_column_follow_its_conditional_law() {
        // U = Φ(Z₂) uniform on (0, 1), Z₂ correlated ρ with the normal X = Z₁: given
        // Z₁ = z, Z₂ ~ N(ρz, 1 − ρ²), so E[U | z] = Φ(ρz/√(2 − ρ²)) (E[Φ(N(m, s²))] =
        // Φ(m/√(1 + s²))). 100 000 draws at z = 1.2; 5 SE.
        let rho = 0.8;
        let space = pair(
            ScalarDistribution::Normal { mean: 0.0, sd: 1.0 },
            ScalarDistribution::Uniform {
                lower: 0.0,
                upper: 1.0,
            },
            rho,
        );
        let sampler = space.conditional_sampler(&[1]).unwrap();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(6);
        let (n, given, mut z) = (100_000, 1.2, Vec::new());
        let draws: Vec<f64> = (0..n)
            .map(|_| {
                let mut row = [given, 0.0];
                sampler.sample(&mut rng, &mut row, &mut z);
                space.latent_to_values(&mut row);
                row[1]
            })
            .collect();
        let mean = draws.iter().sum::<f64>() / n as f64;
        let var = draws.iter().map(|u| (u - mean).powi(2)).sum::<f64>() / (n as f64 - 1.0);
        let exact = crate::scalar::standard_normal_cdf(rho * given / (2.0 - rho * rho).sqrt());
        assert!(
            (mean - exact).abs() < 5.0 * (var / n as f64).sqrt(),
            "{mean} vs {exact}"
        );
    }

    #[test]
    fn quasi_random_rows_transform_copula_columns_too() {
        // Scrambled Sobol' rows of a Rayleigh × normal copula: the Rayleigh column's mean
        // within 1e-3 relative of σ√(π/2) at 4096 points (the RQMC error is far smaller
        // than the Monte Carlo standard error of 0.8 %), every value ≥ 0.
        let rayleigh = ScalarDistribution::Rayleigh { sigma: 1.0 };
        let space = pair(
            rayleigh.clone(),
            ScalarDistribution::Normal { mean: 0.0, sd: 1.0 },
            0.5,
        );
        let n = 4096;
        let points = crate::PointSet::new(
            crate::SamplingMethod::Rqmc,
            space.quasi_dimensions().unwrap(),
            n,
            7,
        )
        .unwrap();
        let mut columns = vec![0.0; 2 * n as usize];
        let mut scratch = crate::SamplerScratch::default();
        space
            .sample_columns_from_points(&points, 0, 0, &mut columns, &mut scratch)
            .unwrap();
        let values = &columns[..n as usize];
        assert!(values.iter().all(|&r| r >= 0.0));
        let mean = values.iter().sum::<f64>() / n as f64;
        assert!((mean / rayleigh.mean() - 1.0).abs() < 1e-3, "{mean}");
    }

    #[test]
    fn from_normal_score_is_the_inverse_cdf_at_phi_and_stays_finite_in_the_tails() {
        let laws = [
            ScalarDistribution::Uniform {
                lower: -1.0,
                upper: 3.0,
            },
            ScalarDistribution::Triangular {
                lower: 0.0,
                mode: 0.3,
                upper: 1.0,
            },
            ScalarDistribution::TruncatedNormal {
                mean: 0.0,
                sd: 1.0,
                lower: -0.5,
                upper: 2.0,
            },
            ScalarDistribution::Rayleigh { sigma: 0.5 },
            ScalarDistribution::FoldedNormal { mean: 0.0, sd: 2.0 },
            ScalarDistribution::FoldedNormal { mean: 1.0, sd: 2.0 },
            ScalarDistribution::Lognormal {
                mu: 0.1,
                sigma: 0.3,
            },
        ];
        for law in &laws {
            let mut previous = f64::NEG_INFINITY;
            for i in -80..=80 {
                let z = i as f64 / 10.0;
                let x = law.from_normal_score(z);
                assert!(
                    x.is_finite() && x >= previous,
                    "{law:?} at {z}: {x} after {previous}"
                );
                previous = x;
                // In the bulk, the inverse CDF at Φ(z): the closed forms of from_uniform.
                if z.abs() <= 3.0 {
                    // The folded normal's reference inverts a CDF built from statrs' erfc,
                    // whose error (about 1e-11 here) sets the tolerance.
                    let (reference, tolerance) = match law {
                        ScalarDistribution::FoldedNormal { mean, sd } => (
                            folded_reference(*mean, *sd, crate::scalar::standard_normal_cdf(z)),
                            1e-9,
                        ),
                        ScalarDistribution::Lognormal { .. } => (x, 0.0),
                        _ => (
                            law.from_uniform(crate::scalar::standard_normal_cdf(z)),
                            1e-12,
                        ),
                    };
                    assert!(
                        (x - reference).abs() <= tolerance * (1.0 + x.abs()),
                        "{law:?} {z}: {x} vs {reference}"
                    );
                }
            }
        }
        // Far in the upper tail the Rayleigh value is σ√(−2 ln Q(z)), Q(8) = 6.22e-16.
        let rayleigh = ScalarDistribution::Rayleigh { sigma: 1.0 };
        assert!((rayleigh.from_normal_score(8.0) - 8.368_206_159).abs() < 1e-6);
    }

    /// The p quantile of |N(μ, σ²)| by bisection on its CDF Φ((x − μ)/σ) − Φ((−x − μ)/σ).
    fn folded_reference(mean: f64, sd: f64, p: f64) -> f64 {
        let cdf = |x: f64| {
            crate::scalar::standard_normal_cdf((x - mean) / sd)
                - crate::scalar::standard_normal_cdf((-x - mean) / sd)
        };
        let (mut low, mut high) = (0.0, mean.abs() + 20.0 * sd);
        for _ in 0..200 {
            let middle = 0.5 * (low + high);
            if cdf(middle) < p {
                low = middle;
            } else {
                high = middle;
            }
        }
        0.5 * (low + high)
    }
}
