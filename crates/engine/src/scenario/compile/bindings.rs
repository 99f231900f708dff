//! How one model input is bound (the `models[i].inputs` of the file): by its own key or by
//! the one `*` pattern that matches it (a family of indexed inputs, `pin_error_mm_*`), to a
//! number (which the model may refuse, `check_constant`), to a parameter of the reducer
//! (`"reducer.KEY"`, a design value the model takes as an input) or to a named column of the
//! input space (an array's member by the star's index), whose unit must be the input's.

use rvtol_models::{ErrorModel, InputSpec};
use serde_json::Value;

use super::super::file::ScenarioFile;
use super::super::Binding;
use super::Compiler;
use crate::error::ScenarioError;

impl Compiler<'_> {
    /// The binding of the input at `position` of `model` (`input`) to `value` (written at
    /// `binding_path`; `index` the star's index when a pattern binds it): `None` when it
    /// names an element that could not be built (reported already).
    pub(super) fn bound_value(
        &self,
        model: &dyn ErrorModel,
        position: usize,
        input: &InputSpec,
        value: &Value,
        binding_path: &str,
        index: Option<u64>,
    ) -> Result<Option<Binding>, ScenarioError> {
        match value {
            serde_json::Value::Number(n) => {
                let v = n.as_f64().unwrap_or(f64::NAN);
                if !v.is_finite() {
                    Err(ScenarioError::new(binding_path, "must be a finite number"))
                } else {
                    model
                        .check_constant(position, v)
                        .map(|()| Some(Binding::Constant(v)))
                        .map_err(|reason| ScenarioError::new(binding_path, reason))
                }
            }
            serde_json::Value::String(name) if name.starts_with(REDUCER_BINDING) => {
                reducer_binding(self.file, name, binding_path).and_then(|v| {
                    model
                        .check_constant(position, v)
                        .map(|()| Some(Binding::Constant(v)))
                        .map_err(|reason| ScenarioError::new(binding_path, reason))
                })
            }
            serde_json::Value::String(name)
                if !self.column_by_name.contains_key(name) && !self.arrays.contains_key(name) =>
            {
                match self.output_binding(input, name, binding_path)? {
                    Some(binding) => Ok(Some(binding)),
                    None => self.column_binding(model, input, name, binding_path, index),
                }
            }
            serde_json::Value::String(name) => {
                self.column_binding(model, input, name, binding_path, index)
            }
            other => Err(ScenarioError::new(
                binding_path,
                format!("expected a number or a variable name, got {other}"),
            )),
        }
    }

    /// The binding of an input to the output `name` of a model above (a chain), `None`
    /// when no model's output has that name. The output's unit must be the input's.
    fn output_binding(
        &self,
        input: &InputSpec,
        name: &str,
        binding_path: &str,
    ) -> Result<Option<Binding>, ScenarioError> {
        if let Some(o) = self.outputs.iter().position(|output| output.name == name) {
            let unit = &self.outputs[o].unit;
            if input.unit != "any" && unit != &input.unit {
                return Err(ScenarioError::new(
                    binding_path,
                    format!(
                        "output {name:?} is in {unit} but the input wants {}: a chained output is not converted (declare the output in {} or the input in {unit})",
                        input.unit, input.unit
                    ),
                ));
            }
            return Ok(Some(Binding::Output(o)));
        }
        match self.outputs_below.get(name) {
            Some(model) if *model == self.models_bound => Err(ScenarioError::new(
                binding_path,
                format!("{name:?} is an output of this model: a model cannot read its own output"),
            )),
            Some(model) => Err(ScenarioError::new(
                binding_path,
                format!(
                    "{name:?} is an output of models[{model}], below this model: a model reads the outputs of the models above it (order the models so; a chain has no cycle)"
                ),
            )),
            None => Ok(None),
        }
    }

    /// The binding of an input to the input-space column `name` (or, with a pattern's
    /// index, to that member of the array `name`).
    fn column_binding(
        &self,
        model: &dyn ErrorModel,
        input: &InputSpec,
        name: &str,
        binding_path: &str,
        index: Option<u64>,
    ) -> Result<Option<Binding>, ScenarioError> {
        // A pattern bound to an array takes the member of its index; an
        // array's name alone names no single column. `None`: a broken
        // variable, reported already.
        let column = match (self.arrays.get(name), index) {
            (Some((_, members)), Some(k)) => {
                members.get(k as usize - 1).copied().map(Some).ok_or_else(|| {
                    ScenarioError::new(
                        binding_path,
                        format!(
                            "binds {:?} to member {k} of {name:?}, which has {} members",
                            input.name,
                            members.len()
                        ),
                    )
                })
            }
            (Some((_, members)), None) => Err(ScenarioError::new(
                binding_path,
                format!(
                    "{name:?} is an array of {} members: bind it with a pattern (\"{}_*\": {name:?}) or name one member ({name}_1 …)",
                    members.len(),
                    input.name
                ),
            )),
            (None, _) => match self.column_by_name.get(name) {
                Some(&column) => Ok(Some(column)),
                None if self.broken.contains(name) => Ok(None),
                None => Err(ScenarioError::new(
                    binding_path,
                    format!("no variable or part component named {name:?}"),
                )),
            },
        };
        match column {
            Ok(Some(column)) => match &self.columns[column].unit {
                // A unit rvtol does not know is the variable's mistake:
                // said at its `unit`.
                Some(unit)
                    if input.unit != "any"
                        && unit != &input.unit
                        && !super::super::units::is_known(unit)
                        && variable_index(self.file, name).is_some() =>
                {
                    Err(ScenarioError::new(
                        format!(
                            "variables[{}].unit",
                            variable_index(self.file, name).unwrap_or_default()
                        ),
                        format!(
                            "{unit:?} is not a unit rvtol knows ({}); {binding_path} wants {}",
                            super::super::units::known(),
                            input.unit
                        ),
                    ))
                }
                Some(unit)
                    if input.unit != "any"
                        && unit != &input.unit
                        && super::super::units::is_known(unit)
                        && !super::super::units::is_known(&input.unit) =>
                {
                    Err(ScenarioError::new(
                        binding_path,
                        format!(
                            "{name:?} is in {unit}, but the input's unit {:?} is not one rvtol converts ({}){}",
                            input.unit,
                            super::super::units::known(),
                            unit_hint(model, input, unit)
                        ),
                    ))
                }
                Some(unit) if input.unit != "any" && unit != &input.unit => {
                    Err(ScenarioError::new(
                        binding_path,
                        format!(
                            "{name:?} is in {unit}{} but the input wants {}{}",
                            if super::super::units::is_known(unit) {
                                String::new()
                            } else {
                                format!(
                                    ", which is not a unit rvtol knows ({})",
                                    super::super::units::known()
                                )
                            },
                            input.unit,
                            unit_hint(model, input, unit)
                        ),
                    ))
                }
                _ => Ok(Some(Binding::Column(column))),
            },
            Ok(None) => Ok(None),
            Err(err) => Err(err),
        }
    }
}

/// What a model whose input units the scenario declares says about a unit that does not
/// convert: where the input's unit is written.
fn unit_hint(model: &dyn ErrorModel, input: &InputSpec, unit: &str) -> String {
    match model.name() {
        "linear_stack" => format!(
            " (the stack's unit); a coefficient that reads it in {unit} says so in params.input_units.{}",
            input.name
        ),
        "expression" => format!(" (params.inputs.{})", input.name),
        _ => String::new(),
    }
}

/// How an input names a parameter of the `reducer` section (`"reducer.KEY"`): a design value
/// a model takes as an input (a modification the torsion curve also draws errors about).
pub(super) const REDUCER_BINDING: &str = "reducer.";

/// The value of the reducer parameter `name` (`reducer.KEY`) an input at `at` is bound to.
fn reducer_binding(file: &ScenarioFile, name: &str, at: &str) -> Result<f64, ScenarioError> {
    let key = &name[REDUCER_BINDING.len()..];
    let Some(reducer) = &file.reducer else {
        return Err(ScenarioError::new(
            at,
            format!("binds {name:?}, but the scenario has no reducer section"),
        ));
    };
    match reducer.params.get(key) {
        Some(serde_json::Value::Number(n)) => match n.as_f64() {
            Some(v) if v.is_finite() => Ok(v),
            _ => Err(ScenarioError::new(
                at,
                format!("{name} must be a finite number"),
            )),
        },
        Some(other) => Err(ScenarioError::new(
            at,
            format!("binds {name:?}, which is {other}, not a number"),
        )),
        None => Err(ScenarioError::new(
            at,
            format!("binds {name:?}, but reducer.params has no {key:?}"),
        )),
    }
}

/// The file index of the variable named `name`, or of the array whose member it is
/// (`name_K`).
fn variable_index(file: &ScenarioFile, name: &str) -> Option<usize> {
    file.variables.iter().find_map(|(i, variable)| {
        let member = variable.count.is_some()
            && name
                .strip_prefix(variable.name.as_str())
                .and_then(|rest| rest.strip_prefix('_'))
                .is_some_and(|k| k.parse::<u64>().is_ok());
        (variable.name == name || member).then_some(*i)
    })
}

/// A `*` pattern of a model's `inputs` (`"pin_radial_error_mm_*"`) split at its star; `None`
/// for a plain input name.
pub(super) fn pattern(key: &str) -> Option<(&str, &str)> {
    key.split_once('*')
}

/// A positive index written without leading zeros (`7`, `40`; not `07`, `0`, `x`): what a
/// pattern's star and a family's trailing `_N` stand for.
pub(super) fn positive_index(digits: &str) -> Option<u64> {
    let ok = !digits.is_empty()
        && !digits.starts_with('0')
        && digits.bytes().all(|b| b.is_ascii_digit());
    ok.then(|| digits.parse().ok()).flatten()
}

/// A name's stem and trailing index (`pin_radial_error_mm_7` → (`pin_radial_error_mm`, 7)).
pub(crate) fn trailing_index(name: &str) -> Option<(&str, u64)> {
    let (stem, digits) = name.rsplit_once('_')?;
    Some((stem, positive_index(digits)?))
}

/// The index an input name gives a pattern's star: the digits between its prefix and
/// suffix ([`positive_index`]).
fn pattern_index(prefix: &str, suffix: &str, input: &str) -> Option<u64> {
    positive_index(input.strip_prefix(prefix)?.strip_suffix(suffix)?)
}

/// How a model input is bound in the file: the bound value, the binding's JSON path, and
/// the star's index when a `*` pattern binds it.
pub(super) struct InputBinding<'a> {
    /// The bound value.
    pub(super) value: &'a serde_json::Value,
    /// The binding's JSON path.
    pub(super) path: String,
    /// The `*` pattern that binds the input and the index its star stands for.
    pub(super) pattern: Option<(&'a str, u64)>,
}

/// The binding of a model input: by its own key, or by the one `*` pattern that matches
/// it. An input bound twice (its own key and a pattern, or two patterns) is an error
/// naming both.
pub(super) fn input_binding<'a>(
    path: &str,
    inputs: &'a serde_json::Map<String, serde_json::Value>,
    input: &str,
) -> Result<Option<InputBinding<'a>>, ScenarioError> {
    let mut found = inputs.get(input).map(|value| InputBinding {
        value,
        path: format!("{path}.inputs.{input}"),
        pattern: None,
    });
    for (key, value) in inputs {
        let Some((prefix, suffix)) = pattern(key) else {
            continue;
        };
        let Some(index) = pattern_index(prefix, suffix, input) else {
            continue;
        };
        let key_path = format!("{path}.inputs.{key}");
        if let Some(earlier) = &found {
            return Err(ScenarioError::new(
                key_path,
                format!("binds {input:?}, which {} binds already", earlier.path),
            ));
        }
        found = Some(InputBinding {
            value,
            path: key_path,
            pattern: Some((key.as_str(), index)),
        });
    }
    Ok(found)
}

/// Names with runs of consecutive trailing indices collapsed (`pin_radial_error_mm_1` …
/// `_40` as `pin_radial_error_mm_{1..40}`), joined with commas: a model's inputs in one
/// readable line.
pub(super) fn indexed_summary(names: &[&str]) -> String {
    let split = trailing_index;
    let mut parts: Vec<String> = Vec::new();
    let mut i = 0;
    while i < names.len() {
        let mut j = i;
        if let Some((stem, first)) = split(names[i]) {
            while j + 1 < names.len()
                && split(names[j + 1]) == Some((stem, first + (j + 1 - i) as u64))
            {
                j += 1;
            }
            if j - i >= 2 {
                parts.push(format!("{stem}_{{{first}..{}}}", first + (j - i) as u64));
                i = j + 1;
                continue;
            }
        }
        parts.push(names[i].to_string());
        i += 1;
    }
    parts.join(", ")
}
