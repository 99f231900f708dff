//! Shapley effects of the error sources: each source's share of an output's variance,
//! well defined when the sources are correlated (Owen 2014; Song, Nelson & Staum 2016).
//!
//! With d players (the scenario's random sources: a part is one player, each variable one)
//! and the cost c(J) = E[Var(Y | X_{−J})] of a set J (c(∅) = 0, c(all) = Var Y):
//!
//! ```text
//! Sh_j = (1/d!)·Σ_π [c(P_j(π) ∪ {j}) − c(P_j(π))] / Var Y
//! ```
//!
//! P_j(π) the players before j in the permutation π. rvtol follows Song, Nelson & Staum
//! (2016, Algorithm 1): when d! is at most the permutation budget, all d! orders, each
//! repeated ⌊budget/d!⌋ times with independent draws; else that many random orders; c(J) by N_o outer draws of the whole row and, for each, N_i
//! inner draws of x_J given x_{−J} (exact conditional normal, rvtol-deviation's
//! `ConditionalSampler`), c(J) ≈ mean over outer draws of the inner sample variance. The
//! effects sum to 1. Interval: ±1.96 standard errors of the mean of each player's marginal
//! contributions over the permutations (independent draws per permutation).
//!
//! Reproducibility: permutation p draws from stream 2⁶¹ + p of the seed, the variance run
//! from stream 2⁶¹ − 1; results are collected in permutation order and summed sequentially.

use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use rvtol_deviation::ConditionalSampler;

use crate::evaluate::ChunkEvaluator;
use crate::run::CHUNK_SIZE;
use crate::scenario::{InputGroup, Scenario, ScenarioError};

const SHAPLEY_STREAM_BASE: u64 = 1 << 61;
/// Rows of the run that estimates Var Y.
const VARIANCE_ROWS: usize = 64 * CHUNK_SIZE;

/// How to estimate the Shapley effects.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShapleySettings {
    /// All permutations when d! is at most this, else this many random ones.
    pub permutations: usize,
    /// Outer draws N_o per cost estimate.
    pub outer: usize,
    /// Inner draws N_i per outer draw (≥ 2).
    pub inner: usize,
    /// Seed.
    pub seed: u64,
}

/// One player's Shapley effect for one output.
#[derive(Debug, Clone, PartialEq)]
pub struct ShapleyEffect {
    /// The source.
    pub input: String,
    /// Its share of the output variance.
    pub effect: f64,
    /// 95 % interval.
    pub interval: [f64; 2],
}

fn factorial(d: usize) -> Option<usize> {
    (1..=d).try_fold(1usize, |acc, k| acc.checked_mul(k))
}

/// The p-th permutation of 0..d in lexicographic order (factorial number system).
fn nth_permutation(d: usize, mut p: usize) -> Vec<usize> {
    let mut pool: Vec<usize> = (0..d).collect();
    let mut out = Vec::with_capacity(d);
    for k in (1..=d).rev() {
        let block = factorial(k - 1).unwrap_or(usize::MAX);
        out.push(pool.remove(p / block));
        p %= block;
    }
    out
}

/// The random sources of a scenario (players of the Shapley game).
pub fn players(scenario: &Scenario) -> Vec<InputGroup> {
    let random = |column: usize| scenario.input_space.is_random(column);
    scenario
        .sources
        .iter()
        .filter(|s| s.columns.iter().any(|&c| random(c)))
        .cloned()
        .collect()
}

/// Shapley effects of every continuous output: `result[output] = (name, effects)`, effects in
/// the order of [`players`].
pub fn shapley_effects(
    scenario: &Scenario,
    settings: ShapleySettings,
) -> Result<Vec<(String, Vec<ShapleyEffect>)>, ScenarioError> {
    if settings.inner < 2 || settings.outer < 1 || settings.permutations < 1 {
        return Err(ScenarioError::new(
            "shapley",
            "needs inner ≥ 2, outer ≥ 1 and permutations ≥ 1",
        ));
    }
    if settings.outer * settings.inner > CHUNK_SIZE {
        return Err(ScenarioError::new(
            "shapley",
            format!("outer × inner draws must not exceed {CHUNK_SIZE}"),
        ));
    }
    let players = players(scenario);
    let d = players.len();
    if d == 0 {
        return Err(ScenarioError::new(
            "parts/variables",
            "the scenario has no random input",
        ));
    }
    let continuous = scenario.continuous_outputs();
    let space = &scenario.input_space;
    let n_columns = space.n_columns();

    // Var Y from a plain run.
    let variance: Vec<f64> = {
        let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
        rng.set_stream(SHAPLEY_STREAM_BASE - 1);
        let mut counts = space.new_constraint_counts();
        let mut evaluator = ChunkEvaluator::new(scenario);
        let mut moments = vec![crate::stats::Moments::new(); continuous.len()];
        let mut rows = vec![0.0; CHUNK_SIZE * n_columns];
        for _ in 0..VARIANCE_ROWS / CHUNK_SIZE {
            space.sample_rows(&mut rng, &mut rows, &mut counts)?;
            evaluator.evaluate(&rows, CHUNK_SIZE);
            for (slot, &o) in continuous.iter().enumerate() {
                moments[slot].merge(&crate::stats::Moments::from_slice(
                    &evaluator.output_columns[o],
                ));
            }
        }
        moments.iter().map(|m| m.variance()).collect()
    };

    // All d! orders, each repeated as often as the budget allows, when d! fits in it.
    let exact = factorial(d).filter(|&f| f <= settings.permutations);
    let n_permutations = match exact {
        Some(f) => f * (settings.permutations / f),
        None => settings.permutations,
    };
    // Marginal contributions per permutation: [permutation][output][player].
    let contributions: Vec<Vec<Vec<f64>>> = (0..n_permutations)
        .into_par_iter()
        .map(|p| -> Result<Vec<Vec<f64>>, ScenarioError> {
            let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
            rng.set_stream(SHAPLEY_STREAM_BASE + p as u64);
            let order = match exact {
                Some(f) => nth_permutation(d, p % f),
                None => {
                    let mut order: Vec<usize> = (0..d).collect();
                    order.shuffle(&mut rng);
                    order
                }
            };
            let mut evaluator = ChunkEvaluator::new(scenario);
            let mut counts = space.new_constraint_counts();
            let mut outer_rows = vec![0.0; settings.outer * n_columns];
            let mut rows = vec![0.0; settings.outer * settings.inner * n_columns];
            let mut delta = vec![vec![0.0; d]; continuous.len()];
            let mut previous = vec![0.0; continuous.len()];
            let mut free: Vec<usize> = Vec::new();
            let mut z = Vec::new();
            for (k, &player) in order.iter().enumerate() {
                let cost: Vec<f64> = if k + 1 == d {
                    variance.clone()
                } else {
                    free.extend(&players[player].columns);
                    let sampler: ConditionalSampler = space.conditional_sampler(&free)?;
                    space.sample_rows(&mut rng, &mut outer_rows, &mut counts)?;
                    for (outer, base) in outer_rows.chunks_exact(n_columns).enumerate() {
                        for inner in 0..settings.inner {
                            let start = (outer * settings.inner + inner) * n_columns;
                            let row = &mut rows[start..start + n_columns];
                            row.copy_from_slice(base);
                            sampler.sample(&mut rng, row, &mut z);
                        }
                    }
                    evaluator.evaluate(&rows, settings.outer * settings.inner);
                    continuous
                        .iter()
                        .map(|&o| {
                            let column = &evaluator.output_columns[o];
                            let total: f64 = column[..settings.outer * settings.inner]
                                .chunks_exact(settings.inner)
                                .map(|group| {
                                    let mean = group.iter().sum::<f64>() / settings.inner as f64;
                                    group.iter().map(|y| (y - mean).powi(2)).sum::<f64>()
                                        / (settings.inner - 1) as f64
                                })
                                .sum();
                            total / settings.outer as f64
                        })
                        .collect()
                };
                for slot in 0..continuous.len() {
                    delta[slot][player] = cost[slot] - previous[slot];
                }
                previous = cost;
            }
            Ok(delta)
        })
        .collect::<Result<_, _>>()?;

    let m = n_permutations as f64;
    Ok(continuous
        .iter()
        .enumerate()
        .map(|(slot, &o)| {
            let v = variance[slot];
            let effects = players
                .iter()
                .enumerate()
                .map(|(j, player)| {
                    let values: Vec<f64> = contributions.iter().map(|c| c[slot][j] / v).collect();
                    let mean = values.iter().sum::<f64>() / m;
                    let sd = if values.len() > 1 {
                        (values.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (m - 1.0)).sqrt()
                    } else {
                        0.0
                    };
                    let half = 1.96 * sd / m.sqrt();
                    ShapleyEffect {
                        input: player.name.clone(),
                        effect: mean,
                        interval: [mean - half, mean + half],
                    }
                })
                .collect();
            (scenario.outputs[o].name.clone(), effects)
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn permutations_in_lexicographic_order() {
        let all: Vec<Vec<usize>> = (0..6).map(|p| nth_permutation(3, p)).collect();
        assert_eq!(
            all,
            [
                [0, 1, 2],
                [0, 2, 1],
                [1, 0, 2],
                [1, 2, 0],
                [2, 0, 1],
                [2, 1, 0]
            ]
        );
    }
}
