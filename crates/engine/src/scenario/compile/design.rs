//! A design value's path checked against the parsed scenario file
//! ([`crate::scenario::design`]): the reducer's parameter, the model's parameter (not one
//! the reducer gives) or the model's input bound to a number or to `reducer.KEY`, with its
//! value in the file.

use serde_json::Value;

use super::super::design::{parse_target, DesignValue, Target};
use super::super::file::ScenarioFile;
use super::REDUCER_BINDING;

impl DesignValue {
    /// The design value at `path` of the scenario `text` (JSON, data files written in);
    /// the error says why the path names none.
    pub fn parse(text: &str, path: &str) -> Result<DesignValue, String> {
        let (file, _) = super::super::file::parse(text).map_err(|err| err.to_string())?;
        design_value(&file, path)
    }
}

/// The design value at `path` of the parsed scenario `file`.
pub(crate) fn design_value(file: &ScenarioFile, path: &str) -> Result<DesignValue, String> {
    let target = parse_target(path)?;
    let reducer_params = file.reducer.as_ref().map(|r| &r.params);
    let model = |i: usize| {
        (file.models.iter())
            .find(|(k, _)| *k == i)
            .map(|(_, m)| m)
            .ok_or_else(|| format!("the scenario has no models[{i}]"))
    };
    let number = |value: &Value, what: &str| {
        value
            .as_f64()
            .map(Some)
            .ok_or_else(|| format!("{path}: {what} is {value}, not a number"))
    };
    let current = match &target {
        Target::Reducer(key) => {
            let value = reducer_params
                .and_then(|p| p.get(key))
                .ok_or_else(|| format!("the scenario's reducer has no parameter {key:?}"))?;
            number(value, "the reducer's value")?
        }
        Target::Param(i, key) => {
            if reducer_params.is_some_and(|p| p.contains_key(key)) {
                return Err(format!(
                    "the reducer gives {key:?} to every model that takes it: set reducer.params.{key}"
                ));
            }
            match model(*i)?.params.get(key) {
                Some(value) => number(value, "the parameter")?,
                None => None,
            }
        }
        Target::Input(i, name) => {
            let binding = (model(*i)?.inputs.get(name))
                .ok_or_else(|| format!("models[{i}] binds no input {name:?}"))?;
            match binding {
                Value::String(s) => match s.strip_prefix(REDUCER_BINDING) {
                    Some(key) => match reducer_params.and_then(|p| p.get(key)) {
                        Some(value) => number(value, "the reducer's value")?,
                        None => None,
                    },
                    None => {
                        return Err(format!(
                            "models[{i}].inputs.{name} is bound to the random quantity {s:?}, not a design value: give the input a number (or bind it to reducer.KEY) to set it"
                        ))
                    }
                },
                other => number(other, "the input")?,
            }
        }
    };
    Ok(DesignValue {
        path: path.to_string(),
        current,
        target,
    })
}
