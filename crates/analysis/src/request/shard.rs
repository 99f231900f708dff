//! Sharded requests: what shard K of N of a run or a sensitivity analysis writes in its
//! file's header (the scenario text, the command's settings, K/N, its chunks and Shapley
//! permutations, the build that computed it), and a checked set of shard files turned back
//! into the request they share and the partials the merges fold ([`merged`]); the files
//! read within the memory a merge may take ([`read_shards`]).

use std::ops::Range;
use std::path::PathBuf;

use rvtol_deviation::human_bytes;

use rvtol_engine::chunk::shard_range;
use rvtol_engine::{RunPartial, RunSettings, Scenario, ScenarioError};

use super::input_file::{read_bytes, ReadLimit};
use super::machine::memory_budget;
use super::memory::BASE_BYTES;
use super::scenario::ScenarioText;
use super::sensitivity::{SensitivityRequest, ShapleyRequest};
use super::{Caller, Refusal};
use crate::sensitivity::{SensitivitySettings, SobolPartial};
use crate::shapley::{shapley_permutations, ShapleyPartial, ShapleySettings};
use crate::shard::{
    decode, Assembly, ShapleyShard, ShardCommand, ShardContent, ShardFile, ShardHeader,
};

/// This build's identity in shard files: the version and the SHA-256 of the running
/// executable. Shards and their merge must come from one binary: another build may draw or
/// evaluate differently in the last bits, and the merged report would not be the run's.
pub fn build_identity() -> Result<String, String> {
    use sha2::{Digest, Sha256};
    let exe = std::env::current_exe()
        .map_err(|err| format!("cannot find this executable to identify it: {err}"))?;
    // Hashed as it is read: the executable is never held whole.
    let cannot = |err: std::io::Error| format!("{}: cannot read: {err}", exe.display());
    let mut hasher = Sha256::new();
    std::io::copy(&mut std::fs::File::open(&exe).map_err(cannot)?, &mut hasher).map_err(cannot)?;
    let digest = hasher.finalize();
    let hex: String = digest[..8].iter().map(|b| format!("{b:02x}")).collect();
    Ok(format!("rvtol {} sha256:{hex}", env!("CARGO_PKG_VERSION")))
}

/// Shard `shard` of `shards` of a run or an analysis.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ShardOf {
    /// Its index K (0-based).
    pub shard: u64,
    /// The shard count N.
    pub shards: u64,
}

impl ShardOf {
    /// Its share of `total` items (chunks, permutations).
    pub fn range(&self, total: u64) -> Range<u64> {
        shard_range(total, self.shard, self.shards)
    }

    /// The header of this shard's file: `command` of the scenario `text` over `chunks`.
    pub fn header(
        &self,
        build: String,
        text: &ScenarioText,
        command: ShardCommand,
        chunks: &Range<u64>,
    ) -> ShardHeader {
        ShardHeader {
            rvtol_version: env!("CARGO_PKG_VERSION").to_string(),
            build,
            scenario_fallback_name: text.fallback_name.clone(),
            scenario_file: text.text.clone(),
            command,
            shard: self.shard,
            shards: self.shards,
            chunks: [chunks.start, chunks.end],
        }
    }
}

/// The command of a run's shards.
pub fn run_command(settings: &RunSettings) -> ShardCommand {
    ShardCommand::Run {
        samples: settings.samples,
        seed: settings.seed,
        exact_percentile_limit: settings.exact_percentile_limit,
        sampling: settings.sampling.method.name().to_string(),
        replicates: settings.sampling.replicates,
    }
}

/// The command of a sensitivity analysis' shards (`shapley`: this shard's Shapley part).
pub fn sensitivity_command(
    request: &SensitivityRequest,
    settings: &SensitivitySettings,
    shapley: Option<ShapleyShard>,
) -> ShardCommand {
    ShardCommand::Sensitivity {
        samples: settings.base_samples,
        seed: settings.seed,
        bootstrap: settings.bootstrap as u64,
        row_bootstrap_limit: request.row_bootstrap_limit,
        sampling: settings.sampling.method.name().to_string(),
        replicates: settings.sampling.replicates,
        shapley,
    }
}

/// This shard's Shapley permutations of the analysis `request` of `scenario` (seed
/// `seed`): the estimate's settings, the header's part and the range, when it has any.
pub fn shapley_shard(
    scenario: &Scenario,
    request: &SensitivityRequest,
    seed: u64,
    of: ShardOf,
) -> Result<Option<(ShapleySettings, ShapleyShard, Range<u64>)>, ScenarioError> {
    let (Some(settings), Some(shapley)) = (request.shapley_settings(seed), request.shapley) else {
        return Ok(None);
    };
    let total = shapley_permutations(scenario, settings)?;
    let range = of.range(total);
    let shard = ShapleyShard {
        budget: shapley.permutations,
        outer: shapley.outer,
        permutations: total,
        range: [range.start, range.end],
    };
    Ok(Some((settings, shard, range)))
}

/// The shards of one run or analysis, turned back into its request and its partials.
pub struct Merged {
    /// The header they share (the first file's).
    pub header: ShardHeader,
    /// The scenario of their text.
    pub scenario: Scenario,
    /// What the merge folds.
    pub work: MergedWork,
}

/// The partials of a run or of a sensitivity analysis, with the settings they were
/// computed under.
pub enum MergedWork {
    /// A run's partials.
    Run {
        /// The run's settings.
        settings: RunSettings,
        /// One per shard, in any order.
        partials: Vec<RunPartial>,
    },
    /// A sensitivity analysis' partials.
    Sensitivity {
        /// The analysis' settings.
        settings: SensitivitySettings,
        /// The Shapley estimate's settings, when it has one.
        shapley: Option<ShapleySettings>,
        /// The Sobol' matrices' values of each shard.
        sobol: Vec<SobolPartial>,
        /// The Shapley permutations of every shard.
        permutations: Vec<ShapleyPartial>,
    },
}

/// Why a checked set of shard files does not give a request back.
#[derive(Debug, Clone, PartialEq)]
pub enum MergeError {
    /// Their scenario text does not compile (here, with this build).
    Scenario(ScenarioError),
    /// A setting of the header this build does not know (a damaged file).
    Damaged(String),
    /// The analysis' settings are refused as a request of them would be.
    Settings(Refusal),
}

/// The request and the partials of a checked set of shard files ([`crate::shard::assemble`],
/// none missing).
pub fn merged(assembly: Assembly) -> Result<Merged, MergeError> {
    let header = assembly.header;
    let scenario = Scenario::from_json(&header.scenario_file, &header.scenario_fallback_name)
        .map_err(MergeError::Scenario)?;
    let work = match &header.command {
        ShardCommand::Run { .. } => MergedWork::Run {
            settings: (header.command.run_settings())
                .map_err(MergeError::Damaged)?
                .expect("a run command has run settings"),
            partials: (assembly.shards.into_iter())
                .filter_map(|f| match f.content {
                    ShardContent::Run(partial) => Some(partial),
                    ShardContent::Sensitivity { .. } => None,
                })
                .collect(),
        },
        ShardCommand::Sensitivity {
            samples,
            seed,
            bootstrap,
            row_bootstrap_limit,
            shapley,
            ..
        } => {
            let sampling = header.command.sampling().map_err(MergeError::Damaged)?;
            let request = SensitivityRequest {
                samples: *samples,
                seed: Some(*seed),
                sampling: Some(sampling.method),
                replicates: Some(sampling.replicates),
                bootstrap: (!sampling.is_replicated()).then_some(*bootstrap),
                row_bootstrap_limit: *row_bootstrap_limit,
                shapley: shapley.as_ref().map(|s| ShapleyRequest {
                    permutations: s.budget,
                    outer: s.outer,
                }),
            };
            let settings =
                (request.settings(&scenario, Caller::CommandLine)).map_err(MergeError::Settings)?;
            let (mut sobol, mut permutations) = (Vec::new(), Vec::new());
            for file in assembly.shards {
                if let ShardContent::Sensitivity {
                    sobol: s,
                    shapley: p,
                } = file.content
                {
                    sobol.push(s);
                    permutations.extend(p);
                }
            }
            MergedWork::Sensitivity {
                settings,
                shapley: request.shapley_settings(*seed),
                sobol,
                permutations,
            }
        }
    };
    Ok(Merged {
        header,
        scenario,
        work,
    })
}

/// The bound of the shard files a merge reads: the memory budget (`max_memory` or what the
/// machine has, within the process's limits, with `threads` workers) less the program's.
/// The files are held decoded, about their size each, while the next is read, so each file
/// is read within what the ones before it left ([`read_shards`]).
pub fn shards_limit(max_memory: Option<f64>, threads: usize, caller: Caller) -> ReadLimit {
    let (budget, budget_source) = memory_budget(max_memory, threads, caller);
    ReadLimit {
        bytes: (budget - BASE_BYTES).max(0.0) as u64,
        source: format!(
            "the memory left for the shard files, of the {} available ({budget_source}), less the files read before it",
            human_bytes(budget)
        ),
    }
}

/// The shard files at `paths`, decoded, with their paths as messages name them; together
/// within `limit` ([`shards_limit`]). Its error is one line.
pub fn read_shards(
    paths: &[PathBuf],
    limit: &ReadLimit,
) -> Result<Vec<(String, ShardFile)>, String> {
    let mut read_so_far = 0u64;
    let mut files = Vec::with_capacity(paths.len());
    for path in paths {
        let bytes = read_bytes(path, &limit.less(read_so_far))?;
        read_so_far += bytes.len() as u64;
        let file = decode(&bytes).map_err(|err| format!("{}: {err}", path.display()))?;
        files.push((path.display().to_string(), file));
    }
    Ok(files)
}
