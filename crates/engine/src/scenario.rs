//! Scenario files: the only serde types of rvtol, their loading and their validation into
//! a [`Scenario`] the run can use.
//!
//! Loading rejects unknown keys and wrong types with the JSON path of the value
//! (`parts[0].covariance[2]`); validation checks every value once (finite, non-negative,
//! symmetric, positive semi-definite, every model input bound, known models and outputs)
//! and reports the first problem as a [`ScenarioError`] naming its JSON path. The keys and
//! units are documented in scenarios/README.md.

use std::collections::BTreeMap;
use std::path::Path;

use rvtol_deviation::{InputSpace, InputSpaceBuilder, PartSpec, ScalarDistribution, SixDof};
use rvtol_models::{ErrorModel, ModelParams, OutputKind, ParamValue};
use serde::Deserialize;

use crate::allocation::spec::{
    compile_allocation, AllocatableSource, AllocationFile, ToleranceKind, ToleranceSource,
};
use crate::stats::SpecLimits;

/// Samples of a run when neither the scenario nor the command line sets them.
pub const DEFAULT_SAMPLES: u64 = 1_000_000;
/// Seed of a run when neither the scenario nor the command line sets it.
pub const DEFAULT_SEED: u64 = 1;

/// A scenario that cannot be read or used, with the JSON path of the problem.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{path}: {message}")]
pub struct ScenarioError {
    /// JSON path of the offending value (`(file)` for the file as a whole).
    pub path: String,
    /// What is wrong, in one line.
    pub message: String,
}

impl ScenarioError {
    /// A new error at `path`.
    pub fn new(path: impl Into<String>, message: impl Into<String>) -> Self {
        ScenarioError {
            path: path.into(),
            message: message.into(),
        }
    }
}

impl From<rvtol_deviation::DeviationError> for ScenarioError {
    fn from(err: rvtol_deviation::DeviationError) -> Self {
        ScenarioError::new(err.path(), err.message())
    }
}

// ---------------------------------------------------------------------------------------
// The file format (serde).

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ScenarioFile {
    #[serde(default)]
    name: Option<String>,
    #[serde(default)]
    description: Option<String>,
    #[serde(default)]
    samples: Option<u64>,
    #[serde(default)]
    seed: Option<u64>,
    #[serde(default)]
    parts: Vec<PartFile>,
    #[serde(default)]
    variables: Vec<VariableFile>,
    #[serde(default)]
    correlations: Vec<CorrelationFile>,
    models: Vec<ModelFile>,
    #[serde(default)]
    spec_limits: BTreeMap<String, SpecFile>,
    #[serde(default)]
    sensitivity_groups: Vec<GroupFile>,
    #[serde(default)]
    allocation: Option<AllocationFile>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct GroupFile {
    name: String,
    members: Vec<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PartFile {
    name: String,
    /// Documentation for the reader of the file; not used by the run.
    #[serde(default)]
    #[allow(dead_code)]
    description: Option<String>,
    #[serde(default)]
    mean: Option<Vec<f64>>,
    #[serde(default)]
    covariance: Option<Vec<Vec<f64>>>,
    #[serde(default)]
    sd: Option<Vec<f64>>,
    #[serde(default)]
    correlation: Option<Vec<Vec<f64>>>,
    #[serde(default)]
    tolerance_band: Option<ToleranceBandFile>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ToleranceBandFile {
    delta_tau_mm: f64,
    length_mm: f64,
    #[serde(default)]
    constraint_eq11: bool,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct VariableFile {
    name: String,
    #[serde(default)]
    unit: Option<String>,
    /// Documentation for the reader of the file; not used by the run.
    #[serde(default)]
    #[allow(dead_code)]
    description: Option<String>,
    distribution: DistributionFile,
}

fn default_cp() -> f64 {
    1.0
}

#[derive(Debug, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
enum DistributionFile {
    Normal {
        mean: f64,
        sd: f64,
    },
    ToleranceBand {
        lower: f64,
        upper: f64,
        #[serde(default = "default_cp")]
        cp: f64,
        #[serde(default)]
        mean_shift: f64,
    },
    Uniform {
        lower: f64,
        upper: f64,
    },
    Triangular {
        lower: f64,
        mode: f64,
        upper: f64,
    },
    TruncatedNormal {
        mean: f64,
        sd: f64,
        lower: f64,
        upper: f64,
    },
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct CorrelationFile {
    between: [String; 2],
    rho: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ModelFile {
    model: String,
    #[serde(default)]
    params: serde_json::Map<String, serde_json::Value>,
    #[serde(default)]
    inputs: serde_json::Map<String, serde_json::Value>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SpecFile {
    #[serde(default)]
    lower: Option<f64>,
    #[serde(default)]
    upper: Option<f64>,
}

// ---------------------------------------------------------------------------------------
// The validated scenario.

/// Where a model input comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Binding {
    /// A fixed value.
    Constant(f64),
    /// A column of the input space.
    Column(usize),
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
    /// The model's input row for one row of the input space: constants and columns.
    pub fn inputs_of_row(&self, row: &[f64]) -> Vec<f64> {
        self.bindings
            .iter()
            .map(|b| match b {
                Binding::Constant(v) => *v,
                Binding::Column(column) => row[*column],
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
}

/// A named column of the input space (a variable or a part component).
#[derive(Debug, Clone, PartialEq)]
pub struct ColumnInfo {
    /// `variable` or `part.component`.
    pub name: String,
    /// Unit, when known.
    pub unit: Option<String>,
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
}

impl Scenario {
    /// Reads and validates a scenario file.
    pub fn load(path: &Path) -> Result<Scenario, ScenarioError> {
        Scenario::read(path).map(|(scenario, _)| scenario)
    }

    /// Reads and validates a scenario file, returning its text too.
    pub fn read(path: &Path) -> Result<(Scenario, String), ScenarioError> {
        let text = std::fs::read_to_string(path).map_err(|err| {
            ScenarioError::new("(file)", format!("cannot read {}: {err}", path.display()))
        })?;
        let fallback_name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "scenario".to_string());
        let scenario = Scenario::from_json(&text, &fallback_name)?;
        Ok((scenario, text))
    }

    /// Parses and validates scenario JSON text.
    pub fn from_json(text: &str, fallback_name: &str) -> Result<Scenario, ScenarioError> {
        let mut deserializer = serde_json::Deserializer::from_str(text);
        let file: ScenarioFile =
            serde_path_to_error::deserialize(&mut deserializer).map_err(|err| {
                let path = err.path().to_string();
                if err.inner().is_syntax() || err.inner().is_eof() {
                    // The position is the useful part; the path stops at the broken token.
                    return ScenarioError::new("JSON syntax", err.into_inner().to_string());
                }
                let path = if path == "." || path.is_empty() {
                    "(root)".to_string()
                } else {
                    path
                };
                ScenarioError::new(path, err.into_inner().to_string())
            })?;
        deserializer
            .end()
            .map_err(|err| ScenarioError::new("(root)", err.to_string()))?;
        compile(file, fallback_name)
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
}

fn fixed_array<const N: usize>(path: &str, values: &[f64]) -> Result<[f64; N], ScenarioError> {
    values.try_into().map_err(|_| {
        ScenarioError::new(path, format!("expected {N} numbers, got {}", values.len()))
    })
}

fn fixed_matrix(path: &str, rows: &[Vec<f64>]) -> Result<[[f64; 6]; 6], ScenarioError> {
    if rows.len() != 6 {
        return Err(ScenarioError::new(
            path,
            format!(
                "expected 6 rows of 6 numbers (row-major), got {} rows",
                rows.len()
            ),
        ));
    }
    let mut matrix = [[0.0; 6]; 6];
    for (i, row) in rows.iter().enumerate() {
        matrix[i] = fixed_array::<6>(&format!("{path}[{i}]"), row)?;
    }
    Ok(matrix)
}

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

fn part_spec(path: &str, part: &PartFile) -> Result<PartSpec, ScenarioError> {
    let forms = [
        part.covariance.is_some(),
        part.sd.is_some() || part.correlation.is_some(),
        part.tolerance_band.is_some(),
    ];
    if forms.iter().filter(|f| **f).count() != 1 {
        return Err(ScenarioError::new(
            path,
            "give exactly one of: mean + covariance, mean + sd + correlation, tolerance_band",
        ));
    }
    if let Some(band) = &part.tolerance_band {
        if part.mean.is_some() {
            return Err(ScenarioError::new(
                format!("{path}.mean"),
                "a tolerance_band part derives its mean (001 Eq. 10); remove mean",
            ));
        }
        return Ok(PartSpec::from_tolerance_band(
            &format!("{path}.tolerance_band"),
            band.delta_tau_mm,
            band.length_mm,
            band.constraint_eq11,
        )?);
    }
    let mean_path = format!("{path}.mean");
    let mean = match &part.mean {
        Some(m) => fixed_array::<6>(&mean_path, m)?,
        None => [0.0; 6],
    };
    if let Some(covariance) = &part.covariance {
        let covariance = fixed_matrix(&format!("{path}.covariance"), covariance)?;
        return Ok(PartSpec::from_covariance(path, mean, covariance)?);
    }
    let sd = part.sd.as_deref().ok_or_else(|| {
        ScenarioError::new(format!("{path}.sd"), "sd is required with correlation")
    })?;
    let sd = fixed_array::<6>(&format!("{path}.sd"), sd)?;
    let correlation = match &part.correlation {
        Some(c) => fixed_matrix(&format!("{path}.correlation"), c)?,
        None => std::array::from_fn(|i| std::array::from_fn(|j| if i == j { 1.0 } else { 0.0 })),
    };
    Ok(PartSpec::from_correlation(path, mean, sd, correlation)?)
}

/// A part's tolerance as `rvtol allocate` reads it (see [`crate::allocation::spec`]).
fn part_tolerance(path: &str, part: &PartFile) -> ToleranceSource {
    let (kind, current, unit) = match &part.tolerance_band {
        Some(band) => (ToleranceKind::PartToleranceBand, band.delta_tau_mm, "mm"),
        None if part.covariance.is_some() => (ToleranceKind::PartCovariance, 1.0, ""),
        None => (ToleranceKind::PartSd, 1.0, ""),
    };
    ToleranceSource {
        name: part.name.clone(),
        path: path.to_string(),
        kind,
        current,
        unit: unit.to_string(),
    }
}

/// A variable's tolerance as `rvtol allocate` reads it (see [`crate::allocation::spec`]).
fn variable_tolerance(path: &str, variable: &VariableFile) -> ToleranceSource {
    let (kind, current) = match variable.distribution {
        DistributionFile::Normal { sd, .. } => (ToleranceKind::VariableNormal, 3.0 * sd),
        DistributionFile::ToleranceBand { lower, upper, .. } => {
            (ToleranceKind::VariableToleranceBand, 0.5 * (upper - lower))
        }
        DistributionFile::Uniform { lower, upper } => {
            (ToleranceKind::VariableUniform, 0.5 * (upper - lower))
        }
        DistributionFile::Triangular { lower, upper, .. } => {
            (ToleranceKind::VariableTriangular, 0.5 * (upper - lower))
        }
        DistributionFile::TruncatedNormal { sd, .. } => {
            (ToleranceKind::VariableTruncatedNormal, 3.0 * sd)
        }
    };
    ToleranceSource {
        name: variable.name.clone(),
        path: path.to_string(),
        kind,
        current,
        unit: variable.unit.clone().unwrap_or_default(),
    }
}

fn distribution(d: &DistributionFile) -> (ScalarDistribution, &'static str) {
    match *d {
        DistributionFile::Normal { mean, sd } => {
            (ScalarDistribution::Normal { mean, sd }, "normal")
        }
        DistributionFile::ToleranceBand {
            lower,
            upper,
            cp,
            mean_shift,
        } => (
            ScalarDistribution::ToleranceBand {
                lower,
                upper,
                cp,
                mean_shift,
            },
            "tolerance_band",
        ),
        DistributionFile::Uniform { lower, upper } => {
            (ScalarDistribution::Uniform { lower, upper }, "uniform")
        }
        DistributionFile::Triangular { lower, mode, upper } => (
            ScalarDistribution::Triangular { lower, mode, upper },
            "triangular",
        ),
        DistributionFile::TruncatedNormal {
            mean,
            sd,
            lower,
            upper,
        } => (
            ScalarDistribution::TruncatedNormal {
                mean,
                sd,
                lower,
                upper,
            },
            "truncated_normal",
        ),
    }
}

fn model_params(
    path: &str,
    map: &serde_json::Map<String, serde_json::Value>,
) -> Result<ModelParams, ScenarioError> {
    let mut params = ModelParams::new();
    for (key, value) in map {
        let value = match value {
            serde_json::Value::Number(n) => ParamValue::Number(n.as_f64().unwrap_or(f64::NAN)),
            serde_json::Value::String(s) => ParamValue::Text(s.clone()),
            serde_json::Value::Object(entries) => {
                let mut named = Vec::with_capacity(entries.len());
                for (name, v) in entries {
                    let number = v.as_f64().ok_or_else(|| {
                        ScenarioError::new(
                            format!("{path}.{key}.{name}"),
                            format!("expected a number, got {v}"),
                        )
                    })?;
                    named.push((name.clone(), number));
                }
                ParamValue::Named(named)
            }
            other => {
                return Err(ScenarioError::new(
                    format!("{path}.{key}"),
                    format!("expected a number, a string or an object of numbers, got {other}"),
                ))
            }
        };
        params.insert(key.clone(), value);
    }
    Ok(params)
}

fn compile(file: ScenarioFile, fallback_name: &str) -> Result<Scenario, ScenarioError> {
    if let Some(samples) = file.samples {
        if samples == 0 {
            return Err(ScenarioError::new("samples", "must be at least 1"));
        }
    }
    let mut builder = InputSpaceBuilder::new();
    let mut columns: Vec<ColumnInfo> = Vec::new();
    let mut sources: Vec<InputGroup> = Vec::new();
    let mut column_by_name: BTreeMap<String, usize> = BTreeMap::new();
    let mut add_name = |path: &str,
                        name: String,
                        column: usize,
                        unit: Option<String>,
                        columns: &mut Vec<ColumnInfo>| {
        if column_by_name.insert(name.clone(), column).is_some() {
            return Err(ScenarioError::new(
                path,
                format!("name {name:?} is used twice"),
            ));
        }
        columns.push(ColumnInfo { name, unit });
        Ok(())
    };

    for (i, part) in file.parts.iter().enumerate() {
        let path = format!("parts[{i}]");
        check_name(&format!("{path}.name"), &part.name)?;
        let spec = part_spec(&path, part)?;
        let first = builder.add_part(&path, &spec);
        sources.push(InputGroup {
            name: part.name.clone(),
            columns: (first..first + 6).collect(),
        });
        for (k, component) in SixDof::NAMES.iter().enumerate() {
            add_name(
                &format!("{path}.name"),
                format!("{}.{component}", part.name),
                first + k,
                Some(SixDof::UNITS[k].to_string()),
                &mut columns,
            )?;
        }
    }
    for (i, variable) in file.variables.iter().enumerate() {
        let path = format!("variables[{i}]");
        check_name(&format!("{path}.name"), &variable.name)?;
        let (dist, kind) = distribution(&variable.distribution);
        dist.validate(&format!("{path}.distribution.{kind}"))?;
        let column = builder.add_scalar(&path, dist);
        sources.push(InputGroup {
            name: variable.name.clone(),
            columns: vec![column],
        });
        add_name(
            &format!("{path}.name"),
            variable.name.clone(),
            column,
            variable.unit.clone(),
            &mut columns,
        )?;
    }
    for (i, correlation) in file.correlations.iter().enumerate() {
        let path = format!("correlations[{i}]");
        let mut ends = [0usize; 2];
        for (k, name) in correlation.between.iter().enumerate() {
            ends[k] = *column_by_name.get(name).ok_or_else(|| {
                ScenarioError::new(
                    format!("{path}.between[{k}]"),
                    format!("no variable or part component named {name:?}"),
                )
            })?;
        }
        builder.correlate(&path, ends[0], ends[1], correlation.rho)?;
    }
    let input_space = builder.build("correlations")?;

    if file.models.is_empty() {
        return Err(ScenarioError::new("models", "needs at least one model"));
    }
    let mut models = Vec::new();
    let mut outputs: Vec<OutputInfo> = Vec::new();
    for (i, model_file) in file.models.iter().enumerate() {
        let path = format!("models[{i}]");
        let entry = rvtol_models::find(&model_file.model).ok_or_else(|| {
            let known: Vec<&str> = rvtol_models::all().iter().map(|e| e.name).collect();
            ScenarioError::new(
                format!("{path}.model"),
                format!(
                    "unknown model {:?}; known models: {}",
                    model_file.model,
                    known.join(", ")
                ),
            )
        })?;
        let params = model_params(&format!("{path}.params"), &model_file.params)?;
        let model = (entry.build)(&params)
            .map_err(|err| ScenarioError::new(format!("{path}.params.{}", err.key), err.reason))?;
        let mut bindings = Vec::with_capacity(model.inputs().len());
        for input in model.inputs() {
            let binding_path = format!("{path}.inputs.{}", input.name);
            let value = model_file.inputs.get(&input.name).ok_or_else(|| {
                ScenarioError::new(
                    format!("{path}.inputs"),
                    format!(
                        "model input {:?} ({}) is not bound: give a number or a variable name",
                        input.name, input.unit
                    ),
                )
            })?;
            let binding = match value {
                serde_json::Value::Number(n) => {
                    let v = n.as_f64().unwrap_or(f64::NAN);
                    if !v.is_finite() {
                        return Err(ScenarioError::new(binding_path, "must be a finite number"));
                    }
                    let index = bindings.len();
                    model
                        .check_constant(index, v)
                        .map_err(|reason| ScenarioError::new(&binding_path, reason))?;
                    Binding::Constant(v)
                }
                serde_json::Value::String(name) => {
                    let column = *column_by_name.get(name).ok_or_else(|| {
                        ScenarioError::new(
                            &binding_path,
                            format!("no variable or part component named {name:?}"),
                        )
                    })?;
                    if let Some(unit) = &columns[column].unit {
                        if input.unit != "any" && unit != &input.unit {
                            return Err(ScenarioError::new(
                                &binding_path,
                                format!("{name:?} is in {unit} but the input wants {}", input.unit),
                            ));
                        }
                    }
                    Binding::Column(column)
                }
                other => {
                    return Err(ScenarioError::new(
                        binding_path,
                        format!("expected a number or a variable name, got {other}"),
                    ))
                }
            };
            bindings.push(binding);
        }
        if let Some(extra) = model_file
            .inputs
            .keys()
            .find(|k| !model.inputs().iter().any(|input| &input.name == *k))
        {
            let known: Vec<&str> = model.inputs().iter().map(|i| i.name.as_str()).collect();
            return Err(ScenarioError::new(
                format!("{path}.inputs.{extra}"),
                format!(
                    "{} has no input {extra:?}; its inputs are: {}",
                    entry.name,
                    known.join(", ")
                ),
            ));
        }
        let first_output = outputs.len();
        for output in model.outputs() {
            if outputs.iter().any(|o| o.name == output.name) {
                return Err(ScenarioError::new(
                    format!("{path}.model"),
                    format!(
                        "output {:?} is produced by an earlier model too",
                        output.name
                    ),
                ));
            }
            outputs.push(OutputInfo {
                name: output.name.clone(),
                unit: output.unit.clone(),
                kind: output.kind,
                description: output.description.to_string(),
                spec: None,
            });
        }
        models.push(BoundModel {
            model,
            bindings,
            first_output,
        });
    }

    for (name, spec) in &file.spec_limits {
        let path = format!("spec_limits.{name}");
        let output = outputs
            .iter_mut()
            .find(|o| &o.name == name)
            .ok_or_else(|| ScenarioError::new(&path, format!("no output named {name:?}")))?;
        if output.kind != OutputKind::Continuous {
            return Err(ScenarioError::new(
                &path,
                "spec limits apply to continuous outputs only",
            ));
        }
        if spec.lower.is_none() && spec.upper.is_none() {
            return Err(ScenarioError::new(&path, "give lower, upper or both"));
        }
        if let (Some(l), Some(u)) = (spec.lower, spec.upper) {
            if l >= u {
                return Err(ScenarioError::new(
                    format!("{path}.upper"),
                    format!("upper {u} must exceed lower {l}"),
                ));
            }
        }
        output.spec = Some(SpecLimits {
            lower: spec.lower,
            upper: spec.upper,
        });
    }

    let mut sensitivity_groups: Vec<InputGroup> = Vec::new();
    let mut grouped: Vec<&str> = Vec::new();
    for (i, group) in file.sensitivity_groups.iter().enumerate() {
        let path = format!("sensitivity_groups[{i}]");
        check_name(&format!("{path}.name"), &group.name)?;
        if group.members.is_empty() {
            return Err(ScenarioError::new(
                format!("{path}.members"),
                "needs at least one member",
            ));
        }
        if sources.iter().any(|s| s.name == group.name) && !group.members.contains(&group.name) {
            return Err(ScenarioError::new(
                format!("{path}.name"),
                format!("{:?} is already the name of a part or variable", group.name),
            ));
        }
        let mut columns = Vec::new();
        for (k, member) in group.members.iter().enumerate() {
            let member_path = format!("{path}.members[{k}]");
            let source = sources.iter().find(|s| &s.name == member).ok_or_else(|| {
                ScenarioError::new(
                    &member_path,
                    format!("no part or variable named {member:?}"),
                )
            })?;
            if grouped.contains(&member.as_str()) {
                return Err(ScenarioError::new(
                    member_path,
                    format!("{member:?} is already in a group"),
                ));
            }
            grouped.push(member);
            columns.extend(&source.columns);
        }
        sensitivity_groups.push(InputGroup {
            name: group.name.clone(),
            columns,
        });
    }
    sensitivity_groups.extend(
        sources
            .iter()
            .filter(|s| !grouped.contains(&s.name.as_str()))
            .cloned(),
    );

    let allocation = match &file.allocation {
        Some(section) => {
            let tolerances: Vec<ToleranceSource> =
                file.parts
                    .iter()
                    .enumerate()
                    .map(|(i, part)| part_tolerance(&format!("parts[{i}]"), part))
                    .chain(file.variables.iter().enumerate().map(|(i, variable)| {
                        variable_tolerance(&format!("variables[{i}]"), variable)
                    }))
                    .collect();
            compile_allocation(section, &tolerances)?
        }
        None => Vec::new(),
    };

    Ok(Scenario {
        name: file.name.unwrap_or_else(|| fallback_name.to_string()),
        description: file.description.unwrap_or_default(),
        samples: file.samples.unwrap_or(DEFAULT_SAMPLES),
        seed: file.seed.unwrap_or(DEFAULT_SEED),
        input_space,
        columns,
        sources,
        sensitivity_groups,
        models,
        outputs,
        allocation,
    })
}
