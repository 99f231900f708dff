//! `rvtol allocate`: the cheapest tolerances within the scenario's `allocation` bounds that
//! meet a target on an output, verified by an independent run; the proposal as a scenario.

use std::io::IsTerminal;
use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rvtol_analysis::allocation::allocate as run_allocation;
use rvtol_analysis::allocation::proposal_document;
use rvtol_analysis::allocation::report::AllocationReport;
use rvtol_analysis::request::allocation::AllocationRequest;
use rvtol_analysis::request::memory;

use super::{
    html_page, outputs_ok, pool_for, problem_of_file, read, refused, scenario_inputs, stage_report,
    target, Destinations, Execution, CALLER,
};
use crate::limits::{parse_count, parse_seed};
use crate::output::{is_stdout, note, Format, StagedOutputs};
use crate::Failed;

/// The arguments of `rvtol allocate`.
#[derive(Debug, Args)]
pub struct AllocateArgs {
    /// Scenario file (JSON) with an `allocation` section.
    pub scenario: PathBuf,
    /// The output the target applies to.
    #[arg(long)]
    pub output: String,
    /// The target: `p99.865 <= 1.0`, `cpk >= 1.33`, `ppm_out <= 100`, `sd <= 0.01`,
    /// `mean <= x`, `cp >= 1.67`.
    #[arg(long, value_name = "EXPR", allow_hyphen_values = true)]
    pub target: String,
    /// Cost model to use where a source gives several: reciprocal, exponential, table.
    #[arg(long, value_name = "MODEL")]
    pub cost: Option<String>,
    /// Samples per Monte Carlo run (default: enough for about 100 samples in the
    /// targeted tail; at least 200,000).
    #[arg(long, value_parser = parse_count, allow_hyphen_values = true)]
    pub samples: Option<u64>,
    /// Seed of the optimisation runs (default: the scenario's `seed`, else 1).
    #[arg(long, value_parser = parse_seed, allow_hyphen_values = true)]
    pub seed: Option<u64>,
    /// Seed of the verification run (default: seed + 1).
    #[arg(long, value_parser = parse_seed, allow_hyphen_values = true)]
    pub verify_seed: Option<u64>,
    /// Estimate a ppm_out target by importance sampling around the out-of-spec event's
    /// most probable points instead of Monte Carlo runs (ppm targets down to 1 ppm and
    /// below; the verification an independent estimate of its own).
    #[arg(long)]
    pub rare: bool,
    /// With --rare: the 95 % interval's half width, as a share of the estimate, each
    /// importance-sampling sample is built for (default 0.1: ±10 %).
    #[arg(long, value_name = "SHARE", allow_hyphen_values = true)]
    pub precision: Option<f64>,
    /// With --rare: the points one importance-sampling sample may have (default
    /// 500,000).
    #[arg(long, value_name = "N", value_parser = parse_count, allow_hyphen_values = true)]
    pub max_evaluations: Option<u64>,
    /// Write the JSON report to PATH ("-" for stdout instead of the table).
    #[arg(long, value_name = "PATH")]
    pub json: Option<PathBuf>,
    /// Write an HTML report to PATH (.html, or "-" for stdout): one self-contained page
    /// with the plots.
    #[arg(long, value_name = "PATH")]
    pub html: Option<PathBuf>,
    /// Write the scenario with the proposed tolerances to PATH (only when the allocation
    /// is met).
    #[arg(long, value_name = "PATH")]
    pub write_scenario: Option<PathBuf>,
    #[command(flatten)]
    pub execution: Execution,
}

/// `rvtol allocate`: the allocation, its reports, and the proposal when it is met; exit 1
/// when no allocation meets the target.
pub fn allocate(args: AllocateArgs) -> Result<()> {
    let (path, execution) = (args.scenario.as_path(), &args.execution);
    let write_scenario = args.write_scenario.as_deref();
    let to = Destinations {
        json: args.json.as_deref(),
        html: args.html.as_deref(),
        samples: None,
    };
    outputs_ok(
        &to.targets(&[target("--write-scenario", write_scenario, Format::Json)]),
        &scenario_inputs(path),
    )?;
    let (scenario, text) = read(path)?;
    let request = AllocationRequest {
        target: &args.target,
        cost: args.cost.as_deref(),
        samples: args.samples,
        seed: args.seed,
        verify_seed: args.verify_seed,
        rare: args.rare,
        precision: args.precision,
        max_evaluations: args.max_evaluations,
    };
    let (target, settings) =
        (request.settings(&scenario, CALLER)).map_err(|refusal| refused(path, refusal))?;
    let pool = pool_for(execution, "allocate", |threads| {
        memory::allocation(&scenario, &settings, threads)
    })?;
    let spinner = if execution.quiet || !std::io::stderr().is_terminal() {
        ProgressBar::hidden()
    } else {
        let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr());
        bar.set_style(
            ProgressStyle::with_template(if settings.rare.is_some() {
                "{spinner} [{elapsed_precise}] allocating: {pos} importance-sampling estimates"
            } else {
                "{spinner} [{elapsed_precise}] allocating: {pos} Monte Carlo runs"
            })
            .expect("valid template"),
        );
        bar
    };
    let allocation = pool
        .install(|| {
            run_allocation(
                &scenario,
                &text.text,
                &args.output,
                target,
                settings,
                &|n| spinner.set_position(n as u64),
            )
        })
        .map_err(|err| problem_of_file(path, err))?;
    spinner.finish_and_clear();
    // Only a verified proposal becomes a scenario: a file that exists after a failed
    // allocation would pass for an answer.
    let met = allocation.status() == "met";
    // An allocation's verdict, met or not, is its result: its reports are written.
    let mut staged = StagedOutputs::new();
    if let Some(proposal) = write_scenario {
        if met {
            let document = proposal_document(&text.text, &allocation)
                .map_err(|err| problem_of_file(path, err))?;
            staged.add(proposal, &document)?;
        } else {
            note(&format!(
                "--write-scenario: nothing written to {}: the allocation is {}",
                proposal.display(),
                allocation.status()
            ));
        }
    }
    let report = AllocationReport::new(&allocation);
    let json = report.to_json();
    let stdout_taken = to.on_stdout() || (met && write_scenario.is_some_and(is_stdout));
    stage_report(
        &mut staged,
        to.json,
        stdout_taken,
        || json.clone(),
        || report.to_text(),
    )?;
    if let Some(html) = to.html {
        let page = html_page(html, path, &scenario, rvtol_report::Kind::Allocation, &json)?;
        staged.add(html, &page)?;
    }
    staged.commit()?;
    match allocation.status() {
        "met" => Ok(()),
        status => Err(Failed(format!("allocation {status}")).into()),
    }
}
