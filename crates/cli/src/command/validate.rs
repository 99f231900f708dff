//! `rvtol validate`: a scenario checked without running it, every problem on its own line.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use rvtol_engine::Scenario;

use super::{read_scenario_text, shown};
use crate::output::{note, print};
use crate::BadInput;

/// The arguments of `rvtol validate`.
#[derive(Debug, Args)]
pub struct ValidateArgs {
    /// Scenario file (JSON; "-" reads standard input).
    pub scenario: PathBuf,
}

/// `rvtol validate`: `valid` with the scenario's sizes, or its problems.
pub fn validate(args: ValidateArgs) -> Result<()> {
    let scenario_path = args.scenario.as_path();
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
