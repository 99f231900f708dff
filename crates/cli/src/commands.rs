//! One function per command: read the scenario, check what the request needs against the
//! machine ([`crate::limits`]), call the engine, print or write the report
//! ([`crate::output`]). The engine computes; nothing here does statistics.

use std::collections::BTreeSet;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::OnceLock;

use anyhow::Result;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rvtol_analysis::allocation::report::AllocationReport;
use rvtol_analysis::allocation::{
    allocate as run_allocation, default_samples, proposal_document, AllocationSettings,
};
use rvtol_analysis::gate;
use rvtol_analysis::sensitivity::{
    sobol_indices, SensitivitySettings, DEFAULT_ROW_BOOTSTRAP_LIMIT,
};
use rvtol_analysis::sensitivity_report::SensitivityReport;
use rvtol_analysis::shapley::{shapley_effects, ShapleySettings};
use rvtol_analysis::target::Target;
use rvtol_deviation::SamplingMethod;
use rvtol_engine::chunk::Sampling;
use rvtol_engine::input_file::{self, ReadLimit};
use rvtol_engine::memory::{self, MemoryNeed};
use rvtol_engine::run::check_non_finite;
use rvtol_engine::scenario::allocation::CostKind;
use rvtol_engine::table::CsvTable;
use rvtol_engine::{
    nominal_curves, run as run_scenario, NominalReport, RunReport, RunSettings, Scenario,
    ScenarioError,
};

use crate::limits::{memory_budget, parse_count, parse_sampling, parse_seed, thread_pool, threads};
use crate::output::{
    check_targets, is_stdout, note, print, write_bytes, write_report, Format, Input, OutputFile,
    StagedOutputs,
};
use crate::{BadInput, Execution, Failed};

fn bad_scenario(path: &Path, err: ScenarioError) -> anyhow::Error {
    BadInput(format!("{}: {err}", shown(path))).into()
}

/// An input path as messages name it: `-` is standard input.
fn shown(path: &Path) -> String {
    if is_stdout(path) {
        "standard input".to_string()
    } else {
        path.display().to_string()
    }
}

/// The bound of a scenario, report or baseline read whole: a quarter of the memory this
/// process may take (a JSON document takes several times its bytes once parsed), worked out
/// once.
fn whole_file_limit() -> &'static ReadLimit {
    static LIMIT: OnceLock<ReadLimit> = OnceLock::new();
    LIMIT.get_or_init(|| {
        let threads = crate::limits::cores() as usize;
        let (budget, source) = memory_budget(None, threads);
        ReadLimit {
            bytes: (budget / 4.0) as u64,
            source: format!(
                "a quarter of the {} of memory ({source})",
                rvtol_deviation::human_bytes(budget)
            ),
        }
    })
}

/// A file's text (standard input's for `-`) of at most `limit.bytes`, or one line saying
/// why it cannot be read. Every file read whole is read through
/// [`rvtol_engine::input_file`].
fn read_text_within(path: &Path, limit: &ReadLimit) -> Result<String> {
    if is_stdout(path) {
        input_file::read_standard_input(limit)
    } else {
        input_file::read_text(path, limit)
    }
    .map_err(|message| BadInput(message).into())
}

/// A scenario's, report's or baseline's text (standard input's for `-`), within
/// [`whole_file_limit`].
fn read_text(path: &Path) -> Result<String> {
    read_text_within(path, whole_file_limit())
}

/// The name a scenario without `name` gets: its file stem (`scenario` from standard input).
fn fallback_name(path: &Path) -> String {
    path.file_stem()
        .filter(|_| !is_stdout(path))
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scenario".to_string())
}

/// The files a command on the scenario at `path` reads: the scenario and the data files it
/// refers to (none for standard input, which cannot be read twice).
fn scenario_inputs(path: &Path) -> Vec<(&'static str, PathBuf)> {
    if is_stdout(path) {
        return Vec::new();
    }
    let mut inputs = vec![("the scenario file", path.to_path_buf())];
    if let Ok(text) = input_file::read_text(path, whole_file_limit()) {
        let folder = rvtol_engine::scenario::scenario_folder(path);
        inputs.extend(
            rvtol_engine::scenario::data::data_files(&text, &folder)
                .into_iter()
                .map(|file| ("a data file of the scenario", file)),
        );
    }
    inputs
}

/// Refuses, before a command's work, outputs that cannot be written or would destroy an
/// input or each other ([`check_targets`]); `inputs` are what the command reads.
/// `targets` are the command's outputs, `None` those not asked for.
fn outputs_ok(targets: &[Option<OutputFile<'_>>], inputs: &[(&str, PathBuf)]) -> Result<()> {
    let targets: Vec<OutputFile<'_>> = targets.iter().flatten().copied().collect();
    let inputs: Vec<Input<'_>> = inputs
        .iter()
        .map(|(what, p)| (*what, p.as_path()))
        .collect();
    check_targets(&targets, &inputs).map_err(|err| BadInput(err.to_string()).into())
}

/// The target of a shard's `--partial` file.
fn partial_target(path: &Path) -> Option<OutputFile<'_>> {
    target("--partial", Some(path), Format::Binary)
}

/// The target of an optional output.
fn target<'a>(
    option: &'static str,
    path: Option<&'a Path>,
    format: Format,
) -> Option<OutputFile<'a>> {
    path.map(|path| OutputFile {
        option,
        path,
        format,
    })
}

/// A scenario file's text, with the numbers of the data files it refers to written in.
fn read_scenario_text(path: &Path) -> Result<String> {
    let text = read_text(path)?;
    let folder = rvtol_engine::scenario::scenario_folder(path);
    match rvtol_engine::scenario::data::inline_data_files(&text, &folder, whole_file_limit()) {
        Ok(inlined) => Ok(inlined.into_owned()),
        Err(err) => Err(bad_scenario(path, err)),
    }
}

fn read(path: &Path) -> Result<(Scenario, String)> {
    let text = read_scenario_text(path)?;
    let scenario =
        Scenario::from_json(&text, &fallback_name(path)).map_err(|err| bad_scenario(path, err))?;
    Ok((scenario, text))
}

fn load(path: &Path) -> Result<Scenario> {
    read(path).map(|(scenario, _)| scenario)
}

/// Writes the JSON to `json_path` when given (standard output for `-`) and prints the text
/// unless an output of the command (`stdout_taken`) goes to standard output.
fn emit(
    json_path: Option<&Path>,
    stdout_taken: bool,
    json: impl FnOnce() -> String,
    text: impl FnOnce() -> String,
) -> Result<()> {
    let mut staged = StagedOutputs::new();
    stage_report(&mut staged, json_path, stdout_taken, json, text)?;
    staged.commit()
}

/// [`emit`] into a command's staged outputs, replaced with the others at its end.
fn stage_report(
    staged: &mut StagedOutputs,
    json_path: Option<&Path>,
    stdout_taken: bool,
    json: impl FnOnce() -> String,
    text: impl FnOnce() -> String,
) -> Result<()> {
    if let Some(path) = json_path {
        staged.add(path, &json())?;
    }
    if !stdout_taken {
        staged.add_stdout(&text());
    }
    Ok(())
}

/// Estimated totals at or below this many seconds go unsaid; the environment variable
/// [`ESTIMATE_THRESHOLD_VARIABLE`] sets another (the tests set it low).
const ESTIMATE_THRESHOLD_SECONDS: f64 = 60.0;

/// The environment variable that sets the threshold of the wall-time estimate, in seconds
/// (not documented for users: for the tests).
const ESTIMATE_THRESHOLD_VARIABLE: &str = "RVTOL_ESTIMATE_THRESHOLD_SECONDS";

/// Seconds after which the estimate is made even when the first chunks of every worker
/// have not all finished.
const ESTIMATE_SETTLE_SECONDS: f64 = 5.0;

/// A duration as a person says it: `45 s`, `12 min`, `10 h 12 min`, `3 days 4 h`.
fn human_duration(seconds: f64) -> String {
    let seconds = seconds.max(0.0).round() as u64;
    let (days, hours, minutes) = (seconds / 86_400, seconds / 3_600 % 24, seconds / 60 % 60);
    if seconds < 90 {
        format!("{seconds} s")
    } else if seconds < 90 * 60 {
        format!("{} min", (seconds + 30) / 60)
    } else if days == 0 {
        format!("{} h {minutes} min", seconds / 3_600)
    } else {
        format!("{days} day{} {hours} h", if days == 1 { "" } else { "s" })
    }
}

/// The progress of a command's samples: a bar on a terminal (not with --quiet), and, on
/// any stderr and with --quiet too, one line estimating the wall time when it will be
/// long: made once, from the pace of the first chunks (one per worker, or what is done
/// after a few seconds), and said when the total exceeds a minute. A run outside a
/// terminal (a batch job) would otherwise run for hours without a word.
struct Progress {
    bar: ProgressBar,
    command: &'static str,
    started: std::time::Instant,
    total: u64,
    done: AtomicU64,
    estimated: AtomicBool,
    /// Samples done when the pace is read: the first chunk of every worker.
    settled: u64,
    threshold_seconds: f64,
}

impl Progress {
    fn new(command: &'static str, samples: u64, quiet: bool, threads: usize) -> Progress {
        let bar = if quiet || !std::io::stderr().is_terminal() {
            ProgressBar::hidden()
        } else {
            let bar = ProgressBar::with_draw_target(Some(samples), ProgressDrawTarget::stderr());
            bar.set_style(
                ProgressStyle::with_template("{spinner} [{elapsed_precise}] {bar:40} {percent:>3}% {human_pos}/{human_len} samples, eta {eta}")
                    .expect("valid template"),
            );
            bar
        };
        let threshold_seconds = std::env::var(ESTIMATE_THRESHOLD_VARIABLE)
            .ok()
            .and_then(|text| text.trim().parse::<f64>().ok())
            .filter(|seconds| seconds.is_finite())
            .unwrap_or(ESTIMATE_THRESHOLD_SECONDS);
        Progress {
            bar,
            command,
            started: std::time::Instant::now(),
            total: samples,
            done: AtomicU64::new(0),
            estimated: AtomicBool::new(false),
            settled: threads.max(1) as u64 * rvtol_engine::chunk::CHUNK_SIZE as u64,
            threshold_seconds,
        }
    }

    /// `samples` more are done.
    fn inc(&self, samples: u64) {
        self.bar.inc(samples);
        let done = self.done.fetch_add(samples, Ordering::Relaxed) + samples;
        if self.estimated.load(Ordering::Relaxed) {
            return;
        }
        let elapsed = self.started.elapsed().as_secs_f64();
        if done < self.settled && elapsed < ESTIMATE_SETTLE_SECONDS {
            return;
        }
        if self.estimated.swap(true, Ordering::Relaxed) || done >= self.total {
            return;
        }
        let total_seconds = elapsed * self.total as f64 / done as f64;
        if total_seconds > self.threshold_seconds {
            let line = format!(
                "{}: {} samples will take about {} at the pace of the first {}; fewer --samples take less",
                self.command,
                rvtol_engine::format::group_thousands(self.total),
                human_duration(total_seconds),
                rvtol_engine::format::group_thousands(done)
            );
            self.bar.suspend(|| note(&line));
        }
    }

    fn finish_and_clear(&self) {
        self.bar.finish_and_clear();
    }
}

/// Refuses a request whose memory need exceeds the budget, with one line.
/// `threads` is the command's worker-thread count (each reserves address space).
fn check_memory(
    need: MemoryNeed,
    execution: &Execution,
    command: &str,
    threads: usize,
) -> Result<()> {
    let (budget, source) = memory_budget(execution.max_memory, threads);
    need.check(budget, &source)
        .map_err(|message| BadInput(format!("{command}: {message}")).into())
}

/// The thread pool of a Monte Carlo command, once its memory need at that thread count
/// (`need`) fits the budget.
fn pool_for(
    execution: &Execution,
    command: &str,
    need: impl FnOnce(usize) -> MemoryNeed,
) -> Result<rayon::ThreadPool> {
    let threads = threads(execution.threads)?;
    check_memory(need(threads), execution, command, threads)?;
    thread_pool(threads)
}

/// The report first, then the failure of a run that lost more samples than allowed.
fn non_finite_failure(
    path: &Path,
    scenario: &Scenario,
    result: &rvtol_engine::RunResult,
    execution: &Execution,
) -> Result<()> {
    check_non_finite(scenario, result, execution.max_non_finite)
        .map_err(|err| bad_scenario(path, err))
}

/// Where the reports of a command go: `--json`, `--html` and (`run` only)
/// `--samples-out`.
#[derive(Clone, Copy, Default)]
pub struct Destinations<'a> {
    pub json: Option<&'a Path>,
    pub html: Option<&'a Path>,
    pub samples: Option<&'a Path>,
}

impl<'a> Destinations<'a> {
    /// `--json`, `--html` and `--samples-out` as targets, then `more`.
    fn targets(&self, more: &[Option<OutputFile<'a>>]) -> Vec<Option<OutputFile<'a>>> {
        [
            target("--json", self.json, Format::Json),
            target("--html", self.html, Format::Html),
            target("--samples-out", self.samples, Format::Table),
        ]
        .into_iter()
        .chain(more.iter().copied())
        .collect()
    }

    /// Whether one of them is standard output: the command's text then stays off it.
    fn on_stdout(&self) -> bool {
        [self.json, self.html, self.samples]
            .into_iter()
            .flatten()
            .any(is_stdout)
    }
}

/// The command line as typed (arguments with spaces or quotes quoted), for the page's
/// record.
fn command_line() -> String {
    // args_os: an argument that is not UTF-8 (a path) is shown lossily, not a panic.
    std::env::args_os()
        .enumerate()
        .map(|(i, a)| {
            let a = if i == 0 {
                "rvtol".to_string()
            } else {
                a.to_string_lossy().into_owned()
            };
            if a.is_empty() || a.contains([' ', '"', '\'', '<', '>', '|', '&']) {
                format!("'{}'", a.replace('\'', "'\\''"))
            } else {
                a
            }
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// The nominal curves of the scenario's models, for a page, and a note for each model whose
/// curves are left out because the model cannot draw them at the nominal point (a point
/// that is not finite): the page says so instead of failing, as the run's report counts
/// the samples the model could not evaluate.
fn page_curves(scenario: &Scenario) -> (Vec<(String, Vec<rvtol_models::Curve>)>, Vec<String>) {
    let mut curves = Vec::new();
    let mut left_out = Vec::new();
    for (model, drawn) in rvtol_engine::run::nominal_curves_per_model(scenario) {
        match drawn {
            Ok(drawn) => curves.push((model.to_string(), drawn)),
            Err(err) => left_out.push(format!("{err}; its curves are left out")),
        }
    }
    (curves, left_out)
}

/// The HTML page of one command's JSON report (`kind` says which) for `path`, with the
/// nominal curves of the scenario's models for a run.
fn html_page(
    path: &Path,
    scenario_path: &Path,
    scenario: &Scenario,
    kind: rvtol_report::Kind,
    json: &str,
) -> Result<String> {
    use rvtol_report::Kind;
    let value = parsed(json);
    let (curves, curves_left_out) = if kind == Kind::Run {
        page_curves(scenario)
    } else {
        (Vec::new(), Vec::new())
    };
    let record = rvtol_report::Record {
        scenario: scenario.name.clone(),
        description: Some(scenario.description.clone()).filter(|d| !d.is_empty()),
        source: Some(scenario_path.display().to_string()),
        command: Some(command_line()),
        version: env!("CARGO_PKG_VERSION").to_string(),
    };
    rvtol_report::render(&rvtol_report::Report {
        record,
        run: (kind == Kind::Run).then_some(&value),
        sensitivity: (kind == Kind::Sensitivity).then_some(&value),
        allocation: (kind == Kind::Allocation).then_some(&value),
        curves: &curves,
        curves_left_out: &curves_left_out,
    })
    .map_err(|err| BadInput(format!("{}: {err}", path.display())).into())
}

fn parsed(json: &str) -> serde_json::Value {
    serde_json::from_str(json).expect("the engine's JSON report parses")
}

/// A run's settings as the command line gives them (each unset one from the scenario).
pub struct RunChoice {
    /// `--samples`.
    pub samples: Option<u64>,
    /// `--seed`.
    pub seed: Option<u64>,
    /// `--exact-percentile-limit`.
    pub exact_percentile_limit: u64,
    /// `--sampling`.
    pub sampling: Option<SamplingMethod>,
    /// `--replicates`.
    pub replicates: Option<u64>,
}

/// A check's error about a value the command line gave (its `option` named when `given`),
/// else about the scenario file's value.
fn option_or_scenario_error(
    path: &Path,
    err: ScenarioError,
    options: &[(&str, &str, bool)],
) -> anyhow::Error {
    match options
        .iter()
        .find(|(key, _, given)| *given && err.path == *key)
    {
        Some((_, option, _)) => BadInput(format!("{option}: {}", err.message)).into(),
        None => bad_scenario(path, err),
    }
}

impl RunChoice {
    /// The error of [`RunSettings::check`], named after the option when the command line
    /// gave the value it is about.
    fn checked_error(&self, path: &Path, err: ScenarioError) -> anyhow::Error {
        option_or_scenario_error(
            path,
            err,
            &[
                ("samples", "--samples", self.samples.is_some()),
                ("sampling", "--sampling", self.sampling.is_some()),
                ("replicates", "--replicates", self.replicates.is_some()),
            ],
        )
    }

    /// The settings for `scenario`: what the command line says, else the scenario's
    /// ([`Sampling::chosen`]).
    pub fn settings(&self, scenario: &Scenario) -> RunSettings {
        RunSettings {
            samples: self.samples.unwrap_or(scenario.samples),
            seed: self.seed.unwrap_or(scenario.seed),
            exact_percentile_limit: self.exact_percentile_limit,
            sampling: Sampling::chosen(scenario.sampling, self.sampling, self.replicates),
        }
    }
}

pub fn run(
    scenario_path: &Path,
    choice: RunChoice,
    to: Destinations<'_>,
    execution: &Execution,
) -> Result<()> {
    outputs_ok(&to.targets(&[]), &scenario_inputs(scenario_path))?;
    let scenario = load(scenario_path)?;
    let settings = choice.settings(&scenario);
    settings
        .check(&scenario)
        .map_err(|err| choice.checked_error(scenario_path, err))?;
    if to.samples.is_some() {
        rvtol_engine::evaluate::check_table_rows(&scenario, settings.samples)
            .map_err(|message| BadInput(format!("--samples-out: {message}; run fewer samples")))?;
    }
    let pool = pool_for(execution, "run", |threads| {
        memory::run(&scenario, &settings, threads)
    })?;
    let bar = Progress::new(
        "run",
        settings.samples,
        execution.quiet,
        pool.current_num_threads(),
    );
    let started = std::time::Instant::now();
    let result = pool
        .install(|| run_scenario(&scenario, settings, &|n| bar.inc(n)))
        .map_err(|err| bad_scenario(scenario_path, err))?;
    bar.finish_and_clear();
    let elapsed = started.elapsed();
    let failure = non_finite_failure(scenario_path, &scenario, &result, execution);
    let report = pool.install(|| RunReport::new(&scenario, result));
    let json = report.to_json();
    let mut staged = StagedOutputs::new();
    stage_report(
        &mut staged,
        to.json,
        to.on_stdout(),
        || json.clone(),
        || report.to_text(),
    )?;
    if failure.is_err() {
        // The report shows what was lost; no file is replaced by a failed run.
        staged.print_only()?;
        return failure;
    }
    if let Some(path) = to.samples {
        let table = pool
            .install(|| rvtol_engine::sample_table(&scenario, settings))
            .map_err(|err| bad_scenario(scenario_path, err))?;
        staged.add_bytes(path, &sample_table_bytes(path, &scenario, &table)?)?;
    }
    if let Some(html) = to.html {
        let page = html_page(
            html,
            scenario_path,
            &scenario,
            rvtol_report::Kind::Run,
            &json,
        )?;
        staged.add(html, &page)?;
    }
    staged.commit()?;
    if !execution.quiet && std::io::stderr().is_terminal() {
        note(&format!(
            "{} samples in {:.2} s ({:.1} ns per sample)",
            settings.samples,
            elapsed.as_secs_f64(),
            elapsed.as_secs_f64() * 1e9 / settings.samples as f64
        ));
    }
    Ok(())
}

pub fn nominal(scenario_path: &Path, json: Option<&Path>) -> Result<()> {
    outputs_ok(
        &[target("--json", json, Format::Json)],
        &scenario_inputs(scenario_path),
    )?;
    let scenario = load(scenario_path)?;
    let values =
        rvtol_engine::nominal(&scenario).map_err(|err| bad_scenario(scenario_path, err))?;
    let report = NominalReport::new(&scenario, &values);
    emit(
        json,
        json.is_some_and(is_stdout),
        || report.to_json(),
        || report.to_text(),
    )
}

pub fn curve(scenario_path: &Path, out_dir: &Path) -> Result<()> {
    if is_stdout(out_dir) {
        return Err(BadInput(
            "--out-dir: a curve is two files (CSV and SVG): name a folder, not '-'".into(),
        )
        .into());
    }
    if std::fs::metadata(out_dir).is_ok_and(|m| !m.is_dir()) {
        return Err(BadInput(format!(
            "--out-dir: {} is a file: name a folder (it is created if missing)",
            out_dir.display()
        ))
        .into());
    }
    let scenario = load(scenario_path)?;
    let drawn = nominal_curves(&scenario).map_err(|err| bad_scenario(scenario_path, err))?;
    if drawn.is_empty() {
        return Err(BadInput(format!(
            "{}: none of its models draws a curve (transmission_error and torsion_curve do)",
            scenario_path.display()
        ))
        .into());
    }
    std::fs::create_dir_all(out_dir).map_err(|err| {
        BadInput(format!(
            "--out-dir: cannot create {}: {err}",
            out_dir.display()
        ))
    })?;
    let mut lines = String::new();
    let mut staged = StagedOutputs::new();
    for (model, curves) in drawn {
        for curve in curves {
            let stem = out_dir.join(&curve.name);
            let (csv, svg) = (stem.with_extension("csv"), stem.with_extension("svg"));
            let drawn = rvtol_report::curve_svg(&curve)
                .map_err(|err| BadInput(format!("{}: {err}", svg.display())))?;
            staged.add(&csv, &rvtol_report::curve_csv(&curve))?;
            staged.add(&svg, &drawn)?;
            lines.push_str(&format!(
                "{model}: {} -> {}, {}\n",
                curve.title,
                csv.display(),
                svg.display()
            ));
        }
    }
    staged.add_stdout(&lines);
    staged.commit()
}

pub fn init(model: &str, params: &[String], output: Option<&Path>) -> Result<()> {
    let mut given = serde_json::Map::new();
    for param in params {
        let Some((key, value)) = param.split_once('=') else {
            return Err(BadInput(format!("--param {param}: expected KEY=VALUE")).into());
        };
        let value = match value.trim().parse::<f64>() {
            Ok(x) if x.is_finite() => serde_json::json!(x),
            _ => serde_json::json!(value),
        };
        given.insert(key.trim().to_string(), value);
    }
    outputs_ok(&[target("-o", output, Format::Json)], &[])?;
    // The engine names a parameter by its scenario path; here it came from --param.
    let text = rvtol_engine::scenario::skeleton::skeleton_with(model, &given).map_err(|m| {
        BadInput(match m.strip_prefix("params.") {
            Some(rest) => format!("--param {rest}"),
            None => m,
        })
    })?;
    match output {
        Some(path) => write_report(path, &text),
        None => print(&text),
    }
}

pub fn validate(scenario_path: &Path) -> Result<()> {
    let text = read_scenario_text(scenario_path)?;
    match Scenario::from_json_all_problems(&text, &fallback_name(scenario_path)) {
        Ok(scenario) => {
            let count =
                |n: usize, noun: &str| format!("{n} {noun}{}", if n == 1 { "" } else { "s" });
            print(&format!(
                "{}: valid ({}, {}, {})\n",
                shown(scenario_path),
                count(scenario.input_space.n_columns(), "input column"),
                count(scenario.models.len(), "model"),
                count(scenario.outputs.len(), "output")
            ))
        }
        Err(problems) => {
            let count = problems.len();
            let mut lines: Vec<String> = problems
                .iter()
                .map(|err| format!("{}: {err}", shown(scenario_path)))
                .collect();
            let last = lines.pop().unwrap_or_default();
            for line in lines {
                note(&format!("error: {line}"));
            }
            Err(BadInput(if count > 1 {
                format!("{last} ({count} problems)")
            } else {
                last
            })
            .into())
        }
    }
}

/// The analysis options of `rvtol sensitivity` (its command line's, and what a merge reads
/// back from the shards).
#[derive(Debug, Clone, clap::Args)]
pub struct SensitivityArgs {
    /// Base samples N; the models are evaluated N·(2·groups + 2) times.
    #[arg(long, default_value_t = 65_536, value_parser = parse_count, allow_hyphen_values = true)]
    pub samples: u64,
    /// Seed of the random streams (default: the scenario's `seed`, else 1).
    #[arg(long, value_parser = parse_seed, allow_hyphen_values = true)]
    pub seed: Option<u64>,
    /// How the rows of A and B are drawn: mc (independent draws; bootstrap intervals),
    /// lhs or rqmc (replicates of a Latin hypercube or scrambled Sobol' design; intervals
    /// from their spread); default: the scenario's `sampling`, else mc.
    #[arg(long, value_name = "METHOD", value_parser = parse_sampling)]
    pub sampling: Option<SamplingMethod>,
    /// Independent randomizations of an lhs or rqmc design (default: the scenario's
    /// `replicates`, else 16); the base samples split evenly between them.
    #[arg(long, value_name = "R", value_parser = parse_count, allow_hyphen_values = true)]
    pub replicates: Option<u64>,
    /// Bootstrap resamples for the 95 % intervals of a Monte Carlo analysis (default 500).
    #[arg(long, value_parser = parse_count, allow_hyphen_values = true)]
    pub bootstrap: Option<u64>,
    /// Most model values kept for the row bootstrap; beyond, the intervals come from a
    /// bootstrap of blocks of rows (bounded memory).
    #[arg(long, value_name = "VALUES", default_value_t = DEFAULT_ROW_BOOTSTRAP_LIMIT, value_parser = parse_count, allow_hyphen_values = true)]
    pub row_bootstrap_limit: u64,
    /// Also estimate Shapley effects per source (exact for correlated inputs; needs
    /// parts without the Eq. 11 constraint).
    #[arg(long)]
    pub shapley: bool,
    /// Shapley: permutation budget (all orders when d! fits, repeated).
    #[arg(long, default_value_t = 600, value_parser = parse_count, allow_hyphen_values = true)]
    pub permutations: u64,
    /// Shapley: outer draws per conditional-variance estimate.
    #[arg(long, default_value_t = 256, value_parser = parse_count, allow_hyphen_values = true)]
    pub outer: u64,
}

/// Bootstrap resamples of a Monte Carlo sensitivity analysis unless the command line says.
const DEFAULT_BOOTSTRAP: u64 = 500;

/// Most Shapley permutations and outer draws: their product sets the model evaluations.
const MAX_SHAPLEY_DRAWS: u64 = 1_000_000_000;

pub fn sensitivity(
    path: &Path,
    args: SensitivityArgs,
    to: Destinations<'_>,
    execution: &Execution,
) -> Result<()> {
    outputs_ok(&to.targets(&[]), &scenario_inputs(path))?;
    let scenario = load(path)?;
    let settings = sensitivity_settings(path, &scenario, &args)?;
    let pool = pool_for(execution, "sensitivity", |threads| {
        rvtol_analysis::memory::sensitivity(&scenario, &settings, threads)
    })?;
    let bar = Progress::new(
        "sensitivity",
        args.samples,
        execution.quiet,
        pool.current_num_threads(),
    );
    let outputs = pool
        .install(|| sobol_indices(&scenario, settings, &|n| bar.inc(n)))
        .map_err(|err| bad_scenario(path, err))?;
    bar.finish_and_clear();
    let shapley = if args.shapley {
        Some(
            pool.install(|| shapley_effects(&scenario, shapley_settings(&args, settings.seed)))
                .map_err(|err| bad_scenario(path, err))?,
        )
    } else {
        None
    };
    finish_sensitivity(
        path, &scenario, settings, outputs, shapley, to, execution, &pool,
    )
}

/// The analysis' settings from the command line, checked.
fn sensitivity_settings(
    path: &Path,
    scenario: &Scenario,
    args: &SensitivityArgs,
) -> Result<SensitivitySettings> {
    if args.samples < 2 {
        return Err(BadInput("--samples: sensitivity needs at least 2 base samples".into()).into());
    }
    let sampling = Sampling::chosen(scenario.sampling, args.sampling, args.replicates);
    if sampling.is_replicated() && args.bootstrap.is_some() {
        return Err(BadInput(format!(
            "--bootstrap: the intervals of a replicated {} design come from its replicates, not a bootstrap; leave --bootstrap out, or give --sampling mc",
            sampling.method.name()
        ))
        .into());
    }
    // The base samples are the command line's (`--samples` or its default), never the
    // scenario's.
    sampling
        .check(args.samples, "base samples", &scenario.input_space)
        .map_err(|err| {
            option_or_scenario_error(
                path,
                err,
                &[
                    ("samples", "--samples", true),
                    ("sampling", "--sampling", args.sampling.is_some()),
                    ("replicates", "--replicates", args.replicates.is_some()),
                ],
            )
        })?;
    let bootstrap = args.bootstrap.unwrap_or(DEFAULT_BOOTSTRAP);
    if !(2..=1_000_000).contains(&bootstrap) {
        return Err(BadInput("--bootstrap: must be between 2 and 1000000 resamples".into()).into());
    }
    if args.shapley && args.permutations.saturating_mul(args.outer) > MAX_SHAPLEY_DRAWS {
        return Err(BadInput(format!(
            "--permutations × --outer: at most {MAX_SHAPLEY_DRAWS} conditional draws, got {} × {}",
            args.permutations, args.outer
        ))
        .into());
    }
    Ok(SensitivitySettings {
        base_samples: args.samples,
        seed: args.seed.unwrap_or(scenario.seed),
        bootstrap: bootstrap as usize,
        confidence: 0.95,
        row_bootstrap_limit: args.row_bootstrap_limit,
        sampling,
    })
}

fn shapley_settings(args: &SensitivityArgs, seed: u64) -> ShapleySettings {
    ShapleySettings {
        permutations: args.permutations as usize,
        outer: args.outer as usize,
        inner: 3,
        seed,
    }
}

/// The screening, the report and its files, and the check of the rows lost to non-finite
/// values: what `sensitivity` and the merge of its shards share.
#[allow(clippy::too_many_arguments)]
fn finish_sensitivity(
    path: &Path,
    scenario: &Scenario,
    settings: SensitivitySettings,
    outputs: Vec<rvtol_analysis::sensitivity::OutputSensitivity>,
    shapley: Option<Vec<(String, Vec<rvtol_analysis::shapley::ShapleyEffect>)>>,
    to: Destinations<'_>,
    execution: &Execution,
    pool: &rayon::ThreadPool,
) -> Result<()> {
    let report = pool
        .install(|| SensitivityReport::complete(scenario, settings, outputs, shapley))
        .map_err(|err| bad_scenario(path, err))?;
    let json = report.to_json();
    let mut staged = StagedOutputs::new();
    stage_report(
        &mut staged,
        to.json,
        to.on_stdout(),
        || json.clone(),
        || report.to_text(),
    )?;
    let lost: Vec<String> = report
        .outputs
        .iter()
        .filter(|o| {
            o.non_finite_rows as f64 > execution.max_non_finite * settings.base_samples as f64
        })
        .map(|o| format!("{} ({} rows)", o.name, o.non_finite_rows))
        .collect();
    if lost.is_empty() {
        if let Some(html) = to.html {
            let page = html_page(html, path, scenario, rvtol_report::Kind::Sensitivity, &json)?;
            staged.add(html, &page)?;
        }
        staged.commit()
    } else {
        // The report shows what was lost; no file is replaced by a failed analysis.
        staged.print_only()?;
        Err(BadInput(format!(
            "{}: rows with non-finite model values were left out of the indices of {}, more than the allowed share {} of the base samples; narrow the distributions to the models' domain, or accept a share with --max-non-finite",
            path.display(),
            lost.join(", "),
            execution.max_non_finite
        ))
        .into())
    }
}

/// `sensitivity --shard K/N --partial FILE`: the model values of shard K of N of the
/// matrices and, with `--shapley`, of its share of the permutations.
pub fn sensitivity_shard(
    path: &Path,
    args: SensitivityArgs,
    (shard, shards): (u64, u64),
    partial_path: &Path,
    execution: &Execution,
) -> Result<()> {
    outputs_ok(&[partial_target(partial_path)], &scenario_inputs(path))?;
    use rvtol_analysis::shard::{ShapleyShard, ShardCommand, ShardContent, ShardHeader};
    let (scenario, text) = read(path)?;
    let settings = sensitivity_settings(path, &scenario, &args)?;
    let build = build_identity()?;
    let pool = pool_for(execution, "sensitivity", |threads| {
        rvtol_analysis::memory::sensitivity(&scenario, &settings, threads)
    })?;
    let chunks = rvtol_engine::shard_range(settings.chunk_count(), shard, shards);
    let bar = Progress::new(
        "sensitivity",
        settings.samples_before_chunk(chunks.end) - settings.samples_before_chunk(chunks.start),
        execution.quiet,
        pool.current_num_threads(),
    );
    let sobol = pool
        .install(|| {
            rvtol_analysis::sensitivity::sobol_chunks(&scenario, settings, chunks.clone(), &|n| {
                bar.inc(n)
            })
        })
        .map_err(|err| bad_scenario(path, err))?;
    bar.finish_and_clear();
    let (shapley, shapley_shard) = if args.shapley {
        let shapley_settings = shapley_settings(&args, settings.seed);
        let total = rvtol_analysis::shapley::shapley_permutations(&scenario, shapley_settings)
            .map_err(|err| bad_scenario(path, err))?;
        let range = rvtol_engine::chunk::shard_range(total, shard, shards);
        let partial = pool
            .install(|| {
                rvtol_analysis::shapley::shapley_partial(&scenario, shapley_settings, range.clone())
            })
            .map_err(|err| bad_scenario(path, err))?;
        (
            Some(partial),
            Some(ShapleyShard {
                budget: args.permutations,
                outer: args.outer,
                permutations: total,
                range: [range.start, range.end],
            }),
        )
    } else {
        (None, None)
    };
    let header = ShardHeader {
        rvtol_version: env!("CARGO_PKG_VERSION").to_string(),
        build,
        scenario_fallback_name: fallback_name(path),
        scenario_file: text,
        command: ShardCommand::Sensitivity {
            samples: settings.base_samples,
            seed: settings.seed,
            bootstrap: settings.bootstrap as u64,
            row_bootstrap_limit: args.row_bootstrap_limit,
            sampling: settings.sampling.method.name().to_string(),
            replicates: settings.sampling.replicates,
            shapley: shapley_shard,
        },
        shard,
        shards,
        chunks: [chunks.start, chunks.end],
    };
    write_bytes(
        partial_path,
        &rvtol_analysis::shard::encode(&header, &ShardContent::Sensitivity { sobol, shapley }),
    )?;
    print(&format!(
        "{}: sensitivity shard {shard}/{shards} of {} ({} of {} base samples, seed {}) written to {}\n",
        path.display(),
        scenario.name,
        rvtol_engine::format::group_thousands(settings.samples_before_chunk(chunks.end) - settings.samples_before_chunk(chunks.start)),
        rvtol_engine::format::group_thousands(settings.base_samples),
        settings.seed,
        partial_path.display()
    ))
}

pub fn baseline(
    path: &Path,
    output: &Path,
    samples: Option<u64>,
    seed: Option<u64>,
    exact_percentile_limit: u64,
    execution: &Execution,
) -> Result<()> {
    outputs_ok(
        &[target("-o", Some(output), Format::Json)],
        &scenario_inputs(path),
    )?;
    let (scenario, text) = read(path)?;
    let settings = RunSettings {
        samples: samples.unwrap_or(scenario.samples),
        seed: seed.unwrap_or(scenario.seed),
        exact_percentile_limit,
        sampling: scenario.sampling,
    };
    if settings.samples < 2 {
        return Err(BadInput("--samples: a baseline needs at least 2 samples".into()).into());
    }
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
            gate::baseline(&scenario, &text, settings, execution.max_non_finite, &|n| {
                bar.inc(n)
            })
        })
        .map_err(|err| bad_scenario(path, err))?;
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

#[allow(clippy::too_many_arguments)]
pub fn check(
    path: &Path,
    baseline_path: &Path,
    seed: Option<u64>,
    junit: Option<&Path>,
    json: Option<&Path>,
    options: &gate::CheckOptions,
    execution: &Execution,
) -> Result<()> {
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
        .map_err(|err| bad_scenario(baseline_path, err))?;
    recorded
        .matches(&scenario)
        .map_err(|err| bad_scenario(baseline_path, err))?;
    for (i, text) in recorded.requirements.iter().enumerate() {
        gate::parse_requirement(&scenario, text).map_err(|err| {
            BadInput(format!(
                "{}: requirements[{i}]: {err}",
                baseline_path.display()
            ))
        })?;
    }
    for text in &options.requirements {
        gate::parse_requirement(&scenario, text)
            .map_err(|err| BadInput(format!("--require: {err}")))?;
    }
    let seed = seed.unwrap_or(recorded.seed);
    let settings = RunSettings {
        samples: recorded.samples,
        seed,
        exact_percentile_limit: recorded.exact_percentile_limit,
        sampling: scenario.sampling,
    };
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
                &text,
                &recorded,
                seed,
                execution.max_non_finite,
                options,
                &|n| bar.inc(n),
            )
        })
        .map_err(|err| bad_scenario(path, err))?;
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

/// The options of `rvtol allocate` beyond the common ones.
pub struct AllocateArgs {
    pub output: String,
    pub target: String,
    pub cost: Option<String>,
    pub samples: Option<u64>,
    pub seed: Option<u64>,
    pub verify_seed: Option<u64>,
}

pub fn allocate(
    path: &Path,
    args: AllocateArgs,
    to: Destinations<'_>,
    write_scenario: Option<&Path>,
    execution: &Execution,
) -> Result<()> {
    outputs_ok(
        &to.targets(&[target("--write-scenario", write_scenario, Format::Json)]),
        &scenario_inputs(path),
    )?;
    let (scenario, text) = read(path)?;
    let target = Target::parse(&args.target).map_err(|err| BadInput(format!("--target: {err}")))?;
    let cost = args
        .cost
        .map(|name| {
            CostKind::parse(&name).ok_or_else(|| {
                BadInput(format!(
                    "--cost: unknown cost model {name:?}; use reciprocal, exponential or table"
                ))
            })
        })
        .transpose()?;
    let seed = args.seed.unwrap_or(scenario.seed);
    let settings = AllocationSettings {
        samples: args.samples.unwrap_or_else(|| default_samples(&target)),
        seed,
        verification_seed: args.verify_seed.unwrap_or(seed.wrapping_add(1)),
        cost,
    };
    let pool = pool_for(execution, "allocate", |threads| {
        rvtol_analysis::memory::allocation(&scenario, settings.samples, threads)
    })?;
    let spinner = if execution.quiet || !std::io::stderr().is_terminal() {
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
            run_allocation(&scenario, &text, &args.output, target, settings, &|n| {
                spinner.set_position(n as u64)
            })
        })
        .map_err(|err| bad_scenario(path, err))?;
    spinner.finish_and_clear();
    // Only a verified proposal becomes a scenario: a file that exists after a failed
    // allocation would pass for an answer.
    let met = allocation.status() == "met";
    // An allocation's verdict, met or not, is its result: its reports are written.
    let mut staged = StagedOutputs::new();
    if let Some(proposal) = write_scenario {
        if met {
            let document =
                proposal_document(&text, &allocation).map_err(|err| bad_scenario(path, err))?;
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

pub fn models() -> Result<()> {
    let mut out = String::new();
    for entry in rvtol_models::all() {
        out.push_str(&format!("{}\n  {}\n", entry.name, entry.summary));
        out.push_str("  parameters:\n");
        for p in entry.params {
            let default = p
                .default
                .map(|d| format!(" (default {})", rvtol_deviation::Shown(d)))
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
    print(&out)
}

/// `rvtol report`: one page from saved JSON reports of one scenario, with its model curves
/// when the scenario file is given.
pub fn report(
    files: &[std::path::PathBuf],
    scenario_path: Option<&Path>,
    output: &Path,
) -> Result<()> {
    use rvtol_report::{kind_of, Kind};
    let mut inputs: Vec<(&str, PathBuf)> = files
        .iter()
        .map(|f| ("a report it composes", f.clone()))
        .collect();
    if let Some(path) = scenario_path {
        inputs.extend(scenario_inputs(path));
    }
    outputs_ok(&[target("-o", Some(output), Format::Html)], &inputs)?;
    let on_stdin = files.iter().filter(|f| is_stdout(f)).count()
        + scenario_path.is_some_and(is_stdout) as usize;
    if on_stdin > 1 {
        return Err(BadInput(
            "standard input ('-') can be read once: give at most one of the reports and the scenario as '-', the others as files".into(),
        )
        .into());
    }
    let scenario_of = |v: &serde_json::Value| v["scenario"].as_str().unwrap_or("").to_string();
    let mut found: Vec<(Kind, serde_json::Value, &Path)> = Vec::new();
    for file in files {
        let text = read_text(file)?;
        let value: serde_json::Value = serde_json::from_str(&text)
            .map_err(|err| BadInput(format!("{}: not JSON: {err}", file.display())))?;
        let kind = kind_of(&value).ok_or_else(|| {
            BadInput(format!(
                "{}: not a JSON report of `rvtol run`, `sensitivity` or `allocate`",
                file.display()
            ))
        })?;
        if let Some((_, first, first_file)) = found.first() {
            let (this, that) = (scenario_of(&value), scenario_of(first));
            if this != that {
                return Err(BadInput(format!(
                    "{}: a report of scenario '{this}', but {} is of '{that}'; one page shows one scenario",
                    file.display(),
                    first_file.display()
                ))
                .into());
            }
        }
        if let Some((_, _, first)) = found.iter().find(|(k, _, _)| *k == kind) {
            return Err(BadInput(format!(
                "{}: a second {} report (the first is {}); one page shows one of each",
                file.display(),
                kind.command(),
                first.display()
            ))
            .into());
        }
        found.push((kind, value, file));
    }
    let name = found
        .first()
        .map(|(_, v, _)| scenario_of(v))
        .ok_or_else(|| BadInput("no report given".into()))?;
    let mut description = None;
    let mut curves = Vec::new();
    let mut curves_left_out = Vec::new();
    if let Some(path) = scenario_path {
        let scenario = load(path)?;
        if scenario.name != name {
            return Err(BadInput(format!(
                "{}: scenario '{}', but the reports are of '{name}'",
                path.display(),
                scenario.name
            ))
            .into());
        }
        description = Some(scenario.description.clone()).filter(|d| !d.is_empty());
        (curves, curves_left_out) = page_curves(&scenario);
    }
    let get = |kind: Kind| found.iter().find(|(k, _, _)| *k == kind).map(|(_, v, _)| v);
    let record = rvtol_report::Record {
        scenario: name.clone(),
        description,
        source: scenario_path.map(|p| p.display().to_string()),
        command: Some(command_line()),
        version: env!("CARGO_PKG_VERSION").to_string(),
    };
    let page = rvtol_report::render(&rvtol_report::Report {
        record,
        run: get(Kind::Run),
        sensitivity: get(Kind::Sensitivity),
        allocation: get(Kind::Allocation),
        curves: &curves,
        curves_left_out: &curves_left_out,
    })
    .map_err(|err| BadInput(format!("{}: {err}", output.display())))?;
    write_report(output, &page)?;
    if is_stdout(output) {
        return Ok(());
    }
    let kinds: Vec<&str> = found.iter().map(|(k, _, _)| k.command()).collect();
    print(&format!(
        "{}: report of {} ({})\n",
        output.display(),
        name,
        kinds.join(", ")
    ))
}

/// Reads a CSV table of numbers (the engine's [`CsvTable`]) of at most `limit.bytes`; its
/// error is one line. `option` names where the file was given (`--inputs`,
/// `MEASUREMENTS`) when it is no CSV text: a Parquet file (`run --samples-out` writes
/// those too) or other binary data.
fn read_csv<'a>(path: &'a Path, limit: &ReadLimit, option: &str) -> Result<CsvTable<'a>> {
    let bytes = if is_stdout(path) {
        input_file::read_standard_input_bytes(limit)
    } else {
        input_file::read_bytes(path, limit)
    }
    .map_err(BadInput)?;
    let text = String::from_utf8(bytes).map_err(|err| {
        BadInput(if err.as_bytes().starts_with(b"PAR1") {
            format!(
                "{option}: {} is a Parquet file; rows are read from CSV only (`rvtol run --samples-out FILE.csv` writes them as CSV)",
                shown(path)
            )
        } else {
            format!(
                "{option}: {} is not a CSV file (its bytes are not UTF-8 text)",
                shown(path)
            )
        })
    })?;
    let name = if is_stdout(path) {
        Path::new("standard input")
    } else {
        path
    };
    CsvTable::parse(name, &text).map_err(|message| BadInput(message).into())
}

/// `rvtol evaluate`: the models on the rows of a CSV.
pub fn evaluate(
    scenario_path: &Path,
    inputs_path: &Path,
    output: Option<&Path>,
    execution: &Execution,
) -> Result<()> {
    if is_stdout(scenario_path) && is_stdout(inputs_path) {
        return Err(BadInput(
            "--inputs: standard input ('-') already gives the scenario: name the rows' file".into(),
        )
        .into());
    }
    let mut inputs = scenario_inputs(scenario_path);
    inputs.push(("the input rows", inputs_path.to_path_buf()));
    outputs_ok(&[target("-o", output, Format::Table)], &inputs)?;
    let scenario = load(scenario_path)?;
    // What evaluating the rows takes, from the file's size before it is read; a pipe or
    // standard input is cut where the rows would exceed the memory.
    let threads = threads(execution.threads)?;
    if let Some(metadata) = std::fs::metadata(inputs_path)
        .ok()
        .filter(|_| !is_stdout(inputs_path))
    {
        if metadata.is_file() {
            let need = memory::table_evaluation(
                &scenario,
                metadata.len(),
                &inputs_path.display().to_string(),
            );
            check_memory(need, execution, "evaluate", threads)?;
        }
    }
    let (budget, budget_source) = memory_budget(execution.max_memory, threads);
    let rows_limit = ReadLimit {
        bytes: ((budget - memory::BASE_BYTES).max(0.0)
            / memory::table_evaluation_factor(&scenario)) as u64,
        source: format!(
            "what the {} of memory available ({budget_source}) allows for rows read, evaluated and written out; split the rows into smaller files",
            rvtol_deviation::human_bytes(budget)
        ),
    };
    let table = read_csv(inputs_path, &rows_limit, "--inputs")?;
    let names = table.names();
    let known_other =
        |name: &str| name == SAMPLE_INDEX || scenario.outputs.iter().any(|o| o.name == name);
    // Where each input column is in the file.
    let mut position = Vec::with_capacity(scenario.columns.len());
    let mut missing = Vec::new();
    for column in &scenario.columns {
        match names.iter().position(|n| *n == column.name) {
            Some(i) => position.push(i),
            None => missing.push(column.name.clone()),
        }
    }
    if !missing.is_empty() {
        return Err(BadInput(format!(
            "{}: no column for the input{} {} (the header names every input column of the scenario, as `rvtol run --samples-out` writes it)",
            table.at(1),
            if missing.len() > 1 { "s" } else { "" },
            missing.join(", ")
        ))
        .into());
    }
    if let Some(unknown) = names
        .iter()
        .find(|n| !known_other(n) && !scenario.columns.iter().any(|c| c.name == **n))
    {
        return Err(BadInput(format!(
            "{}: column '{unknown}' is neither an input nor an output of the scenario",
            table.at(1)
        ))
        .into());
    }
    let n_inputs = scenario.columns.len();
    rvtol_engine::evaluate::check_table_rows(&scenario, table.rows.len() as u64).map_err(
        |message| {
            BadInput(format!(
                "{}: {message}; split the file",
                inputs_path.display()
            ))
        },
    )?;
    // A heading's unit is the column's: converted into the scenario's unit of that input
    // (µm into mm), refused when it cannot be (another kind, or a unit rvtol does not know).
    let mut factor = Vec::with_capacity(position.len());
    for (column, &i) in scenario.columns.iter().zip(&position) {
        factor.push(match (&table.columns[i].1, &column.unit) {
            (Some(given), Some(wanted)) if given != wanted => {
                rvtol_engine::scenario::units::conversion(given, wanted).ok_or_else(|| {
                    BadInput(format!(
                        "{}: column '{} [{given}]' is in {given}, but the input is in {wanted} and {given} does not convert to it (units rvtol knows: {})",
                        table.at(1),
                        column.name,
                        rvtol_engine::scenario::units::known()
                    ))
                })?
            }
            _ => 1.0,
        });
    }
    let mut values = Vec::with_capacity(table.rows.len() * n_inputs);
    for (line, record) in &table.rows {
        for (&i, &f) in position.iter().zip(&factor) {
            let value = table.number(*line, record, i).map_err(BadInput)?;
            values.push(if f == 1.0 { value } else { value * f });
        }
    }
    if values.is_empty() {
        return Err(BadInput(format!("{}: no rows", inputs_path.display())).into());
    }
    let pool = thread_pool(threads)?;
    let rows = pool.install(|| rvtol_engine::evaluate::evaluate_rows(&scenario, values));
    // Rows the models could not evaluate are lost data, as a run's samples: counted and
    // reported, and beyond --max-non-finite a failure that writes no table.
    let row = |r: usize| table.at(table.rows[r].0);
    rvtol_engine::evaluate::check_non_finite_rows(&scenario, &rows, execution.max_non_finite, &row)
        .map_err(|err| bad_scenario(scenario_path, err))?;
    let lost = rvtol_engine::evaluate::non_finite_rows(&scenario, &rows);
    for (o, line) in rvtol_engine::evaluate::non_finite_lines(&scenario, &rows, &lost, &row) {
        note(&format!(
            "warning: {}: {line}, within the allowed {} % (--max-non-finite): written as NaN",
            scenario.model_of_output(o),
            rvtol_deviation::Shown(100.0 * execution.max_non_finite)
        ));
    }
    match output {
        Some(path) => write_bytes(path, &sample_table_bytes(path, &scenario, &rows)?),
        None => print(&rvtol_engine::report::sample_csv(&scenario, &rows)),
    }
}

/// A sample table as the file `path` takes it: Parquet when its name ends in `.parquet`,
/// else CSV.
fn sample_table_bytes(
    path: &Path,
    scenario: &Scenario,
    table: &rvtol_engine::SampleTable,
) -> Result<Vec<u8>> {
    let parquet = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("parquet"));
    if parquet {
        rvtol_engine::report::sample_parquet(scenario, table)
            .map_err(|err| BadInput(format!("{}: {err}", path.display())).into())
    } else {
        Ok(rvtol_engine::report::sample_csv(scenario, table).into_bytes())
    }
}

/// The row index column of `run --samples-out` and `evaluate`: not a measurement, `fit`
/// and `evaluate` leave it out.
const SAMPLE_INDEX: &str = "sample";

/// `rvtol fit`: a normal model of measured parts, as a scenario fragment.
pub fn fit(path: &Path, part: Option<&str>, output: Option<&Path>) -> Result<()> {
    use rvtol_analysis::fit::{check_fragment, fit as fit_normal, fragment, PART_COMPONENTS};
    // Diagnostics go to standard error once the fragment is written: a refused fit says
    // only why.
    let mut notes: Vec<String> = Vec::new();
    outputs_ok(
        &[target("-o", output, Format::Json)],
        &[("the measurements", path.to_path_buf())],
    )?;
    let table = read_csv(path, whole_file_limit(), "MEASUREMENTS")?;
    let names = table.names();
    // A part's columns in its component order.
    let order: Vec<usize> = match part {
        Some(name) => {
            if name.is_empty()
                || !name
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
            {
                return Err(BadInput(format!(
                    "--part: '{name}' is not a part name (letters, digits, _ and -)"
                ))
                .into());
            }
            let prefix = format!("{name}.");
            let component = |n: &str| n.strip_prefix(&prefix).unwrap_or(n).to_string();
            // A file with columns `NAME.du` … (several parts, a sample file, an export
            // with serial numbers) gives the part those six; a file of bare `du` … must
            // hold nothing else.
            let qualified = names.iter().any(|n| n.starts_with(&prefix));
            let ignored: Vec<&str> = names
                .iter()
                .filter(|n| (qualified && !n.starts_with(&prefix)) || **n == SAMPLE_INDEX)
                .copied()
                .collect();
            if !ignored.is_empty() {
                let shown = if ignored.len() > 6 {
                    format!("{}, … ({} in all)", ignored[..5].join(", "), ignored.len())
                } else {
                    ignored.join(", ")
                };
                notes.push(format!(
                    "{}: fitting {name}.du … {name}.dgamma; other columns left out: {shown}",
                    path.display(),
                ));
            }
            // Columns of other parts but none of this one: most likely a misspelt name.
            let parts: BTreeSet<&str> = names
                .iter()
                .filter_map(|n| n.split_once('.'))
                .filter(|(_, c)| PART_COMPONENTS.contains(c))
                .map(|(p, _)| p)
                .collect();
            if !qualified && !parts.is_empty() {
                return Err(BadInput(format!(
                    "{}: no columns {name}.du … {name}.dgamma (the file has the parts {})",
                    table.at(1),
                    parts.into_iter().collect::<Vec<_>>().join(", ")
                ))
                .into());
            }
            if let Some(other) = names
                .iter()
                .find(|n| !ignored.contains(n) && !PART_COMPONENTS.contains(&component(n).as_str()))
            {
                return Err(BadInput(format!(
                    "{}: column '{other}' is not a component of part {name} ({})",
                    table.at(1),
                    PART_COMPONENTS.join(", ")
                ))
                .into());
            }
            let mut order = Vec::new();
            for c in PART_COMPONENTS {
                match names.iter().position(|n| component(n) == c) {
                    Some(i) => order.push(i),
                    None => {
                        return Err(BadInput(format!(
                            "{}: no column for {name}.{c} (a part needs all six components)",
                            table.at(1)
                        ))
                        .into())
                    }
                }
            }
            order
        }
        None => (0..names.len())
            .filter(|&i| names[i] != SAMPLE_INDEX)
            .collect(),
    };
    let mut rows = Vec::with_capacity(table.rows.len());
    for (line, record) in &table.rows {
        rows.push(
            order
                .iter()
                .map(|&i| {
                    table
                        .number(*line, record, i)
                        .map_err(|message| BadInput(message).into())
                })
                .collect::<Result<Vec<f64>>>()?,
        );
    }
    let names: Vec<String> = order.iter().map(|&i| table.columns[i].0.clone()).collect();
    let units: Vec<Option<String>> = order.iter().map(|&i| table.columns[i].1.clone()).collect();
    if part.is_some() {
        // A part's translations share one unit, its rotations one.
        for (kind, range) in [("translation", 0..3), ("rotation", 3..6)] {
            let first = &units[range.start];
            if units[range.clone()].iter().any(|u| u != first) {
                return Err(BadInput(format!(
                    "{}: the {kind} columns of the part are in different units ({}); give them one",
                    table.at(1),
                    units[range]
                        .iter()
                        .map(|u| u.as_deref().unwrap_or("none"))
                        .collect::<Vec<_>>()
                        .join(", ")
                ))
                .into());
            }
        }
    }
    let fitted =
        fit_normal(&names, &rows).map_err(|err| BadInput(format!("{}: {err}", path.display())))?;
    let source = path.file_name().map_or_else(
        || path.display().to_string(),
        |f| f.to_string_lossy().into_owned(),
    );
    let value = fragment(&fitted, part, &units, &source);
    // What is printed must validate when pasted into a scenario.
    let headings: Vec<String> = order
        .iter()
        .map(|&i| match &table.columns[i] {
            (name, Some(unit)) => format!("{name} [{unit}]"),
            (name, None) => name.clone(),
        })
        .collect();
    check_fragment(&fitted, &value, part, &headings)
        .map_err(|message| BadInput(format!("{}: {message}", path.display())))?;
    let text = serde_json::to_string_pretty(&value).expect("a fragment serialises") + "\n";
    match output {
        Some(out) => write_report(out, &text)?,
        None => print(&text)?,
    }
    // The diagnostics where a person reads them; the fragment stays clean for a pipe.
    for line in notes {
        note(&line);
    }
    note(&rvtol_analysis::fit::summary(&fitted, &source));
    let doubtful: Vec<&str> = fitted
        .names
        .iter()
        .zip(&fitted.anderson_darling)
        .filter(|(_, t)| t.is_some_and(|t| t.p_value < 0.05))
        .map(|(n, _)| n.as_str())
        .collect();
    if !doubtful.is_empty() {
        note(&format!(
            "warning: a normal is doubtful for {} (Anderson–Darling p < 0.05): consider another distribution, or resampling the measurements (`empirical`, scenarios/README.md)",
            doubtful.join(", ")
        ));
    }
    Ok(())
}

/// This build's identity in shard files: the version and the SHA-256 of the executable.
/// Shards and their merge must come from one binary: another build may draw or evaluate
/// differently in the last bits, and the merged report would not be the run's.
fn build_identity() -> Result<String> {
    use sha2::{Digest, Sha256};
    let exe = std::env::current_exe()
        .map_err(|err| BadInput(format!("cannot find this executable to identify it: {err}")))?;
    // Hashed as it is read: the executable is never held whole.
    let cannot = |err: std::io::Error| BadInput(format!("{}: cannot read: {err}", exe.display()));
    let mut hasher = Sha256::new();
    std::io::copy(&mut std::fs::File::open(&exe).map_err(cannot)?, &mut hasher).map_err(cannot)?;
    let digest = hasher.finalize();
    let hex: String = digest[..8].iter().map(|b| format!("{b:02x}")).collect();
    Ok(format!("rvtol {} sha256:{hex}", env!("CARGO_PKG_VERSION")))
}

/// `run --shard K/N --partial FILE`: computes shard K of N of the run and writes its
/// partial result.
pub fn run_shard(
    scenario_path: &Path,
    choice: RunChoice,
    (shard, shards): (u64, u64),
    partial_path: &Path,
    execution: &Execution,
) -> Result<()> {
    outputs_ok(
        &[partial_target(partial_path)],
        &scenario_inputs(scenario_path),
    )?;
    let (scenario, text) = read(scenario_path)?;
    let settings = choice.settings(&scenario);
    settings
        .check(&scenario)
        .map_err(|err| choice.checked_error(scenario_path, err))?;
    let build = build_identity()?;
    let chunks = rvtol_engine::shard_range(settings.chunk_count(), shard, shards);
    let pool = pool_for(execution, "run", |threads| {
        memory::run(&scenario, &settings, threads)
    })?;
    let shard_samples =
        settings.samples_before_chunk(chunks.end) - settings.samples_before_chunk(chunks.start);
    let bar = Progress::new(
        "run",
        shard_samples,
        execution.quiet,
        pool.current_num_threads(),
    );
    let partial = pool
        .install(|| rvtol_engine::run_chunks(&scenario, settings, chunks.clone(), &|n| bar.inc(n)))
        .map_err(|err| bad_scenario(scenario_path, err))?;
    bar.finish_and_clear();
    let header = rvtol_analysis::shard::ShardHeader {
        rvtol_version: env!("CARGO_PKG_VERSION").to_string(),
        build,
        scenario_fallback_name: fallback_name(scenario_path),
        scenario_file: text,
        command: rvtol_analysis::shard::ShardCommand::Run {
            samples: settings.samples,
            seed: settings.seed,
            exact_percentile_limit: settings.exact_percentile_limit,
            sampling: settings.sampling.method.name().to_string(),
            replicates: settings.sampling.replicates,
        },
        shard,
        shards,
        chunks: [chunks.start, chunks.end],
    };
    write_bytes(
        partial_path,
        &rvtol_analysis::shard::encode(&header, &rvtol_analysis::shard::ShardContent::Run(partial)),
    )?;
    print(&format!(
        "{}: shard {shard}/{shards} of {} ({} of {} samples, seed {}) written to {}\n",
        scenario_path.display(),
        scenario.name,
        rvtol_engine::format::group_thousands(shard_samples),
        rvtol_engine::format::group_thousands(settings.samples),
        settings.seed,
        partial_path.display()
    ))
}

/// What `rvtol merge` makes of the shards besides the run's report.
pub struct MergeArgs {
    pub partials: Vec<std::path::PathBuf>,
    pub missing: bool,
    pub baseline: Option<std::path::PathBuf>,
    pub check: Option<std::path::PathBuf>,
    pub junit: Option<std::path::PathBuf>,
    pub options: gate::CheckOptions,
}

/// `rvtol merge`: checks the shard files for coverage and identity and folds them into the
/// run's report (or a baseline, or a check against one).
pub fn merge(args: MergeArgs, to: Destinations<'_>, execution: &Execution) -> Result<()> {
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
    use rvtol_analysis::shard;
    let build = build_identity()?;
    // The shard files are held decoded, about their size each, while the next is read:
    // together they take at most the memory the merge may use beyond the program's.
    let (budget, budget_source) = memory_budget(execution.max_memory, threads(execution.threads)?);
    let shards_limit = ReadLimit {
        bytes: (budget - memory::BASE_BYTES).max(0.0) as u64,
        source: format!(
            "the memory left for the shard files, of the {} available ({budget_source}), less the files read before it",
            rvtol_deviation::human_bytes(budget)
        ),
    };
    let mut read_so_far = 0u64;
    let mut files = Vec::with_capacity(args.partials.len());
    for path in &args.partials {
        let bytes =
            input_file::read_bytes(path, &shards_limit.less(read_so_far)).map_err(BadInput)?;
        read_so_far += bytes.len() as u64;
        let file =
            shard::decode(&bytes).map_err(|err| BadInput(format!("{}: {err}", path.display())))?;
        files.push((path.display().to_string(), file));
    }
    let assembly = shard::assemble(files, &build).map_err(BadInput)?;
    let missing_count = assembly.missing_count();
    let header = assembly.header;
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
    let scenario = Scenario::from_json(&header.scenario_file, &header.scenario_fallback_name)
        .map_err(|err| BadInput(format!("{}: its scenario: {err}", first.display())))?;
    let threads = threads(execution.threads)?;
    let pool = thread_pool(threads)?;
    // What the page's record names as the source: the shard files.
    let source = std::path::PathBuf::from(format!(
        "{} shard files of {} ({}, ...)",
        header.shards,
        header.command.name(),
        first.display()
    ));
    let settings = match header.command {
        shard::ShardCommand::Run { .. } => header
            .command
            .run_settings()
            .map_err(|err| BadInput(format!("{}: {err}", first.display())))?
            .expect("a run command has run settings"),
        shard::ShardCommand::Sensitivity {
            samples,
            seed,
            bootstrap,
            row_bootstrap_limit,
            ref shapley,
            ..
        } => {
            if args.baseline.is_some() || args.check.is_some() {
                return Err(BadInput(
                    "--baseline and --check take the shards of a run; these are of a sensitivity analysis".into(),
                )
                .into());
            }
            let sampling = header
                .command
                .sampling()
                .map_err(|err| BadInput(format!("{}: {err}", first.display())))?;
            let sensitivity_args = SensitivityArgs {
                samples,
                seed: Some(seed),
                sampling: Some(sampling.method),
                replicates: Some(sampling.replicates),
                bootstrap: (!sampling.is_replicated()).then_some(bootstrap),
                row_bootstrap_limit,
                shapley: shapley.is_some(),
                permutations: shapley.as_ref().map_or(0, |s| s.budget),
                outer: shapley.as_ref().map_or(0, |s| s.outer),
            };
            let settings = sensitivity_settings(first, &scenario, &sensitivity_args)?;
            let (mut sobol, mut permutations) = (Vec::new(), Vec::new());
            for file in assembly.shards {
                if let shard::ShardContent::Sensitivity {
                    sobol: s,
                    shapley: p,
                } = file.content
                {
                    sobol.push(s);
                    permutations.extend(p);
                }
            }
            let outputs = pool
                .install(|| rvtol_analysis::sensitivity::merge_sobol(&scenario, settings, sobol))
                .map_err(|err| bad_scenario(first, err))?;
            let effects = if sensitivity_args.shapley {
                Some(
                    pool.install(|| {
                        rvtol_analysis::shapley::merge_shapley(
                            &scenario,
                            shapley_settings(&sensitivity_args, seed),
                            permutations,
                        )
                    })
                    .map_err(|err| bad_scenario(first, err))?,
                )
            } else {
                None
            };
            return finish_sensitivity(
                &source, &scenario, settings, outputs, effects, to, execution, &pool,
            );
        }
    };
    let partials = assembly
        .shards
        .into_iter()
        .filter_map(|f| match f.content {
            shard::ShardContent::Run(partial) => Some(partial),
            shard::ShardContent::Sensitivity { .. } => None,
        })
        .collect();
    check_memory(
        memory::run(&scenario, &settings, threads),
        execution,
        "merge",
        threads,
    )?;
    let result = rvtol_engine::merge(&scenario, settings, partials)
        .map_err(|err| bad_scenario(first, err))?;
    if let Some(path) = &args.baseline {
        if settings.samples < 2 {
            return Err(BadInput("a baseline needs at least 2 samples".into()).into());
        }
        let baseline = gate::baseline_of(
            &scenario,
            &header.scenario_file,
            settings,
            result,
            execution.max_non_finite,
        )
        .map_err(|err| bad_scenario(first, err))?;
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
        let baseline_text = read_text(baseline_path)?;
        let recorded = gate::Baseline::from_json(&baseline_text)
            .map_err(|err| bad_scenario(baseline_path, err))?;
        if (recorded.samples, recorded.exact_percentile_limit)
            != (settings.samples, settings.exact_percentile_limit)
        {
            return Err(BadInput(format!(
                "{}: a baseline of {} samples (exact percentiles up to {} values), the shards ran {} ({}): run the shards with --samples {} --exact-percentile-limit {}",
                baseline_path.display(),
                recorded.samples,
                recorded.exact_percentile_limit,
                settings.samples,
                settings.exact_percentile_limit,
                recorded.samples,
                recorded.exact_percentile_limit
            ))
            .into());
        }
        let result = std::sync::Mutex::new(Some(result));
        let report = pool
            .install(|| {
                gate::check_result(
                    &scenario,
                    &header.scenario_file,
                    &recorded,
                    settings.seed,
                    execution.max_non_finite,
                    &args.options,
                    // The settings are the shards' (checked above): the check's run is
                    // the merged one.
                    &|_| {
                        result
                            .lock()
                            .ok()
                            .and_then(|mut r| r.take())
                            .ok_or_else(|| ScenarioError::new("(merge)", "one run per check"))
                    },
                )
            })
            .map_err(|err| bad_scenario(baseline_path, err))?;
        let mut staged = StagedOutputs::new();
        if let Some(junit) = &args.junit {
            staged.add(junit, &report.to_junit())?;
        }
        stage_report(
            &mut staged,
            to.json,
            stdout_taken,
            || report.to_json(),
            || report.to_text(),
        )?;
        staged.commit()?;
        return if report.passed {
            Ok(())
        } else {
            Err(
                Failed("figures moved beyond their baseline bands or requirements violated".into())
                    .into(),
            )
        };
    }
    let failure = non_finite_failure(first, &scenario, &result, execution);
    let report = pool.install(|| RunReport::new(&scenario, result));
    let json = report.to_json();
    let mut staged = StagedOutputs::new();
    stage_report(
        &mut staged,
        to.json,
        to.on_stdout(),
        || json.clone(),
        || report.to_text(),
    )?;
    if failure.is_err() {
        // The report shows what was lost; no file is replaced by a failed merge.
        staged.print_only()?;
        return failure;
    }
    if let Some(html) = to.html {
        let page = html_page(html, &source, &scenario, rvtol_report::Kind::Run, &json)?;
        staged.add(html, &page)?;
    }
    staged.commit()
}
