//! `rvtol merge`: the partial results of a sharded run or sensitivity analysis, checked for
//! coverage and identity (rvtol-analysis' `request::shard`), folded into the command's
//! report, or a run's into a baseline or a check against one.

use std::path::{Path, PathBuf};

use anyhow::Result;
use clap::Args;
use rvtol_analysis::gate;
use rvtol_analysis::request::gate::{
    baseline_matches, baseline_text_matches, check_baseline_samples,
};
use rvtol_analysis::request::memory;
use rvtol_analysis::request::shard::{build_identity, read_shards, shards_limit};
use rvtol_analysis::request::Refusal;
use rvtol_engine::Scenario;

use super::sensitivity::finish_sensitivity;
use super::{
    check_memory, html_page, outputs_ok, problem_of_file, read_text, shown, stage_report,
    staged_run_report, target, thread_pool, threads, Destinations, Execution, CALLER,
};
use crate::output::{is_stdout, print, write_report, Format, StagedOutputs};
use crate::{BadInput, Failed};

/// The arguments of `rvtol merge`.
#[derive(Debug, Args)]
pub struct MergeArgs {
    /// The shards' partial result files, in any order (a shard may appear twice when
    /// both files are identical, as after a rerun).
    #[arg(required = true)]
    pub partials: Vec<PathBuf>,
    /// Print the indices of the shards that have no file as a job-array list (`1,4-6`,
    /// the form of Slurm's --array) and exit; nothing when none is missing.
    #[arg(long, conflicts_with_all = ["json", "html", "baseline", "check"])]
    pub missing: bool,
    /// Write the JSON report to PATH ("-" for stdout instead of the table).
    #[arg(long, value_name = "PATH")]
    pub json: Option<PathBuf>,
    /// Write an HTML report to PATH (.html, or "-" for stdout): one self-contained page
    /// with the plots.
    #[arg(long, value_name = "PATH", conflicts_with_all = ["baseline", "check"])]
    pub html: Option<PathBuf>,
    /// Write the baseline of the merged run to FILE (what `rvtol baseline` writes for
    /// the same samples and seed) instead of the report.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["check", "json"])]
    pub baseline: Option<PathBuf>,
    /// Compare the merged run with a baseline as `rvtol check` does (run the shards
    /// with the baseline's samples and exact-percentile limit): exit 1 when a figure
    /// moved.
    #[arg(long, value_name = "BASELINE")]
    pub check: Option<PathBuf>,
    /// With --check: write a JUnit XML report to PATH.
    #[arg(long, value_name = "PATH", requires = "check")]
    pub junit: Option<PathBuf>,
    /// With --check: fail a figure only when it gets worse (as `check --one-sided`).
    #[arg(long, requires = "check")]
    pub one_sided: bool,
    /// With --check: check although the scenario text differs from the baseline's (as
    /// `check --scenario-changed`).
    #[arg(long, requires = "check")]
    pub scenario_changed: bool,
    /// With --check: an absolute requirement (as `check --require`). Repeatable.
    #[arg(long = "require", value_name = "REQUIREMENT", requires = "check")]
    pub requirements: Vec<String>,
    #[command(flatten)]
    pub execution: Execution,
}

/// A run merged from its shards, for a baseline or a check.
struct MergedRun<'a> {
    scenario: &'a Scenario,
    scenario_text: &'a str,
    settings: rvtol_engine::RunSettings,
    result: rvtol_engine::RunResult,
}

/// `merge --check BASELINE`: the merged run checked against the baseline (whose samples
/// and percentile limit the shards must have run).
fn merge_check(
    merged: MergedRun<'_>,
    baseline_path: &Path,
    args: &MergeArgs,
    json: Option<&Path>,
    stdout_taken: bool,
    execution: &Execution,
    pool: &rayon::ThreadPool,
) -> Result<()> {
    let baseline_text = read_text(baseline_path)?;
    let recorded = gate::Baseline::from_json(&baseline_text)
        .map_err(|err| problem_of_file(baseline_path, err))?;
    baseline_matches(&recorded, &merged.settings)
        .and_then(|()| {
            baseline_text_matches(&recorded, merged.scenario, args.scenario_changed, CALLER)
        })
        .map_err(|message| BadInput(format!("{}: {message}", baseline_path.display())))?;
    let result = std::sync::Mutex::new(Some(merged.result));
    let report = pool
        .install(|| {
            gate::check_result(
                merged.scenario,
                merged.scenario_text,
                &recorded,
                merged.settings.seed,
                execution.max_non_finite,
                &gate::CheckOptions {
                    one_sided: args.one_sided,
                    requirements: args.requirements.clone(),
                },
                // The settings are the shards' (checked above): the check's run is
                // the merged one.
                &|_| {
                    Ok(result
                        .lock()
                        .ok()
                        .and_then(|mut r| r.take())
                        .expect("a check runs once"))
                },
            )
        })
        .map_err(|err| problem_of_file(baseline_path, err))?;
    let mut staged = StagedOutputs::new();
    if let Some(junit) = &args.junit {
        staged.add(junit, &report.to_junit())?;
    }
    stage_report(
        &mut staged,
        json,
        stdout_taken,
        || report.to_json(),
        || report.to_text(),
    )?;
    staged.commit()?;
    if report.passed {
        Ok(())
    } else {
        Err(
            Failed("figures moved beyond their baseline bands or requirements violated".into())
                .into(),
        )
    }
}

/// `rvtol merge`: checks the shard files for coverage and identity and folds them into the
/// run's report (or a baseline, or a check against one).
pub fn merge(args: MergeArgs) -> Result<()> {
    let execution = &args.execution;
    let to = Destinations {
        json: args.json.as_deref(),
        html: args.html.as_deref(),
        samples: None,
    };
    let mut inputs: Vec<(&str, PathBuf)> = args
        .partials
        .iter()
        .map(|p| ("a shard file", p.clone()))
        .collect();
    inputs.extend(args.check.iter().map(|p| ("the baseline", p.clone())));
    outputs_ok(
        &to.targets(&[
            target("--baseline", args.baseline.as_deref(), Format::Json),
            target("--junit", args.junit.as_deref(), Format::Xml),
        ]),
        &inputs,
    )?;
    let stdout_taken = to.on_stdout()
        || [args.baseline.as_deref(), args.junit.as_deref()]
            .into_iter()
            .flatten()
            .any(is_stdout);
    use rvtol_analysis::request::shard::{merged, MergeError, Merged, MergedWork};
    use rvtol_analysis::shard;
    let build = build_identity().map_err(BadInput)?;
    let limit = shards_limit(execution.max_memory, threads(execution)?, CALLER);
    let files = read_shards(&args.partials, &limit).map_err(BadInput)?;
    let assembly = shard::assemble(files, &build).map_err(BadInput)?;
    let missing_count = assembly.missing_count();
    let header = &assembly.header;
    if args.missing {
        return if assembly.missing.is_empty() {
            Ok(())
        } else {
            print(&format!("{}\n", shard::range_list(&assembly.missing)))
        };
    }
    if !assembly.missing.is_empty() {
        let (noun, verb) = if missing_count == 1 {
            ("shard", "has")
        } else {
            ("shards", "have")
        };
        return Err(BadInput(format!(
            "{noun} {} of {} {verb} no file: run them (rvtol {} SCENARIO --shard K/{} --partial FILE) and merge again; merge --missing lists them",
            shard::range_list(&assembly.missing),
            header.shards,
            header.command.name(),
            header.shards
        ))
        .into());
    }
    let first = &args.partials[0];
    let Merged {
        header,
        scenario,
        work,
    } = merged(assembly).map_err(|err| match err {
        MergeError::Scenario(err) => BadInput(format!("{}: its scenario: {err}", first.display())),
        MergeError::Damaged(err) => BadInput(format!("{}: {err}", first.display())),
        MergeError::Settings(Refusal::Scenario(err)) => {
            BadInput(format!("{}: {err}", shown(first)))
        }
        MergeError::Settings(refusal) => BadInput(refusal.to_string()),
    })?;
    let threads = threads(execution)?;
    let pool = thread_pool(threads)?;
    // What the page's record names as the source: the shard files.
    let source = std::path::PathBuf::from(format!(
        "{} shard files of {} ({}, ...)",
        header.shards,
        header.command.name(),
        first.display()
    ));
    let (settings, partials) = match work {
        MergedWork::Run { settings, partials } => (settings, partials),
        MergedWork::Sensitivity {
            settings,
            shapley,
            sobol,
            permutations,
        } => {
            if args.baseline.is_some() || args.check.is_some() {
                return Err(BadInput(
                    "--baseline and --check take the shards of a run; these are of a sensitivity analysis".into(),
                )
                .into());
            }
            let outputs = pool
                .install(|| rvtol_analysis::sensitivity::merge_sobol(&scenario, settings, sobol))
                .map_err(|err| problem_of_file(first, err))?;
            let effects = match shapley {
                Some(shapley) => Some(
                    pool.install(|| {
                        rvtol_analysis::shapley::merge_shapley(&scenario, shapley, permutations)
                    })
                    .map_err(|err| problem_of_file(first, err))?,
                ),
                None => None,
            };
            return finish_sensitivity(
                &source, &scenario, settings, outputs, effects, to, execution, &pool,
            );
        }
    };
    check_memory(
        memory::run(&scenario, &settings, threads),
        execution,
        "merge",
        threads,
    )?;
    let result = rvtol_engine::merge(&scenario, settings, partials)
        .map_err(|err| problem_of_file(first, err))?;
    if let Some(path) = &args.baseline {
        check_baseline_samples(settings.samples).map_err(|message| BadInput(message.into()))?;
        let baseline = gate::baseline_of(
            &scenario,
            &header.scenario_file,
            settings,
            result,
            execution.max_non_finite,
        )
        .map_err(|err| problem_of_file(first, err))?;
        write_report(path, &baseline.to_json())?;
        if is_stdout(path) {
            return Ok(());
        }
        return print(&format!(
            "{} shards: {} figures of {} ({} samples, seed {}) written to {}\n",
            header.shards,
            baseline.figures.len(),
            baseline.scenario,
            settings.samples,
            settings.seed,
            path.display()
        ));
    }
    if let Some(baseline_path) = &args.check {
        let merged = MergedRun {
            scenario: &scenario,
            scenario_text: &header.scenario_file,
            settings,
            result,
        };
        return merge_check(
            merged,
            baseline_path,
            &args,
            to.json,
            stdout_taken,
            execution,
            &pool,
        );
    }
    let (mut staged, json) = staged_run_report(first, &scenario, result, (&to, execution), &pool)?;
    if let Some(html) = to.html {
        let page = html_page(html, &source, &scenario, rvtol_report::Kind::Run, &json)?;
        staged.add(html, &page)?;
    }
    staged.commit()
}
