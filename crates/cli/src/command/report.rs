//! `rvtol report`: one self-contained HTML page from saved JSON reports of one scenario
//! (run, sensitivity, allocate, stack, sweep), with its models' nominal curves when the scenario
//! is given.

use std::path::{Path, PathBuf};

use anyhow::Result;
use clap::Args;

use super::{
    command_line, load, outputs_ok, page_assemblies, page_curves, read_text, scenario_inputs,
    target,
};
use crate::output::{is_stdout, print, write_report, Format};
use crate::BadInput;

/// The arguments of `rvtol report`.
#[derive(Debug, Args)]
pub struct ReportArgs {
    /// JSON reports (`--json` of run, sensitivity, allocate, stack, sweep), at most one of each.
    #[arg(required = true)]
    pub reports: Vec<PathBuf>,
    /// The scenario file: adds its description and its models' nominal curves.
    #[arg(long, value_name = "FILE")]
    pub scenario: Option<PathBuf>,
    /// The HTML file to write.
    #[arg(short = 'o', long = "output", value_name = "PATH")]
    pub output: PathBuf,
}

/// `rvtol report`: one page from saved JSON reports of one scenario, with its model curves
/// when the scenario file is given.
pub fn report(args: ReportArgs) -> Result<()> {
    let (files, scenario_path) = (&args.reports, args.scenario.as_deref());
    let output: &Path = &args.output;
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
    let digest_of = |v: &serde_json::Value| v["scenario_sha256"].as_str().map(str::to_string);
    let shown = |digest: &Option<String>| match digest {
        Some(digest) => format!("text sha256 {}…", &digest[..digest.len().min(12)]),
        None => "a text of unrecorded digest".to_string(),
    };
    let mut found: Vec<(Kind, serde_json::Value, &Path)> = Vec::new();
    for file in files {
        let text = read_text(file)?;
        let value: serde_json::Value = serde_json::from_str(&text)
            .map_err(|err| BadInput(format!("{}: not JSON: {err}", file.display())))?;
        let kind = kind_of(&value).ok_or_else(|| {
            BadInput(format!(
                "{}: not a JSON report of `rvtol run`, `sensitivity`, `allocate`, `stack`, `sweep` or `rare`",
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
            let (this, that) = (digest_of(&value), digest_of(first));
            if this != that {
                return Err(BadInput(format!(
                    "{}: a report of scenario '{}' ({}), but {} is of another text of it ({}); one page shows one scenario text: run the analyses again on one file",
                    file.display(),
                    scenario_of(&value),
                    shown(&this),
                    first_file.display(),
                    shown(&that)
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
    let mut assemblies = Vec::new();
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
        let reports_digest = found.first().and_then(|(_, v, _)| digest_of(v));
        if reports_digest.as_deref() != Some(scenario.digest.as_str()) {
            return Err(BadInput(format!(
                "{}: not the scenario text the reports were computed from (its text sha256 {}…, the reports' {}); give the file they ran, or run them again",
                path.display(),
                &scenario.digest[..12],
                shown(&reports_digest)
            ))
            .into());
        }
        description = Some(scenario.description.clone()).filter(|d| !d.is_empty());
        (curves, curves_left_out) = page_curves(&scenario);
        let run = found.iter().find(|(k, _, _)| *k == Kind::Run);
        if let (Some((_, run, _)), false) = (run, curves.is_empty()) {
            assemblies = page_assemblies(&scenario, run)?;
        }
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
        stack: get(Kind::Stack),
        sweep: get(Kind::Sweep),
        rare: get(Kind::Rare),
        curves: &curves,
        curves_left_out: &curves_left_out,
        assemblies: &assemblies,
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
