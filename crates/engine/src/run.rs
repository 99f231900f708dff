//! The reproducible parallel Monte Carlo run.
//!
//! Reproducibility contract: the same (rvtol version, scenario, seed, samples, sampling)
//! give bit-identical statistics whatever the thread count.
//! - Samples are drawn in chunks of [`CHUNK_SIZE`]; chunk k draws from its own stream,
//!   `ChaCha8Rng::seed_from_u64(seed)` then `set_stream(k)`. The chunk size never depends
//!   on the thread count. A Latin hypercube or RQMC run ([`Sampling`]) lays its replicates
//!   out one after another, each in chunks of its own (its last one shorter), and a row is
//!   the point of its replicate and index, a pure function of the seed: no stream.
//! - Each replicate's counts and distributions stay apart until the merge, which computes
//!   its figures ([`ReplicateFigures`]) for the replicate intervals and then pools them;
//!   a Monte Carlo run has one replicate, so its statistics are those it always had.
//! - Each chunk's moments are kept with its index and merged sequentially in chunk order
//!   (never with a parallel float reduction). Everything else merged across threads is an
//!   integer count (spec violations, events, sketch buckets, constraint attempts) or a
//!   multiset whose order the result does not depend on (the values kept for exact
//!   percentiles).
//! - Chunks run in waves of [`WAVE_CHUNKS`] so memory stays bounded for any sample count.
//! - A run is the merge of partials ([`RunPartial`]: the statistics of a contiguous range
//!   of chunks, their moments still per chunk): [`run`] merges its waves as they finish,
//!   [`merge`] the partials of shards computed anywhere ([`run_chunks`] on the ranges of
//!   [`shard_range`] over [`RunSettings::chunk_count`]); both fold through the same code
//!   in chunk order, so a sharded run has the single run's bits for any shard count.
//!
//! Per chunk, block of [`BLOCK_ROWS`] rows after block: draw the inputs as a column-major
//! block, hand each model its input columns (constants pre-filled once) and evaluate it
//! into the chunk's output columns; then fold each output column into the statistics.
//! Non-finite outputs are counted per output (with the first such sample) and kept out of
//! the statistics; an output's qualifying indicator excludes samples or flags them
//! non-conforming ([`OutputAccumulator`]).

use std::ops::Range;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use rvtol_deviation::{ConstraintCounts, PointSet, SamplerScratch};
use rvtol_models::{ConditionEffect, Curve, OutputKind};

use crate::chunk::{waves, Sampling, BLOCK_ROWS, CHUNK_SIZE};
use crate::error::MergeError;
use crate::evaluate::{check_table_rows, ChunkEvaluator, SampleTable};
use crate::scenario::{OutputInfo, Scenario, ScenarioError};
use crate::stats::conformity::Placement;
use crate::stats::{values_at_ranks, Moments, QuantileSketch, SpecLimits, PERCENTS};

/// Relative accuracy of the quantile sketch used beyond the exact-percentile limit.
pub const SKETCH_RELATIVE_ACCURACY: f64 = 1e-3;
/// Default memory cap for exact percentiles: values kept over all outputs (8 bytes each).
pub const DEFAULT_EXACT_PERCENTILE_LIMIT: u64 = 8_000_000;

/// What to run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunSettings {
    /// Number of samples (≥ 1).
    pub samples: u64,
    /// Seed of the random streams.
    pub seed: u64,
    /// Exact percentiles while samples × outputs stays at or below this; a quantile sketch
    /// beyond it.
    pub exact_percentile_limit: u64,
    /// How the rows are drawn.
    pub sampling: Sampling,
}

impl RunSettings {
    /// Rows per replicate (all the samples for Monte Carlo).
    pub fn replicate_points(&self) -> u64 {
        self.sampling.replicate_points(self.samples)
    }

    /// Number of chunks ([`Sampling::chunk_count`]).
    pub fn chunk_count(&self) -> u64 {
        self.sampling.chunk_count(self.samples)
    }

    /// Chunk `chunk` as (replicate, its first row within the replicate, its first sample
    /// in the run, rows).
    pub fn chunk_rows(&self, chunk: u64) -> (u64, u64, u64, usize) {
        self.sampling.chunk_rows(self.samples, chunk)
    }

    /// Samples in the chunks before `chunk` (for progress).
    pub fn samples_before_chunk(&self, chunk: u64) -> u64 {
        self.sampling.rows_before_chunk(self.samples, chunk)
    }

    /// Checks the settings against the scenario: at least one sample, and the sampling
    /// ([`Sampling::check`]).
    pub fn check(&self, scenario: &Scenario) -> Result<(), ScenarioError> {
        if self.samples == 0 {
            return Err(ScenarioError::new("samples", "must be at least 1"));
        }
        (self.sampling).check(self.samples, "samples", &scenario.input_space)
    }
}

/// One replicate's figures of one output, for the replicate intervals.
///
/// Each is an estimator that is unbiased, or whose bias is bounded, under the design,
/// since a replicated design's estimators vary so little that a bias of order 1/n would
/// otherwise exceed the replicates' standard error and the interval would undercover
/// (docs/models.md §6, "Replicate intervals"):
/// - the sd is √(m2/n + V̂), V̂ the sample variance of the R replicate means: E[m2] =
///   n·σ² − n·Var(x̄) for any design whose points each follow the output's law, so
///   m2/n + V̂ is unbiased for σ² (the n − 1 divisor of independent rows is not: under a
///   stratified design Var(x̄) ≪ σ²/n and m2/(n − 1) is σ²·n/(n − 1));
/// - a percentile is read at two ranks, Hazen's n·p − ½ (unbiased in probability when
///   the output is a monotone function of one stratified input: the i-th order statistic
///   then lies uniformly in the i-th stratum) and Weibull's (n + 1)·p − 1 (unbiased for
///   independent rows); the estimate is their midpoint and half their difference bounds
///   its bias for any design in between.
#[derive(Debug, Clone, PartialEq)]
pub struct ReplicateFigures {
    /// Mean.
    pub mean: f64,
    /// Standard deviation, unbiased in variance under the design (above).
    pub sd: f64,
    /// The percentiles of [`PERCENTS`]: the midpoint of the Hazen and Weibull estimates
    /// (exact order statistics), or the sketch's; `None` where either rank falls outside
    /// the replicate's values.
    pub percentiles: Vec<Option<f64>>,
    /// Half the difference of the Hazen and Weibull estimates of each percentile (0 from
    /// the sketch): the bound of the estimate's bias.
    pub percentile_bias_bounds: Vec<Option<f64>>,
    /// Share of the replicate's rows out of spec.
    pub out_of_spec_fraction: f64,
}

/// The sd of a replicated run's output `o` from its replicates' figures: √ of the mean of
/// their unbiased variances ([`ReplicateFigures`]), which is also m2_all/N + V̂/R of all
/// rows; `None` for a Monte Carlo run (no replicates).
pub fn replicated_sd(replicates: &[Vec<ReplicateFigures>], o: usize) -> Option<f64> {
    (!replicates.is_empty()).then(|| {
        let variance: f64 =
            replicates.iter().map(|r| r[o].sd * r[o].sd).sum::<f64>() / replicates.len() as f64;
        variance.sqrt()
    })
}

/// How the percentiles of a run were computed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PercentileMethod {
    /// Exact order statistics, Hyndman–Fan type 7 interpolation.
    Exact,
    /// Relative-accuracy quantile sketch of the standardised output: the value returned
    /// lies within α·|value − centre| of the order statistic of rank ⌊q·(n−1)⌋, the centre
    /// being the mean of the pilot chunk 0.
    Sketch {
        /// Relative error bound α.
        relative_accuracy: f64,
    },
}

/// What a run keeps of an output's values for its percentiles and histogram: the values
/// themselves, a sketch of them, or nothing. Kept values, not a probability law (the
/// scenario's laws are rvtol-deviation's `ScalarDistribution`).
#[derive(Debug, Clone)]
pub enum KeptValues {
    /// Every finite value (exact percentiles).
    Values(Vec<f64>),
    /// A quantile sketch of the standardised values (x − center)/scale, so its relative
    /// accuracy applies to the distance from the output's centre in units of its spread.
    Sketch {
        /// The sketch.
        sketch: QuantileSketch,
        /// Centre subtracted before insertion (the pilot mean).
        center: f64,
        /// Scale divided out before insertion (the pilot standard deviation).
        scale: f64,
    },
    /// Nothing kept: an indicator output, whose distribution is its event count.
    Indicator,
    /// Nothing kept: the caller asked for this output's moments and counts only
    /// ([`run_for_output`]).
    Dropped,
}

/// The accumulated statistics of one output.
///
/// Every sample lands in exactly one of: a finite value (in the moments and the
/// distribution), `non_finite` (the model could not evaluate it) or `excluded` (its
/// [`ConditionEffect::Excluded`] indicator was set: the output has no value there). A
/// sample conforms to the spec limits when its value is finite, within the limits and not
/// flagged non-conforming; [`OutputAccumulator::out_of_spec`] counts the others.
#[derive(Debug, Clone)]
pub struct OutputAccumulator {
    /// Moments, min and max of the finite values.
    pub moments: Moments,
    /// Samples whose value was NaN or infinite although no condition excluded them: lost
    /// data, kept out of the statistics, counted out of spec, reported and (beyond the
    /// allowed share) failing the run.
    pub non_finite: u64,
    /// The first sample (index in the run) whose value was not finite, if any.
    pub first_non_finite: Option<u64>,
    /// Samples excluded by the output's indicator (an interfering profile): kept out of the
    /// statistics, counted out of spec.
    pub excluded: u64,
    /// Samples flagged non-conforming by the output's indicator (a preloaded stage); their
    /// values are in the statistics.
    pub flagged: u64,
    /// Flagged samples whose value lies within the spec limits: out of spec unless the
    /// scenario lets flagged samples conform.
    pub flagged_within_spec: u64,
    /// Finite samples below the lower spec limit.
    pub below_lower: u64,
    /// Finite samples above the upper spec limit.
    pub above_upper: u64,
    /// Samples whose value was non-zero (the events of an indicator output).
    pub nonzero: u64,
    /// Values or sketch, for percentiles and the histogram: of every finite value, except
    /// those of samples flagged non-conforming (unless `flagged_conform`), which are in
    /// `flagged_kept`.
    pub kept: KeptValues,
    /// The values of the samples flagged non-conforming, kept apart so that a conformity
    /// figure places them beyond the limits ([`crate::stats::conformity`]) while the
    /// histogram and the value percentiles still show them; [`KeptValues::Dropped`] for an
    /// output whose flags do not take samples out of conformity.
    pub flagged_kept: KeptValues,
}

impl OutputAccumulator {
    fn new(kept: KeptValues, flagged_kept: KeptValues) -> OutputAccumulator {
        OutputAccumulator {
            moments: Moments::new(),
            non_finite: 0,
            first_non_finite: None,
            excluded: 0,
            flagged: 0,
            flagged_within_spec: 0,
            below_lower: 0,
            above_upper: 0,
            nonzero: 0,
            kept,
            flagged_kept,
        }
    }

    /// The samples of a run of `samples` that a conformity figure places beyond the
    /// limits: every sample whose value is not among `kept` (not finite, excluded, or
    /// flagged non-conforming).
    pub fn beyond(&self, samples: u64) -> u64 {
        samples.saturating_sub(self.kept.count())
    }

    /// Samples that do not conform to the spec limits: outside them, not finite, excluded,
    /// or flagged non-conforming within them (unless `flagged_conform`).
    pub fn out_of_spec(&self, flagged_conform: bool) -> u64 {
        self.below_lower
            + self.above_upper
            + self.non_finite
            + self.excluded
            + if flagged_conform {
                0
            } else {
                self.flagged_within_spec
            }
    }

    /// Adds another partial's counts and distribution (moments are merged separately, in
    /// chunk order).
    fn add_counts(&mut self, other: &OutputAccumulator) {
        self.non_finite += other.non_finite;
        self.first_non_finite = match (self.first_non_finite, other.first_non_finite) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
        self.excluded += other.excluded;
        self.flagged += other.flagged;
        self.flagged_within_spec += other.flagged_within_spec;
        self.below_lower += other.below_lower;
        self.above_upper += other.above_upper;
        self.nonzero += other.nonzero;
    }
}

/// The result of a run, before it is turned into a report.
#[derive(Debug, Clone)]
pub struct RunResult {
    /// Samples drawn.
    pub samples: u64,
    /// Seed used.
    pub seed: u64,
    /// Percentile method used.
    pub percentile_method: PercentileMethod,
    /// Constraint rejection tally, per independent group of inequalities.
    pub constraint_counts: ConstraintCounts,
    /// One accumulator per scenario output, in order: the statistics of all the rows.
    pub outputs: Vec<OutputAccumulator>,
    /// How the rows were drawn.
    pub sampling: Sampling,
    /// Per replicate of a Latin hypercube or RQMC run, each output's figures (empty for
    /// Monte Carlo).
    pub replicates: Vec<Vec<ReplicateFigures>>,
}

/// Each replicate's accumulators (one per output) among some chunks, by replicate index
/// in increasing order; a Monte Carlo run has replicate 0 only.
pub type ReplicateAccumulators = Vec<(u64, Vec<OutputAccumulator>)>;

/// The accumulators of `replicate` in `list`, created empty by `new` when missing.
fn replicate_entry(
    list: &mut ReplicateAccumulators,
    replicate: u64,
    new: impl FnOnce() -> Vec<OutputAccumulator>,
) -> &mut Vec<OutputAccumulator> {
    let at = match list.binary_search_by_key(&replicate, |(r, _)| *r) {
        Ok(at) => at,
        Err(at) => {
            list.insert(at, (replicate, new()));
            at
        }
    };
    &mut list[at].1
}

/// Adds `other`'s replicates' counts and distributions to `mine` (both by replicate).
fn absorb_replicates(
    mine: &mut ReplicateAccumulators,
    other: ReplicateAccumulators,
) -> Result<(), MergeError> {
    for (replicate, outputs) in other {
        match mine.binary_search_by_key(&replicate, |(r, _)| *r) {
            Ok(at) => absorb_counts(&mut mine[at].1, outputs)?,
            Err(at) => mine.insert(at, (replicate, outputs)),
        }
    }
    Ok(())
}

/// One worker's scratch buffers and the statistics of the chunks it ran.
struct Worker<'a> {
    /// One column-major block of sampled inputs.
    columns: Vec<f64>,
    sampler: SamplerScratch,
    evaluator: ChunkEvaluator<'a>,
    finite: Vec<f64>,
    chunk_moments: Vec<(u64, Vec<Moments>)>,
    /// Counts and distributions per replicate and output (their moments stay per chunk
    /// until the merge).
    replicates: ReplicateAccumulators,
    constraint_counts: ConstraintCounts,
    error: Option<(u64, ScenarioError)>,
}

struct Plan<'a> {
    scenario: &'a Scenario,
    settings: RunSettings,
    exact: bool,
    limits: Vec<Option<SpecLimits>>,
    indicator: Vec<bool>,
    /// Per output: its qualifying indicator output and what a set flag means.
    conditions: Vec<Option<(usize, ConditionEffect)>>,
    /// (center, scale) of each output's sketch, from the pilot chunk.
    sketch_frames: Vec<(f64, f64)>,
    /// The only output whose values are kept, when the caller needs one.
    only_output: Option<usize>,
    /// Per output: whether flagged samples conform (`flagged_conform`).
    flagged_conform: Vec<bool>,
    /// The Latin hypercube or scrambled Sobol' points of a replicated run.
    points: Option<PointSet>,
}

/// The point set of a replicated run (None for Monte Carlo), after checking the settings.
fn point_set(
    scenario: &Scenario,
    settings: RunSettings,
) -> Result<Option<PointSet>, ScenarioError> {
    settings.check(scenario)?;
    if !settings.sampling.is_replicated() {
        return Ok(None);
    }
    let dims = scenario.input_space.quasi_dimensions()?;
    PointSet::new(
        settings.sampling.method,
        dims,
        settings.replicate_points(),
        settings.seed,
    )
    .map(Some)
    .map_err(|message| ScenarioError::new("sampling", message))
}

impl<'a> Plan<'a> {
    /// The plan of a run of `scenario`; the sketch frames are the identity until the pilot
    /// chunk sets them.
    fn new(
        scenario: &'a Scenario,
        settings: RunSettings,
        exact: bool,
        only_output: Option<usize>,
        points: Option<PointSet>,
    ) -> Plan<'a> {
        Plan {
            scenario,
            settings,
            exact,
            limits: scenario.outputs.iter().map(|o| o.spec).collect(),
            indicator: scenario
                .outputs
                .iter()
                .map(|o| o.kind == OutputKind::Indicator)
                .collect(),
            conditions: scenario.outputs.iter().map(|o| o.condition).collect(),
            sketch_frames: vec![(0.0, 1.0); scenario.outputs.len()],
            only_output,
            flagged_conform: scenario.outputs.iter().map(|o| o.flagged_conform).collect(),
            points,
        }
    }

    /// The plan of a run (or of a shard of it): exact percentiles or a sketch as the run's
    /// settings decide, the sketch's frame from the pilot chunk.
    fn for_run(
        scenario: &'a Scenario,
        settings: RunSettings,
        only_output: Option<usize>,
    ) -> Result<Plan<'a>, ScenarioError> {
        let points = point_set(scenario, settings)?;
        // Only continuous outputs keep their values (an indicator's percentiles are its
        // counts), so only they count against the limit.
        let kept_outputs = if only_output.is_some() {
            1
        } else {
            scenario.continuous_outputs().len() as u64
        };
        let exact =
            settings.samples.saturating_mul(kept_outputs.max(1)) <= settings.exact_percentile_limit;
        let mut plan = Plan::new(scenario, settings, exact, only_output, points);
        if !exact {
            plan.sketch_frames = plan.pilot_sketch_frames()?;
        }
        Ok(plan)
    }

    /// The statistics of no chunk, starting at chunk `start`.
    fn empty_partial(&self, start: u64) -> RunPartial {
        RunPartial {
            chunks: start..start,
            percentile_method: if self.exact {
                PercentileMethod::Exact
            } else {
                PercentileMethod::Sketch {
                    relative_accuracy: SKETCH_RELATIVE_ACCURACY,
                }
            },
            constraint_counts: self.scenario.input_space.new_constraint_counts(),
            chunk_moments: Vec::new(),
            replicates: Vec::new(),
        }
    }

    /// Empty accumulators of every output.
    fn new_accumulators(&self) -> Vec<OutputAccumulator> {
        (0..self.scenario.outputs.len())
            .map(|o| {
                let flagged_apart = matches!(
                    self.conditions[o],
                    Some((_, ConditionEffect::NonConforming))
                ) && !self.flagged_conform[o];
                let flagged_kept = if flagged_apart {
                    self.new_kept_values(o)
                } else {
                    KeptValues::Dropped
                };
                OutputAccumulator::new(self.new_kept_values(o), flagged_kept)
            })
            .collect()
    }

    /// Runs the chunks of one wave in parallel and gathers them into one partial.
    fn run_wave(
        &self,
        chunks: Range<u64>,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<RunPartial, ScenarioError> {
        // About four splits per thread, from the chunks this wave really has (a short run
        // with an expensive model must still reach every thread).
        let min_chunks_per_split = ((chunks.end - chunks.start) as usize
            / (4 * rayon::current_num_threads().max(1)))
        .max(1);
        let workers: Vec<Worker> = (chunks.start as usize..chunks.end as usize)
            .into_par_iter()
            // A few splits per thread: each split allocates its scratch buffers and
            // statistics once. Grouping does not change any result (see the module
            // comment).
            .with_min_len(min_chunks_per_split)
            .fold(
                || self.worker(),
                |mut worker, chunk| {
                    let chunk = chunk as u64;
                    self.run_chunk(&mut worker, chunk);
                    progress(self.chunk_len(chunk) as u64);
                    worker
                },
            )
            .collect();
        if let Some((_, err)) = workers
            .iter()
            .filter_map(|w| w.error.as_ref())
            .min_by_key(|(chunk, _)| *chunk)
        {
            return Err(err.clone());
        }
        let mut partial = self.empty_partial(chunks.start);
        partial.chunks = chunks;
        for worker in workers {
            partial.constraint_counts.add(&worker.constraint_counts);
            // The workers' chunks of one wave, of one plan: they always fold.
            absorb_replicates(&mut partial.replicates, worker.replicates)
                .expect("a wave's workers fold");
            partial.chunk_moments.extend(worker.chunk_moments);
        }
        partial
            .chunk_moments
            .sort_unstable_by_key(|(chunk, _)| *chunk);
        Ok(partial)
    }

    fn worker(&self) -> Worker<'a> {
        Worker {
            columns: vec![0.0; BLOCK_ROWS * self.scenario.input_space.n_columns()],
            sampler: SamplerScratch::default(),
            evaluator: ChunkEvaluator::new(self.scenario),
            finite: Vec::with_capacity(CHUNK_SIZE),
            chunk_moments: Vec::new(),
            replicates: Vec::new(),
            constraint_counts: self.scenario.input_space.new_constraint_counts(),
            error: None,
        }
    }

    fn new_kept_values(&self, output: usize) -> KeptValues {
        if self.indicator[output] {
            KeptValues::Indicator
        } else if self.only_output.is_some_and(|o| o != output) {
            KeptValues::Dropped
        } else if self.exact {
            KeptValues::Values(Vec::new())
        } else {
            let (center, scale) = self.sketch_frames[output];
            KeptValues::Sketch {
                sketch: QuantileSketch::new(SKETCH_RELATIVE_ACCURACY),
                center,
                scale,
            }
        }
    }

    fn chunk_len(&self, chunk: u64) -> usize {
        self.settings.chunk_rows(chunk).3
    }

    /// Draws chunk `chunk` and evaluates the models into `worker.output_columns`;
    /// returns the number of samples, or records the error.
    fn evaluate_chunk(&self, worker: &mut Worker, chunk: u64) -> Option<usize> {
        self.evaluate_chunk_keeping(worker, chunk, None)
    }

    /// [`Plan::evaluate_chunk`], appending the drawn input rows (row-major) to `inputs`
    /// when given.
    fn evaluate_chunk_keeping(
        &self,
        worker: &mut Worker,
        chunk: u64,
        mut inputs: Option<&mut Vec<f64>>,
    ) -> Option<usize> {
        let (replicate, first_row, _, m) = self.settings.chunk_rows(chunk);
        let space = &self.scenario.input_space;
        let n_columns = space.n_columns();
        let mut rng = ChaCha8Rng::seed_from_u64(self.settings.seed);
        rng.set_stream(chunk);
        for first in (0..m).step_by(BLOCK_ROWS) {
            let block = (m - first).min(BLOCK_ROWS);
            let columns = &mut worker.columns[..block * n_columns];
            let drawn = match &self.points {
                None => space.sample_columns_with(
                    &mut rng,
                    columns,
                    &mut worker.constraint_counts,
                    &mut worker.sampler,
                ),
                Some(points) => space.sample_columns_from_points(
                    points,
                    replicate,
                    first_row + first as u64,
                    columns,
                    &mut worker.sampler,
                ),
            };
            if let Err(err) = drawn {
                worker.error = Some((chunk, err.into()));
                return None;
            }
            if let Some(rows) = inputs.as_deref_mut() {
                for r in 0..block {
                    rows.extend((0..n_columns).map(|c| columns[c * block + r]));
                }
            }
            worker.evaluator.evaluate_columns_at(columns, block, first);
        }
        Some(m)
    }

    /// Centre and scale of each output's sketch: mean and standard deviation of the finite
    /// values of chunk 0, which every run draws identically whatever its thread count.
    fn pilot_sketch_frames(&self) -> Result<Vec<(f64, f64)>, ScenarioError> {
        let mut worker = self.worker();
        if self.evaluate_chunk(&mut worker, 0).is_none() {
            let (_, err) = worker.error.expect("evaluate_chunk records its error");
            return Err(err);
        }
        let m = self.chunk_len(0);
        Ok(worker
            .evaluator
            .output_columns
            .iter()
            .map(|column| {
                let finite: Vec<f64> = column[..m]
                    .iter()
                    .copied()
                    .filter(|v| v.is_finite())
                    .collect();
                let moments = Moments::from_slice(&finite);
                let center = if moments.n > 0 { moments.mean } else { 0.0 };
                let sd = moments.sd();
                let scale = if sd > 0.0 && sd.is_finite() {
                    sd
                } else if center != 0.0 {
                    center.abs()
                } else {
                    1.0
                };
                (center, scale)
            })
            .collect())
    }

    fn run_chunk(&self, worker: &mut Worker, chunk: u64) {
        if worker.error.is_some() {
            return;
        }
        let Some(m) = self.evaluate_chunk(worker, chunk) else {
            return;
        };
        let (replicate, _, first_sample, _) = self.settings.chunk_rows(chunk);
        let columns = &worker.evaluator.output_columns;
        let accumulators = replicate_entry(&mut worker.replicates, replicate, || {
            self.new_accumulators()
        });
        let mut moments = Vec::with_capacity(columns.len());
        for (o, column) in columns.iter().enumerate() {
            let values = &column[..m];
            let acc = &mut accumulators[o];
            if self.indicator[o] {
                // Events only: the moments follow from the counts at the end.
                let finite = values.iter().filter(|v| v.is_finite()).count();
                note_non_finite(acc, values, m - finite, first_sample);
                acc.nonzero += values
                    .iter()
                    .filter(|&&v| v.is_finite() && v != 0.0)
                    .count() as u64;
                moments.push(Moments::new());
                continue;
            }
            let flags = self.conditions[o].map(|(k, effect)| (&columns[k][..m], effect));
            let kept: &[f64] = match flags {
                Some((flags, ConditionEffect::Excluded)) => {
                    // Flagged samples have no value; any other non-finite one is lost data.
                    worker.finite.clear();
                    let mut excluded = 0;
                    for (&v, &flag) in values.iter().zip(flags) {
                        if is_set(flag) {
                            excluded += 1;
                        } else if v.is_finite() {
                            worker.finite.push(v);
                        }
                    }
                    acc.excluded += excluded;
                    let lost = m - excluded as usize - worker.finite.len();
                    if lost > 0 {
                        let unflagged_non_finite =
                            values
                                .iter()
                                .zip(flags)
                                .map(|(&v, &flag)| if is_set(flag) { 0.0 } else { v });
                        note_first_non_finite(acc, unflagged_non_finite, lost, first_sample);
                    }
                    &worker.finite
                }
                _ => {
                    let finite = values.iter().filter(|v| v.is_finite()).count();
                    if finite < m {
                        note_non_finite(acc, values, m - finite, first_sample);
                        worker.finite.clear();
                        worker
                            .finite
                            .extend(values.iter().copied().filter(|v| v.is_finite()));
                        &worker.finite
                    } else {
                        values
                    }
                }
            };
            moments.push(Moments::from_slice(kept));
            if let Some(limits) = self.limits[o] {
                let below = |v: f64| limits.lower.is_some_and(|lower| v < lower);
                let above = |v: f64| limits.upper.is_some_and(|upper| v > upper);
                if limits.lower.is_some() {
                    acc.below_lower += kept.iter().filter(|&&v| below(v)).count() as u64;
                }
                if limits.upper.is_some() {
                    acc.above_upper += kept.iter().filter(|&&v| above(v)).count() as u64;
                }
                if let Some((flags, ConditionEffect::NonConforming)) = flags {
                    acc.flagged_within_spec += values
                        .iter()
                        .zip(flags)
                        .filter(|&(&v, &flag)| {
                            is_set(flag) && v.is_finite() && !below(v) && !above(v)
                        })
                        .count() as u64;
                }
            }
            if let Some((flags, ConditionEffect::NonConforming)) = flags {
                acc.flagged += flags.iter().filter(|&&flag| is_set(flag)).count() as u64;
            }
            match flags {
                // A flagged sample's value apart: conformity figures place it beyond the
                // limits.
                Some((flags, ConditionEffect::NonConforming))
                    if !matches!(acc.flagged_kept, KeptValues::Dropped) =>
                {
                    let (mut flagged, mut conforming) = (Vec::new(), Vec::new());
                    for (&v, &flag) in values.iter().zip(flags) {
                        if v.is_finite() {
                            if is_set(flag) {
                                &mut flagged
                            } else {
                                &mut conforming
                            }
                            .push(v);
                        }
                    }
                    acc.kept.extend(&conforming);
                    acc.flagged_kept.extend(&flagged);
                }
                _ => acc.kept.extend(kept),
            }
        }
        worker.chunk_moments.push((chunk, moments));
    }
}

/// Draws and evaluates every sample of the run `settings` describes, keeping each row
/// ([`SampleTable`]); at most [`crate::evaluate::MAX_SAMPLE_TABLE_VALUES`] values. Uses the current rayon
/// thread pool; the chunks' rows are joined in chunk order.
pub fn sample_table(
    scenario: &Scenario,
    settings: RunSettings,
) -> Result<SampleTable, ScenarioError> {
    let points = point_set(scenario, settings)?;
    check_table_rows(scenario, settings.samples)
        .map_err(|message| ScenarioError::new("samples", message))?;
    let n_inputs = scenario.input_space.n_columns();
    let n_outputs = scenario.outputs.len();
    let plan = Plan::new(scenario, settings, true, None, points);
    let n_chunks = settings.chunk_count();
    // Per chunk: its input rows and output rows, row-major.
    type Rows = (Vec<f64>, Vec<f64>);
    let chunks: Vec<Result<Rows, ScenarioError>> = (0..n_chunks)
        .into_par_iter()
        .map_init(
            || plan.worker(),
            |worker, chunk| {
                let mut inputs = Vec::with_capacity(plan.chunk_len(chunk) * n_inputs);
                let Some(m) = plan.evaluate_chunk_keeping(worker, chunk, Some(&mut inputs)) else {
                    let (_, err) = worker
                        .error
                        .take()
                        .expect("evaluate_chunk records its error");
                    return Err(err);
                };
                let columns = &worker.evaluator.output_columns;
                let mut outputs = Vec::with_capacity(m * n_outputs);
                for r in 0..m {
                    outputs.extend(columns.iter().map(|column| column[r]));
                }
                Ok((inputs, outputs))
            },
        )
        .collect();
    let rows = settings.samples as usize;
    let mut table = SampleTable {
        rows,
        n_inputs,
        n_outputs,
        inputs: Vec::with_capacity(rows * n_inputs),
        outputs: Vec::with_capacity(rows * n_outputs),
    };
    for chunk in chunks {
        let (inputs, outputs) = chunk?;
        table.inputs.extend(inputs);
        table.outputs.extend(outputs);
    }
    Ok(table)
}

/// Runs the scenario. `progress` is called with the number of samples each finished chunk
/// drew (from worker threads). Uses the current rayon thread pool.
pub fn run(
    scenario: &Scenario,
    settings: RunSettings,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<RunResult, ScenarioError> {
    run_keeping(scenario, settings, None, progress)
}

/// [`run`] for a caller that needs the distribution of one output only (the allocation):
/// the other outputs keep their moments and counts but no values or sketch
/// ([`KeptValues::Dropped`]), so memory grows with one output's values.
pub fn run_for_output(
    scenario: &Scenario,
    settings: RunSettings,
    output: usize,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<RunResult, ScenarioError> {
    run_keeping(scenario, settings, Some(output), progress)
}

fn run_keeping(
    scenario: &Scenario,
    settings: RunSettings,
    only_output: Option<usize>,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<RunResult, ScenarioError> {
    let plan = Plan::for_run(scenario, settings, only_output)?;
    let mut merger = RunMerger::new(scenario, settings);
    // The run's own waves, in order and of one plan: they always fold.
    const FOLDS: &str = "a run's own waves fold in order";
    for wave in waves(0..settings.chunk_count()) {
        merger.add(plan.run_wave(wave, progress)?).expect(FOLDS);
    }
    Ok(merger.finish().expect(FOLDS))
}

/// The statistics of a contiguous range of a run's chunks: what one shard of a run
/// computes ([`run_chunks`]) and [`merge`] folds into the run's result.
///
/// The moments stay per chunk (folding them per shard would change the last bits of the
/// merged moments); everything else is an integer count or a multiset of values or sketch
/// buckets, which merge exactly in any order.
#[derive(Debug, Clone)]
pub struct RunPartial {
    /// The chunks covered.
    pub chunks: Range<u64>,
    /// Percentile method of the run (decided from the run's settings, not the range).
    pub percentile_method: PercentileMethod,
    /// Constraint rejection tally of these chunks.
    pub constraint_counts: ConstraintCounts,
    /// Each chunk's moments of every output, in chunk order.
    pub chunk_moments: Vec<(u64, Vec<Moments>)>,
    /// Counts and distribution of each output over these chunks, per replicate; their
    /// `moments` are empty (see `chunk_moments`).
    pub replicates: ReplicateAccumulators,
}

impl RunPartial {
    /// Adds the statistics of the chunks that directly follow.
    fn append(&mut self, next: RunPartial) -> Result<(), ScenarioError> {
        if next.chunks.start != self.chunks.end {
            return Err(ScenarioError::new(
                "(run)",
                format!(
                    "chunks {}..{} do not follow chunks {}..{}",
                    next.chunks.start, next.chunks.end, self.chunks.start, self.chunks.end
                ),
            ));
        }
        self.constraint_counts.add(&next.constraint_counts);
        // The next wave of the same plan (checked above): it always folds.
        absorb_replicates(&mut self.replicates, next.replicates).expect("a run's waves fold");
        self.chunk_moments.extend(next.chunk_moments);
        self.chunks.end = next.chunks.end;
        Ok(())
    }
}

/// Runs the chunks `chunks` of the run `settings` describes (a shard of it): the same
/// draws and statistics as those chunks have in [`run`], whatever the thread count. Uses
/// the current rayon thread pool. A run with a quantile sketch evaluates chunk 0 first (the
/// sketch's frame) whatever the range.
pub fn run_chunks(
    scenario: &Scenario,
    settings: RunSettings,
    chunks: Range<u64>,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<RunPartial, ScenarioError> {
    let n_chunks = settings.chunk_count();
    if chunks.start > chunks.end || chunks.end > n_chunks {
        return Err(ScenarioError::new(
            "(run)",
            format!(
                "chunks {}..{} are not within the run's {n_chunks} chunks",
                chunks.start, chunks.end
            ),
        ));
    }
    let plan = Plan::for_run(scenario, settings, None)?;
    let mut partial = plan.empty_partial(chunks.start);
    for wave in waves(chunks) {
        partial.append(plan.run_wave(wave, progress)?)?;
    }
    Ok(partial)
}

/// The result of the run `settings` describes, from partials that cover its chunks
/// exactly once (in any order): bit for bit the result of [`run`], since the moments are
/// folded in chunk order as the run folds them and every other statistic merges exactly.
pub fn merge(
    scenario: &Scenario,
    settings: RunSettings,
    mut partials: Vec<RunPartial>,
) -> Result<RunResult, MergeError> {
    partials.sort_by_key(|p| (p.chunks.start, p.chunks.end));
    let mut merger = RunMerger::new(scenario, settings);
    for partial in partials {
        merger.add(partial)?;
    }
    merger.finish()
}

/// Folds partials into a run's result in chunk order.
struct RunMerger<'a> {
    scenario: &'a Scenario,
    settings: RunSettings,
    next_chunk: u64,
    percentile_method: Option<PercentileMethod>,
    constraint_counts: ConstraintCounts,
    /// Each replicate's accumulators, as they arrive.
    replicates: Vec<Option<Vec<OutputAccumulator>>>,
    /// The moments of all rows, folded in chunk order.
    moments: Vec<Moments>,
    /// Each replicate's moments, folded in chunk order (replicated runs only).
    replicate_moments: Vec<Vec<Moments>>,
}

impl<'a> RunMerger<'a> {
    fn new(scenario: &'a Scenario, settings: RunSettings) -> RunMerger<'a> {
        let n_out = scenario.outputs.len();
        let replicates = settings.sampling.replicates.max(1) as usize;
        RunMerger {
            scenario,
            settings,
            next_chunk: 0,
            percentile_method: None,
            constraint_counts: scenario.input_space.new_constraint_counts(),
            replicates: vec![None; replicates],
            moments: vec![Moments::new(); n_out],
            replicate_moments: if settings.sampling.is_replicated() {
                vec![vec![Moments::new(); n_out]; replicates]
            } else {
                Vec::new()
            },
        }
    }

    /// Adds the partial of the chunks that follow those added so far.
    fn add(&mut self, partial: RunPartial) -> Result<(), MergeError> {
        let broken = |message: String| Err(MergeError::new(message));
        if partial.chunks.start != self.next_chunk {
            return broken(if partial.chunks.start < self.next_chunk {
                format!(
                    "chunks {}..{} overlap chunks already merged (up to {})",
                    partial.chunks.start, partial.chunks.end, self.next_chunk
                )
            } else {
                format!(
                    "chunks {}..{} are missing",
                    self.next_chunk, partial.chunks.start
                )
            });
        }
        let n_out = self.scenario.outputs.len();
        if let Some((_, outputs)) = partial.replicates.iter().find(|(_, o)| o.len() != n_out) {
            return broken(format!(
                "a partial has {} outputs, the scenario {n_out}",
                outputs.len()
            ));
        }
        let expected: Vec<u64> = partial.chunks.clone().collect();
        let has: Vec<u64> = partial.chunk_moments.iter().map(|(c, _)| *c).collect();
        let widths_match = partial.chunk_moments.iter().all(|(_, m)| m.len() == n_out);
        let replicates_match = partial
            .replicates
            .iter()
            .all(|(r, _)| (*r as usize) < self.replicates.len());
        if expected != has || !widths_match || !replicates_match {
            return broken(format!(
                "the moments of chunks {}..{} are incomplete",
                partial.chunks.start, partial.chunks.end
            ));
        }
        self.next_chunk = partial.chunks.end;
        match self.percentile_method {
            Some(method) if method != partial.percentile_method => {
                return broken("the partials' percentile methods differ".into());
            }
            _ => self.percentile_method = Some(partial.percentile_method),
        }
        self.constraint_counts.add(&partial.constraint_counts);
        let points = self.settings.replicate_points() as usize;
        for (replicate, outputs) in partial.replicates {
            match &mut self.replicates[replicate as usize] {
                slot @ None => {
                    let mut outputs = outputs;
                    for output in &mut outputs {
                        if let KeptValues::Values(values) = &mut output.kept {
                            values.reserve_exact(points.saturating_sub(values.len()));
                        }
                    }
                    *slot = Some(outputs);
                }
                Some(mine) => absorb_counts(mine, outputs)?,
            }
        }
        for (chunk, moments) in partial.chunk_moments {
            for (output, m) in self.moments.iter_mut().zip(&moments) {
                output.merge(m);
            }
            if !self.replicate_moments.is_empty() {
                let (replicate, ..) = self.settings.chunk_rows(chunk);
                for (output, m) in self.replicate_moments[replicate as usize]
                    .iter_mut()
                    .zip(&moments)
                {
                    output.merge(m);
                }
            }
        }
        Ok(())
    }

    fn finish(self) -> Result<RunResult, MergeError> {
        let n_chunks = self.settings.chunk_count();
        let missing = || {
            MergeError::new(format!(
                "chunks {}..{n_chunks} are missing",
                self.next_chunk.min(n_chunks)
            ))
        };
        if self.next_chunk != n_chunks || self.replicates.iter().any(Option::is_none) {
            return Err(missing());
        }
        let percentile_method = self.percentile_method.ok_or_else(missing)?;
        let indicator: Vec<bool> = (self.scenario.outputs.iter())
            .map(|o| o.kind == OutputKind::Indicator)
            .collect();
        let mut replicates: Vec<Vec<OutputAccumulator>> =
            self.replicates.into_iter().flatten().collect();
        // Each replicate's figures before its values join the others.
        let mut figures: Vec<Vec<ReplicateFigures>> = if self.replicate_moments.is_empty() {
            Vec::new()
        } else {
            let points = self.settings.replicate_points();
            replicates
                .iter_mut()
                .zip(&self.replicate_moments)
                .map(|(outputs, moments)| {
                    outputs
                        .iter_mut()
                        .zip(moments)
                        .zip(self.scenario.outputs.iter().zip(&indicator))
                        .map(|((acc, m), (info, &indicator))| {
                            let m = if indicator {
                                indicator_moments(acc.nonzero, points - acc.non_finite)
                            } else {
                                m.clone()
                            };
                            replicate_figures(acc, &m, points, info)
                        })
                        .collect()
                })
                .collect()
        };
        unbias_replicate_sds(&mut figures);
        let mut replicates = replicates.into_iter();
        let mut outputs = replicates.next().expect("at least one replicate");
        if !figures.is_empty() {
            for output in &mut outputs {
                if let KeptValues::Values(values) = &mut output.kept {
                    values.reserve_exact(self.settings.samples as usize - values.len());
                }
            }
        }
        for other in replicates {
            absorb_counts(&mut outputs, other)?;
        }
        for ((output, moments), &indicator) in outputs.iter_mut().zip(self.moments).zip(&indicator)
        {
            output.moments = if indicator {
                indicator_moments(output.nonzero, self.settings.samples - output.non_finite)
            } else {
                moments
            };
        }
        Ok(RunResult {
            samples: self.settings.samples,
            seed: self.settings.seed,
            percentile_method,
            constraint_counts: self.constraint_counts,
            outputs,
            sampling: self.settings.sampling,
            replicates: figures,
        })
    }
}

/// One replicate's figures of an output from its accumulator and moments (`points` rows);
/// its sd is √(m2/n) until [`unbias_replicate_sds`] adds the replicate means' variance.
fn replicate_figures(
    acc: &mut OutputAccumulator,
    moments: &Moments,
    points: u64,
    info: &OutputInfo,
) -> ReplicateFigures {
    let placement = Placement::of(info.spec);
    let percents: Vec<f64> = PERCENTS.iter().map(|p| p.1 / 100.0).collect();
    let (percentiles, percentile_bias_bounds) = match &mut acc.kept {
        KeptValues::Values(values) => {
            let n = values.len();
            // Among the replicate's points, the samples beyond the limits in the tail each
            // percentile reads (crate::stats::conformity).
            let beyond = (points as usize).saturating_sub(n);
            let total = (n + beyond) as f64;
            // Hazen's and Weibull's positions of each percentile among all the points,
            // as positions among the values (NaN where a sample beyond is read), in one pass.
            let among_values = |position: f64, percent: f64| {
                if beyond == 0 {
                    position
                } else if placement.above(percent) {
                    if position.ceil() <= (n as f64 - 1.0) {
                        position
                    } else {
                        f64::NAN
                    }
                } else if position.floor() >= beyond as f64 {
                    position - beyond as f64
                } else {
                    f64::NAN
                }
            };
            let positions: Vec<f64> = percents
                .iter()
                .flat_map(|&p| {
                    [total * p - 0.5, (total + 1.0) * p - 1.0]
                        .map(|position| among_values(position, 100.0 * p))
                })
                .collect();
            let read = values_at_ranks(values, &positions);
            read.chunks(2)
                .zip(positions.chunks(2))
                .zip(&percents)
                .map(|((pair, at), &p)| match (pair[0], pair[1]) {
                    (Some(hazen), Some(weibull)) => (
                        Some(0.5 * (hazen + weibull)),
                        Some(0.5 * (hazen - weibull).abs()),
                    ),
                    _ if at.iter().any(|h| h.is_nan()) => {
                        (Some(placement.beyond_value(100.0 * p)), Some(0.0))
                    }
                    _ => (None, None),
                })
                .unzip()
        }
        KeptValues::Sketch {
            sketch,
            center,
            scale,
        } => {
            let n = sketch.count();
            let beyond = points.saturating_sub(n);
            let last = (n + beyond).saturating_sub(1);
            percents
                .iter()
                .map(|&p| {
                    // Rank ⌊q·(N − 1)⌋ among the points (the sketch's quantile when no
                    // sample is beyond the limits).
                    let rank = ((p.clamp(0.0, 1.0) * last as f64).floor() as u64).min(last);
                    let at =
                        placement.value_rank(rank as usize, n as usize, beyond as usize, 100.0 * p);
                    let value = match at {
                        Some(k) => sketch
                            .order_statistic(k as u64)
                            .map(|z| (*center + *scale * z).clamp(moments.min, moments.max)),
                        None => Some(placement.beyond_value(100.0 * p)),
                    };
                    (value, value.map(|_| 0.0))
                })
                .unzip()
        }
        KeptValues::Indicator | KeptValues::Dropped => {
            (vec![None; percents.len()], vec![None; percents.len()])
        }
    };
    let population_variance = if moments.n > 0 {
        moments.m2 / moments.n as f64
    } else {
        f64::NAN
    };
    ReplicateFigures {
        mean: moments.mean,
        sd: population_variance.sqrt(),
        percentiles,
        percentile_bias_bounds,
        out_of_spec_fraction: acc.out_of_spec(info.flagged_conform) as f64 / points as f64,
    }
}

/// Makes each replicate's sd √(m2/n + V̂), V̂ the sample variance of the replicates'
/// means of the same output ([`ReplicateFigures`]).
fn unbias_replicate_sds(figures: &mut [Vec<ReplicateFigures>]) {
    let outputs = figures.first().map_or(0, Vec::len);
    for o in 0..outputs {
        let means: Vec<f64> = figures.iter().map(|r| r[o].mean).collect();
        let variance_of_means = Moments::from_slice(&means).variance();
        for replicate in figures.iter_mut() {
            let sd = &mut replicate[o].sd;
            *sd = (*sd * *sd + variance_of_means).sqrt();
        }
    }
}

/// Adds `other`'s counts and distributions (not its moments) to `outputs`.
fn absorb_counts(
    outputs: &mut [OutputAccumulator],
    other: Vec<OutputAccumulator>,
) -> Result<(), MergeError> {
    let mismatch = || MergeError::new("the partials' output statistics differ");
    if outputs.len() != other.len() {
        return Err(mismatch());
    }
    for (output, part) in outputs.iter_mut().zip(other) {
        output.add_counts(&part);
        output.kept.absorb(part.kept)?;
        output.flagged_kept.absorb(part.flagged_kept)?;
    }
    Ok(())
}

impl KeptValues {
    /// Adds `values` (finite) to the values or the sketch.
    fn extend(&mut self, values: &[f64]) {
        match self {
            KeptValues::Values(all) => all.extend_from_slice(values),
            KeptValues::Sketch {
                sketch,
                center,
                scale,
            } => sketch.insert_standardised(values, *center, 1.0 / *scale),
            KeptValues::Indicator | KeptValues::Dropped => {}
        }
    }

    /// The values kept (those in the sketch); 0 for nothing kept.
    pub fn count(&self) -> u64 {
        match self {
            KeptValues::Values(values) => values.len() as u64,
            KeptValues::Sketch { sketch, .. } => sketch.count(),
            KeptValues::Indicator | KeptValues::Dropped => 0,
        }
    }

    /// Adds another partial's values or sketch of the same kind.
    fn absorb(&mut self, part: KeptValues) -> Result<(), MergeError> {
        let mismatch = || MergeError::new("the partials' output statistics differ");
        match (self, part) {
            (KeptValues::Values(all), KeptValues::Values(part)) => all.extend_from_slice(&part),
            (KeptValues::Indicator, KeptValues::Indicator)
            | (KeptValues::Dropped, KeptValues::Dropped) => {}
            (
                KeptValues::Sketch {
                    sketch: all,
                    center,
                    scale,
                },
                KeptValues::Sketch {
                    sketch: part,
                    center: part_center,
                    scale: part_scale,
                },
            ) if center.to_bits() == part_center.to_bits()
                && scale.to_bits() == part_scale.to_bits() =>
            {
                all.merge(&part)
                    .map_err(|err| MergeError::new(err.to_string()))?
            }
            _ => return Err(mismatch()),
        }
        Ok(())
    }
}

/// Whether an indicator value flags its sample: finite and non-zero.
#[inline]
fn is_set(flag: f64) -> bool {
    flag.is_finite() && flag != 0.0
}

/// Whether one sample of output `o` does not conform, by the rule of
/// [`OutputAccumulator::out_of_spec`] sample by sample: its value outside the spec limits
/// or not finite, its qualifying indicator excluding it, or flagging it non-conforming
/// (unless the spec says flagged samples conform within the limits). `value` is the
/// output's, `flag` the value of its qualifying indicator (ignored without one). Without
/// spec limits only the flags and a non-finite value count.
pub fn sample_out_of_spec(scenario: &Scenario, o: usize, value: f64, flag: f64) -> bool {
    let info = &scenario.outputs[o];
    match info.condition {
        Some((_, ConditionEffect::Excluded)) if is_set(flag) => return true,
        Some((_, ConditionEffect::NonConforming)) if is_set(flag) && !info.flagged_conform => {
            return true
        }
        _ => {}
    }
    if !value.is_finite() {
        return true;
    }
    info.spec.is_some_and(|limits| {
        limits.lower.is_some_and(|lower| value < lower)
            || limits.upper.is_some_and(|upper| value > upper)
    })
}

/// Counts `count` non-finite values among `values` and records the first one's sample.
fn note_non_finite(acc: &mut OutputAccumulator, values: &[f64], count: usize, first: u64) {
    if count > 0 {
        note_first_non_finite(acc, values.iter().copied(), count, first);
    }
}

/// Adds `count` lost samples; the first non-finite value of `values` (sample `first` + its
/// position) becomes the output's first non-finite sample if it is earlier.
fn note_first_non_finite(
    acc: &mut OutputAccumulator,
    mut values: impl Iterator<Item = f64>,
    count: usize,
    first: u64,
) {
    acc.non_finite += count as u64;
    let position = values
        .position(|v| !v.is_finite())
        .map(|p| first + p as u64);
    acc.first_non_finite = match (acc.first_non_finite, position) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    };
}

/// Moments of a 0/1 sample with `events` ones among `n` values, in closed form.
fn indicator_moments(events: u64, n: u64) -> Moments {
    if n == 0 {
        return Moments::new();
    }
    let (k, nf) = (events as f64, n as f64);
    let p = k / nf;
    let (one, zero) = (1.0 - p, -p);
    let zeros = nf - k;
    Moments {
        n,
        mean: p,
        m2: k * one * one + zeros * zero * zero,
        m3: k * one.powi(3) + zeros * zero.powi(3),
        m4: k * one.powi(4) + zeros * zero.powi(4),
        min: if events < n { 0.0 } else { 1.0 },
        max: if events > 0 { 1.0 } else { 0.0 },
    }
}

/// Checks that no output lost more than `max_share` of its samples to non-finite values
/// (the model could not evaluate them), and that every output has a value at all (its
/// indicator did not exclude every sample): the first output that fails is an error naming
/// its model's JSON path, the count, the share and the first such sample.
pub fn check_non_finite(
    scenario: &Scenario,
    result: &RunResult,
    max_share: f64,
) -> Result<(), ScenarioError> {
    for (o, acc) in result.outputs.iter().enumerate() {
        if acc.moments.n == 0 && acc.excluded > 0 && acc.excluded + acc.non_finite == result.samples
        {
            let indicator = scenario.outputs[o]
                .condition
                .map_or(String::new(), |(k, _)| scenario.outputs[k].name.clone());
            return Err(ScenarioError::new(
                scenario.model_of_output(o),
                format!(
                    "{} has no value: {indicator} excludes {} of {} samples and the model could not evaluate the rest; the scenario describes an assembly that cannot be built",
                    scenario.outputs[o].name,
                    crate::format::group_thousands(acc.excluded),
                    crate::format::group_thousands(result.samples),
                ),
            ));
        }
        let share = acc.non_finite as f64 / result.samples as f64;
        if acc.non_finite > 0 && share > max_share {
            return Err(ScenarioError::new(
                scenario.model_of_output(o),
                format!(
                    "{} is not finite for {} of {} samples ({} %, first at sample {}), more than the allowed {} %: the model cannot evaluate the inputs the scenario draws there; narrow the distributions to the model's domain, or accept a share with --max-non-finite",
                    scenario.outputs[o].name,
                    crate::format::group_thousands(acc.non_finite),
                    crate::format::group_thousands(result.samples),
                    crate::format::format_sig(100.0 * share),
                    acc.first_non_finite.unwrap_or(0),
                    rvtol_deviation::Shown(100.0 * max_share),
                ),
            ));
        }
    }
    Ok(())
}

/// Every model evaluated in order with every deviation at its mean: each model's input
/// row (a chained input reads the nominal output of a model above) and every output's
/// value.
fn nominal_evaluation(scenario: &Scenario) -> (Vec<Vec<f64>>, Vec<f64>) {
    let row = scenario.input_space.mean_row();
    let mut values = vec![0.0; scenario.outputs.len()];
    let mut model_inputs = Vec::with_capacity(scenario.models.len());
    for bound in &scenario.models {
        let inputs = bound.inputs_of_row(&row, &values);
        let n_out = bound.model.outputs().len();
        bound.model.evaluate(
            &inputs,
            &mut values[bound.first_output..bound.first_output + n_out],
        );
        model_inputs.push(inputs);
    }
    (model_inputs, values)
}

/// The value of each output with every deviation at its mean (the nominal design):
/// `None` where the output's qualifying indicator excludes the nominal sample (an
/// interfering nominal profile). Any other non-finite value is an error naming the model
/// and the output: a nominal design the model cannot evaluate.
pub fn nominal(scenario: &Scenario) -> Result<Vec<Option<f64>>, ScenarioError> {
    let (_, values) = nominal_evaluation(scenario);
    let excluded = |o: usize| match scenario.outputs[o].condition {
        Some((k, ConditionEffect::Excluded)) => is_set(values[k]),
        _ => false,
    };
    (0..values.len())
        .map(|o| {
            if excluded(o) {
                Ok(None)
            } else if values[o].is_finite() {
                Ok(Some(values[o]))
            } else {
                Err(ScenarioError::new(
                    scenario.model_of_output(o),
                    format!(
                        "{} is {} at the nominal point (every deviation at its mean): the model cannot evaluate the scenario's nominal design",
                        scenario.outputs[o].name,
                        rvtol_deviation::Shown(values[o])
                    ),
                ))
            }
        })
        .collect()
}

/// The curves of every model that draws any (`rvtol curve`), with every deviation at its
/// mean: (model name, its curves) in scenario order. A curve with a non-finite point is an
/// error naming the model and the curve.
pub fn nominal_curves(
    scenario: &Scenario,
) -> Result<Vec<(&'static str, Vec<Curve>)>, ScenarioError> {
    nominal_curves_per_model(scenario)
        .into_iter()
        .map(|(name, curves)| curves.map(|curves| (name, curves)))
        .collect()
}

/// [`nominal_curves`] model by model: each model that draws curves with its curves, or the
/// error naming its first point that is not finite (a page leaves that model's curves out
/// and says why; the others are drawn).
pub fn nominal_curves_per_model(
    scenario: &Scenario,
) -> Vec<(&'static str, Result<Vec<Curve>, ScenarioError>)> {
    let (model_inputs, _) = nominal_evaluation(scenario);
    let mut drawn = Vec::new();
    for (i, (bound, inputs)) in scenario.models.iter().zip(&model_inputs).enumerate() {
        let curves = bound.model.curves(inputs);
        if curves.is_empty() {
            continue;
        }
        let broken = curves.iter().find_map(|curve| {
            let (label, (x, y)) = curve.first_non_finite()?;
            Some(ScenarioError::new(
                format!("models[{i}] ({})", bound.model.name()),
                format!(
                    "curve {} ({label}) has a point that is not finite ({}, {}) at the nominal point: the model cannot evaluate the scenario's nominal design",
                    curve.name,
                    rvtol_deviation::Shown(x),
                    rvtol_deviation::Shown(y)
                ),
            ))
        });
        drawn.push((
            bound.model.name(),
            match broken {
                Some(err) => Err(err),
                None => Ok(curves),
            },
        ));
    }
    drawn
}

/// Each model's input row for one row of the input space and its outputs (as a
/// [`SampleTable`] holds them): what its curves are drawn at.
pub fn model_inputs_of_row(scenario: &Scenario, row: &[f64], outputs: &[f64]) -> Vec<Vec<f64>> {
    (scenario.models.iter())
        .map(|bound| bound.inputs_of_row(row, outputs))
        .collect()
}
