//! `rvtol run`: the Monte Carlo run of a scenario and its report (table, JSON, HTML page,
//! the samples), or with `--shard K/N` the partial result of its share of the chunks.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use anyhow::Result;
use clap::Args;
use rvtol_analysis::request::memory;
use rvtol_analysis::request::run::{check_samples_out, RunRequest};
use rvtol_analysis::request::shard::{build_identity, ShardOf};
use rvtol_deviation::SamplingMethod;
use rvtol_engine::{run as run_scenario, RunReport, DEFAULT_EXACT_PERCENTILE_LIMIT};

use super::{
    html_page, load, non_finite_failure, outputs_ok, partial_target, pool_for, problem_of_file,
    read, refused, sample_table_bytes, scenario_inputs, stage_report, Destinations, Execution,
    CALLER,
};
use crate::limits::{parse_count, parse_sampling, parse_seed, parse_shard};
use crate::output::{note, print, write_bytes, StagedOutputs};
use crate::progress::Progress;
use crate::BadInput;

/// The arguments of `rvtol run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// Scenario file (JSON; "-" reads standard input).
    pub scenario: PathBuf,
    /// Number of samples, e.g. 1000000 or 1e6 (default: the scenario's `samples`, else
    /// 1,000,000).
    #[arg(long, value_parser = parse_count, allow_hyphen_values = true)]
    pub samples: Option<u64>,
    /// Seed of the random streams (default: the scenario's `seed`, else 1).
    #[arg(long, value_parser = parse_seed, allow_hyphen_values = true)]
    pub seed: Option<u64>,
    /// How rows are drawn: mc (independent draws), lhs (Latin hypercube) or rqmc
    /// (scrambled Sobol' points); default: the scenario's `sampling`, else mc.
    #[arg(long, value_name = "METHOD", value_parser = parse_sampling)]
    pub sampling: Option<SamplingMethod>,
    /// Independent randomizations of an lhs or rqmc run, whose spread gives the
    /// intervals (default: the scenario's `replicates`, else 16); the samples split
    /// evenly between them.
    #[arg(long, value_name = "R", value_parser = parse_count, allow_hyphen_values = true)]
    pub replicates: Option<u64>,
    /// Write the JSON report to PATH ("-" for stdout instead of the table).
    #[arg(long, value_name = "PATH")]
    pub json: Option<PathBuf>,
    /// Write an HTML report to PATH (.html, or "-" for stdout): one self-contained page
    /// with the plots.
    #[arg(long, value_name = "PATH")]
    pub html: Option<PathBuf>,
    /// Write every sample to PATH, one row per sample: its index, the drawn inputs and
    /// the outputs (the run's own values; same seed, same bytes); PATH ends in .csv or
    /// .parquet, which chooses the format ("-": CSV on stdout instead of the table).
    #[arg(long, value_name = "PATH")]
    pub samples_out: Option<PathBuf>,
    /// Exact percentiles while samples × continuous outputs stays at or below this many values;
    /// a bounded-memory sketch beyond it.
    #[arg(long, value_name = "VALUES", default_value_t = DEFAULT_EXACT_PERCENTILE_LIMIT, value_parser = parse_count, allow_hyphen_values = true)]
    pub exact_percentile_limit: u64,
    /// Compute only shard K of N (0 <= K < N, e.g. a job array's task index) and write
    /// its partial result to --partial instead of a report; `rvtol merge` folds the N
    /// partials into the run's report, byte for byte this command's without --shard.
    #[arg(long, value_name = "K/N", value_parser = parse_shard, allow_hyphen_values = true, requires = "partial", conflicts_with_all = ["json", "html", "samples_out"])]
    pub shard: Option<(u64, u64)>,
    /// The shard's partial result file (with --shard).
    #[arg(long, value_name = "FILE", requires = "shard")]
    pub partial: Option<PathBuf>,
    #[command(flatten)]
    pub execution: Execution,
}

impl RunArgs {
    /// The run the command line asks for.
    fn request(&self) -> RunRequest {
        RunRequest {
            samples: self.samples,
            seed: self.seed,
            exact_percentile_limit: self.exact_percentile_limit,
            sampling: self.sampling,
            replicates: self.replicates,
        }
    }
}

/// `rvtol run`: the whole run and its reports, or one shard of it.
pub fn run(args: RunArgs) -> Result<()> {
    if let (Some(shard), Some(partial)) = (args.shard, &args.partial) {
        return run_shard(&args, shard, partial);
    }
    let (scenario_path, execution) = (args.scenario.as_path(), &args.execution);
    let to = Destinations {
        json: args.json.as_deref(),
        html: args.html.as_deref(),
        samples: args.samples_out.as_deref(),
    };
    outputs_ok(&to.targets(&[]), &scenario_inputs(scenario_path))?;
    let scenario = load(scenario_path)?;
    let settings = (args.request().settings(&scenario, CALLER))
        .map_err(|refusal| refused(scenario_path, refusal))?;
    if to.samples.is_some() {
        check_samples_out(&scenario, settings.samples, CALLER)
            .map_err(|refusal| refused(scenario_path, refusal))?;
    }
    let pool = pool_for(execution, "run", |threads| {
        memory::run(&scenario, &settings, threads)
    })?;
    let bar = Progress::new(
        "run",
        settings.samples,
        execution.quiet,
        pool.current_num_threads(),
    );
    let started = std::time::Instant::now();
    let result = pool
        .install(|| run_scenario(&scenario, settings, &|n| bar.inc(n)))
        .map_err(|err| problem_of_file(scenario_path, err))?;
    bar.finish_and_clear();
    let elapsed = started.elapsed();
    let failure = non_finite_failure(scenario_path, &scenario, &result, execution);
    let report = pool.install(|| RunReport::new(&scenario, result));
    let json = report.to_json();
    let mut staged = StagedOutputs::new();
    stage_report(
        &mut staged,
        to.json,
        to.on_stdout(),
        || json.clone(),
        || report.to_text(),
    )?;
    if failure.is_err() {
        // The report shows what was lost; no file is replaced by a failed run.
        staged.print_only()?;
        return failure;
    }
    if let Some(path) = to.samples {
        let table = pool
            .install(|| rvtol_engine::sample_table(&scenario, settings))
            .map_err(|err| problem_of_file(scenario_path, err))?;
        staged.add_bytes(path, &sample_table_bytes(path, &scenario, &table)?)?;
    }
    if let Some(html) = to.html {
        let page = html_page(
            html,
            scenario_path,
            &scenario,
            rvtol_report::Kind::Run,
            &json,
        )?;
        staged.add(html, &page)?;
    }
    staged.commit()?;
    if !execution.quiet && std::io::stderr().is_terminal() {
        note(&format!(
            "{} samples in {:.2} s ({:.1} ns per sample)",
            settings.samples,
            elapsed.as_secs_f64(),
            elapsed.as_secs_f64() * 1e9 / settings.samples as f64
        ));
    }
    Ok(())
}

/// `run --shard K/N --partial FILE`: computes shard K of N of the run and writes its
/// partial result.
fn run_shard(args: &RunArgs, (shard, shards): (u64, u64), partial_path: &Path) -> Result<()> {
    let (scenario_path, execution) = (args.scenario.as_path(), &args.execution);
    outputs_ok(
        &[partial_target(partial_path)],
        &scenario_inputs(scenario_path),
    )?;
    let (scenario, text) = read(scenario_path)?;
    let settings = (args.request().settings(&scenario, CALLER))
        .map_err(|refusal| refused(scenario_path, refusal))?;
    let build = build_identity().map_err(BadInput)?;
    let of = ShardOf { shard, shards };
    let chunks = of.range(settings.chunk_count());
    let pool = pool_for(execution, "run", |threads| {
        memory::run(&scenario, &settings, threads)
    })?;
    let shard_samples =
        settings.samples_before_chunk(chunks.end) - settings.samples_before_chunk(chunks.start);
    let bar = Progress::new(
        "run",
        shard_samples,
        execution.quiet,
        pool.current_num_threads(),
    );
    let partial = pool
        .install(|| rvtol_engine::run_chunks(&scenario, settings, chunks.clone(), &|n| bar.inc(n)))
        .map_err(|err| problem_of_file(scenario_path, err))?;
    bar.finish_and_clear();
    let command = rvtol_analysis::request::shard::run_command(&settings);
    let header = of.header(build, &text, command, &chunks);
    write_bytes(
        partial_path,
        &rvtol_analysis::shard::encode(&header, &rvtol_analysis::shard::ShardContent::Run(partial)),
    )?;
    print(&format!(
        "{}: shard {shard}/{shards} of {} ({} of {} samples, seed {}) written to {}\n",
        scenario_path.display(),
        scenario.name,
        rvtol_engine::format::group_thousands(shard_samples),
        rvtol_engine::format::group_thousands(settings.samples),
        settings.seed,
        partial_path.display()
    ))
}
