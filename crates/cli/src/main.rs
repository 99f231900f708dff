//! `rvtol`: the command-line interface. Parses arguments (clap), calls the engine, prints
//! the report on stdout and writes report files ([`output`]). Progress goes to stderr, only
//! when it is a terminal and `--quiet` is not given; the one-line estimate of a long
//! command's wall time goes there always.
//!
//! Exit codes: 0 success; 1 a check or gate failed; 2 bad input, usage or an environment
//! that cannot serve the request (memory, an unwritable path). Every error is one line.

mod commands;
mod limits;
mod output;

use std::path::PathBuf;
use std::process::ExitCode;

use crate::commands::SensitivityArgs;
use clap::{Args, Parser, Subcommand};
use rvtol_deviation::SamplingMethod;
use rvtol_engine::DEFAULT_EXACT_PERCENTILE_LIMIT;

use crate::limits::{parse_count, parse_sampling, parse_seed, parse_share, parse_size};

/// `K/N` of `--shard`.
fn parse_shard_arg(text: &str) -> Result<(u64, u64), String> {
    rvtol_analysis::shard::parse_shard(text)
}

/// Monte Carlo tolerance and deviation statistics for RV reducers.
#[derive(Debug, Parser)]
#[command(name = "rvtol", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// Options every Monte Carlo command takes.
#[derive(Debug, Clone, Args)]
struct Execution {
    /// Worker threads (default: all cores; at most 4 per core). Results do not depend on it.
    #[arg(long, value_parser = parse_count, allow_hyphen_values = true)]
    threads: Option<u64>,
    /// Largest share (0 to 1) of samples whose model value may be non-finite (the model
    /// could not evaluate them) before the command fails; they are always counted and
    /// reported, and counted out of spec.
    #[arg(long, value_name = "SHARE", default_value_t = 0.0, value_parser = parse_share, allow_hyphen_values = true)]
    max_non_finite: f64,
    /// Memory the command may use (bytes, or with k, M, G, T: `4G`); default: the memory
    /// available on this machine. A request that needs more is refused before it starts.
    #[arg(long, value_name = "SIZE", value_parser = parse_size, allow_hyphen_values = true)]
    max_memory: Option<f64>,
    /// No progress display (a command whose samples will take more than a minute still
    /// says so in one line).
    #[arg(long, short)]
    quiet: bool,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run the Monte Carlo simulation of a scenario and report its output distributions.
    ///
    /// A run whose samples will take more than a minute says so in one line on stderr,
    /// estimated from the pace of its first chunks (with --quiet and outside a terminal
    /// too: a batch job learns it in its log).
    Run {
        /// Scenario file (JSON; "-" reads standard input).
        scenario: PathBuf,
        /// Number of samples, e.g. 1000000 or 1e6 (default: the scenario's `samples`, else
        /// 1,000,000).
        #[arg(long, value_parser = parse_count, allow_hyphen_values = true)]
        samples: Option<u64>,
        /// Seed of the random streams (default: the scenario's `seed`, else 1).
        #[arg(long, value_parser = parse_seed, allow_hyphen_values = true)]
        seed: Option<u64>,
        /// How rows are drawn: mc (independent draws), lhs (Latin hypercube) or rqmc
        /// (scrambled Sobol' points); default: the scenario's `sampling`, else mc.
        #[arg(long, value_name = "METHOD", value_parser = parse_sampling)]
        sampling: Option<SamplingMethod>,
        /// Independent randomizations of an lhs or rqmc run, whose spread gives the
        /// intervals (default: the scenario's `replicates`, else 16); the samples split
        /// evenly between them.
        #[arg(long, value_name = "R", value_parser = parse_count, allow_hyphen_values = true)]
        replicates: Option<u64>,
        /// Write the JSON report to PATH ("-" for stdout instead of the table).
        #[arg(long, value_name = "PATH")]
        json: Option<PathBuf>,
        /// Write an HTML report to PATH (.html, or "-" for stdout): one self-contained page
        /// with the plots.
        #[arg(long, value_name = "PATH")]
        html: Option<PathBuf>,
        /// Write every sample to PATH, one row per sample: its index, the drawn inputs and
        /// the outputs (the run's own values; same seed, same bytes); PATH ends in .csv or
        /// .parquet, which chooses the format ("-": CSV on stdout instead of the table).
        #[arg(long, value_name = "PATH")]
        samples_out: Option<PathBuf>,
        /// Exact percentiles while samples × continuous outputs stays at or below this many values;
        /// a bounded-memory sketch beyond it.
        #[arg(long, value_name = "VALUES", default_value_t = DEFAULT_EXACT_PERCENTILE_LIMIT, value_parser = parse_count, allow_hyphen_values = true)]
        exact_percentile_limit: u64,
        /// Compute only shard K of N (0 <= K < N, e.g. a job array's task index) and write
        /// its partial result to --partial instead of a report; `rvtol merge` folds the N
        /// partials into the run's report, byte for byte this command's without --shard.
        #[arg(long, value_name = "K/N", value_parser = parse_shard_arg, allow_hyphen_values = true, requires = "partial", conflicts_with_all = ["json", "html", "samples_out"])]
        shard: Option<(u64, u64)>,
        /// The shard's partial result file (with --shard).
        #[arg(long, value_name = "FILE", requires = "shard")]
        partial: Option<PathBuf>,
        #[command(flatten)]
        execution: Execution,
    },
    /// Fold the partial results of a sharded run or sensitivity analysis (`run` or
    /// `sensitivity` with `--shard K/N --partial FILE`) into its report, byte for byte that
    /// of the command without --shard; a run's also into a baseline, or a check against one.
    Merge {
        /// The shards' partial result files, in any order (a shard may appear twice when
        /// both files are identical, as after a rerun).
        #[arg(required = true)]
        partials: Vec<PathBuf>,
        /// Print the indices of the shards that have no file as a job-array list (`1,4-6`,
        /// the form of Slurm's --array) and exit; nothing when none is missing.
        #[arg(long, conflicts_with_all = ["json", "html", "baseline", "check"])]
        missing: bool,
        /// Write the JSON report to PATH ("-" for stdout instead of the table).
        #[arg(long, value_name = "PATH")]
        json: Option<PathBuf>,
        /// Write an HTML report to PATH (.html, or "-" for stdout): one self-contained page
        /// with the plots.
        #[arg(long, value_name = "PATH", conflicts_with_all = ["baseline", "check"])]
        html: Option<PathBuf>,
        /// Write the baseline of the merged run to FILE (what `rvtol baseline` writes for
        /// the same samples and seed) instead of the report.
        #[arg(long, value_name = "FILE", conflicts_with_all = ["check", "json"])]
        baseline: Option<PathBuf>,
        /// Compare the merged run with a baseline as `rvtol check` does (run the shards
        /// with the baseline's samples and exact-percentile limit): exit 1 when a figure
        /// moved.
        #[arg(long, value_name = "BASELINE")]
        check: Option<PathBuf>,
        /// With --check: write a JUnit XML report to PATH.
        #[arg(long, value_name = "PATH", requires = "check")]
        junit: Option<PathBuf>,
        /// With --check: fail a figure only when it gets worse (as `check --one-sided`).
        #[arg(long, requires = "check")]
        one_sided: bool,
        /// With --check: an absolute requirement (as `check --require`). Repeatable.
        #[arg(long = "require", value_name = "REQUIREMENT", requires = "check")]
        requirements: Vec<String>,
        #[command(flatten)]
        execution: Execution,
    },
    /// Evaluate every model with every deviation at its mean.
    Nominal {
        /// Scenario file (JSON; "-" reads standard input).
        scenario: PathBuf,
        /// Write the JSON report to PATH ("-" for stdout instead of the table).
        #[arg(long, value_name = "PATH")]
        json: Option<PathBuf>,
    },
    /// Rank the error sources: Sobol' first-order and total indices with 95 % intervals (bootstrap, or from the replicates of an lhs or rqmc design).
    ///
    /// A sensitivity analysis whose samples will take more than a minute says so in one line on stderr,
    /// estimated from the pace of its first chunks (with --quiet and outside a terminal
    /// too: a batch job learns it in its log).
    Sensitivity {
        /// Scenario file (JSON; "-" reads standard input).
        scenario: PathBuf,
        #[command(flatten)]
        options: SensitivityArgs,
        /// Compute only shard K of N (0 <= K < N) of the analysis' model evaluations (its
        /// share of the base samples and of the Shapley permutations) and write them to
        /// --partial instead of a report; `rvtol merge` folds the N partials into the
        /// report, byte for byte this command's without --shard.
        #[arg(long, value_name = "K/N", value_parser = parse_shard_arg, allow_hyphen_values = true, requires = "partial", conflicts_with_all = ["json", "html"])]
        shard: Option<(u64, u64)>,
        /// The shard's partial result file (with --shard).
        #[arg(long, value_name = "FILE", requires = "shard")]
        partial: Option<PathBuf>,
        /// Write the JSON report to PATH ("-" for stdout instead of the table).
        #[arg(long, value_name = "PATH")]
        json: Option<PathBuf>,
        /// Write an HTML report to PATH (.html, or "-" for stdout): one self-contained page
        /// with the plots.
        #[arg(long, value_name = "PATH")]
        html: Option<PathBuf>,
        #[command(flatten)]
        execution: Execution,
    },
    /// Record the distribution figures of every output, with the band a re-run may move
    /// within, for `rvtol check`.
    ///
    /// A baseline whose samples will take more than a minute says so in one line on stderr,
    /// estimated from the pace of its first chunks (with --quiet and outside a terminal
    /// too: a batch job learns it in its log).
    Baseline {
        /// Scenario file (JSON; "-" reads standard input).
        scenario: PathBuf,
        /// Baseline file to write.
        #[arg(short, long, value_name = "FILE")]
        output: PathBuf,
        /// Number of samples (default: the scenario's `samples`, else 1,000,000).
        #[arg(long, value_parser = parse_count, allow_hyphen_values = true)]
        samples: Option<u64>,
        /// Seed (default: the scenario's `seed`, else 1).
        #[arg(long, value_parser = parse_seed, allow_hyphen_values = true)]
        seed: Option<u64>,
        /// Exact percentiles while samples × continuous outputs stays at or below this many values;
        /// a bounded-memory sketch beyond it (recorded in the baseline for the check).
        #[arg(long, value_name = "VALUES", default_value_t = DEFAULT_EXACT_PERCENTILE_LIMIT, value_parser = parse_count, allow_hyphen_values = true)]
        exact_percentile_limit: u64,
        #[command(flatten)]
        execution: Execution,
    },
    /// Re-run a scenario and compare it with a baseline: exit 1 when a figure moved.
    ///
    /// A check whose samples will take more than a minute says so in one line on stderr,
    /// estimated from the pace of its first chunks (with --quiet and outside a terminal
    /// too: a batch job learns it in its log).
    Check {
        /// Scenario file (JSON; "-" reads standard input).
        scenario: PathBuf,
        /// Baseline file written by `rvtol baseline`.
        #[arg(long, value_name = "FILE")]
        baseline: PathBuf,
        /// Seed of the check run (default: the baseline's).
        #[arg(long, value_parser = parse_seed, allow_hyphen_values = true)]
        seed: Option<u64>,
        /// Write a JUnit XML report to PATH.
        #[arg(long, value_name = "PATH")]
        junit: Option<PathBuf>,
        /// Write the JSON report to PATH ("-" for stdout instead of the summary).
        #[arg(long, value_name = "PATH")]
        json: Option<PathBuf>,
        /// Fail a figure only when it gets worse beyond its band: higher for sd, ppm_out
        /// and indicator fractions, and for the mean and percentiles of an output with an
        /// upper spec limit only (lower for a lower limit only); a figure's `worse` in the
        /// baseline file overrides; the others stay two-sided.
        #[arg(long)]
        one_sided: bool,
        /// An absolute requirement, "[OUTPUT] FIGURE OP VALUE" (e.g. "p99.865 <= 1.5",
        /// "cpk >= 1.33", "ppm_out <= 2700"); fails only when the re-run's whole interval
        /// misses it. Repeatable; the baseline's `requirements` apply too.
        #[arg(long = "require", value_name = "REQUIREMENT")]
        requirements: Vec<String>,
        #[command(flatten)]
        execution: Execution,
    },
    /// Print a complete, valid scenario for MODEL to start from: every parameter, every
    /// input bound to a placeholder variable with its unit (`rvtol models` lists them).
    Init {
        /// Model name (`rvtol models`).
        model: String,
        /// A parameter of the design, KEY=VALUE (a number or a text), in place of the
        /// example's; the inputs follow (e.g. `--param pin_position_errors=1` gives the
        /// transmission error an input per pin). Repeatable.
        #[arg(long = "param", value_name = "KEY=VALUE")]
        params: Vec<String>,
        /// Write the scenario to PATH instead of standard output.
        #[arg(short = 'o', long = "output", value_name = "PATH")]
        output: Option<PathBuf>,
    },
    /// Check a scenario file without running it; one line per problem.
    Validate {
        /// Scenario file (JSON; "-" reads standard input).
        scenario: PathBuf,
    },
    /// Find the cheapest tolerances, within the scenario's `allocation` bounds, that meet a
    /// target on an output; verify them with an independent run (exit 1 when no
    /// allocation meets the target).
    Allocate {
        /// Scenario file (JSON) with an `allocation` section.
        scenario: PathBuf,
        /// The output the target applies to.
        #[arg(long)]
        output: String,
        /// The target: `p99.865 <= 1.0`, `cpk >= 1.33`, `ppm_out <= 100`, `sd <= 0.01`,
        /// `mean <= x`, `cp >= 1.67`.
        #[arg(long, value_name = "EXPR", allow_hyphen_values = true)]
        target: String,
        /// Cost model to use where a source gives several: reciprocal, exponential, table.
        #[arg(long, value_name = "MODEL")]
        cost: Option<String>,
        /// Samples per Monte Carlo run (default: enough for about 100 samples in the
        /// targeted tail; at least 200,000).
        #[arg(long, value_parser = parse_count, allow_hyphen_values = true)]
        samples: Option<u64>,
        /// Seed of the optimisation runs (default: the scenario's `seed`, else 1).
        #[arg(long, value_parser = parse_seed, allow_hyphen_values = true)]
        seed: Option<u64>,
        /// Seed of the verification run (default: seed + 1).
        #[arg(long, value_parser = parse_seed, allow_hyphen_values = true)]
        verify_seed: Option<u64>,
        /// Write the JSON report to PATH ("-" for stdout instead of the table).
        #[arg(long, value_name = "PATH")]
        json: Option<PathBuf>,
        /// Write an HTML report to PATH (.html, or "-" for stdout): one self-contained page
        /// with the plots.
        #[arg(long, value_name = "PATH")]
        html: Option<PathBuf>,
        /// Write the scenario with the proposed tolerances to PATH (only when the allocation
        /// is met).
        #[arg(long, value_name = "PATH")]
        write_scenario: Option<PathBuf>,
        #[command(flatten)]
        execution: Execution,
    },
    /// Write the curves of the scenario's models with every deviation at its mean (the
    /// transmission-error trace and its order spectrum, the torsion curve): a CSV and an
    /// SVG plot per curve.
    Curve {
        /// Scenario file (JSON; "-" reads standard input).
        scenario: PathBuf,
        /// Directory for the files (created when missing).
        #[arg(long, value_name = "DIR", default_value = ".")]
        out_dir: PathBuf,
    },
    /// Evaluate the scenario's models on given input rows (a designed experiment,
    /// measured assemblies, another sampler's design): a CSV with one column per input
    /// (the header of `run --samples-out`), the outputs per row as CSV.
    Evaluate {
        /// Scenario file (JSON; "-" reads standard input).
        scenario: PathBuf,
        /// Input rows: CSV with a header naming every input column (`rvtol run
        /// --samples-out` writes one; a `[unit]` after a name, a `sample` column and
        /// output columns are allowed).
        #[arg(long, value_name = "CSV")]
        inputs: PathBuf,
        /// Write the rows with their outputs to PATH instead of standard output (PATH ends
        /// in .csv or .parquet, which chooses the format).
        #[arg(short = 'o', long = "output", value_name = "PATH")]
        output: Option<PathBuf>,
        #[command(flatten)]
        execution: Execution,
    },
    /// Fit a normal model (mean, shrunk covariance) to measured parts, one row per part
    /// and one column per deviation component, with normality diagnostics: prints the
    /// scenario fragment (`variables` and `correlations`, or one part) to paste.
    Fit {
        /// Measurements: CSV with a header naming each column (`name` or `name [unit]`;
        /// a `sample` column, the row index of a samples file, is left out); "-" reads
        /// standard input.
        measurements: PathBuf,
        /// Fit one 6-DOF part of this name: the columns are its du, dv, dw, dalpha,
        /// dbeta, dgamma (or NAME.du …), in any order.
        #[arg(long, value_name = "NAME")]
        part: Option<String>,
        /// Write the fragment to PATH instead of standard output.
        #[arg(short = 'o', long = "output", value_name = "PATH")]
        output: Option<PathBuf>,
    },
    /// Write one self-contained HTML page (plots, tables, the record to reproduce it)
    /// from JSON reports of `run`, `sensitivity` and `allocate` of one scenario.
    Report {
        /// JSON reports (`--json` of run, sensitivity, allocate), at most one of each.
        #[arg(required = true)]
        reports: Vec<PathBuf>,
        /// The scenario file: adds its description and its models' nominal curves.
        #[arg(long, value_name = "FILE")]
        scenario: Option<PathBuf>,
        /// The HTML file to write.
        #[arg(short = 'o', long = "output", value_name = "PATH")]
        output: PathBuf,
    },
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

fn dispatch(cli: Cli) -> anyhow::Result<()> {
    use commands::*;
    match cli.command {
        Command::Run {
            scenario,
            samples,
            seed,
            sampling,
            replicates,
            json,
            html,
            samples_out,
            exact_percentile_limit,
            shard,
            partial,
            execution,
        } => {
            let request = rvtol_analysis::request::run::RunRequest {
                samples,
                seed,
                exact_percentile_limit,
                sampling,
                replicates,
            };
            match (shard, partial) {
                (Some(shard), Some(partial)) => {
                    run_shard(&scenario, request, shard, &partial, &execution)
                }
                _ => run(
                    &scenario,
                    request,
                    Destinations {
                        json: json.as_deref(),
                        html: html.as_deref(),
                        samples: samples_out.as_deref(),
                    },
                    &execution,
                ),
            }
        }
        Command::Merge {
            partials,
            missing,
            json,
            html,
            baseline,
            check,
            junit,
            one_sided,
            requirements,
            execution,
        } => merge(
            MergeArgs {
                partials,
                missing,
                baseline,
                check,
                junit,
                options: rvtol_analysis::gate::CheckOptions {
                    one_sided,
                    requirements,
                },
            },
            Destinations {
                json: json.as_deref(),
                html: html.as_deref(),
                samples: None,
            },
            &execution,
        ),
        Command::Nominal { scenario, json } => nominal(&scenario, json.as_deref()),
        Command::Curve { scenario, out_dir } => curve(&scenario, &out_dir),
        Command::Validate { scenario } => validate(&scenario),
        Command::Init {
            model,
            params,
            output,
        } => init(&model, &params, output.as_deref()),
        Command::Sensitivity {
            scenario,
            options,
            shard: Some(shard),
            partial: Some(partial),
            execution,
            ..
        } => sensitivity_shard(&scenario, options, shard, &partial, &execution),
        Command::Sensitivity {
            scenario,
            options,
            json,
            html,
            execution,
            ..
        } => sensitivity(
            &scenario,
            options,
            Destinations {
                json: json.as_deref(),
                html: html.as_deref(),
                samples: None,
            },
            &execution,
        ),
        Command::Baseline {
            scenario,
            output,
            samples,
            seed,
            exact_percentile_limit,
            execution,
        } => baseline(
            &scenario,
            &output,
            samples,
            seed,
            exact_percentile_limit,
            &execution,
        ),
        Command::Check {
            scenario,
            baseline,
            seed,
            junit,
            json,
            one_sided,
            requirements,
            execution,
        } => check(
            &scenario,
            &baseline,
            seed,
            junit.as_deref(),
            json.as_deref(),
            &rvtol_analysis::gate::CheckOptions {
                one_sided,
                requirements,
            },
            &execution,
        ),
        Command::Allocate {
            scenario,
            output,
            target,
            cost,
            samples,
            seed,
            verify_seed,
            json,
            html,
            write_scenario,
            execution,
        } => allocate(
            &scenario,
            AllocateArgs {
                output,
                target,
                cost,
                samples,
                seed,
                verify_seed,
            },
            Destinations {
                json: json.as_deref(),
                html: html.as_deref(),
                samples: None,
            },
            write_scenario.as_deref(),
            &execution,
        ),
        Command::Evaluate {
            scenario,
            inputs,
            output,
            execution,
        } => evaluate(&scenario, &inputs, output.as_deref(), &execution),
        Command::Fit {
            measurements,
            part,
            output,
        } => fit(&measurements, part.as_deref(), output.as_deref()),
        Command::Report {
            reports,
            scenario,
            output,
        } => report(&reports, scenario.as_deref(), &output),
        Command::Models => models(),
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
