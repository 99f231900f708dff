//! Rows from uniform points (Latin hypercube, scrambled Sobol'): every column by an
//! inverse CDF, the Eq. 11 constraints by exact conditional inversion.
//!
//! One uniform per dimension, in this order: each unconstrained normal single
//! (x = μ + σ·Φ⁻¹(u)), each correlated block (its `rank` standard normals Φ⁻¹(u), then
//! x = μ + L·z), each non-normal scalar ([`ScalarDistribution::from_uniform`]), each
//! constrained group (its `rank` normals, below).
//!
//! A constrained group is the joint normal x = μ + L·z of its columns (L the block-diagonal
//! factor of its singles and blocks, rank r) conditioned on its inequalities aⱼ·x ≤ cⱼ.
//! With wⱼ = Lᵀaⱼ, σⱼ = |wⱼ| and ŵⱼ = wⱼ/σⱼ, inequality j is ŵⱼ·z ≤ τⱼ = (cⱼ − aⱼ·μ)/σⱼ
//! (a fixed column an inequality reads enters cⱼ at its mean). When the ŵⱼ are mutually
//! orthogonal (each half of Eq. 11 over its own components, the case of 001 Eq. 12's
//! diagonal covariance and of any covariance that does not couple (Δu, Δβ) with
//! (Δv, Δα)), an orthonormal basis E whose first columns are the ŵⱼ turns z = E·t into
//! independent standard normals t with the inequalities tⱼ ≤ τⱼ on the first ones only.
//! So tⱼ = Φ⁻¹(u·Φ(τⱼ)) (the truncated normal's inverse CDF), the other t = Φ⁻¹(u), and
//! x = μ + (L·E)·t: exactly the conditioned law rejection samples, from r uniforms, with
//! the point set's structure intact. Inequalities that the covariance couples
//! (ŵ₁·ŵ₂ ≠ 0) would need the bivariate normal law's inverse; such a scenario is refused
//! for these methods with the reason ([`InputSpace::quasi_dimensions`]).

use super::{column_mut, prefix, InputSpace, SamplerScratch};
use crate::error::DeviationError;
use crate::inverse_normal::standard_normal_inverse as standard_normal_quantile;
use crate::points::PointSet;
use crate::scalar::standard_normal_cdf;

/// Two directions count as orthogonal below this |ŵ₁·ŵ₂| (round-off of a factorised
/// covariance that does not couple them).
const ORTHOGONAL: f64 = 1e-12;

/// A constrained group as truncated and free standard normals (module docs).
#[derive(Debug, Clone)]
pub(super) struct QuasiGroup {
    columns: Vec<usize>,
    means: Vec<f64>,
    rank: usize,
    /// Row-major columns.len() × rank: L·E.
    factor: Vec<f64>,
    /// Φ(τⱼ) of the first `truncated.len()` normals.
    truncated: Vec<f64>,
}

/// How a quasi-random row is drawn: its dimensions, the constrained groups, or why the
/// space cannot be drawn this way.
#[derive(Debug, Clone, Default)]
pub(super) struct QuasiLayout {
    dims: usize,
    groups: Vec<QuasiGroup>,
    refusal: Option<(String, String)>,
}

impl QuasiLayout {
    /// The layout of a built space.
    pub(super) fn new(space: &InputSpace) -> QuasiLayout {
        let mut dims = space.singles.len()
            + space.blocks.iter().map(|b| b.rank).sum::<usize>()
            + space.independent.len();
        let mut groups = Vec::new();
        let fixed_mean = |column: usize| space.fixed.iter().find(|f| f.0 == column).map(|f| f.1);
        for group in &space.constrained_groups {
            let mut columns = Vec::new();
            let mut means = Vec::new();
            // Block-diagonal factor, columns × rank, built row by row.
            let rank = group.singles.len() + group.blocks.iter().map(|b| b.rank).sum::<usize>();
            let mut factor_rows: Vec<Vec<f64>> = Vec::new();
            let mut offset = 0;
            for &(column, mean, sd) in &group.singles {
                columns.push(column);
                means.push(mean);
                let mut row = vec![0.0; rank];
                row[offset] = sd;
                factor_rows.push(row);
                offset += 1;
            }
            for block in &group.blocks {
                for (i, &column) in block.columns.iter().enumerate() {
                    columns.push(column);
                    means.push(block.means[i]);
                    let mut row = vec![0.0; rank];
                    row[offset..offset + block.rank]
                        .copy_from_slice(&block.factor[i * block.rank..(i + 1) * block.rank]);
                    factor_rows.push(row);
                }
                offset += block.rank;
            }
            // Each inequality as (ŵ, τ).
            let mut directions: Vec<Vec<f64>> = Vec::new();
            let mut truncated = Vec::new();
            for q in &group.inequalities {
                let mut w = vec![0.0; rank];
                let mut slack = q.bound;
                for (&column, &a) in q.columns.iter().zip(&q.coefficients) {
                    match columns.iter().position(|&c| c == column) {
                        Some(i) => {
                            slack -= a * means[i];
                            for (wk, lk) in w.iter_mut().zip(&factor_rows[i]) {
                                *wk += a * lk;
                            }
                        }
                        None => slack -= a * fixed_mean(column).unwrap_or(0.0),
                    }
                }
                let sigma = w.iter().map(|x| x * x).sum::<f64>().sqrt();
                if sigma == 0.0 {
                    // The inequality does not depend on the drawn values: the build's
                    // acceptance check has already refused it when it fails.
                    continue;
                }
                w.iter_mut().for_each(|x| *x /= sigma);
                if let Some(coupled) = directions
                    .iter()
                    .find(|d| d.iter().zip(&w).map(|(a, b)| a * b).sum::<f64>().abs() > ORTHOGONAL)
                {
                    let rho: f64 = coupled.iter().zip(&w).map(|(a, b)| a * b).sum();
                    let refusal = (
                        space.constraint_paths.join(", "),
                        format!(
                            "lhs and rqmc draw the Eq. 11 constraint by exact inversion, which needs its two inequalities uncorrelated; this covariance couples them (correlation {rho:.3} between Δu + Δβ·L1/2 and Δv + Δα·L1/2): use \"sampling\": \"mc\", or a covariance that does not couple (Δu, Δβ) with (Δv, Δα)"
                        ),
                    );
                    return QuasiLayout {
                        dims,
                        groups: Vec::new(),
                        refusal: Some(refusal),
                    };
                }
                directions.push(w);
                truncated.push(standard_normal_cdf(slack / sigma));
            }
            let basis = orthonormal_completion(directions, rank);
            // L·E.
            let mut factor = vec![0.0; columns.len() * rank];
            for (i, row) in factor_rows.iter().enumerate() {
                for (k, e) in basis.iter().enumerate() {
                    factor[i * rank + k] = row.iter().zip(e).map(|(l, e)| l * e).sum();
                }
            }
            dims += rank;
            groups.push(QuasiGroup {
                columns,
                means,
                rank,
                factor,
                truncated,
            });
        }
        QuasiLayout {
            dims,
            groups,
            refusal: None,
        }
    }
}

/// An orthonormal basis of R^n (as n vectors) whose first vectors are the given
/// orthonormal `directions`: Gram–Schmidt (twice, for round-off) over the unit vectors,
/// keeping those with a substantial remainder.
fn orthonormal_completion(mut basis: Vec<Vec<f64>>, n: usize) -> Vec<Vec<f64>> {
    for k in 0..n {
        if basis.len() == n {
            break;
        }
        let mut v = vec![0.0; n];
        v[k] = 1.0;
        for _ in 0..2 {
            for b in &basis {
                let dot: f64 = b.iter().zip(&v).map(|(a, c)| a * c).sum();
                v.iter_mut().zip(b).for_each(|(x, b)| *x -= dot * b);
            }
        }
        let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        if norm > 1e-6 {
            v.iter_mut().for_each(|x| *x /= norm);
            basis.push(v);
        }
    }
    basis
}

impl InputSpace {
    /// Uniforms per row when drawn from a point set (module docs of `quasi`), or why this
    /// space cannot be drawn from one (one line naming the constrained parts).
    pub fn quasi_dimensions(&self) -> Result<usize, DeviationError> {
        match &self.quasi.refusal {
            Some((path, reason)) => Err(DeviationError::invalid(path.clone(), reason.clone())),
            None => Ok(self.quasi.dims),
        }
    }

    /// Fills a column-major block (as [`InputSpace::sample_columns_with`]) with points
    /// `first …` of replicate `replicate` of `points`, turned into rows: every value by
    /// an inverse CDF, the constraints by exact conditional inversion (no rejection, no
    /// stream). `points` must have [`InputSpace::quasi_dimensions`] dimensions.
    pub fn sample_columns_from_points(
        &self,
        points: &PointSet,
        replicate: u64,
        first: u64,
        columns: &mut [f64],
        scratch: &mut SamplerScratch,
    ) -> Result<(), DeviationError> {
        let dims = self.quasi_dimensions()?;
        if self.n_columns == 0 {
            return Ok(());
        }
        assert_eq!(points.dims(), dims, "the point set's dimensions");
        let n_rows = columns.len() / self.n_columns;
        let u = prefix(&mut scratch.candidates, dims * n_rows);
        points.fill(replicate, first, n_rows, u);
        let mut uniforms = u.chunks_exact(n_rows.max(1));
        let mut next = || uniforms.next().expect("a column of uniforms per dimension");
        for &(column, mean) in &self.fixed {
            column_mut(columns, column, n_rows).fill(mean);
        }
        for &(column, mean, sd) in &self.singles {
            for (x, &u) in column_mut(columns, column, n_rows).iter_mut().zip(next()) {
                *x = mean + sd * standard_normal_quantile(u);
            }
        }
        let widest = (self.quasi.groups.iter().map(|g| g.rank))
            .chain(self.blocks.iter().map(|b| b.rank))
            .max()
            .unwrap_or(1);
        let z = prefix(&mut scratch.block_z, widest * n_rows.max(1));
        for block in &self.blocks {
            for k in 0..block.rank {
                for (r, &u) in next().iter().enumerate() {
                    z[r * block.rank + k] = standard_normal_quantile(u);
                }
            }
            for r in 0..n_rows {
                block.apply_to_columns(
                    &z[r * block.rank..(r + 1) * block.rank],
                    columns,
                    n_rows,
                    r,
                );
            }
        }
        for (column, distribution) in &self.independent {
            for (x, &u) in column_mut(columns, *column, n_rows).iter_mut().zip(next()) {
                *x = distribution.from_uniform(u);
            }
        }
        for group in &self.quasi.groups {
            let rank = group.rank;
            for k in 0..rank {
                let truncation = group.truncated.get(k).copied();
                for (r, &u) in next().iter().enumerate() {
                    z[r * rank + k] = match truncation {
                        Some(mass) => standard_normal_quantile(u * mass),
                        None => standard_normal_quantile(u),
                    };
                }
            }
            for r in 0..n_rows {
                let t = &z[r * rank..(r + 1) * rank];
                for (i, &column) in group.columns.iter().enumerate() {
                    let row = &group.factor[i * rank..(i + 1) * rank];
                    columns[column * n_rows + r] =
                        group.means[i] + row.iter().zip(t).map(|(l, t)| l * t).sum::<f64>();
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::part::PartSpec;
    use crate::points::SamplingMethod;
    use crate::scalar::ScalarDistribution;
    use crate::InputSpaceBuilder;

    fn density(x: f64) -> f64 {
        (-0.5 * x * x).exp() / (2.0 * std::f64::consts::PI).sqrt()
    }

    #[test]
    fn constrained_rows_follow_the_conditioned_law_exactly() {
        // parts[0]: Eq. 11 with the diagonal 001 Eq. 12 covariance (two groups of two
        // singles); parts[1]: its Δu correlated with a scalar (a group of a block and a
        // single). Every row satisfies Eq. 11, and the mean of each inequality's left side
        // a·x is the truncated normal's μs − σs·φ(τ)/Φ(τ) (τ = (c − μs)/σs): within 5
        // Monte Carlo standard errors σs/√n (RQMC and LHS are more precise than that).
        let band = |path| PartSpec::from_tolerance_band(path, 0.006, 120.0, true).unwrap();
        let mut builder = InputSpaceBuilder::new();
        let p0 = builder.add_part("parts[0]", &band("parts[0]"));
        let p1 = builder.add_part("parts[1]", &band("parts[1]"));
        let s = builder.add_scalar(
            "variables[0]",
            ScalarDistribution::Normal {
                mean: 0.0,
                sd: 0.002,
            },
        );
        let r = builder.add_scalar("variables[1]", ScalarDistribution::Rayleigh { sigma: 2.0 });
        builder.correlate("correlations[0]", p1, s, 0.7).unwrap();
        let space = builder.build("correlations").unwrap();
        let dims = space.quasi_dimensions().unwrap();
        // 12 part components, 4 of them fixed (Δw, Δγ), one normal and one Rayleigh.
        assert_eq!(dims, 8 + 2);
        let n = 1usize << 14;
        for method in [SamplingMethod::Rqmc, SamplingMethod::LatinHypercube] {
            let points = PointSet::new(method, dims, n as u64, 11).unwrap();
            let mut columns = vec![f64::NAN; n * space.n_columns()];
            let mut scratch = SamplerScratch::default();
            space
                .sample_columns_from_points(&points, 0, 0, &mut columns, &mut scratch)
                .unwrap();
            let value = |c: usize, r: usize| columns[c * n + r];
            let constraint = band("parts[0]").constraint.unwrap();
            for first in [p0, p1] {
                for q in constraint.inequalities(first) {
                    let (mu, var) = (0..2).fold((0.0, 0.0), |(m, v), k| {
                        let c = q.columns[k];
                        let a = q.coefficients[k];
                        (
                            m + a * space.mean_row()[c],
                            v + a * a * space.covariance(c, c),
                        )
                    });
                    let sigma = var.sqrt();
                    let tau = (q.bound - mu) / sigma;
                    let expected = mu - sigma * density(tau) / standard_normal_cdf(tau);
                    let mut sum = 0.0;
                    for row in 0..n {
                        let lhs = q.coefficients[0] * value(q.columns[0], row)
                            + q.coefficients[1] * value(q.columns[1], row);
                        assert!(lhs <= q.bound * (1.0 + 1e-12), "{method:?} row {row}");
                        sum += lhs;
                    }
                    let mean = sum / n as f64;
                    assert!(
                        (mean - expected).abs() < 5.0 * sigma / (n as f64).sqrt(),
                        "{method:?}: {mean} against {expected}"
                    );
                }
            }
            // The Rayleigh column by its inverse CDF: mean σ·√(π/2).
            let mean = (0..n).map(|row| value(r, row)).sum::<f64>() / n as f64;
            let expected = 2.0 * (std::f64::consts::PI / 2.0).sqrt();
            let sd = 2.0 * (2.0 - std::f64::consts::PI / 2.0).sqrt();
            assert!((mean - expected).abs() < 5.0 * sd / (n as f64).sqrt());
            // The correlation of parts[1].Δu with the scalar is kept (ρ = 0.7 before the
            // truncation; Δu's share of its inequality is small, so it stays near 0.7).
            let (mx, my) = (
                (0..n).map(|row| value(p1, row)).sum::<f64>() / n as f64,
                (0..n).map(|row| value(s, row)).sum::<f64>() / n as f64,
            );
            let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
            for row in 0..n {
                let (x, y) = (value(p1, row) - mx, value(s, row) - my);
                sxy += x * y;
                sxx += x * x;
                syy += y * y;
            }
            let rho = sxy / (sxx * syy).sqrt();
            assert!((rho - 0.7).abs() < 0.1, "{method:?}: ρ = {rho}");
        }
    }

    #[test]
    fn coupled_inequalities_are_refused_with_the_reason() {
        // A covariance that correlates Δu with Δv couples the two halves of Eq. 11.
        let mut part = PartSpec::from_tolerance_band("parts[0]", 0.006, 120.0, true).unwrap();
        let c = 0.5 * (part.covariance[0][0] * part.covariance[1][1]).sqrt();
        part.covariance[0][1] = c;
        part.covariance[1][0] = c;
        let mut builder = InputSpaceBuilder::new();
        builder.add_part("parts[0]", &part);
        let space = builder.build("correlations").unwrap();
        let err = space.quasi_dimensions().unwrap_err().to_string();
        assert!(err.starts_with("parts[0]: lhs and rqmc"), "{err}");
        assert!(err.contains("\"sampling\": \"mc\""), "{err}");
    }
}
