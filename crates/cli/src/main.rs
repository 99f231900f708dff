//! `rvtol`: the command-line interface. Parses arguments (clap), calls the engine, prints
//! the report on stdout and writes report files atomically. Progress goes to stderr, only
//! when it is a terminal and `--quiet` is not given.
//!
//! Exit codes: 0 success; 1 a check or gate failed; 2 bad input or usage.

mod plot;

use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rvtol_engine::allocation::report::AllocationReport;
use rvtol_engine::allocation::spec::{CostKind, Target};
use rvtol_engine::allocation::{allocate, default_samples, proposal_document, AllocationSettings};
use rvtol_engine::gate;
use rvtol_engine::screening::screening;
use rvtol_engine::sensitivity::{sobol_indices, SensitivitySettings};
use rvtol_engine::sensitivity_report::SensitivityReport;
use rvtol_engine::shapley::{players as shapley_players, shapley_effects, ShapleySettings};
use rvtol_engine::{
    nominal, nominal_curves, run, NominalReport, RunReport, RunSettings, Scenario, ScenarioError,
    DEFAULT_EXACT_PERCENTILE_LIMIT,
};

/// Monte Carlo tolerance and deviation statistics for RV reducers.
#[derive(Debug, Parser)]
#[command(name = "rvtol", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run the Monte Carlo simulation of a scenario and report its output distributions.
    Run {
        /// Scenario file (JSON).
        scenario: PathBuf,
        /// Number of samples (default: the scenario's `samples`, else 1,000,000).
        #[arg(long)]
        samples: Option<u64>,
        /// Seed of the random streams (default: the scenario's `seed`, else 1).
        #[arg(long)]
        seed: Option<u64>,
        /// Worker threads (default: all cores). Results do not depend on it.
        #[arg(long)]
        threads: Option<usize>,
        /// Write the JSON report to PATH ("-" for stdout instead of the table).
        #[arg(long, value_name = "PATH")]
        json: Option<PathBuf>,
        /// Exact percentiles while samples × outputs stays at or below this many values;
        /// a bounded-memory sketch beyond it.
        #[arg(long, value_name = "VALUES", default_value_t = DEFAULT_EXACT_PERCENTILE_LIMIT)]
        exact_percentile_limit: u64,
        /// No progress bar.
        #[arg(long, short)]
        quiet: bool,
    },
    /// Evaluate every model with every deviation at its mean.
    Nominal {
        /// Scenario file (JSON).
        scenario: PathBuf,
        /// Write the JSON report to PATH ("-" for stdout instead of the table).
        #[arg(long, value_name = "PATH")]
        json: Option<PathBuf>,
    },
    /// Rank the error sources: Sobol' first-order and total indices with bootstrap intervals.
    Sensitivity {
        /// Scenario file (JSON).
        scenario: PathBuf,
        /// Base samples N; the models are evaluated N·(2·groups + 2) times.
        #[arg(long, default_value_t = 65_536)]
        samples: u64,
        /// Seed of the random streams (default: the scenario's `seed`, else 1).
        #[arg(long)]
        seed: Option<u64>,
        /// Worker threads (default: all cores). Results do not depend on it.
        #[arg(long)]
        threads: Option<usize>,
        /// Bootstrap resamples for the 95 % intervals.
        #[arg(long, default_value_t = 500)]
        bootstrap: usize,
        /// Also estimate Shapley effects per source (exact for correlated inputs; needs
        /// parts without the Eq. 11 constraint).
        #[arg(long)]
        shapley: bool,
        /// Shapley: permutation budget (all orders when d! fits, repeated).
        #[arg(long, default_value_t = 600)]
        permutations: usize,
        /// Shapley: outer draws per conditional-variance estimate.
        #[arg(long, default_value_t = 256)]
        outer: usize,
        /// Write the JSON report to PATH ("-" for stdout instead of the table).
        #[arg(long, value_name = "PATH")]
        json: Option<PathBuf>,
        /// No progress bar.
        #[arg(long, short)]
        quiet: bool,
    },
    /// Record the distribution figures of every output, with the band a re-run may move
    /// within, for `rvtol check`.
    Baseline {
        /// Scenario file (JSON).
        scenario: PathBuf,
        /// Baseline file to write.
        #[arg(short, long, value_name = "FILE")]
        output: PathBuf,
        /// Number of samples (default: the scenario's `samples`, else 1,000,000).
        #[arg(long)]
        samples: Option<u64>,
        /// Seed (default: the scenario's `seed`, else 1).
        #[arg(long)]
        seed: Option<u64>,
        /// Worker threads (default: all cores). Results do not depend on it.
        #[arg(long)]
        threads: Option<usize>,
        /// No progress bar.
        #[arg(long, short)]
        quiet: bool,
    },
    /// Re-run a scenario and compare it with a baseline: exit 1 when a figure moved.
    Check {
        /// Scenario file (JSON).
        scenario: PathBuf,
        /// Baseline file written by `rvtol baseline`.
        #[arg(long, value_name = "FILE")]
        baseline: PathBuf,
        /// Seed of the check run (default: the baseline's).
        #[arg(long)]
        seed: Option<u64>,
        /// Write a JUnit XML report to PATH.
        #[arg(long, value_name = "PATH")]
        junit: Option<PathBuf>,
        /// Write the JSON report to PATH ("-" for stdout instead of the summary).
        #[arg(long, value_name = "PATH")]
        json: Option<PathBuf>,
        /// Worker threads (default: all cores). Results do not depend on it.
        #[arg(long)]
        threads: Option<usize>,
        /// No progress bar.
        #[arg(long, short)]
        quiet: bool,
    },
    /// Check a scenario file without running it.
    Validate {
        /// Scenario file (JSON).
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
        #[arg(long, value_name = "EXPR")]
        target: String,
        /// Cost model to use where a source gives several: reciprocal, exponential, table.
        #[arg(long, value_name = "MODEL")]
        cost: Option<String>,
        /// Samples per Monte Carlo run (default: enough for about 100 samples in the
        /// targeted tail; at least 200,000).
        #[arg(long)]
        samples: Option<u64>,
        /// Seed of the optimisation runs (default: the scenario's `seed`, else 1).
        #[arg(long)]
        seed: Option<u64>,
        /// Seed of the verification run (default: seed + 1).
        #[arg(long)]
        verify_seed: Option<u64>,
        /// Worker threads (default: all cores). Results do not depend on it.
        #[arg(long)]
        threads: Option<usize>,
        /// Write the JSON report to PATH ("-" for stdout instead of the table).
        #[arg(long, value_name = "PATH")]
        json: Option<PathBuf>,
        /// Write the scenario with the proposed tolerances to PATH.
        #[arg(long, value_name = "PATH")]
        write_scenario: Option<PathBuf>,
        /// No progress display.
        #[arg(long, short)]
        quiet: bool,
    },
    /// Write the curves of the scenario's models with every deviation at its mean (the
    /// transmission-error trace and its order spectrum, the torsion curve): a CSV and an
    /// SVG plot per curve.
    Curve {
        /// Scenario file (JSON).
        scenario: PathBuf,
        /// Directory for the files (created when missing).
        #[arg(long, value_name = "DIR", default_value = ".")]
        out_dir: PathBuf,
    },
    /// List the models with their parameters, inputs and outputs.
    Models,
}

/// An error in the user's input, reported as one line.
#[derive(Debug)]
struct BadInput(String);

impl std::fmt::Display for BadInput {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for BadInput {}

/// A check or gate that failed (exit code 1); its report is already printed.
#[derive(Debug)]
struct GateFailed;

impl std::fmt::Display for GateFailed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("figures moved beyond their baseline bands")
    }
}

impl std::error::Error for GateFailed {}

fn bad_scenario(path: &Path, err: ScenarioError) -> anyhow::Error {
    BadInput(format!("{}: {err}", path.display())).into()
}

fn load(path: &Path) -> Result<Scenario> {
    Scenario::load(path).map_err(|err| bad_scenario(path, err))
}

/// Writes `contents` to `path` through a temporary file in the same directory and a
/// rename, so an interrupted run never leaves a half-written report.
fn write_atomically(path: &Path, contents: &str) -> Result<()> {
    let directory = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let file_name = path
        .file_name()
        .with_context(|| format!("{} is not a file path", path.display()))?;
    let temporary = directory.join(format!(
        ".{}.tmp-{}",
        file_name.to_string_lossy(),
        std::process::id()
    ));
    let result = (|| -> std::io::Result<()> {
        let mut file = std::fs::File::create(&temporary)?;
        file.write_all(contents.as_bytes())?;
        file.sync_all()?;
        std::fs::rename(&temporary, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&temporary);
    }
    result.with_context(|| format!("cannot write {}", path.display()))
}

fn emit(
    json_path: Option<&Path>,
    json: impl FnOnce() -> String,
    text: impl FnOnce() -> String,
) -> Result<()> {
    let mut stdout = std::io::stdout().lock();
    match json_path {
        Some(p) if p == Path::new("-") => stdout.write_all(json().as_bytes())?,
        Some(p) => {
            write_atomically(p, &json())?;
            stdout.write_all(text().as_bytes())?;
        }
        None => stdout.write_all(text().as_bytes())?,
    }
    Ok(())
}

fn progress_bar(samples: u64, quiet: bool) -> ProgressBar {
    if quiet || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::with_draw_target(Some(samples), ProgressDrawTarget::stderr());
    bar.set_style(
        ProgressStyle::with_template("{spinner} [{elapsed_precise}] {bar:40} {percent:>3}% {human_pos}/{human_len} samples, eta {eta}")
            .expect("valid template"),
    );
    bar
}

/// A rayon pool of `threads` workers (all cores when absent).
fn thread_pool(threads: Option<usize>) -> Result<rayon::ThreadPool> {
    if threads == Some(0) {
        return Err(BadInput("--threads: must be at least 1".into()).into());
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .build()
        .context("cannot start the worker threads")
}

#[allow(clippy::too_many_arguments)]
fn command_run(
    scenario_path: &Path,
    samples: Option<u64>,
    seed: Option<u64>,
    threads: Option<usize>,
    json: Option<&Path>,
    exact_percentile_limit: u64,
    quiet: bool,
) -> Result<()> {
    let scenario = load(scenario_path)?;
    let samples = samples.unwrap_or(scenario.samples);
    if samples == 0 {
        return Err(BadInput("--samples: must be at least 1".into()).into());
    }
    let settings = RunSettings {
        samples,
        seed: seed.unwrap_or(scenario.seed),
        exact_percentile_limit,
    };
    let pool = thread_pool(threads)?;
    let bar = progress_bar(samples, quiet);
    let started = std::time::Instant::now();
    let result = pool
        .install(|| run(&scenario, settings, &|n| bar.inc(n)))
        .map_err(|err| bad_scenario(scenario_path, err))?;
    bar.finish_and_clear();
    let elapsed = started.elapsed();
    let report = RunReport::new(&scenario, result);
    emit(json, || report.to_json(), || report.to_text())?;
    if !quiet && std::io::stderr().is_terminal() {
        eprintln!(
            "{} samples in {:.2} s ({:.1} ns per sample)",
            samples,
            elapsed.as_secs_f64(),
            elapsed.as_secs_f64() * 1e9 / samples as f64
        );
    }
    Ok(())
}

fn command_curve(scenario_path: &Path, out_dir: &Path) -> Result<()> {
    let scenario = load(scenario_path)?;
    let drawn = nominal_curves(&scenario);
    if drawn.is_empty() {
        return Err(BadInput(format!(
            "{}: none of its models draws a curve (transmission_error and torsion_curve do)",
            scenario_path.display()
        ))
        .into());
    }
    std::fs::create_dir_all(out_dir)
        .with_context(|| format!("cannot create {}", out_dir.display()))?;
    let mut stdout = std::io::stdout().lock();
    for (model, curves) in drawn {
        for curve in curves {
            let stem = out_dir.join(&curve.name);
            let (csv, svg) = (stem.with_extension("csv"), stem.with_extension("svg"));
            write_atomically(&csv, &plot::to_csv(&curve))?;
            write_atomically(&svg, &plot::to_svg(&curve))?;
            writeln!(
                stdout,
                "{model}: {} -> {}, {}",
                curve.title,
                csv.display(),
                svg.display()
            )?;
        }
    }
    Ok(())
}

fn command_models() -> Result<()> {
    let mut out = String::new();
    for entry in rvtol_models::all() {
        out.push_str(&format!("{}\n  {}\n", entry.name, entry.summary));
        out.push_str("  parameters:\n");
        for p in entry.params {
            let default = p
                .default
                .map(|d| format!(" (default {d})"))
                .unwrap_or_default();
            out.push_str(&format!(
                "    {:<36} {:<6} {}{default}\n",
                p.name, p.unit, p.description
            ));
        }
        let model = (entry.build)(&(entry.example_params)())
            .map_err(|err| anyhow::anyhow!("example of {} does not build: {err}", entry.name))?;
        out.push_str("  inputs:\n");
        for i in model.inputs() {
            out.push_str(&format!(
                "    {:<36} {:<6} {}\n",
                i.name, i.unit, i.description
            ));
        }
        out.push_str("  outputs:\n");
        for o in model.outputs() {
            out.push_str(&format!(
                "    {:<36} {:<8} {}\n",
                o.name, o.unit, o.description
            ));
        }
        out.push('\n');
    }
    std::io::stdout().lock().write_all(out.as_bytes())?;
    Ok(())
}

fn dispatch(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Run {
            scenario,
            samples,
            seed,
            threads,
            json,
            exact_percentile_limit,
            quiet,
        } => command_run(
            &scenario,
            samples,
            seed,
            threads,
            json.as_deref(),
            exact_percentile_limit,
            quiet,
        ),
        Command::Nominal {
            scenario: path,
            json,
        } => {
            let scenario = load(&path)?;
            let report = NominalReport::new(&scenario, &nominal(&scenario));
            emit(json.as_deref(), || report.to_json(), || report.to_text())
        }
        Command::Curve { scenario, out_dir } => command_curve(&scenario, &out_dir),
        Command::Validate { scenario: path } => {
            let scenario = load(&path)?;
            println!(
                "{}: valid ({} input columns, {} models, {} outputs)",
                path.display(),
                scenario.input_space.n_columns(),
                scenario.models.len(),
                scenario.outputs.len()
            );
            Ok(())
        }
        Command::Sensitivity {
            scenario: path,
            samples,
            seed,
            threads,
            bootstrap,
            shapley,
            permutations,
            outer,
            json,
            quiet,
        } => {
            let scenario = load(&path)?;
            if samples < 2 {
                return Err(BadInput(
                    "--samples: sensitivity needs at least 2 base samples".into(),
                )
                .into());
            }
            if bootstrap < 2 {
                return Err(BadInput("--bootstrap: needs at least 2 resamples".into()).into());
            }
            let settings = SensitivitySettings {
                base_samples: samples,
                seed: seed.unwrap_or(scenario.seed),
                bootstrap,
                confidence: 0.95,
            };
            let pool = thread_pool(threads)?;
            let bar = progress_bar(samples, quiet);
            let outputs = pool
                .install(|| sobol_indices(&scenario, settings, &|n| bar.inc(n)))
                .map_err(|err| bad_scenario(&path, err))?;
            bar.finish_and_clear();
            let screening = pool
                .install(|| {
                    screening(
                        &scenario,
                        &shapley_players(&scenario),
                        samples.min(65_536),
                        settings.seed,
                    )
                })
                .map_err(|err| bad_scenario(&path, err))?;
            let mut report =
                SensitivityReport::new(&scenario, settings, outputs).with_screening(screening);
            if shapley {
                let effects = pool
                    .install(|| {
                        shapley_effects(
                            &scenario,
                            ShapleySettings {
                                permutations,
                                outer,
                                inner: 3,
                                seed: settings.seed,
                            },
                        )
                    })
                    .map_err(|err| bad_scenario(&path, err))?;
                report = report.with_shapley(effects);
            }
            emit(json.as_deref(), || report.to_json(), || report.to_text())
        }
        Command::Baseline {
            scenario: path,
            output,
            samples,
            seed,
            threads,
            quiet,
        } => {
            let (scenario, text) = Scenario::read(&path).map_err(|err| bad_scenario(&path, err))?;
            let samples = samples.unwrap_or(scenario.samples);
            if samples < 2 {
                return Err(
                    BadInput("--samples: a baseline needs at least 2 samples".into()).into(),
                );
            }
            let seed = seed.unwrap_or(scenario.seed);
            let pool = thread_pool(threads)?;
            let bar = progress_bar(samples, quiet);
            let baseline = pool
                .install(|| gate::baseline(&scenario, &text, samples, seed, &|n| bar.inc(n)))
                .map_err(|err| bad_scenario(&path, err))?;
            bar.finish_and_clear();
            write_atomically(&output, &baseline.to_json())?;
            println!(
                "{}: {} figures of {} ({} samples, seed {}) written to {}",
                path.display(),
                baseline.figures.len(),
                baseline.scenario,
                samples,
                seed,
                output.display()
            );
            Ok(())
        }
        Command::Check {
            scenario: path,
            baseline,
            seed,
            junit,
            json,
            threads,
            quiet,
        } => {
            let (scenario, text) = Scenario::read(&path).map_err(|err| bad_scenario(&path, err))?;
            let baseline_text = std::fs::read_to_string(&baseline)
                .map_err(|err| BadInput(format!("{}: cannot read: {err}", baseline.display())))?;
            let recorded = gate::Baseline::from_json(&baseline_text)
                .map_err(|err| bad_scenario(&baseline, err))?;
            let seed = seed.unwrap_or(recorded.seed);
            let pool = thread_pool(threads)?;
            let bar = progress_bar(recorded.samples, quiet);
            let report = pool
                .install(|| {
                    gate::check(&scenario, &text, &recorded, recorded.samples, seed, &|n| {
                        bar.inc(n)
                    })
                })
                .map_err(|err| bad_scenario(&path, err))?;
            bar.finish_and_clear();
            if let Some(junit) = &junit {
                write_atomically(junit, &report.to_junit())?;
            }
            emit(json.as_deref(), || report.to_json(), || report.to_text())?;
            if report.passed {
                Ok(())
            } else {
                Err(GateFailed.into())
            }
        }
        Command::Allocate {
            scenario: path,
            output,
            target,
            cost,
            samples,
            seed,
            verify_seed,
            threads,
            json,
            write_scenario,
            quiet,
        } => {
            let (scenario, text) = Scenario::read(&path).map_err(|err| bad_scenario(&path, err))?;
            let target =
                Target::parse(&target).map_err(|err| BadInput(format!("--target: {err}")))?;
            let cost = cost
                .map(|name| {
                    CostKind::parse(&name).ok_or_else(|| {
                        BadInput(format!(
                            "--cost: unknown cost model {name:?}; use reciprocal, exponential or table"
                        ))
                    })
                })
                .transpose()?;
            let seed = seed.unwrap_or(scenario.seed);
            let settings = AllocationSettings {
                samples: samples.unwrap_or_else(|| default_samples(&target)),
                seed,
                verification_seed: verify_seed.unwrap_or(seed.wrapping_add(1)),
                cost,
            };
            let pool = thread_pool(threads)?;
            let spinner = if quiet || !std::io::stderr().is_terminal() {
                ProgressBar::hidden()
            } else {
                let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr());
                bar.set_style(
                    ProgressStyle::with_template(
                        "{spinner} [{elapsed_precise}] allocating: {pos} Monte Carlo runs",
                    )
                    .expect("valid template"),
                );
                bar
            };
            let allocation = pool
                .install(|| {
                    allocate(&scenario, &text, &output, target, settings, &|n| {
                        spinner.set_position(n as u64)
                    })
                })
                .map_err(|err| bad_scenario(&path, err))?;
            spinner.finish_and_clear();
            if let Some(proposal) = &write_scenario {
                let document = proposal_document(&text, &allocation)
                    .map_err(|err| bad_scenario(&path, err))?;
                write_atomically(proposal, &document)?;
            }
            let report = AllocationReport::new(&allocation);
            emit(json.as_deref(), || report.to_json(), || report.to_text())?;
            if allocation.status() == "met" {
                Ok(())
            } else {
                Err(AllocationFailed(allocation.status()).into())
            }
        }
        Command::Models => command_models(),
    }
}

/// `rvtol allocate` found no verified allocation (exit code 1); its report is printed.
#[derive(Debug)]
struct AllocationFailed(&'static str);

impl std::fmt::Display for AllocationFailed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "allocation {}", self.0)
    }
}

impl std::error::Error for AllocationFailed {}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(err) => {
            let _ = err.print();
            return ExitCode::from(if err.use_stderr() { 2 } else { 0 });
        }
    };
    match dispatch(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("error: {err:#}");
            if err.downcast_ref::<GateFailed>().is_some()
                || err.downcast_ref::<AllocationFailed>().is_some()
            {
                ExitCode::from(1)
            } else {
                // Bad input or usage: a scenario, a baseline, a path.
                ExitCode::from(2)
            }
        }
    }
}
