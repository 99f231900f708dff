//! Validation of a parsed scenario file into a [`Scenario`], section by section: every
//! value checked once, every problem collected with its JSON path ([`compile`]).
//!
//! A [`Compiler`] holds what the sections share (the input space being built, the named
//! columns, the error sources, the models and outputs, the names of elements that could
//! not be built) and runs the [`SECTIONS`] in order, each reading what the earlier ones
//! built: the run settings, [`parts`], the [`reducer`] and the models built from their
//! parameters, [`variables`] (their laws in [`distributions`]; their units follow the model
//! inputs they feed), the [`correlations`] that close the input space, the [`models`]'
//! input [`bindings`], the [`outputs`] with their spec limits, the sensitivity [`groups`]
//! and the [`allocation`] section. A problem in one element (a part, a variable, a model)
//! does not hide those of the others; what refers to an element that could not be built
//! is not reported again. A key added to the scenario format lands in its section's file
//! (and its serde type in `file.rs`).

mod allocation;
mod bindings;
mod correlations;
mod design;
mod distributions;
mod groups;
mod models;
mod outputs;
mod parts;
mod reducer;
mod variables;

use bindings::REDUCER_BINDING;

use std::collections::{BTreeMap, BTreeSet};

use rvtol_deviation::{InputSpace, InputSpaceBuilder, SamplingMethod};

use super::allocation::{AllocatableSource, Lever};
use super::file::ScenarioFile;
use super::{
    BoundModel, ColumnInfo, InputGroup, OutputInfo, Scenario, ScenarioError, DEFAULT_SAMPLES,
    DEFAULT_SEED,
};
use crate::chunk::Sampling;

pub(crate) use bindings::trailing_index;
pub(crate) use reducer::model_params;

/// A section of the scenario: it reads the file and what the earlier sections built, adds
/// what it builds to the compiler and reports its problems.
type Section = fn(&mut Compiler);

/// The sections in the order they compile (and report their problems).
pub const SECTIONS: [(&str, Section); 9] = [
    ("samples, seed, sampling", settings),
    ("parts", parts::compile),
    ("reducer, models (built)", reducer::compile),
    ("variables", variables::compile),
    ("correlations", correlations::compile),
    ("models (bound)", models::compile),
    ("outputs, spec_limits", outputs::compile),
    ("sensitivity_groups", groups::compile),
    ("allocation", allocation::compile),
];

/// What the sections of one scenario share while it compiles.
pub struct Compiler<'f> {
    file: &'f ScenarioFile,
    problems: Vec<ScenarioError>,
    /// Whether an element of `models` failed to parse (so an empty list is not reported).
    models_failed_to_parse: bool,
    sampling: Sampling,
    builder: InputSpaceBuilder,
    /// The input space, once the correlations closed it.
    input_space: Option<InputSpace>,
    /// The input-space columns' names, in column order.
    columns: Vec<ColumnInfo>,
    column_by_name: BTreeMap<String, usize>,
    /// The error sources: each part (its six columns) and each variable (its columns).
    sources: Vec<InputGroup>,
    /// Names of parts, variables and members that could not be built: references to them
    /// are not reported again.
    broken: BTreeSet<String>,
    /// The variable arrays (`count`): name → (JSON path, member columns).
    arrays: BTreeMap<String, (String, Vec<usize>)>,
    /// Each model of the file built from its parameters, or its problem (taken by the
    /// binding pass).
    built_models: Vec<models::BuiltModel>,
    /// Per variable name, the units of the model inputs it is bound to, with the binding's
    /// JSON path.
    bound_units: BTreeMap<String, Vec<(String, String)>>,
    models: Vec<BoundModel>,
    outputs: Vec<OutputInfo>,
    /// The output names of every model that built, with its index in the file: an input
    /// bound to one that is not yet among `outputs` names a model below (or its own).
    outputs_below: BTreeMap<String, usize>,
    /// The index in the file of the model being bound.
    models_bound: usize,
    /// Models whose outputs are known (built, bound or not): every output name is known
    /// when all are.
    models_built: usize,
    sensitivity_groups: Vec<InputGroup>,
    allocation: Vec<AllocatableSource>,
    allocation_levers: Vec<Lever>,
}

/// Validates the parsed file and builds the scenario, adding every problem to `problems`
/// (after those of the parse); `None` when something the scenario needs could not be
/// built.
pub(super) fn compile(
    file: ScenarioFile,
    fallback_name: &str,
    problems: &mut Vec<ScenarioError>,
) -> Option<Scenario> {
    let mut compiler = Compiler {
        file: &file,
        models_failed_to_parse: problems_at(problems, "models"),
        problems: std::mem::take(problems),
        sampling: Sampling::default(),
        builder: InputSpaceBuilder::new(),
        input_space: None,
        columns: Vec::new(),
        column_by_name: BTreeMap::new(),
        sources: Vec::new(),
        broken: file.broken_names.clone(),
        arrays: BTreeMap::new(),
        built_models: Vec::new(),
        bound_units: BTreeMap::new(),
        models: Vec::new(),
        outputs: Vec::new(),
        outputs_below: BTreeMap::new(),
        models_bound: 0,
        models_built: 0,
        sensitivity_groups: Vec::new(),
        allocation: Vec::new(),
        allocation_levers: Vec::new(),
    };
    for (_, section) in SECTIONS {
        section(&mut compiler);
    }
    let Compiler {
        problems: found,
        sampling,
        input_space,
        columns,
        sources,
        sensitivity_groups,
        models,
        outputs,
        allocation,
        allocation_levers,
        ..
    } = compiler;
    *problems = found;
    Some(Scenario {
        name: file
            .name
            .clone()
            .unwrap_or_else(|| fallback_name.to_string()),
        description: file.description.clone().unwrap_or_default(),
        samples: file.samples.unwrap_or(DEFAULT_SAMPLES),
        seed: file.seed.unwrap_or(DEFAULT_SEED),
        sampling,
        input_space: input_space?,
        columns,
        sources,
        sensitivity_groups,
        models,
        outputs,
        allocation,
        allocation_levers,
        digest: String::new(),
    })
}

/// Whether a problem of `problems` lies in the section `key`.
fn problems_at(problems: &[ScenarioError], key: &str) -> bool {
    problems.iter().any(|p| p.path.starts_with(key))
}

impl Compiler<'_> {
    /// Keeps the problem of `result`, if any.
    fn report(&mut self, result: Result<(), ScenarioError>) {
        if let Err(err) = result {
            self.problems.push(err);
        }
    }

    /// Names input-space column `column` (its info stays aligned with the index whatever
    /// the name); a name used twice is a problem at `path`.
    fn add_column(
        &mut self,
        path: &str,
        info: ColumnInfo,
        column: usize,
    ) -> Result<(), ScenarioError> {
        let name = info.name.clone();
        self.columns.push(info);
        if self.column_by_name.contains_key(&name) {
            return Err(ScenarioError::new(
                path,
                format!("name {name:?} is used twice"),
            ));
        }
        self.column_by_name.insert(name, column);
        Ok(())
    }
}

/// The run settings: `samples` at least 1, `sampling` and `replicates`.
fn settings(compiler: &mut Compiler) {
    if compiler.file.samples == Some(0) {
        compiler.report(Err(ScenarioError::new("samples", "must be at least 1")));
    }
    let sampling = sampling_of(compiler.file);
    if let Err(err) = &sampling {
        compiler.report(Err(err.clone()));
    }
    compiler.sampling = sampling.unwrap_or_default();
}

/// A name of the file's: letters, digits, `_` and `-`, at least one.
fn check_name(path: &str, name: &str) -> Result<(), ScenarioError> {
    let ok = !name.is_empty()
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
    if ok {
        Ok(())
    } else {
        Err(ScenarioError::new(
            path,
            format!("name {name:?} must be non-empty and use only letters, digits, '_' and '-'"),
        ))
    }
}

/// The scenario's `sampling` and `replicates` (a method name and, for `lhs` and `rqmc`,
/// the replicates, [`Sampling::DEFAULT_REPLICATES`] when not given).
fn sampling_of(file: &ScenarioFile) -> Result<Sampling, ScenarioError> {
    let method = match file.sampling.as_deref() {
        None => SamplingMethod::MonteCarlo,
        Some(name) => SamplingMethod::parse(name).ok_or_else(|| {
            ScenarioError::new(
                "sampling",
                format!(
                    "unknown method {name:?}, expected one of {}",
                    SamplingMethod::NAMES.map(|n| format!("{n:?}")).join(", ")
                ),
            )
        })?,
    };
    let mut sampling = Sampling::of(method);
    if let Some(replicates) = file.replicates {
        if method == SamplingMethod::MonteCarlo {
            return Err(ScenarioError::new(
                "replicates",
                "Monte Carlo rows are independent and have no replicates: give replicates with \"sampling\": \"lhs\" or \"rqmc\"",
            ));
        }
        sampling.replicates = replicates;
    }
    Ok(sampling)
}
