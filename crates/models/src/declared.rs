//! Outputs a scenario declares itself, for the models whose outputs are not fixed (an
//! expression model's formulas, a Python function's results): each an object with a
//! `unit`, an optional `kind` and `description`, and the fields its model reads (an
//! expression's `formula`). One reading for both, so that both refuse the same mistakes
//! with the same words.

use crate::params::{ModelError, ParamValue};
use crate::{OutputKind, OutputSpec};

/// The fields every declared output may have.
const COMMON: [&str; 3] = ["unit", "kind", "description"];

/// The output `name` declared at `path` by `value`: its spec (`description` the model's
/// words for it) and its object's fields, for the caller's own keys `extra` (the only
/// others allowed).
pub fn declared_output(
    name: &str,
    path: &str,
    value: &ParamValue,
    extra: &[&str],
    description: &'static str,
) -> Result<(OutputSpec, Vec<(String, ParamValue)>), ModelError> {
    let fields_named = (extra.iter().chain(&COMMON))
        .map(|k| format!("\"{k}\""))
        .collect::<Vec<_>>()
        .join(", ");
    // An object of numbers only (`{}` among them) parses as named numbers.
    let fields: Vec<(String, ParamValue)> = match value {
        ParamValue::Object(fields) => fields.clone(),
        ParamValue::Named(numbers) => (numbers.iter())
            .map(|(k, v)| (k.clone(), ParamValue::Number(*v)))
            .collect(),
        other => {
            return Err(ModelError::new(
                path,
                format!(
                    "expected an object with {fields_named}, got {}",
                    other.kind()
                ),
            ))
        }
    };
    let field = |key: &str| fields.iter().find(|(k, _)| k == key).map(|(_, v)| v);
    if let Some((key, _)) =
        (fields.iter()).find(|(k, _)| !extra.contains(&k.as_str()) && !COMMON.contains(&k.as_str()))
    {
        return Err(ModelError::new(
            format!("{path}.{key}"),
            format!("unknown field; an output has {fields_named}"),
        ));
    }
    let unit = match field("unit") {
        Some(unit) => unit_text(&format!("{path}.unit"), unit)?,
        None => {
            return Err(ModelError::new(
                path,
                "needs a \"unit\" (\"1\" for a number without one)",
            ))
        }
    };
    let kind = match field("kind") {
        None => OutputKind::Continuous,
        Some(ParamValue::Text(k)) if k == "continuous" => OutputKind::Continuous,
        Some(ParamValue::Text(k)) if k == "indicator" => OutputKind::Indicator,
        Some(other) => {
            return Err(ModelError::new(
                format!("{path}.kind"),
                format!(
                    "{} is no kind: \"continuous\" (the default) or \"indicator\" (a 0/1 event)",
                    match other {
                        ParamValue::Text(k) => format!("{k:?}"),
                        other => other.kind().to_string(),
                    }
                ),
            ))
        }
    };
    match field("description") {
        None | Some(ParamValue::Text(_)) => {}
        Some(other) => {
            return Err(ModelError::new(
                format!("{path}.description"),
                format!("expected a string, got {}", other.kind()),
            ))
        }
    }
    let spec = OutputSpec {
        name: name.to_string(),
        unit,
        description,
        kind,
        condition: None,
    };
    Ok((spec, fields))
}

/// A unit as written: a non-empty string.
pub fn unit_text(path: &str, value: &ParamValue) -> Result<String, ModelError> {
    match value {
        ParamValue::Text(unit) if !unit.trim().is_empty() => Ok(unit.clone()),
        ParamValue::Text(_) => Err(ModelError::new(
            path,
            "the unit is empty (\"1\" for a number without one)",
        )),
        other => Err(ModelError::new(
            path,
            format!("expected a unit (a string), got {}", other.kind()),
        )),
    }
}
