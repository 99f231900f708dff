//! The chunk-and-stream contract, the ground floor of a run: how its rows are laid out
//! in chunks and drawn, whoever draws them (the run, a shard of it, the sensitivity
//! analysis' matrices).
//!
//! - Samples are drawn in chunks of [`CHUNK_SIZE`] rows, each chunk from its own stream
//!   (`ChaCha8Rng::seed_from_u64(seed)` then `set_stream(k)` for chunk k), block of
//!   [`BLOCK_ROWS`] rows after block; neither size depends on the thread count (changing
//!   either changes results).
//! - A Latin hypercube or RQMC run ([`Sampling`]) lays its R replicates out one after
//!   another, each in chunks of its own (its last one shorter).
//! - Chunks are processed in waves of [`WAVE_CHUNKS`] ([`waves`]) so memory stays bounded;
//!   a sharded run takes contiguous ranges of chunks ([`shard_range`]).

use std::ops::Range;

use rvtol_deviation::InputSpace;
pub use rvtol_deviation::SamplingMethod;

use crate::error::ScenarioError;

/// Samples per chunk (part of the reproducibility contract: changing it changes results).
pub const CHUNK_SIZE: usize = 4096;
/// Rows sampled and evaluated at a time inside a chunk (part of the stream layout): small
/// enough that a block's rows, model inputs and outputs stay in the core's caches.
pub const BLOCK_ROWS: usize = 64;
/// Chunks per wave: bounds the memory of in-flight partial results.
pub const WAVE_CHUNKS: u64 = 1024;
/// How a run's rows (and a sensitivity analysis' matrices A and B,
/// rvtol-analysis' `sensitivity`) are drawn: the method and its independent randomizations.
///
/// Monte Carlo has one (its rows are independent; the report's intervals come from them).
/// A Latin hypercube or scrambled Sobol' run of N samples is R independent replicates of
/// n = N/R points (replicate r holds samples r·n … (r+1)·n − 1); its statistics are those
/// of all N rows, and each figure's interval comes from the spread of its R replicate
/// values (Student t with R − 1 degrees of freedom), the rows of one replicate not being
/// independent.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Sampling {
    /// The method.
    pub method: SamplingMethod,
    /// Independent randomizations (1 for Monte Carlo).
    pub replicates: u64,
}

impl Default for Sampling {
    fn default() -> Sampling {
        Sampling::MONTE_CARLO
    }
}

impl Sampling {
    /// Plain Monte Carlo.
    pub const MONTE_CARLO: Sampling = Sampling {
        method: SamplingMethod::MonteCarlo,
        replicates: 1,
    };
    /// Replicates of a Latin hypercube or RQMC run unless the scenario says.
    pub const DEFAULT_REPLICATES: u64 = 16;
    /// Fewest replicates: an interval from R values needs R − 1 ≥ 1 degrees of freedom.
    pub const MIN_REPLICATES: u64 = 2;
    /// Most replicates (each keeps its own statistics).
    pub const MAX_REPLICATES: u64 = 1024;

    /// The method with its default replicates.
    pub fn of(method: SamplingMethod) -> Sampling {
        match method {
            SamplingMethod::MonteCarlo => Sampling::MONTE_CARLO,
            _ => Sampling {
                method,
                replicates: Sampling::DEFAULT_REPLICATES,
            },
        }
    }

    /// The sampling a caller asks for over `scenario`'s: the method given, else the
    /// scenario's; the replicates given, else the scenario's when the method is the
    /// scenario's, else the method's default.
    pub fn chosen(
        scenario: Sampling,
        method: Option<SamplingMethod>,
        replicates: Option<u64>,
    ) -> Sampling {
        let method = method.unwrap_or(scenario.method);
        let mut sampling = if method == scenario.method {
            scenario
        } else {
            Sampling::of(method)
        };
        if let Some(replicates) = replicates {
            sampling.replicates = replicates;
        }
        sampling
    }

    /// Whether the rows come from replicated point sets (Latin hypercube or RQMC).
    pub fn is_replicated(&self) -> bool {
        self.method != SamplingMethod::MonteCarlo
    }
}

impl Sampling {
    /// Rows per replicate of `samples` rows (all of them for Monte Carlo).
    pub fn replicate_points(&self, samples: u64) -> u64 {
        samples / self.replicates.max(1)
    }

    fn chunks_per_replicate(&self, samples: u64) -> u64 {
        self.replicate_points(samples).div_ceil(CHUNK_SIZE as u64)
    }

    /// Number of chunks of `samples` rows: each replicate's rows in chunks of
    /// [`CHUNK_SIZE`] (the last one of each replicate shorter), replicate after replicate.
    pub fn chunk_count(&self, samples: u64) -> u64 {
        self.replicates.max(1) * self.chunks_per_replicate(samples)
    }

    /// Chunk `chunk` of `samples` rows as (replicate, its first row within the replicate,
    /// its first row overall, rows).
    pub fn chunk_rows(&self, samples: u64, chunk: u64) -> (u64, u64, u64, usize) {
        let per = self.chunks_per_replicate(samples).max(1);
        let (replicate, local) = (chunk / per, chunk % per);
        let n = self.replicate_points(samples);
        let first = local * CHUNK_SIZE as u64;
        let rows = (n - first).min(CHUNK_SIZE as u64) as usize;
        (replicate, first, replicate * n + first, rows)
    }

    /// Rows of `samples` in the chunks before `chunk` (for progress).
    pub fn rows_before_chunk(&self, samples: u64, chunk: u64) -> u64 {
        if chunk >= self.chunk_count(samples) {
            return samples;
        }
        self.chunk_rows(samples, chunk).2
    }

    /// Checks this sampling of `samples` rows (`what` names that count in messages)
    /// against the scenario: for a replicated method, replicates within their range
    /// dividing the rows, points per replicate within the method's limit, and an input
    /// space it can draw; Monte Carlo has one replicate (one line each, naming the
    /// setting).
    pub fn check(
        &self,
        samples: u64,
        what: &str,
        input_space: &InputSpace,
    ) -> Result<(), ScenarioError> {
        let Sampling { method, replicates } = *self;
        if !self.is_replicated() {
            if replicates != 1 {
                return Err(ScenarioError::new(
                    "replicates",
                    "Monte Carlo rows are independent and have no replicates: give replicates with \"sampling\": \"lhs\" or \"rqmc\"",
                ));
            }
            return Ok(());
        }
        if !(Sampling::MIN_REPLICATES..=Sampling::MAX_REPLICATES).contains(&replicates) {
            return Err(ScenarioError::new(
                "replicates",
                format!(
                    "must lie in {}..={}, got {replicates}",
                    Sampling::MIN_REPLICATES,
                    Sampling::MAX_REPLICATES
                ),
            ));
        }
        if !samples.is_multiple_of(replicates) || samples < 2 * replicates {
            return Err(ScenarioError::new(
                "samples",
                format!(
                    "{samples} {what} do not split into {replicates} replicates of equal size (at least 2 points each): give a multiple of {replicates}{}",
                    if method == SamplingMethod::Rqmc {
                        format!(", best {replicates} × a power of two such as {}", replicates * (samples / replicates).max(2).next_power_of_two())
                    } else {
                        String::new()
                    }
                ),
            ));
        }
        if self.replicate_points(samples) > method.max_points() {
            return Err(ScenarioError::new(
                "samples",
                format!(
                    "{} points per replicate, {} takes at most {}: give more replicates",
                    self.replicate_points(samples),
                    method.name(),
                    method.max_points()
                ),
            ));
        }
        input_space.quasi_dimensions()?;
        Ok(())
    }
}

/// The `shard`-th of `shards` contiguous ranges of `0..total`, as equal as whole items
/// allow (chunks of a run, permutations of a Shapley estimate).
pub fn shard_range(total: u64, shard: u64, shards: u64) -> Range<u64> {
    let at = |k: u64| (k as u128 * total as u128 / shards.max(1) as u128) as u64;
    at(shard.min(shards))..at((shard + 1).min(shards))
}

/// Consecutive ranges of at most [`WAVE_CHUNKS`] chunks covering `chunks`.
pub fn waves(chunks: Range<u64>) -> impl Iterator<Item = Range<u64>> {
    (chunks.start..chunks.end)
        .step_by(WAVE_CHUNKS as usize)
        .map(move |start| start..(start + WAVE_CHUNKS).min(chunks.end))
}
