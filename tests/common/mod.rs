//! Helpers shared by the library tests: the workspace's folder and the parameters a
//! shipped scenario hands its first model. (The end-to-end tests, which run the `rvtol`
//! binary, have their own helpers in crates/cli/tests/end_to_end/common.rs.)

use std::path::{Path, PathBuf};

/// The workspace root (the parent of this package, `tests/`).
pub fn workspace_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("tests/ has a parent directory")
        .to_path_buf()
}

/// The parameters the engine hands to the first model of a shipped scenario: the model's
/// own and those of the scenario's reducer (a `reducer` section, or the reducer file it
/// names) that the model takes.
pub fn model_params(file: &str) -> rvtol_models::ModelParams {
    let path = workspace_dir().join("scenarios").join(file);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let model = &json["models"][0];
    let entry = rvtol_models::find(model["model"].as_str().unwrap()).unwrap();
    let mut reducer = json["reducer"].clone();
    if let Some(name) = reducer["file"].as_str() {
        let reducer_path = path.parent().unwrap().join(name);
        reducer = serde_json::from_str(&std::fs::read_to_string(reducer_path).unwrap()).unwrap();
    }
    let mut params = rvtol_models::ModelParams::new();
    let mut add = |key: &str, value: &serde_json::Value| {
        let value = match value {
            serde_json::Value::String(text) => rvtol_models::ParamValue::Text(text.clone()),
            other => rvtol_models::ParamValue::Number(other.as_f64().unwrap()),
        };
        params.insert(key.to_string(), value);
    };
    if let Some(shared) = reducer["params"].as_object() {
        for (key, value) in shared {
            if entry.params.iter().any(|spec| spec.name == key) {
                add(key, value);
            }
        }
    }
    for (key, value) in model["params"].as_object().unwrap() {
        add(key, value);
    }
    params
}
