//! Statistical tests of the joint sampler (rvtol-deviation) over 1e6 draws: sample mean and
//! covariance against the specification, Mahalanobis distances against χ² with rank-many
//! degrees of freedom, exact zeros of zero-variance components, the 001 tolerance-band
//! example (validation.md) and the Eq. 11 constraint. Bounds follow the precision policy
//! of the crate (tests/lib.rs).

use nalgebra::{DMatrix, DVector, SymmetricEigen};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rvtol_deviation::{InputSpace, InputSpaceBuilder, PartSpec, ScalarDistribution};
use rvtol_tests::{ks_statistic, KS_CRITICAL_0_001, SIGMA_BOUND};
use statrs::distribution::{ChiSquared, ContinuousCDF};

const N: usize = 1_000_000;

fn draw(space: &InputSpace, seed: u64) -> Vec<f64> {
    let mut rows = vec![0.0; N * space.n_columns()];
    let mut counts = space.new_constraint_counts();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    space.sample_rows(&mut rng, &mut rows, &mut counts).unwrap();
    rows
}

/// A correlated, singular input space: a part with a full covariance (D·R·D, R_ij = 0.5^|i−j|),
/// a tolerance-band part (two zero variances, 001 Eq. 12), two normal scalars, a
/// tolerance-band scalar, and cross-correlations between the parts and a scalar.
fn correlated_space() -> InputSpace {
    let sd = [0.01, 0.008, 0.005, 1e-4, 2e-4, 5e-5];
    let covariance: [[f64; 6]; 6] = std::array::from_fn(|i| {
        std::array::from_fn(|j| sd[i] * sd[j] * 0.5f64.powi((i as i32 - j as i32).abs()))
    });
    let mean = [0.001, -0.002, 0.0005, 1e-4, -2e-4, 3e-5];
    let housing = PartSpec::from_covariance("parts[0]", mean, covariance).unwrap();
    let shaft = PartSpec::from_tolerance_band("parts[1]", 0.01, 120.0, false).unwrap();
    let mut builder = InputSpaceBuilder::new();
    let housing_col = builder.add_part("parts[0]", &housing);
    let shaft_col = builder.add_part("parts[1]", &shaft);
    let a = builder.add_scalar(
        "variables[0]",
        ScalarDistribution::Normal { mean: 2.0, sd: 0.5 },
    );
    let b_col = builder.add_scalar(
        "variables[1]",
        ScalarDistribution::Normal {
            mean: -1.0,
            sd: 0.2,
        },
    );
    let c = builder.add_scalar(
        "variables[2]",
        ScalarDistribution::ToleranceBand {
            lower: -0.01,
            upper: 0.03,
            cp: 1.33,
            mean_shift: 0.002,
        },
    );
    builder.correlate("correlations[0]", a, b_col, 0.6).unwrap();
    builder
        .correlate("correlations[1]", housing_col, shaft_col, 0.3)
        .unwrap();
    builder
        .correlate("correlations[2]", shaft_col + 4, c, -0.4)
        .unwrap();
    builder
        .correlate("correlations[3]", housing_col + 3, a, 0.2)
        .unwrap();
    builder.build("correlations").unwrap()
}

#[test]
fn sample_mean_and_covariance_match_the_specification() {
    let space = correlated_space();
    let rows = draw(&space, 11);
    let (columns, mean, cov) = space.gaussian_specification();
    let k = columns.len();
    let n_cols = space.n_columns();
    let nf = N as f64;
    let mut sample_mean = vec![0.0; k];
    for row in rows.chunks_exact(n_cols) {
        for (i, &c) in columns.iter().enumerate() {
            sample_mean[i] += row[c];
        }
    }
    for m in &mut sample_mean {
        *m /= nf;
    }
    let mut sample_cov = DMatrix::<f64>::zeros(k, k);
    for row in rows.chunks_exact(n_cols) {
        for i in 0..k {
            let di = row[columns[i]] - sample_mean[i];
            for j in i..k {
                sample_cov[(i, j)] += di * (row[columns[j]] - sample_mean[j]);
            }
        }
    }
    for i in 0..k {
        // Mean: standard error σ_i/√n.
        let se_mean = (cov[(i, i)] / nf).sqrt();
        assert!(
            (sample_mean[i] - mean[i]).abs() <= SIGMA_BOUND * se_mean + 1e-18,
            "mean {i}: {} vs {}",
            sample_mean[i],
            mean[i]
        );
        for j in i..k {
            let s = sample_cov[(i, j)] / (nf - 1.0);
            // Sample covariance of normal data: Var(s_ij) = (Σ_ii·Σ_jj + Σ_ij²)/(n−1).
            let se = ((cov[(i, i)] * cov[(j, j)] + cov[(i, j)].powi(2)) / (nf - 1.0)).sqrt();
            assert!(
                (s - cov[(i, j)]).abs() <= SIGMA_BOUND * se + 1e-24,
                "cov ({i},{j}): {s:e} vs {:e} (se {se:e})",
                cov[(i, j)]
            );
        }
    }
}

#[test]
fn mahalanobis_distances_follow_chi_squared_of_the_rank() {
    let space = correlated_space();
    let rows = draw(&space, 12);
    let (columns, mean, cov) = space.gaussian_specification();
    let k = columns.len();
    // Pseudo-inverse on the range of Σ: d² = Σ_r (u_rᵀ(x − μ))² / λ_r over λ_r > tol.
    let eigen = SymmetricEigen::new(cov.clone());
    let largest = eigen.eigenvalues.iter().copied().fold(0.0, f64::max);
    let kept: Vec<usize> = (0..k)
        .filter(|&r| eigen.eigenvalues[r] > 1e-12 * largest)
        .collect();
    let rank = kept.len();
    // The tolerance-band part has two zero variances (001 Eq. 12).
    assert_eq!(rank, k - 2);
    let mut distances: Vec<f64> = rows
        .chunks_exact(space.n_columns())
        .map(|row| {
            let x = DVector::from_iterator(k, columns.iter().map(|&c| row[c])) - &mean;
            kept.iter()
                .map(|&r| {
                    let projection = eigen.eigenvectors.column(r).dot(&x);
                    projection * projection / eigen.eigenvalues[r]
                })
                .sum()
        })
        .collect();
    let chi2 = ChiSquared::new(rank as f64).unwrap();
    let statistic = ks_statistic(&mut distances, |x| chi2.cdf(x));
    assert!(
        statistic < KS_CRITICAL_0_001,
        "√n·D = {statistic}, rank {rank}"
    );
}

#[test]
fn tolerance_band_example_of_001() {
    // validation.md, 001: Δτ = 0.01 mm, L1 = 120 mm → means (Δτ/2, Δτ/2, 0, Δτ/L1, Δτ/L1, 0),
    // σ = (Δτ/6, Δτ/6, 0, Δτ/(3L1), Δτ/(3L1), 0); the zero-variance components are exactly 0.
    let (dt, l1) = (0.01, 120.0);
    let mut builder = InputSpaceBuilder::new();
    builder.add_part(
        "parts[0]",
        &PartSpec::from_tolerance_band("parts[0]", dt, l1, false).unwrap(),
    );
    let space = builder.build("correlations").unwrap();
    let rows = draw(&space, 13);
    let means = [dt / 2.0, dt / 2.0, 0.0, dt / l1, dt / l1, 0.0];
    let sds = [
        dt / 6.0,
        dt / 6.0,
        0.0,
        dt / (3.0 * l1),
        dt / (3.0 * l1),
        0.0,
    ];
    let nf = N as f64;
    for c in 0..6 {
        let values: Vec<f64> = rows.chunks_exact(6).map(|r| r[c]).collect();
        if sds[c] == 0.0 {
            assert!(
                values.iter().all(|&v| v == 0.0),
                "component {c} must be exactly 0"
            );
            continue;
        }
        let m = values.iter().sum::<f64>() / nf;
        let sd = (values.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (nf - 1.0)).sqrt();
        assert!(
            (m - means[c]).abs() <= SIGMA_BOUND * sds[c] / nf.sqrt(),
            "mean {c}: {m}"
        );
        // Standard error of a normal sample sd: σ/√(2(n−1)).
        assert!(
            (sd - sds[c]).abs() <= SIGMA_BOUND * sds[c] / (2.0 * (nf - 1.0)).sqrt(),
            "sd {c}: {sd}"
        );
    }
}

#[test]
fn eq11_constraint_holds_and_its_acceptance_is_one_quarter() {
    // With the Eq. 10 means, each Eq. 11 inequality is a normal with its mean on the bound:
    // acceptance 1/2 each, 1/4 jointly (independent components). The group tallies are
    // geometric counts; bound: 5 standard errors of a binomial proportion over the attempts.
    let (dt, l1) = (0.004, 120.0);
    let mut builder = InputSpaceBuilder::new();
    builder.add_part(
        "parts[0]",
        &PartSpec::from_tolerance_band("parts[0]", dt, l1, true).unwrap(),
    );
    let space = builder.build("correlations").unwrap();
    let mut rows = vec![0.0; N * 6];
    let mut counts = space.new_constraint_counts();
    let mut rng = ChaCha8Rng::seed_from_u64(14);
    space.sample_rows(&mut rng, &mut rows, &mut counts).unwrap();
    for row in rows.chunks_exact(6) {
        assert!(row[0] + row[4] * l1 / 2.0 <= dt);
        assert!(row[1] + row[3] * l1 / 2.0 <= dt);
    }
    assert_eq!(counts.groups.len(), 2);
    for &(attempts, accepted) in &counts.groups {
        assert_eq!(accepted, N as u64);
        let rate = accepted as f64 / attempts as f64;
        let se = (0.25 / attempts as f64).sqrt();
        assert!((rate - 0.5).abs() <= SIGMA_BOUND * se, "group rate {rate}");
    }
    let joint = counts.acceptance_rate();
    assert!((joint - 0.25).abs() < 0.01, "{joint}");
}

#[test]
fn eq11_conditioned_law_matches_the_truncated_normal_closed_form() {
    // One Eq. 11 inequality over independent x ~ N(μx, σx²), y ~ N(μy, σy²):
    // s = x + (L1/2)·y ≤ Δτ with E s = Δτ (Eq. 10 means), so z_s = (s − μs)/σs is a
    // standard normal truncated to z_s ≤ 0: E z_s = −√(2/π), Var z_s = 1 − 2/π. With
    // k_x = σx²/σs and k_y = (L1/2)·σy²/σs (the regression of x and y on z_s), the
    // conditioned law has E x = μx + k_x·E z_s, Var x = σx² − k_x²·(2/π),
    // Cov(x, y) = −k_x·k_y·(2/π), and likewise for y. Bounds: 5 standard errors of a
    // mean (σ/√n) and of a second moment (√(m4 − m2²)/√n, from the sample itself).
    let (dt, l1) = (0.004, 120.0);
    let part = PartSpec::from_tolerance_band("parts[0]", dt, l1, true).unwrap();
    let mut builder = InputSpaceBuilder::new();
    builder.add_part("parts[0]", &part);
    let space = builder.build("correlations").unwrap();
    let rows = draw(&space, 15);
    let sd = part.sd();
    let two_over_pi = 2.0 / std::f64::consts::PI;
    // (Δu, Δβ) and (Δv, Δα): columns (0, 4) and (1, 3).
    for (cx, cy) in [(0, 4), (1, 3)] {
        let (mx, my, sx, sy) = (part.mean[cx], part.mean[cy], sd[cx], sd[cy]);
        let b = l1 / 2.0;
        let sigma_s = sx.hypot(b * sy);
        let (kx, ky) = (sx * sx / sigma_s, b * sy * sy / sigma_s);
        let mean_z = -two_over_pi.sqrt();
        let expected_mean = [mx + kx * mean_z, my + ky * mean_z];
        let expected_var = [
            sx * sx - kx * kx * two_over_pi,
            sy * sy - ky * ky * two_over_pi,
        ];
        let expected_cov = -kx * ky * two_over_pi;
        let xs: Vec<[f64; 2]> = rows.chunks_exact(6).map(|r| [r[cx], r[cy]]).collect();
        let n = xs.len() as f64;
        let mean = [0, 1].map(|k| xs.iter().map(|p| p[k]).sum::<f64>() / n);
        for k in 0..2 {
            let se = expected_var[k].sqrt() / n.sqrt();
            assert!(
                (mean[k] - expected_mean[k]).abs() <= SIGMA_BOUND * se,
                "columns ({cx}, {cy}) mean {k}: {} vs {}",
                mean[k],
                expected_mean[k]
            );
        }
        let second = |f: &dyn Fn(&[f64; 2]) -> f64| {
            let values: Vec<f64> = xs.iter().map(f).collect();
            let m = values.iter().sum::<f64>() / n;
            let m2 = values.iter().map(|v| (v - m).powi(2)).sum::<f64>() / n;
            (m, (m2 / n).sqrt())
        };
        for k in 0..2 {
            let (var, se) = second(&|p| (p[k] - mean[k]).powi(2));
            assert!(
                (var - expected_var[k]).abs() <= SIGMA_BOUND * se,
                "columns ({cx}, {cy}) variance {k}: {var} vs {}",
                expected_var[k]
            );
        }
        let (cov, se) = second(&|p| (p[0] - mean[0]) * (p[1] - mean[1]));
        assert!(
            (cov - expected_cov).abs() <= SIGMA_BOUND * se,
            "columns ({cx}, {cy}) covariance: {cov} vs {expected_cov}"
        );
    }
}
