//! Scenario texts: the only serde types of rvtol and their validation into a [`Scenario`]
//! the run can use (reading the file and the data files it refers to is rvtol-analysis'
//! `request::scenario`: the engine reads no file).
//!
//! [`file`] parses the text section by section, rejecting unknown keys, wrong types and
//! values out of range with the JSON path of the value (`parts[0].covariance[2]`);
//! [`compile`] checks every value once (finite, non-negative, symmetric, positive
//! semi-definite, every model input bound, known models and outputs, each model's geometry)
//! and builds the [`Scenario`]. Every problem is a [`ScenarioError`] naming its JSON path;
//! `rvtol validate` reports them all, the other commands the first. The keys and units are
//! documented in scenarios/README.md.

pub mod allocation;
mod compile;
pub mod design;
mod file;
pub mod skeleton;
pub mod units;

use rvtol_deviation::InputSpace;
use rvtol_models::{ConditionEffect, ErrorModel, OutputKind};

use crate::chunk::Sampling;
use crate::stats::SpecLimits;
use allocation::{AllocatableSource, Lever};

pub use crate::error::ScenarioError;
pub use file::{parse_value, MAX_ARRAY_MEMBERS, MAX_COVARIANCE, MAX_DEVIATION, MAX_PARAMETER};

/// Samples of a run when neither the scenario nor the command line sets them.
pub const DEFAULT_SAMPLES: u64 = 1_000_000;
/// Seed of a run when neither the scenario nor the command line sets it.
pub const DEFAULT_SEED: u64 = 1;

// ---------------------------------------------------------------------------------------
// The validated scenario.

/// Where a model input comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Binding {
    /// A fixed value.
    Constant(f64),
    /// A column of the input space.
    Column(usize),
    /// An output of a model above this one (an index among the scenario's outputs): the
    /// models form a chain evaluated in their order.
    Output(usize),
}

/// A model with its inputs bound to columns or constants.
pub struct BoundModel {
    /// The model.
    pub model: Box<dyn ErrorModel>,
    /// One binding per model input, in the model's order.
    pub bindings: Vec<Binding>,
    /// Index of its first output among the scenario's outputs.
    pub first_output: usize,
}

impl BoundModel {
    /// The model's input row for one row of the input space (`row`) and the scenario's
    /// outputs of that row computed so far (`outputs`, those of the models above).
    pub fn inputs_of_row(&self, row: &[f64], outputs: &[f64]) -> Vec<f64> {
        self.bindings
            .iter()
            .map(|b| match b {
                Binding::Constant(v) => *v,
                Binding::Column(column) => row[*column],
                Binding::Output(o) => outputs[*o],
            })
            .collect()
    }
}

/// One output of the scenario (of one of its models).
#[derive(Debug, Clone, PartialEq)]
pub struct OutputInfo {
    /// Name.
    pub name: String,
    /// Unit.
    pub unit: String,
    /// Continuous or indicator.
    pub kind: OutputKind,
    /// What it is.
    pub description: String,
    /// Spec limits, when the scenario sets them.
    pub spec: Option<SpecLimits>,
    /// The indicator output (its index among the scenario's outputs) that qualifies this
    /// output's samples, and how ([`rvtol_models::OutputCondition`]).
    pub condition: Option<(usize, ConditionEffect)>,
    /// Whether a sample flagged by a [`ConditionEffect::NonConforming`] condition conforms
    /// when its value is within the limits (`spec_limits.<output>.flagged_conform`; by
    /// default it does not).
    pub flagged_conform: bool,
}

/// A named column of the input space (a variable or a part component).
#[derive(Debug, Clone, PartialEq)]
pub struct ColumnInfo {
    /// `variable` or `part.component`.
    pub name: String,
    /// Unit, when known.
    pub unit: Option<String>,
    /// Tolerance limits [lower, upper] in the column's unit: the box a worst case and an
    /// RSS stack read ([`rvtol_deviation::ScalarDistribution::tolerance_limits`] of a
    /// variable, mean ± 3σ of a part component); equal for a column that does not vary.
    pub tolerance: [f64; 2],
    /// Its law as the scenario states it, for the record of the inputs.
    pub law: ColumnLaw,
}

/// The law of one column as the scenario states it (after unit conversion): a part
/// component is a normal of its part's joint law (the 001 Eq. 11 constraint, where the part
/// has one, is not applied to these figures).
#[derive(Debug, Clone, PartialEq)]
pub struct ColumnLaw {
    /// The law's name (`normal`, `tolerance band`, `uniform`, ...).
    pub name: &'static str,
    /// Its parameters as stated ([`rvtol_deviation::ScalarDistribution::law`]).
    pub parameters: Vec<(&'static str, f64)>,
    /// Its mean.
    pub mean: f64,
    /// Its standard deviation.
    pub sd: f64,
}

/// A named set of input-space columns: one error source (a part, a variable) or a group of
/// them.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct InputGroup {
    /// Name: the part or variable name, or names joined with `+`.
    pub name: String,
    /// Its columns.
    pub columns: Vec<usize>,
}

/// A validated scenario: the input space, the bound models and the outputs.
pub struct Scenario {
    /// Name (from the file, or its stem).
    pub name: String,
    /// Description from the file.
    pub description: String,
    /// Samples when the command line does not say.
    pub samples: u64,
    /// Seed when the command line does not say.
    pub seed: u64,
    /// How rows are drawn when the command line does not say (`sampling`, `replicates`).
    pub sampling: Sampling,
    /// The joint input space.
    pub input_space: InputSpace,
    /// Its columns' names.
    pub columns: Vec<ColumnInfo>,
    /// The error sources: each part (its six columns) and each variable (its column).
    pub sources: Vec<InputGroup>,
    /// The units of the Sobol' analysis: the scenario's `sensitivity_groups`, then every
    /// source in none of them.
    pub sensitivity_groups: Vec<InputGroup>,
    /// The models in scenario order.
    pub models: Vec<BoundModel>,
    /// All outputs, models in order.
    pub outputs: Vec<OutputInfo>,
    /// The sources `rvtol allocate` may change (the `allocation` section; empty without
    /// one), in scenario order.
    pub allocation: Vec<AllocatableSource>,
    /// The discrete design choices `rvtol allocate` may make (`allocation.levers`).
    pub allocation_levers: Vec<Lever>,
    /// SHA-256 of the scenario text as loaded (data files written in), lower-case hex:
    /// every report records it, so that a report, a page or a baseline is tied to the
    /// exact text that produced it ([`scenario_digest`]).
    pub digest: String,
}

/// The SHA-256 of a scenario text (its UTF-8 bytes), lower-case hex.
pub fn scenario_digest(text: &str) -> String {
    use sha2::{Digest, Sha256};
    Sha256::digest(text.as_bytes())
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

impl Scenario {
    /// Parses and validates scenario JSON text; the first problem is the error.
    pub fn from_json(text: &str, fallback_name: &str) -> Result<Scenario, ScenarioError> {
        Scenario::from_json_all_problems(text, fallback_name)
            .map_err(|mut problems| problems.swap_remove(0))
    }

    /// Parses and validates scenario JSON text, reporting every problem found (each with
    /// its JSON path; at least one on `Err`). A problem in one element (a part, a variable,
    /// a model) does not hide those of the others; what depends on a broken element is not
    /// checked again.
    pub fn from_json_all_problems(
        text: &str,
        fallback_name: &str,
    ) -> Result<Scenario, Vec<ScenarioError>> {
        let (file, mut problems) = file::parse(text).map_err(|err| vec![err])?;
        match compile::compile(file, fallback_name, &mut problems) {
            Some(mut scenario) if problems.is_empty() => {
                scenario.digest = scenario_digest(text);
                // The file's sampling against its own samples (at least 1, checked by the
                // compiler) and input space.
                (scenario.sampling)
                    .check(scenario.samples, "samples", &scenario.input_space)
                    .map_err(|err| vec![err])?;
                Ok(scenario)
            }
            _ => {
                if problems.is_empty() {
                    problems.push(ScenarioError::new("(root)", "the scenario is not valid"));
                }
                Err(problems)
            }
        }
    }

    /// Indices of the continuous outputs (those with distributions to analyse).
    pub fn continuous_outputs(&self) -> Vec<usize> {
        (0..self.outputs.len())
            .filter(|&o| self.outputs[o].kind == OutputKind::Continuous)
            .collect()
    }

    /// Index of an output by name.
    pub fn output_index(&self, name: &str) -> Option<usize> {
        self.outputs.iter().position(|o| o.name == name)
    }

    /// The JSON path and name of the model that produces output `output`:
    /// `models[i] (name)`.
    pub fn model_of_output(&self, output: usize) -> String {
        self.models
            .iter()
            .enumerate()
            .find(|(_, bound)| {
                (bound.first_output..bound.first_output + bound.model.outputs().len())
                    .contains(&output)
            })
            .map(|(i, bound)| format!("models[{i}] ({})", bound.model.name()))
            .unwrap_or_else(|| "models".to_string())
    }
}
