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
//! exactly their mean. Non-normal scalars are drawn independently, unless the scenario
//! correlates them: such a scalar joins the joint normal through its normal score z
//! (mean 0, variance 1) and takes the value F⁻¹(Φ(z)) once its block is drawn, the Gaussian
//! copula of [`crate::copula`].
//!
//! Parts with the 001 Eq. 11 constraint are drawn by rejection: the blocks that hold the
//! components of an inequality are redrawn until it holds, which conditions the joint
//! normal on Eq. 11 without touching the other blocks (they are independent of these).
//! Inequalities that share no block are independent and get their own rejection loop
//! (for a diagonal 001 covariance, (Δu, Δβ) and (Δv, Δα) separately), so the expected cost
//! is the sum, not the product, of the inverse acceptance rates. A group of independent
//! components is drawn for all the rows of a call at once by branch-free compaction (each
//! candidate is written to the next unfilled row, which advances on acceptance); a group
//! of one inequality over two of them (each half of Eq. 11 for a diagonal covariance) is
//! first rotated so that only the constrained direction is redrawn ([`RotatedPair`]).
//! The acceptance rate of the whole constraint is the product of the groups' rates.
//!
//! A call fills a block of rows: column-major ([`InputSpace::sample_columns_with`], the
//! run's hot loop, where each column is contiguous for the models) or row-major
//! ([`InputSpace::sample_rows_with`], the same draws transposed, for the analyses).

use std::collections::{BTreeMap, BTreeSet};

use nalgebra::{DMatrix, DVector};
use rand::{Rng, SeedableRng};

use crate::cholesky::{factorise_covariance, pivoted_cholesky, smallest_eigenvalue};
use crate::constraint::{LinearInequality, TiltConstraint};
use crate::copula;
use crate::error::{DeviationError, MatrixKind};
use crate::normal::{Ziggurat, ZigguratScratch};
use crate::part::PartSpec;
use crate::scalar::ScalarDistribution;

mod quasi;

/// Most consecutive rejections of one row before the run is abandoned. At the lowest
/// accepted rate (1 %), the chance of reaching it is 0.99^100000 ≈ 1e-437.
const MAX_REJECTIONS_PER_ROW: u64 = 100_000;
/// Lowest acceptance rate of the Eq. 11 constraints that is accepted.
pub const MIN_ACCEPTANCE_RATE: f64 = 0.01;
/// Draws of the deterministic pilot that measures the acceptance rate when building.
const PILOT_DRAWS: u64 = 20_000;

/// Attempts and acceptances of the constraint rejection sampler, per independent group of
/// inequalities.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ConstraintCounts {
    /// (candidate draws, accepted draws) of each group.
    pub groups: Vec<(u64, u64)>,
}

impl ConstraintCounts {
    /// Adds another tally.
    pub fn add(&mut self, other: &ConstraintCounts) {
        if self.groups.len() < other.groups.len() {
            self.groups.resize(other.groups.len(), (0, 0));
        }
        for (mine, theirs) in self.groups.iter_mut().zip(&other.groups) {
            mine.0 += theirs.0;
            mine.1 += theirs.1;
        }
    }

    /// Candidate draws over all groups.
    pub fn attempts(&self) -> u64 {
        self.groups.iter().map(|g| g.0).sum()
    }

    /// Probability that an unconstrained draw satisfies every inequality: the product of
    /// the groups' acceptance rates (1 when nothing was attempted).
    pub fn acceptance_rate(&self) -> f64 {
        self.groups
            .iter()
            .filter(|g| g.0 > 0)
            .map(|g| g.1 as f64 / g.0 as f64)
            .product()
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
    /// Variance of each gaussian column, by gaussian index.
    variance: Vec<f64>,
    /// Covariances between two gaussian columns, keyed by (smaller, larger) gaussian index;
    /// only the non-zero ones.
    cross: BTreeMap<(usize, usize), f64>,
    /// The JSON path of the scenario correlation that set each pair, to refuse a second one.
    correlated_by: BTreeMap<(usize, usize), String>,
    independent: Vec<(usize, ScalarDistribution)>,
    constraints: Vec<ConstraintSpec>,
    /// For each column, its gaussian index, if normal (or a copula column's normal score).
    gaussian_index: Vec<Option<usize>>,
    /// Non-normal scalars drawn through their normal score (the Gaussian copula).
    copula: Vec<(usize, ScalarDistribution)>,
    /// The JSON path of each non-normal scalar, for messages once it is correlated.
    scalar_labels: BTreeMap<usize, String>,
}

/// Most columns one correlated group may hold: its dense covariance and factor take
/// 2·n²·8 bytes (268 MB at 4096) and the factorisation n³/3 multiply-adds (seconds at
/// 4096). Beyond it a scenario is refused before anything is allocated.
pub const MAX_CORRELATED_COLUMNS: usize = 4096;

/// The pair (smaller, larger).
fn ordered(a: usize, b: usize) -> (usize, usize) {
    (a.min(b), a.max(b))
}

impl InputSpaceBuilder {
    /// An empty builder.
    pub fn new() -> Self {
        Self::default()
    }

    fn push_gaussian(&mut self, mean: f64, variance: f64, label: String) -> usize {
        let column = self.n_columns;
        self.n_columns += 1;
        self.gaussian_index.push(Some(self.gaussian.len()));
        self.gaussian.push(GaussianColumn {
            column,
            mean,
            label,
        });
        self.variance.push(variance);
        column
    }

    /// Adds a part (six columns, in the order of [`crate::SixDof::NAMES`]) and returns its
    /// first column. `path` is the part's JSON path, used in messages.
    pub fn add_part(&mut self, path: &str, spec: &PartSpec) -> usize {
        let first = self.n_columns;
        let first_gaussian = self.gaussian.len();
        for i in 0..6 {
            let label = format!("{path}[{}]", crate::SixDof::NAMES[i]);
            self.push_gaussian(spec.mean[i], spec.covariance[i][i], label);
        }
        for i in 0..6 {
            for j in i + 1..6 {
                if spec.covariance[i][j] != 0.0 {
                    self.cross.insert(
                        (first_gaussian + i, first_gaussian + j),
                        spec.covariance[i][j],
                    );
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
            Some((mean, sd)) => self.push_gaussian(mean, sd * sd, path.to_string()),
            None => {
                let column = self.n_columns;
                self.n_columns += 1;
                self.gaussian_index.push(None);
                self.independent.push((column, distribution));
                self.scalar_labels.insert(column, path.to_string());
                column
            }
        }
    }

    /// Correlates two columns with coefficient `rho`; `path` names the entry. A pair may be
    /// correlated once: a second entry for it (with any ρ) is an error naming both. Between
    /// normal columns ρ is their correlation; a non-normal scalar is correlated through its
    /// normal score (the Gaussian copula, [`crate::copula`]), ρ then being the correlation
    /// of the normal scores.
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
                format!("correlation must lie in [-1, 1], got {}", crate::Shown(rho)),
            ));
        }
        if column_a == column_b {
            return Err(DeviationError::invalid(
                path,
                "a variable cannot be correlated with itself",
            ));
        }
        let (Some(a), Some(b)) = (self.normal_score(column_a), self.normal_score(column_b)) else {
            return Err(DeviationError::invalid(path, "no such column to correlate"));
        };
        let key = ordered(a, b);
        if let Some(earlier) = self.correlated_by.get(&key) {
            return Err(DeviationError::invalid(
                path,
                format!("correlates the same pair as {earlier}: give each pair once"),
            ));
        }
        self.correlated_by.insert(key, path.to_string());
        let covariance = rho * self.variance[a].sqrt() * self.variance[b].sqrt();
        // Replaces an earlier entry between the same pair (a part's own covariance).
        self.cross.remove(&key);
        if covariance != 0.0 {
            self.cross.insert(key, covariance);
        }
        Ok(())
    }

    /// The gaussian index of a column: a normal column's own, or, for a non-normal scalar,
    /// that of its normal score, which joins the joint normal (mean 0, variance 1) the
    /// first time the scalar is correlated. `None` for a column that does not exist.
    fn normal_score(&mut self, column: usize) -> Option<usize> {
        if let Some(g) = *self.gaussian_index.get(column)? {
            return Some(g);
        }
        let at = self.independent.iter().position(|(c, _)| *c == column)?;
        let (_, distribution) = self.independent.remove(at);
        let g = self.gaussian.len();
        self.gaussian_index[column] = Some(g);
        self.gaussian.push(GaussianColumn {
            column,
            mean: 0.0,
            label: (self.scalar_labels.get(&column).cloned())
                .unwrap_or_else(|| format!("column {column}")),
        });
        self.variance.push(1.0);
        self.copula.push((column, distribution));
        Some(g)
    }

    /// Number of columns so far.
    pub fn n_columns(&self) -> usize {
        self.n_columns
    }

    /// Factorises the joint covariance block by block and checks the constraints'
    /// acceptance rate. `correlations_path` names the cross-correlations in messages: a
    /// joint covariance that is indefinite only because of them is reported there. Memory
    /// and time grow with the largest correlated group only (a scenario of many independent
    /// variables costs one entry each); a group beyond [`MAX_CORRELATED_COLUMNS`] is refused.
    pub fn build(self, correlations_path: &str) -> Result<InputSpace, DeviationError> {
        let n_g = self.gaussian.len();
        // Connected components of the non-zero pattern (union-find).
        let mut parent: Vec<usize> = (0..n_g).collect();
        fn find(parent: &mut [usize], mut x: usize) -> usize {
            while parent[x] != x {
                parent[x] = parent[parent[x]];
                x = parent[x];
            }
            x
        }
        for &(a, b) in self.cross.keys() {
            let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
            if ra != rb {
                parent[ra.max(rb)] = ra.min(rb);
            }
        }
        let mut components: Vec<Vec<usize>> = Vec::new();
        let mut component_of_root = vec![usize::MAX; n_g];
        let mut component_of = vec![0; n_g];
        for (g, component) in component_of.iter_mut().enumerate() {
            let root = find(&mut parent, g);
            if component_of_root[root] == usize::MAX {
                component_of_root[root] = components.len();
                components.push(Vec::new());
            }
            *component = component_of_root[root];
            components[component_of_root[root]].push(g);
        }
        if let Some(largest) = components.iter().max_by_key(|c| c.len()) {
            if largest.len() > MAX_CORRELATED_COLUMNS {
                let n = largest.len() as f64;
                return Err(DeviationError::invalid(
                    correlations_path,
                    format!(
                        "{} normal columns are correlated into one group (starting at {}); at most {MAX_CORRELATED_COLUMNS} can be: its covariance factor would need {} and about {:.1e} multiply-adds. Correlate fewer columns, or split them into independent groups",
                        largest.len(),
                        self.gaussian[largest[0]].label,
                        crate::human_bytes(2.0 * n * n * 8.0),
                        n * n * n / 3.0
                    ),
                ));
            }
        }
        let mut position = vec![0; n_g];
        for members in &components {
            for (p, &g) in members.iter().enumerate() {
                position[g] = p;
            }
        }
        let mut matrices: Vec<Option<DMatrix<f64>>> = components
            .iter()
            .map(|members| {
                (members.len() > 1).then(|| {
                    DMatrix::from_fn(members.len(), members.len(), |i, j| {
                        if i == j {
                            self.variance[members[i]]
                        } else {
                            0.0
                        }
                    })
                })
            })
            .collect();
        for (&(a, b), &v) in &self.cross {
            if let Some(matrix) = &mut matrices[component_of[a]] {
                let (i, j) = (position[a], position[b]);
                matrix[(i, j)] = v;
                matrix[(j, i)] = v;
            }
        }
        let inequalities: Vec<LinearInequality> = self
            .constraints
            .iter()
            .flat_map(|c| c.constraint.inequalities(c.first_column))
            .collect();
        let constrained_columns: BTreeSet<usize> =
            inequalities.iter().flat_map(|q| q.columns).collect();
        let mut constrained_blocks: Vec<GaussianBlock> = Vec::new();
        let mut covariance_position = vec![None; self.n_columns];
        let mut covariance_blocks = Vec::new();
        let mut variances = vec![0.0; self.n_columns];
        for (g, column) in self.gaussian.iter().enumerate() {
            variances[column.column] = self.variance[g];
        }
        for (column, distribution) in self.independent.iter().chain(&self.copula) {
            variances[*column] = distribution.variance();
        }
        let mut hermite = vec![None; self.n_columns];
        for (column, distribution) in &self.copula {
            hermite[*column] = Some(copula::hermite_coefficients(|z| {
                distribution.from_normal_score(z)
            }));
        }
        let mut space = InputSpace {
            n_columns: self.n_columns,
            fixed: Vec::new(),
            singles: Vec::new(),
            blocks: Vec::new(),
            constrained_groups: Vec::new(),
            independent: self.independent,
            copula: self.copula,
            hermite,
            constraint_paths: self.constraints.iter().map(|c| c.path.clone()).collect(),
            constraint_inequalities: inequalities.clone(),
            gaussian_columns: self.gaussian.iter().map(|g| g.column).collect(),
            gaussian_mean: self.gaussian.iter().map(|g| g.mean).collect(),
            variances,
            covariance_position: Vec::new(),
            covariance_blocks: Vec::new(),
            covariance_group_columns: Vec::new(),
            max_rank: 0,
            quasi: quasi::QuasiLayout::default(),
        };
        for (members, matrix) in components.into_iter().zip(matrices) {
            let columns: Vec<usize> = members.iter().map(|&g| self.gaussian[g].column).collect();
            let means: Vec<f64> = members.iter().map(|&g| self.gaussian[g].mean).collect();
            let factor = match &matrix {
                Some(sub) => {
                    factorise_covariance(correlations_path, sub).map_err(|err| match err {
                        // The user wrote correlations: the message names them, with the
                        // smallest eigenvalue of the joint correlation matrix (a covariance
                        // scaled by its standard deviations keeps its signs of eigenvalues).
                        DeviationError::Indefinite {
                            smallest_eigenvalue: computed,
                            ..
                        } => DeviationError::Indefinite {
                            path: format!(
                                "{correlations_path} (joint correlation of {})",
                                joint_labels(
                                    members.iter().map(|&g| self.gaussian[g].label.as_str())
                                )
                            ),
                            matrix: MatrixKind::Correlation,
                            smallest_eigenvalue: computed
                                .map(|_| smallest_eigenvalue(&correlation_of(sub))),
                        },
                        other => other,
                    })?
                }
                None => pivoted_cholesky(&DMatrix::from_element(1, 1, self.variance[members[0]])),
            };
            if let Some(sub) = matrix {
                for (p, &column) in columns.iter().enumerate() {
                    covariance_position[column] = Some((covariance_blocks.len(), p));
                }
                covariance_blocks.push(sub);
                space.covariance_group_columns.push(columns.clone());
            }
            let constrained = columns.iter().any(|c| constrained_columns.contains(c));
            if factor.rank == 0 {
                space
                    .fixed
                    .extend(columns.iter().copied().zip(means.iter().copied()));
                continue;
            }
            space.max_rank = space.max_rank.max(factor.rank);
            if columns.len() == 1 && !constrained {
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
                constrained_blocks.push(block);
            } else {
                space.blocks.push(block);
            }
        }
        space.covariance_position = covariance_position;
        space.covariance_blocks = covariance_blocks;
        space.constrained_groups = group_inequalities(inequalities, constrained_blocks);
        space.measure_acceptance()?;
        space.quasi = quasi::QuasiLayout::new(&space);
        Ok(space)
    }
}

/// The correlation matrix of a covariance: each entry over the standard deviations of its
/// row and column (a column of zero variance keeps its zero row and column).
fn correlation_of(covariance: &DMatrix<f64>) -> DMatrix<f64> {
    let sd: Vec<f64> = (0..covariance.nrows())
        .map(|i| covariance[(i, i)].max(0.0).sqrt())
        .collect();
    DMatrix::from_fn(covariance.nrows(), covariance.ncols(), |i, j| {
        if sd[i] > 0.0 && sd[j] > 0.0 {
            covariance[(i, j)] / (sd[i] * sd[j])
        } else {
            0.0
        }
    })
}

/// The labels of a correlated group for a message: all of them up to 8, else the first
/// 8 and how many more.
fn joint_labels<'a>(labels: impl ExactSizeIterator<Item = &'a str>) -> String {
    let n = labels.len();
    let shown: Vec<&str> = labels.take(8).collect();
    if n > shown.len() {
        format!("{} and {} more", shown.join(", "), n - shown.len())
    } else {
        shown.join(", ")
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
    fn draw<R: Rng + ?Sized>(
        &self,
        normal: &Ziggurat,
        rng: &mut R,
        z: &mut [f64],
        row: &mut [f64],
    ) {
        let z = &mut z[..self.rank];
        for value in z.iter_mut() {
            *value = normal.sample(rng);
        }
        self.apply(z, row);
    }

    /// Component `i` of μ + L·z (`z` holds `rank` draws).
    #[inline]
    fn component(&self, i: usize, z: &[f64]) -> f64 {
        let factor_row = &self.factor[i * self.rank..(i + 1) * self.rank];
        let mut value = self.means[i];
        for (l, zk) in factor_row.iter().zip(z.iter()) {
            value += l * zk;
        }
        value
    }

    /// Writes μ + L·z into the block's columns of `row`.
    #[inline]
    fn apply(&self, z: &[f64], row: &mut [f64]) {
        for (i, &column) in self.columns.iter().enumerate() {
            row[column] = self.component(i, z);
        }
    }

    /// Writes μ + L·z into the block's columns of row `r` of a column-major block.
    #[inline]
    fn apply_to_columns(&self, z: &[f64], columns: &mut [f64], n_rows: usize, r: usize) {
        for (i, &column) in self.columns.iter().enumerate() {
            columns[column * n_rows + r] = self.component(i, z);
        }
    }
}

/// Inequalities that share blocks, with those blocks: one rejection loop.
#[derive(Debug, Clone)]
struct ConstrainedGroup {
    /// Independent 1×1 blocks: (column, mean, sd).
    singles: Vec<(usize, f64, f64)>,
    /// Dense blocks.
    blocks: Vec<GaussianBlock>,
    inequalities: Vec<LinearInequality>,
    /// The inequalities over candidate slots, when the group holds only singles (the
    /// diagonal covariance of 001 Eq. 12): drawn for all the rows of a call at once
    /// without data-dependent branches.
    slot_inequalities: Option<Vec<LinearInequality>>,
    /// The rotated form, when the group is one inequality over two singles (each half of
    /// 001 Eq. 11 for a diagonal covariance).
    pair: Option<RotatedPair>,
    /// Acceptance rate measured by the build's pilot: sizes the candidate batches.
    pilot_acceptance: f64,
}

/// Candidates drawn for `remaining` unfilled rows at acceptance rate `acceptance`: the
/// expected number needed plus two, so that most blocks fill in one batch and few
/// candidates are left over (they are discarded; the stream stays deterministic).
fn batch_size(remaining: usize, acceptance: f64) -> usize {
    (remaining as f64 / acceptance.max(MIN_ACCEPTANCE_RATE)).ceil() as usize + 2
}

/// One inequality a·x + b·y ≤ c over two independent normals x ~ N(μx, σx²),
/// y ~ N(μy, σy²), drawn without rejecting the direction it does not constrain. With
/// u = (x − μx)/σx, v = (y − μy)/σy and σs = √(a²σx² + b²σy²), the rotation
/// z_s = c1·u + c2·v, z_t = −c2·u + c1·v (c1 = aσx/σs, c2 = bσy/σs) gives independent
/// standard normals with a·x + b·y = μs + σs·z_s. The inequality is z_s ≤ τ =
/// (c − μs)/σs, so only z_s is redrawn until it holds; z_t is drawn once, and
/// u = c1·z_s − c2·z_t, v = c2·z_s + c1·z_t. The joint law is the same as redrawing
/// (x, y) together (the conditioned normal), at one draw fewer per accepted row for a
/// 50 % acceptance.
#[derive(Debug, Clone, Copy)]
struct RotatedPair {
    columns: [usize; 2],
    means: [f64; 2],
    sds: [f64; 2],
    /// (c1, c2).
    rotation: [f64; 2],
    /// τ, the bound on z_s.
    threshold: f64,
}

impl RotatedPair {
    fn new(singles: &[(usize, f64, f64)], q: &LinearInequality) -> Option<RotatedPair> {
        let [(cx, mx, sx), (cy, my, sy)] = match singles {
            [first, second] if first.0 == q.columns[0] && second.0 == q.columns[1] => {
                [*first, *second]
            }
            [first, second] if first.0 == q.columns[1] && second.0 == q.columns[0] => {
                [*second, *first]
            }
            _ => return None,
        };
        let [a, b] = q.coefficients;
        let sigma_s = (a * sx).hypot(b * sy);
        if !(sigma_s > 0.0 && sigma_s.is_finite()) {
            return None;
        }
        Some(RotatedPair {
            columns: [cx, cy],
            means: [mx, my],
            sds: [sx, sy],
            rotation: [a * sx / sigma_s, b * sy / sigma_s],
            threshold: (q.bound - a * mx - b * my) / sigma_s,
        })
    }

    /// Fills the pair's columns of every row of a column-major block of `n_rows` rows;
    /// returns the candidate draws of z_s, or `Err` after [`MAX_REJECTIONS_PER_ROW`]
    /// consecutive rejections. Stream: batches of z_s candidates ([`batch_size`] for the
    /// rows still unfilled; those left once every row is filled are discarded) until every
    /// row is filled; then z_t.
    fn fill_rows<R: Rng + ?Sized>(
        &self,
        acceptance: f64,
        normal: &Ziggurat,
        rng: &mut R,
        columns: &mut [f64],
        n_rows: usize,
        scratch: &mut SamplerScratch,
    ) -> Result<u64, ()> {
        let SamplerScratch {
            candidates,
            accepted,
            ziggurat,
            ..
        } = scratch;
        // Room for every candidate of the last batch past the rows: the candidates drawn
        // after the last row is filled land there and are discarded.
        let accepted_z = prefix(accepted, n_rows + batch_size(n_rows, acceptance));
        let (mut filled, mut attempts, mut rejected_run) = (0, 0u64, 0u64);
        while filled < n_rows {
            let needed = n_rows - filled;
            let batch = prefix(candidates, batch_size(needed, acceptance));
            normal.fill(rng, batch, ziggurat);
            let start = filled;
            for &z in batch.iter() {
                // Branch-free compaction: each candidate goes to the next unfilled row,
                // which advances only on acceptance.
                accepted_z[filled] = z;
                filled += usize::from(z <= self.threshold);
            }
            if filled - start >= needed {
                // Attempts end at the candidate that filled the last row.
                let mut seen = 0;
                let last = batch
                    .iter()
                    .position(|&z| {
                        seen += usize::from(z <= self.threshold);
                        seen == needed
                    })
                    .expect("the batch accepted enough candidates");
                attempts += last as u64 + 1;
                filled = n_rows;
            } else {
                attempts += batch.len() as u64;
                // Consecutive rejections, counted in whole batches that accepted none.
                rejected_run = if filled == start {
                    rejected_run + batch.len() as u64
                } else {
                    0
                };
                if rejected_run >= MAX_REJECTIONS_PER_ROW {
                    return Err(());
                }
            }
        }
        let free_z = prefix(candidates, n_rows);
        normal.fill(rng, free_z, ziggurat);
        let [c1, c2] = self.rotation;
        let [cx, cy] = self.columns;
        let (z_s, z_t) = (&accepted_z[..n_rows], &free_z[..n_rows]);
        for ((x, &z_s), &z_t) in column_mut(columns, cx, n_rows).iter_mut().zip(z_s).zip(z_t) {
            *x = self.means[0] + self.sds[0] * (c1 * z_s - c2 * z_t);
        }
        for ((y, &z_s), &z_t) in column_mut(columns, cy, n_rows).iter_mut().zip(z_s).zip(z_t) {
            *y = self.means[1] + self.sds[1] * (c2 * z_s + c1 * z_t);
        }
        Ok(attempts)
    }
}

/// Column `column` of a column-major block of `n_rows` rows.
#[inline]
fn column_mut(columns: &mut [f64], column: usize, n_rows: usize) -> &mut [f64] {
    &mut columns[column * n_rows..(column + 1) * n_rows]
}

/// The first `n` values of `buffer`, grown (never shrunk) as needed: no memset per call.
fn prefix(buffer: &mut Vec<f64>, n: usize) -> &mut [f64] {
    if buffer.len() < n {
        buffer.resize(n, 0.0);
    }
    &mut buffer[..n]
}

/// Reusable buffers of [`InputSpace::sample_columns_with`] and
/// [`InputSpace::sample_rows_with`], so a hot loop that samples block after block does not
/// allocate.
#[derive(Debug, Clone, Default)]
pub struct SamplerScratch {
    normals: Vec<f64>,
    candidates: Vec<f64>,
    accepted: Vec<f64>,
    block_z: Vec<f64>,
    /// One row of a group drawn by per-row rejection.
    row: Vec<f64>,
    /// The column-major block of [`InputSpace::sample_rows_with`] before it is transposed.
    columns: Vec<f64>,
    ziggurat: ZigguratScratch,
}

/// Most singles a group may hold for the chunk-wide candidate path.
const MAX_SLOT_SINGLES: usize = 8;

impl ConstrainedGroup {
    /// Fills this group's columns of every row by rejection, for a group of singles only:
    /// each candidate is written to the next unfilled row, whose index advances only when
    /// the candidate satisfies every inequality (branch-free compaction, so a 50 %
    /// acceptance costs no branch mispredictions). Stream: batches of candidates
    /// ([`batch_size`] for the rows still unfilled, each candidate's draws consecutive;
    /// those left once every row is filled are discarded). Returns candidate draws.
    fn fill_rows_of_singles<R: Rng + ?Sized>(
        &self,
        slot_inequalities: &[LinearInequality],
        normal: &Ziggurat,
        rng: &mut R,
        columns: &mut [f64],
        n_rows: usize,
        scratch: &mut SamplerScratch,
    ) -> Result<u64, ()> {
        let k = self.singles.len();
        let mut candidate = [0.0f64; MAX_SLOT_SINGLES];
        let (mut filled, mut attempts, mut consecutive, mut too_many) = (0, 0u64, 0u64, false);
        while filled < n_rows {
            let batch = batch_size(n_rows - filled, self.pilot_acceptance);
            let draws = prefix(&mut scratch.candidates, batch * k);
            normal.fill(rng, draws, &mut scratch.ziggurat);
            for z in draws.chunks_exact(k) {
                if filled == n_rows {
                    break;
                }
                for ((value, &(_, mean, sd)), &z) in candidate.iter_mut().zip(&self.singles).zip(z)
                {
                    *value = mean + sd * z;
                }
                let accepted = slot_inequalities
                    .iter()
                    .fold(true, |all, q| all & q.holds(&candidate));
                for (value, &(column, _, _)) in candidate.iter().zip(&self.singles) {
                    columns[column * n_rows + filled] = *value;
                }
                attempts += 1;
                filled += usize::from(accepted);
                consecutive = (consecutive + 1) * u64::from(!accepted);
                too_many |= consecutive >= MAX_REJECTIONS_PER_ROW;
            }
            if too_many {
                return Err(());
            }
        }
        Ok(attempts)
    }
}

impl ConstrainedGroup {
    #[inline]
    fn draw_candidate<R: Rng + ?Sized>(
        &self,
        normal: &Ziggurat,
        rng: &mut R,
        z: &mut [f64],
        row: &mut [f64],
    ) -> bool {
        for &(column, mean, sd) in &self.singles {
            row[column] = mean + sd * normal.sample(rng);
        }
        for block in &self.blocks {
            block.draw(normal, rng, z, row);
        }
        self.inequalities.iter().all(|q| q.holds(row))
    }
}

/// Splits inequalities into groups that share no block (union-find over shared blocks).
fn group_inequalities(
    inequalities: Vec<LinearInequality>,
    blocks: Vec<GaussianBlock>,
) -> Vec<ConstrainedGroup> {
    let blocks_of = |q: &LinearInequality| -> Vec<usize> {
        blocks
            .iter()
            .enumerate()
            .filter(|(_, b)| b.columns.iter().any(|c| q.columns.contains(c)))
            .map(|(i, _)| i)
            .collect()
    };
    let mut group_of_block: Vec<Option<usize>> = vec![None; blocks.len()];
    let mut groups: Vec<(Vec<usize>, Vec<LinearInequality>)> = Vec::new();
    for q in inequalities {
        let touched = blocks_of(&q);
        let mut existing: Vec<usize> = touched.iter().filter_map(|&b| group_of_block[b]).collect();
        existing.sort_unstable();
        existing.dedup();
        let target = match existing.first() {
            Some(&g) => g,
            None => {
                groups.push((Vec::new(), Vec::new()));
                groups.len() - 1
            }
        };
        // Merge every other touched group into the target.
        for &g in existing.iter().skip(1).rev() {
            let (moved_blocks, moved_inequalities) = std::mem::take(&mut groups[g]);
            for &b in &moved_blocks {
                group_of_block[b] = Some(target);
            }
            groups[target].0.extend(moved_blocks);
            groups[target].1.extend(moved_inequalities);
        }
        for b in touched {
            if group_of_block[b].is_none() {
                group_of_block[b] = Some(target);
                groups[target].0.push(b);
            }
        }
        groups[target].1.push(q);
    }
    let mut slots: Vec<Option<GaussianBlock>> = blocks.into_iter().map(Some).collect();
    groups
        .into_iter()
        .filter(|(_, inequalities)| !inequalities.is_empty())
        .map(|(block_indices, inequalities)| {
            let (singles, blocks): (Vec<GaussianBlock>, Vec<GaussianBlock>) = block_indices
                .into_iter()
                .filter_map(|b| slots[b].take())
                .partition(|b| b.columns.len() == 1 && b.rank == 1);
            let singles: Vec<(usize, f64, f64)> = singles
                .iter()
                .map(|b| (b.columns[0], b.means[0], b.factor[0]))
                .collect();
            let slot_of = |column: usize| singles.iter().position(|s| s.0 == column);
            let slot_inequalities = (blocks.is_empty() && singles.len() <= MAX_SLOT_SINGLES)
                .then(|| {
                    inequalities
                        .iter()
                        .map(|q| {
                            Some(LinearInequality {
                                columns: [slot_of(q.columns[0])?, slot_of(q.columns[1])?],
                                ..*q
                            })
                        })
                        .collect::<Option<Vec<_>>>()
                })
                .flatten();
            let pair = match (blocks.is_empty(), inequalities.as_slice()) {
                (true, [q]) => RotatedPair::new(&singles, q),
                _ => None,
            };
            ConstrainedGroup {
                singles,
                blocks,
                inequalities,
                slot_inequalities,
                pair,
                pilot_acceptance: 1.0,
            }
        })
        .collect()
}

/// A built input space: draws sample rows of `n_columns()` values.
#[derive(Debug, Clone)]
pub struct InputSpace {
    n_columns: usize,
    fixed: Vec<(usize, f64)>,
    singles: Vec<(usize, f64, f64)>,
    blocks: Vec<GaussianBlock>,
    constrained_groups: Vec<ConstrainedGroup>,
    independent: Vec<(usize, ScalarDistribution)>,
    /// Non-normal scalars drawn through their normal score, which the sampler draws in
    /// their column first (the Gaussian copula, [`crate::copula`]).
    copula: Vec<(usize, ScalarDistribution)>,
    /// For each copula column, the Hermite coefficients of its value as a function of its
    /// normal score (for [`InputSpace::covariance`]).
    hermite: Vec<Option<Vec<f64>>>,
    constraint_paths: Vec<String>,
    /// The inequalities of the constraints, two per constrained part in the order of
    /// `constraint_paths`.
    constraint_inequalities: Vec<LinearInequality>,
    /// The normal columns and their means, in the order they were added.
    gaussian_columns: Vec<usize>,
    gaussian_mean: Vec<f64>,
    /// Variance of every column (normal or not).
    variances: Vec<f64>,
    /// For each column in a correlated group: (group, position in its matrix).
    covariance_position: Vec<Option<(usize, usize)>>,
    /// The covariance matrix of each correlated group (columns of independent normals and
    /// non-normal scalars have none: their covariance with anything else is 0).
    covariance_blocks: Vec<DMatrix<f64>>,
    /// The columns of each correlated group, in the order of its matrix.
    covariance_group_columns: Vec<Vec<usize>>,
    max_rank: usize,
    /// How rows are drawn from uniform points (`quasi.rs`).
    quasi: quasi::QuasiLayout,
}

impl InputSpace {
    /// Columns per row.
    pub fn n_columns(&self) -> usize {
        self.n_columns
    }

    /// Whether any part carries the Eq. 11 constraint.
    pub fn has_constraints(&self) -> bool {
        !self.constraint_paths.is_empty()
    }

    /// A tally with one slot per independent constraint group.
    pub fn new_constraint_counts(&self) -> ConstraintCounts {
        ConstraintCounts {
            groups: vec![(0, 0); self.constrained_groups.len()],
        }
    }

    /// The share of unconstrained draws that satisfy every inequality, as measured by the
    /// build's deterministic pilot (product over the independent groups).
    pub fn pilot_acceptance_rate(&self) -> f64 {
        self.constrained_groups
            .iter()
            .map(|g| g.pilot_acceptance)
            .product()
    }

    /// The constraints' inequalities over the columns of a row (001 Eq. 11): two per
    /// constrained part, in the order of [`InputSpace::constraint_paths`].
    pub fn inequalities(&self) -> &[LinearInequality] {
        &self.constraint_inequalities
    }

    /// JSON paths of the constrained parts.
    pub fn constraint_paths(&self) -> &[String] {
        &self.constraint_paths
    }

    /// The normal columns (part components, normal and tolerance-band scalars, and the
    /// normal scores of the copula columns), in the order they were added.
    pub fn gaussian_columns(&self) -> &[usize] {
        &self.gaussian_columns
    }

    /// The covariance of two columns' values as specified, before the constraints: the
    /// variance on the diagonal (of any distribution), the scenario's covariance between
    /// two normal columns of one correlated group, Mehler's series where a copula column
    /// takes part (`copula.rs`: exact with a normal partner, a truncated series between
    /// two non-normal laws), 0 otherwise.
    pub fn covariance(&self, column_a: usize, column_b: usize) -> f64 {
        if column_a == column_b {
            return self.variances[column_a];
        }
        // One order for the series, so that the matrix is symmetric to the bit.
        let (column_a, column_b) = (column_a.min(column_b), column_a.max(column_b));
        let latent = self.latent_covariance(column_a, column_b);
        let (ha, hb) = (&self.hermite[column_a], &self.hermite[column_b]);
        if latent == 0.0 || (ha.is_none() && hb.is_none()) {
            return latent;
        }
        let (sa, sb) = (
            self.latent_covariance(column_a, column_a).sqrt(),
            self.latent_covariance(column_b, column_b).sqrt(),
        );
        // A normal column is its normal score times σ: one coefficient, σ.
        let (one_a, one_b) = ([sa], [sb]);
        copula::mehler_covariance(
            ha.as_deref().unwrap_or(&one_a),
            hb.as_deref().unwrap_or(&one_b),
            latent / (sa * sb),
        )
    }

    /// The covariance of two columns in the space the sampler draws them: a copula
    /// column's normal score (variance 1) in place of its value; the value's covariance
    /// for every other column.
    pub(crate) fn latent_covariance(&self, column_a: usize, column_b: usize) -> f64 {
        match (
            self.covariance_position[column_a],
            self.covariance_position[column_b],
        ) {
            (Some((group_a, i)), Some((group_b, j))) if group_a == group_b => {
                self.covariance_blocks[group_a][(i, j)]
            }
            _ if column_a == column_b => match self.hermite[column_a] {
                Some(_) => 1.0,
                None => self.variances[column_a],
            },
            _ => 0.0,
        }
    }

    /// Whether the scenario makes two columns dependent (a non-zero correlation between
    /// them, of their values or their normal scores).
    pub fn dependent(&self, column_a: usize, column_b: usize) -> bool {
        column_a != column_b && self.latent_covariance(column_a, column_b) != 0.0
    }

    /// The non-normal scalars that the scenario correlates, drawn through their normal
    /// score (the Gaussian copula), with their laws.
    pub fn copula_columns(&self) -> &[(usize, ScalarDistribution)] {
        &self.copula
    }

    /// The normal columns, their mean vector and their dense joint covariance (as specified,
    /// before the constraints), built on demand: for tests and diagnostics of small spaces
    /// (it takes (number of normal columns)² values). A copula column enters as its normal
    /// score (mean 0, variance 1).
    pub fn gaussian_specification(&self) -> (Vec<usize>, DVector<f64>, DMatrix<f64>) {
        let columns = &self.gaussian_columns;
        (
            columns.clone(),
            DVector::from_column_slice(&self.gaussian_mean),
            DMatrix::from_fn(columns.len(), columns.len(), |i, j| {
                self.latent_covariance(columns[i], columns[j])
            }),
        )
    }

    /// Whether a column varies (has a positive variance).
    pub fn is_random(&self, column: usize) -> bool {
        self.variances[column] > 0.0
    }

    /// The covariance matrix of the given columns ([`InputSpace::covariance`] entry by entry).
    pub fn covariance_matrix(&self, columns: &[usize]) -> DMatrix<f64> {
        DMatrix::from_fn(columns.len(), columns.len(), |i, j| {
            self.covariance(columns[i], columns[j])
        })
    }

    /// The columns correlated with `column` (its correlated group, itself included); just
    /// itself when it is correlated with nothing.
    pub fn correlated_columns(&self, column: usize) -> Vec<usize> {
        match self.covariance_position[column] {
            Some((group, _)) => self.covariance_group_columns[group].clone(),
            None => vec![column],
        }
    }

    /// The groups of two or more normal columns that the scenario correlates (connected
    /// through non-zero covariances), each as its columns.
    pub fn correlated_groups(&self) -> &[Vec<usize>] {
        &self.covariance_group_columns
    }

    /// The non-normal scalar columns with their distributions.
    pub fn independent_columns(&self) -> &[(usize, ScalarDistribution)] {
        &self.independent
    }

    /// The row of means: every normal column at its mean, every other scalar at its mean
    /// (the constraint is not applied: the Eq. 10 mean lies on its boundary).
    pub fn mean_row(&self) -> Vec<f64> {
        let mut row = vec![0.0; self.n_columns];
        for (&column, &mean) in self.gaussian_columns.iter().zip(&self.gaussian_mean) {
            row[column] = mean;
        }
        for (column, distribution) in self.independent.iter().chain(&self.copula) {
            row[*column] = distribution.mean();
        }
        row
    }

    /// The row of means in the space the sampler draws: [`InputSpace::mean_row`] with a
    /// copula column's normal score at its mean, 0.
    pub(crate) fn latent_mean_row(&self) -> Vec<f64> {
        let mut row = self.mean_row();
        for (column, _) in &self.copula {
            row[*column] = 0.0;
        }
        row
    }

    /// Turns the copula columns of a row drawn in the latent space
    /// ([`InputSpace::sample_latent_rows`], [`crate::ConditionalSampler`]) from normal scores
    /// into values; every other column is its value already.
    pub fn latent_to_values(&self, row: &mut [f64]) {
        for (column, distribution) in &self.copula {
            row[*column] = distribution.from_normal_score(row[*column]);
        }
    }

    /// Turns the copula columns of a column-major block of `n_rows` rows from normal
    /// scores into values.
    fn copula_to_values(&self, columns: &mut [f64], n_rows: usize) {
        for (column, distribution) in &self.copula {
            for x in column_mut(columns, *column, n_rows) {
                *x = distribution.from_normal_score(*x);
            }
        }
    }

    /// Fills `rows` (row-major, a multiple of `n_columns()` long) with independent draws.
    /// Fails only when a constraint rejects 100 000 draws in a row.
    pub fn sample_rows<R: Rng + ?Sized>(
        &self,
        rng: &mut R,
        rows: &mut [f64],
        counts: &mut ConstraintCounts,
    ) -> Result<(), DeviationError> {
        self.sample_rows_with(rng, rows, counts, &mut SamplerScratch::default())
    }

    /// [`InputSpace::sample_rows`] with caller-owned buffers (no allocation once they have
    /// grown to the block size): [`InputSpace::sample_columns_with`], then transposed to
    /// rows. The same stream gives the same values in either layout.
    pub fn sample_rows_with<R: Rng + ?Sized>(
        &self,
        rng: &mut R,
        rows: &mut [f64],
        counts: &mut ConstraintCounts,
        scratch: &mut SamplerScratch,
    ) -> Result<(), DeviationError> {
        self.draw_rows(rng, rows, counts, scratch, false)
    }

    /// [`InputSpace::sample_rows`] in the space the sampler draws: the copula columns hold
    /// their normal scores (the same stream; [`InputSpace::latent_to_values`] turns them
    /// into the values [`InputSpace::sample_rows`] gives). For conditional draws
    /// ([`crate::ConditionalSampler`]), which condition the normal scores.
    pub fn sample_latent_rows<R: Rng + ?Sized>(
        &self,
        rng: &mut R,
        rows: &mut [f64],
        counts: &mut ConstraintCounts,
    ) -> Result<(), DeviationError> {
        self.draw_rows(rng, rows, counts, &mut SamplerScratch::default(), true)
    }

    fn draw_rows<R: Rng + ?Sized>(
        &self,
        rng: &mut R,
        rows: &mut [f64],
        counts: &mut ConstraintCounts,
        scratch: &mut SamplerScratch,
        latent: bool,
    ) -> Result<(), DeviationError> {
        if self.n_columns == 0 {
            return Ok(());
        }
        let n_rows = rows.len() / self.n_columns;
        let mut columns = std::mem::take(&mut scratch.columns);
        let block = prefix(&mut columns, n_rows * self.n_columns);
        let drawn = self.sample_latent_columns(rng, block, counts, scratch);
        if !latent {
            self.copula_to_values(block, n_rows);
        }
        if drawn.is_ok() {
            for (c, column) in block.chunks_exact(n_rows.max(1)).enumerate() {
                for (row, &value) in rows.chunks_exact_mut(self.n_columns).zip(column) {
                    row[c] = value;
                }
            }
        }
        scratch.columns = columns;
        drawn
    }

    /// Fills a column-major block (`columns[c·n + r]` is column c of row r, n =
    /// `columns.len() / n_columns()` rows) with independent draws: the layout of the run's
    /// hot loop, where each column is contiguous for the models. Fails only when a
    /// constraint rejects 100 000 draws in a row.
    ///
    /// Stream layout (part of the reproducibility contract, through the run's chunks):
    /// 1. the standard normals of every unconstrained single and block as one
    ///    [`Ziggurat::fill`]: each single's draws for all rows in turn, then each block's
    ///    draws, `rank` per row, row after row;
    /// 2. the non-normal scalars drawn by their inverse CDF (uniform, triangular, truncated
    ///    normal), row after row;
    /// 3. the magnitude laws (folded normal, Rayleigh, lognormal), column after column,
    ///    each from one [`Ziggurat::fill`] of its normals for all rows (two per row for the
    ///    Rayleigh law, consecutive);
    /// 4. each constraint group in turn: batches of candidates (the rotated z_s of a pair and
    ///    the compaction of singles), or row by row for groups with dense blocks.
    ///
    /// A copula column's normal score is drawn with its block; its value is F⁻¹(Φ(z)) of
    /// that draw (no further stream).
    pub fn sample_columns_with<R: Rng + ?Sized>(
        &self,
        rng: &mut R,
        columns: &mut [f64],
        counts: &mut ConstraintCounts,
        scratch: &mut SamplerScratch,
    ) -> Result<(), DeviationError> {
        self.sample_latent_columns(rng, columns, counts, scratch)?;
        self.copula_to_values(columns, columns.len() / self.n_columns.max(1));
        Ok(())
    }

    /// [`InputSpace::sample_columns_with`] with the copula columns left as normal scores.
    fn sample_latent_columns<R: Rng + ?Sized>(
        &self,
        rng: &mut R,
        columns: &mut [f64],
        counts: &mut ConstraintCounts,
        scratch: &mut SamplerScratch,
    ) -> Result<(), DeviationError> {
        if self.n_columns == 0 {
            return Ok(());
        }
        let normal = Ziggurat::get();
        let n_rows = columns.len() / self.n_columns;
        let block_draws: usize = self.blocks.iter().map(|b| b.rank).sum();
        let n_free = self.singles.len() + block_draws;
        let z = prefix(&mut scratch.normals, n_rows * n_free);
        normal.fill(rng, z, &mut scratch.ziggurat);
        let (single_z, block_z) = z.split_at(n_rows * self.singles.len());
        for &(column, mean) in &self.fixed {
            column_mut(columns, column, n_rows).fill(mean);
        }
        // Singles column by column: their draws are laid out one column after another.
        for (&(column, mean, sd), z) in self
            .singles
            .iter()
            .zip(single_z.chunks_exact(n_rows.max(1)))
        {
            for (x, &z) in column_mut(columns, column, n_rows).iter_mut().zip(z) {
                *x = mean + sd * z;
            }
        }
        // Blocks row by row: each row's `rank` draws of a block are consecutive.
        let mut block_z = block_z;
        for block in &self.blocks {
            let (this, rest) = block_z.split_at(n_rows * block.rank);
            for (r, z) in this.chunks_exact(block.rank).enumerate() {
                block.apply_to_columns(z, columns, n_rows, r);
            }
            block_z = rest;
        }
        if self
            .independent
            .iter()
            .any(|(_, d)| d.normals_per_draw() == 0)
        {
            for r in 0..n_rows {
                for (column, distribution) in &self.independent {
                    if distribution.normals_per_draw() == 0 {
                        columns[column * n_rows + r] = distribution.sample(rng);
                    }
                }
            }
        }
        // The magnitude laws, column after column, each from one block of normals.
        for (column, distribution) in &self.independent {
            let k = distribution.normals_per_draw();
            if k == 0 {
                continue;
            }
            let z = prefix(&mut scratch.normals, k * n_rows);
            normal.fill(rng, z, &mut scratch.ziggurat);
            for (x, z) in column_mut(columns, *column, n_rows)
                .iter_mut()
                .zip(z.chunks_exact(k))
            {
                *x = distribution.from_normals(z);
            }
        }
        if counts.groups.len() < self.constrained_groups.len() {
            counts.groups.resize(self.constrained_groups.len(), (0, 0));
        }
        for (group, tally) in self.constrained_groups.iter().zip(counts.groups.iter_mut()) {
            let attempts = if let Some(pair) = &group.pair {
                pair.fill_rows(
                    group.pilot_acceptance,
                    normal,
                    rng,
                    columns,
                    n_rows,
                    scratch,
                )
                .map_err(|()| self.rejection_error())?
            } else if let Some(slot_inequalities) = &group.slot_inequalities {
                group
                    .fill_rows_of_singles(slot_inequalities, normal, rng, columns, n_rows, scratch)
                    .map_err(|()| self.rejection_error())?
            } else {
                scratch.block_z.resize(self.max_rank.max(1), 0.0);
                // A row for the candidates: the group's columns are drawn into it; an
                // inequality may also read a fixed column, which holds its mean.
                let row = prefix(&mut scratch.row, self.n_columns);
                for &(column, mean) in &self.fixed {
                    row[column] = mean;
                }
                let mut attempts = 0;
                for r in 0..n_rows {
                    attempts += self.draw_group_by_rejection(
                        group,
                        normal,
                        rng,
                        &mut scratch.block_z,
                        row,
                    )?;
                    let group_columns = group
                        .singles
                        .iter()
                        .map(|single| &single.0)
                        .chain(group.blocks.iter().flat_map(|block| &block.columns));
                    for &column in group_columns {
                        columns[column * n_rows + r] = row[column];
                    }
                }
                attempts
            };
            tally.0 += attempts;
            tally.1 += n_rows as u64;
        }
        Ok(())
    }

    fn rejection_error(&self) -> DeviationError {
        DeviationError::invalid(
            self.constraint_paths.join(", "),
            format!("the Eq. 11 constraint rejected {MAX_REJECTIONS_PER_ROW} draws in a row"),
        )
    }

    /// Redraws one group in one row until its inequalities hold; returns the attempts.
    fn draw_group_by_rejection<R: Rng + ?Sized>(
        &self,
        group: &ConstrainedGroup,
        normal: &Ziggurat,
        rng: &mut R,
        z: &mut [f64],
        row: &mut [f64],
    ) -> Result<u64, DeviationError> {
        for attempt in 1..=MAX_REJECTIONS_PER_ROW {
            if group.draw_candidate(normal, rng, z, row) {
                return Ok(attempt);
            }
        }
        Err(self.rejection_error())
    }

    /// Measures the acceptance rate of each constraint group on a fixed pilot stream (kept
    /// to size the candidate batches) and rejects the space when the product is below
    /// [`MIN_ACCEPTANCE_RATE`].
    fn measure_acceptance(&mut self) -> Result<(), DeviationError> {
        if self.constrained_groups.is_empty() {
            return Ok(());
        }
        let mut rng = rand_chacha_pilot();
        let mut z = vec![0.0; self.max_rank.max(1)];
        let mut row = self.mean_row();
        let mut rate = 1.0;
        for group in &mut self.constrained_groups {
            let accepted = (0..PILOT_DRAWS)
                .filter(|_| group.draw_candidate(Ziggurat::get(), &mut rng, &mut z, &mut row))
                .count();
            group.pilot_acceptance = accepted as f64 / PILOT_DRAWS as f64;
            rate *= group.pilot_acceptance;
        }
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
        let mut counts = space.new_constraint_counts();
        space.sample_rows(&mut rng, &mut rows, &mut counts).unwrap();
        for row in rows.chunks_exact(6) {
            assert_eq!(row[2], 0.0);
            assert_eq!(row[5], 0.0);
            assert!(row[0].is_finite() && row[0] != 0.0);
        }
    }

    /// FNV-1a-style hash of the bits of every value, in order.
    fn hash_bits(hash: u64, values: &[f64]) -> u64 {
        values.iter().fold(hash, |hash, x| {
            (hash ^ x.to_bits()).wrapping_mul(0x0000_0100_0000_01b3)
        })
    }

    #[test]
    fn every_sampling_path_fills_its_columns_and_keeps_its_stream() {
        // Every way a column is drawn, in one space: fixed components (Δw, Δγ), an Eq. 11
        // part drawn as rotated pairs (parts[0]), an Eq. 11 part whose Δu is correlated
        // with a scalar, so that half of its constraint is a dense block redrawn row by
        // row (parts[1]), a correlated block without constraint, independent normals, a
        // uniform and a triangular.
        let band = |path| PartSpec::from_tolerance_band(path, 0.006, 120.0, true).unwrap();
        let mut builder = InputSpaceBuilder::new();
        let p0 = builder.add_part("parts[0]", &band("parts[0]"));
        let p1 = builder.add_part("parts[1]", &band("parts[1]"));
        let normal = |sd| ScalarDistribution::Normal { mean: 1.0, sd };
        let s0 = builder.add_scalar("variables[0]", normal(0.002));
        let s1 = builder.add_scalar("variables[1]", normal(1.0));
        let s2 = builder.add_scalar("variables[2]", normal(2.0));
        let s3 = builder.add_scalar("variables[3]", normal(0.5));
        let uniform = ScalarDistribution::Uniform {
            lower: -1.0,
            upper: 1.0,
        };
        let u = builder.add_scalar("variables[4]", uniform);
        let triangular = ScalarDistribution::Triangular {
            lower: -1.0,
            mode: 0.5,
            upper: 2.0,
        };
        let t = builder.add_scalar("variables[5]", triangular);
        builder.correlate("correlations[0]", p1, s0, 0.7).unwrap();
        builder.correlate("correlations[1]", s1, s2, -0.5).unwrap();
        let space = builder.build("correlations").unwrap();
        let n_columns = space.n_columns();
        let groups = &space.constrained_groups;
        assert_eq!(groups.len(), 4);
        assert_eq!(groups.iter().filter(|g| g.pair.is_some()).count(), 3);
        assert_eq!(groups.iter().filter(|g| !g.blocks.is_empty()).count(), 1);

        // Blocks of 37, 64, 1, 0 and 64 rows from one stream, in both layouts.
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let mut columns_rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let (mut counts, mut columns_counts) =
            (space.new_constraint_counts(), space.new_constraint_counts());
        let mut scratch = SamplerScratch::default();
        let (mut hash, mut columns_hash) = (0xcbf2_9ce4_8422_2325u64, 0xcbf2_9ce4_8422_2325u64);
        for n_rows in [37usize, 64, 1, 0, 64] {
            let mut rows = vec![f64::NAN; n_rows * n_columns];
            space
                .sample_rows_with(&mut rng, &mut rows, &mut counts, &mut scratch)
                .unwrap();
            hash = hash_bits(hash, &rows);
            let mut columns = vec![f64::NAN; n_rows * n_columns];
            space
                .sample_columns_with(
                    &mut columns_rng,
                    &mut columns,
                    &mut columns_counts,
                    &mut scratch,
                )
                .unwrap();
            let value = |r: usize, c: usize| columns[c * n_rows + r];
            for r in 0..n_rows {
                // Every cell written: fixed components exact, Eq. 11 holding, the scalars
                // drawn and inside their supports.
                for part in [p0, p1] {
                    let deviation: Vec<f64> = (0..6).map(|k| value(r, part + k)).collect();
                    assert_eq!((deviation[2], deviation[5]), (0.0, 0.0));
                    assert!(band("parts[0]").constraint.unwrap().holds(&deviation));
                }
                for c in [s0, s1, s2, s3] {
                    assert!(value(r, c).is_finite() && value(r, c) != 1.0);
                }
                assert!(value(r, u).abs() <= 1.0);
                assert!((-1.0..=2.0).contains(&value(r, t)));
            }
            let transposed: Vec<f64> = (0..n_rows * n_columns)
                .map(|i| value(i / n_columns, i % n_columns))
                .collect();
            columns_hash = hash_bits(columns_hash, &transposed);
        }
        // The pinned hash and tallies were computed with the row-major sampler this one
        // replaced (commit 3f889db): the column-major blocks draw exactly the same values.
        // A change here changes every run's results and must be deliberate (like the golden
        // values of tests/engine.rs).
        let tallies = vec![(333, 166), (357, 166), (326, 166), (306, 166)];
        assert_eq!(hash, 0xa7bd_83a1_71c8_712c, "{hash:#018x}");
        assert_eq!(counts.groups, tallies);
        assert_eq!(columns_hash, hash);
        assert_eq!(columns_counts.groups, tallies);
    }

    /// A builder with `n` independent standard normals, each correlated with the next by
    /// `rho` (a chain).
    fn chain(n: usize, rho: f64) -> InputSpaceBuilder {
        let mut builder = InputSpaceBuilder::new();
        let columns: Vec<usize> = (0..n)
            .map(|i| {
                builder.add_scalar(
                    &format!("variables[{i}]"),
                    ScalarDistribution::Normal { mean: 0.0, sd: 1.0 },
                )
            })
            .collect();
        for (i, pair) in columns.windows(2).enumerate() {
            builder
                .correlate(&format!("correlations[{i}]"), pair[0], pair[1], rho)
                .unwrap();
        }
        builder
    }

    #[test]
    fn a_pair_correlated_twice_is_an_error_naming_both() {
        let mut builder = chain(3, 0.2);
        let err = builder.correlate("correlations[2]", 1, 0, 0.3).unwrap_err();
        assert_eq!(
            err.to_string(),
            "correlations[2]: correlates the same pair as correlations[0]: give each pair once"
        );
    }

    #[test]
    fn a_correlated_group_beyond_the_limit_is_refused_before_allocating() {
        let err = chain(MAX_CORRELATED_COLUMNS + 1, 0.2)
            .build("correlations")
            .unwrap_err();
        let message = err.to_string();
        assert!(
            message.starts_with(&format!(
                "correlations: {} normal columns are correlated into one group (starting at variables[0]); at most {MAX_CORRELATED_COLUMNS} can be",
                MAX_CORRELATED_COLUMNS + 1
            )),
            "{message}"
        );
    }

    #[test]
    fn a_large_indefinite_group_is_found_by_the_factorisation() {
        // A chain with ρ = 0.6 between neighbours: the tridiagonal Toeplitz matrix has
        // eigenvalues 1 + 2ρ·cos(kπ/(n + 1)), the smallest 1 − 1.2·cos(π/(n + 1)) < 0 for
        // n ≥ 3. Beyond the eigenvalue limit the message says so without the eigenvalue.
        let n = crate::EIGENVALUE_MESSAGE_LIMIT + 1;
        let err = chain(n, 0.6).build("correlations").unwrap_err();
        match err {
            DeviationError::Indefinite {
                path,
                smallest_eigenvalue,
                matrix,
            } => {
                assert_eq!(matrix, MatrixKind::Correlation);
                assert!(path.starts_with("correlations (joint correlation of variables[0]"));
                assert!(path.ends_with(&format!("and {} more)", n - 8)), "{path}");
                assert_eq!(smallest_eigenvalue, None);
            }
            other => panic!("expected Indefinite, got {other}"),
        }
        // A chain with ρ = 0.4 is positive definite (smallest eigenvalue 1 − 0.8·cos(π/(n + 1))
        // > 0.2): it builds.
        chain(n, 0.4).build("correlations").unwrap();
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
                matrix,
            } => {
                assert_eq!(matrix, MatrixKind::Correlation);
                assert!(path.starts_with("correlations (joint correlation of variables[0]"));
                assert!((smallest_eigenvalue.unwrap() - (1.0 - 1.8)).abs() < 1e-12);
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
