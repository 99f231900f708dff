//! Fast screening measures beside the Sobol' indices, per continuous output and source:
//!
//! - derivatives at the nominal point (every deviation at its mean), by central
//!   differences ∂y/∂x_c ≈ (f(x̄ + h·e_c) − f(x̄ − h·e_c))/(2h), h = 1e−4·σ_c;
//! - contribution % of the linearised variance: with g the gradient and Σ the joint
//!   covariance of the random columns, V_lin = gᵀΣg and the share of source s is
//!   Σ_{c∈s} g_c·(Σg)_c / V_lin (the Euler allocation: it sums to 100 % with correlated
//!   inputs, a share can then be negative);
//! - standardized regression coefficients: least squares of the standardized output on
//!   the standardized random columns over a Monte Carlo sample, R² of that fit, and per
//!   source the sum of its squared SRCs (its share of the variance when the inputs are
//!   independent and R² is near 1).
//!
//! The sample is drawn in chunks from streams 2⁶⁰ + k of the seed and the sums run in
//! chunk order, so results do not depend on the thread count.

use nalgebra::{DMatrix, DVector};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use rvtol_engine::chunk::CHUNK_SIZE;
use rvtol_engine::evaluate::ChunkEvaluator;
use rvtol_engine::scenario::{InputGroup, Scenario, ScenarioError};

const SCREENING_STREAM_BASE: u64 = 1 << 60;

/// Screening figures of one source for one output.
#[derive(Debug, Clone, PartialEq)]
pub struct SourceScreening {
    /// The source.
    pub input: String,
    /// Share of the linearised variance (fraction; sums to 1 over the sources).
    pub contribution: f64,
    /// Sum of the squared standardized regression coefficients of its columns.
    pub src_squared: f64,
    /// (column name, derivative at the nominal point) of its random columns.
    pub derivatives: Vec<(String, f64)>,
}

/// Screening figures of one output.
#[derive(Debug, Clone, PartialEq)]
pub struct OutputScreening {
    /// Output name.
    pub name: String,
    /// gᵀΣg.
    pub linearised_variance: f64,
    /// R² of the linear regression.
    pub r_squared: f64,
    /// Per source, in the order of the scenario.
    pub sources: Vec<SourceScreening>,
}

/// Computes the screening measures with `samples` regression rows.
pub fn screening(
    scenario: &Scenario,
    players: &[InputGroup],
    samples: u64,
    seed: u64,
) -> Result<Vec<OutputScreening>, ScenarioError> {
    let space = &scenario.input_space;
    let n_columns = space.n_columns();
    let covariance = |a: usize, b: usize| space.covariance(a, b);
    // Random columns, with their source.
    let columns: Vec<(usize, usize)> = players
        .iter()
        .enumerate()
        .flat_map(|(s, p)| p.columns.iter().map(move |&c| (s, c)))
        .filter(|&(_, c)| covariance(c, c) > 0.0)
        .collect();
    let p = columns.len();
    if p == 0 || 2 * p > CHUNK_SIZE {
        return Err(ScenarioError::new(
            "parts/variables",
            format!(
                "screening needs between 1 and {} random columns, got {p}",
                CHUNK_SIZE / 2
            ),
        ));
    }
    let continuous = scenario.continuous_outputs();
    let mut evaluator = ChunkEvaluator::new(scenario);

    // Derivatives at the nominal point.
    let nominal = space.mean_row();
    let mut rows = Vec::with_capacity(2 * p * n_columns);
    let steps: Vec<f64> = columns
        .iter()
        .map(|&(_, c)| 1e-4 * covariance(c, c).sqrt())
        .collect();
    for (&(_, c), &h) in columns.iter().zip(&steps) {
        for sign in [1.0, -1.0] {
            let mut row = nominal.clone();
            row[c] += sign * h;
            rows.extend(row);
        }
    }
    evaluator.evaluate(&rows, 2 * p);
    let gradients: Vec<Vec<f64>> = continuous
        .iter()
        .map(|&o| {
            let values = &evaluator.output_columns[o];
            (0..p)
                .map(|k| (values[2 * k] - values[2 * k + 1]) / (2.0 * steps[k]))
                .collect()
        })
        .collect();

    // Regression sample, chunk by chunk in order.
    let mut x = DMatrix::<f64>::zeros(samples as usize, p);
    let mut y = DMatrix::<f64>::zeros(samples as usize, continuous.len());
    let mut counts = space.new_constraint_counts();
    let mut block = vec![0.0; CHUNK_SIZE * n_columns];
    let mut done = 0usize;
    let mut chunk = 0u64;
    while done < samples as usize {
        let m = (samples as usize - done).min(CHUNK_SIZE);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(SCREENING_STREAM_BASE + chunk);
        space.sample_rows(&mut rng, &mut block[..m * n_columns], &mut counts)?;
        evaluator.evaluate(&block[..m * n_columns], m);
        for r in 0..m {
            for (k, &(_, c)) in columns.iter().enumerate() {
                x[(done + r, k)] = block[r * n_columns + c];
            }
            for (slot, &o) in continuous.iter().enumerate() {
                y[(done + r, slot)] = evaluator.output_columns[o][r];
            }
        }
        done += m;
        chunk += 1;
    }
    let standardise = |matrix: &mut DMatrix<f64>| {
        for mut column in matrix.column_iter_mut() {
            let n = column.len() as f64;
            let mean = column.sum() / n;
            column.add_scalar_mut(-mean);
            let sd = (column.norm_squared() / (n - 1.0)).sqrt();
            if sd > 0.0 {
                column /= sd;
            }
        }
    };
    standardise(&mut x);
    standardise(&mut y);
    let gram = x.transpose() * &x;
    let tolerance = 1e-10 * gram.diagonal().max();
    let pseudo_inverse = gram
        .pseudo_inverse(tolerance)
        .map_err(|err| ScenarioError::new("(screening)", err.to_string()))?;

    Ok(continuous
        .iter()
        .enumerate()
        .map(|(slot, &o)| {
            let target: DVector<f64> = y.column(slot).into_owned();
            let beta = &pseudo_inverse * (x.transpose() * &target);
            let residual = &target - &x * &beta;
            let total = target.norm_squared();
            let r_squared = if total > 0.0 {
                1.0 - residual.norm_squared() / total
            } else {
                0.0
            };
            let g = &gradients[slot];
            let sigma_g: Vec<f64> = columns
                .iter()
                .map(|&(_, a)| {
                    columns
                        .iter()
                        .zip(g)
                        .map(|(&(_, b), gb)| covariance(a, b) * gb)
                        .sum()
                })
                .collect();
            let linearised_variance: f64 = g.iter().zip(&sigma_g).map(|(a, b)| a * b).sum();
            let sources = players
                .iter()
                .enumerate()
                .map(|(s, player)| {
                    let mine: Vec<usize> = (0..p).filter(|&k| columns[k].0 == s).collect();
                    SourceScreening {
                        input: player.name.clone(),
                        contribution: if linearised_variance > 0.0 {
                            mine.iter().map(|&k| g[k] * sigma_g[k]).sum::<f64>()
                                / linearised_variance
                        } else {
                            0.0
                        },
                        src_squared: mine.iter().map(|&k| beta[k] * beta[k]).sum(),
                        derivatives: mine
                            .iter()
                            .map(|&k| (scenario.columns[columns[k].1].name.clone(), g[k]))
                            .collect(),
                    }
                })
                .collect();
            OutputScreening {
                name: scenario.outputs[o].name.clone(),
                linearised_variance,
                r_squared,
                sources,
            }
        })
        .collect())
}
