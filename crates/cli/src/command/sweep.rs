//! `rvtol sweep`: one or two design values of a scenario over a grid (`--set
//! PATH=VALUES`), a whole run at each point with the same seed and samples, and the
//! chosen outputs' figures with their intervals per point (rvtol-analysis' `sweep`).

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use rvtol_analysis::request::memory;
use rvtol_analysis::request::run::RunRequest;
use rvtol_analysis::request::stack::continuous_outputs;
use rvtol_analysis::sweep::{axes, sweep as sweep_grid};

use super::{
    html_page, outputs_ok, pool_for, problem_of_file, read, refused, scenario_inputs,
    staged_report, Destinations, Execution, CALLER,
};
use crate::limits::{parse_count, parse_seed};
use crate::progress::Progress;
use crate::BadInput;

/// The arguments of `rvtol sweep`.
#[derive(Debug, Args)]
pub struct SweepArgs {
    /// Scenario file (JSON; "-" reads standard input).
    pub scenario: PathBuf,
    /// A design value and its values, PATH=V1,V2,... or PATH=START:STOP:COUNT (COUNT
    /// evenly spaced values, both ends included). PATH is reducer.params.KEY,
    /// models[I].params.KEY or models[I].inputs.NAME (an input bound to a number or to
    /// reducer.KEY). Once or twice (a grid, the first varying slowest).
    #[arg(long = "set", value_name = "PATH=VALUES", required = true)]
    pub set: Vec<String>,
    /// An output to report (repeat for more; default: every continuous output).
    #[arg(long = "output", value_name = "NAME")]
    pub outputs: Vec<String>,
    /// Samples of each point's run (default: the scenario's `samples`).
    #[arg(long, value_parser = parse_count, allow_hyphen_values = true)]
    pub samples: Option<u64>,
    /// Seed of every point's run (default: the scenario's `seed`): the points share their
    /// random rows, so they differ by the design values alone.
    #[arg(long, value_parser = parse_seed, allow_hyphen_values = true)]
    pub seed: Option<u64>,
    /// Write the JSON report to PATH ("-" for stdout instead of the tables).
    #[arg(long, value_name = "PATH")]
    pub json: Option<PathBuf>,
    /// Write an HTML report to PATH (.html, or "-" for stdout): the figures over the grid
    /// as plots and tables.
    #[arg(long, value_name = "PATH")]
    pub html: Option<PathBuf>,
    #[command(flatten)]
    pub execution: Execution,
}

/// `PATH=V1,V2,...` or `PATH=START:STOP:COUNT`.
fn parse_set(text: &str) -> Result<(String, Vec<f64>), String> {
    let (path, values) = text
        .split_once('=')
        .ok_or_else(|| format!("--set {text:?}: write PATH=V1,V2,... or PATH=START:STOP:COUNT"))?;
    let number = |v: &str| {
        v.trim()
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| format!("--set {path}: {v:?} is not a finite number"))
    };
    let parts: Vec<&str> = values.split(':').collect();
    let values = match parts.as_slice() {
        [start, stop, count] => {
            let (start, stop) = (number(start)?, number(stop)?);
            let count: usize =
                (count.trim().parse().ok())
                    .filter(|&n| n >= 2)
                    .ok_or_else(|| {
                        format!(
                        "--set {path}: the count {count:?} must be a whole number of at least 2"
                    )
                    })?;
            (0..count)
                .map(|i| start + (stop - start) * i as f64 / (count - 1) as f64)
                .collect()
        }
        [list] => list.split(',').map(number).collect::<Result<Vec<_>, _>>()?,
        _ => return Err(format!("--set {path}: write V1,V2,... or START:STOP:COUNT")),
    };
    Ok((path.trim().to_string(), values))
}

/// `rvtol sweep`.
pub fn sweep(args: SweepArgs) -> Result<()> {
    let (path, execution) = (args.scenario.as_path(), &args.execution);
    let to = Destinations {
        json: args.json.as_deref(),
        html: args.html.as_deref(),
        samples: None,
    };
    outputs_ok(&to.targets(&[]), &scenario_inputs(path))?;
    if args.set.len() > 2 {
        return Err(
            BadInput("--set: at most two design values (a grid of two axes)".into()).into(),
        );
    }
    let grid = (args.set.iter().map(|s| parse_set(s)))
        .collect::<Result<Vec<_>, _>>()
        .map_err(BadInput)?;
    let (scenario, text) = read(path)?;
    let axes = axes(&text.text, &grid).map_err(|message| BadInput(format!("--set: {message}")))?;
    let outputs = continuous_outputs(&scenario, &args.outputs, "a sweep", CALLER)
        .map_err(|r| refused(path, r))?;
    let request = RunRequest {
        samples: args.samples,
        seed: args.seed,
        ..RunRequest::default()
    };
    let settings = request
        .settings(&scenario, CALLER)
        .map_err(|r| refused(path, r))?;
    let pool = pool_for(execution, "sweep", |threads| {
        memory::run(&scenario, &settings, threads)
    })?;
    let points: u64 = axes.iter().map(|a| a.values.len() as u64).product();
    let bar = Progress::new(
        "sweep",
        settings.samples * points,
        execution.quiet,
        pool.current_num_threads(),
    );
    let report = pool
        .install(|| {
            sweep_grid(
                &scenario,
                &text.text,
                axes,
                &outputs,
                settings,
                execution.max_non_finite,
                &|n| bar.inc(n),
            )
        })
        .map_err(|err| problem_of_file(path, err))?;
    bar.finish_and_clear();
    let json = report.to_json();
    let mut staged = staged_report(&to, &json, || report.to_text())?;
    if let Some(html) = to.html {
        let page = html_page(html, path, &scenario, rvtol_report::Kind::Sweep, &json)?;
        staged.add(html, &page)?;
    }
    staged.commit()
}
