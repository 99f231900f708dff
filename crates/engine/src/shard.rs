//! Shards of a run and their files: what `rvtol run --shard K/N --partial FILE` writes and
//! `rvtol merge` reads.
//!
//! A shard computes the chunks [`crate::run::shard_chunks`] gives it ([`crate::run_chunks`])
//! and stores the [`RunPartial`] with everything the merge must check: the scenario file's
//! text, the run's settings, K and N, the chunk range and the build that computed it.
//! [`assemble`] checks a set of shard files for coverage and identity; [`crate::merge`]
//! folds their partials into the run's result, bit for bit the single-process one.
//!
//! # File layout (format 1)
//!
//! `rvtol-partial\n`, a little-endian u32 format number, a u64 length and that many bytes of
//! the JSON header ([`ShardHeader`]), then the binary payload, then the SHA-256 of every
//! byte before it (32 bytes). Numbers in the payload are little-endian u64, i64 or the bits
//! of an f64 (exact: a float written as decimal text would not always read back to its
//! bits). Payload: the percentile method (u8: 0 exact, 1 sketch), the constraint groups'
//! (candidates, accepted), then per output its counts, its distribution (u8 tag: 0 values,
//! 1 sketch with its frame, 2 indicator, 3 dropped) and then per chunk its index and every
//! output's moments (n, mean, m2, m3, m4, min, max).

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use crate::run::{
    shard_chunks, Distribution, OutputAccumulator, PercentileMethod, RunPartial, RunSettings,
};
use crate::stats::{Moments, QuantileSketch, SketchParts};
use rvtol_deviation::ConstraintCounts;

/// First bytes of a shard file.
pub const MAGIC: &[u8] = b"rvtol-partial\n";
/// Layout version written and read.
pub const FORMAT: u32 = 1;

/// What a shard file says about the run it belongs to.
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
    /// Samples of the whole run.
    pub samples: u64,
    /// Seed of the run.
    pub seed: u64,
    /// Exact percentiles up to this many values (decides the percentile method).
    pub exact_percentile_limit: u64,
    /// This shard's index K (0-based).
    pub shard: u64,
    /// Number of shards N.
    pub shards: u64,
    /// The chunks computed, [first, end).
    pub chunks: [u64; 2],
}

impl ShardHeader {
    /// The run's settings.
    pub fn settings(&self) -> RunSettings {
        RunSettings {
            samples: self.samples,
            seed: self.seed,
            exact_percentile_limit: self.exact_percentile_limit,
        }
    }
}

/// A decoded shard file.
#[derive(Debug, Clone)]
pub struct ShardFile {
    /// Its header.
    pub header: ShardHeader,
    /// Its statistics.
    pub partial: RunPartial,
    /// The SHA-256 the file ends with (equal for byte-identical files).
    pub digest: [u8; 32],
}

/// Parses `K/N` (0 ≤ K < N): a shard's index and the shard count.
pub fn parse_shard(text: &str) -> Result<(u64, u64), String> {
    let usage = || format!("'{text}' is not K/N with 0 <= K < N (shard K of N, counted from 0)");
    let (k, n) = text.split_once('/').ok_or_else(usage)?;
    let (k, n): (u64, u64) = (
        k.trim().parse().map_err(|_| usage())?,
        n.trim().parse().map_err(|_| usage())?,
    );
    if k >= n {
        return Err(usage());
    }
    Ok((k, n))
}

/// Shard indices as a job-array list: increasing, runs of three or more joined as `a-b`
/// (`0,2-5,9`), the form Slurm's `--array` takes.
pub fn index_list(indices: &[u64]) -> String {
    let mut parts = Vec::new();
    let mut i = 0;
    while i < indices.len() {
        let mut j = i;
        while j + 1 < indices.len() && indices[j + 1] == indices[j] + 1 {
            j += 1;
        }
        if j >= i + 2 {
            parts.push(format!("{}-{}", indices[i], indices[j]));
        } else {
            parts.extend(indices[i..=j].iter().map(u64::to_string));
        }
        i = j + 1;
    }
    parts.join(",")
}

/// The bytes of a shard file.
pub fn encode(header: &ShardHeader, partial: &RunPartial) -> Vec<u8> {
    let mut out = Writer(Vec::new());
    out.0.extend_from_slice(MAGIC);
    out.0.extend_from_slice(&FORMAT.to_le_bytes());
    let header = serde_json::to_vec(header).expect("the header serialises");
    out.u64(header.len() as u64);
    out.0.extend_from_slice(&header);
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
    out.u64(partial.outputs.len() as u64);
    for output in &partial.outputs {
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
        match &output.distribution {
            Distribution::Values(values) => {
                out.u8(0);
                out.u64(values.len() as u64);
                for &v in values {
                    out.f64(v);
                }
            }
            Distribution::Sketch {
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
            Distribution::Indicator => out.u8(2),
            Distribution::Dropped => out.u8(3),
        }
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
    let digest: [u8; 32] = Sha256::digest(&out.0).into();
    out.0.extend_from_slice(&digest);
    out.0
}

/// Reads a shard file; the error says in a few words what is wrong with it.
pub fn decode(bytes: &[u8]) -> Result<ShardFile, String> {
    if !bytes.starts_with(MAGIC) {
        return Err("not a shard file of rvtol (run --shard K/N --partial writes them)".into());
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
    let damaged = |what: &str| format!("damaged: {what}");
    let header_len = input.u64()? as usize;
    let header: ShardHeader = serde_json::from_slice(input.take(header_len)?)
        .map_err(|err| damaged(&format!("header: {err}")))?;
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
    let n_outputs = input.count(65)?;
    let mut outputs = Vec::with_capacity(n_outputs);
    for _ in 0..n_outputs {
        let mut counts = [0u64; 8];
        for count in &mut counts {
            *count = input.u64()?;
        }
        let distribution = match input.u8()? {
            0 => {
                let n = input.count(8)?;
                Distribution::Values((0..n).map(|_| input.f64()).collect::<Result<_, _>>()?)
            }
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
                Distribution::Sketch {
                    sketch,
                    center,
                    scale,
                }
            }
            2 => Distribution::Indicator,
            3 => Distribution::Dropped,
            tag => return Err(damaged(&format!("distribution {tag}"))),
        };
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
            distribution,
        });
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
    if !input.bytes.is_empty() {
        return Err(damaged("bytes after the statistics"));
    }
    let [first, end] = header.chunks;
    Ok(ShardFile {
        partial: RunPartial {
            chunks: first..end,
            percentile_method,
            constraint_counts,
            chunk_moments,
            outputs,
        },
        header,
        digest,
    })
}

/// A set of shard files of one run, checked.
#[derive(Debug)]
pub struct Assembly {
    /// The run's header (that of the first file).
    pub header: ShardHeader,
    /// One file per shard present, by shard index.
    pub shards: Vec<ShardFile>,
    /// Shard indices with no file.
    pub missing: Vec<u64>,
}

/// Checks shard files (each with the name to quote) for one run computed by the build
/// `build`: every file of the same scenario text, settings, shard count and build; its
/// chunk range the one its index gets; a shard given twice only as identical files (a
/// rerun shard). The error is one line naming the file.
pub fn assemble(files: Vec<(String, ShardFile)>, build: &str) -> Result<Assembly, String> {
    let mut files = files.into_iter();
    let Some((first_name, first)) = files.next() else {
        return Err("no shard files given".into());
    };
    let run = first.header.clone();
    let mut slots: Vec<Option<(String, ShardFile)>> = Vec::new();
    for (name, file) in std::iter::once((first_name.clone(), first)).chain(files) {
        let h = &file.header;
        let differs = |what: &str| {
            Err(format!(
                "{name}: {what} differs from {first_name}'s: the files belong to different runs"
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
            return differs("the scenario");
        }
        if h.settings() != run.settings() {
            return differs(&format!(
                "samples, seed or exact-percentile limit ({}, {}, {} against {}, {}, {})",
                h.samples,
                h.seed,
                h.exact_percentile_limit,
                run.samples,
                run.seed,
                run.exact_percentile_limit
            ));
        }
        if h.shards != run.shards {
            return differs(&format!(
                "the shard count ({} against {})",
                h.shards, run.shards
            ));
        }
        let expected = shard_chunks(h.samples, h.shard, h.shards);
        if h.shard >= h.shards
            || h.chunks != [expected.start, expected.end]
            || file.partial.chunks != expected
        {
            return Err(format!(
                "{name}: damaged: shard {}/{} does not cover the chunks that shard computes",
                h.shard, h.shards
            ));
        }
        let k = h.shard as usize;
        if slots.len() < h.shards as usize {
            slots.resize_with(h.shards as usize, || None);
        }
        match &slots[k] {
            Some((other, earlier)) if earlier.digest != file.digest => {
                return Err(format!(
                    "{name}: shard {k}/{} is also in {other} with different content: keep one of them",
                    h.shards
                ));
            }
            Some(_) => {}
            None => slots[k] = Some((name, file)),
        }
    }
    let missing = slots
        .iter()
        .enumerate()
        .filter(|(_, slot)| slot.is_none())
        .map(|(k, _)| k as u64)
        .collect();
    Ok(Assembly {
        header: run,
        shards: slots.into_iter().flatten().map(|(_, file)| file).collect(),
        missing,
    })
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
    fn shard_lists_and_indices() {
        assert_eq!(parse_shard("2/4"), Ok((2, 4)));
        assert!(parse_shard("4/4").is_err());
        assert!(parse_shard("1").is_err());
        assert!(parse_shard("-1/4").is_err());
        assert_eq!(index_list(&[0, 2, 3, 4, 5, 9]), "0,2-5,9");
        assert_eq!(index_list(&[1, 2, 7]), "1,2,7");
        assert_eq!(index_list(&[]), "");
    }

    #[test]
    fn every_chunk_belongs_to_one_shard() {
        for samples in [1u64, 4096, 4097, 100_000, 1_000_000] {
            for shards in [1u64, 2, 3, 7, 64] {
                let mut next = 0;
                for k in 0..shards {
                    let range = shard_chunks(samples, k, shards);
                    assert_eq!(range.start, next);
                    next = range.end;
                }
                assert_eq!(next, crate::run::chunk_count(samples));
            }
        }
    }
}
