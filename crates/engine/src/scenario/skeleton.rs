//! `rvtol init MODEL`: a complete, valid scenario for one model to start from. Every
//! parameter appears with the value of the model's representative example (or its
//! default), and every input is bound to a variable of its own name and unit, at the
//! example's design value (zero for a deviation) with zero spread: a placeholder the user
//! replaces with the design's tolerances (scenarios/README.md lists the distributions).

use rvtol_models::ParamValue;
use serde_json::{json, Map, Value};

/// The skeleton scenario of the model `name` as pretty JSON, or the list of models when
/// there is none of that name.
pub fn skeleton(name: &str) -> Result<String, String> {
    let Some(entry) = rvtol_models::find(name) else {
        let names: Vec<&str> = rvtol_models::all().iter().map(|e| e.name).collect();
        return Err(format!(
            "no model {name:?} (models: {}; `rvtol models` describes them)",
            names.join(", ")
        ));
    };
    let example = (entry.example_params)();
    let model = (entry.build)(&example)
        .map_err(|err| format!("the example of {name} does not build: {err}"))?;
    let to_json = |value: &ParamValue| match value {
        ParamValue::Number(x) => json!(x),
        ParamValue::Text(text) => json!(text),
        ParamValue::Named(entries) => Value::Object(
            entries
                .iter()
                .map(|(k, x)| (k.clone(), json!(x)))
                .collect::<Map<String, Value>>(),
        ),
    };
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
    let variables: Vec<Value> = inputs
        .iter()
        .map(|input| {
            let mean = entry
                .example_inputs
                .iter()
                .find(|(key, _)| *key == input.name)
                .map_or(0.0, |(_, value)| *value);
            json!({
                "name": input.name,
                "unit": input.unit,
                "description": input.description,
                "distribution": { "normal": { "mean": mean, "sd": 0.0 } }
            })
        })
        .collect();
    let bindings: Map<String, Value> = inputs
        .iter()
        .map(|input| (input.name.clone(), json!(input.name)))
        .collect();
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
             part). Outputs: {}.",
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
    Ok(text)
}
