//! One file per command, each taking its clap arguments whole: it makes its request
//! through rvtol-analysis' `request` (the scenario read, the settings with their defaults
//! and limits, what it needs against the machine), calls the engine or the analysis and
//! prints or writes the report ([`crate::output`]). The library computes and decides;
//! nothing here does statistics. This module holds what the commands share: the options
//! of every Monte Carlo command ([`Execution`]), reading a scenario, checking the outputs
//! before any work, the thread pool within the memory budget, the report files and the
//! HTML page.

pub mod allocate;
pub mod baseline;
pub mod check;
pub mod curve;
pub mod evaluate;
pub mod fit;
pub mod init;
pub mod merge;
pub mod models;
pub mod nominal;
pub mod rare;
pub mod report;
pub mod run;
pub mod sensitivity;
pub mod stack;
pub mod sweep;
pub mod validate;

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use anyhow::Result;
use clap::Args;
use rvtol_analysis::request::input_file::{self, ReadLimit};
use rvtol_analysis::request::machine;
use rvtol_analysis::request::memory::MemoryNeed;
use rvtol_analysis::request::scenario::{ScenarioSource, ScenarioText, SourceError};
use rvtol_analysis::request::table::CsvTable;
use rvtol_analysis::request::{Caller, Refusal};
use rvtol_engine::run::check_non_finite;
use rvtol_engine::Scenario;

use crate::limits::{parse_count, parse_share, parse_size};
use crate::output::{check_targets, is_stdout, Format, Input, OutputFile, StagedOutputs};
use crate::BadInput;

/// Options every Monte Carlo command takes.
#[derive(Debug, Clone, Args)]
pub struct Execution {
    /// Worker threads (default: all cores; at most 4 per core). Results do not depend on it.
    #[arg(long, value_parser = parse_count, allow_hyphen_values = true)]
    pub threads: Option<u64>,
    /// Largest share (0 to 1) of samples whose model value may be non-finite (the model
    /// could not evaluate them) before the command fails; they are always counted and
    /// reported, and counted out of spec.
    #[arg(long, value_name = "SHARE", default_value_t = 0.0, value_parser = parse_share, allow_hyphen_values = true)]
    pub max_non_finite: f64,
    /// Memory the command may use (bytes, or with k, M, G, T: `4G`); default: the memory
    /// available on this machine. A request that needs more is refused before it starts.
    #[arg(long, value_name = "SIZE", value_parser = parse_size, allow_hyphen_values = true)]
    pub max_memory: Option<f64>,
    /// No progress display (a command whose samples will take more than a minute still
    /// says so in one line).
    #[arg(long, short)]
    pub quiet: bool,
}

/// The command line's spelling of options in the library's messages.
const CALLER: Caller = Caller::CommandLine;

/// A problem of the file at `path` (a scenario's, a baseline's, a set of shard files') as
/// one line named after the file.
fn problem_of_file(path: &Path, err: impl std::fmt::Display) -> anyhow::Error {
    BadInput(format!("{}: {err}", shown(path))).into()
}

/// A refused request as one line: a scenario's problem named after its file (`path`), a
/// request value after its option.
fn refused(path: &Path, refusal: Refusal) -> anyhow::Error {
    match refusal {
        Refusal::Scenario(err) => problem_of_file(path, err),
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
        SourceError::Scenario(err) => problem_of_file(path, err),
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

/// A run's report (`run` and `merge`): its JSON and text staged; when the run lost more
/// samples than `--max-non-finite` allows, the text printed and the failure returned, no
/// file replaced (the report shows what was lost). Gives the staged outputs, for the
/// caller's other files, and the JSON.
fn staged_run_report(
    path: &Path,
    scenario: &Scenario,
    result: rvtol_engine::RunResult,
    (to, execution): (&Destinations, &Execution),
    pool: &rayon::ThreadPool,
) -> Result<(StagedOutputs, String)> {
    let failure = non_finite_failure(path, scenario, &result, execution);
    let report = pool.install(|| rvtol_engine::RunReport::new(scenario, result));
    let json = report.to_json();
    let staged = staged_report(to, &json, || report.to_text())?;
    if let Err(failed) = failure {
        staged.print_only()?;
        return Err(failed);
    }
    Ok((staged, json))
}

/// A report's JSON and text staged for `to`: the JSON file when asked, the text on
/// standard output unless another of the command's outputs takes it.
fn staged_report(
    to: &Destinations,
    json: &str,
    text: impl FnOnce() -> String,
) -> Result<StagedOutputs> {
    let mut staged = StagedOutputs::new();
    stage_report(
        &mut staged,
        to.json,
        to.on_stdout(),
        || json.to_string(),
        text,
    )?;
    Ok(staged)
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
        .map_err(|err| problem_of_file(path, err))
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

/// The curves of the assemblies a page draws beside the nominal ones: for each model that
/// draws curves, those nearest the run report's P50 and P99.865 of the model's output (of
/// its values, flagged samples included, where the report gives them apart), among rows
/// drawn with the run's seed (rvtol-analysis' `assemblies`).
fn page_assemblies(
    scenario: &Scenario,
    run: &serde_json::Value,
) -> Result<Vec<rvtol_report::AssemblyCurves>> {
    use rvtol_engine::format::{format_sig, group_thousands};
    let output_of =
        |name: &str| (run["outputs"].as_array().into_iter().flatten()).find(|o| o["name"] == name);
    let targets = |name: &str| -> Vec<(String, f64)> {
        let Some(output) = output_of(name) else {
            return Vec::new();
        };
        let percentiles = match output.get("value_percentiles") {
            Some(values) if values.is_object() => values,
            _ => &output["percentiles"],
        };
        [("P50", "50"), ("P99.865", "99.865")]
            .into_iter()
            .filter_map(|(label, key)| Some((label.to_string(), percentiles[key].as_f64()?)))
            .collect()
    };
    let (Some(seed), Some(samples)) = (run["seed"].as_u64(), run["samples"].as_u64()) else {
        return Ok(Vec::new());
    };
    let chosen = rvtol_analysis::assemblies::chosen_assemblies(scenario, seed, samples, &targets)
        .map_err(|err| BadInput(format!("the assemblies a page draws: {err}")))?;
    Ok(chosen
        .into_iter()
        .map(|a| {
            let unit = (scenario.outputs.iter())
                .find(|o| o.name == a.output)
                .map_or("", |o| o.unit.as_str());
            rvtol_report::AssemblyCurves {
                model: a.model.to_string(),
                heading: format!("the {} assembly of {}", a.label, a.output),
                note: format!(
                    "Of the first {} assemblies drawn with seed {seed}, the one whose {} lies nearest the run's {} of its values, {} {unit}: row {}, where it is {} {unit}.",
                    group_thousands(a.rows),
                    a.output,
                    a.label,
                    format_sig(a.target),
                    group_thousands(a.sample),
                    format_sig(a.value),
                ),
                curves: a.curves,
                left_out: a.left_out,
            }
        })
        .collect())
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
    let assemblies = match kind {
        Kind::Run if !curves.is_empty() => page_assemblies(scenario, &value)?,
        _ => Vec::new(),
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
        stack: (kind == Kind::Stack).then_some(&value),
        sweep: (kind == Kind::Sweep).then_some(&value),
        rare: (kind == Kind::Rare).then_some(&value),
        curves: &curves,
        curves_left_out: &curves_left_out,
        assemblies: &assemblies,
    })
    .map_err(|err| BadInput(format!("{}: {err}", path.display())).into())
}

fn parsed(json: &str) -> serde_json::Value {
    serde_json::from_str(json).expect("the engine's JSON report parses")
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
