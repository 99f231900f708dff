//! `rvtol baseline`: every output's distribution figures with the band a re-run may move
//! within, written for `rvtol check`.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use rvtol_analysis::gate;
use rvtol_analysis::request::gate::BaselineRequest;
use rvtol_analysis::request::memory;
use rvtol_engine::DEFAULT_EXACT_PERCENTILE_LIMIT;

use super::{
    outputs_ok, pool_for, problem_of_file, read, refused, scenario_inputs, target, Execution,
    CALLER,
};
use crate::limits::{parse_count, parse_seed};
use crate::output::{is_stdout, print, write_report, Format};
use crate::progress::Progress;

/// The arguments of `rvtol baseline`.
#[derive(Debug, Args)]
pub struct BaselineArgs {
    /// Scenario file (JSON; "-" reads standard input).
    pub scenario: PathBuf,
    /// Baseline file to write.
    #[arg(short, long, value_name = "FILE")]
    pub output: PathBuf,
    /// Number of samples (default: the scenario's `samples`, else 1,000,000).
    #[arg(long, value_parser = parse_count, allow_hyphen_values = true)]
    pub samples: Option<u64>,
    /// Seed (default: the scenario's `seed`, else 1).
    #[arg(long, value_parser = parse_seed, allow_hyphen_values = true)]
    pub seed: Option<u64>,
    /// Exact percentiles while samples × continuous outputs stays at or below this many values;
    /// a bounded-memory sketch beyond it (recorded in the baseline for the check).
    #[arg(long, value_name = "VALUES", default_value_t = DEFAULT_EXACT_PERCENTILE_LIMIT, value_parser = parse_count, allow_hyphen_values = true)]
    pub exact_percentile_limit: u64,
    #[command(flatten)]
    pub execution: Execution,
}

/// `rvtol baseline`: the run and its baseline file.
pub fn baseline(args: BaselineArgs) -> Result<()> {
    let (path, output, execution) = (
        args.scenario.as_path(),
        args.output.as_path(),
        &args.execution,
    );
    outputs_ok(
        &[target("-o", Some(output), Format::Json)],
        &scenario_inputs(path),
    )?;
    let (scenario, text) = read(path)?;
    let request = BaselineRequest {
        samples: args.samples,
        seed: args.seed,
        exact_percentile_limit: args.exact_percentile_limit,
    };
    let settings =
        (request.settings(&scenario, CALLER)).map_err(|refusal| refused(path, refusal))?;
    let pool = pool_for(execution, "baseline", |threads| {
        memory::run(&scenario, &settings, threads)
    })?;
    let bar = Progress::new(
        "baseline",
        settings.samples,
        execution.quiet,
        pool.current_num_threads(),
    );
    let baseline = pool
        .install(|| {
            gate::baseline(
                &scenario,
                &text.text,
                settings,
                execution.max_non_finite,
                &|n| bar.inc(n),
            )
        })
        .map_err(|err| problem_of_file(path, err))?;
    bar.finish_and_clear();
    write_report(output, &baseline.to_json())?;
    if is_stdout(output) {
        return Ok(());
    }
    print(&format!(
        "{}: {} figures of {} ({} samples, seed {}) written to {}\n",
        path.display(),
        baseline.figures.len(),
        baseline.scenario,
        settings.samples,
        settings.seed,
        output.display()
    ))
}
