//! `rvtol stack`: the worst case, the arithmetic and RSS stacks and the contributor table
//! of the scenario's outputs over its tolerance box, beside the Monte Carlo run's
//! percentiles and out-of-spec share.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use rvtol_analysis::request::memory;
use rvtol_analysis::request::stack::StackRequest;
use rvtol_analysis::stack::report::stack_report;

use super::{
    html_page, load, outputs_ok, pool_for, problem_of_file, refused, scenario_inputs,
    staged_report, Destinations, Execution, CALLER,
};
use crate::limits::{parse_count, parse_seed};
use crate::progress::Progress;

/// The arguments of `rvtol stack`.
#[derive(Debug, Args)]
pub struct StackArgs {
    /// Scenario file (JSON; "-" reads standard input).
    pub scenario: PathBuf,
    /// An output to analyse (repeat for more; default: every continuous output).
    #[arg(long = "output", value_name = "NAME")]
    pub outputs: Vec<String>,
    /// Samples of the Monte Carlo run beside the stack (default: the scenario's
    /// `samples`, else 1,000,000).
    #[arg(long, value_parser = parse_count, allow_hyphen_values = true)]
    pub samples: Option<u64>,
    /// Leave the Monte Carlo run out (the stack alone).
    #[arg(long, conflicts_with = "samples")]
    pub no_monte_carlo: bool,
    /// Seed of the Monte Carlo run and of the linearity rows (default: the scenario's
    /// `seed`, else 1).
    #[arg(long, value_parser = parse_seed, allow_hyphen_values = true)]
    pub seed: Option<u64>,
    /// Write the JSON report to PATH ("-" for stdout instead of the tables).
    #[arg(long, value_name = "PATH")]
    pub json: Option<PathBuf>,
    /// Write an HTML report to PATH (.html, or "-" for stdout): one self-contained page
    /// with the figures side by side and the contributors' shares.
    #[arg(long, value_name = "PATH")]
    pub html: Option<PathBuf>,
    #[command(flatten)]
    pub execution: Execution,
}

/// `rvtol stack`.
pub fn stack(args: StackArgs) -> Result<()> {
    let (path, execution) = (args.scenario.as_path(), &args.execution);
    let to = Destinations {
        json: args.json.as_deref(),
        html: args.html.as_deref(),
        samples: None,
    };
    outputs_ok(&to.targets(&[]), &scenario_inputs(path))?;
    let scenario = load(path)?;
    let request = StackRequest {
        outputs: args.outputs.clone(),
        seed: args.seed,
        monte_carlo: !args.no_monte_carlo,
        samples: args.samples,
        max_non_finite: execution.max_non_finite,
    };
    let (settings, run_settings) =
        (request.settings(&scenario, CALLER)).map_err(|r| refused(path, r))?;
    let pool = pool_for(execution, "stack", |threads| {
        memory::stack(&scenario, run_settings.as_ref(), threads)
    })?;
    let samples = run_settings.map_or(0, |run| run.samples);
    let bar = Progress::new(
        "stack",
        samples,
        execution.quiet,
        pool.current_num_threads(),
    );
    let report = (pool
        .install(|| stack_report(&scenario, &settings, run_settings, &|n| bar.inc(n))))
    .map_err(|err| problem_of_file(path, err))?;
    bar.finish_and_clear();
    let json = report.to_json();
    let mut staged = staged_report(&to, &json, || report.to_text())?;
    if let Some(html) = to.html {
        let page = html_page(html, path, &scenario, rvtol_report::Kind::Stack, &json)?;
        staged.add(html, &page)?;
    }
    staged.commit()
}
