//! The `reducer` section and the models built from their parameters: a reducer is
//! described once (`reducer.params`, with the `sources` of its values) and each model
//! takes the parameters it knows from it (a key a model gives itself as well, or one no
//! model takes, is refused). Built before the variables, whose units follow the inputs
//! they feed.

use std::collections::{BTreeMap, BTreeSet};

use rvtol_models::{ModelEntry, ModelParams, ParamValue};

use super::super::file::{ModelFile, ReducerFile, ScenarioFile};
use super::bindings::{input_binding, InputBinding, REDUCER_BINDING};
use super::models::BuiltModel;
use super::Compiler;
use crate::error::ScenarioError;

/// Builds every model of the file (its problems are reported by the binding pass), checks
/// the `reducer` section and notes the units of the inputs each variable feeds.
pub(super) fn compile(compiler: &mut Compiler) {
    let file = compiler.file;
    let built: Vec<BuiltModel> = file
        .models
        .iter()
        .map(|(i, model_file)| {
            build_model(&format!("models[{i}]"), model_file, file.reducer.as_ref())
        })
        .collect();
    compiler.problems.extend(check_reducer(file));
    compiler.bound_units = bound_input_units(file, &built);
    compiler.built_models = built;
}

/// The model of `model_file` (at `path`) built from its parameters and those of the
/// reducer it knows.
fn build_model(path: &str, model_file: &ModelFile, reducer: Option<&ReducerFile>) -> BuiltModel {
    let Some(entry) = rvtol_models::find(&model_file.model) else {
        let known: Vec<&str> = rvtol_models::all().iter().map(|e| e.name).collect();
        return Err(vec![ScenarioError::new(
            format!("{path}.model"),
            format!(
                "unknown model {:?}; known models: {}",
                model_file.model,
                known.join(", ")
            ),
        )]);
    };
    let mut params =
        model_params(&format!("{path}.params"), &model_file.params).map_err(|e| vec![e])?;
    // The reducer's parameters this model knows, unless it gives them itself (an error:
    // a reducer is defined once).
    let mut shared = BTreeSet::new();
    if let Some(reducer) = reducer {
        let given = model_params("reducer.params", &reducer.params).map_err(|e| vec![e])?;
        for (key, value) in given.entries() {
            if !entry.params.iter().any(|spec| spec.name == key) {
                continue;
            }
            if model_file.params.contains_key(key) {
                return Err(vec![ScenarioError::new(
                    format!("{path}.params.{key}"),
                    "also given in reducer.params: a reducer is defined once, leave it out here",
                )]);
            }
            params.insert(key.to_string(), value.clone());
            shared.insert(key.to_string());
        }
    }
    // Every problem the build found (an expression names each formula's).
    let model = (entry.build)(&params).map_err(|err| {
        (err.all())
            .map(|err| {
                let section = if shared.contains(&err.key) {
                    "reducer"
                } else {
                    path
                };
                ScenarioError::new(format!("{section}.params.{}", err.key), &err.reason)
            })
            .collect::<Vec<_>>()
    })?;
    Ok((entry, model))
}

/// The `reducer` section's own checks: each of its parameters is taken by some model of
/// the scenario (by some model of rvtol when the reducer comes from a shared file, which
/// defines it for every model), and each source names one of its parameters and is a text.
fn check_reducer(file: &ScenarioFile) -> Vec<ScenarioError> {
    let Some(reducer) = &file.reducer else {
        return Vec::new();
    };
    let entries: Vec<&ModelEntry> = file
        .models
        .iter()
        .filter_map(|(_, model)| rvtol_models::find(&model.model))
        .collect();
    let mut problems = Vec::new();
    // Keys an input is bound to (`reducer.KEY`) are taken too.
    let bound: BTreeSet<&str> = file
        .models
        .iter()
        .flat_map(|(_, model)| model.inputs.values())
        .filter_map(|value| value.as_str()?.strip_prefix(REDUCER_BINDING))
        .collect();
    let takes = |e: &&ModelEntry, key: &str| {
        bound.contains(key) || e.params.iter().any(|spec| spec.name == key)
    };
    for key in reducer.params.keys() {
        if reducer.file.is_some() {
            if !rvtol_models::all().iter().any(|e| takes(&e, key)) {
                problems.push(ScenarioError::new(
                    format!("reducer.params.{key}"),
                    format!(
                        "no model of rvtol takes it (in {}; `rvtol models` lists their parameters)",
                        reducer.file.as_deref().unwrap_or_default()
                    ),
                ));
            }
            continue;
        }
        if !entries.iter().any(|e| takes(e, key)) {
            let names: Vec<&str> = entries.iter().map(|e| e.name).collect();
            problems.push(ScenarioError::new(
                format!("reducer.params.{key}"),
                format!(
                    "no model of this scenario takes it (models: {}; `rvtol models` lists their parameters)",
                    names.join(", ")
                ),
            ));
        }
    }
    for (key, source) in &reducer.sources {
        if !reducer.params.contains_key(key) {
            problems.push(ScenarioError::new(
                format!("reducer.sources.{key}"),
                "not a key of reducer.params: a source says where a parameter's value comes from",
            ));
        } else if !source.is_string() {
            problems.push(ScenarioError::new(
                format!("reducer.sources.{key}"),
                format!("must be a text (a document, a reference, or an estimate and its rule), got {source}"),
            ));
        }
    }
    problems
}

/// Per variable name, the units of the model inputs it is bound to, each with the binding's
/// JSON path. Models that do not build are left out here: the binding pass reports them.
fn bound_input_units(
    file: &ScenarioFile,
    built: &[BuiltModel],
) -> BTreeMap<String, Vec<(String, String)>> {
    let mut units: BTreeMap<String, Vec<(String, String)>> = BTreeMap::new();
    for ((i, model_file), built) in file.models.iter().zip(built) {
        let Ok((_, model)) = built else {
            continue;
        };
        for input in model.inputs() {
            let binding = input_binding(&format!("models[{i}]"), &model_file.inputs, &input.name);
            if let Ok(Some(InputBinding {
                value: serde_json::Value::String(name),
                path,
                ..
            })) = binding
            {
                units
                    .entry(name.clone())
                    .or_default()
                    .push((input.unit.clone(), path));
            }
        }
    }
    units
}

/// A model's parameters as written (numbers, texts, objects of named numbers, and objects
/// of those, the formulas of an `expression`), each at its JSON path under `path`.
pub(crate) fn model_params(
    path: &str,
    map: &serde_json::Map<String, serde_json::Value>,
) -> Result<ModelParams, ScenarioError> {
    let mut params = ModelParams::new();
    for (key, value) in map {
        params.insert(
            key.clone(),
            param_value(&format!("{path}.{key}"), value, 0)?,
        );
    }
    Ok(params)
}

/// Deepest nesting of objects a model's parameters take (an expression's output is an
/// object in an object).
const MOST_PARAM_DEPTH: usize = 3;

/// One parameter value at `path`, nested `depth` objects deep: an object of numbers only
/// is [`ParamValue::Named`] (a stack's coefficients), any other object an
/// [`ParamValue::Object`].
fn param_value(
    path: &str,
    value: &serde_json::Value,
    depth: usize,
) -> Result<ParamValue, ScenarioError> {
    Ok(match value {
        serde_json::Value::Number(n) => ParamValue::Number(n.as_f64().unwrap_or(f64::NAN)),
        serde_json::Value::String(s) => ParamValue::Text(s.clone()),
        serde_json::Value::Object(entries) if depth < MOST_PARAM_DEPTH => {
            if let Some(named) = entries
                .iter()
                .map(|(name, v)| Some((name.clone(), v.as_f64()?)))
                .collect::<Option<Vec<_>>>()
            {
                ParamValue::Named(named)
            } else {
                let mut object = Vec::with_capacity(entries.len());
                for (name, v) in entries {
                    object.push((
                        name.clone(),
                        param_value(&format!("{path}.{name}"), v, depth + 1)?,
                    ));
                }
                ParamValue::Object(object)
            }
        }
        other => {
            return Err(ScenarioError::new(
                path,
                format!("expected a number, a string or an object of those, got {other}"),
            ))
        }
    })
}
