//! Shards of a run or a sensitivity analysis and their files: what `rvtol run` and
//! `rvtol sensitivity` write with `--shard K/N --partial FILE`, and `rvtol merge` reads.
//!
//! A shard of a run computes the chunks [`rvtol_engine::chunk::shard_range`] (over the run's chunk count) gives it
//! ([`rvtol_engine::run_chunks`]) and stores the [`RunPartial`]; a shard of a sensitivity analysis
//! the same chunks of its matrices ([`crate::sensitivity::sobol_chunks`]) and, with
//! Shapley effects, its range of permutations ([`crate::shapley::shapley_partial`]). The
//! file holds everything the merge must check: the scenario file's text, the command's
//! settings, K and N, the ranges and the build that computed it. [`assemble`] checks a set
//! of shard files for coverage and identity; the merges fold their partials in order, bit
//! for bit the single-process result.
//!
//! # File layout (format 1)
//!
//! `rvtol-partial\n`, a little-endian u32 format number, a u64 length and that many bytes of
//! the JSON header ([`ShardHeader`]), then the binary payload, then the SHA-256 of every
//! byte before it (32 bytes). Numbers in the payload are little-endian u64, i64 or the bits
//! of an f64 (exact: a float written as decimal text would not always read back to its
//! bits); a list is its length then its items. Payload of a run: the percentile method (u8:
//! 0 exact, 1 sketch and its accuracy), the constraint groups' (candidates, accepted), then
//! per output its counts, its distribution (u8 tag: 0 values, 1 sketch with its frame, 2
//! indicator, 3 dropped) and then per chunk its index and every output's moments (n, mean,
//! m2, m3, m4, min, max). Of a sensitivity analysis: the Sobol' values (u8 tag: 0 every
//! value per chunk, output and matrix; 1 the centres, then per chunk and output the rows
//! left out and the block sums), then u8 1 and the Shapley partial (the variance run when
//! it has it, and per permutation its order and costs) or u8 0.

pub use rvtol_deviation::index_list;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use std::collections::BTreeMap;
use std::ops::Range;

use rvtol_engine::format::group_thousands;

use crate::sensitivity::{BlockSums, SobolChunks, SobolPartial};
use crate::shapley::ShapleyPartial;
use rvtol_deviation::ConstraintCounts;
use rvtol_engine::chunk::{shard_range, Sampling, SamplingMethod};
use rvtol_engine::run::{KeptValues, OutputAccumulator, PercentileMethod, RunPartial, RunSettings};
use rvtol_engine::stats::{Moments, QuantileSketch, SketchParts};

/// First bytes of a shard file.
pub const MAGIC: &[u8] = b"rvtol-partial\n";
/// Layout version written and read.
pub const FORMAT: u32 = 4;

/// What a shard file says about the run or analysis it belongs to.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShardHeader {
    /// rvtol version that wrote it.
    pub rvtol_version: String,
    /// Identity of the build that computed it (the CLI: version and the SHA-256 of its
    /// executable); the merge accepts only its own.
    pub build: String,
    /// Name a scenario without `name` takes (its file's stem).
    pub scenario_fallback_name: String,
    /// The scenario file's text, byte for byte.
    pub scenario_file: String,
    /// The command and its settings.
    pub command: ShardCommand,
    /// This shard's index K (0-based).
    pub shard: u64,
    /// Number of shards N.
    pub shards: u64,
    /// The chunks computed, [first, end).
    pub chunks: [u64; 2],
}

/// The sharded command and the settings every shard of it must share.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum ShardCommand {
    /// `rvtol run`.
    Run {
        /// Samples of the whole run.
        samples: u64,
        /// Seed.
        seed: u64,
        /// Exact percentiles up to this many values (decides the percentile method).
        exact_percentile_limit: u64,
        /// Sampling method (`mc`, `lhs`, `rqmc`).
        sampling: String,
        /// Its replicates (1 for Monte Carlo).
        replicates: u64,
    },
    /// `rvtol sensitivity`.
    Sensitivity {
        /// Base samples N.
        samples: u64,
        /// Seed.
        seed: u64,
        /// Bootstrap resamples.
        bootstrap: u64,
        /// Most model values kept for the row bootstrap.
        row_bootstrap_limit: u64,
        /// Sampling method of A and B (`mc`, `lhs`, `rqmc`).
        sampling: String,
        /// Its replicates (1 for Monte Carlo).
        replicates: u64,
        /// With Shapley effects: their settings and this shard's permutations.
        shapley: Option<ShapleyShard>,
    },
}

/// The Shapley part of a sensitivity shard.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShapleyShard {
    /// Permutation budget (`--permutations`).
    pub budget: u64,
    /// Outer draws (`--outer`).
    pub outer: u64,
    /// Permutations the estimate runs in all.
    pub permutations: u64,
    /// This shard's permutations, [first, end).
    pub range: [u64; 2],
}

impl ShardCommand {
    /// The settings all shards share (the command without this shard's ranges).
    fn shared(&self) -> ShardCommand {
        let mut shared = self.clone();
        if let ShardCommand::Sensitivity {
            shapley: Some(shapley),
            ..
        } = &mut shared
        {
            shapley.range = [0, 0];
        }
        shared
    }

    /// Base samples or samples: what the chunks divide.
    pub fn samples(&self) -> u64 {
        match self {
            ShardCommand::Run { samples, .. } | ShardCommand::Sensitivity { samples, .. } => {
                *samples
            }
        }
    }

    /// The command's sampling; Err for a method name this rvtol does not know (a damaged
    /// file; `decode` refuses it).
    pub fn sampling(&self) -> Result<Sampling, String> {
        let (ShardCommand::Run {
            sampling,
            replicates,
            ..
        }
        | ShardCommand::Sensitivity {
            sampling,
            replicates,
            ..
        }) = self;
        let method = SamplingMethod::parse(sampling)
            .ok_or_else(|| damaged(&format!("sampling {sampling:?}")))?;
        Ok(Sampling {
            method,
            replicates: *replicates,
        })
    }

    /// A run command's settings (None for a sensitivity analysis); Err as
    /// [`ShardCommand::sampling`].
    pub fn run_settings(&self) -> Result<Option<RunSettings>, String> {
        let ShardCommand::Run {
            samples,
            seed,
            exact_percentile_limit,
            ..
        } = self
        else {
            return Ok(None);
        };
        Ok(Some(RunSettings {
            samples: *samples,
            seed: *seed,
            exact_percentile_limit: *exact_percentile_limit,
            sampling: self.sampling()?,
        }))
    }

    /// The chunks the command's work divides into: the run's or the analysis' rows in
    /// chunks, replicate after replicate ([`Sampling::chunk_count`]).
    pub fn chunk_count(&self) -> u64 {
        self.sampling()
            .map_or(0, |sampling| sampling.chunk_count(self.samples()))
    }

    /// The command's name on the command line.
    pub fn name(&self) -> &'static str {
        match self {
            ShardCommand::Run { .. } => "run",
            ShardCommand::Sensitivity { .. } => "sensitivity",
        }
    }
}

/// A shard's statistics.
#[derive(Debug, Clone)]
pub enum ShardContent {
    /// Of a run.
    Run(RunPartial),
    /// Of a sensitivity analysis.
    Sensitivity {
        /// The Sobol' matrices' values of its chunks.
        sobol: SobolPartial,
        /// Its Shapley permutations, when the analysis has them.
        shapley: Option<ShapleyPartial>,
    },
}

/// A decoded shard file.
#[derive(Debug, Clone)]
pub struct ShardFile {
    /// Its header.
    pub header: ShardHeader,
    /// Its statistics.
    pub content: ShardContent,
    /// The SHA-256 the file ends with (equal for byte-identical files).
    pub digest: [u8; 32],
}

/// Most shards of one run or analysis: a job array's largest size in practice (a
/// Kubernetes Indexed Job takes up to 100,000 completions), far beyond what any run needs
/// (a shard of one chunk each is already 4,096 samples per job).
pub const MAX_SHARDS: u64 = 100_000;

/// Parses `K/N` (0 ≤ K < N ≤ [`MAX_SHARDS`]): a shard's index and the shard count.
pub fn parse_shard(text: &str) -> Result<(u64, u64), String> {
    let usage = || format!("'{text}' is not K/N with 0 <= K < N (shard K of N, counted from 0)");
    let (k, n) = text.split_once('/').ok_or_else(usage)?;
    let (k, n): (u64, u64) = (
        k.trim().parse().map_err(|_| usage())?,
        n.trim().parse().map_err(|_| usage())?,
    );
    if n > MAX_SHARDS {
        return Err(format!(
            "N must be at most {} shards",
            group_thousands(MAX_SHARDS)
        ));
    }
    if k >= n {
        return Err(usage());
    }
    Ok((k, n))
}

/// The bytes of a shard file.
pub fn encode(header: &ShardHeader, content: &ShardContent) -> Vec<u8> {
    let mut out = Writer(Vec::new());
    out.0.extend_from_slice(MAGIC);
    out.0.extend_from_slice(&FORMAT.to_le_bytes());
    let header = serde_json::to_vec(header).expect("the header serialises");
    out.u64(header.len() as u64);
    out.0.extend_from_slice(&header);
    match content {
        ShardContent::Run(partial) => {
            out.u8(0);
            write_run(&mut out, partial);
        }
        ShardContent::Sensitivity { sobol, shapley } => {
            out.u8(1);
            write_sobol(&mut out, sobol);
            match shapley {
                None => out.u8(0),
                Some(shapley) => {
                    out.u8(1);
                    write_shapley(&mut out, shapley);
                }
            }
        }
    }
    let digest: [u8; 32] = Sha256::digest(&out.0).into();
    out.0.extend_from_slice(&digest);
    out.0
}

fn write_run(out: &mut Writer, partial: &RunPartial) {
    match partial.percentile_method {
        PercentileMethod::Exact => out.u8(0),
        PercentileMethod::Sketch { relative_accuracy } => {
            out.u8(1);
            out.f64(relative_accuracy);
        }
    }
    out.u64(partial.constraint_counts.groups.len() as u64);
    for &(candidates, accepted) in &partial.constraint_counts.groups {
        out.u64(candidates);
        out.u64(accepted);
    }
    out.u64(partial.replicates.len() as u64);
    for (replicate, outputs) in &partial.replicates {
        out.u64(*replicate);
        write_outputs(out, outputs);
    }
    out.u64(partial.chunk_moments.len() as u64);
    for (chunk, moments) in &partial.chunk_moments {
        out.u64(*chunk);
        out.u64(moments.len() as u64);
        for m in moments {
            out.u64(m.n);
            for v in [m.mean, m.m2, m.m3, m.m4, m.min, m.max] {
                out.f64(v);
            }
        }
    }
}

fn write_outputs(out: &mut Writer, outputs: &[OutputAccumulator]) {
    out.u64(outputs.len() as u64);
    for output in outputs {
        for count in [
            output.non_finite,
            output.first_non_finite.map_or(u64::MAX, |first| first),
            output.excluded,
            output.flagged,
            output.flagged_within_spec,
            output.below_lower,
            output.above_upper,
            output.nonzero,
        ] {
            out.u64(count);
        }
        write_kept(out, &output.kept);
        write_kept(out, &output.flagged_kept);
    }
}

fn write_kept(out: &mut Writer, kept: &KeptValues) {
    match kept {
        KeptValues::Values(values) => {
            out.u8(0);
            out.f64s(values);
        }
        KeptValues::Sketch {
            sketch,
            center,
            scale,
        } => {
            out.u8(1);
            out.f64(*center);
            out.f64(*scale);
            let parts = sketch.to_parts();
            out.f64(parts.relative_accuracy);
            out.u64(parts.zero_count);
            for buckets in [&parts.positive, &parts.negative] {
                out.u64(buckets.len() as u64);
                for &(index, count) in buckets {
                    out.0.extend_from_slice(&index.to_le_bytes());
                    out.u64(count);
                }
            }
        }
        KeptValues::Indicator => out.u8(2),
        KeptValues::Dropped => out.u8(3),
    }
}

fn write_sobol(out: &mut Writer, sobol: &SobolPartial) {
    match &sobol.values {
        SobolChunks::Rows(chunks) => {
            out.u8(0);
            out.u64(chunks.len() as u64);
            for chunk in chunks {
                out.u64(chunk.len() as u64);
                for output in chunk {
                    out.u64(output.len() as u64);
                    for variant in output {
                        out.f64s(variant);
                    }
                }
            }
        }
        SobolChunks::Blocks { centres, chunks } => {
            out.u8(1);
            out.f64s(centres);
            out.u64(chunks.len() as u64);
            for chunk in chunks {
                out.u64(chunk.len() as u64);
                for (blocks, dropped) in chunk {
                    out.u64(*dropped);
                    out.u64(blocks.len() as u64);
                    for block in blocks {
                        out.u64(block.rows);
                        out.f64(block.sum);
                        out.f64(block.sum_squares);
                        out.f64s(&block.first);
                        out.f64s(&block.total);
                    }
                }
            }
        }
    }
}

fn write_shapley(out: &mut Writer, shapley: &ShapleyPartial) {
    match &shapley.variance {
        None => out.u8(0),
        Some(variance) => {
            out.u8(1);
            out.f64s(variance);
        }
    }
    out.u64(shapley.steps.len() as u64);
    for (order, costs) in &shapley.steps {
        out.u64(order.len() as u64);
        for &player in order {
            out.u64(player);
        }
        out.u64(costs.len() as u64);
        for cost in costs {
            out.f64s(cost);
        }
    }
}

/// Reads a shard file; the error says in a few words what is wrong with it.
pub fn decode(bytes: &[u8]) -> Result<ShardFile, String> {
    if !bytes.starts_with(MAGIC) {
        return Err(
            "not a shard file of rvtol (run and sensitivity write them with --shard K/N --partial)"
                .into(),
        );
    }
    if bytes.len() < MAGIC.len() + 4 + 32 {
        return Err("damaged: truncated".into());
    }
    let (body, digest) = bytes.split_at(bytes.len() - 32);
    let digest: [u8; 32] = digest.try_into().expect("32 bytes");
    let format = u32::from_le_bytes(bytes[MAGIC.len()..MAGIC.len() + 4].try_into().expect("4"));
    if format != FORMAT {
        return Err(format!(
            "format {format}, this rvtol reads format {FORMAT}: merge with the rvtol that wrote it"
        ));
    }
    if <[u8; 32]>::from(Sha256::digest(body)) != digest {
        return Err(
            "damaged: its checksum does not match its content (truncated or altered)".into(),
        );
    }
    let mut input = Reader {
        bytes: &body[MAGIC.len() + 4..],
    };
    let header_len = input.count(1)?;
    let header: ShardHeader = serde_json::from_slice(input.take(header_len)?)
        .map_err(|err| damaged(&format!("header: {err}")))?;
    header.command.sampling()?;
    let [first, end] = header.chunks;
    let content = match input.u8()? {
        0 => {
            let partial = read_run(&mut input, first..end)?;
            check_run_statistics(&header.command, &partial).map_err(|what| damaged(&what))?;
            ShardContent::Run(partial)
        }
        1 => {
            let sobol = read_sobol(&mut input, first..end)?;
            let shapley = match input.u8()? {
                0 => None,
                1 => {
                    let range = match &header.command {
                        ShardCommand::Sensitivity {
                            shapley: Some(shapley),
                            ..
                        } => shapley.range,
                        _ => return Err(damaged("Shapley permutations without their settings")),
                    };
                    Some(read_shapley(&mut input, range[0]..range[1])?)
                }
                tag => return Err(damaged(&format!("Shapley tag {tag}"))),
            };
            ShardContent::Sensitivity { sobol, shapley }
        }
        tag => return Err(damaged(&format!("content {tag}"))),
    };
    if !input.bytes.is_empty() {
        return Err(damaged("bytes after the statistics"));
    }
    Ok(ShardFile {
        header,
        content,
        digest,
    })
}

fn damaged(what: &str) -> String {
    format!("damaged: {what}")
}

/// Checks what a run's statistics are whatever produced them, so that a file whose checksum
/// was recomputed over impossible numbers is refused by name rather than merged into a
/// report: its chunks within the run and each once, in order; per chunk and output, no
/// more values than the chunk's rows and, where there are values, finite moments with
/// non-negative even sums and min ≤ max (none: the empty summary); per replicate and
/// output, the finite, non-finite and excluded samples adding up to its rows, every other
/// count within them, and no NaN among the values kept. The error says what is wrong.
fn check_run_statistics(command: &ShardCommand, partial: &RunPartial) -> Result<(), String> {
    let sampling = command.sampling()?;
    let samples = command.samples();
    let chunk_count = sampling.chunk_count(samples);
    let chunks = &partial.chunks;
    if chunks.start > chunks.end || chunks.end > chunk_count {
        return Err(format!(
            "chunks {}..{} of a run of {chunk_count} chunks",
            chunks.start, chunks.end
        ));
    }
    if let PercentileMethod::Sketch { relative_accuracy } = partial.percentile_method {
        if !(relative_accuracy > 0.0 && relative_accuracy < 1.0) {
            return Err(format!(
                "a sketch's relative accuracy of {}",
                rvtol_deviation::Shown(relative_accuracy)
            ));
        }
    }
    for (group, &(candidates, accepted)) in partial.constraint_counts.groups.iter().enumerate() {
        if accepted > candidates {
            return Err(format!(
                "constraint group {group}: {accepted} rows accepted of {candidates} candidates"
            ));
        }
    }
    // Rows and finite values (per output) of each replicate the chunks belong to.
    let mut tally: BTreeMap<u64, (u128, Vec<u128>)> = BTreeMap::new();
    let outputs = partial
        .chunk_moments
        .first()
        .map(|(_, moments)| moments.len());
    for (position, (chunk, moments)) in partial.chunk_moments.iter().enumerate() {
        let expected = chunks.start + position as u64;
        if *chunk != expected {
            let seen = partial.chunk_moments[..position]
                .iter()
                .any(|(c, _)| c == chunk);
            return Err(if seen {
                format!("chunk {chunk} appears twice")
            } else {
                format!("chunk {chunk} where chunk {expected} belongs")
            });
        }
        if Some(moments.len()) != outputs {
            return Err(format!(
                "chunk {chunk} has {} outputs, chunk {} {}",
                moments.len(),
                chunks.start,
                outputs.unwrap_or(0)
            ));
        }
        let (replicate, _, _, rows) = sampling.chunk_rows(samples, *chunk);
        let (replicate_rows, finite) = tally
            .entry(replicate)
            .or_insert_with(|| (0, vec![0; moments.len()]));
        *replicate_rows += rows as u128;
        for (output, (m, finite)) in moments.iter().zip(finite.iter_mut()).enumerate() {
            check_moments(m, rows as u64)
                .map_err(|what| format!("chunk {chunk}, output {output}: {what}"))?;
            *finite += m.n as u128;
        }
    }
    if partial.chunk_moments.len() as u64 != chunks.end - chunks.start {
        return Err(format!(
            "moments of {} chunks for chunks {}..{}",
            partial.chunk_moments.len(),
            chunks.start,
            chunks.end
        ));
    }
    let present: Vec<u64> = partial.replicates.iter().map(|(r, _)| *r).collect();
    let expected: Vec<u64> = tally.keys().copied().collect();
    if present != expected {
        return Err(format!(
            "counts of replicates {} for chunks of replicates {}",
            index_list(&present),
            index_list(&expected)
        ));
    }
    for (replicate, accumulators) in &partial.replicates {
        let (rows, finite) = &tally[replicate];
        if accumulators.len() != finite.len() {
            return Err(format!(
                "replicate {replicate} counts {} outputs, the chunks {}",
                accumulators.len(),
                finite.len()
            ));
        }
        for (output, (acc, &finite)) in accumulators.iter().zip(finite).enumerate() {
            check_counts(acc, *rows, finite, samples)
                .map_err(|what| format!("replicate {replicate}, output {output}: {what}"))?;
        }
    }
    Ok(())
}

/// One chunk's moments of one output, of a chunk of `rows` rows.
fn check_moments(m: &Moments, rows: u64) -> Result<(), String> {
    if m.n > rows {
        return Err(format!(
            "n = {} values in a chunk of {rows} rows",
            group_thousands(m.n)
        ));
    }
    if m.n == 0 {
        return if *m == Moments::new() {
            Ok(())
        } else {
            Err("moments of no values".into())
        };
    }
    for (name, value) in [
        ("mean", m.mean),
        ("m2", m.m2),
        ("m3", m.m3),
        ("m4", m.m4),
        ("min", m.min),
        ("max", m.max),
    ] {
        if !value.is_finite() {
            return Err(format!(
                "its {name} is {} (n = {})",
                rvtol_deviation::Shown(value),
                m.n
            ));
        }
    }
    if m.m2 < 0.0 || m.m4 < 0.0 {
        return Err("a negative sum of even powers".into());
    }
    if m.min > m.max {
        return Err(format!(
            "min {} above max {}",
            rvtol_deviation::Shown(m.min),
            rvtol_deviation::Shown(m.max)
        ));
    }
    Ok(())
}

/// One replicate's counts of one output over `rows` rows, `finite` of them finite values
/// (per the chunks' moments), in a run of `samples` samples.
fn check_counts(
    acc: &OutputAccumulator,
    rows: u128,
    finite: u128,
    samples: u64,
) -> Result<(), String> {
    let wide = |count: u64| count as u128;
    let indicator = matches!(acc.kept, KeptValues::Indicator);
    if indicator {
        if finite != 0 || wide(acc.non_finite) + wide(acc.nonzero) > rows {
            return Err(format!(
                "{} events and {} non-finite samples in {rows} rows",
                acc.nonzero, acc.non_finite
            ));
        }
    } else if finite + wide(acc.non_finite) + wide(acc.excluded) != rows {
        return Err(format!(
            "{finite} finite, {} non-finite and {} excluded samples in {rows} rows",
            acc.non_finite, acc.excluded
        ));
    }
    if wide(acc.below_lower) + wide(acc.above_upper) > finite
        || acc.flagged_within_spec > acc.flagged
        || wide(acc.flagged) > rows
    {
        return Err(format!(
            "{} below and {} above the limits, {} flagged ({} within the limits) of {finite} finite values in {rows} rows",
            acc.below_lower, acc.above_upper, acc.flagged, acc.flagged_within_spec
        ));
    }
    match acc.first_non_finite {
        Some(first) if acc.non_finite == 0 || first >= samples => {
            return Err(format!(
                "a first non-finite sample {first} of {} non-finite in {samples} samples",
                acc.non_finite
            ));
        }
        None if acc.non_finite > 0 => {
            return Err(format!(
                "{} non-finite samples without the first",
                acc.non_finite
            ));
        }
        _ => {}
    }
    let apart = acc.flagged_kept.count() as u128;
    if apart > wide(acc.flagged) {
        return Err(format!(
            "{apart} flagged values kept of {} flagged",
            acc.flagged
        ));
    }
    if let KeptValues::Values(flagged) = &acc.flagged_kept {
        if flagged.iter().any(|v| v.is_nan()) {
            return Err("a flagged value is NaN".to_string());
        }
    }
    match &acc.kept {
        KeptValues::Values(values) => {
            if values.len() as u128 + apart != finite {
                return Err(format!(
                    "{} values kept of {finite} finite ({apart} flagged apart)",
                    values.len()
                ));
            }
            if let Some(position) = values.iter().position(|v| v.is_nan()) {
                return Err(format!("value {position} is NaN"));
            }
        }
        KeptValues::Sketch {
            sketch,
            center,
            scale,
        } => {
            if !(center.is_finite() && scale.is_finite() && *scale > 0.0) {
                return Err(format!(
                    "a sketch centred at {} with scale {}",
                    rvtol_deviation::Shown(*center),
                    rvtol_deviation::Shown(*scale)
                ));
            }
            if wide(sketch.count()) + apart > finite {
                return Err(format!(
                    "a sketch of {} values of {finite} finite",
                    sketch.count()
                ));
            }
        }
        KeptValues::Indicator | KeptValues::Dropped => {}
    }
    Ok(())
}

fn read_run(input: &mut Reader, chunks: Range<u64>) -> Result<RunPartial, String> {
    let percentile_method = match input.u8()? {
        0 => PercentileMethod::Exact,
        1 => PercentileMethod::Sketch {
            relative_accuracy: input.f64()?,
        },
        tag => return Err(damaged(&format!("percentile method {tag}"))),
    };
    let groups = input.count(16)?;
    let constraint_counts = ConstraintCounts {
        groups: (0..groups)
            .map(|_| Ok((input.u64()?, input.u64()?)))
            .collect::<Result<_, String>>()?,
    };
    let n_replicates = input.count(16)?;
    let mut replicates = Vec::with_capacity(n_replicates);
    for _ in 0..n_replicates {
        let replicate = input.u64()?;
        if replicates.last().is_some_and(|(r, _)| *r >= replicate) {
            return Err(damaged("replicates out of order"));
        }
        replicates.push((replicate, read_outputs(input)?));
    }
    let n_chunks = input.count(16)?;
    let mut chunk_moments = Vec::with_capacity(n_chunks);
    for _ in 0..n_chunks {
        let chunk = input.u64()?;
        let n = input.count(56)?;
        let moments = (0..n)
            .map(|_| {
                Ok(Moments {
                    n: input.u64()?,
                    mean: input.f64()?,
                    m2: input.f64()?,
                    m3: input.f64()?,
                    m4: input.f64()?,
                    min: input.f64()?,
                    max: input.f64()?,
                })
            })
            .collect::<Result<_, String>>()?;
        chunk_moments.push((chunk, moments));
    }
    Ok(RunPartial {
        chunks,
        percentile_method,
        constraint_counts,
        chunk_moments,
        replicates,
    })
}

fn read_outputs(input: &mut Reader) -> Result<Vec<OutputAccumulator>, String> {
    let n_outputs = input.count(65)?;
    let mut outputs = Vec::with_capacity(n_outputs);
    for _ in 0..n_outputs {
        let mut counts = [0u64; 8];
        for count in &mut counts {
            *count = input.u64()?;
        }
        let kept = read_kept(input)?;
        let flagged_kept = read_kept(input)?;
        let [non_finite, first, excluded, flagged, flagged_within_spec, below_lower, above_upper, nonzero] =
            counts;
        outputs.push(OutputAccumulator {
            moments: Moments::new(),
            non_finite,
            first_non_finite: (first != u64::MAX).then_some(first),
            excluded,
            flagged,
            flagged_within_spec,
            below_lower,
            above_upper,
            nonzero,
            kept,
            flagged_kept,
        });
    }
    Ok(outputs)
}

fn read_kept(input: &mut Reader) -> Result<KeptValues, String> {
    Ok(match input.u8()? {
        0 => KeptValues::Values(input.f64s()?),
        1 => {
            let (center, scale) = (input.f64()?, input.f64()?);
            let relative_accuracy = input.f64()?;
            let zero_count = input.u64()?;
            let mut buckets = || -> Result<Vec<(i64, u64)>, String> {
                let n = input.count(16)?;
                (0..n)
                    .map(|_| Ok((input.u64()? as i64, input.u64()?)))
                    .collect()
            };
            let (positive, negative) = (buckets()?, buckets()?);
            let sketch = QuantileSketch::from_parts(&SketchParts {
                relative_accuracy,
                zero_count,
                positive,
                negative,
            })
            .map_err(|err| damaged(&format!("sketch: {err}")))?;
            KeptValues::Sketch {
                sketch,
                center,
                scale,
            }
        }
        2 => KeptValues::Indicator,
        3 => KeptValues::Dropped,
        tag => return Err(damaged(&format!("distribution {tag}"))),
    })
}

fn read_sobol(input: &mut Reader, chunks: Range<u64>) -> Result<SobolPartial, String> {
    let values = match input.u8()? {
        0 => {
            let n = input.count(8)?;
            let mut all = Vec::with_capacity(n);
            for _ in 0..n {
                let outputs = input.count(8)?;
                let mut chunk = Vec::with_capacity(outputs);
                for _ in 0..outputs {
                    let variants = input.count(8)?;
                    chunk.push(
                        (0..variants)
                            .map(|_| input.f64s())
                            .collect::<Result<_, _>>()?,
                    );
                }
                all.push(chunk);
            }
            SobolChunks::Rows(all)
        }
        1 => {
            let centres = input.f64s()?;
            let n = input.count(8)?;
            let mut all = Vec::with_capacity(n);
            for _ in 0..n {
                let outputs = input.count(16)?;
                let mut chunk = Vec::with_capacity(outputs);
                for _ in 0..outputs {
                    let dropped = input.u64()?;
                    let n_blocks = input.count(40)?;
                    let blocks = (0..n_blocks)
                        .map(|_| {
                            Ok(BlockSums {
                                rows: input.u64()?,
                                sum: input.f64()?,
                                sum_squares: input.f64()?,
                                first: input.f64s()?,
                                total: input.f64s()?,
                            })
                        })
                        .collect::<Result<_, String>>()?;
                    chunk.push((blocks, dropped));
                }
                all.push(chunk);
            }
            SobolChunks::Blocks {
                centres,
                chunks: all,
            }
        }
        tag => return Err(damaged(&format!("Sobol' values {tag}"))),
    };
    Ok(SobolPartial { chunks, values })
}

fn read_shapley(input: &mut Reader, permutations: Range<u64>) -> Result<ShapleyPartial, String> {
    let variance = match input.u8()? {
        0 => None,
        1 => Some(input.f64s()?),
        tag => return Err(damaged(&format!("Shapley variance {tag}"))),
    };
    let n = input.count(16)?;
    let mut steps = Vec::with_capacity(n);
    for _ in 0..n {
        let players = input.count(8)?;
        let order = (0..players)
            .map(|_| input.u64())
            .collect::<Result<_, _>>()?;
        let n_costs = input.count(8)?;
        let costs = (0..n_costs)
            .map(|_| input.f64s())
            .collect::<Result<_, _>>()?;
        steps.push((order, costs));
    }
    Ok(ShapleyPartial {
        permutations,
        variance,
        steps,
    })
}

/// A set of shard files of one run or analysis, checked.
#[derive(Debug)]
pub struct Assembly {
    /// The header of the first file (the shared settings).
    pub header: ShardHeader,
    /// One file per shard present, by shard index.
    pub shards: Vec<ShardFile>,
    /// Shard indices with no file, as increasing ranges (worked out from the files present:
    /// nothing is held per declared shard).
    pub missing: Vec<Range<u64>>,
}

impl Assembly {
    /// How many shards have no file.
    pub fn missing_count(&self) -> u64 {
        self.missing
            .iter()
            .map(|range| range.end - range.start)
            .sum()
    }
}

/// Checks shard files (each with the name to quote) for one run or analysis computed by
/// the build `build`: every file of the same scenario text, command, settings, shard count
/// and build; its ranges those its index gets; a shard given twice only as identical files
/// (a rerun shard). The error is one line naming the file.
pub fn assemble(files: Vec<(String, ShardFile)>, build: &str) -> Result<Assembly, String> {
    let mut files = files.into_iter();
    let Some((first_name, first)) = files.next() else {
        return Err("no shard files given".into());
    };
    let run = first.header.clone();
    // By shard index, the files given only: a shard count is checked against MAX_SHARDS,
    // but nothing here is held per declared shard.
    let mut slots: BTreeMap<u64, (String, ShardFile)> = BTreeMap::new();
    for (name, file) in std::iter::once((first_name.clone(), first)).chain(files) {
        let h = &file.header;
        let differs = |what: &str, details: String| {
            Err(format!(
                "{name}: {what} from {first_name}'s ({details}): the files belong to different runs"
            ))
        };
        if h.build != build {
            return Err(format!(
                "{name}: computed by another build of rvtol ({}) than this one ({build}): merge with the rvtol binary the shards ran, and run every shard with one binary",
                h.build
            ));
        }
        if h.scenario_file != run.scenario_file
            || h.scenario_fallback_name != run.scenario_fallback_name
        {
            return differs("the scenario differs", "another scenario file".into());
        }
        if h.command.name() != run.command.name() {
            return differs(
                "the command differs",
                format!("{} against {}", h.command.name(), run.command.name()),
            );
        }
        if h.command.shared() != run.command.shared() {
            return differs(
                "the settings differ",
                format!(
                    "{} against {}",
                    settings_text(&h.command),
                    settings_text(&run.command)
                ),
            );
        }
        if h.shards != run.shards {
            return differs(
                "the shard count differs",
                format!("{} against {}", h.shards, run.shards),
            );
        }
        if h.shards > MAX_SHARDS {
            return Err(format!(
                "{name}: damaged: {} shards, more than the {} a run may have",
                group_thousands(h.shards),
                group_thousands(MAX_SHARDS)
            ));
        }
        if h.shard >= h.shards || !covers_its_ranges(&file) {
            return Err(format!(
                "{name}: damaged: shard {}/{} does not cover what that shard computes",
                h.shard, h.shards
            ));
        }
        let k = h.shard;
        match slots.get(&k) {
            Some((other, earlier)) if earlier.digest != file.digest => {
                return Err(format!(
                    "{name}: shard {k}/{} is also in {other} with different content: keep one of them",
                    h.shards
                ));
            }
            Some(_) => {}
            None => {
                slots.insert(k, (name, file));
            }
        }
    }
    // The gaps between the shards present, and after the last one.
    let mut missing = Vec::new();
    let mut next = 0;
    for &k in slots.keys().chain(std::iter::once(&run.shards)) {
        if k > next {
            missing.push(next..k);
        }
        next = k + 1;
    }
    Ok(Assembly {
        header: run,
        shards: slots.into_values().map(|(_, file)| file).collect(),
        missing,
    })
}

/// Ranges of indices as a person (and Slurm's `--array`) writes them: `0,2-5,9` (a range of
/// three or more as `a-b`, as [`index_list`] writes its indices).
pub fn range_list(ranges: &[Range<u64>]) -> String {
    let mut parts = Vec::new();
    for range in ranges.iter().filter(|range| range.end > range.start) {
        let last = range.end - 1;
        match last - range.start {
            0 => parts.push(range.start.to_string()),
            1 => parts.push(format!("{},{last}", range.start)),
            _ => parts.push(format!("{}-{last}", range.start)),
        }
    }
    parts.join(",")
}

/// The settings of a command as the refusal quotes them.
fn settings_text(command: &ShardCommand) -> String {
    match command {
        ShardCommand::Run {
            samples,
            seed,
            exact_percentile_limit,
            sampling,
            replicates,
        } => format!(
            "samples {samples}, seed {seed}, exact percentile limit {exact_percentile_limit}, sampling {sampling} × {replicates}"
        ),
        ShardCommand::Sensitivity {
            samples,
            seed,
            bootstrap,
            row_bootstrap_limit,
            sampling,
            replicates,
            shapley,
        } => format!(
            "samples {samples}, seed {seed}, {}, {}",
            if sampling == "mc" {
                format!("bootstrap {bootstrap}, row bootstrap limit {row_bootstrap_limit}")
            } else {
                format!("sampling {sampling} × {replicates}")
            },
            shapley.as_ref().map_or("no Shapley".to_string(), |s| format!(
                "Shapley permutations {} outer {}",
                s.budget, s.outer
            ))
        ),
    }
}

/// Whether the file's ranges and content are those its shard index gets.
fn covers_its_ranges(file: &ShardFile) -> bool {
    let h = &file.header;
    let chunks = shard_range(h.command.chunk_count(), h.shard, h.shards);
    if h.chunks != [chunks.start, chunks.end] {
        return false;
    }
    match (&file.content, &h.command) {
        (ShardContent::Run(partial), ShardCommand::Run { .. }) => partial.chunks == chunks,
        (
            ShardContent::Sensitivity { sobol, shapley },
            ShardCommand::Sensitivity {
                shapley: settings, ..
            },
        ) => {
            sobol.chunks == chunks
                && match (shapley, settings) {
                    (None, None) => true,
                    (Some(partial), Some(settings)) => {
                        let range = shard_range(settings.permutations, h.shard, h.shards);
                        settings.range == [range.start, range.end]
                            && partial.permutations == range
                            && partial.variance.is_some() == (h.shard == 0)
                    }
                    _ => false,
                }
        }
        _ => false,
    }
}

struct Writer(Vec<u8>);

impl Writer {
    fn u8(&mut self, v: u8) {
        self.0.push(v);
    }
    fn u64(&mut self, v: u64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn f64(&mut self, v: f64) {
        self.u64(v.to_bits());
    }
    fn f64s(&mut self, values: &[f64]) {
        self.u64(values.len() as u64);
        for &v in values {
            self.f64(v);
        }
    }
}

struct Reader<'a> {
    bytes: &'a [u8],
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], String> {
        if n > self.bytes.len() {
            return Err("damaged: truncated".into());
        }
        let (taken, rest) = self.bytes.split_at(n);
        self.bytes = rest;
        Ok(taken)
    }
    fn u8(&mut self) -> Result<u8, String> {
        Ok(self.take(1)?[0])
    }
    fn u64(&mut self) -> Result<u64, String> {
        Ok(u64::from_le_bytes(
            self.take(8)?.try_into().expect("8 bytes"),
        ))
    }
    fn f64(&mut self) -> Result<f64, String> {
        Ok(f64::from_bits(self.u64()?))
    }
    fn f64s(&mut self) -> Result<Vec<f64>, String> {
        let n = self.count(8)?;
        (0..n).map(|_| self.f64()).collect()
    }
    /// A count of items of at least `item_bytes` bytes each, checked against the bytes
    /// left (a damaged count must not allocate).
    fn count(&mut self, item_bytes: usize) -> Result<usize, String> {
        let n = self.u64()?;
        if n > (self.bytes.len() / item_bytes.max(1)) as u64 {
            return Err("damaged: a count exceeds the file".into());
        }
        Ok(n as usize)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shard_arguments_parse() {
        assert_eq!(parse_shard("2/4"), Ok((2, 4)));
        assert!(parse_shard("4/4").is_err());
        assert!(parse_shard("1").is_err());
        assert!(parse_shard("-1/4").is_err());
        assert_eq!(parse_shard("99999/100000"), Ok((99_999, 100_000)));
        for beyond in ["0/100001", "0/18446744073709551615"] {
            assert!(
                parse_shard(beyond)
                    .unwrap_err()
                    .ends_with("N must be at most 100,000 shards"),
                "{beyond}"
            );
        }
    }

    /// Shard `shard` of `shards` of a run of one sample (one chunk, in the last shard): a
    /// shard with no chunk unless it is the last.
    fn shard_of_one_sample(shard: u64, shards: u64) -> ShardFile {
        let command = ShardCommand::Run {
            samples: 1,
            seed: 1,
            exact_percentile_limit: 1,
            sampling: "mc".into(),
            replicates: 1,
        };
        let chunks = shard_range(command.chunk_count(), shard, shards);
        assert!(chunks.is_empty());
        ShardFile {
            header: ShardHeader {
                rvtol_version: "test".into(),
                build: "test".into(),
                scenario_fallback_name: "test".into(),
                scenario_file: String::new(),
                command,
                shard,
                shards,
                chunks: [chunks.start, chunks.end],
            },
            content: ShardContent::Run(RunPartial {
                chunks,
                percentile_method: PercentileMethod::Exact,
                constraint_counts: ConstraintCounts { groups: Vec::new() },
                chunk_moments: Vec::new(),
                replicates: Vec::new(),
            }),
            digest: [shard as u8; 32],
        }
    }

    #[test]
    fn missing_shards_are_the_ranges_the_files_leave_out() {
        let files = vec![
            ("seven".to_string(), shard_of_one_sample(7, MAX_SHARDS)),
            ("five".to_string(), shard_of_one_sample(5, MAX_SHARDS)),
        ];
        let assembly = assemble(files, "test").unwrap();
        assert_eq!(assembly.missing, vec![0..5, 6..7, 8..MAX_SHARDS]);
        assert_eq!(assembly.missing_count(), MAX_SHARDS - 2);
        assert_eq!(range_list(&assembly.missing), "0-4,6,8-99999");
        assert_eq!(range_list(&[0..2, 3..4, 9..12]), "0,1,3,9-11");
        assert_eq!(range_list(&[]), "");
        // A file declaring more shards than a run may have is refused, whatever it holds.
        for shards in [MAX_SHARDS + 1, u64::MAX] {
            let err = assemble(
                vec![("huge".to_string(), shard_of_one_sample(0, shards))],
                "test",
            )
            .unwrap_err();
            assert!(
                err.starts_with("huge: damaged: ") && err.contains("more than the 100,000"),
                "{err}"
            );
        }
    }

    #[test]
    fn every_chunk_belongs_to_one_shard() {
        for samples in [1u64, 4096, 4097, 100_000, 1_000_000] {
            for shards in [1u64, 2, 3, 7, 64] {
                let mut next = 0;
                for k in 0..shards {
                    let range = shard_range(Sampling::MONTE_CARLO.chunk_count(samples), k, shards);
                    assert_eq!(range.start, next);
                    next = range.end;
                }
                assert_eq!(next, Sampling::MONTE_CARLO.chunk_count(samples));
            }
        }
    }
}
