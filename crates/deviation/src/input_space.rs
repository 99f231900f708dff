//! The joint input space of a scenario: every part component and scalar parameter as one
//! column of a sample row, drawn together.
//!
//! All normal columns (part components, normal and tolerance-band scalars) form one
//! multivariate normal N(μ, Σ) over their union (001 Eq. 2 generalised across parts):
//! Σ holds each part's 6×6 covariance on its diagonal block and the scenario's
//! cross-correlations between any two normal columns. The columns split into independent
//! blocks (connected components of Σ's non-zero pattern); each block is drawn as
//! x = μ + L·z with L from the pivoted Cholesky factor and z standard normal, so a
//! diagonal Σ costs one normal draw per non-degenerate column and zero-variance columns are
//! exactly their mean. Non-normal scalars are drawn independently.
//!
//! Parts with the 001 Eq. 11 constraint are drawn by rejection: the blocks that hold their
//! components are redrawn until every constraint holds, which conditions the joint normal on
//! Eq. 11 without touching the other blocks (they are independent of these).

use nalgebra::{DMatrix, DVector};
use rand::{Rng, SeedableRng};
use rand_distr::StandardNormal;

use crate::cholesky::pivoted_cholesky;
use crate::constraint::TiltConstraint;
use crate::error::DeviationError;
use crate::part::{check_covariance, PartSpec};
use crate::scalar::ScalarDistribution;

/// Most consecutive rejections of one row before the run is abandoned. At the lowest
/// accepted rate (1 %), the chance of reaching it is 0.99^100000 ≈ 1e-437.
const MAX_REJECTIONS_PER_ROW: u64 = 100_000;
/// Lowest acceptance rate of the Eq. 11 constraints that is accepted.
pub const MIN_ACCEPTANCE_RATE: f64 = 0.01;
/// Draws of the deterministic pilot that measures the acceptance rate when building.
const PILOT_DRAWS: u64 = 20_000;

/// Attempts and acceptances of the constraint rejection sampler.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ConstraintCounts {
    /// Candidate draws of the constrained blocks.
    pub attempts: u64,
    /// Candidates that satisfied every constraint.
    pub accepted: u64,
}

impl ConstraintCounts {
    /// Adds another tally.
    pub fn add(&mut self, other: ConstraintCounts) {
        self.attempts += other.attempts;
        self.accepted += other.accepted;
    }

    /// Accepted / attempts (1 when nothing was attempted).
    pub fn acceptance_rate(&self) -> f64 {
        if self.attempts == 0 {
            1.0
        } else {
            self.accepted as f64 / self.attempts as f64
        }
    }
}

#[derive(Debug, Clone)]
struct GaussianColumn {
    column: usize,
    mean: f64,
    label: String,
}

#[derive(Debug, Clone)]
struct ConstraintSpec {
    first_column: usize,
    constraint: TiltConstraint,
    path: String,
}

/// Collects the columns of an input space, then builds it.
#[derive(Debug, Clone, Default)]
pub struct InputSpaceBuilder {
    n_columns: usize,
    gaussian: Vec<GaussianColumn>,
    /// Covariance entries between gaussian columns, by gaussian index (upper and lower).
    covariance: Vec<((usize, usize), f64)>,
    independent: Vec<(usize, ScalarDistribution)>,
    constraints: Vec<ConstraintSpec>,
    /// For each column, its gaussian index, if normal.
    gaussian_index: Vec<Option<usize>>,
}

impl InputSpaceBuilder {
    /// An empty builder.
    pub fn new() -> Self {
        Self::default()
    }

    fn push_gaussian(&mut self, mean: f64, label: String) -> usize {
        let column = self.n_columns;
        self.n_columns += 1;
        self.gaussian_index.push(Some(self.gaussian.len()));
        self.gaussian.push(GaussianColumn {
            column,
            mean,
            label,
        });
        column
    }

    /// Adds a part (six columns, in the order of [`crate::SixDof::NAMES`]) and returns its
    /// first column. `path` is the part's JSON path, used in messages.
    pub fn add_part(&mut self, path: &str, spec: &PartSpec) -> usize {
        let first = self.n_columns;
        let indices: Vec<usize> = (0..6)
            .map(|i| {
                let label = format!("{path}[{}]", crate::SixDof::NAMES[i]);
                self.push_gaussian(spec.mean[i], label);
                self.gaussian.len() - 1
            })
            .collect();
        for i in 0..6 {
            for j in 0..6 {
                if spec.covariance[i][j] != 0.0 {
                    self.covariance
                        .push(((indices[i], indices[j]), spec.covariance[i][j]));
                }
            }
        }
        if let Some(constraint) = spec.constraint {
            self.constraints.push(ConstraintSpec {
                first_column: first,
                constraint,
                path: path.to_string(),
            });
        }
        first
    }

    /// Adds a scalar parameter and returns its column.
    pub fn add_scalar(&mut self, path: &str, distribution: ScalarDistribution) -> usize {
        match distribution.as_normal() {
            Some((mean, sd)) => {
                let column = self.push_gaussian(mean, path.to_string());
                let g = self.gaussian.len() - 1;
                if sd != 0.0 {
                    self.covariance.push(((g, g), sd * sd));
                }
                column
            }
            None => {
                let column = self.n_columns;
                self.n_columns += 1;
                self.gaussian_index.push(None);
                self.independent.push((column, distribution));
                column
            }
        }
    }

    /// Standard deviation of a normal column (from its variance), if normal.
    fn gaussian_sd(&self, g: usize) -> f64 {
        self.covariance
            .iter()
            .filter(|((a, b), _)| *a == g && *b == g)
            .map(|(_, v)| *v)
            .sum::<f64>()
            .sqrt()
    }

    /// Correlates two normal columns with coefficient `rho`; `path` names the entry.
    pub fn correlate(
        &mut self,
        path: &str,
        column_a: usize,
        column_b: usize,
        rho: f64,
    ) -> Result<(), DeviationError> {
        DeviationError::finite(&format!("{path}.rho"), rho)?;
        if rho.abs() > 1.0 {
            return Err(DeviationError::invalid(
                format!("{path}.rho"),
                format!("correlation must lie in [-1, 1], got {rho}"),
            ));
        }
        if column_a == column_b {
            return Err(DeviationError::invalid(
                path,
                "a variable cannot be correlated with itself",
            ));
        }
        let gaussian = |c: usize| self.gaussian_index.get(c).copied().flatten();
        let (Some(a), Some(b)) = (gaussian(column_a), gaussian(column_b)) else {
            return Err(DeviationError::invalid(
                path,
                "only normal variables (normal, tolerance_band, part components) can be correlated",
            ));
        };
        let covariance = rho * self.gaussian_sd(a) * self.gaussian_sd(b);
        // Replace an earlier entry between the same pair (a part's own covariance).
        self.covariance
            .retain(|((i, j), _)| !((*i == a && *j == b) || (*i == b && *j == a)));
        if covariance != 0.0 {
            self.covariance.push(((a, b), covariance));
            self.covariance.push(((b, a), covariance));
        }
        Ok(())
    }

    /// Number of columns so far.
    pub fn n_columns(&self) -> usize {
        self.n_columns
    }

    /// Factorises the joint covariance block by block and checks the constraints'
    /// acceptance rate. `correlations_path` names the cross-correlations in messages: a
    /// joint covariance that is indefinite only because of them is reported there.
    pub fn build(self, correlations_path: &str) -> Result<InputSpace, DeviationError> {
        let n_g = self.gaussian.len();
        let mut full = DMatrix::<f64>::zeros(n_g, n_g);
        for &((a, b), v) in &self.covariance {
            full[(a, b)] = v;
        }
        // Connected components of the non-zero pattern (union-find).
        let mut parent: Vec<usize> = (0..n_g).collect();
        fn find(parent: &mut [usize], mut x: usize) -> usize {
            while parent[x] != x {
                parent[x] = parent[parent[x]];
                x = parent[x];
            }
            x
        }
        for &((a, b), v) in &self.covariance {
            if v != 0.0 && a != b {
                let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
                if ra != rb {
                    parent[ra.max(rb)] = ra.min(rb);
                }
            }
        }
        let mut components: Vec<Vec<usize>> = Vec::new();
        let mut component_of_root = vec![usize::MAX; n_g];
        for g in 0..n_g {
            let root = find(&mut parent, g);
            if component_of_root[root] == usize::MAX {
                component_of_root[root] = components.len();
                components.push(Vec::new());
            }
            components[component_of_root[root]].push(g);
        }
        let constrained_columns: Vec<usize> = self
            .constraints
            .iter()
            .flat_map(|c| [0, 1, 3, 4].map(|k| c.first_column + k))
            .collect();
        let mut space = InputSpace {
            n_columns: self.n_columns,
            fixed: Vec::new(),
            singles: Vec::new(),
            blocks: Vec::new(),
            constrained_blocks: Vec::new(),
            independent: self.independent,
            constraints: self
                .constraints
                .iter()
                .map(|c| (c.first_column, c.constraint))
                .collect(),
            constraint_paths: self.constraints.iter().map(|c| c.path.clone()).collect(),
            gaussian_columns: self.gaussian.iter().map(|g| g.column).collect(),
            gaussian_mean: DVector::from_iterator(n_g, self.gaussian.iter().map(|g| g.mean)),
            gaussian_covariance: full.clone(),
            max_rank: 0,
        };
        for members in components {
            let size = members.len();
            let sub = DMatrix::from_fn(size, size, |i, j| full[(members[i], members[j])]);
            if size > 1 {
                check_covariance(correlations_path, &sub).map_err(|err| match err {
                    DeviationError::Indefinite {
                        smallest_eigenvalue,
                        ..
                    } => DeviationError::Indefinite {
                        path: format!(
                            "{correlations_path} (joint covariance of {})",
                            members
                                .iter()
                                .map(|&g| self.gaussian[g].label.as_str())
                                .collect::<Vec<_>>()
                                .join(", ")
                        ),
                        smallest_eigenvalue,
                    },
                    other => other,
                })?;
            }
            let columns: Vec<usize> = members.iter().map(|&g| self.gaussian[g].column).collect();
            let means: Vec<f64> = members.iter().map(|&g| self.gaussian[g].mean).collect();
            let factor = pivoted_cholesky(&sub);
            let constrained = columns.iter().any(|c| constrained_columns.contains(c));
            if factor.rank == 0 {
                space
                    .fixed
                    .extend(columns.iter().copied().zip(means.iter().copied()));
                continue;
            }
            space.max_rank = space.max_rank.max(factor.rank);
            if size == 1 && !constrained {
                space
                    .singles
                    .push((columns[0], means[0], factor.entries[0]));
                continue;
            }
            let block = GaussianBlock {
                columns,
                means,
                rank: factor.rank,
                factor: factor.entries,
            };
            if constrained {
                space.constrained_blocks.push(block);
            } else {
                space.blocks.push(block);
            }
        }
        space.check_acceptance()?;
        Ok(space)
    }
}

#[derive(Debug, Clone)]
struct GaussianBlock {
    columns: Vec<usize>,
    means: Vec<f64>,
    rank: usize,
    /// Row-major columns.len() × rank.
    factor: Vec<f64>,
}

impl GaussianBlock {
    #[inline]
    fn draw<R: Rng + ?Sized>(&self, rng: &mut R, z: &mut [f64], row: &mut [f64]) {
        let z = &mut z[..self.rank];
        for value in z.iter_mut() {
            *value = rng.sample(StandardNormal);
        }
        for (i, (&column, &mean)) in self.columns.iter().zip(&self.means).enumerate() {
            let factor_row = &self.factor[i * self.rank..(i + 1) * self.rank];
            let mut value = mean;
            for (l, zk) in factor_row.iter().zip(z.iter()) {
                value += l * zk;
            }
            row[column] = value;
        }
    }
}

/// A built input space: draws sample rows of `n_columns()` values.
#[derive(Debug, Clone)]
pub struct InputSpace {
    n_columns: usize,
    fixed: Vec<(usize, f64)>,
    singles: Vec<(usize, f64, f64)>,
    blocks: Vec<GaussianBlock>,
    constrained_blocks: Vec<GaussianBlock>,
    independent: Vec<(usize, ScalarDistribution)>,
    constraints: Vec<(usize, TiltConstraint)>,
    constraint_paths: Vec<String>,
    gaussian_columns: Vec<usize>,
    gaussian_mean: DVector<f64>,
    gaussian_covariance: DMatrix<f64>,
    max_rank: usize,
}

impl InputSpace {
    /// Columns per row.
    pub fn n_columns(&self) -> usize {
        self.n_columns
    }

    /// Whether any part carries the Eq. 11 constraint.
    pub fn has_constraints(&self) -> bool {
        !self.constraints.is_empty()
    }

    /// JSON paths of the constrained parts.
    pub fn constraint_paths(&self) -> &[String] {
        &self.constraint_paths
    }

    /// The normal columns, their mean vector and joint covariance (as specified, before the
    /// constraints), for tests and diagnostics.
    pub fn gaussian_specification(&self) -> (&[usize], &DVector<f64>, &DMatrix<f64>) {
        (
            &self.gaussian_columns,
            &self.gaussian_mean,
            &self.gaussian_covariance,
        )
    }

    /// The row of means: every normal column at its mean, every other scalar at its mean
    /// (the constraint is not applied: the Eq. 10 mean lies on its boundary).
    pub fn mean_row(&self) -> Vec<f64> {
        let mut row = vec![0.0; self.n_columns];
        for (&column, &mean) in self.gaussian_columns.iter().zip(self.gaussian_mean.iter()) {
            row[column] = mean;
        }
        for (column, distribution) in &self.independent {
            row[*column] = distribution.mean();
        }
        row
    }

    /// Fills `rows` (row-major, a multiple of `n_columns()` long) with independent draws.
    /// Fails only when a constraint rejects [`MAX_REJECTIONS_PER_ROW`] draws in a row.
    pub fn sample_rows<R: Rng + ?Sized>(
        &self,
        rng: &mut R,
        rows: &mut [f64],
        counts: &mut ConstraintCounts,
    ) -> Result<(), DeviationError> {
        if self.n_columns == 0 {
            return Ok(());
        }
        let mut z = vec![0.0; self.max_rank.max(1)];
        for row in rows.chunks_exact_mut(self.n_columns) {
            for &(column, mean) in &self.fixed {
                row[column] = mean;
            }
            for &(column, mean, sd) in &self.singles {
                let draw: f64 = rng.sample(StandardNormal);
                row[column] = mean + sd * draw;
            }
            for block in &self.blocks {
                block.draw(rng, &mut z, row);
            }
            for (column, distribution) in &self.independent {
                row[*column] = distribution.sample(rng);
            }
            if !self.constraints.is_empty() {
                self.draw_constrained(rng, &mut z, row, counts)?;
            }
        }
        Ok(())
    }

    fn draw_constrained<R: Rng + ?Sized>(
        &self,
        rng: &mut R,
        z: &mut [f64],
        row: &mut [f64],
        counts: &mut ConstraintCounts,
    ) -> Result<(), DeviationError> {
        for _ in 0..MAX_REJECTIONS_PER_ROW {
            counts.attempts += 1;
            for block in &self.constrained_blocks {
                block.draw(rng, z, row);
            }
            if self
                .constraints
                .iter()
                .all(|(first, c)| c.holds(&row[*first..*first + 6]))
            {
                counts.accepted += 1;
                return Ok(());
            }
        }
        Err(DeviationError::invalid(
            self.constraint_paths.join(", "),
            format!("the Eq. 11 constraint rejected {MAX_REJECTIONS_PER_ROW} draws in a row"),
        ))
    }

    /// Measures the acceptance rate of the constraints on a fixed pilot stream and rejects
    /// the space when it is below [`MIN_ACCEPTANCE_RATE`].
    fn check_acceptance(&self) -> Result<(), DeviationError> {
        if self.constraints.is_empty() {
            return Ok(());
        }
        let mut rng = rand_chacha_pilot();
        let mut z = vec![0.0; self.max_rank.max(1)];
        let mut row = self.mean_row();
        let mut accepted = 0u64;
        for _ in 0..PILOT_DRAWS {
            for block in &self.constrained_blocks {
                block.draw(&mut rng, &mut z, &mut row);
            }
            if self
                .constraints
                .iter()
                .all(|(first, c)| c.holds(&row[*first..*first + 6]))
            {
                accepted += 1;
            }
        }
        let rate = accepted as f64 / PILOT_DRAWS as f64;
        if rate < MIN_ACCEPTANCE_RATE {
            return Err(DeviationError::invalid(
                self.constraint_paths.join(", "),
                format!(
                    "the Eq. 11 constraint accepts only {:.3} % of draws (minimum {} %): widen the band or remove the constraint",
                    100.0 * rate,
                    100.0 * MIN_ACCEPTANCE_RATE
                ),
            ));
        }
        Ok(())
    }
}

/// A fixed generator for the acceptance pilot, independent of the run's streams.
fn rand_chacha_pilot() -> rand_chacha::ChaCha8Rng {
    rand_chacha::ChaCha8Rng::seed_from_u64(0x005e_ed0f_e911)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zero_variance_columns_are_exact_means() {
        let part = PartSpec::from_tolerance_band("parts[0]", 0.006, 120.0, false).unwrap();
        let mut builder = InputSpaceBuilder::new();
        builder.add_part("parts[0]", &part);
        let space = builder.build("correlations").unwrap();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut rows = vec![f64::NAN; 6 * 1000];
        let mut counts = ConstraintCounts::default();
        space.sample_rows(&mut rng, &mut rows, &mut counts).unwrap();
        for row in rows.chunks_exact(6) {
            assert_eq!(row[2], 0.0);
            assert_eq!(row[5], 0.0);
            assert!(row[0].is_finite() && row[0] != 0.0);
        }
    }

    #[test]
    fn correlating_a_uniform_is_an_error() {
        let mut builder = InputSpaceBuilder::new();
        let a = builder.add_scalar(
            "variables[0]",
            ScalarDistribution::Uniform {
                lower: 0.0,
                upper: 1.0,
            },
        );
        let b = builder.add_scalar(
            "variables[1]",
            ScalarDistribution::Normal { mean: 0.0, sd: 1.0 },
        );
        let err = builder.correlate("correlations[0]", a, b, 0.5).unwrap_err();
        assert!(err
            .to_string()
            .starts_with("correlations[0]: only normal variables"));
    }

    #[test]
    fn indefinite_joint_covariance_names_correlations() {
        // Three unit normals with pairwise ρ = −0.9: the matrix has eigenvalue 1 − 1.8 < 0.
        let mut builder = InputSpaceBuilder::new();
        let c: Vec<usize> = (0..3)
            .map(|i| {
                builder.add_scalar(
                    &format!("variables[{i}]"),
                    ScalarDistribution::Normal { mean: 0.0, sd: 1.0 },
                )
            })
            .collect();
        builder
            .correlate("correlations[0]", c[0], c[1], -0.9)
            .unwrap();
        builder
            .correlate("correlations[1]", c[1], c[2], -0.9)
            .unwrap();
        builder
            .correlate("correlations[2]", c[0], c[2], -0.9)
            .unwrap();
        let err = builder.build("correlations").unwrap_err();
        match err {
            DeviationError::Indefinite {
                path,
                smallest_eigenvalue,
            } => {
                assert!(path.starts_with("correlations (joint covariance of variables[0]"));
                assert!((smallest_eigenvalue - (1.0 - 1.8)).abs() < 1e-12);
            }
            other => panic!("expected Indefinite, got {other}"),
        }
    }

    #[test]
    fn constraint_with_tiny_acceptance_is_rejected() {
        // A part whose mean translation is far outside its own band: Eq. 11 never holds.
        let mut part = PartSpec::from_tolerance_band("parts[0]", 0.006, 120.0, true).unwrap();
        part.mean[0] = 0.05;
        let mut builder = InputSpaceBuilder::new();
        builder.add_part("parts[0]", &part);
        let err = builder.build("correlations").unwrap_err().to_string();
        assert!(
            err.starts_with("parts[0]: the Eq. 11 constraint accepts only 0.000 %"),
            "{err}"
        );
    }
}
