//! Design values a command may set in a scenario's text: an allocation lever's candidates
//! and a sweep's grid. Three kinds of path name one:
//!
//! - `reducer.params.KEY`: a parameter of the reducer, which every model that knows the key
//!   takes and every input bound to `reducer.KEY` reads (one reducer, one geometry: the
//!   lever for a design value the reducer defines, such as `shift_modification_mm`);
//! - `models[i].params.KEY`: a parameter of one model (the number of pin classes of
//!   selective fitting); not one the reducer gives, which is set there;
//! - `models[i].inputs.NAME`: a model input bound to a number or to `reducer.KEY` (a design
//!   value of that model alone); an input bound to a random part or variable is not a
//!   design value and is refused.
//!
//! Setting one writes the number into the scenario's JSON document (with its data files
//! written in); the text is then loaded as any scenario, so every check of a scenario
//! holds for each value. The path is checked against the scenario (`DesignValue::parse`,
//! with the reason when it names no design value) by `compile/design.rs`.

use serde_json::Value;

use crate::error::ScenarioError;

/// Where a design value lives in the scenario's document.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Target {
    /// `reducer.params.KEY`.
    Reducer(String),
    /// `models[i].params.KEY`.
    Param(usize, String),
    /// `models[i].inputs.NAME`.
    Input(usize, String),
}

/// A design value of a scenario, named by its path (checked against the scenario).
#[derive(Debug, Clone, PartialEq)]
pub struct DesignValue {
    /// The path as written (`reducer.params.shift_modification_mm`).
    pub path: String,
    /// Its value in the scenario as written, when it gives one (a model parameter left at
    /// the model's default has none).
    pub current: Option<f64>,
    pub(crate) target: Target,
}

pub(crate) const EXAMPLES: &str =
    "\"reducer.params.KEY\", \"models[0].params.KEY\" or \"models[0].inputs.NAME\"";

impl DesignValue {
    /// Writes `value` into the scenario document `document` (the JSON the path was
    /// checked against).
    pub fn set(&self, document: &mut Value, value: f64) -> Result<(), ScenarioError> {
        let slot = match &self.target {
            Target::Reducer(key) => document
                .get_mut("reducer")
                .and_then(|r| r.get_mut("params"))
                .and_then(Value::as_object_mut)
                .map(|params| (params, key)),
            Target::Param(model, key) => model_object(document, *model, "params").map(|p| (p, key)),
            Target::Input(model, name) => {
                model_object(document, *model, "inputs").map(|p| (p, name))
            }
        };
        let (object, key) = slot.ok_or_else(|| {
            ScenarioError::new(&self.path, "the scenario's document has no such place")
        })?;
        object.insert(key.clone(), Value::from(value));
        Ok(())
    }
}

/// The `section` object (`params` or `inputs`) of model `model`, created when missing.
fn model_object<'d>(
    document: &'d mut Value,
    model: usize,
    section: &str,
) -> Option<&'d mut serde_json::Map<String, Value>> {
    let object = document
        .get_mut("models")?
        .get_mut(model)?
        .as_object_mut()?;
    object
        .entry(section)
        .or_insert_with(|| Value::Object(Default::default()))
        .as_object_mut()
}

/// The target a path names, by its form alone.
pub(crate) fn parse_target(path: &str) -> Result<Target, String> {
    let not = || format!("{path:?} is not a design value path such as {EXAMPLES}");
    let plain = |key: &str| !key.is_empty() && !key.contains(['.', '[', ']']);
    if let Some(key) = path.strip_prefix("reducer.params.") {
        return plain(key)
            .then(|| Target::Reducer(key.into()))
            .ok_or_else(not);
    }
    let (index, rest) = (path.strip_prefix("models["))
        .and_then(|rest| rest.split_once("]."))
        .ok_or_else(not)?;
    let index: usize = index.parse().map_err(|_| not())?;
    match rest.split_once('.') {
        Some(("params", key)) if plain(key) => Ok(Target::Param(index, key.into())),
        Some(("inputs", name)) if plain(name) => Ok(Target::Input(index, name.into())),
        _ => Err(not()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_parse_by_their_form() {
        assert_eq!(
            parse_target("reducer.params.shift_modification_mm"),
            Ok(Target::Reducer("shift_modification_mm".into()))
        );
        assert_eq!(
            parse_target("models[2].params.pin_classes"),
            Ok(Target::Param(2, "pin_classes".into()))
        );
        assert_eq!(
            parse_target("models[0].inputs.shift_modification_mm"),
            Ok(Target::Input(0, "shift_modification_mm".into()))
        );
        for bad in [
            "models[0].params.",
            "models[x].params.a",
            "models[0].other.a",
            "reducer.params.a.b",
            "params.a",
            "",
        ] {
            assert!(
                parse_target(bad)
                    .unwrap_err()
                    .contains("is not a design value path"),
                "{bad}"
            );
        }
    }
}
