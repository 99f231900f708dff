//! `rvtol nominal`: every model with every deviation at its mean.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use rvtol_engine::NominalReport;

use super::{emit, load, outputs_ok, problem_of_file, scenario_inputs, target};
use crate::output::{is_stdout, Format};

/// The arguments of `rvtol nominal`.
#[derive(Debug, Args)]
pub struct NominalArgs {
    /// Scenario file (JSON; "-" reads standard input).
    pub scenario: PathBuf,
    /// Write the JSON report to PATH ("-" for stdout instead of the table).
    #[arg(long, value_name = "PATH")]
    pub json: Option<PathBuf>,
}

/// `rvtol nominal`: the nominal values' report.
pub fn nominal(args: NominalArgs) -> Result<()> {
    let (scenario_path, json) = (args.scenario.as_path(), args.json.as_deref());
    outputs_ok(
        &[target("--json", json, Format::Json)],
        &scenario_inputs(scenario_path),
    )?;
    let scenario = load(scenario_path)?;
    let values =
        rvtol_engine::nominal(&scenario).map_err(|err| problem_of_file(scenario_path, err))?;
    let report = NominalReport::new(&scenario, &values);
    emit(
        json,
        json.is_some_and(is_stdout),
        || report.to_json(),
        || report.to_text(),
    )
}
