//! `rvtol check`: a scenario re-run and compared with its baseline (the bands, the
//! requirements), the verdict as the exit code, a JSON and a JUnit XML report.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use rvtol_analysis::gate;
use rvtol_analysis::request::gate::{
    baseline_text_matches, check_requirements, check_settings, RequirementError,
};
use rvtol_analysis::request::memory;

use super::{
    outputs_ok, pool_for, problem_of_file, read, read_text, scenario_inputs, stage_report, target,
    Execution, CALLER,
};
use crate::limits::parse_seed;
use crate::output::{is_stdout, Format, StagedOutputs};
use crate::progress::Progress;
use crate::{BadInput, Failed};

/// The arguments of `rvtol check`.
#[derive(Debug, Args)]
pub struct CheckArgs {
    /// Scenario file (JSON; "-" reads standard input).
    pub scenario: PathBuf,
    /// Baseline file written by `rvtol baseline`.
    #[arg(long, value_name = "FILE")]
    pub baseline: PathBuf,
    /// Seed of the check run (default: the baseline's).
    #[arg(long, value_parser = parse_seed, allow_hyphen_values = true)]
    pub seed: Option<u64>,
    /// Write a JUnit XML report to PATH.
    #[arg(long, value_name = "PATH")]
    pub junit: Option<PathBuf>,
    /// Write the JSON report to PATH ("-" for stdout instead of the summary).
    #[arg(long, value_name = "PATH")]
    pub json: Option<PathBuf>,
    /// Fail a figure only when it gets worse beyond its band: higher for sd, ppm_out
    /// and indicator fractions, and for the mean and percentiles of an output with an
    /// upper spec limit only (lower for a lower limit only); a figure's `worse` in the
    /// baseline file overrides; the others stay two-sided.
    #[arg(long)]
    pub one_sided: bool,
    /// Check a scenario whose text differs from the one the baseline was recorded from (a
    /// design change): the report says where the text changed. Without it such a baseline
    /// is refused.
    #[arg(long)]
    pub scenario_changed: bool,
    /// An absolute requirement, "[OUTPUT] FIGURE OP VALUE" (e.g. "p99.865 <= 1.5",
    /// "cpk >= 1.33", "ppm_out <= 2700"); fails only when the re-run's whole interval
    /// misses it. Repeatable; the baseline's `requirements` apply too.
    #[arg(long = "require", value_name = "REQUIREMENT")]
    pub requirements: Vec<String>,
    #[command(flatten)]
    pub execution: Execution,
}

/// `rvtol check`: the re-run against the baseline; exit 1 when a figure moved or a
/// requirement is violated.
pub fn check(args: CheckArgs) -> Result<()> {
    let (path, baseline_path) = (args.scenario.as_path(), args.baseline.as_path());
    let (junit, json, execution) = (args.junit.as_deref(), args.json.as_deref(), &args.execution);
    let options = &gate::CheckOptions {
        one_sided: args.one_sided,
        requirements: args.requirements.clone(),
    };
    let mut inputs = scenario_inputs(path);
    inputs.push(("the baseline", baseline_path.to_path_buf()));
    outputs_ok(
        &[
            target("--junit", junit, Format::Xml),
            target("--json", json, Format::Json),
        ],
        &inputs,
    )?;
    if is_stdout(path) && is_stdout(baseline_path) {
        return Err(BadInput(
            "--baseline: standard input ('-') already gives the scenario, and it can be read once: name the baseline's file".into(),
        )
        .into());
    }
    let (scenario, text) = read(path)?;
    let baseline_text = read_text(baseline_path)?;
    let recorded = gate::Baseline::from_json(&baseline_text)
        .map_err(|err| problem_of_file(baseline_path, err))?;
    recorded
        .matches(&scenario)
        .map_err(|err| problem_of_file(baseline_path, err))?;
    baseline_text_matches(&recorded, &scenario, args.scenario_changed, CALLER)
        .map_err(|message| BadInput(format!("{}: {message}", baseline_path.display())))?;
    check_requirements(&scenario, &recorded, options, CALLER).map_err(|err| match err {
        RequirementError::Baseline { index, message } => BadInput(format!(
            "{}: requirements[{index}]: {message}",
            baseline_path.display()
        )),
        RequirementError::Given(refusal) => BadInput(refusal.to_string()),
    })?;
    let settings = check_settings(&scenario, &recorded, args.seed);
    let seed = settings.seed;
    let pool = pool_for(execution, "check", |threads| {
        memory::run(&scenario, &settings, threads)
    })?;
    let bar = Progress::new(
        "check",
        recorded.samples,
        execution.quiet,
        pool.current_num_threads(),
    );
    let report = pool
        .install(|| {
            gate::check_with(
                &scenario,
                &text.text,
                &recorded,
                seed,
                execution.max_non_finite,
                options,
                &|n| bar.inc(n),
            )
        })
        .map_err(|err| problem_of_file(path, err))?;
    bar.finish_and_clear();
    // A check's verdict, passed or failed, is its result: both reports are written.
    let mut staged = StagedOutputs::new();
    if let Some(junit) = junit {
        staged.add(junit, &report.to_junit())?;
    }
    let stdout_taken = [junit, json].into_iter().flatten().any(is_stdout);
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
        Err(Failed(
            if report.comparisons.iter().all(|c| c.passed) {
                "requirements violated"
            } else {
                "figures moved beyond their baseline bands"
            }
            .into(),
        )
        .into())
    }
}
