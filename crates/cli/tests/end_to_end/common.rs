//! Helpers shared by the end-to-end tests: the `rvtol` binary of this package, running it,
//! scenario files in the temporary directory that remove themselves, the workspace's
//! files.

#![allow(dead_code)]

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The workspace root (two folders above this package, `crates/cli`).
pub fn workspace_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .expect("the workspace folder exists")
}

/// A shipped scenario's path as a command-line argument.
pub fn scenario(file: &str) -> String {
    workspace_dir()
        .join("scenarios")
        .join(file)
        .display()
        .to_string()
}

/// Path of the `rvtol` binary: Cargo builds it for this package's tests, in the profile
/// of the test, and names it in `CARGO_BIN_EXE_rvtol`.
pub fn rvtol_binary() -> &'static Path {
    Path::new(env!("CARGO_BIN_EXE_rvtol"))
}

/// Runs `rvtol` with `args` and returns its exit status and captured output.
pub fn run_rvtol<S: AsRef<OsStr>>(args: &[S]) -> Output {
    Command::new(rvtol_binary())
        .args(args)
        .output()
        .expect("cannot start rvtol")
}

/// What `rvtol` prints on stdout with `args`, the command asserted to succeed.
pub fn stdout_of(args: &[&str]) -> Vec<u8> {
    let out = run_rvtol(args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out.stdout
}

/// The JSON report `rvtol` prints with `args` (which send it to stdout), the command
/// asserted to succeed.
pub fn json_of(args: &[&str]) -> serde_json::Value {
    serde_json::from_slice(&stdout_of(args)).expect("a JSON report")
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
