//! `rvtol init MODEL`: a complete, valid scenario for one model to start from. Every
//! parameter appears with the value of the model's representative example (or its
//! default), and every input is bound to a variable of its own name and unit, at the
//! example's design value (zero for a deviation) with zero spread: a placeholder the user
//! replaces with the design's tolerances (scenarios/README.md lists the distributions).
//!
//! What `init` writes must validate: the given parameters are checked as `validate`
//! checks a scenario's (the skeleton is loaded before it is returned, and a parameter
//! the model takes as a number must be one even where this model's reading does not read
//! it), each problem named by its `params.KEY` path.

use rvtol_models::ParamValue;
use serde_json::{json, Map, Value};

/// A parameter value as JSON.
fn to_json(value: &ParamValue) -> Value {
    match value {
        ParamValue::Number(x) => json!(x),
        ParamValue::Text(text) => json!(text),
        ParamValue::Named(entries) => Value::Object(
            entries
                .iter()
                .map(|(k, x)| (k.clone(), json!(x)))
                .collect::<Map<String, Value>>(),
        ),
        ParamValue::Object(entries) => Value::Object(
            entries
                .iter()
                .map(|(k, v)| (k.clone(), to_json(v)))
                .collect::<Map<String, Value>>(),
        ),
    }
}

/// The skeleton scenario of the model `name` as pretty JSON, or the list of models when
/// there is none of that name.
pub fn skeleton(name: &str) -> Result<String, String> {
    skeleton_with(name, &Map::new())
}

/// The skeleton of the model `name` with some parameters given (`rvtol init --param`):
/// they replace the example's values, and the inputs are those of the model so built (a
/// transmission error with `pin_position_errors` on has an input per pin).
pub fn skeleton_with(name: &str, given: &Map<String, Value>) -> Result<String, String> {
    let Some(entry) = rvtol_models::find(name) else {
        let names: Vec<&str> = rvtol_models::all().iter().map(|e| e.name).collect();
        return Err(format!(
            "no model {name:?} (models: {}; `rvtol models` describes them)",
            names.join(", ")
        ));
    };
    let mut example = (entry.example_params)();
    if !given.is_empty() {
        // A parameter the model takes as a number (the example gives one, or it has a
        // default) given as something else: a reading that does not read it would carry
        // it through unchecked.
        for (key, value) in given {
            let numeric = match example.entries().find(|(k, _)| k == key) {
                Some((_, value)) => matches!(value, ParamValue::Number(_)),
                None => entry
                    .params
                    .iter()
                    .any(|spec| spec.name == key && spec.default.is_some()),
            };
            if numeric && !value.is_number() {
                return Err(format!(
                    "params.{key}: must be a number, got {}",
                    if value.is_string() {
                        "a string"
                    } else {
                        "something else"
                    }
                ));
            }
        }
        let given = super::compile::model_params("params", given).map_err(|err| err.to_string())?;
        // An expression's given formulas are a model of their own: the example's
        // inputs, `let`s and outputs do not mix into them.
        if entry.name == "expression" {
            example = rvtol_models::ModelParams::new();
        }
        for (key, value) in given.entries() {
            example.insert(key.to_string(), value.clone());
        }
    }
    let model =
        (entry.build)(&example).map_err(|err| format!("params.{}: {}", err.key, err.reason))?;
    // Parameters in the model's order, then any other key of the example.
    let mut params = Map::new();
    for spec in entry.params {
        if let Some((_, value)) = example.entries().find(|(k, _)| *k == spec.name) {
            params.insert(spec.name.into(), to_json(value));
        } else if let Some(default) = spec.default {
            params.insert(spec.name.into(), json!(default));
        }
    }
    for (key, value) in example.entries() {
        if !params.contains_key(key) {
            params.insert(key.into(), to_json(value));
        }
    }
    let inputs = model.inputs();
    let design_value = |input: &str| {
        entry
            .example_inputs
            .iter()
            .find(|(key, _)| *key == input)
            .map_or(0.0, |(_, value)| *value)
    };
    // A family of indexed inputs (`pin_radial_error_mm_1` … `_40`, one unit, one design
    // value) is one variable array bound by a `*` pattern.
    let stem_of = super::compile::trailing_index;
    let mut variables: Vec<Value> = Vec::new();
    let mut bindings = Map::new();
    let mut i = 0;
    while i < inputs.len() {
        let input = &inputs[i];
        if let Some((stem, 1)) = stem_of(&input.name) {
            let mut n = 1;
            while i + n < inputs.len()
                && stem_of(&inputs[i + n].name) == Some((stem, n as u64 + 1))
                && inputs[i + n].unit == input.unit
                && design_value(&inputs[i + n].name) == design_value(&input.name)
            {
                n += 1;
            }
            let whole = inputs
                .iter()
                .filter(|other| stem_of(&other.name).is_some_and(|(s, _)| s == stem))
                .count()
                == n;
            if n >= 3 && whole {
                variables.push(json!({
                    "name": stem,
                    "unit": input.unit,
                    "count": n,
                    "description": format!(
                        "{}; one member per index, {stem}_1 … {stem}_{n}",
                        input.description
                    ),
                    "distribution": { "normal": { "mean": design_value(&input.name), "sd": 0.0 } }
                }));
                bindings.insert(format!("{stem}_*"), json!(stem));
                i += n;
                continue;
            }
        }
        variables.push(json!({
            "name": input.name,
            "unit": input.unit,
            "description": input.description,
            "distribution": { "normal": { "mean": design_value(&input.name), "sd": 0.0 } }
        }));
        bindings.insert(input.name.clone(), json!(input.name));
        i += 1;
    }
    let outputs: Vec<String> = model
        .outputs()
        .iter()
        .map(|o| format!("{} ({})", o.name, o.unit))
        .collect();
    let scenario = json!({
        "name": format!("{name}-skeleton"),
        "description": format!(
            "Written by rvtol init {name}: {}. Parameters at the example design's values (or \
             their defaults); every input is a variable at the example's design value (0 for \
             a deviation) with no spread, to be replaced by the design's tolerances (scenarios/README.md: normal, tolerance_band, uniform, \
             triangular, truncated normal, folded_normal, rayleigh, lognormal, or a 6-DOF \
             part); a family of indexed inputs is one variable array (`count`, bound by a \
             `*` pattern). Outputs: {}.",
            entry.summary,
            outputs.join(", ")
        ),
        "samples": 100000,
        "seed": 1,
        "variables": variables,
        "models": [ { "model": name, "params": params, "inputs": bindings } ]
    });
    let mut text = serde_json::to_string_pretty(&scenario).expect("a JSON value serialises");
    text.push('\n');
    // The skeleton as `validate` takes it: the ranges every scenario's numbers must keep
    // (a parameter of 1e308 builds a model but is no scenario's).
    super::Scenario::from_json(&text, name).map_err(|err| {
        match err.path.strip_prefix("models[0].") {
            Some(path) if path.starts_with("params") => format!("{path}: {}", err.message),
            _ => format!(
                "the skeleton of these parameters does not validate: {}",
                err
            ),
        }
    })?;
    Ok(text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_parameter_validate_would_refuse_is_refused_naming_it() {
        for entry in rvtol_models::all() {
            assert!(skeleton(entry.name).is_ok(), "{}", entry.name);
            for spec in entry.params {
                let mut given = Map::new();
                given.insert(spec.name.to_string(), json!(1e308));
                let err = skeleton_with(entry.name, &given).unwrap_err();
                // This parameter, or another the model checks it against (a stage's
                // eccentricity against its pin-circle radius).
                assert!(
                    err.starts_with("params.") && !err.contains('\n'),
                    "{} {}: {err}",
                    entry.name,
                    spec.name
                );
            }
        }
        let mut given = Map::new();
        given.insert("output_pin_circle_radius_mm".into(), json!("abc"));
        assert_eq!(
            skeleton_with("transmission_error", &given).unwrap_err(),
            "params.output_pin_circle_radius_mm: must be a number, got a string"
        );
    }
}
