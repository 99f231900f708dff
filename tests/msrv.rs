//! The minimum Rust version the workspace states (`rust-version` in Cargo.toml) must be at
//! least what the locked dependencies declare they need: a claim below it is false, since
//! the lockfile would not build with that toolchain. The machines that run the tests cannot
//! download another toolchain, so the check reads the dependencies' own `rust-version`
//! from `cargo metadata` instead of building with an older compiler.

use crate::common;

use std::process::Command;

use common::workspace_dir;
use serde_json::Value;

/// "1.88" or "1.85.0" as (major, minor, patch).
fn version(text: &str) -> (u64, u64, u64) {
    let mut parts = text
        .split('.')
        .map(|p| p.parse::<u64>().expect("numeric version"));
    (
        parts.next().expect("major"),
        parts.next().unwrap_or(0),
        parts.next().unwrap_or(0),
    )
}

#[test]
fn stated_rust_version_covers_every_locked_dependency() {
    // The packages of this machine's platform: a build downloads no other, so the
    // platform-specific dependencies of other targets (plotters' wasm ones) are not on
    // disk, and no toolchain here would build them.
    let rustc = std::env::var_os("RUSTC").unwrap_or_else(|| "rustc".into());
    let verbose = Command::new(rustc)
        .arg("-vV")
        .output()
        .expect("run rustc -vV");
    let host = String::from_utf8_lossy(&verbose.stdout)
        .lines()
        .find_map(|line| line.strip_prefix("host: ").map(str::to_string))
        .expect("rustc -vV names the host");
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let output = Command::new(cargo)
        .current_dir(workspace_dir())
        .args(["metadata", "--format-version", "1", "--locked", "--offline"])
        .args(["--filter-platform", &host])
        .output()
        .expect("run cargo metadata");
    assert!(
        output.status.success(),
        "cargo metadata failed: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    let metadata: Value = serde_json::from_slice(&output.stdout).expect("metadata JSON");
    let members: Vec<&str> = metadata["workspace_members"]
        .as_array()
        .expect("members")
        .iter()
        .filter_map(Value::as_str)
        .collect();
    let packages = metadata["packages"].as_array().expect("packages");
    let stated: Vec<(u64, u64, u64)> = packages
        .iter()
        .filter(|p| members.contains(&p["id"].as_str().unwrap_or("")))
        .map(|p| {
            version(
                p["rust_version"]
                    .as_str()
                    .expect("members state rust-version"),
            )
        })
        .collect();
    assert!(!stated.is_empty());
    let claimed = stated.iter().min().copied().expect("a member");
    let (needed, by) = packages
        .iter()
        .filter(|p| !members.contains(&p["id"].as_str().unwrap_or("")))
        .filter_map(|p| {
            let rust = p["rust_version"].as_str()?;
            Some((
                version(rust),
                format!(
                    "{} {}",
                    p["name"].as_str().unwrap_or("?"),
                    p["version"].as_str().unwrap_or("?")
                ),
            ))
        })
        .max()
        .expect("dependencies declare rust versions");
    assert!(
        claimed >= needed,
        "the workspace claims Rust {claimed:?} but {by} needs {needed:?}"
    );
}
