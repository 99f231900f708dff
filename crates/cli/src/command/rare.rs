//! `rvtol rare`: the probability of an output's rare event (beyond its spec limits, or a
//! threshold) by importance sampling around FORM's design points and by subset
//! simulation, each with its 95 % interval and the evaluations it took.

use std::path::PathBuf;

use anyhow::Result;
use clap::{Args, ValueEnum};
use rvtol_analysis::rare::report::rare_report;
use rvtol_analysis::rare::Method;
use rvtol_analysis::request::memory;
use rvtol_analysis::request::rare::RareRequest;

use super::{
    html_page, load, outputs_ok, pool_for, problem_of_file, refused, scenario_inputs,
    staged_report, Destinations, Execution, CALLER,
};
use crate::limits::{parse_count, parse_seed};
use crate::progress::Progress;

/// An estimator as the option names it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum MethodArg {
    /// Importance sampling around FORM's most probable points.
    Importance,
    /// Subset simulation (no assumption about where the event lies).
    Subset,
}

/// The arguments of `rvtol rare`.
#[derive(Debug, Args)]
pub struct RareArgs {
    /// Scenario file (JSON; "-" reads standard input).
    pub scenario: PathBuf,
    /// The output (default: the scenario's only continuous output).
    #[arg(long, value_name = "NAME")]
    pub output: Option<String>,
    /// The event: the output above this value (default: out of its spec limits, with the
    /// samples its indicator flags non-conforming).
    #[arg(
        long,
        value_name = "VALUE",
        allow_hyphen_values = true,
        conflicts_with = "below"
    )]
    pub above: Option<f64>,
    /// The event: the output below this value.
    #[arg(long, value_name = "VALUE", allow_hyphen_values = true)]
    pub below: Option<f64>,
    /// An estimator (repeat for both; default: both).
    #[arg(long = "method", value_enum, value_name = "METHOD")]
    pub methods: Vec<MethodArg>,
    /// Stop when the 95 % interval's half width is at most this share of the estimate.
    #[arg(long, value_name = "SHARE", allow_hyphen_values = true)]
    pub precision: Option<f64>,
    /// Model evaluations each estimator may make (default 10,000,000); the search for
    /// importance sampling's centre, its first batch and subset simulation's first run are
    /// made whatever the budget.
    #[arg(long, value_parser = parse_count, allow_hyphen_values = true)]
    pub max_evaluations: Option<u64>,
    /// Points per level of subset simulation (default 2,000).
    #[arg(long, value_parser = parse_count, allow_hyphen_values = true)]
    pub level_samples: Option<u64>,
    /// Seed (default: the scenario's `seed`, else 1).
    #[arg(long, value_parser = parse_seed, allow_hyphen_values = true)]
    pub seed: Option<u64>,
    /// Write the JSON report to PATH ("-" for stdout instead of the text).
    #[arg(long, value_name = "PATH")]
    pub json: Option<PathBuf>,
    /// Write an HTML report to PATH (.html, or "-" for stdout): one self-contained page
    /// with the importance factors drawn.
    #[arg(long, value_name = "PATH")]
    pub html: Option<PathBuf>,
    #[command(flatten)]
    pub execution: Execution,
}

/// `rvtol rare`.
pub fn rare(args: RareArgs) -> Result<()> {
    let (path, execution) = (args.scenario.as_path(), &args.execution);
    let to = Destinations {
        json: args.json.as_deref(),
        html: args.html.as_deref(),
        samples: None,
    };
    outputs_ok(&to.targets(&[]), &scenario_inputs(path))?;
    let scenario = load(path)?;
    let request = RareRequest {
        output: args.output.clone(),
        above: args.above,
        below: args.below,
        methods: (args.methods.iter())
            .map(|m| match m {
                MethodArg::Importance => Method::Importance,
                MethodArg::Subset => Method::Subset,
            })
            .collect(),
        precision: args.precision,
        max_evaluations: args.max_evaluations,
        level_samples: args.level_samples,
        seed: args.seed,
        max_non_finite: execution.max_non_finite,
    };
    let settings = request
        .settings(&scenario, CALLER)
        .map_err(|r| refused(path, r))?;
    let pool = pool_for(execution, "rare", |threads| {
        memory::rare(&scenario, settings.level_samples, threads)
    })?;
    let budget = settings.budget.max_evaluations * settings.methods.len() as u64;
    let bar = Progress::counter("rare", budget, execution.quiet, pool.current_num_threads());
    let report = (pool.install(|| rare_report(&scenario, &settings, &|n| bar.inc(n))))
        .map_err(|err| problem_of_file(path, err))?;
    bar.finish_and_clear();
    let json = report.to_json();
    let mut staged = staged_report(&to, &json, || report.to_text())?;
    if let Some(html) = to.html {
        let page = html_page(html, path, &scenario, rvtol_report::Kind::Rare, &json)?;
        staged.add(html, &page)?;
    }
    staged.commit()
}
