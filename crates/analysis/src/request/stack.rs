//! A stack analysis as a caller asks for it (`rvtol stack`, Python's `stack`): the outputs
//! by name (every continuous output when none is named), the seed of its linearity rows
//! and of the Monte Carlo run beside it, and that run's samples (each the scenario's
//! unless given; the run as [`super::run::RunRequest`] checks it).

use rvtol_engine::{RunSettings, Scenario, DEFAULT_EXACT_PERCENTILE_LIMIT};
use rvtol_models::OutputKind;

use super::run::RunRequest;
use super::{Caller, Refusal};
use crate::stack::StackSettings;

/// What a caller asks of a stack analysis.
#[derive(Debug, Clone, PartialEq)]
pub struct StackRequest {
    /// The outputs, by name; every continuous output when empty.
    pub outputs: Vec<String>,
    /// Seed of the linearity rows and of the run.
    pub seed: Option<u64>,
    /// Whether the Monte Carlo run goes beside the stack.
    pub monte_carlo: bool,
    /// Its samples.
    pub samples: Option<u64>,
    /// The share of rows an output may be non-finite in (`--max-non-finite`).
    pub max_non_finite: f64,
}

impl Default for StackRequest {
    fn default() -> StackRequest {
        StackRequest {
            outputs: Vec::new(),
            seed: None,
            monte_carlo: true,
            samples: None,
            max_non_finite: 0.0,
        }
    }
}

impl StackRequest {
    /// The stack's settings and the run's (when asked), checked against `scenario`.
    pub fn settings(
        &self,
        scenario: &Scenario,
        caller: Caller,
    ) -> Result<(StackSettings, Option<RunSettings>), Refusal> {
        let stack = self.stack_settings(scenario, caller)?;
        let run = RunRequest {
            samples: self.samples,
            seed: self.seed,
            exact_percentile_limit: DEFAULT_EXACT_PERCENTILE_LIMIT,
            sampling: None,
            replicates: None,
        };
        let run = (self.monte_carlo)
            .then(|| run.settings(scenario, caller))
            .transpose()?;
        Ok((stack, run))
    }

    /// The stack's settings: an unknown or indicator output is refused, naming the option
    /// and the outputs there are.
    fn stack_settings(
        &self,
        scenario: &Scenario,
        caller: Caller,
    ) -> Result<StackSettings, Refusal> {
        let outputs = continuous_outputs(scenario, &self.outputs, "the stack", caller)?;
        Ok(StackSettings {
            seed: self.seed.unwrap_or(scenario.seed),
            outputs,
            max_non_finite: self.max_non_finite,
        })
    }
}

/// The continuous outputs `names` of `scenario` (every one when none is named), for an
/// analysis (`reader`, "the stack") that reads continuous outputs only: an unknown or
/// indicator output is refused, naming the `--output` option and the outputs there are.
pub fn continuous_outputs(
    scenario: &Scenario,
    names: &[String],
    reader: &str,
    caller: Caller,
) -> Result<Vec<usize>, Refusal> {
    let continuous = scenario.continuous_outputs();
    if names.is_empty() {
        return Ok(continuous);
    }
    let known: Vec<&str> = (continuous.iter())
        .map(|&o| scenario.outputs[o].name.as_str())
        .collect();
    (names.iter())
        .map(|name| match scenario.output_index(name) {
            Some(o) if scenario.outputs[o].kind == OutputKind::Continuous => Ok(o),
            Some(_) => Err(format!(
                "{name:?} is an indicator; {reader} reads continuous outputs: {}",
                known.join(", ")
            )),
            None => Err(format!(
                "no output {name:?}; the scenario's continuous outputs: {}",
                known.join(", ")
            )),
        })
        .collect::<Result<Vec<usize>, String>>()
        .map_err(|message| Refusal::option(caller, "output", message))
}
