//! Rows from uniform points (Latin hypercube, scrambled Sobol'): every column by an
//! inverse CDF, the Eq. 11 constraints by exact conditional inversion.
//!
//! One uniform per dimension, in this order: each unconstrained normal single
//! (x = μ + σ·Φ⁻¹(u)), each correlated block (its `rank` standard normals Φ⁻¹(u), then
//! x = μ + L·z), each non-normal scalar ([`ScalarDistribution::from_uniform`]), each
//! constrained group (its `rank` normals, below). A correlated non-normal scalar is part
//! of its block as its normal score z and takes its value F⁻¹(Φ(z)) at the end, as in the
//! random sampler.
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
//! the point set's structure intact.
//!
//! Two inequalities that the covariance couples (ρ = ŵ₁·ŵ₂ ≠ 0, a part's 6×6 covariance
//! that correlates (Δu, Δβ) with (Δv, Δα)) are drawn by the same idea in two steps
//! ([`CoupledPair`]): with E's first columns ŵ₁ and e₂ = (ŵ₂ − ρŵ₁)/s, s = √(1 − ρ²), the
//! inequalities read t₁ ≤ τ₁ and ρt₁ + s·t₂ ≤ τ₂. The marginal of t₁ has the density
//! φ(t)·Φ((τ₂ − ρt)/s) on t ≤ τ₁ (over Φ₂(τ₁, τ₂; ρ)); its CDF is tabulated once by
//! Gauss–Legendre quadrature and inverted per row by Newton steps on the exact integral
//! from the nearest node, to round-off; then t₂ given t₁ is the normal truncated at
//! (τ₂ − ρt₁)/s, by its inverse CDF. Three or more coupled inequalities (two constrained
//! parts correlated with each other) are refused for these methods with the reason
//! ([`InputSpace::quasi_dimensions`]).

use super::{column_mut, prefix, InputSpace, SamplerScratch};
use crate::error::DeviationError;
use crate::inverse_normal::{
    standard_normal_inverse as standard_normal_quantile, standard_normal_inverse_in_place,
};
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
    /// The first two normals, when two inequalities are coupled (then `truncated` is
    /// empty).
    coupled: Option<CoupledPair>,
}

/// Nodes and weights of 5-point Gauss–Legendre quadrature on [−1, 1] (closed form:
/// nodes 0, ±⅓√(5 ∓ 2√(10/7)), weights 128/225, (322 ± 13√70)/900).
fn gauss_legendre_5() -> [(f64, f64); 5] {
    let a = (5.0 - 2.0 * (10.0f64 / 7.0).sqrt()).sqrt() / 3.0;
    let b = (5.0 + 2.0 * (10.0f64 / 7.0).sqrt()).sqrt() / 3.0;
    let wa = (322.0 + 13.0 * 70.0f64.sqrt()) / 900.0;
    let wb = (322.0 - 13.0 * 70.0f64.sqrt()) / 900.0;
    [(0.0, 128.0 / 225.0), (-a, wa), (a, wa), (-b, wb), (b, wb)]
}

/// Two coupled inequalities t₁ ≤ τ₁, ρt₁ + s·t₂ ≤ τ₂ over standard normals (module docs).
#[derive(Debug, Clone)]
pub(super) struct CoupledPair {
    rho: f64,
    s: f64,
    tau2: f64,
    /// Nodes t_k of the table, from [`CoupledPair::LOWEST`] to min(τ₁, −LOWEST).
    nodes: Vec<f64>,
    /// ∫ from the lowest node to t_k of the unnormalised marginal density.
    cdf: Vec<f64>,
    rule: [(f64, f64); 5],
}

impl CoupledPair {
    /// Below this the marginal holds less than Φ(−9) ≈ 1e−19 of its mass: the table
    /// starts there.
    const LOWEST: f64 = -9.0;
    /// Spacing of the table's nodes.
    const STEP: f64 = 1.0 / 256.0;

    fn new(rho: f64, tau1: f64, tau2: f64) -> CoupledPair {
        let s = (1.0 - rho * rho).sqrt();
        let top = tau1.min(-Self::LOWEST);
        let intervals = ((top - Self::LOWEST) / Self::STEP).ceil().max(1.0) as usize;
        let nodes: Vec<f64> = (0..=intervals)
            .map(|k| {
                if k == intervals {
                    top
                } else {
                    Self::LOWEST + k as f64 * Self::STEP
                }
            })
            .collect();
        let mut pair = CoupledPair {
            rho,
            s,
            tau2,
            nodes,
            cdf: Vec::new(),
            rule: gauss_legendre_5(),
        };
        let mut cdf = Vec::with_capacity(pair.nodes.len());
        let mut total = 0.0;
        cdf.push(0.0);
        for k in 1..pair.nodes.len() {
            total += pair.integral(pair.nodes[k - 1], pair.nodes[k]);
            cdf.push(total);
        }
        pair.cdf = cdf;
        pair
    }

    /// The unnormalised marginal density of t₁: φ(t)·Φ((τ₂ − ρt)/s).
    #[inline]
    fn density(&self, t: f64) -> f64 {
        (-0.5 * t * t).exp() / (2.0 * std::f64::consts::PI).sqrt()
            * standard_normal_cdf((self.tau2 - self.rho * t) / self.s)
    }

    /// ∫ₐᵇ of the density (one 5-point rule: a and b lie within one table step).
    fn integral(&self, a: f64, b: f64) -> f64 {
        let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
        half * self
            .rule
            .iter()
            .map(|&(x, w)| w * self.density(mid + half * x))
            .sum::<f64>()
    }

    /// t₁ at the uniform u: the inverse of the marginal CDF, by Newton steps on the exact
    /// integral from the node below, kept inside that node's interval.
    fn first(&self, u: f64) -> f64 {
        let target = u * self.cdf[self.cdf.len() - 1];
        let k = self
            .cdf
            .partition_point(|&c| c <= target)
            .clamp(1, self.cdf.len() - 1)
            - 1;
        let (lo, hi) = (self.nodes[k], self.nodes[k + 1]);
        let (c_lo, c_hi) = (self.cdf[k], self.cdf[k + 1]);
        let mut t = if c_hi > c_lo {
            lo + (hi - lo) * ((target - c_lo) / (c_hi - c_lo)).clamp(0.0, 1.0)
        } else {
            lo
        };
        for _ in 0..4 {
            let g = self.density(t);
            if g <= 0.0 {
                break;
            }
            let step = (c_lo + self.integral(lo, t) - target) / g;
            t = (t - step).clamp(lo, hi);
            if step.abs() <= 1e-15 * t.abs().max(1.0) {
                break;
            }
        }
        t
    }

    /// t₂ given t₁ at the uniform u: the normal truncated at (τ₂ − ρt₁)/s.
    #[inline]
    fn second(&self, t1: f64, u: f64) -> f64 {
        standard_normal_quantile(u * standard_normal_cdf((self.tau2 - self.rho * t1) / self.s))
    }
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
            let mut thresholds = Vec::new();
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
                directions.push(w);
                thresholds.push(slack / sigma);
            }
            let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
            let coupling = (0..directions.len())
                .flat_map(|i| (i + 1..directions.len()).map(move |j| (i, j)))
                .map(|(i, j)| dot(&directions[i], &directions[j]))
                .find(|rho| rho.abs() > ORTHOGONAL);
            let (truncated, coupled) = match (coupling, directions.len()) {
                (None, _) => (
                    thresholds
                        .iter()
                        .map(|&tau| standard_normal_cdf(tau))
                        .collect(),
                    None,
                ),
                (Some(rho), 2) if rho.abs() < 1.0 - 1e-9 => {
                    // E's first two columns: ŵ₁ and the part of ŵ₂ orthogonal to it.
                    let s = (1.0 - rho * rho).sqrt();
                    let e2: Vec<f64> = (directions[1].iter().zip(&directions[0]))
                        .map(|(w2, w1)| (w2 - rho * w1) / s)
                        .collect();
                    directions[1] = e2;
                    (
                        Vec::new(),
                        Some(CoupledPair::new(rho, thresholds[0], thresholds[1])),
                    )
                }
                (Some(rho), n) => {
                    let refusal = (
                        space.constraint_paths.join(", "),
                        format!(
                            "lhs and rqmc draw the Eq. 11 constraint by exact inversion, which handles at most two coupled inequalities per group of correlated columns; here {n} are coupled (correlation {rho:.3}), as when constrained parts are correlated with each other: use \"sampling\": \"mc\""
                        ),
                    );
                    return QuasiLayout {
                        dims,
                        groups: Vec::new(),
                        refusal: Some(refusal),
                    };
                }
            };
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
                coupled,
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

    /// Per dimension of [`InputSpace::quasi_dimensions`], the columns its value moves
    /// (one for a single or a non-normal scalar, a correlated block's or a constrained
    /// group's columns for each of its dimensions): what a result found per dimension
    /// (a rare event's importance factors) is told by.
    pub fn quasi_dimension_columns(&self) -> Vec<Vec<usize>> {
        let mut dims: Vec<Vec<usize>> = self.singles.iter().map(|s| vec![s.0]).collect();
        for block in &self.blocks {
            dims.extend(std::iter::repeat_n(block.columns.clone(), block.rank));
        }
        dims.extend(self.independent.iter().map(|(c, _)| vec![*c]));
        for group in &self.quasi.groups {
            dims.extend(std::iter::repeat_n(group.columns.clone(), group.rank));
        }
        dims
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
        assert_eq!(points.dims(), dims, "the point set's dimensions");
        self.sample_columns_from_point_dims(points, 0, replicate, first, columns, scratch)
    }

    /// [`InputSpace::sample_columns_from_points`] from the dimensions `first_dim ..
    /// first_dim + quasi_dimensions()` of a wider point set: the A and B matrices of a
    /// sensitivity design are the two halves of one point.
    pub fn sample_columns_from_point_dims(
        &self,
        points: &PointSet,
        first_dim: usize,
        replicate: u64,
        first: u64,
        columns: &mut [f64],
        scratch: &mut SamplerScratch,
    ) -> Result<(), DeviationError> {
        let dims = self.quasi_dimensions()?;
        if self.n_columns == 0 {
            return Ok(());
        }
        let n_rows = columns.len() / self.n_columns;
        let mut u = std::mem::take(&mut scratch.candidates);
        let uniforms = prefix(&mut u, dims * n_rows);
        points.fill_dims(
            replicate,
            first,
            n_rows,
            first_dim..first_dim + dims,
            uniforms,
        );
        self.columns_from_dims(uniforms, Scale::Uniform, columns, scratch);
        scratch.candidates = u;
        Ok(())
    }

    /// Rows from standard normal scores, one per dimension (the same dimensions, in the
    /// same order, as [`InputSpace::sample_columns_from_points`]'s uniforms: a score z
    /// stands for the uniform Φ(z)): the map of the standard normal space onto the
    /// scenario's law that the rare-event methods search and sample in. `scores` is
    /// column-major, [`InputSpace::quasi_dimensions`] columns of `columns.len() /
    /// n_columns()` rows, and is overwritten. A normal column takes its score as it is,
    /// a non-normal scalar its [`ScalarDistribution::from_normal_score`] (the far tails
    /// kept), a truncated one Φ⁻¹(Φ(z)·Φ(τ)).
    ///
    /// [`ScalarDistribution::from_normal_score`]: crate::ScalarDistribution::from_normal_score
    pub fn sample_columns_from_normals(
        &self,
        scores: &mut [f64],
        columns: &mut [f64],
        scratch: &mut SamplerScratch,
    ) -> Result<(), DeviationError> {
        let dims = self.quasi_dimensions()?;
        if self.n_columns == 0 {
            return Ok(());
        }
        assert_eq!(scores.len(), dims * (columns.len() / self.n_columns));
        self.columns_from_dims(scores, Scale::Normal, columns, scratch);
        Ok(())
    }

    /// The rows of `columns` from one column of `dims` values per dimension, uniforms or
    /// normal scores (`scale`).
    fn columns_from_dims(
        &self,
        dims: &mut [f64],
        scale: Scale,
        columns: &mut [f64],
        scratch: &mut SamplerScratch,
    ) {
        let n_rows = columns.len() / self.n_columns;
        let mut dimensions = dims.chunks_exact_mut(n_rows.max(1));
        let mut next = || dimensions.next().expect("a column of values per dimension");
        // The next dimension as standard normals (a column of uniforms turned in place,
        // by batched Φ⁻¹).
        let mut normals = || {
            let column = next();
            if scale == Scale::Uniform {
                standard_normal_inverse_in_place(column);
            }
            column
        };
        for &(column, mean) in &self.fixed {
            column_mut(columns, column, n_rows).fill(mean);
        }
        for &(column, mean, sd) in &self.singles {
            for (x, &z) in column_mut(columns, column, n_rows)
                .iter_mut()
                .zip(normals().iter())
            {
                *x = mean + sd * z;
            }
        }
        let widest = (self.quasi.groups.iter().map(|g| g.rank))
            .chain(self.blocks.iter().map(|b| b.rank))
            .max()
            .unwrap_or(1);
        let z = prefix(&mut scratch.block_z, widest * n_rows.max(1));
        for block in &self.blocks {
            for k in 0..block.rank {
                for (r, &normal) in normals().iter().enumerate() {
                    z[r * block.rank + k] = normal;
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
            for (x, &u) in column_mut(columns, *column, n_rows)
                .iter_mut()
                .zip(next().iter())
            {
                *x = match scale {
                    Scale::Uniform => distribution.from_uniform(u),
                    Scale::Normal => distribution.from_normal_score(u),
                };
            }
        }
        for group in &self.quasi.groups {
            let rank = group.rank;
            let mut k = 0;
            if let Some(pair) = &group.coupled {
                let (first, second) = (next(), next());
                if scale == Scale::Normal {
                    (first.iter_mut().chain(second.iter_mut()))
                        .for_each(|z| *z = standard_normal_cdf(*z));
                }
                for (r, (&u1, &u2)) in first.iter().zip(second.iter()).enumerate() {
                    let t1 = pair.first(u1);
                    z[r * rank] = t1;
                    z[r * rank + 1] = pair.second(t1, u2);
                }
                k = 2;
            }
            for k in k..rank {
                let column = next();
                match (scale, group.truncated.get(k)) {
                    (Scale::Uniform, mass) => {
                        if let Some(&mass) = mass {
                            column.iter_mut().for_each(|u| *u *= mass);
                        }
                        standard_normal_inverse_in_place(column);
                    }
                    (Scale::Normal, Some(&mass)) => {
                        column
                            .iter_mut()
                            .for_each(|z| *z = standard_normal_cdf(*z) * mass);
                        standard_normal_inverse_in_place(column);
                    }
                    (Scale::Normal, None) => {}
                }
                for (r, &normal) in column.iter().enumerate() {
                    z[r * rank + k] = normal;
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
        self.copula_to_values(columns, n_rows);
    }
}

/// What the values of a dimension are.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Scale {
    /// Uniforms on (0, 1), from a point set.
    Uniform,
    /// Standard normal scores.
    Normal,
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

    /// Φ₂(τ₁, τ₂; ρ) by composite Simpson over t₁ (200,000 intervals from −12): a
    /// different quadrature from the pair's table.
    fn bivariate_cdf(tau1: f64, tau2: f64, rho: f64) -> f64 {
        let s = (1.0 - rho * rho).sqrt();
        let f = |t: f64| density(t) * standard_normal_cdf((tau2 - rho * t) / s);
        let (a, n) = (-12.0, 200_000);
        let h = (tau1 - a) / n as f64;
        let inner: f64 = (1..n)
            .map(|k| f(a + k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 })
            .sum();
        h / 3.0 * (f(a) + inner + f(tau1))
    }

    /// A tolerance-band part whose covariance correlates Δu with Δv (ρ = 0.5), which
    /// couples the two halves of its Eq. 11.
    fn coupled_part(path: &str) -> PartSpec {
        let mut part = PartSpec::from_tolerance_band(path, 0.006, 120.0, true).unwrap();
        let c = 0.5 * (part.covariance[0][0] * part.covariance[1][1]).sqrt();
        part.covariance[0][1] = c;
        part.covariance[1][0] = c;
        part
    }

    #[test]
    fn coupled_inequalities_follow_the_truncated_bivariate_law() {
        // A covariance that correlates Δu with Δv (ρ_uv = 0.5) couples the two halves of
        // Eq. 11. Every row satisfies both, and the means of the standardised left sides
        // X₁, X₂ are Tallis's (1961) moments of the bivariate normal truncated to
        // X₁ ≤ τ₁, X₂ ≤ τ₂: E[X₁] = −(φ(τ₁)Φ((τ₂ − ρτ₁)/s) + ρφ(τ₂)Φ((τ₁ − ρτ₂)/s))/Φ₂,
        // within 5 Monte Carlo standard errors (the truncated sd is below 1).
        let part = coupled_part("parts[0]");
        let c = part.covariance[0][1];
        let mut builder = InputSpaceBuilder::new();
        builder.add_part("parts[0]", &part);
        let space = builder.build("correlations").unwrap();
        let dims = space.quasi_dimensions().unwrap();
        let n = 1usize << 14;
        let constraint = part.constraint.unwrap();
        let q = constraint.inequalities(0);
        let standardised = |k: usize| {
            let (mu, var) = (0..2).fold((0.0, 0.0), |(m, v), j| {
                let (c, a) = (q[k].columns[j], q[k].coefficients[j]);
                (
                    m + a * space.mean_row()[c],
                    v + a * a * space.covariance(c, c),
                )
            });
            (mu, var.sqrt())
        };
        let (s1, s2) = (standardised(0), standardised(1));
        // ρ between the two sums: Cov(Δu + hΔβ, Δv + hΔα) = Cov(Δu, Δv) (the tilts are
        // independent of everything).
        let rho = c / (s1.1 * s2.1);
        let (tau1, tau2) = ((q[0].bound - s1.0) / s1.1, (q[1].bound - s2.0) / s2.1);
        let s = (1.0 - rho * rho).sqrt();
        let z = bivariate_cdf(tau1, tau2, rho);
        let tallis = |a: f64, b: f64| {
            -(density(a) * standard_normal_cdf((b - rho * a) / s)
                + rho * density(b) * standard_normal_cdf((a - rho * b) / s))
                / z
        };
        let expected = [tallis(tau1, tau2), tallis(tau2, tau1)];
        for method in [SamplingMethod::Rqmc, SamplingMethod::LatinHypercube] {
            let points = PointSet::new(method, dims, n as u64, 23).unwrap();
            let mut columns = vec![f64::NAN; n * space.n_columns()];
            space
                .sample_columns_from_points(
                    &points,
                    0,
                    0,
                    &mut columns,
                    &mut SamplerScratch::default(),
                )
                .unwrap();
            for (k, (mu, sigma)) in [s1, s2].into_iter().enumerate() {
                let mut sum = 0.0;
                for row in 0..n {
                    let lhs = q[k].coefficients[0] * columns[q[k].columns[0] * n + row]
                        + q[k].coefficients[1] * columns[q[k].columns[1] * n + row];
                    assert!(lhs <= q[k].bound * (1.0 + 1e-12), "{method:?} row {row}");
                    sum += (lhs - mu) / sigma;
                }
                let mean = sum / n as f64;
                assert!(
                    (mean - expected[k]).abs() < 5.0 / (n as f64).sqrt(),
                    "{method:?} inequality {k}: {mean} against {}",
                    expected[k]
                );
            }
        }
    }

    #[test]
    fn normal_scores_give_the_rows_of_their_uniforms() {
        // A row from scores z is the row from the uniforms Φ(z): the same map, entered in
        // the normal space. Checked on a space with every kind of dimension (an uncoupled
        // Eq. 11 part, a coupled one, a correlated block, a Rayleigh and a triangular
        // scalar) at scores over ±4.5, to 1e-9 of each column's spread (Φ⁻¹(Φ(z)) is z to
        // round-off; the coupled pair's Newton inversion to its tolerance). Farther out the
        // uniform Φ(z) rounds near 1 and the scores' path is the more precise one.
        let coupled = coupled_part("parts[1]");
        let mut builder = InputSpaceBuilder::new();
        let band = PartSpec::from_tolerance_band("parts[0]", 0.006, 120.0, true).unwrap();
        builder.add_part("parts[0]", &band);
        builder.add_part("parts[1]", &coupled);
        let a = builder.add_scalar(
            "variables[0]",
            ScalarDistribution::Normal { mean: 1.0, sd: 0.1 },
        );
        let b = builder.add_scalar(
            "variables[1]",
            ScalarDistribution::Normal { mean: 0.0, sd: 2.0 },
        );
        builder.correlate("correlations[0]", a, b, -0.4).unwrap();
        builder.add_scalar("variables[2]", ScalarDistribution::Rayleigh { sigma: 2.0 });
        builder.add_scalar(
            "variables[3]",
            ScalarDistribution::Triangular {
                lower: -1.0,
                mode: 0.5,
                upper: 2.0,
            },
        );
        let space = builder.build("correlations").unwrap();
        let dims = space.quasi_dimensions().unwrap();
        let moved = space.quasi_dimension_columns();
        assert_eq!(moved.len(), dims);
        // Each column is moved by some dimension, except the parts' fixed Δw, Δγ.
        let moving = (0..space.n_columns())
            .filter(|c| moved.iter().any(|d| d.contains(c)))
            .count();
        assert_eq!(moving, space.n_columns() - 4);
        let n = 25;
        let scores: Vec<f64> = (0..dims * n)
            .map(|i| -4.5 + 9.0 * ((i * 7919) % 1009) as f64 / 1008.0)
            .collect();
        let mut from_scores = vec![f64::NAN; n * space.n_columns()];
        let mut scratch = SamplerScratch::default();
        space
            .sample_columns_from_normals(&mut scores.clone(), &mut from_scores, &mut scratch)
            .unwrap();
        // The same dimensions as uniforms, through a point set's layout: one column of
        // uniforms per dimension, fed through the points path's body.
        let mut uniforms: Vec<f64> = scores.iter().map(|&z| standard_normal_cdf(z)).collect();
        let mut from_uniforms = vec![f64::NAN; n * space.n_columns()];
        space.columns_from_dims(
            &mut uniforms,
            Scale::Uniform,
            &mut from_uniforms,
            &mut scratch,
        );
        for column in 0..space.n_columns() {
            let spread = space.covariance(column, column).sqrt().max(1.0);
            for row in 0..n {
                let (x, y) = (
                    from_scores[column * n + row],
                    from_uniforms[column * n + row],
                );
                assert!(x.is_finite(), "column {column} row {row}");
                assert!(
                    (x - y).abs() <= 1e-9 * spread,
                    "column {column} row {row}: {x} against {y}"
                );
            }
        }
    }

    #[test]
    fn three_coupled_inequalities_are_refused_with_the_reason() {
        // parts[0]'s halves coupled (Δu with Δv), and parts[1]'s Δu correlated with
        // parts[0]'s Δu: three coupled inequalities in one group.
        let band = |path| PartSpec::from_tolerance_band(path, 0.006, 120.0, true).unwrap();
        let part = coupled_part("parts[0]");
        let mut builder = InputSpaceBuilder::new();
        let p0 = builder.add_part("parts[0]", &part);
        let p1 = builder.add_part("parts[1]", &band("parts[1]"));
        builder.correlate("correlations[0]", p0, p1, 0.3).unwrap();
        let space = builder.build("correlations").unwrap();
        let err = space.quasi_dimensions().unwrap_err().to_string();
        assert!(err.starts_with("parts[0], parts[1]: lhs and rqmc"), "{err}");
        assert!(err.contains("here 3 are coupled"), "{err}");
        assert!(err.contains("\"sampling\": \"mc\""), "{err}");
    }
}
