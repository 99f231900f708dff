//! `rvtol`: the command-line interface. Parses arguments (clap), calls the engine, prints
//! the report on stdout and writes report files ([`output`]). Progress goes to stderr, only
//! when it is a terminal and `--quiet` is not given; the one-line estimate of a long
//! command's wall time goes there always.
//!
//! Exit codes: 0 success; 1 a check or gate failed; 2 bad input, usage or an environment
//! that cannot serve the request (memory, an unwritable path). Every error is one line.

mod command;
mod limits;
mod output;
mod progress;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

use crate::command::{
    allocate::AllocateArgs, baseline::BaselineArgs, check::CheckArgs, curve::CurveArgs,
    evaluate::EvaluateArgs, fit::FitArgs, init::InitArgs, merge::MergeArgs, nominal::NominalArgs,
    rare::RareArgs, report::ReportArgs, run::RunArgs, sensitivity::SensitivityArgs,
    stack::StackArgs, sweep::SweepArgs, validate::ValidateArgs,
};

/// Monte Carlo tolerance and deviation statistics for RV reducers.
#[derive(Debug, Parser)]
#[command(name = "rvtol", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// The commands, each with its arguments (in its file under `command/`).
#[derive(Debug, Subcommand)]
enum Command {
    /// Run the Monte Carlo simulation of a scenario and report its output distributions.
    ///
    /// A run whose samples will take more than a minute says so in one line on stderr,
    /// estimated from the pace of its first chunks (with --quiet and outside a terminal
    /// too: a batch job learns it in its log).
    Run(RunArgs),
    /// Fold the partial results of a sharded run or sensitivity analysis (`run` or
    /// `sensitivity` with `--shard K/N --partial FILE`) into its report, byte for byte that
    /// of the command without --shard; a run's also into a baseline, or a check against one.
    Merge(MergeArgs),
    /// Evaluate every model with every deviation at its mean.
    Nominal(NominalArgs),
    /// Rank the error sources: Sobol' first-order and total indices with 95 % intervals (bootstrap, or from the replicates of an lhs or rqmc design).
    ///
    /// A sensitivity analysis whose samples will take more than a minute says so in one line on stderr,
    /// estimated from the pace of its first chunks (with --quiet and outside a terminal
    /// too: a batch job learns it in its log).
    Sensitivity(SensitivityArgs),
    /// Worst case, arithmetic and RSS stacks and the contributor table over the tolerance
    /// box (each input between its tolerance limits), beside the Monte Carlo run's
    /// P0.135, P99.865 and out-of-spec share.
    Stack(StackArgs),
    /// The probability of a rare event of an output (out of its spec limits, or beyond a
    /// threshold) down to 1 ppm and below: importance sampling around FORM's most
    /// probable points and subset simulation, each with its 95 % interval, and the
    /// sources' importance factors.
    Rare(RareArgs),
    /// One or two design values over a grid (`--set PATH=VALUES`): a whole run at each
    /// point with the same seed, and the outputs' figures with their intervals per point.
    Sweep(SweepArgs),
    /// Record the distribution figures of every output, with the band a re-run may move
    /// within, for `rvtol check`.
    ///
    /// A baseline whose samples will take more than a minute says so in one line on stderr,
    /// estimated from the pace of its first chunks (with --quiet and outside a terminal
    /// too: a batch job learns it in its log).
    Baseline(BaselineArgs),
    /// Re-run a scenario and compare it with a baseline: exit 1 when a figure moved.
    ///
    /// A check whose samples will take more than a minute says so in one line on stderr,
    /// estimated from the pace of its first chunks (with --quiet and outside a terminal
    /// too: a batch job learns it in its log).
    Check(CheckArgs),
    /// Print a complete, valid scenario for MODEL to start from: every parameter, every
    /// input bound to a placeholder variable with its unit (`rvtol models` lists them).
    Init(InitArgs),
    /// Check a scenario file without running it; one line per problem.
    Validate(ValidateArgs),
    /// Find the cheapest tolerances, within the scenario's `allocation` bounds, that meet a
    /// target on an output; verify them with an independent run (exit 1 when no
    /// allocation meets the target).
    Allocate(AllocateArgs),
    /// Write the curves of the scenario's models with every deviation at its mean (the
    /// transmission-error trace and its order spectrum, the torsion curve): a CSV and an
    /// SVG plot per curve.
    Curve(CurveArgs),
    /// Evaluate the scenario's models on given input rows (a designed experiment,
    /// measured assemblies, another sampler's design): a CSV with one column per input
    /// (the header of `run --samples-out`), the outputs per row as CSV.
    Evaluate(EvaluateArgs),
    /// Fit a normal model (mean, shrunk covariance) to measured parts, one row per part
    /// and one column per deviation component, with normality diagnostics: prints the
    /// scenario fragment (`variables` and `correlations`, or one part) to paste.
    Fit(FitArgs),
    /// Write one self-contained HTML page (plots, tables, the record to reproduce it)
    /// from JSON reports of `run`, `sensitivity`, `allocate`, `stack` and `sweep` of one scenario.
    Report(ReportArgs),
    /// List the models with their parameters, inputs and outputs.
    Models,
}

/// An error in the user's input or environment, reported as one line (exit code 2).
#[derive(Debug)]
pub struct BadInput(pub String);

impl std::fmt::Display for BadInput {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for BadInput {}

/// A check, gate or allocation that failed (exit code 1); its report is already printed.
#[derive(Debug)]
pub struct Failed(pub String);

impl std::fmt::Display for Failed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Failed {}

/// Each command with its arguments whole.
fn dispatch(cli: Cli) -> anyhow::Result<()> {
    use command::*;
    match cli.command {
        Command::Run(args) => run::run(args),
        Command::Merge(args) => merge::merge(args),
        Command::Nominal(args) => nominal::nominal(args),
        Command::Sensitivity(args) => sensitivity::sensitivity(args),
        Command::Stack(args) => stack::stack(args),
        Command::Rare(args) => rare::rare(args),
        Command::Sweep(args) => sweep::sweep(args),
        Command::Baseline(args) => baseline::baseline(args),
        Command::Check(args) => check::check(args),
        Command::Init(args) => init::init(args),
        Command::Validate(args) => validate::validate(args),
        Command::Allocate(args) => allocate::allocate(args),
        Command::Curve(args) => curve::curve(args),
        Command::Evaluate(args) => evaluate::evaluate(args),
        Command::Fit(args) => fit::fit(args),
        Command::Report(args) => report::report(args),
        Command::Models => models::models(),
    }
}

/// A clap error as one line: its message and where to read more.
fn usage_line(err: &clap::Error) -> String {
    let rendered = err.render().to_string();
    // The message is what comes before the usage block; some span several lines (a list
    // of missing arguments), which are joined.
    let message = rendered
        .lines()
        .take_while(|line| {
            !line.starts_with("Usage:")
                && !line.starts_with("  tip:")
                && !line.starts_with("For more information")
        })
        .map(str::trim)
        .filter(|line| !line.is_empty())
        .collect::<Vec<_>>()
        .join(" ");
    let message = message.strip_prefix("error: ").unwrap_or(&message);
    let subcommand = std::env::args_os()
        .nth(1)
        .map(|a| a.to_string_lossy().into_owned())
        .filter(|a| Cli::command_names().contains(&a.as_str()));
    let help = match subcommand {
        Some(name) => format!("rvtol {name} --help"),
        None => "rvtol --help".to_string(),
    };
    format!("error: {message} (see '{help}')")
}

impl Cli {
    fn command_names() -> Vec<&'static str> {
        vec![
            "run",
            "merge",
            "nominal",
            "sensitivity",
            "baseline",
            "check",
            "validate",
            "init",
            "allocate",
            "curve",
            "evaluate",
            "fit",
            "report",
            "models",
        ]
    }
}

/// What `rvtol` alone prints: a few lines, the commands and where their help is.
fn short_usage() -> String {
    format!(
        "usage: rvtol <COMMAND> [ARGUMENTS]\ncommands: {}\n'rvtol --help' says what each does, 'rvtol <COMMAND> --help' its options",
        Cli::command_names().join(", ")
    )
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(err) => {
            use clap::error::ErrorKind;
            return match err.kind() {
                // `rvtol` alone: the commands and where to read more, not the whole help.
                ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
                    if std::env::args_os().len() <= 1 =>
                {
                    output::note(&short_usage());
                    ExitCode::from(2)
                }
                ErrorKind::DisplayHelp
                | ErrorKind::DisplayVersion
                | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
                    let text = err.render().to_string();
                    if err.use_stderr() {
                        output::note(text.trim_end());
                        ExitCode::from(2)
                    } else {
                        match output::print(&text) {
                            Ok(()) => ExitCode::SUCCESS,
                            Err(err) => {
                                output::note(&format!("error: {err:#}"));
                                ExitCode::from(2)
                            }
                        }
                    }
                }
                _ => {
                    output::note(&usage_line(&err));
                    ExitCode::from(2)
                }
            };
        }
    };
    match dispatch(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            let line = format!("{err:#}").replace('\n', " ");
            output::note(&format!("error: {line}"));
            if err.downcast_ref::<Failed>().is_some() {
                ExitCode::from(1)
            } else {
                ExitCode::from(2)
            }
        }
    }
}
