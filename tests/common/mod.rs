//! Helpers shared by the end-to-end tests: locating (building) the `rvtol` binary, running
//! it, and scenario files in the temporary directory that remove themselves.

#![allow(dead_code)]

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;

/// The workspace root (the parent of this package, `tests/`).
pub fn workspace_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("tests/ has a parent directory")
        .to_path_buf()
}

/// A shipped scenario's path as a command-line argument.
pub fn scenario(file: &str) -> String {
    workspace_dir()
        .join("scenarios")
        .join(file)
        .display()
        .to_string()
}

/// Path of the `rvtol` binary, built once per test process.
///
/// Binaries of another package are not exposed through `CARGO_BIN_EXE_*`, so the first
/// call runs `cargo build -q -p rvtol --bin rvtol` (with `--release` when this test is
/// built without debug assertions) and returns `<target>/<debug|release>/rvtol`, where
/// `<target>` is `CARGO_TARGET_DIR` (relative to the workspace when relative) or
/// `<workspace>/target`.
pub fn rvtol_binary() -> &'static Path {
    static BINARY: OnceLock<PathBuf> = OnceLock::new();
    BINARY.get_or_init(|| {
        let workspace = workspace_dir();
        let release = !cfg!(debug_assertions);
        let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
        let mut build = Command::new(cargo);
        build
            .current_dir(&workspace)
            .args(["build", "-q", "-p", "rvtol", "--bin", "rvtol"]);
        if release {
            build.arg("--release");
        }
        let status = build.status().expect("cannot start cargo to build rvtol");
        assert!(status.success(), "cargo build of rvtol failed: {status}");
        let target = match std::env::var_os("CARGO_TARGET_DIR") {
            Some(dir) => workspace.join(dir),
            None => workspace.join("target"),
        };
        let binary = target
            .join(if release { "release" } else { "debug" })
            .join(format!("rvtol{}", std::env::consts::EXE_SUFFIX));
        assert!(binary.is_file(), "no rvtol binary at {}", binary.display());
        binary
    })
}

/// Runs `rvtol` with `args` and returns its exit status and captured output.
pub fn run_rvtol<S: AsRef<OsStr>>(args: &[S]) -> Output {
    Command::new(rvtol_binary())
        .args(args)
        .output()
        .expect("cannot start rvtol")
}

/// A scenario file in the temporary directory, removed when dropped.
pub struct TempScenario {
    path: PathBuf,
}

impl TempScenario {
    /// Writes `contents` to `<temp>/rvtol-<label>-<pid>.json`; `label` must be unique
    /// among the tests of one process.
    pub fn new(label: &str, contents: &str) -> Self {
        let path = std::env::temp_dir().join(format!("rvtol-{label}-{}.json", std::process::id()));
        std::fs::write(&path, contents)
            .unwrap_or_else(|err| panic!("cannot write {}: {err}", path.display()));
        TempScenario { path }
    }

    /// Its path.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for TempScenario {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
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
