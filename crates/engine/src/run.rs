//! The reproducible parallel Monte Carlo run.
//!
//! Reproducibility contract: the same (rvtol version, scenario, seed, samples) give
//! bit-identical statistics whatever the thread count.
//! - Samples are drawn in chunks of [`CHUNK_SIZE`]; chunk k draws from its own stream,
//!   `ChaCha8Rng::seed_from_u64(seed)` then `set_stream(k)`. The chunk size never depends
//!   on the thread count.
//! - Each chunk's moments are kept with its index and merged sequentially in chunk order
//!   (never with a parallel float reduction). Everything else merged across threads is an
//!   integer count (spec violations, events, sketch buckets, constraint attempts) or a
//!   multiset whose order the result does not depend on (the values kept for exact
//!   percentiles).
//! - Chunks run in waves of [`WAVE_CHUNKS`] so memory stays bounded for any sample count.
//!
//! Per chunk, block of [`BLOCK_ROWS`] rows after block: draw the inputs as a column-major
//! block, hand each model its input columns (constants pre-filled once) and evaluate it
//! into the chunk's output columns; then fold each output column into the statistics.
//! Non-finite outputs are counted per output and kept out of the statistics.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use rvtol_deviation::{ConstraintCounts, SamplerScratch};
use rvtol_models::{Curve, OutputKind};

use crate::evaluate::ChunkEvaluator;
use crate::scenario::{Scenario, ScenarioError};
use crate::stats::{Moments, QuantileSketch, SpecLimits};

/// Samples per chunk (part of the reproducibility contract: changing it changes results).
pub const CHUNK_SIZE: usize = 4096;
/// Rows sampled and evaluated at a time inside a chunk (part of the stream layout): small
/// enough that a block's rows, model inputs and outputs stay in the core's caches.
pub const BLOCK_ROWS: usize = 64;
/// Chunks per wave: bounds the memory of in-flight partial results.
pub const WAVE_CHUNKS: u64 = 1024;
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

/// Where an output's values went during the run.
#[derive(Debug, Clone)]
pub enum Distribution {
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
}

/// The accumulated statistics of one output.
#[derive(Debug, Clone)]
pub struct OutputAccumulator {
    /// Moments, min and max of the finite values.
    pub moments: Moments,
    /// Samples whose value was NaN or infinite (kept out of every statistic).
    pub non_finite: u64,
    /// Samples below the lower spec limit.
    pub below_lower: u64,
    /// Samples above the upper spec limit.
    pub above_upper: u64,
    /// Samples whose value was non-zero (the events of an indicator output).
    pub nonzero: u64,
    /// Values or sketch, for percentiles and the histogram.
    pub distribution: Distribution,
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
    /// One accumulator per scenario output, in order.
    pub outputs: Vec<OutputAccumulator>,
}

/// Per-thread scratch buffers and partial results.
struct Partial<'a> {
    /// One column-major block of sampled inputs.
    columns: Vec<f64>,
    sampler: SamplerScratch,
    evaluator: ChunkEvaluator<'a>,
    finite: Vec<f64>,
    chunk_moments: Vec<(u64, Vec<Moments>)>,
    non_finite: Vec<u64>,
    below_lower: Vec<u64>,
    above_upper: Vec<u64>,
    nonzero: Vec<u64>,
    distributions: Vec<Distribution>,
    constraint_counts: ConstraintCounts,
    error: Option<(u64, ScenarioError)>,
}

struct Plan<'a> {
    scenario: &'a Scenario,
    settings: RunSettings,
    exact: bool,
    limits: Vec<Option<SpecLimits>>,
    indicator: Vec<bool>,
    /// (center, scale) of each output's sketch, from the pilot chunk.
    sketch_frames: Vec<(f64, f64)>,
}

impl<'a> Plan<'a> {
    fn partial(&self) -> Partial<'a> {
        let n_out = self.scenario.outputs.len();
        Partial {
            columns: vec![0.0; BLOCK_ROWS * self.scenario.input_space.n_columns()],
            sampler: SamplerScratch::default(),
            evaluator: ChunkEvaluator::new(self.scenario),
            finite: Vec::with_capacity(CHUNK_SIZE),
            chunk_moments: Vec::new(),
            non_finite: vec![0; n_out],
            below_lower: vec![0; n_out],
            above_upper: vec![0; n_out],
            nonzero: vec![0; n_out],
            distributions: (0..n_out)
                .map(|o| {
                    if self.indicator[o] {
                        Distribution::Indicator
                    } else if self.exact {
                        Distribution::Values(Vec::new())
                    } else {
                        let (center, scale) = self.sketch_frames[o];
                        Distribution::Sketch {
                            sketch: QuantileSketch::new(SKETCH_RELATIVE_ACCURACY),
                            center,
                            scale,
                        }
                    }
                })
                .collect(),
            constraint_counts: self.scenario.input_space.new_constraint_counts(),
            error: None,
        }
    }

    fn chunk_len(&self, chunk: u64) -> usize {
        let start = chunk * CHUNK_SIZE as u64;
        (self.settings.samples - start).min(CHUNK_SIZE as u64) as usize
    }

    /// Draws chunk `chunk` and evaluates the models into `partial.output_columns`;
    /// returns the number of samples, or records the error.
    fn evaluate_chunk(&self, partial: &mut Partial, chunk: u64) -> Option<usize> {
        let m = self.chunk_len(chunk);
        let space = &self.scenario.input_space;
        let n_columns = space.n_columns();
        let mut rng = ChaCha8Rng::seed_from_u64(self.settings.seed);
        rng.set_stream(chunk);
        for first in (0..m).step_by(BLOCK_ROWS) {
            let block = (m - first).min(BLOCK_ROWS);
            let columns = &mut partial.columns[..block * n_columns];
            if let Err(err) = space.sample_columns_with(
                &mut rng,
                columns,
                &mut partial.constraint_counts,
                &mut partial.sampler,
            ) {
                partial.error = Some((chunk, err.into()));
                return None;
            }
            partial.evaluator.evaluate_columns_at(columns, block, first);
        }
        Some(m)
    }

    /// Centre and scale of each output's sketch: mean and standard deviation of the finite
    /// values of chunk 0, which every run draws identically whatever its thread count.
    fn pilot_sketch_frames(&self) -> Result<Vec<(f64, f64)>, ScenarioError> {
        let mut partial = self.partial();
        if self.evaluate_chunk(&mut partial, 0).is_none() {
            let (_, err) = partial.error.expect("evaluate_chunk records its error");
            return Err(err);
        }
        let m = self.chunk_len(0);
        Ok(partial
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

    fn run_chunk(&self, partial: &mut Partial, chunk: u64) {
        if partial.error.is_some() {
            return;
        }
        let Some(m) = self.evaluate_chunk(partial, chunk) else {
            return;
        };
        let mut moments = Vec::with_capacity(partial.evaluator.output_columns.len());
        for (o, column) in partial.evaluator.output_columns.iter().enumerate() {
            let mut values = &column[..m];
            if self.indicator[o] {
                // Events only: the moments follow from the counts at the end.
                let finite = values.iter().filter(|v| v.is_finite()).count();
                partial.non_finite[o] += (m - finite) as u64;
                partial.nonzero[o] += values
                    .iter()
                    .filter(|&&v| v.is_finite() && v != 0.0)
                    .count() as u64;
                moments.push(Moments::new());
                continue;
            }
            if values.iter().any(|v| !v.is_finite()) {
                partial.finite.clear();
                partial
                    .finite
                    .extend(values.iter().copied().filter(|v| v.is_finite()));
                partial.non_finite[o] += (m - partial.finite.len()) as u64;
                values = &partial.finite;
            }
            moments.push(Moments::from_slice(values));
            if let Some(limits) = self.limits[o] {
                if let Some(lower) = limits.lower {
                    partial.below_lower[o] += values.iter().filter(|&&v| v < lower).count() as u64;
                }
                if let Some(upper) = limits.upper {
                    partial.above_upper[o] += values.iter().filter(|&&v| v > upper).count() as u64;
                }
            }
            match &mut partial.distributions[o] {
                Distribution::Values(kept) => kept.extend_from_slice(values),
                Distribution::Sketch {
                    sketch,
                    center,
                    scale,
                } => {
                    sketch.insert_standardised(values, *center, 1.0 / *scale);
                }
                Distribution::Indicator => {}
            }
        }
        partial.chunk_moments.push((chunk, moments));
    }
}

/// Runs the scenario. `progress` is called with the number of samples each finished chunk
/// drew (from worker threads). Uses the current rayon thread pool.
pub fn run(
    scenario: &Scenario,
    settings: RunSettings,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<RunResult, ScenarioError> {
    if settings.samples == 0 {
        return Err(ScenarioError::new("samples", "must be at least 1"));
    }
    let n_out = scenario.outputs.len() as u64;
    let exact = settings.samples.saturating_mul(n_out.max(1)) <= settings.exact_percentile_limit;
    let mut plan = Plan {
        scenario,
        settings,
        exact,
        limits: scenario.outputs.iter().map(|o| o.spec).collect(),
        indicator: scenario
            .outputs
            .iter()
            .map(|o| o.kind == OutputKind::Indicator)
            .collect(),
        sketch_frames: vec![(0.0, 1.0); scenario.outputs.len()],
    };
    if !exact {
        plan.sketch_frames = plan.pilot_sketch_frames()?;
    }
    let n_chunks = settings.samples.div_ceil(CHUNK_SIZE as u64);
    let mut result = RunResult {
        samples: settings.samples,
        seed: settings.seed,
        percentile_method: if exact {
            PercentileMethod::Exact
        } else {
            PercentileMethod::Sketch {
                relative_accuracy: SKETCH_RELATIVE_ACCURACY,
            }
        },
        constraint_counts: scenario.input_space.new_constraint_counts(),
        outputs: plan
            .partial()
            .distributions
            .into_iter()
            .map(|distribution| OutputAccumulator {
                moments: Moments::new(),
                non_finite: 0,
                below_lower: 0,
                above_upper: 0,
                nonzero: 0,
                distribution,
            })
            .collect(),
    };
    if exact {
        for output in &mut result.outputs {
            if let Distribution::Values(values) = &mut output.distribution {
                values.reserve_exact(settings.samples as usize);
            }
        }
    }
    let mut wave_start = 0;
    while wave_start < n_chunks {
        let wave_end = (wave_start + WAVE_CHUNKS).min(n_chunks);
        // About four splits per thread, from the chunks this wave really has (a short run
        // with an expensive model must still reach every thread).
        let min_chunks_per_split =
            ((wave_end - wave_start) as usize / (4 * rayon::current_num_threads().max(1))).max(1);
        let partials: Vec<Partial> = (wave_start as usize..wave_end as usize)
            .into_par_iter()
            // A few splits per thread: each split allocates its scratch buffers and
            // partial statistics once. Grouping does not change any result (see the
            // module comment).
            .with_min_len(min_chunks_per_split)
            .fold(
                || plan.partial(),
                |mut partial, chunk| {
                    let chunk = chunk as u64;
                    plan.run_chunk(&mut partial, chunk);
                    progress(plan.chunk_len(chunk) as u64);
                    partial
                },
            )
            .collect();
        merge_wave(&mut result, partials)?;
        wave_start = wave_end;
    }
    for (output, info) in result.outputs.iter_mut().zip(&scenario.outputs) {
        if info.kind == OutputKind::Indicator {
            let n = settings.samples - output.non_finite;
            output.moments = indicator_moments(output.nonzero, n);
        }
    }
    Ok(result)
}

fn merge_wave(result: &mut RunResult, partials: Vec<Partial>) -> Result<(), ScenarioError> {
    if let Some((_, err)) = partials
        .iter()
        .filter_map(|p| p.error.as_ref())
        .min_by_key(|(chunk, _)| *chunk)
    {
        return Err(err.clone());
    }
    let mut chunk_moments: Vec<(u64, Vec<Moments>)> = Vec::new();
    for partial in partials {
        result.constraint_counts.add(&partial.constraint_counts);
        chunk_moments.extend(partial.chunk_moments);
        for (o, distribution) in partial.distributions.into_iter().enumerate() {
            let output = &mut result.outputs[o];
            output.non_finite += partial.non_finite[o];
            output.below_lower += partial.below_lower[o];
            output.above_upper += partial.above_upper[o];
            output.nonzero += partial.nonzero[o];
            match (&mut output.distribution, distribution) {
                (Distribution::Values(all), Distribution::Values(part)) => {
                    all.extend_from_slice(&part)
                }
                (Distribution::Indicator, Distribution::Indicator) => {}
                (
                    Distribution::Sketch { sketch: all, .. },
                    Distribution::Sketch { sketch: part, .. },
                ) => all
                    .merge(&part)
                    .map_err(|err| ScenarioError::new("(run)", err.to_string()))?,
                _ => unreachable!("one percentile method per run"),
            }
        }
    }
    chunk_moments.sort_unstable_by_key(|(chunk, _)| *chunk);
    for (_, moments) in chunk_moments {
        for (output, m) in result.outputs.iter_mut().zip(&moments) {
            output.moments.merge(m);
        }
    }
    Ok(())
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

/// Evaluates every model at the mean row of the input space (the nominal design).
pub fn nominal(scenario: &Scenario) -> Vec<f64> {
    let row = scenario.input_space.mean_row();
    let mut values = vec![0.0; scenario.outputs.len()];
    for bound in &scenario.models {
        let inputs = bound.inputs_of_row(&row);
        let n_out = bound.model.outputs().len();
        bound.model.evaluate(
            &inputs,
            &mut values[bound.first_output..bound.first_output + n_out],
        );
    }
    values
}

/// The curves of every model that draws any (`rvtol curve`), with every deviation at its
/// mean: (model name, its curves) in scenario order.
pub fn nominal_curves(scenario: &Scenario) -> Vec<(&'static str, Vec<Curve>)> {
    let row = scenario.input_space.mean_row();
    scenario
        .models
        .iter()
        .map(|bound| {
            (
                bound.model.name(),
                bound.model.curves(&bound.inputs_of_row(&row)),
            )
        })
        .filter(|(_, curves)| !curves.is_empty())
        .collect()
}
