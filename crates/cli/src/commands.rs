//! One function per command: make its request through rvtol-analysis' `request` (the
//! scenario read, the settings with their defaults and limits, what it needs against the
//! machine), call the engine or the analysis, print or write the report
//! ([`crate::output`]). The library computes and decides; nothing here does statistics.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::OnceLock;

use anyhow::Result;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rvtol_analysis::allocation::allocate as run_allocation;
use rvtol_analysis::allocation::proposal_document;
use rvtol_analysis::allocation::report::AllocationReport;
use rvtol_analysis::gate;
use rvtol_analysis::request::allocation::AllocationRequest;
use rvtol_analysis::request::gate::{
    baseline_matches, check_baseline_samples, check_requirements, check_settings, BaselineRequest,
    RequirementError,
};
use rvtol_analysis::request::input_file::{self, ReadLimit};
use rvtol_analysis::request::machine::{self, memory_budget};
use rvtol_analysis::request::memory::{self, MemoryNeed};
use rvtol_analysis::request::run::{check_samples_out, RunRequest};
use rvtol_analysis::request::scenario::{ScenarioSource, ScenarioText, SourceError};
use rvtol_analysis::request::sensitivity::{SensitivityRequest, ShapleyRequest};
use rvtol_analysis::request::shard::{build_identity, ShardOf};
use rvtol_analysis::request::table::CsvTable;
use rvtol_analysis::request::{Caller, Refusal};
use rvtol_analysis::sensitivity::{
    sobol_indices, SensitivitySettings, DEFAULT_ROW_BOOTSTRAP_LIMIT,
};
use rvtol_analysis::sensitivity_report::SensitivityReport;
use rvtol_analysis::shapley::shapley_effects;
use rvtol_deviation::SamplingMethod;
use rvtol_engine::run::check_non_finite;
use rvtol_engine::{
    nominal_curves, run as run_scenario, NominalReport, RunReport, Scenario, ScenarioError,
};

use crate::limits::{parse_count, parse_sampling, parse_seed};
use crate::output::{
    check_targets, is_stdout, note, print, write_bytes, write_report, Format, Input, OutputFile,
    StagedOutputs,
};
use crate::{BadInput, Execution, Failed};

/// The command line's spelling of options in the library's messages.
const CALLER: Caller = Caller::CommandLine;

fn bad_scenario(path: &Path, err: ScenarioError) -> anyhow::Error {
    BadInput(format!("{}: {err}", shown(path))).into()
}

/// A refused request as one line: a scenario's problem named after its file (`path`), a
/// request value after its option.
fn refused(path: &Path, refusal: Refusal) -> anyhow::Error {
    match refusal {
        Refusal::Scenario(err) => bad_scenario(path, err),
        other => BadInput(other.to_string()).into(),
    }
}

/// An input path as messages name it: `-` is standard input.
fn shown(path: &Path) -> String {
    if is_stdout(path) {
        "standard input".to_string()
    } else {
        path.display().to_string()
    }
}

/// The bound of a scenario, report or baseline read whole ([`machine::whole_file_limit`]),
/// worked out once.
fn whole_file_limit() -> &'static ReadLimit {
    static LIMIT: OnceLock<ReadLimit> = OnceLock::new();
    LIMIT.get_or_init(|| machine::whole_file_limit(CALLER))
}

/// A report's or baseline's text (standard input's for `-`), within [`whole_file_limit`],
/// or one line saying why it cannot be read.
fn read_text(path: &Path) -> Result<String> {
    if is_stdout(path) {
        input_file::read_standard_input(whole_file_limit())
    } else {
        input_file::read_text(path, whole_file_limit())
    }
    .map_err(|message| BadInput(message).into())
}

/// The files a command on the scenario at `path` reads: the scenario and the data files it
/// refers to (none for standard input, which cannot be read twice).
fn scenario_inputs(path: &Path) -> Vec<(&'static str, PathBuf)> {
    ScenarioSource::of_path(path).files(whole_file_limit())
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

/// A source error as one line: a file that cannot be read, or the scenario's problem
/// named after its file.
fn unreadable(path: &Path, err: SourceError) -> anyhow::Error {
    match err {
        SourceError::Read(message) => BadInput(message).into(),
        SourceError::Scenario(err) => bad_scenario(path, err),
    }
}

/// A scenario file's text, with the numbers of the data files it refers to written in.
fn read_scenario_text(path: &Path) -> Result<ScenarioText> {
    (ScenarioSource::of_path(path))
        .read(whole_file_limit())
        .map_err(|err| unreadable(path, err))
}

fn read(path: &Path) -> Result<(Scenario, ScenarioText)> {
    (ScenarioSource::of_path(path))
        .load(whole_file_limit())
        .map_err(|err| unreadable(path, err))
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
    machine::check_memory(need, command, execution.max_memory, threads, CALLER)
        .map_err(|message| BadInput(message).into())
}

/// The worker-thread count of a command ([`machine::threads`]).
fn threads(execution: &Execution) -> Result<usize> {
    machine::threads(execution.threads, CALLER)
        .map_err(|refusal| BadInput(refusal.to_string()).into())
}

/// A pool of `threads` workers.
fn thread_pool(threads: usize) -> Result<rayon::ThreadPool> {
    machine::thread_pool(threads).map_err(|message| BadInput(message).into())
}

/// The thread pool of a Monte Carlo command, once its memory need at that thread count
/// (`need`) fits the budget ([`machine::pool_for`]).
fn pool_for(
    execution: &Execution,
    command: &str,
    need: impl FnOnce(usize) -> MemoryNeed,
) -> Result<rayon::ThreadPool> {
    machine::pool_for(
        command,
        execution.threads,
        execution.max_memory,
        CALLER,
        need,
    )
    .map_err(|message| BadInput(message).into())
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

pub fn run(
    scenario_path: &Path,
    request: RunRequest,
    to: Destinations<'_>,
    execution: &Execution,
) -> Result<()> {
    outputs_ok(&to.targets(&[]), &scenario_inputs(scenario_path))?;
    let scenario = load(scenario_path)?;
    let settings =
        (request.settings(&scenario, CALLER)).map_err(|refusal| refused(scenario_path, refusal))?;
    if to.samples.is_some() {
        check_samples_out(&scenario, settings.samples, CALLER)
            .map_err(|refusal| refused(scenario_path, refusal))?;
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
    match Scenario::from_json_all_problems(&text.text, &text.fallback_name) {
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
    #[arg(long, default_value_t = rvtol_analysis::request::sensitivity::DEFAULT_SAMPLES, value_parser = parse_count, allow_hyphen_values = true)]
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
    #[arg(long, default_value_t = rvtol_analysis::request::sensitivity::DEFAULT_PERMUTATIONS, value_parser = parse_count, allow_hyphen_values = true)]
    pub permutations: u64,
    /// Shapley: outer draws per conditional-variance estimate.
    #[arg(long, default_value_t = rvtol_analysis::request::sensitivity::DEFAULT_OUTER, value_parser = parse_count, allow_hyphen_values = true)]
    pub outer: u64,
}

impl SensitivityArgs {
    /// The analysis the command line asks for.
    pub fn request(&self) -> SensitivityRequest {
        SensitivityRequest {
            samples: self.samples,
            seed: self.seed,
            sampling: self.sampling,
            replicates: self.replicates,
            bootstrap: self.bootstrap,
            row_bootstrap_limit: self.row_bootstrap_limit,
            shapley: self.shapley.then_some(ShapleyRequest {
                permutations: self.permutations,
                outer: self.outer,
            }),
        }
    }
}

pub fn sensitivity(
    path: &Path,
    args: SensitivityArgs,
    to: Destinations<'_>,
    execution: &Execution,
) -> Result<()> {
    outputs_ok(&to.targets(&[]), &scenario_inputs(path))?;
    let scenario = load(path)?;
    let request = args.request();
    let settings =
        (request.settings(&scenario, CALLER)).map_err(|refusal| refused(path, refusal))?;
    let pool = pool_for(execution, "sensitivity", |threads| {
        memory::sensitivity(&scenario, &settings, threads)
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
    let shapley = match request.shapley_settings(settings.seed) {
        Some(shapley) => Some(
            pool.install(|| shapley_effects(&scenario, shapley))
                .map_err(|err| bad_scenario(path, err))?,
        ),
        None => None,
    };
    finish_sensitivity(
        path, &scenario, settings, outputs, shapley, to, execution, &pool,
    )
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
    use rvtol_analysis::request::shard::{sensitivity_command, shapley_shard};
    use rvtol_analysis::shard::ShardContent;
    let (scenario, text) = read(path)?;
    let request = args.request();
    let settings =
        (request.settings(&scenario, CALLER)).map_err(|refusal| refused(path, refusal))?;
    let build = build_identity().map_err(BadInput)?;
    let pool = pool_for(execution, "sensitivity", |threads| {
        memory::sensitivity(&scenario, &settings, threads)
    })?;
    let of = ShardOf { shard, shards };
    let chunks = of.range(settings.chunk_count());
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
    let (shapley, shapley_part) = match shapley_shard(&scenario, &request, settings.seed, of)
        .map_err(|err| bad_scenario(path, err))?
    {
        Some((shapley_settings, part, range)) => {
            let partial = pool
                .install(|| {
                    rvtol_analysis::shapley::shapley_partial(&scenario, shapley_settings, range)
                })
                .map_err(|err| bad_scenario(path, err))?;
            (Some(partial), Some(part))
        }
        None => (None, None),
    };
    let command = sensitivity_command(&request, &settings, shapley_part);
    let header = of.header(build, &text, command, &chunks);
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
    let request = BaselineRequest {
        samples,
        seed,
        exact_percentile_limit,
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
    check_requirements(&scenario, &recorded, options, CALLER).map_err(|err| match err {
        RequirementError::Baseline { index, message } => BadInput(format!(
            "{}: requirements[{index}]: {message}",
            baseline_path.display()
        )),
        RequirementError::Given(refusal) => BadInput(refusal.to_string()),
    })?;
    let settings = check_settings(&scenario, &recorded, seed);
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
    let request = AllocationRequest {
        target: &args.target,
        cost: args.cost.as_deref(),
        samples: args.samples,
        seed: args.seed,
        verify_seed: args.verify_seed,
    };
    let (target, settings) =
        (request.settings(&scenario, CALLER)).map_err(|refusal| refused(path, refusal))?;
    let pool = pool_for(execution, "allocate", |threads| {
        memory::allocation(&scenario, settings.samples, threads)
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
            run_allocation(
                &scenario,
                &text.text,
                &args.output,
                target,
                settings,
                &|n| spinner.set_position(n as u64),
            )
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
            let document = proposal_document(&text.text, &allocation)
                .map_err(|err| bad_scenario(path, err))?;
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
    let threads = threads(execution)?;
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
    let (budget, budget_source) = memory_budget(execution.max_memory, threads, CALLER);
    let rows_limit = ReadLimit {
        bytes: ((budget - memory::BASE_BYTES).max(0.0)
            / memory::table_evaluation_factor(&scenario)) as u64,
        source: format!(
            "what the {} of memory available ({budget_source}) allows for rows read, evaluated and written out; split the rows into smaller files",
            rvtol_deviation::human_bytes(budget)
        ),
    };
    let table = read_csv(inputs_path, &rows_limit, "--inputs")?;
    let values = rvtol_analysis::request::evaluate::input_rows(
        &table,
        &inputs_path.display().to_string(),
        &scenario,
    )
    .map_err(|refusal| BadInput(refusal.to_string()))?;
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
        None => print(&rvtol_analysis::request::samples::sample_csv(
            &scenario, &rows,
        )),
    }
}

/// A sample table as the file `path` takes it: Parquet when its name ends in `.parquet`,
/// else CSV.
fn sample_table_bytes(
    path: &Path,
    scenario: &Scenario,
    table: &rvtol_engine::SampleTable,
) -> Result<Vec<u8>> {
    rvtol_analysis::request::samples::sample_table_bytes(path, scenario, table)
        .map_err(|err| BadInput(format!("{}: {err}", path.display())).into())
}

/// `rvtol fit`: a normal model of measured parts, as a scenario fragment.
pub fn fit(path: &Path, part: Option<&str>, output: Option<&Path>) -> Result<()> {
    use rvtol_analysis::fit::{check_fragment, fit as fit_normal, fragment};
    use rvtol_analysis::request::fit::{fit_columns, FitColumns};
    outputs_ok(
        &[target("-o", output, Format::Json)],
        &[("the measurements", path.to_path_buf())],
    )?;
    let table = read_csv(path, whole_file_limit(), "MEASUREMENTS")?;
    // Diagnostics go to standard error once the fragment is written: a refused fit says
    // only why.
    let FitColumns {
        names,
        units,
        headings,
        rows,
        notes,
        ..
    } = fit_columns(&table, &path.display().to_string(), part, CALLER)
        .map_err(|refusal| BadInput(refusal.to_string()))?;
    let fitted =
        fit_normal(&names, &rows).map_err(|err| BadInput(format!("{}: {err}", path.display())))?;
    let source = path.file_name().map_or_else(
        || path.display().to_string(),
        |f| f.to_string_lossy().into_owned(),
    );
    let value = fragment(&fitted, part, &units, &source);
    // What is printed must validate when pasted into a scenario.
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

/// `run --shard K/N --partial FILE`: computes shard K of N of the run and writes its
/// partial result.
pub fn run_shard(
    scenario_path: &Path,
    request: RunRequest,
    (shard, shards): (u64, u64),
    partial_path: &Path,
    execution: &Execution,
) -> Result<()> {
    outputs_ok(
        &[partial_target(partial_path)],
        &scenario_inputs(scenario_path),
    )?;
    let (scenario, text) = read(scenario_path)?;
    let settings =
        (request.settings(&scenario, CALLER)).map_err(|refusal| refused(scenario_path, refusal))?;
    let build = build_identity().map_err(BadInput)?;
    let of = ShardOf { shard, shards };
    let chunks = of.range(settings.chunk_count());
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
    let command = rvtol_analysis::request::shard::run_command(&settings);
    let header = of.header(build, &text, command, &chunks);
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

/// The shard files at `paths`, decoded. They are held decoded, about their size each,
/// while the next is read: together they take at most the memory the merge may use beyond
/// the program's.
fn read_shards(
    paths: &[PathBuf],
    execution: &Execution,
) -> Result<Vec<(String, rvtol_analysis::shard::ShardFile)>> {
    let (budget, budget_source) = memory_budget(execution.max_memory, threads(execution)?, CALLER);
    let shards_limit = ReadLimit {
        bytes: (budget - memory::BASE_BYTES).max(0.0) as u64,
        source: format!(
            "the memory left for the shard files, of the {} available ({budget_source}), less the files read before it",
            rvtol_deviation::human_bytes(budget)
        ),
    };
    let mut read_so_far = 0u64;
    let mut files = Vec::with_capacity(paths.len());
    for path in paths {
        let bytes =
            input_file::read_bytes(path, &shards_limit.less(read_so_far)).map_err(BadInput)?;
        read_so_far += bytes.len() as u64;
        let file = rvtol_analysis::shard::decode(&bytes)
            .map_err(|err| BadInput(format!("{}: {err}", path.display())))?;
        files.push((path.display().to_string(), file));
    }
    Ok(files)
}

/// A run merged from its shards, for a baseline or a check.
struct MergedRun<'a> {
    scenario: &'a Scenario,
    scenario_text: &'a str,
    settings: rvtol_engine::RunSettings,
    result: rvtol_engine::RunResult,
}

/// `merge --check BASELINE`: the merged run checked against the baseline (whose samples
/// and percentile limit the shards must have run).
fn merge_check(
    merged: MergedRun<'_>,
    baseline_path: &Path,
    args: &MergeArgs,
    json: Option<&Path>,
    stdout_taken: bool,
    execution: &Execution,
    pool: &rayon::ThreadPool,
) -> Result<()> {
    let baseline_text = read_text(baseline_path)?;
    let recorded = gate::Baseline::from_json(&baseline_text)
        .map_err(|err| bad_scenario(baseline_path, err))?;
    baseline_matches(&recorded, &merged.settings)
        .map_err(|message| BadInput(format!("{}: {message}", baseline_path.display())))?;
    let result = std::sync::Mutex::new(Some(merged.result));
    let report = pool
        .install(|| {
            gate::check_result(
                merged.scenario,
                merged.scenario_text,
                &recorded,
                merged.settings.seed,
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
        json,
        stdout_taken,
        || report.to_json(),
        || report.to_text(),
    )?;
    staged.commit()?;
    if report.passed {
        Ok(())
    } else {
        Err(
            Failed("figures moved beyond their baseline bands or requirements violated".into())
                .into(),
        )
    }
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
    use rvtol_analysis::request::shard::{merged, MergeError, Merged, MergedWork};
    use rvtol_analysis::shard;
    let build = build_identity().map_err(BadInput)?;
    let files = read_shards(&args.partials, execution)?;
    let assembly = shard::assemble(files, &build).map_err(BadInput)?;
    let missing_count = assembly.missing_count();
    let header = &assembly.header;
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
    let Merged {
        header,
        scenario,
        work,
    } = merged(assembly).map_err(|err| match err {
        MergeError::Scenario(err) => BadInput(format!("{}: its scenario: {err}", first.display())),
        MergeError::Damaged(err) => BadInput(format!("{}: {err}", first.display())),
        MergeError::Settings(Refusal::Scenario(err)) => {
            BadInput(format!("{}: {err}", shown(first)))
        }
        MergeError::Settings(refusal) => BadInput(refusal.to_string()),
    })?;
    let threads = threads(execution)?;
    let pool = thread_pool(threads)?;
    // What the page's record names as the source: the shard files.
    let source = std::path::PathBuf::from(format!(
        "{} shard files of {} ({}, ...)",
        header.shards,
        header.command.name(),
        first.display()
    ));
    let (settings, partials) = match work {
        MergedWork::Run { settings, partials } => (settings, partials),
        MergedWork::Sensitivity {
            settings,
            shapley,
            sobol,
            permutations,
        } => {
            if args.baseline.is_some() || args.check.is_some() {
                return Err(BadInput(
                    "--baseline and --check take the shards of a run; these are of a sensitivity analysis".into(),
                )
                .into());
            }
            let outputs = pool
                .install(|| rvtol_analysis::sensitivity::merge_sobol(&scenario, settings, sobol))
                .map_err(|err| bad_scenario(first, err))?;
            let effects = match shapley {
                Some(shapley) => Some(
                    pool.install(|| {
                        rvtol_analysis::shapley::merge_shapley(&scenario, shapley, permutations)
                    })
                    .map_err(|err| bad_scenario(first, err))?,
                ),
                None => None,
            };
            return finish_sensitivity(
                &source, &scenario, settings, outputs, effects, to, execution, &pool,
            );
        }
    };
    check_memory(
        memory::run(&scenario, &settings, threads),
        execution,
        "merge",
        threads,
    )?;
    let result = rvtol_engine::merge(&scenario, settings, partials)
        .map_err(|err| bad_scenario(first, err))?;
    if let Some(path) = &args.baseline {
        check_baseline_samples(settings.samples).map_err(|message| BadInput(message.into()))?;
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
        let merged = MergedRun {
            scenario: &scenario,
            scenario_text: &header.scenario_file,
            settings,
            result,
        };
        return merge_check(
            merged,
            baseline_path,
            &args,
            to.json,
            stdout_taken,
            execution,
            &pool,
        );
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
