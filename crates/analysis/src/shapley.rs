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
//! The estimate is the merge of partials of permutation ranges ([`shapley_partial`],
//! [`merge_shapley`]), so a sharded estimate is the single one bit for bit.

use std::ops::Range;

use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use rvtol_deviation::ConditionalSampler;

use rvtol_engine::chunk::CHUNK_SIZE;
use rvtol_engine::evaluate::ChunkEvaluator;
use rvtol_engine::scenario::{InputGroup, Scenario, ScenarioError};
use rvtol_engine::{FoldError, MergeError};

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

/// What a range of permutations contributes to the Shapley effects: the part of the
/// estimate a shard computes ([`shapley_partial`]) and [`merge_shapley`] finishes.
#[derive(Debug, Clone, PartialEq)]
pub struct ShapleyPartial {
    /// The permutations covered.
    pub permutations: Range<u64>,
    /// Var Y per continuous output, from the plain run (the partial that starts at
    /// permutation 0 has it).
    pub variance: Option<Vec<f64>>,
    /// Per permutation: its order of the players, and the cost c(J) after each of its
    /// first d − 1 players, per continuous output (the last one's is Var Y).
    pub steps: Vec<(Vec<u64>, Vec<Vec<f64>>)>,
}

/// The checked settings of one estimate.
struct ShapleyPlan {
    players: Vec<InputGroup>,
    continuous: Vec<usize>,
    /// d! when all orders are used.
    exact: Option<usize>,
    permutations: usize,
}

fn shapley_plan(
    scenario: &Scenario,
    settings: ShapleySettings,
) -> Result<ShapleyPlan, ScenarioError> {
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
    // All d! orders, each repeated as often as the budget allows, when d! fits in it.
    let exact = factorial(d).filter(|&f| f <= settings.permutations);
    let permutations = match exact {
        Some(f) => f * (settings.permutations / f),
        None => settings.permutations,
    };
    Ok(ShapleyPlan {
        players,
        continuous: scenario.continuous_outputs(),
        exact,
        permutations,
    })
}

/// Number of permutations the estimate runs (all d! orders repeated, or the budget).
pub fn shapley_permutations(
    scenario: &Scenario,
    settings: ShapleySettings,
) -> Result<u64, ScenarioError> {
    Ok(shapley_plan(scenario, settings)?.permutations as u64)
}

/// Shapley effects of every continuous output: `result[output] = (name, effects)`, effects in
/// the order of [`players`].
pub fn shapley_effects(
    scenario: &Scenario,
    settings: ShapleySettings,
) -> Result<Vec<(String, Vec<ShapleyEffect>)>, ScenarioError> {
    let n = shapley_permutations(scenario, settings)?;
    let partial = shapley_partial(scenario, settings, 0..n)?;
    merge_shapley(scenario, settings, vec![partial]).map_err(FoldError::of_own_partial)
}

/// Runs permutations `permutations` of the estimate (a shard of it), and the variance run
/// when the range starts at permutation 0.
pub fn shapley_partial(
    scenario: &Scenario,
    settings: ShapleySettings,
    permutations: Range<u64>,
) -> Result<ShapleyPartial, ScenarioError> {
    let plan = shapley_plan(scenario, settings)?;
    if permutations.start > permutations.end || permutations.end > plan.permutations as u64 {
        return Err(ScenarioError::new(
            "shapley",
            format!(
                "permutations {}..{} are not within the estimate's {}",
                permutations.start, permutations.end, plan.permutations
            ),
        ));
    }
    let (players, continuous) = (&plan.players, &plan.continuous);
    let d = players.len();
    let space = &scenario.input_space;
    let n_columns = space.n_columns();

    // Var Y from a plain run.
    let variance = if permutations.start == 0 {
        let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
        rng.set_stream(SHAPLEY_STREAM_BASE - 1);
        let mut counts = space.new_constraint_counts();
        let mut evaluator = ChunkEvaluator::new(scenario);
        let mut moments = vec![rvtol_engine::stats::Moments::new(); continuous.len()];
        let mut rows = vec![0.0; CHUNK_SIZE * n_columns];
        for _ in 0..VARIANCE_ROWS / CHUNK_SIZE {
            space.sample_rows(&mut rng, &mut rows, &mut counts)?;
            evaluator.evaluate(&rows, CHUNK_SIZE);
            for (slot, &o) in continuous.iter().enumerate() {
                moments[slot].merge(&rvtol_engine::stats::Moments::from_slice(
                    &evaluator.output_columns[o],
                ));
            }
        }
        Some(moments.iter().map(|m| m.variance()).collect())
    } else {
        None
    };

    // The cost after each of the first d − 1 players of each permutation.
    let steps = (permutations.start..permutations.end)
        .into_par_iter()
        .map(|p| -> Result<(Vec<u64>, Vec<Vec<f64>>), ScenarioError> {
            let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
            rng.set_stream(SHAPLEY_STREAM_BASE + p);
            let order = match plan.exact {
                Some(f) => nth_permutation(d, p as usize % f),
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
            let mut free: Vec<usize> = Vec::new();
            let mut z = Vec::new();
            let mut costs = Vec::with_capacity(d.saturating_sub(1));
            for &player in &order[..d - 1] {
                free.extend(&players[player].columns);
                let sampler: ConditionalSampler = space.conditional_sampler(&free)?;
                // Conditional draws work on normal scores (a copula column's), then values.
                space.sample_latent_rows(&mut rng, &mut outer_rows, &mut counts)?;
                for (outer, base) in outer_rows.chunks_exact(n_columns).enumerate() {
                    for inner in 0..settings.inner {
                        let start = (outer * settings.inner + inner) * n_columns;
                        let row = &mut rows[start..start + n_columns];
                        row.copy_from_slice(base);
                        sampler.sample(&mut rng, row, &mut z);
                        space.latent_to_values(row);
                    }
                }
                evaluator.evaluate(&rows, settings.outer * settings.inner);
                costs.push(
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
                        .collect(),
                );
            }
            Ok((order.iter().map(|&j| j as u64).collect(), costs))
        })
        .collect::<Result<_, _>>()?;
    Ok(ShapleyPartial {
        permutations,
        variance,
        steps,
    })
}

/// The effects from partials that cover the estimate's permutations exactly once (in any
/// order): bit for bit those of [`shapley_effects`], which merges its own single partial.
pub fn merge_shapley(
    scenario: &Scenario,
    settings: ShapleySettings,
    mut partials: Vec<ShapleyPartial>,
) -> Result<Vec<(String, Vec<ShapleyEffect>)>, FoldError> {
    let plan = shapley_plan(scenario, settings)?;
    let broken = |message: String| Err(MergeError::new(message).into());
    partials.sort_by_key(|p| (p.permutations.start, p.permutations.end));
    let (players, continuous) = (&plan.players, &plan.continuous);
    let d = players.len();
    let mut next = 0;
    for partial in &partials {
        if partial.permutations.start != next {
            return broken(format!(
                "Shapley permutations {}..{} are missing or in two partials",
                next.min(partial.permutations.start),
                next.max(partial.permutations.start)
            ));
        }
        let fits = partial.steps.len() as u64 == partial.permutations.end - next
            && partial.steps.iter().all(|(order, costs)| {
                let mut seen = vec![false; d];
                order.len() == d
                    && order.iter().all(|&j| {
                        (j as usize) < d && !std::mem::replace(&mut seen[j as usize], true)
                    })
                    && costs.len() == d - 1
                    && costs.iter().all(|c| c.len() == continuous.len())
            });
        if !fits {
            return broken("a partial's Shapley permutations do not fit the estimate".into());
        }
        next = partial.permutations.end;
    }
    if next != plan.permutations as u64 {
        return broken(format!(
            "Shapley permutations {next}..{} are missing",
            plan.permutations
        ));
    }
    let Some(variance) = partials
        .first()
        .and_then(|p| p.variance.clone())
        .filter(|v| v.len() == continuous.len())
    else {
        return broken("the Shapley variance run is missing".into());
    };

    // Marginal contributions per permutation: [permutation][output][player].
    let contributions: Vec<Vec<Vec<f64>>> = partials
        .iter()
        .flat_map(|p| &p.steps)
        .map(|(order, costs)| {
            let mut delta = vec![vec![0.0; d]; continuous.len()];
            let mut previous = vec![0.0; continuous.len()];
            for (k, &player) in order.iter().enumerate() {
                let cost = if k + 1 == d { &variance } else { &costs[k] };
                for slot in 0..continuous.len() {
                    delta[slot][player as usize] = cost[slot] - previous[slot];
                }
                previous.clone_from(cost);
            }
            delta
        })
        .collect();

    let m = plan.permutations as f64;
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
