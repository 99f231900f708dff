//! `rvtol sensitivity`: Sobol' indices of the scenario's source groups (and with
//! `--shapley` Shapley effects) with their intervals, or with `--shard K/N` the model values
//! of its share of the analysis; the report's end shared with the merge of its shards.

use std::path::{Path, PathBuf};

use anyhow::Result;
use clap::Args;
use rvtol_analysis::request::memory;
use rvtol_analysis::request::sensitivity::{SensitivityRequest, ShapleyRequest};
use rvtol_analysis::request::shard::{build_identity, ShardOf};
use rvtol_analysis::sensitivity::{
    sobol_indices, SensitivitySettings, DEFAULT_ROW_BOOTSTRAP_LIMIT,
};
use rvtol_analysis::sensitivity_report::SensitivityReport;
use rvtol_analysis::shapley::shapley_effects;
use rvtol_deviation::SamplingMethod;
use rvtol_engine::Scenario;

use super::{
    html_page, load, outputs_ok, partial_target, pool_for, problem_of_file, read, refused,
    scenario_inputs, staged_report, Destinations, Execution, CALLER,
};
use crate::limits::{parse_count, parse_sampling, parse_seed, parse_shard};
use crate::output::{print, write_bytes};
use crate::progress::Progress;
use crate::BadInput;

/// The arguments of `rvtol sensitivity`.
#[derive(Debug, Args)]
pub struct SensitivityArgs {
    /// Scenario file (JSON; "-" reads standard input).
    pub scenario: PathBuf,
    #[command(flatten)]
    pub options: SensitivityOptions,
    /// Compute only shard K of N (0 <= K < N) of the analysis' model evaluations (its
    /// share of the base samples and of the Shapley permutations) and write them to
    /// --partial instead of a report; `rvtol merge` folds the N partials into the
    /// report, byte for byte this command's without --shard.
    #[arg(long, value_name = "K/N", value_parser = parse_shard, allow_hyphen_values = true, requires = "partial", conflicts_with_all = ["json", "html"])]
    pub shard: Option<(u64, u64)>,
    /// The shard's partial result file (with --shard).
    #[arg(long, value_name = "FILE", requires = "shard")]
    pub partial: Option<PathBuf>,
    /// Write the JSON report to PATH ("-" for stdout instead of the table).
    #[arg(long, value_name = "PATH")]
    pub json: Option<PathBuf>,
    /// Write an HTML report to PATH (.html, or "-" for stdout): one self-contained page
    /// with the plots.
    #[arg(long, value_name = "PATH")]
    pub html: Option<PathBuf>,
    #[command(flatten)]
    pub execution: Execution,
}

/// The analysis options of `rvtol sensitivity`.
#[derive(Debug, Clone, Args)]
pub struct SensitivityOptions {
    /// Base samples N; the models are evaluated N·(2·groups + 2) times.
    #[arg(long, default_value_t = rvtol_analysis::request::sensitivity::DEFAULT_SAMPLES, value_parser = parse_count, allow_hyphen_values = true)]
    pub samples: u64,
    /// Seed of the random streams (default: the scenario's `seed`, else 1).
    #[arg(long, value_parser = parse_seed, allow_hyphen_values = true)]
    pub seed: Option<u64>,
    /// How the rows of A and B are drawn: mc (independent draws; bootstrap intervals),
    /// lhs or rqmc (replicates of a Latin hypercube or scrambled Sobol' design; intervals
    /// from their spread); default: the scenario's `sampling`, else mc.
    #[arg(long, value_name = "METHOD", value_parser = parse_sampling)]
    pub sampling: Option<SamplingMethod>,
    /// Independent randomizations of an lhs or rqmc design (default: the scenario's
    /// `replicates`, else 16); the base samples split evenly between them.
    #[arg(long, value_name = "R", value_parser = parse_count, allow_hyphen_values = true)]
    pub replicates: Option<u64>,
    /// Bootstrap resamples for the 95 % intervals of a Monte Carlo analysis (default 500).
    #[arg(long, value_parser = parse_count, allow_hyphen_values = true)]
    pub bootstrap: Option<u64>,
    /// Most model values kept for the row bootstrap; beyond, the intervals come from a
    /// bootstrap of blocks of rows (bounded memory).
    #[arg(long, value_name = "VALUES", default_value_t = DEFAULT_ROW_BOOTSTRAP_LIMIT, value_parser = parse_count, allow_hyphen_values = true)]
    pub row_bootstrap_limit: u64,
    /// Also estimate Shapley effects per source (exact for correlated inputs; needs
    /// parts without the Eq. 11 constraint).
    #[arg(long)]
    pub shapley: bool,
    /// Shapley: permutation budget (all orders when d! fits, repeated).
    #[arg(long, default_value_t = rvtol_analysis::request::sensitivity::DEFAULT_PERMUTATIONS, value_parser = parse_count, allow_hyphen_values = true)]
    pub permutations: u64,
    /// Shapley: outer draws per conditional-variance estimate.
    #[arg(long, default_value_t = rvtol_analysis::request::sensitivity::DEFAULT_OUTER, value_parser = parse_count, allow_hyphen_values = true)]
    pub outer: u64,
}

impl SensitivityOptions {
    /// The analysis the command line asks for.
    pub fn request(&self) -> SensitivityRequest {
        SensitivityRequest {
            samples: self.samples,
            seed: self.seed,
            sampling: self.sampling,
            replicates: self.replicates,
            bootstrap: self.bootstrap,
            row_bootstrap_limit: self.row_bootstrap_limit,
            shapley: self.shapley.then_some(ShapleyRequest {
                permutations: self.permutations,
                outer: self.outer,
            }),
        }
    }
}

/// `rvtol sensitivity`: the whole analysis and its report, or one shard of it.
pub fn sensitivity(args: SensitivityArgs) -> Result<()> {
    if let (Some(shard), Some(partial)) = (args.shard, &args.partial) {
        return sensitivity_shard(&args, shard, partial);
    }
    let (path, execution) = (args.scenario.as_path(), &args.execution);
    let to = Destinations {
        json: args.json.as_deref(),
        html: args.html.as_deref(),
        samples: None,
    };
    outputs_ok(&to.targets(&[]), &scenario_inputs(path))?;
    let scenario = load(path)?;
    let request = args.options.request();
    let settings =
        (request.settings(&scenario, CALLER)).map_err(|refusal| refused(path, refusal))?;
    let pool = pool_for(execution, "sensitivity", |threads| {
        memory::sensitivity(&scenario, &settings, threads)
    })?;
    let bar = Progress::new(
        "sensitivity",
        args.options.samples,
        execution.quiet,
        pool.current_num_threads(),
    );
    let outputs = pool
        .install(|| sobol_indices(&scenario, settings, &|n| bar.inc(n)))
        .map_err(|err| problem_of_file(path, err))?;
    bar.finish_and_clear();
    let shapley = match request.shapley_settings(settings.seed) {
        Some(shapley) => Some(
            pool.install(|| shapley_effects(&scenario, shapley))
                .map_err(|err| problem_of_file(path, err))?,
        ),
        None => None,
    };
    finish_sensitivity(
        path, &scenario, settings, outputs, shapley, to, execution, &pool,
    )
}

/// The screening, the report and its files, and the check of the rows lost to non-finite
/// values: what `sensitivity` and the merge of its shards share.
#[allow(clippy::too_many_arguments)]
pub(super) fn finish_sensitivity(
    path: &Path,
    scenario: &Scenario,
    settings: SensitivitySettings,
    outputs: Vec<rvtol_analysis::sensitivity::OutputSensitivity>,
    shapley: Option<Vec<(String, Vec<rvtol_analysis::shapley::ShapleyEffect>)>>,
    to: Destinations<'_>,
    execution: &Execution,
    pool: &rayon::ThreadPool,
) -> Result<()> {
    let report = pool
        .install(|| SensitivityReport::complete(scenario, settings, outputs, shapley))
        .map_err(|err| problem_of_file(path, err))?;
    let json = report.to_json();
    let mut staged = staged_report(&to, &json, || report.to_text())?;
    let lost: Vec<String> = report
        .outputs
        .iter()
        .filter(|o| {
            o.non_finite_rows as f64 > execution.max_non_finite * settings.base_samples as f64
        })
        .map(|o| format!("{} ({} rows)", o.name, o.non_finite_rows))
        .collect();
    if lost.is_empty() {
        if let Some(html) = to.html {
            let page = html_page(html, path, scenario, rvtol_report::Kind::Sensitivity, &json)?;
            staged.add(html, &page)?;
        }
        staged.commit()
    } else {
        // The report shows what was lost; no file is replaced by a failed analysis.
        staged.print_only()?;
        Err(BadInput(format!(
            "{}: rows with non-finite model values were left out of the indices of {}, more than the allowed share {} of the base samples; narrow the distributions to the models' domain, or accept a share with --max-non-finite",
            path.display(),
            lost.join(", "),
            execution.max_non_finite
        ))
        .into())
    }
}

/// `sensitivity --shard K/N --partial FILE`: the model values of shard K of N of the
/// matrices and, with `--shapley`, of its share of the permutations.
fn sensitivity_shard(
    args: &SensitivityArgs,
    (shard, shards): (u64, u64),
    partial_path: &Path,
) -> Result<()> {
    let (path, execution) = (args.scenario.as_path(), &args.execution);
    outputs_ok(&[partial_target(partial_path)], &scenario_inputs(path))?;
    use rvtol_analysis::request::shard::{sensitivity_command, shapley_shard};
    use rvtol_analysis::shard::ShardContent;
    let (scenario, text) = read(path)?;
    let request = args.options.request();
    let settings =
        (request.settings(&scenario, CALLER)).map_err(|refusal| refused(path, refusal))?;
    let build = build_identity().map_err(BadInput)?;
    let pool = pool_for(execution, "sensitivity", |threads| {
        memory::sensitivity(&scenario, &settings, threads)
    })?;
    let of = ShardOf { shard, shards };
    let chunks = of.range(settings.chunk_count());
    let bar = Progress::new(
        "sensitivity",
        settings.samples_before_chunk(chunks.end) - settings.samples_before_chunk(chunks.start),
        execution.quiet,
        pool.current_num_threads(),
    );
    let sobol = pool
        .install(|| {
            rvtol_analysis::sensitivity::sobol_chunks(&scenario, settings, chunks.clone(), &|n| {
                bar.inc(n)
            })
        })
        .map_err(|err| problem_of_file(path, err))?;
    bar.finish_and_clear();
    let (shapley, shapley_part) = match shapley_shard(&scenario, &request, settings.seed, of)
        .map_err(|err| problem_of_file(path, err))?
    {
        Some((shapley_settings, part, range)) => {
            let partial = pool
                .install(|| {
                    rvtol_analysis::shapley::shapley_partial(&scenario, shapley_settings, range)
                })
                .map_err(|err| problem_of_file(path, err))?;
            (Some(partial), Some(part))
        }
        None => (None, None),
    };
    let command = sensitivity_command(&request, &settings, shapley_part);
    let header = of.header(build, &text, command, &chunks);
    write_bytes(
        partial_path,
        &rvtol_analysis::shard::encode(&header, &ShardContent::Sensitivity { sobol, shapley }),
    )?;
    print(&format!(
        "{}: sensitivity shard {shard}/{shards} of {} ({} of {} base samples, seed {}) written to {}\n",
        path.display(),
        scenario.name,
        rvtol_engine::format::group_thousands(settings.samples_before_chunk(chunks.end) - settings.samples_before_chunk(chunks.start)),
        rvtol_engine::format::group_thousands(settings.base_samples),
        settings.seed,
        partial_path.display()
    ))
}
