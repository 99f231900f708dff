//! Subset simulation (Au & Beck, "Estimation of small failure probabilities in high
//! dimensions by subset simulation", Probab. Eng. Mech. 16 (2001) 263–277) with the
//! conditional-sampling Markov chains of Papaioannou, Betz, Zwirglmaier & Straub ("MCMC
//! algorithms for subset simulation", Probab. Eng. Mech. 41 (2015) 89–103).
//!
//! One run: N points from the standard normal law; at each level the threshold b is the
//! midpoint of the (p₀N)-th and (p₀N + 1)-th largest scores, the level's conditional
//! probability the share of points above it, and those points seed chains that stay
//! above it: from z, the candidate ρz + √(1 − ρ²)ξ (ξ standard normal; it leaves φ
//! invariant, so the chain's law is φ conditioned on s > b with no rejection on the
//! density) is taken when its score is above b, else z is repeated. The chains move in
//! step (each step one parallel batch) until the level holds N points again. When at
//! least p₀N points are in the event, the run ends with P̂ = Π(level shares) × (share in
//! the event). ρ starts at 0.8 and adapts between levels to an acceptance near 0.44
//! (σ = √(1 − ρ²) multiplied by exp(a − 0.44), Papaioannou et al. §4).
//!
//! One run's estimate has a small bias (O(1/N)) and a spread that its chains' correlation
//! makes hard to state from the run alone, so rvtol repeats independent runs (run r from
//! the ChaCha8 stream `STREAM + r` of the seed) and states the mean of the runs with
//! Student's interval from their spread: at least [`MIN_RUNS`], until the half width is
//! at most the asked share of the mean or the budget is spent. The same figures for a
//! seed at any thread count.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use statrs::distribution::{ContinuousCDF, StudentsT};

use super::limit::LimitState;
use super::{Budget, Estimate};

/// Conditional probability per level.
pub const LEVEL_PROBABILITY: f64 = 0.1;
/// Runs before the interval may stop the repetitions.
pub const MIN_RUNS: u64 = 10;
/// Levels before a run gives up (p₀³⁰ = 10⁻³⁰).
const MAX_LEVELS: usize = 30;
/// The streams of the runs: 2⁶² + r.
const STREAM: u64 = 1 << 62;
/// The stream of the run that finds the importance sampling's centre: 2⁶² + 2⁶⁰.
pub const CENTRE_STREAM: u64 = (1 << 62) + (1 << 60);

/// One run's result.
struct Run {
    probability: f64,
    /// Per intermediate level, its threshold and the probability of scoring above it.
    levels: Vec<(f64, f64)>,
    /// Its last level (the one that reached the event).
    last: Level,
}

/// The subset-simulation estimate of `limit`'s event with `level_samples` points per
/// level, or why there is none (a run that found no way towards the event).
pub fn estimate(
    limit: &mut LimitState,
    level_samples: usize,
    seed: u64,
    budget: &Budget,
) -> Result<Estimate, String> {
    let start = limit.evaluations;
    let mut runs: Vec<f64> = Vec::new();
    let mut levels: Vec<Vec<(f64, f64)>> = Vec::new();
    loop {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(STREAM + runs.len() as u64);
        let run = one_run(limit, level_samples, &mut rng)?;
        runs.push(run.probability);
        levels.push(run.levels);
        let spent = limit.evaluations - start;
        let per_run = spent / runs.len() as u64;
        let (mean, half) = interval(&runs);
        let reached = runs.len() as u64 >= MIN_RUNS && half <= budget.precision * mean;
        if reached || spent + per_run > budget.max_evaluations {
            return Ok(Estimate {
                probability: mean,
                interval: [(mean - half).max(0.0), mean + half],
                evaluations: spent,
                reached,
                events: 0,
                runs: runs.len() as u64,
                tail: mean_levels(&levels),
                warning: (runs.len() < 2)
                    .then(|| "one run only: no interval (raise the evaluation budget)".to_string()),
            });
        }
    }
}

/// The mean threshold and probability of each intermediate level that every run reached.
fn mean_levels(levels: &[Vec<(f64, f64)>]) -> Vec<(f64, f64)> {
    let common = levels.iter().map(Vec::len).min().unwrap_or(0);
    let r = levels.len() as f64;
    (0..common)
        .map(|l| {
            let (b, p) =
                (levels.iter()).fold((0.0, 0.0), |(b, p), run| (b + run[l].0, p + run[l].1));
            (b / r, p / r)
        })
        .collect()
}

/// The mean of the runs and the half width of its 95 % Student interval (∞ for one run).
fn interval(runs: &[f64]) -> (f64, f64) {
    let r = runs.len() as f64;
    let mean = runs.iter().sum::<f64>() / r;
    if runs.len() < 2 {
        return (mean, f64::INFINITY);
    }
    let variance = runs.iter().map(|p| (p - mean).powi(2)).sum::<f64>() / (r - 1.0);
    let t = StudentsT::new(0.0, 1.0, r - 1.0)
        .expect("at least one degree of freedom")
        .inverse_cdf(0.975);
    (mean, t * (variance / r).sqrt())
}

/// One subset-simulation run: its estimate, and its last level's points and scores.
fn one_run(limit: &mut LimitState, n: usize, rng: &mut ChaCha8Rng) -> Result<Run, String> {
    let dims = limit.dims().max(1);
    let seeds_wanted = ((LEVEL_PROBABILITY * n as f64).round() as usize).max(1);
    let points: Vec<f64> = (0..n * dims).map(|_| rng.sample(StandardNormal)).collect();
    let scores = limit.scores(&points);
    let mut level = Level {
        points,
        scores,
        sigma: (1.0f64 - 0.8 * 0.8).sqrt(),
    };
    let mut probability = 1.0;
    let mut levels = Vec::new();
    for step in 0..MAX_LEVELS {
        let count = level.scores.len();
        let in_event = level.scores.iter().filter(|&&s| s > 0.0).count();
        if in_event >= seeds_wanted {
            return Ok(Run {
                probability: probability * in_event as f64 / count as f64,
                levels,
                last: level,
            });
        }
        let threshold = level_threshold(&level.scores, seeds_wanted);
        let seeds: Vec<usize> = (0..count)
            .filter(|&i| level.scores[i] > threshold)
            .collect();
        if seeds.is_empty() || !threshold.is_finite() {
            return Err(format!(
                "level {} found no points above its threshold (the score is flat there): the event cannot be approached step by step",
                step + 1
            ));
        }
        probability *= seeds.len() as f64 / count as f64;
        levels.push((threshold, probability));
        level = level.grow(limit, &seeds, threshold, n, rng);
    }
    Err(format!(
        "{MAX_LEVELS} levels did not reach the event (below {:e})",
        LEVEL_PROBABILITY.powi(MAX_LEVELS as i32)
    ))
}

/// The points of one level with their scores, and the chains' step σ.
struct Level {
    points: Vec<f64>,
    scores: Vec<f64>,
    sigma: f64,
}

impl Level {
    /// The next level: chains from `seeds` (indices of points) that stay above
    /// `threshold`, moved in step until they hold at least `n` points; σ adapted to the
    /// acceptance.
    fn grow(
        &self,
        limit: &mut LimitState,
        seeds: &[usize],
        threshold: f64,
        n: usize,
        rng: &mut ChaCha8Rng,
    ) -> Level {
        let dims = limit.dims().max(1);
        let mut chains: Vec<f64> = (seeds.iter())
            .flat_map(|&i| self.points[i * dims..(i + 1) * dims].to_vec())
            .collect();
        let mut chain_scores: Vec<f64> = seeds.iter().map(|&i| self.scores[i]).collect();
        let steps = n.div_ceil(seeds.len());
        let (sigma, rho) = (self.sigma, (1.0 - self.sigma * self.sigma).max(0.0).sqrt());
        let mut points = chains.clone();
        let mut scores = chain_scores.clone();
        let mut accepted = 0usize;
        for _ in 1..steps {
            let candidates: Vec<f64> = (chains.iter())
                .map(|&z| rho * z + sigma * rng.sample::<f64, _>(StandardNormal))
                .collect();
            let candidate_scores = limit.scores(&candidates);
            for (c, &s) in candidate_scores.iter().enumerate() {
                if s > threshold {
                    chains[c * dims..(c + 1) * dims]
                        .copy_from_slice(&candidates[c * dims..(c + 1) * dims]);
                    chain_scores[c] = s;
                    accepted += 1;
                }
            }
            points.extend_from_slice(&chains);
            scores.extend_from_slice(&chain_scores);
        }
        let moves = (steps - 1) * seeds.len();
        let sigma = match moves {
            0 => sigma,
            _ => (sigma * (accepted as f64 / moves as f64 - 0.44).exp()).min(1.0),
        };
        Level {
            points,
            scores,
            sigma,
        }
    }
}

/// The mean of the normal law conditioned on the event, E[z | s(z) > 0]: the centre of
/// the importance sampling where FORM finds none (the normal law closest in cross entropy
/// to the optimal importance density φ·1[s > 0]/P has this mean; Rubinstein & Kroese,
/// *The Cross-Entropy Method*, 2004). From one subset-simulation run of `n` points a level
/// (ChaCha8 stream [`CENTRE_STREAM`] of `seed`), whose event points seed chains that stay
/// in the event until they hold `n` points (one more level at threshold 0): their mean.
///
/// Refused when more than [`FAR_SIDE`] of those points lie on the far side of the nominal
/// point from their mean (z·μ < 0): the event surrounds the nominal point (a sum of
/// squares beyond a radius) or has regions in opposite directions, and no one centre
/// stands for it.
pub fn conditional_mean(limit: &mut LimitState, n: usize, seed: u64) -> Result<Vec<f64>, String> {
    let dims = limit.dims().max(1);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(CENTRE_STREAM);
    let run = one_run(limit, n, &mut rng)?;
    let seeds: Vec<usize> = (0..run.last.scores.len())
        .filter(|&i| run.last.scores[i] > 0.0)
        .collect();
    let filled = run.last.grow(limit, &seeds, 0.0, n, &mut rng);
    let count = filled.scores.len() as f64;
    let mean: Vec<f64> = (0..dims)
        .map(|d| filled.points.iter().skip(d).step_by(dims).sum::<f64>() / count)
        .collect();
    let far = (filled.points.chunks_exact(dims))
        .filter(|z| z.iter().zip(&mean).map(|(z, m)| z * m).sum::<f64>() < 0.0)
        .count() as f64
        / count;
    if far > FAR_SIDE {
        return Err(format!(
            "{:.0} % of the event's points lie on the far side of the nominal point from their mean: the event surrounds it or lies in opposite directions, and no one centre stands for it",
            100.0 * far
        ));
    }
    Ok(mean)
}

/// The share of the event's points beyond which their mean is no centre.
pub const FAR_SIDE: f64 = 0.05;

/// The midpoint of the `k`-th and (k + 1)-th largest scores.
fn level_threshold(scores: &[f64], k: usize) -> f64 {
    let mut sorted = scores.to_vec();
    sorted.sort_unstable_by(|a, b| b.total_cmp(a));
    let (upper, lower) = (sorted[k - 1], sorted[k.min(sorted.len() - 1)]);
    if upper == f64::INFINITY {
        return lower;
    }
    0.5 * (upper + lower)
}
