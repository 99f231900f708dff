//! Conditional draws: redraw some columns of a sample row given the others, from the joint
//! distribution of the input space. Needed by Shapley effects, which average the expected
//! conditional variance of the output over subsets of correlated inputs.
//!
//! For the normal columns, with F the free and G the given ones (Anderson 2003, Thm 2.5.1):
//!
//! ```text
//! x_F | x_G ~ N( μ_F + Σ_FG·Σ_GG⁺·(x_G − μ_G),  Σ_FF − Σ_FG·Σ_GG⁺·Σ_GF )
//! ```
//!
//! with Σ_GG⁺ the pseudo-inverse (eigenvalues below 1e−12 of the largest dropped), so
//! singular covariances work; the conditional covariance is factorised with the pivoted
//! Cholesky. A non-normal scalar that the scenario correlates (the Gaussian copula) is
//! conditioned through its normal score: the sampler works on rows in the space the input
//! space draws ([`InputSpace::sample_latent_rows`]), where such a column holds its normal
//! score, and [`InputSpace::latent_to_values`] turns the row into values afterwards; as
//! the values are an increasing function of the scores, conditioning on one is
//! conditioning on the other. The other non-normal scalars are independent of everything
//! and are drawn from their marginal. Every normal comes from the project's ziggurat ([`Ziggurat`]), the one
//! normal source of every sampling path. Parts with the Eq. 11 constraint are not normal any more; a space with
//! constraints has no conditional sampler.

use std::collections::BTreeSet;

use nalgebra::{DMatrix, SymmetricEigen};
use rand::Rng;

use crate::cholesky::pivoted_cholesky;
use crate::error::DeviationError;
use crate::input_space::InputSpace;
use crate::normal::Ziggurat;
use crate::scalar::ScalarDistribution;

/// Draws the free columns of a row given its other columns.
#[derive(Debug, Clone)]
pub struct ConditionalSampler {
    /// (column, mean) of the free normal columns.
    free: Vec<(usize, f64)>,
    /// (column, mean) of the given normal columns.
    given: Vec<(usize, f64)>,
    /// Σ_FG·Σ_GG⁺, row-major |F| × |G|.
    regression: Vec<f64>,
    /// Factor of the conditional covariance, row-major |F| × rank.
    factor: Vec<f64>,
    rank: usize,
    /// Free non-normal columns.
    independent: Vec<(usize, ScalarDistribution)>,
}

impl InputSpace {
    /// A sampler of `free_columns` given all other columns.
    pub fn conditional_sampler(
        &self,
        free_columns: &[usize],
    ) -> Result<ConditionalSampler, DeviationError> {
        if self.has_constraints() {
            return Err(DeviationError::invalid(
                self.constraint_paths().join(", "),
                "conditional draws (Shapley effects) need parts without the Eq. 11 constraint",
            ));
        }
        // Only the given columns correlated with a free one enter the regression: the
        // others are independent of the free columns and leave their law unchanged.
        let mean = self.latent_mean_row();
        let free: Vec<usize> = self
            .gaussian_columns()
            .iter()
            .copied()
            .filter(|c| free_columns.contains(c))
            .collect();
        let related: BTreeSet<usize> = free
            .iter()
            .flat_map(|&c| self.correlated_columns(c))
            .collect();
        let given: Vec<usize> = related
            .into_iter()
            .filter(|c| !free_columns.contains(c))
            .collect();
        let sub = |rows: &[usize], cols: &[usize]| {
            DMatrix::from_fn(rows.len(), cols.len(), |i, j| {
                self.latent_covariance(rows[i], cols[j])
            })
        };
        let s_ff = sub(&free, &free);
        let s_fg = sub(&free, &given);
        let s_gg = sub(&given, &given);
        let pseudo_inverse = if given.is_empty() {
            DMatrix::zeros(0, 0)
        } else {
            let eigen = SymmetricEigen::new(s_gg);
            let largest = eigen.eigenvalues.iter().copied().fold(0.0, f64::max);
            let inverted = eigen
                .eigenvalues
                .map(|l| if l > 1e-12 * largest { 1.0 / l } else { 0.0 });
            &eigen.eigenvectors * DMatrix::from_diagonal(&inverted) * eigen.eigenvectors.transpose()
        };
        let regression = &s_fg * &pseudo_inverse;
        let mut conditional = &s_ff - &regression * s_fg.transpose();
        // Symmetrise rounding; clamp the tiny negative diagonal rounding can leave.
        conditional = (&conditional + conditional.transpose()) * 0.5;
        for i in 0..conditional.nrows() {
            conditional[(i, i)] = conditional[(i, i)].max(0.0);
        }
        let factor = pivoted_cholesky(&conditional);
        Ok(ConditionalSampler {
            free: free.iter().map(|&c| (c, mean[c])).collect(),
            given: given.iter().map(|&c| (c, mean[c])).collect(),
            regression: (0..free.len())
                .flat_map(|i| (0..given.len()).map(move |j| (i, j)))
                .map(|(i, j)| regression[(i, j)])
                .collect(),
            rank: factor.rank,
            factor: factor.entries,
            independent: self
                .independent_columns()
                .iter()
                .filter(|(c, _)| free_columns.contains(c))
                .cloned()
                .collect(),
        })
    }
}

impl ConditionalSampler {
    /// Overwrites the free columns of `row` with a draw given its other columns; `row` is
    /// in the space the input space draws (copula columns as normal scores, module docs).
    /// `z` is scratch space, reused across calls so that a draw does not allocate.
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R, row: &mut [f64], z: &mut Vec<f64>) {
        let n_given = self.given.len();
        z.clear();
        let normal = Ziggurat::get();
        z.extend((0..self.rank).map(|_| normal.sample(rng)));
        for (i, &(column, mean)) in self.free.iter().enumerate() {
            let mut value = mean;
            for (j, &(given_column, given_mean)) in self.given.iter().enumerate() {
                value += self.regression[i * n_given + j] * (row[given_column] - given_mean);
            }
            for (k, zk) in z.iter().enumerate() {
                value += self.factor[i * self.rank + k] * zk;
            }
            row[column] = value;
        }
        for (column, distribution) in &self.independent {
            row[*column] = distribution.sample(rng);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::InputSpaceBuilder;
    use rand::SeedableRng;

    #[test]
    fn conditional_of_a_bivariate_normal() {
        // x ~ N(0, [[1, ρ], [ρ, 1]]): x2 | x1 ~ N(ρ·x1, 1 − ρ²). 200 000 draws at x1 = 1.5;
        // bounds: 5 standard errors of the mean and of the variance.
        let mut builder = InputSpaceBuilder::new();
        let a = builder.add_scalar("a", ScalarDistribution::Normal { mean: 0.0, sd: 1.0 });
        let b = builder.add_scalar("b", ScalarDistribution::Normal { mean: 0.0, sd: 1.0 });
        builder.correlate("c", a, b, 0.8).unwrap();
        let space = builder.build("correlations").unwrap();
        let sampler = space.conditional_sampler(&[b]).unwrap();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        let n = 200_000;
        let mut z = Vec::new();
        let draws: Vec<f64> = (0..n)
            .map(|_| {
                let mut row = [1.5, 0.0];
                sampler.sample(&mut rng, &mut row, &mut z);
                assert_eq!(row[0], 1.5);
                row[1]
            })
            .collect();
        let mean = draws.iter().sum::<f64>() / n as f64;
        let var = draws.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n as f64 - 1.0);
        let (m, v) = (0.8 * 1.5, 1.0 - 0.64);
        assert!((mean - m).abs() < 5.0 * (v / n as f64).sqrt(), "{mean}");
        assert!((var - v).abs() < 5.0 * v * (2.0 / n as f64).sqrt(), "{var}");
    }
}
